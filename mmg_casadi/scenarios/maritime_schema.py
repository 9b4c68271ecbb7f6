"""Traffic situations in DNV's open maritime-schema JSON, read into and written from our :class:`Scenario`.

Schema: ``TrafficSituation`` version 0.2.0 of dnv-opensource/maritime-schema, ``schemas/traffic_situation.json``
(commit 14d9ad70772a055687b5664ef31aa4b7233c580d; MIT). A situation has an ``ownShip`` and ``targetShips``;
each ship has ``static`` (``id``, ``name``, ``dimensions.length`` in m), ``initial`` (``position.lat`` /
``position.lon`` in WGS-84 degrees, ``sog`` in knots, ``cog`` and ``heading`` in degrees from north,
clockwise) and ``waypoints`` (``position``, optional ``leg.sog`` / ``leg.data.sog.value`` in knots). The
older field names of the schema's first releases and of DNV's ship-traffic-generator output
(``position.latitude`` / ``position.longitude``, ``static.length``; dnv-opensource/maritime-schema
``schema/caga/input_schema.json``, commit 0d76daf3ac5cd138f093d23795bbcd46c819a597) are read as well.

Geometry. Positions are mapped to a local tangent plane (x north, y east, metres) at a reference point on the
WGS-84 ellipsoid (a = 6378137 m, f = 1/298.257223563): geodetic → Earth-centred Earth-fixed → rotation into
the reference's north/east/up frame, dropping "up". Reading, the reference is the own ship's initial position;
writing, it is a stated latitude/longitude. The map preserves distances from the reference to within
d³/(6R²) (0.5 m at d = 50 km) and is inverted exactly (to < 1 mm) by a short fixed-point iteration. Courses
and headings are given against the local north of each ship; they are turned into the plane by projecting
the ship's local direction (this accounts for the convergence of the meridians, 0.7° at 50 km east of the
reference at 58° N). Metres become ship lengths of the KCS (L = 230 m) or, with ``length_scale="own-ship"``,
of the own ship (``ownShip.static.dimensions.length``; speeds then Froude-scaled to that length). Speeds in
knots become fractions of the design speed (24 kn for the KCS); outside the model's range
:data:`~mmg_casadi.scenarios.scenario.SPEED_RANGE` a :class:`~mmg_casadi.errors.ScenarioError` names the field.

Ships. The own ship uses ``method`` (the scenario's ``settings.method``); target ships use ``target_method``
(``"none"``: they track their own waypoints, or hold their course, without avoiding anyone). Waypoints within
:data:`START_TOLERANCE` of a ship's start are dropped (trafficgen repeats the start as the first waypoint);
a ship's path is extended along its last leg (its course if it has no waypoint) until it reaches at least
``extend_past`` ship lengths beyond the point it passes at the last closest approach of the own ship to any
target (all ships on straight courses at their initial speeds), so every encounter happens before the goal.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mmg_casadi.errors import ScenarioError
from mmg_casadi.guidance.methods import NAMES as METHODS
from mmg_casadi.scenarios.scenario import SPEED_RANGE, Scenario, dump_scenario, scenario_from_dict

WGS84_A = 6378137.0
"""WGS-84 semi-major axis [m]."""
WGS84_F = 1.0 / 298.257223563
"""WGS-84 flattening."""
WGS84_E2 = WGS84_F * (2.0 - WGS84_F)
KNOT = 1852.0 / 3600.0
"""One knot in m/s."""
START_TOLERANCE = 0.5
"""Waypoints closer than this to the ship's start are dropped [ship lengths]."""
EXTEND_PAST = 30.0
"""Default path length past the last closest approach [ship lengths] (twice the default safe radius)."""
DEFAULT_REFERENCE = (58.61, 10.59)
"""Default reference latitude/longitude [deg] when writing a scenario that records none (outer Oslofjord)."""
SCHEMA_VERSION = "0.2.0"
T_MAX_MARGIN = 1.5
"""``t_max`` of a converted scenario: this factor times the longest sailing time of any ship, at least 300."""
LENGTH_SCALES = ("kcs", "own-ship")

_HEADER = re.compile(r"^# maritime-schema reference: lat = (\S+), lon = (\S+), length = (\S+) m$", re.M)


