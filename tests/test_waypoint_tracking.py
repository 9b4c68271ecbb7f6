"""Closed-loop waypoint tracking (ILOS + PD + steering gear + MMG, compiled rollout) and the square study."""

import math

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.closed_loop.layout import default_globals, Layout, pack_params
from mmg_casadi.closed_loop.state import initial_state
from mmg_casadi.closed_loop.outcome import S_
from mmg_casadi.errors import InputError, ParameterError
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed
from mmg_casadi.scenarios.scenario import scenario_from_dict
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.closed_loop.simulation import simulate
from mmg_casadi.scenarios.encounters import waypoint_square as square_scenario
from studies.waypoint_square import PAPER


@pytest.fixture(scope="module")
def square():
    return run_scenario(square_scenario())


def test_square_reaches_every_waypoint_and_matches_paper_within_30_percent(square):
    own = square.metrics["ships"][0]
    assert own["reached_goal"] and own["status"] == "reached"
    assert own["ce"] == pytest.approx(PAPER["ce"], rel=0.30)
    assert own["mcte"] == pytest.approx(PAPER["mcte"], rel=0.30)
    # the path visits the four corners within R_tol = 3 L
    x, y = square.trajectory.state("x", 0), square.trajectory.state("y", 0)
    for wx, wy in square.scenario.ships[0].waypoints:
        assert np.min(np.hypot(x - wx, y - wy)) <= 3.0 + 1e-9


def test_square_waypoint_switching_happens_at_r_tol(square):
    tr = square.trajectory
    idx = tr.state("idx", 0)
    x, y = tr.state("x", 0), tr.state("y", 0)
    wps = square.scenario.ships[0].waypoints
    switches = np.flatnonzero(np.diff(idx) > 0) + 1
    assert len(switches) == 3
    for k, s in enumerate(switches):
        d_before = math.hypot(x[s - 1] - wps[k][0], y[s - 1] - wps[k][1])
        d_after = math.hypot(x[s] - wps[k][0], y[s] - wps[k][1])
        assert d_after <= 3.0 < d_before


def test_batch_accumulators_agree_with_trajectory_metrics(square):
    fin = square.trajectory.final[0]
    T = fin[S_["t_goal"]]
    ce_acc = fin[S_["ce_int"]] / (math.radians(35) * T)
    mcte_acc = fin[S_["mcte_int"]] / T
    own = square.metrics["ships"][0]
    assert ce_acc == pytest.approx(own["ce"], rel=0.02)
    assert mcte_acc == pytest.approx(own["mcte"], rel=0.02)


def test_rudder_never_exceeds_35_degrees(square):
    d = square.trajectory.state("delta", 0)
    dc = square.trajectory.auxiliary("delta_c", 0)
    assert np.max(np.abs(d)) <= math.radians(35) + 1e-9
    assert np.max(np.abs(dc)) <= math.radians(35) + 1e-9
    assert np.max(np.abs(dc)) == pytest.approx(math.radians(35))  # the corners saturate the command


def test_path_heading_west_does_not_make_the_ship_circle():
    d = {"settings": {"method": "none", "t_max": 200.0},
         "ships": [{"name": "own", "start": [0, 1.0], "heading": 175.0, "speed": 1.0, "waypoints": [[-60, 0]]}]}
    r = run_scenario(scenario_from_dict(d))
    psi = np.unwrap(r.trajectory.state("psi", 0))
    assert r.metrics["ships"][0]["reached_goal"]
    assert np.ptp(psi) < math.radians(30)
    assert np.max(np.abs(r.trajectory.auxiliary("y_e", 0))) < 1.5


def test_ilos_integrator_stays_bounded_and_cross_track_converges():
    d = {"settings": {"method": "none", "t_max": 200.0},
         "ships": [{"name": "own", "start": [0, 8.0], "heading": 0.0, "speed": 1.0, "waypoints": [[150, 0]]}]}
    r = run_scenario(scenario_from_dict(d))
    y_int = r.trajectory.state("y_int", 0)
    y_e = r.trajectory.auxiliary("y_e", 0)
    # |ẏ_int| ≤ |y_e|/Δ ≤ 4: over the voyage y_int stays far below that bound times T, and the error settles
    assert np.max(np.abs(y_int)) < 20.0
    assert abs(y_e[-20]) < 0.05
    assert r.metrics["ships"][0]["mcte"] < 1.0


