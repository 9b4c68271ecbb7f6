"""The velocity obstacle with speed levels (``velocity-obstacle-speed``): the levels come from the model's steady
state, the search picks the admissible velocity closest to the preferred one, and in the closed loop the ship's
propeller speed follows the chosen level while the heading-only ``velocity-obstacle`` keeps its rpm exactly."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest

from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import simulate
from mmg_casadi.guidance import methods
from mmg_casadi.guidance.velocity_obstacle import speed_levels, velocity_obstacle, velocity_obstacle_speed
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.run import packaged_scenario, run_scenario
from mmg_casadi.scenarios.scenario import Scenario, Settings, ShipSpec
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed


def test_steady_speed_is_proportional_to_rpm():
    """The levels' speeds rest on X_H(u) + X_P(u, n) = 0 being homogeneous in (u, n): rpm/speed is one number."""
    n1 = propeller_rpm_for_speed(1.0)
    for s in (0.25, 0.4, 0.5, 0.75, 1.0, 1.2):
        assert propeller_rpm_for_speed(s) / n1 == pytest.approx(s, rel=1e-12, abs=0.0)


def test_levels_span_service_to_dead_slow():
    ship = load_vessel().ship
    dead = PARAMETERS["engine_dead_slow"].default * ship.n_design_rpm
    n1 = propeller_rpm_for_speed(1.0)
    lv = speed_levels(n1, dead, n1, PARAMETERS["vo_speed_levels"].default)
    assert [float(n) for n, _ in lv] == pytest.approx([n1, n1 - (n1 - dead) / 3, n1 - 2 * (n1 - dead) / 3, dead])
    assert float(lv[0][0]) == n1 and float(lv[0][1]) == 1.0  # level 0 is the service rpm exactly
    slow = speed_levels(0.2 * n1, dead, n1, 4)  # service already below dead slow: every level at the service rpm
    assert all(float(n) == 0.2 * n1 for n, _ in slow)


KW = dict(levels=speed_levels(100.0, 25.0, 100.0, 4), collision_distance=2.0, n_candidates=80)
CROSSER = (ca.DM([[4], [-4]]), ca.DM([[0], [1]]))


def test_slowing_wins_when_it_is_closer_to_the_preferred_velocity():
    psi, rpm, k = velocity_obstacle_speed([0, 0], [50, 0], *CROSSER, [1], speed_weight=0.0, **KW)
    assert (round(math.degrees(float(psi)), 6), float(rpm), int(k)) == (-13.5, 50.0, 2)
    # at the service speed the heading search alone would turn 45°
    full = velocity_obstacle([0, 0], 1.0, [50, 0], *CROSSER, [1], collision_distance=2.0, n_candidates=80)
    assert math.degrees(float(full)) == pytest.approx(45.0)


def test_the_weight_prefers_turning_and_nobody_active_keeps_the_service_rpm():
    psi, rpm, k = velocity_obstacle_speed([0, 0], [50, 0], *CROSSER, [1], speed_weight=1.0, **KW)
    assert (round(math.degrees(float(psi)), 6), float(rpm), int(k)) == (45.0, 100.0, 0)
    psi, rpm, k = velocity_obstacle_speed([0, 0], [50, 0], *CROSSER, [0], speed_weight=0.0, **KW)
    assert (float(psi), float(rpm), int(k)) == (0.0, 100.0, 0)


def test_registry_pairs_the_two_readings():
    vo, vs = methods.get("velocity-obstacle"), methods.get("velocity-obstacle-speed")
    assert not vo.commands_speed and vs.commands_speed
    assert vo.groups == vs.groups and vo.memory == vs.memory
    assert "keeps its speed" in vs.source


def test_closed_loop_speed_command_reaches_the_engine():
    """A ship crossing from starboard on a collision course (both at the design speed): the heading-only VO keeps
    the service rpm at every step; the speed VO orders a lower level and the engine follows."""
    own = ShipSpec("own", [0.0, 0.0], 0.0, 1.0, [[80.0, 0.0]])
    tgt = ShipSpec("t", [20.0, -20.0], 90.0, 1.0, [[20.0, 80.0]], method="none")
    out = {}
    for m in ("velocity-obstacle", "velocity-obstacle-speed"):
        pr = build_problem(Scenario(Settings(m), [own, tgt]), {"t_max": 40.0})
        tr = simulate(pr.layout, pr.x0, pr.p)
        sailing = tr.state("status", 0) == 0  # a contact ends her voyage, engine stopped (issue 43)
        out[m] = (tr.state("n_prop", 0)[sailing], pr.ships[0]["n_rpm"], pr.model.params)
    n, n0, _ = out["velocity-obstacle"]
    assert np.all(n == n0)
    n, n0, params = out["velocity-obstacle-speed"]
    dead = params["engine_dead_slow"] * load_vessel().ship.n_design_rpm
    assert n[0] == n0 and n.min() < 0.8 * n0 and n.min() >= dead


@pytest.mark.slow  # about 20 s with an empty compile cache
def test_channel_crossing_only_slowing_avoids_the_ferry():
    """The shipped ``channel_crossing``: a give-way ship leaving a dolphin-lined channel, a ferry crossing the
    mouth from starboard. Turning alone runs into the dolphins; the speed levels let the ferry pass ahead."""
    sc = packaged_scenario("channel_crossing")
    turn = run_scenario(sc, method="velocity-obstacle").metrics
    slow = run_scenario(sc).metrics  # the scenario's method: velocity-obstacle-speed
    assert slow["method"] == "velocity-obstacle-speed"
    own_t, own_s = turn["ships"][0], slow["ships"][0]
    assert turn["collision"] and own_t["collision_kind"] == "obstacle"
    assert own_t["collision_time"] == pytest.approx(21.25)
    # the hard turn's speed loss; rpm never changed (0.617 before the velocity obstacle saw the bank, issue 24)
    assert own_t["min_speed"] == pytest.approx(0.640, abs=1e-3)
    assert not slow["collision"] and own_s["reached_goal"]
    assert own_s["time_to_goal"] == pytest.approx(76.5)
    assert own_s["min_distance"] == pytest.approx(2.19, abs=5e-3)  # just outside the 2 L the cones keep
    assert own_s["min_speed"] == pytest.approx(0.639, abs=1e-3)  # half ahead ordered while the ferry crosses
    assert own_s["reduced_speed_time"] == pytest.approx(27.0)
    assert own_s["delay"] == pytest.approx(9.5)
    ferry = slow["ships"][1]
    assert ferry["min_speed"] == 0.5 and ferry["delay"] == 0.0  # she held her course and speed
