"""``nmpc``: a nonlinear model-predictive planner with COLREG constraints, solved inside the compiled closed loop.

At every guidance step a ship under ``nmpc`` solves the optimal control problem of
:mod:`mmg_casadi.guidance.nmpc_ocp`: over 20 intervals of ``nmpc_step`` (L/U) it chooses her rudder and propeller
commands so that her predicted track (the prediction model of :mod:`mmg_casadi.guidance.nmpc_model`, identified
from her MMG model) follows the line of sight to her waypoint while keeping soft separation constraints to the
ships around her (predicted at constant velocity), to static obstacles and to land, and the COLREG constraints of
the roles her own encounter logic gives (below). The solve (``sqpmethod`` with ``qrqp``, warm-started from the
previous plan) is a call inside the closed-loop step, so CasADi generates its C code with the rest of the step and
a Monte Carlo rolls it out with ``map``/``mapaccum`` like every other method.

**Encounters** (the planner's own logic and thresholds; the role rules are
:func:`mmg_casadi.guidance.colregs_encounters.classify_role`, with the planner's head-on sector
``nmpc_head_on_deg``): a ship within R_safe + ``nmpc_r_look`` whose straight-line passing distance is below
``nmpc_d_risk`` within ``nmpc_t_risk`` is a risk of collision; her role is judged at that onset and kept in a
memory slot until she leaves the planner's view (:data:`SLOTS` slots, matched by position like colregs-vortex's).

* give-way (crossing from starboard, Rule 15) and head-on (Rule 14): the heading stays ``nmpc_alter_deg`` or more
  to starboard of the heading at the onset (Rules 8(b), 16: readily apparent, to starboard), while the other ship
  is still closing;
* overtaking (Rule 13): separation only, on either side;
* stand-on (Rule 17(a)(i)) and overtaken: course and speed held, and only the near tier of separation within
  ``nmpc_t_must`` counts, until the give-way ship's inaction is apparent: she is within ``nmpc_r_act``, still on a
  passing below ``nmpc_d_risk``, and has not altered her course by ``nmpc_seen_deg`` since the onset. From then
  on (latched) the stand-on ship acts (Rule 17(a)(ii)) with the full separation, and a crossing stand-on ship does
  not turn to port of her course (Rule 17(c)).

**Execution.** The first rudder command ``δ_c`` is handed to the closed loop's PD heading controller as the
heading ``ψ + (δ_c + K_d r)/K_p``, which makes the controller order exactly ``δ_c`` (a vector of length 10⁶,
so the channel walls' field that the closed loop adds does not move it: the planner keeps its own clearance from
land), and the first propeller command as the rpm ordered.

**Fallback.** A solve fails when its result is not finite or it neither converged (projected gradient above
``nmpc_kkt_fail``) nor improved on its starting plan; the ship then takes the previous plan's command for the
present time, or, without a previous plan, a hard starboard turn (δ_max) at ``nmpc_nu_min`` of her service
propeller speed. The tallies ``nmpc_solves`` and ``nmpc_fallbacks`` (state rows, :attr:`Method.tallies`) count the
solves and the fallbacks of each ship over a run.
"""

from __future__ import annotations

import math

import casadi as ca

from mmg_casadi.errors import ParameterError
from mmg_casadi.guidance.colregs_encounters import (ACTING, CODE, GIVE_WAY, HEAD_ON, OVERTAKEN, OVERTAKING, STAND_ON,
                                                    classify_role, open_encounters, recall)
from mmg_casadi.guidance.contract import Command, GuidanceInputs, Method
from mmg_casadi.guidance.ilos import wrap_angle
from mmg_casadi.guidance.nmpc_model import reduced_model
from mmg_casadi.guidance.nmpc_ocp import SHIP_FIELDS, WEIGHTS, OcpShape, param_layout, solver_function
from mmg_casadi.params import Param
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import scene_scales

