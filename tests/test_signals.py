"""A study survives termination signals and lost workers: nothing orphaned, nothing lost, nothing counted twice.

The CLI runs in a subprocess in its own session (so its process group holds exactly the study and its pool
workers); environment 1 with the inverse-square APF (the lightest cell, a few seconds for a few hundred runs).
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mmg_casadi.montecarlo.batching import BatchTask, LocalExecutor, RayExecutor
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


def _group_commands(pgid: int) -> list[str]:
    out = []
    for pid in _live_group_members(pgid):
        try:
            out.append(Path(f"/proc/{pid}/comm").read_text().strip())
        except OSError:
            pass
    return out


@pytest.mark.slow
def test_sigterm_during_the_first_compile_does_not_wait_for_the_compiler(tmp_path, cli, monkeypatch):
    # a fresh cache: the study first compiles its closed loop in a process pool (tens of seconds for the
    # velocity obstacle); SIGTERM must stop the pool at once instead of waiting for the compile to finish
    monkeypatch.setenv("MMG_CASADI_CACHE", str(tmp_path / "cache"))
    study = ["study", "statistics", "--runs", "1", "--envs", "1", "--methods", "velocity-obstacle",
             "--workers", "2", "--out", str(tmp_path / "out")]
    proc = cli(study)
    t0 = time.monotonic()
    while "cc1" not in _group_commands(proc.pid):
        assert proc.poll() is None and time.monotonic() - t0 < 300, "no compiler started"
        time.sleep(0.05)
    t_signal = time.monotonic()
    proc.send_signal(signal.SIGTERM)
    _o, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 143, stderr
    assert time.monotonic() - t_signal < 10.0
    # the pool workers are gone; the C compilers they started finish their file on their own
    assert not [c for c in _group_commands(proc.pid) if c.startswith("python")]
