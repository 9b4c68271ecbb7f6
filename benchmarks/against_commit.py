"""Monte Carlo throughput of this checkout against an earlier commit, side by side in one session.

The same workload — ``--runs`` runs of every (environment, method) cell, simulated the way each version's own
study does it (tasks of that version's ``DEFAULT_BATCH`` runs through its ``run_batch``) on one core — is timed in
fresh subprocesses for the current code (A) and for the code of ``--baseline`` (B, checked out with ``git
worktree`` into a temporary folder), alternately A B A B ... ``--repeats`` times after one warm-up each (which
also compiles both versions' closed loops into the shared cache). Prints per cell the median time of each and the
ratio B/A (the speed-up), the projected full study (5 000 runs per cell over ``--cores`` cores) for both, and
checks that both versions give the same success/failure per run.

Usage: ``python benchmarks/against_commit.py [--baseline 79ba6c0] [--runs 256] [--envs 1,5] [--repeats 3] [--params JSON]``

With ``--study ARGS`` it times the whole command ``mmg-casadi study statistics ARGS`` of both versions instead
(start-up, compilation or loading, the pool, the summary and figures included), each in a fresh process with
the version's own package first on ``PYTHONPATH``, in alternated pairs (current first, then baseline first, ...)
after one warm-up of each, and reports per version the median wall time, CPU time (user + system of the whole
process tree), the peak resident memory of its largest process (``ru_maxrss``, what ``/usr/bin/time`` reports)
and the peak of the whole tree's resident memory (sampled every 20 ms), with the ratios current / baseline. With
``--cold`` every run starts from an empty compile cache (``MMG_CASADI_CACHE``), so the compilation is timed too,
and there is no warm-up. Then ``import mmg_casadi`` is timed the same way (median of 11 alternated pairs).
The baseline may also be given as the first positional argument::

    python benchmarks/against_commit.py a728b36 --study "--runs 1000 --envs 1-5 --workers 2" [--cold]
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
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


def _tree_rss(root: int) -> int:
    """Resident bytes of ``root`` and all its descendants (Linux ``/proc``)."""
    kids: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            kids.setdefault(int(stat[stat.rindex(")") + 2:].split()[1]), []).append(int(entry.name))
    total, todo, page = 0, [root], os.sysconf("SC_PAGE_SIZE")
    while todo:
        pid = todo.pop()
        try:
            total += int(Path(f"/proc/{pid}/statm").read_text().split()[1]) * page
        except (OSError, IndexError, ValueError):
            pass
        todo += kids.get(pid, [])
    return total


def _run_study(path: Path, args: list[str], cache: str | None) -> dict:
    """One ``study statistics`` of the version at ``path``: wall, CPU, largest process's peak RSS, tree peak."""
    out = Path(tempfile.mkdtemp(prefix="study-"))
    env = {**os.environ, "PYTHONPATH": str(path)}
    if cache is not None:
        env["MMG_CASADI_CACHE"] = cache
    t0 = time.perf_counter()
    proc = subprocess.Popen([sys.executable, "-m", "mmg_casadi.cli", "study", "statistics", *args, "--out",
                             str(out / "o")], cwd=path, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    peak = 0
    while True:
        pid, status, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid:
            break
        peak = max(peak, _tree_rss(proc.pid))
        time.sleep(0.02)
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    err = proc.stderr.read().decode(errors="replace")
    shutil.rmtree(out, ignore_errors=True)
    if proc.returncode != 0:
        raise RuntimeError(f"study of {path} failed ({proc.returncode}): {err[-2000:]}")
    # on Linux wait4 reports the process with its waited-for descendants (the pool, the compilers): CPU summed,
    # ru_maxrss the largest of them
    return {"wall": wall, "cpu": usage.ru_utime + usage.ru_stime, "maxrss_mib": usage.ru_maxrss / 1024.0,
            "tree_peak_mib": peak / 2**20}


def _study_main(a, base: Path) -> None:
    args = shlex.split(a.study)
    versions = (("current", ROOT), ("baseline", base))
    cache = None
    results: dict[str, list[dict]] = {"current": [], "baseline": []}
    if not a.cold:
        for _name, path in versions:  # warm-up: fills the (shared) compile cache with both versions' libraries
            _run_study(path, args, None)
    for k in range(a.repeats):
        order = versions if k % 2 == 0 else versions[::-1]
        for name, path in order:
            if a.cold:
                cache = tempfile.mkdtemp(prefix="cold-cache-")
            r = _run_study(path, args, cache)
            if a.cold:
                shutil.rmtree(cache, ignore_errors=True)
            results[name].append(r)
            print(f"  pair {k + 1} {name:>8s}: wall {r['wall']:7.1f} s, cpu {r['cpu']:7.1f} s, largest process "
                  f"{r['maxrss_mib']:6.0f} MiB, tree peak {r['tree_peak_mib']:6.0f} MiB", flush=True)
    med = {n: {key: statistics.median(r[key] for r in rs) for key in rs[0]} for n, rs in results.items()}
    label = "cold (empty compile cache)" if a.cold else "warm (compiled libraries cached)"
    print(f"study statistics {a.study} -- {label}, median of {a.repeats} alternated pairs")
    for key, unit in (("wall", "s"), ("cpu", "s"), ("maxrss_mib", "MiB"), ("tree_peak_mib", "MiB")):
        c, b = med["current"][key], med["baseline"][key]
        print(f"  {key:>14s}: current {c:8.1f} {unit:3s}  baseline {a.baseline} {b:8.1f} {unit:3s}  "
              f"ratio current/baseline {c / b:5.3f}")
    times = {"current": [], "baseline": []}
    for k in range(11):
        for name, path in versions if k % 2 == 0 else versions[::-1]:
            env = {**os.environ, "PYTHONPATH": str(path)}
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-c", "import mmg_casadi"], cwd=path, env=env, check=True)
            times[name].append(time.perf_counter() - t0)
    c, b = (statistics.median(times[n]) for n in ("current", "baseline"))
    print(f"  import mmg_casadi: current {c:.3f} s  baseline {b:.3f} s  ratio {c / b:5.3f} (median of 11 pairs)")


def _hms(seconds: float) -> str:
    m, s = divmod(int(round(seconds)), 60)
    return f"{m} min {s:02d} s"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("commit", nargs="?", default=None, help="commit to compare against (same as --baseline)")
    ap.add_argument("--baseline", default="79ba6c0", help="commit to compare against (default: before the "
                    "performance work)")
    ap.add_argument("--study", default=None, metavar="ARGS", help="time `study statistics ARGS` of both versions "
                    "(module notes), e.g. \"--runs 1000 --envs 1-5 --workers 2\"")
    ap.add_argument("--cold", action="store_true", help="with --study: every run from an empty compile cache")
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
    if a.commit:
        a.baseline = a.commit
    if a.cold and not a.study:
        ap.error("--cold only with --study")
    envs = [int(e) for e in a.envs.split(",")]
    methods = [m for m in a.methods.split(",") if m]
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp) / "baseline"
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(base), a.baseline], check=True,
                       capture_output=True)
        try:
            if a.study:
                _study_main(a, base)
                return 0
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