def test_gains_are_parameters_from_python_and_cli(tmp_path):
    soft = run_scenario(square_scenario(), params={"kp": 1.0, "kd": 2.0}).metrics["ships"][0]
    paper = run_scenario(square_scenario()).metrics["ships"][0]
    assert soft["ce"] != pytest.approx(paper["ce"], rel=0.01)
    assert main(["study", "waypoint-square", "--kp", "2.5", "--kd", "3", "--out", str(tmp_path / "sq")]) == 0
    import json
    m = json.loads((tmp_path / "sq" / "metrics.json").read_text())
    assert {"ce", "mcte", "time_to_goal"} <= set(m)
    assert m["params"]["kp"] == 2.5 and m["params"]["kd"] == 3.0 and m["params"]["ilos_k"] == 0.05
    assert (tmp_path / "sq" / "waypoint_square.png").stat().st_size > 10000


@pytest.mark.parametrize("args,field", [(["--ilos-delta", "-1"], "delta"), (["--kd", "-0.5"], "kd"),
                                        (["--kp", "0"], "kp")])
def test_invalid_gains_exit_2_naming_the_field(tmp_path, capsys, args, field):
    out = tmp_path / "bad"
    assert main(["study", "waypoint-square", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0] and "Traceback" not in err[0]
    assert not out.exists()


def test_fewer_than_two_waypoints_is_an_error():
    with pytest.raises(ParameterError, match="waypoints"):
        from mmg_casadi.guidance.ilos import validate_waypoints
        validate_waypoints([(0.0, 0.0)])
    with pytest.raises(InputError, match=r"ships\[0\].waypoints"):
        scenario_from_dict({"settings": {"method": "none"},
                            "ships": [{"start": [0, 0], "heading": 0, "speed": 1, "waypoints": []}]})


def test_ship_stops_being_integrated_after_its_last_waypoint():
    lay = Layout(methods=("none",), max_path=2)
    ships = [dict(n_rpm=propeller_rpm_for_speed(1.0), path=[(0, 0), (20, 0)], start=(0, 0), heading=0.0,
                  speed=1.0)]
    tr = simulate(lay, initial_state(lay, ships), pack_params(lay, default_globals(t_max=100.0), ships))
    st = tr.state("status", 0)
    assert st[-1] == 1
    k = int(np.argmax(st == 1))
    assert tr.t[-1] == tr.t[k]  # the rollout ends with the last ship
    assert tr.final[0][S_["t_goal"]] == pytest.approx(tr.t[k])
    assert math.hypot(tr.final[0][S_["x"]] - 20, tr.final[0][S_["y"]]) <= 3.0


def test_ship_leaving_the_envelope_is_reported_diverged():
    lay = Layout(methods=("none",), max_path=2)
    ships = [dict(n_rpm=115.5, path=[(0, 0), (50, 0)], start=(0, 0), heading=0.0, speed=1.0)]
    x0 = initial_state(lay, ships)
    x0[lay.row("u", 0)] = 50.0  # far outside any sane envelope
    tr = simulate(lay, x0, pack_params(lay, default_globals(t_max=50.0), ships))
    assert tr.final[0][S_["status"]] == 2
    assert np.all(np.isfinite(tr.states))


def test_ship_circling_without_progress_is_reported_stalled():
    d = {"settings": {"method": "none", "t_max": 150.0, "goal_tolerance": 0.3},
         "ships": [{"name": "own", "start": [0, 0], "heading": 0.0, "speed": 1.0, "waypoints": [[1.0, 1.5]]}]}
    own = run_scenario(scenario_from_dict(d)).metrics["ships"][0]
    assert own["status"] == "stalled" and not own["reached_goal"]
    assert own["stalled_at"] is not None and len(own["stalled_at"]) == 2


def test_aux_history_is_per_ship_for_several_ships():
    """The recorded cross-track error of each ship equals the one recomputed from its own states."""
    from mmg_casadi.guidance.ilos import path_errors
    d = {"settings": {"method": "modified-vortex", "t_max": 60.0},
         "ships": [{"name": "a", "start": [0, 0], "heading": 0.0, "speed": 1.0, "waypoints": [[50, 0]]},
                   {"name": "b", "start": [50, 1], "heading": 180.0, "speed": 0.6, "waypoints": [[0, 1]]},
                   {"name": "c", "start": [25, -30], "heading": 90.0, "speed": 0.8, "waypoints": [[25, 30]]}]}
    r = run_scenario(scenario_from_dict(d))
    tr = r.trajectory
    mask = tr.sailing_mask()[:-1]
    for i, s in enumerate(r.scenario.ships):
        k = np.flatnonzero(mask[:, i])[::7]
        for kk in k:
            _, y_e = path_errors([tr.state("x", i)[kk], tr.state("y", i)[kk]], s.start, s.waypoints[0])
            assert tr.auxiliary("y_e", i)[kk] == pytest.approx(float(y_e), abs=1e-9)
