"""One batch of the statistical study: sampled scenarios rolled out together by the compiled closed loop, each
run judged from its final state.

:func:`run_batch` samples the runs of one (environment, method) with
:func:`~mmg_casadi.montecarlo.sampling.sample_scenario` (so every method meets the same scenarios), stacks their
initial states and parameter vectors as columns and rolls them out together with
:func:`~mmg_casadi.closed_loop.simulation.simulate_batch`: *one* compiled step per (environment, method) (all its runs
share one :class:`~mmg_casadi.closed_loop.layout.Layout`), ``map`` over the scenarios and ``mapaccum`` over chunks of
steps until every scenario has finished. Each run is classified from its *final* state only
(:func:`~mmg_casadi.closed_loop.outcome.run_outcome`): the closed-loop state carries goal time, CE/MCTE integrals, closest approach and the
first collision of every ship. Every run becomes one row of :data:`~mmg_casadi.montecarlo.results.RUN_COLUMNS`.

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
``colregs_risky``, ``colregs_lawful``, ``colregs_score``, ``colregs_compliant``, ``colregs_verdicts``
    the encounter scorer's view (:func:`mmg_casadi.colregs.scorer.score_encounters` with ``own = 0``, profile the
    parameter ``colregs_profile``) on a history of positions and headings kept every :data:`HISTORY_EVERY` guidance
    steps by :func:`~mmg_casadi.closed_loop.simulation.simulate_batch_history`: how many encounters with a risk of
    collision the own ship had with other ships (Rule 7 gate; those with at least one applicable rule), how many of
    them it kept every applicable rule in, the mean of their graded scores (``nan`` without one), the run-level
    flag (every risky encounter kept; empty without one) and each encounter's role, score and rule verdicts
    (:func:`format_verdicts`); see :func:`own_ship_encounters`.
``colregs_verdicts_published``, ``colregs_verdicts_iitm_lab``, ``colregs_verdicts_ntnu_2023``
    the same encounters' verdicts under each scoring profile (:data:`PROFILE_COLUMNS`): the headline
    (``colregs_profile``) always, every profile with ``colregs_all_profiles``, so that a study reports them side by
    side; empty for a profile not scored.
``colregs_rule9``
    the own ship's COLREG Rule 9(a) score in a narrow channel (:func:`mmg_casadi.colregs.narrow_channel.rule9`
    on the same history): the share of her time in a narrow channel spent on the starboard side of its centre
    line (kept from 0.9); ``nan`` when she was never in one (every environment without walls or land).

Outcome, CE and MCTE are judged by :meth:`mmg_casadi.closed_loop.problem.ClosedLoopModel.outcomes`, as for a single
scenario run (a diverged ship's CE/MCTE are ``nan``; summaries average them over successful runs only). Fleet
metrics are means over the ships that reached their goals. ``guidance_call_us`` is the compiled time of one
guidance evaluation (field / velocity obstacle + ILOS + PD) per ship, measured per batch on the batch's initial
and final states (:func:`time_guidance`); it is a timing and differs between repetitions, everything else is a
deterministic function of ``(environment, method, run, seed, t_max)``.
"""

from __future__ import annotations

import math
import time
from functools import lru_cache

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop.simulation import (
    compiled_guidance,
    sailing_mask,
    simulate_batch,
    simulate_batch_history,
)
from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.closed_loop.outcome import run_outcome
from mmg_casadi.closed_loop.problem import ClosedLoopModel, build_problem
from mmg_casadi.closed_loop.state import tallies
from mmg_casadi.colregs.narrow_channel import rule9
from mmg_casadi.colregs.profiles import SCORING_PROFILES, scoring_profile
from mmg_casadi.colregs.scorer import prepare, score_prepared
from mmg_casadi.guidance.methods import forget_on_unregister
from mmg_casadi.montecarlo.encounter_summary import format_verdicts
from mmg_casadi.montecarlo.disturbance_sampling import ENV_COLUMNS, DisturbanceRanges, sample_disturbance
from mmg_casadi.montecarlo.failures import failure_mechanism, turn_time_90, unavoidable_at_start
from mmg_casadi.montecarlo.results import RUN_COLUMNS, TALLIES_KEY
from mmg_casadi.montecarlo.sampling import sample_scenario
from mmg_casadi.params import PARAMETERS, resolve
from mmg_casadi.perception.layer import perception_error, run_seed
from mmg_casadi.traffic.mix import is_mix
from mmg_casadi.traffic.sample import describe, draw_behaviours
from mmg_casadi.scenarios.scenario import Scenario, scenario_from_dict, with_params
from mmg_casadi.vessel.library import pair_collision_distance, ship_size

