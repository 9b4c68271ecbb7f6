"""One closed-loop guidance step for N ships, static obstacles and channel walls, as a CasADi Function.

Every ship runs: ILOS guidance along its own waypoint path (outside R_safe of every neighbour) or the reactive
method (field / velocity obstacle) inside R_safe, PD heading control, the steering gear and the MMG model, all
integrated over one guidance step ``dt`` with the rudder command held (RK4). The ship-level bookkeeping that the
studies need (waypoint index, ILOS integrator, goal time, CE/MCTE integrals, closest approach, first collision,
progress towards the goal) is part of the state, so a rollout only has to keep the final state.

Layout of the scenario state (one column): ``[t, ship_0 (NS rows), ship_1, ...]`` with the per-ship rows in
:data:`SHIP_STATE`. Numeric parameters (gains, field constants, speeds, paths, obstacles) are an input vector
``p`` laid out by :class:`Layout`, so one compiled Function serves every scenario of the same shape.

Current and wind (table group "environment", :mod:`mmg_casadi.vessel.environment`): a layout with either (or with
crab-angle compensation) is :attr:`Layout.disturbed` and its step takes :data:`ENV_INPUTS` as well; calm layouts
keep the calm-water step exactly. The state's ``u, v`` are then velocities through the water and the current
carries the ship over the ground. What guidance does with the disturbance: the fields and the velocity obstacle
see every ship's velocity over the ground (and the velocity obstacle the own speed over the ground); ILOS and the
waypoint switching use positions, so the ILOS integral compensates the drift; with ``crab_compensation = "on"``
ILOS steers the heading ``psi_d = chi_d - beta`` with the crab angle ``beta`` over the ground (Fossen, Pettersen
& Galeazzi 2015). The reactive methods' desired heading is not crab-compensated, and gusts
(:func:`~mmg_casadi.vessel.environment.gust_speeds`) are not wired into the closed loop. The model envelope (divergence)
is checked on the velocities through the water.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from mmg_casadi.vessel import environment

from mmg_casadi.guidance import fields

from mmg_casadi.guidance import methods
from mmg_casadi.guidance.heading_control import pd_heading
from mmg_casadi.errors import ParameterError, ScenarioError
from mmg_casadi.guidance.ilos import ilos_step_terms, switch_waypoint, validate_waypoints
from mmg_casadi.guidance.methods import GuidanceInputs
from mmg_casadi.vessel.mmg import NX, build_mmg, propeller_rpm_for_speed, rk4
from mmg_casadi.params import PARAMETERS, resolve
from mmg_casadi.vessel.ship import ShipParams, SteeringParams, load_kcs, load_steering

#: Names of one ship's rows of the scenario state, in order (see the comments for each row).
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
    "vo_heading",   # heading chosen by the reactive method while a neighbour is within R_safe, else the heading
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
"""Numeric inputs of the compiled step, in order: the table's parameters (:mod:`mmg_casadi.params`) with the
angles ``delta_max`` and ``gamma_max`` in rad (the table holds them in degrees); see :func:`step_values`."""
_DEG_INPUTS = {"delta_max": "delta_max_deg", "gamma_max": "gamma_max_deg"}
SHIP_PARAMS = ("n_rpm", "n_path", "stays")

ENVELOPE = {"speed": 3.0, "r": 5.0, "position": 1.0e4}

ENV_INPUTS = ("V_c", "beta_c", "U_w", "psi_w", "crab")
"""Trailing numeric inputs of a disturbed step (:attr:`Layout.disturbed`): the model's disturbance ``env =
[V_c, beta_c, U_w, psi_w]`` (:mod:`mmg_casadi.vessel.environment`, prime-II units, rad) and the crab-angle switch (0/1);
see :func:`env_values`."""


@dataclass(frozen=True)
class Layout:
    """Shape of a closed-loop step: per-ship methods, number of obstacles and walls, path length.

    Parameters
    ----------
    methods : tuple of str
        Guidance method of each ship (a name in :data:`mmg_casadi.guidance.methods.METHODS`); the first ship is the own
        ship.
    n_obstacles, n_walls : int
        Static circular obstacles and straight wall segments.
    max_path : int
        Columns of each ship's padded path (start + waypoints).
    vo_candidates : int
        Candidate headings of the velocity obstacle.
    vo_cone : str
        ``"wide"`` or ``"huang"`` (see :mod:`mmg_casadi.guidance.velocity_obstacle`).
    vo_hold : bool
        The velocity obstacle keeps its chosen heading while it stays feasible (``vo_heading`` state).
    smooth : float or None
        ``None`` for the exact switching logic; a sharpness ``s > 0`` replaces every switch by a sigmoid of
        that sharpness (for gradient-based tuning).
    disturbed : bool
        Current / wind / crab-angle compensation present (:func:`is_disturbed`): the step takes the inputs
        :data:`ENV_INPUTS` after the others. Calm layouts keep the calm-water step exactly.
    """

    methods: tuple
    n_obstacles: int = 0
    n_walls: int = 0
    max_path: int = 2
    vo_candidates: int = PARAMETERS["vo_candidates"].default
    vo_cone: str = PARAMETERS["vo_cone"].default
    vo_hold: bool = PARAMETERS["vo_hold"].default
    smooth: float | None = None
    disturbed: bool = False

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
    def method_inputs(self) -> tuple[str, ...]:
        """Numeric step inputs of the methods this layout uses (the ``inputs`` of each
        :class:`mmg_casadi.guidance.methods.Method`), after the others in the parameter vector."""
        used = set(self.methods)
        return tuple(k for n, m in methods.METHODS.items() if n in used for k in m.inputs)

    @property
    def np(self) -> int:
        """Rows of the parameter vector."""
        return (len(GLOBAL_PARAMS) + self.n_ships * (len(SHIP_PARAMS) + 2 * self.max_path)
                + 3 * self.n_obstacles + 4 * self.n_walls + (len(ENV_INPUTS) if self.disturbed else 0)
                + len(self.method_inputs))

    def key(self) -> str:
        """Short identifier used in Function names."""
        meth = "_".join(m.replace("-", "") for m in self.methods)
        if len(set(self.methods)) == 1:
            meth = f"{self.methods[0].replace('-', '')}x{self.n_ships}"
        s = "" if self.smooth is None else f"_s{self.smooth:g}".replace(".", "p")
        s += "_env" if self.disturbed else ""
        return (f"{meth}_o{self.n_obstacles}_w{self.n_walls}_k{self.max_path}_v{self.vo_candidates}{self.vo_cone}"
                f"{'h' if self.vo_hold else ''}{s}")

    def split_params(self, p):
        """Split a parameter vector (symbolic or numeric) into named pieces.

        Parameters
        ----------
        p : SX, MX, DM or ndarray
            A parameter vector of this layout (:attr:`np` rows).
        """
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
        if self.disturbed:
            out["env"] = p[i:i + len(ENV_INPUTS)]
            i += len(ENV_INPUTS)
        for name in self.method_inputs:
            out[name] = p[i]
            i += 1
        assert i == self.np
        return out


def pack_params(layout: Layout, globals_: dict, ships: list[dict], obstacles=(), walls=(), env=None) -> np.ndarray:
    """Numeric parameter vector for ``layout``.

    ``ships[i]`` has ``n_rpm``, ``path`` (K_i x 2 array: start then waypoints) and ``stays``; paths are padded to
    ``layout.max_path`` columns by repeating the last waypoint. ``obstacles`` are ``(x, y, radius)``, walls
    ``(ax, ay, bx, by)``; ``env`` the :data:`ENV_INPUTS` of a disturbed layout (:func:`env_values`).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the scenario.
    globals_ : dict
        The step's global numeric inputs (:func:`default_globals`, :func:`step_values`).
    ships : list of dict
        Per ship ``n_rpm``, ``path`` (L) and ``stays``.
    obstacles : sequence of (float, float, float), optional
        Static obstacles ``(x, y, radius)`` (L).
    walls : sequence of (float, float, float, float), optional
        Wall segments ``(ax, ay, bx, by)`` (L).
    env : dict, optional
        The :data:`ENV_INPUTS` of a disturbed layout (:func:`env_values`).
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
    if layout.disturbed:
        if env is None or len(env) != len(ENV_INPUTS):
            raise ValueError(f"a disturbed layout needs env = {ENV_INPUTS}, got {env!r}")
        vals += [float(v) for v in env]
    vals += [float(globals_[name]) for name in layout.method_inputs]
    p = np.array(vals)
    assert p.size == layout.np
    return p


