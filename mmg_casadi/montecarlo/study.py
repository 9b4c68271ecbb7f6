"""The paper's statistical study at scale: plan → sampler → executor → results handler (resumable).

A study is the cross product *environments × methods × runs*. Each (environment, method, run) is one random
encounter drawn by :func:`~mmg_casadi.montecarlo.sampling.sample_scenario` (so every method meets the same scenarios),
simulated by the compiled closed loop and reduced to one row of :data:`~mmg_casadi.montecarlo.results.RUN_COLUMNS`.

* **Plan** – :func:`plan_batches` splits the runs that are not yet in ``runs.csv`` into batches (tasks) of
  ``batch_size`` runs of one (environment, method), interleaved over the cells.
* **Sampler / batch** – :func:`run_batch` samples the batch's scenarios, stacks their initial states and
  parameter vectors as columns and rolls them out together with
  :func:`~mmg_casadi.closed_loop.simulation.simulate_batch`: *one* compiled step per (environment, method) (all its runs
  share one :class:`~mmg_casadi.closed_loop.step.Layout`), ``map`` over the scenarios and ``mapaccum`` over chunks of
  steps until every scenario has finished. Each run is classified from its *final* state only
  (:func:`classify`): the closed-loop state carries goal time, CE/MCTE integrals, closest approach and the
  first collision of every ship.
* **Executors** – :class:`LocalExecutor` (a process pool, ``fork``) or :class:`RayExecutor` (a Ray cluster)
  run the batches and yield their rows as they complete. Workers never compile: :func:`prepare_layouts` builds
  every needed native library in the parent first (in parallel), workers load it from the disk cache
  (``$MMG_CASADI_CACHE``, forwarded to Ray workers).
* **Results** – :func:`run_study` appends each finished batch to ``runs.csv`` (durably; keys already stored are
  skipped, so an interrupted study resumes where it stopped and nothing is counted twice), then writes
  ``summary.csv``, ``summary.md``, ``statistics.png``, ``metrics.json`` and replayable TOML files of the first
  failures of every cell. A lock file keeps a second study from writing into the same directory at once.

Outcome of a run (own ship = agent 0, judged from the final state):

``success``
    the own ship reached its goal (status 1, so ``t_goal <= t_max``) and never came closer than the collision
    distance to another ship or a static obstacle (``t_collision < 0``).
``fleet_success``
    every ship reached its goal and no ship collided.
``failure``
    ``"collision"`` (own ship collided; ``failure_pair`` ``"0-j"`` for ship j or ``"0-obsk"`` for obstacle k,
    ``failure_time`` the first collision time), ``"diverged"`` (the own ship left the model envelope),
    ``"stalled"`` (not reached and no progress towards the goal for ``STALL_WINDOW`` before the end;
    ``failure_time`` the time of its closest approach to the goal), ``"timeout"`` (otherwise;
    ``failure_time`` = end time); ``""`` on success.

``failure_mechanism``
    why a failed run failed, one of :data:`mmg_casadi.montecarlo.failures.MECHANISMS` (``""`` on success): started too
    close, obstacle near the goal, near-goal, ship–ship, obstacle, stalled, timeout, diverged (see there).
``colregs_compliant``, ``colregs_encounters``
    whether the own ship kept the COLREGs (profile ``iitm-lab``) in all of its classified encounters with other
    ships, and how many there were (:func:`mmg_casadi.colregs.compliance.own_ship_compliance`, empty without one); judged
    on a history of positions and headings kept every :data:`HISTORY_EVERY` guidance steps by
    :func:`~mmg_casadi.closed_loop.simulation.simulate_batch_history`.

The summary adds the compliance rate per cell (Wilson 95 % interval over the runs with an encounter) and the
failure counts per mechanism; ``comparisons.csv`` holds the paired comparison of every two methods per
environment (:mod:`mmg_casadi.montecarlo.comparisons`).

Outcome, CE and MCTE are judged by :meth:`mmg_casadi.closed_loop.step.ClosedLoopModel.outcomes`, as for a single
scenario run (a diverged ship's CE/MCTE are ``nan``; summaries average them over successful runs only). Every
run uses the same resolved parameter set (``params`` of :func:`run_study`: the table's defaults with the
user's overrides), recorded in ``study.json``; a study is resumed only with the same parameters. Fleet metrics are means over the ships that
reached their goals. ``guidance_call_us`` is the compiled time of one guidance evaluation (field / velocity
obstacle + ILOS + PD) per ship, measured per batch on the batch's initial and final states; it is a timing
and differs between repetitions, everything else is a deterministic function of
``(environment, method, run, seed, t_max)``.

With ``current``/``wind`` ranges (:mod:`mmg_casadi.montecarlo.disturbance_sampling`) every run meets its own steady
current and wind, drawn from ``(environment, run, seed)`` by a generator of its own (the same for every method;
the encounters are those of the calm study); the columns ``current_speed``, ``current_direction_deg``,
``wind_speed``, ``wind_direction_deg`` of ``runs.csv`` record it (or the fixed values of ``params``), and
``study.json`` the ranges: a study is resumed only with the same ranges.
"""

