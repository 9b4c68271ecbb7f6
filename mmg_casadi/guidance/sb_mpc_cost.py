"""The hazard of each control behaviour of ``sb-mpc`` and the choice of the least (CasADi, branch-free).

Johansen, Perez & Cristofaro (2016, IEEE T-ITS 17(12)) score a behaviour k (a course offset and a propulsion
level P, held over the horizon) by its predicted hazard (their eq. 9, with the transitional term of Hagen et al.
2018 and the grounding term of Tengesdal et al. 2022)::

    H_k = Σ_i ( max_t [ C_i R_i(t) + κ μ_i(t) + κ_TC τ_i(t) ] + K_mean mean_t C_i R_i(t) )   (ships, obstacles i)
          + κ_SO SO_k + κ_RA RA_k + κ_port PT_k + G_k + f(P, χ_ca) + g(P, χ_ca)

* **collision risk × cost** (Johansen eqs. 6–7): R_i(t) = (d_safe / d_i(t))^q / t^p while the predicted range
  d_i(t) < d_safe, else 0, discounted in time by 1/t^p; C_i = K_coll max(‖v_0(t) − v_i‖², Δv_min²) (the own
  ship's predicted velocity, the neighbour's constant one; ours: the relative speed floored at Δv_min, since two
  ships on parallel courses at equal speed otherwise meet at no cost and a small turn of either collides).
  q = 4 (:data:`Q`), the value of the group's implementations;
* **COLREG violation** μ_i(t) ∈ {0, 1} (Johansen eq. 8): the neighbour is close (d < d_close) on the own ship's
  starboard side while head-on, or crossing and not overtaking the own ship (a give-way or head-on ship that
  did not pass it to port); the situation tests use the angles φ_AH, φ_OT, φ_HO, φ_CR and the predicted
  velocities, as the group's SB-MPC (``mpc_cost_cpu.hpp``, ``determine_COLREGS_violation``), except "passed",
  here the range opening beyond d_safe (the group tests bearings abaft the beam of either ship); μ and τ are
  evaluated at every second sample;
* **transitional cost** τ_i(t) (Hagen, Kufoalor, Brekke & Johansen 2018, ICRA): a behaviour that makes an
  overtaking, an overtaken ship, a crossing (for a port offset) or a head-on ship change the side it is on at the
  decision (``determine_transitional_cost_indicator`` of the group's SB-MPC);
* **stand-on** (Rule 17(a)(i); the group's PSB-MPC penalises a stand-on ship's predicted change of course or
  speed, ``colregs_violation_evaluator.hpp``, ``evaluate_SO_violation``): while the own ship has a stand-on duty
  (below; a ship crossing from port or overtaking her) and the give-way ship can still act (range above r_free,
  or passing beyond d_safe, or TCPA above t_free), SO_k = 1 for a behaviour that alters course by more than
  ``dpsi_keep`` or changes the propulsion level; ours: that neighbour's safety distance is then d_standon, a near
  miss, instead of d_safe (the stand-on ship expects the give-way ship to keep clear, Rule 16, and acts alone
  only for a passing that close, Rule 17(b));
* **give-way side** (Rules 14, 15; the PSB-MPC's ``evaluate_GW_violation``): κ_GW when a ship crossing from
  starboard or meeting head-on, with a duty (below), is on the own starboard side at the behaviour's predicted
  closest approach within d_close (the own ship crossed ahead of her, or did not pass her port to port);
* **readily apparent** (Rules 8(b), 16; the PSB-MPC's ``kappa_RA``): RA_k = 1 for a course less than
  ``dpsi_apparent`` from the heading at the onset of the give-way duties (memory ``sb_base``) while the own ship
  has a give-way, head-on or overtaking duty: an alteration, once needed, is substantial and kept until the ship
  is past. A **duty**: an encounter opens when a ship closes with a straight-line passing inside d_close and a
  TCPA below t_duty, with the role judged then from the bearings (as colregs-vortex's ``classify_role``) and
  kept in a memory slot while she closes; it becomes a duty once that passing is inside d_safe;
* **no port alteration** (Rules 14(a), 15, 17(c); ours, after the PSB-MPC's give-way violation, a port turn of
  a give-way ship): PT_k = 1 for an alteration to port beyond ``dpsi_keep`` while the own ship meets a ship
  head-on, gives way to one crossing from starboard, or is free to act for one crossing from port;
* **grounding** (Tengesdal, Johansen, Grande & Blindheim 2022, IEEE Access 10; the group's ``psbmpc``
  ``calculate_grounding_cost`` without wind): G_k = max_t G_1 exp(−G_3 max(d_land(t) − d_land_safe, 0) − G_4 t)
  with d_land(t) the predicted distance to the nearest wall or land edge, every second sample;
* **control deviation and transition** (Johansen eqs. 10–11): f = K_P (1 − P) + K_χ χ_ca², K_χ larger to port;
  g = K_ΔP abs(P − P_last) + K_Δχ (χ_ca − χ_ca,last)², K_Δχ larger to port (prefer starboard, penalise switching).

Johansen et al. take the maximum over the neighbours; ours is the sum (and, for each neighbour, the mean over
time added to the maximum, ``K_mean``): with maxima alone a behaviour-independent term of one neighbour (a risk
already inside d_safe at the first sample, a transitional cost every behaviour incurs) masks what the behaviours
change for the others, and the choice falls to the deviation costs (measured in environment 5: ships steered
onto static obstacles and along other ships).

**Behaviours** (:func:`behaviours`): the paper's 13 course offsets from −90° to +90° at each of its propulsion
levels full, half and stop, plus the course to the waypoint at full propulsion and the course and level held since
the last decision (41). Ours: the offsets are taken from the present heading, not from the course to the waypoint:
the ships of the Monte Carlo start on random headings, and offsets about a waypoint course far from the heading
leave no starboard alteration of the present course; the deviation cost f still measures χ_ca from the course to
the waypoint, and g the change of the course ordered. "Held" lets an alteration under way complete (a behaviour
from the heading mid-turn would stop it short).

The behaviour of least hazard wins (strict <, the first in :func:`behaviours` order wins a tie). Everything is one
CasADi Function per (neighbour count, samples, walls) (:func:`plan_function`): the own ship's predicted track of a
behaviour and its hazard are Functions ``map``-ped over the behaviours and the neighbours, so the generated code
does not grow with either.

Examples
--------
>>> b = behaviours()
>>> len(b["offset"]), float(b["waypoint"][-2]), float(b["held"][-1]), round(math.degrees(float(b["offset"][0])))
(41, 1.0, 1.0, -90)
"""

