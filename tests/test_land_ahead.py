"""Issue 43: land every method sees in time, a grounding or collision that ends a voyage in every output, routes
checked against the chart and planned around it."""

import csv
import json
import math

import numpy as np
import pytest
from shapely.geometry import LineString, Polygon

from mmg_casadi.cli import main
from mmg_casadi.closed_loop.layout import STOPPED
from mmg_casadi.errors import ScenarioError
from mmg_casadi.guidance.land_ahead import hull_advance
from mmg_casadi.montecarlo.execution import run_scenarios
from mmg_casadi.montecarlo.land_sampling import sample_strait
from mmg_casadi.scenarios.routes import check_routes, plan_route
from mmg_casadi.scenarios.run import packaged_scenario, run_scenario
from mmg_casadi.scenarios.scenario import dump_scenario, scenario_from_dict, with_method

ISLAND = [[25.0, -3.0], [31.0, -3.0], [31.0, 3.0], [25.0, 3.0]]


def _island_on_track(method="none", **settings):
    return scenario_from_dict({
        "settings": {"method": method, "t_max": 150.0, **settings},
        "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[60, 0]]}],
        "land": [{"points": ISLAND}]})


def test_the_look_ahead_is_two_advances_of_the_own_hull():
    # the KCS's advance at 35° rudder from her design speed is 3.56 L; a KVLCC2 (3.09 of her 320 m) in a KCS scene
    assert hull_advance("kcs", "kcs") == pytest.approx(3.558, abs=1e-3)
    assert hull_advance("kvlcc2", "kcs") == pytest.approx(3.085 * 320.0 / 230.0, abs=2e-3)


def test_the_compiled_look_ahead_is_the_reference_one():
    # the step's loop over the edges (far ones skipped by a conditional) against the plain expression, both
    # directions, on environment 6's land from random positions and headings
    import casadi as ca
    from mmg_casadi.guidance.land_ahead import land_ahead_function, land_seen_ahead
    land = sample_strait(3)["land"]
    segs = ca.DM(np.array([[*a, *b] for poly in land for a, b in zip(poly, np.roll(poly, -1, axis=0))]).T)
    f = land_ahead_function(segs.size2())
    rng = np.random.default_rng(0)
    hits = 0
    for _ in range(60):
        pos = ca.DM(rng.uniform([0, 20], [100, 80]))
        a, b = rng.uniform(-np.pi, np.pi, 2)
        dc, do = ca.DM([np.cos(a), np.sin(a)]), ca.DM([np.cos(b), np.sin(b)])
        got = f(pos, dc, do, 7.1, 1.07, segs)
        for k, d in ((0, dc), (2, do)):
            ref = land_seen_ahead(pos, d, 7.1, 1.07, segs)
            assert float(got[k]) == float(ref["ahead"]) and np.array_equal(np.array(got[k + 1]),
                                                                           np.array(ref["point"]))
            hits += int(float(ref["ahead"]))
    assert 10 < hits < 110


@pytest.mark.parametrize("method", ["colregs-vortex", "velocity-obstacle"])
def test_a_ship_alone_rounds_an_island_on_her_track(method):
    # main a6a8e24: every method grounded at t = 25.0, as the ship that avoids nothing: the method was only switched
    # on within 2 L of the land (wall_d_act), too late for a hull whose advance is 3.56 L
    r = run_scenario(_island_on_track(method))
    own = r.metrics["ships"][0]
    assert own["status"] == "reached" and not own["collided"]
    x, y = r.trajectory.state("x", 0), r.trajectory.state("y", 0)
    beside = (x > 24.0) & (x < 32.0)
    assert np.all(np.abs(y[beside]) > 3.0 + 0.07)  # off the island's sides while abreast of it
    assert own["reactive_time"] > 0  # the method took over from ILOS with no other ship near


def test_a_grounded_ship_stops_and_is_never_called_arrived():
    r = run_scenario(_island_on_track("none"))
    own = r.metrics["ships"][0]
    assert (own["status"], own["collision_kind"], own["reached_goal"], own["time_to_goal"]) == (
        "grounded", "land", False, None)
    assert own["collision_time"] == pytest.approx(25.0)
    # she is held where she touched: engine stopped, rudder amidships, no speed; the run ends there
    tr = r.trajectory
    assert tr.t[-1] == pytest.approx(25.0)
    assert tr.state("status", 0)[-1] == STOPPED
    assert (tr.state("u", 0)[-1], tr.state("r", 0)[-1], tr.state("delta", 0)[-1]) == (0.0, 0.0, 0.0)
    assert math.isfinite(own["ce"]) and own["mcte"] == pytest.approx(0.0, abs=1e-9)  # her voyage up to the contact


