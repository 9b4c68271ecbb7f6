"""A study survives termination signals and lost workers: nothing orphaned, nothing lost, nothing counted twice.

The CLI runs in a subprocess in its own session (so its process group holds exactly the study and its pool
workers); environment 1 with the inverse-square APF (the lightest cell, a few seconds for a few hundred runs).
"""

from __future__ import annotations

import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import casadi as ca
import pytest

from mmg_casadi.compiled import BUILD_PREFIX, compile_function, library_is_complete, library_path
from mmg_casadi.errors import RunError
from mmg_casadi.montecarlo.batching import RAY_MAX_RETRIES, BatchTask, LocalExecutor, RayExecutor
from mmg_casadi.montecarlo.execution import TIMING_COLUMNS, run_batch
from mmg_casadi.montecarlo.results import RUN_COLUMNS, ResultsTable
from mmg_casadi.signals import Terminated, exit_status, terminate_as_interrupt

METHOD = "inverse-square"
RUNS = 320  # 10 batches of 32: several seconds with 2 workers, so a signal lands mid-study
STUDY = ["study", "statistics", "--runs", str(RUNS), "--envs", "1", "--methods", METHOD, "--workers", "2"]


@pytest.fixture
def cli():
    """Start ``mmg-casadi ARGS`` in a new session; at teardown kill whatever is left of its process group."""
    started = []

    def start(args):
        proc = subprocess.Popen([sys.executable, "-m", "mmg_casadi.cli", *args], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True, start_new_session=True)
        started.append(proc)
        return proc

    yield start
    for proc in started:
        if _live_group_members(proc.pid):
            os.killpg(proc.pid, signal.SIGKILL)
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def _live_group_members(pgid: int) -> list[int]:
    """Pids of the processes of process group ``pgid`` that are not zombies (from /proc)."""
    out = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()  # after "pid (comm) ": state ppid pgrp ...
        if int(fields[2]) == pgid and fields[0] != "Z":
            out.append(int(entry.name))
    return out