DEFAULT_CHUNK = 48
"""Steps per ``mapaccum`` chunk (the rollout stops after the chunk in which every run has finished; outcomes do not
depend on it: the clock stops at the horizon and a finished run is held)."""
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

    Returns
    -------
    Scenario
        The validated scenario, its source ``env<environment>/<method>/run<run>``.

    Examples
    --------
    >>> sc = sampled_scenario(1, "modified-vortex", 0, params={"t_max": 100.0})
    >>> len(sc.ships), len(sc.obstacles), sc.settings.method, sc.settings.t_max
    (3, 1, 'modified-vortex', 100.0)
    """
    sample = sample_scenario(environment, run, base_seed)
    targets = (params or {}).get("targets", PARAMETERS["targets"].default)
    slowdown = (params or {}).get("target_slowdown", PARAMETERS["target_slowdown"].default)
    hulls = (params or {}).get("target_vessels", PARAMETERS["target_vessels"].default)
    drawn = run_behaviours(environment, run, base_seed, sample.n_ships - 1, params) if is_mix(targets) else None
    sc = scenario_from_dict(sample.to_scenario_dict(method=method, targets=targets, target_slowdown=slowdown,
                                                    target_vessels=hulls, behaviours=drawn),
                            source=f"env{environment}/{method}/run{run}")
    if (params or {}).get("perception", "off") != "off":  # the run's own sensor noise, drawn from the study's seed
        params = {**params, "perception_seed": run_perception_seed(environment, run, base_seed, params)}
    return with_params(sc, params)


def run_behaviours(environment: int, run: int, base_seed: int, n_targets: int, params: dict | None) -> list[dict]:
    """The drawn behaviours of a run's targets under the study's ``params`` (:func:`mmg_casadi.traffic.sample.draw_behaviours`).

    Parameters
    ----------
    environment, run, base_seed : int
        The run.
    n_targets : int
        Its target ships.
    params : dict or None
        The study's parameter values (``targets`` and the ranges of group ``traffic``; the table's defaults for the
        rest).

    Returns
    -------
    list of dict
        One per target.
    """
    return draw_behaviours(environment, run, base_seed, n_targets, resolve(params))


def run_perception_seed(environment: int, run: int, base_seed: int, params: dict | None) -> int:
    """The ``perception_seed`` of a run: drawn from the study's seed and the run (the same for every method), with
    the study's ``perception_seed`` as a further word of the sequence (:func:`mmg_casadi.perception.layer.run_seed`).

    Parameters
    ----------
    environment, run, base_seed : int
        The run.
    params : dict or None
        The study's parameter values.

    Returns
    -------
    int
        The seed.
    """
    return run_seed(int(base_seed) + (1 << 32) * int((params or {}).get("perception_seed", 0)), environment, run)


def target_behaviours(environment: int, run: int, base_seed: int, n_ships: int, params: dict | None) -> str:
    """The ``target_behaviours`` cell of a run: each target's drawn behaviour (a mix,
    :func:`mmg_casadi.traffic.sample.describe`) or the study's one behaviour for every target.

    Parameters
    ----------
    environment, run, base_seed : int
        The run.
    n_ships : int
        Its ships, the own ship included.
    params : dict or None
        The study's parameter values.

    Returns
    -------
    str
        One ``;``-separated entry per target.
    """
    targets = (params or {}).get("targets", PARAMETERS["targets"].default)
    if is_mix(targets):
        return describe(run_behaviours(environment, run, base_seed, n_ships - 1, params))
    return ";".join([targets] * (n_ships - 1))


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

    Returns
    -------
    Layout
        The layout of run 0 with seed 0 (every run of the pair has the same one).

    Examples
    --------
    >>> lay = layout_for(2, "inverse-square")
    >>> lay.n_ships, lay.n_obstacles, lay.max_path
    (4, 2, 2)
    """
    return build_problem(sampled_scenario(environment, method, 0, 0, params=params)).layout


# ------------------------------------------------------------------------------------------ classification

# ------------------------------------------------------------------------------------------ batch rollout

