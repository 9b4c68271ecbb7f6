"""The parameter table: one declaration per parameter of the closed loop (default, range, unit, meaning, source).

Everything else is derived from :data:`PARAMETERS`: the defaults and range checks of the parameter dataclasses
(:class:`~mmg_casadi.guidance.ilos.IlosParams`, :class:`~mmg_casadi.guidance.heading_control.PdHeadingParams`, the field parameter
classes of :mod:`mmg_casadi.guidance.fields`), the keys a scenario file's ``[settings]`` table and a ``--params`` file
accept, the CLI help, the README table (:func:`markdown_table`) and the resolved parameter set every run writes
into its outputs (:func:`resolve`).

Units: lengths in ship lengths L, times in L/U (U the design speed), angles in degrees (as in scenario files; the
closed loop converts them to rad).

Examples
--------
>>> PARAMETERS["r_safe"].default, PARAMETERS["r_safe"].unit
(15.0, 'L')
>>> resolve({"kp": 2.0})["kp"], resolve()["kd"]
(2.0, 4.0)
>>> resolve({"kd": -1.0})
Traceback (most recent call last):
...
mmg_casadi.errors.ParameterError: kd: expected a number in [0, inf) L/U, got -1.0
"""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

from mmg_casadi.colregs.profiles import SCORING_PROFILES
from mmg_casadi.errors import InputError, ParameterError
from mmg_casadi.param_spec import Param, _is_real
from mmg_casadi.traffic.mix import ALLOWED as TARGETS_ALLOWED, parse_targets
from mmg_casadi.vessel.library import VESSELS

GROUPS = ("simulation", "vessel", "ilos", "pd", "inverse-square", "sink-vortex", "modified-vortex", "colregs-vortex",
          "walls", "velocity-obstacle", "outcome", "environment", "traffic", "perception")
"""Parameter groups of the shipped table, in the order of the README table; a method's guidance uses its own
group(s). A method that declares its own parameters (``Method.params``) adds a group
named after it while it is registered (:func:`groups`)."""

CLOSED_LOOP_GROUPS = ("simulation", "vessel", "ilos", "pd", "walls", "outcome", "environment", "traffic", "perception")
"""Groups every run reads whatever its methods; every other group holds the parameters of methods (the groups a
:class:`~mmg_casadi.guidance.methods.Method` lists), which a run may set only if one of its ships uses such a
method (:func:`mmg_casadi.guidance.methods.check_used`)."""

_METHOD_GROUPS: dict[str, tuple[str, ...]] = {}
"""Groups added by registered methods: group name -> the names of its parameters (:func:`add_group`)."""


_P = Param
_REAL = dict(low=None, high=None)

TARGET_METHODS = ("inverse-square", "sink-vortex", "modified-vortex", "velocity-obstacle", "velocity-obstacle-speed",
                  "colregs-vortex", "sb-mpc", "nmpc")
"""Methods the sampled target ships of a study may use whatever the study's method (parameter ``targets``): the
shipped avoiding methods (:data:`mmg_casadi.guidance.methods.AVOIDING` and the on-demand ones; a test keeps the
lists equal)."""
TARGETS_TEXT = TARGETS_ALLOWED.replace("avoid, hold or ", f"avoid, hold, a method ({', '.join(TARGET_METHODS)}) or ",
                                       1)
"""The allowed values of ``targets``, in words."""


def parse_study_targets(value, field: str = "targets", cls=InputError) -> str:
    """``value`` checked as a value of ``targets``: ``avoid``, ``hold``, a method of :data:`TARGET_METHODS` or a
    mix (:func:`mmg_casadi.traffic.mix.parse_targets`).

    Parameters
    ----------
    value : object
        The value given.
    field : str
        Name in the error message.
    cls : type
        Error raised (an :class:`~mmg_casadi.errors.InputError` subclass).

    Returns
    -------
    str
        The value (a mix in its canonical form).

    Examples
    --------
    >>> parse_study_targets("colregs-vortex"), parse_study_targets("mix:hold=0.5, avoid=0.5")
    ('colregs-vortex', 'mix:hold=0.5,avoid=0.5')
    """
    if isinstance(value, str) and value in TARGET_METHODS:
        return value
    try:
        return parse_targets(value, field)
    except InputError:
        raise cls(field, TARGETS_TEXT, value) from None