# --------------------------------------------------------------------------------------------- geometry

def _ecef(lat: float, lon: float, h: float = 0.0) -> np.ndarray:
    phi, lam = math.radians(lat), math.radians(lon)
    n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * math.sin(phi) ** 2)
    return np.array([(n + h) * math.cos(phi) * math.cos(lam), (n + h) * math.cos(phi) * math.sin(lam),
                     (n * (1.0 - WGS84_E2) + h) * math.sin(phi)])


def _geodetic(p) -> tuple[float, float, float]:
    """(lat, lon, h) of an ECEF point (iterated to 1e-14 rad)."""
    x, y, z = p
    lon = math.atan2(y, x)
    r = math.hypot(x, y)
    lat = math.atan2(z, r * (1.0 - WGS84_E2))
    for _ in range(10):
        n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * math.sin(lat) ** 2)
        h = r / math.cos(lat) - n if abs(lat) < math.pi / 4 else z / math.sin(lat) - n * (1.0 - WGS84_E2)
        new = math.atan2(z, r * (1.0 - WGS84_E2 * n / (n + h)))
        if abs(new - lat) < 1e-14:
            lat = new
            break
        lat = new
    n = WGS84_A / math.sqrt(1.0 - WGS84_E2 * math.sin(lat) ** 2)
    h = r / math.cos(lat) - n if abs(lat) < math.pi / 4 else z / math.sin(lat) - n * (1.0 - WGS84_E2)
    return math.degrees(lat), math.degrees(lon), h


def _neu(lat: float, lon: float) -> np.ndarray:
    """Rows: unit north, east, up vectors (ECEF) at a point."""
    phi, lam = math.radians(lat), math.radians(lon)
    sp, cp, sl, cl = math.sin(phi), math.cos(phi), math.sin(lam), math.cos(lam)
    return np.array([[-sp * cl, -sp * sl, cp], [-sl, cl, 0.0], [cp * cl, cp * sl, sp]])


def _wrap(angle_deg: float) -> float:
    """``angle_deg`` in [0, 360) (``-1e-17 % 360`` is 360.0 in floating point)."""
    a = angle_deg % 360.0
    return 0.0 if a >= 360.0 else a


@dataclass(frozen=True)
class LocalPlane:
    """Local tangent plane (x north, y east, metres) at the reference ``lat``, ``lon`` [deg] on WGS-84.

    Parameters
    ----------
    lat : float
        Latitude of the reference point (the plane's origin) [deg, WGS-84, north positive], in [-90, 90].
    lon : float
        Longitude of the reference point [deg, WGS-84, east positive], in [-180, 180].

    Examples
    --------
    >>> plane = LocalPlane(58.61, 10.59)
    >>> plane.to_plane(58.61, 10.59)
    (0.0, 0.0)
    >>> x, y = plane.to_plane(58.70, 10.80)
    >>> lat, lon = plane.to_geodetic(x, y)
    >>> abs(lat - 58.70) < 1e-9 and abs(lon - 10.80) < 1e-9
    True
    """

    lat: float
    lon: float

    def _frame(self):
        return _ecef(self.lat, self.lon), _neu(self.lat, self.lon)

    def to_plane(self, lat: float, lon: float) -> tuple[float, float]:
        """(x north, y east) [m] of a point on the ellipsoid.

        Parameters
        ----------
        lat : float
            Latitude of the point [deg, WGS-84].
        lon : float
            Longitude of the point [deg, WGS-84].

        Returns
        -------
        (float, float)
            The point's projection on the plane: metres north and east of the reference.
        """
        origin, neu = self._frame()
        d = neu @ (_ecef(lat, lon) - origin)
        return float(d[0]), float(d[1])

    def to_geodetic(self, x: float, y: float) -> tuple[float, float]:
        """(lat, lon) [deg] of the point on the ellipsoid whose projection on the plane is (x, y).

        The inverse of :meth:`to_plane` (to < 1 mm; a fixed-point iteration over the height above the plane).

        Parameters
        ----------
        x : float
            Metres north of the reference, in the plane.
        y : float
            Metres east of the reference, in the plane.

        Returns
        -------
        (float, float)
            Latitude and longitude [deg, WGS-84].
        """
        origin, neu = self._frame()
        up = 0.0
        for _ in range(20):
            lat, lon, _h = _geodetic(origin + neu.T @ np.array([x, y, up]))
            d = neu @ (_ecef(lat, lon) - origin)
            if abs(d[2] - up) < 1e-7:
                break
            up = float(d[2])
        return lat, lon

    def course_to_plane(self, course_deg: float, lat: float, lon: float) -> float:
        """A course [deg from local north, clockwise] at (lat, lon) as an angle in the plane [deg from x to y].

        Parameters
        ----------
        course_deg : float
            Course or heading [deg from the local north at (lat, lon), clockwise].
        lat : float
            Latitude of the ship [deg, WGS-84].
        lon : float
            Longitude of the ship [deg, WGS-84].

        Returns
        -------
        float
            The direction in the plane [deg from x (north of the reference) towards y (east)], in [0, 360).
        """
        c = math.radians(course_deg)
        local = _neu(lat, lon)
        v = _neu(self.lat, self.lon) @ (math.cos(c) * local[0] + math.sin(c) * local[1])
        return _wrap(math.degrees(math.atan2(v[1], v[0])))

    def course_from_plane(self, angle_deg: float, lat: float, lon: float) -> float:
        """The inverse of :meth:`course_to_plane` (to ~(d/R)² rad): a plane angle as a course at (lat, lon).

        Parameters
        ----------
        angle_deg : float
            Direction in the plane [deg from x (north of the reference) towards y (east)].
        lat : float
            Latitude of the ship [deg, WGS-84].
        lon : float
            Longitude of the ship [deg, WGS-84].

        Returns
        -------
        float
            The course [deg from the local north at (lat, lon), clockwise], in [0, 360).
        """
        a = math.radians(angle_deg)
        ref = _neu(self.lat, self.lon)
        v = _neu(lat, lon) @ (math.cos(a) * ref[0] + math.sin(a) * ref[1])
        return _wrap(math.degrees(math.atan2(v[1], v[0])))


