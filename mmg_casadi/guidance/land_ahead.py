"""Land seen ahead: the look-ahead that switches a method on before land is within reach of the paper's wall field.

The paper's walls act within ``wall_d_act`` = 2 L (§Narrow Waterways), less than the room a KCS needs to turn away
(advance 3.56 L, tactical diameter 3.37 L at 35° rudder, :func:`mmg_casadi.vessel.maneuvers.turning_circle`). A
ship sailing at land with no other ship near would reach it under ILOS. So, in layouts with land, every ship looks
ahead along her course over the ground:

- **Look-ahead distance** ``D = land_lookahead × A``, ``A`` the **advance** of her own hull (the forward travel
  until her heading has turned 90° at her largest rudder angle, from her design speed; :func:`hull_advance`, in the
  scene's L). With the default ``land_lookahead`` = 2 advances: 7.1 L for the KCS (7.1 L/U at her design speed),
  4.3 L for a KVLCC2 in a KCS scene (3.09 of her own lengths). The advance is the distance below which a ship that
  starts turning can no longer turn parallel to a coast ahead; twice it leaves room for the rudder to come over
  (the steering gear's rate) and for a turn at less than hard-over (a method's turn, not an emergency one). The
  advance in ship lengths hardly depends on the speed, so ``D`` does not either (a slower ship has more time).
- **Land ahead** (:func:`land_seen_ahead`): the straight path from her position along her course over the ground
  over ``D`` comes within ``clearance`` = half her beam + ``grounding_margin`` + ``land_clearance`` of a land edge
  (the closed-form segment test of :func:`mmg_casadi.guidance.land_test.land_blocked`). While it does, her
  method is in charge whether or not a ship is near (:mod:`mmg_casadi.closed_loop.step`). Her path ahead is
  tested along her course and along the heading ILOS orders (so ILOS does not turn her back into land she has
  just turned away from).
- **The land term** of a method without a land test of its own (the fields; ``Method.land_test``): the paper's
  wall model, a line source of strength ``wall_lam`` (:func:`land_source`), at the point of land she would meet
  (the nearest point of the nearest edge that blocks her path), added to her method's vector from the look-ahead
  distance on instead of within ``wall_d_act``. The velocity obstacle and colregs-vortex test their candidate
  headings against the land themselves (:mod:`mmg_casadi.guidance.land_test`).

Channel walls keep the paper's wall model (they switch a method on within ``wall_d_act`` only), so the paper's
narrow-channel figures are those of the paper.

Examples
--------
>>> import casadi as ca
>>> coast = ca.DM([[20.0, -50.0, 20.0, 50.0]]).T            # a coast across the course, 20 L ahead
>>> r = land_seen_ahead(ca.DM([0, 0]), ca.DM([1, 0]), 25.0, 1.0, coast)
>>> float(r["ahead"]), r["point"].T, float(r["distance"])
(1.0, DM([[20, 0]]), 20.0)
>>> float(land_seen_ahead(ca.DM([0, 0]), ca.DM([1, 0]), 15.0, 1.0, coast)["ahead"])
0.0
"""

from __future__ import annotations

import functools

import casadi as ca

from mmg_casadi.guidance.fields import R_MIN, _matrix
from mmg_casadi.guidance.land_test import _path_blocked
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.maneuvers import turning_circle
from mmg_casadi.vessel.mmg import scene_scales

_FAR = 1.0e12


@functools.lru_cache(maxsize=None)
def hull_advance(vessel: str, unit: str) -> float:
    """The advance of ``vessel`` in the scene's length unit (``unit``'s L): the forward travel until her heading
    has turned 90° at her largest rudder angle, from her design speed (:func:`~mmg_casadi.vessel.maneuvers.turning_circle`).

    Parameters
    ----------
    vessel : str
        The hull (a name of :data:`~mmg_casadi.vessel.library.VESSELS`).
    unit : str
        The hull whose length is the scene's unit (the own ship's).

    Returns
    -------
    float
        The advance (L of ``unit``).

    Examples
    --------
    >>> round(hull_advance("kcs", "kcs"), 2), round(hull_advance("kvlcc2", "kcs"), 2)
    (3.56, 4.29)
    """
    v = load_vessel(vessel)
    turn = turning_circle(v.steering.delta_max_deg, ship=v.ship, steering=v.steering)
    lam, _ = scene_scales(v.ship, load_vessel(unit).ship)
    return float(turn.metrics["advance"]) * lam


def land_seen_ahead(pos, direction, reach, clearance, segments) -> dict:
    """Whether the straight path ahead comes within ``clearance`` of a segment, and the point of land met.

    Parameters
    ----------
    pos : SX or DM (2×1)
        The ship's position (L).
    direction : SX or DM (2×1)
        Unit vector of her course over the ground.
    reach : SX or float
        Length of the path ahead (L): the look-ahead distance ``D``.
    clearance : SX or float
        Distance from land the path must keep (L).
    segments : SX or DM (4×W)
        Land edges ``(ax, ay, bx, by)`` (L); W ≥ 1.

    Returns
    -------
    dict
        ``ahead`` (1 when some segment blocks the path, else 0), ``point`` (2×1, the nearest point of the nearest
        blocking segment, the ship's own position when none blocks) and ``distance`` (L, from the ship to that
        point; a large number when none blocks).
    """
    segments = _matrix(segments, 4)
    cos_u, sin_u = direction[0], direction[1]
    best, point = ca.SX(_FAR) if isinstance(pos, ca.SX) else ca.DM(_FAR), pos
    for k in range(segments.size2()):
        seg = segments[:, k]
        blocked = _path_blocked(pos, reach, clearance, seg, cos_u, sin_u)
        near, d2 = _nearest(pos, seg)
        take = ca.logic_and(blocked, d2 < best)
        best = ca.if_else(take, d2, best)
        point = ca.if_else(take, near, point)
    ahead = best < _FAR / 2
    return {"ahead": ahead, "point": point, "distance": ca.if_else(ahead, ca.sqrt(best), _FAR)}


