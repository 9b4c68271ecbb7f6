"""One closed-loop guidance step for N ships, static obstacles and channel walls, as a CasADi Function.

Every ship runs: ILOS guidance along its own waypoint path (outside R_safe of every neighbour) or the reactive
method (field / velocity obstacle) inside R_safe, PD heading control, the steering gear and the MMG model, all
integrated over one guidance step ``dt`` with the rudder command held (RK4). The ship-level bookkeeping that the
studies need (waypoint index, ILOS integrator, goal time, CE/MCTE integrals, closest approach, first collision,
progress towards the goal) is part of the state, so a rollout only has to keep the final state.

Layout of the scenario state (one column): ``[t, ship_0 (NS rows), ship_1, ...]`` with the per-ship rows in
:data:`SHIP_STATE`. Numeric parameters (gains, field constants, speeds, paths, obstacles) are an input vector
``p`` laid out by :class:`Layout`, so one compiled Function serves every scenario of the same shape.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from . import fields, velocity_obstacle
from .control import PdHeadingParams, pd_heading
from .errors import ParameterError, check_range
from .fields import InverseSquareParams, ModifiedVortexParams, SinkVortexParams, WallParams
from .guidance import IlosParams, ilos_step_terms, switch_waypoint, validate_waypoints
from .model import NX, build_mmg, rk4
from .ship import ShipParams, SteeringParams, load_kcs, load_steering

METHODS = ("inverse-square", "sink-vortex", "modified-vortex", "velocity-obstacle", "none")

SHIP_STATE = (
    "u", "v", "r", "x", "y", "psi", "delta",  # MMG state
    "y_int",        # ILOS integrator state
    "idx",          # index of the waypoint being tracked (column of the path)
    "status",       # 0 sailing, 1 reached its goal, 2 diverged
    "t_goal",       # time the goal was reached (-1 before)
    "ce_int",       # ∫|δ| dt while sailing
    "mcte_int",     # ∫|y_e| dt while sailing
    "d_min",        # closest approach to any other ship or obstacle
    "d_min_with",   # index of that agent (ships 0..N-1, obstacles N..N+S-1)
    "t_collision",  # first time closer than the collision distance (-1 if never)
    "collision_with",
    "best_goal_dist",  # smallest distance to the final goal so far
    "t_best",       # when it was reached
    "x_best", "y_best",
    "reactive_time",  # time spent under reactive guidance
)
NS = len(SHIP_STATE)
S_ = {name: i for i, name in enumerate(SHIP_STATE)}

AUX = ("delta_c", "psi_d", "y_e", "reactive")
NAUX = len(AUX)

GLOBAL_PARAMS = (
    "dt", "r_safe", "collision_distance", "goal_tolerance",
    "ilos_delta", "ilos_k", "kp", "kd", "delta_max",
    "k_att", "k_rep", "d0", "lam_sink", "k_vor", "k_vor0", "r_tol_vortex", "gamma_max",
    "wall_lam", "wall_d_act", "ship_radius", "t_max",
)
SHIP_PARAMS = ("n_rpm", "n_path", "stays")

ENVELOPE = {"speed": 3.0, "r": 5.0, "position": 1.0e4}


@dataclass(frozen=True)
class Layout:
    """Shape of a closed-loop step: per-ship methods, number of obstacles and walls, path length.

    Parameters
    ----------
    methods : tuple of str
        Guidance method of each ship (one of :data:`METHODS`); the first ship is the own ship.
    n_obstacles, n_walls : int
        Static circular obstacles and straight wall segments.
    max_path : int
        Columns of each ship's padded path (start + waypoints).
    vo_candidates : int
        Candidate headings of the velocity obstacle.
    vo_cone : str
        ``"wide"`` or ``"huang"`` (see :mod:`mmg_casadi.velocity_obstacle`).
    smooth : float or None
        ``None`` for the exact switching logic; a sharpness ``s > 0`` replaces every switch by a sigmoid of
        that sharpness (for gradient-based tuning).
    """

    methods: tuple
    n_obstacles: int = 0
    n_walls: int = 0
    max_path: int = 2
    vo_candidates: int = 80
    vo_cone: str = "wide"
    smooth: float | None = None

    @property
    def n_ships(self) -> int:
        return len(self.methods)

    @property
    def nx(self) -> int:
        """Rows of the scenario state."""
        return 1 + self.n_ships * NS

    @property
    def n_agents(self) -> int:
        return self.n_ships + self.n_obstacles

    @property
    def np(self) -> int:
        """Rows of the parameter vector."""
        return (len(GLOBAL_PARAMS) + self.n_ships * (len(SHIP_PARAMS) + 2 * self.max_path)
                + 3 * self.n_obstacles + 4 * self.n_walls)

    def key(self) -> str:
        """Short identifier used in Function names."""
        meth = "_".join(m.replace("-", "") for m in self.methods)
        if len(set(self.methods)) == 1:
            meth = f"{self.methods[0].replace('-', '')}x{self.n_ships}"
        s = "" if self.smooth is None else f"_s{self.smooth:g}".replace(".", "p")
        return f"{meth}_o{self.n_obstacles}_w{self.n_walls}_k{self.max_path}_v{self.vo_candidates}{self.vo_cone}{s}"

    def split_params(self, p):
        """Split a parameter vector (symbolic or numeric) into named pieces."""
        out = {}
        i = 0
        for name in GLOBAL_PARAMS:
            out[name] = p[i]
            i += 1
        ships = []
        for _ in range(self.n_ships):
            d = {}
            for name in SHIP_PARAMS:
                d[name] = p[i]
                i += 1
            d["path"] = ca.reshape(p[i:i + 2 * self.max_path], 2, self.max_path)
            i += 2 * self.max_path
            ships.append(d)
        out["ships"] = ships
        out["obstacles"] = ca.reshape(p[i:i + 3 * self.n_obstacles], 3, self.n_obstacles)
        i += 3 * self.n_obstacles
        out["walls"] = ca.reshape(p[i:i + 4 * self.n_walls], 4, self.n_walls)
        i += 4 * self.n_walls
        assert i == self.np
        return out


def pack_params(layout: Layout, globals_: dict, ships: list[dict], obstacles=(), walls=()) -> np.ndarray:
    """Numeric parameter vector for ``layout``.

    ``ships[i]`` has ``n_rpm``, ``path`` (K_i x 2 array: start then waypoints) and ``stays``; paths are padded to
    ``layout.max_path`` columns by repeating the last waypoint. ``obstacles`` are ``(x, y, radius)``, walls
    ``(ax, ay, bx, by)``.
    """
    vals = [float(globals_[name]) for name in GLOBAL_PARAMS]
    for i, s in enumerate(ships):
        path = np.asarray(validate_waypoints(s["path"], f"ships[{i}].path"))
        k = len(path)
        if k > layout.max_path:
            raise ValueError(f"path of {k} points exceeds layout.max_path={layout.max_path}")
        padded = np.vstack([path, np.repeat(path[-1:], layout.max_path - k, axis=0)])
        vals += [float(s["n_rpm"]), float(k), float(bool(s.get("stays", False)))]
        vals += list(padded.reshape(-1))  # column-major (x0, y0, x1, y1, ...) = reshape(2, K)
    for o in obstacles:
        vals += [float(o[0]), float(o[1]), float(o[2])]
    for w in walls:
        vals += [float(v) for v in w]
    p = np.array(vals)
    assert p.size == layout.np
    return p


def initial_state(layout: Layout, ships: list[dict]) -> np.ndarray:
    """Scenario state at t = 0: each ship at ``start`` with ``heading`` (rad) and surge speed ``speed`` × U_des."""
    x = np.zeros(layout.nx)
    for i, s in enumerate(ships):
        row = np.zeros(NS)
        row[S_["u"]] = float(s["speed"])
        row[S_["x"]], row[S_["y"]] = s["start"]
        row[S_["psi"]] = float(s["heading"])
        row[S_["idx"]] = 1.0
        row[S_["t_goal"]] = -1.0
        row[S_["d_min"]] = 1.0e6
        row[S_["d_min_with"]] = -1.0
        row[S_["t_collision"]] = -1.0
        row[S_["collision_with"]] = -1.0
        goal = np.asarray(s["path"], float).reshape(-1, 2)[-1]
        row[S_["best_goal_dist"]] = float(np.hypot(*(goal - np.asarray(s["start"], float))))
        row[S_["x_best"]], row[S_["y_best"]] = s["start"]
        x[1 + i * NS: 1 + (i + 1) * NS] = row
    return x


def _indicator(cond_margin, smooth):
    """1 where ``cond_margin > 0`` (exact) or its sigmoid of sharpness ``smooth``."""
    if smooth is None:
        return cond_margin > 0
    return 0.5 * (1 + ca.tanh(0.5 * smooth * cond_margin))


def build_closed_loop_step(layout: Layout, ship: ShipParams | None = None,
                           steering: SteeringParams | None = None, *, n_sub: int = 1) -> ca.Function:
    """Named Function ``closed_loop_<key>(x, p) -> (x_next, aux)`` for one guidance step of the whole scenario.

    ``aux`` (NAUX x N) holds per ship the commanded rudder, desired heading, cross-track error and whether the
    reactive guidance was in charge during the step.
    """
    ship = ship or load_kcs()
    steering = steering or load_steering()
    mmg = build_mmg(ship, steering)
    N, S, W = layout.n_ships, layout.n_obstacles, layout.n_walls
    sm = layout.smooth
    x = ca.SX.sym("x", layout.nx)
    p = ca.SX.sym("p", layout.np)
    P = layout.split_params(p)
    t = x[0]
    dt = P["dt"]
    X = [x[1 + i * NS: 1 + (i + 1) * NS] for i in range(N)]

    pos = [ca.vertcat(Xi[S_["x"]], Xi[S_["y"]]) for Xi in X]
    psi = [Xi[S_["psi"]] for Xi in X]
    vel = [ca.vertcat(Xi[S_["u"]] * ca.cos(Xi[S_["psi"]]) - Xi[S_["v"]] * ca.sin(Xi[S_["psi"]]),
                      Xi[S_["u"]] * ca.sin(Xi[S_["psi"]]) + Xi[S_["v"]] * ca.cos(Xi[S_["psi"]])) for Xi in X]
    running = t < P["t_max"] - 1e-9
    sailing = [ca.logic_and(Xi[S_["status"]] == 0, running) for Xi in X]
    # A ship is present as an obstacle while sailing, or after its goal if it stays; a diverged ship is removed.
    present = [ca.if_else(Xi[S_["status"]] == 0, 1, ca.if_else(Xi[S_["status"]] == 1, P["ships"][i]["stays"], 0))
               for i, Xi in enumerate(X)]
    obs = P["obstacles"]
    walls = P["walls"]

    x_next, aux = [], []
    for i in range(N):
        Xi = X[i]
        Pi = P["ships"][i]
        method = layout.methods[i]
        terms = ilos_step_terms(pos[i], Pi["path"], Xi[S_["idx"]], Xi[S_["y_int"]], P["ilos_delta"], P["ilos_k"])
        goal = terms["wp_next"]
        others = [j for j in range(N) if j != i]
        nb_pos = ca.horzcat(*[pos[j] for j in others], obs[0:2, :]) if (others or S) else ca.SX(2, 0)
        nb_vel = ca.horzcat(*[vel[j] for j in others], ca.SX.zeros(2, S)) if (others or S) else ca.SX(2, 0)
        nb_rad = ca.horzcat(*[P["ship_radius"] for _ in others], obs[2:3, :]) if (others or S) else ca.SX(1, 0)
        nb_present = ca.horzcat(*[present[j] for j in others], ca.SX.ones(1, S)) if (others or S) else ca.SX(1, 0)
        M = len(others) + S
        if M:
            d_nb = ca.sqrt(ca.sum1((nb_pos - ca.repmat(pos[i], 1, M)) ** 2))
            active = nb_present * _indicator(P["r_safe"] - d_nb, sm)
        else:
            active = ca.SX(1, 0)

        psi_ilos = terms["psi_d"]
        if method == "none" or (M == 0 and W == 0):
            psi_d = psi_ilos
            w_react = ca.SX(0)
        else:
            if M:
                any_active = 1 - ca.exp(ca.sum2(ca.log(ca.fmax(1 - active, 1e-300)))) if sm is not None \
                    else ca.sum2(active) > 0
            else:
                any_active = ca.SX(0)
            wall_vec = ca.SX.zeros(2, 1)
            near_wall = ca.SX(0)
            if W:
                wall_vec = fields.channel_walls(pos[i], walls[0:2, :], walls[2:4, :], lam=P["wall_lam"],
                                                d_act=P["wall_d_act"])
                near_wall = _indicator(ca.sumsqr(wall_vec) - 1e-12, sm)
            w_react = ca.fmax(any_active, near_wall) if sm is None else 1 - (1 - any_active) * (1 - near_wall)
            if method == "velocity-obstacle":
                speed = ca.sqrt(Xi[S_["u"]] ** 2 + Xi[S_["v"]] ** 2)
                psi_vo = velocity_obstacle.velocity_obstacle(
                    pos[i], speed, goal, nb_pos, nb_vel, active, collision_distance=P["collision_distance"],
                    n_candidates=layout.vo_candidates, cone=layout.vo_cone)
                field_vec = ca.vertcat(ca.cos(psi_vo), ca.sin(psi_vo)) + wall_vec
            elif method == "inverse-square":
                field_vec = fields.inverse_square(pos[i], goal, nb_pos, nb_rad, active, k_att=P["k_att"],
                                                  k_rep=P["k_rep"], d0=P["d0"]) + wall_vec
            elif method == "sink-vortex":
                field_vec = fields.sink_vortex(pos[i], goal, nb_pos, active, lam_sink=P["lam_sink"],
                                               k_vor=P["k_vor"]) + wall_vec
            elif method == "modified-vortex":
                field_vec = fields.modified_vortex(
                    pos[i], psi[i], vel[i], goal, nb_pos, nb_vel, active, lam_sink=P["lam_sink"],
                    k_vor0=P["k_vor0"], r_safe=P["r_safe"], r_tol=P["r_tol_vortex"], gamma_max=P["gamma_max"],
                    smooth=sm) + wall_vec
            else:
                raise ValueError(f"unknown method {method!r}; allowed: {', '.join(METHODS)}")
            if sm is None:
                psi_d = ca.if_else(w_react, ca.atan2(field_vec[1], field_vec[0]), psi_ilos)
            else:
                e_f = field_vec / ca.sqrt(ca.sumsqr(field_vec) + 1e-12)
                e = w_react * e_f + (1 - w_react) * ca.vertcat(ca.cos(psi_ilos), ca.sin(psi_ilos))
                psi_d = ca.atan2(e[1], e[0])

        delta_c = pd_heading(psi[i], psi_d, Xi[S_["r"]], P["kp"], P["kd"], P["delta_max"])
        xm = Xi[:NX]
        xm_next = rk4(mmg, xm, (delta_c, Pi["n_rpm"]), dt / n_sub)
        for _ in range(n_sub - 1):
            xm_next = rk4(mmg, xm_next, (delta_c, Pi["n_rpm"]), dt / n_sub)
        y_int_next = Xi[S_["y_int"]] + dt * terms["y_int_dot"] * (1 - w_react)
        pos_next = xm_next[3:5]
        idx_next, reached = switch_waypoint(pos_next, Pi["path"], Xi[S_["idx"]], Pi["n_path"], P["goal_tolerance"])
        t_next = t + dt

        finite = ca.logic_and(ca.logic_and(ca.fabs(xm_next[0]) < ENVELOPE["speed"],
                                           ca.fabs(xm_next[1]) < ENVELOPE["speed"]),
                              ca.logic_and(ca.fabs(xm_next[2]) < ENVELOPE["r"],
                                           ca.fabs(xm_next[3]) + ca.fabs(xm_next[4]) < ENVELOPE["position"]))
        status_new = ca.if_else(finite, ca.if_else(reached, 1, 0), 2)
        abs_d = 0.5 * (ca.fabs(Xi[S_["delta"]]) + ca.fabs(xm_next[6]))

        final_goal = Pi["path"][:, -1]
        gdist = ca.norm_2(pos_next - final_goal)
        better = gdist < Xi[S_["best_goal_dist"]] - 1e-9

        new = ca.vertcat(
            xm_next,
            y_int_next,
            idx_next,
            status_new,
            ca.if_else(status_new == 1, t_next, -1),
            Xi[S_["ce_int"]] + abs_d * dt,
            Xi[S_["mcte_int"]] + ca.fabs(terms["y_e"]) * dt,
            Xi[S_["d_min"]], Xi[S_["d_min_with"]], Xi[S_["t_collision"]], Xi[S_["collision_with"]],
            ca.if_else(better, gdist, Xi[S_["best_goal_dist"]]),
            ca.if_else(better, t_next, Xi[S_["t_best"]]),
            ca.if_else(better, pos_next[0], Xi[S_["x_best"]]),
            ca.if_else(better, pos_next[1], Xi[S_["y_best"]]),
            Xi[S_["reactive_time"]] + w_react * dt,
        )
        x_next.append(ca.if_else(sailing[i], new, Xi))
        aux.append(ca.vertcat(delta_c, psi_d, terms["y_e"], w_react))

    # Closest approach and first collision, from the positions after the step, for every pair present at its start.
    pos_n = [xn[3:5] for xn in x_next]
    out = []
    for i in range(N):
        xn = x_next[i]
        d_min, d_with = xn[S_["d_min"]], xn[S_["d_min_with"]]
        t_col, c_with = xn[S_["t_collision"]], xn[S_["collision_with"]]
        counts_i = present[i]
        agents = [(j, pos_n[j], present[j]) for j in range(N) if j != i]
        agents += [(N + k, obs[0:2, k], ca.SX(1)) for k in range(S)]
        for j, pj, pres_j in agents:
            dij = ca.norm_2(pos_n[i] - pj)
            valid = ca.logic_and(ca.logic_and(counts_i, pres_j), running)
            closer = ca.logic_and(valid, dij < d_min)
            d_min = ca.if_else(closer, dij, d_min)
            d_with = ca.if_else(closer, j, d_with)
            hit = ca.logic_and(ca.logic_and(valid, dij < P["collision_distance"]), t_col < 0)
            t_col = ca.if_else(hit, t + dt, t_col)
            c_with = ca.if_else(hit, j, c_with)
        xn = ca.vertcat(xn[:S_["d_min"]], d_min, d_with, t_col, c_with, xn[S_["collision_with"] + 1:])
        out.append(xn)

    x_new = ca.vertcat(ca.if_else(running, t + dt, t), *out)
    aux_m = ca.horzcat(*aux)
    return ca.Function(f"closed_loop_{layout.key()}", [x, p], [x_new, aux_m], ["x", "p"], ["x_next", "aux"])


def build_guidance(layout: Layout, ship: ShipParams | None = None,
                   steering: SteeringParams | None = None) -> ca.Function:
    """Guidance-and-control part only: ``guidance_<key>(x, p) -> delta_c (1 x N)``, for timing the methods."""
    step = build_closed_loop_step(layout, ship, steering)
    x = ca.SX.sym("x", layout.nx)
    p = ca.SX.sym("p", layout.np)
    _, aux = step(x, p)
    return ca.Function(f"guidance_{layout.key()}", [x, p], [aux[0, :]], ["x", "p"], ["delta_c"])


def ship_rows(layout: Layout, X: np.ndarray) -> np.ndarray:
    """Reshape scenario states ``(nx, T)`` (or ``(nx,)``) to ``(T, N, NS)`` (or ``(N, NS)``)."""
    X = np.asarray(X)
    if X.ndim == 1:
        return X[1:].reshape(layout.n_ships, NS)
    return X[1:, :].T.reshape(X.shape[1], layout.n_ships, NS)


#: closed-loop parameter -> (parameter dataclass, its field); defaults and range checks live in the dataclasses
PARAM_SOURCES = {
    "goal_tolerance": (IlosParams, "r_tol"), "ilos_delta": (IlosParams, "delta"), "ilos_k": (IlosParams, "k"),
    "kp": (PdHeadingParams, "kp"), "kd": (PdHeadingParams, "kd"),
    "k_att": (InverseSquareParams, "k_att"), "k_rep": (InverseSquareParams, "k_rep"),
    "d0": (InverseSquareParams, "d0"),
    "lam_sink": (ModifiedVortexParams, "lam_sink"), "k_vor": (SinkVortexParams, "k_vor"),
    "k_vor0": (ModifiedVortexParams, "k_vor0"), "r_safe": (ModifiedVortexParams, "r_safe"),
    "r_tol_vortex": (ModifiedVortexParams, "r_tol"), "gamma_max": (ModifiedVortexParams, "gamma_max"),
    "wall_lam": (WallParams, "lam"), "wall_d_act": (WallParams, "d_act"),
}
OTHER_DEFAULTS = {"dt": 0.25, "collision_distance": 2.0, "ship_radius": 0.5, "t_max": 300.0}


def default_globals(**overrides) -> dict:
    """The paper's parameters (lengths in L, angles in rad) for :func:`pack_params`, with ``overrides``.

    Values are range-checked by the parameter dataclasses they come from; a bad value raises
    :class:`~mmg_casadi.errors.ParameterError` naming the closed-loop parameter.

    Examples
    --------
    >>> g = default_globals(kp=2.0)
    >>> g["kp"], g["kd"], g["d0"]
    (2.0, 4.0, 8.0)
    >>> default_globals(ilos_delta=-1.0)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ParameterError: ilos_delta: expected a number in (0, inf) L, got -1.0
    """
    unknown = set(overrides) - set(PARAM_SOURCES) - set(OTHER_DEFAULTS) - {"delta_max"}
    if unknown:
        raise ParameterError(sorted(unknown)[0], f"one of: {', '.join(sorted(set(PARAM_SOURCES) | set(OTHER_DEFAULTS)))}")
    g = {}
    for name, (cls, attr) in PARAM_SOURCES.items():
        value = overrides.get(name, getattr(cls(), attr))
        try:
            cls(**{attr: value})
        except ParameterError as e:
            raise ParameterError(name, e.allowed, e.got) from None
        g[name] = float(value)
    g["delta_max"] = float(overrides.get("delta_max", PdHeadingParams().delta_max))
    for name, default in OTHER_DEFAULTS.items():
        g[name] = float(check_range(name, overrides.get(name, default), 0.0, None, low_open=True))
    return g