# ------------------------------------------------------------------------------------------ JSON parsing

def _kcs():
    from mmg_casadi.vessel.ship import load_kcs
    return load_kcs()


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


def _num(value, field: str, low=None, high=None, unit: str = "") -> float:
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    if ok and (low is None or value >= low) and (high is None or value <= high):
        return float(value)
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    raise ScenarioError(field, f"a number in [{lo}, {hi}]" + (f" {unit}" if unit else ""), value)


def _position(d, field: str) -> tuple[float, float]:
    """(lat, lon) of ``d["position"]`` (``lat``/``lon`` or ``latitude``/``longitude``)."""
    where = f"{field}.position"
    p = _get(d, field, "position")
    lat = _num(_get(p, where, "lat", "latitude"), f"{where}.lat", -90.0, 90.0, "deg")
    lon = _num(_get(p, where, "lon", "longitude"), f"{where}.lon", -180.0, 180.0, "deg")
    return lat, lon


def _leg_sog(wp: dict, field: str):
    leg = wp.get("leg") if isinstance(wp, dict) else None
    if not isinstance(leg, dict):
        return None
    data = leg.get("data")
    if isinstance(data, dict) and isinstance(data.get("sog"), dict) and "value" in data["sog"]:
        return _num(data["sog"]["value"], f"{field}.leg.data.sog.value", 0.0, None, "kn")
    if leg.get("sog") is not None:
        return _num(leg["sog"], f"{field}.leg.sog", 0.0, None, "kn")
    return None


@dataclass
class _Ship:
    name: str
    lat: float
    lon: float
    sog_kn: float
    cog: float
    heading: float
    waypoints: list  # [(lat, lon)]
    length_m: float | None
    field: str


