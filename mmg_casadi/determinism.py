"""Double-run determinism: compare the outputs of two runs of a command outside their timing columns.

``mmg-casadi simulate ... --check-determinism`` and ``mmg-casadi study NAME ... --check-determinism`` run the
command a second time into a temporary folder and compare what the two runs wrote with :func:`compare_outputs`:
every ``.csv``, ``.json`` and ``.toml`` file (byte for byte, as text, after leaving out the timing columns and
keys :data:`TIMING`) and every ``.npz`` file (array by array, bit for bit); figures (``.png``) and Markdown reports
are not compared. A table of runs (a CSV file with the columns :data:`RUN_KEY`, e.g. a study's ``runs.csv``, whose
rows are appended in the order the batches finish) is compared row by row matched on that key, not on the row
order. The first difference is reported and the command exits with status 1; identical outputs exit 0.

Examples
--------
>>> is_timing("guidance_call_us_mean"), is_timing("wall_s"), is_timing("ce")
(True, True, False)
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import numpy as np

TIMING = ("guidance_call_us", "wall_s", "elapsed_s")
"""Column and key names that measure the machine and the moment, not the runs: the guidance call time of the
Monte Carlo (:data:`mmg_casadi.montecarlo.execution.TIMING_COLUMNS`, also in the summaries as ``<name>_mean``,
``<name>_ci_low``, ...), the wall-clock time of a run of ``study encounters`` and of a whole study."""
COMPARED = (".csv", ".json", ".toml", ".npz")
"""File types compared; the others (figures, Markdown reports) are not."""
RUN_KEY = ("environment", "method", "run")
"""Columns that identify a row of a table of runs: such tables are compared row by row on this key."""


def is_timing(name: str) -> bool:
    """Whether a column or key ``name`` is a timing (one of :data:`TIMING`, or one followed by ``_suffix``).

    Parameters
    ----------
    name : str
        A CSV column or a JSON key.

    Returns
    -------
    bool
        True for a timing column or key.
    """
    return any(name == t or name.startswith(t + "_") for t in TIMING)


def _without_timing(value):
    """A JSON value with every timing key left out, recursively."""
    if isinstance(value, dict):
        return {k: _without_timing(v) for k, v in value.items() if not is_timing(k)}
    if isinstance(value, list):
        return [_without_timing(v) for v in value]
    return value


def _first_json_difference(a, b, where: str) -> str | None:
    """Where two JSON values first differ (a dotted path and both values), or None."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in list(a) + [k for k in b if k not in a]:
            if k not in a or k not in b:
                return f"{where}.{k}: only in the {'first' if k in a else 'second'} run"
            d = _first_json_difference(a[k], b[k], f"{where}.{k}")
            if d:
                return d
        return None
    if isinstance(a, list) and isinstance(b, list):
        for k, (x, y) in enumerate(zip(a, b)):
            d = _first_json_difference(x, y, f"{where}[{k}]")
            if d:
                return d
        return None if len(a) == len(b) else f"{where}: {len(a)} entries vs {len(b)}"
    same = json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
    return None if same else f"{where}: {json.dumps(a)[:80]} vs {json.dumps(b)[:80]}"


def _csv_rows(text: str) -> tuple[list[str], list[list[str]]]:
    """Header (timing columns left out) and rows of a CSV text."""
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return [], []
    keep = [k for k, name in enumerate(rows[0]) if not is_timing(name)]
    return [rows[0][k] for k in keep], [[r[k] if k < len(r) else "" for k in keep] for r in rows[1:]]


