"""Our :class:`Scenario` written as a traffic situation in DNV's open maritime-schema JSON (version 0.2.0).

The scenario's origin (0, 0) is put at a stated reference latitude/longitude (:data:`DEFAULT_REFERENCE` if none)
and the plane mapped back to WGS-84 by :class:`~mmg_casadi.scenarios.geodesy.LocalPlane` (exact inverse of the
reading; points farther than :data:`~mmg_casadi.scenarios.geodesy.MAX_RANGE` from the origin are refused, so that
what is written reads back); lengths become metres and speeds knots at the scale of a stated ship length (the
KCS's by default). Each ship's static data comes back: ``id``, ``name``, its own length and beam (``length_m``,
``beam_m`` of its :class:`~mmg_casadi.scenarios.scenario.ShipSpec`) and every key of its ``metadata``. The schema
and the reading direction are described in :mod:`mmg_casadi.scenarios.maritime_schema`.
"""

from __future__ import annotations

import copy
import json
import math

from mmg_casadi.errors import ScenarioError
from mmg_casadi.scenarios.geodesy import LocalPlane
from mmg_casadi.scenarios.maritime_schema import KNOT, check_number
from mmg_casadi.scenarios.scenario import Scenario
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.ship import load_kcs

DEFAULT_REFERENCE = (58.61, 10.59)
"""Default reference latitude/longitude [deg] when writing a scenario that records none (outer Oslofjord)."""
SCHEMA_VERSION = "0.2.0"


def scenario_to_traffic_situation(sc: Scenario, *, reference=DEFAULT_REFERENCE, unit_m: float | None = None,
                                  title: str = "mmg-casadi scenario") -> dict:
    """``sc`` as a maritime-schema (0.2.0) traffic situation, positions about ``reference`` = (lat, lon) [deg].

    The scenario's origin (0, 0) is put at ``reference``; lengths are ``unit_m`` metres per ship length (the
    KCS length by default), speeds fractions of the matching Froude-scaled design speed. Each ship's
    waypoints start with its initial position (as trafficgen writes them), each later one carries the leg's
    ``sog`` (from the ship's ``speeds`` if given); obstacles and walls have no place in the schema and are left
    out. A ship's ``static`` object is the ``metadata`` of its :class:`~mmg_casadi.scenarios.scenario.ShipSpec`
    with ``name``, ``dimensions.length`` (its
    ``length_m``, else ``unit_m``) and ``dimensions.width`` (its ``beam_m``, if any) put in, and an ``id`` (the
    metadata's, else the smallest integer from its index + 1 that no other ship uses).

    Parameters
    ----------
    sc : Scenario
        The scenario (positions in ship lengths, x north, y east; speeds as fractions of the design speed).
    reference : (float, float), optional
        Latitude and longitude [deg, WGS-84] of the scenario's origin, lat in [-90, 90] and lon in
        [-180, 180]; default :data:`DEFAULT_REFERENCE`.
    unit_m : float, optional
        Metres per ship length (> 0), also written as the length of each ship without its own ``length_m``;
        the KCS length (230 m) if None. Speeds are scaled with the design speed Froude-scaled to this length
        (24 kn at 230 m).
    title : str, optional
        The situation's ``title``.

    Returns
    -------
    dict
        The traffic situation (``version``, ``title``, ``description``, ``ownShip`` = the first ship,
        ``targetShips`` = the others), ready for :func:`json.dumps`.

    Raises
    ------
    ScenarioError
        A bad ``reference`` or ``unit_m``, or a start or waypoint farther than
        :data:`~mmg_casadi.scenarios.geodesy.MAX_RANGE` from the origin (``ships[i].start``,
        ``ships[i].waypoints[j]``).

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
    >>> sit["ownShip"]["static"]
    {'id': 1, 'name': 'own', 'dimensions': {'length': 230.0}}
    """
    lat0, lon0 = (check_number(v, f"reference[{i}]", lo, hi, "deg")
                  for i, (v, lo, hi) in enumerate(zip(reference, (-90.0, -180.0), (90.0, 180.0))))
    kcs = load_kcs()
    unit = kcs.L if unit_m is None else check_number(unit_m, "unit_m", 1e-3, None, "m")
    u_des = kcs.U_design * math.sqrt(unit / kcs.L)
    plane = LocalPlane(lat0, lon0)

    def pos(p, field):
        lat, lon = plane.to_geodetic(p[0] * unit, p[1] * unit, field=field)
        return {"lat": lat, "lon": lon}

    used = {s.metadata["id"] for s in sc.ships if isinstance(s.metadata.get("id"), (int, str))}
    ships = []
    for i, s in enumerate(sc.ships):
        start = pos(s.start, f"ships[{i}].start")
        course = plane.course_from_plane(s.heading_deg, start["lat"], start["lon"], field=f"ships[{i}].start")
        # speeds are fractions of the ship's own hull's design speed (Froude-scaled with the unit as the KCS's)
        u_ship = u_des if s.vessel is None else load_vessel(s.vessel).ship.U_design * u_des / kcs.U_design
        sog = s.speed * u_ship / KNOT
        route, legs = (s.waypoints, s.speeds or (s.speed,) * len(s.waypoints)) if s.track is None else \
            _track_route(s.track)
        wps = [{"position": start}] + [{"position": pos(p, f"ships[{i}].waypoints[{j}]"),
                                        "leg": {"sog": v * u_ship / KNOT}}
                                       for j, (p, v) in enumerate(zip(route, legs))]
        ships.append({
            "static": _static(s, unit, i, used),
            "initial": {"position": start, "sog": sog, "cog": course, "heading": course,
                        "navStatus": "Under way using engine"},
            "waypoints": wps,
        })
    return {"version": SCHEMA_VERSION, "title": title,
            "description": f"written by mmg-casadi; {len(sc.ships)} ships, collision-avoidance method "
                           f"{sc.settings.method}",
            "ownShip": ships[0], "targetShips": ships[1:]}


def _track_route(track) -> tuple[list, list]:
    """A replayed ship's route for export: its track's samples after the start (L) and the speed of the track on
    the way to each (U); the timing between them is the recorded one only as far as a constant speed per leg is."""
    later = [k for k, t in enumerate(track.t) if t > 0]
    points = [(track.x[k], track.y[k]) for k in later]
    speeds = [track.speed(0.5 * (max(track.t[k - 1], 0.0) + track.t[k])) for k in later]
    return points, speeds


def _static(s, unit: float, index: int, used: set) -> dict:
    """The ``static`` object of ship ``s`` (``index`` in the scenario; ``used``: ids taken, updated)."""
    meta = copy.deepcopy(s.metadata)
    ident = meta.pop("id", None)
    if ident is None:
        ident = index + 1
        while ident in used:
            ident += 1
        used.add(ident)
    dims = {"length": unit if s.length_m is None else s.length_m}
    if s.beam_m is not None:
        dims["width"] = s.beam_m
    extra = meta.pop("dimensions", {})
    if not isinstance(extra, dict):
        raise ScenarioError(f"ships[{index}].metadata.dimensions", "a table of dimensions in m (height, draught, ...)",
                            extra)
    for k, v in extra.items():
        dims.setdefault(k, v)  # length_m and beam_m take precedence
    name = meta.pop("name", s.name)
    return {"id": ident, "name": name, "dimensions": dims, **meta}


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