def _ship(d, field: str, index: int) -> _Ship:
    if not isinstance(d, dict):
        raise ScenarioError(field, "an object with static, initial and waypoints", d)
    static = _get(d, field, "static", required=False) or {}
    if not isinstance(static, dict):
        raise ScenarioError(f"{field}.static", "an object", static)
    name = static.get("name")
    if not isinstance(name, str) or not name.strip():
        name = f"ship{index}" if "id" not in static else f"ship{static['id']}"
    dims = static.get("dimensions")
    length = dims.get("length") if isinstance(dims, dict) else static.get("length")
    length_m = None if length is None else _num(length, f"{field}.static.dimensions.length", 1e-3, None, "m")
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
        plane = LocalPlane(lat, lon)
        x, y = plane.to_plane(*waypoints[1])
        cog = _wrap(math.degrees(math.atan2(y, x)))
        heading = cog
        sog = _leg_sog(wps[1], f"{field}.waypoints[1]")
        if sog is None:
            raise ScenarioError(f"{field}.waypoints[1].leg.sog", "a speed in knots (no initial state given)")
    else:
        lat, lon = _position(initial, f"{field}.initial")
        sog = _num(_get(initial, f"{field}.initial", "sog"), f"{field}.initial.sog", 0.0, None, "kn")
        cog = _num(_get(initial, f"{field}.initial", "cog"), f"{field}.initial.cog", 0.0, 360.0, "deg")
        h = _get(initial, f"{field}.initial", "heading", required=False)
        heading = cog if h is None else _num(h, f"{field}.initial.heading", 0.0, 360.0, "deg")
    return _Ship(name.strip(), lat, lon, sog, cog, heading, waypoints, length_m, field)


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


def traffic_situation_to_scenario(data: dict, *, method: str = "modified-vortex", target_method: str = "none",
                                  length_scale: str = "kcs", extend_past: float = EXTEND_PAST,
                                  source: str = "<json>") -> tuple[Scenario, LocalPlane, float]:
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
    """
    for name, value in (("method", method), ("target_method", target_method)):
        if value not in METHODS:
            raise ScenarioError(name, f"one of: {', '.join(METHODS)}", value)
    if length_scale not in LENGTH_SCALES:
        raise ScenarioError("length_scale", f"one of: {', '.join(LENGTH_SCALES)}", length_scale)
    if not (isinstance(extend_past, (int, float)) and math.isfinite(extend_past) and extend_past >= 0):
        raise ScenarioError("extend_past", "a number >= 0 (ship lengths)", extend_past)
    try:
        if not isinstance(data, dict):
            raise ScenarioError("traffic situation", "a JSON object with ownShip and targetShips", data)
        own = _ship(_get(data, "", "ownShip"), "ownShip", 0)
        targets = data.get("targetShips") or []
        if not isinstance(targets, list):
            raise ScenarioError("targetShips", "an array of target ships", targets)
        ships = [own] + [_ship(t, f"targetShips[{i}]", i + 1) for i, t in enumerate(targets)]
        kcs = _kcs()
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
        for s in ships:
            speed = s.sog_kn * KNOT / u_des
            if not lo <= speed <= hi:
                raise ScenarioError(f"{s.field}.initial.sog", f"a speed in [{lo * u_des / KNOT:.2f}, "
                                    f"{hi * u_des / KNOT:.2f}] kn ([{lo:g}, {hi:g}] x the design speed "
                                    f"{u_des / KNOT:.2f} kn)", s.sog_kn)
            x, y = plane.to_plane(s.lat, s.lon)
            start = (x / unit, y / unit)
            heading = plane.course_to_plane(s.heading, s.lat, s.lon)
            course = plane.course_to_plane(s.cog, s.lat, s.lon)
            path = []
            for lat, lon in s.waypoints:
                px, py = plane.to_plane(lat, lon)
                p = (px / unit, py / unit)
                if not path and math.dist(p, start) < START_TOLERANCE:
                    continue
                path.append(p)
            name = s.name if s.name not in names else f"{s.name} ({len(rows)})"
            names[name] = len(rows)
            rows.append({"name": name, "start": start, "heading": heading, "course": course, "speed": speed,
                         "path": path})
        starts = [np.asarray(r["start"]) for r in rows]
        vel = [r["speed"] * np.array([math.cos(math.radians(r["course"])), math.sin(math.radians(r["course"]))])
               for r in rows]
        t_cpa = _last_cpa_time(starts, vel)
        t_sail = 0.0
        out_ships = []
        for i, r in enumerate(rows):
            needed = r["speed"] * t_cpa + extend_past
            path = _extend(r["start"], r["path"], math.radians(r["course"]), needed)
            pts = [r["start"]] + path
            t_sail = max(t_sail, sum(math.dist(a, b) for a, b in zip(pts[:-1], pts[1:])) / r["speed"])
            ship = {"name": r["name"], "start": list(r["start"]), "heading": r["heading"], "speed": r["speed"],
                    "waypoints": [list(p) for p in path]}
            if i > 0:
                ship["method"] = target_method
            out_ships.append(ship)
        t_max = min(10000.0, max(300.0, math.ceil(T_MAX_MARGIN * t_sail)))
        sc = scenario_from_dict({"settings": {"method": method, "t_max": t_max}, "ships": out_ships},
                                source=source)
    except ScenarioError as err:
        err.source = source
        raise
    return sc, plane, unit


def load_traffic_situation(path, **kw) -> tuple[Scenario, LocalPlane, float]:
    """Read a maritime-schema JSON file; see :func:`traffic_situation_to_scenario` for ``kw`` and the result.

    A missing file, invalid JSON or a malformed situation raise a :class:`~mmg_casadi.errors.ScenarioError`.

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
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as err:
        raise ScenarioError(str(path), "an existing, readable JSON file", err.strerror or str(err)) from None
    except UnicodeDecodeError as err:
        raise ScenarioError("json", f"UTF-8 text in {path}", str(err)) from None
    try:
        data = json.loads(text)
    except (ValueError, RecursionError) as err:
        raise ScenarioError("json", f"valid JSON in {path}", str(err)) from None
    return traffic_situation_to_scenario(data, source=str(path), **kw)


