"""maritime-schema traffic situations in and out: geometry, units, static data, errors, CLI convert, round trip."""

from __future__ import annotations

import copy
import json
import math
import tomllib
from importlib.resources import files

import pytest

from mmg_casadi.cli import main
from mmg_casadi.errors import InputError, ScenarioError
from mmg_casadi.scenarios.geodesy import MAX_RANGE, LocalPlane
from mmg_casadi.scenarios.interchange import read_header
from mmg_casadi.scenarios.maritime_export import scenario_to_traffic_situation
from mmg_casadi.scenarios.maritime_schema import KNOT, load_traffic_situation, traffic_situation_to_scenario
from mmg_casadi.scenarios.scenario import Scenario, Settings, ShipSpec, load_scenario

EXAMPLE = files("mmg_casadi") / "data" / "traffic_situation.json"
L = 230.0
A, F = 6378137.0, 1 / 298.257223563
E2 = F * (2 - F)


def _radii(lat):
    """Meridian and prime-vertical radii of curvature of WGS-84 (textbook formulas, independent of the code)."""
    s2 = math.sin(math.radians(lat)) ** 2
    return A * (1 - E2) / (1 - E2 * s2) ** 1.5, A / math.sqrt(1 - E2 * s2)


def _offset(lat, lon, north_m, east_m):
    """The point about (north_m, east_m) metres from (lat, lon) (local radii; ~0.1 % at 50 km)."""
    M, N = _radii(lat)
    return lat + math.degrees(north_m / M), lon + math.degrees(east_m / (N * math.cos(math.radians(lat))))


def _vincenty(lat1, lon1, lat2, lon2):
    """(distance [m], azimuth at the first point [deg]) on WGS-84 by Vincenty's inverse formula.

    T. Vincenty, "Direct and inverse solutions of geodesics on the ellipsoid with application of nested
    equations", Survey Review 23(176), 88-93, 1975: an algorithm independent of the code under test (Karney's),
    accurate to 0.1 mm at these distances.
    """
    b = A * (1 - F)
    lam0 = math.radians(lon2 - lon1)
    u1, u2 = (math.atan((1 - F) * math.tan(math.radians(p))) for p in (lat1, lat2))
    su1, cu1, su2, cu2 = math.sin(u1), math.cos(u1), math.sin(u2), math.cos(u2)
    lam = lam0
    for _ in range(200):
        sl, cl = math.sin(lam), math.cos(lam)
        sin_s = math.hypot(cu2 * sl, cu1 * su2 - su1 * cu2 * cl)
        if sin_s == 0.0:
            return 0.0, 0.0
        cos_s = su1 * su2 + cu1 * cu2 * cl
        sigma = math.atan2(sin_s, cos_s)
        sin_a = cu1 * cu2 * sl / sin_s
        cos2_a = 1 - sin_a ** 2
        c2m = cos_s - 2 * su1 * su2 / cos2_a if cos2_a else 0.0
        c = F / 16 * cos2_a * (4 + F * (4 - 3 * cos2_a))
        prev = lam
        lam = lam0 + (1 - c) * F * sin_a * (sigma + c * sin_s * (c2m + c * cos_s * (-1 + 2 * c2m ** 2)))
        if abs(lam - prev) < 1e-14:
            break
    u_2 = cos2_a * (A ** 2 - b ** 2) / b ** 2
    big_a = 1 + u_2 / 16384 * (4096 + u_2 * (-768 + u_2 * (320 - 175 * u_2)))
    big_b = u_2 / 1024 * (256 + u_2 * (-128 + u_2 * (74 - 47 * u_2)))
    d_sigma = big_b * sin_s * (c2m + big_b / 4 * (cos_s * (-1 + 2 * c2m ** 2)
                                                 - big_b / 6 * c2m * (-3 + 4 * sin_s ** 2) * (-3 + 4 * c2m ** 2)))
    azimuth = math.degrees(math.atan2(cu2 * math.sin(lam), cu1 * su2 - su1 * cu2 * math.cos(lam)))
    return b * big_a * (sigma - d_sigma), azimuth % 360.0


def _angle_diff(a, b):
    return (a - b + 180.0) % 360.0 - 180.0


def _ship(lat, lon, sog=12.0, cog=0.0, heading=None, name=None, waypoints=()):
    d = {"static": {"id": 1}, "initial": {"position": {"lat": lat, "lon": lon}, "sog": sog, "cog": cog},
         "waypoints": [{"position": {"lat": lat, "lon": lon}}] + [{"position": {"lat": a, "lon": b}}
                                                                  for a, b in waypoints]}
    if heading is not None:
        d["initial"]["heading"] = heading
    if name:
        d["static"]["name"] = name
    return d


