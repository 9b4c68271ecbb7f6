"""``sb-mpc``: the scenario-based model predictive control of Johansen, Perez & Cristofaro (2016), with the
published extensions for transitions (Hagen et al. 2018), stand-on and readily apparent manoeuvres (the group's
PSB-MPC) and grounding hazards (Tengesdal et al. 2022).

T. A. Johansen, T. Perez & A. Cristofaro, "Ship collision avoidance and COLREGS compliance using simulation-based
control behavior selection with predictive hazard assessment", IEEE Trans. Intelligent Transportation Systems
17(12) (2016) 3407–3422, doi:10.1109/TITS.2016.2551780. At every decision the own ship predicts, over a horizon,
her track under each of a finite set of **control behaviours** (a course offset from the course to her waypoint
and a propulsion level, held over the horizon; :func:`~mmg_casadi.guidance.sb_mpc_cost.behaviours`) with a
reduced model of her closed loop (:mod:`mmg_casadi.guidance.sb_mpc_model`), and every neighbour's track at
constant velocity; she takes the behaviour of least **hazard** (:mod:`mmg_casadi.guidance.sb_mpc_cost`: collision
risk × collision cost discounted in time, COLREG violation, transitions, stand-on and readily apparent terms,
grounding, control deviation and switching) and holds it until the next decision, ``sb_mpc_interval`` later.

Extensions, each published:

* I. B. Hagen, D. K. M. Kufoalor, E. F. Brekke & T. A. Johansen, "MPC-based collision avoidance strategy for
  existing marine vessel guidance systems", IEEE ICRA 2018, pp. 7618–7623: the transitional cost κ_TC;
* T. Tengesdal, T. A. Johansen, T. D. Grande & S. Blindheim, "Ship collision avoidance and anti grounding using
  parallelized cost evaluation in probabilistic scenario-based model predictive control", IEEE Access 10 (2022)
  111650–111664 (and T. D. Grande, "PSB-MPC collision avoidance with anti-grounding", NTNU MSc thesis 2021): the
  grounding cost G_1, G_3, G_4 (:func:`~mmg_casadi.guidance.sb_mpc_cost.grounding_function`), evaluated on the
  layout's wall and land segments as the velocity obstacle's land test uses them;
* the group's open implementation github.com/ntnu-itk-autonomous-ship-lab/psbmpc (``sbmpc_parameters.cpp``,
  ``mpc_cost_cpu.hpp``, ``colregs_violation_evaluator.hpp``; S. V. Rothmund & T. Tengesdal): the stand-on (κ_SO)
  and readily apparent (κ_RA) violation costs, the port/starboard split of K_χ and K_Δχ.

Weights are those of NTNU's colav-simulator (``colav_simulator/core/colav/sbmpc/sbmpc.py``, the 2016 paper's
numbers) where the paper's formulation is kept, converted to the scene's units where they have one (lengths in
L, times in L/U, speeds in U); each :data:`PARAMS` entry names its source and says where the choice is ours.

**In the closed loop.** The method is in charge while a neighbour is within its own sensing range ``sb_mpc_range``
(``Method.sensing``) or a wall or land edge within reach of its horizon, and
orders the course and the propeller speed of its behaviour (the engine model follows the rpm, keeping at least
dead slow ahead). Its memory (:data:`MEMORY`): the course held, a code of the behaviour held (level and offset) and
the time since the decision. Between decisions nothing is evaluated (a conditional). The own ship's yaw rate at a
decision is not among the method's inputs; the prediction starts from a steady heading.

Examples
--------
>>> from mmg_casadi.guidance.methods import METHODS
>>> m = METHODS["sb-mpc"]
>>> m.memory[:4], m.commands_speed, m.sensing
(('sb_course', 'sb_state', 'sb_clock', 'sb_base'), True, 'sb_mpc_range')
"""

from __future__ import annotations

import functools
import math

import casadi as ca

from mmg_casadi.errors import ParameterError
from mmg_casadi.guidance.colregs_encounters import (GIVE_WAY, HEAD_ON, OVERTAKEN, OVERTAKING, SLOTS, STAND_ON,
                                                    classify_role, open_encounters, recall, remember)
from mmg_casadi.guidance.contract import Command
from mmg_casadi.guidance.fields import R_MIN
from mmg_casadi.guidance.sb_mpc_cost import LEVELS, NB_ROWS, plan_function
from mmg_casadi.guidance.sb_mpc_model import reduced_model
from mmg_casadi.params import Param
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed, scene_scales

