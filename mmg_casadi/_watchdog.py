"""Watchdog processes that clean up after their parent, also when it is killed with SIGKILL and runs no cleanup.

Run as a script in Python's isolated mode, ``python -I -S _watchdog.py MODE ...`` (standard library only, so it
starts in a few ms and never imports the package); the parent (the study, or a pool worker of it) passes its
pid. A watchdog notices the parent's death within :data:`POLL` s: it is re-parented, ``os.getppid()`` changes.

``build PARENT BUILD_DIR SOURCE BUILT TARGET -- COMMAND...``
    Compile one library for :func:`mmg_casadi.compiled.compile_function`: create ``BUILD_DIR`` (a fresh folder in
    the cache, mode 0700), write standard input to ``BUILD_DIR/SOURCE``, run ``COMMAND`` (the C compiler) in
    ``BUILD_DIR`` in a process group of its own, and on success flush ``BUILD_DIR/BUILT`` to disk, write its
    SHA-256 to ``TARGET.sha256`` and rename the library atomically to ``TARGET``. On SIGTERM, SIGINT or SIGHUP,
    or when the parent dies, the compiler's whole process group (``gcc`` and its ``cc1``/``as``/``ld``) is
    killed, and any process of the compiler that left it; ``BUILD_DIR`` is removed in every case. The exit
    status is the compiler's, or ``128 + signal`` when stopped. The caller starts this watchdog in a process
    group of its own, so that a SIGKILL of the caller's group leaves it alive to do this; on Linux it is a child
    subreaper (``prctl(PR_SET_CHILD_SUBREAPER)``: a compiler process whose parent died becomes its child) and the
    compiler gets SIGKILL if the watchdog itself dies (``prctl(PR_SET_PDEATHSIG)``).
``reap DRIVER ROOT...``
    Guard a local Ray cluster started by ``DRIVER``: every :data:`REAP_POLL` s record the processes ``ROOT...`` (the
    children ``ray.init`` started) and all their descendants (Linux ``/proc``); when ``DRIVER`` dies, or when it
    writes a line to standard input or closes it (after ``ray.shutdown()``), kill every recorded process still
    alive (SIGKILL; Ray's own agents would otherwise linger for a minute after a driver killed by SIGKILL) and
    exit. SIGTERM, SIGINT and SIGHUP are ignored (a terminal's Ctrl-C or a signal to the whole process group
    reaches it too): the watchdog outlives the driver that it cleans up after.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import select
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

POLL = 0.05
"""Seconds between two checks of the parent (and of the compiler, in ``build`` mode)."""
REAP_POLL = 0.5
"""Seconds between two snapshots of the Ray cluster's processes in ``reap`` mode."""
REAP_GIVE_UP = 10.0
"""Seconds after which ``reap`` mode stops killing (a process stuck in the kernel ignores even SIGKILL)."""
STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT, signal.SIGHUP)
"""Signals that stop a ``build`` watchdog and its compiler (a ``reap`` watchdog ignores them)."""
PR_SET_PDEATHSIG = 1
"""``prctl`` option: signal delivered to a process when its parent dies (``<linux/prctl.h>``)."""
PR_SET_CHILD_SUBREAPER = 36
"""``prctl`` option: orphaned descendants of a process become its children (``<linux/prctl.h>``)."""


