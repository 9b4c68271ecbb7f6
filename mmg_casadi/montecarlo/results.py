"""Tidy results table of a Monte Carlo study, resumable after a crash, and its summary with 95 % intervals.

One CSV row per (environment, method, run) with the columns :data:`RUN_COLUMNS`. :class:`ResultsTable`
appends rows durably (flush + fsync per append), skips rows already stored, and tolerates a truncated last
line left by a killed process. :func:`summarize` reduces the rows to one line per (environment, method)
with the paper's statistics: success rate with a Wilson score interval and means of time to goal, CE,
MCTE and guidance-call time with normal-approximation 95 % confidence intervals, the run-level COLREG
compliance and the encounter scorer's per-encounter compliance (Wilson interval) and mean graded score.
"""

from __future__ import annotations

import csv
import io
import math
import os
from dataclasses import dataclass
from pathlib import Path


from mmg_casadi.closed_loop.outcome import RUN_FAILURES
from mmg_casadi.errors import InputError
from mmg_casadi.io import atomic_open
from mmg_casadi.montecarlo import failures as failure_mechanisms
from mmg_casadi.montecarlo.stats import wilson

RUN_COLUMNS: tuple[str, ...] = (
    "environment", "method", "run", "seed", "success", "fleet_success", "failure", "failure_pair",
    "failure_time", "time_to_goal", "ce", "mcte", "fleet_time_to_goal", "fleet_ce", "fleet_mcte",
    "min_distance", "guidance_call_us", "n_ships", "n_obstacles",
    "current_speed", "current_direction_deg", "wind_speed", "wind_direction_deg",
    "failure_mechanism", "colregs_risky", "colregs_lawful", "colregs_score", "colregs_compliant",
    "colregs_verdicts", "colregs_rule9", "colregs_verdicts_published", "colregs_verdicts_iitm_lab",
    "colregs_verdicts_ntnu_2023", "target_behaviours", "perception_error",
)
"""Columns of the results CSV, in order (version :data:`RESULTS_VERSION`)."""

RESULTS_VERSION = 7
"""Version of :data:`RUN_COLUMNS`: 2 added ``failure_mechanism``, ``colregs_compliant`` and
``colregs_encounters`` (the legacy scorer); 3 added the encounter scorer's ``colregs_risky``, ``colregs_lawful``
and ``colregs_score``; 4 dropped the legacy scorer (``colregs_encounters``; ``colregs_compliant`` is now the
encounter scorer's run-level flag) and added ``colregs_verdicts``
(:mod:`mmg_casadi.montecarlo.encounter_summary`); 5 added ``colregs_rule9`` (the own ship's Rule 9(a) score in a
narrow channel, :mod:`mmg_casadi.colregs.narrow_channel`); 6 added ``colregs_verdicts_<profile>``, the verdicts
under every scoring profile (:data:`mmg_casadi.montecarlo.execution.PROFILE_COLUMNS`); 7 added ``target_behaviours``
(what each target ship did, :mod:`mmg_casadi.traffic`) and ``perception_error`` (the mean distance between where the
own ship's method saw the targets within R_safe and where they were, :mod:`mmg_casadi.perception`; empty with
perfect knowledge); a table of another version is refused, never misread."""

TALLIES_KEY = "tallies"
"""Key of a row that carries the own ship's tallies (``Method.tallies``) beside the columns; not a column of
``runs.csv`` (the study keeps them in ``tallies.csv``, :mod:`mmg_casadi.montecarlo.tallies`)."""

_RETIRED_COLUMNS = frozenset({"colregs_encounters"})  # columns of older versions, no longer written

MECHANISMS: tuple[str, ...] = failure_mechanisms.MECHANISMS
"""Allowed non-empty values of ``failure_mechanism`` (:data:`mmg_casadi.montecarlo.failures.MECHANISMS`)."""

KEY_COLUMNS: tuple[str, str, str] = ("environment", "method", "run")
"""Columns that identify a run; a key is stored at most once."""

