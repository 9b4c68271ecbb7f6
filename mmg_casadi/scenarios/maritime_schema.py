"""Traffic situations in DNV's open maritime-schema JSON, read into our :class:`Scenario`.

Schema: ``TrafficSituation`` version 0.2.0 of dnv-opensource/maritime-schema, ``schemas/traffic_situation.json``
(commit 14d9ad70772a055687b5664ef31aa4b7233c580d; MIT). A situation has an ``ownShip`` and ``targetShips``;
each ship has ``static`` (``id``, ``name``, ``dimensions.length`` in m), ``initial`` (``position.lat`` /
``position.lon`` in WGS-84 degrees, ``sog`` in knots, ``cog`` and ``heading`` in degrees from north,
clockwise) and ``waypoints`` (``position``, optional ``leg.sog`` / ``leg.data.sog.value`` in knots: the speed
on the leg to that waypoint, read into the ship's ``speeds``; a route without a leg speed different from the
initial one keeps the initial speed on every leg). The
older field names of the schema's first releases and of DNV's ship-traffic-generator output
(``position.latitude`` / ``position.longitude``, ``static.length``; dnv-opensource/maritime-schema
``schema/caga/input_schema.json``, commit 0d76daf3ac5cd138f093d23795bbcd46c819a597) are read as well.
Writing a scenario as a traffic situation is :mod:`mmg_casadi.scenarios.maritime_export`; converting files
either way is :mod:`mmg_casadi.scenarios.interchange`.

Geometry. Positions are mapped to the plane (x north, y east, metres) of
:class:`~mmg_casadi.scenarios.geodesy.LocalPlane`, the azimuthal equidistant projection about the own ship's
initial position computed with Karney's geodesics (see :mod:`mmg_casadi.scenarios.geodesy`). Every position
(initial and waypoints) must lie within :data:`~mmg_casadi.scenarios.geodesy.MAX_RANGE` (60 km) of it, where
the plane keeps distances to < 1 m; a position beyond raises a :class:`~mmg_casadi.errors.ScenarioError` naming
it (``targetShips[0].initial.position``, ``ownShip.waypoints[2].position``). Courses and headings, given
against the local north of each ship, are turned into the plane by
:meth:`~mmg_casadi.scenarios.geodesy.LocalPlane.course_to_plane`. Metres become ship lengths of the KCS
(L = 230 m) or, with ``length_scale="own-ship"``, of the own ship (``ownShip.static.dimensions.length``; speeds
then Froude-scaled to that length). Speeds in knots become fractions of the design speed (24 kn for the KCS);
outside the model's range :data:`~mmg_casadi.scenarios.scenario.SPEED_RANGE` a
:class:`~mmg_casadi.errors.ScenarioError` names the field.

Static data. Each ship's ``static`` object is kept in its :class:`~mmg_casadi.scenarios.scenario.ShipSpec`: the
length and width (m) become ``length_m`` and ``beam_m`` (each ship's collision geometry), everything else (``id``, ``mmsi``, ``imo``, ``shipType``, ``sogMax``, ``dimensions.height``, any other key)
``metadata``, under the names of schema 0.2.0: the flat ``length``, ``width``, ``height`` of the older files go
to ``dimensions`` and trafficgen's ``speedMax`` (maximum speed in knots) to ``sogMax``, its name in 0.2.0.
``name`` becomes the ship's name (kept in ``metadata`` only when the scenario's name differs: a blank, repeated
or padded name); keys whose value is null are left out.

Hulls. With lengths in KCS lengths, a target of known length sails the library's closest hull
(:func:`~mmg_casadi.vessel.library.closest_vessel`: of its kind if ``shipType`` names one, e.g. a tanker, then the
closest length), written as its ``vessel`` when it is not the KCS; its speeds are then fractions of that hull's
design speed (15.5 kn for the KVLCC2). :func:`hull_choices` says which hull each ship got. The own ship is the
table's ``vessel``, the scenario's unit.

Ships. The own ship uses ``method`` (the scenario's ``settings.method``); target ships use ``target_method``
(``"none"``: they track their own waypoints, or hold their course, without avoiding anyone). Waypoints within
:data:`START_TOLERANCE` of a ship's start are dropped (trafficgen repeats the start as the first waypoint);
a ship's path is extended along its last leg (its course if it has no waypoint) until it reaches at least
``extend_past`` ship lengths beyond the point it passes at the last closest approach of the own ship to any
target (all ships on straight courses at their initial speeds), so every encounter happens before the goal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mmg_casadi.errors import ScenarioError
from mmg_casadi.guidance.methods import DEFAULT as DEFAULT_METHOD
from mmg_casadi.guidance import methods as registry
from mmg_casadi.readers import is_finite, load_json
from mmg_casadi.scenarios.geodesy import LocalPlane, initial_azimuth
from mmg_casadi.scenarios.geojson_land import land_polygons, read_geojson
from mmg_casadi.scenarios.scenario import SPEED_RANGE, Scenario, check_metadata, scenario_from_dict
from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL, closest_vessel, load_vessel
from mmg_casadi.vessel.ship import load_kcs

KNOT = 1852.0 / 3600.0
"""One knot in m/s."""
START_TOLERANCE = 0.5
"""Waypoints closer than this to the ship's start are dropped [ship lengths]."""
EXTEND_PAST = 30.0
"""Default path length past the last closest approach [ship lengths] (twice the default safe radius)."""
T_MAX_MARGIN = 1.5
"""``t_max`` of a converted scenario: this factor times the longest sailing time of any ship, at least 300."""
LENGTH_SCALES = ("kcs", "own-ship")
RENAMED = {"length": ("dimensions", "length"), "width": ("dimensions", "width"), "height": ("dimensions", "height"),
           "speedMax": (None, "sogMax")}
