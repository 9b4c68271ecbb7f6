"""The land test of the velocity obstacle (:mod:`mmg_casadi.guidance.velocity_obstacle`) and of ``colregs-vortex``:
which candidate headings' straight paths reach a wall or land edge.

A heading is blocked when the straight path at the present speed over the horizon T (``vo_land_horizon``) comes
within the clearance (half the beam plus ``vo_land_margin``) of a segment (:func:`land_blocked`), closed-form and
branch-free per candidate and segment; in the closed loop a conditional skips every segment beyond the path's
reach (:func:`_land_function`), so the cost grows with the segments near the ship only.
"""

from __future__ import annotations

import functools
import math

import casadi as ca
import numpy as np

from mmg_casadi.guidance.fields import R_MIN, _col2, _matrix


def _has_walls(walls):
    """Whether ``walls`` holds at least one segment (None and 4×0 hold none)."""
    return walls is not None and _matrix(walls, 4).size2() > 0


def _path_blocked(own_pos, reach, clearance, wall, cos_u, sin_u):
    """0/1 per direction u = (``cos_u``, ``sin_u``) (rows of numbers or expressions): 1 when the straight path
    from ``own_pos`` of length ``reach`` along u comes within ``clearance`` of the segment ``wall`` = (ax, ay, bx,
    by); for a ship already within ``clearance`` of it, when u heads closer to it (distance from a straight path
    to a segment is convex along the path, so it then never gets closer).

    Branch-free: the segment–segment distance is below r when the two cross properly or one of the four
    endpoint-to-segment distances is below r (squared distances, no square roots)."""
    ex, ey = wall[2] - wall[0], wall[3] - wall[1]
    ee = ca.fmax(ex * ex + ey * ey, R_MIN ** 2)
    ax, ay = wall[0] - own_pos[0], wall[1] - own_pos[1]  # a − p
    bx, by = wall[2] - own_pos[0], wall[3] - own_pos[1]  # b − p
    r2 = clearance * clearance
    # gap g = p − c0 from the segment's point c0 nearest to the own position
    t0 = ca.fmin(ca.fmax(-(ax * ex + ay * ey) / ee, 0), 1)
    gx, gy = -ax - t0 * ex, -ay - t0 * ey
    inside = gx * gx + gy * gy < r2
    # path end q = p + reach u against the segment: q − a = reach u − (a − p)
    qx, qy = reach * cos_u - ax, reach * sin_u - ay
    tq = ca.fmin(ca.fmax((qx * ex + qy * ey) / ee, 0), 1)
    near_q = (qx - tq * ex) ** 2 + (qy - tq * ey) ** 2 < r2
    # segment endpoints against the path: s = clamp((a − p)·u, 0, reach), |a − p − s u|² = |a − p|² − 2 s (a − p)·u + s²
    pa, pb = ax * cos_u + ay * sin_u, bx * cos_u + by * sin_u
    sa, sb = ca.fmin(ca.fmax(pa, 0), reach), ca.fmin(ca.fmax(pb, 0), reach)
    near_a = ax * ax + ay * ay - 2 * sa * pa + sa * sa < r2
    near_b = bx * bx + by * by - 2 * sb * pb + sb * sb < r2
    # proper crossing: a, b on opposite sides of the path's line and p, q on opposite sides of the segment's line
    side_a, side_b = cos_u * ay - sin_u * ax, cos_u * by - sin_u * bx  # u × (a − p), u × (b − p)
    k0 = ey * ax - ex * ay  # e × (p − a)
    kq = k0 + reach * (ex * sin_u - ey * cos_u)  # e × (q − a) = e × (p − a) + reach e × u
    crossing = (side_a * side_b < 0) * (k0 * kq < 0)
    near = (crossing + near_q + near_a + near_b) > 0
    approach = gx * cos_u + gy * sin_u < 0  # d/ds |p + s u − c0| < 0 at s = 0
    return inside * approach + (1 - inside) * near


