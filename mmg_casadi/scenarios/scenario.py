"""Scenario files: ships, static obstacles and channel walls of one encounter (TOML, read with :mod:`tomllib`,
written with ``tomli_w``).

Conventions: positions in ship lengths L, x forward/north and y to starboard/east, headings in degrees measured
from x towards y (clockwise in the marine view, x up and y right), speeds as fractions of the design speed,
times non-dimensional (L/U). A scenario file looks like::

    [settings]
    method = "modified-vortex"   # inverse-square | sink-vortex | modified-vortex | velocity-obstacle | none
    dt = 0.25                    # guidance step
    t_max = 300.0                # horizon
    r_safe = 15.0                # L, safe radius
    collision_distance = 2.0     # L, ship centres closer than this collide (times the pair's mean length in L)
    [[ships]]                    # the first ship is the own ship
    name = "own"
    start = [0.0, 0.0]
    heading = 0.0                # degrees from x towards y
    speed = 1.0                  # fraction of design speed
    waypoints = [[50.0, 0.0]]
    # method = "none"            # optional per-ship override of settings.method
    # stays = false              # optional: after reaching its goal the ship stays as an obstacle
    # vessel = "kcs"             # optional: the ship's hull (default the table's 'vessel')
    # speeds = [1.0]             # optional: speed on the leg to each waypoint (default: speed on every leg)
    # route = "plan"             # optional: plan the route around the land (default settings.route, "as-given")
    # behaviour = "late"         # a target only: avoid | hold | late | wrong | intent (mmg_casadi.traffic)
    # late_delay = 4.0           #   late: her method acts once it has wanted to this long (L/U)
    # wrong_turn = 40.0          #   wrong: the turn to port (deg) in a head-on or crossing risk
    # track = "target.csv"       # a target only, instead of start ... speeds and method: it replays this
                                 #   recorded track (t, x, y) in time (mmg_casadi.scenarios.tracks)
    # length_m = 122.0           # optional: the ship's own length and beam in metres (default: its vessel's);
    # beam_m = 20.0              #   its collision geometry (the length unit L stays the default hull's, 230 m)
    # [ships.metadata]           # optional: further static data kept as is (maritime-schema names), e.g.
    # id = 7                     #   id, mmsi, imo, shipType, sogMax, dimensions.height; written back on export
    [[obstacles]]
    position = [25.0, 0.0]
    radius = 0.5
    [[walls]]
    points = [[0.0, 5.0], [50.0, 55.0]]   # polyline; each consecutive pair of points is one wall segment
    [[land]]
    points = [[60.0, -5.0], [70.0, -5.0], [65.0, 5.0]]  # polygon (closed), at least 3 points; no ship starts
                                                        # or waypoint inside; touching it is a grounding
    # [chart]                    # optional: land from a GeoJSON file (mmg_casadi.scenarios.geojson_land)
    # land_file = "coast.geojson"  #   Polygon/MultiPolygon features (lon, lat), relative to this file's folder
    # origin = [58.61, 10.59]    #   latitude, longitude of the frame's (0, 0); length_m = 230.0 per L (optional)
    [environment]                # optional; calm water without it
    current_speed = 0.1          # fraction of design speed, [0, 1]
    current_direction = 90.0     # degrees, the direction the current flows TOWARDS
    wind_speed = 15.0            # m/s, [0, 60]
    wind_direction = -90.0       # degrees, the direction the wind comes FROM
    # crab_compensation = "on"   # ILOS steers the course over the ground (default "off")

The ``[environment]`` keys are aliases of the table parameters ``current_speed``, ``current_direction_deg``,
``wind_speed``, ``wind_direction_deg`` and ``crab_compensation`` (:data:`ENVIRONMENT_KEYS`), which ``[settings]``,
``--params``, ``--set`` and ``params=`` accept as well; giving one in both tables is an error. The model is
described in :mod:`mmg_casadi.vessel.environment`: the ship's ``u, v`` are velocities through the water, the current
carries it over the ground, the wind load comes from Blendermann (1994).

Besides ``method``, ``[settings]`` accepts every parameter of the table :data:`mmg_casadi.params.PARAMETERS`
(range-checked here); ``dt``, ``t_max``, ``r_safe``, ``collision_distance`` and ``goal_tolerance`` are fields of
:class:`Settings`, the others are kept in :attr:`Settings.params`.

Every malformed entry raises one :class:`~mmg_casadi.errors.ScenarioError` whose ``field`` is the dotted key
(``ships[1].speed``, ``settings.method``, ``obstacles[0].position``) and whose message lists the allowed values.
"""