HORIZON = 20
"""Intervals of the planning horizon (its length is ``HORIZON * nmpc_step``)."""
BLOCKS = 4
"""Propeller commands over the horizon (each held over ``HORIZON / BLOCKS`` intervals)."""
SLOTS = 4
"""Encounter slots of the planner's memory."""
LIVE = CODE
"""Value of the memory row ``nmpc_live`` while the planner has a plan (any other value, a heading, means none)."""
VECTOR_LENGTH = 1.0e6
"""Length of the heading vector handed to the closed loop (module notes, Execution)."""
BIG = 1.0e6
"""A score that no neighbour reaches (selection of the nearest)."""

PLAN = tuple(f"nmpc_plan{k}" for k in range(HORIZON + BLOCKS))
"""Memory rows of the last plan: the rudder commands (rad), then the propeller commands (n/n_design)."""
SLOT_ROWS = tuple(f"nmpc_slot{k}_{c}" for k in range(SLOTS) for c in ("x", "y", "code", "chi", "age"))
"""Memory rows of the encounter slots: the ship's position at the last step, ``CODE + role (+ ACTING)``, her
course at the onset and the time since the onset (L/U)."""
TALLIES = ("nmpc_solves", "nmpc_fallbacks")
"""Counts over a run: solves, and solves that failed (the fallback was taken)."""
MEMORY = ("nmpc_live", "nmpc_engaged", "nmpc_base", "nmpc_course") + PLAN + SLOT_ROWS + TALLIES
"""Every memory row of the planner."""


def _p(name, default, low, high, unit, meaning, source, **kw):
    return Param(name, default, low, high, unit, meaning, source, **kw)