@lru_cache(maxsize=32)
def _mapped_guidance(layout: Layout, n: int) -> ca.Function:
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
        Parameter vectors, one column per call (:func:`~mmg_casadi.closed_loop.layout.pack_params`).
    min_time : float, default 0.02
        Approximate measuring time (seconds).
    max_repeats : int, default 50
        Largest number of timed calls.

    Returns
    -------
    float
        Time per guidance call per ship (µs).
    """
    X = np.array(X, float)
    P = np.asarray(P, float)
    X[0] = 0.0
    X[layout.rows("status")] = 0.0
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

PROFILE_COLUMNS: dict[str, str] = {name: f"colregs_verdicts_{name.replace('-', '_')}" for name in SCORING_PROFILES}
"""Column of ``runs.csv`` holding each scoring profile's ``colregs_verdicts``."""


def profile_columns(params: dict) -> dict[str, str]:
    """The :data:`PROFILE_COLUMNS` a study with the resolved ``params`` fills: its ``colregs_profile`` first, then,
    with ``colregs_all_profiles``, the others in registry order.

    Parameters
    ----------
    params : dict
        The study's resolved parameters.

    Returns
    -------
    dict
        ``{profile: column}``.

    Examples
    --------
    >>> list(profile_columns({"colregs_profile": "iitm-lab", "colregs_all_profiles": True}))
    ['iitm-lab', 'published', 'ntnu-2023']
    >>> list(profile_columns({"colregs_profile": "iitm-lab", "colregs_all_profiles": False}))
    ['iitm-lab']
    """
    headline = params["colregs_profile"]
    others = {n: c for n, c in PROFILE_COLUMNS.items() if n != headline} if params["colregs_all_profiles"] else {}
    return {headline: PROFILE_COLUMNS[headline], **others}


def own_ship_encounters(t, states, profile=None, *, alternatives=()) -> dict:
    """``colregs_risky``, ``colregs_lawful``, ``colregs_score``, ``colregs_compliant`` and ``colregs_verdicts`` of
    one run: the own ship's (ship 0) encounters with a risk of collision, judged by
    :func:`~mmg_casadi.colregs.scorer.score_encounters`; an encounter that ends before its CPA is unfinished and not
    counted.

    Only the ships that come within the risk gate's reach of the own ship while both sail are scored: the range
    ``r_risk``, or with a time horizon ``d_risk`` plus the largest closing speed of the history over ``t_risk``
    (a ship farther away has no risk of collision and no duty; the verdicts are the same).

    Parameters
    ----------
    t : array (K,)
        Sample times (L/U).
    states : array (K, N, 4)
        ``x``, ``y`` (L), ``psi`` (rad) and ``status`` of every ship (ship 0 the own ship), as kept by
        :func:`mmg_casadi.closed_loop.simulation.simulate_batch_history`.
    profile : ScoringProfile or str, optional
        Scoring profile or its name (default ``"published"``).
    alternatives : sequence of str, optional
        Names of profiles (:data:`~mmg_casadi.colregs.profiles.SCORING_PROFILES`) whose verdicts are also given,
        each as the column :data:`PROFILE_COLUMNS` names.

    Returns
    -------
    dict
        ``colregs_risky`` (int), ``colregs_lawful`` (int), ``colregs_score`` (float, ``nan`` if no risky one),
        ``colregs_compliant`` (every risky encounter kept; ``None`` without one) and ``colregs_verdicts`` (str,
        :func:`~mmg_casadi.montecarlo.encounter_summary.format_verdicts` with the ships' scenario indices); and the
        verdicts of each of ``alternatives`` under its :data:`PROFILE_COLUMNS` name.

    Examples
    --------
    Head-on 2 L abeam, nobody alters course: one risky encounter, not kept (Rule 14 needs a starboard turn).

    >>> t = np.linspace(0.0, 40.0, 81)
    >>> own = np.column_stack([t, 0 * t, 0 * t, 0 * t])
    >>> other = np.column_stack([50.0 - t, 2.0 + 0 * t, np.pi + 0 * t, 0 * t])
    >>> r = own_ship_encounters(t, np.stack([own, other], axis=1))
    >>> r["colregs_risky"], r["colregs_lawful"], r["colregs_score"] < 0.5, r["colregs_compliant"]
    (1, 0, True, False)
    >>> r["colregs_verdicts"].split(":")[:2]
    ['1', 'head-on']
    """
    t = np.asarray(t, float)
    states = np.asarray(states, float)
    mask = sailing_mask(states[:, :, 3])
    dist = np.linalg.norm(states[:, 1:, :2] - states[:, :1, :2], axis=2)
    both = mask[:, :1] & mask[:, 1:]
    speed = (np.max(np.linalg.norm(np.diff(states[:, :, :2], axis=0), axis=2) / np.diff(t)[:, None])
             if t.size > 1 else 0.0)
    profiles = list(dict.fromkeys((scoring_profile(profile), *(scoring_profile(n) for n in alternatives))))
    # a ship that never comes within a profile's risk gate's reach has no risk of collision and no duty under it
    reach = max(min(p.r_risk, p.d_risk + 2.0 * speed * p.t_risk) if math.isfinite(p.t_risk) else p.r_risk
                for p in profiles)
    ships = [0, *(1 + np.flatnonzero(np.any((dist <= reach) & both, axis=0)))]
    scored = {p: [] for p in profiles}  # profile -> its risky encounters
    if len(ships) > 1 and t.size > 1:  # one sample has no velocity, hence no risk of collision
        prep = prepare(t, states[:, ships, :2], states[:, ships, 2], active=mask[:, ships], own=0)
        for p in profiles:
            scored[p] = [e for e in score_prepared(prep, p, applicable_only=True) if e.judged]
    risky = scored[scoring_profile(profile)]
    lawful = sum(1 for e in risky if e.compliant)
    return {"colregs_risky": len(risky), "colregs_lawful": lawful,
            "colregs_score": float(np.mean([e.score for e in risky])) if risky else math.nan,
            "colregs_compliant": lawful == len(risky) if risky else None,
            "colregs_verdicts": format_verdicts(risky, ships),
            **{PROFILE_COLUMNS[n]: format_verdicts(scored[scoring_profile(n)], ships) for n in alternatives}}


