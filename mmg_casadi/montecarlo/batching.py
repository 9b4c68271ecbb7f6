"""How the statistical study's runs are grouped and run: batches (tasks), the compiled libraries, executors.

* **Plan** – :func:`plan_batches` splits the runs that are not yet stored into batches (:class:`BatchTask`) of
  ``batch_size`` runs of one (environment, method), interleaved over the cells. A batch is the unit of work and
  of resumption; it runs through :func:`~mmg_casadi.montecarlo.execution.run_batch`.
* **Compiled libraries** – workers never compile: :func:`prepare_layouts` builds every needed native library in
  the parent first (in parallel), workers load it from the disk cache (``$MMG_CASADI_CACHE``, forwarded to Ray
  workers).
* **Executors** – :class:`LocalExecutor` (a process pool, ``fork``) or :class:`RayExecutor` (a Ray cluster)
  run the batches and yield their rows as they complete.
"""

from __future__ import annotations

import multiprocessing
import os
import socket
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass

import numpy as np

from mmg_casadi.compiled import NOTICES, library_path
from mmg_casadi.closed_loop.simulation import compiled_step, rollout_functions
from mmg_casadi.errors import InputError, RunError
from mmg_casadi.guidance.plugins import ensure
from mmg_casadi.limits import MAX_WORKERS_PER_CORE, max_workers
from mmg_casadi.montecarlo.disturbance_sampling import DisturbanceRanges
from mmg_casadi.montecarlo.execution import DEFAULT_CHUNK, _non_default, run_batch
from mmg_casadi.signals import (child_pids, keep_termination_handlers, start_reaper, stop_pool, stop_reaper,
                                worker_initializer)

BACKENDS: tuple[str, ...] = ("local", "ray")
DEFAULT_BATCH = 128
"""Runs per task (the unit of resumption): ≥ ~1 s of compiled work even for the lightest cell; inside a task
:func:`~mmg_casadi.closed_loop.simulation.simulate_batch` steps ``DEFAULT_WIDTH`` runs side by side and refills finished
columns with waiting runs."""


# ------------------------------------------------------------------------------------------------ planning

@dataclass(frozen=True)
class BatchTask:
    """One unit of work: runs of one (environment, method) with one parameter set (``params``: sorted
    ``(name, value)`` pairs of the overrides) and the ranges of the per-run disturbance.

    Parameters
    ----------
    environment : int
        Environment number.
    method : str
        Collision-avoidance method.
    runs : tuple of int
        Run indices of the batch.
    base_seed : int, default 0
        Base seed of the scenario sampling.
    params : tuple, optional
        Sorted ``(name, value)`` pairs of the parameter overrides.
    chunk : int, optional
        Steps per ``mapaccum`` chunk.
    disturbance : DisturbanceRanges or None, optional
        Ranges of the per-run disturbance (``None``: undisturbed).
    plugins : tuple of PluginSource, optional
        The plugins of the process that planned the batch (:func:`mmg_casadi.guidance.plugins.sources`): a worker
        that does not have their methods loads them before it runs the batch
        (:func:`~mmg_casadi.guidance.plugins.ensure`; a Ray worker is another process, possibly on another machine).
    """

    environment: int
    method: str
    runs: tuple
    base_seed: int = 0
    params: tuple = ()
    chunk: int = DEFAULT_CHUNK
    disturbance: DisturbanceRanges | None = None
    plugins: tuple = ()

    def __call__(self) -> list[dict]:
        ensure(self.plugins)
        return run_batch(self.environment, self.method, list(self.runs), self.base_seed,
                         params=dict(self.params), chunk=self.chunk, disturbance=self.disturbance)


def _run_task(task: BatchTask) -> list[dict]:
    return task()