def _situation(*targets, own=None):
    return {"version": "0.2.0", "ownShip": own or _ship(58.6, 10.6, name="OS"), "targetShips": list(targets)}


# ------------------------------------------------------------------------------------------- geometry

LATITUDES = [0.0, 35.0, 58.61, -58.0, 70.0, 80.0]


@pytest.mark.parametrize("lat0", LATITUDES)
def test_small_offsets_match_the_radii_of_curvature(lat0):
    plane = LocalPlane(lat0, 10.0)
    M, N = _radii(lat0)
    dphi = 1e-3  # deg, ~110 m: the plane and the radii agree to well below a millimetre
    x, _ = plane.to_plane(lat0 + dphi, 10.0)
    _, y = plane.to_plane(lat0, 10.0 + dphi)
    assert x == pytest.approx(M * math.radians(dphi), abs=1e-3)
    assert y == pytest.approx(N * math.cos(math.radians(lat0)) * math.radians(dphi), abs=1e-3)


@pytest.mark.parametrize("lat0", LATITUDES)
def test_distance_and_bearing_from_the_reference_are_the_geodesic_ones(lat0):
    # the plane is the azimuthal equidistant projection: a point's distance and bearing from the origin are its
    # geodesic distance and azimuth from the reference (checked with Vincenty's independent algorithm)
    plane = LocalPlane(lat0, -20.0)
    for bearing in range(0, 360, 30):
        for d in (1e3, 25e3, MAX_RANGE):
            x, y = d * math.cos(math.radians(bearing)), d * math.sin(math.radians(bearing))
            lat, lon = plane.to_geodetic(x, y)
            s, az = _vincenty(lat0, -20.0, lat, lon)
            assert abs(s - d) < 1e-3, (bearing, d)
            assert abs(_angle_diff(az, bearing)) < 1e-7, (bearing, d)
            bx, by = plane.to_plane(lat, lon)
            assert math.hypot(bx - x, by - y) < 1e-6


@pytest.mark.parametrize("lat0", [0.0, 58.61, -58.0, 80.0])
def test_distances_between_points_within_range_kept_to_a_metre(lat0):
    # any two accepted points: their distance in the plane is within 1 m of the geodesic distance (the reason
    # for MAX_RANGE); at twice the range the projection would be off by several metres
    def worst(radius):
        plane = LocalPlane(lat0, 5.0, max_range=2 * MAX_RANGE)
        pts = [(r * math.cos(math.radians(b)), r * math.sin(math.radians(b)))
               for b in range(0, 360, 15) for r in (radius / 2, radius)]
        geo = [plane.to_geodetic(*p) for p in pts]
        return max(abs(math.dist(pts[i], pts[j]) - _vincenty(*geo[i], *geo[j])[0])
                   for i in range(len(pts)) for j in range(i))
    assert worst(MAX_RANGE) < 1.0
    assert worst(2 * MAX_RANGE) > 3.0


def test_course_in_the_plane_is_the_direction_of_a_short_step():
    # a course at a point maps to the plane direction of a 10 m step along it (step from the local radii:
    # independent of the Jacobian in the code); includes the convergence of the meridians away from the origin
    for lat0 in (58.61, -58.0, 80.0):
        plane = LocalPlane(lat0, 10.59)
        assert plane.course_to_plane(37.0, lat0, 10.59) == pytest.approx(37.0, abs=1e-9)
        for north, east in ((0.0, 50e3), (-40e3, -30e3), (55e3, 5e3)):
            lat, lon = _offset(lat0, 10.59, north, east)
            p = plane.to_plane(lat, lon)
            for c in (0.0, 45.0, 190.0, 359.0):
                q = plane.to_plane(*_offset(lat, lon, 10 * math.cos(math.radians(c)), 10 * math.sin(math.radians(c))))
                step = math.degrees(math.atan2(q[1] - p[1], q[0] - p[0]))
                angle = plane.course_to_plane(c, lat, lon)
                assert abs(_angle_diff(angle, step)) < 1e-3, (lat0, north, east, c)
                assert abs(_angle_diff(plane.course_from_plane(angle, lat, lon), c)) < 1e-9
    # 50 km east at 58.6 N: north there points west of the plane's x axis by about dlon sin(lat)
    plane = LocalPlane(58.61, 10.59)
    lat, lon = _offset(58.61, 10.59, 0.0, 50e3)
    gamma = (lon - 10.59) * math.sin(math.radians(58.61))
    assert plane.course_to_plane(0.0, lat, lon) == pytest.approx(360.0 - gamma, abs=0.01)