def explain_run(scenario, model: ClosedLoopModel, x_final, t, states) -> dict:
    """``failure_mechanism`` and the COLREG columns (:func:`own_ship_encounters`) of one run.

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

    Returns
    -------
    dict
        ``failure_mechanism`` (one of :data:`~mmg_casadi.montecarlo.failures.MECHANISMS`, ``""`` for a success)
        and the columns of :func:`own_ship_encounters`.
    """
    P = model.params
    row = run_outcome(model.layout, x_final, model.params)
    own = model.outcomes(x_final)[0]
    goals = np.array([s.waypoints[-1] for s in scenario.ships], float)
    obstacles = np.array([o.position for o in scenario.obstacles], float).reshape(-1, 2)
    at = None
    if own["collision_time"] is not None and len(t) > 1:
        at = np.column_stack([np.interp(own["collision_time"], t, states[:, :, c][:, i])
                              for i in range(states.shape[1]) for c in (0, 1)]).reshape(-1, 2)
    unavoidable = False
    if own["collision_kind"] in ("ship", "obstacle"):  # walls and land have no start-time test
        j, ships = own["collision_with"], scenario.ships
        reach = float(P["collision_distance"])
        if j < len(ships):
            h = ships[j].heading_rad
            other, vel = ships[j].start, (ships[j].speed * math.cos(h), ships[j].speed * math.sin(h))
            own_len, other_len = (ship_size(s.vessel or P["vessel"], s.length_m, unit=ships[0].vessel or P["vessel"])[0]
                                  for s in (ships[0], ships[j]))
            reach = pair_collision_distance(reach, own_len, other_len)
        else:
            other, vel = obstacles[j - len(ships)], (0.0, 0.0)
        unavoidable = unavoidable_at_start(ships[0].start, ships[0].heading_rad, ships[0].speed,
                                           other, vel, collision_distance=reach,
                                           rudder_deg=float(P["delta_max_deg"]))
    mech = failure_mechanism(row["failure"], collision_time=own["collision_time"],
                             collision_with=own["collision_with"], goals=goals, obstacles=obstacles,
                             positions_at_collision=at, turn_time=turn_time_90(float(P["delta_max_deg"])),
                             near_goal_distance=float(P["near_goal_distance"]), unavoidable=unavoidable)
    return {"failure_mechanism": mech, **dict.fromkeys(PROFILE_COLUMNS.values(), ""),  # "" for a profile not scored
            **own_ship_encounters(t, states, P["colregs_profile"],
                                  alternatives=tuple(SCORING_PROFILES) if P["colregs_all_profiles"] else
                                  (P["colregs_profile"],)),
            "colregs_rule9": own_ship_rule9(scenario, t, states, P["colregs_profile"])}