from __future__ import annotations

import contextlib
import fcntl
import math
import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from mmg_casadi.guidance import methods as method_registry
from mmg_casadi.closed_loop.step import NS, S_, ClosedLoopModel, Layout, build_problem
from mmg_casadi.montecarlo.disturbance_sampling import ENV_COLUMNS, DisturbanceRanges, sample_disturbance
from mmg_casadi.errors import InputError
from mmg_casadi.io import write_json
from mmg_casadi.params import PARAMETERS, diff, resolve
from mmg_casadi.progress import progress_bar
from mmg_casadi.montecarlo.results import RUN_COLUMNS, ResultsTable, summarize
from mmg_casadi.montecarlo.sampling import ENVIRONMENTS, parse_envs, sample_scenario
from mmg_casadi.scenarios.scenario import Scenario, dump_scenario, scenario_from_dict, with_params
from mmg_casadi.signals import keep_termination_handlers, stop_pool, worker_initializer

DEFAULT_METHODS: tuple[str, ...] = method_registry.PAPER_STATISTICS
"""Methods compared by the paper's statistical analysis."""

BACKENDS: tuple[str, ...] = ("local", "ray")
DEFAULT_BATCH = 128
"""Runs per task (the unit of resumption): ≥ ~1 s of compiled work even for the lightest cell; inside a task
:func:`~mmg_casadi.closed_loop.simulation.simulate_batch` steps ``DEFAULT_WIDTH`` runs side by side and refills finished
columns with waiting runs."""
DEFAULT_CHUNK = 48
"""Steps per ``mapaccum`` chunk (the rollout stops after the chunk in which every run has finished; outcomes do not
depend on it: the clock stops at the horizon and a finished run is held)."""
MAX_FAILURE_FILES = 20
"""Replayable scenario files written per (environment, method) cell."""
TIMING_COLUMNS: tuple[str, ...] = ("guidance_call_us",)
"""Columns that are measurements of time (not reproducible run to run)."""


# ----------------------------------------------------------------------------------------------- sampling

def sampled_scenario(environment: int, method: str, run: int, base_seed: int = 0, *,
                     params: dict | None = None) -> Scenario:
    """The scenario of run ``run`` of ``environment`` with every ship using ``method`` and the parameter values
    ``params`` written into its settings (replayable on its own).

    Parameters
    ----------
    environment : int
        Environment number.
    method : str
        Collision-avoidance method of every ship.
    run : int
        Run index.
    base_seed : int, default 0
        Base seed of the scenario sampling.
    params : dict or None, optional
        Parameter values (table names) written into the settings.

    Examples
    --------
    >>> sc = sampled_scenario(1, "modified-vortex", 0, params={"t_max": 100.0})
    >>> len(sc.ships), len(sc.obstacles), sc.settings.method, sc.settings.t_max
    (3, 1, 'modified-vortex', 100.0)
    """
    sample = sample_scenario(environment, run, base_seed)
    sc = scenario_from_dict(sample.to_scenario_dict(method=method), source=f"env{environment}/{method}/run{run}")
    return with_params(sc, params)


def _non_default(params: dict | None) -> dict:
    """The entries of ``params`` that differ from the table's defaults (what a scenario file must carry)."""
    return {k: v for k, v in (params or {}).items() if v != PARAMETERS[k].default}


def layout_for(environment: int, method: str, params: dict | None = None) -> Layout:
    """The closed-loop :class:`Layout` shared by all runs of ``(environment, method)`` with ``params``.

    Parameters
    ----------
    environment : int
        Environment number.
    method : str
        Collision-avoidance method.
    params : dict or None, optional
        Parameter overrides (table names).

    Examples
    --------
    >>> lay = layout_for(2, "inverse-square")
    >>> lay.n_ships, lay.n_obstacles, lay.max_path
    (4, 2, 2)
    """
    return build_problem(sampled_scenario(environment, method, 0, 0, params=params)).layout


# ------------------------------------------------------------------------------------------ classification

