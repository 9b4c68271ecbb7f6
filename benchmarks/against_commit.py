"""Monte Carlo throughput of this checkout against an earlier commit, side by side in one session.

The same workload — ``--runs`` runs of every (environment, method) cell, simulated the way each version's own
study does it (tasks of that version's ``DEFAULT_BATCH`` runs through its ``run_batch``) on one core — is timed in
fresh subprocesses for the current code (A) and for the code of ``--baseline`` (B, checked out with ``git
worktree`` into a temporary folder), alternately A B A B ... ``--repeats`` times after one warm-up each (which
also compiles both versions' closed loops into the shared cache). Prints per cell the median time of each and the
ratio B/A (the speed-up), the projected full study (5 000 runs per cell over ``--cores`` cores) for both, and
checks that both versions give the same success/failure per run.

Usage: ``python benchmarks/against_commit.py [--baseline 79ba6c0] [--runs 256] [--envs 1,5] [--repeats 3] [--params JSON]``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PAPER_RUNS_PER_CELL = 5000

WORKLOAD = r"""
import inspect, json, sys, time
try:  # 0.3 layout (subpackages)
    from mmg_casadi.montecarlo.batching import DEFAULT_BATCH, prepare_layouts
    from mmg_casadi.montecarlo.execution import layout_for, run_batch
except ImportError:  # a baseline before the subpackages: the flat module
    from mmg_casadi.montecarlo import DEFAULT_BATCH, layout_for, prepare_layouts, run_batch
env, method, n, seed = int(sys.argv[1]), sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
params = json.loads(sys.argv[5])
kw = {"params": params} if "params" in inspect.signature(run_batch).parameters else {}
prepare_layouts([layout_for(env, method, **kw)], 1)
t0 = time.perf_counter()
rows = []
for s in range(0, n, DEFAULT_BATCH):
    rows += run_batch(env, method, range(s, min(n, s + DEFAULT_BATCH)), seed, **kw)
wall = time.perf_counter() - t0
print(json.dumps({"wall": wall, "outcomes": [[r["run"], bool(r["success"]), r["failure"]] for r in rows]}))
"""


def _run(path: Path, env: int, method: str, runs: int, seed: int, params: dict) -> dict:
    env_vars = {**os.environ, "PYTHONPATH": str(path)}
    out = subprocess.run([sys.executable, "-c", WORKLOAD, str(env), method, str(runs), str(seed),
                          json.dumps(params)], cwd=path,
                         env=env_vars, capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def _hms(seconds: float) -> str:
    m, s = divmod(int(round(seconds)), 60)
    return f"{m} min {s:02d} s"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", default="79ba6c0", help="commit to compare against (default: before the "
                    "performance work)")
    ap.add_argument("--runs", type=int, default=256, help="runs per cell and repeat")
    ap.add_argument("--envs", default="1,3,5", help="comma-separated environments")
    ap.add_argument("--methods", default="modified-vortex,inverse-square,velocity-obstacle")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--cores", type=int, default=os.cpu_count() or 1, help="cores of the projected full study")
    ap.add_argument("--params", default='{"vo_cone": "wide", "vo_hold": false}',
                    help="JSON parameter overrides for the current code (default: the velocity obstacle as the "
                    "baseline commit defined it, so both run the same algorithm)")
    a = ap.parse_args(argv)
    envs = [int(e) for e in a.envs.split(",")]
    methods = [m for m in a.methods.split(",") if m]
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "baseline"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(base), a.baseline], check=True,
                       capture_output=True)
        try:
            print(f"{'env':>3s} {'method':>18s} {'current [s]':>12s} {'baseline [s]':>13s} {'speed-up':>9s} "
                  f"{'same outcomes':>14s}")
            proj = {"current": 0.0, "baseline": 0.0}
            for e in envs:
                for m in methods:
                    times = {"current": [], "baseline": []}
                    outcomes = {}
                    for k in range(a.repeats + 1):
                        for name, path in (("current", ROOT), ("baseline", base)):
                            r = _run(path, e, m, a.runs, a.seed, json.loads(a.params) if name == "current" else {})
                            if k:
                                times[name].append(r["wall"])
                            outcomes[name] = r["outcomes"]
                    med = {n: statistics.median(t) for n, t in times.items()}
                    same = outcomes["current"] == outcomes["baseline"]
                    for n in proj:
                        proj[n] += med[n] / a.runs * PAPER_RUNS_PER_CELL / a.cores
                    print(f"{e:3d} {m:>18s} {med['current']:12.2f} {med['baseline']:13.2f} "
                          f"{med['baseline'] / med['current']:9.2f} {str(same):>14s}", flush=True)
            scale = 5 / len(envs) * 3 / len(methods)
            print(f"Projected full study (5 x 3 x {PAPER_RUNS_PER_CELL} runs, {a.cores} cores, scaled from the "
                  f"cells above): current {_hms(proj['current'] * scale)}, baseline {a.baseline} "
                  f"{_hms(proj['baseline'] * scale)}")
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base)], check=False,
                           capture_output=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