def _nearest(pos, seg):
    """The point of segment ``seg`` nearest to ``pos`` and its squared distance."""
    a, ab = seg[0:2], seg[2:4] - seg[0:2]
    t = ca.fmin(ca.fmax(ca.dot(pos - a, ab) / ca.fmax(ca.dot(ab, ab), R_MIN ** 2), 0), 1)
    near = a + t * ab
    return near, ca.sumsqr(pos - near)


@functools.lru_cache(maxsize=None)
def _pass() -> ca.Function:
    """One segment's step of :func:`land_ahead_function`: ``(acc, seg, pos, course, ordered, reach, clearance) ->
    acc`` with ``acc`` = (best d², point) along the course, then along the ordered heading; a segment farther than
    ``reach + clearance`` cannot block either path and is skipped (a conditional: not evaluated)."""
    acc, seg, pos = ca.SX.sym("acc", 6), ca.SX.sym("seg", 4), ca.SX.sym("pos", 2)
    dc, do, reach, r = ca.SX.sym("course", 2), ca.SX.sym("ordered", 2), ca.SX.sym("reach"), ca.SX.sym("r")
    near, d2 = _nearest(pos, seg)
    out = []
    for k, u in enumerate((dc, do)):
        best, point = acc[3 * k], acc[3 * k + 1:3 * k + 3]
        take = ca.logic_and(_path_blocked(pos, reach, r, seg, u[0], u[1]), d2 < best)
        out += [ca.if_else(take, d2, best), ca.if_else(take, near, point)]
    ins = [acc, seg, pos, dc, do, reach, r]
    near_f = ca.Function("land_ahead_near", ins, [ca.vertcat(*out)], {"cse": True})
    far_f = ca.Function("land_ahead_far", ins, [acc])
    cond = ca.Function.conditional("land_ahead_switch", [near_f], far_f)
    xm = [ca.MX.sym(f"x{i}", v.sparsity()) for i, v in enumerate(ins)]
    a, b, p = xm[1][0:2], xm[1][2:4], xm[2]
    ab = b - a
    t = ca.fmin(ca.fmax(ca.dot(p - a, ab) / ca.fmax(ca.dot(ab, ab), R_MIN ** 2), 0), 1)
    far_away = ca.sumsqr(p - a - t * ab) >= (xm[5] + xm[6]) ** 2  # index 1: the far branch
    return ca.Function("land_ahead_pass", xm, [cond(far_away, *xm)])


@functools.lru_cache(maxsize=None)
def land_ahead_function(w: int) -> ca.Function:
    """Never-inlined ``(pos, course, ordered, reach, clearance, segments 4×w) -> (ahead_course, point_course,
    ahead_ordered, point_ordered)``: :func:`land_seen_ahead` along two directions at once, a loop (``mapaccum``)
    over the segments that skips those out of reach, so the cost grows with the land near the ship only.

    Parameters
    ----------
    w : int
        Number of land edges (≥ 1).

    Returns
    -------
    casadi.Function
        The function; per direction 1/0 and the point of land met (the ship's position when none).

    Examples
    --------
    >>> import casadi as ca
    >>> f = land_ahead_function(1)
    >>> out = f([0, 0], [1, 0], [0, 1], 25.0, 1.0, ca.DM([20.0, -50.0, 20.0, 50.0]))
    >>> float(out[0]), out[1].T, float(out[2])
    (1.0, DM([[20, 0]]), 0.0)
    """
    pos, dc, do = ca.MX.sym("pos", 2), ca.MX.sym("course", 2), ca.MX.sym("ordered", 2)
    reach, r, segs = ca.MX.sym("reach"), ca.MX.sym("r"), ca.MX.sym("segments", 4, w)
    init = ca.vertcat(_FAR, pos, _FAR, pos)
    acc = _pass().mapaccum(w)(init, segs, ca.repmat(pos, 1, w), ca.repmat(dc, 1, w), ca.repmat(do, 1, w),
                              ca.repmat(reach, 1, w), ca.repmat(r, 1, w))[:, -1]
    return ca.Function(f"land_ahead_w{w}", [pos, dc, do, reach, r, segs],
                       [acc[0] < _FAR / 2, acc[1:3], acc[3] < _FAR / 2, acc[4:6]], {"never_inline": True})


def land_source(pos, point, lam):
    """The paper's wall field (a line source, §Narrow Waterways, :func:`mmg_casadi.guidance.fields.channel_walls`)
    of the land edge met ahead, at ``pos``: ``Λ / (2π r)`` along ``pos − point``, ``point`` the nearest point of
    the edge (radial from a corner), ``r`` its distance (clipped at ``R_MIN``).

    Parameters
    ----------
    pos, point : SX or DM (2×1)
        The ship's position and the point of land met (L).
    lam : SX or float
        Source strength Λ (``wall_lam``, L²/(L/U)).

    Returns
    -------
    SX or DM (2×1)
        The field (L per L/U).

    Examples
    --------
    >>> import casadi as ca
    >>> v = land_source(ca.DM([0, 0]), ca.DM([5, 0]), 10 * ca.pi)
    >>> v.T
    DM([[-1, 0]])
    """
    d = pos - point
    r2 = ca.fmax(ca.sumsqr(d), R_MIN ** 2)
    return lam / (2 * ca.pi * r2) * d