FAILURES: tuple[str, ...] = ("", *RUN_FAILURES)
"""Allowed values of the ``failure`` column (``""`` for a successful run)."""

_INT_COLUMNS = frozenset({"environment", "run", "seed", "n_ships", "n_obstacles", "colregs_risky",
                          "colregs_lawful"})
_BOOL_COLUMNS = frozenset({"success", "fleet_success", "colregs_compliant"})
_STR_COLUMNS = frozenset({"method", "failure", "failure_pair", "failure_mechanism", "colregs_verdicts",
                          "colregs_verdicts_published", "colregs_verdicts_iitm_lab", "colregs_verdicts_ntnu_2023",
                          "target_behaviours"})
_FLOAT_COLUMNS = frozenset(RUN_COLUMNS) - _INT_COLUMNS - _BOOL_COLUMNS - _STR_COLUMNS

METRICS: tuple[str, ...] = ("time_to_goal", "ce", "mcte", "guidance_call_us")
"""Metrics summarised with a mean and a 95 % confidence interval."""

_OVER_SUCCESSES = frozenset({"time_to_goal", "ce", "mcte"})

SUMMARY_COLUMNS: tuple[str, ...] = (
    "environment", "method", "runs", "success_rate", "success_ci_low", "success_ci_high",
    *(f"{m}_{s}" for m in METRICS for s in ("mean", "ci_low", "ci_high")),
    "compliance_runs", "compliance_rate", "compliance_ci_low", "compliance_ci_high",
    "colregs_risky", "colregs_lawful", "colregs_encounter_rate", "colregs_encounter_ci_low",
    "colregs_encounter_ci_high", "colregs_score_mean",
    *(f"failures_{m.replace('-', '_')}" for m in MECHANISMS),
)
"""Columns of :meth:`Summary.to_csv`, in order."""

Z_95 = 1.96


def _format_cell(column: str, value) -> str:
    if value is None:
        return ""
    if column in _STR_COLUMNS:
        return str(value)
    if column in _BOOL_COLUMNS:
        if isinstance(value, str):
            value = _parse_bool(column, value)
            if value is None:
                return ""
        return "True" if bool(value) else "False"
    if column in _INT_COLUMNS:
        if isinstance(value, str) and value == "":
            return ""
        try:
            as_float = float(value)
        except (TypeError, ValueError):
            raise InputError(column, "an integer", value) from None
        if as_float != as_float:
            return ""
        if as_float != int(as_float):
            raise InputError(column, "an integer", value)
        return str(int(as_float))
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise InputError(column, "a number", value) from None
    return "" if x != x else repr(x)


def _parse_bool(column: str, text: str):
    t = text.strip().lower()
    if t == "":
        return None
    if t in ("true", "1"):
        return True
    if t in ("false", "0"):
        return False
    raise InputError(column, "True or False", text)


def _parse_cell(column: str, text: str):
    if column in _STR_COLUMNS:
        return text
    if column in _BOOL_COLUMNS:
        return _parse_bool(column, text)
    if column in _INT_COLUMNS:
        return int(text) if text != "" else None
    return float(text) if text != "" else math.nan


def _key(row: dict) -> tuple[int, str, int]:
    return int(row["environment"]), str(row["method"]), int(row["run"])