def initial_state(layout: Layout, ships: list[dict]) -> np.ndarray:
    """Scenario state at t = 0: each ship at ``start`` with ``heading`` (rad) and surge speed ``speed`` × U_des.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the scenario.
    ships : list of dict
        Per ship ``start`` (L), ``heading`` (rad), ``speed`` (fraction of U_des) and ``path`` (L).
    """
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
        row[S_["vo_heading"]] = float(s["heading"])
        x[1 + i * NS: 1 + (i + 1) * NS] = row
    return x


def _indicator(cond_margin, smooth):
    """1 where ``cond_margin > 0`` (exact) or its sigmoid of sharpness ``smooth``."""
    if smooth is None:
        return cond_margin > 0
    return 0.5 * (1 + ca.tanh(0.5 * smooth * cond_margin))


def build_closed_loop_step(layout: Layout, ship: ShipParams | None = None,
                           steering: SteeringParams | None = None, *, n_sub: int = 1,
                           sparse: bool = False) -> ca.Function:
    """Named Function ``closed_loop_<key>(x, p) -> (x_next, aux)`` for one guidance step of the whole scenario.

    ``aux`` (NAUX x N) holds per ship the commanded rudder, desired heading, cross-track error and whether the
    reactive guidance was in charge during the step.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the scenario.
    ship : mmg_casadi.vessel.ship.ShipParams, optional
        Hull and propulsion parameters (default: the KCS, :func:`~mmg_casadi.vessel.ship.load_kcs`).
    steering : mmg_casadi.vessel.ship.SteeringParams, optional
        Steering-gear parameters (default: :func:`~mmg_casadi.vessel.ship.load_steering`).
    n_sub : int, default 1
        Number of RK4 sub-steps per guidance step.
    sparse : bool, default False
        Evaluate only what a step needs (for rollouts; exact layouts only): a ship that is not sailing skips its
        guidance and its integration (its state is held, as in the dense step, and its ``aux`` column is NaN),
        and a method sees only its neighbours within R_safe, gathered in order (the other neighbours are masked
        out by ``active`` and add exact zeros in the dense step). Same ``x_next`` as the dense step; the dense
        step (a single SX expression) is the one to differentiate.

    Examples
    --------
    >>> lay = Layout(("modified-vortex",) * 3, n_obstacles=1)
    >>> build_closed_loop_step(lay).name(), build_closed_loop_step(lay, sparse=True).name()
    ('closed_loop_modifiedvortexx3_o1_w0_k2_v80huangh', 'closed_loop_modifiedvortexx3_o1_w0_k2_v80huangh')
    """
    ship = ship or load_kcs()
    steering = steering or load_steering()
    if sparse:
        _check_sparse(layout)
        return _sparse_functions(layout, ship, steering, n_sub)[0]
    mmg = build_mmg(ship, steering, disturbed=layout.disturbed)
    x = ca.SX.sym("x", layout.nx)
    p = ca.SX.sym("p", layout.np)
    c = _step_context(layout, x, p)
    x_next, aux = [], []
    for i in range(layout.n_ships):
        new, aux_i = _ship_update(layout, i, c, mmg, n_sub)
        x_next.append(ca.if_else(c["sailing"][i], new, c["X"][i]))
        aux.append(aux_i)
    x_new = _bookkeeping(layout, c, x_next)
    # common-subexpression elimination: the same operations without repeats, so results are bit-identical
    return ca.Function(f"closed_loop_{layout.key()}", [x, p], [x_new, ca.horzcat(*aux)], ["x", "p"],
                       ["x_next", "aux"], {"cse": True})