"""Static fields of the older files (flat keys) and trafficgen's ``speedMax``: their place in schema 0.2.0."""


def _get(d: dict, path: str, *names, required=True):
    """``d[name]`` for the first of ``names`` present; ScenarioError naming ``path.names[0]`` if required."""
    if not isinstance(d, dict):
        raise ScenarioError(path, "an object", d)
    for n in names:
        if n in d and d[n] is not None:
            return d[n]
    if required:
        raise ScenarioError(f"{path}.{names[0]}" if path else names[0], "a value (required)")
    return None


def check_number(value, field: str, low=None, high=None, unit: str = "") -> float:
    """``value`` as a float if it is a finite number (not a bool) in [``low``, ``high``], else a ScenarioError.

    Parameters
    ----------
    value : object
        The value to check (a JSON number).
    field : str
        Dotted name of the field, named in the error.
    low, high : float or None, optional
        Inclusive bounds (``None``: unbounded).
    unit : str, optional
        Unit shown after the bounds in the error message.

    Returns
    -------
    float
        ``float(value)``.

    Examples
    --------
    >>> check_number(12, "ownShip.initial.sog", 0.0, None, "kn")
    12.0
    >>> check_number(True, "ownShip.initial.sog", 0.0, None, "kn")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ScenarioError: ownShip.initial.sog: expected a number in [0, inf] kn, got True
    """
    ok = is_finite(value)
    if ok and (low is None or value >= low) and (high is None or value <= high):
        return float(value)
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    raise ScenarioError(field, f"a number in [{lo}, {hi}]" + (f" {unit}" if unit else ""), value)


def _position(d, field: str) -> tuple[float, float]:
    """(lat, lon) of ``d["position"]`` (``lat``/``lon`` or ``latitude``/``longitude``)."""
    where = f"{field}.position"
    p = _get(d, field, "position")
    lat = check_number(_get(p, where, "lat", "latitude"), f"{where}.lat", -90.0, 90.0, "deg")
    lon = check_number(_get(p, where, "lon", "longitude"), f"{where}.lon", -180.0, 180.0, "deg")
    return lat, lon


def _leg_speed(sog_kn: float, u_des: float, field: str) -> float:
    """A leg's speed over ground (kn) as a fraction of the design speed, within the scenario's speed range."""
    lo, hi = SPEED_RANGE
    speed = sog_kn * KNOT / u_des
    if not lo <= speed <= hi:
        raise ScenarioError(field, f"a speed in [{lo * u_des / KNOT:.2f}, {hi * u_des / KNOT:.2f}] kn "
                            f"([{lo:g}, {hi:g}] x the design speed {u_des / KNOT:.2f} kn)", sog_kn)
    return speed


def _leg_sog(wp: dict, field: str):
    leg = wp.get("leg") if isinstance(wp, dict) else None
    if not isinstance(leg, dict):
        return None
    data = leg.get("data")
    if isinstance(data, dict) and isinstance(data.get("sog"), dict) and "value" in data["sog"]:
        return check_number(data["sog"]["value"], f"{field}.leg.data.sog.value", 0.0, None, "kn")
    if leg.get("sog") is not None:
        return check_number(leg["sog"], f"{field}.leg.sog", 0.0, None, "kn")
    return None


