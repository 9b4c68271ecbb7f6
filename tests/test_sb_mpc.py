"""sb-mpc, the scenario-based MPC (Johansen, Perez & Cristofaro 2016): its reduced model, its decisions, the
closed loop and every place a method runs (simulate, the studies on both backends, environment 6, tune search)."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from mmg_casadi import cli
from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.errors import ParameterError
from mmg_casadi.guidance import methods
from mmg_casadi.guidance.sb_mpc import CODE, MEMORY, PARAMS
from mmg_casadi.guidance.sb_mpc_cost import LEVELS, N_BEHAVIOURS, hazard_function, plan_function
from mmg_casadi.guidance.sb_mpc_decision import decide, decision_at
from mmg_casadi.guidance.sb_mpc_model import (REDUCED_MODELS, _round4, _simulated_runs, identify_reduced_model,
                                              predict, reduced_model)
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.run import packaged_scenario, run_scenario
from mmg_casadi.scenarios.scenario import with_method


def _main(capsys, *argv) -> tuple[int, str]:
    code = cli.main([str(a) for a in argv])
    return code, capsys.readouterr().err


def _rows(path) -> list[dict]:
    with open(path, newline="", encoding="utf-8") as fh:
        return [{k: v for k, v in r.items() if k != "guidance_call_us"} for r in csv.DictReader(fh)]


# ---------------------------------------------------------------------------------------------- reduced model

@pytest.mark.parametrize("vessel", ["kcs", "kvlcc2"])
def test_the_stored_reduced_model_is_identified_again_from_the_mmg_model(vessel):
    fit = identify_reduced_model(vessel)
    assert [_round4(v) for v in fit["model"].as_vector()] == pytest.approx(REDUCED_MODELS[vessel].as_vector(),
                                                                           rel=2e-3)
    assert fit["rms_position"] < 0.5 and fit["max_position"] < 1.5  # L, over 21 runs of 20 L/U


def test_the_prediction_follows_the_mmg_closed_loop_through_a_60_degree_alteration():
    runs = _simulated_runs("kcs")
    course, speed, sim = next(r for r in runs if abs(math.degrees(r[0]) - 60.0) < 1e-9 and r[1] == 1.0)
    pred = predict(reduced_model("kcs"), psi0=0.0, u0=1.0, course=course, speed=speed, horizon=15.0, samples=15)
    k = (np.arange(1, 16) * 4) - 1  # the simulation's samples every 0.25 L/U at the prediction's 1, 2, ... 15
    err = np.hypot(pred["x"] - sim[k, 0], pred["y"] - sim[k, 1])
    assert err.max() < 1.0, err
    assert abs(math.degrees(pred["psi"][-1]) - 60.0) < 1.0


# -------------------------------------------------------------------------------------------------- decisions

def test_a_head_on_meeting_is_answered_by_a_starboard_alteration_of_at_least_30_degrees():
    d = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], [[25.0], [0.3]], [[-1.0], [0.0]])
    row = d.to_pandas().iloc[d.chosen]
    assert row["turn_deg"] >= 30.0 and row["level"] == 1.0
    assert d.hazard.size == N_BEHAVIOURS
    # the mirror-image alteration to port costs more (COLREG violation, port cost and K_chi)
    port = d.to_pandas().query("level == 1.0 and waypoint == False and held == False and turn_deg == @row.turn_deg * -1")
    assert float(port["hazard"].iloc[0]) > float(row["hazard"])


def test_a_give_way_ship_turns_to_starboard_and_passes_astern():
    # a ship crossing from starboard on a collision course (both at 1 U, 90 degrees)
    d = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], [[14.0], [14.0]], [[0.0], [-1.0]])
    row = d.to_pandas().iloc[d.chosen]
    assert row["turn_deg"] >= 30.0


def test_a_stand_on_ship_keeps_her_course_and_speed_while_the_give_way_ship_can_act():
    # a ship crossing from port on a collision course, far enough that she can still give way
    memory = {"sb_course": 0.0, "sb_state": CODE + 0, "sb_clock": 0.0}
    d = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], [[20.0], [-20.0]], [[0.0], [1.0]], memory=memory)
    row = d.to_pandas().iloc[d.chosen]
    assert row["turn_deg"] == 0.0 and row["level"] == 1.0
    # the same geometry 4 L off: she is free to act alone, and does
    d = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], [[3.0], [-3.0]], [[0.0], [1.0]], memory=memory)
    assert d.to_pandas().iloc[d.chosen]["turn_deg"] != 0.0


def test_the_hazard_ignores_a_neighbour_that_is_not_active():
    both = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], [[25.0, 40.0], [0.3, 30.0]], [[-1.0, 0.0], [0.0, -1.0]],
                  active=[1, 0])
    one = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], [[25.0], [0.3]], [[-1.0], [0.0]])
    assert np.array_equal(both.hazard, one.hazard)  # bit for bit: what the sparse step relies on


def test_land_ahead_makes_the_behaviours_that_reach_it_the_most_hazardous():
    shore = [[12.0], [-50.0], [12.0], [50.0]]  # a coast across the course, 12 L ahead
    d = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], np.zeros((2, 0)), np.zeros((2, 0)), walls=shore)
    df = d.to_pandas().query("level == 1.0 and waypoint == False and held == False")
    straight, abeam = df.query("turn_deg == 0.0")["hazard"].iloc[0], df.query("turn_deg == 90.0")["hazard"].iloc[0]
    assert straight > abeam + 10.0
    assert abs(d.to_pandas().iloc[d.chosen]["turn_deg"]) > 59.0


def test_the_decision_skips_the_reduced_levels_only_when_they_cannot_win():
    """The step evaluates the reduced propulsion levels only when needed; its choice is the argmin over every
    behaviour, bit for bit, in situations where they are skipped and where one of them wins."""
    rng = np.random.default_rng(5)
    used = set()
    for _ in range(30):
        m = int(rng.integers(1, 4))
        pos = rng.uniform(-15, 15, (2, m))
        vel = rng.uniform(-1, 1, (2, m))
        d = decide([0.0, 0.0], [1.0, 0.0], 0.0, [60.0, 0.0], pos, vel,
                   memory={"sb_course": 0.0, "sb_state": CODE + float(rng.integers(3)), "sb_clock": 0.0})
        plan = plan_function(m, PARAMETERS["sb_mpc_samples"].default, PARAMETERS["sb_mpc_substeps"].default)
        course, level, _ = (float(v) for v in np.array(plan(1, [9.0, 0, 0], *d.inputs)).ravel())
        row = d.to_pandas().iloc[d.chosen]
        assert math.isclose(course, math.radians(row["turn_deg"]), abs_tol=1e-12) and LEVELS[int(level)] == row["level"]
        used.add(row["level"] < 1.0)
    assert used == {True, False}  # both cases happened


def test_the_hazard_function_is_one_compiled_loop_over_behaviours_and_neighbours():
    small, large = (hazard_function(m, 15, 2) for m in (2, 13))
    # the code of a pair and of a behaviour's prediction is written once: the Function grows by far less than
    # the number of pairs
    assert large.n_nodes() < 2 * small.n_nodes()


# ------------------------------------------------------------------------------------------ the registered method

def test_every_parameter_is_in_the_table_with_a_source_and_refused_without_the_method():
    for p in PARAMS:
        q = PARAMETERS[p.name]
        assert q.group == "sb-mpc" and q.source and q.meaning
    assert methods.owners("sb_mpc_d_safe") == ("sb-mpc",)
    with pytest.raises(ParameterError, match="sb_mpc_d_safe"):
        methods.check_used({"sb_mpc_d_safe": 9.0}, ["colregs-vortex"])
    methods.check_used({"sb_mpc_d_safe": 9.0}, ["sb-mpc", "none"])


def test_mixed_hulls_with_sb_mpc_are_refused_in_one_line():
    from mmg_casadi.closed_loop.step import build_closed_loop_step
    with pytest.raises(ParameterError, match="vessels"):
        build_closed_loop_step(Layout(("sb-mpc", "sb-mpc"), vessels=("kcs", "kvlcc2")))


def test_head_on_in_the_closed_loop_both_ships_pass_port_to_port_beyond_a_nautical_mile(tmp_path, capsys):
    code, err = _main(capsys, "simulate", "head_on", "--method", "sb-mpc", "--out", tmp_path)
    assert code == 0, err
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert not m["collision"] and all(s["reached_goal"] for s in m["ships"])
    pair = m["pairs"][0]
    assert pair["min_distance"] > 8.05  # 1 nm of the 230 m KCS
    enc = pair["encounters"]["a"][0]
    assert enc["role"] == "head-on" and enc["rules"]["14"]["verdict"], enc["rules"]["14"]
    assert enc["rules"]["8"]["in_ample_time"] and enc["rules"]["8"]["safe_distance"], enc["rules"]["8"]


@pytest.mark.xfail(strict=True, reason="measured under the published profile (scorer version 5): the starboard "
                   "alteration reaches 27.9° of course change, under its 30° readily apparent threshold, so Rule 8 "
                   "is broken although Rule 14 is kept and the ships pass at 10.55 L")
def test_head_on_in_the_closed_loop_keeps_rule_8_under_the_published_profile(tmp_path, capsys):
    code, err = _main(capsys, "simulate", "head_on", "--method", "sb-mpc", "--out", tmp_path)
    assert code == 0, err
    enc = json.loads((tmp_path / "metrics.json").read_text())["pairs"][0]["encounters"]["a"][0]
    assert enc["compliant"], enc["rules"]["8"]


def test_the_behaviour_is_held_between_decisions():
    res = run_scenario(with_method(packaged_scenario("crossing"), "sb-mpc"), params={"t_max": 30.0})
    traj = res.trajectory
    lay = traj.layout
    clock = traj.state("sb_clock", 0)
    engaged = traj.state("sb_state", 0) > CODE / 2
    ordered = traj.state("sb_course", 0)
    interval = PARAMETERS["sb_mpc_interval"].default
    # while engaged the course ordered changes only at a decision (the clock restarts at one step)
    steps = np.flatnonzero(engaged[1:] & engaged[:-1])
    changed = steps[ordered[steps + 1] != ordered[steps]]
    assert changed.size and np.allclose(clock[changed + 1], PARAMETERS["dt"].default)
    assert clock[engaged].max() <= interval + 2 * PARAMETERS["dt"].default
    assert set(MEMORY) <= set(lay.memory)


def test_a_decision_of_a_simulated_run_can_be_drawn(tmp_path):
    import matplotlib
    matplotlib.use("Agg")
    res = run_scenario(with_method(packaged_scenario("head_on"), "sb-mpc"), params={"t_max": 20.0})
    d = decision_at(res, 12.0)
    fig = d.plot()
    fig.savefig(tmp_path / "d.png")
    assert (tmp_path / "d.png").stat().st_size > 10_000
    df = d.to_pandas()
    assert len(df) == N_BEHAVIOURS and df["chosen"].sum() == 1


def test_study_statistics_runs_sb_mpc_paired_with_the_reactive_methods(tmp_path, capsys):
    code, err = _main(capsys, "study", "statistics", "--methods", "sb-mpc,colregs-vortex", "--runs", "3", "--envs",
                      "1", "--workers", "1", "--set", "sb_mpc_d_safe=9", "--out", tmp_path)
    assert code == 0, err
    rows = _rows(tmp_path / "runs.csv")
    assert {r["method"] for r in rows} == {"sb-mpc", "colregs-vortex"} and len(rows) == 6
    assert json.loads((tmp_path / "runs.params.json").read_text())["params"]["sb_mpc_d_safe"] == 9.0


@pytest.mark.slow
def test_study_statistics_local_and_ray_give_the_same_rows(tmp_path, capsys):
    pytest.importorskip("ray")
    common = ["study", "statistics", "--methods", "sb-mpc", "--runs", "3", "--envs", "1", "--workers", "1"]
    for backend in ("local", "ray"):
        code, err = _main(capsys, *common, "--backend", backend, "--out", tmp_path / backend)
        assert code == 0, err
    key = lambda r: int(r["run"])  # noqa: E731
    assert sorted(_rows(tmp_path / "local" / "runs.csv"), key=key) == sorted(_rows(tmp_path / "ray" / "runs.csv"),
                                                                             key=key)


@pytest.mark.slow
def test_targets_hold_and_environment_6(tmp_path, capsys):
    code, err = _main(capsys, "study", "statistics", "--methods", "sb-mpc", "--runs", "3", "--envs", "1,6",
                      "--targets", "hold", "--workers", "1", "--out", tmp_path)
    assert code == 0, err
    rows = _rows(tmp_path / "runs.csv")
    assert {int(r["environment"]) for r in rows} == {1, 6}
    assert not any(r["failure_mechanism"] == "grounding" for r in rows)


@pytest.mark.slow
def test_study_imazu_encounters_and_land(tmp_path, capsys):
    code, err = _main(capsys, "generate", "--situations", "3", "--seed", "0", "--out", tmp_path / "set")
    assert code == 0, err
    for study, *args in (("imazu",), ("encounters", tmp_path / "set"), ("land",)):
        code, err = _main(capsys, "study", study, *args, "--methods", "sb-mpc", "--out", tmp_path / study)
        assert code == 0, (study, err)
    res = json.loads((tmp_path / "imazu" / "metrics.json").read_text())["results"]["hold"]["sb-mpc"]
    assert len(res["cases"]) == 22 and res["safe"] == 22


@pytest.mark.slow
def test_tune_search_over_the_weights(tmp_path, capsys):
    code, err = _main(capsys, "tune", "search", "--method", "sb-mpc", "--search", "sb_mpc_d_safe=8:11",
                      "--search", "sb_mpc_kappa_so=2:20", "--design", "2", "--holdout", "2", "--candidates", "1",
                      "--refine", "0", "--envs", "1", "--workers", "1", "--out", tmp_path)
    assert code == 0, err
    report = json.loads((tmp_path / "report.json").read_text())
    assert report["method"] == "sb-mpc" and len(report["candidates"]) == 2
    assert report["candidates"][0]["sb_mpc_d_safe"] == PARAMETERS["sb_mpc_d_safe"].default
