"""Issue 48: target behaviours and the own ship's perception (AIS, radar, tracker) in the compiled step."""

import math

import numpy as np
import pytest

from mmg_casadi.closed_loop.layout import SHIP_STATE
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import simulate
from mmg_casadi.errors import InputError, ParameterError, ScenarioError
from mmg_casadi.montecarlo.execution import TIMING_COLUMNS, run_batch, sampled_scenario
from mmg_casadi.montecarlo.study import check_study_args
from mmg_casadi.params import resolve
from mmg_casadi.perception import rng, sensors
from mmg_casadi.perception.layer import run_seed
from mmg_casadi.scenarios.scenario import dump_scenario, scenario_from_dict
from mmg_casadi.traffic.mix import mix_weights, parse_targets
from mmg_casadi.traffic.sample import apply_behaviours, draw_behaviours

PERFECT_SENSORS = {"ais_interval_scale": 0.0, "ais_latency_s": 0.0, "ais_dropout": 0.0, "ais_position_sigma_m": 0.0,
                   "ais_sog_sigma_kn": 0.0, "ais_cog_sigma_deg": 0.0}
"""Every AIS report at every step, without noise, delay or loss."""
PERFECT_RADAR = {"radar_range_sigma_m": 0.0, "radar_bearing_sigma_deg": 0.0}


def _run(d, params=None):
    pr = build_problem(scenario_from_dict(d), params)
    return simulate(pr.layout, pr.x0, pr.p)


# ------------------------------------------------------------------------------------------------ the generator

def test_generator_in_floating_point_equals_the_integer_recursion():
    for seed in range(5):
        s = rng.seed_state([seed, 1])
        si = [int(v) for v in s]
        for _ in range(2000):
            s, u = rng.mrg_next(s)
            si, ui = rng.mrg_next_int(si)
            assert u == ui and 0.0 < u < 1.0
        assert [int(v) for v in s] == si


def test_generator_uniforms_and_normals_have_their_moments():
    s, us = rng.seed_state([7]), []
    for _ in range(20000):
        s, u = rng.mrg_next(s)
        us.append(float(u))
    us = np.array(us)
    z = np.array([rng.normals(a, b) for a, b in zip(us[0::2], us[1::2])]).ravel()
    assert abs(us.mean() - 0.5) < 0.01 and abs(us.var() - 1 / 12) < 0.003
    assert abs(z.mean()) < 0.03 and abs(z.std() - 1.0) < 0.03


# ------------------------------------------------------------------------------------------------ sensors

def test_ais_intervals_follow_itu_r_m1371_tables():
    assert [sensors.ais_interval_s(v, 0.0, 0.0) for v in (5.0, 14.0, 18.0, 23.0, 30.0)] == [10.0, 10.0, 6.0, 6.0, 2.0]
    assert [sensors.ais_interval_s(v, 1.0, 0.0) for v in (5.0, 18.0, 30.0)] == [10.0 / 3.0, 2.0, 2.0]
    assert [sensors.ais_interval_s(v, 0.0, 1.0) for v in (1.0, 2.0, 12.0)] == [180.0, 180.0, 30.0]


def _two_ships(target_speed=0.5, **extra):
    return {"settings": {"method": "modified-vortex", "t_max": 30.0},
            "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[70, 0]],
                       "method": "none"},
                      {"name": "tgt", "start": [10, 20], "heading": 0, "speed": target_speed,
                       "waypoints": [[80, 20]], **extra}]}


@pytest.mark.parametrize("speed, interval_s", [(0.5, 10.0), (0.8, 6.0), (1.0, 2.0)])
def test_ais_reports_arrive_at_the_table_interval(speed, interval_s):
    """A Class A ship on a straight course at 12, 19 and 24 kn (the KCS's 0.5, 0.8, 1.0 U) reports every 10, 6, 2 s;
    without loss every report is taken, its time stamp exactly one interval after the previous one."""
    tr = _run(_two_ships(speed), {"perception": "ais", "ais_dropout": 0.0})
    stamps = np.unique(tr.state("ais_t", 1))
    stamps = stamps[stamps > -1e8]
    from mmg_casadi.vessel.library import load_vessel
    ship = load_vessel().ship
    T = interval_s / (ship.L / ship.U_design)
    steps = np.diff(stamps)
    assert len(stamps) > 5
    np.testing.assert_allclose(steps[steps < 1.5 * T], T, rtol=1e-9)  # reports in consecutive steps
    assert np.all(np.abs(steps / T - np.round(steps / T)) < 1e-9)  # a step longer than T skips whole intervals