NAME = "sb-mpc"
"""The method's name in the registry."""

SLOT_MEMORY = tuple(f"sb_slot{k}_{c}" for k in range(SLOTS) for c in ("x", "y", "code"))
"""Encounter slots: the position of the slot's ship at the last step and the code of the own ship's role at the
onset (as colregs-vortex's, :mod:`mmg_casadi.guidance.colregs_encounters`)."""

MEMORY = ("sb_course", "sb_state", "sb_clock", "sb_base") + SLOT_MEMORY
"""Memory rows: the course held (rad), the code ``CODE + level`` of the propulsion level held while the method is
engaged, the time since the last decision (L/U), the heading at the onset of the give-way duties (rad; the
readily apparent alteration is measured from it) and the encounter slots (:data:`SLOT_MEMORY`)."""

CODE = 1000.0
"""Offset of the behaviour code (any value below CODE/2, such as the heading the closed loop writes when the method
was not in charge, is "no behaviour held": the next step decides afresh)."""

STERN = math.radians(112.5)
"""Start of the stern sector from the bow (COLREG Rule 13(b)), for the roles of the stand-on and give-way terms."""


def _p(name, default, low, high, unit, meaning, source, **kw) -> Param:
    return Param(f"sb_mpc_{name}", default, low, high, unit, meaning, source, **kw)


_JOHANSEN = "Johansen, Perez & Cristofaro 2016 (IEEE T-ITS 17(12)) as configured in NTNU's colav-simulator sbmpc.py"
_PSBMPC = "the NTNU group's SB-MPC (github.com/ntnu-itk-autonomous-ship-lab/psbmpc, sbmpc_parameters.cpp)"