def _step_context(layout: Layout, x, p, shared=None) -> dict:
    """Named pieces of a step's inputs: parameters, time, ship states, positions, velocities over the ground,
    whether each ship sails and is present as an obstacle (from ``shared`` = per ship ``[x, y, v_x, v_y,
    present]`` when given, as the sparse step passes them)."""
    N = layout.n_ships
    P = layout.split_params(p)
    t = x[0]
    X = [x[1 + i * NS: 1 + (i + 1) * NS] for i in range(N)]
    psi = [Xi[S_["psi"]] for Xi in X]
    E, env_args = None, ()
    if shared is None:
        pos = [ca.vertcat(Xi[S_["x"]], Xi[S_["y"]]) for Xi in X]
        vel = [ca.vertcat(Xi[S_["u"]] * ca.cos(Xi[S_["psi"]]) - Xi[S_["v"]] * ca.sin(Xi[S_["psi"]]),
                          Xi[S_["u"]] * ca.sin(Xi[S_["psi"]]) + Xi[S_["v"]] * ca.cos(Xi[S_["psi"]])) for Xi in X]
    else:
        pos = [shared[5 * i: 5 * i + 2] for i in range(N)]
        vel = [shared[5 * i + 2: 5 * i + 4] for i in range(N)]
    if layout.disturbed:  # u, v are through the water; guidance sees velocities over the ground
        E = P["env"]
        env_args = (E[0:4],)
        if shared is None:
            vel = [ca.vertcat(*environment.velocity_over_ground(Xi[S_["u"]], Xi[S_["v"]], Xi[S_["psi"]], E[0], E[1]))
                   for Xi in X]
    running = t < P["t_max"] - 1e-9
    sailing = [ca.logic_and(Xi[S_["status"]] == 0, running) for Xi in X]
    if shared is None:
        # A ship is present as an obstacle while sailing, or after its goal if it stays; a diverged ship is removed.
        present = [ca.if_else(Xi[S_["status"]] == 0, 1,
                              ca.if_else(Xi[S_["status"]] == 1, P["ships"][i]["stays"], 0))
                   for i, Xi in enumerate(X)]
    else:
        present = [shared[5 * i + 4] for i in range(N)]
    return {"P": P, "t": t, "X": X, "pos": pos, "psi": psi, "vel": vel, "E": E, "env_args": env_args,
            "running": running, "sailing": sailing, "present": present}


def _ship_update(layout: Layout, i: int, c: dict, mmg, n_sub: int, *, sparse: bool = False):
    """Ship ``i``'s state after the step while it sails (``NS`` rows; the caller holds a ship that does not)
    and its ``aux`` column."""
    N, S, W = layout.n_ships, layout.n_obstacles, layout.n_walls
    sm = layout.smooth
    P, t, X, pos, psi, vel, E = c["P"], c["t"], c["X"], c["pos"], c["psi"], c["vel"], c["E"]
    present = c["present"]
    dt = P["dt"]
    obs = P["obstacles"]
    walls = P["walls"]
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
    spec = methods.get(method, f"methods[{i}]")
    if spec.goal_capture:
        # past its final waypoint (missed outside the acceptance radius) the ship turns back to it instead of
        # following the extended last leg for ever
        past = ca.logic_and(Xi[S_["idx"]] > Pi["n_path"] - 1.5,
                            terms["x_e"] > ca.norm_2(terms["wp_next"] - terms["wp_prev"]))
        to_goal = terms["wp_next"] - pos[i]
        psi_ilos = ca.if_else(past, ca.atan2(to_goal[1], to_goal[0]), psi_ilos)
    if layout.disturbed:  # optional crab-angle compensation: steer the course, psi_d = chi_d - beta
        u_g, v_g = environment.ground_velocity(Xi[S_["u"]], Xi[S_["v"]], psi[i], E[0], E[1])
        psi_ilos = psi_ilos - E[4] * environment.crab_angle(u_g, v_g)
    chosen = None  # heading chosen by the method while a neighbour is within R_safe
    if spec.builder is None or (M == 0 and W == 0):
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
        speed = ca.norm_2(vel[i]) if layout.disturbed else ca.sqrt(Xi[S_["u"]] ** 2 + Xi[S_["v"]] ** 2)
        inputs = GuidanceInputs(pos=pos[i], vel=vel[i], psi=psi[i], speed=speed, goal=goal,
                                nb_pos=nb_pos, nb_vel=nb_vel, nb_radius=nb_rad, active=active, P=P,
                                layout=layout, held_heading=Xi[S_["vo_heading"]])
        method_vec = _within_range(layout, method, M)(ca.sum2(active), *_dispatch_args(layout, inputs)) \
            if sparse and M > 1 else spec.builder(inputs)
        if M:
            chosen = (any_active > 0.5, ca.atan2(method_vec[1], method_vec[0]))
        field_vec = method_vec + wall_vec
        if sm is None:
            psi_d = ca.if_else(w_react, ca.atan2(field_vec[1], field_vec[0]), psi_ilos)
        else:
            e_f = field_vec / ca.sqrt(ca.sumsqr(field_vec) + 1e-12)
            e = w_react * e_f + (1 - w_react) * ca.vertcat(ca.cos(psi_ilos), ca.sin(psi_ilos))
            psi_d = ca.atan2(e[1], e[0])

    delta_c = pd_heading(psi[i], psi_d, Xi[S_["r"]], P["kp"], P["kd"], P["delta_max"])
    xm = Xi[:NX]
    xm_next = rk4(mmg, xm, (delta_c, Pi["n_rpm"], *c["env_args"]), dt / n_sub)
    for _ in range(n_sub - 1):
        xm_next = rk4(mmg, xm_next, (delta_c, Pi["n_rpm"], *c["env_args"]), dt / n_sub)
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
        xm_next[5] if chosen is None else ca.if_else(chosen[0], chosen[1], xm_next[5]),
    )
    return new, ca.vertcat(delta_c, psi_d, terms["y_e"], w_react)


