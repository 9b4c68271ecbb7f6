"""Summaries of one slice of a statistics study's runs (issue 42: design runs 0-999, held-out runs from 1000).

Reads a study directory's ``runs.csv`` and ``runs.params.json``, keeps the runs with ``first <= run < stop``,
and writes what ``study statistics`` writes for them (the same library functions): ``summary.csv``,
``comparisons.csv`` (paired, exact McNemar), ``colregs.csv``, ``colregs_comparisons.csv`` and ``summary.md``.

Usage: ``python docs/results/issue42/summarize.py STUDY_DIR OUT_DIR [--runs FIRST-STOP] [--methods a,b,c]``
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from mmg_casadi.montecarlo import encounter_summary
from mmg_casadi.montecarlo.comparisons import compare_methods, to_markdown, write_csv
from mmg_casadi.montecarlo.execution import profile_columns
from mmg_casadi.montecarlo.results import ResultsTable, summarize


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("study")
    ap.add_argument("out")
    ap.add_argument("--runs", default="0-1000000", help="FIRST-STOP: runs FIRST <= run < STOP")
    ap.add_argument("--methods", default="", help="methods in this order (default: as in runs.csv)")
    a = ap.parse_args(argv)
    first, stop = (int(v) for v in a.runs.split("-"))
    study, out = Path(a.study), Path(a.out)
    params = json.loads((study / "runs.params.json").read_text())["params"]
    rows = [r for r in ResultsTable(study / "runs.csv").read() if first <= r["run"] < stop]
    methods = [m for m in a.methods.split(",") if m] or list(dict.fromkeys(r["method"] for r in rows))
    order = {m: i for i, m in enumerate(methods)}
    rows = [r for r in rows if r["method"] in order]
    rows.sort(key=lambda r: (r["environment"], order[r["method"]], r["run"]))
    out.mkdir(parents=True, exist_ok=True)
    summary = summarize(rows)
    summary.to_csv(out / "summary.csv")
    comparisons = compare_methods(rows, methods)
    write_csv(comparisons, out / "comparisons.csv")
    columns = profile_columns(params)
    by_encounter = encounter_summary.summarize_profiles(rows, columns)
    pairs = encounter_summary.compare_profiles(rows, columns, methods)
    encounter_summary.write_csv(by_encounter, out / "colregs.csv", encounter_summary.ENCOUNTER_COLUMNS)
    encounter_summary.write_csv(pairs, out / "colregs_comparisons.csv", encounter_summary.PAIR_COLUMNS)
    (out / "summary.md").write_text(
        f"Runs {first} to {min(stop, 1 + max(r['run'] for r in rows)) - 1} of {study.name}.\n\n"
        + summary.to_markdown() + "\n\n## Failure mechanisms (own ship)\n\n" + summary.failures_markdown()
        + "\n\n## Paired comparisons (same runs; exact McNemar test)\n\n" + to_markdown(comparisons)
        + "\n\n## COLREG encounters with a risk of collision (own ship; profile " + ", ".join(columns) + ")\n\n"
        + encounter_summary.to_markdown(by_encounter, pairs) + "\n", encoding="utf-8")
    print(f"{len(rows)} runs -> {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
