"""Failure mechanisms of Monte Carlo runs: the classification on hand-built inputs and on short scenarios."""

import math

import pytest

from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.failures import MECHANISMS, failure_mechanism, turn_time_90, unavoidable_at_start
from mmg_casadi.vessel.maneuvers import turning_circle
from mmg_casadi.montecarlo.execution import run_scenarios
from mmg_casadi.montecarlo.results import MECHANISMS as RESULT_MECHANISMS
from mmg_casadi.scenarios.scenario import scenario_from_dict

GOALS = [[50.0, 0.0], [0.0, 0.0], [0.0, 50.0]]


def _mech(failure="collision", t=30.0, j=1, obstacles=(), at=None, **kw):
    return failure_mechanism(failure, collision_time=t, collision_with=j, goals=GOALS, obstacles=obstacles,
                             positions_at_collision=at, turn_time=5.0, **kw)


def test_the_set_is_the_results_columns_set():
    assert MECHANISMS == RESULT_MECHANISMS


def test_turn_time_is_where_the_turning_circle_passes_90_degrees():
    t90 = turn_time_90()
    res = turning_circle(35.0, t_end=40.0)
    psi = res.state("psi")
    assert psi[res.t <= t90 - 0.1].max() < math.pi / 2 <= psi[res.t >= t90 + 0.1].min()


def test_every_mechanism_from_hand_built_inputs():
    far = [[25.0, 0.0], [27.0, 0.0], [30.0, 30.0]]
    assert _mech(failure="") == ""
    assert _mech(t=4.9, at=far) == "started-too-close"
    assert _mech(t=4.9, j=3, obstacles=[[40.0, 40.0, 0.5]]) == "started-too-close"
    assert _mech(j=3, obstacles=[[45.0, 3.0, 0.5]]) == "obstacle-near-goal"   # 5.8 L from own goal
    assert _mech(j=3, obstacles=[[30.0, 3.0, 0.5]]) == "obstacle"             # 20.2 L from it
    assert _mech(at=[[41.0, 0.0], [43.0, 0.0], [30.0, 30.0]]) == "near-goal"  # own ship 9 L from its goal
    assert _mech(at=[[3.0, 0.0], [1.0, 0.0], [30.0, 30.0]]) == "near-goal"    # the other ship 1 L from its goal
    assert _mech(at=far) == "ship-ship"
    assert _mech(at=far, near_goal_distance=30.0) == "near-goal"
    for f in ("stalled", "timeout", "diverged"):
        assert _mech(failure=f) == f


def test_near_goal_needs_a_ship_within_the_stated_distance():
    # the other ship (goal at the origin) is at distance hypot(8, 7) = 10.63 L from its goal
    at = [[8.0, 5.0], [8.0, 7.0], [30.0, 30.0]]
    assert _mech(at=at, near_goal_distance=10.6) == "ship-ship"
    assert _mech(at=at, near_goal_distance=10.7) == "near-goal"


def test_bad_input_names_the_field():
    with pytest.raises(InputError, match="failure"):
        _mech(failure="sunk")
    with pytest.raises(InputError, match="collision_with"):
        _mech(j=5, obstacles=[[1.0, 1.0, 0.5]])


def _sc(ships, obstacles=(), t_max=60.0):
    d = {"settings": {"method": "none", "t_max": t_max}, "ships": ships}
    if obstacles:
        d["obstacles"] = [{"position": list(o), "radius": 0.5} for o in obstacles]
    return scenario_from_dict(d)


def test_short_scenarios_are_classified_from_their_rollout():
    # head-on 6 L apart at design speed: they meet after ~2 L/U, long before a 90 deg turn
    close = _sc([{"name": "a", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[50.0, 0.0]]},
                 {"name": "b", "start": [6.0, 0.0], "heading": 180.0, "speed": 1.0, "waypoints": [[-50.0, 0.0]]}])
    # a ship holding its course onto an obstacle 5 L before its goal
    near = _sc([{"name": "a", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[30.0, 0.0]]}],
               obstacles=[(25.0, 0.0)])
    # the same obstacle 25 L before a goal at 50 L
    plain = _sc([{"name": "a", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[50.0, 0.0]]}],
                obstacles=[(25.0, 0.0)])
    # two ships meeting head-on in the middle of 60 L voyages
    ships = _sc([{"name": "a", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[60.0, 0.0]]},
                 {"name": "b", "start": [60.0, 0.5], "heading": 180.0, "speed": 1.0, "waypoints": [[0.0, 0.5]]}])
    rows = run_scenarios([close, near, plain, ships], time_guidance_calls=False)
    assert [r["failure"] for r in rows] == ["collision"] * 4
    assert [r["failure_mechanism"] for r in rows] == ["started-too-close", "obstacle-near-goal", "obstacle",
                                                      "ship-ship"]


def test_unavoidable_at_start_tries_holding_and_both_hard_turns():
    kw = dict(collision_distance=2.0)
    # an obstacle 3 L dead ahead: the turning circle's advance (3.6 L) carries the ship into it whichever way
    assert unavoidable_at_start([0, 0], 0.0, 1.0, [3.0, 0.0], [0, 0], **kw)
    # 3 L off on the beam: holding course passes it at 3 L
    assert not unavoidable_at_start([0, 0], 0.0, 1.0, [0.0, 3.0], [0, 0], **kw)
    # 8 L dead ahead: the advance of a hard turn (3.6 L at design speed) stays short of it
    assert not unavoidable_at_start([0, 0], 0.0, 1.0, [8.0, 0.0], [0, 0], **kw)
    # a ship overtaking at twice the speed 4 L astern on the own track: a 90 deg turn moves only ~1.6 L sideways
    assert unavoidable_at_start([0, 0], 0.0, 0.5, [-4.0, 0.0], [1.0, 0.0], **kw)
    # rotation: the same head-on geometry pointing north-east is still unavoidable
    c = math.cos(math.pi / 4)
    assert unavoidable_at_start([0, 0], math.pi / 4, 1.0, [6 * c, 6 * c], [-c, -c], **kw)


def test_an_unavoidable_collision_started_too_close_whenever_it_happens():
    args = dict(collision_time=40.0, collision_with=1, goals=[[50, 0], [0, 0]], obstacles=[], turn_time=4.0)
    assert failure_mechanism("collision", **args, unavoidable=True) == "started-too-close"
    assert failure_mechanism("collision", **args) == "ship-ship"
