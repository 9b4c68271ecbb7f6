"""Any number of signals at any moment: one line, the documented exit status, and outputs old or complete new.

* Repeated Ctrl-C (3-5 SIGINTs 30-150 ms apart to the study's process group, as a terminal sends them) while the
  package loads, while the study runs and while it writes its final files: exactly one line on stderr besides the
  progress bar, status 130, never a traceback (before: "Exception ignored ... stop_pool ... KeyboardInterrupt").
* A signal at any point of a study's final writes leaves every final file either as it was or complete and new
  (before: statistics.png cut to 124 bytes, metrics.json and failures/ missing).
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="POSIX signals, /proc")

STUDY = ["study", "statistics", "--envs", "1", "--methods", "inverse-square", "--workers", "2"]
FINAL = ("summary.csv", "comparisons.csv", "colregs.csv", "colregs_comparisons.csv", "summary.md",
         "statistics.png", "metrics.json")


def _start(args):
    return subprocess.Popen([sys.executable, "-m", "mmg_casadi.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def _burst(pgid: int, n: int, rng: random.Random) -> None:
    """``n`` SIGINTs to the process group, 30-150 ms apart (a user pressing Ctrl-C again and again)."""
    for _ in range(n):
        try:
            os.killpg(pgid, signal.SIGINT)
        except ProcessLookupError:
            return
        time.sleep(rng.uniform(0.03, 0.15))


def _wait(condition, proc, timeout=120.0) -> bool:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if condition():
            return True
        if proc.poll() is not None:
            return False
        time.sleep(0.01)
    return False


def _rows(path: Path) -> int:
    try:
        return max(0, path.read_text().count("\n") - 1)
    except OSError:
        return 0


@pytest.mark.parametrize("moment,seed", [("loading", 1), ("running", 2), ("writing", 3),
                                         pytest.param("loading", 4, marks=pytest.mark.slow),
                                         pytest.param("running", 5, marks=pytest.mark.slow),
                                         pytest.param("writing", 6, marks=pytest.mark.slow),
                                         pytest.param("writing", 7, marks=pytest.mark.slow)])
def test_repeated_ctrl_c_prints_one_line_and_exits_130(tmp_path, moment, seed):
    rng = random.Random(seed)
    out = tmp_path / "out"
    runs = 64 if moment != "writing" else 32
    proc = _start([*STUDY, "--runs", str(runs), "--out", str(out)])
    try:
        if moment == "loading":
            time.sleep(rng.uniform(0.15, 0.4))
        elif moment == "running":
            assert _wait(lambda: _rows(out / "runs.csv") >= 1, proc), proc.communicate()
        else:  # every row is in: the summary and the final files are being made
            assert _wait(lambda: _rows(out / "runs.csv") >= runs, proc), proc.communicate()
            time.sleep(rng.uniform(0.0, 0.3))
        _burst(proc.pid, rng.randint(3, 5), rng)
        _o, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert "Traceback" not in stderr and "Exception ignored" not in stderr, stderr
    ours = [line for line in stderr.splitlines() if line.startswith("mmg-casadi")]
    if moment == "writing" and proc.returncode == 0:  # it finished before the first signal: no line at all
        assert ours == [], stderr
        return
    assert proc.returncode == 130, stderr
    assert ours == ["mmg-casadi: interrupted by SIGINT (finished results are kept; rerun the same command to "
                    "resume)"], stderr
    assert stderr.rstrip().splitlines()[-1] == ours[0]


# ------------------------------------------------------------------------------ final writes: old or new

def _snapshot(out: Path) -> dict[str, bytes]:
    files = [out / n for n in FINAL] + sorted((out / "failures").glob("*.toml"))
    return {p.relative_to(out).as_posix(): p.read_bytes() for p in files if p.exists()}


def _complete(name: str, data: bytes, runs: int) -> bool:
    """Whether ``data`` is a whole file of a summary of ``runs`` runs."""
    if name.endswith(".png"):
        import matplotlib.image
        import io
        try:
            matplotlib.image.imread(io.BytesIO(data), format="png")
        except Exception:  # noqa: BLE001 - any decoding failure is a cut file
            return False
        return data.endswith(b"IEND\xaeB`\x82")
    text = data.decode("utf-8")
    if name.endswith(".json"):
        return json.loads(text)["runs_total"] == runs
    if name == "summary.csv":
        return text.endswith("\n") and text.count("\n") == 2 and f",{runs}," in text.splitlines()[1]
    if name.endswith(".toml"):
        import tomllib
        return bool(tomllib.loads(text)["ships"])
    return text.endswith("\n")


@pytest.fixture(scope="module")
def first_summary(tmp_path_factory):
    """A study of 24 runs (its final files are the "old" set) and an uninterrupted one of 48 (for the count)."""
    from mmg_casadi.cli import main
    base = tmp_path_factory.mktemp("first")
    assert main([*STUDY[:-2], "--workers", "1", "--runs", "24", "--out", str(base / "old")]) == 0
    return base / "old"


def _interrupted_resume(tmp_path, first_summary, monkeypatch, capsys, hook):
    """Copy the old study, resume it to 48 runs with ``hook`` installed (it sends SIGTERM at its moment) and
    return the old and the new final files."""
    import shutil
    from mmg_casadi.cli import main
    out = tmp_path / "out"
    shutil.copytree(first_summary, out)
    old = _snapshot(out)
    hook(out)
    status = main([*STUDY[:-2], "--workers", "1", "--runs", "48", "--out", str(out)])
    err = capsys.readouterr().err
    assert status in (0, 143), err
    if status == 143:
        assert err.strip().splitlines()[-1].startswith("mmg-casadi: interrupted by SIGTERM"), err
    new = _snapshot(out)
    left = [p.name for p in out.rglob(".*tmp-*")]
    return old, new, status, left


def _check_old_or_complete_new(old, new):
    assert set(new) >= set(old)
    for name, data in new.items():
        assert data == old.get(name) or _complete(name, data, 48), (name, len(data))


@pytest.mark.parametrize("k", [0, 3, 6, pytest.param(1, marks=pytest.mark.slow),
                               pytest.param(2, marks=pytest.mark.slow), pytest.param(4, marks=pytest.mark.slow),
                               pytest.param(5, marks=pytest.mark.slow), pytest.param(7, marks=pytest.mark.slow),
                               pytest.param(9, marks=pytest.mark.slow)])
def test_a_signal_at_the_kth_rename_of_the_final_writes_leaves_old_or_complete_files(
        tmp_path, first_summary, monkeypatch, capsys, k):
    real = os.replace
    count = []

    def hook(out):
        def replace(src, dst, *args, **kwargs):
            if Path(dst).parent in (out, out / "failures") and Path(dst).name != "runs.csv":
                if len(count) == k:
                    os.kill(os.getpid(), signal.SIGTERM)  # held back during the renames of the final set
                count.append(dst)
            return real(src, dst, *args, **kwargs)
        monkeypatch.setattr(os, "replace", replace)

    old, new, status, left = _interrupted_resume(tmp_path, first_summary, monkeypatch, capsys, hook)
    _check_old_or_complete_new(old, new)
    assert not left, left
    if status == 143 and len(count) > k and Path(count[k]).name != "study.json":
        # the signal came during the final set's renames: it was acted on after them, the set is new
        assert all(_complete(n, d, 48) for n, d in new.items() if not n.startswith("failures/")), status


@pytest.mark.parametrize("writer", ["figure", "markdown", pytest.param("csv", marks=pytest.mark.slow),
                                    pytest.param("failures", marks=pytest.mark.slow)])
def test_a_signal_while_a_final_file_is_written_leaves_the_old_files(tmp_path, first_summary, monkeypatch,
                                                                      capsys, writer):
    import matplotlib.figure
    import mmg_casadi.io
    import mmg_casadi.montecarlo.encounter_summary as es
    import mmg_casadi.montecarlo.study as study

    def half_then_signal(path):
        Path(path).write_bytes(b"half a file")
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(10)  # the handler raises here

    def hook(_out):
        if writer == "figure":
            monkeypatch.setattr(matplotlib.figure.Figure, "savefig", lambda self, path, **kw: half_then_signal(path))
        elif writer == "markdown":
            real = mmg_casadi.io.write_text
            monkeypatch.setattr(study, "write_text", lambda path, text: (half_then_signal(path), real(path, text)))
        elif writer == "csv":
            monkeypatch.setattr(es, "write_csv", lambda table, path, columns: half_then_signal(path))
        else:
            real_dump = study.dump_scenario
            monkeypatch.setattr(study, "dump_scenario", lambda sc: (os.kill(os.getpid(), signal.SIGTERM),
                                                                    time.sleep(10), real_dump(sc))[-1])

    old, new, status, left = _interrupted_resume(tmp_path, first_summary, monkeypatch, capsys, hook)
    assert status == 143
    assert new == old  # no final file changed: the new set was never renamed into place
    assert not left, left