from __future__ import annotations

import copy
import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mmg_casadi.vessel.library import VESSELS, pair_collision_distance, ship_size
from mmg_casadi.guidance import methods
from mmg_casadi.errors import ParameterError, ScenarioError
from mmg_casadi.io import read_toml
from mmg_casadi.limits import MAX_COORDINATE
from mmg_casadi.scenarios.geodesy import read_header
from mmg_casadi.scenarios.geojson_land import chart_land
from mmg_casadi.scenarios.scenario_checks import (_POINT, _as_point, _as_points, _name, _point, _points,
                                                 _range_text, _ranged, _required, _string, _table, _tables,
                                                 check_metadata, toml_key, valid_polygon)
from mmg_casadi.scenarios.tracks import Track, parse_track
from mmg_casadi.traffic import behaviour as traffic_behaviour
from mmg_casadi.scenarios.scenario_write import (PARAM_KEYS, SETTINGS_FIELDS, dump_scenario,  # noqa: F401
                                                 scenario_to_dict)  # (dump_scenario, scenario_to_dict re-exported)
from mmg_casadi.params import PARAMETERS, check_value, resolve

SETTINGS_KEYS = ("method",) + tuple(PARAMETERS)
SHIP_KEYS = ("name", "start", "heading", "speed", "waypoints", "method", "stays", "vessel", "speeds", "length_m",
             "beam_m", "metadata", "track", "route", "behaviour", "late_delay", "wrong_turn")
REPLAY_KEYS = ("name", "track", "stays", "vessel", "length_m", "beam_m", "metadata")
"""Keys of a replayed ship (one with a ``track``): its start, heading, speed and goal come from the track."""
OBSTACLE_KEYS = ("position", "radius")
WALL_KEYS = ("points",)
LAND_KEYS = ("points",)
TOP_KEYS = ("settings", "ships", "obstacles", "walls", "land", "environment", "chart")
ENVIRONMENT_KEYS = {"current_speed": "current_speed", "current_direction": "current_direction_deg",
                    "wind_speed": "wind_speed", "wind_direction": "wind_direction_deg",
                    "crab_compensation": "crab_compensation"}
"""Keys of the optional ``[environment]`` table and the table parameter each one sets."""
SPEED_RANGE = (0.2, 1.2)
"""Allowed ``speed`` of a ship (``[[ships]]`` table), (low, high) as fractions of the design speed, inclusive."""
SHIP_HALF_LENGTH = 0.5

@dataclass(frozen=True)
class Settings:
    """Scenario-wide settings.

    ``method``: collision-avoidance method, a name in :data:`mmg_casadi.guidance.methods.METHODS`; ``dt``: guidance step (non-dimensional time,
    rudder command held over the step); ``t_max``: horizon (non-dimensional time); ``r_safe``: safe radius
    inside which other ships and obstacles act (L); ``collision_distance``: ship centres closer than this
    collide (L); ``goal_tolerance``: goal reached within this distance (L); ``params``: optional field and
    guidance parameter overrides (keys from :data:`PARAM_KEYS`; ``params`` is left out of the hash).

    Parameters
    ----------
    method : str
        Collision-avoidance method, a name in :data:`mmg_casadi.guidance.methods.METHODS`.
    dt : float, optional
        Guidance step (L/U); the rudder command is held over the step.
    t_max : float, optional
        Horizon (L/U).
    r_safe : float, optional
        Safe radius inside which other ships and obstacles act (L).
    collision_distance : float, optional
        Ship centres closer than this collide (L).
    goal_tolerance : float, optional
        A goal is reached within this distance (L).
    params : dict, optional
        Field and guidance parameter overrides (keys from :data:`PARAM_KEYS`).

    Examples
    --------
    >>> Settings("none").dt, Settings("none").params
    (0.25, {})
    """

    method: str
    dt: float = PARAMETERS["dt"].default
    t_max: float = PARAMETERS["t_max"].default
    r_safe: float = PARAMETERS["r_safe"].default
    collision_distance: float = PARAMETERS["collision_distance"].default
    goal_tolerance: float = PARAMETERS["goal_tolerance"].default
    params: dict = field(default_factory=dict, hash=False)

    def __post_init__(self):
        object.__setattr__(self, "params", dict(self.params))

    def resolved(self, overrides: dict | None = None, *, cls=ParameterError) -> dict:
        """The full parameter set of this scenario: table defaults, these settings, then ``overrides``.

        Parameters
        ----------
        overrides : dict or None, optional
            Parameter values (table names) applied last.
        cls : type, default ParameterError
            Exception class raised for an invalid value.

        Returns
        -------
        dict
            Every parameter of :data:`~mmg_casadi.params.PARAMETERS` by table name, in table units.

        Examples
        --------
        >>> Settings("none", r_safe=10.0).resolved({"kp": 2.0})["r_safe"]
        10.0
        """
        own = {k: getattr(self, k) for k in SETTINGS_FIELDS}
        return resolve(own, self.params, overrides, cls=cls)