def _bookkeeping(layout: Layout, c: dict, x_next: list):
    """The next scenario state: closest approach and first collision, from the positions after the step, for
    every pair present at its start, and the clock."""
    out = []
    for i in range(layout.n_ships):
        xn = x_next[i]
        xn = ca.vertcat(xn[:S_["d_min"]], _encounter_row(layout, c, x_next, i), xn[S_["collision_with"] + 1:])
        out.append(xn)
    return ca.vertcat(ca.if_else(c["running"], c["t"] + c["P"]["dt"], c["t"]), *out)


_ROW = ("d_min", "d_min_with", "t_collision", "collision_with")
"""Rows of a ship's state updated by :func:`_encounter_row` (consecutive in :data:`SHIP_STATE`)."""


def _encounter_row(layout: Layout, c: dict, x_next: list, i: int):
    """Ship ``i``'s closest approach (and with whom) and first collision (when, with whom) after the step."""
    N, S = layout.n_ships, layout.n_obstacles
    P, t, present, running = c["P"], c["t"], c["present"], c["running"]
    dt = P["dt"]
    obs = P["obstacles"]
    pos_n = [xn[3:5] for xn in x_next]
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
    return ca.vertcat(d_min, d_with, t_col, c_with)


@functools.lru_cache(maxsize=16)
def _sparse_functions(layout: Layout, ship: ShipParams, steering: SteeringParams,
                      n_sub: int) -> tuple[ca.Function, ca.Function]:
    """The steps of :func:`build_closed_loop_step` and :func:`build_guidance` with ``sparse=True``.

    A prelude computes every ship's position, velocity over the ground, presence and sailing flag; per ship a
    conditional (``Function.conditional``) either holds the ship or runs :func:`_ship_update`; the bookkeeping
    follows. They are generated as calls, so a branch not taken costs nothing. The guidance Function runs the
    same per-ship pieces up to the rudder command."""
    mmg = build_mmg(ship, steering, disturbed=layout.disturbed)
    N, key = layout.n_ships, layout.key()
    xs, ps = ca.SX.sym("x", layout.nx), ca.SX.sym("p", layout.np)
    c = _step_context(layout, xs, ps)
    shared = ca.vertcat(*[ca.vertcat(c["pos"][i], c["vel"][i], c["present"][i]) for i in range(N)])
    counted = [ca.logic_and(c["present"][i], c["running"]) for i in range(N)]
    pre = ca.Function(f"pre_{key}", [xs, ps], [shared, ca.vertcat(*c["sailing"]), ca.vertcat(*counted)],
                      {"cse": True})
    sh = ca.SX.sym("shared", 5 * N)
    cs = _step_context(layout, xs, ps, shared=sh)
    nxt = ca.SX.sym("next", N * NS)
    rows_next = [nxt[i * NS:(i + 1) * NS] for i in range(N)]
    x, p = ca.MX.sym("x", layout.nx), ca.MX.sym("p", layout.np)
    sh_mx, sailing, counts = pre(x, p)
    news, auxs, rudders = [], [], []
    for i in range(N):
        new, aux_i = _ship_update(layout, i, cs, mmg, n_sub, sparse=True)
        run = ca.Function(f"sail{i}_{key}", [xs, ps, sh], [new, aux_i], {"cse": True})
        hold = ca.Function(f"hold{i}_{key}", [xs, ps, sh], [cs["X"][i], ca.DM.nan(NAUX, 1)])
        new_mx, aux_mx = ca.Function.conditional(f"ship{i}_{key}", [hold], run)(sailing[i], x, p, sh_mx)
        news.append(new_mx)
        auxs.append(aux_mx)
        steer = ca.Function(f"steer{i}_{key}", [xs, ps, sh], [aux_i[0]], {"cse": True})
        idle = ca.Function(f"idle{i}_{key}", [xs, ps, sh], [ca.DM.nan(1, 1)])
        rudders.append(ca.Function.conditional(f"rudder{i}_{key}", [idle], steer)(sailing[i], x, p, sh_mx))
    # closest approach and collisions: a ship absent at the start of the step (or past the horizon) keeps its row
    nxt_mx = ca.vertcat(*news)
    r0, r1 = S_[_ROW[0]], S_[_ROW[-1]] + 1
    clock = ca.Function(f"clock_{key}", [xs, ps], [ca.if_else(c["running"], c["t"] + c["P"]["dt"], c["t"])])
    rows = [clock(x, p)]
    for i in range(N):
        update = ca.Function(f"meet{i}_{key}", [xs, ps, nxt], [_encounter_row(layout, c, rows_next, i)],
                             {"cse": True})
        keep = ca.Function(f"keep{i}_{key}", [xs, ps, nxt], [rows_next[i][r0:r1]])
        row = ca.Function.conditional(f"row{i}_{key}", [keep], update)(counts[i], x, p, nxt_mx)
        rows += [news[i][:r0], row, news[i][r1:]]
    step = ca.Function(f"closed_loop_{key}", [x, p], [ca.vertcat(*rows), ca.horzcat(*auxs)],
                       ["x", "p"], ["x_next", "aux"])
    guidance = ca.Function(f"guidance_{key}", [x, p], [ca.horzcat(*rudders)], ["x", "p"], ["delta_c"])
    return step, guidance