from __future__ import annotations

import functools
import math

import casadi as ca
import numpy as np

from mmg_casadi.guidance.sb_mpc_model import predict_function

OFFSETS_DEG = (-90.0, -75.0, -60.0, -45.0, -30.0, -15.0, 0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0)
"""Course offsets of the behaviours (degrees, positive to starboard): Johansen et al. 2016 §IV. Ours: from the
present heading, not from the course to the waypoint (module notes)."""

LEVELS = (1.0, 0.5, 0.0)
"""Propulsion levels P of the behaviours, fractions of the service propeller speed: full, half and stop (Johansen et
al. 2016 §IV, without full astern, which the engine model cannot give); the engine keeps at least dead slow ahead
(``engine_dead_slow``), so "stop" is dead slow ahead."""

Q = 4
"""Exponent q of the collision risk (d_safe / d)^q: 4, as in the group's implementations (q ≥ 1 in the paper); a
constant, so the compiled cost has no ``pow``."""

BIG = 1.0e12
"""Initial value of the least-hazard fold."""

NB_ROWS = ("lx", "ly", "vx", "vy", "speed", "active", "s0", "si0", "o0", "q0", "h0", "x0", "d_safe", "gw")
"""Rows of a neighbour's column in the hazard Function: line of sight from the own ship (L), velocity (U) and speed,
the mask, the transitional indicators at the decision, its safety distance (d_safe for a ship, d_standon for a
ship the own ship stands on for, d_obstacle for a static obstacle) and the give-way side duty (1 for a ship crossing
from starboard or meeting head-on) (Hagen et al. 2018: the neighbour on
the own starboard side, the own ship on its starboard side, the own ship overtaking it, it overtaking the own ship,
head-on, crossing)."""

PAIR_PARAMS = ("d_safe", "d_close", "k_coll", "kappa", "kappa_tc", "cos_ah", "cos_ot", "cos_ho", "cos_cr", "v_min",
               "dv_min", "k_mean", "kappa_gw")
"""Numbers of the pair hazard, in this order."""