def classify(model: ClosedLoopModel, x_final) -> dict:
    """Outcome and metrics of one run from its final scenario state (see the module docstring).

    Parameters
    ----------
    model : ClosedLoopModel
        The run's closed loop (layout and resolved parameters).
    x_final : array (nx,)
        Final scenario state ``[t, ship_0, ship_1, ...]``.

    Returns
    -------
    dict
        The non-key columns of :data:`~mmg_casadi.montecarlo.results.RUN_COLUMNS` except ``seed`` and
        ``guidance_call_us``.
    """
    x = np.asarray(x_final, float).ravel()
    layout = model.layout
    N = layout.n_ships
    ships = model.outcomes(x)
    own = ships[0]
    reached = np.array([s["status"] == "reached" for s in ships])
    collided = np.array([s["collision_time"] is not None for s in ships])
    if collided[0]:
        j = own["collision_with"]
        failure, pair, failure_time = "collision", (f"0-{j}" if j < N else f"0-obs{j - N}"), own["collision_time"]
    elif reached[0]:
        failure, pair, failure_time = "", "", math.nan
    elif own["status"] == "stalled":
        failure, pair, failure_time = "stalled", "", own["stalled_time"]
    elif own["status"] == "diverged":
        failure, pair, failure_time = "diverged", "", math.nan
    else:
        failure, pair, failure_time = "timeout", "", float(x[0])

    def fleet_mean(key):
        v = [s[key] for s, r in zip(ships, reached) if r]
        return float(np.mean(v)) if v else math.nan

    return {
        "success": bool(reached[0] and not collided[0]),
        "fleet_success": bool(np.all(reached) and not np.any(collided)),
        "failure": failure,
        "failure_pair": pair,
        "failure_time": failure_time,
        "time_to_goal": own["time_to_goal"] if reached[0] else math.nan,
        "ce": own["ce"],
        "mcte": own["mcte"],
        "fleet_time_to_goal": fleet_mean("time_to_goal"),
        "fleet_ce": fleet_mean("ce"),
        "fleet_mcte": fleet_mean("mcte"),
        "min_distance": math.nan if own["min_distance"] is None else own["min_distance"],
        "n_ships": N,
        "n_obstacles": layout.n_obstacles,
    }


# ------------------------------------------------------------------------------------------ batch rollout

@lru_cache(maxsize=32)
def _mapped_guidance(layout: Layout, n: int) -> ca.Function:
    from mmg_casadi.closed_loop.simulation import compiled_guidance
    return compiled_guidance(layout).map(n)


MIN_TIMING_COLUMNS = 256
"""Guidance timing evaluates at least this many scenario states per call (tiling the batch's states), so the
Python call overhead is negligible against the compiled work."""


def time_guidance(layout: Layout, X: np.ndarray, P: np.ndarray, *, min_time: float = 0.02,
                  max_repeats: int = 50) -> float:
    """Compiled time per guidance call per ship (µs), from the states ``X`` (nx, K) with parameters ``P``.

    The compiled guidance Function (:func:`~mmg_casadi.closed_loop.simulation.compiled_guidance`) is mapped over the
    columns (tiled to at least :data:`MIN_TIMING_COLUMNS`), called once to warm up and then repeatedly for
    about ``min_time`` seconds; the result is ``elapsed / (repeats * columns * N)``. Every ship is timed as
    sailing (status 0, clock 0) in the positions of ``X``: the rollouts skip the guidance of a ship that no
    longer sails, and a method sees only the neighbours within R_safe, so the time is that of the guidance
    the rollouts run for ``N`` sailing ships in those configurations.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout of the scenarios.
    X : numpy.ndarray (nx, K)
        Scenario states, one column per call.
    P : numpy.ndarray (np, K)
        Parameter vectors, one column per call (:func:`~mmg_casadi.closed_loop.step.pack_params`).
    min_time : float, default 0.02
        Approximate measuring time (seconds).
    max_repeats : int, default 50
        Largest number of timed calls.
    """
    X = np.array(X, float)
    P = np.asarray(P, float)
    X[0] = 0.0
    X[[1 + i * NS + S_["status"] for i in range(layout.n_ships)]] = 0.0
    reps = max(1, math.ceil(MIN_TIMING_COLUMNS / X.shape[1]))
    X = np.tile(X, (1, reps))
    P = np.tile(P, (1, reps))
    n = X.shape[1]
    F = _mapped_guidance(layout, n)
    Xd, Pd = ca.DM(X), ca.DM(P)
    F(Xd, Pd)  # warm-up (page in the library, allocate work vectors)
    t0 = time.perf_counter()
    F(Xd, Pd)
    one = time.perf_counter() - t0
    repeats = int(min(max_repeats, max(1, math.ceil(min_time / max(one, 1e-9)))))
    t0 = time.perf_counter()
    for _ in range(repeats):
        F(Xd, Pd)
    elapsed = time.perf_counter() - t0
    return 1e6 * elapsed / (repeats * n * layout.n_ships)


