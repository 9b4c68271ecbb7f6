"""Tests of the Monte Carlo study: reproducibility across executors, resume, classification, metrics, input.

Environment 1 with the modified sink-vortex APF (a ~1 s compile) and hand-built scenarios with method "none";
everything runs in well under a minute on 2 cores apart from the Ray start-up.
"""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.closed_loop.problem import ClosedLoopModel
from mmg_casadi.closed_loop.state import initial_state
from mmg_casadi.params import resolve
from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.batching import BatchTask, LocalExecutor, RayExecutor, plan_batches
from mmg_casadi.closed_loop.outcome import run_outcome
from mmg_casadi.montecarlo.execution import TIMING_COLUMNS, run_batch, run_scenarios, sampled_scenario
from mmg_casadi.montecarlo.study import run_study
from mmg_casadi.montecarlo.results import RUN_COLUMNS, ResultsTable
from mmg_casadi.montecarlo.sampling import sample_scenario
from mmg_casadi.scenarios.scenario import scenario_from_dict
from mmg_casadi.scenarios.run import run_scenario

METHOD = "modified-vortex"
RUNS = [0, 1, 2, 3]
SEED = 7


def _comparable(rows):
    """Rows keyed by (env, method, run) without the timing columns; nan replaced so that == works."""
    out = {}
    for r in rows:
        key = (r["environment"], r["method"], r["run"])
        out[key] = {c: ("nan" if isinstance(r[c], float) and math.isnan(r[c]) else r[c])
                    for c in RUN_COLUMNS if c not in TIMING_COLUMNS}
    return out


def _tasks(batch=2):
    return [BatchTask(1, METHOD, tuple(RUNS[i:i + batch]), SEED) for i in range(0, len(RUNS), batch)]


@pytest.fixture(scope="module")
def reference_rows():
    rows = run_batch(1, METHOD, RUNS, SEED)
    assert [r["run"] for r in rows] == RUNS
    for r in rows:
        assert set(r) == set(RUN_COLUMNS)
        assert r["seed"] == SEED and r["n_ships"] == 3 and r["n_obstacles"] == 1
        assert r["guidance_call_us"] > 0
    return rows


def test_same_seed_same_scenario():
    assert sample_scenario(1, 3, SEED) == sample_scenario(1, 3, SEED)
    assert sampled_scenario(1, METHOD, 3, SEED) == sampled_scenario(1, METHOD, 3, SEED)
    assert sample_scenario(1, 3, SEED) != sample_scenario(1, 3, SEED + 1)


def test_rows_reproducible_with_local_executor(reference_rows):
    ref = _comparable(reference_rows)
    assert _comparable(run_batch(1, METHOD, RUNS, SEED)) == ref
    for workers in (1, 2):
        rows = [row for _task, batch in LocalExecutor(workers).run(_tasks()) for row in batch]
        # batches of 2 instead of 4: a run's row does not depend on the other runs of its batch
        assert _comparable(rows) == ref, f"workers={workers}"


def test_rows_reproducible_with_ray(reference_rows):
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    try:
        with RayExecutor() as ex:
            rows = [row for _task, batch in ex.run(_tasks()) for row in batch]
        assert ray.is_initialized()  # the executor does not shut down a Ray it did not start
    finally:
        ray.shutdown()
    assert _comparable(rows) == _comparable(reference_rows)


def test_plan_batches_skips_done_and_interleaves():
    tasks = plan_batches((1, 2), ("a", "b"), 3, done={(1, "a", 1), (2, "b", 0)}, batch_size=2)
    assert [(t.environment, t.method, t.runs) for t in tasks] == [
        (1, "a", (0, 2)), (1, "b", (0, 1)), (2, "a", (0, 1)), (2, "b", (1, 2)), (1, "b", (2,)), (2, "a", (2,))]


def _raw_keys(path):
    with open(path, newline="") as f:
        return [(r["environment"], r["method"], r["run"]) for r in csv.DictReader(f)]


def test_resume_equals_uninterrupted_study(tmp_path):
    common = dict(envs="1", methods=(METHOD,), base_seed=SEED, workers=1, progress=False, batch_size=2)
    resumed = tmp_path / "resumed"
    run_study(resumed, runs=3, **common)  # "killed" after 3 runs
    assert len(ResultsTable(resumed / "runs.csv").read()) == 3
    summary = run_study(resumed, runs=6, **common)
    fresh = tmp_path / "fresh"
    run_study(fresh, runs=6, **common)

    keys = _raw_keys(resumed / "runs.csv")
    assert len(keys) == 6 and len(set(keys)) == 6
    assert _comparable(ResultsTable(resumed / "runs.csv").read()) == _comparable(ResultsTable(fresh / "runs.csv").read())
    assert summary.rows[0]["runs"] == 6
    for name in ("summary.csv", "summary.md", "statistics.png", "metrics.json"):
        assert (resumed / name).is_file(), name
    # running again simulates nothing and changes nothing
    before = (resumed / "runs.csv").read_bytes()
    run_study(resumed, runs=6, **common)
    assert (resumed / "runs.csv").read_bytes() == before