def behaviours() -> dict:
    """The control behaviours: every offset of :data:`OFFSETS_DEG` from the present heading at every level of
    :data:`LEVELS` (level-major), then the course to the waypoint at full propulsion, then the course and level held
    since the last decision.

    Returns
    -------
    dict
        ``offset`` (rad from the present heading; 0 for the last two), ``level`` (index in :data:`LEVELS`; -1 for
        "held"), ``waypoint`` (1 for "the course to the waypoint") and ``held`` (1 for "the course and level held")
        as numpy arrays.
    """
    off = np.radians(np.array(OFFSETS_DEG))
    n = len(off) * len(LEVELS)
    offset = np.concatenate([off for _ in LEVELS] + [[0.0, 0.0]])
    level = np.concatenate([np.full(len(off), k, float) for k in range(len(LEVELS))] + [[0.0, -1.0]])
    waypoint = np.concatenate([np.zeros(n), [1.0, 0.0]])
    held = np.concatenate([np.zeros(n), [0.0, 1.0]])
    return {"offset": offset, "level": level, "waypoint": waypoint, "held": held}


N_BEHAVIOURS = len(OFFSETS_DEG) * len(LEVELS) + 2
"""Behaviours per decision (:func:`behaviours`)."""


def _pair_expr(own, chi_m, nb, t, w, par, ship: bool):
    """Max over the samples of one neighbour's hazard (:func:`pair_function`); ``ship=False``: the collision term
    alone (a static obstacle, for which μ and τ vanish). The COLREG and transitional indicators are evaluated at
    every second sample (a situation lasts several samples), the collision risk at every one."""
    samples = own.size2()
    _, d_close, k_coll, kappa, kappa_tc, cos_ah, cos_ot, cos_ho, cos_cr, v_min, dv_min, k_mean, kappa_gw = \
        (par[i] for i in range(len(PAIR_PARAMS)))
    lx0, ly0, vix, viy, ni, _, s0, si0, o0, q0, h0, x0, d_safe, gw = (nb[i] for i in range(len(NB_ROWS)))
    ds2, dc2 = d_safe * d_safe, d_close * d_close
    cah2 = cos_ah * cos_ah
    worst, total = ca.SX(0), ca.SX(0)
    near2, side = ca.SX(1e18), ca.SX(0)  # the closest predicted approach and the neighbour's side there
    for k in range(samples):
        x, y, vx, vy, u = own[0, k], own[1, k], own[2, k], own[3, k], own[4, k]
        lx, ly = lx0 + vix * t[k] - x, ly0 + viy * t[k] - y  # line of sight at the sample
        d2 = lx * lx + ly * ly
        dvx, dvy = vx - vix, vy - viy
        ratio = ds2 / ca.fmax(d2, 1e-6)
        risk = ca.if_else(d2 < ds2, ratio * ratio * w[k], 0)  # Johansen eq. 6, q = 4
        cost = k_coll * ca.fmax(dvx * dvx + dvy * dvy, dv_min * dv_min) * risk  # eq. 7, relative speed floored
        total = total + cost
        if ship:
            starboard = (vx * ly - vy * lx) > 0  # the neighbour on the own starboard side
            closer = d2 < near2
            near2 = ca.fmin(near2, d2)
            side = ca.if_else(closer, starboard, side)
        if ship and k % 2 == 1:
            n0ni = u * ni
            dot = vx * vix + vy * viy
            v_los = vx * lx + vy * ly
            moving = u > v_min  # the neighbour moves (the kind of the pair)
            # angles by their cosines, without square roots: v·l > c |v| d ⟺ (v·l > 0, v·l² > c² |v|² d²) for c > 0
            ahead = (v_los > 0) * (v_los * v_los > cah2 * u * u * d2)
            head_on = moving * (dot < -cos_ho * n0ni) * ahead
            overtaken = (dot > cos_ot * n0ni) * (u < ni) * moving  # the neighbour overtakes the own ship
            passed = ((lx * dvx + ly * dvy) < 0) * (d2 > ds2)  # past: the range opens beyond d_safe
            crossing = moving * (dot < cos_cr * n0ni) * (1 - head_on) * (1 - passed)
            mu = (d2 < dc2) * starboard * ((head_on + crossing * (1 - overtaken)) > 0)  # eq. 8
            own_starboard = (viy * lx - vix * ly) > 0  # the own ship on the neighbour's starboard side
            tc_x = x0 * s0 * starboard * (chi_m < 0)
            tau = (o0 * (starboard != s0) + q0 * (own_starboard != si0) + tc_x
                   + h0 * (1 - s0) * starboard * (1 - tc_x)) > 0  # Hagen et al. 2018
            cost = cost + kappa * mu + kappa_tc * tau
        worst = ca.fmax(worst, cost)
    out = worst + k_mean * total / samples
    if ship:  # give-way side (the psbmpc's GW violation): the neighbour on the own starboard side at the CPA
        out = out + kappa_gw * gw * side * (near2 < dc2)
    return out