def test_ais_dropout_loses_that_share_of_the_reports():
    full = _run(_two_ships(1.0), {"perception": "ais", "ais_dropout": 0.0})
    lossy = _run(_two_ships(1.0), {"perception": "ais", "ais_dropout": 0.5})
    n_full = len(np.unique(full.state("ais_t", 1)))
    n_lossy = len(np.unique(lossy.state("ais_t", 1)))
    assert 0.3 < n_lossy / n_full < 0.7


def test_sensor_noise_has_the_stated_spread():
    """AIS position errors of the reports taken (noise 50 m, no latency) have a standard deviation of 50 m."""
    from mmg_casadi.vessel.library import load_vessel
    L = load_vessel().ship.L
    tr = _run(_two_ships(1.0), {"perception": "ais", "ais_dropout": 0.0, "ais_latency_s": 0.0,
                                "ais_position_sigma_m": 50.0})
    t_rep = tr.state("ais_t", 1)
    new = np.flatnonzero(np.diff(t_rep) != 0) + 1  # samples after a step that took a report
    x_tx = tr.state("x", 1)[new - 1] - tr.state("u", 1)[new - 1] * (tr.t[new - 1] - t_rep[new])  # on course 0
    err = tr.state("ais_x", 1)[new] - x_tx
    assert len(err) > 20 and 0.6 < np.std(err) * L / 50.0 < 1.4


# ------------------------------------------------------------------------------------------------ perfect sensors

@pytest.mark.parametrize("mode", ["ais", "ais-radar"])
def test_zero_noise_without_dropouts_equals_the_perfect_run_to_the_bit(mode):
    """Every report at every step without noise, delay or loss: the own ship's method sees the truth, and the run's
    true states are those of the run with perfect knowledge, bit for bit (radar plots without noise too)."""
    sc = sampled_scenario(2, "modified-vortex", 0)
    ref = simulate(*_problem(sc, {}))
    tr = simulate(*_problem(sc, {"perception": mode, **PERFECT_SENSORS, **(PERFECT_RADAR if "radar" in mode else {})}))
    n = len(SHIP_STATE)
    assert tr.states.shape[:2] == ref.states.shape[:2]
    assert np.array_equal(tr.states[:, :, :n], ref.states[:, :, :n])
    assert np.array_equal(tr.aux, ref.aux, equal_nan=True)


def _problem(sc, params):
    pr = build_problem(sc, params)
    return pr.layout, pr.x0, pr.p


def test_zero_noise_study_rows_equal_the_perfect_ones():
    perfect = run_batch(2, "velocity-obstacle", range(4))
    seen = run_batch(2, "velocity-obstacle", range(4), params={"perception": "ais-radar", **PERFECT_SENSORS,
                                                                **PERFECT_RADAR})
    for a, b in zip(perfect, seen):
        assert {k: str(v) for k, v in a.items() if k not in TIMING_COLUMNS + ("perception_error",)} == \
               {k: str(v) for k, v in b.items() if k not in TIMING_COLUMNS + ("perception_error",)}
        assert math.isnan(a["perception_error"]) and (b["perception_error"] == 0.0 or b["colregs_risky"] == 0)


def test_noisy_perception_is_deterministic_under_the_seed_and_tracks_closely():
    a = run_batch(2, "modified-vortex", [0, 1], params={"perception": "ais-radar"})
    b = run_batch(2, "modified-vortex", [0, 1], params={"perception": "ais-radar"})
    c = run_batch(2, "modified-vortex", [0, 1], params={"perception": "ais-radar", "perception_seed": 1})
    assert [r["perception_error"] for r in a] == [r["perception_error"] for r in b]
    assert [r["perception_error"] for r in a] != [r["perception_error"] for r in c]
    errors = [r["perception_error"] for r in a + c if not math.isnan(r["perception_error"])]
    assert errors and max(errors) < 0.05  # L: the fused track within about 10 m of the truth on average
    assert run_seed(0, 2, 0) != run_seed(0, 2, 1)


def test_radar_tracker_converges_on_a_steady_target():
    tr = _run(_two_ships(0.8), {"perception": "radar", "radar_p_detect": 1.0})
    known = tr.state("trk_known", 1) > 0.5
    assert known[1]  # detected at the first scan (20 L is well inside 11 NM)
    v_err = np.hypot(tr.state("trk_vx", 1)[-40:] - 0.8, tr.state("trk_vy", 1)[-40:])
    assert np.mean(v_err) < 0.06  # U: radar alone, 0.5 deg of bearing noise at 20-40 L


