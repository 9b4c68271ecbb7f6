"""What the environments of :mod:`mmg_casadi.gym` compute around the compiled step, for a batch of scenario columns:
the problem of a scenario with the own ship commanded, the action's orders, the observation, the reward and the
end of an episode (numpy; the state is read through :class:`~mmg_casadi.closed_loop.layout.Layout` names only).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mmg_casadi.closed_loop.layout import STOPPED, Layout
from mmg_casadi.closed_loop.problem import Problem, build_problem
from mmg_casadi.closed_loop.simulation import Trajectory, command_rows, simulate
from mmg_casadi.closed_loop.state import ship_rows
from mmg_casadi.errors import InputError
from mmg_casadi.vessel.library import load_vessel

EVENTS = ("goal", "collision", "grounding", "diverged")
"""What ends an episode (``terminated``); the horizon ``t_max`` truncates it (``"timeout"``)."""

OWN_FEATURES = ("u", "v", "r", "delta", "n_prop", "t")
"""The own ship's part of the observation: surge and sway speed through the water (U), yaw rate (U/L), rudder angle
(rad), propeller speed as a fraction of her design rpm, and the time as a fraction of the horizon ``t_max``."""
WAYPOINT_FEATURES = ("ahead", "starboard", "distance", "to_go")
"""The next waypoint in the own ship's frame (L ahead, L to starboard), its distance and the length of the route
still to sail through it to the goal (L)."""
SHIP_FEATURES = ("present", "ahead", "starboard", "v_ahead", "v_starboard", "distance")
"""Per slot of the K nearest other ships: 1 if the slot holds a ship (0 and zeros otherwise), her position and her
velocity over the ground relative to the own ship's, in the own ship's frame (L, U), and her distance (L)."""
HAZARD_FEATURES = ("present", "ahead", "starboard", "distance")
"""Per slot of the K nearest hazards (static obstacles, channel walls, land edges): 1 if the slot holds one, the
nearest point of it in the own ship's frame (L; an obstacle's centre) and the clearance to it (L; to an obstacle's
rim)."""


@dataclass(frozen=True)
class RewardConfig:
    """The reward of one guidance step and what ends an episode (every weight may be 0).

    reward = ``progress`` × (route to go before the step − after it, L) − ``time`` (per step)
    + ``goal`` on reaching the goal − ``collision`` on the first collision with a ship or an obstacle
    − ``grounding`` on touching a wall or land − ``diverged`` on leaving the model's envelope
    − ``proximity`` × max(0, 1 − d / ``proximity_range``) for the nearest other ship at distance d.

    Parameters
    ----------
    progress : float, default 1.0
        Per ship length sailed along the route towards the goal (the straight line to the next waypoint, then the
        remaining legs).
    time : float, default 0.01
        Cost of each step.
    goal : float, default 100.0
        Reaching the goal (within the acceptance radius of the last waypoint).
    collision : float, default 100.0
        The first collision of the own ship with a ship or a static obstacle.
    grounding : float, default 100.0
        The first contact of the own ship with a channel wall or a land edge.
    diverged : float, default 100.0
        The own ship leaving the MMG model's envelope.
    proximity : float, default 0.0
        Weight of the nearness of the nearest other ship.
    proximity_range : float, default 5.0
        Range (L) within which nearness costs.
    terminate_on : tuple of str, default EVENTS
        Events (:data:`EVENTS`) that end the episode; e.g. without ``"collision"`` the own ship sails on after one
        (it is penalised once).
    """

    progress: float = 1.0
    time: float = 0.01
    goal: float = 100.0
    collision: float = 100.0
    grounding: float = 100.0
    diverged: float = 100.0
    proximity: float = 0.0
    proximity_range: float = 5.0
    terminate_on: tuple = EVENTS

    def __post_init__(self):
        for name in ("progress", "time", "goal", "collision", "grounding", "diverged", "proximity"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise InputError(f"reward.{name}", "a finite number", v)
        if not (isinstance(self.proximity_range, (int, float)) and self.proximity_range > 0):
            raise InputError("reward.proximity_range", "a number > 0 (L)", self.proximity_range)
        bad = [e for e in self.terminate_on if e not in EVENTS]
        if bad:
            raise InputError("reward.terminate_on", f"events among: {', '.join(EVENTS)}", bad[0])


def commanded_problem(scenario, params=None, *, rpm: bool = False) -> Problem:
    """The problem of ``scenario`` with its first ship (the own ship) steered from outside.

    Parameters
    ----------
    scenario : Scenario
        The scenario; its other ships keep their methods.
    params : dict, optional
        Parameter overrides.
    rpm : bool, default False
        The own ship also orders her propeller speed.

    Returns
    -------
    Problem
        :func:`~mmg_casadi.closed_loop.problem.build_problem` with ``commanded=(0,)``.
    """
    pr = build_problem(scenario, params, commanded=(0,), command_rpm=rpm)
    if pr.layout.neighbours:
        raise InputError("scenario", "fewer ships than fleet_from_ships (the fleet step takes no commands)",
                         pr.layout.n_ships)
    return pr


@dataclass
class Statics:
    """What does not change in an episode, for a batch of ``B`` columns (numpy).

    Parameters
    ----------
    path : ndarray (B, K, 2)
        The own ship's padded path (start, then waypoints; L).
    to_go : ndarray (B, K)
        Route length from path column k to the goal (L).
    n_path : ndarray (B,)
        Columns of the path in use.
    stays : ndarray (B, N)
        1 if a ship stays as an obstacle after her goal.
    obstacles : ndarray (B, S, 3)
        Static obstacles: x, y, radius (L).
    walls : ndarray (B, W, 4)
        Wall and land segments: ax, ay, bx, by (L).
    current : ndarray (B, 2)
        The current's velocity over the ground (U).
    rpm_range : ndarray (B, 2)
        The own ship's commandable propeller speeds (rev/min).
    rpm_design : float
        The own ship's design propeller speed (rev/min).
    t_max : ndarray (B,)
        Horizons (L/U).
    """

    path: np.ndarray
    to_go: np.ndarray
    n_path: np.ndarray
    stays: np.ndarray
    obstacles: np.ndarray
    walls: np.ndarray
    current: np.ndarray
    rpm_range: np.ndarray
    rpm_design: float
    t_max: np.ndarray


def statics(layout: Layout, P: np.ndarray) -> Statics:
    """:class:`Statics` of parameter vectors ``P`` (np, B) of ``layout``.

    Parameters
    ----------
    layout : Layout
        The commanded layout.
    P : ndarray (np, B)
        Parameter vectors.

    Returns
    -------
    Statics
        The routes, hazards and limits of every column.
    """
    cols = [layout.split_params(P[:, b]) for b in range(P.shape[1])]
    path = np.stack([np.asarray(c["ships"][0]["path"], float).reshape(2, layout.max_path).T for c in cols])
    legs = np.linalg.norm(np.diff(path, axis=1), axis=2)  # (B, K-1)
    to_go = np.concatenate([np.cumsum(legs[:, ::-1], axis=1)[:, ::-1], np.zeros((len(cols), 1))], axis=1)
    S, W = layout.n_obstacles, layout.n_walls
    current = np.zeros((len(cols), 2))
    if layout.disturbed:
        env = np.array([np.asarray(c["env"], float).ravel() for c in cols])
        current = env[:, :1] * np.column_stack([np.cos(env[:, 1]), np.sin(env[:, 1])])
    return Statics(
        path=path, to_go=to_go,
        n_path=np.array([float(c["ships"][0]["n_path"]) for c in cols]),
        stays=np.array([[float(s["stays"]) for s in c["ships"]] for c in cols]),
        obstacles=np.array([np.asarray(c["obstacles"], float).reshape(3, S).T for c in cols]),
        walls=np.array([np.asarray(c["walls"], float).reshape(4, W).T for c in cols]),
        current=current,
        rpm_range=np.array([[float(c["ships"][0]["rpm_min"]), float(c["ships"][0]["rpm_max"])] for c in cols]),
        rpm_design=load_vessel(layout.vessel(0)).ship.n_design_rpm,
        t_max=np.array([float(c["t_max"]) for c in cols]))


def orders(layout: Layout, X: np.ndarray, st: Statics, actions: np.ndarray, *, mode: str,
           max_turn: float) -> np.ndarray:
    """The own ship's orders (heading in rad, then rpm) from actions in [-1, 1], for columns ``X`` (nx, B).

    Parameters
    ----------
    layout : Layout
        The commanded layout.
    X : ndarray (nx, B)
        States before the step.
    st : Statics
        The columns' statics.
    actions : ndarray (B, A)
        Actions: the heading (``mode`` "relative": ``max_turn`` × a from the present heading; "absolute": π × a),
        then with ``command_rpm`` the propeller speed (dead slow ahead at -1, the maximum at +1).
    mode : {"relative", "absolute"}
        How the heading action is read.
    max_turn : float
        Largest alteration of a relative action (rad).

    Returns
    -------
    ndarray (B, 1 + command_rpm)
        The orders written into the ``command_heading`` (and ``command_rpm``) rows.
    """
    a = np.clip(np.asarray(actions, float).reshape(X.shape[1], -1), -1.0, 1.0)
    psi = X[layout.row("psi", 0)]
    heading = psi + max_turn * a[:, 0] if mode == "relative" else math.pi * a[:, 0]
    out = [heading]
    if layout.command_rpm:
        lo, hi = st.rpm_range[:, 0], st.rpm_range[:, 1]
        out.append(lo + 0.5 * (a[:, 1] + 1.0) * (hi - lo))
    return np.column_stack(out)


def write_orders(layout: Layout, X: np.ndarray, cmd: np.ndarray) -> None:
    """Write orders ``cmd`` (B, 1 + command_rpm) into the own ship's command rows of ``X`` (nx, B), in place.

    Parameters
    ----------
    layout : Layout
        The commanded layout.
    X : ndarray (nx, B)
        States.
    cmd : ndarray (B, C)
        Orders of :func:`orders`.
    """
    for j, r in enumerate(command_rows(layout)[0]):
        X[r] = cmd[:, j]


def _frame(vec: np.ndarray, psi: np.ndarray) -> np.ndarray:
    """Global vectors (B, ..., 2) in the own ship's frame (ahead, starboard), headings ``psi`` (B,)."""
    c, s = np.cos(psi), np.sin(psi)
    c = c.reshape((-1,) + (1,) * (vec.ndim - 2))
    s = s.reshape((-1,) + (1,) * (vec.ndim - 2))
    return np.stack([vec[..., 0] * c + vec[..., 1] * s, -vec[..., 0] * s + vec[..., 1] * c], axis=-1)


