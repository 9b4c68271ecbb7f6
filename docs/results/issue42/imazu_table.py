"""Per-case table of a ``study imazu`` run (issue 42): ``summary.csv`` with one row per (targets, method, case) and
``totals.csv`` per (targets, method): safe cases, risky encounters kept, cases with no rule broken.

Usage: ``python docs/results/issue42/imazu_table.py STUDY_DIR/metrics.json OUT_DIR``
"""

from __future__ import annotations

import csv
import json
import sys
from pathlib import Path


def main(argv=None) -> int:
    src, out = (argv or sys.argv[1:])[:2]
    results = json.loads(Path(src).read_text())["results"]
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rows, totals = [], []
    for targets, by_method in results.items():
        for method, res in by_method.items():
            for case in res["cases"]:
                risky = [e for e in case["encounters"] if e["applicable"]]
                broken = [e for e in risky if not e["compliant"]]
                rows.append({"targets": targets, "method": method, "case": case["case"], "safe": case["safe"],
                             "min_distance": round(case["min_distance"], 3), "risky": len(risky),
                             "kept": len(risky) - len(broken), "no_rule_broken": not broken})
            mine = [r for r in rows if r["targets"] == targets and r["method"] == method]
            totals.append({"targets": targets, "method": method, "cases": len(mine),
                           "safe": sum(r["safe"] for r in mine), "risky": sum(r["risky"] for r in mine),
                           "kept": sum(r["kept"] for r in mine),
                           "no_rule_broken": sum(r["no_rule_broken"] for r in mine),
                           "all_kept_with_risk": sum(r["no_rule_broken"] and r["risky"] > 0 for r in mine)})
    for name, table in (("summary.csv", rows), ("totals.csv", totals)):
        with open(out / name, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=list(table[0]))
            w.writeheader()
            w.writerows(table)
    return 0


if __name__ == "__main__":
    sys.exit(main())
