"""The own ship's tallies in a statistical study: ``tallies.csv`` beside ``runs.csv`` and their summary.

A method may count events over a run in its memory (``Method.tallies``, e.g. ``nmpc``'s solves and fallbacks). A
study of such a method appends, per run, the own ship's counts to ``tallies.csv`` (columns ``environment, method,
run`` and one per tally) as its batches finish, before the run's row of ``runs.csv``; a study without such a method
writes no such file. A resumed study may append a run's counts twice (interrupted between the two appends): the
reader keeps the last. :func:`summarize` gives per (environment, method) the runs, the sum of each tally and, for
``nmpc``, the share of solves that failed.

Examples
--------
>>> import tempfile, pathlib
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> t = TallyTable(d / "tallies.csv")
>>> t.append([{"environment": 5, "method": "nmpc", "run": 0, "tallies": {"nmpc_solves": 10.0,
...                                                                    "nmpc_fallbacks": 1.0}}])
1
>>> summarize(t.read())[0]["nmpc_fallbacks"], summarize(t.read())[0]["fallback_rate"]
(1.0, 0.1)
"""

from __future__ import annotations

import csv
import os
from pathlib import Path

from mmg_casadi.montecarlo.results import TALLIES_KEY

KEYS = ("environment", "method", "run")
"""Columns that identify a run."""


class TallyTable:
    """The append-only ``tallies.csv`` of a study (module notes).

    Parameters
    ----------
    path : str or Path
        The file.
    """

    def __init__(self, path):
        self.path = Path(path)

    def append(self, rows) -> int:
        """Append the tallies of the rows that carry some (the key :data:`~mmg_casadi.montecarlo.results.TALLIES_KEY`).

        Parameters
        ----------
        rows : iterable of dict
            Rows of a batch (the columns of ``runs.csv`` and, for a method with tallies, ``tallies``).

        Returns
        -------
        int
            Lines written.
        """
        lines = [(r, r[TALLIES_KEY]) for r in rows if r.get(TALLIES_KEY)]
        if not lines:
            return 0
        new = not self.path.exists() or self.path.stat().st_size == 0
        if new:
            names = sorted({k for _, t in lines for k in t})
        else:  # the columns of the first write (a study's tallies are fixed by its methods)
            with open(self.path, newline="", encoding="utf-8") as fh:
                names = [c for c in next(csv.reader(fh), []) if c not in KEYS]
        with open(self.path, "a", newline="", encoding="utf-8") as fh:
            w = csv.writer(fh)
            if new:
                w.writerow([*KEYS, *names])
            for r, t in lines:
                w.writerow([r["environment"], r["method"], r["run"], *(repr(float(t.get(k, 0.0))) for k in names)])
            fh.flush()
            os.fsync(fh.fileno())
        return len(lines)

    def read(self) -> list[dict]:
        """The stored rows, the last one of each run (a resumed batch may have appended a run twice).

        Returns
        -------
        list of dict
            ``environment`` (int), ``method``, ``run`` (int) and one float per tally.
        """
        if not self.path.exists():
            return []
        out = {}
        with open(self.path, newline="", encoding="utf-8") as fh:
            for row in csv.DictReader(fh):
                if None in row or any(v in (None, "") for v in row.values()):
                    continue  # a line cut short by an interrupted write
                key = (int(row["environment"]), row["method"], int(row["run"]))
                out[key] = {"environment": key[0], "method": key[1], "run": key[2],
                            **{k: float(v) for k, v in row.items() if k not in KEYS}}
        return list(out.values())


def summarize(rows) -> list[dict]:
    """Per (environment, method): runs, the sum of every tally and, with ``nmpc_solves`` and ``nmpc_fallbacks``,
    ``fallback_rate`` (fallbacks per solve) and ``runs_with_fallback``.

    Parameters
    ----------
    rows : iterable of dict
        Rows of :meth:`TallyTable.read`.

    Returns
    -------
    list of dict
        One per cell, in the order of first appearance.
    """
    cells: dict = {}
    for r in rows:
        c = cells.setdefault((r["environment"], r["method"]), {"environment": r["environment"],
                                                                "method": r["method"], "runs": 0})
        c["runs"] += 1
        for k, v in r.items():
            if k not in KEYS:
                c[k] = c.get(k, 0.0) + v
        if r.get("nmpc_fallbacks", 0) > 0:
            c["runs_with_fallback"] = c.get("runs_with_fallback", 0) + 1
    out = list(cells.values())
    for c in out:
        if "nmpc_solves" in c:
            c["fallback_rate"] = c.get("nmpc_fallbacks", 0.0) / c["nmpc_solves"] if c["nmpc_solves"] else 0.0
            c.setdefault("runs_with_fallback", 0)
    return out


def to_markdown(summary) -> str:
    """The summary as a Markdown table.

    Parameters
    ----------
    summary : list of dict
        :func:`summarize`'s rows.

    Returns
    -------
    str
        The table (empty for no rows).
    """
    if not summary:
        return ""
    cols = list(dict.fromkeys(k for c in summary for k in c))
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for c in summary:
        lines.append("| " + " | ".join(f"{c.get(k, ''):.4g}" if isinstance(c.get(k), float) else str(c.get(k, ''))
                                       for k in cols) + " |")
    return "\n".join(lines)
