"""One closed-loop guidance step for N ships and the hazards, as a CasADi Function (dense or sparse).

Every ship runs: ILOS guidance along its own waypoint path (outside R_safe of every neighbour) or the reactive
method inside R_safe, PD heading control, the steering gear, the engine and its vessel's MMG model, all
integrated over one guidance step ``dt`` with the rudder and propeller commands held (RK4). The ship-level
bookkeeping that the studies need (waypoint index, ILOS integrator, goal time, CE/MCTE integrals, closest
approach, first collision, progress towards the goal) is part of the state, so a rollout only has to keep the
final state. The state and parameter layout: :mod:`mmg_casadi.closed_loop.layout`.

A method (:mod:`mmg_casadi.guidance.methods`) returns a :class:`~mmg_casadi.guidance.methods.Command`: a
desired-heading vector and, optionally, a propeller speed, which the engine
(:func:`~mmg_casadi.vessel.actuators.engine_step`) follows at its rate; a method that commands no speed keeps the
ship's service propeller speed, exactly. Hazards (:mod:`mmg_casadi.guidance.hazards`): circular obstacles are
neighbours of the methods; walls add their field to every method's vector; touching either is a collision. Land
is seen ahead (:mod:`mmg_casadi.guidance.land_ahead`): in layouts with land a method is in charge while the
ship's path ahead reaches it, and a method without a land test of its own gets the paper's wall source at the
point of land met. A method that keeps Rule 9 (``Method.rule9``) follows the starboard lane of a narrow channel
(:mod:`mmg_casadi.guidance.fairway`). A collision or grounding ends that ship's voyage (:func:`stop_on_contact`).

Current and wind (table group "environment", :mod:`mmg_casadi.vessel.environment`): a layout with either (or with
crab-angle compensation) is ``Layout.disturbed`` and its step takes
:data:`~mmg_casadi.closed_loop.layout.ENV_INPUTS` as well; calm layouts keep the calm-water step exactly. The
state's ``u, v`` are then velocities through the water and the current carries the ship over the ground. What
guidance does with the disturbance: the fields and the velocity obstacle see every ship's velocity over the
ground (and the velocity obstacle the own speed over the ground); ILOS and the waypoint switching use positions,
so the ILOS integral compensates the drift; with ``crab_compensation = "on"`` ILOS steers the heading
``psi_d = chi_d - beta`` with the crab angle ``beta`` over the ground (Fossen, Pettersen & Galeazzi 2015). The
reactive methods' desired heading is not crab-compensated, and gusts
(:func:`~mmg_casadi.vessel.environment.gust_speeds`) are not wired into the closed loop. The model envelope
(divergence) is checked on the velocities through the water.
"""

from __future__ import annotations

import functools
import math

import casadi as ca

from mmg_casadi.closed_loop.layout import COMMAND_ROWS, STOPPED, Layout
from mmg_casadi.closed_loop.neighbours import dispatch_args, within_range
from mmg_casadi.closed_loop.behaviours import gate as traffic_gate
from mmg_casadi.closed_loop.replay import replay_update
from mmg_casadi.closed_loop.sensing import perceive
from mmg_casadi.perception import layer as perception_layer
from mmg_casadi.traffic import behaviour as traffic_behaviour
from mmg_casadi.errors import ParameterError
from mmg_casadi.guidance import fairway, hazards, methods
from mmg_casadi.guidance.heading_control import pd_heading
from mmg_casadi.guidance.ilos import (ilos_heading, ilos_integrator_rate, ilos_step_terms, limit_turn,
                                      switch_waypoint)
from mmg_casadi.guidance.land_ahead import hull_advance, land_ahead_function, land_source
from mmg_casadi.guidance.methods import GuidanceInputs, command_from_vector, forget_on_unregister
from mmg_casadi.vessel import environment
from mmg_casadi.vessel.actuators import engine_step
from mmg_casadi.vessel.library import load_vessel, pair_collision_distance
from mmg_casadi.vessel.mmg import NX, build_mmg, in_scene_units, rk4, scene_scales

AUX = ("delta_c", "psi_d", "y_e", "reactive")
"""Per-ship outputs of a step besides the state: rudder command, desired heading, cross-track error, and whether
the reactive guidance was in charge."""
NAUX = len(AUX)

ENVELOPE = {"speed": 3.0, "r": 5.0, "position": 1.0e4}
"""The model's envelope: a ship whose speeds (U), yaw rate (U/L) or ``|x| + |y|`` (L) leave it has diverged."""


def _indicator(cond_margin, smooth):
    """1 where ``cond_margin > 0`` (exact) or its sigmoid of sharpness ``smooth``."""
    if smooth is None:
        return cond_margin > 0
    return 0.5 * (1 + ca.tanh(0.5 * smooth * cond_margin))


def _either(a, b, smooth):
    """1 where ``a`` or ``b`` is 1 (exact: their maximum), or ``1 − (1 − a)(1 − b)`` for smooth indicators."""
    return ca.fmax(a, b) if smooth is None else 1 - (1 - a) * (1 - b)