def _nearest(dist: np.ndarray, k: int) -> np.ndarray:
    """Indices (B, k) of the k smallest entries of each row (ties by index), padded with -1 past the row's width."""
    order = np.argsort(dist, axis=1, kind="stable")[:, :k]
    if order.shape[1] < k:
        order = np.concatenate([order, -np.ones((order.shape[0], k - order.shape[1]), int)], axis=1)
    return order


def observe(layout: Layout, X: np.ndarray, st: Statics, *, k_ships: int, k_hazards: int) -> tuple:
    """Observations (B, D) of the columns ``X`` (nx, B) and the route to go (B,) and nearest ship distance (B,).

    Parameters
    ----------
    layout : Layout
        The commanded layout.
    X : ndarray (nx, B)
        States.
    st : Statics
        The columns' statics.
    k_ships, k_hazards : int
        Slots of other ships and of hazards.

    Returns
    -------
    obs : ndarray (B, D)
        :data:`OWN_FEATURES`, :data:`WAYPOINT_FEATURES`, ``k_ships`` × :data:`SHIP_FEATURES`, ``k_hazards`` ×
        :data:`HAZARD_FEATURES`.
    to_go : ndarray (B,)
        Route still to sail (L).
    nearest : ndarray (B,)
        Distance to the nearest present ship (L; inf without one).
    """
    B = X.shape[1]
    R = ship_rows(layout, X).reshape(B, layout.n_ships, layout.ns)
    col = layout.column
    psi = R[:, :, col("psi")]
    u, v = R[:, :, col("u")], R[:, :, col("v")]
    pos = np.stack([R[:, :, col("x")], R[:, :, col("y")]], axis=-1)                   # (B, N, 2)
    vel = np.stack([u * np.cos(psi) - v * np.sin(psi), u * np.sin(psi) + v * np.cos(psi)], axis=-1)
    vel = vel + st.current[:, None, :]
    status = R[:, :, col("status")]
    present = (status == 0) | ((status == 1) & (st.stays > 0.5)) | (status == STOPPED)  # a stopped ship is a hazard
    own_psi, own_pos = psi[:, 0], pos[:, 0]
    own = np.column_stack([u[:, 0], v[:, 0], R[:, 0, col("r")], R[:, 0, col("delta")],
                           R[:, 0, col("n_prop")] / st.rpm_design, X[0] / st.t_max])
    idx = np.clip(np.rint(R[:, 0, col("idx")]).astype(int), 0, layout.max_path - 1)
    wp = st.path[np.arange(B), idx]
    d_wp = np.linalg.norm(wp - own_pos, axis=1)
    to_go = d_wp + st.to_go[np.arange(B), idx]
    waypoint = np.column_stack([_frame(wp - own_pos, own_psi), d_wp, to_go])

    rel = pos[:, 1:] - own_pos[:, None]
    dist = np.linalg.norm(rel, axis=2)
    dist_m = np.where(present[:, 1:], dist, np.inf)
    pick = _nearest(dist_m, k_ships)
    ok = (pick >= 0) & np.isfinite(np.take_along_axis(dist_m, np.maximum(pick, 0), axis=1))
    gather = np.maximum(pick, 0)
    rel_k = np.take_along_axis(rel, gather[..., None], axis=1)
    vrel_k = np.take_along_axis(vel[:, 1:] - vel[:, :1], gather[..., None], axis=1)
    ships = np.concatenate([ok[..., None], _frame(rel_k, own_psi), _frame(vrel_k, own_psi),
                            np.take_along_axis(dist, gather, axis=1)[..., None]], axis=2) * ok[..., None]

    near_pts, clear = [], []
    if layout.n_obstacles:
        c = st.obstacles[:, :, :2] - own_pos[:, None]
        near_pts.append(c)
        clear.append(np.linalg.norm(c, axis=2) - st.obstacles[:, :, 2])
    if layout.n_walls:
        a, b = st.walls[:, :, :2], st.walls[:, :, 2:]
        ab = b - a
        t = np.clip(np.sum((own_pos[:, None] - a) * ab, axis=2) / np.maximum(np.sum(ab * ab, axis=2), 1e-12), 0, 1)
        q = a + t[..., None] * ab - own_pos[:, None]
        near_pts.append(q)
        clear.append(np.linalg.norm(q, axis=2))
    if near_pts:
        pts, cl = np.concatenate(near_pts, axis=1), np.concatenate(clear, axis=1)
        hp = _nearest(cl, k_hazards)
        hok = hp >= 0
        g = np.maximum(hp, 0)
        hz = np.concatenate([hok[..., None], _frame(np.take_along_axis(pts, g[..., None], axis=1), own_psi),
                             np.take_along_axis(cl, g, axis=1)[..., None]], axis=2) * hok[..., None]
    else:
        hz = np.zeros((B, k_hazards, len(HAZARD_FEATURES)))
    obs = np.concatenate([own, waypoint, ships.reshape(B, -1), hz.reshape(B, -1)], axis=1)
    nearest = np.min(dist_m, axis=1) if dist_m.shape[1] else np.full(B, np.inf)
    return obs, to_go, nearest


