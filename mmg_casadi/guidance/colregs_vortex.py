"""COLREG-complete modified sink-vortex guidance (``colregs-vortex``): the paper's modified sink-vortex field
extended with what a watch officer does and the paper leaves out.

Per neighbour (one column of ``nb_pos`` / ``nb_vel``; conventions and shapes as in :mod:`mmg_casadi.guidance.fields`).
The own ship's *planned course* is the bearing of its next waypoint at its current speed; roles and "what if I
keep my course" predictions are judged against it, so the own evasive turn changes neither (no latched state).

- **Role** (Rules 13–15). γ is the bearing of the neighbour from the planned course, α the bearing of the own
  ship from the neighbour's bow (its heading taken from its velocity). The own ship is **stand-on** for a ship
  abaft its beam (``|γ| > γ_max``: being overtaken, Rule 13) and for a ship on its port side (γ < 0) that is neither
  on a nearly reciprocal course (Rule 14: ``|γ|`` and the course difference from reciprocal both below θ_ho) nor
  being overtaken by the own ship (``|α| > γ_max``). Everything else, including static obstacles (speed below
  ``v_ship_min``), is **give-way** and gets the paper's modified vortex
  (:func:`~mmg_casadi.guidance.fields.modified_vortex_terms`).
- **Static obstacles** get the vortex only while the range closes (once it opens the ship is past it; without
  this a far goal's weak sink lets the vortex hold the ship in an orbit about the obstacle).
- **Rule 17(a)(i)**: a stand-on neighbour gets no vortex — course and speed are kept.
- **Rule 17(a)(ii) and 17(b)**: the stand-on ship acts alone when the give-way ship has not made the passing
  safe in time: the CPA distance *if the own ship kept its planned course* is below ``d_cpa_act`` while the
  TCPA is below ``t_act`` or the range below ``r_act``. A give-way ship whose *present* manoeuvre still leads
  inside ``d_cpa_act`` under the same timing (the other ship not helping) escalates the same way. The action is
  an escape term of strength ``k_standon · t_act / max(min(TCPA, TCPA_now, t_act), t_close)`` (growing to the
  "best aid" of 17(b) as TCPA falls to ``t_close``, and held there while the present motion already opens the
  range but resuming the planned course would not be safe) pointing off the neighbour's track (the part of
  the line of sight across its course) plus, with half weight, perpendicular to the relative velocity. It
  never turns to port (**17(c)** for a vessel crossing from port; Rules 14/15 for an escalating give-way ship;
  a port component is mirrored to starboard) except away from an overtaking ship, i.e. to the side opposite
  the one on which it would pass.
- **Rule 8**: while any ship is a threat (give-way with a planned-course CPA below ``d_clear`` and TCPA > 0, or
  a ship the own ship acts for), the heading from the ship terms differs from the bearing of the goal by at
  least ``dpsi_min`` to starboard (readily apparent), unless they already turn further to port. It acts as soon
  as the ship is inside R_safe, i.e. early. Static obstacles and the guard below are added after this step, so
  they keep their full say.
- **Near the goal** (the paper's second failure mechanism): while anything is being avoided, the sink's strength
  is evaluated at max(distance to the goal, distance to the nearest avoided neighbour, ``d_att_floor``): by
  default the goal never attracts more strongly than a goal at the edge of R_safe, so the vortex of a ship or of
  an obstacle near the goal keeps its weight and the obstacle is passed on the vortex's side.
- **Guard**: inside ``r_guard`` every neighbour also pushes radially, λ_guard (1/d − 1/r_guard), a last-resort
  term for whatever the rules above did not resolve.
- **Close quarters** (Rule 17(b) "best aid to avoid collision", Rule 2(b) departure to avoid immediate danger):
  the heading of the whole field is kept unless its velocity (at the current speed) lies inside the collision
  cone of a ship or obstacle within ``r_cq``, the linear velocity obstacle of Huang et al. 2018 (Ocean Eng. 151)
  with combined radius ``d_cq`` (:mod:`mmg_casadi.guidance.velocity_obstacle`). The velocity judged is the one at the
  heading the ship turns through next on its way to the field's, at most ``dpsi_cq`` from its present heading
  (a reversal to starboard through a ship abeam is not admissible because its end point is); if it is inside
  a cone, the ship steers the admissible heading (the velocity obstacle's candidate) closest to a readily
  apparent alteration of its present heading to starboard (``dpsi_min``, Rule 8): a small alteration it can
  complete quickly, to starboard unless that is much longer (the least-penetrating candidate if none is
  admissible). Terms of several neighbours, or of a neighbour and the rules, can cancel or point into a third
  ship; this filter is what keeps their sum out of the way of whatever is close.

Everything is branch-free CasADi (0/1 products and ``if_else``), with no closed-loop state. The exact switches
are used even when the closed loop asks for smooth ones (``Layout.smooth``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields as dc_fields

import casadi as ca

from mmg_casadi.params import PARAMETERS, check_fields
from mmg_casadi.params import field as param_field
from mmg_casadi.guidance.fields import R_MIN, _col2, _matrix, _row, modified_vortex_terms, vortex
from mmg_casadi.guidance.ilos import wrap_angle
from mmg_casadi.guidance.velocity_obstacle import heading_feasible, velocity_obstacle

_BIG = 1.0e6


@dataclass(frozen=True)
class ColregsVortexParams:
    """Thresholds of ``colregs-vortex`` beyond the modified vortex's (lengths in L, times in L/U, angles in rad);
    defaults and ranges are the parameter table's ``cv_*`` entries (:mod:`mmg_casadi.params`, angles in degrees).

    Parameters
    ----------
    theta_head_on : float
        Tolerance, both on the bearing from the bow and on the course difference from reciprocal, within which
        a meeting counts as head-on (rad, (0, π/2)); 22.5° as the paper laboratory's head-on sector 7π/8–9π/8
        of relative heading.
    d_cpa_act : float
        The stand-on ship acts alone when its planned-course CPA distance is below this (L, > 0); 3 L = 1.5 ×
        the 2 L collision distance, below the ≈ 4 L (2 R_tol) passing distance the modified vortex's give-way
        action aims at, so a give-way ship that acts as the paper's does never triggers it.
    t_act : float
        TCPA below which the stand-on ship acts alone, 17(a)(ii) (L/U, > 0); 7 L/U ≈ 2.2 min for the KCS
        (L/U ≈ 18.6 s): a give-way ship that entered R_safe = 15 L in a right-angle crossing (closing speed
        √2 U, TCPA ≈ 10.6) had ≈ 3.6 L/U, more than twice its time to alter course by 30°, to act.
    r_act : float
        Range below which it acts alone whatever the TCPA (L, > 0); 8 L = 4 collision distances, for slowly
        closing ships (being overtaken) whose TCPA stays long.
    t_close : float
        TCPA at which the stand-on action reaches its full strength, 17(b) close quarters (L/U, > 0); 3 L/U is
        about the KCS's time to turn 90° with full rudder.
    k_standon : float
        Strength of the stand-on escape term at the trigger (L/unit time, > 0); 1.0 matches the sink of the
        paper's Λ = −100 at the 15 L detection range (100 / 2π 15 ≈ 1.06).
    dpsi_min : float
        Minimum alteration from the goal bearing while a threat is present, Rule 8 "readily apparent" (rad,
        [0, π/2]); 30° as NTNU's evaluator (Hagen et al. 2023 configuration, Δχ_app).
    d_clear : float
        Planned-course passing distance below which a give-way ship keeps its alteration (L, > 0); 6 L = 3
        collision distances, above the 4 L the vortex aims at so the ship resumes its course only when clear.
    v_ship_min : float
        Neighbours slower than this are static obstacles without COLREG role (U, > 0); 0.05 is below the
        slowest ship speed a scenario allows (0.2).
    r_guard : float
        Range inside which every neighbour also repels radially (L, > 0); 5 L = 2.5 collision distances, about
        the KCS's advance in a full-rudder 90° turn plus the collision distance.
    lam_guard : float
        Strength of that repulsion, λ (1/d − 1/r_guard) (L²/unit time, ≥ 0; 0 disables it); 15 makes it 2,
        about twice the capped sink, at 3 L.
    d_att_floor : float
        While anything is avoided, the goal attracts at most as strongly as from this distance (L, ≥ 0);
        15 L = R_safe, the range at which avoidance starts.
    r_cq : float
        Range within which a neighbour's collision cone filters the field's heading, close quarters (L, ≥ 0;
        0 disables the filter); 8 L = ``r_act``, the range at which the stand-on ship acts whatever the TCPA
        (4 collision distances).
    d_cq : float
        Combined radius of those cones (L, > 0); 3 L = 1.5 × the 2 L collision distance, the margin
        ``d_cpa_act`` also uses, for the heading the ship has not reached yet.
    dpsi_cq : float
        The filter judges not the field's heading itself but the heading the ship turns through next on its
        way there, at most this far from its present heading (rad, (0, π]); 45° ≈ what the KCS turns in
        half of ``t_close`` (3 L/U ≈ its 90° turn with full rudder), while the PD's rudder is saturated
        anyway for any larger heading error.
    """

    theta_head_on: float = param_field("cv_theta_head_on_deg", math.pi / 180.0)
    d_cpa_act: float = param_field("cv_d_cpa_act")
    t_act: float = param_field("cv_t_act")
    r_act: float = param_field("cv_r_act")
    t_close: float = param_field("cv_t_close")
    k_standon: float = param_field("cv_k_standon")
    dpsi_min: float = param_field("cv_dpsi_min_deg", math.pi / 180.0)
    d_clear: float = param_field("cv_d_clear")
    v_ship_min: float = param_field("cv_v_ship_min")
    r_guard: float = param_field("cv_r_guard")
    lam_guard: float = param_field("cv_lam_guard")
    d_att_floor: float = param_field("cv_d_att_floor")
    r_cq: float = param_field("cv_r_cq")
    d_cq: float = param_field("cv_d_cq")
    dpsi_cq: float = param_field("cv_dpsi_cq_deg", math.pi / 180.0)

    def __post_init__(self):
        check_fields(self)

    def as_dict(self) -> dict:
        """The thresholds as keyword arguments of :func:`colregs_vortex`.

        Examples
        --------
        >>> sorted(ColregsVortexParams().as_dict())[:3]
        ['d_att_floor', 'd_clear', 'd_cpa_act']
        """
        return {f.name: getattr(self, f.name) for f in dc_fields(self)}


def _cpa(rel_pos, rel_vel):
    """TCPA (1×M, negative when opening) and the relative position at the CPA (2×M, for TCPA clipped at 0)."""
    vv = ca.fmax(ca.sum1(rel_vel * rel_vel), 1e-9)
    tcpa = -ca.sum1(rel_pos * rel_vel) / vv
    p_cpa = rel_pos + rel_vel * ca.repmat(ca.fmax(tcpa, 0), 2, 1)
    return tcpa, p_cpa


def colregs_vortex_terms(own_pos, own_psi, own_vel, goal, nb_pos, nb_vel, *, k_vor0, r_safe, r_tol, gamma_max,
                         theta_head_on, d_cpa_act, t_act, r_act, t_close, k_standon, dpsi_min, d_clear,
                         v_ship_min, r_guard, lam_guard, d_att_floor=None, r_cq=None, d_cq=None,
                         dpsi_cq=None):
    """Per-neighbour quantities of :func:`colregs_vortex` (each a 1×M row unless stated).

    Keys: ``gamma`` (bearing from the planned course), ``d``, ``ship`` (1 for a moving neighbour), ``head_on``,
    ``stand_on``, ``tcpa`` / ``dcpa`` (for the own ship keeping its planned course), ``act_alone`` (1 where the
    stand-on ship acts alone, 17(a)(ii)/(b)), ``act`` (``act_alone`` or a give-way escalation), ``weight``
    (strength of the escape term), ``escape`` (2×M unit escape directions), ``k_vor`` (give-way vortex
    strength), ``threat`` (1 where the Rule 8 minimum alteration applies), ``guard`` (radial push strength),
    ``avoid`` (1 where the neighbour is being avoided). ``d_att_floor``, ``r_cq``, ``d_cq`` and ``dpsi_cq`` are
    accepted so that :meth:`ColregsVortexParams.as_dict` can be passed whole; only :func:`colregs_vortex` uses
    them.

    Parameters
    ----------
    own_pos : array_like
        Own position (2×1, L).
    own_psi : float or casadi.SX or casadi.MX
        Own heading (rad, from x towards y).
    own_vel : array_like
        Own velocity in the global frame (2×1, L/unit time); its magnitude is the speed of the planned course.
    goal : array_like
        Own goal, the next waypoint (2×1, L); the planned course points at it.
    nb_pos : array_like
        Neighbour positions (2×M, L); M may be 0.
    nb_vel : array_like
        Neighbour velocities in the global frame (2×M, L/unit time).
    k_vor0, r_safe, r_tol, gamma_max : float
        Modified-vortex parameters, as in :class:`~mmg_casadi.guidance.fields.ModifiedVortexParams`: nominal vortex
        strength (L²/unit time), detection radius R_safe (L), R_tol of the tangential-velocity threshold (L)
        and the largest ``|γ|`` at which the vortex acts (rad).
    theta_head_on, d_cpa_act, t_act, r_act, t_close, k_standon : float
        COLREG thresholds of :class:`ColregsVortexParams` (meaning, units and ranges there).
    dpsi_min, d_clear, v_ship_min, r_guard, lam_guard : float
        The remaining COLREG thresholds of :class:`ColregsVortexParams`.
    d_att_floor, r_cq, d_cq, dpsi_cq : float, optional
        Ignored here (see above).

    Returns
    -------
    dict
        The quantities named above, CasADi expressions (DM for numeric input).

    Examples
    --------
    >>> import casadi as ca
    >>> kw = dict(k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=5 * ca.pi / 8, **ColregsVortexParams().as_dict())
    >>> t = colregs_vortex_terms([0, 0], 0.0, [1, 0], [50, 0], ca.DM([[10], [-10]]), ca.DM([[0], [1]]), **kw)
    >>> int(t["stand_on"]), int(t["act"]), round(float(t["tcpa"]), 3)  # crossing from port, far: hold on
    (1, 0, 10.0)
    """
    own_pos, own_vel, goal = _col2(own_pos), _col2(own_vel), _col2(goal)
    nb_pos, nb_vel = _matrix(nb_pos, 2), _matrix(nb_vel, 2)
    m = nb_pos.size2()
    mv = modified_vortex_terms(own_pos, own_psi, own_vel, nb_pos, nb_vel, k_vor0=k_vor0, r_safe=r_safe,
                               r_tol=r_tol, gamma_max=gamma_max)
    d = mv["d"]
    los = nb_pos - ca.repmat(own_pos, 1, m)
    # planned course: towards the goal at the current speed (what "keeping course" means for this ship); roles
    # are judged against it, so an evasive turn does not change them
    own_speed = ca.sqrt(ca.sumsqr(own_vel))
    to_goal = goal - own_pos
    e_goal = to_goal / ca.fmax(ca.sqrt(ca.sumsqr(to_goal)), R_MIN)
    v_plan = own_speed * e_goal
    psi_plan = ca.atan2(e_goal[1], e_goal[0])
    gamma = wrap_angle(ca.atan2(los[1, :], los[0, :]) - psi_plan)
    speed_nb = ca.sqrt(ca.sum1(nb_vel * nb_vel))
    ship = speed_nb > v_ship_min
    chi_nb = ca.atan2(nb_vel[1, :], nb_vel[0, :])
    alpha = wrap_angle(ca.atan2(-los[1, :], -los[0, :]) - chi_nb)
    recip = wrap_angle(chi_nb - psi_plan - ca.pi)
    head_on = (ca.fabs(recip) < theta_head_on) * (ca.fabs(gamma) < theta_head_on)
    astern = ca.fabs(gamma) > gamma_max
    overtaking_it = ca.fabs(alpha) > gamma_max
    port_crossing = (gamma < 0) * (1 - astern) * (1 - overtaking_it) * (1 - head_on)
    stand_on = ship * ((astern + port_crossing) > 0)
    tcpa, p_cpa = _cpa(los, nb_vel - ca.repmat(v_plan, 1, m))
    dcpa = ca.sqrt(ca.sum1(p_cpa * p_cpa))
    closing = tcpa > 0
    soon = ((tcpa < t_act) + (d < r_act)) > 0
    act_alone = stand_on * closing * (dcpa < d_cpa_act) * soon
    # a give-way ship whose present manoeuvre still leads into close quarters (the other ship not helping)
    # escalates with the same escape term
    v_rel = nb_vel - ca.repmat(own_vel, 1, m)
    tcpa_now, p_cpa_now = _cpa(los, v_rel)
    dcpa_now = ca.sqrt(ca.sum1(p_cpa_now * p_cpa_now))
    soon_now = ((tcpa_now < t_act) + (d < r_act)) > 0
    escalate = ship * (1 - stand_on) * (1 - astern) * (tcpa_now > 0) * (dcpa_now < d_cpa_act) * soon_now
    act = ((act_alone + escalate) > 0)
    # strength grows as either TCPA falls; it stays at its maximum while the present motion already opens the
    # range (TCPA_now < 0) but resuming the planned course would not yet be safe
    weight = act * k_standon * t_act / ca.fmax(ca.fmin(ca.fmin(tcpa, tcpa_now), t_act), t_close)

    # escape: perpendicular to the actual relative velocity, on the side the rules ask for ...
    n = -v_rel / ca.repmat(ca.fmax(ca.sqrt(ca.sum1(v_rel * v_rel)), 1e-9), 2, 1)
    e_plus = ca.vertcat(-n[1, :], n[0, :])  # n turned 90° from x towards y
    c, s = ca.cos(psi_plan), ca.sin(psi_plan)
    lat_plus = -s * e_plus[0, :] + c * e_plus[1, :]  # > 0: e_plus points to the own starboard side
    lat_cpa = -s * p_cpa[0, :] + c * p_cpa[1, :]  # > 0: the neighbour would pass on the own starboard side
    side = 1 - 2 * astern * (lat_cpa > 0)  # +1 starboard (17(c) and default), -1 port (away from an overtaker)
    flip = 2 * ((side * lat_plus) >= 0) - 1
    # ... plus getting off the neighbour's track: the part of −LOS across its course, relative to the range
    course = nb_vel / ca.repmat(ca.fmax(speed_nb, 1e-9), 2, 1)
    along = ca.sum1(los * course)
    off_track = -(los - course * ca.repmat(along, 2, 1)) / ca.repmat(d, 2, 1)
    escape = 0.5 * e_plus * ca.repmat(flip, 2, 1) + 2 * off_track
    # never to port except away from an overtaker (17(c); Rules 14/15 for an escalating give-way ship): a port
    # component is mirrored to starboard of the planned course
    lat_esc = -s * escape[0, :] + c * escape[1, :]
    mirror = (1 - astern) * (ca.fabs(lat_esc) - lat_esc)
    escape = escape + ca.vertcat(-s, c) @ mirror
    escape = escape / ca.repmat(ca.fmax(ca.sqrt(ca.sum1(escape * escape)), 1e-9), 2, 1)

    giveway = 1 - stand_on
    # a static obstacle is circled only while the range closes: once it opens the ship is past it (without this
    # the vortex can hold the ship in an orbit about an obstacle when the goal is far and its sink weak)
    k_vor = giveway * mv["k_vor"] * (ship + (1 - ship) * (mv["v_r"] < 0))
    threat = ship * closing * ((giveway * (1 - astern) * (dcpa < d_clear) + act) > 0)
    guard = lam_guard * ca.fmax(0, 1 / d - 1 / r_guard)  # radial push away inside r_guard, whatever the rules
    avoid = ((k_vor != 0) + act + threat + (d < r_guard)) > 0
    return {"gamma": gamma, "d": d, "ship": ship, "head_on": head_on, "stand_on": stand_on, "tcpa": tcpa,
            "dcpa": dcpa, "act_alone": act_alone, "act": act, "weight": weight, "escape": escape, "k_vor": k_vor,
            "threat": threat, "guard": guard, "avoid": avoid}


def colregs_vortex(own_pos, own_psi, own_vel, goal, nb_pos, nb_vel, active, *, lam_sink, k_vor0, r_safe, r_tol,
                   gamma_max, theta_head_on, d_cpa_act, t_act, r_act, t_close, k_standon, dpsi_min, d_clear,
                   v_ship_min, r_guard, lam_guard, d_att_floor, r_cq=0.0, d_cq=PARAMETERS["cv_d_cq"].default,
                   dpsi_cq=PARAMETERS["cv_dpsi_cq_deg"].default * math.pi / 180.0,
                   n_candidates=PARAMETERS["vo_candidates"].default):
    """Desired-heading vector of ``colregs-vortex`` (2×1; its direction is the desired heading).

    Sink at the goal (strength capped while avoiding), the modified vortex at every active give-way ship, the
    escape term of every ship the own ship acts for, the Rule 8 minimum alteration, then the modified vortex
    of static obstacles and the close-range guard, and finally the close-quarters filter of its heading; see the
    module docstring. ``active`` (1×M, 0/1) masks neighbours as in :mod:`mmg_casadi.guidance.fields`.

    Parameters
    ----------
    own_pos : array_like
        Own position (2×1, L).
    own_psi : float or casadi.SX or casadi.MX
        Own heading (rad, from x towards y).
    own_vel : array_like
        Own velocity in the global frame (2×1, L/unit time); its magnitude is the speed of the planned course.
    goal : array_like
        Own goal, the next waypoint (2×1, L); the planned course points at it.
    nb_pos : array_like
        Neighbour positions (2×M, L); M may be 0.
    nb_vel : array_like
        Neighbour velocities in the global frame (2×M, L/unit time).
    active : array_like
        0/1 mask of the neighbours to consider (1×M; neighbour exists and lies within R_safe).
    lam_sink : float
        Sink strength Λ at the goal (L²/unit time, < 0 attracts).
    k_vor0, r_safe, r_tol, gamma_max : float
        Modified-vortex parameters, as in :class:`~mmg_casadi.guidance.fields.ModifiedVortexParams`: nominal vortex
        strength (L²/unit time), detection radius R_safe (L), R_tol of the tangential-velocity threshold (L)
        and the largest ``|γ|`` at which the vortex acts (rad).
    theta_head_on, d_cpa_act, t_act, r_act, t_close, k_standon : float
        COLREG thresholds of :class:`ColregsVortexParams` (meaning, units and ranges there).
    dpsi_min, d_clear, v_ship_min, r_guard, lam_guard : float
        The remaining COLREG thresholds of :class:`ColregsVortexParams`.
    d_att_floor : float
        While anything is avoided, the goal attracts at most as strongly as from this distance (L, ≥ 0).
    r_cq : float
        Close-quarters range of the heading filter (L, ≥ 0; 0, the default here, disables it).
    d_cq : float
        Combined radius of the filter's collision cones (L, > 0).
    dpsi_cq : float
        The filter judges the heading the ship turns through next, at most this far from its own on the way to
        the field's (rad, (0, π]).
    n_candidates : int
        Candidate headings of the filter's velocity obstacle (evenly spread; the closed loop passes the layout's
        ``vo_candidates``).

    Returns
    -------
    casadi.DM or casadi.SX or casadi.MX
        The 2×1 desired-heading vector (see :func:`~mmg_casadi.guidance.fields.heading_of`).

    Examples
    --------
    >>> import casadi as ca
    >>> from mmg_casadi.guidance.fields import heading_of
    >>> kw = dict(lam_sink=-100.0, k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=5 * ca.pi / 8,
    ...           **ColregsVortexParams().as_dict())
    >>> v = colregs_vortex([0, 0], 0.0, [1, 0], [50, 0], ca.DM([[10], [-10]]), ca.DM([[0], [1]]), [1], **kw)
    >>> round(float(heading_of(v)), 6)  # stand-on, give-way ship still has time: keep course
    0.0
    >>> v = colregs_vortex([0, 0], 0.0, [1, 0], [50, 0], ca.DM([[12], [0]]), ca.DM([[-1], [0]]), [1], **kw)
    >>> round(math.degrees(float(heading_of(v))))  # head-on at 12 L: give way to starboard, escalating
    79
    """
    own_pos, own_vel, goal = _col2(own_pos), _col2(own_vel), _col2(goal)
    nb_pos, nb_vel = _matrix(nb_pos, 2), _matrix(nb_vel, 2)
    m = nb_pos.size2()
    to_goal = goal - own_pos
    dist_goal = ca.fmax(ca.sqrt(ca.sumsqr(to_goal)), R_MIN)
    psi_goal = ca.atan2(to_goal[1], to_goal[0])
    if m == 0:
        return -lam_sink / (2 * ca.pi * dist_goal * dist_goal) * to_goal
    active = _row(active, m)
    t = colregs_vortex_terms(own_pos, own_psi, own_vel, goal, nb_pos, nb_vel, k_vor0=k_vor0, r_safe=r_safe,
                             r_tol=r_tol, gamma_max=gamma_max, theta_head_on=theta_head_on, d_cpa_act=d_cpa_act,
                             t_act=t_act, r_act=r_act, t_close=t_close, k_standon=k_standon, dpsi_min=dpsi_min,
                             d_clear=d_clear, v_ship_min=v_ship_min, r_guard=r_guard, lam_guard=lam_guard)
    avoid = active * t["avoid"]
    d_threat = ca.mmin(avoid * t["d"] + (1 - avoid) * _BIG)
    d_eff = ca.fmax(dist_goal, ca.if_else(d_threat < _BIG / 2, ca.fmax(d_threat, d_att_floor), 0))
    att = -lam_sink / (2 * ca.pi * d_eff * dist_goal) * to_goal  # |att| = |Λ| / (2π d_eff), towards the goal
    vor_ship = ca.sum2(vortex(own_pos, nb_pos, active * t["ship"] * t["k_vor"]))
    esc = ca.sum2(t["escape"] * ca.repmat(active * t["weight"], 2, 1))
    ships = att + vor_ship + esc
    # Rule 8 on the ship part only: obstacles and the close-range guard keep their full say afterwards
    apparent = ca.sum2(active * t["threat"]) > 0
    delta = wrap_angle(ca.atan2(ships[1], ships[0]) - psi_goal)
    delta_min = ca.if_else(delta > -dpsi_min, ca.fmax(delta, dpsi_min), delta)  # starboard unless the field turns
    # to port by more than the minimum itself (several neighbours, an overtaker on the own starboard side)
    psi_s = psi_goal + ca.if_else(apparent, delta_min, delta)
    ships = ca.sqrt(ca.sumsqr(ships)) * ca.vertcat(ca.cos(psi_s), ca.sin(psi_s))
    vor_static = ca.sum2(vortex(own_pos, nb_pos, active * (1 - t["ship"]) * t["k_vor"]))
    rep = ca.sum2((ca.repmat(own_pos, 1, m) - nb_pos) * ca.repmat(active * t["guard"] / t["d"], 2, 1))
    out = ships + vor_static + rep
    # close quarters: keep the field's heading unless it leads into the cone of something within r_cq
    close = active * (t["d"] < r_cq)
    psi_f = ca.atan2(out[1], out[0])
    # the heading the ship turns through next: at most dpsi_cq from its own on the way to the field's
    psi_next = own_psi + ca.fmin(ca.fmax(wrap_angle(psi_f - own_psi), -dpsi_cq), dpsi_cq)
    speed = ca.fmax(ca.sqrt(ca.sumsqr(own_vel)), 1e-6)
    ok = heading_feasible(own_pos, speed, psi_next, nb_pos, nb_vel, close, collision_distance=d_cq)
    psi_pref = own_psi + dpsi_min  # a readily apparent alteration to starboard (Rule 8) is preferred
    e_pref = ca.vertcat(ca.cos(psi_pref), ca.sin(psi_pref))
    psi_vo = velocity_obstacle(own_pos, speed, own_pos + e_pref, nb_pos, nb_vel, close, collision_distance=d_cq,
                               n_candidates=n_candidates, current_heading=own_psi)
    psi_out = ca.if_else(ok, psi_f, psi_vo)
    return ca.sqrt(ca.sumsqr(out)) * ca.vertcat(ca.cos(psi_out), ca.sin(psi_out))
