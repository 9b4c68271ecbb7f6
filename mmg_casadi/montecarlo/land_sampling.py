"""Environment 6 of the Monte Carlo (ours, not the paper's): a strait of random width with random islands and
traffic in both directions.

In the paper's 100 L × 100 L square (x north, y east), the strait runs north between two shores, each a
rectangle 20 L deep from x = 35 L to x = 65 L, leaving a channel of width ``w`` uniform in :data:`WIDTH_RANGE`
about y = 50 L. Two square islands (side uniform in :data:`ISLAND_SIDE`) lie in the open water off the strait's
mouths, one at each, beside the fairway: centre x uniform in [10, 25] L (south) and [75, 90] L (north), on a
side of the fairway chosen with equal odds, with a gap uniform in :data:`ISLAND_GAP` between the island and the
channel's band (the band in which routes run, 1.5 L inside the channel). Ships turning out of the fairway to
avoid each other meet them. The own ship and :data:`NORTHBOUND` targets start south of the strait
(x ∈ [0, 10] L) and are bound north (goal x ∈ [90, 100] L); :data:`SOUTHBOUND` targets the other way. Every start
and goal lies in the channel's band, 1.5 L inside it (so the straight route between them clears the shores),
starts are at least :data:`START_SEPARATION` apart, and a route that passes within :data:`ROUTE_CLEARANCE` of an
island is drawn again: no ship starts on land and every route stays in water. Initial headings are the bearing
of the goal plus a uniform offset within ±:data:`HEADING_SPREAD_DEG` (ships in a traffic lane, not the paper's
uniform headings, which would turn ships into the shores at the start); target speeds as in environments 1–5.

A scenario depends only on ``(run, base_seed)`` through ``SeedSequence([base_seed, 6, run])``; the draws are, in
order: width, island sides, island positions, starts and goals ship by ship (rejection), headings,
speeds. Every scenario has the same number of land edges (two shores and two islands, 4 edges each), so one
compiled closed loop serves the whole environment.
"""

from __future__ import annotations

import math

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.scenarios.scenario import LandSpec

ENVIRONMENT = 6
"""The strait's environment number."""
WIDTH_RANGE = (8.0, 16.0)
"""Channel width of the strait (L), uniform."""
STRAIT_X = (35.0, 65.0)
"""Southern and northern ends of the shores (L)."""
SHORE_DEPTH = 20.0
"""How far each shore extends east or west of the channel (L)."""
CENTRE_Y = 50.0
"""The channel's centreline (L)."""
ISLAND_SIDE = (2.0, 5.0)
"""Side of a square island (L), uniform."""
ISLAND_GAP = (1.5, 6.0)
"""Gap between an island and the fairway's band (L), uniform."""
NORTHBOUND, SOUTHBOUND = 2, 2
"""Targets bound north (with the own ship) and south."""
START_SEPARATION = 4.0
"""Least distance between two starts (L); smaller than the paper's 10 L, which a channel 8 L wide has no room
for."""
ROUTE_CLEARANCE = 1.5
"""Least distance of a straight route from an island (L)."""
HEADING_SPREAD_DEG = 20.0
"""Initial heading: the goal's bearing ± this, uniform (deg)."""
MAX_DRAWS = 10_000
"""Rejection budget per drawn item."""


def _square(cx: float, cy: float, side: float) -> np.ndarray:
    h = 0.5 * side
    return np.array([[cx - h, cy - h], [cx + h, cy - h], [cx + h, cy + h], [cx - h, cy + h]])


def shores(width: float) -> tuple[np.ndarray, np.ndarray]:
    """The western and eastern shores of a strait of ``width`` (L), each a 4-point polygon (x, y).

    Parameters
    ----------
    width : float
        Channel width (L).

    Returns
    -------
    west : numpy.ndarray (4, 2)
        Vertices of the western shore (L).
    east : numpy.ndarray (4, 2)
        Vertices of the eastern shore (L).

    Examples
    --------
    >>> west, east = shores(10.0)
    >>> float(west[:, 1].max()), float(east[:, 1].min())
    (45.0, 55.0)
    """
    lo, hi = STRAIT_X
    w = 0.5 * float(width)
    west = np.array([[lo, CENTRE_Y - w - SHORE_DEPTH], [hi, CENTRE_Y - w - SHORE_DEPTH], [hi, CENTRE_Y - w],
                     [lo, CENTRE_Y - w]])
    east = np.array([[lo, CENTRE_Y + w], [hi, CENTRE_Y + w], [hi, CENTRE_Y + w + SHORE_DEPTH],
                     [lo, CENTRE_Y + w + SHORE_DEPTH]])
    return west, east


