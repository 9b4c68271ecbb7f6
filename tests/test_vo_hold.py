"""The velocity obstacle's "keep the chosen velocity" behaviour (vo_hold) and its memory row held_heading."""

import math

import casadi as ca
import numpy as np
import pytest

from mmg_casadi.closed_loop.layout import Layout, SHIP_STATE
from mmg_casadi.closed_loop.state import initial_state
from mmg_casadi.closed_loop.outcome import S_
from mmg_casadi.scenarios.encounters import colregs_cases
from mmg_casadi.params import PARAMETERS, resolve
from mmg_casadi.scenarios.scenario import with_method
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.guidance.velocity_obstacle import heading_feasible, hold_heading

KW = {"collision_distance": 2.0, "cone": "huang"}


def test_defaults_are_the_papers_reading():
    assert PARAMETERS["vo_cone"].default == "huang" and PARAMETERS["vo_hold"].default is True
    assert resolve({"vo_hold": False})["vo_hold"] is False
    with pytest.raises(Exception, match="vo_hold: expected true or false"):
        resolve({"vo_hold": 1})
    assert Layout(("velocity-obstacle",)).key() != Layout(("velocity-obstacle",), vo_hold=False).key()


def test_memory_is_declared_by_the_method_and_initialised_to_the_heading():
    assert "held_heading" not in SHIP_STATE and Layout(("none", "none")).memory == ()
    lay = Layout(("velocity-obstacle", "none"))
    assert lay.memory == ("held_heading",) and lay.ship_state[-1] == "held_heading"
    assert lay.ns == len(SHIP_STATE) + 1
    x = initial_state(lay, [{"start": (0, 0), "heading": 0.3, "speed": 1.0, "path": [[0, 0], [50, 0]]},
                            {"start": (9, 9), "heading": -1.2, "speed": 0.5, "path": [[9, 9], [0, 50]]}])
    assert x[lay.row("held_heading", 0)] == 0.3 and x[lay.row("held_heading", 1)] == -1.2


def test_heading_feasible_is_the_exact_collision_cone():
    # neighbour 10 L dead ahead, at rest: the cone's half-angle is asin(2/10) = 11.54 deg
    nb, v = ca.DM([[10], [0]]), ca.DM.zeros(2, 1)
    half = math.asin(0.2)
    assert int(heading_feasible([0, 0], 1.0, half - 1e-3, nb, v, [1], **KW)) == 0
    assert int(heading_feasible([0, 0], 1.0, half + 1e-3, nb, v, [1], **KW)) == 1
    assert int(heading_feasible([0, 0], 1.0, -half + 1e-3, nb, v, [1], **KW)) == 0
    # a moving neighbour shifts the apex: same heading, neighbour running away as fast -> w = 0 is never forbidden
    assert int(heading_feasible([0, 0], 1.0, 0.0, nb, ca.DM([[1.0], [0.0]]), [1], **KW)) == 1


def test_hold_keeps_a_feasible_heading_and_repicks_a_forbidden_one_symbolically():
    fresh, held = ca.SX.sym("f"), ca.SX.sym("h")
    f = ca.Function("f", [fresh, held], [hold_heading(fresh, held, [0, 0], 1.0, ca.DM([[10], [0]]),
                                                      ca.DM.zeros(2, 1), [1], **KW)])
    assert float(f(0.4, -0.7)) == -0.7   # far outside the cone: kept
    assert float(f(0.4, 0.05)) == 0.4    # inside the cone: the fresh choice


def _global_velocity(states):
    u, v, psi = states[..., S_["u"]], states[..., S_["v"]], states[..., S_["psi"]]
    return np.stack([u * np.cos(psi) - v * np.sin(psi), u * np.sin(psi) + v * np.cos(psi)], axis=-1)


@pytest.mark.parametrize("case", ["head-on", "crossing"])
def test_closed_loop_changes_its_held_heading_only_when_it_became_forbidden(case):
    sc = with_method(colregs_cases()[case], "velocity-obstacle")
    res = run_scenario(sc, params={"vo_hold": True})
    tr = res.trajectory
    P = res.params
    reactive = tr.auxiliary("reactive", 0) > 0.5
    psi_d = tr.auxiliary("psi_d", 0)
    changes, checked = 0, 0
    for k in range(1, len(psi_d)):
        if not (reactive[k] and reactive[k - 1]):
            continue
        checked += 1
        if abs(math.remainder(psi_d[k] - psi_d[k - 1], 2 * math.pi)) > 1e-9:
            changes += 1
            s = tr.states[k]  # the state the step k decided on
            pos = s[:, [S_["x"], S_["y"]]]
            vel = _global_velocity(s)
            speed = float(np.hypot(s[0, S_["u"]], s[0, S_["v"]]))
            ok = heading_feasible(pos[0], speed, psi_d[k - 1], pos[1:].T, vel[1:].T, [1],
                                  collision_distance=P["collision_distance"], cone=P["vo_cone"])
            assert int(ok) == 0, f"step {k}: a still-feasible heading was dropped"
    assert checked > 10
    # the re-pick-every-step variant changes its desired heading more often on the same case
    rep = run_scenario(sc, params={"vo_hold": False}).trajectory
    rr, pd = rep.auxiliary("reactive", 0) > 0.5, rep.auxiliary("psi_d", 0)
    rep_changes = sum(1 for k in range(1, len(pd)) if rr[k] and rr[k - 1]
                      and abs(math.remainder(pd[k] - pd[k - 1], 2 * math.pi)) > 1e-9)
    assert rep_changes > changes


def test_without_neighbours_the_memory_follows_the_heading():
    d = {"settings": {"method": "velocity-obstacle", "t_max": 20.0},
         "ships": [{"name": "own", "start": [0.0, 0.0], "heading": 30.0, "speed": 1.0, "waypoints": [[60.0, 0.0]]}]}
    from mmg_casadi.scenarios.scenario import scenario_from_dict
    tr = run_scenario(scenario_from_dict(d)).trajectory
    assert np.allclose(tr.state("held_heading", 0)[1:], tr.state("psi", 0)[1:])
