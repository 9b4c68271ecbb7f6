"""maritime-schema traffic situations in and out: geometry, units, errors, CLI convert, round trip."""

from __future__ import annotations

import copy
import json
import math
import tomllib
from importlib.resources import files

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.errors import InputError
from mmg_casadi.scenarios.geodesy import LocalPlane, _ecef
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

@pytest.mark.parametrize("lat0", [0.0, 35.0, 58.61, 70.0, -45.0])
def test_small_offsets_match_the_radii_of_curvature(lat0):
    plane = LocalPlane(lat0, 10.0)
    M, N = _radii(lat0)
    dphi = 1e-3  # deg, ~110 m: the plane and the radii agree to well below a millimetre
    x, _ = plane.to_plane(lat0 + dphi, 10.0)
    _, y = plane.to_plane(lat0, 10.0 + dphi)
    assert x == pytest.approx(M * math.radians(dphi), abs=1e-3)
    assert y == pytest.approx(N * math.cos(math.radians(lat0)) * math.radians(dphi), abs=1e-3)


def test_distances_from_the_reference_within_a_metre_at_50_km():
    # the plane preserves distance from the reference up to d^3/(6 R^2) ~ 0.5 m at 50 km; compare with the
    # chord through the Earth converted to an arc on the local sphere of radius sqrt(M N)
    lat0, lon0 = 58.61, 10.59
    plane = LocalPlane(lat0, lon0)
    R = math.sqrt(math.prod(_radii(lat0)))
    for bearing in range(0, 360, 30):
        b = math.radians(bearing)
        lat = lat0 + math.degrees(50e3 * math.cos(b) / _radii(lat0)[0])
        lon = lon0 + math.degrees(50e3 * math.sin(b) / (_radii(lat0)[1] * math.cos(math.radians(lat0))))
        chord = float(np.linalg.norm(_ecef(lat, lon) - _ecef(lat0, lon0)))
        arc = 2 * R * math.asin(chord / (2 * R))
        x, y = plane.to_plane(lat, lon)
        assert abs(math.hypot(x, y) - arc) < 1.0, bearing
        back = plane.to_geodetic(x, y)
        assert back == pytest.approx((lat, lon), abs=1e-9)


def test_course_in_the_plane_accounts_for_meridian_convergence():
    plane = LocalPlane(58.61, 10.59)
    assert plane.course_to_plane(37.0, 58.61, 10.59) == pytest.approx(37.0, abs=1e-9)
    # 50 km east at 58.6 N: meridians converge by dlon * sin(lat) (spherical approximation), so north there
    # points that much west of the plane's x axis
    lon = 10.59 + math.degrees(50e3 / (_radii(58.61)[1] * math.cos(math.radians(58.61))))
    gamma = (lon - 10.59) * math.sin(math.radians(58.61))
    assert plane.course_to_plane(0.0, 58.61, lon) == pytest.approx(360.0 - gamma, abs=0.01)
    for c in (0.0, 45.0, 190.0, 359.0):
        back = plane.course_from_plane(plane.course_to_plane(c, 58.7, lon), 58.7, lon)
        assert (back - c + 180) % 360 - 180 == pytest.approx(0.0, abs=0.01)


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
])
def test_bad_situations_name_the_field(mutate, field):
    d = _situation(_ship(58.65, 10.6, cog=180.0))
    mutate(d)
    with pytest.raises(InputError) as err:
        traffic_situation_to_scenario(d)
    assert err.value.field == field
    if "sog" in field:
        assert "[4.80, 28.80] kn" in str(err.value)


# ---------------------------------------------------------------------------------------- round trip / CLI

def _distance_m(p, q):
    return float(np.linalg.norm(_ecef(p["lat"], p["lon"]) - _ecef(q["lat"], q["lon"])))


def test_round_trip_json_toml_json_within_a_metre_and_a_tenth_of_a_degree(tmp_path):
    src = json.loads(EXAMPLE.read_text())
    # move one target ~45 km away so that the curvature and meridian convergence matter
    far = copy.deepcopy(src["targetShips"][1])
    far["static"]["name"] = "FAR"
    far["initial"]["position"] = {"lat": 58.45, "lon": 11.30}
    far["waypoints"] = [{"position": {"lat": 58.45, "lon": 11.30}}, {"position": {"lat": 58.30, "lon": 10.95}}]
    src["targetShips"].append(far)
    original = tmp_path / "in.json"
    original.write_text(json.dumps(src))
    assert main(["convert", str(original), "--out", str(tmp_path / "mid.toml")]) == 0
    assert main(["convert", str(tmp_path / "mid.toml"), "--out", str(tmp_path / "out.json")]) == 0
    out = json.loads((tmp_path / "out.json").read_text())
    pairs = [(src["ownShip"], out["ownShip"])] + list(zip(src["targetShips"], out["targetShips"]))
    assert len(out["targetShips"]) == len(src["targetShips"])
    for a, b in pairs:
        assert _distance_m(a["initial"]["position"], b["initial"]["position"]) < 1.0
        assert (b["initial"]["heading"] - a["initial"]["heading"] + 180) % 360 - 180 == pytest.approx(0, abs=0.1)
        assert b["initial"]["sog"] == pytest.approx(a["initial"]["sog"], rel=1e-9)
        # the file's waypoints come back in order (the first repeats the start); extensions may follow
        for wa, wb in zip(a["waypoints"], b["waypoints"]):
            assert _distance_m(wa["position"], wb["position"]) < 1.0
        assert b["static"]["name"] == a["static"]["name"]


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
