"""Throughput of the statistical study on this machine: runs/s of one batch per environment and method.

For every environment and method, :func:`mmg_casadi.montecarlo.execution.run_batch` simulates ``--runs`` random
encounters (32 by default) as one batch on one core, after a warm-up (compiling the closed loop once, loading
it, building the batched ``map``/``mapaccum`` Function). Prints runs/s per cell, the ratio to a baseline cell
measured in the same process (environment 1, modified-vortex), and the projected wall time of the full study
(5 environments × 3 methods × 5000 runs = 75 000 runs) with the local process pool over all cores, assuming
the rate scales with the number of cores (runs/s × cores).

The first run compiles the closed loops (the velocity obstacle with 10 ships and 4 obstacles takes several
minutes with gcc -O2); later runs load them from the cache (``$MMG_CASADI_CACHE`` or ``~/.cache/mmg-casadi``).

Usage: ``python benchmarks/statistics_throughput.py [--runs 32] [--envs 1-5] [--methods a,b] [--seed 0]``
"""

from __future__ import annotations

import argparse
import datetime
import os
import sys
import time

from mmg_casadi.montecarlo.batching import prepare_layouts
from mmg_casadi.montecarlo.execution import DEFAULT_CHUNK, layout_for, run_batch
from mmg_casadi.montecarlo.study import DEFAULT_METHODS
from mmg_casadi.montecarlo.sampling import parse_envs

PAPER_RUNS_PER_CELL = 5000
WARMUP_RUNS_OFFSET = 100_000  # warm-up runs are different scenarios from the timed ones


def _hms(seconds: float) -> str:
    return str(datetime.timedelta(seconds=int(round(seconds))))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=32, help="runs per timed batch")
    ap.add_argument("--envs", default="1-5")
    ap.add_argument("--methods", default=",".join(DEFAULT_METHODS))
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--chunk", type=int, default=DEFAULT_CHUNK)
    ap.add_argument("--cores", type=int, default=os.cpu_count() or 1, help="cores of the local pool")
    a = ap.parse_args(argv)
    envs = parse_envs(a.envs)
    methods = [m.strip() for m in a.methods.split(",") if m.strip()]
    baseline = (1, "modified-vortex")
    cells = [baseline] + [(e, m) for e in envs for m in methods if (e, m) != baseline]

    t0 = time.perf_counter()
    prepare_layouts([layout_for(e, m) for e, m in cells], a.cores, log=sys.stderr)
    print(f"compiled / loaded {len(cells)} closed loops in {time.perf_counter() - t0:.1f} s", file=sys.stderr)

    rates, success, busy = {}, {}, {}
    for e, m in cells:
        # warm-up: same batch size (builds the batched Function), one chunk of steps only
        run_batch(e, m, range(WARMUP_RUNS_OFFSET, WARMUP_RUNS_OFFSET + a.runs), a.seed, params={"t_max": 0.25 * a.chunk},
                  chunk=a.chunk)
        t = time.perf_counter()
        rows = run_batch(e, m, range(a.runs), a.seed, chunk=a.chunk)
        wall = time.perf_counter() - t
        rates[(e, m)] = a.runs / wall
        busy[(e, m)] = wall
        success[(e, m)] = sum(r["success"] for r in rows) / len(rows)
        print(f"  env {e} {m:>18s}: {a.runs} runs in {wall:6.2f} s", file=sys.stderr)

    base = rates[baseline]
    print(f"Statistics throughput, one core, batches of {a.runs} runs (chunk {a.chunk} steps)")
    print(f"{'env':>3s} {'method':>18s} {'runs/s':>9s} {'ratio':>7s} {'success':>8s} "
          f"{f'{PAPER_RUNS_PER_CELL} runs, {a.cores} cores':>22s}")
    total = 0.0
    for e in envs:
        for m in methods:
            r = rates[(e, m)]
            cell_time = PAPER_RUNS_PER_CELL / (r * a.cores)
            total += cell_time
            print(f"{e:3d} {m:>18s} {r:9.2f} {r / base:7.3f} {100 * success[(e, m)]:7.1f}% {_hms(cell_time):>22s}")
    n_total = PAPER_RUNS_PER_CELL * len(envs) * len(methods)
    print(f"Projected full study ({n_total} runs) with the local pool over {a.cores} cores: {_hms(total)} "
          f"(baseline env {baseline[0]} {baseline[1]}: {base:.1f} runs/s per core)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