PARAMETERS: dict[str, Param] = {p.name: p for p in (
    # simulation
    _P("dt", 0.25, 0.0, 2.0, "L/U", "guidance step; the rudder command is held over it (RK4, one step)",
       "our choice: the paper gives no guidance rate; 0.25 L/U ≈ 4.7 s", "simulation", low_open=True),
    _P("t_max", 300.0, 0.0, 10000.0, "L/U", "horizon of a run", "our choice: every paper scenario ends well before",
       "simulation", low_open=True),
    _P("r_safe", 15.0, 0.0, None, "L", "safe radius R_safe: inside it the reactive method replaces ILOS",
       "paper Table 3 (R_safe = 15 L)", "simulation", low_open=True),
    _P("collision_distance", 2.0, 0.0, None, "L", "ship centres (or a ship and an obstacle centre) closer than "
       "this collide", "paper §Statistical Analysis (collision within 2 L)", "simulation", low_open=True),
    _P("goal_tolerance", 3.0, 0.0, None, "L", "waypoint acceptance radius R_tol; the goal is reached within it",
       "paper Table 2 (R_tol = 3 L)", "simulation", low_open=True),
    _P("fleet_from_ships", 16, 2, None, "", "a scenario of at least this many ships runs the fleet step (one "
       "ship's step mapped over the fleet; compile cost independent of the fleet) instead of the unrolled step",
       "our choice from benchmarks/fleet_scaling.py: the unrolled step compiles in 12/37/73/144 s at 10/20/30/40 "
       "ships, the fleet step in 3-4 s; per ship-step 18-27 µs vs 8-21 µs; every paper scenario (<= 10 ships) "
       "stays unrolled", "simulation", kind="int", structural=True),
    _P("neighbour_slots", 16, 1, 64, "", "neighbours a ship of the fleet step sees: the nearest within the "
       "candidate radius R_safe + 2 V_max T_chunk; with more, the farther ones are ignored (counted)",
       "our choice: 4 × the about 3.5 candidates expected at environment 5's density within 25 L",
       "simulation", kind="int", structural=True),
    _P("ship_radius", 0.5, 0.0, None, "L", "radius of another ship as an inverse-square obstacle",
       "our choice: half a ship length, like the paper's static obstacles", "simulation", low_open=True),
    # vessel and engine
    _P("vessel", "kcs", None, None, "", "hull of every ship that names none (scenario files: per-ship "
       "'vessel')", "paper §2: the KRISO Container Ship (mmg_casadi.vessel.library)", "vessel", kind="choice",
       choices=VESSELS, structural=True),
    _P("engine_rate_rpm_s", 1.0, 0.0, None, "rpm/s", "largest rate at which the engine changes propeller speed "
       "towards a method's command (methods that command no speed keep the service rpm exactly)",
       "our choice: the KCS's service 115.5 rpm to stop in about 2 min", "vessel"),
    _P("engine_lag_s", 10.0, 0.0, None, "s", "time constant of the engine's first-order response to an rpm "
       "command", "our choice: a slow-speed two-stroke diesel under its governor answers a telegraph order within "
       "tens of seconds; the rate limit dominates large orders", "vessel"),
    _P("engine_dead_slow", 0.25, 0.0, 1.0, "", "lowest propeller speed a method may command (dead slow ahead), "
       "as a fraction of the vessel's design rpm", "our choice: dead slow ahead of a 24-kn container ship is about "
       "5-7 kn, 0.2-0.3 of its design speed", "vessel", low_open=True),
    _P("engine_rpm_max", 1.05, 1.0, 2.0, "", "highest propeller speed a method may command, as a fraction of the "
       "vessel's design rpm", "our choice: the maximum continuous rating a few per cent above the design (service) "
       "rpm", "vessel"),
    # ILOS
    _P("ilos_delta", 2.0, 0.0, None, "L", "ILOS look-ahead distance Δ (K_p^g = 1/Δ)", "paper Table 2", "ilos",
       low_open=True),
    _P("ilos_k", 0.05, 0.0, None, "", "ILOS integral ratio k (K_i^g = k K_p^g)", "paper Table 2", "ilos"),
    # PD heading control
    _P("kp", 3.5, 0.0, None, "", "PD heading gain K_p^c (rad of rudder per rad of heading error)",
       "paper Table 2", "pd", low_open=True),
    _P("kd", 4.0, 0.0, None, "L/U", "PD derivative gain K_d^c on the measured yaw rate", "paper Table 2", "pd"),
    _P("delta_max_deg", 35.0, 0.0, 45.0, "deg", "rudder command saturation",
       "paper §3 (KCS rudder limit 35°)", "pd", low_open=True),
    # inverse-square APF
    _P("k_att", 50.0, 0.0, None, "1/(L/U)", "attractive gain of the inverse-square field",
       "paper Table 3", "inverse-square"),
    _P("k_rep", 200000.0, 0.0, None, "L³/(L/U)", "repulsive gain of the inverse-square field",
       "paper Table 3", "inverse-square"),
    _P("d0", 8.0, 0.0, None, "L", "influence distance of an obstacle, from its rim", "our choice: puts the "
       "stagnation point of the paper's field example 5.4 L from the obstacle (paper: about 5 L)",
       "inverse-square", low_open=True),
    # sink-vortex APF
    _P("k_vor", -10.0, **_REAL, unit="L²/(L/U)", meaning="vortex strength K at every active neighbour "
       "(< 0 turns a head-on ship to starboard)", source="paper Table 3", group="sink-vortex"),
    _P("lam_sink", -100.0, None, 0.0, "L²/(L/U)", "sink strength Λ at the goal (< 0 attracts)",
       "paper Table 3", "sink-vortex", high_open=True),
    # modified sink-vortex APF
    _P("k_vor0", -10.0, **_REAL, unit="L²/(L/U)", meaning="nominal vortex strength K⁰_vor of the modified "
       "vortex, eq. (modified_vortex)", source="paper Table 3", group="modified-vortex"),
    _P("r_tol_vortex", 2.0, 0.0, None, "L", "R_tol of the tangential-velocity threshold −2 R_tol v_r / d",
       "laboratory code (the collision distance; the paper writes R_tol)", "modified-vortex"),
    _P("gamma_max_deg", 112.5, 0.0, 180.0, "deg", "largest |relative bearing γ| at which the vortex acts",
       "COLREG Rule 13: the 112.5° that leaves the stern sector (22.5° abaft the beam) without vortex",
       "modified-vortex", low_open=True),
    # colregs-vortex (the modified vortex plus Rules 8, 13 and 17; mmg_casadi.guidance.colregs_vortex)
    _P("cv_theta_head_on_deg", 22.5, 0.0, 90.0, "deg", "head-on tolerance on the bearing and on the course "
       "difference from reciprocal", "the paper laboratory's head-on sector 7π/8–9π/8 of relative heading",
       "colregs-vortex", low_open=True, high_open=True),
    _P("cv_d_cpa_act", 3.0, 0.0, None, "L", "the stand-on ship acts alone when its passing distance at the present "
       "velocities is below this (Rule 17(a)(ii))", "our choice: 1.5 × the 2 L collision distance, below the ≈ 4 L the modified "
       "vortex's give-way action aims at", "colregs-vortex", low_open=True),
    _P("cv_t_act", 4.0, 0.0, None, "L/U", "TCPA below which the give-way ship's inaction is apparent and the "
       "stand-on ship acts alone (Rule 17(a)(ii))", "Cockcroft & Lameijer, A Guide to the Collision Avoidance "
       "Rules, 7th ed., on Rule 17: in open sea a give-way ship that has not acted by about 2 nm in a crossing of "
       "two merchant ships has usually waited too long, i.e. when a substantial alteration no longer completes "
       "well before the CPA; for the KCS a 60° alteration takes 3.7 L/U (≈ 75 s at 4 L/U); the iitm-lab scoring "
       "profile's late_tcpa has the same number, which this default does not read", "colregs-vortex",
       low_open=True),
    _P("cv_r_act", 8.0, 0.0, None, "L", "range below which the overtaken ship acts alone whatever the TCPA (slowly "
       "closing overtakers), and within which a stand-on ship keeping her course circles a static obstacle", "our choice: 4 collision distances", "colregs-vortex", low_open=True),
    _P("cv_t_close", 3.0, 0.0, None, "L/U", "TCPA at which the stand-on action reaches full strength (Rule 17(b))",
       "our choice: about the KCS's 90° turn time with full rudder", "colregs-vortex", low_open=True),
    _P("cv_k_standon", 1.0, 0.0, None, "L/(L/U)", "strength of the stand-on escape term at the trigger",
       "our choice: the paper's sink (Λ = −100) at the 15 L detection range", "colregs-vortex", low_open=True),
    _P("cv_dpsi_min_deg", 30.0, 0.0, 90.0, "deg", "smallest alteration from the heading at the onset of a give-way "
       "duty or of the stand-on action (Rule 8, readily apparent)", "our choice: an alteration another ship sees at "
       "once by eye and radar (Rule 8(b)); Cockcroft & Lameijer (p. 51) count alterations under 10° unlikely to be "
       "readily apparent, and the KCS completes 30° in 2.5 L/U; the published evaluators' readily apparent "
       "alteration (Hagen et al. 2023) has the same number, which this default does not read", "colregs-vortex"),
    _P("cv_d_risk", 4.0, 0.0, None, "L", "risk of collision (Rule 7), the onset of an encounter: a ship within R_safe "
       "whose straight-line passing distance at the present velocities is below this while the range closes; a "
       "head-on or crossing give-way ship alters at least until her straight line passes at this (Rule 16)",
       "our choice: twice the paper's 2 L collision distance (§Statistical Analysis), a passing with less than one "
       "collision distance of clearance (the iitm-lab scoring profile's gate d_risk has the same number; this "
       "default does not read it)", "colregs-vortex", low_open=True),
    _P("cv_r_look", 0.0, 0.0, None, "L", "how far beyond R_safe colregs-vortex sees a ship it must give way to "
       "(head-on, crossing from starboard, overtaking): with a risk of collision (cv_d_risk) within R_safe + cv_r_look "
       "such a ship opens the give-way duty there, and the method steers while that encounter lasts; stand-on "
       "encounters and every other term keep R_safe; 0 = off", "COLREG Rules 7(b) (long-range scanning for early "
       "warning of risk of collision) and 16 (early action). Off by default, measured in environment 5 (5000 runs, "
       "seed 0, paired against 0): 3 L, success 98.84 -> 99.30 % (McNemar p = 0.002), risky encounters kept "
       "(iitm-lab) -2.2 pp (p = 0.0005; stand-on 82.4 -> 71.4 %); 7 L, 99.22 % (p = 0.03), -5.6 pp, ntnu-2023 "
       "+3.1 pp: a give-way turn far out is no duty the iitm-lab scorer sees, so it counts against the ship's "
       "stand-on duties to third ships", "colregs-vortex"),
    _P("cv_d_clear", 6.0, 0.0, None, "L", "a give-way ship holds its alteration until the planned-course passing "
       "distance exceeds this", "our choice: 3 collision distances", "colregs-vortex", low_open=True),
    _P("cv_v_ship_min", 0.05, 0.0, None, "U", "slower neighbours are static obstacles without a COLREG role, and a "
       "ship that closes more slowly than this is past (alongside on a parallel course her CPA never comes)",
       "our choice: below the slowest ship speed a scenario allows (0.2)", "colregs-vortex", low_open=True),
    _P("cv_r_guard", 5.0, 0.0, None, "L", "range inside which a static obstacle, and a ship while she is a risk of collision (closing, passing below "
       "cv_d_risk) or within the collision distance, also repels radially (last resort)",
       "our choice: about the KCS's advance in a 90° turn plus the collision distance", "colregs-vortex",
       low_open=True),
    _P("cv_lam_guard", 15.0, 0.0, None, "L²/(L/U)", "strength of that radial repulsion λ (1/d − 1/r_guard)",
       "our choice: 2 at 3 L, about twice the capped sink", "colregs-vortex"),
    _P("cv_d_att_floor", 15.0, 0.0, None, "L", "while anything is avoided the goal attracts at most as from this "
       "distance (the paper's near-goal failure)", "our choice: R_safe, the range at which avoidance starts",
       "colregs-vortex"),
    _P("cv_r_cq", 8.0, 0.0, None, "L", "range within which a neighbour's collision cone filters the heading "
       "(Rule 17(b) close quarters; 0 disables)", "our choice: cv_r_act's 8 L, the range at which the stand-on ship "
       "acts whatever the TCPA", "colregs-vortex"),
    _P("cv_d_cq", 3.0, 0.0, None, "L", "combined radius of those collision cones (linear velocity obstacle, Huang "
       "et al. 2018); for a ship the own ship holds her course for, while the TCPA is above cv_t_act, r_tol_vortex "
       "instead (the filter acts only on a collision course while the give-way ship can still act)",
       "our choice: 1.5 × the 2 L collision distance, as cv_d_cpa_act", "colregs-vortex",
       low_open=True),
    _P("cv_dpsi_cq_deg", 45.0, 0.0, 180.0, "deg", "the filter judges the heading the ship turns through next, at most "
       "this far from its own on the way to the field's", "our choice: about the KCS's turn in half of cv_t_close; "
       "beyond 10° of heading error the PD's rudder is saturated anyway", "colregs-vortex", low_open=True),
    _P("cv_dpsi_free_deg", 15.0, 0.0, 180.0, "deg", "while no neighbour is within R_safe (ILOS steers) and "
       "the waypoint is farther than R_safe, or a neighbour is within R_safe but nothing is avoided and nothing is "
       "within cv_r_cq, the heading ordered is at most this far from the present one (a moderate turn; 180 = no "
       "limit)",
       "measured: the largest order ahead, in 5° steps, from whose steady turn (11.4°/(L/U)) the KCS under the "
       "closed loop's PD swings on by less than 10° when ordered to check her swing (6.9°; 20° ahead: 10.0°), the "
       "smallest alteration Cockcroft & Lameijer (p. 51) count as readily apparent (tests/test_colregs_vortex.py)",
       "colregs-vortex", low_open=True),
    _P("cv_speed_cut", 0.5, 0.0, 1.0, "", "fraction of the propeller speed a stand-on ship takes off while she acts "
       "alone for a ship crossing from port (Rule 17(a)(ii), with the starboard escape)", "our choice: half the "
       "propeller speed, the engine order from full to half ahead (Rule 8(b), (e)); the published evaluators' "
       "readily apparent speed reduction (Hagen et al. 2023) has the same number, which this default does not read",
       "colregs-vortex",
       high_open=True),
    _P("cv_speed_giveway", 0.0, 0.0, 1.0, "", "fraction of the propeller speed a give-way ship takes off while her "
       "alteration alone still leads into close quarters (passing distance below cv_d_cpa_act at a TCPA below "
       "cv_t_act; Rule 8(e) slackening speed); 0 = off", "COLREG Rule 8(e). Off by default, measured: environment "
       "5, 1000 paired runs, 0.5 changes success 99.3 -> 98.9 % (4 runs lost, none gained, McNemar p = 0.13) and "
       "with targets that hold 95.0 -> 94.6 % (p = 0.13): the KCS slowed by its engine turns away later in time",
       "colregs-vortex", high_open=True),
    _P("cv_speed_extremis", 0.0, 0.0, 1.0, "", "fraction of the propeller speed taken off in extremis, while no "
       "heading within cv_dpsi_cq_deg of the present one avoids the collision cones within cv_r_cq at the present "
       "speed but one does at the reduced speed (1 = down to dead slow ahead, the least the engine model gives); "
       "0 = off", "COLREG Rules 17(b) and 8(e). Off by default, measured: environment 5, 1000 paired runs, 1.0 "
       "changes success 99.3 -> 99.0 % (3 lost, none gained, p = 0.25); with cv_speed_giveway = 0.5 as well "
       "99.3 -> 98.6 % (7 lost, none gained, p = 0.016) and, targets holding, 95.0 -> 94.2 % (p = 0.008)",
       "colregs-vortex"),
    # channel walls
    _P("wall_lam", 10.0, 0.0, None, "L²/(L/U)", "line-source strength of a channel wall",
       "paper §Narrow Waterways (Λ = 10)", "walls"),
    _P("wall_d_act", 2.0, 0.0, None, "L", "perpendicular distance below which a wall acts",
       "paper §Narrow Waterways", "walls", low_open=True),
    _P("grounding_margin", 0.0, 0.0, None, "L", "a ship grounds when her centre comes within half her beam plus "
       "this margin of land ([[land]] edges; channel walls keep the hull's side)", "our choice: 0, the hull's side "
       "at the coastline, as the paper's walls; a margin stands for the bank and under-keel clearance a chart's "
       "depth contour leaves out", "walls"),
    _P("land_lookahead", 2.0, 0.0, None, "advances", "in layouts with land, a method takes over from ILOS while "
       "the ship's straight path ahead over this many advances of her own hull (90° turn at her largest rudder "
       "angle from her design speed; 3.56 L for the KCS: 7.1 L, 7.1 L/U at her design speed) comes within half "
       "her beam + grounding_margin + land_clearance of land (mmg_casadi.guidance.land_ahead)", "our choice: "
       "within one advance a ship can no longer turn parallel to a coast ahead; two leave room for the rudder to "
       "come over and for a turn short of hard-over", "walls", low_open=True),
    _P("land_clearance", 1.0, 0.0, None, "L", "clearance from land beyond half the beam + grounding_margin that "
       "the path ahead of the land look-ahead keeps", "our choice: as vo_land_margin, half the 2 L collision "
       "distance (paper §Statistical Analysis)", "walls"),
    _P("route", "as-given", None, None, "", "'plan': every ship's route is replaced by the shortest one that "
       "clears every land polygon by route_clearance (a visibility graph over the buffered polygons, "
       "mmg_casadi.scenarios.route_plan); 'as-given': the waypoints as written, each leg checked against the land",
       "our choice", "walls", kind="choice", choices=("as-given", "plan")),
    _P("route_clearance", 2.0, 0.0, None, "L", "least distance of a planned route from land (route = 'plan')",
       "our choice: the 2 L collision distance, more than the land look-ahead's half beam + land_clearance "
       "(1.07 L for the KCS), so a ship on her planned route is not taken from ILOS for the land beside it",
       "walls", low_open=True),
    _P("channel_width", 20.0, 0.0, None, "L", "widest channel (bank to bank across the route) in which a method "
       "that keeps Rule 9 (colregs-vortex) keeps to its starboard side", "our choice: includes the paper's 10 L "
       "channel, environment 6's 8-16 L straits and the fjord's 6 L channels, and leaves out water wider than "
       "the 2 × R_safe (30 L) across which the guidance sees both banks", "walls", low_open=True),
    _P("bank_clearance", 3.0, 0.0, None, "L", "distance from the starboard bank of a narrow channel of the lane "
       "a method that keeps Rule 9 follows (the centre line in a channel narrower than twice this)", "our choice: "
       "the paper's wall field acts within 2 L (wall_d_act), so in the lane the bank does not push the ship back "
       "to the centre line; two ships in their lanes of an 8 L strait pass 4 L apart, twice the collision "
       "distance", "walls", low_open=True),
    # velocity obstacle
    _P("vo_candidates", 80, 1, 720, "", "candidate headings of the velocity obstacle (at the current speed)",
       "our choice: 4.5° resolution (at most 0.5°: the compiled loop grows with the count)", "velocity-obstacle",
       kind="int", structural=True),
    _P("vo_cone", "huang", None, None, "", "cone half-angle about the neighbour's centre, D = collision_distance: "
       "'huang' asin(D/d) (exact linear VO) or 'wide' 2·atan(D/d) (a superset)", "Huang et al. 2018 (Ocean Eng. "
       "151), the LVO the paper follows (§Dynamic Obstacle Avoidance); 'wide' is the laboratory's later version",
       "velocity-obstacle", kind="choice", choices=("huang", "wide"), structural=True),
    _P("vo_hold", True, None, None, "", "keep the chosen heading while it stays outside every cone (re-pick when "
       "it becomes forbidden or no neighbour is within R_safe); false: re-pick the goal-closest every step",
       "paper §Statistical Analysis (the VO 'maintains this velocity until it steers clear')",
       "velocity-obstacle", kind="bool", structural=True),
    _P("vo_speed_levels", 4, 2, 16, "", "speed levels of 'velocity-obstacle-speed': propeller speeds evenly "
       "spaced from the service rpm down to dead slow ahead (engine_dead_slow), each searched over every candidate "
       "heading ('velocity-obstacle' keeps its speed)", "our choice: the four ahead orders of an engine telegraph "
       "(full, half, slow, dead slow ahead); for the KCS at its design speed 1, 0.75, 0.5 and 0.25 U",
       "velocity-obstacle", kind="int", structural=True),
    _P("vo_speed_weight", 0.0, 0.0, None, "", "extra cost of slowing down in 'velocity-obstacle-speed', per unit of "
       "speed reduction (fraction of the service speed), added to |v - v_pref| / V_service (v_pref: the service "
       "speed towards the goal)", "the velocity-obstacle selection rule, the admissible velocity closest to the "
       "preferred one (Fiorini & Shiller 1998, Int. J. Robot. Res. 17(7); van den Berg et al. 2008, ICRA), "
       "without extra weight; > 0 prefers course alterations (COLREG Rule 8(b)) over slowing (Rule 8(e))",
       "velocity-obstacle"),
    _P("vo_land_horizon", 10.0, 0.0, None, "L/U", "land test of the velocity obstacle (both methods) and of "
       "colregs-vortex's velocity-obstacle steps, in layouts with walls or land only: a heading whose straight "
       "path at the present speed over this time comes within half the beam plus vo_land_margin of a wall or land "
       "edge is inadmissible", "our choice: at the design speed 10 L, over twice the largest advance in a 90° turn "
       "the IMO manoeuvring standards allow (4.5 L, MSC.137(76)), two thirds of R_safe; from the centre of the "
       "8 L strait of environment 6 it leaves headings within about 17° of the strait's axis",
       "velocity-obstacle", low_open=True),
    _P("vo_land_margin", 1.0, 0.0, None, "L", "clearance the land test's path keeps from a wall or land edge "
       "beyond the ship's half beam", "our choice: half the 2 L collision distance, the room another ship's centre "
       "is given by the cone's combined radius of two ships (paper §Statistical Analysis)", "velocity-obstacle"),
    # outcome
    _P("stall_window", 50.0, 0.0, None, "L/U", "a run that made no progress towards its goal for this long "
       "before t_max is 'stalled'", "our choice", "outcome", low_open=True),
    _P("near_goal_distance", 10.0, 0.0, None, "L", "a collision with a ship within this distance of its goal "
       "(or with an obstacle this close to the own goal) is a 'near-goal' failure",
       "our choice: where the sink's pull |Λ|/r_g (Λ = −100) still beats the modified vortex f|K⁰|/d at the "
       "collision distance d = 2 L with f = 2 (K⁰ = −10): r_g < 10 L (paper §Limitations, 2nd mechanism)",
       "outcome", low_open=True),
    _P("colregs_profile", "published", None, None, "", "thresholds of the COLREG encounter scorer "
       "(mmg_casadi.colregs.scorer: Rule 7 risk gate, encounter sectors, graded Rules 8, 13-17) in metrics.json "
       "'encounters' and the Monte Carlo's colregs_risky/colregs_lawful/colregs_score",
       "published: the thresholds of Woerner et al. 2019 and Hagen et al. 2023 with seamanship distances and "
       "timing (Cockcroft & Lameijer); iitm-lab: the paper laboratory's R_safe, collision distance and head-on "
       "sector (paper Table 3, "
       "§Statistical Analysis); ntnu-2023: Hagen et al. 2023 (Ocean Eng. 288); every threshold's source in "
       "mmg_casadi.colregs.profiles", "outcome", kind="choice", choices=tuple(SCORING_PROFILES)),
    _P("colregs_all_profiles", False, None, None, "", "score every run of a statistics study under every scoring "
       "profile (runs.csv colregs_verdicts_<profile>, colregs.csv, summary.md), not only colregs_profile; about 2.5 "
       "times the scorer's time", "our choice: off, so that the scorer adds at most 10 % to a study "
       "(benchmarks/colregs_scoring.py)", "outcome", kind="bool"),
    _P("targets", "avoid", None, None, "", "what the sampled target ships of the statistical study do: 'avoid' "
       "(every ship uses the study's method), 'hold' (ships other than the own ship hold course and speed, "
       "method 'none'), avoid with the method named (every method of the study then meets the same targets) or a "
       "mix 'mix:avoid=0.6,hold=0.3,wrong=0.1' drawn per ship (behaviours avoid, hold, late, wrong, intent: "
       "mmg_casadi.traffic); only the study's sampled scenarios read it", "avoid: the paper's statistical analysis; "
       "hold: the own ship alone responsible, as the Imazu study's held targets; a method: a planner too costly "
       "for every ship of a Monte Carlo (nmpc) on the own ship only; a mix: issue 48", "outcome", kind="text",
       choices=(TARGETS_TEXT,), parse=parse_study_targets),
    _P("target_slowdown", 0.0, 0.0, 0.6, "", "fraction of its speed every sampled target ship takes off halfway "
       "along its route (a waypoint at the midpoint, the reduced speed on the leg to the goal); 0: constant speed; "
       "only the study's sampled scenarios read it", "0: the paper's constant-speed targets; at most 0.6 keeps "
       "the slowest sampled target (0.5 U) within the scenario speeds' 0.2 U", "outcome"),
    _P("target_vessels", "own", None, None, "", "hulls of the sampled target ships: 'own' (the own ship's, the "
       "table's 'vessel'), one vessel name, or two separated by a comma, which the targets take in turn (agent1 "
       "the first, agent2 the second, ...); only the study's sampled scenarios read it", "own: the paper's "
       "single-hull traffic; a list: mixed traffic (issue 25)", "outcome", kind="choice",
       choices=("own",) + VESSELS + tuple(f"{a},{b}" for a in VESSELS for b in VESSELS if a != b)),
    # traffic: the behaviours a target of a mix draws (mmg_casadi.traffic), each from a uniform range
    _P("target_late_delay_low", 2.0, 0.0, None, "L/U", "shortest delay of a target that gives way late: her method "
       "takes charge only after a neighbour has been within R_safe this long", "our choice: a fifth of the about "
       "10 L/U a crossing at the study's speeds takes from R_safe (15 L) to its CPA", "traffic"),
    _P("target_late_delay_high", 8.0, 0.0, None, "L/U", "longest such delay (the delay is uniform between the two)",
       "our choice: four fifths of that time, an alteration at a few ship lengths", "traffic"),
    _P("target_wrong_turn_low_deg", 20.0, 0.0, 90.0, "deg", "smallest turn to port of a target that turns the wrong "
       "way", "our choice: a readily apparent alteration (Rule 8(b); Cockcroft & Lameijer count those under 10 deg "
       "unlikely to be seen)", "traffic", low_open=True),
    _P("target_wrong_turn_high_deg", 60.0, 0.0, 90.0, "deg", "largest such turn (uniform between the two)",
       "our choice: a bold alteration as Rule 16 asks of a give-way ship, in the wrong direction", "traffic",
       low_open=True),
    _P("target_wrong_dcpa", 4.0, 0.0, None, "L", "a target that turns the wrong way does so when a ship within "
       "R_safe ahead of her beam (bearing within 112.5 deg of her bow) closes with a passing distance below this",
       "our choice: twice the 2 L collision distance", "traffic", low_open=True),
    _P("target_intent_time_low", 10.0, 0.0, None, "L/U", "earliest time of a target's change of mind (intent: one "
       "alteration of course or speed)", "our choice: after the first 10 L/U, so that the change comes while "
       "the study's encounters develop", "traffic"),
    _P("target_intent_time_high", 60.0, 0.0, None, "L/U", "latest such time (uniform between the two)",
       "our choice: at the study's speeds most encounters of environment 5 begin before 60 L/U", "traffic"),
    _P("target_intent_course_low_deg", 30.0, 0.0, 180.0, "deg", "smallest course alteration of a change of mind "
       "(to either side, drawn with equal chance; half the changes of mind are of course, half of speed)",
       "our choice: a readily apparent alteration", "traffic"),
    _P("target_intent_course_high_deg", 90.0, 0.0, 180.0, "deg", "largest such alteration", "our choice",
       "traffic"),
    _P("target_intent_speed_low", 0.5, 0.0, None, "", "smallest factor of a change of speed (the new speed is "
       "clipped to the scenario speeds 0.2-1.2 U)", "our choice: half ahead", "traffic", low_open=True),
    _P("target_intent_speed_high", 1.5, 0.0, None, "", "largest factor of a change of speed", "our choice",
       "traffic", low_open=True),
    # perception: the own ship's sensors and tracker (mmg_casadi.perception); off: perfect knowledge
    _P("perception", "off", None, None, "", "what the own ship's method knows of the other ships: 'off' their true "
       "states; 'ais' their AIS reports, dead-reckoned to the present; 'radar' a Kalman-filter track of radar "
       "plots; 'ais-radar' a track fusing both (obstacles stay known from the chart; the COLREG scorer judges the "
       "true states)", "off: the paper's perfect knowledge; the sensors of issue 48", "perception", kind="choice",
       choices=("off", "ais", "radar", "ais-radar"), structural=True),
    _P("perception_seed", 0, 0, None, "", "seed of the sensor noise (a study draws one per run from its own seed)",
       "our choice", "perception", kind="int"),
    _P("ais_class", "A", None, None, "", "AIS equipment of the target ships: 'A' (SOLAS ships) or 'B' (Class B "
       "'CS')", "A: the study's ships are large merchant ships (ITU-R M.1371-5 Annex 1 Tables 1, 2)", "perception",
       kind="choice", choices=("A", "B")),
    _P("ais_interval_scale", 1.0, 0.0, None, "", "factor on the AIS reporting intervals of ITU-R M.1371-5; 0: a "
       "report at every guidance step", "1: the nominal intervals (Annex 1 Table 1: 10 s, 6 s or 2 s by speed, "
       "shorter while changing course)", "perception"),
    _P("ais_latency_s", 2.0, 0.0, 60.0, "s", "time from a report's position fix to its use by the own ship",
       "our choice: a report goes out in the SOTDMA slot after its fix (M.1371-5 Annex 2) and the display adds "
       "its processing, about two seconds together", "perception"),
    _P("ais_dropout", 0.1, 0.0, 1.0, "", "probability that a report is lost (independently per report)", "our "
       "choice: about one report in ten lost to slot collisions and fading at a few nautical miles", "perception",
       high_open=True),
    _P("ais_position_sigma_m", 5.3, 0.0, None, "m", "standard deviation of a reported position, per axis",
       "IMO MSC.112(73): GPS within 13 m (95 %) horizontally, 13 m / 2.45 per axis", "perception"),
    _P("ais_sog_sigma_kn", 0.1, 0.0, None, "kn", "standard deviation of a reported speed over the ground",
       "half the 0.2 kn resolution-and-accuracy figure of IMO A.824(19) for speed logs (95 %)", "perception"),
    _P("ais_cog_sigma_deg", 1.0, 0.0, 45.0, "deg", "standard deviation of a reported course over the ground",
       "our choice: the course of a GNSS receiver at sea speeds", "perception"),
    _P("radar_range_sigma_m", 15.0, 0.0, None, "m", "standard deviation of a radar range", "IMO MSC.192(79) "
       "§5.20: range within 30 m (95 %)", "perception"),
    _P("radar_bearing_sigma_deg", 0.5, 0.0, 45.0, "deg", "standard deviation of a radar bearing", "IMO MSC.192(79) "
       "§5.20: bearing within 1 deg (95 %)", "perception"),
    _P("radar_range_nm", 11.0, 0.0, None, "NM", "range within which the radar detects a target", "IMO MSC.192(79) "
       "Table 1: a ship over 5000 GT detected at 11 NM", "perception", low_open=True),
    _P("radar_p_detect", 0.9, 0.0, 1.0, "", "probability that a target within range is detected on a scan",
       "our choice: above the 0.8 that MSC.192(79) asks at the ranges of its Table 1, for targets well inside them",
       "perception"),
    _P("tracker_q", 0.05, 0.0, None, "m²/s³", "spectral density of the white acceleration noise of the tracker's "
       "constant-velocity model", "our choice: accelerations of about 0.1 m/s², a merchant ship's in a turn, over "
       "a few seconds", "perception", low_open=True),
    _P("tracker_gate", 9.21, 0.0, None, "", "largest squared Mahalanobis distance of a radar plot a track takes "
       "(nearest neighbour)", "chi-square 99 % of 2 degrees of freedom (Bar-Shalom, Li & Kirubarajan 2001)",
       "perception", low_open=True),
    # environment (calm water by default, as in the paper; see mmg_casadi.vessel.environment)
    _P("current_speed", 0.0, 0.0, 1.0, "U", "speed of a uniform current (fraction of the design speed)",
       "our choice: calm water as in the paper; model Fossen 2021 §10.3 (mmg_casadi.vessel.environment)",
       "environment"),
    _P("current_direction_deg", 0.0, -360.0, 360.0, "deg", "direction the current flows TOWARDS (from x "
       "towards y)", "our choice", "environment"),
    _P("wind_speed", 0.0, 0.0, 60.0, "m/s", "true wind speed (the model takes it over U_des = 12.347 m/s)",
       "our choice: calm air as in the paper; loads Blendermann 1994, KCS windage our estimate "
       "(mmg_casadi.vessel.environment)", "environment"),
    _P("wind_direction_deg", 0.0, -360.0, 360.0, "deg", "direction the wind comes FROM (from x towards y)",
       "our choice", "environment"),
    _P("crab_compensation", "off", None, None, "", "'on': ILOS steers ψ_d = χ_d − β with the measured crab "
       "angle β = atan2(v_g, u_g) over the ground", "Fossen, Pettersen & Galeazzi 2015 (IEEE TCST 23(2)); off "
       "so that the ILOS integral alone compensates drift, as in the paper", "environment", kind="choice",
       choices=("off", "on")),
)}
"""Every parameter, by name."""