# ---------------------------------------------------------------------------------------------- writing

def scenario_to_traffic_situation(sc: Scenario, *, reference=DEFAULT_REFERENCE, unit_m: float | None = None,
                                  title: str = "mmg-casadi scenario") -> dict:
    """``sc`` as a maritime-schema (0.2.0) traffic situation, positions about ``reference`` = (lat, lon) [deg].

    The scenario's origin (0, 0) is put at ``reference``; lengths are ``unit_m`` metres per ship length (the
    KCS length by default), speeds fractions of the matching Froude-scaled design speed. Each ship's
    waypoints start with its initial position (as trafficgen writes them); obstacles and walls have no place
    in the schema and are left out.

    Parameters
    ----------
    sc : Scenario
        The scenario (positions in ship lengths, x north, y east; speeds as fractions of the design speed).
    reference : (float, float), optional
        Latitude and longitude [deg, WGS-84] of the scenario's origin, lat in [-90, 90] and lon in
        [-180, 180]; default :data:`DEFAULT_REFERENCE`.
    unit_m : float, optional
        Metres per ship length (> 0), also written as every ship's length; the KCS length (230 m) if None.
        Speeds are scaled with the design speed Froude-scaled to this length (24 kn at 230 m).
    title : str, optional
        The situation's ``title``.

    Returns
    -------
    dict
        The traffic situation (``version``, ``title``, ``description``, ``ownShip`` = the first ship,
        ``targetShips`` = the others), ready for :func:`json.dumps`.

    Examples
    --------
    >>> from mmg_casadi.scenarios.scenario import Settings, ShipSpec
    >>> sc = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 90, 0.5, [[0, 50]])])
    >>> sit = scenario_to_traffic_situation(sc)
    >>> p = sit["ownShip"]["initial"]["position"]
    >>> round(p["lat"], 9), round(p["lon"], 9), round(sit["ownShip"]["initial"]["sog"], 2)
    (58.61, 10.59, 12.0)
    >>> round(sit["ownShip"]["initial"]["cog"], 6)
    90.0
    """
    lat0, lon0 = (_num(v, f"reference[{i}]", lo, hi, "deg")
                  for i, (v, lo, hi) in enumerate(zip(reference, (-90.0, -180.0), (90.0, 180.0))))
    kcs = _kcs()
    unit = kcs.L if unit_m is None else _num(unit_m, "unit_m", 1e-3, None, "m")
    u_des = kcs.U_design * math.sqrt(unit / kcs.L)
    plane = LocalPlane(lat0, lon0)

    def pos(p):
        lat, lon = plane.to_geodetic(p[0] * unit, p[1] * unit)
        return {"lat": lat, "lon": lon}

    ships = []
    for i, s in enumerate(sc.ships):
        start = pos(s.start)
        course = plane.course_from_plane(s.heading_deg, start["lat"], start["lon"])
        sog = s.speed * u_des / KNOT
        wps = [{"position": start}] + [{"position": pos(p), "leg": {"sog": sog}} for p in s.waypoints]
        ships.append({
            "static": {"id": i + 1, "name": s.name, "dimensions": {"length": unit}},
            "initial": {"position": start, "sog": sog, "cog": course, "heading": course,
                        "navStatus": "Under way using engine"},
            "waypoints": wps,
        })
    return {"version": SCHEMA_VERSION, "title": title,
            "description": f"written by mmg-casadi; {len(sc.ships)} ships, collision-avoidance method "
                           f"{sc.settings.method}",
            "ownShip": ships[0], "targetShips": ships[1:]}