PARAMS: tuple[Param, ...] = (
    _p("range", 50.0, 0.0, None, "L", "sensing range: the closed loop gives the method every neighbour within it "
       "(its duties are judged for all of them, its hazard for those that can come within d_close over the horizon)",
       "ours: 6.2 nm for the KCS, the 6 nm range scale on which a radar watch in open water is commonly kept; "
       "twice the distance the own ship sails at her design speed over t_duty (2 U t_duty), the farthest a ship "
       "on a reciprocal course can be and still have a duty", low_open=True),
    _p("t_duty", 25.0, 0.0, None, "L/U", "a ship closing with a straight-line passing inside d_close and a TCPA "
       "below this opens an encounter (its role judged then and kept); with the passing inside d_safe it gives a "
       "stand-on duty (a give-way duty: with a TCPA inside the horizon)", "ours: 7.7 min for the KCS, within the 6 to 12 min at which mariners commonly set the "
       "ARPA's TCPA alarm", low_open=True),
    _p("horizon", 15.0, 0.0, None, "L/U", "prediction horizon T", "ours: 15 L/U = 4.7 min for the KCS, about the "
       "300 s of NTNU's colav-simulator; long enough that a ship closing at twice the design speed is seen 30 L "
       "(about 4 nm) before the CPA", low_open=True),
    _p("samples", 15, 2, 200, "", "prediction samples over the horizon (structural)", "ours: one per L/U "
       "(18.6 s for the KCS; colav-simulator samples every 5 s a vessel whose time unit is about 2 s)",
       kind="int", structural=True),
    _p("substeps", 2, 1, 20, "", "Euler steps of the own-ship prediction per sample (structural)", "ours: a step "
       "of 0.5 L/U with the default horizon and samples, the step the reduced model was identified with "
       "(mmg_casadi.guidance.sb_mpc_model)", kind="int", structural=True),
    _p("interval", 1.0, 0.0, None, "L/U", "time between decisions (and a decision at once when an encounter opens); "
       "the behaviour chosen is held in between",
       "ours: 1 L/U = 18.6 s for the KCS, under the 2.5 L/U she takes to complete a 30° alteration (the "
       "paper re-evaluates every few seconds for a 5 m vessel)", low_open=True),
    _p("d_safe", 11.0, 0.0, None, "L", "safety distance d_safe of the collision risk (Johansen eq. 6)",
       "ours: close quarters begin at about 1 nm between ships in sight (Cockcroft & Lameijer p. 52), 8.05 L "
       "for the 230 m KCS, which Rule 8(c) asks a give-way ship to avoid; plus half a length for the reduced "
       "model's position error (0.4 L rms). The published evaluator's safe passing distance is also 1 nm; this "
       "default does not read it", low_open=True),
    _p("d_obstacle", 4.0, 0.0, None, "L", "safety distance of the collision risk for a static obstacle",
       "ours: twice the 2 L collision distance; a ship passes a buoy or a rock much closer than another ship (the "
       "1 nm of d_safe is close quarters between ships, Rule 8(c))", low_open=True),
    _p("d_standon", 4.0, 0.0, None, "L", "safety distance of the collision risk for a ship the own ship stands on "
       "for while the give-way ship can still act (Rule 17(a)(i)); below it she acts alone (17(b))",
       "ours: twice the 2 L collision distance, a near miss: a passing so close that the give-way ship's action "
       "alone will not do", low_open=True),
    _p("d_close", 16.0, 0.0, None, "L", "range d_close within which the COLREG terms apply (Johansen eq. 8); also "
       "the straight-line passing below which a stand-on duty holds", "ours: 2 nm (16.1 L for the KCS), by "
       "which a give-way ship in a crossing should have acted (Cockcroft & Lameijer p. 108); the paper and "
       "colav-simulator use 5 × d_safe", low_open=True),
    _p("k_coll", 5.0, 0.0, None, "(U)^-2", "collision cost K_coll: C = K_coll |v_0 − v_i|² (Johansen eq. 7)",
       _JOHANSEN + ": 0.5 (the relative speed there in m/s of a 5 m vessel; here in U, the risk's scale set "
       "by d_safe in L and t in L/U: ours)"),
    _p("dv_min", 0.8, 0.0, None, "U", "relative speed floor Δv_min of the collision cost: C = K_coll max(|v_0 − v_i|², "
       "Δv_min²)", "ours: Johansen's C vanishes for two ships on parallel courses at equal speed, which then close "
       "at no cost; the floor prices such a collision as one at half the design speed"),
    _p("k_mean", 1.0, 0.0, None, "", "weight of the time average of a neighbour's collision cost, added to its "
       "maximum over time", "ours: with the maximum alone (Johansen eq. 9), a neighbour already within d_safe "
       "makes every behaviour's hazard that of the first sample, before any behaviour has turned the ship, and "
       "the choice falls to the deviation costs; the average ranks the behaviours by the risk they carry "
       "later"),
    _p("p", 0.5, 0.5, None, "", "time exponent p of the collision risk's discount 1/t^p (Johansen eq. 6)",
       _JOHANSEN),
    _p("kappa", 3.0, 0.0, None, "", "COLREG violation cost κ (Johansen eq. 9)", _JOHANSEN),
    _p("kappa_tc", 10.0, 0.0, None, "", "transitional cost κ_TC (Hagen et al. 2018)", "Hagen et al. 2018 as in "
       "the DUNE SB-MPC of the Autosea project (KAPPA_TC 10)"),
    _p("k_p", 2.5, 0.0, None, "", "cost K_P of a propulsion level P below full: K_P (1 − P) (Johansen eq. 10)",
       _JOHANSEN),
    _p("k_chi_strb", 1.3, 0.0, None, "rad^-2", "cost K_χ of a course offset to starboard: K_χ χ_ca² "
       "(Johansen eq. 10)", _JOHANSEN),
    _p("k_chi_port", 1.6, 0.0, None, "rad^-2", "cost K_χ of a course offset to port (prefer starboard)", _PSBMPC),
    _p("k_dp", 2.0, 0.0, None, "", "cost K_ΔP of changing the propulsion level: K_ΔP |P − P_last| (Johansen "
       "eq. 11)", _JOHANSEN),
    _p("k_dchi_strb", 0.9, 0.0, None, "rad^-2", "cost K_Δχ of changing the offset to starboard: "
       "K_Δχ (χ_ca − χ_ca,last)² (Johansen eq. 11)", _JOHANSEN),
    _p("k_dchi_port", 1.2, 0.0, None, "rad^-2", "cost K_Δχ of changing the offset to port (prefer starboard, "
       "penalise switching)", _JOHANSEN),
    _p("phi_ah_deg", 68.5, 0.0, 180.0, "deg", "a neighbour within this angle of the own velocity is ahead φ_AH",
       _JOHANSEN),
    _p("phi_ot_deg", 68.5, 0.0, 180.0, "deg", "overtaking: velocities within this angle φ_OT", _JOHANSEN),
    _p("phi_ho_deg", 22.5, 0.0, 90.0, "deg", "head-on: velocities within this angle of reciprocal φ_HO; also "
       "the bearing tolerance of the roles of the stand-on and give-way terms", _JOHANSEN),
    _p("phi_cr_deg", 68.5, 0.0, 180.0, "deg", "crossing: velocities more than this angle apart φ_CR", _JOHANSEN),
    _p("v_min", 0.05, 0.0, None, "U", "a neighbour slower than this has no COLREG situation (an obstacle)",
       "ours: 0.6 m/s for the KCS, about colav-simulator's 0.05 m/s test of a moving obstacle scaled to a "
       "ship", low_open=True),
    _p("kappa_so", 5.0, 0.0, None, "", "stand-on cost κ_SO of a behaviour that changes course or speed while the "
       "own ship keeps them for a give-way ship (Rule 17(a)(i))", "ours, after the psbmpc's stand-on violation "
       "(colregs_violation_evaluator.hpp): more than the largest control deviation cost (K_χ (π/2)² + K_P), so "
       "a stand-on ship keeps her course unless a collision is at stake"),
    _p("dpsi_keep_deg", 2.5, 0.0, 90.0, "deg", "a behaviour whose course differs by more than this from the present "
       "heading changes course (stand-on term)", "psbmpc's max_acceptable_SO_course_change (2.5°)"),
    _p("r_free", 16.0, 0.0, None, "L", "a give-way ship's inaction is apparent (Rule 17(a)(ii)) inside this range "
       "with the passing still below d_safe and the TCPA below t_free: the stand-on term ends", "ours: 2 nm "
       "(Cockcroft & Lameijer p. 108: a give-way ship that has not acted by 2 nm has usually waited too long); "
       "the published evaluator's ample time ends at the same range; this default does not read it"),
    _p("t_free", 6.0, 0.0, None, "L/U", "... and inside this TCPA (see r_free)", "ours: 6 L/U ≈ 2 min for the KCS, "
       "time for a 60° alteration (3.7 L/U) and two decisions, so the stand-on ship still avoids alone"),
    _p("kappa_gw", 10.0, 0.0, None, "", "give-way cost κ_GW of a behaviour after which a ship crossing from "
       "starboard or meeting head-on is on the own starboard side at the predicted closest approach within d_close "
       "(the own ship crossed ahead of her, Rule 15, or did not pass her port to port, Rule 14)",
       "ours, after the psbmpc's GW violation (colregs_violation_evaluator.hpp, evaluate_GW_violation), with its "
       "weight as κ_TC"),
    _p("kappa_port", 5.0, 0.0, None, "", "cost κ_port of an alteration to port while the own ship meets a ship "
       "head-on (Rule 14(a)), gives way to one crossing from starboard (Rule 15: it would cross ahead of her) or, "
       "free to act, stands on for one crossing from port (Rule 17(c))", "ours, after the psbmpc's GW violation "
       "(a port alteration of a give-way ship, colregs_violation_evaluator.hpp), with κ_RA's weight"),
    _p("kappa_ra", 5.0, 0.0, None, "", "readily apparent cost κ_RA of a course less than dpsi_apparent from the "
       "heading at the onset of a give-way duty while the duty lasts (Rule 8(b))", "ours, after the psbmpc's kappa_RA: above the 15° offset's deviation "
       "cost advantage over 30°"),
    _p("dpsi_apparent_deg", 30.0, 0.0, 90.0, "deg", "the smallest course offset that is readily apparent",
       "ours: two of the paper's 15° offset steps; a single 15° step is easily missed on radar (Cockcroft & "
       "Lameijer, Rule 8(b)). The published evaluators also use 30°; this default does not read them"),
    _p("g1", 100.0, 0.0, None, "", "grounding cost G_1 (Tengesdal et al. 2022)", _PSBMPC + " (G_1 = 100)"),
    _p("g3", 2.5, 0.0, None, "1/L", "grounding cost's decay G_3 with the distance beyond d_land",
       _PSBMPC + ": G_3 = 0.25 per metre for its ~10 m own ship, kept per ship length (ours)"),
    _p("g4", 0.07, 0.0, None, "1/(L/U)", "grounding cost's decay G_4 with the prediction time",
       _PSBMPC + ": G_4 = 0.01 per second over its 110 s horizon, a decay of exp(-1.1) at the horizon, kept over "
       "ours (ours: 1.1 / 15 L/U; the KCS's 18.6 s time unit would make it 0.19 per L/U and land at the horizon "
       "cost less than a turn)"),
    _p("d_land", 1.5, 0.0, None, "L", "distance from land inside which the grounding cost is full",
       "ours: 1.5 L, the band 1.5 L inside environment 6's channel in which routes run; the psbmpc uses its "
       "d_safe (50 m for a ~10 m vessel)"),
)
"""The method's parameters (the table's group ``sb-mpc``)."""


