"""Termination signals handled like Ctrl-C, and worker processes that never outlive the study process.

* :func:`terminate_as_interrupt` — while active, SIGTERM (sent by ``timeout``, batch schedulers, ``docker stop``)
  and SIGHUP (the terminal went away) raise :class:`Terminated`, a :class:`KeyboardInterrupt`, in the main
  thread, so they take exactly the path of Ctrl-C: running batches are stopped, finished rows stay in
  ``runs.csv`` and the CLI prints one line saying how to resume. :func:`exit_status` gives the conventional
  status ``128 + signal`` (130 for Ctrl-C, 143 for SIGTERM, 129 for SIGHUP). The CLI handles SIGINT the same
  way (:data:`CLI_SIGNALS`): only the first of any number of signals raises, the others are ignored while the
  interruption unwinds (a second Ctrl-C used to interrupt the cleanup that stops the workers, with an
  "Exception ignored ... KeyboardInterrupt" traceback), and :func:`settle` ends the raising once the command
  has decided its outcome (the line it prints and its exit status).
* :func:`worker_initializer` — the ``initializer`` of a forked process pool: it restores the default action of
  SIGTERM/SIGHUP in the worker (a fork inherits the parent's Python handlers, with which ``terminate()`` would
  only raise an exception inside the running task) and makes the worker die with its parent, also when the
  parent is killed with SIGKILL and can run no cleanup: on Linux through ``prctl(PR_SET_PDEATHSIG, SIGTERM)``
  (``man 2 prctl``), elsewhere by a daemon thread that polls ``os.getppid()``.
* :func:`stop_pool` — stop a process pool at once (interruption), without waiting for running tasks.
* :func:`start_reaper` / :func:`stop_reaper` — a watchdog process (``mmg_casadi/_watchdog.py``, mode ``reap``)
  that kills the processes of a local Ray cluster, agents included, when the study process dies (also by
  SIGKILL) or has shut the cluster down (Linux; it follows the process tree in ``/proc``).

The C compilers run under the same watchdog script (mode ``build``, :mod:`mmg_casadi.compiled`).
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from mmg_casadi import _watchdog

TERMINATION_SIGNALS: tuple[int, ...] = (signal.SIGTERM, signal.SIGHUP)
"""Signals handled like Ctrl-C by :func:`terminate_as_interrupt`."""
CLI_SIGNALS: tuple[int, ...] = (signal.SIGINT, *TERMINATION_SIGNALS)
"""Signals the command line program handles (:func:`terminate_as_interrupt`): Ctrl-C and the termination signals."""
PR_SET_PDEATHSIG = 1
"""``prctl`` option: signal delivered to this process when its parent thread exits (``<linux/prctl.h>``)."""
PARENT_POLL_INTERVAL = 1.0
"""Seconds between two parent checks of the fallback watcher thread (platforms without ``prctl``)."""
REAPER_STOP_TIMEOUT = _watchdog.REAP_GIVE_UP + 5.0
"""Seconds :func:`stop_reaper` waits for the watchdog to finish before killing it."""


class Terminated(KeyboardInterrupt):
    """A termination signal received while :func:`terminate_as_interrupt` was active.

    Parameters
    ----------
    signum : int
        Number of the signal received (e.g. ``signal.SIGTERM``), kept as the attribute ``signum``; the
        exception's message is the signal's name (``"SIGTERM"``). It must be a valid signal number.

    Examples
    --------
    >>> err = Terminated(signal.SIGTERM)
    >>> isinstance(err, KeyboardInterrupt), err.signum, str(err)
    (True, 15, 'SIGTERM')
    """

    def __init__(self, signum: int):
        self.signum = int(signum)
        super().__init__(signal.Signals(self.signum).name)


def exit_status(err: BaseException) -> int:
    """Conventional exit status of a process stopped by ``err``: ``128 + signal number``.

    A plain :class:`KeyboardInterrupt` is Ctrl-C (SIGINT, 130).

    Parameters
    ----------
    err : BaseException
        The interruption: a :class:`Terminated` (or any exception with a ``signum`` attribute) or a plain
        :class:`KeyboardInterrupt` (taken as SIGINT).

    Returns
    -------
    int
        ``128 + signum``: 130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP.

    Examples
    --------
    >>> exit_status(KeyboardInterrupt()), exit_status(Terminated(signal.SIGTERM))
    (130, 143)
    >>> exit_status(Terminated(signal.SIGHUP))
    129
    """
    return 128 + int(getattr(err, "signum", signal.SIGINT))


def signal_name(err: BaseException) -> str:
    """Name of the signal behind an interruption (``"SIGINT"`` for a plain :class:`KeyboardInterrupt`).

    Parameters
    ----------
    err : BaseException
        The interruption: a :class:`Terminated` (or any exception with a ``signum`` attribute) or a plain
        :class:`KeyboardInterrupt` (taken as SIGINT).

    Returns
    -------
    str
        The signal's name, e.g. ``"SIGTERM"``.

    Examples
    --------
    >>> signal_name(KeyboardInterrupt()), signal_name(Terminated(signal.SIGHUP))
    ('SIGINT', 'SIGHUP')
    """
    return signal.Signals(int(getattr(err, "signum", signal.SIGINT))).name


_FIRED: list[int] = []
"""Signals that raised :class:`Terminated` in the active :func:`terminate_as_interrupt` block (or were raised by
:func:`end_deferred_signals`), and 0 once :func:`settle` was called: while it is not empty, signals are ignored."""
_PROGRAM: list[bool] = []
"""True once :func:`defer_startup_signals` ran: this process is the ``mmg-casadi`` program, not a library user."""


def settle() -> None:
    """Ignore the signals of the active :func:`terminate_as_interrupt` block from now on: the command has decided
    its outcome (an error line, a result) and a late signal must not add a second line or a traceback.

    Examples
    --------
    >>> with terminate_as_interrupt():
    ...     settle()
    ...     os.kill(os.getpid(), signal.SIGTERM)  # ignored
    ...     time.sleep(0.05)
    >>> print("still here")
    still here
    """
    _FIRED.append(0)


def is_program() -> bool:
    """Whether this process is the ``mmg-casadi`` program (:func:`defer_startup_signals` ran at start-up).

    Returns
    -------
    bool
        True in the command line program, False where the package is imported as a library.
    """
    return bool(_PROGRAM)


@contextlib.contextmanager
def terminate_as_interrupt(signals=TERMINATION_SIGNALS, *, ignore_on_exit: bool = False):
    """Within the block, the first of ``signals`` raises :class:`Terminated` in the main thread.

    Further signals are ignored while the interruption unwinds (so the cleanup that stops the workers and keeps
    the finished rows is not itself interrupted), and after :func:`settle`; the previous handlers are restored
    on exit (or, with ``ignore_on_exit``, the signals stay ignored: the program is about to exit and a signal
    while it does must neither print a traceback nor kill it without its line). Outside the main thread (where
    Python cannot install handlers) the block runs unchanged.

    Parameters
    ----------
    signals : iterable of int, optional
        Signal numbers to handle; default :data:`TERMINATION_SIGNALS` (SIGTERM and SIGHUP); the CLI passes
        :data:`CLI_SIGNALS` (SIGINT too). A SIGINT raises ``Terminated(SIGINT)`` (exit status 130).
    ignore_on_exit : bool, optional
        Leave the signals ignored on exit from the block instead of restoring the previous handlers (the
        ``mmg-casadi`` program, :func:`is_program`).

    Yields
    ------
    None
        Nothing; the block runs with the handlers installed.

    Examples
    --------
    >>> with terminate_as_interrupt():
    ...     try:
    ...         os.kill(os.getpid(), signal.SIGTERM)
    ...     except KeyboardInterrupt as err:
    ...         print(exit_status(err))
    143
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    outer = list(_FIRED)
    _FIRED.clear()

    def handler(signum, _frame):
        if _FIRED:
            return
        _FIRED.append(signum)
        raise Terminated(signum)

    previous = {s: signal.signal(s, handler) for s in signals}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, signal.SIG_IGN if ignore_on_exit else h)
        _FIRED[:] = outer