@functools.lru_cache(maxsize=None)
def pair_function(samples: int) -> ca.Function:
    """Hazard of one behaviour against one neighbour, max over the samples (module notes):
    ``sbmpc_pair_n<samples>(own, chi_m, nb, t, w, par) -> h``.

    ``own`` (5 × samples): predicted own position relative to the decision point (L), velocity and speed (U) at
    each sample; ``chi_m`` the behaviour's course offset (rad); ``nb`` a neighbour's column (:data:`NB_ROWS`);
    ``t`` and ``w`` (1 × samples) the sample times and their discount 1/t^p; ``par`` the numbers of
    :data:`PAIR_PARAMS`. An inactive neighbour (``active`` 0) gives 0 without evaluating anything, a static one
    (speed ``v_min`` or less) only its collision term (a conditional on the neighbour's kind).

    Parameters
    ----------
    samples : int
        Prediction samples.

    Returns
    -------
    casadi.Function
        The pair hazard (MX calling SX branches).
    """
    sx = [ca.SX.sym("own", 5, samples), ca.SX.sym("chi_m"), ca.SX.sym("nb", len(NB_ROWS)),
          ca.SX.sym("t", 1, samples), ca.SX.sym("w", 1, samples), ca.SX.sym("par", len(PAIR_PARAMS))]
    names = ["own", "chi_m", "nb", "t", "w", "par"]
    zero = ca.Function(f"sbmpc_pair_off_n{samples}", sx, [ca.SX(0)])
    static = ca.Function(f"sbmpc_pair_static_n{samples}", sx, [_pair_expr(*sx, ship=False)], {"cse": True})
    ship = ca.Function(f"sbmpc_pair_ship_n{samples}", sx, [_pair_expr(*sx, ship=True)], {"cse": True})
    cond = ca.Function.conditional(f"sbmpc_pair_kind_n{samples}", [zero, static], ship)
    mx = [ca.MX.sym(n, v.sparsity()) for n, v in zip(names, sx)]
    nb, v_min = mx[2], mx[5][9]
    kind = (nb[5] > 0.5) * (1 + (nb[4] > v_min))  # 0 inactive, 1 static, 2 a ship
    return ca.Function(f"sbmpc_pair_n{samples}", mx, [cond(kind, *mx)], names, ["h"])


@functools.lru_cache(maxsize=None)
def grounding_function(samples: int, n_walls: int) -> ca.Function:
    """Grounding hazard of one behaviour (Tengesdal et al. 2022 without wind; module notes):
    ``sbmpc_ground_n<samples>_w<walls>(own, walls, t, par) -> g`` with ``own`` (2 × samples) the predicted
    positions (absolute, L), ``walls`` (4 × W) the segments, ``t`` the sample times and ``par`` = [G_1, G_3, G_4,
    d_land_safe]; every second sample is tested.

    Parameters
    ----------
    samples : int
        Prediction samples.
    n_walls : int
        Wall and land segments.

    Returns
    -------
    casadi.Function
        The grounding hazard (SX).
    """
    own, walls = ca.SX.sym("own", 2, samples), ca.SX.sym("walls", 4, n_walls)
    t, par = ca.SX.sym("t", 1, samples), ca.SX.sym("par", 4)
    g1, g3, g4, d_land = par[0], par[1], par[2], par[3]
    worst = ca.SX(0)
    for k in range(1, samples, 2):
        px, py = own[0, k], own[1, k]
        near2 = ca.SX(1e18)
        for j in range(n_walls):
            ax, ay, bx, by = walls[0, j], walls[1, j], walls[2, j], walls[3, j]
            ex, ey = bx - ax, by - ay
            s = ca.fmin(ca.fmax(((px - ax) * ex + (py - ay) * ey) / ca.fmax(ex * ex + ey * ey, 1e-12), 0), 1)
            gx, gy = px - ax - s * ex, py - ay - s * ey
            near2 = ca.fmin(near2, gx * gx + gy * gy)
        gap = ca.fmax(ca.sqrt(near2) - d_land, 0)
        worst = ca.fmax(worst, g1 * ca.exp(-g3 * gap - g4 * t[k]))
    return ca.Function(f"sbmpc_ground_n{samples}_w{n_walls}", [own, walls, t, par], [worst],
                       ["own", "walls", "t", "par"], ["g"], {"cse": True})