@dataclass
class _Ship:
    name: str
    raw_name: object  # static.name as given (None if absent)
    lat: float
    lon: float
    sog_kn: float
    cog: float
    heading: float
    waypoints: list  # [(lat, lon)]
    leg_sog_kn: list  # per waypoint: speed on the leg to it (kn), None where not given
    length_m: float | None
    beam_m: float | None
    metadata: dict
    field: str
    start_field: str  # the field of the start position (initial.position, else waypoints[0].position)


def _static(static: dict, field: str):
    """(name, length_m, beam_m, metadata) of a ship's ``static`` object (see the module docstring)."""
    where = f"{field}.static"
    static = {k: v for k, v in static.items() if v is not None}
    dims = static.pop("dimensions", {})
    if not isinstance(dims, dict):
        raise ScenarioError(f"{where}.dimensions", "an object (length, width, height, ... in m)", dims)
    dims = {k: v for k, v in dims.items() if v is not None}
    source = {"length": f"{where}.dimensions.length", "width": f"{where}.dimensions.width"}
    for old, (table, new) in RENAMED.items():
        if old not in static:
            continue
        target = dims if table == "dimensions" else static
        if new in target:
            continue  # both names given: the 0.2.0 one counts, the old one is kept as it is
        target[new] = static.pop(old)
        if new in source:
            source[new] = f"{where}.{old}"
    size = [check_number(dims.pop(k), source[k], 1e-3, None, "m") if k in dims else None
            for k in ("length", "width")]
    name = static.pop("name", None)
    if name is not None:
        check_metadata({"name": name}, where)
    if dims:
        static["dimensions"] = dims
    return name, size[0], size[1], check_metadata(static, where, drop_nulls=True)


def _ship(d, field: str, index: int) -> _Ship:
    if not isinstance(d, dict):
        raise ScenarioError(field, "an object with static, initial and waypoints", d)
    static = _get(d, field, "static", required=False) or {}
    if not isinstance(static, dict):
        raise ScenarioError(f"{field}.static", "an object", static)
    raw_name, length_m, beam_m, metadata = _static(static, field)
    name = raw_name
    if not isinstance(name, str) or not name.strip():
        ident = metadata.get("id")
        name = f"ship{index}" if ident is None or isinstance(ident, (dict, list)) else f"ship{ident}"
    wps = _get(d, field, "waypoints", required=False) or []
    if not isinstance(wps, list):
        raise ScenarioError(f"{field}.waypoints", "an array of waypoints", wps)
    waypoints = [_position(w, f"{field}.waypoints[{j}]") for j, w in enumerate(wps)]
    initial = _get(d, field, "initial", required=False)
    if initial is None:
        if len(waypoints) < 2:
            raise ScenarioError(f"{field}.initial", "an initial state (required unless the ship has at least "
                                "two waypoints)")
        lat, lon = waypoints[0]
        start_field = f"{field}.waypoints[0].position"
        cog = initial_azimuth(lat, lon, *waypoints[1])
        heading = cog
        sog = _leg_sog(wps[1], f"{field}.waypoints[1]")
        if sog is None:
            raise ScenarioError(f"{field}.waypoints[1].leg.sog", "a speed in knots (no initial state given)")
    else:
        lat, lon = _position(initial, f"{field}.initial")
        start_field = f"{field}.initial.position"
        sog = check_number(_get(initial, f"{field}.initial", "sog"), f"{field}.initial.sog", 0.0, None, "kn")
        cog = check_number(_get(initial, f"{field}.initial", "cog"), f"{field}.initial.cog", 0.0, 360.0, "deg")
        h = _get(initial, f"{field}.initial", "heading", required=False)
        heading = cog if h is None else check_number(h, f"{field}.initial.heading", 0.0, 360.0, "deg")
    legs = [_leg_sog(w, f"{field}.waypoints[{j}]") for j, w in enumerate(wps)]
    return _Ship(name.strip(), raw_name, lat, lon, sog, cog, heading, waypoints, legs, length_m, beam_m, metadata,
                 field, start_field)


def _last_cpa_time(starts, velocities) -> float:
    """Latest time (≥ 0) of closest approach of ship 0 to any other, all on straight courses."""
    t_last = 0.0
    for j in range(1, len(starts)):
        dp = starts[j] - starts[0]
        dv = velocities[j] - velocities[0]
        vv = float(dv @ dv)
        t_last = max(t_last, 0.0 if vv < 1e-12 else max(0.0, -float(dp @ dv) / vv))
    return t_last