def test_resume_refuses_another_seed_or_horizon(tmp_path):
    run_study(tmp_path, runs=1, envs="1", methods=(METHOD,), base_seed=SEED, workers=1, progress=False)
    with pytest.raises(InputError) as err:
        run_study(tmp_path, runs=1, envs="1", methods=(METHOD,), base_seed=SEED + 1, workers=1, progress=False)
    assert err.value.field == "base_seed"
    with pytest.raises(InputError) as err:
        run_study(tmp_path, runs=1, envs="1", methods=(METHOD,), base_seed=SEED, params={"t_max": 100.0},
                  workers=1, progress=False)
    assert err.value.field == "params.t_max"
    with pytest.raises(InputError) as err:
        run_study(tmp_path, runs=1, envs="1", methods=(METHOD,), base_seed=SEED, params={"r_safe": 3.0},
                  workers=1, progress=False)
    assert err.value.field == "params.r_safe" and "15.0" in str(err.value)


def _ship(name, start, heading, goal, speed=1.0):
    return {"name": name, "start": list(start), "heading": heading, "speed": speed, "waypoints": [list(goal)]}


def _scenario(ships, obstacles=(), t_max=300.0, method="none"):
    return scenario_from_dict({"settings": {"method": method, "t_max": t_max}, "ships": ships,
                               "obstacles": [{"position": list(p), "radius": 0.5} for p in obstacles]})


@pytest.fixture(scope="module")
def hand_built():
    scs = {
        "head_on": _scenario([_ship("own", (0, 0), 0.0, (50, 0)), _ship("target", (50, 0), 180.0, (0, 0))]),
        "obstacle": _scenario([_ship("own", (0, 0), 0.0, (50, 0))], obstacles=[(25, 0)]),
        "timeout": _scenario([_ship("own", (0, 0), 0.0, (50, 0))], t_max=10.0),
        "success": _scenario([_ship("own", (0, 0), 0.0, (50, 0))]),
    }
    rows = run_scenarios(list(scs.values()), time_guidance_calls=False)
    return dict(zip(scs, rows))


def test_forced_head_on_collision(hand_built):
    r = hand_built["head_on"]
    assert not r["success"] and not r["fleet_success"]
    assert r["failure"] == "collision" and r["failure_pair"] == "0-1"
    assert 15.0 < r["failure_time"] < 35.0
    assert r["min_distance"] < 2.0


def test_collision_with_static_obstacle(hand_built):
    r = hand_built["obstacle"]
    assert r["failure"] == "collision" and r["failure_pair"] == "0-obs0" and not r["success"]


def test_timeout(hand_built):
    r = hand_built["timeout"]
    assert r["failure"] == "timeout" and not r["success"] and not r["fleet_success"]
    assert r["failure_time"] == pytest.approx(10.0)
    assert math.isnan(r["time_to_goal"])


def test_success(hand_built):
    r = hand_built["success"]
    assert r["success"] and r["fleet_success"] and r["failure"] == "" and r["failure_pair"] == ""
    assert 40.0 < r["time_to_goal"] < 60.0
    assert r["fleet_time_to_goal"] == r["time_to_goal"]
    assert r["ce"] >= 0 and r["mcte"] >= 0
    assert math.isnan(r["min_distance"])  # nobody else around


def _final_state(layout, **own):
    x = initial_state(layout, [{"speed": 1.0, "start": (0.0, 0.0), "heading": 0.0, "path": [(0, 0), (80, 0)]}])
    x[0] = 300.0
    for k, v in own.items():
        x[layout.row(k, 0)] = v
    return x


def classify(model, x):
    return run_outcome(model.layout, x, model.params)


def test_classify_stalled_diverged_from_final_state():
    layout = Layout(methods=("none",))
    model = ClosedLoopModel(layout, resolve())
    r = classify(model, _final_state(layout, t_best=200.0))
    assert r["failure"] == "stalled" and r["failure_time"] == 200.0
    assert classify(model, _final_state(layout, t_best=280.0))["failure"] == "timeout"
    assert classify(ClosedLoopModel(layout, resolve({"stall_window": 10.0})),
                    _final_state(layout, t_best=280.0))["failure"] == "stalled"
    r = classify(model, _final_state(layout, status=2.0))
    assert r["failure"] == "diverged" and math.isnan(r["ce"])
    r = classify(model, _final_state(layout, status=1.0, t_goal=90.0, ce_int=0.2 * math.radians(35) * 90.0,
                                     mcte_int=45.0))
    assert r["success"] and r["ce"] == pytest.approx(0.2) and r["mcte"] == pytest.approx(0.5)
    assert layout.ns == len(_final_state(layout)) - 1