def test_positions_beyond_the_range_are_refused():
    plane = LocalPlane(58.6, 10.6)
    inside = _offset(58.6, 10.6, 0.99 * MAX_RANGE, 0.0)
    assert math.hypot(*plane.to_plane(*inside)) == pytest.approx(0.99 * MAX_RANGE, rel=2e-3)
    for lat, lon in (_offset(58.6, 10.6, 0.0, 1.01 * MAX_RANGE), (-58.0, 20.0), (58.6, -169.4)):
        with pytest.raises(ScenarioError) as err:
            plane.to_plane(lat, lon, field="targetShips[3].initial.position")
        assert err.value.field == "targetShips[3].initial.position"
        assert "within 60 km (geodesic distance) of the reference 58.6, 10.6" in str(err.value)
        with pytest.raises(ScenarioError):
            plane.course_to_plane(0.0, lat, lon)
    with pytest.raises(ScenarioError) as err:
        plane.to_geodetic(0.0, -60001.0, field="ships[2].start")
    assert err.value.field == "ships[2].start" and "60.0 km away" in str(err.value)


# ----------------------------------------------------------------------------------------------- reading

def test_units_and_methods():
    target = _ship(58.65, 10.6, sog=18.0, cog=180.0, heading=181.0, name="T")
    sc, plane, unit = traffic_situation_to_scenario(_situation(target), target_method="inverse-square")
    assert unit == L and (plane.lat, plane.lon) == (58.6, 10.6)
    own, t = sc.ships
    assert own.start == (0.0, 0.0) and own.heading_deg == pytest.approx(0.0)
    assert own.speed == pytest.approx(12 * KNOT / 12.347, rel=1e-12)
    assert t.speed == pytest.approx(18 * KNOT / 12.347, rel=1e-12)
    assert t.heading_deg == pytest.approx(181.0, abs=1e-5)  # heading (not cog) is the initial heading
    assert t.start[0] == pytest.approx(_radii(58.625)[0] * math.radians(0.05) / L, rel=1e-4)
    assert sc.method_of(0) == "modified-vortex" and sc.method_of(1) == "inverse-square"


def test_own_ship_length_scale_froude_scales_speeds():
    own = _ship(58.6, 10.6, sog=12.0)
    own["static"]["dimensions"] = {"length": 115.0}
    sc, _plane, unit = traffic_situation_to_scenario(_situation(_ship(58.62, 10.6, cog=180.0), own=own),
                                                     length_scale="own-ship")
    assert unit == 115.0
    assert sc.ships[0].speed == pytest.approx(12 * KNOT / (12.347 * math.sqrt(0.5)), rel=1e-12)
    assert sc.ships[1].start[0] * 115.0 == pytest.approx(_radii(58.61)[0] * math.radians(0.02), rel=1e-4)


def test_paths_extended_past_the_encounter():
    # head-on at 10 km, both 12 kn, no waypoint beyond the start: CPA after 5 km each; paths reach
    # 5 km + 30 L along the course
    target = _ship(58.6 + math.degrees(10e3 / _radii(58.6)[0]), 10.6, cog=180.0)
    sc, _p, _u = traffic_situation_to_scenario(_situation(target))
    own, t = sc.ships
    assert len(own.waypoints) == 1 and len(t.waypoints) == 1
    assert own.goal[0] == pytest.approx(5e3 / L + 30.0, rel=1e-3) and abs(own.goal[1]) < 1e-6
    assert t.goal[0] == pytest.approx(10e3 / L - (5e3 / L + 30.0), rel=1e-3)
    # a file route that already reaches past the encounter is kept as is
    far = 58.6 + math.degrees(40e3 / _radii(58.6)[0])
    sc2, _p, _u = traffic_situation_to_scenario(_situation(target, own=_ship(58.6, 10.6, waypoints=[(far, 10.6)])))
    assert len(sc2.ships[0].waypoints) == 1 and sc2.ships[0].goal[0] == pytest.approx(40e3 / L, rel=1e-4)


def test_old_field_names_and_missing_initial():
    own = {"static": {"id": 1, "length": 200.0, "name": "OLD"},
           "initial": {"position": {"latitude": 58.6, "longitude": 10.6}, "sog": 10.0, "cog": 90.0}}
    tgt = {"static": {"id": 7}, "waypoints": [
        {"position": {"lat": 58.6, "lon": 10.8}},
        {"position": {"lat": 58.6, "lon": 10.7}, "leg": {"data": {"sog": {"value": 11.0}}}}]}
    sc, _p, _u = traffic_situation_to_scenario({"version": "0.1", "ownShip": own, "targetShips": [tgt]})
    assert [s.name for s in sc.ships] == ["OLD", "ship7"]
    assert sc.ships[1].speed == pytest.approx(11 * KNOT / 12.347)
    assert (sc.ships[1].heading_deg - 270.0 + 180) % 360 - 180 == pytest.approx(0.0, abs=0.2)