# ------------------------------------------------------------------------------------------------ behaviours

def _crossing(**extra):
    """The target crosses from the own ship's port side, so she gives way; the own ship holds."""
    return {"settings": {"method": "modified-vortex", "t_max": 60.0},
            "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[70, 0]],
                       "method": "none"},
                      {"name": "tgt", "start": [30, -30], "heading": 90, "speed": 1.0, "waypoints": [[30, 40]],
                       **extra}]}


def _onset(tr):
    d = np.hypot(tr.state("x", 0) - tr.state("x", 1), tr.state("y", 0) - tr.state("y", 1))
    return tr.t[np.argmax(d < 15.0)]  # R_safe


def test_avoid_behaviour_is_the_method_itself():
    a, b = _run(_crossing()), _run(_crossing(behaviour="avoid"))
    n = len(SHIP_STATE)
    assert np.array_equal(a.states[:, :, :n], b.states[:, :, :n])


def test_late_give_way_ship_turns_at_the_drawn_delay():
    prompt = _run(_crossing())
    for delay in (2.0, 4.0):
        late = _run(_crossing(behaviour="late", late_delay=delay))
        t_enter = _onset(late)
        t_act = late.t[np.argmax(late.auxiliary("reactive", 1) > 0.5)]
        assert t_act == pytest.approx(t_enter + delay)
        psi = late.state("psi", 1)
        k = int(np.searchsorted(late.t, t_act))
        assert np.max(np.abs(psi[:k] - psi[0])) < 1e-6 < abs(psi[k + 4] - psi[0])  # she holds until then, then turns
    assert prompt.t[np.argmax(prompt.auxiliary("reactive", 1) > 0.5)] == pytest.approx(_onset(prompt))


def test_holding_ship_keeps_course_and_speed():
    tr = _run(_crossing(behaviour="hold"))
    sails = tr.state("status", 1) == 0  # until a contact ends her voyage (then she is held, engine stopped)
    assert sails.sum() > 100
    assert np.ptp(tr.state("psi", 1)[sails]) < 1e-9 and np.ptp(tr.state("u", 1)[sails]) < 1e-9
    assert tr.auxiliary("reactive", 1).max() == 0.0


def test_wrong_way_ship_turns_to_port_in_a_head_on_risk():
    d = {"settings": {"method": "modified-vortex", "t_max": 60.0},
         "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[80, 0]],
                    "method": "none"},
                   {"name": "tgt", "start": [60, 1], "heading": 180, "speed": 1.0, "waypoints": [[-20, 1]],
                    "behaviour": "wrong", "wrong_turn": 40.0}]}
    tr = _run(d)
    on = tr.state("wrong_on", 1) > 0.5
    k = int(np.argmax(on))
    assert on.any() and _onset(tr) <= tr.t[k]
    psi = np.degrees(np.unwrap(tr.state("psi", 1)))
    assert np.degrees(tr.state("wrong_psi", 1)[k]) == pytest.approx(psi[k - 1] - 40.0)
    assert psi[k:k + 40].min() < 150.0  # to port: her heading falls from 180 deg
    assert not on[-1]  # back on her route once the risk is past
    # the same ship with her method turns to starboard (her heading grows)
    d["ships"][1].pop("behaviour"), d["ships"][1].pop("wrong_turn")
    assert np.degrees(np.unwrap(_run(d).state("psi", 1))).max() > 185.0


def test_intent_change_alters_course_near_the_drawn_time():
    d = {"settings": {"method": "modified-vortex", "t_max": 80.0},
         "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[80, 0]],
                    "method": "none"},
                   {"name": "tgt", "start": [0, 30], "heading": 0, "speed": 0.8, "waypoints": [[70, 30]]}]}
    apply_behaviours(d["ships"], [{"kind": "intent", "time": 20.0, "course_deg": 45.0}], goal_tolerance=3.0,
                     waypoint=True)
    tr = _run(d)
    psi = np.degrees(tr.state("psi", 1))
    t_turn = tr.t[np.argmax(np.abs(psi) > 2.0)]
    assert 19.0 <= t_turn <= 23.0 and psi[-1] == pytest.approx(45.0, abs=1.0)
    d["ships"][1]["speeds"] = [0.8, 0.4]
    d["ships"][1]["waypoints"] = [d["ships"][1]["waypoints"][0], [70.0, 30.0]]
    slow = _run(d)
    assert slow.state("u", 1)[-1] < 0.5 and slow.state("u", 1)[int(np.searchsorted(slow.t, 18.0))] > 0.75