@dataclass(frozen=True)
class ShipSpec:
    """One ship: ``name``; ``start`` position (L); ``heading_deg`` initial heading (degrees from x towards y);
    ``speed`` as a fraction of the design speed; ``waypoints`` (L, the last one is the goal); ``method`` an
    optional override of :attr:`Settings.method`; ``stays``: after reaching its goal the ship stays there as an
    obstacle (otherwise it leaves the scenario).

    Parameters
    ----------
    name : str
        Name of the ship.
    start : tuple of float
        Start position (x, y) (L).
    heading_deg : float
        Initial heading (degrees from x towards y).
    speed : float
        Initial speed as a fraction of the design speed.
    waypoints : sequence of (float, float)
        Waypoints (L); the last one is the goal.
    method : str or None, optional
        Collision-avoidance method of this ship (default: :attr:`Settings.method`).
    stays : bool, optional
        Whether the ship stays at its goal as an obstacle after reaching it.
    vessel : str or None, optional
        The ship's hull (:data:`mmg_casadi.vessel.library.VESSELS`; default: the table's ``vessel``).
    speeds : tuple of float or None, optional
        Speed on the leg to each waypoint (fractions of the design speed); ``None``: ``speed`` on every leg. The
        closed loop orders the propeller speed of each leg's steady speed, which the engine follows.
    length_m, beam_m : float or None, optional
        The ship's own length and beam [m], as an imported traffic situation gives them (> 0); default its
        vessel's. They set its collision geometry (:func:`~mmg_casadi.vessel.library.ship_size`): it collides
        with another ship within ``collision_distance`` times their mean length (in L, the default hull's length,
        the scenario's unit) and touches a wall or land at half its beam. Its motion is still its vessel's.
    metadata : dict, optional
        Further static data kept as read and written back on export (JSON-compatible values, see
        :func:`check_metadata`): for a maritime-schema ship its ``static`` object without ``name`` and the
        length and width, e.g. ``id``, ``mmsi``, ``shipType``, ``sogMax``, ``dimensions.height``. Left out of the
        hash.
    behaviour : str or None, optional
        A target's behaviour (:data:`~mmg_casadi.traffic.behaviour.FILE_BEHAVIOURS`, :mod:`mmg_casadi.traffic`);
        ``None``: she sails with her method as always.
    late_delay : float or None, optional
        A late ship's delay (L/U).
    wrong_turn_deg : float or None, optional
        A wrong-way ship's turn to port (deg).
    track : Track or None, optional
        A replayed ship's recorded track (:mod:`mmg_casadi.scenarios.tracks`): it follows the track instead of
        being simulated, and ``start``, ``heading_deg``, ``speed`` and ``waypoints`` (its last position) are the
        track's at t = 0; ``None`` for a simulated ship.
    route : str or None, optional
        ``"plan"``: her route is planned around the land (:mod:`mmg_casadi.scenarios.routes`); ``"as-given"``: her
        waypoints as written; ``None``: the parameter ``route``.

    Examples
    --------
    >>> s = ShipSpec("own", [0, 0], 90, 1.0, [[50, 0]])
    >>> s.start, s.goal, round(s.heading_rad, 4)
    ((0.0, 0.0), (50.0, 0.0), 1.5708)
    """

    name: str
    start: tuple[float, float]
    heading_deg: float
    speed: float
    waypoints: tuple[tuple[float, float], ...]
    method: str | None = None
    stays: bool = False
    vessel: str | None = None
    speeds: tuple | None = None
    length_m: float | None = None
    beam_m: float | None = None
    metadata: dict = field(default_factory=dict, hash=False)
    track: Track | None = None
    route: str | None = None
    behaviour: str | None = None
    late_delay: float | None = None
    wrong_turn_deg: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "start", _as_point(self.start))
        object.__setattr__(self, "heading_deg", float(self.heading_deg))
        object.__setattr__(self, "speed", float(self.speed))
        object.__setattr__(self, "waypoints", _as_points(self.waypoints))
        for name in ("length_m", "beam_m"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, float(getattr(self, name)))
        object.__setattr__(self, "metadata", copy.deepcopy(dict(self.metadata)))

    @property
    def heading_rad(self) -> float:
        """Initial heading in rad (from x towards y)."""
        return math.radians(self.heading_deg)

    @property
    def goal(self) -> tuple[float, float]:
        """The last waypoint (L)."""
        return self.waypoints[-1]