def _prctl(option: int, value: int) -> bool:
    """``prctl(option, value)`` through libc (Linux); False where it is not available or fails."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        return ctypes.CDLL(None, use_errno=True).prctl(option, value, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _die_with_parent() -> None:
    """``preexec_fn`` of the compiler: SIGKILL when the watchdog dies (nothing else runs after a fork here)."""
    _prctl(PR_SET_PDEATHSIG, signal.SIGKILL)


def process_stat(pid: int) -> tuple[str, int, int] | None:
    """State letter, parent pid and start time (clock ticks since boot) of ``pid`` from ``/proc``, or None.

    Parameters
    ----------
    pid : int
        Process id.
    """
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # after "pid (comm) ": state ppid pgrp ... starttime (22nd)
    return fields[0], int(fields[1]), int(fields[19])


def children_by_parent() -> dict[int, list[int]]:
    """The pids of every live (not zombie) process, grouped by parent pid (from ``/proc``)."""
    out: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            st = process_stat(int(entry.name))
            if st is not None and st[0] != "Z":
                out.setdefault(st[1], []).append(int(entry.name))
    return out


def descendants(roots) -> dict[int, int]:
    """``{pid: start time}`` of the live processes ``roots`` and all their descendants.

    Parameters
    ----------
    roots : iterable of int
        Pids whose process trees are listed (pids that are gone are skipped).
    """
    kids = children_by_parent()
    out: dict[int, int] = {}
    todo = list(roots)
    while todo:
        pid = todo.pop()
        st = process_stat(pid)
        if pid in out or st is None or st[0] == "Z":
            continue
        out[pid] = st[2]
        todo += kids.get(pid, [])
    return out


def _parent_gone(parent: int) -> bool:
    return os.getppid() != parent


def build(parent: int, build_dir: Path, source: str, built: str, target: Path, command: list[str]) -> int:
    """The ``build`` mode (see the module notes); returns the exit status.

    Parameters
    ----------
    parent : int
        Pid of the process that compiles (this watchdog's parent).
    build_dir : Path
        Folder to create for the build (it must not exist); removed on exit.
    source : str
        File name in ``build_dir`` to which standard input (the C source) is written.
    built : str
        File name in ``build_dir`` that ``command`` writes.
    target : Path
        Final path of the library (atomic rename of ``built``).
    command : list of str
        The compiler command line.
    """
    stopped: list[int] = []

    def on_signal(signum, _frame):
        stopped.append(signum)

    for s in STOP_SIGNALS:
        signal.signal(s, on_signal)
    _prctl(PR_SET_CHILD_SUBREAPER, 1)
    try:
        if _parent_gone(parent):
            return 128 + signal.SIGTERM
        build_dir.mkdir(mode=0o700)
        (build_dir / source).write_bytes(sys.stdin.buffer.read())
        if stopped or _parent_gone(parent):
            return 128 + (stopped[0] if stopped else signal.SIGTERM)
        compiler = subprocess.Popen(command, stdin=subprocess.DEVNULL, cwd=build_dir, process_group=0,
                                    preexec_fn=_die_with_parent)
        while True:
            try:
                status = compiler.wait(POLL)
                break
            except subprocess.TimeoutExpired:
                pass
            if stopped or _parent_gone(parent):
                # gcc and the cc1/as/ld it started (the group lives on while gcc's pid is not reaped)
                os.killpg(compiler.pid, signal.SIGKILL)
                compiler.wait()
                return 128 + (stopped[0] if stopped else signal.SIGTERM)
        if status == 0:
            fd = os.open(build_dir / built, os.O_RDONLY)
            try:
                os.fsync(fd)  # the data is on disk before the name is: a crash never leaves a short library
            finally:
                os.close(fd)
            _write_record(build_dir / built, Path(str(target) + ".sha256"))
            os.replace(build_dir / built, target)
        return status
    finally:
        _kill_descendants()
        shutil.rmtree(build_dir, ignore_errors=True)


def _write_record(library: Path, record: Path) -> None:
    """Write the SHA-256 of ``library`` to ``record`` atomically (temporary name in the same folder, rename)."""
    h = hashlib.sha256()
    with open(library, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    tmp = library.with_name(record.name + ".tmp")
    tmp.write_text(h.hexdigest() + "\n", encoding="ascii")
    os.replace(tmp, record)


def _kill_descendants() -> None:
    """Kill whatever this watchdog's compiler left behind (its children re-parented to this subreaper)."""
    if not Path("/proc/self/stat").exists():
        return
    for _ in range(50):
        left = [p for p in descendants(children_by_parent().get(os.getpid(), [])) if p != os.getpid()]
        if not left:
            return
        for pid in left:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        while True:  # reap them (they are our children, as subreaper)
            try:
                if os.waitpid(-1, os.WNOHANG)[0] == 0:
                    break
            except ChildProcessError:
                break
        time.sleep(0.01)


def reap(driver: int, roots: list[int]) -> int:
    """The ``reap`` mode (see the module notes); returns the exit status (0).

    Parameters
    ----------
    driver : int
        Pid of the Ray driver (this watchdog's parent).
    roots : list of int
        Pids of the processes ``ray.init`` started.
    """
    for s in STOP_SIGNALS:  # a terminal's Ctrl-C, a group-wide SIGTERM: the driver shuts Ray down and tells us
        signal.signal(s, signal.SIG_IGN)
    tracked = descendants(roots)
    while not _parent_gone(driver):
        told, _, _ = select.select([sys.stdin], [], [], REAP_POLL)
        if told:  # "stop" after ray.shutdown(), or end of file: the driver closed the pipe
            break
        tracked = descendants(_unchanged(tracked))
    deadline = time.monotonic() + REAP_GIVE_UP
    while True:  # kill what is recorded, then whatever those processes started meanwhile
        alive = descendants(_unchanged(tracked))
        if not alive or time.monotonic() > deadline:
            return 0
        for pid in alive:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        tracked = alive
        time.sleep(POLL)


def _unchanged(tracked: dict[int, int]) -> list[int]:
    """The pids of ``tracked`` (``{pid: start time}``) still alive as the same process (not a reused pid)."""
    out = []
    for pid, start in tracked.items():
        st = process_stat(pid)
        if st is not None and st[0] != "Z" and st[2] == start:
            out.append(pid)
    return out


def main(argv: list[str]) -> int:
    """Run the watchdog mode named by ``argv[0]`` with the arguments that follow; returns the exit status.

    Parameters
    ----------
    argv : list of str
        ``["build", PARENT, BUILD_DIR, SOURCE, BUILT, TARGET, "--", COMMAND...]`` or ``["reap", DRIVER, ROOT...]``.
    """
    if argv[0] == "build" and argv[6] == "--":
        return build(int(argv[1]), Path(argv[2]), argv[3], argv[4], Path(argv[5]), argv[7:])
    if argv[0] == "reap":
        return reap(int(argv[1]), [int(a) for a in argv[2:]])
    print(f"_watchdog.py: unknown arguments {argv!r}", file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