NUMERIC = tuple(n for n, p in PARAMETERS.items() if not p.structural)
"""Parameters of the shipped table that are numeric inputs of the compiled closed loop (or of the outcome
judgement); a registered method's own parameters are in :data:`PARAMETERS` only."""
STRUCTURAL = tuple(n for n, p in PARAMETERS.items() if p.structural)
"""Parameters of the shipped table that select the compiled closed loop's shape."""


def check_value(name: str, value, *, field: str | None = None, cls=ParameterError):
    """``value`` checked against parameter ``name`` (unknown names raise ``cls`` listing the known ones).

    Parameters
    ----------
    name : str
        Table name of the parameter.
    value : object
        The value to check.
    field : str or None, optional
        Name used in the error message (default: ``name``).
    cls : type, default ParameterError
        Exception class raised for an invalid value or unknown name.

    Returns
    -------
    str or bool or int or float
        The value converted to the parameter's type (:meth:`Param.check`).

    Examples
    --------
    >>> check_value("ilos_k", 0.1)
    0.1
    >>> check_value("r_saf", 1.0, field="params.r_saf")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ParameterError: params.r_saf: expected a parameter name (one of: dt, t_max, ...
    """
    if name not in PARAMETERS and not any(hook(name) for hook in _UNKNOWN_HOOKS):
        raise cls(field or name, f"a parameter name (one of: {', '.join(PARAMETERS)})")
    return PARAMETERS[name].check(value, field=field, cls=cls)