def _wrap(a):
    """``a`` wrapped to (−π, π]."""
    return ca.atan2(ca.sin(a), ca.cos(a))


N_FULL = len(OFFSETS_DEG)
"""The behaviours at full propulsion come first (:func:`behaviours`)."""

PARTS = {"all": tuple(range(N_BEHAVIOURS)),
         "full": tuple(range(N_FULL)) + (N_BEHAVIOURS - 2, N_BEHAVIOURS - 1),
         "reduced": tuple(range(N_FULL, N_BEHAVIOURS - 2))}
"""Behaviours by part: all, those at full propulsion with "waypoint" and "held", those at a reduced level."""


def _choice_terms(idx, own, costs):
    """Course, level, alteration, χ_ca and the hazard terms that need no prediction (deviation, stand-on, readily
    apparent, port) of the behaviours ``idx`` (module notes); MX rows."""
    n = len(idx)
    b = {k: v[list(idx)] for k, v in behaviours().items()}
    psi, chi_wp, level_now, course_held = own[2], own[4], own[5], own[6]
    offsets, to_wp, held = ca.DM(b["offset"]).T, ca.DM(b["waypoint"]).T, ca.DM(b["held"]).T
    level_b = ca.if_else(held > 0.5, ca.repmat(level_now, 1, n), ca.DM(b["level"]).T)
    course_b = ca.if_else(to_wp > 0.5, ca.repmat(chi_wp, 1, n),
                          ca.if_else(held > 0.5, ca.repmat(course_held, 1, n), psi + offsets))
    turn = _wrap(course_b - psi)  # the alteration from the present heading
    chi_ca = _wrap(course_b - chi_wp)  # the offset from the course to the waypoint (Johansen's χ_ca)
    so_w, ra_w, k_p, k_chi_s, k_chi_p, k_dp, k_dchi_s, k_dchi_p, so_any, ra_any, dpsi_keep, dpsi_app, port_w, \
        port_any, base = (costs[i] for i in range(15))
    so = so_any * ((ca.fabs(turn) > dpsi_keep) + (ca.fabs(level_b - level_now) > 0.5) > 0)
    ra = ra_any * (ca.fabs(_wrap(course_b - base)) < dpsi_app - 1e-9)
    p_b = (level_b < 0.5) * LEVELS[0] + (level_b > 0.5) * (level_b < 1.5) * LEVELS[1] + (level_b > 1.5) * LEVELS[2]
    p_last = ca.if_else(level_now < 0.5, LEVELS[0], ca.if_else(level_now < 1.5, LEVELS[1], LEVELS[2]))
    k_chi = ca.if_else(chi_ca > 0, ca.repmat(k_chi_s, 1, n), ca.repmat(k_chi_p, 1, n))
    d_chi = _wrap(course_b - course_held)  # the change of the course ordered
    k_dchi = ca.if_else(d_chi > 0, ca.repmat(k_dchi_s, 1, n), ca.repmat(k_dchi_p, 1, n))
    deviation = k_p * (1 - p_b) + k_chi * chi_ca ** 2 + k_dp * ca.fabs(p_b - p_last) + k_dchi * d_chi ** 2
    port = port_any * (turn < -dpsi_keep)
    return course_b, level_b, turn, chi_ca, so_w * so + ra_w * ra + port_w * port + deviation