@dataclass(frozen=True)
class ObstacleSpec:
    """A static circular obstacle: centre ``position`` (L) and ``radius`` (L).

    Parameters
    ----------
    position : tuple of float
        Centre (x, y) of the obstacle (L).
    radius : float, default 0.5
        Radius of the obstacle (L).

    Examples
    --------
    >>> ObstacleSpec([25, 0])
    ObstacleSpec(position=(25.0, 0.0), radius=0.5)
    """

    position: tuple[float, float]
    radius: float = 0.5

    def __post_init__(self):
        object.__setattr__(self, "position", _as_point(self.position))
        object.__setattr__(self, "radius", float(self.radius))


@dataclass(frozen=True)
class WallSpec:
    """A channel wall: a polyline of at least two ``points`` (L); each consecutive pair is one segment.

    Parameters
    ----------
    points : sequence of (float, float)
        Vertices of the polyline, at least two (L).

    Examples
    --------
    >>> WallSpec([[0, 5], [50, 55], [60, 55]]).segments
    (((0.0, 5.0), (50.0, 55.0)), ((50.0, 55.0), (60.0, 55.0)))
    """

    points: tuple[tuple[float, float], ...]

    def __post_init__(self):
        object.__setattr__(self, "points", _as_points(self.points))

    @property
    def segments(self) -> tuple[tuple[tuple[float, float], tuple[float, float]], ...]:
        """The wall segments as pairs of end points (L)."""
        return tuple(zip(self.points[:-1], self.points[1:]))


@dataclass(frozen=True)
class LandSpec:
    """Land: a polygon of at least three ``points`` (L), closed (the last point joins the first); its edges are
    hazards a ship grounds on (:mod:`mmg_casadi.guidance.hazards`, kind ``land``).

    Parameters
    ----------
    points : sequence of (float, float)
        Vertices of the polygon, at least three, not all on one line (L).

    Examples
    --------
    >>> island = LandSpec([[0, 0], [4, 0], [4, 2]])
    >>> len(island.edges), island.contains((3.0, 1.0)), island.contains((1.0, 1.0))
    (3, True, False)
    """

    points: tuple[tuple[float, float], ...]

    def __post_init__(self):
        object.__setattr__(self, "points", _as_points(self.points))

    @property
    def edges(self) -> tuple[tuple[tuple[float, float], tuple[float, float]], ...]:
        """The polygon's edges as pairs of end points (L), the closing edge last."""
        return tuple(zip(self.points, self.points[1:] + self.points[:1]))

    def contains(self, points):
        """Whether each point lies inside the polygon (even-odd rule; a point on an edge may go either way).

        Parameters
        ----------
        points : array-like (2,) or (K, 2)
            One point (x, y) or K points (L).

        Returns
        -------
        bool or numpy.ndarray of bool (K,)
            For one point a bool, for K points an array.
        """
        pts = np.asarray(points, dtype=float)
        x, y = np.atleast_2d(pts)[:, 0], np.atleast_2d(pts)[:, 1]
        inside = np.zeros(x.shape, bool)
        for (ax, ay), (bx, by) in self.edges:
            if ay != by:  # a horizontal edge crosses no ray
                inside ^= ((ay > y) != (by > y)) & (x < ax + (y - ay) * (bx - ax) / (by - ay))
        return bool(inside[0]) if pts.ndim == 1 else inside