def plan_batches(envs, methods, runs: int, *, done=frozenset(), base_seed: int = 0, params: dict | None = None,
                 batch_size: int = DEFAULT_BATCH, chunk: int = DEFAULT_CHUNK,
                 disturbance: DisturbanceRanges | None = None, plugins=()) -> list[BatchTask]:
    """Batches of the runs ``0..runs-1`` of every (environment, method) whose key is not in ``done``.

    Batches are interleaved over the cells (first batch of every cell, then the second, ...), so the
    progress rate and ETA are representative early on and the heavy cells do not all come last.

    Parameters
    ----------
    envs : iterable of int
        Environment numbers.
    methods : iterable of str
        Collision-avoidance methods.
    runs : int
        Number of runs per (environment, method).
    done : collection of tuple, optional
        Keys ``(environment, method, run)`` already stored, skipped.
    base_seed : int, default 0
        Base seed of the scenario sampling.
    params : dict or None, optional
        Parameter overrides (table names).
    batch_size : int, default 128
        Largest number of runs per batch.
    chunk : int, optional
        Steps per ``mapaccum`` chunk.
    disturbance : DisturbanceRanges or None, optional
        Ranges of the per-run disturbance (``None``: undisturbed).
    plugins : tuple of PluginSource, optional
        Plugins every batch carries to its worker (:attr:`BatchTask.plugins`).

    Returns
    -------
    list of BatchTask
        The batches, interleaved over the cells; empty when every run is done.

    Examples
    --------
    >>> tasks = plan_batches((1, 2), ("inverse-square",), 5, done={(1, "inverse-square", 0)}, batch_size=2)
    >>> [(t.environment, t.runs) for t in tasks]
    [(1, (1, 2)), (2, (0, 1)), (1, (3, 4)), (2, (2, 3)), (2, (4,))]
    """
    items = tuple(sorted(_non_default(params).items()))
    cells = []
    for env in envs:
        for m in methods:
            todo = [r for r in range(runs) if (env, m, r) not in done]
            cells.append([BatchTask(env, m, tuple(todo[i:i + batch_size]), base_seed, items, chunk, disturbance,
                                    tuple(plugins))
                          for i in range(0, len(todo), batch_size)])
    tasks = []
    for k in range(max((len(c) for c in cells), default=0)):
        tasks += [c[k] for c in cells if k < len(c)]
    return tasks


def _compile_item(layout) -> float:
    NOTICES["stream"] = None  # a forked compiler process: prepare_layouts reports for it
    t0 = time.perf_counter()
    compiled_step(layout)
    return time.perf_counter() - t0


def _compile_cost(layout) -> float:
    """A rough order of compile time: ships × neighbours, the velocity obstacle's candidates weigh most."""
    n = layout.n_ships * (layout.n_agents - 1)
    return n * (1 + sum(m == "velocity-obstacle" for m in layout.methods) * layout.vo_candidates / 20 / layout.n_ships)


def prepare_layouts(layouts, workers: int = 1, *, log=None) -> None:
    """Compile (or load from the disk cache) the library of every layout (its step and guidance Functions,
    :func:`~mmg_casadi.closed_loop.simulation.rollout_functions`), in this process.

    Libraries missing from the cache are first compiled in parallel by up to ``workers`` forked processes, the
    costliest first (the velocity obstacle for 10 ships takes the longest), each one named in ``log`` as it is
    done; afterwards this process loads all of them, so forked pool workers inherit them and Ray workers find
    them on disk. The cache is keyed by the generated C source, so a library compiled by any version of the
    package with the same source is reused.

    Parameters
    ----------
    layouts : iterable of Layout
        The closed loops a study needs.
    workers : int
        Parallel compiler processes.
    log : file-like, optional
        Where to report what is compiled.
    """
    layouts = list(dict.fromkeys(layouts))
    missing = []
    for lay in layouts:
        step, guidance = rollout_functions(lay)
        if not library_path(step, also=[guidance])[0].exists():
            missing.append(lay)
    if missing:
        missing.sort(key=_compile_cost, reverse=True)
        if log:
            print(f"compiling {len(missing)} closed-loop librar{'y' if len(missing) == 1 else 'ies'} with "
                  f"{min(max(1, workers), len(missing))} processes (once; cached in the mmg-casadi cache)",
                  file=log, flush=True)
        n = min(max(1, workers), len(missing))
        ctx = multiprocessing.get_context("fork")
        pool = ProcessPoolExecutor(max_workers=n, mp_context=ctx, initializer=worker_initializer,
                                   initargs=(os.getpid(),))
        try:
            futures = {pool.submit(_compile_item, item): item for item in missing}
            for k, fut in enumerate(as_completed(futures), 1):
                lay, seconds = futures[fut], fut.result()
                if log:
                    print(f"  [{k}/{len(missing)}] {lay.key()} ({seconds:.0f} s)", file=log, flush=True)
        except BaseException:
            stop_pool(pool, WORKER_JOIN_TIMEOUT)  # do not wait minutes for compilers on Ctrl-C / SIGTERM
            raise
        pool.shutdown()
    for lay in layouts:
        compiled_step(lay)