def own_ship_rule9(scenario, t, states, profile=None) -> float:
    """The own ship's Rule 9(a) score (:func:`mmg_casadi.colregs.narrow_channel.rule9`) of one run.

    Parameters
    ----------
    scenario : Scenario
        The run's scenario (its walls and land).
    t, states : array (K,), (K, N, 4)
        Decimated history, as for :func:`own_ship_encounters`.
    profile : str, optional
        The scoring profile, whose ``rule9_width`` says which channels are narrow (default ``published``).

    Returns
    -------
    float
        The share of the own ship's time in a narrow channel on its starboard side; ``nan`` when she was never in
        one.
    """
    banks = [seg for w in scenario.walls for seg in w.segments] + [e for land in scenario.land for e in land.edges]
    if not banks:
        return math.nan
    states = np.asarray(states, float)
    r = rule9(t, states[:, 0, :2], states[:, 0, 2], sailing_mask(states[:, :, 3])[:, 0], banks, profile=profile)
    return math.nan if r is None else r.score


def run_scenarios(scenarios, *, params: dict | None = None, chunk: int = DEFAULT_CHUNK,
                  time_guidance_calls: bool = True, explain: bool = True, histories: dict | None = None) -> list[dict]:
    """Simulate scenarios together and classify each from its final state.

    Scenarios with the same :class:`Layout` are rolled out as one batch (one compiled step, ``map`` over the
    scenarios, ``mapaccum`` over chunks of ``chunk`` steps). Returns one dict per scenario, in order, with the
    columns of :func:`~mmg_casadi.closed_loop.outcome.run_outcome` plus ``guidance_call_us`` (``nan`` unless ``time_guidance_calls``) and, with
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
    histories : dict, optional
        With ``explain``, filled with ``{i: (scenario, t, states)}``: the decimated history the row of scenario ``i``
        was judged from (:func:`mmg_casadi.montecarlo.explain.explain_run`).

    Returns
    -------
    list of dict
        One row per scenario, in the order of ``scenarios``.
    """
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
            row = run_outcome(problems[i].layout, XF[:, col], problems[i].params)
            row["guidance_call_us"] = us
            row["perception_error"] = perception_error(layout, XF[:, col])
            counts = tallies(layout, XF[:, col])[0]  # the own ship's planner counts, if her method has any
            if counts:
                row[TALLIES_KEY] = counts
            if explain:
                row.update(explain_run(scenarios[i], problems[i].model, XF[:, col], *hist.column(col)))
                if histories is not None:
                    histories[i] = (scenarios[i], *hist.column(col))
            out[i] = row
    return out  # type: ignore[return-value]


def run_batch(environment: int, method: str, runs, base_seed: int = 0, *, params: dict | None = None,
              chunk: int = DEFAULT_CHUNK, disturbance: DisturbanceRanges | None = None,
              histories: dict | None = None) -> list[dict]:
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
    histories : dict, optional
        Filled with each run's scenario and history, by position in ``runs`` (:func:`run_scenarios`).

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
    results = run_scenarios(scenarios, chunk=chunk, histories=histories)
    rows = []
    for r, res, d in zip(runs, results, env):
        row = {"environment": int(environment), "method": method, "run": r, "seed": int(base_seed), **res, **d,
               "target_behaviours": target_behaviours(environment, r, base_seed, res["n_ships"], params)}
        rows.append({c: row.get(c) for c in RUN_COLUMNS + ((TALLIES_KEY,) if TALLIES_KEY in res else ())})
    return rows


def _run_disturbances(environment: int, runs, base_seed: int, params: dict | None,
                      ranges: DisturbanceRanges | None) -> list[dict]:
    """Per run, the :data:`ENV_COLUMNS` values: sampled from ``ranges`` if any, else those of ``params``."""
    if ranges is not None and ranges.active:
        return [sample_disturbance(environment, r, base_seed, ranges) for r in runs]
    fixed = resolve(params)
    return [{c: fixed[c] for c in ENV_COLUMNS} for _ in runs]


forget_on_unregister(_mapped_guidance.cache_clear)