@dataclass(frozen=True)
class Scenario:
    """A whole scenario (tuples throughout, so a scenario is hashable).

    Parameters
    ----------
    settings : Settings
        Method and parameters.
    ships : sequence of ShipSpec
        The ships; the first is the own ship.
    obstacles : sequence of ObstacleSpec
        Static circular obstacles.
    walls : sequence of WallSpec
        Channel walls.
    land : sequence of LandSpec
        Land polygons.

    Examples
    --------
    >>> s = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 1, [[50, 0]])])
    >>> s.ships[0].name, s.obstacles, s.method_of(0)
    ('own', (), 'none')
    """

    settings: Settings
    ships: tuple[ShipSpec, ...]
    obstacles: tuple[ObstacleSpec, ...] = ()
    walls: tuple[WallSpec, ...] = ()
    land: tuple[LandSpec, ...] = ()

    def __post_init__(self):
        for name in ("ships", "obstacles", "walls", "land"):
            object.__setattr__(self, name, tuple(getattr(self, name)))

    def method_of(self, i: int) -> str:
        """The method ship ``i`` uses: its own override, else :attr:`Settings.method`.

        Parameters
        ----------
        i : int
            Ship index (0 is the own ship).

        Returns
        -------
        str
            A name of :data:`~mmg_casadi.guidance.methods.METHODS`.
        """
        own = self.ships[i].method
        return self.settings.method if own is None else own


def _settings(d: dict) -> Settings:
    """Validated [settings] table (every parameter range-checked against the table)."""
    if "settings" not in d:
        raise ScenarioError("settings", "a [settings] table (required)")
    s = _table(d["settings"], "settings", SETTINGS_KEYS)
    method = _required(s, "method", "settings", f"one of: {', '.join(methods.offered())}")
    method = _string(method, "settings.method", methods.offered(method))
    values = {k: check_value(k, v, field=f"settings.{k}", cls=ScenarioError) for k, v in s.items()
              if k != "method"}
    values.update(_environment(d, values))
    kw = {k: values.pop(k) for k in SETTINGS_FIELDS if k in values}
    return Settings(method, params=values, **kw)


def _environment(d: dict, settings: dict) -> dict:
    """Table parameters from the optional [environment] table (checked; none may repeat a [settings] key)."""
    if "environment" not in d:
        return {}
    env = _table(d["environment"], "environment", tuple(ENVIRONMENT_KEYS))
    out = {}
    for k, v in env.items():
        name = ENVIRONMENT_KEYS[k]
        if name in settings:
            raise ScenarioError(f"environment.{k}", f"a value given once (settings.{name} gives it already)", v)
        out[name] = check_value(name, v, field=f"environment.{k}", cls=ScenarioError)
    return out