def build_closed_loop_step(layout: Layout, *, n_sub: int = 1, sparse: bool = False) -> ca.Function:
    """Named Function ``closed_loop_<key>(x, p) -> (x_next, aux)`` for one guidance step of the whole scenario.

    ``aux`` (NAUX x N) holds per ship the commanded rudder, desired heading, cross-track error and whether the
    reactive guidance was in charge during the step.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, vessels, methods, obstacles, walls) of the scenario.
    n_sub : int, default 1
        Number of RK4 sub-steps per guidance step.
    sparse : bool, default False
        Evaluate only what a step needs (for rollouts; exact layouts only): a ship that is not sailing skips its
        guidance and its integration (its state is held, as in the dense step, and its ``aux`` column is NaN),
        and a method sees only its neighbours within R_safe, gathered in order (the other neighbours are masked
        out by ``active`` and add exact zeros in the dense step). Same ``x_next`` as the dense step; the dense
        step (a single SX expression) is the one to differentiate.

    Returns
    -------
    casadi.Function
        ``closed_loop_<key>(x, p) -> (x_next, aux)``: the scenario state after one guidance step (``nx``) and the
        ``(NAUX, N)`` auxiliary signals of the step.

    Examples
    --------
    >>> lay = Layout(("modified-vortex",) * 3, n_obstacles=1)
    >>> build_closed_loop_step(lay).name(), build_closed_loop_step(lay, sparse=True).name()
    ('closed_loop_modifiedvortexx3_o1_w0_k2_v80huangh', 'closed_loop_modifiedvortexx3_o1_w0_k2_v80huangh')
    """
    if sparse:
        _check_sparse(layout)
        return _sparse_functions(layout, n_sub)[0]
    mmgs = _models(layout)
    x = ca.SX.sym("x", layout.nx)
    p = ca.SX.sym("p", layout.np)
    c = _step_context(layout, x, p)
    seen, sensed = _perceived(layout, c)
    x_next, aux = [], []
    for i in range(layout.n_ships):
        ci = c if seen is None or i else _step_context(layout, x, p, shared=seen)  # the own ship's view
        new, aux_i = _ship_update(layout, i, ci, mmgs[layout.vessel(i)], n_sub)
        x_next.append(_with_rows(layout, ca.if_else(c["sailing"][i], new, c["X"][i]), sensed, i))
        aux.append(aux_i)
    x_new = _bookkeeping(layout, c, x_next)
    # common-subexpression elimination: the same operations without repeats, so results are bit-identical
    return ca.Function(f"closed_loop_{layout.key()}", [x, p], [x_new, ca.horzcat(*aux)], ["x", "p"],
                       ["x_next", "aux"], {"cse": True})


def _perceived(layout: Layout, c: dict):
    """With perception (:mod:`mmg_casadi.perception.layer`): the own ship's view of the ships (the shared vector of
    the sparse step) and every ship's perception rows after the step; ``(None, None)`` without."""
    if layout.perception == "off":
        return None, None
    return perceive(layout, c)


def _with_rows(layout: Layout, xi, sensed, i: int):
    """Ship ``i``'s rows ``xi`` with its perception rows (the last ones) replaced by ``sensed[i]``."""
    if sensed is None:
        return xi
    k = len(perception_layer.rows(layout.perception))
    return ca.vertcat(xi[:layout.ns - k], sensed[i])


def _models(layout: Layout) -> dict:
    """The MMG Function of every vessel the layout uses, in the scene's units (the own ship's hull,
    :meth:`Layout.unit_vessel`; :func:`~mmg_casadi.vessel.mmg.in_scene_units`)."""
    out = {}
    unit = load_vessel(layout.unit_vessel()).ship
    for name in dict.fromkeys(layout.vessel(i) for i in range(layout.n_ships)):
        v = load_vessel(name)
        out[name] = in_scene_units(build_mmg(v.ship, v.steering, disturbed=layout.disturbed), v.ship, unit)
    return out


def _own_time(layout: Layout, vessel: str, r):
    """The yaw rate ``r`` (per scene time unit) of a ship of ``vessel`` per unit of its own hull's time L/U_des, as
    its heading controller sees it: the PD gains act in each hull's own units, as in ``maneuver --vessel``."""
    lam, mu = scene_scales(load_vessel(vessel).ship, load_vessel(layout.unit_vessel()).ship)
    return r if lam == mu else r * (lam / mu)


def ship_kinematics(Xi, S_: dict, E, stays):
    """One ship's position, velocity over the ground (through the water plus the current ``E`` when disturbed)
    and presence as an obstacle.

    Parameters
    ----------
    Xi : SX
        The ship's rows of the scenario state.
    S_ : dict
        Column of each state name in ``Xi``.
    E : SX or None
        The disturbance inputs of a disturbed layout (:data:`~mmg_casadi.closed_loop.layout.ENV_INPUTS`).
    stays : SX
        1 if the ship stays as an obstacle after reaching its goal.

    Returns
    -------
    pos : casadi.SX (2, 1)
        Position (L).
    vel : casadi.SX (2, 1)
        Earth-fixed velocity over the ground (U_des units).
    present : casadi.SX
        1 if the ship counts as an obstacle, else 0: while she sails, after her goal if she ``stays``, and held
        where she stopped after a collision or grounding (:data:`STOPPED`); a diverged ship is removed.
    """
    u, v, psi, status = Xi[S_["u"]], Xi[S_["v"]], Xi[S_["psi"]], Xi[S_["status"]]
    if E is None:
        vel = ca.vertcat(u * ca.cos(psi) - v * ca.sin(psi), u * ca.sin(psi) + v * ca.cos(psi))
    else:  # u, v are through the water; guidance sees velocities over the ground; a stopped ship is held
        vel = ca.if_else(status == STOPPED, ca.SX.zeros(2, 1),
                         ca.vertcat(*environment.velocity_over_ground(u, v, psi, E[0], E[1])))
    present = ca.if_else(status == 0, 1, ca.if_else(status == 1, stays, ca.if_else(status == STOPPED, 1, 0)))
    return ca.vertcat(Xi[S_["x"]], Xi[S_["y"]]), vel, present


