"""Share of the COLREG encounter scorer in a statistics study's time, per method, measured in the same batch.

For every environment and method, :func:`mmg_casadi.montecarlo.execution.run_batch` simulates ``--runs`` random
encounters as one batch on one core, after a warm-up batch; the time spent in
:func:`mmg_casadi.montecarlo.execution.own_ship_encounters` (the scorer on the run's decimated history, under the
study's profile, ``published``; with ``--all-profiles`` under all three, as ``--set colregs_all_profiles=true``
makes a study do) is measured inside that batch and reported as a share of the batch's time. Both are CPU times of this process
(:func:`time.process_time`; the batch runs on one core), so other work on the machine does not bend the ratio.
The target of the encounter scorer is a share of at most 10 % of the environment's study, i.e. of the
summed time of the methods' batches (each method runs the same runs); the per-method shares are printed beside it.

Usage: ``python benchmarks/colregs_scoring.py [--runs 200] [--envs 1-5] [--methods a,b] [--repeats 3]
[--all-profiles]``
"""

from __future__ import annotations

import argparse
import sys
import time

from mmg_casadi.montecarlo import execution
from mmg_casadi.montecarlo.batching import prepare_layouts
from mmg_casadi.montecarlo.sampling import parse_envs
from mmg_casadi.montecarlo.study import DEFAULT_METHODS

TARGET_SHARE = 0.10
WARMUP_RUNS_OFFSET = 100_000


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=200, help="runs per batch")
    ap.add_argument("--envs", default="1-5", help="environments, e.g. 1-5 or 5")
    ap.add_argument("--methods", default=",".join(DEFAULT_METHODS))
    ap.add_argument("--repeats", type=int, default=3, help="timed batches per cell (the median is reported)")
    ap.add_argument("--all-profiles", action="store_true", help="score every profile (colregs_all_profiles)")
    a = ap.parse_args(argv)
    params = {"colregs_all_profiles": True} if a.all_profiles else None
    methods = [m.strip() for m in a.methods.split(",") if m.strip()]
    envs = parse_envs(a.envs)
    prepare_layouts([execution.layout_for(e, m) for e in envs for m in methods], 1, log=sys.stderr)

    spent = [0.0]
    scorer = execution.own_ship_encounters

    def timed(*args, **kwargs):
        t = time.process_time()
        try:
            return scorer(*args, **kwargs)
        finally:
            spent[0] += time.process_time() - t

    execution.own_ship_encounters = timed
    total_batch = total_score = 0.0
    print(f"COLREG scorer share of a batch of {a.runs} runs, one core (median of {a.repeats}); "
          + ("every profile scored" if a.all_profiles else "the study's profile scored"))
    print(f"{'env':>4s} {'method':>18s} {'batch CPU [s]':>14s} {'scorer CPU [s]':>15s} {'share':>7s} {'ms/run':>7s}")
    for env in envs:
        for m in methods:
            execution.run_batch(env, m, range(WARMUP_RUNS_OFFSET, WARMUP_RUNS_OFFSET + 8), params=params)
            samples = []
            for _ in range(a.repeats):
                spent[0] = 0.0
                t = time.process_time()
                execution.run_batch(env, m, range(a.runs), params=params)
                samples.append((time.process_time() - t, spent[0]))
            wall, score = sorted(samples, key=lambda s: s[1] / s[0])[len(samples) // 2]
            total_batch, total_score = total_batch + wall, total_score + score
            print(f"{env:>4d} {m:>18s} {wall:14.2f} {score:15.2f} {100 * score / wall:6.1f}% "
                  f"{1e3 * score / a.runs:7.2f}")
    share = total_score / total_batch
    print(f"study (all cells): scorer {total_score:.2f} s of {total_batch:.2f} s CPU = {100 * share:.1f} % "
          f"(target <= {100 * TARGET_SHARE:.0f} %): " + ("met" if share <= TARGET_SHARE else "NOT met"))
    return 0 if share <= TARGET_SHARE else 1


if __name__ == "__main__":
    sys.exit(main())