_OURS = "ours: "
PARAMS = (
    _p("nmpc_step", 1.0, 0.25, 2.0, "L/U", "interval of the planning grid; the horizon is 20 intervals",
       _OURS + "20 L/U ahead (6 min for the KCS) covers a crossing from first sight at the planner's view range to "
               "the passing, and 1 L/U resolves a turn (a 35° rudder turns the KCS 35° in about 2 L/U)"),
    _p("nmpc_r_look", 30.0, 0.0, None, "L", "how far beyond R_safe the planner sees other ships and obstacles",
       _OURS + "45 L with R_safe = 15 L: a ship closing at twice the own speed within the planner's risk horizon "
               "nmpc_t_risk (22.5 L/U = 45 L) is seen, so a stand-on ship knows her role before she turns for "
               "anything else"),
    _p("nmpc_d_pass", 10.0, 0.0, None, "L", "passing distance the planner keeps from other ships (soft)",
       _OURS + "1 nautical mile, where close quarters begins for ships in sight (Cockcroft & Lameijer p. 52, "
               "8.05 L of a 230 m ship; the published scoring profile reads the same source), plus 2 L for the "
               "constant-velocity prediction of the targets"),
    _p("nmpc_d_close", 4.0, 0.0, None, "L", "near passing distance, kept with the heavy weight nmpc_w_close",
       _OURS + "twice the collision distance of 2 L: a near miss"),
    _p("nmpc_d_risk", 10.0, 0.0, None, "L", "straight-line passing distance below which a ship is a risk of "
       "collision (Rule 7) for the planner", _OURS + "its own passing distance nmpc_d_pass"),
    _p("nmpc_d_watch", 14.0, 0.0, None, "L", "straight-line passing distance below which a ship to which the own "
       "ship would be the stand-on ship opens an encounter", _OURS + "wider than nmpc_d_risk: a turn that sweeps the "
       "passing of such a ship downwards is stopped at 14 L, before the passing becomes a risk of collision, "
       "rather than met by a stand-on duty while the ship is still turning"),
    _p("nmpc_t_risk", 25.0, 0.0, None, "L/U", "time to the closest approach within which a passing below "
       "nmpc_d_risk is a risk of collision", _OURS + "the planning horizon of 20 L/U and 5 L/U more: a ship whose "
       "stand-on encounter is about to begin stops turning for anything else before it does"),
    _p("nmpc_head_on_deg", 22.5, 0.0, 90.0, "deg", "head-on when each ship sees the other within this angle of "
       "her bow (Rule 14; crossing otherwise)", _OURS + "two points of the compass, the widest reading of Rule "
       "14(b)'s 'ahead or nearly ahead', since Rule 14(c) says to assume head-on in doubt (it coincides with the "
       "published profile's doubt band and the paper laboratory's head-on sector)"),
    _p("nmpc_alter_deg", 35.0, 0.0, 90.0, "deg", "a give-way ship keeps her heading at least this far to "
       "starboard of her heading at the onset while the other ship closes", _OURS + "an alteration of 30° or "
       "more is readily apparent to a radar observer (Cockcroft & Lameijer p. 51; the published profile's "
       "threshold reads it too) and 5° more absorb the soft constraint's give and the drift angle"),
    _p("nmpc_r_act", 12.0, 0.0, None, "L", "a stand-on ship acts once the give-way ship is this close without "
       "having altered course", _OURS + "1.5 nautical miles of a 230 m ship: inside the 2 miles at which a "
       "crossing give-way ship has usually waited too long (Cockcroft & Lameijer p. 108), so her inaction is "
       "apparent, with some 6 L/U left before close quarters at a closing speed of 1.4 U"),
    _p("nmpc_t_wait", 4.0, 0.0, None, "L/U", "a stand-on ship gives the give-way ship at least this long after the "
       "onset before she acts", _OURS + "75 s for the KCS: the time a ship of her kind takes for a 60° alteration "
       "(3.7 L/U at 35° rudder), so a give-way ship that began at the onset has visibly turned"),
    _p("nmpc_seen_deg", 15.0, 0.0, 180.0, "deg", "a give-way ship that has altered her course by this much "
       "since the onset is taken to be acting", _OURS + "well above the drift of a course over ground through "
       "the plotting noise, below a readily apparent alteration"),
    _p("nmpc_t_must", 5.0, 0.0, None, "L/U", "while a stand-on ship holds, she still avoids a near passing "
       "predicted within this time (Rule 17(b))", _OURS + "93 s for the KCS: a 35° turn still takes her 3 L "
       "off her track"),
    _p("nmpc_obstacle_clear", 4.0, 0.0, None, "L", "centre distance kept from a static obstacle (soft, heavy "
       "weight)", _OURS + "the collision distance of 2 L plus 2 L"),
    _p("nmpc_land_margin", 1.5, 0.0, None, "L", "clearance kept from land and walls beyond half the beam (soft, "
       "heavy weight)", _OURS + "a KCS's turning advance at 35° is about 3 L; 1.5 L leaves room to turn away"),
    _p("nmpc_nu_min", 0.5, 0.25, 1.0, "", "lowest propeller speed the planner orders, a fraction of the service "
       "propeller speed", _OURS + "half speed, a readily apparent slowing; the engine's dead slow ahead lies "
       "below"),
    _p("nmpc_v_static", 0.1, 0.0, None, "U", "neighbours slower than this are static obstacles (no COLREG role)",
       _OURS + "2.5 kn for the KCS: a ship barely making way"),
    _p("nmpc_kkt_fail", 1.0, 0.0, None, "", "a solve that ends with a projected gradient above this and no "
       "improvement on its starting plan failed", _OURS + "the cost is O(1) per interval"),
    _p("nmpc_w_route", 1.0, 0.0, None, "", "weight of following the line of sight to the waypoint",
       _OURS + "the unit of the cost"),
    _p("nmpc_w_rudder", 0.01, 0.0, None, "1/rad²", "weight of the rudder command", _OURS + "small: a 20° "
       "rudder costs 1 % of a heading 90° off the route"),
    _p("nmpc_w_rate", 0.1, 0.0, None, "1/rad²", "weight of the change of the rudder command between intervals",
       _OURS + "smooth rudder orders"),
    _p("nmpc_w_speed", 1.0, 0.0, None, "", "weight of a propeller command off the service speed",
       _OURS + "a slowing to half speed costs as much as a heading 60° off the route for one interval"),
    _p("nmpc_w_pass", 10.0, 0.0, None, "1/L²", "weight of a passing closer than nmpc_d_pass", _OURS +
       "1 L inside the passing distance costs as much as heading 90° off the route for five intervals"),
    _p("nmpc_w_close", 1000.0, 0.0, None, "1/L²", "weight of a passing closer than nmpc_d_close, of a static "
       "obstacle", _OURS + "a hundred times nmpc_w_pass: in effect hard"),
    _p("nmpc_w_colreg", 100.0, 0.0, None, "1/rad²", "weight of the COLREG constraints (starboard alteration, "
       "stand-on course and speed, no crossing ahead)", _OURS + "above the route and the passing distance (a "
       "stand-on ship holds her course although the route lies elsewhere), below the near passing"),
    _p("nmpc_w_land", 1000.0, 0.0, None, "1/L²", "weight of a passing inside the land clearance",
       _OURS + "as nmpc_w_close"),
    _p("nmpc_w_hold", 10000.0, 0.0, None, "1/rad²", "weight of a stand-on ship's course and speed",
       _OURS + "a 2° drift costs about as much as a heading 45° off the route: she keeps her course to the degree "
               "(a change of course or speed of a stand-on ship misleads the give-way ship)"),
    _p("nmpc_ships", 4, 1, 8, "", "target ships the planner considers (the nearest in view)",
       _OURS + "four: environment 5 rarely has more within 25 L", kind="int", structural=True),
    _p("nmpc_obstacles", 2, 0, 8, "", "static obstacles the planner considers (the nearest in view)",
       _OURS + "two", kind="int", structural=True),
    _p("nmpc_land", 4, 0, 16, "", "land and wall segments the planner considers (the nearest)",
       _OURS + "four: a strait's two shores and an island's near edges", kind="int", structural=True),
    _p("nmpc_max_iter", 10, 1, 100, "", "SQP iterations per solve at most",
       _OURS + "a warm-started solve takes 1-4; ten bound the cost of the first solve of an encounter",
       kind="int", structural=True),
)
"""The planner's own parameters (prefix ``nmpc_``)."""