def _own_mcte_from_states(res):
    """Own-ship MCTE of a run_scenario trajectory with y_e re-evaluated by the step at every stored state."""
    from trajectory_metrics import tracking_metrics
    from mmg_casadi.closed_loop.problem import build_problem
    from mmg_casadi.closed_loop.simulation import compiled_step
    pr = build_problem(res.scenario)
    layout, p, g = pr.layout, pr.p, pr.model.values
    tr = res.trajectory
    X = np.vstack([tr.t[None, :-1], tr.states[:-1].reshape(len(tr.t) - 1, -1).T])
    T = X.shape[1]
    _, aux = compiled_step(layout).map(T)(X, np.tile(p[:, None], (1, T)))
    y_e = np.array(aux)[2].reshape(T, layout.n_ships)[:, 0]
    reached = tr.state("status", 0)[1:] == 1
    m = tracking_metrics(tr.t[:-1], tr.state("delta", 0)[:-1], y_e, reached, delta_max=g["delta_max"])
    return m.mcte, y_e


def test_batch_ce_mcte_agree_with_run_scenario(reference_rows):
    checked = 0
    for row in reference_rows[:3]:
        res = run_scenario(sampled_scenario(1, METHOD, row["run"], SEED))
        own = res.metrics["ships"][0]
        assert own["reached_goal"] == row["success"] or own["collided"]
        if not own["reached_goal"]:
            continue
        assert row["time_to_goal"] == own["time_to_goal"]
        # one definition (the compiled accumulators): batch rows and single runs agree exactly
        assert row["ce"] == own["ce"] and row["mcte"] == own["mcte"], f"run {row['run']}"
        reached = [s for s in res.metrics["ships"] if s["reached_goal"]]
        assert row["fleet_ce"] == pytest.approx(np.mean([s["ce"] for s in reached]), rel=1e-12)
        # check against the trajectory definition (trapezoid of |delta| and |y_e| up to the goal)
        from trajectory_metrics import tracking_metrics
        tr = res.trajectory
        ref = tracking_metrics(tr.t[:-1], tr.state("delta", 0)[:-1], tr.auxiliary("y_e", 0),
                               tr.state("status", 0)[1:] == 1, delta_max=math.radians(35.0))
        assert row["ce"] == pytest.approx(ref.ce, rel=0.02), f"run {row['run']} CE"
        mcte_ref, y_e = _own_mcte_from_states(res)
        assert row["mcte"] == pytest.approx(mcte_ref, rel=0.02), f"run {row['run']} MCTE"
        np.testing.assert_allclose(res.trajectory.auxiliary("y_e", 0), y_e, atol=1e-9)
        checked += 1
    assert checked >= 2


@pytest.mark.parametrize("kwargs, field", [
    ({"runs": 0}, "runs"),
    ({"runs": 2.5}, "runs"),
    ({"backend": "x"}, "backend"),
    ({"methods": ("modified-vortex", "nope")}, "methods"),
    ({"envs": "0-2"}, "envs"),
    ({"envs": (7,)}, "envs"),
    ({"base_seed": -1}, "base_seed"),
    ({"workers": 0}, "workers"),
    ({"params": {"kd": -1.0}}, "params.kd"),
    ({"params": {"nope": 1.0}}, "params.nope"),
    ({"address": "x:1"}, "address"),
])
def test_bad_input_names_the_field(tmp_path, kwargs, field):
    out = tmp_path / "out"
    with pytest.raises(InputError) as err:
        run_study(out, progress=False, **kwargs)
    assert err.value.field == field
    assert not out.exists()


def test_cli_statistics(tmp_path, capsys):
    from mmg_casadi.cli import main
    out = tmp_path / "stat"
    assert main(["study", "statistics", "--runs", "2", "--envs", "1", "--methods", METHOD, "--workers", "1",
                 "--seed", str(SEED), "--out", str(out)]) == 0
    rows = ResultsTable(out / "runs.csv").read()
    assert sorted(r["run"] for r in rows) == [0, 1]
    assert main(["study", "statistics", "--runs", "0", "--out", str(tmp_path / "bad")]) == 2
    assert "--runs" in capsys.readouterr().err


def test_one_study_per_output_directory(tmp_path):
    from mmg_casadi.montecarlo.study import _exclusive
    with _exclusive(tmp_path):
        with pytest.raises(InputError) as err:
            run_study(tmp_path, runs=1, envs="1", methods=(METHOD,), workers=1, progress=False)
    assert err.value.field == "out_dir"


def test_scenarios_with_different_horizons_share_a_batch():
    from mmg_casadi.scenarios.scenario import scenario_from_dict

    def sc(t_max):
        return scenario_from_dict({"settings": {"method": "none", "t_max": t_max},
                                   "ships": [{"start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[60, 0]]}]})
    short, long_ = run_scenarios([sc(10.0), sc(100.0)])
    assert short["failure"] == "timeout" and long_["success"]