_SLOTS = (1, 2, 4)
"""Neighbour counts for which :func:`_within_range` has a gathered branch (more active ones: all M)."""


def _method_scalars(layout: Layout) -> tuple[str, ...]:
    return GLOBAL_PARAMS + layout.method_inputs


def _dispatch_args(layout: Layout, g: GuidanceInputs) -> list:
    return [g.pos, g.vel, g.psi, g.speed, g.goal, g.nb_pos, g.nb_vel, g.nb_radius, g.active, g.held_heading,
            ca.vertcat(*[g.P[k] for k in _method_scalars(layout)])]


@functools.lru_cache(maxsize=None)
def _within_range(layout: Layout, method: str, m: int) -> ca.Function:
    """Never-inlined Function ``(k, pos, vel, psi, speed, goal, nb_pos, nb_vel, nb_radius, active, held, P)``
    → the method's 2×1 vector, evaluating the method on the ``k`` active neighbours only (gathered in their
    order into 1, 2 or 4 slots, the unused slots inactive) or on all ``m`` when more are active; with none
    active and no walls it returns (1, 0) without evaluating the method (the step does not read it). Exact only
    because every method ignores an inactive neighbour (a masked term adds an exact zero; a test checks each
    registered method)."""
    spec = methods.get(method)
    names = _method_scalars(layout)
    sym = [ca.SX.sym("pos", 2), ca.SX.sym("vel", 2), ca.SX.sym("psi"), ca.SX.sym("speed"), ca.SX.sym("goal", 2),
           ca.SX.sym("nb_pos", 2, m), ca.SX.sym("nb_vel", 2, m), ca.SX.sym("nb_radius", 1, m),
           ca.SX.sym("active", 1, m), ca.SX.sym("held"), ca.SX.sym("P", len(names))]
    pos, vel, psi, speed, goal, nb_pos, nb_vel, nb_rad, active, held, pv = sym
    P = {k: pv[n] for n, k in enumerate(names)}

    def branch(slots):
        if slots >= m:
            g_pos, g_vel, g_rad, g_act = nb_pos, nb_vel, nb_rad, active
        else:
            cols = [[ca.SX.zeros(2, 1), ca.SX.zeros(2, 1), ca.SX(0), ca.SX(0)] for _ in range(slots)]
            before = ca.SX(0)  # active neighbours before column j
            for j in range(m):
                for q in range(slots):
                    take = ca.logic_and(active[j] == 1, before == q)
                    src = (nb_pos[:, j], nb_vel[:, j], nb_rad[j], active[j])
                    cols[q] = [ca.if_else(take, s_, d_) for s_, d_ in zip(src, cols[q])]
                before = before + active[j]
            g_pos = ca.horzcat(*[cq[0] for cq in cols])
            g_vel = ca.horzcat(*[cq[1] for cq in cols])
            g_rad = ca.horzcat(*[cq[2] for cq in cols])
            g_act = ca.horzcat(*[cq[3] for cq in cols])
        g = GuidanceInputs(pos=pos, vel=vel, psi=psi, speed=speed, goal=goal, nb_pos=g_pos, nb_vel=g_vel,
                           nb_radius=g_rad, active=g_act, P=P, layout=layout, held_heading=held)
        return ca.Function(f"{method.replace('-', '')}_{layout.key()}_m{m}_s{min(slots, m)}", sym,
                           [spec.builder(g)], {"cse": True})

    sizes = [s for s in _SLOTS if s < m]
    by_size = {s: branch(s) for s in sizes}
    cases = [by_size[min(s for s in sizes if s >= max(k, 1))] for k in range(max(sizes) + 1)]
    if layout.n_walls == 0:
        # nothing within R_safe and no walls: the step follows ILOS and never reads the method's vector
        cases[0] = ca.Function(f"{method.replace('-', '')}_{layout.key()}_m{m}_idle", sym, [ca.DM([1.0, 0.0])])
    cond = ca.Function.conditional(f"within_{method.replace('-', '')}_{layout.key()}_m{m}", cases, branch(m))
    xm = [ca.MX.sym(f"a{n}", *cond.size_in(n)) for n in range(cond.n_in())]
    return ca.Function(f"within_range_{method.replace('-', '')}_{layout.key()}_m{m}", xm, [cond(*xm)],
                       {"never_inline": True})


def _check_sparse(layout: Layout) -> None:
    if layout.smooth is not None:
        raise ParameterError("sparse", "False for a smooth layout (the smoothed step is the one differentiated)",
                             True)