@contextlib.contextmanager
def keep_termination_handlers(signals=CLI_SIGNALS):
    """Undo changes made within the block to the handlers of ``signals`` (e.g. by ``ray.init``, which installs
    its own SIGTERM handler that exits without the resume message).

    Outside the main thread (where Python cannot install handlers) the block runs unchanged. A handler that was
    not installed from Python (``signal.getsignal`` gives None) is not restored.

    Parameters
    ----------
    signals : iterable of int, optional
        Signal numbers whose handlers are saved on entry and restored on exit; default
        :data:`TERMINATION_SIGNALS` (SIGTERM and SIGHUP).

    Yields
    ------
    None
        Nothing; the block runs unchanged.

    Examples
    --------
    >>> before = signal.getsignal(signal.SIGTERM)
    >>> with keep_termination_handlers():
    ...     _ = signal.signal(signal.SIGTERM, signal.SIG_IGN)
    >>> signal.getsignal(signal.SIGTERM) is before
    True
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.getsignal(s) for s in signals}
    try:
        yield
    finally:
        for s, h in previous.items():
            if h is not None:
                signal.signal(s, h)


_DEFERRED: dict[int, object] = {}
"""Signals whose handler :func:`defer_startup_signals` replaced, with the handler it replaced."""
_RECEIVED: list[int] = []
"""Signals received while deferred (the first is raised by :func:`end_deferred_signals`)."""


def _record(signum, _frame):
    _RECEIVED.append(signum)


def _ignore_sigint_in_child() -> None:
    try:
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    except ValueError:  # not the main thread of the child (cannot happen after fork, but never fail there)
        pass


def defer_startup_signals(signals=(*TERMINATION_SIGNALS, signal.SIGINT), *, program: bool = False,
                          early=None) -> None:
    """Record, instead of acting on, the ``signals`` that arrive while the command line program starts.

    Loading the package takes seconds (CasADi, NumPy, SciPy); a SIGTERM then (e.g. the first seconds of a cold
    compile) would kill the process with no message, a Ctrl-C would print an import traceback. The package calls
    this when it is loaded as the ``mmg-casadi`` program; the CLI's :func:`end_deferred_signals`, once its own
    handlers are installed, raises the first signal recorded, which then takes the path of every interruption
    (one line, exit status ``128 + signal``). Only a signal with its default handler is deferred (an ignored
    SIGHUP, under ``nohup``, stays ignored). Outside the main thread nothing is changed.

    Parameters
    ----------
    signals : iterable of int, optional
        Signals to defer; default SIGTERM, SIGHUP and SIGINT.
    program : bool, optional
        This process is the ``mmg-casadi`` program (:func:`is_program`; the package passes True when it is
        loaded as the program): children it forks ignore SIGINT from their first instruction on.
    early : tuple of (dict, list), optional
        ``(previous handlers, signals received)`` of a recorder installed before this module was imported (the
        package installs one with the ``signal`` module alone, so a Ctrl-C while this module loads is deferred
        too): its signals are taken over, and those it received come first.

    Examples
    --------
    >>> defer_startup_signals([signal.SIGUSR1])
    >>> os.kill(os.getpid(), signal.SIGUSR1)  # recorded, not acted on (SIGUSR1 would end the process)
    >>> try:
    ...     end_deferred_signals()
    ... except KeyboardInterrupt as err:
    ...     print(signal_name(err), signal.getsignal(signal.SIGUSR1) is signal.SIG_DFL)
    SIGUSR1 True
    """
    if threading.current_thread() is not threading.main_thread():
        return
    if program and not _PROGRAM:
        _PROGRAM.append(True)
        # a child forked by the program (a pool worker) ignores Ctrl-C from the first instruction on: the
        # program stops its workers itself (SIGTERM), a worker's KeyboardInterrupt would print a traceback
        os.register_at_fork(after_in_child=_ignore_sigint_in_child)
    previous, received = early if early is not None else ({}, [])
    for s in signals:
        current = signal.getsignal(s)
        if s in previous:
            _DEFERRED[s] = previous[s]
            signal.signal(s, _record)
        elif current is signal.SIG_DFL or current is signal.default_int_handler:
            _DEFERRED[s] = current
            signal.signal(s, _record)
    _RECEIVED[:0] = list(received)  # those of the early recorder came first


def end_deferred_signals() -> None:
    """Stop deferring (:func:`defer_startup_signals`): restore the handlers replaced (those that nobody has set
    since, e.g. :func:`terminate_as_interrupt`), then raise :class:`Terminated` for the first signal recorded.

    Raises
    ------
    Terminated
        A deferred signal was received (a :class:`KeyboardInterrupt`; ``exit_status`` gives ``128 + signal``).
    """
    for s, previous in list(_DEFERRED.items()):
        if signal.getsignal(s) is _record:
            signal.signal(s, previous)
        del _DEFERRED[s]
    if _RECEIVED:
        signum = _RECEIVED[0]
        _RECEIVED.clear()
        _FIRED.append(signum)  # as if the handler of terminate_as_interrupt had raised it: the next are ignored
        raise Terminated(signum)


def _set_parent_death_signal(signum: int) -> bool:
    """``prctl(PR_SET_PDEATHSIG, signum)`` through libc; False where it is not available."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, signum, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch_parent(parent_pid: int, interval: float) -> None:
    """Exit this process as soon as its parent is no longer ``parent_pid`` (re-parented after its death)."""
    while os.getppid() == parent_pid:
        time.sleep(interval)
    os._exit(128 + signal.SIGTERM)


