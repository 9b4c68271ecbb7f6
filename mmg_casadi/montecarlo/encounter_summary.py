"""Per-encounter COLREG reporting of a Monte Carlo study: the ``colregs_verdicts`` column of ``runs.csv``, rates by
role and by rule with Wilson intervals, and paired comparisons of methods encounter by encounter.

Each run stores its own ship's encounters with a risk of collision in one text cell (:func:`format_verdicts`),
e.g. ``2:give-way:0.731:8=1/16=0/15=1;4:stand-on:1:17a_i=1/8=1:e``: per encounter the other ship's index, the own
ship's role at the onset of risk, the graded score, each applicable rule's verdict (1 kept, 0 not) and, as a fifth
field ``e``, whether an excuse by a give-way duty to another ship changed a verdict (``excuse_changed`` of
:class:`~mmg_casadi.colregs.scorer.Encounter`). A study keeps one such cell per scoring profile
(``colregs_verdicts_<profile>``, :data:`~mmg_casadi.montecarlo.execution.PROFILE_COLUMNS`).

:func:`summarize_encounters` reduces the cells to one row per (environment, method, group) where the group is
``all``, a role (``head-on``, ``give-way``, ``stand-on``, ``overtaking``, ``overtaken``) or a rule
(``rule 8`` ... ``rule 17c``): encounters ``n``, kept ``k``, the rate ``k / n`` with a Wilson 95 % interval and
the mean graded score. For a rule, ``n`` counts the encounters in which the rule applies. Cells whose runs sailed
a narrow channel also get the group ``rule 9``: per run the own ship's Rule 9(a) share (``colregs_rule9``,
:mod:`mmg_casadi.colregs.narrow_channel`), ``n`` the runs in a channel, kept those at
:data:`~mmg_casadi.colregs.narrow_channel.KEPT_SHARE` or more, the score the mean share. ``excused`` counts the
group's encounters whose verdict an excuse changed. :func:`summarize_profiles` and :func:`compare_profiles` do the
same for every scoring profile's column, with a ``profile`` column.

:func:`compare_encounters` pairs two methods' encounters of the same run with the same other ship (the i-th risky
encounter with ship j in run r of one method with the i-th of the other) and compares their compliance with the
exact McNemar test (:func:`~mmg_casadi.montecarlo.stats.paired_comparison`). An encounter that only one method had
(the other method never came into risk with that ship) has no pair; the number of such encounters is reported.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

from mmg_casadi.colregs.narrow_channel import KEPT_SHARE
from mmg_casadi.colregs.roles import ROLES
from mmg_casadi.colregs.verdict import RULES
from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.stats import paired_comparison, wilson

GROUPS: tuple[str, ...] = ("all", *ROLES, *(f"rule {r}" for r in RULES))
"""Groups of :func:`summarize_encounters`, in order."""

ENCOUNTER_COLUMNS: tuple[str, ...] = ("profile", "environment", "method", "group", "n", "kept", "rate", "ci_low",
                                      "ci_high", "score_mean", "excused")
"""Columns of ``colregs.csv`` (:func:`write_csv`)."""

PAIR_COLUMNS: tuple[str, ...] = ("profile", "environment", "method_a", "method_b", "pairs", "rate_a", "rate_b", "both",
                                 "a_only", "b_only", "neither", "difference", "ci_low", "ci_high", "p_value",
                                 "unpaired_a", "unpaired_b")
"""Columns of ``colregs_comparisons.csv`` (:func:`write_csv`)."""


@dataclass(frozen=True)
class Verdict:
    """One risky encounter of a run's own ship, as stored in ``colregs_verdicts``.

    Parameters
    ----------
    other : int
        Index of the other ship in the scenario.
    role : str
        The own ship's role (:data:`~mmg_casadi.colregs.roles.ROLES`).
    score : float
        Graded score in [0, 1].
    rules : dict
        ``{rule: kept}`` for the applicable rules (keys of :data:`~mmg_casadi.colregs.verdict.RULES`).
    excused : bool
        Whether an excuse by a give-way duty to another ship changed a verdict.
    """

    other: int
    role: str
    score: float
    rules: dict
    excused: bool = False

    @property
    def compliant(self) -> bool:
        """Whether every applicable rule is kept."""
        return all(self.rules.values())


def format_verdicts(encounters, ships=None) -> str:
    """The ``colregs_verdicts`` cell of a run from its own ship's applicable encounters.

    Parameters
    ----------
    encounters : iterable of Encounter
        Applicable encounters with at least one rule (:class:`~mmg_casadi.colregs.scorer.Encounter`).
    ships : sequence of int, optional
        Scenario index of each ship index used by the encounters (default: the same index).

    Returns
    -------
    str
        ``other:role:score:rule=0|1/...`` per encounter (``:e`` appended where an excuse changed a verdict), joined
        by ``;`` (``""`` without any).

    Examples
    --------
    >>> from mmg_casadi.colregs.verdict import RuleResult
    >>> class E:  # the fields of an Encounter this function reads
    ...     other, role, score = 1, "give-way", 0.73125
    ...     rules = {"8": RuleResult(True, 1.0), "16": RuleResult(False, 0.2)}
    >>> format_verdicts([E()], ships=[0, 3])
    '3:give-way:0.73125:8=1/16=0'
    """
    tokens = []
    for e in encounters:
        other = e.other if ships is None else int(ships[e.other])
        rules = "/".join(f"{r}={int(v.verdict)}" for r, v in e.rules.items())
        excused = ":e" if getattr(e, "excuse_changed", False) else ""
        tokens.append(f"{other}:{e.role}:{float(e.score):.6g}:{rules}{excused}")
    return ";".join(tokens)


def parse_verdicts(text, field: str = "colregs_verdicts") -> list[Verdict]:
    """The encounters of one ``colregs_verdicts`` cell (``[]`` for an empty cell).

    Parameters
    ----------
    text : str or None
        The cell.
    field : str
        Name used in the error message.

    Returns
    -------
    list of Verdict
        One per encounter of the cell, in cell order.

    Examples
    --------
    >>> [(v.compliant, v.excused) for v in parse_verdicts("3:give-way:0.73:8=1/16=0;4:stand-on:1:17a_i=1:e")]
    [(False, False), (True, True)]
    >>> parse_verdicts("3:sideways:1:8=1")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: colregs_verdicts: expected encounters 'other:role:score:rule=0|1/...' with a role in head-on, give-way, stand-on, overtaking, overtaken and rules in 8, 13, 14, 15, 16, 17a_i, 17a_ii, 17b, 17c, got '3:sideways:1:8=1'
    """
    if text is None or (isinstance(text, float) and math.isnan(text)) or str(text).strip() == "":
        return []
    out = []
    for token in str(text).split(";"):
        try:
            other, role, score, rules, *flag = token.split(":")
            if flag not in ([], ["e"]):
                raise ValueError
            pairs = [item.split("=") for item in rules.split("/")] if rules else []
            kept = {r: {"1": True, "0": False}[v] for r, v in pairs}
            verdict = Verdict(int(other), role, float(score), kept, bool(flag))
            if role not in ROLES or any(r not in RULES for r in kept) or not 0.0 <= verdict.score <= 1.0:
                raise ValueError
        except (ValueError, KeyError):
            raise InputError(field, "encounters 'other:role:score:rule=0|1/...' with a role in "
                             f"{', '.join(ROLES)} and rules in {', '.join(RULES)}", text) from None
        out.append(verdict)
    return out


def _rate(n: int, k: int, scores: list, excused: int = 0) -> dict:
    low, high = wilson(k, n) if n else (math.nan, math.nan)
    return {"n": n, "kept": k, "rate": k / n if n else math.nan, "ci_low": low, "ci_high": high,
            "score_mean": math.fsum(scores) / len(scores) if scores else math.nan, "excused": excused}


def _cells(rows):
    cells: dict[tuple[int, str], list[dict]] = {}
    for row in rows:
        cells.setdefault((int(row["environment"]), str(row["method"])), []).append(row)
    return cells


def summarize_encounters(rows, column: str = "colregs_verdicts", profile: str = "") -> list[dict]:
    """Per (environment, method) and group (:data:`GROUPS`), the encounters, how many were kept, the rate with a
    Wilson 95 % interval, the mean graded score and how many verdicts an excuse changed (module docstring).

    Parameters
    ----------
    rows : iterable of dict
        Rows of ``runs.csv`` (:meth:`~mmg_casadi.montecarlo.results.ResultsTable.read`).
    column : str, default "colregs_verdicts"
        The column of verdicts to read.
    profile : str, default ""
        The value of the ``profile`` column of every row returned.

    Returns
    -------
    list of dict
        Keys :data:`ENCOUNTER_COLUMNS`; groups without an encounter have ``n = 0`` and ``nan`` rates; ``rule 9``
        only for cells with a run in a narrow channel.

    Examples
    --------
    >>> rows = [{"environment": 5, "method": "cv", "run": 0, "colregs_verdicts": "1:give-way:0.5:8=1/16=0"},
    ...         {"environment": 5, "method": "cv", "run": 1, "colregs_verdicts": "2:stand-on:1:17a_i=1/8=1"}]
    >>> s = {r["group"]: (r["n"], r["kept"]) for r in summarize_encounters(rows)}
    >>> s["all"], s["give-way"], s["stand-on"], s["rule 8"], s["rule 16"], s["head-on"]
    ((2, 1), (1, 0), (1, 1), (2, 2), (1, 0), (0, 0))
    >>> rows[0]["colregs_rule9"], rows[1]["colregs_rule9"] = "0.95", "0.4"   # both runs in a narrow channel
    >>> [(r["n"], r["kept"]) for r in summarize_encounters(rows) if r["group"] == "rule 9"]
    [(2, 1)]
    """
    out = []
    for (env, method), group in _cells(rows).items():
        verdicts = [v for r in group for v in parse_verdicts(r.get(column), column)]
        for name in GROUPS:
            if name.startswith("rule "):
                rule = name[5:]
                chosen = [v for v in verdicts if rule in v.rules]
                k = sum(1 for v in chosen if v.rules[rule])
            else:
                chosen = [v for v in verdicts if name in ("all", v.role)]
                k = sum(1 for v in chosen if v.compliant)
            out.append({"profile": profile, "environment": env, "method": method, "group": name,
                        **_rate(len(chosen), k, [v.score for v in chosen], sum(v.excused for v in chosen))})
        shares = [x for x in (_share(r.get("colregs_rule9")) for r in group) if x is not None]
        if shares:  # runs in a narrow channel: Rule 9(a), one verdict per run
            out.append({"profile": profile, "environment": env, "method": method, "group": "rule 9",
                        **_rate(len(shares), sum(x >= KEPT_SHARE for x in shares), shares)})
    return out


def summarize_profiles(rows, columns: dict) -> list[dict]:
    """:func:`summarize_encounters` of every profile's column, one after the other.

    Parameters
    ----------
    rows : iterable of dict
        Rows of ``runs.csv``.
    columns : dict
        ``{profile: column}`` (:data:`~mmg_casadi.montecarlo.execution.PROFILE_COLUMNS`).

    Returns
    -------
    list of dict
        Keys :data:`ENCOUNTER_COLUMNS`, the profiles in the order of ``columns``.

    Examples
    --------
    >>> rows = [{"environment": 5, "method": "cv", "run": 0, "a": "1:give-way:0.5:8=1/16=0", "b": "1:give-way:1:8=1"}]
    >>> [(r["profile"], r["kept"]) for r in summarize_profiles(rows, {"p": "a", "q": "b"}) if r["group"] == "all"]
    [('p', 0), ('q', 1)]
    """
    rows = list(rows)
    return [r for name, column in columns.items() for r in summarize_encounters(rows, column, name)]


def _share(value) -> float | None:
    """A run's ``colregs_rule9`` as a float, None when the own ship was never in a narrow channel."""
    if value is None or value == "":
        return None
    x = float(value)
    return None if math.isnan(x) else x


