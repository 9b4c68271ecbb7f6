"""Robustness of a run: how far the own ship stayed from failing, evaluated exactly on the compiled rollout.

Objectives (:data:`OBJECTIVES`), each a number that is negative exactly when the run fails:

``collision``
    the smallest margin ``min_k min_j (d_0j(t_k) − r_j)`` of the own ship (ship 0) to any ship, static obstacle or
    land edge over the guidance steps: ``d`` the centre distance (to a land edge the distance to the segment), ``r``
    what the closed loop calls touching (:func:`~mmg_casadi.closed_loop.step.meet`: for two ships the collision
    distance scaled by their mean length, for an obstacle the collision distance, for land half the own beam plus
    the grounding margin). A pair counts at step ``k + 1`` when both were present at step ``k`` and the run was
    still running, as the closed loop counts it; so the margin is negative exactly when the own ship collides or
    grounds (its ``d_min`` row less the collision distance, with land).
``grounding``
    the same margin to land edges only (environment 6).
``colregs``
    the own ship's COLREG rule scores (:mod:`mmg_casadi.colregs`, the study's scoring profile): over its encounters
    with a risk of collision that are judged (:func:`~mmg_casadi.montecarlo.execution.own_ship_encounters`) and
    every applicable rule, the smallest ``score`` of a kept rule and ``score − 1`` of a broken one; negative exactly
    when a rule is broken, and ``1`` when the own ship met no risk of collision. Scores on the history every
    :data:`~mmg_casadi.montecarlo.execution.HISTORY_EVERY` steps, as the study.

Every evaluation rolls the scenarios out with the study's compiled step
(:func:`~mmg_casadi.closed_loop.simulation.simulate_batch_history`, a history at every step) and keeps, for a failure,
the encounter geometry
that :mod:`~mmg_casadi.falsify.report` clusters (:func:`failure_geometry`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mmg_casadi.closed_loop.outcome import run_outcome
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import sailing_mask, simulate_batch_history
from mmg_casadi.colregs.profiles import scoring_profile
from mmg_casadi.colregs.scorer import prepare, score_prepared
from mmg_casadi.errors import InputError
from mmg_casadi.falsify.envelope import Envelope
from mmg_casadi.guidance.methods import run_of
from mmg_casadi.montecarlo.execution import DEFAULT_CHUNK, HISTORY_EVERY
from mmg_casadi.montecarlo.land_sampling import ENVIRONMENT as LAND_ENVIRONMENT
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.scenario import Scenario, scenario_from_dict, with_params
from mmg_casadi.vessel.library import pair_collision_distance

OBJECTIVES: tuple[str, ...] = ("collision", "colregs", "grounding")
"""The falsification objectives (module docstring)."""
NO_RISK = 1.0
"""The ``colregs`` robustness of a run without an encounter that carries verdicts."""


def check_objective(objective: str, environment: int) -> str:
    """``objective`` if it is one of :data:`OBJECTIVES` and applies to ``environment``, else an InputError.

    Parameters
    ----------
    objective : str
        The objective's name.
    environment : int
        The environment searched (``grounding`` needs land: environment 6).

    Returns
    -------
    str
        ``objective``.

    Examples
    --------
    >>> check_objective("grounding", 5)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: objective: expected collision or colregs in environment 5 (grounding needs land: environment 6), got 'grounding'
    """
    if objective not in OBJECTIVES:
        raise InputError("objective", f"one of: {', '.join(OBJECTIVES)}", objective)
    if objective == "grounding" and environment != LAND_ENVIRONMENT:
        raise InputError("objective", f"collision or colregs in environment {environment} (grounding needs land: "
                         "environment 6)", objective)
    return objective


def scenario_of(envelope: Envelope, theta, method: str, params: dict | None = None, *, label: str = "") -> Scenario:
    """The scenario of a parameter vector: every ship sails ``method`` (as in the study), ``params`` and the
    vector's current and wind are written into its settings, so the scenario file replays it on its own.

    Parameters
    ----------
    envelope : Envelope
        The envelope ``theta`` belongs to.
    theta : array (dimension,)
        The parameter vector.
    method : str
        Every ship's method.
    params : dict, optional
        Parameter values written into the settings (table names; those equal to the default are left out).
    label : str, optional
        The scenario's source label.

    Returns
    -------
    Scenario
        The validated scenario.
    """
    s = envelope.decode(theta)
    values = {**(params or {}), **envelope.disturbance_of(theta)}
    values = {k: v for k, v in values.items() if v != PARAMETERS[k].default}
    sc = scenario_from_dict(s.to_scenario_dict(method=method), source=label or f"falsify/env{envelope.environment}")
    return with_params(sc, values)


@dataclass
class Evaluation:
    """One simulated parameter vector and its robustness.

    Parameters
    ----------
    theta : numpy.ndarray
        The parameter vector.
    robustness : float
        The exact robustness under the objective (negative: a failure).
    failure : bool
        ``robustness < 0``.
    row : dict
        The run's outcome (:func:`~mmg_casadi.closed_loop.outcome.run_outcome`).
    detail : dict
        Where the robustness was attained: ``agent`` (index, ships first, then obstacles and land edges) and
        ``kind``, ``time`` (L/U), ``margin`` per kind; for ``colregs`` the encounter's ``other``, ``role``,
        ``rule``.
    geometry : dict or None
        The encounter geometry where the robustness was attained (:func:`failure_geometry`): for a failure what
        :mod:`~mmg_casadi.falsify.report` clusters, else the closest call's (None when nothing counted).
    """

    theta: np.ndarray
    robustness: float
    failure: bool
    row: dict
    detail: dict = field(default_factory=dict)
    geometry: dict | None = None


def evaluate(envelope: Envelope, thetas, method: str, objective: str = "collision", params: dict | None = None, *,
             chunk: int = DEFAULT_CHUNK) -> list[Evaluation]:
    """Simulate parameter vectors with the study's compiled rollout and evaluate their exact robustness.

    Parameters
    ----------
    envelope : Envelope
        The envelope of the vectors.
    thetas : sequence of array
        Parameter vectors (inside the envelope).
    method : str
        Every ship's method.
    objective : str, default "collision"
        One of :data:`OBJECTIVES`.
    params : dict, optional
        Parameter overrides (table names) of every run.
    chunk : int
        Steps per compiled call.

    Returns
    -------
    list of Evaluation
        One per vector, in order.
    """
    check_objective(objective, envelope.environment)
    scenarios = [scenario_of(envelope, th, method, params) for th in thetas]
    problems = [build_problem(sc) for sc in scenarios]
    groups: dict = {}
    for i, pr in enumerate(problems):
        groups.setdefault(pr.layout, []).append(i)
    out: list = [None] * len(problems)
    with run_of([method], params):
        for layout, idx in groups.items():
            X0 = np.column_stack([problems[i].x0 for i in idx])
            P = np.column_stack([problems[i].p for i in idx])
            XF, _busy, hist = simulate_batch_history(layout, X0, P, chunk=chunk, every=1)
            for col, i in enumerate(idx):
                t, states = hist.column(col)
                out[i] = judge(problems[i], scenarios[i], np.asarray(thetas[i], float), XF[:, col], t, states,
                               objective)
    return out


def judge(problem, scenario: Scenario, theta, x_final, t, states, objective: str) -> Evaluation:
    """The :class:`Evaluation` of one rollout from its final state and its history at every step.

    Parameters
    ----------
    problem : Problem
        The run's problem (:func:`~mmg_casadi.closed_loop.problem.build_problem`).
    scenario : Scenario
        Its scenario.
    theta : numpy.ndarray
        Its parameter vector.
    x_final : numpy.ndarray (nx,)
        Final scenario state.
    t, states : numpy.ndarray (K,), (K, N, 4)
        Times and ``x, y, psi, status`` of every ship at every step.
    objective : str
        One of :data:`OBJECTIVES`.

    Returns
    -------
    Evaluation
        Robustness, failure, outcome row, where the robustness was attained and, for a failure, its geometry.
    """
    row = run_outcome(problem.layout, x_final, problem.params)
    if objective == "colregs":
        rho, detail = colregs_robustness(t, states, problem.params["colregs_profile"])
    else:
        margins, kinds = own_margins(problem, scenario, t, states)
        if objective == "grounding":
            margins = np.where(np.array(kinds) == "land", margins, np.nan)
        rho, detail = _least_margin(margins, kinds, t)
    fail = bool(rho < 0.0)
    ev = Evaluation(np.asarray(theta, float), float(rho), fail, row, detail)
    if detail.get("time") is not None:  # a failure's geometry, or that of the closest call
        ev.geometry = failure_geometry(scenario, t, states, detail, float(problem.params["r_safe"]))
    return ev


def agent_reaches(problem, scenario: Scenario) -> tuple[np.ndarray, list[str], np.ndarray]:
    """Per agent of the own ship (ships 1..N-1, obstacles, walls and land edges in the closed loop's order): the
    distance below which the closed loop calls it touching, its kind, and the agent's geometry.

    Parameters
    ----------
    problem : Problem
        The run's problem.
    scenario : Scenario
        Its scenario (obstacles, walls and land).

    Returns
    -------
    reach : numpy.ndarray (A,)
        Touching distances (L).
    kinds : list of str
        ``"ship"``, ``"obstacle"``, ``"wall"`` or ``"land"``.
    where : numpy.ndarray (A, 4)
        Obstacles ``(x, y, nan, nan)``, segments ``(ax, ay, bx, by)``; ships ``nan``.
    """
    P = problem.params
    c = float(P["collision_distance"])
    ships = problem.ships
    reach = [pair_collision_distance(c, ships[0]["length"], s["length"]) for s in ships[1:]]
    kinds = ["ship"] * (len(ships) - 1)
    where = [[math.nan] * 4 for _ in ships[1:]]
    for o in scenario.obstacles:
        reach.append(c)
        kinds.append("obstacle")
        where.append([o.position[0], o.position[1], math.nan, math.nan])
    half_beam = float(ships[0]["half_beam"])
    for w in scenario.walls:
        for a, b in w.segments:
            reach.append(half_beam)
            kinds.append("wall")
            where.append([a[0], a[1], b[0], b[1]])
    for land in scenario.land:
        for a, b in land.edges:
            reach.append(half_beam + float(P["grounding_margin"]))
            kinds.append("land")
            where.append([a[0], a[1], b[0], b[1]])
    return np.array(reach, float), kinds, np.array(where, float).reshape(-1, 4)


def segment_distance(points, seg) -> tuple[np.ndarray, np.ndarray]:
    """Distance from points to a segment and the segment's parameter of the nearest point.

    Parameters
    ----------
    points : array (K, 2)
        Points (L).
    seg : array (4,)
        ``(ax, ay, bx, by)`` (L).

    Returns
    -------
    distance : numpy.ndarray (K,)
        Distance to the nearest point of the segment (L).
    s : numpy.ndarray (K,)
        Its parameter in ``[0, 1]`` from ``a`` to ``b``.

    Examples
    --------
    >>> d, s = segment_distance(np.array([[5.0, 2.0], [-3.0, 4.0]]), np.array([0.0, 0.0, 10.0, 0.0]))
    >>> d.tolist(), s.tolist()
    ([2.0, 5.0], [0.5, 0.0])
    """
    a, b = np.asarray(seg[:2], float), np.asarray(seg[2:], float)
    ab = b - a
    s = np.clip(((points - a) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
    return np.linalg.norm(points - a - s[:, None] * ab, axis=1), s


def own_margins(problem, scenario: Scenario, t, states) -> tuple[np.ndarray, list[str]]:
    """The own ship's margin to every agent at every step, NaN where the pair does not count (module docstring).

    Parameters
    ----------
    problem : Problem
        The run's problem.
    scenario : Scenario
        Its scenario.
    t, states : numpy.ndarray (K,), (K, N, 4)
        Times and ``x, y, psi, status`` of every ship at every step.

    Returns
    -------
    margins : numpy.ndarray (K - 1, A)
        Row ``k``: the margins after step ``k`` (distance less touching distance, L).
    kinds : list of str
        The kind of each agent (:func:`agent_reaches`).
    """
    reach, kinds, where = agent_reaches(problem, scenario)
    states = np.asarray(states, float)
    K, N = states.shape[:2]
    t_max = float(problem.params["t_max"])
    stays = np.array([bool(s.get("stays", False)) for s in problem.ships])
    status = states[:, :, 3]
    present = (status == 0) | ((status == 1) & stays[None, :])
    running = np.asarray(t, float) < t_max - 1e-9
    own_on = present[:-1, 0] & running[:-1]
    pos = states[1:, :, :2]
    out = np.full((K - 1, len(kinds)), np.nan)
    for a, kind in enumerate(kinds):
        if kind == "ship":
            j = a + 1
            d = np.linalg.norm(pos[:, 0] - pos[:, j], axis=1)
            valid = own_on & present[:-1, j]
        elif kind == "obstacle":
            d = np.linalg.norm(pos[:, 0] - where[a, :2], axis=1)
            valid = own_on
        else:
            d, _ = segment_distance(pos[:, 0], where[a])
            valid = own_on
        out[:, a] = np.where(valid, d - reach[a], np.nan)
    return out, kinds


def _least_margin(margins: np.ndarray, kinds: list[str], t) -> tuple[float, dict]:
    """The smallest margin, with the agent, its kind and the time; for a negative one the first step below 0."""
    if margins.size == 0 or np.all(np.isnan(margins)):
        return math.inf, {"agent": None, "kind": None, "time": None}
    k, a = np.unravel_index(np.nanargmin(margins), margins.shape)
    rho = float(margins[k, a])
    if rho < 0.0:  # the failure: the first step at which any margin is negative
        neg = np.where(np.isnan(margins), np.inf, margins) < 0.0
        k = int(np.argmax(neg.any(axis=1)))
        a = int(np.argmin(np.where(np.isnan(margins[k]), np.inf, margins[k])))
    return rho, {"agent": int(a), "kind": kinds[a], "time": float(t[k + 1]), "step": int(k + 1),
                 "margin_at": float(margins[k, a])}


def own_encounters(t, states, profile) -> list:
    """The own ship's judged encounters with a risk of collision under ``profile``, as the study scores them
    (:func:`~mmg_casadi.montecarlo.execution.own_ship_encounters`: the ships within the risk gate's reach, every
    :data:`~mmg_casadi.montecarlo.execution.HISTORY_EVERY` steps).

    Parameters
    ----------
    t, states : numpy.ndarray (K,), (K, N, 4)
        Times and ``x, y, psi, status`` at every step.
    profile : str or ScoringProfile
        The scoring profile.

    Returns
    -------
    list of tuple
        ``(encounter, ship index)`` per judged encounter (:class:`~mmg_casadi.colregs.scorer.Encounter`).
    """
    t = np.asarray(t, float)[::HISTORY_EVERY]
    states = np.asarray(states, float)[::HISTORY_EVERY]
    prof = scoring_profile(profile)
    mask = sailing_mask(states[:, :, 3])
    if t.size < 2:
        return []
    dist = np.linalg.norm(states[:, 1:, :2] - states[:, :1, :2], axis=2)
    both = mask[:, :1] & mask[:, 1:]
    speed = np.max(np.linalg.norm(np.diff(states[:, :, :2], axis=0), axis=2) / np.diff(t)[:, None])
    reach = min(prof.r_risk, prof.d_risk + 2.0 * speed * prof.t_risk) if math.isfinite(prof.t_risk) else prof.r_risk
    ships = [0, *(1 + np.flatnonzero(np.any((dist <= reach) & both, axis=0)))]
    if len(ships) < 2:
        return []
    prep = prepare(t, states[:, ships, :2], states[:, ships, 2], active=mask[:, ships], own=0)
    return [(e, int(ships[e.other])) for e in score_prepared(prep, prof, applicable_only=True) if e.judged]


def colregs_robustness(t, states, profile) -> tuple[float, dict]:
    """The ``colregs`` robustness (module docstring) of a history and where it was attained.

    Parameters
    ----------
    t, states : numpy.ndarray (K,), (K, N, 4)
        Times and ``x, y, psi, status`` at every step.
    profile : str or ScoringProfile
        The scoring profile.

    Returns
    -------
    robustness : float
        Smallest kept score / broken score − 1 (:data:`NO_RISK` without a judged encounter).
    detail : dict
        ``agent`` (the other ship's index − 1, as the collision objectives count agents), ``kind``
        (``"rule <r>"``), ``role``, ``rule``, ``time`` (the onset of risk), ``score`` and ``encounters``.
    """
    best, detail = NO_RISK, {"agent": None, "kind": None, "time": None, "encounters": 0}
    encounters = own_encounters(t, states, profile)
    for e, ship in encounters:
        for rule, r in e.rules.items():
            value = float(r.score) - (0.0 if r.verdict else 1.0)
            if value < best:
                best = value
                detail = {"agent": ship - 1, "kind": f"rule {rule}", "rule": rule, "role": e.role,
                          "time": float(e.onset["t"]), "score": float(r.score)}
    detail["encounters"] = len(encounters)
    return best, detail


def failure_geometry(scenario: Scenario, t, states, detail: dict, r_safe: float) -> dict:
    """The encounter geometry of a failure, the coordinates :mod:`~mmg_casadi.falsify.report` clusters.

    The *onset* is the first moment the failing agent came within ``r_safe`` of the own ship (when the methods
    start to react; the start if it was within from the beginning; for a COLREG failure the onset of risk). At
    the onset: the agent's relative bearing from the own ship's heading (deg, ``[-180, 180)``; for land the nearest
    point's) and, for a ship, its heading relative to the own ship's (deg). At the failure (collision or onset of
    risk): how far along its route the own ship was (0 at the start, 1 at the goal, the projection on the straight
    route).

    Parameters
    ----------
    scenario : Scenario
        The run's scenario.
    t, states : numpy.ndarray (K,), (K, N, 4)
        Times and ``x, y, psi, status`` at every step.
    detail : dict
        The evaluation's ``detail`` (``agent``, ``kind``, ``time``).
    r_safe : float
        The safe radius R_safe (L).

    Returns
    -------
    dict
        ``kind``, ``rule`` and ``role`` (a COLREG failure; else None), ``agent``, ``onset_time``, ``bearing_deg``,
        ``relative_heading_deg`` (NaN unless a ship) and ``progress``.
    """
    t = np.asarray(t, float)
    states = np.asarray(states, float)
    k_fail = int(np.searchsorted(t, detail["time"] - 1e-9))
    k_fail = min(k_fail, len(t) - 1)
    own = states[:, 0]
    n_ships = states.shape[1]
    agent = int(detail["agent"])
    kind = detail["kind"]
    if kind.startswith("rule") or kind == "ship":
        other = states[:, agent + 1, :2]
    elif kind == "obstacle":
        o = scenario.obstacles[agent - (n_ships - 1)].position
        other = np.tile(np.asarray(o, float), (len(t), 1))
    else:
        segs = [seg for w in scenario.walls for seg in w.segments] + [e for land in scenario.land
                                                                      for e in land.edges]
        a, b = (np.asarray(v, float) for v in segs[agent - (n_ships - 1) - len(scenario.obstacles)])
        ab = b - a
        s = np.clip(((own[:, :2] - a) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
        other = a + s[:, None] * ab
    if kind.startswith("rule"):
        k_on = k_fail
    else:
        near = np.linalg.norm(other[:k_fail + 1] - own[:k_fail + 1, :2], axis=1) <= r_safe
        k_on = int(np.argmax(near)) if near.any() else k_fail
    rel = other[k_on] - own[k_on, :2]
    bearing = math.degrees(float(wrap(math.atan2(rel[1], rel[0]) - own[k_on, 2])))
    rel_heading = math.nan
    if kind.startswith("rule") or kind == "ship":
        rel_heading = math.degrees(float(wrap(states[k_on, agent + 1, 2] - own[k_on, 2])))
    start, goal = np.asarray(scenario.ships[0].start, float), np.asarray(scenario.ships[0].waypoints[-1], float)
    route = goal - start
    progress = float(np.clip((own[k_fail, :2] - start) @ route / max(float(route @ route), 1e-12), 0.0, 1.0))
    return {"kind": "ship" if kind.startswith("rule") else kind, "rule": detail.get("rule"),
            "role": detail.get("role"), "agent": agent,
            "onset_time": float(t[k_on]), "bearing_deg": bearing, "relative_heading_deg": rel_heading,
            "progress": progress}


def wrap(a: float) -> float:
    """An angle (rad) wrapped to ``[-pi, pi)``.

    Parameters
    ----------
    a : float
        Angle (rad).

    Returns
    -------
    float
        The same angle in ``[-pi, pi)``.
    """
    return (a + math.pi) % (2.0 * math.pi) - math.pi