def _vessel(layout) -> str:
    """The one hull of every ship of ``layout`` that uses ``nmpc``."""
    hulls = {layout.vessel(i) for i in range(layout.n_ships) if layout.methods[i] == "nmpc"}
    if len(hulls) != 1:
        raise ParameterError("vessels", "one vessel for every ship of a layout that uses nmpc", sorted(hulls))
    return hulls.pop()


def shape_of(layout) -> OcpShape:
    """The problem structure of the ``nmpc`` ships of ``layout`` (:class:`~mmg_casadi.guidance.nmpc_ocp.OcpShape`).

    Parameters
    ----------
    layout : Layout
        A closed-loop layout with a ship that uses ``nmpc``.

    Returns
    -------
    OcpShape
        Her hull, the scene's unit hull, the horizon and the slots (structural parameters of the layout).
    """
    return OcpShape(_vessel(layout), layout.unit_vessel(), HORIZON, int(layout.option("nmpc_ships")),
                    int(layout.option("nmpc_obstacles")), int(layout.option("nmpc_land")) if layout.n_walls else 0,
                    BLOCKS)


def _nearest(score, mask, k: int) -> list:
    """``k`` one-hot rows (1×M) picking the ``mask``ed columns of least ``score`` in increasing order (the first
    column on a tie); a row of zeros once none is left."""
    m = score.size2()
    taken = ca.SX.zeros(1, m)
    rows = []
    for _ in range(k):
        s = score + BIG * (1 - mask * (1 - taken))
        low = ca.mmin(s) if m else ca.SX(BIG)
        hit, seen = ca.SX.zeros(1, m), ca.SX(0)
        for j in range(m):
            hit[j] = (s[j] <= low) * (low < BIG / 2) * (1 - seen)
            seen = seen + hit[j]
        rows.append(hit)
        taken = taken + hit
    return rows


def _pick(row, values):
    """The column of ``values`` (n×M) that one-hot ``row`` picks (zeros for an empty row)."""
    return ca.mtimes(values, row.T)