def _ship(t: dict, i: int, base_dir=None) -> ShipSpec:
    """Validated ``ships[i]`` table (a replayed ship's track file relative to ``base_dir``)."""
    if "track" in t:
        return _replayed_ship(t, i, base_dir)
    p = f"ships[{i}]"
    name = _name(t["name"], f"{p}.name") if "name" in t else f"ship{i}"
    start = _point(_required(t, "start", p, _POINT), f"{p}.start")
    heading = _ranged(_required(t, "heading", p, "a number in [-360, 360] degrees"), f"{p}.heading", -360.0, 360.0,
                      unit="degrees")
    lo, hi = SPEED_RANGE
    unit = "(fraction of design speed)"
    speed = _ranged(_required(t, "speed", p, _range_text(f"{p}.speed", lo, hi, unit=unit)), f"{p}.speed", lo, hi,
                    unit=unit)
    waypoints = _points(_required(t, "waypoints", p, "a list of waypoints [[x, y], ...]"), f"{p}.waypoints", 1)
    method = _string(t["method"], f"{p}.method", methods.offered(t["method"])) if "method" in t else None
    stays = t.get("stays", False)
    if not isinstance(stays, bool):
        raise ScenarioError(f"{p}.stays", "true or false", stays)
    vessel = _string(t["vessel"], f"{p}.vessel", VESSELS) if "vessel" in t else None
    speeds = None
    if "speeds" in t:
        allowed = f"a list of {len(waypoints)} speeds (one per waypoint), each in [{lo:g}, {hi:g}] {unit}"
        if not isinstance(t["speeds"], list) or len(t["speeds"]) != len(waypoints):
            raise ScenarioError(f"{p}.speeds", allowed, t["speeds"])
        speeds = tuple(_ranged(v, f"{p}.speeds[{k}]", lo, hi, unit=unit) for k, v in enumerate(t["speeds"]))
    size = _size(t, p)
    metadata = check_metadata(t["metadata"], f"{p}.metadata") if "metadata" in t else {}
    route = _string(t["route"], f"{p}.route", PARAMETERS["route"].choices) if "route" in t else None
    return ShipSpec(name, start, heading, speed, waypoints, method, stays, vessel, speeds, metadata=metadata,
                    route=route, **size, **traffic_behaviour.file_behaviour(t, p, i))


def _replayed_ship(t: dict, i: int, base_dir=None) -> ShipSpec:
    """Validated ``ships[i]`` table of a replayed ship: its track and static data (:data:`REPLAY_KEYS`)."""
    p = f"ships[{i}]"
    if i == 0:
        raise ScenarioError(f"{p}.track", "no track for the own ship (the first ship sails with a method; "
                            "replayed ships are targets)", t["track"] if isinstance(t["track"], str) else None)
    for k in t:
        if k not in REPLAY_KEYS:
            raise ScenarioError(f"{p}.{toml_key(k)}", f"a key of a replayed ship (one of: {', '.join(REPLAY_KEYS)}; "
                                "the track gives its start, heading, speed and goal)")
    track = parse_track(t["track"], f"{p}.track", base_dir)
    name = _name(t["name"], f"{p}.name") if "name" in t else f"ship{i}"
    stays = t.get("stays", False)
    if not isinstance(stays, bool):
        raise ScenarioError(f"{p}.stays", "true or false", stays)
    vessel = _string(t["vessel"], f"{p}.vessel", VESSELS) if "vessel" in t else None
    size = _size(t, p)
    metadata = check_metadata(t["metadata"], f"{p}.metadata") if "metadata" in t else {}
    end = (track.x[-1], track.y[-1])
    return ShipSpec(name, tuple(track.position(0.0)), math.degrees(track.heading(0.0)), track.speed(0.0), (end,),
                    None, stays, vessel, None, metadata=metadata, track=track, **size)


SIZE_RANGE_M = {"length_m": 1000.0, "beam_m": 200.0}
"""Largest ``length_m`` and ``beam_m`` of a ship [m] (the largest ships afloat are under 460 m by 70 m)."""


def _size(t: dict, p: str) -> dict:
    """The ship's own ``length_m`` and ``beam_m``, each in (0, :data:`SIZE_RANGE_M`] m."""
    return {k: _ranged(t[k], f"{p}.{k}", 0.0, hi, low_open=True, unit="m") for k, hi in SIZE_RANGE_M.items()
            if k in t}


def _obstacle(t: dict, i: int) -> ObstacleSpec:
    """Validated ``obstacles[i]`` table."""
    p = f"obstacles[{i}]"
    position = _point(_required(t, "position", p, _POINT), f"{p}.position")
    if "radius" not in t:
        return ObstacleSpec(position)
    return ObstacleSpec(position, _ranged(t["radius"], f"{p}.radius", 0.0, MAX_COORDINATE, low_open=True, unit="L"))


