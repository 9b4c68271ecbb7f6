"""Linear velocity obstacle (LVO) baseline at constant speed (Huang et al. 2018, Ocean Eng. 151; paper §5).

The own ship keeps its current speed and chooses a heading among ``n_candidates`` headings
θ_j = −π + 2π j / n (j = 0 … n−1). For every active neighbour i (the caller's 0/1 mask: it exists and lies
within R_safe) the candidate velocity v_j is forbidden when the relative velocity w = v_j − v_i points into the
collision cone about the line of sight p_i − p_own, i.e. the angle between w and p_i − p_own is below the cone's
half-angle α_i and w ≠ 0 (testing w instead of v_j is the cone's apex shifted by the neighbour's velocity). Two
cones are offered, d the distance to the neighbour and D the collision distance (combined radius):

* ``"huang"``: α = asin(min(1, D/d)), the exact cone of relative velocities whose straight line passes within D
  (the linear velocity obstacle of Huang et al. 2018 the paper follows; the default);
* ``"wide"``: α = min(π/2, 2 atan(D/d)), the wider cone of the laboratory's later version (a superset).

The chosen heading is the feasible candidate closest to the goal direction. Near-ties (within 1e-6 rad) go to
the candidate closest to ``current_heading`` when it is given, else to starboard of the goal direction (as COLREG
rules 14–15 ask). When no candidate is feasible the fallback picks the least-bad heading: the candidate whose
largest penetration max_i (α_i − angle_ij) over the neighbours forbidding it is smallest, ties broken by the goal
cost as above. All selection is done with CasADi ``if_else`` folds, so every argument may be symbolic (SX or MX);
plain numbers, numpy arrays and DM give DM.

**Combined radius D.** The cone is built around the neighbour's *centre* with D = the collision distance (2 L,
the paper's collision threshold between ship centres). Huang et al. enlarge each agent to a disc and use the sum
of the two radii; our outcome judges a collision by the distance between centres (2 L for ship–ship and
ship–obstacle alike), so a velocity outside the cone of half-angle asin(D/d) is exactly one whose straight line
keeps the centres at least D apart — the VO avoids what the outcome counts, no more, no less.

**Hold or re-pick** (:func:`hold_heading`). The paper describes the VO as selecting a velocity that avoids
collision and maintaining it "until it steers clear of the other vessel" (§Statistical Analysis). With ``hold``
the ship keeps a remembered heading while the velocity at that heading (at the current speed) stays outside
every active cone, and picks again (the goal-closest feasible candidate) when it becomes forbidden; while no
neighbour is within R_safe the memory follows the ship's heading, so the choice starts afresh at the next
encounter. Without ``hold`` the goal-closest feasible candidate is picked at every step.

**Land** (``walls``, :func:`~mmg_casadi.guidance.land_test.land_blocked`). With wall and land segments, a candidate whose straight path at the
present speed over the horizon T (``vo_land_horizon``) comes within the clearance (half the beam plus
``vo_land_margin``) of a segment is inadmissible too, and in the fallback it comes after every candidate clear of
land (:data:`LAND_PENALTY`); the held heading is dropped when its path reaches land. The closed loop passes the
segments only in layouts that have some, so without walls none of these expressions exists.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mmg_casadi.errors import ParameterError, check_range
from mmg_casadi.guidance.fields import R_MIN, _col2, _matrix, _row
from mmg_casadi.guidance.ilos import wrap_angle
from mmg_casadi.guidance.land_test import _has_walls, _land_function, _path_blocked, land_blocked  # noqa: F401
from mmg_casadi.params import PARAMETERS

CONES = ("huang", "wide")
TIE_EPS = 1e-6
"""Weight (rad) of the tie-break term added to the goal cost."""
_PEN_TOL = 1e-9
_BIG = 1e9
LAND_PENALTY = 2 * math.pi
"""Added to the penetration (rad) of a candidate whose path reaches land: more than any cone's (at most π/2; −π without one),
so the fallback takes the least-penetrating heading clear of land, and a heading towards land only when all are."""


@dataclass(frozen=True)
class VelocityObstacleParams:
    """Velocity-obstacle parameters.

    ``collision_distance``: combined radius D of the cone (L, > 0; the collision threshold, 2 L);
    ``n_candidates``: number of candidate headings evenly spread around the circle (integer ≥ 2);
    ``cone``: ``"huang"`` (half-angle asin(min(1, D/d)), Huang et al. 2018, the default) or ``"wide"``
    (half-angle min(π/2, 2 atan(D/d)), the laboratory's later version).

    Parameters
    ----------
    collision_distance : float, default 2.0
        Combined radius D of the cone (L, > 0).
    n_candidates : int, default 80
        Number of candidate headings evenly spread around the circle (≥ 2).
    cone : str, default 'huang'
        Cone formula, ``"huang"`` or ``"wide"``.
    """

    collision_distance: float = PARAMETERS["collision_distance"].default
    n_candidates: int = PARAMETERS["vo_candidates"].default
    cone: str = PARAMETERS["vo_cone"].default

    def __post_init__(self):
        check_range("collision_distance", self.collision_distance, 0.0, None, low_open=True, unit="L")
        _check_structure(self.n_candidates, self.cone)


def _check_structure(n_candidates, cone):
    if isinstance(n_candidates, bool) or not isinstance(n_candidates, (int, np.integer)) or n_candidates < 2:
        raise ParameterError("n_candidates", "an integer >= 2", n_candidates)
    if cone not in CONES:
        raise ParameterError("cone", "one of 'huang', 'wide'", cone)


def _half_angle(d, collision_distance, cone):
    """Half-angle of the collision cone of a neighbour at distance ``d``."""
    ratio = collision_distance / d
    if cone == "huang":
        return ca.asin(ca.fmin(1, ratio))
    return ca.fmin(ca.pi / 2, 2 * ca.atan(ratio))


def velocity_obstacle_terms(own_pos, own_speed, goal, nb_pos, nb_vel, active, *, collision_distance,
                            n_candidates, cone=PARAMETERS["vo_cone"].default, current_heading=None, walls=None,
                            clearance=None, horizon=None):
    """Candidate headings and their feasibility, penetration and goal cost.

    Returns a dict: ``headings`` (1×n, θ_j), ``forbidden`` (M×n, 1 where neighbour i forbids candidate j),
    ``feasible`` (1×n), ``penetration`` (1×n, max_i (α_i − angle_ij) over the neighbours forbidding j, −π when
    none does), ``cost`` (1×n, ``|wrap(θ_j − θ_goal)|`` plus the tie-break term), ``half_angle`` (1×M, α_i) and
    ``goal_heading`` (θ_goal).

    Parameters
    ----------
    own_pos : array-like (2,) or casadi.SX
        Own-ship position (L).
    own_speed : float or casadi.SX
        Own-ship speed, the length of every candidate velocity (L per unit time).
    goal : array-like (2,) or casadi.SX
        Goal position (L).
    nb_pos : array-like (2, M) or casadi.SX
        Neighbour positions, one column per neighbour (L).
    nb_vel : array-like (2, M) or casadi.SX
        Neighbour velocities, one column per neighbour (same units as ``own_speed``).
    active : array-like (M,) or casadi.SX
        1 for a neighbour that counts, 0 for one that is ignored.
    collision_distance : float
        Combined radius D of the cone (L).
    n_candidates : int
        Number of candidate headings evenly spread around the circle.
    cone : str, default 'huang'
        Cone formula, ``"huang"`` or ``"wide"`` (see :class:`VelocityObstacleParams`).
    current_heading : float or casadi.SX, optional
        Current heading (rad); near-ties go to the candidate closest to it (default: starboard of the goal direction).
    walls : array-like (4, W) or casadi matrix, optional
        Wall and land segments (ax, ay, bx, by), one column each (L): a candidate whose straight path reaches one
        (:func:`land_blocked`) is infeasible and its penetration is raised by 2π, so the fallback prefers any
        heading clear of land. None (or no column): no land test.
    clearance : float or casadi scalar, optional
        Distance the path keeps from the segments (L); needed with ``walls``.
    horizon : float or casadi scalar, optional
        Time over which the path is followed (L/U); needed with ``walls``.

    Returns
    -------
    dict
        ``headings``, ``forbidden``, ``feasible``, ``penetration`` (rad), ``cost`` (rad), ``half_angle`` (rad) and
        ``goal_heading`` (rad), as described above; CasADi expressions.

    Examples
    --------
    >>> import casadi as ca
    >>> t = velocity_obstacle_terms([0, 0], 1.0, [50, 0], ca.DM([[10], [0]]), ca.DM.zeros(2, 1), [1],
    ...                             collision_distance=2.0, n_candidates=8, cone="huang")
    >>> t["forbidden"]  # candidates at -180, -135, ..., 135 deg; only 0 deg points into the cone
    DM([[0, 0, 0, 0, 1, 0, 0, 0]])
    """
    _check_structure(n_candidates, cone)
    theta = -math.pi + 2 * math.pi * np.arange(int(n_candidates)) / int(n_candidates)
    blocked = None
    if _has_walls(walls):
        blocked = land_blocked(own_pos, own_speed, theta, walls, clearance=clearance, horizon=horizon)
    return _candidate_terms(own_pos, own_speed, goal, nb_pos, nb_vel, active, collision_distance, cone,
                            ca.DM(theta.reshape(1, -1)), ca.DM(np.vstack([np.cos(theta), np.sin(theta)])),
                            current_heading, blocked)


def _candidate_terms(own_pos, own_speed, goal, nb_pos, nb_vel, active, collision_distance, cone, headings,
                     directions, current_heading=None, blocked=None):
    """:func:`velocity_obstacle_terms` for the candidate headings ``headings`` (1×n) with unit directions
    ``directions`` (2×n): numbers (all candidates unrolled) or symbols (one candidate of a mapped loop);
    ``blocked`` (1×n, 0/1) marks the candidates whose path reaches land (None: no land test)."""
    own_pos, goal, nb_pos, nb_vel = _col2(own_pos), _col2(goal), _matrix(nb_pos, 2), _matrix(nb_vel, 2)
    m, n = nb_pos.size2(), headings.size2()
    active = _row(active, m)
    v_cand = own_speed * directions
    forbidden, penetration, halves = [], ca.DM.ones(1, n) * -math.pi, []
    for i in range(m):
        los = nb_pos[:, i] - own_pos
        half = _half_angle(ca.fmax(ca.norm_2(los), R_MIN), collision_distance, cone)
        w = v_cand - ca.repmat(nb_vel[:, i], 1, n)  # relative velocity: apex shifted by the neighbour's velocity
        dot = los[0] * w[0, :] + los[1] * w[1, :]
        cross = los[0] * w[1, :] - los[1] * w[0, :]
        angle = ca.atan2(ca.fabs(cross), dot)
        forb = active[i] * (ca.sum1(w * w) > 1e-12) * (angle < half)
        penetration = ca.fmax(penetration, forb * (half - angle) + (1 - forb) * -math.pi)
        forbidden.append(forb)
        halves.append(half)
    forbidden = ca.vertcat(*forbidden) if m else ca.DM.zeros(0, n)
    feasible = ca.DM.ones(1, n)
    for i in range(m):
        feasible = feasible * (1 - forbidden[i, :])
    if blocked is not None:  # land: infeasible, and after every heading clear of land in the fallback
        feasible = feasible * (1 - blocked)
        penetration = penetration + LAND_PENALTY * blocked
    goal_heading = ca.atan2(goal[1] - own_pos[1], goal[0] - own_pos[0])
    off_goal = wrap_angle(headings - goal_heading)
    if current_heading is None:
        tie = off_goal < 0  # prefer starboard of the goal direction
    else:
        tie = ca.fabs(wrap_angle(headings - current_heading)) / ca.pi
    return {
        "headings": headings,
        "forbidden": forbidden,
        "feasible": feasible,
        "penetration": penetration,
        "cost": ca.fabs(off_goal) + TIE_EPS * tie,
        "half_angle": ca.horzcat(*halves) if m else ca.DM.zeros(1, 0),
        "goal_heading": goal_heading,
    }


def velocity_obstacle(own_pos, own_speed, goal, nb_pos, nb_vel, active, *, collision_distance, n_candidates,
                      cone=PARAMETERS["vo_cone"].default, current_heading=None, walls=None, clearance=None,
                      horizon=None):
    """Desired heading ψ_d (rad, (−π, π]) chosen by the constant-speed linear velocity obstacle.

    The feasible candidate with the smallest goal cost wins (strict <, so the first minimum in candidate order
    wins exact ties); with no feasible candidate, the one with the smallest penetration (see the module notes).

    Implementation: the cone test angle(w, l) < α is evaluated without trigonometry on the symbols, as
    ``sin(α)·(w·l) − cos(α)·|w × l| > 0`` (the sign of ``|w||l| sin(α − angle)``), with sin α and cos α from the
    cone formula algebraically and w·l, w × l linear in the numeric candidate directions. Only when no candidate is
    feasible, or in the degenerate cases where that test might not be the same decision (an active neighbour
    within R_MIN of the own position, e.g. exactly on it, or ``|own speed − neighbour speed| ≤ 1e-5`` so that some w
    may be ~0), the direct implementation (the one this replaces) is evaluated — inside a conditional
    (``Function.conditional``) called as a never-inlined node, so it costs nothing otherwise. The whole guidance
    is itself a never-inlined Function per (neighbour count, candidates, cone), so a closed loop of many ships
    generates and compiles its code once.

    Parameters
    ----------
    own_pos : array-like (2,) or casadi.SX
        Own-ship position (L).
    own_speed : float or casadi.SX
        Own-ship speed, the length of every candidate velocity (L per unit time).
    goal : array-like (2,) or casadi.SX
        Goal position (L).
    nb_pos : array-like (2, M) or casadi.SX
        Neighbour positions, one column per neighbour (L).
    nb_vel : array-like (2, M) or casadi.SX
        Neighbour velocities, one column per neighbour (same units as ``own_speed``).
    active : array-like (M,) or casadi.SX
        1 for a neighbour that counts, 0 for one that is ignored.
    collision_distance : float
        Combined radius D of the cone (L).
    n_candidates : int
        Number of candidate headings evenly spread around the circle.
    cone : str, default 'huang'
        Cone formula, ``"huang"`` or ``"wide"`` (see :class:`VelocityObstacleParams`).
    current_heading : float or casadi.SX, optional
        Current heading (rad); near-ties go to the candidate closest to it (default: starboard of the goal direction).
    walls : array-like (4, W) or casadi matrix, optional
        Wall and land segments (ax, ay, bx, by), one column each (L): a candidate whose straight path at
        ``own_speed`` over ``horizon`` comes within ``clearance`` of one (:func:`land_blocked`) is inadmissible,
        and in the fallback it comes after every heading clear of land. None or no column: no land test (the
        expressions of the land test do not exist, the Function is the one without walls).
    clearance : float or casadi scalar, optional
        Distance the path keeps from the segments (L; the closed loop passes half the beam plus
        ``vo_land_margin``); needed with ``walls``.
    horizon : float or casadi scalar, optional
        Time over which the path is followed (L/U; ``vo_land_horizon``); needed with ``walls``.

    Returns
    -------
    casadi.DM or casadi.SX or casadi.MX
        Desired heading ψ_d (rad, in (−π, π]); a DM for numeric inputs.

    Examples
    --------
    >>> import casadi as ca
    >>> psi = velocity_obstacle([0, 0], 1.0, [50, 0], ca.DM([[10], [0]]), ca.DM.zeros(2, 1), [1],
    ...                         collision_distance=2.0, n_candidates=80, cone="wide")
    >>> round(float(psi) * 180 / ca.pi, 6)  # 22.5 deg is still inside the 22.6 deg cone: turn 27 deg to starboard
    27.0
    """
    _check_structure(n_candidates, cone)
    own_pos, goal, nb_pos, nb_vel = _col2(own_pos), _col2(goal), _matrix(nb_pos, 2), _matrix(nb_vel, 2)
    m, n = nb_pos.size2(), int(n_candidates)
    args = [own_pos, own_speed, goal, nb_pos, nb_vel, _row(active, m), collision_distance]
    if current_heading is not None:
        args.append(current_heading)
    if not _has_walls(walls):
        return _vo_function(m, n, cone, current_heading is not None)(*args)
    walls = _matrix(walls, 4)
    blocked = _land_function(n, walls.size2())(own_pos, own_speed * horizon, clearance, walls)  # eq. land_reach
    return _vo_function(m, n, cone, current_heading is not None, True)(*args, blocked)


@functools.lru_cache(maxsize=None)
def _vo_function(m, n, cone, with_heading, with_land=False):
    """The velocity obstacle for ``m`` neighbours as a never-inlined Function: a closed loop of many ships calls
    it once per ship but its code is generated (and compiled) only once. ``with_land`` adds a last input, the
    candidates' land test (n×1, 0/1, :func:`_land_function`)."""
    X = ca.MX if m else ca.SX  # MX keeps the loop over the neighbours a loop
    own, speed, goal = X.sym("own", 2), X.sym("U"), X.sym("goal", 2)
    nb, nbv, act, dist = X.sym("nb", 2, m), X.sym("nbv", 2, m), X.sym("a", 1, m), X.sym("D")
    ins = [own, speed, goal, nb, nbv, act, dist] + ([X.sym("h")] if with_heading else [])
    blocked = None
    if with_land:
        blocked = X.sym("land", n)
        ins.append(blocked)
    out = _velocity_obstacle_expr(own, speed, goal, nb, nbv, act, dist, n, cone, ins[7] if with_heading else None,
                                  blocked)
    tag = f"vo_m{m}_n{n}_{cone}{'_h' if with_heading else ''}{'_land' if with_land else ''}"
    return ca.Function(tag, ins, [out], {"never_inline": True})


def _velocity_obstacle_expr(own_pos, own_speed, goal, nb_pos, nb_vel, active, collision_distance, n, cone,
                            current_heading, blocked=None):
    """Expression of :func:`velocity_obstacle` (inputs already as CasADi matrices, ``n`` candidates).

    With neighbours it is generated as a loop (``mapaccum``) over them of :func:`_neighbour_pass` followed by
    :func:`_selection`: the same operations in the same order as unrolling them, in code whose size does not
    grow with the number of neighbours. ``blocked`` (n×1, 0/1; None without walls) adds the land test: a blocked
    candidate counts as forbidden once more, and when nothing is left the direct implementation's fallback
    decides (:data:`LAND_PENALTY`)."""
    m = nb_pos.size2()
    args = [own_pos, own_speed, goal, nb_pos, nb_vel, active, collision_distance]
    if current_heading is not None:
        args.append(current_heading)
    if m == 0:
        if blocked is None:
            psi, _ = _selection_expr(None, goal, own_pos, n, current_heading)
            return psi
        psi, best_c = _selection_expr([blocked[j] for j in range(n)], goal, own_pos, n, current_heading)
        direct = best_c >= _BIG / 2
        psi_direct = _direct_function(m, n, cone, current_heading is not None, True)(ca.logic_not(direct), *args,
                                                                                     blocked.T)
        return ca.if_else(direct, psi_direct, psi)
    acc = _neighbour_pass(n, cone).mapaccum(m)(
        ca.DM.zeros(n + 1, 1), ca.vertcat(nb_pos, nb_vel, active), ca.repmat(own_pos, 1, m),
        ca.repmat(own_speed, 1, m), ca.repmat(collision_distance, 1, m))[:, -1]
    sel_acc = acc if blocked is None else acc + ca.vertcat(blocked, 0)
    sel_args = [sel_acc, goal, own_pos] + ([current_heading] if current_heading is not None else [])
    psi, best_c = _selection(n, current_heading is not None)(*sel_args)
    direct = (best_c >= _BIG / 2) + (acc[n] > 0)
    if blocked is None:
        psi_direct = _direct_function(m, n, cone, current_heading is not None)(ca.logic_not(direct), *args)
    else:
        psi_direct = _direct_function(m, n, cone, current_heading is not None, True)(ca.logic_not(direct), *args,
                                                                                     blocked.T)
    return ca.if_else(direct, psi_direct, psi)


@functools.lru_cache(maxsize=None)
def _neighbour_pass(n, cone):
    """One neighbour's step of the velocity obstacle: ``(acc, [nb_pos; nb_vel; active], own_pos, own_speed, D)
    -> acc`` where ``acc[:n]`` counts the neighbours forbidding each candidate and ``acc[n]`` the degenerate ones
    (see :func:`velocity_obstacle`)."""
    acc, col = ca.SX.sym("acc", n + 1), ca.SX.sym("nb", 5)
    own_pos, own_speed, collision_distance = ca.SX.sym("own", 2), ca.SX.sym("U"), ca.SX.sym("D")
    theta = -math.pi + 2 * math.pi * np.arange(n) / n
    cos_t, sin_t = np.cos(theta), np.sin(theta)
    pair = n % 2 == 0
    half = n // 2 if pair else n
    # S_ij = sin α_i (l_i · w_ij) − cos α_i |l_i × w_ij| with w_ij = U (cos θ_j, sin θ_j) − v_i; forbidden ⟺ S_ij > 0
    nb_pos, nb_vel, active = col[0:2], col[2:4], col[4]
    los = nb_pos - own_pos
    dist_i = ca.norm_2(los)
    r = collision_distance / ca.fmax(dist_i, R_MIN)
    if cone == "huang":
        r1 = ca.fmin(1, r)
        sin_a, cos_a = r1, ca.sqrt(1 - r1 * r1)
    else:  # 2 atan(r) ≥ π/2 ⟺ r ≥ 1
        r1 = ca.fmin(1, r)
        q = 1 + r1 * r1
        sin_a, cos_a = 2 * r1 / q, (1 - r1 * r1) / q
    on = active == 1  # the direct product ∏(1 − active·forbidden) vanishes only for active == 1
    sin_a, cos_a = ca.if_else(on, sin_a, 0), ca.if_else(on, cos_a, 1)  # off: S = −|l × w| ≤ 0, never > 0
    us, ut = sin_a * own_speed, cos_a * own_speed
    a, b = us * los[0], us * los[1]
    k = sin_a * (los[0] * nb_vel[0] + los[1] * nb_vel[1])
    e, f = -ut * los[1], ut * los[0]
    g = cos_a * (los[0] * nb_vel[1] - los[1] * nb_vel[0])
    # S_ij > 0 ⟺ x − k > |y − g| ⟺ (x − y > k − g) ∧ (x + y > k + g), x = U sin α l·u_j, y = U cos α l×u_j:
    # both sides are linear in the candidate direction u_j; the opposite candidate (θ + π, n even) reuses the
    # products with the comparisons reversed
    p1, q1, k1, p2, q2, k2 = a - e, b - f, k - g, a + e, b + f, k + g
    m1, m2 = -k1, -k2
    hit = [None] * n
    for j in range(half):
        u1, u2 = p1 * cos_t[j] + q1 * sin_t[j], p2 * cos_t[j] + q2 * sin_t[j]
        hit[j] = ca.logic_and(u1 > k1, u2 > k2)
        if pair:
            hit[j + half] = ca.logic_and(u1 < m1, u2 < m2)
    speed_gap = ca.fabs(ca.fabs(own_speed) - ca.norm_2(nb_vel))
    degenerate = on * ((dist_i <= R_MIN) + (speed_gap <= 1e-5))
    out = ca.vertcat(*[acc[j] + hit[j] for j in range(n)], acc[n] + degenerate)
    return ca.Function(f"vo_neighbour_n{n}_{cone}", [acc, col, own_pos, own_speed, collision_distance], [out])


def _reduce(d):
    """``d`` in (−2π, 2π) brought into (−π, π] by adding or subtracting 2π (no trigonometry)."""
    return d - 2 * ca.pi * (d > ca.pi) + 2 * ca.pi * (d <= -ca.pi)


def _selection_expr(n_forb, goal, own_pos, n, current_heading):
    """The goal-closest candidate not forbidden (``n_forb[j] == 0``; all when ``n_forb`` is None) and its cost.

    The angles between candidates and the goal direction (and the current heading) are reduced to (−π, π] by
    adding or subtracting 2π instead of :func:`~mmg_casadi.guidance.ilos.wrap_angle` (atan2 of sine and cosine,
    the form of the direct implementation): the costs differ in the last bits only, so the chosen candidate
    is the same except at exact ties, and 2 × ``n`` trigonometric calls per evaluation are saved."""
    theta = -math.pi + 2 * math.pi * np.arange(n) / n
    goal_heading = ca.atan2(goal[1] - own_pos[1], goal[0] - own_pos[0])
    headings = ca.DM(theta.reshape(1, n))
    off_goal = _reduce(headings - goal_heading)
    if current_heading is None:
        tie = off_goal < 0
    else:
        tie = ca.fabs(_reduce(headings - wrap_angle(current_heading))) / ca.pi
    cost = ca.fabs(off_goal) + TIE_EPS * tie
    best_c, best_th = _BIG, goal_heading
    for j in range(n):
        ok = cost[j] < best_c if n_forb is None else (n_forb[j] == 0) * (cost[j] < best_c)
        best_c = ca.if_else(ok, cost[j], best_c)
        best_th = ca.if_else(ok, theta[j], best_th)
    return wrap_angle(best_th), best_c


@functools.lru_cache(maxsize=None)
def _selection(n, with_heading):
    """:func:`_selection_expr` as a Function ``(acc, goal, own_pos[, heading]) -> (psi, best cost)``."""
    acc, goal, own = ca.SX.sym("acc", n + 1), ca.SX.sym("goal", 2), ca.SX.sym("own", 2)
    ins = [acc, goal, own] + ([ca.SX.sym("h")] if with_heading else [])
    psi, best_c = _selection_expr([acc[j] for j in range(n)], goal, own, n, ins[3] if with_heading else None)
    return ca.Function(f"vo_select_n{n}{'_h' if with_heading else ''}", ins, [psi, best_c])


@functools.lru_cache(maxsize=None)
def _direct_function(m, n, cone, with_heading, with_land=False):
    """Never-inlined conditional: index 0 → the direct implementation, otherwise 0 (nothing evaluated).

    The direct implementation is generated as loops over the candidates (a ``map`` of one candidate's terms
    and a ``mapaccum`` of the selection), the same operations as :func:`_velocity_obstacle_reference` in the
    same order, so its code stays small: it runs only in the rare fallback and degenerate cases. ``with_land``
    adds a last input, the candidates' land test (1×n, 0/1)."""
    own, speed, goal = ca.SX.sym("own", 2), ca.SX.sym("U"), ca.SX.sym("goal", 2)
    nb, nbv, act, dist = ca.SX.sym("nb", 2, m), ca.SX.sym("nbv", 2, m), ca.SX.sym("a", 1, m), ca.SX.sym("D")
    ins = [own, speed, goal, nb, nbv, act, dist] + ([ca.SX.sym("h")] if with_heading else [])
    tag = f"vo_direct_m{m}_n{n}_{cone}{'_h' if with_heading else ''}{'_land' if with_land else ''}"
    th, u = ca.SX.sym("theta"), ca.SX.sym("u", 2)
    lead = [th, u]
    blk = None
    if with_land:
        blk = ca.SX.sym("land")
        lead.append(blk)
    t = _candidate_terms(own, speed, goal, nb, nbv, act, dist, cone, th, u, ins[7] if with_heading else None, blk)
    one = ca.Function(tag + "_candidate", lead + ins, [t["feasible"], t["cost"], t["penetration"]])
    state, inp = ca.SX.sym("best", 5), ca.SX.sym("cand", 4)
    best_c, best_th, fb_p, fb_c, fb_th = (state[k] for k in range(5))
    feasible, cost, pen, heading = (inp[k] for k in range(4))
    better = feasible * (cost < best_c)
    fb_better = (pen < fb_p - _PEN_TOL) + (ca.fabs(pen - fb_p) <= _PEN_TOL) * (cost < fb_c)
    fold = ca.Function(tag + "_select", [state, inp], [ca.vertcat(
        ca.if_else(better, cost, best_c), ca.if_else(better, heading, best_th),
        ca.if_else(fb_better, pen, fb_p), ca.if_else(fb_better, cost, fb_c), ca.if_else(fb_better, heading, fb_th))])
    theta = -math.pi + 2 * math.pi * np.arange(n) / n
    xm = [ca.MX.sym(f"x{i}", v.sparsity()) for i, v in enumerate(ins)]
    extra = [ca.MX.sym("land", 1, n)] if with_land else []
    headings = ca.DM(theta.reshape(1, n))
    feas, costs, pens = one.map(n)(headings, ca.DM(np.vstack([np.cos(theta), np.sin(theta)])), *extra, *xm)
    goal_heading = ca.atan2(xm[2][1] - xm[0][1], xm[2][0] - xm[0][0])
    init = ca.vertcat(_BIG, goal_heading, _BIG, _BIG, goal_heading)
    final = fold.mapaccum(n)(init, ca.vertcat(feas, costs, pens, headings))[:, -1]
    out = wrap_angle(ca.if_else(final[0] < _BIG / 2, final[1], final[4]))
    full = ca.Function(tag + "_eval", xm + extra, [out])
    skip = ca.Function(tag + "_skip", xm + extra, [ca.MX(0)])
    cond = ca.Function.conditional(tag + "_switch", [full], skip)
    xc = [ca.MX.sym(f"x{i}", *cond.size_in(i)) for i in range(cond.n_in())]
    return ca.Function(tag, xc, [cond(*xc)], {"never_inline": True})


def _velocity_obstacle_reference(own_pos, own_speed, goal, nb_pos, nb_vel, active, *, collision_distance,
                                 n_candidates, cone=PARAMETERS["vo_cone"].default, current_heading=None, walls=None,
                                 clearance=None, horizon=None):
    """The direct implementation (every candidate against every neighbour, trigonometric tests).

    Used by :func:`velocity_obstacle` for the fallback and the degenerate cases; see it for the semantics.
    """
    t = velocity_obstacle_terms(own_pos, own_speed, goal, nb_pos, nb_vel, active,
                                collision_distance=collision_distance, n_candidates=n_candidates, cone=cone,
                                current_heading=current_heading, walls=walls, clearance=clearance, horizon=horizon)
    headings, feasible, cost, pen = t["headings"], t["feasible"], t["cost"], t["penetration"]
    best_c, best_th = _BIG, t["goal_heading"]
    fb_p, fb_c, fb_th = _BIG, _BIG, t["goal_heading"]
    for j in range(headings.size2()):
        better = feasible[j] * (cost[j] < best_c)
        best_c = ca.if_else(better, cost[j], best_c)
        best_th = ca.if_else(better, headings[j], best_th)
        fb_better = (pen[j] < fb_p - _PEN_TOL) + (ca.fabs(pen[j] - fb_p) <= _PEN_TOL) * (cost[j] < fb_c)
        fb_p = ca.if_else(fb_better, pen[j], fb_p)
        fb_c = ca.if_else(fb_better, cost[j], fb_c)
        fb_th = ca.if_else(fb_better, headings[j], fb_th)
    return wrap_angle(ca.if_else(best_c < _BIG / 2, best_th, fb_th))


def heading_feasible(own_pos, own_speed, heading, nb_pos, nb_vel, active, *, collision_distance,
                     cone=PARAMETERS["vo_cone"].default, walls=None, clearance=None, horizon=None):
    """1 if the velocity ``own_speed`` (cos ψ, sin ψ) at ``heading`` ψ lies outside the cone of every active
    neighbour, else 0 (same cone test as :func:`velocity_obstacle_terms`: angle(w, l) < α and w ≠ 0); with
    ``walls``, also 0 when its straight path reaches land (:func:`land_blocked`).

    Parameters
    ----------
    own_pos : sequence of float or casadi.DM, SX or MX
        Own ship position (x, y) (L), a 2-vector.
    own_speed : float or casadi scalar
        Own ship speed (U), kept constant.
    heading : float or casadi scalar
        Heading ψ tested (rad).
    nb_pos : array_like or casadi matrix
        Neighbour positions (L), one column (x, y) per neighbour (2×M).
    nb_vel : array_like or casadi matrix
        Neighbour velocities (U), one column per neighbour (2×M).
    active : sequence of float or casadi row
        0/1 mask per neighbour (1×M; a scalar is repeated): only active neighbours have a cone.
    collision_distance : float, casadi scalar or row (1×M)
        Combined radius D of the cones (L); a row gives each neighbour its own.
    cone : {"huang", "wide"}
        Cone half-angle formula (see the module notes).
    walls : array_like or casadi matrix, optional
        Wall and land segments (4×W, L); None or no column: no land test.
    clearance : float or casadi scalar, optional
        Distance the path keeps from the segments (L); needed with ``walls``.
    horizon : float or casadi scalar, optional
        Time over which the path is followed (L/U); needed with ``walls``.

    Returns
    -------
    casadi.DM, SX or MX
        1 if the heading is feasible, else 0 (DM for numeric inputs).

    Examples
    --------
    >>> import casadi as ca
    >>> nb, v = ca.DM([[10], [0]]), ca.DM.zeros(2, 1)
    >>> [int(heading_feasible([0, 0], 1.0, h, nb, v, [1], collision_distance=2.0)) for h in (0.0, 0.2, 0.25)]
    [0, 0, 1]
    >>> int(heading_feasible([0, 0], 1.0, 0.0, nb, v, [0], collision_distance=2.0))  # inactive: no cone
    1
    >>> nb2, v2 = ca.DM([[10, 0], [0, 10]]), ca.DM.zeros(2, 2)  # ahead and abeam; the one ahead with D = 1
    >>> [int(heading_feasible([0, 0], 1.0, h, nb2, v2, [1, 1], collision_distance=[1.0, 2.0])) for h in (0.0, 0.15)]
    [0, 1]
    """
    _check_structure(2, cone)
    own_pos, nb_pos, nb_vel = _col2(own_pos), _matrix(nb_pos, 2), _matrix(nb_vel, 2)
    m = nb_pos.size2()
    active = _row(active, m)
    radius = _row(collision_distance, m)
    v = own_speed * ca.vertcat(ca.cos(heading), ca.sin(heading))
    ok = 1
    for i in range(m):
        los = nb_pos[:, i] - own_pos
        half = _half_angle(ca.fmax(ca.norm_2(los), R_MIN), radius[i], cone)
        w = v - nb_vel[:, i]
        angle = ca.atan2(ca.fabs(los[0] * w[1] - los[1] * w[0]), los[0] * w[0] + los[1] * w[1])
        forb = (active[i] > 0) * (ca.sumsqr(w) > 1e-12) * (angle < half)
        ok = ok * (1 - forb)
    if _has_walls(walls):
        ok = ok * (1 - land_blocked(own_pos, own_speed, heading, walls, clearance=clearance, horizon=horizon))
    return ok


def hold_heading(fresh, held, own_pos, own_speed, nb_pos, nb_vel, active, *, collision_distance,
                 cone=PARAMETERS["vo_cone"].default, walls=None, clearance=None, horizon=None):
    """The heading the ship steers with the paper's "keep the chosen velocity" behaviour.

    ``held`` (the remembered heading) while some neighbour is active and ``held`` is feasible
    (:func:`heading_feasible`); otherwise ``fresh`` (the heading :func:`velocity_obstacle` picks now).

    Parameters
    ----------
    fresh : float or casadi scalar
        Heading chosen afresh at this step (rad), e.g. by :func:`velocity_obstacle`.
    held : float or casadi scalar
        Remembered heading (rad).
    own_pos : sequence of float or casadi.DM, SX or MX
        Own ship position (x, y) (L), a 2-vector.
    own_speed : float or casadi scalar
        Own ship speed (U) at which ``held`` is tested.
    nb_pos : array_like or casadi matrix
        Neighbour positions (L), one column (x, y) per neighbour (2×M).
    nb_vel : array_like or casadi matrix
        Neighbour velocities (U), one column per neighbour (2×M).
    active : sequence of float or casadi row
        0/1 mask per neighbour (1×M; a scalar is repeated): exists and lies within R_safe.
    collision_distance : float or casadi scalar
        Combined radius D of the cones (L).
    cone : {"huang", "wide"}
        Cone half-angle formula (see the module notes).
    walls, clearance, horizon : optional
        The land test of :func:`heading_feasible`: ``held`` is also dropped when its path reaches land.

    Returns
    -------
    casadi.DM, SX or MX
        ``held`` or ``fresh`` (rad).

    Examples
    --------
    >>> import casadi as ca
    >>> nb, v = ca.DM([[10], [0]]), ca.DM.zeros(2, 1)
    >>> kw = dict(collision_distance=2.0, cone="huang")
    >>> float(hold_heading(0.3, 0.5, [0, 0], 1.0, nb, v, [1], **kw))  # 0.5 rad still clear: keep it
    0.5
    >>> float(hold_heading(0.3, 0.1, [0, 0], 1.0, nb, v, [1], **kw))  # 0.1 rad forbidden: choose again
    0.3
    >>> float(hold_heading(0.3, 0.5, [0, 0], 1.0, nb, v, [0], **kw))  # nobody within R_safe: fresh choice
    0.3
    """
    m = _matrix(nb_pos, 2).size2()
    act = _row(active, m)
    any_active = ca.sum2(act) > 0 if m else 0
    ok = heading_feasible(own_pos, own_speed, held, nb_pos, nb_vel, act, collision_distance=collision_distance,
                          cone=cone, walls=walls, clearance=clearance, horizon=horizon)
    return ca.if_else(any_active * ok, held, fresh)


def speed_levels(service_rpm, dead_slow_rpm, rpm_per_speed, n_levels):
    """Propeller speeds and steady speeds of the levels searched by :func:`velocity_obstacle_speed`.

    ``n_levels`` propeller speeds evenly spaced from the service rpm (level 0) down to dead slow ahead
    (level ``n_levels - 1``); a ship whose service rpm is already at or below dead slow has every level at its
    service rpm. The steady speed of each level is its rpm over ``rpm_per_speed``: in this model the steady
    straight-line speed is proportional to the propeller speed (the surge balance X_H(u) + X_P(u, n) = 0 is
    homogeneous of degree 2 in u and n: X_H ∝ u², X_P ∝ n² K_T(J), J ∝ u/n), so the rpm of the speed
    ``s`` is ``s`` times :func:`~mmg_casadi.vessel.mmg.propeller_rpm_for_speed` (1).

    Parameters
    ----------
    service_rpm : float or casadi scalar
        The ship's service propeller speed (rev/min), level 0.
    dead_slow_rpm : float or casadi scalar
        Dead slow ahead (rev/min), the last level.
    rpm_per_speed : float
        Propeller speed of the steady speed 1 U (rev/min per U).
    n_levels : int
        Number of levels (≥ 2).

    Returns
    -------
    list of (rpm, speed)
        One pair per level, level 0 first.

    Examples
    --------
    >>> [(float(n), float(s)) for n, s in speed_levels(100.0, 25.0, 100.0, 4)]
    [(100.0, 1.0), (75.0, 0.75), (50.0, 0.5), (25.0, 0.25)]
    """
    if isinstance(n_levels, bool) or not isinstance(n_levels, (int, np.integer)) or n_levels < 2:
        raise ParameterError("n_levels", "an integer >= 2", n_levels)
    span = ca.fmax(service_rpm - dead_slow_rpm, 0)
    out = []
    for k in range(int(n_levels)):
        rpm = service_rpm - (k / (n_levels - 1)) * span
        out.append((rpm, rpm / rpm_per_speed))
    return out


def velocity_obstacle_speed(own_pos, goal, nb_pos, nb_vel, active, *, levels, collision_distance, n_candidates,
                            speed_weight, cone=PARAMETERS["vo_cone"].default, walls=None, clearance=None,
                            horizon=None):
    """Desired heading and propeller speed chosen by the linear velocity obstacle over headings and speed levels.

    The constant-speed search of :func:`velocity_obstacle` is run at the steady speed of every level of
    ``levels`` (:func:`speed_levels`); a level counts when its heading passes the cone test
    (:func:`heading_feasible`) at that speed. Its cost is the distance of its velocity from the preferred
    velocity (the service speed towards the goal), over the service speed, plus ``speed_weight`` times the speed
    reduction as a fraction of the service speed: ``|v − v_pref| / V_0 + w (V_0 − V) / V_0``. With ``w = 0`` it
    is the selection rule of the velocity-obstacle literature, the admissible velocity closest to the preferred
    one (Fiorini & Shiller 1998, Int. J. Robot. Res. 17(7); van den Berg, Lin & Manocha 2008, ICRA); at one
    speed it is the heading closest to the goal direction, the rule of :func:`velocity_obstacle` (the paper's
    baseline), since ``|v − v_pref|`` grows with the angle. The counting level of least cost wins (strict <, so
    the faster level wins a tie); when no level counts the slowest level is taken with its own fallback heading
    (the least-penetrating candidate): slacken speed (COLREG Rule 8(e)) and steer the least-bad heading.

    The velocity obstacle of Huang et al. 2018 (Ocean Eng. 151) is a set of velocities, course and speed; the
    paper's baseline (and :func:`velocity_obstacle`) searches the headings at the present speed only. This
    function is the reading with speed changes, offered as the method ``velocity-obstacle-speed`` so the two
    readings can be compared on the same scenarios.

    Parameters
    ----------
    own_pos : array-like (2,) or casadi.SX
        Own-ship position (L).
    goal : array-like (2,) or casadi.SX
        Goal position (L).
    nb_pos : array-like (2, M) or casadi.SX
        Neighbour positions, one column per neighbour (L).
    nb_vel : array-like (2, M) or casadi.SX
        Neighbour velocities, one column per neighbour (U).
    active : array-like (M,) or casadi.SX
        1 for a neighbour that counts, 0 for one that is ignored.
    levels : list of (rpm, speed)
        The levels of :func:`speed_levels`, level 0 (the service speed) first.
    collision_distance : float or casadi scalar
        Combined radius D of the cone (L).
    n_candidates : int
        Number of candidate headings evenly spread around the circle.
    speed_weight : float or casadi scalar
        Extra cost of a speed reduction w (per unit of reduction, a fraction of the service speed; ≥ 0).
    cone : str, default 'huang'
        Cone formula, ``"huang"`` or ``"wide"`` (see :class:`VelocityObstacleParams`).
    walls, clearance, horizon : optional
        The land test of :func:`velocity_obstacle`, over the path the service level covers in ``horizon`` at every
        level (its horizon is stretched by the ratio of the speeds): a ship ordered to slow does not shed her way at
        once, so a slower order does not make a heading into land admissible.

    Returns
    -------
    psi : casadi.DM or casadi.SX or casadi.MX
        Desired heading (rad).
    rpm : casadi.DM or casadi.SX or casadi.MX
        Desired propeller speed (rev/min), that of the chosen level.
    level : casadi.DM or casadi.SX or casadi.MX
        Index of the chosen level in ``levels``.

    Examples
    --------
    A ship crossing from starboard, 5.7 L away: at the service speed the goal-closest free heading is 45° to
    starboard; at half speed 13.5° to port is free and closer to the preferred velocity; an extra weight of 1
    per unit of slowing makes the ship turn instead:

    >>> import casadi as ca
    >>> lv = speed_levels(100.0, 25.0, 100.0, 4)
    >>> nb, v = ca.DM([[4], [-4]]), ca.DM([[0], [1]])
    >>> kw = dict(levels=lv, collision_distance=2.0, n_candidates=80)
    >>> psi, rpm, k = velocity_obstacle_speed([0, 0], [50, 0], nb, v, [1], speed_weight=0.0, **kw)
    >>> round(float(psi) * 180 / ca.pi, 6), float(rpm), int(k)
    (-13.5, 50.0, 2)
    >>> psi, rpm, k = velocity_obstacle_speed([0, 0], [50, 0], nb, v, [1], speed_weight=1.0, **kw)
    >>> round(float(psi) * 180 / ca.pi, 6), float(rpm), int(k)
    (45.0, 100.0, 0)
    >>> psi, rpm, k = velocity_obstacle_speed([0, 0], [50, 0], nb, v, [0], speed_weight=0.0, **kw)
    >>> round(float(psi) * 180 / ca.pi, 6), float(rpm), int(k)  # nobody active: service rpm towards the goal
    (0.0, 100.0, 0)
    """
    own_pos, goal = _col2(own_pos), _col2(goal)
    goal_heading = ca.atan2(goal[1] - own_pos[1], goal[0] - own_pos[0])
    speed0 = levels[0][1]
    best_c, best_psi, best_rpm, best_k = _BIG, None, None, None
    for k, (rpm, speed) in enumerate(levels):
        # every level tests land over the service level's path: a ship ordered to slow does not shed her way at once
        land = dict(walls=walls, clearance=clearance, horizon=None if horizon is None else horizon * speed0 / speed)
        psi = velocity_obstacle(own_pos, speed, goal, nb_pos, nb_vel, active, collision_distance=collision_distance,
                                n_candidates=n_candidates, cone=cone, **land)
        ok = heading_feasible(own_pos, speed, psi, nb_pos, nb_vel, active, collision_distance=collision_distance,
                              cone=cone, **land)
        gap = 2 * speed * speed0 * (1 - ca.cos(psi - goal_heading)) + (speed0 - speed) ** 2
        cost = ca.sqrt(gap) / speed0 + speed_weight * (speed0 - speed) / speed0
        if k == 0:
            better = ok
            best_psi, best_rpm, best_k = psi, rpm, ca.DM(0)
        else:
            better = ok * (cost < best_c)
        best_c = ca.if_else(better, cost, best_c)
        best_psi = ca.if_else(better, psi, best_psi)
        best_rpm = ca.if_else(better, rpm, best_rpm)
        best_k = ca.if_else(better, k, best_k)
    found = best_c < _BIG / 2
    return (ca.if_else(found, best_psi, psi), ca.if_else(found, best_rpm, rpm),
            ca.if_else(found, best_k, len(levels) - 1))