def _option(layout, name: str):
    """The structural parameter ``name`` of the layout, or its default in a layout built without options (a
    benchmark's ``Layout(("sb-mpc",) * n)``)."""
    try:
        return layout.option(name)
    except KeyError:
        return next(p.default for p in PARAMS if p.name == name)


def _vessel(layout) -> str:
    """The one hull of the layout's ``sb-mpc`` ships (the reduced model is the hull's)."""
    hulls = {layout.vessel(i) for i in range(layout.n_ships) if layout.methods[i] == NAME}
    if len(hulls) != 1:
        raise ParameterError("vessels", "one vessel for every ship that uses sb-mpc (its prediction model is the "
                             "hull's)", sorted(hulls))
    return hulls.pop()


@functools.lru_cache(maxsize=None)
def _hull(vessel: str, unit: str) -> tuple:
    """Reduced model vector, rpm per U (own units), design rpm and scene scales of ``vessel`` in ``unit``'s scene."""
    ship = load_vessel(vessel).ship
    lam, mu = scene_scales(ship, load_vessel(unit).ship)
    return (reduced_model(vessel).as_vector() + [lam, mu], propeller_rpm_for_speed(1.0, ship), ship.n_design_rpm,
            lam, mu)


RISKY = 5
"""Added to the role code of an encounter once its straight-line passing was inside d_safe (colregs_encounters'
ACTING, reused: the codes stay within what its slots recall)."""


