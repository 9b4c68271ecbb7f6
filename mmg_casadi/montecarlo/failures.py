"""Why a Monte Carlo run failed: one mechanism per failed run from a documented set (numpy post-processing).

The paper names two failure mechanisms of the modified sink-vortex APF (§Limitations): ships that start too
close to avoid each other given their initial orientations, and encounters in which a ship is very close to its
goal waypoint, where the attraction of the goal overshadows the repulsion. The set :data:`MECHANISMS`, checked in
this order (the first that applies wins):

``"started-too-close"``
    the collision was decided by the initial positions and headings (the paper's first mechanism): the own
    ship collided (with a ship or an obstacle) no later than :func:`turn_time_90` after the start — the time
    our KCS needs to change heading by 90° with full (35°) rudder from a straight course at design speed
    (:func:`mmg_casadi.vessel.maneuvers.turning_circle`), so no avoidance manoeuvre could be completed — or, at any
    time, the agent it hit could not have been avoided from the start by the own ship alone
    (:func:`unavoidable_at_start`: holding course, or full rudder to either side from t = 0, each passes
    within the collision distance of it while it keeps its initial course and speed);
``"obstacle-near-goal"``
    the own ship hit a static obstacle whose centre lies within ``near_goal_distance`` of the own ship's goal
    (the paper's second mechanism with a static obstacle);
``"near-goal"``
    the own ship hit another ship while one of the two was within ``near_goal_distance`` of its own goal (the
    paper's second mechanism);
``"ship-ship"``, ``"obstacle"``
    any other collision with a ship or a static obstacle;
``"grounding"``
    the own ship touched land (the ``failure`` column's ``"grounding"``);
``"stalled"``, ``"timeout"``, ``"diverged"``
    no collision, goal not reached (the ``failure`` column's meaning).

A successful run has the mechanism ``""``.

Examples
--------
>>> failure_mechanism("collision", collision_time=3.0, collision_with=1, goals=[[50, 0], [0, 0]],
...                   obstacles=[], positions_at_collision=[[20, 0], [22, 0]], turn_time=4.0)
'started-too-close'
>>> failure_mechanism("collision", collision_time=30.0, collision_with=1, goals=[[50, 0], [0, 0]],
...                   obstacles=[], positions_at_collision=[[45, 0], [47, 0]], turn_time=4.0)
'near-goal'
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.params import PARAMETERS
from mmg_casadi.vessel.maneuvers import turning_circle

MECHANISMS: tuple[str, ...] = ("started-too-close", "obstacle-near-goal", "near-goal", "ship-ship", "obstacle",
                               "grounding", "stalled", "timeout", "diverged")
"""Failure mechanisms, in the order they are checked (see the module notes)."""

@lru_cache(maxsize=8)
def turn_time_90(rudder_deg: float = PARAMETERS["delta_max_deg"].default, speed: float = 1.0) -> float:
    """Time (L/U) our KCS needs to change heading by 90° with ``rudder_deg`` from a straight course at ``speed``.

    From :func:`mmg_casadi.vessel.maneuvers.turning_circle` (the steering gear's delay included), linearly interpolated.

    Parameters
    ----------
    rudder_deg : float
        Rudder angle (degrees).
    speed : float
        Approach speed (fraction of the design speed).

    Examples
    --------
    >>> 3.0 < turn_time_90() < 8.0
    True
    """
    res = turning_circle(rudder_deg, speed=speed, t_end=40.0)
    psi = np.abs(res.state("psi"))
    k = int(np.argmax(psi >= math.pi / 2))
    if psi[k] < math.pi / 2:
        return math.inf
    t0, t1, p0, p1 = res.t[k - 1], res.t[k], psi[k - 1], psi[k]
    return float(t0 + (math.pi / 2 - p0) * (t1 - t0) / (p1 - p0))


@lru_cache(maxsize=64)
def _hard_turn(rudder_deg: float, speed: float) -> tuple[np.ndarray, np.ndarray]:
    """Times and positions (K, 2) of a hard starboard turn from the origin, heading 0, until 180°."""
    res = turning_circle(rudder_deg, speed=speed, t_end=80.0 / speed)
    psi = np.abs(res.state("psi"))
    k = int(np.argmax(psi >= math.pi)) if (psi >= math.pi).any() else len(psi) - 1
    return res.t[:k + 1], np.column_stack([res.state("x"), res.state("y")])[:k + 1]


def unavoidable_at_start(own_start, own_heading: float, own_speed: float, other_start, other_velocity, *,
                         collision_distance: float, rudder_deg: float = PARAMETERS["delta_max_deg"].default) -> bool:
    """Whether the own ship alone could not avoid the other agent from ``t = 0``.

    Three manoeuvres of the own ship from its initial state are tried: holding course and speed, and full
    rudder (``rudder_deg``) to starboard and to port until the heading has changed by 180° (the KCS turning
    circle at its initial speed, :func:`mmg_casadi.vessel.maneuvers.turning_circle`); the other agent keeps its initial
    velocity (zero for a static obstacle). Unavoidable when each comes within ``collision_distance`` of it during
    the 180° turn time.

    Parameters
    ----------
    own_start : array (2,)
        Own initial position (L).
    own_heading : float
        Own initial heading (rad).
    own_speed : float
        Own initial speed (fraction of the design speed, > 0).
    other_start : array (2,)
        The other agent's initial position (L).
    other_velocity : array (2,)
        Its (constant) velocity (U).
    collision_distance : float
        Centre distance counted as a collision (L): for another ship the pair's
        (:func:`~mmg_casadi.vessel.library.pair_collision_distance` of the two ships' lengths), for an obstacle the
        table's ``collision_distance``.
    rudder_deg : float
        Rudder angle of the hard turns (degrees).

    Returns
    -------
    bool
        True if all three manoeuvres come within ``collision_distance`` of the other agent.

    Examples
    --------
    Meeting head-on 6 L apart at full speed: no turn gets clear of 2 L; 30 L apart it can.

    >>> unavoidable_at_start([0, 0], 0.0, 1.0, [6, 0], [-1, 0], collision_distance=2.0)
    True
    >>> unavoidable_at_start([0, 0], 0.0, 1.0, [30, 0], [-1, 0], collision_distance=2.0)
    False
    """
    t, track = _hard_turn(float(rudder_deg), round(float(own_speed), 3))
    c, s = math.cos(own_heading), math.sin(own_heading)
    rot = np.array([[c, -s], [s, c]])
    own0 = np.asarray(own_start, float)
    other = np.asarray(other_start, float) + np.outer(t, np.asarray(other_velocity, float))
    straight = own0 + np.outer(t, [c * own_speed, s * own_speed])
    for path in (straight, own0 + track @ rot.T, own0 + (track * [1.0, -1.0]) @ rot.T):
        if float(np.min(np.hypot(*(path - other).T))) >= collision_distance:
            return False
    return True


def failure_mechanism(failure: str, *, collision_time=None, collision_with=None, goals=(), obstacles=(),
                      positions_at_collision=None, turn_time: float,
                      near_goal_distance: float = PARAMETERS["near_goal_distance"].default,
                      unavoidable: bool = False) -> str:
    """The mechanism (:data:`MECHANISMS`, ``""`` on success) of one run of the own ship (ship 0).

    Parameters
    ----------
    failure : str
        The run's ``failure`` column: ``""``, ``"collision"``, ``"stalled"``, ``"timeout"`` or ``"diverged"``.
    collision_time : float, optional
        Time of the own ship's first collision (L/U).
    collision_with : int, optional
        Agent it collided with: ships ``1..N-1``, then obstacles ``N..N+S-1``.
    goals : array (N, 2)
        Final waypoint of every ship (L).
    obstacles : array (S, 2) or (S, 3)
        Static obstacles' centres (L; a radius column is ignored).
    positions_at_collision : array (N, 2), optional
        Every ship's position at the collision (needed for ``"near-goal"``; without it that test is skipped).
    turn_time : float
        Time to turn 90° (:func:`turn_time_90`).
    near_goal_distance : float
        Distance (L) from its goal within which a ship is "near its goal" (default: the table's
        ``near_goal_distance``).
    unavoidable : bool
        The agent it hit could not be avoided from the start (:func:`unavoidable_at_start`).

    Returns
    -------
    str
        A name of :data:`MECHANISMS`, or ``""`` when ``failure`` is empty.

    Examples
    --------
    >>> failure_mechanism("collision", collision_time=40.0, collision_with=2, goals=[[50, 0], [0, 0]],
    ...                   obstacles=[[48, 5, 0.5]], turn_time=4.0)
    'obstacle-near-goal'
    >>> failure_mechanism("stalled", turn_time=4.0)
    'stalled'
    """
    if failure in ("", None):
        return ""
    if failure in ("grounding", "stalled", "timeout", "diverged"):
        return failure
    if failure != "collision":
        raise InputError("failure", "one of '', 'collision', 'grounding', 'stalled', 'timeout', 'diverged'",
                         failure)
    if collision_time is None or collision_with is None:
        raise InputError("collision_time", "the collision's time and agent for a collision", collision_time)
    goals = np.asarray(goals, float).reshape(-1, 2)
    n = len(goals)
    j = int(collision_with)
    if collision_time <= turn_time or unavoidable:
        return "started-too-close"
    if j >= n:
        obs = np.asarray(obstacles, float)
        if j - n >= len(obs):
            raise InputError("collision_with", f"a ship (< {n}) or an obstacle (< {n + len(obs)})", j)
        centre = obs.reshape(len(obs), -1)[j - n, :2]
        near = n > 0 and float(np.hypot(*(centre - goals[0]))) <= near_goal_distance
        return "obstacle-near-goal" if near else "obstacle"
    if positions_at_collision is not None:
        pos = np.asarray(positions_at_collision, float).reshape(-1, 2)
        for k in (0, j):
            if float(np.hypot(*(pos[k] - goals[k]))) <= near_goal_distance:
                return "near-goal"
    return "ship-ship"