_UNKNOWN_HOOKS: list = []
"""Callables ``name -> bool`` asked about a name not in the table before it is refused (the method registry's
on-demand methods, :func:`mmg_casadi.guidance.methods.load_on_demand`); True when the name is in the table now."""


def on_unknown_parameter(hook) -> None:
    """Have :func:`check_value` ask ``hook(name)`` about a parameter name not in the table before refusing it.

    Parameters
    ----------
    hook : callable
        ``name -> bool``: True if it entered ``name`` into :data:`PARAMETERS`.
    """
    _UNKNOWN_HOOKS.append(hook)


def resolve(*layers: dict | None, cls=ParameterError, prefix: str = "") -> dict:
    """The full parameter set: table defaults updated with each mapping of ``layers`` in turn, all checked.

    Parameters
    ----------
    *layers : dict or None
        Overrides by parameter name, later ones winning (e.g. scenario settings, then a ``--params`` file).
    cls : type
        Error raised for an unknown name or a bad value (an :class:`~mmg_casadi.errors.InputError` subclass).
    prefix : str
        Prepended to the parameter name in error messages (e.g. ``"params."``).

    Returns
    -------
    dict
        Every parameter of :data:`PARAMETERS`, in table order.

    Examples
    --------
    >>> resolve({"dt": 0.5}, {"dt": 0.1})["dt"]
    0.1
    """
    out = {n: p.default for n, p in PARAMETERS.items()}
    for layer in layers:
        for k, v in (layer or {}).items():
            out[k] = check_value(k, v, field=f"{prefix}{k}", cls=cls)
    return out