def _extend(start, path, heading_rad: float, needed: float):
    """``path`` (list of points after ``start``) lengthened along its last leg to at least ``needed``."""
    pts = [np.asarray(start, float)] + [np.asarray(p, float) for p in path]
    length = sum(float(np.linalg.norm(b - a)) for a, b in zip(pts[:-1], pts[1:]))
    if length >= needed:
        return path
    if len(pts) >= 2:
        direction = (pts[-1] - pts[-2]) / np.linalg.norm(pts[-1] - pts[-2])
    else:
        direction = np.array([math.cos(heading_rad), math.sin(heading_rad)])
    end = pts[-1] + direction * (needed - length)
    return list(path) + [(float(end[0]), float(end[1]))]


def traffic_situation_to_scenario(data: dict, *, method: str = DEFAULT_METHOD, target_method: str = "none",
                                  length_scale: str = "kcs", extend_past: float = EXTEND_PAST,
                                  source: str = "<json>", land: dict | None = None,
                                  land_source: str = "<geojson>") -> tuple[Scenario, LocalPlane, float]:
    """A :class:`Scenario` from a maritime-schema traffic situation (a parsed JSON object).

    Parameters
    ----------
    data : dict
        The traffic situation.
    method, target_method : str
        Collision-avoidance method of the own ship and of the target ships (one of
        :data:`~mmg_casadi.guidance.methods.METHODS`).
    length_scale : str
        ``"kcs"``: lengths in KCS lengths (230 m), speeds as fractions of 24 kn; ``"own-ship"``: lengths in the
        own ship's length, speeds as fractions of the KCS design speed Froude-scaled to it.
    extend_past : float
        Minimum path length past the last closest approach [ship lengths], ≥ 0.
    source : str
        Name for error messages.
    land : dict, optional
        A parsed GeoJSON object whose Polygon/MultiPolygon features are land
        (:func:`~mmg_casadi.scenarios.geojson_land.land_polygons`, projected on the same plane in the same unit).
    land_source : str
        Name of the GeoJSON object in error messages.

    Returns
    -------
    (Scenario, LocalPlane, float)
        The scenario, the plane it is drawn in (reference: the own ship's initial position) and the length
        unit in metres.

    Examples
    --------
    >>> sit = {"version": "0.2.0", "ownShip": {
    ...     "static": {"id": 1, "name": "OS"}, "waypoints": [{"position": {"lat": 58.0, "lon": 10.0}}],
    ...     "initial": {"position": {"lat": 58.0, "lon": 10.0}, "sog": 12.0, "cog": 0.0}},
    ...     "targetShips": [{"static": {"id": 2}, "waypoints": [{"position": {"lat": 58.1, "lon": 10.0}}],
    ...     "initial": {"position": {"lat": 58.1, "lon": 10.0}, "sog": 12.0, "cog": 180.0}}]}
    >>> sc, plane, unit = traffic_situation_to_scenario(sit)
    >>> [s.name for s in sc.ships], round(sc.ships[0].speed, 3)   # 12 kn = 0.5 x 24 kn
    (['OS', 'ship2'], 0.5)
    >>> round(sc.ships[1].start[0], 1)   # 0.1 deg of meridian at 58 deg N: M * 0.1 deg = 11138 m = 48.4 L
    48.4
    >>> sc.method_of(0), sc.method_of(1), sc.ships[0].waypoints[-1][0] > 24.2 + 30
    ('modified-vortex', 'none', True)
    >>> sit["targetShips"][0]["static"].update(dimensions={"length": 50.0, "width": 10.0}, mmsi=257000123)
    >>> t = traffic_situation_to_scenario(sit)[0].ships[1]
    >>> t.length_m, t.beam_m, t.metadata
    (50.0, 10.0, {'id': 2, 'mmsi': 257000123})
    """
    for name, value in (("method", method), ("target_method", target_method)):
        registry.get(value, name, ScenarioError)
    if length_scale not in LENGTH_SCALES:
        raise ScenarioError("length_scale", f"one of: {', '.join(LENGTH_SCALES)}", length_scale)
    if not (is_finite(extend_past) and extend_past >= 0):
        raise ScenarioError("extend_past", "a number >= 0 (ship lengths)", extend_past)
    try:
        if not isinstance(data, dict):
            raise ScenarioError("traffic situation", "a JSON object with ownShip and targetShips", data)
        own = _ship(_get(data, "", "ownShip"), "ownShip", 0)
        targets = data.get("targetShips") or []
        if not isinstance(targets, list):
            raise ScenarioError("targetShips", "an array of target ships", targets)
        ships = [own] + [_ship(t, f"targetShips[{i}]", i + 1) for i, t in enumerate(targets)]
        kcs = load_kcs()
        if length_scale == "kcs":
            unit = kcs.L
            u_des = kcs.U_design
        else:
            if own.length_m is None:
                raise ScenarioError("ownShip.static.dimensions.length", "the own ship's length in m (required "
                                    "with length_scale='own-ship')")
            unit = own.length_m
            u_des = kcs.U_design * math.sqrt(own.length_m / kcs.L)
        plane = LocalPlane(own.lat, own.lon)
        lo, hi = SPEED_RANGE
        rows = []
        names: dict[str, int] = {}
        for k, s in enumerate(ships):
            # a target of known length sails the library's closest hull (lengths in KCS lengths only); its speeds
            # are fractions of that hull's design speed
            hull = closest_vessel(s.length_m, s.metadata.get("shipType"))[0] if k and length_scale == "kcs" \
                else DEFAULT_VESSEL
            u_ship = u_des if hull == DEFAULT_VESSEL else load_vessel(hull).ship.U_design
            speed = s.sog_kn * KNOT / u_ship
            if not lo <= speed <= hi:
                raise ScenarioError(f"{s.field}.initial.sog", f"a speed in [{lo * u_ship / KNOT:.2f}, "
                                    f"{hi * u_ship / KNOT:.2f}] kn ([{lo:g}, {hi:g}] x the design speed "
                                    f"{u_ship / KNOT:.2f} kn of the hull {hull})", s.sog_kn)
            x, y = plane.to_plane(s.lat, s.lon, field=s.start_field)
            start = (x / unit, y / unit)
            heading = plane.course_to_plane(s.heading, s.lat, s.lon, field=s.start_field)
            course = plane.course_to_plane(s.cog, s.lat, s.lon, field=s.start_field)
            path, legs = [], []
            for j, (lat, lon) in enumerate(s.waypoints):
                px, py = plane.to_plane(lat, lon, field=f"{s.field}.waypoints[{j}].position")
                p = (px / unit, py / unit)
                if not path and math.dist(p, start) < START_TOLERANCE:
                    continue
                path.append(p)
                legs.append(speed if s.leg_sog_kn[j] is None else
                            _leg_speed(s.leg_sog_kn[j], u_ship, f"{s.field}.waypoints[{j}].leg.sog"))
            name = s.name if s.name not in names else f"{s.name} ({len(rows)})"
            names[name] = len(rows)
            metadata = dict(s.metadata)
            if s.raw_name is not None and s.raw_name != name:
                metadata["name"] = s.raw_name  # the name as read, when the scenario's differs
            rows.append({"name": name, "start": start, "heading": heading, "course": course, "speed": speed,
                         "path": path, "legs": legs, "metadata": metadata, "length_m": s.length_m,
                         "beam_m": s.beam_m, "vessel": hull, "scene_speed": speed * u_ship / u_des})
        starts = [np.asarray(r["start"]) for r in rows]
        vel = [r["scene_speed"] * np.array([math.cos(math.radians(r["course"])),
                                            math.sin(math.radians(r["course"]))]) for r in rows]
        t_cpa = _last_cpa_time(starts, vel)
        t_sail = 0.0
        out_ships = []
        for i, r in enumerate(rows):
            needed = r["scene_speed"] * t_cpa + extend_past
            path = _extend(r["start"], r["path"], math.radians(r["course"]), needed)
            pts = [r["start"]] + path
            t_sail = max(t_sail, sum(math.dist(a, b) for a, b in zip(pts[:-1], pts[1:])) / r["scene_speed"])
            ship = {"name": r["name"], "start": list(r["start"]), "heading": r["heading"], "speed": r["speed"],
                    "waypoints": [list(p) for p in path]}
            legs = r["legs"] + [r["legs"][-1] if r["legs"] else r["speed"]] * (len(path) - len(r["legs"]))
            if any(v != r["speed"] for v in legs):  # a route with speeds; otherwise every leg at the initial speed
                ship["speeds"] = legs
            if i > 0:
                ship["method"] = target_method
            if r["vessel"] != DEFAULT_VESSEL:
                ship["vessel"] = r["vessel"]
            ship.update({k: r[k] for k in ("length_m", "beam_m") if r[k] is not None})
            if r["metadata"]:
                ship["metadata"] = r["metadata"]
            out_ships.append(ship)
        t_max = min(10000.0, max(300.0, math.ceil(T_MAX_MARGIN * t_sail)))
        table = {"settings": {"method": method, "t_max": t_max}, "ships": out_ships}
        if land is not None:
            table["land"] = [{"points": [list(p) for p in poly]}
                             for poly in land_polygons(land, plane, unit, land_source)]
        sc = scenario_from_dict(table, source=source)
    except ScenarioError as err:
        err.source = source
        raise
    return sc, plane, unit