HISTORY_EVERY = 2
"""The batch rollout keeps every 2nd guidance step (0.5 L/U) of positions and headings for the COLREG scoring."""


def explain_run(scenario, model: ClosedLoopModel, x_final, t, states) -> dict:
    """``failure_mechanism``, ``colregs_compliant`` and ``colregs_encounters`` of one run.

    Parameters
    ----------
    scenario : Scenario
        The run's scenario (goals, obstacles).
    model : ClosedLoopModel
        Its closed loop (layout, resolved parameters).
    x_final : array (nx,)
        Final scenario state.
    t, states : array (K,), (K, N, 4)
        Decimated history (:meth:`mmg_casadi.closed_loop.simulation.BatchHistory.column`).
    """
    from mmg_casadi.colregs.compliance import own_ship_compliance
    from mmg_casadi.montecarlo.failures import failure_mechanism, turn_time_90, unavoidable_at_start
    P = model.params
    row = classify(model, x_final)
    own = model.outcomes(x_final)[0]
    goals = np.array([s.waypoints[-1] for s in scenario.ships], float)
    obstacles = np.array([o.position for o in scenario.obstacles], float).reshape(-1, 2)
    at = None
    if own["collision_time"] is not None and len(t) > 1:
        at = np.column_stack([np.interp(own["collision_time"], t, states[:, :, c][:, i])
                              for i in range(states.shape[1]) for c in (0, 1)]).reshape(-1, 2)
    unavoidable = False
    if own["collision_time"] is not None:
        j, ships = own["collision_with"], scenario.ships
        if j < len(ships):
            h = ships[j].heading_rad
            other, vel = ships[j].start, (ships[j].speed * math.cos(h), ships[j].speed * math.sin(h))
        else:
            other, vel = obstacles[j - len(ships)], (0.0, 0.0)
        unavoidable = unavoidable_at_start(ships[0].start, ships[0].heading_rad, ships[0].speed,
                                           other, vel, collision_distance=float(P["collision_distance"]),
                                           rudder_deg=float(P["delta_max_deg"]))
    mech = failure_mechanism(row["failure"], collision_time=own["collision_time"],
                             collision_with=own["collision_with"], goals=goals, obstacles=obstacles,
                             positions_at_collision=at, turn_time=turn_time_90(float(P["delta_max_deg"])),
                             near_goal_distance=float(P["near_goal_distance"]), unavoidable=unavoidable)
    compliant, n = own_ship_compliance(t, states, r_safe=float(P["r_safe"]),
                                       collision_distance=float(P["collision_distance"]))
    return {"failure_mechanism": mech, "colregs_compliant": compliant, "colregs_encounters": n}


def run_scenarios(scenarios, *, params: dict | None = None, chunk: int = DEFAULT_CHUNK,
                  time_guidance_calls: bool = True, explain: bool = True) -> list[dict]:
    """Simulate scenarios together and classify each from its final state.

    Scenarios with the same :class:`Layout` are rolled out as one batch (one compiled step, ``map`` over the
    scenarios, ``mapaccum`` over chunks of ``chunk`` steps). Returns one dict per scenario, in order, with the
    columns of :func:`classify` plus ``guidance_call_us`` (``nan`` unless ``time_guidance_calls``) and, with
    ``explain``, the columns of :func:`explain_run` (from a history kept every :data:`HISTORY_EVERY` steps).

    Parameters
    ----------
    scenarios : list of Scenario
        The scenarios.
    params : dict, optional
        Parameter overrides applied to every scenario (they win over its settings).
    chunk : int
        Steps per compiled chunk.
    time_guidance_calls : bool
        Measure the compiled guidance call per ship of every batch.
    explain : bool
        Keep a history and add the failure mechanism and the own ship's COLREG compliance.
    """
    from mmg_casadi.closed_loop.simulation import simulate_batch, simulate_batch_history
    problems = [build_problem(sc, params) for sc in scenarios]
    groups: dict[Layout, list[int]] = {}
    for i, pr in enumerate(problems):
        groups.setdefault(pr.layout, []).append(i)
    out: list[dict | None] = [None] * len(problems)
    for layout, idx in groups.items():
        X0 = np.column_stack([problems[i].x0 for i in idx])
        P = np.column_stack([problems[i].p for i in idx])
        every = HISTORY_EVERY if chunk % HISTORY_EVERY == 0 else 1
        if explain:
            XF, _busy, hist = simulate_batch_history(layout, X0, P, chunk=chunk, every=every)
        else:
            XF, _busy = simulate_batch(layout, X0, P, chunk=chunk)
        us = time_guidance(layout, np.hstack([X0, XF]), np.hstack([P, P])) if time_guidance_calls else math.nan
        for col, i in enumerate(idx):
            row = classify(problems[i].model, XF[:, col])
            row["guidance_call_us"] = us
            if explain:
                row.update(explain_run(scenarios[i], problems[i].model, XF[:, col], *hist.column(col)))
            out[i] = row
    return out  # type: ignore[return-value]


