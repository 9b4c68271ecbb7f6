"""A colregs-vortex ship that passes its goal outside the acceptance radius turns back to it; the paper's methods
keep the paper's ILOS (the extended last leg)."""

from mmg_casadi.scenarios.scenario import scenario_from_dict
from mmg_casadi.scenarios.run import run_scenario


def _offset_goal(method):
    # the final waypoint 2 L to starboard of the first: with a 1 L acceptance radius the ship cannot turn onto it
    # (tactical diameter 3.4 L) and passes it; the last leg then points away from where the ship ends up
    return scenario_from_dict({"settings": {"method": method, "t_max": 150.0},
                               "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0,
                                          "waypoints": [[20, 0], [20, 2.0]]}]})


def test_colregs_vortex_returns_to_a_missed_final_waypoint():
    sc = _offset_goal("colregs-vortex")
    r = run_scenario(sc, params={"goal_tolerance": 1.0})
    assert r.metrics["ships"][0]["status"] == "reached"


def test_paper_methods_keep_following_the_last_leg():
    r = run_scenario(_offset_goal("modified-vortex"), params={"goal_tolerance": 1.0})
    assert r.metrics["ships"][0]["status"] == "stalled"
