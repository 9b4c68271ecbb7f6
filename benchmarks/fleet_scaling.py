"""Fleet scaling: compile time, peak memory (compiler included) and run time per ship-step of the closed loop for
generated traffic of N ships at environment 5's density (:func:`mmg_casadi.montecarlo.sampling.sample_traffic`).

Each (N, method, step) cell runs in a fresh process with an empty cache, so the compile is cold and the peak
memory is that cell's own: the process's and its children's (gcc/cc1) largest resident set. The run time is
the rollout of 200 guidance steps after the compile, divided by ships × steps. Targets (issue "Traffic at the
scale of a busy strait"): compile <= 60 s and <= 2 GB at every N; the ship-step cost at N = 1000 within 3× of
N = 10 — the ratio is measured in the same run.

    python benchmarks/fleet_scaling.py                     # N = 10, 30, 100, 300, 1000; fleet step; two methods
    python benchmarks/fleet_scaling.py --sizes 10,30 --step unrolled   # the unrolled step, for the crossover
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import compiled_step, simulate
from mmg_casadi.montecarlo.sampling import sample_traffic
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.scenario import scenario_from_dict

STEPS = 200
METHODS = ("modified-vortex", "colregs-vortex")


def one(n: int, method: str, step: str) -> dict:
    """Compile and roll out one cell in this process (called in a fresh subprocess)."""
    dt = PARAMETERS["dt"].default
    sc = scenario_from_dict(sample_traffic(n, seed=0).to_scenario_dict(method=method, t_max=STEPS * dt))
    pr = build_problem(sc, {"fleet_from_ships": 2 if step == "fleet" else 10**6})
    t0 = time.perf_counter()
    compiled_step(pr.layout)
    t_compile = time.perf_counter() - t0
    t0 = time.perf_counter()
    tr = simulate(pr.layout, pr.x0, pr.p)
    t_run = time.perf_counter() - t0
    steps = len(tr.t) - 1
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    children = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
    return {"n": n, "method": method, "step": step, "compile_s": t_compile, "run_s": t_run, "steps": steps,
            "us_per_ship_step": 1e6 * t_run / (n * steps), "peak_mb": max(own, children),
            "python_mb": own, "compiler_mb": children, "overflows": tr.neighbour_overflows}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", default="10,30,100,300,1000")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--step", choices=("fleet", "unrolled"), default="fleet")
    ap.add_argument("--one", nargs=3, metavar=("N", "METHOD", "STEP"), help=argparse.SUPPRESS)
    ap.add_argument("--json", help="also write the rows to this file")
    args = ap.parse_args(argv)
    if args.one:
        print(json.dumps(one(int(args.one[0]), args.one[1], args.one[2])))
        return 0
    rows = []
    print(f"{'N':>5} {'method':>16} {'step':>8} {'compile s':>10} {'peak MB':>8} {'compiler MB':>11} "
          f"{'us/ship-step':>12} {'overflows':>9}")
    for method in args.methods.split(","):
        for n in (int(v) for v in args.sizes.split(",")):
            with tempfile.TemporaryDirectory() as cache:
                env = {**os.environ, "MMG_CASADI_CACHE": cache}
                out = subprocess.run([sys.executable, __file__, "--one", str(n), method, args.step], env=env,
                                     capture_output=True, text=True, check=True)
            r = json.loads(out.stdout.strip().splitlines()[-1])
            rows.append(r)
            print(f"{n:>5} {method:>16} {args.step:>8} {r['compile_s']:>10.1f} {r['peak_mb']:>8.0f} "
                  f"{r['compiler_mb']:>11.0f} {r['us_per_ship_step']:>12.1f} {r['overflows']:>9}", flush=True)
    for method in args.methods.split(","):
        cells = {r["n"]: r for r in rows if r["method"] == method}
        if len(cells) > 1:
            lo, hi = min(cells), max(cells)
            print(f"{method}: ship-step cost N={hi} / N={lo} = "
                  f"{cells[hi]['us_per_ship_step'] / cells[lo]['us_per_ship_step']:.2f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