def compare_file(a: Path, b: Path, name: str) -> str | None:
    """The first difference between two output files of one name, or None if they agree outside the timings.

    Parameters
    ----------
    a, b : Path
        The first and the second run's file.
    name : str
        The file's path relative to the output folder (for the message).

    Returns
    -------
    str or None
        One line: the file, where it differs and both values.
    """
    suffix = a.suffix.lower()
    if suffix == ".npz":
        with np.load(a) as fa, np.load(b) as fb:
            for key in sorted(set(fa.files) | set(fb.files)):
                if key not in fa.files or key not in fb.files:
                    return f"{name}: array {key} only in the {'first' if key in fa.files else 'second'} run"
                x, y = fa[key], fb[key]
                if x.shape != y.shape or x.dtype != y.dtype:
                    return f"{name}: array {key} of {x.dtype} {x.shape} vs {y.dtype} {y.shape}"
                if x.tobytes() != y.tobytes():  # bit for bit (a NaN equals the same NaN)
                    bits = (np.ascontiguousarray(x).view(np.uint8).reshape(x.size, -1)
                            != np.ascontiguousarray(y).view(np.uint8).reshape(y.size, -1))
                    k = int(np.flatnonzero(bits.any(axis=1))[0])
                    at = tuple(int(v) for v in np.unravel_index(k, x.shape))
                    return f"{name}: array {key} entry {at}: {x.ravel()[k].item()!r} vs {y.ravel()[k].item()!r}"
        return None
    ta, tb = a.read_text(encoding="utf-8"), b.read_text(encoding="utf-8")
    if suffix == ".json":
        return _first_json_difference(_without_timing(json.loads(ta)), _without_timing(json.loads(tb)), name)
    if suffix == ".csv":
        (ha, ra), (hb, rb) = _csv_rows(ta), _csv_rows(tb)
        if ha != hb:
            return f"{name}: columns {ha} vs {hb}"
        if set(RUN_KEY) <= set(ha):
            return _keyed_difference(name, ha, ra, rb)
        for k, (x, y) in enumerate(zip(ra, rb)):
            for col, u, v in zip(ha, x, y):
                if u != v:
                    return f"{name} row {k + 1} column {col}: {u!r} vs {v!r}"
        return None if len(ra) == len(rb) else f"{name}: {len(ra)} rows vs {len(rb)}"
    if ta != tb:
        la, lb = ta.splitlines(), tb.splitlines()
        k = next((k for k, (u, v) in enumerate(zip(la, lb)) if u != v), min(len(la), len(lb)))
        return f"{name} line {k + 1}: {(la[k] if k < len(la) else '<end>')[:80]!r} vs " \
               f"{(lb[k] if k < len(lb) else '<end>')[:80]!r}"
    return None


def _keyed_difference(name: str, header: list[str], ra: list[list[str]], rb: list[list[str]]) -> str | None:
    """The first difference between two tables of runs matched on :data:`RUN_KEY` (the row order is free)."""
    at = [header.index(c) for c in RUN_KEY]

    def keyed(rows):
        out = {}
        for r in rows:
            key = tuple(r[k] if k < len(r) else "" for k in at)
            if key in out:
                return None, key
            out[key] = r
        return out, None

    (ka, dup_a), (kb, dup_b) = keyed(ra), keyed(rb)
    if dup_a or dup_b:
        which, key = ("first", dup_a) if dup_a else ("second", dup_b)
        return f"{name}: run {dict(zip(RUN_KEY, key))} twice in the {which} run"
    only = sorted(set(ka) ^ set(kb), key=_natural)
    if only:
        return f"{name}: run {dict(zip(RUN_KEY, only[0]))} only in the {'first' if only[0] in ka else 'second'} run"
    for key in sorted(ka, key=_natural):
        for col, u, v in zip(header, ka[key], kb[key]):
            if u != v:
                return f"{name} run {dict(zip(RUN_KEY, key))} column {col}: {u!r} vs {v!r}"
    return None


def _natural(key: tuple[str, ...]) -> tuple:
    """Sort key of a run key: numbers as numbers."""
    return tuple((0, int(k), "") if k.lstrip("-").isdigit() else (1, 0, k) for k in key)


def compare_outputs(first, second) -> tuple[str | None, int]:
    """Compare the output folders of two runs (:data:`COMPARED` files, recursively, timings left out).

    Parameters
    ----------
    first, second : str or Path
        The two runs' output folders.

    Returns
    -------
    (str or None, int)
        The first difference (one line; a file written by one run only counts) or None, and the number of files
        compared.
    """
    first, second = Path(first), Path(second)

    def files(d: Path) -> set[str]:
        return {p.relative_to(d).as_posix() for p in d.rglob("*") if p.is_file() and p.suffix.lower() in COMPARED}

    fa, fb = files(first), files(second)
    only = sorted(fa ^ fb)
    if only:
        return f"{only[0]}: written by the {'first' if only[0] in fa else 'second'} run only", len(fa & fb)
    for name in sorted(fa):
        d = compare_file(first / name, second / name, name)
        if d:
            return d, len(fa)
    return None, len(fa)