def _keyed(group, column) -> dict:
    """``{(run, other, occurrence): compliant}`` of one cell's runs."""
    out = {}
    for row in group:
        seen: dict[int, int] = {}
        for v in parse_verdicts(row.get(column), column):
            i = seen[v.other] = seen.get(v.other, -1) + 1
            out[(int(row["run"]), v.other, i)] = v.compliant
    return out


def compare_encounters(rows, methods=None, column: str = "colregs_verdicts", profile: str = "") -> list[dict]:
    """Paired per-encounter compliance of every two methods per environment (module docstring).

    Parameters
    ----------
    rows : iterable of dict
        Rows of ``runs.csv``.
    methods : sequence of str, optional
        Methods in the order to pair them (default: order of first appearance).
    column : str, default "colregs_verdicts"
        The column of verdicts to read.
    profile : str, default ""
        The value of the ``profile`` column of every row returned.

    Returns
    -------
    list of dict
        Keys :data:`PAIR_COLUMNS`; ``difference`` is rate A − rate B over the paired encounters with Newcombe's
        interval, ``p_value`` the exact McNemar test on the discordant pairs; ``unpaired_a``/``unpaired_b`` count
        the encounters that only A (or B) had.

    Examples
    --------
    >>> rows = [{"environment": 5, "method": m, "run": r, "colregs_verdicts": f"1:give-way:1:8={int(m == 'a' or r > 0)}"}
    ...         for m in ("a", "b") for r in range(3)]
    >>> c = compare_encounters(rows)[0]
    >>> c["pairs"], c["a_only"], c["b_only"], round(c["difference"], 3)
    (3, 1, 0, 0.333)
    """
    rows = list(rows)
    cells = _cells(rows)
    order = list(dict.fromkeys(str(r["method"]) for r in rows)) if methods is None else [str(m) for m in methods]
    out = []
    for env in sorted({e for e, _ in cells}):
        present = [m for m in order if (env, m) in cells]
        keyed = {m: _keyed(cells[(env, m)], column) for m in present}
        for i, a in enumerate(present):
            for b in present[i + 1:]:
                common = sorted(keyed[a].keys() & keyed[b].keys())
                row = {"profile": profile, "environment": env, "method_a": a, "method_b": b, "pairs": len(common),
                       "unpaired_a": len(keyed[a]) - len(common), "unpaired_b": len(keyed[b]) - len(common)}
                if common:
                    c = paired_comparison([keyed[a][k] for k in common], [keyed[b][k] for k in common])
                    row.update({"rate_a": c.rate_a, "rate_b": c.rate_b, "both": c.both, "a_only": c.a_only,
                                "b_only": c.b_only, "neither": c.neither, "difference": c.difference,
                                "ci_low": c.ci[0], "ci_high": c.ci[1], "p_value": c.p_value})
                else:
                    row.update({k: math.nan for k in ("rate_a", "rate_b", "difference", "ci_low", "ci_high",
                                                      "p_value")})
                    row.update({k: 0 for k in ("both", "a_only", "b_only", "neither")})
                out.append(row)
    return out