def _wall(t: dict, i: int) -> WallSpec:
    """Validated ``walls[i]`` table."""
    key = f"walls[{i}].points"
    points = _points(_required(t, "points", f"walls[{i}]", "a list of at least 2 points"), key, 2)
    for j in range(1, len(points)):
        if points[j] == points[j - 1]:
            raise ScenarioError(f"{key}[{j}]", "a point different from the previous one", list(points[j]))
    return WallSpec(points)


def _land(t: dict, i: int) -> LandSpec:
    """Validated ``land[i]`` table: at least three points, consecutive ones distinct, a non-zero area."""
    key = f"land[{i}].points"
    points = _points(_required(t, "points", f"land[{i}]", "a list of at least 3 points"), key, 3)
    for j in range(len(points)):
        if points[j] == points[j - 1]:
            raise ScenarioError(f"{key}[{j}]", "a point different from the previous one", list(points[j]))
    area = 0.5 * sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(points, points[1:] + points[:1]))
    if abs(area) < 1e-9:
        raise ScenarioError(key, "a polygon with a non-zero area (not all points on one line)",
                            [list(p) for p in points])
    valid_polygon(points, key)
    return LandSpec(points)


def _check_water(ships, land) -> None:
    """No ship starts, and no waypoint lies, on land."""
    for k, poly in enumerate(land):
        for i, ship in enumerate(ships):
            if poly.contains(ship.start):
                raise ScenarioError(f"ships[{i}].start", f"a point outside land[{k}] (ships start in water)",
                                    list(ship.start))
            for j, wp in enumerate(ship.waypoints):
                if poly.contains(wp):
                    raise ScenarioError(f"ships[{i}].waypoints[{j}]", f"a point outside land[{k}] (a route "
                                        "goes through water)", list(wp))


def _check_starts(ships, obstacles, collision_distance: float, vessel: str | None = None) -> None:
    """Ship starts must lie outside every obstacle (radius + half a ship length) and apart from each other: two
    ships at least their collision distance (``collision_distance`` times their mean length,
    :func:`~mmg_casadi.vessel.library.pair_collision_distance`; each ship's length its own ``length_m`` or its
    vessel's, ``vessel`` for a ship that names none)."""
    lengths = [ship_size(s.vessel or vessel, s.length_m, unit=ships[0].vessel or vessel)[0] for s in ships]
    names = {}
    for i, ship in enumerate(ships):
        if ship.name in names:
            raise ScenarioError(f"ships[{i}].name", f"a name not already used by ships[{names[ship.name]}]",
                                ship.name)
        names[ship.name] = i
        for j, ob in enumerate(obstacles):
            limit = ob.radius + SHIP_HALF_LENGTH
            if math.dist(ship.start, ob.position) < limit:
                raise ScenarioError(f"ships[{i}].start", f"a start at least {limit:g} L (radius + 0.5 L) from "
                                    f"the centre of obstacles[{j}], not inside it", list(ship.start))
        for j in range(i):
            limit = pair_collision_distance(collision_distance, lengths[i], lengths[j])
            if math.dist(ship.start, ships[j].start) < limit:
                what = (f"collision_distance = {collision_distance:g} L" if limit == collision_distance else
                        f"{limit:g} L (collision_distance = {collision_distance:g} L times the two ships' mean "
                        "length)")
                raise ScenarioError(f"ships[{i}].start", f"a start at least {what} from ships[{j}].start",
                                    list(ship.start))