def _wait_for_rows(path: Path, proc, timeout=120.0) -> int:
    """Wait until ``runs.csv`` holds at least one data row (the study is under way); return the row count."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        assert proc.poll() is None, proc.communicate()
        if path.exists():
            n = path.read_text().count("\n") - 1
            if n >= 1:
                return n
        time.sleep(0.02)
    raise AssertionError("the study wrote no row in time")


def _wait_gone(pgid: int, timeout: float) -> list[int]:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        left = _live_group_members(pgid)
        if not left:
            return []
        time.sleep(0.05)
    return _live_group_members(pgid)


def _comparable(rows):
    out = {}
    for r in rows:
        out[(r["environment"], r["method"], r["run"])] = {
            c: ("nan" if isinstance(r[c], float) and math.isnan(r[c]) else r[c])
            for c in RUN_COLUMNS if c not in TIMING_COLUMNS}
    return out


pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")


def test_terminate_as_interrupt_restores_handlers_and_ignores_repeats():
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Terminated) as err:
        with terminate_as_interrupt():
            try:
                os.kill(os.getpid(), signal.SIGHUP)
                time.sleep(1)
            finally:
                os.kill(os.getpid(), signal.SIGTERM)  # a second signal during the cleanup is ignored
                time.sleep(0.05)
    assert err.value.signum == signal.SIGHUP and exit_status(err.value) == 129
    assert signal.getsignal(signal.SIGTERM) is before


def test_pool_workers_stop_on_terminate_although_the_parent_handles_sigterm():
    # forked workers inherit the parent's handlers; without the initializer terminate() would only raise
    # inside the task and the worker would carry on
    with terminate_as_interrupt():
        ex = LocalExecutor(2)
        it = ex.run([BatchTask(1, METHOD, tuple(range(32 * k, 32 * k + 32))) for k in range(4)])
        next(it)
        it.close()  # the consumer stops: remaining workers are terminated and joined
    assert not [p for p in _live_group_members(os.getpgrp()) if p != os.getpid() and _is_child(p)]


def _is_child(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return int(stat[stat.rindex(")") + 2:].split()[1]) == os.getpid()


def test_sigterm_mid_study_keeps_rows_and_resumes_to_the_uninterrupted_rows(tmp_path, cli):
    out = tmp_path / "interrupted"
    proc = cli([*STUDY, "--out", str(out)])
    n_before = _wait_for_rows(out / "runs.csv", proc)
    proc.send_signal(signal.SIGTERM)
    _stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 143, stderr
    last = stderr.strip().splitlines()[-1]
    assert "SIGTERM" in last and "rerun" in last, stderr
    assert _wait_gone(proc.pid, 5.0) == []
    kept = ResultsTable(out / "runs.csv").read()
    assert n_before <= len(kept) < RUNS

    resumed = cli([*STUDY, "--out", str(out)])
    _o, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err
    rows = ResultsTable(out / "runs.csv").read()
    keys = [(r["environment"], r["method"], r["run"]) for r in rows]
    assert len(keys) == RUNS and len(set(keys)) == RUNS
    # the rows kept at the interruption are unchanged by the resume
    assert {k: v for k, v in _comparable(rows).items() if k in _comparable(kept)} == _comparable(kept)

    fresh = tmp_path / "fresh"
    full = cli([*STUDY, "--out", str(fresh)])
    _o, err = full.communicate(timeout=300)
    assert full.returncode == 0, err
    assert _comparable(rows) == _comparable(ResultsTable(fresh / "runs.csv").read())


def test_sighup_mid_study_exits_129_without_orphans(tmp_path, cli):
    out = tmp_path / "hup"
    proc = cli([*STUDY, "--out", str(out)])
    _wait_for_rows(out / "runs.csv", proc)
    proc.send_signal(signal.SIGHUP)
    _stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 129, stderr
    assert "SIGHUP" in stderr.strip().splitlines()[-1]
    assert _wait_gone(proc.pid, 5.0) == []


def test_sigkill_of_the_study_leaves_no_worker(tmp_path, cli):
    out = tmp_path / "killed"
    proc = cli([*STUDY, "--out", str(out)])
    _wait_for_rows(out / "runs.csv", proc)
    workers = [p for p in _live_group_members(proc.pid) if p != proc.pid]
    assert workers, "the study runs no pool worker"
    proc.kill()
    proc.communicate(timeout=30)
    assert _wait_gone(proc.pid, 5.0) == []


class _DiesOnFirstAttempt(BatchTask):
    """A batch whose worker process dies (SIGKILL) the first time it runs ``marker``'s batch."""

    marker: str = ""

    def __call__(self):
        if self.marker and not os.path.exists(self.marker):
            Path(self.marker).write_text(str(os.getpid()))
            os.kill(os.getpid(), signal.SIGKILL)
        return super().__call__()


def test_ray_worker_killed_mid_batch_loses_and_duplicates_no_run(tmp_path):
    ray = pytest.importorskip("ray")
    from ray import cloudpickle
    cloudpickle.register_pickle_by_value(sys.modules[__name__])  # the workers need not import this test file
    runs = list(range(12))
    tasks = [BatchTask(1, METHOD, tuple(runs[i:i + 4])) for i in range(0, len(runs), 4)]
    marker = tmp_path / "killed.pid"
    killer = _DiesOnFirstAttempt(1, METHOD, tasks[1].runs)
    object.__setattr__(killer, "marker", str(marker))
    tasks[1] = killer
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        table = ResultsTable(tmp_path / "runs.csv")
        with RayExecutor() as ex:
            for _task, rows in ex.run(tasks):
                table.append(rows)
    finally:
        ray.shutdown()
    assert marker.exists()  # a worker really died
    rows = table.read()
    keys = [r["run"] for r in rows]
    assert sorted(keys) == runs
    assert _comparable(rows) == _comparable(run_batch(1, METHOD, runs))


def test_sigterm_mid_ray_study_exits_143_without_orphans(tmp_path, cli):
    pytest.importorskip("ray")
    out = tmp_path / "ray"
    proc = cli([*STUDY, "--backend", "ray", "--out", str(out)])
    _wait_for_rows(out / "runs.csv", proc)
    proc.send_signal(signal.SIGTERM)
    _stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 143, stderr
    assert "SIGTERM" in stderr.strip().splitlines()[-1]
    assert _wait_gone(proc.pid, 10.0) == []


