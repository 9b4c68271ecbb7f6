"""Hazards of the closed loop, one protocol for every kind: a distance, a field contribution and a collision rule.

A hazard kind declares how many numbers describe one hazard (its columns in the parameter vector), the distance
from a ship's centre to it, the distance below which a ship touches it (a collision, reported by kind), and its
contribution to the guidance field. Kinds (:data:`KINDS`):

- ``obstacle``: a circle ``(x, y, radius)``; the paper counts a collision when the ship's centre comes within
  the collision distance of the obstacle's centre (paper §Statistical Analysis). Circles are neighbours of every
  method (the fields repel them, the velocity obstacle builds their cones), so their field term is the method's.
- ``wall``: a straight segment ``(ax, ay, bx, by)``; its field is the paper's line source (§Narrow Waterways,
  :func:`mmg_casadi.guidance.fields.channel_walls`) added to every method's vector; a ship touches it when its
  centre comes within half its beam of the segment.
- ``land``: an edge of a land polygon, a segment like a wall (same field, same contact at half the beam); the
  layout keeps land edges as the last wall segments (``Layout.n_land``,
  :class:`~mmg_casadi.closed_loop.layout.Layout`), so the compiled step gives them the walls' field and contact,
  touching one is reported as a grounding, and the step also looks ahead for them
  (:mod:`mmg_casadi.guidance.land_ahead`).

Examples
--------
>>> import casadi as ca
>>> float(segment_distance(ca.DM([5.0, 2.0]), ca.DM([[0.0], [0.0], [10.0], [0.0]])))
2.0
>>> float(segment_distance(ca.DM([-3.0, 4.0]), ca.DM([[0.0], [0.0], [10.0], [0.0]])))
5.0
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import casadi as ca

from mmg_casadi.guidance import fields


def circle_distance(pos, h):
    """Distance from ``pos`` (2×1) to the centre of circle ``h = (x, y, radius)`` (L).

    Parameters
    ----------
    pos : SX or DM (2×1)
        Ship position (L).
    h : SX or DM (3×1)
        The circle's column of the parameter vector.

    Returns
    -------
    casadi.SX or casadi.DM
        Centre distance (L; the radius is not subtracted).
    """
    return ca.norm_2(pos - h[0:2])


def segment_distance(pos, h):
    """Distance from ``pos`` (2×1) to the segment ``h = (ax, ay, bx, by)`` (L).

    Parameters
    ----------
    pos : SX or DM (2×1)
        Ship position (L).
    h : SX or DM (4×1)
        The segment's column of the parameter vector.

    Returns
    -------
    casadi.SX or casadi.DM
        Distance to the nearest point of the segment (L).
    """
    a, b = h[0:2], h[2:4]
    ab = b - a
    t = ca.fmin(ca.fmax(ca.dot(pos - a, ab) / ca.fmax(ca.dot(ab, ab), fields.R_MIN ** 2), 0), 1)
    return ca.norm_2(pos - a - t * ab)


def _wall_field(pos, H, P):
    return fields.channel_walls(pos, H[0:2, :], H[2:4, :], lam=P["wall_lam"], d_act=P["wall_d_act"])


@dataclass(frozen=True)
class HazardKind:
    """One kind of hazard.

    Parameters
    ----------
    name : str
        Kind reported with a collision (``collision_kind`` of an outcome).
    columns : int
        Numbers per hazard in the parameter vector.
    distance : callable
        ``(pos, column) -> distance`` from a ship's centre (L).
    touch : str
        What the distance is compared with for a collision: ``"collision_distance"`` (the table's, between
        centres) or ``"half_beam"`` (half the ship's beam, from its centre).
    field : callable or None
        ``(pos, hazards 2-D, P) -> 2×1`` contribution added to every method's vector; ``None`` when the hazards are
        neighbours that the method itself sees.
    """

    name: str
    columns: int
    distance: Callable
    touch: str
    field: Callable | None = None


KINDS: dict[str, HazardKind] = {k.name: k for k in (
    HazardKind("obstacle", 3, circle_distance, "collision_distance"),
    HazardKind("wall", 4, segment_distance, "half_beam", _wall_field),
    HazardKind("land", 4, segment_distance, "half_beam", _wall_field),
)}
"""Every hazard kind, in the order of their blocks in the parameter vector and of their agent indices."""