def plan_inputs(g: GuidanceInputs) -> dict:
    """The planner's problem at one step: its structure, start plan, parameters and bounds, and the memory it keeps.

    Parameters
    ----------
    g : GuidanceInputs
        The ship's guidance inputs (with ``own``).

    Returns
    -------
    dict
        ``shape``, ``w0``, ``p``, ``lbw``, ``ubw`` (the solve's inputs), ``need`` (1 when anything is in view or
        land is near), ``live`` (a previous plan exists), ``plan`` (the previous plan), ``fallback`` (its command
        for now, or the hard starboard turn), ``memory`` (the encounter rows after the step), ``engaged`` and
        ``r_own`` (the yaw rate the PD controller sees).
    """
    lay, P, own = g.layout, g.P, g.own
    if lay.smooth is not None:
        raise ParameterError("smooth", "None for a layout with nmpc (the planner's solve has no smooth form)",
                             lay.smooth)
    shape = shape_of(lay)
    model = reduced_model(shape.vessel, shape.unit)
    lam, mu = scene_scales(load_vessel(shape.vessel).ship, load_vessel(shape.unit).ship)
    r_own = own["r"] * (lam / mu)
    M = g.nb_pos.size2()
    pos, vel, psi = g.pos, g.vel, g.psi
    mem = g.memory
    nu_ref = g.service_rpm / model.n_design
    nb_speed = ca.sqrt(ca.sum1(g.nb_vel ** 2)) if M else ca.SX(1, 0)
    moving = nb_speed > P["nmpc_v_static"] if M else ca.SX(1, 0)
    ship = g.active * moving if M else ca.SX(1, 0)
    static = g.active * (1 - moving) if M else ca.SX(1, 0)
    rel = g.nb_pos - ca.repmat(pos, 1, M) if M else ca.SX(2, 0)
    dist = ca.sqrt(ca.sum1(rel ** 2)) if M else ca.SX(1, 0)
    # encounters: risk, role at the onset, kept in slots (the planner's own thresholds)
    slots = [(mem[f"nmpc_slot{k}_x"], mem[f"nmpc_slot{k}_y"], mem[f"nmpc_slot{k}_code"]) for k in range(SLOTS)]
    code = ca.SX.zeros(1, M)
    slot_rows = {}
    if M:
        dv = g.nb_vel - ca.repmat(vel, 1, M)
        dv2 = ca.fmax(ca.sum1(dv ** 2), 1e-9)
        tcpa = -ca.sum1(rel * dv) / dv2
        dcpa = ca.sqrt(ca.sum1((rel + dv * ca.repmat(ca.fmax(tcpa, 0), 2, 1)) ** 2))
        soon = ship * (tcpa > 0) * (tcpa < P["nmpc_t_risk"])
        risk = soon * (dcpa < P["nmpc_d_risk"])
        chi = ca.atan2(g.nb_vel[1, :], g.nb_vel[0, :])
        beta = wrap_angle(ca.atan2(rel[1, :], rel[0, :]) - psi)
        alpha = wrap_angle(ca.atan2(-rel[1, :], -rel[0, :]) - chi)
        role_now = classify_role(beta, alpha, psi, chi, g.speed, nb_speed, theta_head_on=P["nmpc_head_on"],
                                 stern=5 * math.pi / 8)
        # a ship to which she would be the stand-on ship counts from a wider passing (nmpc_d_watch): she stops turning
        # before such a ship's passing closes to a risk
        risk = risk + (1 - risk) * soon * (dcpa < P["nmpc_d_watch"]) * (role_now < OVERTAKEN + 0.5)
        link, code = recall(g.nb_pos, ship, slots)
        had = sum(link)
        chi_kept = sum(row * mem[f"nmpc_slot{k}_chi"] for k, row in enumerate(link))
        age = sum(row * (mem[f"nmpc_slot{k}_age"] + P["dt"]) for k, row in enumerate(link))
        passed = (tcpa <= 0) * (dcpa > P["nmpc_d_close"])  # the encounter is over once the range opens, clear
        link = [row * (1 - passed) for row in link]
        code = code * (1 - passed)
        link, code = open_encounters(g.nb_pos, risk, role_now, link, code)
        chi_onset = chi_kept + (sum(link) - had) * chi
        stand_on = (code > STAND_ON - 0.5) * (code < OVERTAKEN + 0.5)
        altered = ca.fabs(wrap_angle(chi - chi_onset)) > P["nmpc_seen"]
        inaction = (stand_on * (1 - altered) * (dist < P["nmpc_r_act"]) * (age >= P["nmpc_t_wait"])
                    * (dcpa < P["nmpc_d_risk"]) * (tcpa > 0))
        code_next = code + ACTING * inaction
        for k, row in enumerate(link):
            used = ca.sum2(row)
            for c, vals in (("x", g.nb_pos[0, :]), ("y", g.nb_pos[1, :]), ("code", CODE + code_next),
                            ("chi", chi_onset), ("age", age)):
                slot_rows[f"nmpc_slot{k}_{c}"] = ca.if_else(used > 0.5, ca.sum2(row * vals), psi)
        code = code_next
    else:
        slot_rows = {f"nmpc_slot{k}_{c}": psi for k in range(SLOTS) for c in ("x", "y", "code", "chi", "age")}
    give_way = (ca.fabs(code - GIVE_WAY) < 0.5) + (ca.fabs(code - HEAD_ON) < 0.5)
    holding = (ca.fabs(code - STAND_ON) < 0.5) + (ca.fabs(code - OVERTAKEN) < 0.5)
    acting = (code > STAND_ON + ACTING - 0.5) * (code < OVERTAKEN + ACTING + 0.5)
    crossing_acting = ca.fabs(code - (STAND_ON + ACTING)) < 0.5
    # the own headings the COLREG constraints refer to: at the onset of the first give-way / stand-on encounter
    old = [s[2] - CODE for s in slots]
    gw_before = sum((ca.fabs(c - GIVE_WAY) < 0.5) + (ca.fabs(c - HEAD_ON) < 0.5) for c in old) > 0.5
    so_before = sum((c > STAND_ON - 0.5) * (c < OVERTAKEN + 0.5) + (c > STAND_ON + ACTING - 0.5)
                    * (c < OVERTAKEN + ACTING + 0.5) for c in old) > 0.5
    base = ca.if_else(gw_before, mem["nmpc_base"], psi)
    course = ca.if_else(so_before, mem["nmpc_course"], psi)
    # the problem's parameters
    lay_p = param_layout(shape)
    p = ca.SX.zeros(lay_p["size"])
    nu_now = own["n_prop"] / model.n_design
    p[lay_p["state"]] = ca.vertcat(0, 0, psi, own["r"], own["delta"], own["u"], nu_now)
    p[lay_p["goal"]] = g.goal - pos
    p[lay_p["h"]] = P["nmpc_step"]
    p[lay_p["engine"]] = ca.vertcat(own["engine_lag"], own["engine_rate"] / model.n_design)
    p[lay_p["nu_ref"]] = nu_ref
    p[lay_p["weights"]] = ca.vertcat(*[P[f"nmpc_w_{k}"] for k in WEIGHTS])
    any_give_way = ca.sum2(give_way * ship) > 0.5 if M else ca.SX(0)
    # a stand-on ship holds her course and speed, unless a give-way duty to another ship forces her to starboard;
    # then she only keeps from turning to port of her course
    any_hold = (ca.sum2(holding * ship) > 0.5) * (1 - any_give_way) if M else ca.SX(0)
    starboard_only = crossing_acting + holding * any_give_way
    p[lay_p["colreg"]] = ca.vertcat(psi + wrap_angle(base + P["nmpc_alter"] - psi), psi + wrap_angle(course - psi),
                                    any_hold)
    p[lay_p["clearance"]] = (g.half_beam if g.half_beam is not None else 0) + P["nmpc_land_margin"]
    head_on = ca.fabs(code - HEAD_ON) < 0.5
    no_ahead = (ca.fabs(code - GIVE_WAY) < 0.5) + (ca.fabs(code - OVERTAKING) < 0.5) + head_on
    if M:
        c_nb = g.nb_vel / ca.repmat(ca.fmax(nb_speed, 1e-9), 2, 1)  # their courses
        side = ca.sign(c_nb[0, :] * (-rel[1, :]) - c_nb[1, :] * (-rel[0, :]))  # own ship right of her course: +1
        side = head_on * -1 + (1 - head_on) * side  # meeting head-on: pass port to port (on her port side)
    fields = []
    for row in _nearest(dist, ship, shape.ships) if M else [ca.SX(1, 0)] * shape.ships:
        on = ca.sum2(row) if M else ca.SX(0)
        hold_j = _pick(row, holding) if M else ca.SX(0)
        vals = {"px": _pick(row, rel[0, :]) if M else 0, "py": _pick(row, rel[1, :]) if M else 0,
                "vx": _pick(row, g.nb_vel[0, :]) if M else 0, "vy": _pick(row, g.nb_vel[1, :]) if M else 0,
                "d_pass": P["nmpc_d_pass"], "d_close": P["nmpc_d_close"], "a_pass": on * (1 - hold_j),
                "a_close": on, "t_lim": ca.if_else(hold_j > 0.5, P["nmpc_t_must"], BIG),
                "give_way": _pick(row, give_way) if M else 0,
                "starboard": _pick(row, starboard_only) if M else 0, "no_ahead": _pick(row, no_ahead) if M else 0,
                "side": _pick(row, side) if M else 0}
        fields.append(ca.vertcat(*[vals[k] for k in SHIP_FIELDS]))
    if shape.ships:
        p[lay_p["ships"]] = ca.vertcat(*fields)
    obst = []
    for row in _nearest(dist, static, shape.obstacles) if M else [ca.SX(1, 0)] * shape.obstacles:
        on = ca.sum2(row) if M else ca.SX(0)
        obst.append(ca.vertcat(_pick(row, rel[0, :]) if M else 0, _pick(row, rel[1, :]) if M else 0,
                               P["nmpc_obstacle_clear"], on))
    if shape.obstacles:
        p[lay_p["obstacles"]] = ca.vertcat(*obst)
    near_land = ca.SX(0)
    if shape.land:
        walls = g.walls
        W = walls.size2()
        seg = ca.SX.zeros(1, W)
        for j in range(W):
            a, b = walls[0:2, j], walls[2:4, j]
            ab = b - a
            t = ca.fmin(ca.fmax(ca.dot(pos - a, ab) / ca.fmax(ca.dot(ab, ab), 1e-9), 0), 1)
            seg[j] = ca.norm_2(pos - (a + t * ab))
        rows = _nearest(seg, ca.SX.ones(1, W), shape.land)
        land = []
        for row in rows:
            land.append(ca.vertcat(_pick(row, walls[0:2, :] - ca.repmat(pos, 1, W)),
                                   _pick(row, walls[2:4, :] - ca.repmat(pos, 1, W)), ca.sum2(row)))
        p[lay_p["land"]] = ca.vertcat(*land)
        near_land = ca.mmin(seg) < P["r_safe"]
    engaged = ca.sum2(ship) > 0.5 if M else ca.SX(0)
    need = ca.fmax(ca.sum2(g.active) > 0.5 if M else ca.SX(0), near_land)
    # the start plan: the previous plan (warm start) or straight ahead at the service speed
    live = ca.fabs(mem["nmpc_live"] - LIVE) < 0.5
    plan = ca.vertcat(*[mem[k] for k in PLAN])
    d_max = ca.fmin(P["delta_max"], model.delta_max)
    nu_hi = ca.fmin(nu_ref, own["rpm_max"] / model.n_design)
    nu_lo = ca.fmax(P["nmpc_nu_min"] * nu_ref, own["rpm_min"] / model.n_design)
    lbw = ca.vertcat(ca.repmat(-d_max, HORIZON, 1), ca.repmat(nu_lo, BLOCKS, 1))
    ubw = ca.vertcat(ca.repmat(d_max, HORIZON, 1), ca.repmat(nu_hi, BLOCKS, 1))
    cold = ca.vertcat(ca.SX.zeros(HORIZON, 1), ca.repmat(nu_ref, BLOCKS, 1))
    w0 = ca.fmin(ca.fmax(ca.if_else(live, plan, cold), lbw), ubw)
    fallback = ca.if_else(live, ca.vertcat(plan[0], plan[HORIZON]), ca.vertcat(d_max, nu_lo))
    return {"shape": shape, "w0": w0, "p": p, "lbw": lbw, "ubw": ubw, "need": need, "live": live, "plan": plan,
            "fallback": fallback, "memory": {"nmpc_base": base, "nmpc_course": course, **slot_rows},
            "engaged": engaged, "r_own": r_own, "n_design": model.n_design, "acting": acting}