def _processes_naming(text: str) -> list[str]:
    """Names of the live processes whose command line contains ``text`` (from /proc)."""
    out = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes()
            stat = (entry / "stat").read_text()
            comm = (entry / "comm").read_text().strip()
        except OSError:
            continue
        if text.encode() in cmdline and stat[stat.rindex(")") + 2] != "Z":
            out.append(comm)
    return out


def _wait_until(condition, timeout: float) -> bool:
    t0 = time.monotonic()
    while not condition():
        if time.monotonic() - t0 > timeout:
            return False
        time.sleep(0.05)
    return True


def _fleet_scenario(path: Path, ships: int = 60) -> Path:
    subprocess.run([sys.executable, "-m", "mmg_casadi.cli", "traffic", str(ships), "--out", str(path)], check=True,
                   capture_output=True)
    return path


@pytest.mark.parametrize("where", ["pool", pytest.param("main", marks=pytest.mark.slow)])
@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_signal_during_the_first_compile_leaves_no_compiler_and_no_build_folder(tmp_path, cli, monkeypatch, sig,
                                                                                where):
    # an empty cache: the study compiles its closed loop in a forked pool worker ("pool"; the velocity obstacle
    # takes tens of seconds), `simulate` of a 60-ship scenario in the main process ("main"). The compiler and its
    # cc1 run under a watchdog in a process group of their own, in <cache>/.build-*; whatever kills the study,
    # they must be gone at once, the folder too (before: cc1 ran on for 12-70 s, the folder stayed)
    cache = tmp_path / "cache"
    monkeypatch.setenv("MMG_CASADI_CACHE", str(cache))
    if where == "pool":
        args = ["study", "statistics", "--runs", "1", "--envs", "1", "--methods", "velocity-obstacle", "--workers",
                "2"]
    else:
        args = ["simulate", str(_fleet_scenario(tmp_path / "fleet.toml"))]
    proc = cli([*args, "--out", str(tmp_path / "out")])
    assert _wait_until(lambda: "cc1" in _processes_naming(str(cache)) or proc.poll() is not None, 300)
    assert proc.poll() is None, proc.communicate()
    t_signal = time.monotonic()
    proc.send_signal(sig)
    _o, stderr = proc.communicate(timeout=60)
    assert proc.returncode == (143 if sig == signal.SIGTERM else -signal.SIGKILL), stderr
    assert time.monotonic() - t_signal < 10.0  # nobody waits for the compiler
    gone = _wait_until(lambda: not _processes_naming(str(cache)) and not any(p.is_dir() for p in cache.iterdir()),
                       5.0)
    assert gone, (_processes_naming(str(cache)), list(cache.iterdir()))
    assert not list(cache.glob("*.so"))  # the compile was stopped, not finished


@pytest.mark.parametrize("when,sig", [("loading", signal.SIGTERM), ("compiling", signal.SIGTERM),
                                      ("loading", signal.SIGINT)], ids=["loading", "compiling", "loading-SIGINT"])
def test_a_signal_while_a_fleet_scenario_starts_cold_prints_the_message(tmp_path, cli, monkeypatch, when, sig):
    # SIGTERM while the package loads (the first seconds, before the CLI's handlers are in place: the process
    # used to die at once with status 143 and no message; Ctrl-C gave an import traceback) or while the fleet
    # step compiles (a 20-ship scenario runs the fleet step, as 300 ships do): one line, 128 + signal, no
    # compiler, no build folder, no output
    scenario = _fleet_scenario(tmp_path / "fleet.toml", 20)
    cache = tmp_path / "cache"
    cache.mkdir()
    monkeypatch.setenv("MMG_CASADI_CACHE", str(cache))
    proc = cli(["simulate", str(scenario), "--out", str(tmp_path / "out")])
    if when == "loading":
        time.sleep(0.2)
    else:
        assert _wait_until(lambda: any(cache.glob(BUILD_PREFIX + "*")) or proc.poll() is not None, 120)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(sig)
    _o, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig, stderr
    lines = stderr.splitlines()
    if when != "loading":  # the compile notice, cut short
        assert lines[0] == "compiling fleet step for 20 ships (modified-vortex) … stopped", lines
        lines = lines[1:]
    assert lines == [f"mmg-casadi: interrupted by {signal.Signals(sig).name} (this command does not "
                     "resume: rerun it to start again)"]
    assert _wait_until(lambda: not _processes_naming(str(cache)), 5.0), _processes_naming(str(cache))
    assert not list(cache.iterdir()) and not (tmp_path / "out").exists()