class ResultsTable:
    """A CSV file of run results (columns :data:`RUN_COLUMNS`) that can be appended to and resumed.

    Every :meth:`append` opens the file, writes the new rows in one call, flushes and fsyncs, so a killed
    process loses at most the rows of the append in progress. A final line without its newline (a write
    cut short) is ignored by :meth:`read` and :meth:`completed` and removed by the next :meth:`append`.

    Parameters
    ----------
    path : str or Path
        The CSV file; it need not exist yet.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "runs.csv"
    >>> table = ResultsTable(path)
    >>> table.append([{"environment": 1, "method": "apf", "run": 0, "success": True, "ce": 0.12}])
    1
    >>> table.append([{"environment": 1, "method": "apf", "run": 0, "success": False}])
    0
    >>> table.completed()
    {(1, 'apf', 0)}
    >>> row = table.read()[0]
    >>> row["success"], row["ce"], row["seed"], row["failure"]
    (True, 0.12, None, '')
    """

    def __init__(self, path):
        self.path = Path(path)
        self._cache: tuple[int, int, set[tuple[int, str, int]]] | None = None

    def __repr__(self) -> str:
        return f"ResultsTable({str(self.path)!r})"

    def _scan(self) -> tuple[list[dict], int, int]:
        """Parse the file: (rows with unique keys, byte length of the complete part, file size)."""
        if not self.path.exists():
            return [], 0, 0
        data = self.path.read_bytes()
        end = data.rfind(b"\n") + 1
        text = data[:end].decode("utf-8")
        if not text:
            return [], 0, len(data)
        reader = csv.reader(io.StringIO(text, newline=""))
        header = next(reader)
        if tuple(header) != RUN_COLUMNS:
            missing = [c for c in RUN_COLUMNS if c not in header]
            if missing and all(c in RUN_COLUMNS or c in _RETIRED_COLUMNS for c in header):
                raise InputError(str(self.path), f"a results table of version {RESULTS_VERSION} (this one is from an "
                                 f"older version, without the columns {', '.join(missing)}; use a new output "
                                 "directory or rerun the study there)", ",".join(header))
            raise InputError(str(self.path), f"a results CSV with the columns {', '.join(RUN_COLUMNS)}",
                             ",".join(header))
        rows, seen = [], set()
        for lineno, cells in enumerate(reader, start=2):
            if len(cells) != len(RUN_COLUMNS):
                raise InputError(f"{self.path}:{lineno}", f"{len(RUN_COLUMNS)} comma-separated fields",
                                 len(cells))
            row = {c: _parse_cell(c, v) for c, v in zip(RUN_COLUMNS, cells)}
            key = _key(row)
            if key not in seen:
                seen.add(key)
                rows.append(row)
        return rows, end, len(data)

    def read(self) -> list[dict]:
        """All stored rows, each key once (the first occurrence), with typed values.

        Integers are ``int`` (``None`` if empty), booleans ``bool`` (``None`` if empty), numbers ``float``
        (``nan`` if empty), text ``str`` (``""`` if empty). An incomplete final line is ignored.

        Returns
        -------
        list of dict
            One dict per stored row, column name to typed value, in file order.
        """
        return self._scan()[0]

    def completed(self) -> set[tuple[int, str, int]]:
        """Keys ``(environment, method, run)`` already stored.

        Returns
        -------
        set of tuple of (int, str, int)
            The ``(environment, method, run)`` of every stored row (a copy).
        """
        rows, end, size = self._scan()
        keys = {_key(r) for r in rows}
        self._cache = (size, end, keys)
        return set(keys)

    def _state(self) -> tuple[set, int, int]:
        """(stored keys, byte length of the complete part, file size), re-read only if the size changed."""
        size = self.path.stat().st_size if self.path.exists() else 0
        if self._cache is not None and self._cache[0] == size:
            return self._cache[2], self._cache[1], size
        rows, end, size = self._scan()
        keys = {_key(r) for r in rows}
        self._cache = (size, end, keys)
        return keys, end, size

    def append(self, rows) -> int:
        """Append rows (dicts keyed by :data:`RUN_COLUMNS`); rows whose key is already stored are skipped.

        Missing columns are written empty; unknown columns raise :class:`InputError`. The header is written
        when the file is new or empty; an incomplete final line from an interrupted write is removed first.

        Parameters
        ----------
        rows : iterable of dict
            Rows keyed by :data:`RUN_COLUMNS`.

        Returns
        -------
        int
            Number of rows written.
        """
        rows = list(rows)
        lines = []
        keys, end, size = self._state()
        new_keys = set()
        for i, row in enumerate(rows):
            if not isinstance(row, dict):
                raise InputError(f"rows[{i}]", "a dict keyed by the results columns", type(row).__name__)
            unknown = set(row) - set(RUN_COLUMNS) - {TALLIES_KEY}
            if unknown:
                raise InputError(f"rows[{i}]", f"keys among {', '.join(RUN_COLUMNS)}", ", ".join(sorted(unknown)))
            missing = [c for c in KEY_COLUMNS if row.get(c) is None]
            if missing:
                raise InputError(f"rows[{i}].{missing[0]}", "a value (key column)", None)
            failure = row.get("failure") or ""
            if failure not in FAILURES:
                raise InputError(f"rows[{i}].failure", " or ".join(repr(f) for f in FAILURES), failure)
            mechanism = row.get("failure_mechanism") or ""
            if mechanism not in ("", *MECHANISMS):
                raise InputError(f"rows[{i}].failure_mechanism", f"'' or one of {', '.join(MECHANISMS)}", mechanism)
            cells = [_format_cell(c, row.get(c)) for c in RUN_COLUMNS]
            key = _key(dict(zip(RUN_COLUMNS, (_parse_cell(c, v) for c, v in zip(RUN_COLUMNS, cells)))))
            if key in keys or key in new_keys:
                continue
            new_keys.add(key)
            lines.append(cells)
        if end < size:
            with open(self.path, "r+b") as f:
                f.truncate(end)
                f.flush()
                os.fsync(f.fileno())
            size = end
        if not lines and size > 0:
            self._cache = (size, size, keys)
            return 0
        buf = io.StringIO(newline="")
        writer = csv.writer(buf, lineterminator="\n")
        if size == 0:
            writer.writerow(RUN_COLUMNS)
        writer.writerows(lines)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with open(self.path, "a", encoding="utf-8", newline="") as f:
            f.write(buf.getvalue())
            f.flush()
            os.fsync(f.fileno())
        size = self.path.stat().st_size
        self._cache = (size, size, keys | new_keys)
        return len(lines)