# ----------------------------------------------------------------------------------------------- executors

def _check_workers(field: str, value):
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= max_workers():
        raise InputError(field, f"an integer in [1, {max_workers()}] ({MAX_WORKERS_PER_CORE} per core; or nothing "
                         "for all cores)", value)
    return int(value)


WORKER_JOIN_TIMEOUT = 5.0
"""Seconds to wait for each terminated pool worker to exit when a study is interrupted."""
RAY_MAX_RETRIES = 3
"""Times Ray reruns a batch whose worker process died (its rows are appended once: appends skip stored keys)."""
RAY_LOST = ("WorkerCrashedError", "NodeDiedError", "OutOfMemoryError", "ObjectLostError", "LocalRayletDiedError")
"""``ray.exceptions`` that mean a batch was lost with its worker or node (not an error of the batch itself)."""
RAY_PROBE_TIMEOUT = 3.0
"""Seconds :func:`check_ray_address` waits for a Ray cluster's head to accept a connection."""
RAY_LOCAL_ADDRESSES = ("auto", "local")
"""Addresses ``ray.init`` resolves itself (a cluster running on this machine, a new local one): not probed."""


def check_ray_address(address, field: str = "address") -> str | None:
    """Refuse a Ray address that is malformed or that no cluster answers at, before any work.

    ``ray.init`` with a wrong address waits minutes and only after the study has compiled its closed loops; this
    opens (and closes) one TCP connection to ``host:port`` within :data:`RAY_PROBE_TIMEOUT` s instead.

    Parameters
    ----------
    address : str or None
        ``host:port`` of the head's GCS (``ray start --head`` prints it), ``ray://host:port`` (Ray Client),
        ``[ipv6]:port``, one of :data:`RAY_LOCAL_ADDRESSES` (not probed), or None (a new local cluster).
    field : str, default 'address'
        Name of the input, for the error message.

    Returns
    -------
    str or None
        ``address``.

    Raises
    ------
    InputError
        The address does not parse or nothing accepts a connection there.

    Examples
    --------
    >>> check_ray_address(None), check_ray_address("auto")
    (None, 'auto')
    >>> check_ray_address("127.0.0.1:1")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: address: expected the host:port of a running Ray cluster (... refused), got '127.0.0.1:1'
    >>> check_ray_address("head")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: address: expected host:port, ray://host:port, auto or local, got 'head'
    """
    if address is None or address in RAY_LOCAL_ADDRESSES:
        return address
    forms = f"host:port, ray://host:port, {' or '.join(RAY_LOCAL_ADDRESSES)}"
    if not isinstance(address, str):
        raise InputError(field, forms, address)
    host, _, port = address.removeprefix("ray://").rpartition(":")
    host = host.removeprefix("[").removesuffix("]")
    if not host or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise InputError(field, forms, address)
    try:
        socket.create_connection((host, int(port)), timeout=RAY_PROBE_TIMEOUT).close()
    except (OSError, UnicodeError) as err:
        reason = getattr(err, "strerror", None) or str(err) or type(err).__name__
        raise InputError(field, f"the host:port of a running Ray cluster (ray start --head; connecting to "
                         f"{host}:{port} within {RAY_PROBE_TIMEOUT:g} s failed: {reason})", address) from None
    return address