def _step_context(layout: Layout, x, p, shared=None) -> dict:
    """Named pieces of a step's inputs: parameters, time, ship states, positions, velocities over the ground,
    whether each ship sails and is present as an obstacle (from ``shared`` = per ship ``[x, y, v_x, v_y,
    present]`` when given, as the sparse step passes them)."""
    N = layout.n_ships
    P = layout.split_params(p)
    S_ = {name: layout.column(name) for name in layout.ship_state}
    t = x[0]
    X = [x[layout.ship_block(i)] for i in range(N)]
    psi = [Xi[S_["psi"]] for Xi in X]
    E, env_args = (P["env"], (P["env"][0:4],)) if layout.disturbed else (None, ())
    if shared is None:
        pos, vel, present = map(list, zip(*(ship_kinematics(Xi, S_, E, P["ships"][i]["stays"])
                                            for i, Xi in enumerate(X))))
    else:
        pos = [shared[5 * i: 5 * i + 2] for i in range(N)]
        vel = [shared[5 * i + 2: 5 * i + 4] for i in range(N)]
        present = [shared[5 * i + 4] for i in range(N)]
    running = t < P["t_max"] - 1e-9
    sailing = [ca.logic_and(Xi[S_["status"]] == 0, running) for Xi in X]
    return {"P": P, "S": S_, "t": t, "X": X, "pos": pos, "psi": psi, "vel": vel, "E": E, "env_args": env_args,
            "running": running, "sailing": sailing, "present": present}