@pytest.mark.parametrize("before", [{}, {"metrics.json": "old", "trajectory.csv": "old", "notes.txt": "mine"}],
                         ids=["new", "existing"])
def test_sigterm_while_simulate_writes_leaves_no_partial_file(tmp_path, monkeypatch, capsys, before):
    # a real SIGTERM arrives while the figure is being written (the trajectory files are written already): the
    # output directory is as before (absent, or its old files whole) and no staging folder is left
    import mmg_casadi.plotting
    from mmg_casadi.cli import main

    def figure(_res, path):
        Path(path).write_bytes(b"half a figure")
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(10)  # the handler raises here

    out = tmp_path / "out"
    for name, text in before.items():
        out.mkdir(exist_ok=True)
        (out / name).write_text(text)
    monkeypatch.setattr(mmg_casadi.plotting, "plot_scenario", figure)
    scenario = Path(__file__).resolve().parents[1] / "mmg_casadi" / "data" / "scenarios" / "head_on.toml"
    t0 = time.monotonic()
    assert main(["simulate", str(scenario), "--set", "t_max=20", "--out", str(out)]) == 143
    assert time.monotonic() - t0 < 60
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith("mmg-casadi: interrupted by SIGTERM")
    assert sorted(p.name for p in tmp_path.iterdir()) == (["out"] if before else [])
    if before:
        assert {p.name: p.read_text() for p in out.iterdir()} == before


def test_a_cut_short_cached_library_is_rebuilt_not_loaded(tmp_path, monkeypatch):
    monkeypatch.setenv("MMG_CASADI_CACHE", str(tmp_path))
    x = ca.SX.sym("x")
    f = ca.Function("cut_short_square", [x], [x**2 + 1])
    compile_function(f)
    so, _src = library_path(f)
    whole = so.read_bytes()
    for n in (0, 100, len(whole) // 2, len(whole) - 1):
        cut = tmp_path / "cut"
        cut.write_bytes(whole[:n])
        os.replace(cut, so)  # a new file: the loaded library keeps its own
        assert not library_is_complete(so)
        g = compile_function(f)
        assert so.read_bytes() == whole and library_is_complete(so)
        assert float(g(3.0)) == 10.0


def test_build_folders_of_dead_processes_are_removed_by_the_next_compile(tmp_path, monkeypatch):
    monkeypatch.setenv("MMG_CASADI_CACHE", str(tmp_path))
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    host = socket.gethostname()
    stale = tmp_path / f"{BUILD_PREFIX}{dead.pid}-0badc0de@{host}"
    live = tmp_path / f"{BUILD_PREFIX}{os.getpid()}-0badc0de@{host}"  # e.g. a concurrent compile of this process
    other_host = tmp_path / f"{BUILD_PREFIX}{dead.pid}-0badc0de@not-{host}"  # a shared cache: not ours to judge
    for d in (stale, live, other_host):
        d.mkdir()
        (d / "part.c").write_text("int x;")
    x = ca.SX.sym("x")
    compile_function(ca.Function("stale_sweep_square", [x], [x**2]))
    assert not stale.exists() and live.exists() and other_host.exists()


def test_reaper_kills_the_tree_it_guards_when_its_parent_is_killed(tmp_path):
    # a "driver" process starts a child that starts a grandchild, guards the child with start_reaper and is
    # killed with SIGKILL: both descendants must die at once
    pids = tmp_path / "pids"
    driver = subprocess.Popen([sys.executable, "-c", (
        "import subprocess, sys, time\n"
        "from mmg_casadi.signals import start_reaper\n"
        "child = subprocess.Popen([sys.executable, '-c', 'import subprocess, time; "
        "subprocess.Popen([\"sleep\", \"60\"]); time.sleep(60)'])\n"
        "start_reaper([child.pid])\n"
        "time.sleep(1.0)\n"
        f"open({str(pids)!r}, 'w').write(str(child.pid))\n"
        "time.sleep(60)\n")])
    try:
        assert _wait_until(lambda: pids.exists() and pids.read_text(), 30)
        child = int(pids.read_text())
        tree = [child, *_children(child)]
        assert len(tree) == 2
        driver.kill()
        driver.wait()
        assert _wait_until(lambda: not [p for p in tree if _alive(p)], 5.0)
    finally:
        driver.kill()
        driver.wait()


def _children(pid: int) -> list[int]:
    return [int(e.name) for e in Path("/proc").iterdir() if e.name.isdigit() and _ppid(int(e.name)) == pid]


def _ppid(pid: int):
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return int(stat[stat.rindex(")") + 2:].split()[1])


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rindex(")") + 2] != "Z"