def hull_choices(sc: Scenario) -> list[str]:
    """One line per ship of an imported scenario with a length: the hull it sails and why.

    Parameters
    ----------
    sc : Scenario
        A scenario from :func:`traffic_situation_to_scenario`.

    Returns
    -------
    list of str
        E.g. ``"ship2: 300 m, Tanker -> kvlcc2 (tanker hull, closest length (320 m))"``; the own ship's line says
        it is the table's hull.

    Examples
    --------
    >>> sit = {"ownShip": {"static": {"id": 1, "name": "OS", "dimensions": {"length": 230.0}},
    ...     "initial": {"position": {"lat": 58.0, "lon": 10.0}, "sog": 12.0, "cog": 0.0}},
    ...     "targetShips": [{"static": {"id": 2, "shipType": "Tanker", "dimensions": {"length": 300.0}},
    ...     "initial": {"position": {"lat": 58.1, "lon": 10.0}, "sog": 12.0, "cog": 180.0}}]}
    >>> sc = traffic_situation_to_scenario(sit)[0]
    >>> sc.ships[1].vessel, round(sc.ships[1].speed, 3)   # 12 kn of the KVLCC2's 15.5 kn
    ('kvlcc2', 0.774)
    >>> hull_choices(sc)[1]
    'ship2: 300 m, Tanker -> kvlcc2 (tanker hull, closest length (320 m))'
    """
    out = []
    for i, s in enumerate(sc.ships):
        if s.length_m is None:
            continue
        kind = s.metadata.get("shipType")
        what = f"{s.name}: {s.length_m:g} m" + (f", {kind}" if isinstance(kind, str) else "")
        if i == 0:
            out.append(f"{what} -> {s.vessel or DEFAULT_VESSEL} (own ship: the table's vessel)")
        else:
            hull, why = closest_vessel(s.length_m, kind)
            if hull != (s.vessel or DEFAULT_VESSEL):
                why = "lengths in the own ship's length: every ship the KCS, Froude-scaled"
            out.append(f"{what} -> {s.vessel or DEFAULT_VESSEL} ({why})")
    return out