def diff(a: dict, b: dict) -> str | None:
    """First key (table order) whose value differs between two resolved sets, or None.

    Parameters
    ----------
    a : dict
        A resolved parameter set.
    b : dict
        Another resolved parameter set.

    Returns
    -------
    str or None
        The first differing name, or None if the sets agree on every parameter.

    Examples
    --------
    >>> diff(resolve(), resolve({"kd": 3.0}))
    'kd'
    """
    for k in PARAMETERS:
        if a.get(k) != b.get(k):
            return k
    return None


def group(name: str) -> tuple[str, ...]:
    """Names of the parameters of one group.

    Parameters
    ----------
    name : str
        Name of the parameter group.

    Returns
    -------
    tuple of str
        The parameter names of the group, in table order.

    Examples
    --------
    >>> group("ilos")
    ('ilos_delta', 'ilos_k')
    """
    if name not in groups():
        raise InputError("group", f"one of: {', '.join(groups())}", name)
    return tuple(n for n, p in PARAMETERS.items() if p.group == name)


def groups() -> tuple[str, ...]:
    """Every parameter group: :data:`GROUPS`, then those of registered methods that declare parameters.

    Returns
    -------
    tuple of str
        Group names, in the order of the Markdown table.

    Examples
    --------
    >>> groups()[:3]
    ('simulation', 'vessel', 'ilos')
    """
    return GROUPS + tuple(_METHOD_GROUPS)