def test_a_collided_ship_stops_and_stays_a_hazard():
    # two ships head-on holding course: both collide, stop where they touched and are no longer sailing; a third
    # ship that holds her course through the place later runs into them
    sc = scenario_from_dict({
        "settings": {"method": "none", "t_max": 120.0},
        "ships": [{"name": "a", "start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[60, 0]]},
                  {"name": "b", "start": [60, 0], "heading": 180, "speed": 1, "waypoints": [[0, 0]]},
                  {"name": "c", "start": [30, -40], "heading": 90, "speed": 1, "waypoints": [[30, 40]]}]})
    m = run_scenario(sc).metrics["ships"]
    assert [s["status"] for s in m] == ["collided"] * 3
    assert m[0]["collision_with"] == "b" and m[1]["collision_with"] == "a"
    assert m[2]["collision_with"] in ("a", "b") and m[2]["collision_time"] > m[0]["collision_time"]
    assert not any(s["reached_goal"] for s in m) and all(s["time_to_goal"] is None for s in m)


def test_grounded_in_simulate_statistics_and_encounters_alike(tmp_path, capsys):
    d = {"settings": {"method": "none", "t_max": 150.0}, "land": [{"points": ISLAND}],
         "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[60, 0]]},
                   {"name": "far", "start": [0, 40], "heading": 0, "speed": 0.5, "waypoints": [[60, 40]]}]}
    sc = scenario_from_dict(d)
    (tmp_path / "set").mkdir()
    (tmp_path / "set" / "island.toml").write_text(dump_scenario(sc), encoding="utf-8")
    # simulate
    assert main(["simulate", str(tmp_path / "set" / "island.toml"), "--out", str(tmp_path / "sim")]) == 0
    own = json.loads((tmp_path / "sim" / "metrics.json").read_text())["ships"][0]
    assert (own["status"], own["reached_goal"], own["time_to_goal"]) == ("grounded", False, None)
    said = capsys.readouterr().out.splitlines()[0]  # simulate's summary line
    assert said.startswith("own") and "grounded on land" in said and "reached" not in said
    # the Monte Carlo's row (study statistics writes it to runs.csv): a grounding, the own ship not arrived
    (row,) = run_scenarios([sc], time_guidance_calls=False)
    assert (row["success"], row["failure"], row["failure_mechanism"]) == (False, "grounding", "grounding")
    assert math.isnan(row["time_to_goal"]) and not row["fleet_success"]
    # study encounters
    assert main(["study", "encounters", str(tmp_path / "set"), "--methods", "none", "--out",
                 str(tmp_path / "enc")]) == 0
    with open(tmp_path / "enc" / "situations.csv", newline="") as f:
        (sit,) = list(csv.DictReader(f))
    assert (sit["status"], sit["reached_goal"], sit["safe"], sit["collided"]) == ("grounded", "0", "0", "1")


def test_a_route_across_land_is_reported_in_one_line_and_in_metrics(tmp_path, capsys):
    path = tmp_path / "island.toml"
    path.write_text(dump_scenario(_island_on_track("colregs-vortex")), encoding="utf-8")
    assert main(["simulate", str(path), "--out", str(tmp_path / "out")]) == 0
    err = [line for line in capsys.readouterr().err.splitlines() if "route:" in line]
    assert err == ["mmg-casadi: warning: route: ships[0] 'own' leg 0 (0, 0) -> (60, 0) crosses land0 at (25, 0)"]
    m = json.loads((tmp_path / "out" / "metrics.json").read_text())
    (w,) = m["route_warnings"]
    assert (w["ship"], w["leg"], w["land"], w["crosses"], w["where"]) == ("own", 0, "land0", True, [25.0, 0.0])
    assert m["ships"][0]["status"] == "reached"  # reported, and the method still keeps her off the land


def test_a_leg_within_the_grounding_clearance_is_reported():
    # a leg 0.05 L off the island's side: within half the KCS's beam (0.07 L); with a 1 L grounding margin a leg
    # 0.5 L off is reported too, and one 2 L off is not
    def legs(y, margin=0.0):
        sc = scenario_from_dict({
            "settings": {"method": "none"},
            "ships": [{"name": "own", "start": [0, y], "heading": 0, "speed": 1, "waypoints": [[60, y]]}],
            "land": [{"points": ISLAND}]})
        return check_routes(sc, [0.07 + margin])
    (w,) = legs(3.05)
    assert not w["crosses"] and w["distance"] == pytest.approx(0.05) and w["where"][1] == pytest.approx(3.05)
    assert len(legs(3.5, margin=1.0)) == 1 and legs(5.0, margin=1.0) == []