def route_clearance(a, b, polygon) -> float:
    """Least distance (L) between the segment ``a``–``b`` and a polygon's boundary; 0 if the segment enters it.

    Parameters
    ----------
    a, b : array-like (2,)
        Ends of the route.
    polygon : array-like (K, 2)
        Vertices of the polygon, in order.

    Returns
    -------
    float
        Clearance (L), measured at 401 points along the segment; 0.0 if one of them is inside the polygon.

    Examples
    --------
    >>> square = _square(0.0, 0.0, 2.0)
    >>> route_clearance([-5, 3], [5, 3], square), route_clearance([-5, 0], [5, 0], square)
    (2.0, 0.0)
    """
    a, b, poly = np.asarray(a, float), np.asarray(b, float), np.asarray(polygon, float)
    pts = a + np.linspace(0.0, 1.0, 401)[:, None] * (b - a)
    if LandSpec(poly).contains(pts).any():
        return 0.0
    best = np.inf
    for p, q in zip(poly, np.roll(poly, -1, axis=0)):
        e = q - p
        s = np.clip(((pts - p) @ e) / (e @ e), 0.0, 1.0)[:, None]
        best = min(best, float(np.min(np.linalg.norm(pts - (p + s * e), axis=1))))
    return best


def sample_strait(run: int, base_seed: int = 0, speed_range=(0.5, 1.0)):
    """Draw run ``run`` of environment 6 (module docstring).

    Parameters
    ----------
    run : int
        Run index (>= 0).
    base_seed : int
        Base seed of the study (>= 0).
    speed_range : (float, float)
        Speeds of the targets (fractions of the design speed), as environments 1–5.

    Returns
    -------
    dict
        The fields of a :class:`~mmg_casadi.montecarlo.sampling.SampledScenario` (which
        :func:`~mmg_casadi.montecarlo.sampling.sample_scenario` builds from them): no obstacles, ``land`` the two
        shores and the two islands.

    Examples
    --------
    >>> s = sample_strait(3)
    >>> s["environment"], len(s["starts"]), len(s["obstacles"]), len(s["land"])
    (6, 5, 0, 4)
    >>> bool(np.all(s["goals"][:3, 0] >= 90) and np.all(s["goals"][3:, 0] <= 10))
    True
    """
    rng = np.random.default_rng(np.random.SeedSequence([int(base_seed), ENVIRONMENT, int(run)]))
    width = float(rng.uniform(*WIDTH_RANGE))
    sides = rng.uniform(*ISLAND_SIDE, size=2)
    band = (CENTRE_Y - 0.5 * width + 1.5, CENTRE_Y + 0.5 * width - 1.5)
    centres = []
    for side, x_lo in zip(sides, (10.0, 75.0)):
        x = rng.uniform(x_lo, x_lo + 15.0)
        gap = rng.uniform(*ISLAND_GAP) + 0.5 * side
        centres.append(np.array([x, band[1] + gap if rng.uniform() < 0.5 else band[0] - gap]))
    islands = [_square(c[0], c[1], s) for c, s in zip(centres, sides)]
    starts, goals = [], []
    for i in range(1 + NORTHBOUND + SOUTHBOUND):
        north = i <= NORTHBOUND
        for _ in range(MAX_DRAWS):
            start = np.array([rng.uniform(0.0, 10.0) + (0.0 if north else 90.0), rng.uniform(*band)])
            goal = np.array([rng.uniform(90.0, 100.0) if north else rng.uniform(0.0, 10.0), rng.uniform(*band)])
            if all(np.hypot(*(start - s)) >= START_SEPARATION for s in starts) and \
                    all(route_clearance(start, goal, poly) >= ROUTE_CLEARANCE for poly in islands):
                starts.append(start)
                goals.append(goal)
                break
        else:
            raise InputError("START_SEPARATION", "starts and routes that fit the strait", START_SEPARATION)
    starts, goals = np.array(starts), np.array(goals)
    bearing = np.arctan2(goals[:, 1] - starts[:, 1], goals[:, 0] - starts[:, 0])
    spread = math.radians(HEADING_SPREAD_DEG)
    headings = (bearing + rng.uniform(-spread, spread, size=len(starts)) + math.pi) % (2 * math.pi) - math.pi
    speeds = np.concatenate([[1.0], rng.uniform(*speed_range, size=len(starts) - 1)])
    return {"environment": ENVIRONMENT, "run": int(run), "seed": int(base_seed), "starts": starts, "goals": goals,
            "headings": headings, "speeds": speeds, "obstacles": np.zeros((0, 2)), "land": (*shores(width), *islands)}