def dump_traffic_situation(sc: Scenario, **kw) -> str:
    """:func:`scenario_to_traffic_situation` as JSON text.

    Parameters
    ----------
    sc : Scenario
        The scenario to write.
    **kw
        Keyword arguments of :func:`scenario_to_traffic_situation`: ``reference``, ``unit_m``, ``title``.

    Returns
    -------
    str
        The JSON text (indented by 2, with a final newline).
    """
    return json.dumps(scenario_to_traffic_situation(sc, **kw), indent=2) + "\n"


def scenario_header(plane: LocalPlane, unit_m: float) -> str:
    """A TOML comment recording the reference of a converted scenario (read back by :func:`read_header`).

    Parameters
    ----------
    plane : LocalPlane
        The plane the scenario is drawn in; its reference ``lat``, ``lon`` [deg] are recorded.
    unit_m : float
        The length unit [m per ship length] of the scenario.

    Returns
    -------
    str
        Two comment lines, each ending with a newline, to be put before the scenario's TOML text.

    Examples
    --------
    >>> read_header(scenario_header(LocalPlane(58.5, 10.25), 230.0))
    (58.5, 10.25, 230.0)
    """
    return (f"# maritime-schema reference: lat = {plane.lat!r}, lon = {plane.lon!r}, length = {unit_m!r} m\n"
            "# (x north, y east in the local tangent plane at this point; lengths in ship lengths)\n")


def read_header(text: str):
    """(lat, lon, length_m) from a :func:`scenario_header` comment in ``text``, or None.

    Parameters
    ----------
    text : str
        Text of a scenario TOML file; the first header line anywhere in it counts.

    Returns
    -------
    (float, float, float) or None
        Reference latitude and longitude [deg] and the length unit [m]; None if there is no header line or
        one of its numbers is not a finite float.

    Examples
    --------
    >>> read_header("[settings]") is None
    True
    """
    m = _HEADER.search(text)
    if m is None:
        return None
    try:
        values = tuple(float(v) for v in m.groups())
    except ValueError:
        return None
    return values if all(math.isfinite(v) for v in values) else None


def json_to_toml_text(path, **kw) -> str:
    """Scenario-file TOML text (with its reference header) of a maritime-schema JSON file.

    Parameters
    ----------
    path : str or os.PathLike
        The maritime-schema JSON file.
    **kw
        Keyword arguments of :func:`traffic_situation_to_scenario`: ``method``, ``target_method``,
        ``length_scale``, ``extend_past``.

    Returns
    -------
    str
        The :func:`scenario_header` comment followed by the scenario (:func:`~mmg_casadi.scenarios.scenario.dump_scenario`).
    """
    sc, plane, unit = load_traffic_situation(path, **kw)
    return scenario_header(plane, unit) + dump_scenario(sc)


def toml_to_json_text(path, *, reference=None) -> str:
    """maritime-schema JSON text of a scenario TOML file, about ``reference`` = (lat, lon), else the reference
    recorded in the file's header, else :data:`DEFAULT_REFERENCE`.

    Parameters
    ----------
    path : str or os.PathLike
        The scenario TOML file (UTF-8); its name without suffix becomes the situation's ``title``.
    reference : (float, float), optional
        Latitude and longitude [deg] of the scenario's origin. If None, the file's :func:`scenario_header`
        supplies the reference and the length unit; without a header the reference is
        :data:`DEFAULT_REFERENCE` and the unit the KCS length (230 m). A given ``reference`` always uses the
        KCS length, even if the file has a header.

    Returns
    -------
    str
        The JSON text (:func:`dump_traffic_situation`).
    """
    from mmg_casadi.scenarios.scenario import load_scenario
    sc = load_scenario(path)
    header = read_header(Path(path).read_text(encoding="utf-8"))
    unit = None
    if reference is None and header is not None:
        reference, unit = header[:2], header[2]
    return dump_traffic_situation(sc, reference=reference or DEFAULT_REFERENCE, unit_m=unit,
                                  title=Path(path).stem)