def run_batch(environment: int, method: str, runs, base_seed: int = 0, *, params: dict | None = None,
              chunk: int = DEFAULT_CHUNK, disturbance: DisturbanceRanges | None = None) -> list[dict]:
    """Simulate runs of one (environment, method) together and return their result rows.

    Parameters
    ----------
    environment : int
        Environment 1-5.
    method : str
        Collision-avoidance method of every ship.
    runs : list of int
        Run indices.
    base_seed : int
        Base seed of the study (stored in the ``seed`` column).
    params : dict, optional
        Parameter values of every run (by name; the table's defaults for the rest).
    chunk : int
        Steps per compiled chunk.
    disturbance : DisturbanceRanges, optional
        Ranges of the per-run current and wind (:func:`~mmg_casadi.montecarlo.disturbance_sampling.sample_disturbance`).

    Returns
    -------
    list of dict
        One row per run (keys :data:`~mmg_casadi.montecarlo.results.RUN_COLUMNS`), in the order of ``runs``.
    """
    runs = [int(r) for r in runs]
    if not runs:
        return []
    overrides = _non_default(params)
    env = _run_disturbances(environment, runs, base_seed, params, disturbance)
    scenarios = [sampled_scenario(environment, method, r, base_seed, params=_non_default({**overrides, **d}))
                 for r, d in zip(runs, env)]
    results = run_scenarios(scenarios, chunk=chunk)
    rows = []
    for r, res, d in zip(runs, results, env):
        row = {"environment": int(environment), "method": method, "run": r, "seed": int(base_seed), **res, **d}
        rows.append({c: row.get(c) for c in RUN_COLUMNS})
    return rows


