"""Paired comparison of the methods of a Monte Carlo study, per environment (``comparisons.csv``).

Every method of a study meets the same sampled scenario in run ``r`` of an environment, so two methods are
compared on the runs both completed, paired by run index, with :func:`mmg_casadi.montecarlo.stats.paired_comparison`: the
success difference A − B with Newcombe's 95 % interval and the exact McNemar p-value on the discordant runs.

Examples
--------
>>> rows = [{"environment": 1, "method": m, "run": r, "success": m == "a" or r % 2 == 0}
...         for m in ("a", "b") for r in range(20)]
>>> c = compare_methods(rows)[0]
>>> c["method_a"], c["method_b"], c["n"], c["a_only"], c["b_only"], c["difference"]
('a', 'b', 20, 10, 0, 0.5)
>>> round(c["p_value"], 5)
0.00195
"""

from __future__ import annotations

import csv
import math
from itertools import combinations
from pathlib import Path

from mmg_casadi.io import atomic_open
from mmg_casadi.montecarlo.stats import paired_comparison

COMPARISON_COLUMNS: tuple[str, ...] = (
    "environment", "method_a", "method_b", "n", "success_a", "success_b", "difference", "ci_low", "ci_high",
    "a_only", "b_only", "p_value", "verdict",
)
"""Columns of ``comparisons.csv``."""


def compare_methods(rows, methods=None) -> list[dict]:
    """One paired comparison per environment and pair of methods (in ``methods`` order, A before B).

    Parameters
    ----------
    rows : iterable of dict
        Run rows (``environment``, ``method``, ``run``, ``success``).
    methods : sequence of str, optional
        Methods to compare, in order (default: order of first appearance).

    Returns
    -------
    list of dict
        Keys :data:`COMPARISON_COLUMNS`; ``verdict`` is ``"A better"``, ``"B better"`` or
        ``"no significant difference"`` at the 5 % level. Pairs without a common run are left out.
    """
    by: dict[tuple[int, str], dict[int, bool]] = {}
    order: list[str] = []
    for r in rows:
        m = str(r["method"])
        if m not in order:
            order.append(m)
        by.setdefault((int(r["environment"]), m), {})[int(r["run"])] = r.get("success") is True or r.get(
            "success") == 1
    methods = list(methods) if methods is not None else order
    out = []
    for env in sorted({e for e, _ in by}):
        for a, b in combinations(methods, 2):
            sa, sb = by.get((env, a), {}), by.get((env, b), {})
            common = sorted(set(sa) & set(sb))
            if not common:
                continue
            c = paired_comparison([sa[k] for k in common], [sb[k] for k in common])
            out.append({"environment": env, "method_a": a, "method_b": b, "n": c.n, "success_a": c.rate_a,
                        "success_b": c.rate_b, "difference": c.difference, "ci_low": c.ci[0], "ci_high": c.ci[1],
                        "a_only": c.a_only, "b_only": c.b_only, "p_value": c.p_value,
                        "verdict": c.verdict().replace("A better", f"{a} better").replace("B better",
                                                                                             f"{b} better")})
    return out


def write_csv(comparisons, path) -> Path:
    """Write comparisons (:func:`compare_methods`) to ``path`` (columns :data:`COMPARISON_COLUMNS`).

    Parameters
    ----------
    comparisons : list of dict
        The comparisons.
    path : str or Path
        Destination.

    Returns
    -------
    pathlib.Path
        The path written.
    """
    path = Path(path)
    with atomic_open(path, "w", encoding="utf-8", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(COMPARISON_COLUMNS)
        for c in comparisons:
            w.writerow([repr(v) if isinstance(v, float) else v for v in (c[k] for k in COMPARISON_COLUMNS)])
    return path


def read_csv(path) -> list[dict]:
    """Comparisons written by :func:`write_csv` (numbers as int/float).

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    list of dict
        One dict per row, keys :data:`COMPARISON_COLUMNS`; ``environment``, ``n``, ``a_only``, ``b_only`` as int,
        the method names and ``verdict`` as str, the rest as float.
    """
    ints = {"environment", "n", "a_only", "b_only"}
    text = {"method_a", "method_b", "verdict"}
    with open(path, encoding="utf-8", newline="") as f:
        return [{k: (v if k in text else int(v) if k in ints else float(v)) for k, v in row.items()}
                for row in csv.DictReader(f)]


def to_markdown(comparisons) -> str:
    """A Markdown table: success difference in percentage points with its 95 % interval, discordant runs and
    the exact McNemar p-value.

    Parameters
    ----------
    comparisons : list of dict
        The comparisons.

    Returns
    -------
    str
        The table, one row per comparison, without a final newline.

    Examples
    --------
    >>> rows = [{"environment": 1, "method": m, "run": r, "success": m == "a" or r % 2 == 0}
    ...         for m in ("a", "b") for r in range(20)]
    >>> print(to_markdown(compare_methods(rows)).splitlines()[2])
    | 1 | a − b | 20 | +50.0 [+24.3, +70.1] | 10 / 0 | 0.00195 | a better |
    """
    lines = ["| Env | A − B | Runs | Success difference [pp] (95 % CI) | A only / B only | McNemar p | Verdict |",
             "|---:|:---|---:|:---|:---|---:|:---|"]
    for c in comparisons:
        p = c["p_value"]
        ptxt = "n/a" if p != p else (f"{p:.3g}" if p >= 1e-4 else f"{p:.1e}")
        diff = (f"{100 * c['difference']:+.1f} [{100 * c['ci_low']:+.1f}, {100 * c['ci_high']:+.1f}]"
                if math.isfinite(c["difference"]) else "n/a")
        lines.append(f"| {c['environment']} | {c['method_a']} − {c['method_b']} | {c['n']} | {diff} | "
                     f"{c['a_only']} / {c['b_only']} | {ptxt} | {c['verdict']} |")
    return "\n".join(lines)