def wilson_interval(k: int, n: int, z: float = Z_95) -> tuple[float, float]:
    """Wilson score interval of a binomial proportion ``k / n``.

    Parameters
    ----------
    k : int
        Number of successes, ``0 <= k <= n``.
    n : int
        Number of trials, ``n >= 1``.
    z : float
        Standard-normal quantile (1.96 for 95 %).

    Returns
    -------
    tuple of float
        ``(low, high)`` within [0, 1].

    Examples
    --------
    >>> low, high = wilson_interval(95, 100)
    >>> round(low, 4), round(high, 4)
    (0.8882, 0.9785)
    >>> wilson_interval(0, 10)[0]
    0.0
    >>> wilson_interval(10, 10)[1]
    1.0
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise InputError("n", "an integer >= 1", n)
    if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k <= n:
        raise InputError("k", f"an integer in [0, {n}]", k)
    if not z > 0:
        raise InputError("z", "a number > 0", z)
    from scipy.stats import norm  # scipy.stats takes about 1 s to import: only when an interval is asked for

    p = k / n
    low, high = wilson(k, n, confidence=float(2 * norm.cdf(z) - 1))
    # the interval always contains p; clamp so rounding at k = 0 or k = n cannot put p outside it
    return min(p, max(0.0, low)), max(p, min(1.0, high))


def mean_ci(values, z: float = Z_95) -> tuple[float, float, float]:
    """Mean and normal-approximation interval ``mean ± z * s / sqrt(n)`` of the finite values.

    ``s`` is the sample standard deviation (ddof=1). With no finite value all three are ``nan``; with one
    the interval is ``nan``.

    Parameters
    ----------
    values : array-like of float
        Sample values; non-finite ones are ignored.
    z : float, default 1.96
        Normal quantile of the interval (1.96 for 95 %).

    Returns
    -------
    mean : float
        Mean of the finite values (``nan`` without any).
    low : float
        Lower end of the interval (``nan`` with fewer than two values).
    high : float
        Upper end of the interval (``nan`` with fewer than two values).

    Examples
    --------
    >>> [round(x, 4) for x in mean_ci([1.0, 2.0, 3.0, float("nan")])]
    [2.0, 0.8684, 3.1316]
    """
    xs = [float(v) for v in values if v is not None and math.isfinite(float(v))]
    n = len(xs)
    if n == 0:
        return math.nan, math.nan, math.nan
    mean = math.fsum(xs) / n
    if n == 1:
        return mean, math.nan, math.nan
    s = math.sqrt(math.fsum((x - mean) ** 2 for x in xs) / (n - 1))
    half = z * s / math.sqrt(n)
    return mean, mean - half, mean + half


@dataclass(frozen=True)
class Summary:
    """One row per (environment, method) with success rate and metric means, each with a 95 % interval.

    ``rows`` are dicts with the keys :data:`SUMMARY_COLUMNS`, sorted by environment and then by the order
    in which the methods first appear in the results.

    Parameters
    ----------
    rows : list of dict
        Summary rows keyed by :data:`SUMMARY_COLUMNS`.
    """

    rows: list

    @property
    def methods(self) -> list[str]:
        """Methods in order of first appearance."""
        return list(dict.fromkeys(r["method"] for r in self.rows))

    @property
    def environments(self) -> list[int]:
        """Environments, ascending."""
        return sorted({r["environment"] for r in self.rows})

    def to_dict(self) -> dict:
        """Column-oriented dictionary ``{column: [values]}`` over :data:`SUMMARY_COLUMNS`.

        Returns
        -------
        dict
            Each column of :data:`SUMMARY_COLUMNS` to the list of its values, one per row.
        """
        return {c: [r[c] for r in self.rows] for c in SUMMARY_COLUMNS}

    def to_csv(self, path) -> Path:
        """Write the summary to a CSV file (``nan`` written empty); returns the path.

        Parameters
        ----------
        path : str or path-like
            Path of the CSV file to write.

        Returns
        -------
        pathlib.Path
            The path written.
        """
        path = Path(path)
        with atomic_open(path, "w", encoding="utf-8", newline="") as f:
            writer = csv.writer(f, lineterminator="\n")
            writer.writerow(SUMMARY_COLUMNS)
            for r in self.rows:
                writer.writerow([_summary_cell(r[c]) for c in SUMMARY_COLUMNS])
        return path

    def to_markdown(self) -> str:
        """A Markdown table: success in % (one decimal), metrics to 3 significant digits, ``mean [low, high]``.

        Numbers of 1000 and above are rounded to 3 significant digits without an exponent; ``nan`` is ``n/a``.

        Returns
        -------
        str
            The table, one row per (environment, method), without a final newline.

        Examples
        --------
        >>> rows = [{"environment": 1, "method": "apf", "run": i, "success": i > 0, "time_to_goal": 60.0 + i,
        ...          "ce": 0.1, "guidance_call_us": 3.0} for i in range(4)]
        >>> print(summarize(rows).to_markdown())
        | Env | Method | Runs | Success [%] | Time to goal [L/U] | CE | MCTE [L] | Guidance call [µs] | COLREG-compliant [%] (runs) | COLREG encounters kept [%] (risky) | COLREG score |
        |---:|:---|---:|:---|:---|:---|:---|:---|:---|:---|:---|
        | 1 | apf | 4 | 75.0 [30.1, 95.4] | 62.0 [60.9, 63.1] | 0.100 [0.100, 0.100] | n/a [n/a, n/a] | 3.00 [3.00, 3.00] | n/a (0) | n/a (0) | n/a |
        """
        head = ["Env", "Method", "Runs", "Success [%]", "Time to goal [L/U]", "CE", "MCTE [L]",
                "Guidance call [µs]", "COLREG-compliant [%] (runs)", "COLREG encounters kept [%] (risky)",
                "COLREG score"]
        lines = ["| " + " | ".join(head) + " |", "|---:|:---|---:|" + ":---|" * 8]
        for r in self.rows:
            success = (f"{100 * r['success_rate']:.1f} [{100 * r['success_ci_low']:.1f}, "
                       f"{100 * r['success_ci_high']:.1f}]")
            cells = [str(r["environment"]), str(r["method"]), str(r["runs"]), success]
            for m in METRICS:
                cells.append(f"{_sig3(r[f'{m}_mean'])} [{_sig3(r[f'{m}_ci_low'])}, {_sig3(r[f'{m}_ci_high'])}]")
            n_c = r.get("compliance_runs", 0)
            cells.append(f"{100 * r['compliance_rate']:.1f} [{100 * r['compliance_ci_low']:.1f}, "
                         f"{100 * r['compliance_ci_high']:.1f}] ({n_c})" if n_c else "n/a (0)")
            n_e = r.get("colregs_risky", 0)
            cells.append(f"{100 * r['colregs_encounter_rate']:.1f} [{100 * r['colregs_encounter_ci_low']:.1f}, "
                         f"{100 * r['colregs_encounter_ci_high']:.1f}] ({n_e})" if n_e else "n/a (0)")
            cells.append(_sig3(r.get("colregs_score_mean", math.nan)))
            lines.append("| " + " | ".join(cells) + " |")
        return "\n".join(lines)

    def failures_markdown(self) -> str:
        """A Markdown table of the failed runs of every cell by mechanism (:data:`MECHANISMS`).

        Returns
        -------
        str
            The table: per (environment, method) the runs, the failed runs and the count of each mechanism.

        Examples
        --------
        >>> rows = [{"environment": 1, "method": "apf", "run": 0, "success": False, "failure_mechanism": "near-goal"}]
        >>> print(summarize(rows).failures_markdown().splitlines()[2])
        | 1 | apf | 1 | 1 | 0 | 0 | 1 | 0 | 0 | 0 | 0 | 0 | 0 |
        """
        head = ["Env", "Method", "Runs", "Failed", *MECHANISMS]
        lines = ["| " + " | ".join(head) + " |", "|---:|:---|---:|---:|" + "---:|" * len(MECHANISMS)]
        for r in self.rows:
            counts = [r[f"failures_{m.replace('-', '_')}"] for m in MECHANISMS]
            failed = r["runs"] - round(r["success_rate"] * r["runs"])
            lines.append("| " + " | ".join(str(v) for v in (r["environment"], r["method"], r["runs"], failed,
                                                               *counts)) + " |")
        return "\n".join(lines)

    def to_pandas(self):
        """The summary as a ``pandas.DataFrame``.

        Returns
        -------
        pandas.DataFrame
            One row per (environment, method), the columns of :data:`SUMMARY_COLUMNS`.
        """
        import pandas as pd  # about 0.3 s to import: only for to_pandas
        return pd.DataFrame(self.rows, columns=list(SUMMARY_COLUMNS))


def _summary_cell(value) -> str:
    if isinstance(value, float):
        return "" if value != value else repr(value)
    return str(value)


def _sig3(x) -> str:
    if x is None or x != x:
        return "n/a"
    if math.isfinite(x) and abs(x) >= 1000:
        return f"{round(x, 2 - int(math.floor(math.log10(abs(x))))):.0f}"
    text = f"{x:#.3g}"
    return text[:-1] if text.endswith(".") else text


def summarize(rows) -> Summary:
    """Reduce run rows to one row per (environment, method).

    Success rate: fraction of runs with ``success`` true, with a Wilson score 95 % interval. Time to goal,
    CE and MCTE: mean over the *successful* runs (their finite values), guidance-call time: mean over *all*
    runs (finite values); each with the normal-approximation interval ``mean ± 1.96 * s / sqrt(n)``
    (``s`` the sample standard deviation, ``n`` the number of values; ``nan`` when ``n < 2``).

    COLREGs: ``compliance_*`` is the run-level rate (runs with ``colregs_compliant`` true, i.e. every risky
    encounter kept, among the runs with a risky encounter, Wilson interval; secondary to the per-encounter rate). ``colregs_encounter_rate`` is the encounter scorer's per-encounter rate,
    ``sum(colregs_lawful) / sum(colregs_risky)`` over the runs, with a Wilson interval (``nan`` without a risky
    encounter), and ``colregs_score_mean`` the mean graded score over those encounters (each run's
    ``colregs_score`` weighted by its ``colregs_risky``).

    Parameters
    ----------
    rows : iterable of dict
        Rows as returned by :meth:`ResultsTable.read` (missing metric keys count as missing values).

    Returns
    -------
    Summary
        One row per (environment, method) with the columns of :data:`SUMMARY_COLUMNS`, environments ascending and
        methods in order of first appearance.

    Examples
    --------
    >>> rows = [{"environment": 2, "method": "vo", "run": i, "success": i % 2 == 0, "ce": float(i),
    ...          "guidance_call_us": 10.0} for i in range(4)]
    >>> r = summarize(rows).rows[0]
    >>> r["runs"], r["success_rate"], r["ce_mean"], r["guidance_call_us_mean"]
    (4, 0.5, 1.0, 10.0)
    """
    groups: dict[tuple[int, str], list[dict]] = {}
    method_order: dict[str, int] = {}
    for i, row in enumerate(rows):
        try:
            key = (int(row["environment"]), str(row["method"]))
        except (KeyError, TypeError, ValueError):
            raise InputError(f"rows[{i}]", "a dict with 'environment' and 'method'", row) from None
        method_order.setdefault(key[1], len(method_order))
        groups.setdefault(key, []).append(row)
    out = []
    for (env, method) in sorted(groups, key=lambda k: (k[0], method_order[k[1]])):
        group = groups[(env, method)]
        n = len(group)
        successes = [r for r in group if r.get("success") is True or r.get("success") == 1]
        k = len(successes)
        low, high = wilson_interval(k, n)
        summary = {"environment": env, "method": method, "runs": n, "success_rate": k / n,
                   "success_ci_low": low, "success_ci_high": high}
        for m in METRICS:
            pool = successes if m in _OVER_SUCCESSES else group
            mean, lo, hi = mean_ci(r.get(m) for r in pool)
            summary.update({f"{m}_mean": mean, f"{m}_ci_low": lo, f"{m}_ci_high": hi})
        judged = [r.get("colregs_compliant") for r in group if r.get("colregs_compliant") in (True, False)]
        kc = sum(1 for c in judged if c)
        clo, chi = wilson_interval(kc, len(judged)) if judged else (math.nan, math.nan)
        summary.update({"compliance_runs": len(judged), "compliance_rate": kc / len(judged) if judged else math.nan,
                        "compliance_ci_low": clo, "compliance_ci_high": chi})
        summary.update(_encounter_summary(group))
        for mech in MECHANISMS:
            summary[f"failures_{mech.replace('-', '_')}"] = sum(1 for r in group if r.get("failure_mechanism") == mech)
        out.append(summary)
    return Summary(rows=out)


def _encounter_summary(group: list) -> dict:
    """The per-encounter COLREG columns of one summary row (:func:`summarize`) from its runs."""
    counted = [r for r in group if isinstance(r.get("colregs_risky"), int) and r["colregs_risky"] > 0]
    risky = sum(r["colregs_risky"] for r in counted)
    lawful = sum(int(r.get("colregs_lawful") or 0) for r in counted)
    if not risky:
        return {"colregs_risky": 0, "colregs_lawful": 0, "colregs_encounter_rate": math.nan,
                "colregs_encounter_ci_low": math.nan, "colregs_encounter_ci_high": math.nan,
                "colregs_score_mean": math.nan}
    low, high = wilson_interval(lawful, risky)
    weighted = [(r["colregs_risky"], float(r["colregs_score"])) for r in counted
                if r.get("colregs_score") is not None and math.isfinite(float(r["colregs_score"]))]
    n_scored = sum(n for n, _ in weighted)
    return {"colregs_risky": risky, "colregs_lawful": lawful, "colregs_encounter_rate": lawful / risky,
            "colregs_encounter_ci_low": low, "colregs_encounter_ci_high": high,
            "colregs_score_mean": math.fsum(n * x for n, x in weighted) / n_scored if n_scored else math.nan}