class LocalExecutor:
    """Run batches in a local process pool (``fork``), one batch per task.

    Workers run :func:`~mmg_casadi.signals.worker_initializer`: SIGTERM stops them at once and they die with
    the study process, also when it is killed with SIGKILL.

    Parameters
    ----------
    workers : int, optional
        Worker processes; ``None`` for ``os.cpu_count()``. With ``1`` the batches run in this process.
    """

    def __init__(self, workers: int | None = None):
        workers = _check_workers("workers", workers)
        self.workers = workers or os.cpu_count() or 1

    @property
    def parallelism(self) -> int:
        return self.workers

    def run(self, tasks):
        """Yield ``(task, rows)`` for every task as it completes (completion order).

        Parameters
        ----------
        tasks : iterable of BatchTask
            The batches to run.

        Yields
        ------
        task : BatchTask
            A completed batch.
        rows : list of dict
            Its rows of ``runs.csv``, one per run.
        """
        tasks = list(tasks)
        if self.workers == 1 or len(tasks) <= 1:
            for t in tasks:
                yield t, _run_task(t)
            return
        ctx = multiprocessing.get_context("fork")
        pool = ProcessPoolExecutor(max_workers=min(self.workers, len(tasks)), mp_context=ctx,
                                   initializer=worker_initializer, initargs=(os.getpid(),))
        try:
            futures = {pool.submit(_run_task, t): t for t in tasks}
            for fut in as_completed(futures):
                yield futures[fut], fut.result()
        except BaseException:
            # interrupted (Ctrl-C, SIGTERM, an error, or the consumer stopped): drop queued batches and stop
            # the running ones at once; their rows were never appended, so a rerun simulates them again
            stop_pool(pool, WORKER_JOIN_TIMEOUT)
            raise
        pool.shutdown()

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class RayExecutor:
    """Run batches as Ray tasks (one CPU each) on a local or remote Ray cluster.

    ``ray.init(address=address, num_cpus=num_cpus)`` is called if Ray is not initialised yet (and
    ``ray.shutdown()`` on :meth:`close` in that case); ``num_cpus`` only applies to a new local cluster.
    ``$MMG_CASADI_CACHE`` is forwarded to the workers, which load the compiled steps from that cache (on a
    multi-machine cluster, point it at a shared directory or let each machine compile once). A batch whose
    worker dies is rerun up to :data:`RAY_MAX_RETRIES` times (a batch that raises is not); each batch result
    is yielded once and :meth:`ResultsTable.append <mmg_casadi.montecarlo.results.ResultsTable.append>` skips stored
    keys, so no run is lost or counted twice. A batch lost more often (:data:`RAY_LOST`) does not stop the
    others: once they are done, :meth:`run` raises :class:`~mmg_casadi.errors.RunError` naming it.

    A local cluster started here is guarded by a watchdog process (:func:`~mmg_casadi.signals.start_reaper`,
    Linux): if this process dies, even by SIGKILL, the cluster's processes (raylet, GCS, agents, workers) are
    killed at once instead of lingering for a minute; :meth:`close` also kills any of them left after
    ``ray.shutdown()``.

    Parameters
    ----------
    address : str or None, optional
        Address of the Ray cluster passed to ``ray.init``.
    num_cpus : int or None, optional
        CPUs of a new local Ray cluster.
    """

    def __init__(self, address: str | None = None, num_cpus: int | None = None):
        self.address = address
        self.num_cpus = _check_workers("workers", num_cpus)
        self._owns = False
        self._reaper = None
        try:
            import ray  # noqa: F401  (optional dependency: is it installed?)
        except ImportError:
            raise InputError("backend", "'local' (Ray is not installed; pip install 'mmg-casadi[ray]')",
                             "ray") from None

    def _runtime_env(self) -> dict | None:
        cache = os.environ.get("MMG_CASADI_CACHE")
        return {"env_vars": {"MMG_CASADI_CACHE": cache}} if cache else None

    def _ensure(self) -> dict:
        import ray  # optional dependency (extra [ray]): imported where used
        renv = self._runtime_env()
        if ray.is_initialized():
            return {"runtime_env": renv} if renv else {}
        kw = {"address": self.address, "include_dashboard": False, "log_to_driver": False}
        if self.address is None and self.num_cpus is not None:
            kw["num_cpus"] = self.num_cpus
        if renv:
            kw["runtime_env"] = renv
        before = child_pids()
        with keep_termination_handlers():  # SIGTERM keeps the CLI's resume path
            ray.init(**kw)
        self._owns = True
        self._reaper = start_reaper(child_pids() - before)  # none when ray.init joined a running cluster
        return {}

    @property
    def parallelism(self) -> int:
        import ray  # optional dependency (extra [ray]): imported where used
        if ray.is_initialized():
            return max(1, int(ray.cluster_resources().get("CPU", 1)))
        return self.num_cpus or os.cpu_count() or 1

    def run(self, tasks):
        """Yield ``(task, rows)`` for every task as it completes (completion order).

        Parameters
        ----------
        tasks : iterable of BatchTask
            The batches to run.

        Yields
        ------
        task : BatchTask
            A completed batch.
        rows : list of dict
            Its rows of ``runs.csv``, one per run.
        """
        import ray  # optional dependency (extra [ray]): imported where used
        tasks = list(tasks)
        if not tasks:
            return
        opts = self._ensure()
        remote = ray.remote(num_cpus=1, max_retries=RAY_MAX_RETRIES, retry_exceptions=False)(_run_task)
        if opts:
            remote = remote.options(**opts)
        lost_types = tuple(getattr(ray.exceptions, name) for name in RAY_LOST if hasattr(ray.exceptions, name))
        refs = {remote.remote(t): t for t in tasks}
        pending = list(refs)
        lost = []
        try:
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                for ref in ready:
                    try:
                        rows = ray.get(ref)
                    except lost_types as err:  # retries used up: the other batches go on, the error comes last
                        lost.append((refs[ref], type(err).__name__))
                        continue
                    yield refs[ref], rows
        finally:
            # a Ray this executor started is shut down by close(), which stops its tasks; cancelling them here
            # as well can race with a task completing and abort the driver (Ray 2.60 task_manager check)
            for ref in (() if self._owns else pending):
                try:
                    ray.cancel(ref, force=True)
                except Exception:  # noqa: BLE001 - best effort on interruption
                    pass
        if lost:
            raise RunError(_lost_message(lost, len(tasks)))

    def close(self) -> None:
        if self._owns:
            import ray  # optional dependency (extra [ray]): imported where used
            ray.shutdown()
            self._owns = False
            stop_reaper(self._reaper)
            self._reaper = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _lost_message(lost, n_tasks: int) -> str:
    """One line for the batches a Ray study lost: the first of them, how many, and how to resume."""
    task, name = lost[0]
    runs = f"run {task.runs[0]}" if len(task.runs) == 1 else f"runs {task.runs[0]}-{task.runs[-1]}"
    more = f" (and {len(lost) - 1} more of the {n_tasks} batches)" if len(lost) > 1 else ""
    return (f"backend ray: the batch of environment {task.environment}, {task.method}, {runs}{more} was lost "
            f"({name}: its worker died, also on each of the {RAY_MAX_RETRIES} retries, e.g. out of memory or "
            "killed); the finished runs are kept, rerun the same command to run the missing ones")