def build_guidance(layout: Layout, ship: ShipParams | None = None,
                   steering: SteeringParams | None = None, *, sparse: bool = False) -> ca.Function:
    """Guidance-and-control part only: ``guidance_<key>(x, p) -> delta_c (1 x N)``, for timing the methods.

    With ``sparse`` (see :func:`build_closed_loop_step`) a ship that is not sailing gets NaN without any
    computation and a method sees only its neighbours within R_safe: the cost of the guidance the rollouts run.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the scenario.
    ship : mmg_casadi.vessel.ship.ShipParams, optional
        Hull and propulsion parameters (default: the KCS, :func:`~mmg_casadi.vessel.ship.load_kcs`).
    steering : mmg_casadi.vessel.ship.SteeringParams, optional
        Steering-gear parameters (default: :func:`~mmg_casadi.vessel.ship.load_steering`).
    sparse : bool, default False
        The guidance of the sparse step (exact layouts only).
    """
    if sparse:
        _check_sparse(layout)
        return _sparse_functions(layout, ship or load_kcs(), steering or load_steering(), 1)[1]
    step = build_closed_loop_step(layout, ship, steering)
    x = ca.SX.sym("x", layout.nx)
    p = ca.SX.sym("p", layout.np)
    _, aux = step(x, p)
    return ca.Function(f"guidance_{layout.key()}", [x, p], [aux[0, :]], ["x", "p"], ["delta_c"], {"cse": True})


def ship_rows(layout: Layout, X: np.ndarray) -> np.ndarray:
    """Reshape scenario states ``(nx, T)`` (or ``(nx,)``) to ``(T, N, NS)`` (or ``(N, NS)``).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the scenario.
    X : numpy.ndarray
        Scenario states, ``(nx, T)`` or ``(nx,)``.
    """
    X = np.asarray(X)
    if X.ndim == 1:
        return X[1:].reshape(layout.n_ships, NS)
    return X[1:, :].T.reshape(X.shape[1], layout.n_ships, NS)


def step_values(resolved: dict) -> dict:
    """The step's numeric inputs (:data:`GLOBAL_PARAMS` and the ``inputs`` of every
    :class:`~mmg_casadi.guidance.methods.Method`) from a resolved parameter set (table angles in degrees to rad).

    Parameters
    ----------
    resolved : dict
        A resolved parameter set (table names and units).

    Examples
    --------
    >>> g = step_values(resolve())
    >>> round(g["gamma_max"], 6), g["kp"]
    (1.963495, 3.5)
    """
    out = {}
    for name in GLOBAL_PARAMS:
        src = _DEG_INPUTS.get(name)
        out[name] = math.radians(float(resolved[src])) if src else float(resolved[name])
    for m in methods.METHODS.values():
        for name in m.inputs:
            out[name] = math.radians(float(resolved[name + "_deg"])) if name not in resolved else float(resolved[name])
    return out


def is_disturbed(resolved: dict) -> bool:
    """Whether a resolved parameter set has a current, a wind or crab-angle compensation (a disturbed layout).

    Parameters
    ----------
    resolved : dict
        A full parameter set (:func:`mmg_casadi.params.resolve`); only ``current_speed``, ``wind_speed`` and
        ``crab_compensation`` are read (a direction without a speed does not count).

    Returns
    -------
    bool
        True if ``current_speed > 0``, ``wind_speed > 0`` or ``crab_compensation == "on"``.

    Examples
    --------
    >>> is_disturbed(resolve()), is_disturbed(resolve({"current_direction_deg": 90.0}))
    (False, False)
    >>> is_disturbed(resolve({"wind_speed": 15.0}))
    True
    """
    return (float(resolved["current_speed"]) > 0.0 or float(resolved["wind_speed"]) > 0.0
            or resolved["crab_compensation"] == "on")


def env_values(resolved: dict, ship: ShipParams | None = None) -> list[float]:
    """The :data:`ENV_INPUTS` of a resolved parameter set: speeds over ``ship``'s design speed (default the KCS,
    12.347 m/s; the table's current is already a fraction of it, its wind in m/s), directions in rad, crab 0/1.

    Parameters
    ----------
    resolved : dict
        A full parameter set (:func:`mmg_casadi.params.resolve`); reads ``current_speed`` (fraction of the
        design speed), ``current_direction_deg`` and ``wind_direction_deg`` (deg), ``wind_speed`` (m/s) and
        ``crab_compensation`` (``"on"`` or ``"off"``).
    ship : ShipParams, optional
        Ship whose design speed ``U_design`` [m/s] makes the wind speed non-dimensional; the KCS
        (:func:`mmg_casadi.vessel.ship.load_kcs`) if omitted.

    Returns
    -------
    list of float
        ``[V_c, beta_c, U_w, psi_w, crab]`` in the order of :data:`ENV_INPUTS`.

    Examples
    --------
    >>> [round(v, 4) for v in env_values(resolve({"current_speed": 0.1, "current_direction_deg": 90.0,
    ...                                          "wind_speed": 15.0, "crab_compensation": "on"}))]
    [0.1, 1.5708, 1.2149, 0.0, 1.0]
    """
    U = (ship or load_kcs()).U_design
    return [float(resolved["current_speed"]), math.radians(float(resolved["current_direction_deg"])),
            float(resolved["wind_speed"]) / U, math.radians(float(resolved["wind_direction_deg"])),
            1.0 if resolved["crab_compensation"] == "on" else 0.0]