def scenario_from_dict(d: dict, source: str = "<dict>", base_dir=None, reference=None) -> Scenario:
    """A validated :class:`Scenario` from a dict shaped like a scenario file.

    ``source`` (a file name) is stored as the ``source`` attribute of any :class:`ScenarioError` raised.

    Parameters
    ----------
    d : dict
        Scenario data shaped like a scenario file.
    source : str, default '<dict>'
        Name of the source (a file name) stored in any :class:`ScenarioError` raised.
    base_dir : str or Path, optional
        Folder that a replayed ship's relative ``track`` file name and a ``[chart]`` table's ``land_file`` are
        relative to (default the working directory).
    reference : (float, float, float), optional
        The scenario's geographic origin (latitude, longitude in deg, metres per L), e.g. from the header of a
        converted scenario: a ``[chart]`` table without ``origin`` uses it.

    Returns
    -------
    Scenario
        The validated scenario.

    Examples
    --------
    >>> d = {"settings": {"method": "none"},
    ...      "ships": [{"start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[50, 0]]}]}
    >>> scenario_from_dict(d).ships[0].name
    'ship0'
    >>> d["ships"][0]["speed"] = 2
    >>> scenario_from_dict(d)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ScenarioError: ships[0].speed: expected a number in [0.2, 1.2] (fraction of design speed), got 2
    """
    try:
        table = _table(d, "", TOP_KEYS)
        settings = _settings(table)
        ships = tuple(_ship(t, i, base_dir) for i, t in
                      enumerate(_tables(table, "ships", SHIP_KEYS, required=True)))
        obstacles = tuple(_obstacle(t, i) for i, t in
                          enumerate(_tables(table, "obstacles", OBSTACLE_KEYS, required=False)))
        walls = tuple(_wall(t, i) for i, t in enumerate(_tables(table, "walls", WALL_KEYS, required=False)))
        land = tuple(_land(t, i) for i, t in enumerate(_tables(table, "land", LAND_KEYS, required=False)))
        if "chart" in table:  # land from a GeoJSON file, after the inline polygons
            land += tuple(_land({"points": [list(p) for p in poly]}, len(land) + k)
                          for k, poly in enumerate(chart_land(table["chart"], base_dir, reference)))
        _check_starts(ships, obstacles, settings.collision_distance, settings.params.get("vessel"))
        _check_water(ships, land)
    except ScenarioError as err:
        err.source = source
        raise
    return Scenario(settings, ships, obstacles, walls, land)


def load_scenario(path) -> Scenario:
    """Read and validate a scenario TOML file.

    Parameters
    ----------
    path : str or Path
        The file (see the module docstring for its keys).

    Returns
    -------
    Scenario
        The validated scenario.

    Raises
    ------
    ScenarioError
        A missing or unreadable file: its field is the path; a TOML syntax error: its field is ``"toml"`` and
        its message carries the parser's message.

    Examples
    --------
    >>> from importlib.resources import files
    >>> s = load_scenario(files("mmg_casadi") / "data" / "scenarios" / "head_on.toml")
    >>> [ship.start for ship in s.ships]
    [(0.0, 0.0), (50.0, 0.0)]
    """
    data = read_toml(path, "scenario", ScenarioError)
    reference = read_header(Path(str(path)).read_text(encoding="utf-8")) if "chart" in data else None
    return scenario_from_dict(data, source=str(path), base_dir=Path(str(path)).parent, reference=reference)


def with_method(s: Scenario, method: str) -> Scenario:
    """``s`` with ``settings.method`` replaced (per-ship overrides are kept).

    Parameters
    ----------
    s : Scenario
        The scenario.
    method : str
        Name of the new scenario-wide method.

    Returns
    -------
    Scenario
        A new scenario; ``s`` is not changed.

    Examples
    --------
    >>> s = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 1, [[50, 0]])])
    >>> with_method(s, "sink-vortex").settings.method
    'sink-vortex'
    """
    method = _string(method, "method", methods.offered(method))
    return dataclasses.replace(s, settings=dataclasses.replace(s.settings, method=method))


def with_params(s: Scenario, params: dict | None) -> Scenario:
    """``s`` with parameter values written into its settings (so the scenario file carries them).

    Parameters
    ----------
    s : Scenario
        The scenario.
    params : dict or None
        Parameter values (table names) to write into the settings; ``None`` or empty returns ``s``.

    Returns
    -------
    Scenario
        A new scenario with the values checked and written into ``settings`` (``s`` itself if ``params`` is empty).

    Examples
    --------
    >>> s = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 1, [[50, 0]])])
    >>> t = with_params(s, {"r_safe": 10.0, "kp": 2.0})
    >>> t.settings.r_safe, t.settings.params
    (10.0, {'kp': 2.0})
    """
    if not params:
        return s
    values = {k: check_value(k, v, field=f"params.{k}") for k, v in params.items()}
    kw = {k: values.pop(k) for k in SETTINGS_FIELDS if k in values}
    settings = dataclasses.replace(s.settings, params={**s.settings.params, **values}, **kw)
    return dataclasses.replace(s, settings=settings)
