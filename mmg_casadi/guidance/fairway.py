"""The starboard lane of a narrow channel or fairway (COLREG Rule 9(a)), for the methods that keep the rule.

Rule 9(a): "A vessel proceeding along the course of a narrow channel or fairway shall keep as near to the outer
limit of the channel or fairway which lies on her starboard side as is safe and practicable."

**Cross-section.** Across the ship's route (the normal of the leg she sails, ``π_p``), the banks are the nearest
wall or land edges met on each side, at ``d_port`` and ``d_stbd``; she is in a *narrow channel* when both exist and
``w = d_port + d_stbd ≤ channel_width``. Her offset from the centre line is ``o = (d_port − d_stbd) / 2`` (> 0 to
starboard), as the Rule 9 scorer measures it (:mod:`mmg_casadi.colregs.narrow_channel`, there across the heading).

**Lane.** As near the starboard limit as is safe: ``bank_clearance`` from the starboard bank, ``o* = max(w/2 −
bank_clearance, 0)`` (the centre line in a channel narrower than twice the clearance). The lane error ``o − o*``
(> 0: starboard of the lane), clipped so that ILOS approaches the lane at no more than :data:`APPROACH_DEG`
from the route, replaces the route's cross-track error in ILOS (:func:`lane`), so ILOS, its integral included,
steers the lane while the ship is in the channel; a method in charge steers towards a goal moved onto
the lane (:mod:`mmg_casadi.closed_loop.step`: the direction ILOS would take to the lane, at the goal's distance, so
the sink's strength is the goal's own). The cross-section is taken at the ship and one look-ahead distance ahead
along the route (:mod:`mmg_casadi.guidance.land_ahead`): a ship moves onto the lane before she enters the
channel, and keeps it until she has left it. A section taken at a point on land (the point ahead beyond a
shore) is no channel.

Examples
--------
A channel 10 L wide along x (banks y = ±5 L), a ship northbound on its centre line: the lane is 3 L to starboard,
so the lane error is −3 L (port of the lane).

>>> import casadi as ca
>>> banks = ca.DM([[-50.0, -5.0, 150.0, -5.0], [-50.0, 5.0, 150.0, 5.0]]).T
>>> r = lane(ca.DM([10.0, 0.0]), 0.0, banks, width=20.0, clearance=2.0, ahead=7.0)
>>> float(r["in_channel"]), float(r["error"])
(1.0, -3.0)
"""

from __future__ import annotations

import casadi as ca

from mmg_casadi.guidance.fields import _matrix

_FAR = 1.0e12
_PARALLEL = 1e-12


APPROACH_DEG = 30.0
"""Largest angle (deg) between the route and the heading ILOS takes towards the lane: the lane error it sees is
clipped at ``Δ tan(30°)`` (Δ the ILOS look-ahead). Our choice: ILOS alone turns ``atan(e/Δ)``, 74° for a lane
7 L off with Δ = 2 L, which crosses a strait's mouth broadside; 30° moves a ship into her lane over about twice
the lateral distance, inside the look-ahead before the channel."""


def cross_section(point, normal, segments, first_land: int | None = None) -> tuple:
    """Distances from ``point`` to the nearest segment along ``-normal`` (port) and ``+normal`` (starboard).

    Parameters
    ----------
    point : SX or DM (2×1)
        Where the section is taken (L).
    normal : SX or DM (2×1)
        Unit normal to the route, pointing to starboard.
    segments : SX or DM (4×W)
        Walls and land edges (L).
    first_land : int, optional
        Index of the first land edge in ``segments`` (the others are walls): a point inside a land polygon (an odd
        number of its edges met to starboard) has no section; None: no land.

    Returns
    -------
    d_port, d_stbd : SX or DM
        Distances (L; a large number where no segment is met, and on both sides for a point on land).
    """
    segments = _matrix(segments, 4)
    d_port, d_stbd = _FAR, _FAR
    crossings = 0
    nx, ny = normal[0], normal[1]
    for k in range(segments.size2()):
        ax, ay = segments[0, k] - point[0], segments[1, k] - point[1]
        ex, ey = segments[2, k] - segments[0, k], segments[3, k] - segments[1, k]
        den = nx * ey - ny * ex  # n × e
        ok = ca.fabs(den) > _PARALLEL
        safe = ca.if_else(ok, den, 1.0)
        s = (ax * ey - ay * ex) / safe  # p + s n = a + u e
        u = (ax * ny - ay * nx) / safe
        hit = ok * (u >= 0) * (u <= 1)
        d_stbd = ca.if_else(hit * (s > 0), ca.fmin(d_stbd, s), d_stbd)
        d_port = ca.if_else(hit * (s < 0), ca.fmin(d_port, -s), d_port)
        if first_land is not None and k >= first_land:
            crossings = crossings + hit * (s > 0)
    if first_land is not None:  # on land: no channel here
        on_land = ca.fmod(crossings, 2) > 0.5
        d_port, d_stbd = ca.if_else(on_land, _FAR, d_port), ca.if_else(on_land, _FAR, d_stbd)
    return d_port, d_stbd


def _section_error(point, normal, segments, width, clearance, first_land):
    d_port, d_stbd = cross_section(point, normal, segments, first_land)
    w = d_port + d_stbd  # channel width across the route (eq. channel_width)
    inside = w <= width
    offset = 0.5 * (d_port - d_stbd)  # > 0: starboard of the centre line (eq. channel_offset)
    target = ca.fmax(0.5 * w - clearance, 0)  # as near the starboard limit as is safe
    return inside, ca.if_else(inside, offset - target, 0)


def lane(pos, pi_p, segments, *, width, clearance, ahead, first_land=None) -> dict:
    """The Rule 9 lane at ``pos`` for a route of direction ``pi_p``: whether the ship is in a narrow channel (at
    her position or ``ahead`` along the route) and her lateral error from the starboard lane.

    Parameters
    ----------
    pos : SX or DM (2×1)
        The ship's position (L).
    pi_p : SX or float
        Direction of the route's leg (rad).
    segments : SX or DM (4×W)
        Walls and land edges (L).
    width : SX or float
        Widest channel that counts as narrow (``channel_width``, L).
    clearance : SX or float
        Distance of the lane from the starboard bank (``bank_clearance``, L).
    ahead : SX or float
        How far ahead along the route the channel is also measured (L).
    first_land : int, optional
        Index of the first land edge in ``segments`` (:func:`cross_section`: no channel on land).

    Returns
    -------
    dict
        ``in_channel`` (0/1) and ``error`` (L, > 0 to starboard of the lane; 0 outside a channel): the section
        ``ahead`` when it is in a channel, else the one at the ship.
    """
    u = ca.vertcat(ca.cos(pi_p), ca.sin(pi_p))
    n = ca.vertcat(-u[1], u[0])  # starboard normal of the route
    in_here, e_here = _section_error(pos, n, segments, width, clearance, first_land)
    in_ahead, e_ahead = _section_error(pos + ahead * u, n, segments, width, clearance, first_land)
    return {"in_channel": ca.logic_or(in_here, in_ahead), "error": ca.if_else(in_ahead, e_ahead, e_here)}