def _ship_update(layout: Layout, i: int, c: dict, mmg, n_sub: int, *, sparse: bool = False, nb=None,
                 method: str | None = None, vessel: str | None = None):
    """Ship ``i``'s state after the step while it sails (``layout.ns`` rows; the caller holds a ship that does
    not) and its ``aux`` column. Its neighbours are every other ship and obstacle of ``c``, or ``nb`` = (positions,
    velocities, radii, presence) of gathered neighbour slots (the fleet step)."""
    if i in layout.replay and nb is None:  # a replayed ship follows its track (mmg_casadi.closed_loop.replay)
        return replay_update(layout, i, c)
    N, S, W = layout.n_ships, layout.n_obstacles, layout.n_walls
    sm = layout.smooth
    P, S_, t, X, pos, psi, vel, E = c["P"], c["S"], c["t"], c["X"], c["pos"], c["psi"], c["vel"], c["E"]
    present = c["present"]
    dt = P["dt"]
    obs = P["obstacles"]
    walls = P["walls"]
    Xi = X[i]
    Pi = P["ships"][i]
    method = method or layout.methods[i]
    terms = ilos_step_terms(pos[i], Pi["path"], Xi[S_["idx"]], Xi[S_["y_int"]], P["ilos_delta"], P["ilos_k"])
    goal = terms["wp_next"]
    spec = methods.get(method or layout.methods[i], f"methods[{i}]")
    vessel = vessel or layout.vessel(i)
    commanded = i in layout.commanded and nb is None
    goal_seen, y_int_rate = goal, terms["y_int_dot"]  # the goal the method steers for; ILOS's integral rate
    if spec.rule9 and W and not commanded:  # Rule 9: ILOS and the method follow the starboard lane of a channel
        terms, goal_seen, y_int_rate = _lane(layout, terms, pos[i], Xi[S_["y_int"]], walls, P, vessel)
    if nb is None:
        others = [j for j in range(N) if j != i]
        nb_pos = ca.horzcat(*[pos[j] for j in others], obs[0:2, :]) if (others or S) else ca.SX(2, 0)
        nb_vel = ca.horzcat(*[vel[j] for j in others], ca.SX.zeros(2, S)) if (others or S) else ca.SX(2, 0)
        nb_rad = ca.horzcat(*[P["ship_radius"] for _ in others], obs[2:3, :]) if (others or S) else ca.SX(1, 0)
        nb_present = ca.horzcat(*[present[j] for j in others], ca.SX.ones(1, S)) if (others or S) else ca.SX(1, 0)
    else:
        nb_pos, nb_vel, nb_rad, nb_present = nb
    M = nb_pos.size2()
    if M:
        d_nb = ca.sqrt(ca.sum1((nb_pos - ca.repmat(pos[i], 1, M)) ** 2))
        active = nb_present * _indicator(P["r_safe"] - d_nb, sm)
    else:
        active = ca.SX(1, 0)

    psi_ilos = terms["psi_d"]
    method = method or layout.methods[i]
    look = active  # the neighbours the method gets as active: within R_safe, plus its lookout if it has one
    if spec.lookout and M:
        look = nb_present * _indicator(P["r_safe"] + P[spec.lookout] - d_nb, sm)
    if spec.sensing and M:  # or within its own sensing range
        look = nb_present * _indicator(P[spec.sensing] - d_nb, sm)
    n_service = Pi["leg_rpm"][0]  # the propeller speed of the leg being sailed (exact when every leg has one)
    for k in range(1, layout.max_path):
        n_service = ca.if_else(Xi[S_["idx"]] > k - 0.5, Pi["leg_rpm"][k], n_service)
    if spec.goal_capture:
        # past its final waypoint (missed outside the acceptance radius) the ship turns back to it instead of
        # following the extended last leg for ever
        beyond = terms["x_e"] > ca.norm_2(terms["wp_next"] - terms["wp_prev"])  # abeam of the waypoint or past it
        past = ca.logic_and(Xi[S_["idx"]] > Pi["n_path"] - 1.5, beyond)
        to_goal = terms["wp_next"] - pos[i]
        psi_ilos = ca.if_else(past, ca.atan2(to_goal[1], to_goal[0]), psi_ilos)
    psi_plain = terms["psi_d"]  # ILOS as a ship of the method "none" steers it (a traffic ship that holds)
    if layout.disturbed:  # optional crab-angle compensation: steer the course, psi_d = chi_d - beta
        u_g, v_g = environment.ground_velocity(Xi[S_["u"]], Xi[S_["v"]], psi[i], E[0], E[1])
        crab = E[4] * environment.crab_angle(u_g, v_g)
        psi_ilos, psi_plain = psi_ilos - crab, psi_plain - crab
    if spec.turn_limit:
        # the method's moderate turn also while ILOS steers, except within R_safe of the waypoint: there a ship
        # that arrives off her track could circle a waypoint that lies inside her moderate turning circle for ever
        lim = ca.if_else(ca.norm_2(goal - pos[i]) > P["r_safe"], P[spec.turn_limit], ca.pi)
        psi_ilos = limit_turn(psi[i], psi_ilos, lim)
    land = None  # land seen ahead (layouts with land): the method is in charge while the path ahead reaches it
    if layout.n_land and spec.builder is not None and not commanded:
        land = _land_ahead(layout, pos[i], vel[i], psi[i], psi_ilos, walls, Pi, P, vessel)
    cmd = None  # the method's command, and whether a neighbour is within R_safe
    if commanded:  # steered from outside: the heading ordered in the state (Layout.commanded)
        psi_d = Xi[S_["command_heading"]]
        w_react = ca.SX(1)
    elif spec.builder is None or (M == 0 and W == 0):
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
            wall_vec = hazards.KINDS["wall"].field(pos[i], walls, P)
            near_wall = _indicator(ca.sumsqr(wall_vec) - 1e-12, sm)
        if land is not None and not spec.tests_land:  # the paper's wall source at the point of land met, from afar
            wall_vec = wall_vec + land["ahead"] * land_source(pos[i], land["point"], P["wall_lam"])
        w_react = _either(any_active, near_wall, sm)
        if land is not None:
            w_react = _either(w_react, land["ahead"], sm)
        speed = ca.norm_2(vel[i]) if layout.disturbed else ca.sqrt(Xi[S_["u"]] ** 2 + Xi[S_["v"]] ** 2)
        own = {}
        if spec.own_state:  # the ship's own state and engine, for a method that predicts with a model of her
            own = {k: Xi[S_[k]] for k in ("u", "v", "r", "delta", "n_prop")}
            own.update({k: Pi[k] for k in ("rpm_min", "rpm_max")}, engine_rate=Pi["engine_rate"],
                       engine_lag=Pi["engine_lag"])
        inputs = GuidanceInputs(pos=pos[i], vel=vel[i], psi=psi[i], speed=speed, goal=goal_seen,
                                nb_pos=nb_pos, nb_vel=nb_vel, nb_radius=nb_rad, active=look, P=P,
                                layout=layout, memory={k: Xi[S_[k]] for k in spec.memory},
                                service_rpm=n_service, walls=walls if W else None,
                                half_beam=Pi["half_beam"] if W else None, own=own)
        if sparse and M > 1:
            command = command_from_vector(spec, within_range(layout, method, M)(ca.sum2(look),
                                                                               *dispatch_args(layout, inputs)))
        else:
            command = spec.builder(inputs)
        if spec.engaged is not None and M:
            # an encounter with a ship beyond R_safe, within the method's lookout, keeps the method in charge
            engaged = spec.engaged(command.memory)
            any_active = _either(any_active, engaged, sm)
            w_react = _either(w_react, engaged, sm)
        cmd = (command, any_active > 0.5 if M else None)
        field_vec = command.heading + wall_vec
        if sm is None:
            psi_d = ca.if_else(w_react, ca.atan2(field_vec[1], field_vec[0]), psi_ilos)
        else:
            e_f = field_vec / ca.sqrt(ca.sumsqr(field_vec) + 1e-12)
            e = w_react * e_f + (1 - w_react) * ca.vertcat(ca.cos(psi_ilos), ca.sin(psi_ilos))
            psi_d = ca.atan2(e[1], e[0])

    traffic_rows = ()
    if i in layout.traffic and nb is None:  # a target's behaviour (mmg_casadi.traffic.behaviour)
        n_nb = nb_pos.size2()
        psi_d, w_react, traffic_rows = traffic_gate(
            c, i, Xi, S_, psi_d=psi_d, w_react=w_react, psi_route=psi_ilos, psi_plain=psi_plain, nb_pos=nb_pos,
            nb_vel=nb_vel, active=active if M else ca.SX(1, 0), n_ships=min(N, n_nb + 1))
    elif layout.traffic:
        traffic_rows = [Xi[S_[k]] for k in traffic_behaviour.ROWS]
    r_own = _own_time(layout, vessel, Xi[S_["r"]])
    delta_c = pd_heading(psi[i], psi_d, r_own, P["kp"], P["kd"], P["delta_max"])
    n_c = n_service  # the leg's propeller speed, unless the method in charge commands another
    if commanded and layout.command_rpm:
        n_c = ca.fmin(ca.fmax(Xi[S_["command_rpm"]], Pi["rpm_min"]), Pi["rpm_max"])
    if cmd is not None and spec.commands_speed:
        rpm = ca.fmin(ca.fmax(cmd[0].rpm, Pi["rpm_min"]), Pi["rpm_max"])  # dead slow ahead .. maximum rpm
        n_c = ca.if_else(w_react, rpm, n_c) if sm is None else w_react * rpm + (1 - w_react) * n_c
    n_prop = Xi[S_["n_prop"]]
    xm = Xi[:NX]
    xm_next = rk4(mmg, xm, (delta_c, n_prop, *c["env_args"]), dt / n_sub)
    for _ in range(n_sub - 1):
        xm_next = rk4(mmg, xm_next, (delta_c, n_prop, *c["env_args"]), dt / n_sub)
    y_int_next = Xi[S_["y_int"]] + dt * y_int_rate * (1 - w_react)
    pos_next = ca.vertcat(xm_next[S_["x"]], xm_next[S_["y"]])
    idx_next, reached = switch_waypoint(pos_next, Pi["path"], Xi[S_["idx"]], Pi["n_path"], P["goal_tolerance"])
    idx_plain = idx_next
    if spec.goal_capture:
        # a waypoint before the final one that the ship passed abeam outside the acceptance radius (avoiding
        # something) counts as passed: she does not turn back to it
        abeam = ca.logic_and(Xi[S_["idx"]] < Pi["n_path"] - 1.5, beyond)
        idx_next = ca.if_else(ca.logic_and(abeam, idx_next < Xi[S_["idx"]] + 0.5), Xi[S_["idx"]] + 1, idx_next)
    if i in layout.traffic and nb is None:  # a holding traffic ship switches her waypoints as a ship of "none"
        idx_next = ca.if_else(P["traffic"][i]["hold"] > 0.5, idx_plain, idx_next)
    t_next = t + dt

    u_n, v_n, r_n, x_n, y_n = (xm_next[S_[k]] for k in ("u", "v", "r", "x", "y"))
    finite = ca.logic_and(ca.logic_and(ca.fabs(u_n) < ENVELOPE["speed"], ca.fabs(v_n) < ENVELOPE["speed"]),
                          ca.logic_and(ca.fabs(r_n) < ENVELOPE["r"],
                                       ca.fabs(x_n) + ca.fabs(y_n) < ENVELOPE["position"]))
    status_new = ca.if_else(finite, ca.if_else(reached, 1, 0), 2)
    abs_d = 0.5 * (ca.fabs(Xi[S_["delta"]]) + ca.fabs(xm_next[S_["delta"]]))

    final_goal = Pi["path"][:, -1]
    gdist = ca.norm_2(pos_next - final_goal)
    better = gdist < Xi[S_["best_goal_dist"]] - 1e-9

    psi_next = xm_next[S_["psi"]]
    memory = []
    for k in layout.memory:  # the method's memory while a neighbour is within R_safe, else the heading
        if k in COMMAND_ROWS:  # the orders of a commanded ship: written by the caller, carried unchanged
            memory.append(Xi[S_[k]])
            continue
        if k in layout.tallies:  # a count over the run: the builder's value while the method steers, else kept
            counted = cmd[0].memory.get(k) if cmd is not None else None
            memory.append(Xi[S_[k]] if counted is None else ca.if_else(w_react > 0.5, counted, Xi[S_[k]]))
            continue
        held = cmd[0].memory.get(k) if cmd is not None and cmd[1] is not None else None
        memory.append(psi_next if held is None else ca.if_else(cmd[1], held, psi_next))
    new = ca.vertcat(
        xm_next,
        engine_step(n_prop, n_c, Pi["engine_rate"], dt, Pi["engine_lag"]),
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
        *memory,
        *traffic_rows,
        *[Xi[S_[k]] for k in perception_layer.rows(layout.perception)],  # replaced by the step's perception update
    )
    return new, ca.vertcat(delta_c, psi_d, terms["y_e"], w_react)