def events(layout: Layout, X: np.ndarray) -> np.ndarray:
    """What has happened to the own ship by the states ``X`` (nx, B): a flag per :data:`EVENTS` and column.

    Parameters
    ----------
    layout : Layout
        The commanded layout.
    X : ndarray (nx, B)
        States.

    Returns
    -------
    ndarray of bool (B, 4)
        ``goal`` (reached), ``collision`` (with a ship or an obstacle), ``grounding`` (a wall or land edge touched),
        ``diverged``; the closed loop keeps the first collision, so a flag once set stays set.
    """
    status = X[layout.row("status", 0)]
    with_ = X[layout.row("collision_with", 0)]
    hit = X[layout.row("t_collision", 0)] >= 0
    hazard = with_ >= layout.n_ships + layout.n_obstacles
    return np.column_stack([status == 1, hit & ~hazard, hit & hazard, status == 2])


def event_name(flags: np.ndarray, terminate_on=EVENTS) -> str:
    """The event that ends (or would end) an episode with ``flags`` (one row of :func:`events`), or ``""``.

    Parameters
    ----------
    flags : ndarray of bool (4,)
        A row of :func:`events`.
    terminate_on : tuple of str
        The events that end an episode.

    Returns
    -------
    str
        The first of collision, grounding, diverged, goal that is set and in ``terminate_on``; else ``""``.
    """
    for name in ("collision", "grounding", "diverged", "goal"):
        if flags[EVENTS.index(name)] and name in terminate_on:
            return name
    return ""