@functools.lru_cache(maxsize=None)
def hazard_function(m: int, samples: int, substeps: int, n_walls: int = 0, part: str = "all") -> ca.Function:
    """The hazard of every behaviour (of one part, :data:`PARTS`) and its predicted track (module notes), for ``m``
    neighbours.

    ``sbmpc_hazard_<part>_m<m>_n<samples>_s<substeps>_w<walls>(own, nb, model, gains, costs, pair, ground, walls)
    -> (hazard, x, y, collision, course, level, offset)``:

    * ``own`` = [x, y, ψ, u, χ_wp, level_now, course_held, horizon, speed_0, speed_1, speed_2, p]: the own position
      (L), heading (rad), speed (U), the course to the waypoint (rad), the present level (index of :data:`LEVELS`)
      and course ordered (rad), the horizon (L/U), the steady speed of each level (U) and the time exponent p;
    * ``nb`` (:data:`NB_ROWS` × m), ``model`` = [K', T', T_u, a, λ, μ], ``gains`` = [K_p, K_d, δ_max];
    * ``costs`` = [κ_SO, κ_RA, K_P, K_χ,strb, K_χ,port, K_ΔP, K_Δχ,strb, K_Δχ,port, so_any, ra_any, dpsi_keep,
      dpsi_apparent, κ_port, port_any, base]; ``so_any``, ``ra_any`` and ``port_any`` say whether a stand-on hold,
      a give-way duty or a duty that forbids a port alteration is active, ``base`` is the heading at the onset of
      the give-way duties (rad);
    * ``pair`` (:data:`PAIR_PARAMS`), ``ground`` = [G_1, G_3, G_4, d_land_safe] and ``walls`` (4 × W; only with
      walls).

    Outputs: per behaviour (1 × B) its hazard, and (samples × B) its predicted positions (absolute, L);
    ``collision`` (1 × B) the neighbours' part alone; its course (rad), level (index) and offset χ_ca from the
    course to the waypoint (rad).

    Parameters
    ----------
    m : int
        Neighbours.
    samples, substeps : int
        Prediction samples and Euler steps per sample.
    n_walls : int, default 0
        Wall and land segments.
    part : {"all", "full", "reduced"}, default "all"
        The behaviours evaluated (:data:`PARTS`).

    Returns
    -------
    casadi.Function
        The hazards (MX, never inlined).
    """
    idx = PARTS[part]
    nbh = len(idx)
    own, nb = ca.MX.sym("own", 12), ca.MX.sym("nb", len(NB_ROWS), m)
    model, gains, costs = ca.MX.sym("model", 6), ca.MX.sym("gains", 3), ca.MX.sym("costs", 15)
    pair, ground = ca.MX.sym("pair", len(PAIR_PARAMS)), ca.MX.sym("ground", 4)
    walls = ca.MX.sym("walls", 4, n_walls)
    px, py, psi, u, horizon = own[0], own[1], own[2], own[3], own[7]
    level_speed = own[8:11]
    p_exp = own[11]
    course_b, level_b, turn, chi_ca, cheap = _choice_terms(idx, own, costs)
    speed_b = (level_b < 0.5) * level_speed[0] + (level_b > 0.5) * (level_b < 1.5) * level_speed[1] \
        + (level_b > 1.5) * level_speed[2]
    h = horizon / (samples * substeps)
    dt_s = horizon / samples
    t = dt_s * ca.DM(np.arange(1, samples + 1)).T
    w = ca.exp(-p_exp * ca.log(t))  # 1 / t^p, once per decision
    pred = predict_function(samples, substeps).map(nbh)
    xs, ys, vxs, vys, _, us = pred(ca.vertcat(psi, 0, u), ca.vertcat(course_b, speed_b, ca.repmat(h, 1, nbh)),
                                   model, gains)
    own_tracks = ca.vertcat(xs, ys, vxs, vys, us)  # 5 × (samples nbh)
    if m:
        o_sym, c_sym = ca.MX.sym("o", 5, samples), ca.MX.sym("c")
        t_sym, w_sym, nb_sym, par_sym = ca.MX.sym("t", 1, samples), ca.MX.sym("w", 1, samples), \
            ca.MX.sym("nb", len(NB_ROWS), m), ca.MX.sym("par", len(PAIR_PARAMS))
        worst = ca.sum2(pair_function(samples).map(m)(o_sym, c_sym, nb_sym, t_sym, w_sym, par_sym))
        per_b = ca.Function(f"sbmpc_behaviour_m{m}_n{samples}", [o_sym, c_sym, nb_sym, t_sym, w_sym, par_sym],
                            [worst])
        collision = per_b.map(nbh)(own_tracks, turn, nb, t, w, pair)
    else:
        collision = ca.MX.zeros(1, nbh)
    hazard = collision + cheap
    abs_x, abs_y = px + ca.reshape(xs, samples, nbh), py + ca.reshape(ys, samples, nbh)
    ins = [own, nb, model, gains, costs, pair, ground]
    if n_walls:
        per_g = grounding_function(samples, n_walls).map(nbh)
        hazard = hazard + per_g(ca.vertcat(px + xs, py + ys), walls, t, ground)
        ins.append(walls)
    name = f"sbmpc_hazard_{part}_m{m}_n{samples}_s{substeps}_w{n_walls}"
    return ca.Function(name, ins, [hazard, abs_x, abs_y, collision, course_b, level_b, chi_ca],
                       ["own", "nb", "model", "gains", "costs", "pair", "ground"] + (["walls"] if n_walls else []),
                       ["hazard", "x", "y", "collision", "course", "level", "offset"], {"never_inline": True})