def default_globals(**overrides) -> dict:
    """The step's numeric inputs for the table's defaults updated with ``overrides`` (table names), checked.

    Parameters
    ----------
    **overrides : float
        Parameter values by table name, replacing the defaults.

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
    return step_values(resolve(overrides))


OUTCOMES = ("reached", "diverged", "stalled", "timeout")
"""A ship's outcome: reached its goal, left the model envelope, made no progress (``stall_window``), or none."""


def ship_outcome(row, t_end: float, stall_window: float) -> tuple[str, tuple[float, float] | None]:
    """Outcome of one ship from its final state row (:data:`SHIP_STATE`) — the one judgement every runner uses.

    Returns the outcome (one of :data:`OUTCOMES`) and, for ``"stalled"``, the position closest to the goal.

    Parameters
    ----------
    row : numpy.ndarray (NS,)
        Final state row of the ship (:data:`SHIP_STATE`).
    t_end : float
        End time of the run (L/U).
    stall_window : float
        A ship that has not come closer to its goal for this long is stalled (L/U).

    Examples
    --------
    >>> row = np.zeros(NS); row[S_["status"]] = 1
    >>> ship_outcome(row, 80.0, 50.0)
    ('reached', None)
    >>> row[S_["status"]] = 0; row[S_["t_best"]] = 20.0; row[S_["x_best"]] = 3.0
    >>> ship_outcome(row, 300.0, 50.0)
    ('stalled', (3.0, 0.0))
    """
    status = row[S_["status"]]
    if status == 1:
        return "reached", None
    if status == 2:
        return "diverged", None
    if t_end - row[S_["t_best"]] >= stall_window:
        return "stalled", (float(row[S_["x_best"]]), float(row[S_["y_best"]]))
    return "timeout", None


def voyage_metrics(rows: np.ndarray, t_end: float, delta_max: float) -> tuple[np.ndarray, np.ndarray]:
    """CE and MCTE of every ship from final state rows ``(N, NS)`` — the one definition every runner uses.

    ``CE = ∫|δ| dt / (δ_max T)`` (eq. (controller_effort_equation)) and ``MCTE = ∫|y_e| dt / T`` (eq.
    (crosstrack_metric_equation)) with the integrals accumulated by the compiled step while the ship sails
    (trapezoidal in δ, the cross-track error sampled at each step's start) and ``T`` the time to goal, or the
    end time for a ship still sailing; ``nan`` for a diverged ship (its voyage time is not in the state).

    Parameters
    ----------
    rows : numpy.ndarray (N, NS)
        Final state rows of the ships.
    t_end : float
        End time of the run (L/U).
    delta_max : float
        Largest rudder angle δ_max (rad).

    Examples
    --------
    >>> rows = np.zeros((1, NS)); rows[0, S_["status"]] = 1; rows[0, S_["t_goal"]] = 10.0
    >>> rows[0, S_["ce_int"]] = 1.0; rows[0, S_["mcte_int"]] = 5.0
    >>> ce, mcte = voyage_metrics(rows, 10.0, 0.5)
    >>> float(ce[0]), float(mcte[0])
    (0.2, 0.5)
    """
    rows = np.atleast_2d(np.asarray(rows, float))
    status = rows[:, S_["status"]]
    T = np.where(status == 1, rows[:, S_["t_goal"]], np.where(status == 0, t_end, np.nan))
    with np.errstate(invalid="ignore", divide="ignore"):
        T = np.where(T > 0, T, np.nan)
        return rows[:, S_["ce_int"]] / (delta_max * T), rows[:, S_["mcte_int"]] / T