def parse_reference(text):
    """``"LAT,LON"`` [deg] as a (lat, lon) tuple (None stays None).

    Parameters
    ----------
    text : str or None
        Two numbers separated by one comma (spaces allowed), latitude in [-90, 90] and longitude in
        [-180, 180] degrees, as given to ``--reference``; anything else raises a
        :class:`~mmg_casadi.errors.ScenarioError`.

    Returns
    -------
    (float, float) or None
        ``(lat, lon)``, or None if ``text`` is None.

    Examples
    --------
    >>> parse_reference("58.5, 10.25")
    (58.5, 10.25)
    >>> parse_reference("north")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ScenarioError: --reference: expected LAT,LON in degrees (lat in [-90, 90], lon in [-180, 180]), got 'north'
    """
    if text is None:
        return None
    allowed = "LAT,LON in degrees (lat in [-90, 90], lon in [-180, 180])"
    parts = str(text).split(",")
    try:
        lat, lon = (float(v) for v in parts)
    except ValueError:
        raise ScenarioError("--reference", allowed, text) from None
    if not (math.isfinite(lat) and math.isfinite(lon) and -90 <= lat <= 90 and -180 <= lon <= 180):
        raise ScenarioError("--reference", allowed, text)
    return lat, lon


def convert_file(src, out, *, method: str = "modified-vortex", target_method: str = "none",
                 length_scale: str = "kcs", reference=None) -> dict:
    """Convert ``src`` (``.json`` traffic situation or ``.toml`` scenario) into ``out`` (the other format).

    The output is written only if the conversion succeeds (a temporary file, then a rename). ``reference``
    (``"LAT,LON"`` or a tuple) applies to TOML → JSON; the other keywords to JSON → TOML.

    Parameters
    ----------
    src : str or os.PathLike
        The input file: a ``.json`` traffic situation or a ``.toml`` scenario (suffix case-insensitive).
    out : str or os.PathLike
        The output file, with the other suffix (``.toml`` for a JSON input, ``.json`` for a TOML one); its
        directory is created if needed.
    method : str, optional
        Collision-avoidance method of the own ship (JSON → TOML), one of :data:`~mmg_casadi.guidance.methods.METHODS`.
    target_method : str, optional
        Method of the target ships (JSON → TOML); ``"none"``: they do not avoid anyone.
    length_scale : str, optional
        ``"kcs"`` or ``"own-ship"`` (JSON → TOML), see :func:`traffic_situation_to_scenario`.
    reference : str or (float, float), optional
        Latitude and longitude [deg] of the scenario's origin (TOML → JSON), ``"LAT,LON"``
        (:func:`parse_reference`) or a tuple; None: the file's header, else :data:`DEFAULT_REFERENCE`.

    Returns
    -------
    dict
        ``{"out": str(out), "ships": number of ships}``.
    """
    src, out = Path(src), Path(out)
    kinds = {".json": ".toml", ".toml": ".json"}
    if src.suffix.lower() not in kinds:
        raise ScenarioError("file", "a .json traffic situation or a .toml scenario file", str(src))
    if out.suffix.lower() != kinds[src.suffix.lower()]:
        raise ScenarioError("--out", f"a {kinds[src.suffix.lower()]} file (converting {src.suffix})", str(out))
    if isinstance(reference, str):
        reference = parse_reference(reference)
    if src.suffix.lower() == ".json":
        text = json_to_toml_text(src, method=method, target_method=target_method, length_scale=length_scale)
        n = len(scenario_from_dict(_toml_loads(text)).ships)
    else:
        text = toml_to_json_text(src, reference=reference)
        n = 1 + len(json.loads(text)["targetShips"])
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(out.suffix + ".tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(out)
    return {"out": str(out), "ships": n}


def _toml_loads(text: str) -> dict:
    import tomllib
    return tomllib.loads(text)