def _run_disturbances(environment: int, runs, base_seed: int, params: dict | None,
                      ranges: DisturbanceRanges | None) -> list[dict]:
    """Per run, the :data:`ENV_COLUMNS` values: sampled from ``ranges`` if any, else those of ``params``."""
    if ranges is not None and ranges.active:
        return [sample_disturbance(environment, r, base_seed, ranges) for r in runs]
    fixed = resolve(params)
    return [{c: fixed[c] for c in ENV_COLUMNS} for _ in runs]


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
    """

    environment: int
    method: str
    runs: tuple
    base_seed: int = 0
    params: tuple = ()
    chunk: int = DEFAULT_CHUNK
    disturbance: DisturbanceRanges | None = None

    def __call__(self) -> list[dict]:
        return run_batch(self.environment, self.method, list(self.runs), self.base_seed,
                         params=dict(self.params), chunk=self.chunk, disturbance=self.disturbance)


def _run_task(task: BatchTask) -> list[dict]:
    return task()


def plan_batches(envs, methods, runs: int, *, done=frozenset(), base_seed: int = 0, params: dict | None = None,
                 batch_size: int = DEFAULT_BATCH, chunk: int = DEFAULT_CHUNK,
                 disturbance: DisturbanceRanges | None = None) -> list[BatchTask]:
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
            cells.append([BatchTask(env, m, tuple(todo[i:i + batch_size]), base_seed, items, chunk, disturbance)
                          for i in range(0, len(todo), batch_size)])
    tasks = []
    for k in range(max((len(c) for c in cells), default=0)):
        tasks += [c[k] for c in cells if k < len(c)]
    return tasks


def _compile_item(layout) -> float:
    from mmg_casadi.closed_loop.simulation import compiled_step
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
    from mmg_casadi.closed_loop.compiled import library_path
    from mmg_casadi.closed_loop.simulation import compiled_step, rollout_functions
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
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise InputError(field, "an integer >= 1 (or nothing for all cores)", value)
    return int(value)


WORKER_JOIN_TIMEOUT = 5.0
"""Seconds to wait for each terminated pool worker to exit when a study is interrupted."""
RAY_MAX_RETRIES = 3
"""Times Ray reruns a batch whose worker process died (its rows are appended once: appends skip stored keys)."""


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
    keys, so no run is lost or counted twice.

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
        try:
            import ray  # noqa: F401
        except ImportError:
            raise InputError("backend", "'local' (Ray is not installed; pip install 'mmg-casadi[ray]')",
                             "ray") from None

    def _runtime_env(self) -> dict | None:
        cache = os.environ.get("MMG_CASADI_CACHE")
        return {"env_vars": {"MMG_CASADI_CACHE": cache}} if cache else None

    def _ensure(self) -> dict:
        import ray
        renv = self._runtime_env()
        if ray.is_initialized():
            return {"runtime_env": renv} if renv else {}
        kw = {"address": self.address, "include_dashboard": False, "log_to_driver": False}
        if self.address is None and self.num_cpus is not None:
            kw["num_cpus"] = self.num_cpus
        if renv:
            kw["runtime_env"] = renv
        with keep_termination_handlers():  # SIGTERM keeps the CLI's resume path
            ray.init(**kw)
        self._owns = True
        return {}

    @property
    def parallelism(self) -> int:
        import ray
        if ray.is_initialized():
            return max(1, int(ray.cluster_resources().get("CPU", 1)))
        return self.num_cpus or os.cpu_count() or 1

    def run(self, tasks):
        """Yield ``(task, rows)`` for every task as it completes (completion order).

        Parameters
        ----------
        tasks : iterable of BatchTask
            The batches to run.
        """
        import ray
        tasks = list(tasks)
        if not tasks:
            return
        opts = self._ensure()
        remote = ray.remote(num_cpus=1, max_retries=RAY_MAX_RETRIES, retry_exceptions=False)(_run_task)
        if opts:
            remote = remote.options(**opts)
        refs = {remote.remote(t): t for t in tasks}
        pending = list(refs)
        try:
            while pending:
                ready, pending = ray.wait(pending, num_returns=1)
                for ref in ready:
                    yield refs[ref], ray.get(ref)
        finally:
            # a Ray this executor started is shut down by close(), which stops its tasks; cancelling them here
            # as well can race with a task completing and abort the driver (Ray 2.60 task_manager check)
            for ref in (() if self._owns else pending):
                try:
                    ray.cancel(ref, force=True)
                except Exception:  # noqa: BLE001 - best effort on interruption
                    pass

    def close(self) -> None:
        if self._owns:
            import ray
            ray.shutdown()
            self._owns = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# ----------------------------------------------------------------------------------------------- the study

def _check_envs(envs) -> tuple[int, ...]:
    if isinstance(envs, str):
        return parse_envs(envs)
    try:
        items = list(envs)
    except TypeError:
        raise InputError("envs", "environment numbers in 1-5", envs) from None
    if not items or any(isinstance(e, bool) or not isinstance(e, (int, np.integer)) or e not in ENVIRONMENTS
                        for e in items):
        raise InputError("envs", "environment numbers in 1-5", envs)
    return tuple(sorted({int(e) for e in items}))


def _check_int(field: str, value, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise InputError(field, f"an integer >= {low}", value)
    return int(value)


def run_study(out_dir, *, runs: int = 200, envs=(1, 2, 3, 4, 5), methods=DEFAULT_METHODS, base_seed: int = 0,
              params: dict | None = None, backend: str = "local", address: str | None = None,
              workers: int | None = None, progress: bool = True, batch_size: int = DEFAULT_BATCH,
              chunk: int = DEFAULT_CHUNK, executor=None, current=None, wind=None):
    """Run (or resume) the statistical study and write its outputs into ``out_dir``.

    Parameters
    ----------
    out_dir : str or Path
        Output directory: ``runs.csv`` (one row per run, appended as batches finish), ``study.json`` (the
        resolved parameter set and the seed the table was made with), ``summary.csv``, ``summary.md`` (with
        the failure mechanisms and the paired comparisons), ``comparisons.csv``,
        ``statistics.png``, ``metrics.json`` (config, parameters and summary rows) and
        ``failures/env{e}_{method}_run{r}.toml`` (first ≤ 20 failures per cell, replayable with
        ``mmg-casadi simulate``).
    runs : int
        Runs per (environment, method), ≥ 1; run indices ``0..runs-1``.
    envs : str or iterable of int
        Environments, e.g. ``"1-5"`` or ``(1, 3)``.
    methods : str or iterable of str
        Collision-avoidance methods (names in :data:`mmg_casadi.guidance.methods.METHODS`).
    base_seed : int
        Base seed of the scenario sampler (≥ 0); a resumed table must have been made with the same seed.
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`) for every run, e.g. from
        ``tune apf``; a resumed table must have been made with the same resolved parameters.
    backend : {"local", "ray"}
        Local process pool or a Ray cluster.
    address : str, optional
        Ray cluster address (backend ``"ray"``).
    workers : int, optional
        Local worker processes (default: all cores); for Ray the CPUs of a new local cluster.
    progress : bool
        Show a progress bar on stderr (rate and ETA count only runs simulated by this call).
    batch_size : int
        Runs per task.
    chunk : int
        Steps per compiled chunk.
    executor : LocalExecutor or RayExecutor, optional
        Use this executor instead of one made from ``backend``/``address``/``workers`` (not closed here).
    current : (float, float), optional
        Range of a per-run current speed (fraction of U_des, in [0, 1]; direction uniform); a resumed table
        must have been made with the same range. Not together with a ``current_speed`` in ``params``.
    wind : (float, float), optional
        Range of a per-run true wind speed (m/s, in [0, 60]; direction uniform), likewise.

    Returns
    -------
    Summary
        The summary of the requested cells (rows already in ``runs.csv`` included).
    """
    runs = _check_int("runs", runs, 1)
    if backend not in BACKENDS:
        raise InputError("backend", f"one of: {', '.join(BACKENDS)}", backend)
    if address is not None and backend != "ray":
        raise InputError("address", "nothing unless backend is 'ray'", address)
    envs = _check_envs(envs)
    methods = method_registry.parse_list(methods)
    base_seed = _check_int("base_seed", base_seed, 0)
    workers = _check_workers("workers", workers)
    batch_size = _check_int("batch_size", batch_size, 1)
    chunk = _check_int("chunk", chunk, 1)
    resolved = resolve(params, prefix="params.")
    ranges = DisturbanceRanges(current=current, wind=wind)
    for name, rng in (("current", ranges.current), ("wind", ranges.wind)):
        for key in (f"{name}_speed", f"{name}_direction_deg"):
            if rng is not None and resolved[key] != PARAMETERS[key].default:
                raise InputError(name, f"nothing while params sets {key} (a fixed {name})", list(rng))

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with _exclusive(out):
        return _run_study(out, runs, envs, methods, base_seed, resolved, backend, address, workers, progress,
                          batch_size, chunk, executor, ranges)


@contextlib.contextmanager
def _exclusive(out: Path):
    """Hold an exclusive lock on ``out/.study.lock`` so two studies never append to one ``runs.csv``."""
    fh = open(out / ".study.lock", "a+")
    try:
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise InputError("out_dir", "a directory no other running study is writing to", str(out)) from None
        yield
    finally:
        fh.close()


def _run_study(out, runs, envs, methods, base_seed, params, backend, address, workers, progress, batch_size,
               chunk, executor, ranges=DisturbanceRanges()):
    table = ResultsTable(out / "runs.csv")
    planned = {(e, m, r) for e in envs for m in methods for r in range(runs)}
    stored = [row for row in table.read() if (row["environment"], row["method"], row["run"]) in planned]
    for row in stored:
        if row["seed"] != base_seed:
            raise InputError("base_seed", f"the seed {row['seed']} that {table.path} was made with (or a new "
                             "output directory)", base_seed)
    done = {(row["environment"], row["method"], row["run"]) for row in stored}
    _check_study_params(out / "study.json", params, has_rows=bool(table.completed()), ranges=ranges)
    tasks = plan_batches(envs, methods, runs, done=done, base_seed=base_seed, params=params,
                         batch_size=batch_size, chunk=chunk, disturbance=ranges)
    log = sys.stderr if progress else None

    own_executor = executor is None
    if executor is None:
        executor = LocalExecutor(workers) if backend == "local" else RayExecutor(address, workers)
    started = time.perf_counter()
    new_runs = 0
    try:
        if tasks:
            cells = list(dict.fromkeys((t.environment, t.method) for t in tasks))
            n_compile = workers or os.cpu_count() or 1
            prepare_layouts([layout_for(e, m, _non_default({**params, **_run_disturbances(e, [0], base_seed, params,
                                                                                        ranges)[0]}))
                             for e, m in cells], n_compile, log=log)
            bar = None
            if progress:
                bar = progress_bar(len(planned), desc="statistics", initial=len(done))
            try:
                for _task, rows in executor.run(tasks):
                    written = table.append(rows)
                    new_runs += written
                    if bar is not None:
                        bar.update(written)
            finally:
                if bar is not None:
                    bar.close()
    finally:
        if own_executor:
            executor.close()
    elapsed = time.perf_counter() - started

    order = {m: i for i, m in enumerate(methods)}
    rows = [row for row in table.read() if (row["environment"], row["method"], row["run"]) in planned]
    rows.sort(key=lambda r: (r["environment"], order[r["method"]], r["run"]))
    summary = summarize(rows)
    summary.to_csv(out / "summary.csv")
    from mmg_casadi.montecarlo.comparisons import compare_methods, to_markdown, write_csv
    comparisons = compare_methods(rows, methods)
    write_csv(comparisons, out / "comparisons.csv")
    (out / "summary.md").write_text(
        summary.to_markdown() + "\n\n## Failure mechanisms (own ship; mmg_casadi.montecarlo.failures)\n\n"
        + summary.failures_markdown() + "\n\n## Paired comparisons (same runs; exact McNemar test)\n\n"
        + to_markdown(comparisons) + "\n", encoding="utf-8")
    from mmg_casadi.montecarlo.plots import plot_statistics
    plot_statistics(summary, out / "statistics.png")
    failures = write_failures(rows, out / "failures", params=params)

    config = {"runs": runs, "envs": list(envs), "methods": list(methods), "base_seed": base_seed,
              "backend": backend, "address": address, "workers": workers, "batch_size": batch_size, "chunk": chunk,
              **ranges.to_dict()}
    write_json(out / "metrics.json", {
        "config": config, "params": params, "summary": summary.rows, "comparisons": comparisons,
        "runs_total": len(rows),
        "runs_new": new_runs, "elapsed_s": elapsed, "failure_files": [str(p.relative_to(out)) for p in failures]})
    return summary


def _check_study_params(path: Path, params: dict, *, has_rows: bool,
                        ranges: DisturbanceRanges = DisturbanceRanges()) -> None:
    """Refuse to resume a table made with other parameters (they are not columns of ``runs.csv``) or other
    disturbance ranges; record them in ``study.json``. The error names the first differing parameter."""
    import json
    if has_rows and path.exists():
        try:
            stored = json.loads(path.read_text(encoding="utf-8"))["params"]
        except (OSError, ValueError, KeyError, TypeError):
            raise InputError("out_dir", f"a directory whose study.json records the parameters of its runs.csv "
                             f"({path} is unreadable or from an older version; use a new output directory)",
                             str(path.parent)) from None
        key = diff(stored, params)
        if key is not None:
            raise InputError(f"params.{key}", f"{stored.get(key)!r}, the value {path.parent / 'runs.csv'} was made "
                             "with (or a new output directory)", params[key])
        made = json.loads(path.read_text(encoding="utf-8")).get("disturbance") or DisturbanceRanges().to_dict()
        for name, rng in ranges.to_dict().items():
            if made.get(name) != rng:
                raise InputError(name, f"{made.get(name)!r}, the range {path.parent / 'runs.csv'} was made with "
                                 "(or a new output directory)", rng)
    if not path.exists() or not has_rows:
        write_json(path, {"params": params, "disturbance": ranges.to_dict()})


def write_failures(rows, directory, *, params: dict | None = None, limit: int = MAX_FAILURE_FILES) -> list[Path]:
    """Write the first ``limit`` failed runs (by run index) of every cell as replayable scenario TOML files.

    Files are named ``env{e}_{method}_run{r}.toml``; each holds the sampled scenario with that method and the
    study's non-default parameter values in its ``[settings]``.

    Parameters
    ----------
    rows : list of dict
        Rows of ``runs.csv``.
    directory : str or Path
        Where to write.
    params : dict, optional
        The study's parameters.
    limit : int
        Files per (environment, method).
    """
    directory = Path(directory)
    by_cell: dict[tuple[int, str], list[dict]] = {}
    for r in rows:
        if r.get("failure"):
            by_cell.setdefault((r["environment"], r["method"]), []).append(r)
    paths = []
    overrides = _non_default(params)
    for (env, method), failed in by_cell.items():
        for r in sorted(failed, key=lambda r: r["run"])[:limit]:
            recorded = {c: r[c] for c in ENV_COLUMNS if r.get(c) is not None and r[c] == r[c]}
            sc = sampled_scenario(env, method, r["run"], r["seed"] or 0, params=_non_default({**overrides,
                                                                                             **recorded}))
            path = directory / f"env{env}_{method}_run{r['run']}.toml"
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(dump_scenario(sc), encoding="utf-8")
            paths.append(path)
    return paths
