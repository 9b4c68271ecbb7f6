"""Land from a GeoJSON file (RFC 7946): Polygon and MultiPolygon features, longitude/latitude on WGS-84, projected
on the scenario's local plane like the maritime-schema import (:mod:`mmg_casadi.scenarios.geodesy`).

A scenario file declares it in a ``[chart]`` table::

    [chart]
    land_file = "coast.geojson"   # relative to the scenario file's folder
    origin = [58.61, 10.59]       # latitude, longitude (deg, WGS-84) of the local frame's (0, 0); x north, y east
    length_m = 230.0              # optional: metres per ship length L (default the KCS's 230 m)

``origin`` and ``length_m`` may be left out in a scenario that has a geographic origin of its own: one converted
from maritime-schema (``mmg-casadi convert``) records its reference and length unit in its header comment
(:func:`~mmg_casadi.scenarios.geodesy.read_header`), and ``[chart]`` then uses them.

Each polygon's exterior ring becomes one land polygon (``[[land]]``) in ship lengths, after the inline ones; the
closing position (equal to the first) is dropped, as are repeated consecutive positions. Interior rings (lakes
on an island) are ignored: a ship never sails there. Features of other geometry types (a LineString of a
coastline, a Point of a light) are refused, as are files that are not a FeatureCollection, a Feature or a bare
geometry. Positions farther than :data:`~mmg_casadi.scenarios.geodesy.MAX_RANGE` from the origin are refused.

The maritime-schema import (``mmg-casadi convert``, :func:`~mmg_casadi.scenarios.maritime_schema.load_traffic_situation`)
reads a GeoJSON file next to the situation with the same stem (``encounter.json`` → ``encounter.geojson``) the
same way, projected on the situation's plane (origin: the own ship's initial position) in its length unit.

Every malformed input raises one :class:`~mmg_casadi.errors.ScenarioError` naming the field and the allowed values.

Examples
--------
>>> from mmg_casadi.scenarios.geodesy import LocalPlane
>>> square = {"type": "Polygon", "coordinates": [[[10.0, 58.01], [10.01, 58.01], [10.01, 58.02], [10.0, 58.02],
...                                                [10.0, 58.01]]]}
>>> (poly,) = land_polygons(square, LocalPlane(58.0, 10.0), 230.0, "coast.geojson")
>>> [(round(x, 1), round(y, 1)) for x, y in poly]  # 1.1 km north and 0.6 km east of the origin, in 230 m units
[(4.8, 0.0), (4.8, 2.6), (9.7, 2.6), (9.7, 0.0)]
"""

from __future__ import annotations

import math
from pathlib import Path

from mmg_casadi.errors import ScenarioError
from mmg_casadi.readers import finite, load_json
from mmg_casadi.scenarios.geodesy import LocalPlane

CHART_KEYS = ("land_file", "origin", "length_m")
"""Keys of a scenario file's ``[chart]`` table."""
DEFAULT_LENGTH_M = 230.0
"""Metres per ship length when ``[chart]`` gives no ``length_m``: the KCS's length (the length unit L)."""
GEOMETRIES = ("Polygon", "MultiPolygon")
"""GeoJSON geometry types read as land."""


def read_geojson(path, field: str) -> dict:
    """The parsed GeoJSON object of ``path``.

    Parameters
    ----------
    path : str or Path
        The file (UTF-8 JSON).
    field : str
        The field named in errors (e.g. ``chart.land_file``).

    Returns
    -------
    dict
        The parsed object.
    """
    data = load_json(path, "GeoJSON", field, ScenarioError)  # size, UTF-8, nesting, no NaN: before any work
    if not isinstance(data, dict):
        raise ScenarioError(field, "a GeoJSON object (FeatureCollection, Feature or geometry)", type(data).__name__)
    return data


def _geometries(data: dict, where: str):
    """``(field, geometry)`` of every feature of a FeatureCollection, a Feature or a bare geometry."""
    kind = data.get("type")
    if kind == "FeatureCollection":
        features = data.get("features")
        if not isinstance(features, list):
            raise ScenarioError(f"{where}.features", "a list of features", features)
        for i, f in enumerate(features):
            if not isinstance(f, dict) or f.get("type") != "Feature":
                raise ScenarioError(f"{where}.features[{i}]", "a GeoJSON Feature", f)
            yield f"{where}.features[{i}].geometry", f.get("geometry")
    elif kind == "Feature":
        yield f"{where}.geometry", data.get("geometry")
    else:
        yield where, data


def _number(value, field: str, low: float, high: float) -> float:
    return finite(value, field, low, high, ScenarioError, unit="(deg)")