def _role(code):
    """The role of an encounter's code (without :data:`RISKY`; 0 for none)."""
    return code - RISKY * (code > RISKY + 0.5)


def _gives(role):
    """1 for a role in which the own ship gives way: give-way, head-on, overtaking."""
    return (ca.fabs(role - GIVE_WAY) < 0.5) + (ca.fabs(role - HEAD_ON) < 0.5) + (ca.fabs(role - OVERTAKING) < 0.5)


def neighbour_columns(pos, vel, psi, nb_pos, nb_vel, active, P, slots=None) -> dict:
    """What the hazard needs of each neighbour at the decision (:data:`~mmg_casadi.guidance.sb_mpc_cost.NB_ROWS`),
    and the duties of the stand-on and readily apparent terms.

    Parameters
    ----------
    pos, vel : SX (2×1)
        Own position (L) and velocity over the ground (U).
    psi : SX
        Own heading (rad).
    nb_pos, nb_vel : SX (2×M)
        Neighbours' positions and velocities.
    active : SX (1×M)
        Neighbours within the sensing range (0/1).
    P : dict
        The step's parameters (the method's in rad without ``_deg``).
    slots : list of (x, y, code), optional
        The encounter slots of the memory (:data:`SLOT_MEMORY`); without them every role is judged afresh.

    Returns
    -------
    dict
        ``nb`` (len(NB_ROWS) × M), ``hold`` (1×M: a stand-on duty), ``giveway`` (1×M: a give-way, head-on or
        overtaking duty), ``port`` (1×M: a duty that forbids a port alteration), ``role`` (0 where no encounter is open), ``tcpa`` and ``cpa`` (straight-line, at the
        present velocities), ``memory`` (the slot rows after the step, by name; empty without ``slots``),
        ``opened`` (1 when an encounter opened at this step) and ``gave_way`` (1 when a give-way duty was open
        before this step).
    """
    m = nb_pos.size2()
    los = nb_pos - ca.repmat(pos, 1, m)
    d2 = ca.sum1(los * los)
    d = ca.sqrt(ca.fmax(d2, R_MIN ** 2))
    vx, vy = vel[0], vel[1]
    u0 = ca.sqrt(vx * vx + vy * vy)
    nvx, nvy = nb_vel[0, :], nb_vel[1, :]
    ni = ca.sqrt(nvx * nvx + nvy * nvy)
    v_min = P["sb_mpc_v_min"]
    ship = ni > v_min
    # straight-line CPA at the present velocities
    rvx, rvy = nvx - vx, nvy - vy
    rv2 = ca.fmax(rvx * rvx + rvy * rvy, 1e-9)
    tcpa = -(los[0, :] * rvx + los[1, :] * rvy) / rv2
    cx, cy = los[0, :] + rvx * ca.fmax(tcpa, 0), los[1, :] + rvy * ca.fmax(tcpa, 0)
    cpa = ca.sqrt(cx * cx + cy * cy)
    # roles (the bearings of each ship from the other's bow)
    beta = ca.atan2(ca.cos(psi) * los[1, :] - ca.sin(psi) * los[0, :], ca.cos(psi) * los[0, :] + ca.sin(psi) * los[1, :])
    chi_nb = ca.atan2(nvy, nvx)
    alpha = ca.atan2(ca.cos(chi_nb) * -los[1, :] + ca.sin(chi_nb) * los[0, :],
                     ca.cos(chi_nb) * -los[0, :] - ca.sin(chi_nb) * los[1, :])
    role_now = classify_role(beta, alpha, psi, chi_nb, u0, ni, theta_head_on=P["sb_mpc_phi_ho"], stern=STERN)
    # encounters: a ship closing within t_duty with a straight-line passing inside d_close opens one, with the role
    # of the onset, kept (in a slot of the memory) while she closes; its code is the role, plus RISKY once the
    # passing is inside d_safe (a risk of collision as the planner sees it) within t_duty for a stand-on ship,
    # within the horizon for a give-way one: from then on it gives the own ship a duty
    closing = active * ship * (tcpa > 0)
    opens = closing * (tcpa < P["sb_mpc_t_duty"]) * (cpa < P["sb_mpc_d_close"])
    memory = {}
    if slots is None:
        code, opened, gave_way = opens * role_now, ca.SX(0), ca.SX(0)
    else:
        link, code = recall(nb_pos, closing, slots)
        gave_way = ca.sum2(_gives(_role(code)) * (code > RISKY + 0.5)) > 0 if m else ca.SX(0)  # before the step
        opened = ca.sum2(opens * (1 - sum(link))) > 0 if m else ca.SX(0)  # an encounter opens at this step
        link, code = open_encounters(nb_pos, opens, role_now, link, code)
    stands = (ca.fabs(_role(code) - STAND_ON) < 0.5) + (ca.fabs(_role(code) - OVERTAKEN) < 0.5)
    within = ca.if_else(stands, P["sb_mpc_t_duty"], P["sb_mpc_horizon"])
    risky_now = closing * (cpa < P["sb_mpc_d_safe"]) * (tcpa < within)
    code = code + RISKY * risky_now * (code > 0.5) * (code < RISKY + 0.5)  # the risk arises: mark it
    if slots is not None:
        memory = {k.replace("cv_", "sb_"): v for k, v in remember(nb_pos, link, code, psi).items()}
    role = _role(code)
    duty = closing * (code > RISKY + 0.5)
    stand_on = (ca.fabs(role - STAND_ON) < 0.5) + (ca.fabs(role - OVERTAKEN) < 0.5)
    free = (d < P["sb_mpc_r_free"]) * (cpa < P["sb_mpc_d_safe"]) * (tcpa < P["sb_mpc_t_free"])
    hold = duty * stand_on * (1 - free)
    giveway = duty * _gives(role)
    gw_side = duty * ((ca.fabs(role - GIVE_WAY) < 0.5) + (ca.fabs(role - HEAD_ON) < 0.5))
    # no alteration to port: head-on (Rule 14(a)), crossing give-way (Rule 15) and crossing stand-on once free
    # (Rule 17(c))
    port = gw_side + duty * (ca.fabs(role - STAND_ON) < 0.5) * free
    # a neighbour that cannot come within d_close over the horizon has no hazard to evaluate
    reach = P["sb_mpc_d_close"] + (u0 + ni) * P["sb_mpc_horizon"]
    relevant = active * (d2 < reach * reach)
    # transitional indicators at the decision (Hagen et al. 2018, as the group's update_transitional_variables)
    cos_ot, cos_ho, cos_cr = ca.cos(P["sb_mpc_phi_ot"]), ca.cos(P["sb_mpc_phi_ho"]), ca.cos(P["sb_mpc_phi_cr"])
    dot = vx * nvx + vy * nvy
    ahead = (vx * los[0, :] + vy * los[1, :]) > ca.cos(P["sb_mpc_phi_ah"]) * u0 * d
    close = d < P["sb_mpc_d_close"]
    s0 = (ca.cos(psi) * los[1, :] - ca.sin(psi) * los[0, :]) > 0
    si0 = (nvx * -los[1, :] - nvy * -los[0, :]) > 0
    moving = (u0 > v_min) * ship
    o0 = (dot > cos_ot * u0 * ni) * (ni < u0) * ship * close * ahead
    q0 = (dot > cos_ot * u0 * ni) * (u0 < ni) * (u0 > v_min) * close * (1 - ahead)
    cos_p = math.cos(STERN)
    passed = (((vx * los[0, :] + vy * los[1, :]) < cos_p * u0 * d) * (1 - q0)
              + ((nvx * -los[0, :] + nvy * -los[1, :]) < cos_p * ni * d) * (1 - o0) > 0) * (d > P["sb_mpc_d_safe"])
    h0 = (dot < -cos_ho * u0 * ni) * moving * ahead
    x0 = (dot < cos_cr * u0 * ni) * (1 - h0) * (1 - passed) * moving
    d_safe = ca.if_else(ship, ca.if_else(hold, P["sb_mpc_d_standon"], P["sb_mpc_d_safe"]), P["sb_mpc_d_obstacle"])
    nb = ca.vertcat(los, nb_vel, ni, relevant, s0, si0, o0, q0, h0, x0, d_safe, gw_side)
    assert nb.size1() == len(NB_ROWS)
    return {"nb": nb, "hold": hold, "giveway": giveway, "port": port, "role": role, "tcpa": tcpa, "cpa": cpa,
            "memory": memory, "opened": opened, "gave_way": gave_way}