@pytest.mark.parametrize("mutate, field", [
    (lambda d: d["ownShip"]["initial"].update(sog=30.0), "ownShip.initial.sog"),
    (lambda d: d["targetShips"][0]["initial"].update(sog=2.0), "targetShips[0].initial.sog"),
    (lambda d: d["targetShips"][0]["initial"]["position"].update(lat=95.0), "targetShips[0].initial.position.lat"),
    (lambda d: d["ownShip"]["initial"].update(cog="north"), "ownShip.initial.cog"),
    (lambda d: d["ownShip"]["initial"].update(cog=float("nan")), "ownShip.initial.cog"),
    (lambda d: d.pop("ownShip"), "ownShip"),
    (lambda d: d.update(targetShips={"a": 1}), "targetShips"),
    (lambda d: d["targetShips"][0]["initial"].update(position={"lat": 58.6, "lon": 10.6}), "ships[1].start"),
    # the case: a target at 58 S (it came back at 4.58 S on course 119 instead of 20)
    (lambda d: d["targetShips"][0]["initial"].update(position={"lat": -58.0, "lon": 10.6}),
     "targetShips[0].initial.position"),
    (lambda d: d["ownShip"]["waypoints"].append({"position": {"lat": 59.2, "lon": 10.6}}),
     "ownShip.waypoints[1].position"),
    (lambda d: d["targetShips"][0].update(initial=None, waypoints=[
        {"position": {"lat": 58.6, "lon": 12.0}}, {"position": {"lat": 58.6, "lon": 11.9}, "leg": {"sog": 12.0}}]),
     "targetShips[0].waypoints[0].position"),  # no initial state: the first waypoint is the start
    (lambda d: d["targetShips"][0]["static"].update(dimensions={"length": 0.0}),
     "targetShips[0].static.dimensions.length"),
    (lambda d: d["targetShips"][0]["static"].update(width="wide"), "targetShips[0].static.width"),
    (lambda d: d["targetShips"][0]["static"].update(dimensions=[122.0]), "targetShips[0].static.dimensions"),
    (lambda d: d["targetShips"][0]["static"].update(mmsi=float("nan")), "targetShips[0].static.mmsi"),
])
def test_bad_situations_name_the_field(mutate, field):
    d = _situation(_ship(58.65, 10.6, cog=180.0))
    mutate(d)
    with pytest.raises(InputError) as err:
        traffic_situation_to_scenario(d)
    assert err.value.field == field
    if "sog" in field:
        assert "[4.80, 28.80] kn" in str(err.value)
    if field.endswith("position"):
        assert "expected a position within 60 km (geodesic distance) of the reference 58.6, 10.6" in str(err.value)


def _trafficgen_ship(name, lat, lon, cog, length, width, height, speed_max, mmsi=None, sog=12.0, legs=()):
    """A ship as trafficgen writes it (schema of its first releases: flat length/width/height, speedMax)."""
    static = {"id": f"00000000-0000-4000-8000-{int(length * 1000):012d}", "length": length, "width": width,
              "height": height, "speedMax": speed_max, "name": name, "shipType": "Passenger"}
    if mmsi is not None:
        static["mmsi"] = mmsi
    return {"static": static,
            "initial": {"position": {"lat": lat, "lon": lon}, "sog": sog, "cog": cog, "heading": cog,
                        "navStatus": "Under way using engine"},
            "waypoints": [{"position": {"lat": lat, "lon": lon}}] + [{"position": {"lat": a, "lon": b}}
                                                                     for a, b in legs]}


def test_static_data_of_every_ship_is_kept():
    own = _trafficgen_ship("FERRY", 58.76, 10.49, 0.0, 122.0, 20.0, 8.0, 17.0, mmsi=257000123,
                           legs=[(58.79, 10.49)])
    t1 = _trafficgen_ship("target_ship_1", 58.84, 10.50, 183.0, 178.0, 30.0, 30.0, 21.0)
    t2 = _trafficgen_ship("target_ship_2", 58.82, 10.51, 198.0, 50.0, 10.0, 8.0, 15.0)
    t2["static"]["imo"] = 1234567
    t2["static"]["callsign"] = None  # null: left out
    sc, _plane, unit = traffic_situation_to_scenario({"ownShip": own, "targetShips": [t1, t2]})
    assert unit == L  # the length unit is still the KCS's; each ship's own size is data
    assert [(s.length_m, s.beam_m) for s in sc.ships] == [(122.0, 20.0), (178.0, 30.0), (50.0, 10.0)]
    assert [s.name for s in sc.ships] == ["FERRY", "target_ship_1", "target_ship_2"]
    assert sc.ships[0].metadata == {"id": own["static"]["id"], "sogMax": 17.0, "mmsi": 257000123,
                                    "shipType": "Passenger", "dimensions": {"height": 8.0}}
    assert sc.ships[2].metadata["imo"] == 1234567 and "callsign" not in sc.ships[2].metadata
    # repeated and blank names: the scenario's name is unique, the name as read is kept in the metadata
    t1["static"]["name"] = "FERRY"
    t2["static"]["name"] = " "
    sc, _plane, _unit = traffic_situation_to_scenario({"ownShip": own, "targetShips": [t1, t2]})
    assert [s.name for s in sc.ships] == ["FERRY", "FERRY (1)", f"ship{t2['static']['id']}"]
    assert [s.metadata.get("name") for s in sc.ships] == [None, "FERRY", " "]


