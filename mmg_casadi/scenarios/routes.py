"""Routes against the chart: every leg checked against the land, and on request a route planned around it.

**Check** (:func:`check_routes`). A ship's route is her start and waypoints; leg ``j`` runs from point ``j`` to
point ``j + 1`` (leg 0 from the start). A leg that crosses a land polygon, or passes within the grounding
clearance of one (half the ship's beam plus ``grounding_margin``, where the closed loop counts a grounding), is
reported: ship, leg, the polygon, the distance and *where* (the first point of the leg on the land, or the point of
the leg nearest to it). ``mmg-casadi simulate`` prints one line per such leg on stderr (:func:`warning_line`) and
``metrics.json`` lists them (``route_warnings``); the run goes ahead, and the methods keep the ship off the land
(:mod:`mmg_casadi.guidance.land_ahead`). A start or a waypoint on land is refused when the scenario is read
(:func:`mmg_casadi.scenarios.scenario.scenario_from_dict`).

**Plan** (:func:`plan_route`, :func:`plan_routes`; ``route = "plan"`` in ``[settings]`` or a ship's table,
``--set route=plan``). Between consecutive route points the shortest path that keeps ``route_clearance`` from every
polygon: a visibility graph over the polygons buffered by the clearance (shapely), searched with Dijkstra's
algorithm. The buffers are round, drawn with :data:`QUAD_SEGS` chords per quarter circle and a radius enlarged so
that every chord keeps the clearance; a path only turns at the convex corners of a buffer (a shortest path never
turns at a reflex one). The planned route is what the ship sails: it replaces her waypoints (the user's waypoints
are kept, the turning points inserted between them sail at the speed of the leg they split) and is written into
``metrics.json`` (``ships[].route``) and the figure. A route point within the clearance of land, or one that water
does not connect to the previous one, is refused (one line naming the field).

Shapely (GEOS) is used for the polygons' union, buffers and segment tests: a well-kept geometry library, exact and
fast on charts of many edges, where our own code would be neither.

Examples
--------
>>> island = [[(25.0, -3.0), (31.0, -3.0), (31.0, 3.0), (25.0, 3.0)]]
>>> route = plan_route([(0.0, 0.0), (60.0, 0.0)], island, 2.0)
>>> len(route) > 1, route[-1]
(True, (60.0, 0.0))
>>> from shapely.geometry import LineString, Polygon
>>> LineString([(0.0, 0.0), *route]).distance(Polygon(island[0])) >= 2.0
True
"""

from __future__ import annotations

import dataclasses
import heapq
import math

import numpy as np
import shapely
from shapely.geometry import LineString, Point, Polygon
from shapely.geometry.polygon import orient
from shapely.ops import nearest_points, unary_union

from mmg_casadi.errors import ScenarioError

QUAD_SEGS = 4
"""Chords per quarter circle of a planning buffer's round corners (a turn of at most 22.5° at each)."""
ROUTES = ("as-given", "plan")
"""Values of ``route``: the waypoints as written, or planned around the land."""
_EPS = 1e-6


def land_polygons(sc) -> list:
    """The scenario's land as shapely polygons (an invalid ring, e.g. a self-intersecting one, made valid).

    Parameters
    ----------
    sc : Scenario
        The scenario.

    Returns
    -------
    list of shapely.geometry.Polygon or MultiPolygon
        One per ``[[land]]`` polygon, in order.
    """
    return [_polygon(poly.points) for poly in sc.land]


def _polygon(points):
    p = Polygon(points)
    return p if p.is_valid else shapely.make_valid(p)


def _route_points(ship) -> list[tuple[float, float]]:
    return [tuple(ship.start), *[tuple(w) for w in ship.waypoints]]