def _land_near(pos, walls, reach):
    """1 when a wall or land segment lies within ``reach`` of ``pos``."""
    near = 0
    for j in range(walls.size2()):
        a, b = walls[0:2, j], walls[2:4, j]
        e = b - a
        s = ca.fmin(ca.fmax(ca.dot(pos - a, e) / ca.fmax(ca.dot(e, e), 1e-12), 0), 1)
        near = near + (ca.sumsqr(pos - a - s * e) < reach * reach)
    return near > 0


def decision_inputs(g, vessel: str) -> dict:
    """The arguments of the decision Function (:func:`~mmg_casadi.guidance.sb_mpc_cost.plan_function`) for one
    ship's guidance inputs, without ``due`` and ``held``; also what the command needs.

    Parameters
    ----------
    g : GuidanceInputs
        The ship's guidance inputs (the method's memory, the step's parameters).
    vessel : str
        The ship's hull.

    Returns
    -------
    dict
        ``args`` (list), ``engaged``, ``level_last``, ``course_held``, ``fresh``, ``rpm`` (per level), ``walls``,
        ``chi_wp`` (the course to the waypoint), ``slots`` (the encounter slots after the step), ``opened`` (an
        encounter opened at this step) and ``base`` (the ``sb_base`` row after the step).
    """
    P = g.P
    model, rpm_per_u, n_design, _, mu = _hull(vessel, g.layout.unit_vessel())
    state = g.memory["sb_state"]
    fresh = state < CODE / 2
    level_last = ca.if_else(fresh, 0, ca.floor(state - CODE + 0.5))
    course_held = ca.if_else(fresh, g.psi, g.memory["sb_course"])
    chi_wp = ca.atan2(g.goal[1] - g.pos[1], g.goal[0] - g.pos[0])
    dead_slow = P["engine_dead_slow"] * n_design
    rpm = [ca.fmax(f * g.service_rpm, dead_slow) for f in LEVELS]
    speeds = [r / rpm_per_u * mu for r in rpm]
    slots = [(g.memory[f"sb_slot{k}_x"], g.memory[f"sb_slot{k}_y"], g.memory[f"sb_slot{k}_code"])
             for k in range(SLOTS)] if "sb_slot0_x" in g.memory else None
    cols = neighbour_columns(g.pos, g.vel, g.psi, g.nb_pos, g.nb_vel, g.active, P, slots)
    m = g.nb_pos.size2()
    engaged = ca.sum2(g.active) > 0 if m else ca.SX(0)
    walls = g.walls if g.walls is not None and g.walls.size2() else None
    if walls is not None:
        reach = P["sb_mpc_horizon"] * g.speed + P["sb_mpc_d_land"]
        engaged = ca.logic_or(engaged, _land_near(g.pos, walls, reach))
    own = ca.vertcat(g.pos, g.psi, g.speed, chi_wp, level_last, course_held, P["sb_mpc_horizon"], *speeds,
                     P["sb_mpc_p"])
    so_any = ca.sum2(cols["hold"]) > 0 if m else ca.SX(0)
    ra_any = ca.sum2(cols["giveway"]) > 0 if m else ca.SX(0)
    base = ca.if_else(cols["gave_way"], g.memory["sb_base"], g.psi) if "sb_base" in g.memory else g.psi
    port_any = ca.sum2(cols["port"]) > 0 if m else ca.SX(0)
    costs = ca.vertcat(P["sb_mpc_kappa_so"], P["sb_mpc_kappa_ra"], P["sb_mpc_k_p"], P["sb_mpc_k_chi_strb"],
                       P["sb_mpc_k_chi_port"], P["sb_mpc_k_dp"], P["sb_mpc_k_dchi_strb"], P["sb_mpc_k_dchi_port"],
                       so_any, ra_any, P["sb_mpc_dpsi_keep"], P["sb_mpc_dpsi_apparent"], P["sb_mpc_kappa_port"],
                       port_any, base)
    pair = ca.vertcat(P["sb_mpc_d_safe"], P["sb_mpc_d_close"], P["sb_mpc_k_coll"], P["sb_mpc_kappa"],
                      P["sb_mpc_kappa_tc"], ca.cos(P["sb_mpc_phi_ah"]), ca.cos(P["sb_mpc_phi_ot"]),
                      ca.cos(P["sb_mpc_phi_ho"]), ca.cos(P["sb_mpc_phi_cr"]), P["sb_mpc_v_min"], P["sb_mpc_dv_min"],
                      P["sb_mpc_k_mean"], P["sb_mpc_kappa_gw"])
    ground = ca.vertcat(P["sb_mpc_g1"], P["sb_mpc_g3"], P["sb_mpc_g4"], P["sb_mpc_d_land"])
    gains = ca.vertcat(P["kp"], P["kd"], P["delta_max"])
    args = [own, cols["nb"], ca.DM(model), gains, costs, pair, ground] + ([walls] if walls is not None else [])
    return {"args": args, "engaged": engaged, "level_last": level_last, "course_held": course_held,
            "fresh": fresh, "rpm": rpm, "walls": walls, "chi_wp": chi_wp, "slots": cols["memory"],
            "opened": cols["opened"], "base": ca.if_else(ra_any, base, g.psi)}