def compare_profiles(rows, columns: dict, methods=None) -> list[dict]:
    """:func:`compare_encounters` of every profile's column, one after the other.

    Parameters
    ----------
    rows : iterable of dict
        Rows of ``runs.csv``.
    columns : dict
        ``{profile: column}``.
    methods : sequence of str, optional
        Methods in the order to pair them.

    Returns
    -------
    list of dict
        Keys :data:`PAIR_COLUMNS`, the profiles in the order of ``columns``.
    """
    rows = list(rows)
    return [r for name, column in columns.items() for r in compare_encounters(rows, methods, column, name)]


def write_csv(table, path, columns) -> Path:
    """Write rows of :func:`summarize_encounters` or :func:`compare_encounters` (``nan`` empty); returns the path.

    Parameters
    ----------
    table : list of dict
        The rows.
    path : str or path-like
        CSV file to write.
    columns : sequence of str
        :data:`ENCOUNTER_COLUMNS` or :data:`PAIR_COLUMNS`.

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    with open(path, "w", encoding="utf-8", newline="") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(columns)
        for r in table:
            writer.writerow(["" if isinstance(r[c], float) and math.isnan(r[c]) else r[c] for c in columns])
    return path


def _pct(r) -> str:
    if not r["n"]:
        return "n/a (0)"
    return f"{100 * r['rate']:.1f} [{100 * r['ci_low']:.1f}, {100 * r['ci_high']:.1f}] ({r['n']})"


def to_markdown(summary, comparisons) -> str:
    """Markdown tables: per-encounter compliance by role and by rule (``rate [95 % CI] (n)``) and the paired
    comparisons, per scoring profile.

    Parameters
    ----------
    summary : list of dict
        :func:`summarize_encounters` or :func:`summarize_profiles`.
    comparisons : list of dict
        :func:`compare_encounters` or :func:`compare_profiles`.

    Returns
    -------
    str
        The tables, separated by blank lines, without a final newline.

    Examples
    --------
    >>> rows = [{"environment": 5, "method": "cv", "run": 0, "colregs_verdicts": "1:give-way:0.5:8=1/16=0"}]
    >>> print(to_markdown(summarize_encounters(rows, profile="published"), []).splitlines()[2])
    | published | 5 | cv | 0.0 [0.0, 79.3] (1) | 0.500 | 0 | n/a (0) | 0.0 [0.0, 79.3] (1) | n/a (0) | n/a (0) | n/a (0) |
    """
    by_cell: dict[tuple, dict] = {}
    for r in summary:
        by_cell.setdefault((r["profile"], r["environment"], r["method"]), {})[r["group"]] = r
    roles = ["Profile", "Env", "Method", "All [%] (n)", "Mean score", "Excused", *(f"{g} [%] (n)" for g in ROLES)]
    lines = ["| " + " | ".join(roles) + " |", "|:---|---:|:---|" + ":---|" * (len(roles) - 3)]
    for (profile, env, method), g in by_cell.items():
        score = g["all"]["score_mean"]
        lines.append("| " + " | ".join([profile, str(env), method, _pct(g["all"]), "n/a" if math.isnan(score) else
                                        f"{score:.3f}", str(g["all"]["excused"]), *(_pct(g[x]) for x in ROLES)])
                     + " |")
    shown = list(RULES) + (["9"] if any("rule 9" in g for g in by_cell.values()) else [])
    rules = ["Profile", "Env", "Method", *(f"Rule {r} kept [%] (applied)" for r in shown)]
    lines += ["", "| " + " | ".join(rules) + " |", "|:---|---:|:---|" + ":---|" * len(shown)]
    for (profile, env, method), g in by_cell.items():
        lines.append("| " + " | ".join([profile, str(env), method, *(_pct(g[f"rule {r}"]) if f"rule {r}" in g else
                                                                     "n/a (0)" for r in shown)]) + " |")
    if comparisons:
        head = ["Profile", "Env", "A", "B", "Paired encounters", "A kept [%]", "B kept [%]", "A only", "B only",
                "A − B [pp] (95 % CI)", "McNemar p", "Unpaired A / B"]
        lines += ["", "| " + " | ".join(head) + " |",
                  "|:---|---:|:---|:---|---:|---:|---:|---:|---:|:---|---:|---:|"]
        for c in comparisons:
            if not c["pairs"]:
                cells = [c["profile"], str(c["environment"]), c["method_a"], c["method_b"], "0", *["n/a"] * 6]
            else:
                cells = [c["profile"], str(c["environment"]), c["method_a"], c["method_b"], str(c["pairs"]),
                         f"{100 * c['rate_a']:.1f}", f"{100 * c['rate_b']:.1f}", str(c["a_only"]), str(c["b_only"]),
                         f"{100 * c['difference']:+.1f} [{100 * c['ci_low']:+.1f}, {100 * c['ci_high']:+.1f}]",
                         f"{c['p_value']:.3g}"]
            lines.append("| " + " | ".join(cells + [f"{c['unpaired_a']} / {c['unpaired_b']}"]) + " |")
    return "\n".join(lines)