def add_group(name: str, params) -> None:
    """Enter the parameters a method declares into :data:`PARAMETERS` as group ``name`` (the method's name).

    Called by :func:`mmg_casadi.guidance.methods.register`; nothing is entered when a name is taken.

    Parameters
    ----------
    name : str
        The group: the method's name, not one of :func:`groups`.
    params : iterable of Param
        The parameters, each with ``group`` equal to ``name``.
    """
    params = tuple(params)
    if name in groups():
        raise InputError("method.name", f"a name that is not a parameter group ({', '.join(groups())})", name)
    taken = [p.name for p in params if p.name in PARAMETERS]
    if taken:
        raise InputError("method.params", "parameter names not yet in the table (see `mmg-casadi params`)", taken[0])
    for p in params:
        PARAMETERS[p.name] = p
    _METHOD_GROUPS[name] = tuple(p.name for p in params)


def remove_group(name: str) -> None:
    """Remove a group entered by :func:`add_group` and its parameters from :data:`PARAMETERS` (no-op if absent).

    Parameters
    ----------
    name : str
        The group (a method's name).
    """
    for n in _METHOD_GROUPS.pop(name, ()):
        PARAMETERS.pop(n, None)


def field(name: str, attr_unit_scale: float = 1.0):
    """A dataclass field whose default is parameter ``name``'s, scaled by ``attr_unit_scale``.

    Used by the parameter dataclasses so their defaults are the table's; :func:`check_fields` checks them.

    Parameters
    ----------
    name : str
        Table name of the parameter.
    attr_unit_scale : float, default 1.0
        Factor from the table's unit to the attribute's (e.g. degrees to rad).

    Returns
    -------
    dataclasses.Field
        A field with that default and ``metadata`` ``{"param": name, "scale": attr_unit_scale}``.
    """
    return dataclasses.field(default=PARAMETERS[name].default * attr_unit_scale,
                             metadata={"param": name, "scale": attr_unit_scale})