def land_blocked(own_pos, own_speed, headings, walls, *, clearance, horizon):
    """1 for each heading whose straight path at ``own_speed`` over ``horizon`` reaches land, else 0.

    A heading ψ is blocked when the path ``own_pos + s (cos ψ, sin ψ)``, 0 ≤ s ≤ ``own_speed · horizon``, comes
    within ``clearance`` of some segment of ``walls`` (channel walls and land edges; for a ship already within
    ``clearance`` of a segment, when ψ heads closer to it). The velocity obstacle treats a blocked heading as
    inadmissible (``walls`` of :func:`velocity_obstacle`).

    Parameters
    ----------
    own_pos : array-like (2,) or casadi.SX
        Own-ship position (L).
    own_speed : float or casadi scalar
        Own-ship speed (U).
    headings : array-like (n,) or casadi scalar
        Headings tested (rad).
    walls : array-like (4, W) or casadi matrix
        Segments (ax, ay, bx, by), one column each (L).
    clearance : float or casadi scalar
        Distance from a segment the path must keep (L): the ship's half beam plus ``vo_land_margin``.
    horizon : float or casadi scalar
        Time over which the path is followed (L/U; the table's ``vo_land_horizon``).

    Returns
    -------
    casadi.DM or casadi.SX or casadi.MX
        1×n row of 0/1 (a DM for numeric inputs).

    Examples
    --------
    >>> shore = [[20.0], [-50.0], [20.0], [50.0]]  # a coast along x = 20 L
    >>> land_blocked([0, 0], 1.0, [0.0, 0.5, 1.0, 1.5], shore, clearance=1.0, horizon=25.0)
    DM([[1, 1, 0, 0]])
    """
    own_pos, walls = _col2(own_pos), _matrix(walls, 4)
    if isinstance(headings, (ca.SX, ca.MX)):
        cos_u, sin_u = ca.cos(ca.vec(headings).T), ca.sin(ca.vec(headings).T)
    else:
        h = np.asarray(headings, dtype=float).reshape(1, -1)
        cos_u, sin_u = ca.DM(np.cos(h)), ca.DM(np.sin(h))
    reach = own_speed * horizon  # path length (eq. land_reach)
    hit = 0
    for k in range(walls.size2()):
        hit = hit + _path_blocked(own_pos, reach, clearance, walls[:, k], cos_u, sin_u)
    return hit > 0


@functools.lru_cache(maxsize=None)
def _land_pass(n):
    """One segment's step of the candidates' land test: ``(acc, wall, own_pos, reach, clearance) -> acc`` where
    ``acc`` (n) counts the segments blocking each candidate; a segment farther than ``reach + clearance`` cannot
    block any and is skipped (a conditional: its test is not evaluated, so the cost grows with the segments
    near the ship only)."""
    acc, wall, own, reach, r = ca.SX.sym("acc", n), ca.SX.sym("wall", 4), ca.SX.sym("own", 2), ca.SX.sym("L"), \
        ca.SX.sym("r")
    theta = -math.pi + 2 * math.pi * np.arange(n) / n
    blocked = _path_blocked(own, reach, r, wall, ca.DM(np.cos(theta).reshape(1, -1)),
                            ca.DM(np.sin(theta).reshape(1, -1)))
    ins = [acc, wall, own, reach, r]
    near = ca.Function(f"vo_land_near_n{n}", ins, [acc + blocked.T])
    far = ca.Function(f"vo_land_far_n{n}", ins, [acc])
    cond = ca.Function.conditional(f"vo_land_switch_n{n}", [near], far)
    xm = [ca.MX.sym(f"x{i}", v.sparsity()) for i, v in enumerate(ins)]
    a, b, p = xm[1][0:2], xm[1][2:4], xm[2]
    ab = b - a
    t = ca.fmin(ca.fmax(ca.dot(p - a, ab) / ca.fmax(ca.dot(ab, ab), R_MIN ** 2), 0), 1)
    gap = p - a - t * ab
    far_away = ca.sumsqr(gap) >= (xm[3] + xm[4]) ** 2  # index 1: the far branch
    return ca.Function(f"vo_land_pass_n{n}", xm, [cond(far_away, *xm)])


@functools.lru_cache(maxsize=None)
def _land_function(n, w):
    """Never-inlined ``(own_pos, reach, clearance, walls 4×w) -> blocked`` (n×1, 0/1) for the ``n`` candidates:
    a loop (``mapaccum``) of :func:`_land_pass` over the segments."""
    own, reach, r, walls = ca.MX.sym("own", 2), ca.MX.sym("L"), ca.MX.sym("r"), ca.MX.sym("walls", 4, w)
    acc = _land_pass(n).mapaccum(w)(ca.DM.zeros(n, 1), walls, ca.repmat(own, 1, w), ca.repmat(reach, 1, w),
                                    ca.repmat(r, 1, w))[:, -1]
    return ca.Function(f"vo_land_n{n}_w{w}", [own, reach, r, walls], [acc > 0], {"never_inline": True})