def load_traffic_situation(path, **kw) -> tuple[Scenario, LocalPlane, float]:
    """Read a maritime-schema JSON file; see :func:`traffic_situation_to_scenario` for ``kw`` and the result.

    A missing file, invalid JSON or a malformed situation raise a :class:`~mmg_casadi.errors.ScenarioError`. A
    GeoJSON file next to it with the same stem (``situation.json`` → ``situation.geojson``), if there is one, is
    read as land (:mod:`mmg_casadi.scenarios.geojson_land`).

    Parameters
    ----------
    path : str or os.PathLike
        The JSON file (UTF-8); also the ``source`` named in error messages.
    **kw
        Keyword arguments of :func:`traffic_situation_to_scenario`: ``method``, ``target_method``,
        ``length_scale``, ``extend_past`` (not ``source``).

    Returns
    -------
    (Scenario, LocalPlane, float)
        The scenario, its plane (reference: the own ship's initial position) and the length unit in metres.

    Examples
    --------
    >>> from importlib.resources import files
    >>> sc, plane, unit = load_traffic_situation(files("mmg_casadi") / "data" / "traffic_situation.json")
    >>> len(sc.ships), unit
    (3, 230.0)
    """
    path = Path(path)
    data = load_json(path, "traffic situation", "json", ScenarioError)  # size, UTF-8, nesting, no NaN
    chart = path.with_suffix(".geojson")
    if chart.is_file():
        kw = {**kw, "land": read_geojson(chart, str(chart)), "land_source": chart.name}
    return traffic_situation_to_scenario(data, source=str(path), **kw)