def check_fields(obj) -> None:
    """Check every field of a parameter dataclass made with :func:`field` against the table.

    The error names the table's parameter (e.g. ``ilos_delta``), the name used everywhere else.

    Parameters
    ----------
    obj : dataclass instance
        A parameter dataclass whose fields were made with :func:`field`.
    """
    for f in dataclasses.fields(obj):
        if "param" in f.metadata:
            value = getattr(obj, f.name)
            scale = f.metadata["scale"]
            check_value(f.metadata["param"], value / scale if scale != 1.0 and _is_real(value) else value)



def markdown_table() -> str:
    """The table as Markdown (name, default, allowed, unit, meaning, source), grouped as in :func:`groups`;
    a ``|`` inside a cell is escaped as ``\\|``.

    Returns
    -------
    str
        The table, a header row, a rule and one row per parameter, without a final newline.

    Examples
    --------
    >>> markdown_table().splitlines()[0]
    '| parameter | default | allowed | meaning | source |'
    """
    rows = ["| parameter | default | allowed | meaning | source |", "|---|---|---|---|---|"]
    for g in groups():
        for n in group(g):
            p = PARAMETERS[n]
            allowed = p.allowed().removeprefix("a number in ").removeprefix("one of: ")
            default = str(p.default).lower() if p.kind == "bool" else str(p.default)
            cells = (default, allowed, p.meaning, p.source)
            rows.append(f"| `{n}` | " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
    return "\n".join(rows)


def help_text() -> str:
    """One line per parameter for the CLI's ``--params`` help.

    Returns
    -------
    str
        Lines ``name = default (allowed): meaning``, in table order.

    Examples
    --------
    >>> help_text().splitlines()[0].split()[0]
    'dt'
    """
    return "\n".join(f"{n} = {p.default} ({p.allowed()}): {p.meaning}" for n, p in PARAMETERS.items())


def load_file(path) -> dict:
    """Parameter values from a TOML file (top level, or a ``[params]`` table as ``tune apf`` writes), checked.

    Parameters
    ----------
    path : str or Path
        The file.

    Returns
    -------
    dict
        Parameter name → value, only the keys the file gives.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "p.toml"
    >>> _ = f.write_text("[params]\\nr_safe = 12.0\\n")
    >>> load_file(f)
    {'r_safe': 12.0}
    """
    from mmg_casadi.readers import load_toml  # size, UTF-8, nesting checked while reading
    path = Path(path)
    raw = load_toml(path, "parameter", "params file", ParameterError)
    if "params" in raw:
        if set(raw) != {"params"} or not isinstance(raw["params"], dict):
            raise ParameterError("params file", "either parameters at the top level or one [params] table",
                                 str(path))
        raw = raw["params"]
    return {k: check_value(k, v, field=f"params.{_key(k)}") for k, v in raw.items()}


def _key(k: str) -> str:
    """A TOML key as written in a file: bare if it can be, else quoted (one line, never empty)."""
    return k if re.fullmatch(r"[A-Za-z0-9_-]+", k) else json.dumps(k)