def _ring(ring, field: str, plane: LocalPlane, unit: float) -> list[tuple[float, float]]:
    """One linear ring ([[lon, lat], ...], closed) as land points in L."""
    if not isinstance(ring, list) or len(ring) < 4:
        raise ScenarioError(field, "a linear ring of at least 4 positions [lon, lat], the last equal to the first",
                            ring)
    points: list[tuple[float, float]] = []
    for j, pos in enumerate(ring):
        if not isinstance(pos, list) or len(pos) < 2:
            raise ScenarioError(f"{field}[{j}]", "a position [lon, lat]", pos)
        lon = _number(pos[0], f"{field}[{j}][0]", -180.0, 180.0)
        lat = _number(pos[1], f"{field}[{j}][1]", -90.0, 90.0)
        x, y = plane.to_plane(lat, lon, field=f"{field}[{j}]")
        p = (x / unit, y / unit)
        if not points or p != points[-1]:
            points.append(p)
    if len(points) > 1 and points[-1] == points[0]:
        points.pop()  # the closing position
    area = 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(points, points[1:] + points[:1]))
    if len(points) < 3 or abs(area) < 1e-9:
        raise ScenarioError(field, "a ring of at least 3 distinct positions enclosing a non-zero area", ring)
    return points


def land_polygons(data: dict, plane: LocalPlane, unit: float, where: str) -> list[list[tuple[float, float]]]:
    """The land polygons (exterior rings, in L on ``plane``) of a parsed GeoJSON object.

    Parameters
    ----------
    data : dict
        A FeatureCollection, a Feature or a bare Polygon/MultiPolygon geometry.
    plane : LocalPlane
        The local plane (x north, y east, metres) the positions are projected on.
    unit : float
        Metres per ship length L.
    where : str
        Name of the object in errors (e.g. the file name).

    Returns
    -------
    list of list of (float, float)
        One polygon per Polygon (one per member of a MultiPolygon), its points in L, not closed.
    """
    out = []
    for field, geom in _geometries(data, where):
        if not isinstance(geom, dict) or geom.get("type") not in GEOMETRIES:
            got = geom.get("type") if isinstance(geom, dict) else geom
            raise ScenarioError(f"{field}.type", "one of: Polygon, MultiPolygon (land)", got)
        coords = geom.get("coordinates")
        polys = [coords] if geom["type"] == "Polygon" else coords
        if not isinstance(polys, list) or not polys:
            raise ScenarioError(f"{field}.coordinates", f"the coordinates of a non-empty {geom['type']}", coords)
        for k, poly in enumerate(polys):
            at = f"{field}.coordinates" + ("" if geom["type"] == "Polygon" else f"[{k}]")
            if not isinstance(poly, list) or not poly:
                raise ScenarioError(at, "a list of linear rings (the exterior ring first)", poly)
            out.append(_ring(poly[0], f"{at}[0]", plane, unit))
    return out


def chart_land(chart, base_dir=None, reference=None) -> list[list[tuple[float, float]]]:
    """The land polygons (in L) of a scenario file's ``[chart]`` table.

    Parameters
    ----------
    chart : dict
        The ``[chart]`` table: ``land_file`` (required), ``origin`` = [lat, lon] (required) and ``length_m``.
    base_dir : str or Path, optional
        Folder ``land_file`` is relative to (the scenario file's; default the working directory).
    reference : (float, float, float), optional
        The scenario's own geographic origin (latitude, longitude in deg, metres per L): the default of
        ``origin`` and ``length_m``.

    Returns
    -------
    list of list of (float, float)
        The polygons, in the file's order.
    """
    if not isinstance(chart, dict):
        raise ScenarioError("chart", "a table with keys: " + ", ".join(CHART_KEYS), chart)
    for key in chart:
        if key not in CHART_KEYS:
            raise ScenarioError(f"chart.{key}", "one of the keys: " + ", ".join(CHART_KEYS), key)
    name = chart.get("land_file")
    if not isinstance(name, str) or not name.strip():
        raise ScenarioError("chart.land_file", "the name of a GeoJSON file, relative to the scenario's folder",
                            name)
    origin = chart.get("origin", None if reference is None else list(reference[:2]))
    if not isinstance(origin, list) or len(origin) != 2:
        raise ScenarioError("chart.origin", "[latitude, longitude] (deg, WGS-84) of the local frame's (0, 0) "
                            "(required unless the scenario records its reference, as a converted one does)", origin)
    lat = _number(origin[0], "chart.origin[0]", -90.0, 90.0)
    lon = _number(origin[1], "chart.origin[1]", -180.0, 180.0)
    unit = chart.get("length_m", DEFAULT_LENGTH_M if reference is None else reference[2])
    if isinstance(unit, bool) or not isinstance(unit, (int, float)) or not math.isfinite(unit) or unit <= 0:
        raise ScenarioError("chart.length_m", "a number > 0 (metres per ship length)", unit)
    path = Path(base_dir or ".") / name
    return land_polygons(read_geojson(path, "chart.land_file"), LocalPlane(lat, lon), float(unit), name)