def check_routes(sc, clearances) -> list[dict]:
    """The legs of every ship's route (replayed ships excepted) that cross land or pass within its clearance.

    Parameters
    ----------
    sc : Scenario
        The scenario.
    clearances : sequence of float
        Per ship, the grounding clearance (L): half her beam plus ``grounding_margin``.

    Returns
    -------
    list of dict
        Per offending leg and polygon, in ship, leg and polygon order: ``ship`` (name), ``index`` (ship index),
        ``leg``, ``from``, ``to`` (the leg's end points), ``land`` (``"land<k>"``), ``crosses`` (the leg enters the
        polygon), ``distance`` (L, 0 when it crosses), ``clearance`` (L) and ``where`` ([x, y]: the first point of
        the leg on the land, or its point nearest to the land).

    Examples
    --------
    >>> from mmg_casadi.scenarios.scenario import scenario_from_dict
    >>> sc = scenario_from_dict({"settings": {"method": "none"}, "ships": [{"name": "own", "start": [0, 0],
    ...     "heading": 0, "speed": 1, "waypoints": [[60, 0]]}], "land": [{"points": [[25, -3], [31, -3], [31, 3],
    ...     [25, 3]]}]})
    >>> [(w["ship"], w["leg"], w["land"], w["crosses"], w["where"]) for w in check_routes(sc, [0.07])]
    [('own', 0, 'land0', True, [25.0, 0.0])]
    """
    polys = land_polygons(sc)
    out = []
    for i, ship in enumerate(sc.ships):
        if getattr(ship, "track", None) is not None:
            continue
        pts = _route_points(ship)
        for j, (a, b) in enumerate(zip(pts[:-1], pts[1:])):
            leg = LineString([a, b])
            for k, poly in enumerate(polys):
                d = float(leg.distance(poly))
                if d >= clearances[i]:
                    continue
                crosses = d == 0.0
                where = _entry(leg, poly, a) if crosses else nearest_points(leg, poly)[0]
                out.append({"ship": ship.name, "index": i, "leg": j, "from": list(a), "to": list(b),
                            "land": f"land{k}", "crosses": crosses, "distance": d,
                            "clearance": float(clearances[i]), "where": [float(where.x), float(where.y)]})
    return out


def _entry(leg: LineString, poly, start) -> Point:
    """The first point of ``leg`` (from ``start``) on ``poly``."""
    hit = leg.intersection(poly)
    pts = [Point(c) for g in getattr(hit, "geoms", [hit]) for c in g.coords]
    return min(pts, key=lambda p: p.distance(Point(start))) if pts else Point(start)


def warning_line(w: dict) -> str:
    """One line for a reported leg (:func:`check_routes`), as ``mmg-casadi simulate`` prints it on stderr.

    Parameters
    ----------
    w : dict
        One entry of :func:`check_routes`.

    Returns
    -------
    str
        E.g. ``"route: ships[0] 'own' leg 0 (0, 0) -> (60, 0) crosses land0 at (25, 0)"``.

    Examples
    --------
    >>> print(warning_line({"ship": "own", "index": 0, "leg": 0, "from": [0, 0], "to": [60, 0], "land": "land0",
    ...                     "crosses": True, "distance": 0.0, "clearance": 0.07, "where": [25.0, 0.0]}))
    route: ships[0] 'own' leg 0 (0, 0) -> (60, 0) crosses land0 at (25, 0)
    """
    def pt(p):
        return f"({p[0]:.4g}, {p[1]:.4g})"
    what = "crosses" if w["crosses"] else f"passes {w['distance']:.3g} L (< {w['clearance']:.3g} L) from"
    return (f"route: ships[{w['index']}] '{w['ship']}' leg {w['leg']} {pt(w['from'])} -> {pt(w['to'])} {what} "
            f"{w['land']} at {pt(w['where'])}")


def _buffers(polygons, clearance: float):
    """The union of the polygons buffered for the search (its corners are the graph's nodes) and for the test
    (prepared; a segment that touches it may come closer than ``clearance`` to land)."""
    radius = clearance / math.cos(math.pi / (4 * QUAD_SEGS))  # every chord of the round corners keeps the clearance
    test = unary_union([p.buffer(radius, quad_segs=QUAD_SEGS) for p in polygons])
    search = unary_union([p.buffer(radius * (1 + _EPS) + _EPS, quad_segs=QUAD_SEGS) for p in polygons])
    shapely.prepare(test)
    return search, test


def _corners(area) -> list[tuple[float, float]]:
    """The convex corners of every ring of ``area`` (the land side on the left after ``orient``): where a shortest
    path may turn."""
    out = []
    for poly in getattr(area, "geoms", [area]):
        poly = orient(poly, 1.0)
        for ring in (poly.exterior, *poly.interiors):
            c = np.asarray(ring.coords)[:-1]
            prev, nxt = np.roll(c, 1, axis=0), np.roll(c, -1, axis=0)
            cross = (c[:, 0] - prev[:, 0]) * (nxt[:, 1] - c[:, 1]) - (c[:, 1] - prev[:, 1]) * (nxt[:, 0] - c[:, 0])
            out += [tuple(map(float, p)) for p in c[cross > 0]]
    return out


