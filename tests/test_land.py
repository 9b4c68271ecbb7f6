"""Land as polygons: scenario keys, grounding as a failure, land edges that act like the paper's walls, the
shipped land scenarios and their figures."""

import math

import numpy as np
import pytest
from matplotlib.figure import Figure

from mmg_casadi.errors import ScenarioError
from mmg_casadi.montecarlo.execution import run_scenarios
from mmg_casadi.plotting import LAND_COLOR, plot_scenario
from mmg_casadi.scenarios.run import packaged_scenario, run_scenario
from mmg_casadi.scenarios.scenario import LandSpec, dump_scenario, scenario_from_dict, with_method
import tomllib


def _into_land(method="none"):
    # one ship sailing north at design speed into a square of land whose southern shore is at x = 20 L
    return scenario_from_dict({
        "settings": {"method": method, "t_max": 60.0},
        "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[50, 0]]}],
        "land": [{"points": [[20, -5], [30, -5], [30, 5], [20, 5]]}]})


def test_a_ship_sailing_into_land_grounds_with_time_and_place():
    own = run_scenario(_into_land()).metrics["ships"][0]
    # the KCS's centre reaches half its beam (32.2 m / 230 m / 2 = 0.07 L) from the shore at t = 19.93 L/U;
    # the step that crosses it ends at t = 20.0
    assert own["collided"] and own["collision_kind"] == "land" and own["collision_with"] == "land3"
    assert own["collision_time"] == pytest.approx(20.0)
    assert own["collision_position"] == pytest.approx([20.0, 0.0], abs=0.05)


def test_a_grounding_margin_grounds_the_ship_earlier_on_land_only():
    # margin 2 L: the centre reaches 0.07 + 2 L from the shore at t = 17.93 L/U, so the step ending at 18.0 grounds
    own = run_scenario(_into_land(), {"grounding_margin": 2.0}).metrics["ships"][0]
    assert own["collision_kind"] == "land" and own["collision_time"] == pytest.approx(18.0)
    assert own["collision_position"] == pytest.approx([18.0, 0.0], abs=0.05)
    # a channel wall keeps the hull's side: the same shore as a wall is touched at t = 20.0 whatever the margin
    sc = scenario_from_dict({
        "settings": {"method": "none", "t_max": 60.0},
        "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[50, 0]]}],
        "walls": [{"points": [[20, -5], [20, 5]]}]})
    wall = run_scenario(sc, {"grounding_margin": 2.0}).metrics["ships"][0]
    assert wall["collision_time"] == pytest.approx(20.0)


def test_grounding_is_the_run_failure_and_its_mechanism():
    (row,) = run_scenarios([_into_land()], time_guidance_calls=False)
    assert (row["success"], row["failure"], row["failure_pair"], row["failure_mechanism"]) == (
        False, "grounding", "0-land3", "grounding")
    assert row["failure_time"] == pytest.approx(20.0)


def test_land_edges_act_like_the_paper_walls_and_are_seen_ahead():
    # the paper's narrow channel with its banks as land polygons whose first edges are the walls: every other
    # edge lies beyond the walls' range of action (2 L). With the look-ahead shrunk to nothing (a path ahead of
    # 1e-9 advances that must keep clear of the hull's side only) the trajectories are those with walls, to the
    # bit; with the default look-ahead land is seen ahead and they differ
    walls = run_scenario(with_method(packaged_scenario("narrow_channel"), "modified-vortex")).trajectory
    land_sc = with_method(packaged_scenario("narrow_channel_land"), "modified-vortex")
    near = run_scenario(land_sc, {"land_lookahead": 1e-9, "land_clearance": 0.0}).trajectory
    for name in ("x", "y", "psi"):
        for i in range(2):
            assert np.array_equal(walls.state(name, i), near.state(name, i))
    ahead = run_scenario(land_sc)
    assert not np.array_equal(walls.state("y", 0), ahead.trajectory.state("y", 0)[:len(walls.t)])
    assert not ahead.metrics["collision"]


@pytest.mark.parametrize("case", ["strait_crossing", "fjord_island"])
@pytest.mark.parametrize("method", ["colregs-vortex", "modified-vortex", "velocity-obstacle"])
def test_shipped_land_scenarios_are_safe(case, method):
    m = run_scenario(with_method(packaged_scenario(case), method)).metrics
    assert not m["collision"], [(s["name"], s["collision_kind"]) for s in m["ships"]]
    assert all(s["reached_goal"] for s in m["ships"])