def _lookahead(layout: Layout, P: dict, vessel: str):
    """The land look-ahead distance of a ship of ``vessel`` (L): ``land_lookahead`` advances of her hull."""
    return P["land_lookahead"] * hull_advance(vessel, layout.unit_vessel())


def _land_ahead(layout: Layout, pos, vel, psi, psi_ilos, walls, Pi: dict, P: dict, vessel: str) -> dict:
    """Land seen ahead by one ship (:func:`~mmg_casadi.guidance.land_ahead.land_seen_ahead`): her straight path
    over the look-ahead distance along her course over the ground (her heading when she hardly moves) or along
    the heading ILOS orders, against the land edges (the last ``n_land`` wall segments) with the clearance half
    her beam + ``grounding_margin`` + ``land_clearance``; the point of land met is her course's, else ILOS's."""
    speed = ca.norm_2(vel)
    course = ca.if_else(speed > 1e-6, vel / ca.fmax(speed, 1e-6), ca.vertcat(ca.cos(psi), ca.sin(psi)))
    clearance = Pi["half_beam"] + P["grounding_margin"] + P["land_clearance"]
    reach, land = _lookahead(layout, P, vessel), walls[:, layout.n_walls - layout.n_land:]
    now, p_now, ordered, p_ordered = land_ahead_function(layout.n_land)(
        pos, course, ca.vertcat(ca.cos(psi_ilos), ca.sin(psi_ilos)), reach, clearance, land)
    return {"ahead": ca.logic_or(now, ordered), "point": ca.if_else(now, p_now, p_ordered)}