def _shortest(a, b, nodes, test) -> list[tuple[float, float]] | None:
    """Dijkstra's shortest path from ``a`` to ``b`` over ``nodes`` along segments clear of ``test``; None if
    none."""
    pts = [a, b, *nodes]
    n = len(pts)
    P = np.asarray(pts, float)
    ii, jj = np.triu_indices(n, 1)
    lines = shapely.linestrings(np.stack([P[ii], P[jj]], axis=1))
    clear = ~shapely.intersects(lines, test)
    adj: dict[int, list[tuple[int, float]]] = {k: [] for k in range(n)}
    for i, j in zip(ii[clear], jj[clear]):
        d = float(np.hypot(*(P[i] - P[j])))
        adj[i].append((j, d))
        adj[j].append((i, d))
    dist, prev, heap = {0: 0.0}, {}, [(0.0, 0)]
    while heap:
        d, k = heapq.heappop(heap)
        if k == 1:
            break
        if d > dist.get(k, math.inf):
            continue
        for j, w in adj[k]:
            if d + w < dist.get(j, math.inf):
                dist[j], prev[j] = d + w, k
                heapq.heappush(heap, (d + w, j))
    if 1 not in dist:
        return None
    path, k = [], 1
    while k != 0:
        path.append(pts[k])
        k = prev[k]
    return path[::-1]


def plan_route(points, polygons, clearance: float, *, field: str = "route") -> list[tuple[float, float]]:
    """The shortest route through ``points`` (start first) that keeps ``clearance`` from every polygon.

    Parameters
    ----------
    points : sequence of (float, float)
        The start and the waypoints to visit in order (L).
    polygons : sequence
        Land: shapely polygons or sequences of vertices (L).
    clearance : float
        Least distance of the route from land (L, > 0).
    field : str, optional
        Name of the route in an error (``ships[i]``).

    Returns
    -------
    list of (float, float)
        The waypoints of the planned route (the start left out): the given waypoints with the turning points
        between them.

    Raises
    ------
    ScenarioError
        A route point within ``clearance`` of land, or one that water does not connect to the previous one.
    """
    polys = [p if hasattr(p, "geom_type") else _polygon(p) for p in polygons]
    points = [tuple(map(float, p)) for p in points]
    if not polys:
        return points[1:]
    search, test = _buffers(polys, clearance)
    for j, p in enumerate(points):
        if test.intersects(Point(p)):
            key = f"{field}.start" if j == 0 else f"{field}.waypoints[{j - 1}]"
            raise ScenarioError(key, f"a point at least route_clearance = {clearance:g} L from land to plan the "
                                "route around it (route = 'plan')", list(p))
    nodes = _corners(search)
    out: list[tuple[float, float]] = []
    for j, (a, b) in enumerate(zip(points[:-1], points[1:])):
        leg = _shortest(a, b, nodes, test)
        if leg is None:
            raise ScenarioError(f"{field}.waypoints[{j}]", "a point that water connects to the previous one with "
                                f"route_clearance = {clearance:g} L from land (route = 'plan')", list(b))
        out += leg
    return out


def plan_routes(sc, resolved: dict):
    """``sc`` with the route of every ship that asks for it (her ``route``, else the parameter ``route``) planned
    around the land (:func:`plan_route`, clearance ``route_clearance``).

    Parameters
    ----------
    sc : Scenario
        The scenario.
    resolved : dict
        Its resolved parameters (``route``, ``route_clearance``).

    Returns
    -------
    Scenario
        A new scenario whose planned ships sail the planned waypoints (their leg speeds repeated over the legs
        they were split into); ``sc`` itself if no ship plans.
    """
    ships = list(sc.ships)
    changed = False
    polys = land_polygons(sc)
    for i, ship in enumerate(ships):
        mode = getattr(ship, "route", None) or resolved["route"]
        if mode != "plan" or getattr(ship, "track", None) is not None:
            continue
        planned = plan_route(_route_points(ship), polys, float(resolved["route_clearance"]), field=f"ships[{i}]")
        speeds = None
        if ship.speeds is not None:  # each given waypoint ends a leg: the turning points before it take its speed
            it, speeds = iter(zip(ship.waypoints, ship.speeds)), []
            target, v = next(it)
            for p in planned:
                speeds.append(v)
                if p == tuple(target):
                    target, v = next(it, (None, v))
        ships[i] = dataclasses.replace(ship, waypoints=tuple(planned), speeds=None if speeds is None else
                                       tuple(speeds))
        changed = True
    return dataclasses.replace(sc, ships=tuple(ships)) if changed else sc