def _solve_if_needed(shape: OcpShape, max_iter: int) -> ca.Function:
    """``(need, w0, p, lbw, ubw) -> (w, f0, f, kkt)``: the solve when ``need``, else the start plan at once."""
    solve = solver_function(shape, max_iter)
    ins = [ca.MX.sym(solve.name_in(k), solve.size_in(k)) for k in range(solve.n_in())]
    skip = ca.Function(f"{solve.name()}_skip", ins, [ins[0], ca.MX(0), ca.MX(0), ca.MX(0)])
    cond = ca.Function.conditional(f"{solve.name()}_if", [skip], solve)
    args = [ca.MX.sym(cond.name_in(k), cond.size_in(k)) for k in range(cond.n_in())]
    return ca.Function(f"{solve.name()}_when", args, cond(*args), {"never_inline": True})


def _nmpc(g: GuidanceInputs) -> Command:
    q = plan_inputs(g)
    P = g.P
    shape = q["shape"]
    w, f0, f, kkt = _solve_if_needed(shape, int(g.layout.option("nmpc_max_iter")))(
        q["need"], q["w0"], q["p"], q["lbw"], q["ubw"])
    finite = ca.logic_and(ca.fabs(ca.sum1(w)) < ca.inf, ca.fabs(f) < ca.inf)  # NaN or inf anywhere: not finite
    fail = q["need"] * ca.logic_or(1 - finite, ca.logic_and(kkt > P["nmpc_kkt_fail"], f >= f0))
    cmd = ca.if_else(fail, q["fallback"], ca.vertcat(w[0], w[HORIZON]))
    kept = ca.if_else(q["live"], q["plan"], ca.vertcat(ca.repmat(q["fallback"][0], HORIZON, 1),
                                                       ca.repmat(q["fallback"][1], BLOCKS, 1)))
    plan_next = ca.if_else(fail, kept, w)
    psi_d = g.psi + (cmd[0] + P["kd"] * q["r_own"]) / P["kp"]  # the PD controller then orders exactly cmd[0]
    memory = {"nmpc_live": LIVE, "nmpc_engaged": q["engaged"], **q["memory"],
              **{k: plan_next[i] for i, k in enumerate(PLAN)},
              "nmpc_solves": g.memory["nmpc_solves"] + q["need"],
              "nmpc_fallbacks": g.memory["nmpc_fallbacks"] + fail}
    return Command(VECTOR_LENGTH * ca.vertcat(ca.cos(psi_d), ca.sin(psi_d)), cmd[1] * q["n_design"], memory)


def engaged(memory: dict):
    """1 while the planner has a ship in view (its ``engaged`` test, :class:`~mmg_casadi.guidance.contract.Method`).

    Parameters
    ----------
    memory : dict
        The planner's memory rows after the step.

    Returns
    -------
    SX
        1 or 0.
    """
    return memory["nmpc_engaged"] > 0.5


METHOD = Method(
    "nmpc", _nmpc, (), "ours: nonlinear MPC over a model identified from the own ship's MMG model, soft separation, "
    "COLREG and land constraints, sqpmethod + qrqp inside the compiled step (mmg_casadi.guidance.nmpc)",
    goal_capture=True, memory=MEMORY, commands_speed=True, lookout="nmpc_r_look", engaged=engaged, params=PARAMS,
    own_state=True, tallies=TALLIES)
"""The method's declaration; registered on first use (:data:`mmg_casadi.guidance.methods.ON_DEMAND`)."""