def _lane(layout: Layout, terms: dict, pos, y_int, walls, P: dict, vessel: str):
    """ILOS's terms, the goal a method steers for and ILOS's integral rate along the starboard lane of a narrow
    channel (Rule 9, :func:`~mmg_casadi.guidance.fairway.lane`): in a channel the lane error replaces the route's
    cross-track error (``y_e`` itself, the MCTE's, stays the route's) and the goal is moved onto the direction ILOS
    takes to the lane, at its own distance."""
    lane = fairway.lane(pos, terms["pi_p"], walls, width=P["channel_width"], clearance=P["bank_clearance"],
                        ahead=_lookahead(layout, P, vessel),
                        first_land=layout.n_walls - layout.n_land if layout.n_land else None)
    inside = lane["in_channel"]
    e_max = P["ilos_delta"] * math.tan(math.radians(fairway.APPROACH_DEG))
    e = ca.if_else(inside, ca.fmin(ca.fmax(lane["error"], -e_max), e_max), terms["y_e"])
    psi_d = ilos_heading(terms["pi_p"], e, y_int, P["ilos_delta"], P["ilos_k"])
    rate = ilos_integrator_rate(e, y_int, P["ilos_delta"], P["ilos_k"])
    psi_lane = terms["pi_p"] - ca.atan(e / P["ilos_delta"])  # towards the lane, without the integral
    reach = ca.norm_2(terms["wp_next"] - pos)
    goal = ca.if_else(inside, pos + reach * ca.vertcat(ca.cos(psi_lane), ca.sin(psi_lane)), terms["wp_next"])
    return {**terms, "psi_d": ca.if_else(inside, psi_d, terms["psi_d"])}, goal, \
        ca.if_else(inside, rate, terms["y_int_dot"])


def _bookkeeping(layout: Layout, c: dict, x_next: list):
    """The next scenario state: closest approach and first collision, from the positions after the step, for
    every pair present at its start; a ship whose first collision or grounding happened in the step stops
    (:func:`stop_on_contact`); and the clock."""
    S_ = c["S"]
    out = []
    for i in range(layout.n_ships):
        xn = x_next[i]
        xn = ca.vertcat(xn[:S_["d_min"]], _encounter_row(layout, c, x_next, i), xn[S_["collision_with"] + 1:])
        out.append(stop_on_contact(layout, c["X"][i], xn))
    return ca.vertcat(ca.if_else(c["running"], c["t"] + c["P"]["dt"], c["t"]), *out)


STOP_ROWS = {"u": 0.0, "v": 0.0, "r": 0.0, "delta": 0.0, "n_prop": 0.0, "status": float(STOPPED), "t_goal": -1.0}
"""The rows a collision or grounding sets: the ship is held (no speed, no yaw rate), rudder amidships, engine
stopped, status :data:`~mmg_casadi.closed_loop.layout.STOPPED`, goal not reached."""


def stop_on_contact(layout: Layout, before, after):
    """One ship's rows after a step, stopped if her first collision or grounding happened in it.

    Her voyage ends where she touched: the model has no contact forces, so drifting on with the engine stopped
    would carry a grounded hull through the land and two collided hulls through each other; the ground (or the
    other hull) holds her. She stays in the scene as a static hazard the other ships must avoid (a ship aground
    or disabled by a collision is one), with the rows :data:`STOP_ROWS`; a stopped ship is not sailing, so the
    step holds her state from then on.

    Parameters
    ----------
    layout : Layout
        The closed loop's shape (names of the ship's rows).
    before, after : SX or MX
        The ship's rows (``layout.ns``) at the start of the step and after it (with its encounter rows).

    Returns
    -------
    SX or MX
        ``after``, with :data:`STOP_ROWS` where ``t_collision`` became set in the step.
    """
    col = layout.column("t_collision")
    hit = ca.logic_and(after[col] >= 0, before[col] < 0)
    rows = {layout.column(k): v for k, v in STOP_ROWS.items()}
    return ca.vertcat(*[ca.if_else(hit, rows[k], after[k]) if k in rows else after[k] for k in range(layout.ns)])


_ROW = ("d_min", "d_min_with", "t_collision", "collision_with")
"""Rows of a ship's state updated by :func:`_encounter_row` (consecutive in
:data:`~mmg_casadi.closed_loop.layout.SHIP_STATE`)."""