def reward(cfg: RewardConfig, before: np.ndarray, after: np.ndarray, to_go_before, to_go_after,
           nearest) -> np.ndarray:
    """The reward of one step per column (:class:`RewardConfig`): event flags ``before`` and ``after`` it.

    Parameters
    ----------
    cfg : RewardConfig
        Weights.
    before, after : ndarray of bool (B, 4)
        :func:`events` before and after the step (an event is rewarded once, when its flag is first set).
    to_go_before, to_go_after : ndarray (B,)
        Route to go (L).
    nearest : ndarray (B,)
        Distance to the nearest other ship after the step (L).

    Returns
    -------
    ndarray (B,)
        The rewards.
    """
    r = cfg.progress * (to_go_before - to_go_after) - cfg.time
    new = after & ~before
    for k, name in enumerate(EVENTS):
        w = getattr(cfg, name)
        r = r + np.where(new[:, k], w if name == "goal" else -w, 0.0)
    if cfg.proximity:
        r = r - cfg.proximity * np.clip(1.0 - nearest / cfg.proximity_range, 0.0, None)
    return r


@dataclass
class Episode:
    """An episode of the environment: its scenario and the own ship's orders, replayable with
    :func:`~mmg_casadi.closed_loop.simulation.simulate`.

    Parameters
    ----------
    scenario : Scenario
        The scenario (the own ship's method is not used: she is commanded).
    params : dict or None
        The parameter overrides the environment ran with.
    rpm : bool
        The orders include the propeller speed.
    commands : list of ndarray
        The orders of each step (heading in rad, then rpm), as written into the state.
    seed : int or None
        The seed of the reset that drew the scenario.
    """

    scenario: object
    params: dict | None
    rpm: bool
    commands: list = field(default_factory=list)
    seed: int | None = None

    def problem(self) -> Problem:
        """The episode's problem (:func:`commanded_problem`).

        Returns
        -------
        Problem
            Layout, initial state and parameter vector.
        """
        return commanded_problem(self.scenario, self.params, rpm=self.rpm)

    def rollout(self) -> Trajectory:
        """The closed-loop rollout of the same orders (the same compiled step; equal to the episode to the bit).

        Returns
        -------
        Trajectory
            The states at every step, the first holding the first orders.
        """
        pr = self.problem()
        cmd = np.array(self.commands, float).reshape(len(self.commands), 1, 1 + int(self.rpm))
        return simulate(pr.layout, pr.x0, pr.p, commands=cmd if self.rpm else cmd[:, :, 0])