@functools.lru_cache(maxsize=None)
def plan_function(m: int, samples: int, substeps: int, n_walls: int = 0) -> ca.Function:
    """The decision: ``(due, held, own, nb, model, gains, costs, pair, ground[, walls]) -> [course, level,
    offset]``, the behaviour of least hazard (:func:`hazard_function`) when ``due`` is 1, else ``held`` = [course,
    level, offset] unchanged; a conditional (``Function.conditional``), so nothing is evaluated between decisions.

    The behaviours at full propulsion (with "waypoint" and "held") are evaluated first; those at a reduced level
    only when one of them could still win: when the least hazard found is not below the least of their hazard
    terms that need no prediction (deviation, stand-on, readily apparent, port; their other terms are ≥ 0). The
    choice is the one over every behaviour, bit for bit (a test checks it), at about 15/41 of the cost when a
    full-speed behaviour is free of collision risk.

    Parameters
    ----------
    m : int
        Neighbours.
    samples, substeps : int
        Prediction samples and Euler steps per sample.
    n_walls : int, default 0
        Wall and land segments.

    Returns
    -------
    casadi.Function
        The decision (never inlined).
    """
    full = hazard_function(m, samples, substeps, n_walls, "full")
    reduced = hazard_function(m, samples, substeps, n_walls, "reduced")
    ins = [ca.MX.sym(full.name_in(i), full.sparsity_in(i)) for i in range(full.n_in())]
    own, costs = ins[0], ins[4]
    held = ca.MX.sym("held", 3)
    tag = f"m{m}_n{samples}_s{substeps}_w{n_walls}"
    h_full = full(*ins)[0]
    course, level, _, offset, _ = _choice_terms(PARTS["all"], own, costs)
    bound = _choice_terms(PARTS["reduced"], own, costs)[4]
    skip = ca.Function(f"sbmpc_skip_{tag}", ins, [ca.DM.ones(1, len(PARTS["reduced"])) * BIG])
    eval_reduced = ca.Function(f"sbmpc_reduced_{tag}", ins, [reduced(*ins)[0]])
    h_reduced = ca.Function.conditional(f"sbmpc_maybe_{tag}", [skip], eval_reduced)(
        ca.mmin(h_full) >= ca.mmin(bound), *ins)
    hazard = [None] * N_BEHAVIOURS
    for j, k in enumerate(PARTS["full"]):
        hazard[k] = h_full[j]
    for j, k in enumerate(PARTS["reduced"]):
        hazard[k] = h_reduced[j]
    best = ca.vertcat(BIG, held[0], held[1], held[2])
    for k in range(N_BEHAVIOURS):  # least hazard, the first on a tie
        better = hazard[k] < best[0]
        best = ca.if_else(better, ca.vertcat(hazard[k], course[k], level[k], offset[k]), best)
    choose = ca.Function(f"sbmpc_choose_{tag}", [held] + ins, [best[1:]])
    keep = ca.Function(f"sbmpc_keep_{tag}", [held] + ins, [held])
    cond = ca.Function.conditional(f"sbmpc_switch_{tag}", [keep], choose)
    xs = [ca.MX.sym("due")] + [ca.MX.sym(f"a{i}", *cond.size_in(i + 1)) for i in range(cond.n_in() - 1)]
    return ca.Function(f"sbmpc_plan_{tag}", xs, [cond(*xs)], {"never_inline": True})
