"""What sb-mpc costs in a Monte Carlo study: the wall time of ``study statistics --runs N --envs 5`` with sb-mpc
(every ship planning) against colregs-vortex's, both measured in this one run.

Each method runs the whole statistics study (:func:`mmg_casadi.montecarlo.study.run_study`: simulation, scoring
under the three profiles, summaries and figures) into its own temporary directory, one after the other, on the same
local process pool size; the compiled closed loops are built or loaded first and not timed. Prints both wall times
and their ratio, the target of issue 42 being at most 5. A ratio is only meaningful against a baseline measured in the
same run: the machine's load moves both times together.

Usage: ``python benchmarks/sb_mpc_cost.py [--runs 1000] [--workers 2] [--methods colregs-vortex,sb-mpc]``
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from mmg_casadi.montecarlo.batching import prepare_layouts
from mmg_casadi.montecarlo.execution import layout_for
from mmg_casadi.montecarlo.study import run_study

TARGET = 5.0
"""Largest ratio of sb-mpc's study time to colregs-vortex's that issue 42 accepts."""


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1000, help="runs of environment 5 per method")
    ap.add_argument("--workers", type=int, default=2, help="local worker processes")
    ap.add_argument("--methods", default="colregs-vortex,sb-mpc", help="baseline first, then the planner")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args(argv)
    methods = [m.strip() for m in a.methods.split(",") if m.strip()]
    prepare_layouts([layout_for(5, m) for m in methods], a.workers, log=sys.stderr)
    wall = {}
    with tempfile.TemporaryDirectory() as tmp:
        for m in methods:
            t = time.perf_counter()
            run_study(Path(tmp) / m, runs=a.runs, envs=(5,), methods=(m,), base_seed=a.seed, workers=a.workers,
                      progress=False)
            wall[m] = time.perf_counter() - t
            print(f"  {m:>16s}: {a.runs} runs of environment 5 in {wall[m]:8.1f} s", file=sys.stderr, flush=True)
    base = wall[methods[0]]
    print(f"study statistics --runs {a.runs} --envs 5 --workers {a.workers}, wall time in one run")
    for m in methods:
        print(f"{m:>16s} {wall[m]:9.1f} s  {wall[m] / base:6.2f} x {methods[0]}")
    ratio = wall[methods[-1]] / base
    print(f"ratio {methods[-1]} / {methods[0]} = {ratio:.2f} (target <= {TARGET:g}): "
          f"{'met' if ratio <= TARGET else 'not met'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
