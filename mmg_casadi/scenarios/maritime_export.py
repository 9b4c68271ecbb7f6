"""Our :class:`Scenario` written as a traffic situation in DNV's open maritime-schema JSON (version 0.2.0).

The scenario's origin (0, 0) is put at a stated reference latitude/longitude (:data:`DEFAULT_REFERENCE` if none)
and the plane mapped back to WGS-84 by :class:`~mmg_casadi.scenarios.geodesy.LocalPlane`; lengths become metres
and speeds knots at the scale of a stated ship length (the KCS's by default). The schema and the reading
direction are described in :mod:`mmg_casadi.scenarios.maritime_schema`.
"""

from __future__ import annotations

import json
import math

from mmg_casadi.scenarios.geodesy import LocalPlane
from mmg_casadi.scenarios.maritime_schema import KNOT, check_number
from mmg_casadi.scenarios.scenario import Scenario
from mmg_casadi.vessel.ship import load_kcs

DEFAULT_REFERENCE = (58.61, 10.59)
"""Default reference latitude/longitude [deg] when writing a scenario that records none (outer Oslofjord)."""
SCHEMA_VERSION = "0.2.0"


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
    lat0, lon0 = (check_number(v, f"reference[{i}]", lo, hi, "deg")
                  for i, (v, lo, hi) in enumerate(zip(reference, (-90.0, -180.0), (90.0, 180.0))))
    kcs = load_kcs()
    unit = kcs.L if unit_m is None else check_number(unit_m, "unit_m", 1e-3, None, "m")
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