# ---------------------------------------------------------------------------------------- round trip / CLI

def _round_trip(src: dict, tmp_path, *args) -> dict:
    """``src`` through ``mmg-casadi convert`` to a scenario file and back."""
    original = tmp_path / "in.json"
    original.write_text(json.dumps(src))
    assert main(["convert", str(original), "--out", str(tmp_path / "mid.toml"), *args]) == 0
    assert main(["convert", str(tmp_path / "mid.toml"), "--out", str(tmp_path / "out.json")]) == 0
    return json.loads((tmp_path / "out.json").read_text())


def _ships(sit):
    return [sit["ownShip"]] + sit["targetShips"]


@pytest.mark.parametrize("lat0, lon0", [(58.61, 10.59), (-58.0, 20.0), (0.0, -30.0), (35.0, 140.0),
                                        (70.0, 179.9), (80.0, -10.0)])
def test_round_trip_keeps_positions_courses_and_static_data(tmp_path, lat0, lon0):
    # maritime-schema 0.2.0 -> scenario file -> maritime-schema: static objects come back as they were,
    # positions to < 1 mm (geodesic distance, Vincenty), courses to < 1e-6 deg, speeds to 1e-12
    def ship(name, north, east, course, length, extra, legs=()):
        lat, lon = _offset(lat0, lon0, north, east)
        wps = [_offset(lat, lon, n, e) for n, e in legs]
        d = _ship(lat, lon, sog=12.0, cog=course, heading=course, name=name, waypoints=wps)
        d["static"] = {"id": extra.pop("id"), "name": name, "dimensions": {"length": length, **extra.pop("dims")},
                       **extra}
        return d
    own = ship("OWN", 0.0, 0.0, 20.0, 122.0, {"id": 7, "dims": {"width": 20.0, "height": 8.0}, "mmsi": 257000123,
                                             "shipType": "Passenger", "sogMax": 17.0}, legs=[(3e3, 1e3)])
    head_on = ship("HEAD-ON", 9e3, 3e3, 200.0, 178.0, {"id": 8, "dims": {"width": 30.0}, "imo": 9074729,
                                                       "shipType": "Cargo hazardous category A"}, legs=[(-8e3, -3e3)])
    far = ship("FAR", 40e3, -36e3, 135.0, 50.0, {"id": "a-uuid", "dims": {"draught": 3.5, "a": 40.0, "b": 10.0},
                                                 "pathType": "rtz", "initDelay": 15.0}, legs=[(-6e3, 6e3)])
    src = _situation(head_on, far, own=own)
    assert 50e3 < _vincenty(lat0, lon0, *_offset(lat0, lon0, 40e3, -36e3))[0] < MAX_RANGE  # a far target
    out = _round_trip(src, tmp_path)
    assert len(out["targetShips"]) == len(src["targetShips"])
    for a, b in zip(_ships(src), _ships(out)):
        assert b["static"] == a["static"]
        assert _vincenty(a["initial"]["position"]["lat"], a["initial"]["position"]["lon"],
                         b["initial"]["position"]["lat"], b["initial"]["position"]["lon"])[0] < 1e-3
        for key in ("heading", "cog"):
            assert abs(_angle_diff(b["initial"][key], a["initial"][key])) < 1e-6
        assert b["initial"]["sog"] == pytest.approx(a["initial"]["sog"], rel=1e-12)
        # the file's waypoints come back in order (the first repeats the start); extensions may follow
        for wa, wb in zip(a["waypoints"], b["waypoints"]):
            pa, pb = wa["position"], wb["position"]
            assert _vincenty(pa["lat"], pa["lon"], pb["lat"], pb["lon"])[0] < 1e-3