def test_a_start_or_waypoint_on_land_is_refused_in_one_line(tmp_path, capsys):
    d = {"settings": {"method": "none"},
         "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[28, 0], [60, 0]]}],
         "land": [{"points": ISLAND}]}
    with pytest.raises(ScenarioError, match=r"ships\[0\]\.waypoints\[0\]"):
        scenario_from_dict(d)
    path = tmp_path / "bad.toml"
    path.write_text("[settings]\nmethod = 'none'\n[[ships]]\nname = 'own'\nstart = [28.0, 0.0]\nheading = 0.0\n"
                    "speed = 1.0\nwaypoints = [[60.0, 0.0]]\n[[land]]\npoints = " + json.dumps(ISLAND) + "\n")
    assert main(["simulate", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "ships[0].start" in err[0] and not (tmp_path / "out").exists()


@pytest.mark.parametrize("seed", range(4))
def test_plan_clears_every_polygon_by_the_clearance(seed):
    # environment 6's shores and islands, a route from south of the strait to north of it drawn across the land
    s = sample_strait(seed)
    polys = [Polygon(p) for p in s["land"]]
    start, goal = (2.0, 2.0 + 10 * seed), (98.0, 95.0 - 10 * seed)
    for clearance in (1.0, 2.0):
        route = plan_route([start, goal], s["land"], clearance)
        line = LineString([start, *route])
        assert route[-1] == goal
        assert min(line.distance(p) for p in polys) >= clearance - 1e-9
        assert line.length < 1.5 * math.dist(start, goal)


def test_plan_keeps_the_waypoints_and_refuses_a_point_within_the_clearance():
    route = plan_route([(0, 0), (20, 6), (60, 0)], [ISLAND], 2.0)
    assert (20.0, 6.0) in route and route[-1] == (60.0, 0.0)
    assert LineString([(0, 0), *route]).distance(Polygon(ISLAND)) >= 2.0 - 1e-9
    with pytest.raises(ScenarioError, match=r"ships\[0\]\.waypoints\[0\]"):
        plan_route([(0, 0), (24, 0), (60, 0)], [ISLAND], 2.0, field="ships[0]")


def test_route_plan_in_a_scenario_is_sailed_and_written(tmp_path):
    sc = _island_on_track("none", route="plan")
    r = run_scenario(sc)
    own = r.metrics["ships"][0]
    assert own["status"] == "reached" and own["route"]["planned"] and r.metrics["route_warnings"] == []
    line = LineString([(0.0, 0.0), *own["route"]["waypoints"]])
    assert line.distance(Polygon(ISLAND)) >= r.params["route_clearance"] - 1e-9
    # per ship, and from the command line
    d = {"settings": {"method": "none"}, "land": [{"points": ISLAND}],
         "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[60, 0]],
                    "route": "plan"}]}
    assert run_scenario(scenario_from_dict(d)).metrics["ships"][0]["route"]["planned"]
    path = tmp_path / "island.toml"
    path.write_text(dump_scenario(_island_on_track("none")), encoding="utf-8")
    assert main(["simulate", str(path), "--set", "route=plan", "--set", "route_clearance=3", "--out",
                 str(tmp_path / "out")]) == 0
    m = json.loads((tmp_path / "out" / "metrics.json").read_text())
    assert m["ships"][0]["status"] == "reached" and m["params"]["route_clearance"] == 3.0
    wps = m["ships"][0]["route"]["waypoints"]
    assert LineString([(0.0, 0.0), *wps]).distance(Polygon(ISLAND)) >= 3.0 - 1e-9


def test_colregs_vortex_keeps_to_the_starboard_side_of_a_strait():
    # Rule 9(a): the own ship sails north through a 10 L strait whose route runs on its centre line
    m = run_scenario(packaged_scenario("land_strait_traffic")).metrics
    own = m["ships"][0]
    assert own["status"] == "reached" and own["rule9"]["verdict"] and own["rule9"]["mean_offset"] > 1.0
    assert not any(s["collision_kind"] == "land" for s in m["ships"])


@pytest.mark.slow
@pytest.mark.parametrize("case", ["land_island_on_track", "land_island_off_track", "land_headland",
                                  "land_strait_traffic", "land_channel_bend"])
@pytest.mark.parametrize("method", ["colregs-vortex", "velocity-obstacle"])
def test_no_grounding_in_the_land_library(case, method):
    m = run_scenario(with_method(packaged_scenario(case), method)).metrics
    assert not any(s["status"] == "grounded" for s in m["ships"]), [(s["name"], s["status"]) for s in m["ships"]]
    assert m["ships"][0]["status"] == "reached"