class _AlwaysDies(BatchTask):
    """A batch whose worker process dies (SIGKILL) every time it runs it."""

    def __call__(self):
        os.kill(os.getpid(), signal.SIGKILL)


@pytest.mark.slow  # ~40 s on 2 busy cores: a local cluster and four worker starts
def test_ray_batch_lost_on_every_retry_ends_in_one_run_error_after_the_other_batches(tmp_path):
    pytest.importorskip("ray")
    from ray import cloudpickle
    cloudpickle.register_pickle_by_value(sys.modules[__name__])
    tasks = [BatchTask(1, METHOD, (0, 1)), _AlwaysDies(1, METHOD, (2, 3)), BatchTask(1, METHOD, (4, 5))]
    done = []
    with RayExecutor(num_cpus=2) as ex:  # its own local cluster: close() also stops the reaper
        with pytest.raises(RunError) as err:
            for task, rows in ex.run(tasks):
                done += [r["run"] for r in rows]
        reaper = ex._reaper
    assert sorted(done) == [0, 1, 4, 5]  # the other batches finished and were yielded
    msg = str(err.value)
    assert "\n" not in msg and "environment 1, inverse-square, runs 2-3" in msg and "WorkerCrashedError" in msg
    assert f"{RAY_MAX_RETRIES} retries" in msg and "rerun the same command" in msg
    assert reaper is not None and reaper.returncode == 0


def test_cli_prints_a_run_error_as_one_line_exit_1_and_keeps_the_finished_rows(tmp_path, monkeypatch, capsys):
    from mmg_casadi.cli import main
    from mmg_casadi.montecarlo import study

    class _LosesTheRest:
        def __init__(self, workers=None):
            self.parallelism = 1

        def run(self, tasks):
            first = min(tasks, key=lambda t: len(t.runs))
            yield first, first()
            raise RunError("backend ray: the batch of environment 1 was lost")

        def close(self):
            pass

    monkeypatch.setattr(study, "LocalExecutor", _LosesTheRest)
    out = tmp_path / "out"
    status = main(["study", "statistics", "--runs", "130", "--envs", "1", "--methods", METHOD, "--out", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 1
    assert err[-1] == "mmg-casadi: error: backend ray: the batch of environment 1 was lost"
    assert "Traceback" not in "\n".join(err)
    assert sorted(r["run"] for r in ResultsTable(out / "runs.csv").read()) == [128, 129]


@pytest.mark.slow
def test_sigkill_of_a_ray_study_leaves_no_ray_process(tmp_path, cli):
    # before: the dashboard and runtime-env agents of the local cluster lived on for 60-90 s after the driver
    pytest.importorskip("ray")
    out = tmp_path / "ray"
    proc = cli(["study", "statistics", "--runs", "3000", "--envs", "1", "--methods", METHOD, "--workers", "2",
                "--backend", "ray", "--out", str(out)])
    _wait_for_rows(out / "runs.csv", proc)
    time.sleep(1.0)  # the reaper has taken a snapshot of the running cluster
    tree, todo = [], [proc.pid]
    while todo:
        pid = todo.pop()
        tree.append(pid)
        todo += _children(pid)
    assert len(tree) >= 4, "the local Ray cluster runs no process"
    proc.kill()
    proc.communicate(timeout=30)
    assert _wait_until(lambda: not [p for p in tree if _alive(p)], 5.0), [
        Path(f"/proc/{p}/cmdline").read_bytes().split(b"\0")[0] for p in tree if _alive(p)]