def test_round_trip_of_a_trafficgen_file_writes_schema_0_2_names(tmp_path):
    # the finding: target lengths 178 and 50 m came back as 230 m; ids, MMSI, types, sizes were dropped
    own = _trafficgen_ship("FERRY", 58.76, 10.49, 0.0, 122.0, 20.0, 8.0, 17.0, mmsi=257000123, sog=10.0,
                           legs=[(58.79, 10.49)])
    t1 = _trafficgen_ship("target_ship_1", 58.84, 10.50, 183.0, 178.0, 30.0, 30.0, 21.0, sog=12.0,
                          legs=[(58.81, 10.49)])
    t2 = _trafficgen_ship("target_ship_2", 58.82, 10.51, 198.3, 50.0, 10.0, 8.0, 15.0, sog=6.0,
                          legs=[(58.807, 10.5007)])
    src = {"title": "HO", "ownShip": own, "targetShips": [t1, t2]}
    out = _round_trip(src, tmp_path)
    for a, b in zip(_ships(src), _ships(out)):
        old = a["static"]
        expected = {"id": old["id"], "name": old["name"], "shipType": "Passenger", "sogMax": old["speedMax"],
                    "dimensions": {"length": old["length"], "width": old["width"], "height": old["height"]}}
        if "mmsi" in old:
            expected["mmsi"] = old["mmsi"]
        assert b["static"] == expected
    assert [b["static"]["dimensions"]["length"] for b in _ships(out)] == [122.0, 178.0, 50.0]
    # the own ship's length as the unit: the same static data, speeds Froude-scaled to 122 m, positions kept
    again = _round_trip(src, tmp_path, "--length-scale", "own-ship")
    assert [b["static"] for b in _ships(again)] == [b["static"] for b in _ships(out)]
    p, q = again["targetShips"][1]["initial"]["position"], t2["initial"]["position"]
    assert _vincenty(p["lat"], p["lon"], q["lat"], q["lon"])[0] < 1e-3


def test_scenario_ids_are_unique_on_export():
    ships = [ShipSpec("a", [0, 0], 0, 0.5, [[50, 0]]), ShipSpec("b", [20, 10], 270, 0.5, [[20, -40]]),
             ShipSpec("c", [-20, 10], 90, 0.5, [[-20, 40]], metadata={"id": 2})]
    sit = scenario_to_traffic_situation(Scenario(Settings("none"), ships))
    assert [s["static"]["id"] for s in _ships(sit)] == [1, 3, 2]
    assert [s["static"]["dimensions"] for s in _ships(sit)] == [{"length": L}] * 3
    # per-leg speeds are written as each leg's sog (12.347 m/s design speed = 24.0 kn)
    ships[0] = ShipSpec("a", [0, 0], 0, 0.5, [[25, 0], [50, 0]], speeds=(0.5, 0.75))
    sit = scenario_to_traffic_situation(Scenario(Settings("none"), ships))
    legs = [w["leg"]["sog"] * KNOT / 12.347 for w in sit["ownShip"]["waypoints"][1:]]
    assert legs == pytest.approx([0.5, 0.75], rel=1e-12)
    assert [w["leg"]["sog"] for w in sit["targetShips"][0]["waypoints"][1:]] == pytest.approx([0.5 * 12.347 / KNOT])


def test_route_speeds_round_trip_and_are_checked():
    # the speed on each leg (leg.sog) is read into the ship's speeds; a route without one keeps the initial speed
    ships = [ShipSpec("a", [0, 0], 0, 0.5, [[25, 0], [50, 0]], speeds=(0.5, 0.75)),
             ShipSpec("b", [20, 10], 270, 0.5, [[20, -40]])]
    sit = scenario_to_traffic_situation(Scenario(Settings("none"), ships))
    back = traffic_situation_to_scenario(sit)[0].ships
    assert back[0].speeds == pytest.approx((0.5, 0.75), rel=1e-12) and len(back[0].waypoints) == 2
    assert back[1].speeds is None
    sit["ownShip"]["waypoints"][2]["leg"]["sog"] = 40.0  # 1.67 x the design speed
    with pytest.raises(InputError) as err:
        traffic_situation_to_scenario(sit)
    assert err.value.field == "ownShip.waypoints[2].leg.sog"