def test_replayed_target_is_perceived_like_any_ship():
    d = _two_ships()
    d["ships"][1] = {"name": "tgt", "track": {"t": [-1.0, 40.0], "x": [10.0, 40.0], "y": [20.0, 20.0]}}
    tr = _run(d, {"perception": "ais-radar"})
    assert tr.state("trk_known", 1)[-1] == 1.0
    assert abs(tr.state("seen_x", 1)[-1] - tr.state("x", 1)[-2]) < 0.2


# ------------------------------------------------------------------------------------------------ the mix

def test_mix_values_are_checked_with_one_line_errors():
    assert parse_targets("mix:avoid=0.6,hold=0.3,wrong=0.1") == "mix:avoid=0.6,hold=0.3,wrong=0.1"
    for bad in ("mix:avoid=0.6,hold=0.3", "mix:avoid=0.5,fast=0.5", "mix:", "sometimes", "mix:avoid=1,avoid=0"):
        with pytest.raises(InputError) as e:
            parse_targets(bad)
        assert "\n" not in str(e.value) and "targets" in str(e.value)
    with pytest.raises(ParameterError):
        resolve({"targets": "mix:avoid=2"})


def test_mix_draws_follow_the_probabilities_and_are_deterministic():
    params = {**resolve(), "targets": "mix:avoid=0.6,hold=0.3,wrong=0.1"}
    kinds = [b["kind"] for r in range(300) for b in draw_behaviours(5, r, 0, 9, params)]
    share = {k: kinds.count(k) / len(kinds) for k in ("avoid", "hold", "wrong")}
    assert abs(share["avoid"] - 0.6) < 0.03 and abs(share["hold"] - 0.3) < 0.03 and abs(share["wrong"] - 0.1) < 0.02
    assert draw_behaviours(5, 3, 0, 9, params) == draw_behaviours(5, 3, 0, 9, params)
    late = {**resolve(), "targets": "mix:late=1"}
    delays = [b["delay"] for b in draw_behaviours(5, 0, 0, 9, late)]
    assert all(2.0 <= d <= 8.0 for d in delays) and mix_weights("mix:late=1")["late"] == 1.0


@pytest.mark.parametrize("pure", ["avoid", "hold"])
def test_a_mix_of_one_behaviour_equals_the_pure_study(pure):
    a = run_batch(2, "velocity-obstacle", range(3), params={"targets": pure})
    b = run_batch(2, "velocity-obstacle", range(3), params={"targets": f"mix:{pure}=1"})
    skip = TIMING_COLUMNS + ("target_behaviours",)
    assert [{k: str(v) for k, v in r.items() if k not in skip} for r in a] == \
           [{k: str(v) for k, v in r.items() if k not in skip} for r in b]
    assert a[0]["target_behaviours"] == b[0]["target_behaviours"] == ";".join([pure] * 3)


def test_a_mixed_run_records_each_target_and_replays_from_its_file():
    params = {"targets": "mix:avoid=0.4,hold=0.2,late=0.2,wrong=0.1,intent=0.1", "perception": "ais"}
    row = run_batch(3, "modified-vortex", [4], params=params)[0]
    assert len(row["target_behaviours"].split(";")) == row["n_ships"] - 1
    sc = sampled_scenario(3, "modified-vortex", 4, params=params)
    again = scenario_from_dict(__import__("tomllib").loads(dump_scenario(sc)))
    assert again == sc and again.settings.params["perception_seed"] == sc.settings.params["perception_seed"]


def test_inputs_that_do_not_apply_are_refused():
    with pytest.raises(InputError, match="params.target_late_delay_low"):
        check_study_args(runs=2, envs="1", methods="none", params={"target_late_delay_low": 1.0})
    with pytest.raises(InputError, match="params.ais_dropout"):
        check_study_args(runs=2, envs="1", methods="none", params={"ais_dropout": 0.2})
    with pytest.raises(InputError, match="params.radar_p_detect"):
        check_study_args(runs=2, envs="1", methods="none", params={"perception": "ais", "radar_p_detect": 0.5})
    d = _crossing(behaviour="late")
    with pytest.raises(ScenarioError, match=r"ships\[1\].late_delay"):
        scenario_from_dict(d)
    d = _crossing(behaviour="hold", wrong_turn=30.0)
    with pytest.raises(ScenarioError, match=r"ships\[1\].wrong_turn"):
        scenario_from_dict(d)
    d = _crossing()
    d["ships"][0]["behaviour"] = "hold"
    with pytest.raises(ScenarioError, match=r"ships\[0\].behaviour"):
        scenario_from_dict(d)
