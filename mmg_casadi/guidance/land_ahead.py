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
>>> float(r["ahead"]), [float(v) for v in r["point"]], float(r["distance"])
(1.0, [20.0, 0.0], 20.0)
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
        a, ab = seg[0:2], seg[2:4] - seg[0:2]
        t = ca.fmin(ca.fmax(ca.dot(pos - a, ab) / ca.fmax(ca.dot(ab, ab), R_MIN ** 2), 0), 1)
        near = a + t * ab
        d2 = ca.sumsqr(pos - near)
        take = ca.logic_and(blocked, d2 < best)
        best = ca.if_else(take, d2, best)
        point = ca.if_else(take, near, point)
    ahead = best < _FAR / 2
    return {"ahead": ahead, "point": point, "distance": ca.if_else(ahead, ca.sqrt(best), _FAR)}


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
    >>> [float(c) for c in v]
    [-1.0, 0.0]
    """
    d = pos - point
    r2 = ca.fmax(ca.sumsqr(d), R_MIN ** 2)
    return lam / (2 * ca.pi * r2) * d