def test_far_position_refused_by_convert_nothing_written(tmp_path, capsys):
    src = _situation(_ship(58.65, 10.6, cog=180.0), _ship(-58.0, 10.6, cog=20.0))
    bad = tmp_path / "far.json"
    bad.write_text(json.dumps(src))
    out = tmp_path / "o" / "far.toml"
    assert main(["convert", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "targetShips[1].initial.position: expected a position within 60 km" in err[0]
    assert not out.exists() and not out.parent.exists()
    # the other way: a scenario reaching beyond the range is refused too (its file would not read back)
    toml = tmp_path / "wide.toml"
    assert main(["convert", str(EXAMPLE), "--out", str(toml)]) == 0
    text = toml.read_text().replace("waypoints = [", "waypoints = [[300.0, 0.0], ", 1)
    toml.write_text(text)
    assert load_scenario(toml).ships[0].waypoints[0] == (300.0, 0.0)  # 69 km at 230 m per L
    assert main(["convert", str(toml), "--out", str(tmp_path / "wide.json")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "ships[0].waypoints[0]: expected a position within 60 km" in err[0]
    assert not (tmp_path / "wide.json").exists()


def test_toml_to_json_about_a_stated_reference(tmp_path):
    sc = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 0.5, [[50, 0]]),
                                     ShipSpec("b", [20, 10], 270, 1.0, [[20, -40]])])
    sit = scenario_to_traffic_situation(sc, reference=(-33.9, 18.4))
    p = sit["targetShips"][0]["initial"]["position"]
    M, N = _radii(-33.9)
    assert (p["lat"] + 33.9) * math.pi / 180 * M == pytest.approx(20 * L, rel=1e-3)
    assert (p["lon"] - 18.4) * math.pi / 180 * N * math.cos(math.radians(33.9)) == pytest.approx(10 * L, rel=1e-3)
    assert sit["targetShips"][0]["initial"]["sog"] == pytest.approx(12.347 / KNOT)
    back, _plane, _unit = traffic_situation_to_scenario(sit, target_method="none", method="none")
    for s, t in zip(sc.ships, back.ships):
        assert math.dist(s.start, t.start) * L < 1.0
        assert math.dist(s.goal, t.goal) * L < 1.0


def test_cli_convert_bad_input_writes_nothing(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(_situation(_ship(58.65, 10.6, sog=40.0))))
    out = tmp_path / "o" / "bad.toml"
    assert main(["convert", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "targetShips[0].initial.sog" in err[0]
    assert not out.exists() and not out.parent.exists()
    (tmp_path / "broken.json").write_text("{not json")
    assert main(["convert", str(tmp_path / "broken.json"), "--out", str(out)]) == 2
    assert main(["convert", str(EXAMPLE), "--out", str(tmp_path / "x.json")]) == 2
    assert main(["convert", str(EXAMPLE), "--out", str(out), "--method", "bogus"]) == 2
    assert not out.exists()
    toml = tmp_path / "s.toml"
    assert main(["convert", str(EXAMPLE), "--out", str(toml)]) == 0
    assert main(["convert", str(toml), "--out", str(tmp_path / "s.json"), "--reference", "95,0"]) == 2
    assert not (tmp_path / "s.json").exists()


def test_example_converts_to_a_valid_scenario_with_its_reference(tmp_path):
    sc, plane, unit = load_traffic_situation(EXAMPLE)
    toml = tmp_path / "ex.toml"
    assert main(["convert", str(EXAMPLE), "--out", str(toml)]) == 0
    text = toml.read_text()
    assert read_header(text) == (plane.lat, plane.lon, unit)
    assert load_scenario(toml) == sc
    assert tomllib.loads(text)["ships"][1]["method"] == "none"


def test_simulate_accepts_a_traffic_situation(tmp_path):
    out = tmp_path / "sim"
    assert main(["simulate", str(EXAMPLE), "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert [s["name"] for s in metrics["ships"]] == ["OWN", "HEAD-ON", "CROSSING"]
    assert metrics["ships"][0]["reached_goal"] and not metrics["collision"]


def test_a_tanker_sails_the_closest_hull_and_convert_says_which(tmp_path, capsys):
    """A 300 m tanker gets the KVLCC2: her speed is a fraction of its 15.5 kn; her 12 kn come back unchanged; a
    122 m general cargo ship stays a KCS (closest length) and a ship of no known length the default hull."""
    tanker = _ship(58.7, 10.6, sog=12.0, cog=180.0, name="TANKER")
    tanker["static"].update(shipType="Tanker", dimensions={"length": 300.0, "width": 50.0})
    cargo = _ship(58.6, 10.7, sog=12.0, cog=270.0, name="CARGO")
    cargo["static"].update(id=2, shipType="Cargo", dimensions={"length": 122.0})
    bare = _ship(58.5, 10.6, sog=12.0, cog=0.0, name="BARE")
    bare["static"]["id"] = 3
    src = _situation(tanker, cargo, bare)
    sc = traffic_situation_to_scenario(src)[0]
    assert [s.vessel for s in sc.ships] == [None, "kvlcc2", None, None]
    assert sc.ships[1].speed == pytest.approx(12.0 * KNOT / 7.9739, rel=1e-12)  # its data file's U_design (m/s)
    assert sc.ships[2].speed == pytest.approx(12.0 * KNOT / 12.347, rel=1e-12)  # the KCS's
    out = _round_trip(src, tmp_path)
    printed = capsys.readouterr().out
    assert "TANKER: 300 m, Tanker -> kvlcc2 (tanker hull, closest length (320 m))" in printed
    assert "CARGO: 122 m, Cargo -> kcs (container hull, closest length (230 m))" in printed
    for a, b in zip(_ships(src), _ships(out)):
        assert b["initial"]["sog"] == pytest.approx(a["initial"]["sog"], rel=1e-12)
    # the own-ship length scale keeps every ship a (Froude-scaled) KCS, and says so
    src["ownShip"]["static"]["dimensions"] = {"length": 200.0}
    sc = traffic_situation_to_scenario(src, length_scale="own-ship")[0]
    assert all(s.vessel is None for s in sc.ships)


# ------------------------------------------------------------------ each ship's own collision geometry

def _abreast(gap: float, own: dict, target: dict, **settings) -> dict:
    """Two ships sailing the same way side by side, ``gap`` L apart (centres), as a scenario dict."""
    ships = [{"name": "own", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[40.0, 0.0]], **own},
             {"name": "target", "start": [0.0, gap], "heading": 0.0, "speed": 1.0, "waypoints": [[40.0, gap]],
              **target}]
    return {"settings": {"method": "none", "t_max": 3.0, **settings}, "ships": ships}


def test_two_ships_of_the_unit_length_collide_at_exactly_the_collision_distance():
    from mmg_casadi.vessel.library import load_vessel, pair_collision_distance, ship_size
    kcs = load_vessel().ship
    assert ship_size() == (1.0, 0.5 * kcs.B / kcs.L) and ship_size(length_m=kcs.L, beam_m=kcs.B) == ship_size()
    assert pair_collision_distance(2.0, 1.0, 1.0) == 2.0  # the paper's 2 L, to the bit
    assert pair_collision_distance(2.5, 1.0, 1.0) == 2.5
    assert pair_collision_distance(2.0, 1.0, 122.0 / 230.0) == pytest.approx((230.0 + 122.0) / 230.0)


@pytest.mark.parametrize("fleet", [False, True], ids=["unrolled", "fleet"])
def test_a_122_m_target_beside_a_230_m_own_ship_collides_at_1_53_l_not_2_l(fleet):
    from mmg_casadi.scenarios.run import run_scenario
    from mmg_casadi.scenarios.scenario import scenario_from_dict
    params = {"fleet_from_ships": 2} if fleet else None
    sizes = ({"length_m": 230.0}, {"length_m": 122.0})
    # 1.8 L apart: inside the 2 L of two KCS (a start the file check refuses), outside the pair's 1.53 L
    with pytest.raises(ScenarioError, match=r"ships\[1\].start: expected a start at least collision_distance = 2 L"):
        scenario_from_dict(_abreast(1.8, {}, {}))
    res = run_scenario(scenario_from_dict(_abreast(1.8, *sizes)), params=params)
    assert [s["collided"] for s in res.metrics["ships"]] == [False, False]
    with pytest.raises(ScenarioError, match=r"at least 1.53043 L \(collision_distance = 2 L times the two ships'"):
        scenario_from_dict(_abreast(1.5, *sizes))
    sc = Scenario(Settings("none", t_max=3.0), [ShipSpec(**s) for s in (
        {"name": "own", "start": [0, 0], "heading_deg": 0, "speed": 1, "waypoints": [[40, 0]], "length_m": 230.0},
        {"name": "target", "start": [0, 1.5], "heading_deg": 0, "speed": 1, "waypoints": [[40, 1.5]],
         "length_m": 122.0})])  # built directly: no start check, so the step decides
    ships = run_scenario(sc, params=params).metrics["ships"]
    assert [s["collided"] for s in ships] == [True, True] and ships[0]["collision_with"] == "target"


def test_a_ship_touches_a_wall_at_half_its_own_beam():
    from mmg_casadi.scenarios.run import run_scenario
    from mmg_casadi.scenarios.scenario import scenario_from_dict
    d = {"settings": {"method": "none", "t_max": 3.0},
         "ships": [{"start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[40.0, 0.0]]}],
         "walls": [{"points": [[-5.0, 0.15], [45.0, 0.15]]}]}  # 0.15 L = 34.5 m from the centre line
    assert run_scenario(scenario_from_dict(d)).metrics["ships"][0]["collided"] is False  # a KCS: 16.1 m
    d["ships"][0]["beam_m"] = 80.0
    ship = run_scenario(scenario_from_dict(d)).metrics["ships"][0]
    assert ship["collided"] is True and ship["collision_kind"] == "wall"