def _encounter_row(layout: Layout, c: dict, x_next: list, i: int):
    """Ship ``i``'s closest approach to a ship or an obstacle (and with whom) and first collision with a ship or
    any hazard (when, with whom: ships 0..N-1, then the hazards in the order of
    :data:`~mmg_casadi.guidance.hazards.KINDS`) after the step."""
    N, S = layout.n_ships, layout.n_obstacles
    P, S_, t, present, running = c["P"], c["S"], c["t"], c["present"], c["running"]
    obs = P["obstacles"]
    pos_n = [ca.vertcat(xn[S_["x"]], xn[S_["y"]]) for xn in x_next]
    xn = x_next[i]
    d_min, d_with = xn[S_["d_min"]], xn[S_["d_min_with"]]
    t_col, c_with = xn[S_["t_collision"]], xn[S_["collision_with"]]
    ell = P["ships"][i]["length"]
    sails = ca.logic_and(present[i], c["X"][i][S_["status"]] != STOPPED)  # a stopped ship's rows are final
    agents = [(j, pos_n[j], present[j], pair_collision_distance(P["collision_distance"], ell,
                                                                  P["ships"][j]["length"]))
              for j in range(N) if j != i]
    agents += [(N + k, obs[0:2, k], ca.SX(1), P["collision_distance"]) for k in range(S)]
    return meet(layout, P, pos_n[i], (d_min, d_with, t_col, c_with), sails, running, t, agents,
                P["ships"][i]["half_beam"])


def meet(layout: Layout, P: dict, pos, rows, counts, running, t, agents, half_beam):
    """A ship's closest approach (and with whom) and first collision (when, with whom) after a step.

    Parameters
    ----------
    layout : Layout
        The closed loop's shape (its walls; agent indices of walls follow ships and obstacles).
    P : dict
        The step's named parameters (``dt``, ``collision_distance``, ``walls``).
    pos : SX (2×1)
        The ship's position after the step.
    rows : tuple of SX
        Its ``d_min``, ``d_min_with``, ``t_collision``, ``collision_with`` before the step.
    counts, running : SX
        Whether the ship is present and the run still running (1/0).
    t : SX
        Time at the start of the step.
    agents : list of (index, SX (2×1), SX, SX)
        Other ships and obstacles in agent order: index, position after the step, presence at its start and the
        centre distance below which the two collide (for two ships ``collision_distance`` times their mean
        length, :func:`~mmg_casadi.vessel.library.pair_collision_distance`; for an obstacle
        ``collision_distance``).
    half_beam : SX
        Half the ship's own beam: the distance at which its side touches a wall (land: plus the step input
        ``grounding_margin``).

    Returns
    -------
    casadi.SX (4, 1)
        ``d_min`` (L), ``d_min_with`` (agent index), ``t_collision`` (L/U, -1 for none yet) and ``collision_with``
        (agent index, -1 for none) after the step.
    """
    d_min, d_with, t_col, c_with = rows
    dt = P["dt"]
    for j, pj, pres_j, reach in agents:
        dij = ca.norm_2(pos - pj)
        valid = ca.logic_and(ca.logic_and(counts, pres_j), running)
        closer = ca.logic_and(valid, dij < d_min)
        d_min = ca.if_else(closer, dij, d_min)
        d_with = ca.if_else(closer, j, d_with)
        hit = ca.logic_and(ca.logic_and(valid, dij < reach), t_col < 0)
        t_col = ca.if_else(hit, t + dt, t_col)
        c_with = ca.if_else(hit, j, c_with)
    wall = hazards.KINDS["wall"]
    first_land = layout.n_walls - layout.n_land  # land edges are the last wall segments
    for k in range(layout.n_walls):  # touching a wall: the hull's side reaches it (no closest-approach row)
        d = wall.distance(pos, P["walls"][:, k])
        clearance = half_beam + P["grounding_margin"] if k >= first_land else half_beam  # grounding on land
        hit = ca.logic_and(ca.logic_and(ca.logic_and(counts, running), d < clearance), t_col < 0)
        t_col = ca.if_else(hit, t + dt, t_col)
        c_with = ca.if_else(hit, layout.n_ships + layout.n_obstacles + k, c_with)
    return ca.vertcat(d_min, d_with, t_col, c_with)