@dataclass(frozen=True)
class ClosedLoopModel:
    """The closed loop of one scenario shape, declared once and consumed by simulation, Monte Carlo and tuning.

    Parameters
    ----------
    layout : Layout
        Ships' methods, obstacles, walls, path length and the structural parameters.
    params : dict
        The resolved parameter set (every entry of :data:`mmg_casadi.params.PARAMETERS`).

    Examples
    --------
    >>> m = ClosedLoopModel(Layout(("none",)), resolve())
    >>> m.values["kp"], m.layout.nx == 1 + NS
    (3.5, True)
    """

    layout: Layout
    params: dict = field(hash=False, compare=False)

    @property
    def values(self) -> dict:
        """The step's numeric inputs by name (:func:`step_values`)."""
        return step_values(self.params)

    def step(self, *, smooth: float | None = None) -> ca.Function:
        """The exact or smoothed symbolic step ``(x, p) -> (x_next, aux)``.

        Parameters
        ----------
        smooth : float, optional
            ``None`` for the exact switching logic, else the sigmoid sharpness of the smoothed step (tuning).
        """
        lay = self.layout if smooth is None else dataclasses.replace(self.layout, smooth=float(smooth))
        return build_closed_loop_step(lay)

    def compiled_step(self) -> ca.Function:
        """The natively compiled exact step the rollouts use (its sparse form, cached on disk)."""
        from mmg_casadi.closed_loop.simulation import compiled_step
        return compiled_step(self.layout)

    def pack(self, ships: list[dict], obstacles=(), walls=()) -> np.ndarray:
        """Numeric parameter vector (:func:`pack_params`) with this model's parameter values.

        Parameters
        ----------
        ships : list of dict
            Per ship ``n_rpm``, ``path`` (start then waypoints) and ``stays``.
        obstacles : sequence of (x, y, radius)
            Static obstacles.
        walls : sequence of (ax, ay, bx, by)
            Wall segments.
        """
        return pack_params(self.layout, self.values, ships, obstacles, walls,
                           env_values(self.params) if self.layout.disturbed else None)

    def initial_state(self, ships: list[dict]) -> np.ndarray:
        """Scenario state at t = 0 (:func:`initial_state`).

        Parameters
        ----------
        ships : list of dict
            Per ship ``start``, ``heading`` (rad), ``speed`` and ``path``.
        """
        return initial_state(self.layout, ships)

    def ship_rows(self, X) -> np.ndarray:
        """Ship rows of scenario states: ``(N, NS)`` for one state, ``(T, N, NS)`` for columns ``(nx, T)``.

        Parameters
        ----------
        X : ndarray
            One scenario state ``(nx,)`` or states as columns ``(nx, T)``.
        """
        return ship_rows(self.layout, X)

    def state(self, x, name: str, ship: int | None = None):
        """One state variable of every ship (or of ``ship``) in the state(s) ``x``.

        Parameters
        ----------
        x : ndarray
            One scenario state ``(nx,)`` or states as columns ``(nx, T)``.
        name : str
            A name of :data:`SHIP_STATE`.
        ship : int, optional
            Ship index; all ships if omitted.
        """
        rows = self.ship_rows(x)
        col = rows[..., S_[name]]
        return col if ship is None else col[..., ship]

    def outcomes(self, x_final) -> list[dict]:
        """Per ship: outcome, stalled position, time to goal, CE, MCTE, collision and closest approach.

        Every runner judges a run with this one method (:func:`ship_outcome`, :func:`voyage_metrics`).

        Parameters
        ----------
        x_final : ndarray (nx,)
            Final scenario state.
        """
        x = np.asarray(x_final, float).ravel()
        rows = self.ship_rows(x)
        t_end = float(x[0])
        ce, mcte = voyage_metrics(rows, t_end, math.radians(self.params["delta_max_deg"]))
        out = []
        for i, row in enumerate(rows):
            status, where = ship_outcome(row, t_end, float(self.params["stall_window"]))
            t_col = float(row[S_["t_collision"]])
            d_min = float(row[S_["d_min"]])
            out.append({
                "status": status, "stalled_at": where,
                "stalled_time": float(row[S_["t_best"]]) if status == "stalled" else None,
                "time_to_goal": float(row[S_["t_goal"]]) if status == "reached" else None,
                "ce": float(ce[i]), "mcte": float(mcte[i]),
                "collision_time": t_col if t_col >= 0 else None,
                "collision_with": int(row[S_["collision_with"]]) if t_col >= 0 else None,
                "min_distance": d_min if d_min < 1e5 else None,
                "min_distance_with": int(row[S_["d_min_with"]]) if d_min < 1e5 else None,
                "reactive_time": float(row[S_["reactive_time"]]),
            })
        return out


@dataclass(frozen=True)
class Problem:
    """A scenario ready to simulate.

    Parameters
    ----------
    model : ClosedLoopModel
        Its closed loop.
    x0 : ndarray (nx,)
        Initial state.
    p : ndarray (np,)
        Parameter vector.
    ships : tuple of dict
        The per-ship dicts given to :func:`pack_params` / :func:`initial_state`.
    """

    model: ClosedLoopModel
    x0: np.ndarray = field(compare=False)
    p: np.ndarray = field(compare=False)
    ships: tuple = field(default=(), compare=False)

    @property
    def layout(self) -> Layout:
        """The model's layout."""
        return self.model.layout

    @property
    def params(self) -> dict:
        """The resolved parameter set."""
        return self.model.params


def build_problem(sc, params: dict | None = None, *, error=None) -> Problem:
    """The :class:`Problem` of a scenario: parameters resolved from the table, the scenario's settings and
    ``params`` (which win), the layout from its ships, obstacles and walls.

    Parameters
    ----------
    sc : Scenario
        A validated scenario (:func:`mmg_casadi.scenarios.scenario.load_scenario`).
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`).
    error : type, optional
        Error class for a bad override (default :class:`~mmg_casadi.errors.ParameterError`).

    Examples
    --------
    >>> from mmg_casadi.scenarios.scenario import Scenario, Settings, ShipSpec
    >>> sc = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 1, [[50, 0]])])
    >>> pr = build_problem(sc, {"kp": 2.0})
    >>> pr.layout.methods, pr.params["kp"], pr.params["t_max"]
    (('none',), 2.0, 300.0)
    """
    resolved = sc.settings.resolved(params, cls=error or ParameterError)
    methods_ = tuple(sc.method_of(i) for i in range(len(sc.ships)))
    for i, m in enumerate(methods_):
        if m not in methods.METHODS:
            raise ScenarioError(f"ships[{i}].method", f"one of: {', '.join(methods.NAMES)}", m)
    walls = []
    for w in sc.walls:
        pts = np.asarray(w.points, float)
        walls += [(a[0], a[1], b[0], b[1]) for a, b in zip(pts[:-1], pts[1:])]
    layout = Layout(methods=methods_, n_obstacles=len(sc.obstacles), n_walls=len(walls),
                    max_path=max(1 + len(s.waypoints) for s in sc.ships),
                    vo_candidates=resolved["vo_candidates"], vo_cone=resolved["vo_cone"],
                    disturbed=is_disturbed(resolved), vo_hold=resolved["vo_hold"])
    model = ClosedLoopModel(layout, resolved)
    ships = tuple({"n_rpm": propeller_rpm_for_speed(s.speed), "path": [s.start, *s.waypoints], "stays": s.stays,
                   "start": s.start, "heading": math.radians(s.heading_deg), "speed": s.speed} for s in sc.ships)
    obstacles = [(o.position[0], o.position[1], o.radius) for o in sc.obstacles]
    return Problem(model, model.initial_state(list(ships)), model.pack(list(ships), obstacles, walls), ships)