def test_the_crossing_in_the_strait_is_a_collision_course():
    m = run_scenario(with_method(packaged_scenario("strait_crossing"), "none")).metrics
    assert [s["collision_kind"] for s in m["ships"]] == ["ship", "ship"]


@pytest.mark.parametrize("land, field", [
    ([{"points": [[0, 0], [1, 0]]}], "land[0].points"),
    ([{"points": [[0, 0], [1, 1], [2, 2]]}], "land[0].points"),
    ([{"points": [[0, 0], [0, 0], [1, 1]]}], "land[0].points[1]"),
    ([{"points": [[-5, -5], [5, -5], [5, 5], [-5, 5]]}], "ships[0].start"),
    ([{"points": [[45, -5], [55, -5], [55, 5], [45, 5]]}], "ships[0].waypoints[0]"),
    ([{"points": [[20, -5], [30, -5], [30, 5]], "height": 3}], "land[0].height"),
])
def test_bad_land_names_the_field(land, field):
    d = {"settings": {"method": "none"},
         "ships": [{"start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[50, 0]]}], "land": land}
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(d)
    assert err.value.field == field


def test_land_round_trips_through_the_scenario_file():
    sc = packaged_scenario("fjord_island")
    back = scenario_from_dict(tomllib.loads(dump_scenario(sc)))
    assert back == sc and len(back.land) == 3 and len(back.land[2].edges) == 4


def test_polygon_inside_test():
    square = LandSpec([[0, 0], [2, 0], [2, 2], [0, 2]])
    assert square.contains((1, 1)) and not square.contains((3, 1)) and not square.contains((1, -math.pi))


def test_the_figure_fills_the_land():
    fig = plot_scenario(run_scenario(_into_land()))
    assert isinstance(fig, Figure)
    patches = [p for ax in fig.axes for p in ax.patches if p.get_label() == "land"]
    assert len(patches) == 1 and patches[0].get_facecolor()[:3] == pytest.approx(
        tuple(int(LAND_COLOR[i:i + 2], 16) / 255 for i in (1, 3, 5)))


def test_environment_6_is_a_strait_with_islands_and_routes_in_water():
    from mmg_casadi.montecarlo.land_sampling import ROUTE_CLEARANCE, WIDTH_RANGE, route_clearance
    from mmg_casadi.montecarlo.sampling import sample_scenario
    for run in range(50):
        s = sample_scenario(6, run)
        assert s == sample_scenario(6, run) and s.n_obstacles == 0 and len(s.land) == 4
        sc = scenario_from_dict(s.to_scenario_dict())  # refuses a start or a goal on land
        west, east = s.land[0], s.land[1]
        assert WIDTH_RANGE[0] <= east[:, 1].min() - west[:, 1].max() <= WIDTH_RANGE[1]
        for a, b in zip(s.starts, s.goals):
            assert all(route_clearance(a, b, poly) >= ROUTE_CLEARANCE for poly in s.land)
        assert [sh.goal[0] >= 90 for sh in sc.ships] == [True, True, True, False, False]
    assert sample_scenario(6, 0) != sample_scenario(6, 1)


def test_environment_6_runs_in_the_monte_carlo_and_reports_grounding():
    from mmg_casadi.montecarlo.execution import run_batch
    rows = run_batch(6, "none", range(6))
    assert {r["n_obstacles"] for r in rows} == {0} and {r["n_ships"] for r in rows} == {5}
    # ships that hold their routes never ground (routes run in the channel, clear of the islands)
    assert not [r for r in rows if r["failure"] == "grounding"]
    grounded = run_scenarios([_into_land()], time_guidance_calls=False)
    assert grounded[0]["failure_mechanism"] == "grounding"
    # Rule 9 in the study's COLREG summary: one verdict per run that sailed the strait's narrow part
    from mmg_casadi.montecarlo.encounter_summary import summarize_encounters, to_markdown
    shares = [r["colregs_rule9"] for r in rows if not math.isnan(r["colregs_rule9"])]
    rule9 = [s for s in summarize_encounters(rows) if s["group"] == "rule 9"]
    assert shares and len(rule9) == 1 and rule9[0]["n"] == len(shares)
    assert rule9[0]["kept"] == sum(x >= 0.9 for x in shares)
    assert "Rule 9 kept [%] (applied)" in to_markdown(summarize_encounters(rows), [])