@functools.lru_cache(maxsize=16)
def _sparse_functions(layout: Layout, n_sub: int) -> tuple[ca.Function, ca.Function]:
    """The steps of :func:`build_closed_loop_step` and :func:`build_guidance` with ``sparse=True``.

    A prelude computes every ship's position, velocity over the ground, presence and sailing flag; per ship a
    conditional (``Function.conditional``) either holds the ship or runs :func:`_ship_update`; the bookkeeping
    follows. They are generated as calls, so a branch not taken costs nothing. The guidance Function runs the
    same per-ship pieces up to the rudder command."""
    mmgs = _models(layout)
    N, NS, key = layout.n_ships, layout.ns, layout.key()
    xs, ps = ca.SX.sym("x", layout.nx), ca.SX.sym("p", layout.np)
    c = _step_context(layout, xs, ps)
    shared = ca.vertcat(*[ca.vertcat(c["pos"][i], c["vel"][i], c["present"][i]) for i in range(N)])
    counted = [ca.logic_and(ca.logic_and(c["present"][i], c["running"]), c["X"][i][c["S"]["status"]] != STOPPED)
               for i in range(N)]
    pre = ca.Function(f"pre_{key}", [xs, ps], [shared, ca.vertcat(*c["sailing"]), ca.vertcat(*counted)],
                      {"cse": True})
    sh = ca.SX.sym("shared", 5 * N)
    cs = _step_context(layout, xs, ps, shared=sh)
    nxt = ca.SX.sym("next", N * NS)
    rows_next = [nxt[i * NS:(i + 1) * NS] for i in range(N)]
    x, p = ca.MX.sym("x", layout.nx), ca.MX.sym("p", layout.np)
    sh_mx, sailing, counts = pre(x, p)
    seen_mx, sensed_mx = sh_mx, None
    if layout.perception != "off":  # the own ship's view of the others and every ship's perception rows
        seen, sensed = perceive(layout, cs)
        seen_mx, sensed_mx = ca.Function(f"sense_{key}", [xs, ps, sh], [seen, ca.vertcat(*sensed)],
                                         {"cse": True})(x, p, sh_mx)
    news, auxs, rudders = [], [], []
    for i in range(N):
        new, aux_i = _ship_update(layout, i, cs, mmgs[layout.vessel(i)], n_sub, sparse=True)
        view = seen_mx if i == 0 else sh_mx
        run = ca.Function(f"sail{i}_{key}", [xs, ps, sh], [new, aux_i], {"cse": True})
        hold = ca.Function(f"hold{i}_{key}", [xs, ps, sh], [cs["X"][i], ca.DM.nan(NAUX, 1)])
        new_mx, aux_mx = ca.Function.conditional(f"ship{i}_{key}", [hold], run)(sailing[i], x, p, view)
        news.append(new_mx)
        auxs.append(aux_mx)
        steer = ca.Function(f"steer{i}_{key}", [xs, ps, sh], [aux_i[0]], {"cse": True})
        idle = ca.Function(f"idle{i}_{key}", [xs, ps, sh], [ca.DM.nan(1, 1)])
        rudders.append(ca.Function.conditional(f"rudder{i}_{key}", [idle], steer)(sailing[i], x, p, view))
    # closest approach and collisions: a ship absent at the start of the step (or past the horizon) keeps its row
    nxt_mx = ca.vertcat(*news)
    r0, r1 = layout.column(_ROW[0]), layout.column(_ROW[-1]) + 1
    clock = ca.Function(f"clock_{key}", [xs, ps], [ca.if_else(c["running"], c["t"] + c["P"]["dt"], c["t"])])
    stop = stop_function(layout)
    rows = [clock(x, p)]
    for i in range(N):
        update = ca.Function(f"meet{i}_{key}", [xs, ps, nxt], [_encounter_row(layout, c, rows_next, i)],
                             {"cse": True})
        keep = ca.Function(f"keep{i}_{key}", [xs, ps, nxt], [rows_next[i][r0:r1]])
        row = ca.Function.conditional(f"row{i}_{key}", [keep], update)(counts[i], x, p, nxt_mx)
        k = len(perception_layer.rows(layout.perception))
        tail = [news[i][r1:NS - k], sensed_mx[i * k:(i + 1) * k]] if k else [news[i][r1:]]
        rows.append(stop(x[layout.ship_block(i)], ca.vertcat(news[i][:r0], row, *tail)))
    step = ca.Function(f"closed_loop_{key}", [x, p], [ca.vertcat(*rows), ca.horzcat(*auxs)],
                       ["x", "p"], ["x_next", "aux"])
    guidance = ca.Function(f"guidance_{key}", [x, p], [ca.horzcat(*rudders)], ["x", "p"], ["delta_c"])
    return step, guidance



def stop_function(layout: Layout) -> ca.Function:
    """:func:`stop_on_contact` as a Function of one ship's rows.

    Parameters
    ----------
    layout : Layout
        The closed loop's shape.

    Returns
    -------
    casadi.Function
        ``stop_<key>(before, after) -> after``, each ``layout.ns`` rows.
    """
    b, a = ca.SX.sym("before", layout.ns), ca.SX.sym("after", layout.ns)
    return ca.Function(f"stop_{layout.key()}", [b, a], [stop_on_contact(layout, b, a)], {"cse": True})


def _check_sparse(layout: Layout) -> None:
    if layout.smooth is not None:
        raise ParameterError("sparse", "False for a smooth layout (the smoothed step is the one differentiated)",
                             True)


def build_guidance(layout: Layout, *, sparse: bool = False) -> ca.Function:
    """Guidance-and-control part only: ``guidance_<key>(x, p) -> delta_c (1 x N)``, for timing the methods.

    With ``sparse`` (see :func:`build_closed_loop_step`) a ship that is not sailing gets NaN without any
    computation and a method sees only its neighbours within R_safe: the cost of the guidance the rollouts run.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, vessels, methods, obstacles, walls) of the scenario.
    sparse : bool, default False
        The guidance of the sparse step (exact layouts only).

    Returns
    -------
    casadi.Function
        ``guidance_<key>(x, p) -> delta_c``: the commanded rudder angle of every ship (1 x N, rad).
    """
    if sparse:
        _check_sparse(layout)
        return _sparse_functions(layout, 1)[1]
    step = build_closed_loop_step(layout)
    x = ca.SX.sym("x", layout.nx)
    p = ca.SX.sym("p", layout.np)
    _, aux = step(x, p)
    return ca.Function(f"guidance_{layout.key()}", [x, p], [aux[0, :]], ["x", "p"], ["delta_c"], {"cse": True})


forget_on_unregister(_sparse_functions.cache_clear)