def sb_mpc_command(g) -> Command:
    """The builder of ``sb-mpc`` (module notes): the course and propeller speed of the behaviour held, decided
    afresh every ``sb_mpc_interval``.

    Parameters
    ----------
    g : GuidanceInputs
        One ship's guidance inputs.

    Returns
    -------
    Command
        Unit heading vector of the course held, its level's propeller speed and the memory rows
        (:data:`MEMORY`).
    """
    lay, P = g.layout, g.P
    d = decision_inputs(g, _vessel(lay))
    clock = g.memory["sb_clock"]
    due = ca.logic_and(d["engaged"], ca.logic_or(ca.logic_or(d["fresh"], clock > P["sb_mpc_interval"] - 1e-9),
                                                 d["opened"]))
    held = ca.vertcat(d["course_held"], d["level_last"], 0)
    samples, substeps = _option(lay, "sb_mpc_samples"), _option(lay, "sb_mpc_substeps")
    n_walls = d["walls"].size2() if d["walls"] is not None else 0
    plan = plan_function(g.nb_pos.size2(), samples, substeps, n_walls)
    out = plan(due, held, *d["args"])
    course, level = out[0], out[1]
    rpm = ca.if_else(level < 0.5, d["rpm"][0], ca.if_else(level < 1.5, d["rpm"][1], d["rpm"][2]))
    state = ca.if_else(d["engaged"], CODE + level, 0)
    memory = {"sb_course": course, "sb_state": state,
              "sb_clock": ca.if_else(due, P["dt"], clock + P["dt"]), "sb_base": d["base"], **d["slots"]}
    return Command(ca.vertcat(ca.cos(course), ca.sin(course)), rpm, memory)


def engaged(memory: dict):
    """1 while the method holds a behaviour (a neighbour within its range, or land within its reach), so the closed
    loop keeps it in charge beyond R_safe (``Method.engaged``).

    Parameters
    ----------
    memory : dict
        The method's memory rows after the step.

    Returns
    -------
    SX or bool
        1 or 0.

    Examples
    --------
    >>> int(engaged({"sb_state": CODE + 1})), int(engaged({"sb_state": 0.4}))
    (1, 0)
    """
    return memory["sb_state"] > CODE / 2
