"""What one ``nmpc`` solve costs: every solve of some environment runs re-posed from their histories and solved
again (:mod:`mmg_casadi.closed_loop.nmpc_solves`): the compiled solver's wall and CPU time (median, 90th and
99th percentile), ``sqpmethod``'s iterations and return statuses, the share of solves the planner's failure test
rejects (the fallback), and the largest difference between the re-posed solution and the plan the closed loop
stored (the same generated code on the same inputs: 0 up to rounding).

The own ship plans with ``nmpc``; the targets use ``--targets`` (default colregs-vortex, as the issue-42 studies).
Wall times depend on the machine and its load: say both when quoting them.

Usage: ``python benchmarks/nmpc_solves.py [--env 5] [--runs 0-2] [--targets colregs-vortex] [--out DIR]``
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from mmg_casadi.montecarlo.execution import sampled_scenario
from mmg_casadi.closed_loop.nmpc_solves import solve_statistics, solves_of_run


def _runs(text: str) -> list[int]:
    lo, _, hi = text.partition("-")
    return list(range(int(lo), int(hi or lo) + 1))


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", type=int, default=5)
    ap.add_argument("--runs", default="0-2", help="run indices, e.g. 0-2")
    ap.add_argument("--targets", default="colregs-vortex")
    ap.add_argument("--out", default=None, help="folder for solves.json (summary) and solves.csv")
    a = ap.parse_args(argv)
    solves = []
    for r in _runs(a.runs):
        sc = sampled_scenario(a.env, "nmpc", r, params={"targets": a.targets})
        for s in solves_of_run(sc):
            solves.append({"run": r, **s})
    stats = {"env": a.env, "runs": a.runs, "targets": a.targets, "load_average": os.getloadavg()[0],
             "cpus": os.cpu_count(), **solve_statistics(solves)}
    print(json.dumps(stats, indent=1))
    if a.out:
        out = Path(a.out)
        out.mkdir(parents=True, exist_ok=True)
        (out / "solves.json").write_text(json.dumps(stats, indent=1) + "\n", encoding="utf-8")
        keys = ("run", "t", "time_us", "cpu_us", "iterations", "status", "failed", "f0", "f", "kkt")
        lines = [",".join(keys)] + [",".join(str(s[k]) for k in keys) for s in solves]
        (out / "solves.csv").write_text("\n".join(lines) + "\n", encoding="utf-8")
    return stats


if __name__ == "__main__":
    main()