def worker_initializer(parent_pid: int) -> None:
    """Initializer of a forked pool worker: default SIGTERM/SIGHUP, SIGINT ignored (the parent, which gets the
    terminal's Ctrl-C too, stops its workers with SIGTERM), and death with the parent ``parent_pid``.

    Pass the parent's pid (``os.getpid()`` in the parent, before the pool starts): if the parent died between
    the fork and this call the worker exits at once.

    Parameters
    ----------
    parent_pid : int
        Process id of the parent (the process that creates the pool), passed through ``initargs``. On Linux
        the worker gets SIGTERM when its parent dies (``prctl(PR_SET_PDEATHSIG)``); elsewhere a daemon thread
        checks every :data:`PARENT_POLL_INTERVAL` s whether ``os.getppid()`` still equals ``parent_pid``.

    Examples
    --------
    >>> from concurrent.futures import ProcessPoolExecutor
    >>> import multiprocessing
    >>> with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork"),
    ...                          initializer=worker_initializer, initargs=(os.getpid(),)) as pool:
    ...     pool.submit(os.getppid).result() == os.getpid()
    True
    """
    for s in TERMINATION_SIGNALS:
        signal.signal(s, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # a terminal's Ctrl-C reaches the whole group: the parent stops us
    if not _set_parent_death_signal(signal.SIGTERM):
        threading.Thread(target=_watch_parent, args=(parent_pid, PARENT_POLL_INTERVAL), daemon=True,
                         name="parent-watch").start()
    if os.getppid() != parent_pid:
        os._exit(128 + signal.SIGTERM)


def stop_pool(pool, timeout: float = 5.0) -> None:
    """Stop a ``concurrent.futures.ProcessPoolExecutor`` at once: drop queued tasks, terminate its workers
    (SIGTERM; with :func:`worker_initializer` they exit immediately) and reap them (``timeout`` s each).

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
        The pool to stop. Its worker processes are read from the executor's private ``_processes`` mapping
        (none if it has no such attribute, in which case the pool is only shut down without waiting).
    timeout : float, optional
        Seconds to wait for each worker process to exit after SIGTERM (``Process.join``); default 5. A worker
        still alive after that is killed (SIGKILL).

    Examples
    --------
    >>> from concurrent.futures import ProcessPoolExecutor
    >>> import multiprocessing
    >>> pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork"),
    ...                            initializer=worker_initializer, initargs=(os.getpid(),))
    >>> fut = pool.submit(time.sleep, 60)
    >>> workers = list(pool._processes.values())
    >>> stop_pool(pool)
    >>> [w.is_alive() for w in workers]  # the sleeping worker was stopped, not waited for
    [False]
    """
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    for proc in processes:
        _reaped(proc, timeout)
    for proc in processes:  # e.g. SIGTERM arrived before the initializer restored its default action
        if not _reaped(proc, 0.0):
            proc.kill()
            _reaped(proc, timeout)


def _reaped(proc, timeout: float) -> bool:
    """Join ``proc`` for up to ``timeout`` s and say whether it has exited. The pool's own manager thread may reap
    the same child at the same moment; ``join`` then returns at once without an exit code (the wait fails with
    ECHILD) until that thread has stored it, so the exit code is polled until the deadline."""
    deadline = time.monotonic() + timeout
    proc.join(timeout)
    while proc.exitcode is None and time.monotonic() < deadline:
        time.sleep(0.005)
    return proc.exitcode is not None


def child_pids(pid: int | None = None) -> set[int]:
    """Pids of the live (not zombie) child processes of ``pid`` (default this process); empty off Linux.

    Parameters
    ----------
    pid : int, optional
        Parent process id; default ``os.getpid()``.

    Returns
    -------
    set of int
        The children found in ``/proc`` (an empty set where there is no ``/proc``).

    Examples
    --------
    >>> child = subprocess.Popen(["sleep", "5"])
    >>> child.pid in child_pids(), os.getpid() in child_pids()
    (True, False)
    >>> child.kill(); _ = child.wait()
    """
    if not Path("/proc/self/stat").exists():
        return set()
    return set(_watchdog.children_by_parent().get(os.getpid() if pid is None else pid, ()))


def start_reaper(roots) -> subprocess.Popen | None:
    """Start a watchdog that kills the processes ``roots`` and their descendants when this process dies or calls
    :func:`stop_reaper` (module notes); None if ``roots`` is empty or there is no ``/proc`` (not Linux).

    Parameters
    ----------
    roots : iterable of int
        Pids of child processes of this process (e.g. those ``ray.init`` started: :func:`child_pids` after minus
        before). Processes they start later are followed (a snapshot of the tree every 0.5 s).

    Returns
    -------
    subprocess.Popen or None
        The watchdog process, for :func:`stop_reaper`.

    Examples
    --------
    >>> child = subprocess.Popen(["sleep", "60"])
    >>> reaper = start_reaper({child.pid})
    >>> stop_reaper(reaper)
    >>> child.wait(5) == -signal.SIGKILL
    True
    """
    roots = sorted(int(p) for p in roots)
    if not roots or not Path("/proc/self/stat").exists():
        return None
    return subprocess.Popen([sys.executable, "-I", "-S", _watchdog.__file__, "reap", str(os.getpid()),
                             *map(str, roots)], stdin=subprocess.PIPE)


def stop_reaper(reaper: subprocess.Popen | None) -> None:
    """Tell a watchdog of :func:`start_reaper` to kill what is left of its processes, and wait for it.

    Parameters
    ----------
    reaper : subprocess.Popen or None
        The watchdog (None: nothing to do). If it has not finished within :data:`REAPER_STOP_TIMEOUT` s it is
        killed.
    """
    if reaper is None:
        return
    try:
        reaper.stdin.write(b"stop\n")
        reaper.stdin.close()
    except OSError:  # it is gone already
        pass
    try:
        reaper.wait(REAPER_STOP_TIMEOUT)
    except subprocess.TimeoutExpired:
        reaper.kill()
        reaper.wait()
