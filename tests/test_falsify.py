"""Falsification (issue 45): the envelope, the exact and smooth robustness, the adjoint gradient, the searches on a
case whose failing region is known in closed form, reproduction by ``simulate``, the CLI and ``study hardest``."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.falsify.cases import CrossingCase
from mmg_casadi.falsify.envelope import Envelope
from mmg_casadi.falsify.falsifier import Falsification, falsify, load_falsification
from mmg_casadi.falsify.gradient import MarginGradient, soft_min
from mmg_casadi.falsify.report import cluster, geometry_distance
from mmg_casadi.falsify.robustness import evaluate
from mmg_casadi.falsify.search import SearchConfig, run_search
from mmg_casadi.montecarlo.disturbance_sampling import DisturbanceRanges
from mmg_casadi.montecarlo.sampling import sample_scenario
from mmg_casadi.scenarios.scenario import load_scenario
from mmg_casadi.params import PARAMETERS

COLLISION = 2.0  # the table's collision distance (L), two KCS


# ------------------------------------------------------------------------------------------ envelope

@pytest.mark.parametrize("environment", [1, 3, 5, 6])
def test_the_study_sample_is_inside_and_decodes_to_the_sampler_scenario(environment):
    env = Envelope(environment)
    for run in range(5):
        theta = env.sample(run, seed=2)
        assert env.violation(theta) == 0.0
        s, ref = env.decode(theta, run=run, seed=2), sample_scenario(environment, run, 2)
        for name in ("starts", "goals", "headings", "speeds", "obstacles"):
            np.testing.assert_allclose(getattr(s, name), getattr(ref, name), atol=1e-12, err_msg=name)
        for a, b in zip(s.land, ref.land):
            np.testing.assert_allclose(a, b, atol=1e-12)
        np.testing.assert_allclose(env.from_unit(env.to_unit(theta)), theta, atol=1e-12)


@pytest.mark.parametrize("environment", [1, 5])
def test_projection_lands_inside_the_envelope(environment):
    env = Envelope(environment, disturbance=DisturbanceRanges(current=(0.0, 0.1), wind=(0.0, 15.0)))
    rng = np.random.default_rng(3)
    for _ in range(40):
        theta, inside = env.project(env.from_unit(rng.uniform(-0.2, 1.2, env.dimension)))
        assert inside and env.violation(theta) == 0.0
    theta = env.sample(0)
    theta[env.index("ship0.goal_x"):env.index("ship0.goal_x") + 2] = theta[:2] + 3.0  # goal next to its start
    assert env.violation(theta) > 0.0
    moved, inside = env.project(theta)
    assert inside and np.linalg.norm(moved[env.index("ship0.goal_x"):][:2] - moved[:2]) >= 50.0


def test_envelope_refuses_bad_input():
    with pytest.raises(ValueError, match="environment"):
        Envelope(7)
    with pytest.raises(ValueError, match="theta"):
        Envelope(1).decode([0.0, 1.0])


# ------------------------------------------------------------------------------------------ closed-form case

def test_exact_robustness_is_the_closed_form_closest_approach():
    """Method none: both ships hold course and speed, so the margin is R |sin(beta - phi)| - c (discretised). A
    contact ends both voyages (issue 43: the ships are held where they touched), so inside the failing bearings the
    robustness is the margin at the contact: negative, no deeper than the straight-line closest approach and less
    than one step's closing (2 L/U x dt) past the collision distance."""
    case = CrossingCase()
    betas = np.radians([0.0, 30.0, 41.0, 42.0, 45.0, 48.0, 49.0, 60.0, 90.0])
    lo, hi = case.failing_bearings(COLLISION)
    for beta, ev in zip(betas, evaluate(case, [[b] for b in betas], "none")):
        d, t_star = case.closest_approach(beta)
        assert t_star > 0
        assert ev.failure == (lo < beta < hi)
        if ev.failure:
            assert d - COLLISION - 0.06 <= ev.robustness < 0.0
            assert ev.robustness > -2.0 * PARAMETERS["dt"].default
        else:
            assert ev.robustness == pytest.approx(d - COLLISION, abs=0.06)


def test_adjoint_gradient_equals_finite_differences():
    case = CrossingCase()
    grad = MarginGradient(case, "none", compiled=False)
    for deg in (30.0, 41.0, 60.0):  # outside the failing bearings (inside, the contact ends the voyage)
        theta = np.array([math.radians(deg)])
        ev, smooth, g = grad(theta)
        h = 1e-6
        fd = (grad(theta + h)[1] - grad(theta - h)[1]) / (2 * h)
        assert g[0] == pytest.approx(fd, rel=1e-5, abs=1e-7)
        assert smooth <= ev.robustness + 1e-9


def test_adjoint_gradient_in_environment_1_equals_finite_differences():
    """Every coordinate of a 3-ship, 1-obstacle scenario (method none: no switching), the gradient's largest."""
    env = Envelope(1)
    grad = MarginGradient(env, "none", compiled=False)
    theta = env.sample(0)
    _, _, g = grad(theta)
    for j in np.argsort(-np.abs(g))[:4]:
        h = 1e-5 * (env.high[j] - env.low[j])
        up, down = theta.copy(), theta.copy()
        up[j] += h
        down[j] -= h
        fd = (grad(up)[1] - grad(down)[1]) / (2 * h)
        assert g[j] == pytest.approx(fd, rel=1e-4), env.names[j]


def test_soft_min_bounds_the_minimum():
    m = np.array([[3.0, np.nan], [1.0, 2.0]])
    v, w = soft_min(m, 2.0)
    assert v <= 1.0 <= v + math.log(3) / 2.0
    assert w.sum() == pytest.approx(1.0) and w[0, 1] == 0.0


@pytest.mark.parametrize("search", ["gradient", "cmaes"])
def test_the_search_finds_the_known_failing_region(search):
    """The failing bearings are 45° ± 3.8° (2.1 % of the circle): each search finds failures, and every one lies in
    the closed-form interval."""
    case = CrossingCase()
    lo, hi = case.failing_bearings(COLLISION)
    r = run_search(search, "none", case, "collision", SearchConfig(budget=40, screen=0.25, local_budget=10))
    assert len(r.evaluations) == 40 and r.failures
    found = [float(e.theta[0]) for e in r.failures]
    tol = math.radians(0.3)  # the collision test runs every dt = 0.25 L/U
    assert all(lo - tol < b < hi + tol for b in found), np.degrees(found)
    # a contact ends the voyage (issue 43), so the depth of a failure is that of its contact step, not -c at 45°
    assert r.best.failure and lo - tol < float(r.best.theta[0]) < hi + tol


def test_the_gradient_search_finds_more_than_random_sampling_on_the_known_case():
    case = CrossingCase()
    cfg = SearchConfig(budget=40, screen=0.25, local_budget=10)
    grad = run_search("gradient", "none", case, "collision", cfg)
    rand = run_search("random", "none", case, "collision", cfg)
    assert len(grad.failures) > len(rand.failures)


def _same(a, b):
    """Two search results equal to the bit outside the timing fields."""
    assert [e.theta.tolist() for e in a.evaluations] == [e.theta.tolist() for e in b.evaluations]
    assert [e.robustness for e in a.evaluations] == [e.robustness for e in b.evaluations]
    untimed = [[{k: v for k, v in t.items() if k != "seconds"} for t in r.trace] for r in (a, b)]
    assert json.dumps(untimed[0]) == json.dumps(untimed[1])  # NaN smooth values compare equal as text


@pytest.mark.parametrize("search", ["gradient", "cmaes", "random"])
def test_a_search_is_deterministic_under_its_seed(search):
    case = CrossingCase()
    cfg = SearchConfig(budget=30, screen=0.25, local_budget=10, seed=3)
    first = run_search(search, "none", case, "collision", cfg)
    _same(first, run_search(search, "none", case, "collision", cfg))
    other = run_search(search, "none", case, "collision", SearchConfig(budget=30, screen=0.25, local_budget=10))
    assert [e.theta.tolist() for e in other.evaluations] != [e.theta.tolist() for e in first.evaluations]


@pytest.mark.parametrize("search, stop", [("gradient", 22), ("cmaes", 22), ("random", 35)])
def test_an_interrupted_search_resumes_to_the_uninterrupted_result(monkeypatch, search, stop):
    """Ctrl-C in the middle of a search (the simulation after the stop-th): what was kept (every CHECKPOINT_EVERY
    simulations, at the end of a batch) is replayed, not simulated again, and the search ends as an uninterrupted
    one does."""
    import mmg_casadi.falsify.gradient as gradient_module
    import mmg_casadi.falsify.search as search_module
    from mmg_casadi.falsify.search import SearchResult

    case = CrossingCase()
    cfg = SearchConfig(budget=40, screen=0.25, local_budget=10)
    whole = run_search(search, "none", case, "collision", cfg)
    real_evaluate, real_gradient = search_module.evaluate, gradient_module.MarginGradient.__call__
    simulated, limit = [0], [stop]

    def count(n):
        if simulated[0] + n > limit[0]:
            raise KeyboardInterrupt
        simulated[0] += n

    def evaluate(envelope, thetas, *a, **k):
        count(len(thetas))
        return real_evaluate(envelope, thetas, *a, **k)

    def gradient(self, theta):
        count(1)
        return real_gradient(self, theta)
    monkeypatch.setattr(search_module, "evaluate", evaluate)
    monkeypatch.setattr(gradient_module.MarginGradient, "__call__", gradient)
    monkeypatch.setattr(search_module, "CHECKPOINT_EVERY", 4)
    kept = []

    def save(result, gradients):  # what the checkpoint file holds (through JSON, as falsify writes it)
        kept.append(json.loads(json.dumps({"result": result.to_dict(), "gradients": gradients})))
    with pytest.raises(KeyboardInterrupt):
        run_search(search, "none", case, "collision", cfg, save=save)
    done = len(kept[-1]["result"]["evaluations"])
    assert stop - 8 <= done <= stop  # a batch of the screening or a CMA-ES generation is at most 8 here
    simulated[0], limit[0] = 0, math.inf
    resumed = run_search(search, "none", case, "collision", cfg,
                         resume=SearchResult.from_dict(kept[-1]["result"], case), gradients=kept[-1]["gradients"])
    _same(whole, resumed)
    assert simulated[0] == cfg.budget - done  # nothing kept was simulated again


# ------------------------------------------------------------------------------------------ outputs

@pytest.fixture(scope="module")
def crossing(tmp_path_factory):
    """A falsification of the crossing case with its outputs written."""
    case = CrossingCase()
    cfg = SearchConfig(budget=30, screen=0.25, local_budget=10)
    f = Falsification("none", case, "collision", cfg)
    for s in ("gradient", "cmaes", "random"):
        f.results[s] = run_search(s, "none", case, "collision", cfg)
    out = tmp_path_factory.mktemp("crossing")
    summary = f.save(out, figures="distinct")
    return f, out, summary


def test_every_failure_is_written_reproduced_and_inside(crossing):
    f, out, summary = crossing
    fails = f.failures()
    assert fails and summary["failures_written"] == len(fails) == summary["reproduced"]
    rows = (out / "failures.csv").read_text().splitlines()
    assert len(rows) == len(fails) + 1
    for _, _, e in fails:
        assert f.envelope.violation(e.theta) == 0.0
    assert (out / "trace.png").exists() and (out / "distinct.csv").exists()
    assert len(list((out / "failures").glob("*.png"))) == summary["pooled_distinct"]


def test_simulate_replays_a_failure_exactly(crossing, tmp_path, capsys):
    f, out, _ = crossing
    search, k, e = f.failures()[0]
    path = out / "failures" / f"{search}_{k:05d}.toml"
    assert main(["simulate", str(path), "--out", str(tmp_path / "sim"), "--quiet"]) == 0
    own = json.loads((tmp_path / "sim" / "metrics.json").read_text())["ships"][0]
    assert own["collided"] and own["min_distance"] == e.row["min_distance"]
    assert own["collision_time"] == e.row["failure_time"]
    assert load_scenario(path).settings.method == "none"


def test_failures_cluster_by_geometry(crossing):
    f, _, summary = crossing
    # one target from one side at one aspect: a single distinct failure, however many the searches met
    assert summary["pooled_distinct"] == 1
    g = {"kind": "ship", "bearing_deg": 0.0, "relative_heading_deg": 180.0, "progress": 0.5}
    assert geometry_distance(g, {**g, "bearing_deg": 29.0}) < 1 < geometry_distance(g, {**g, "bearing_deg": 31.0})
    assert geometry_distance(g, {**g, "progress": 0.75}) > 1
    assert cluster([g, {**g, "kind": "obstacle", "relative_heading_deg": math.nan}]).tolist() == [0, 1]


def test_hardest_takes_distinct_failures_first(crossing):
    f, _, _ = crossing
    suite = f.hardest(5)
    assert len(suite) == 5 and suite[0].failure
    assert [e.robustness for e in suite if e.failure] == sorted(e.robustness for e in suite if e.failure)
    assert len({e.theta.tobytes() for e in suite}) == 5


# ------------------------------------------------------------------------------------------ CLI and study

def test_cli_falsify_resumes_and_study_hardest_pairs_methods(tmp_path, capsys, monkeypatch):
    out = tmp_path / "f"
    argv = ["falsify", "--method", "modified-vortex", "--env", "1", "--budget", "12", "--search", "cmaes,random",
            "--figures", "none", "--out", str(out)]
    assert main(argv) == 0
    first = json.loads((out / "summary.json").read_text())
    assert first["searches"]["random"]["simulations"] == 12 and first["environment"] == 1
    import mmg_casadi.falsify.falsifier as falsifier

    def refuse(*a, **k):
        raise AssertionError("a finished search ran again")
    monkeypatch.setattr(falsifier, "run_search", refuse)
    assert main(argv) == 0  # resumes from search_<name>.json: nothing runs again
    assert json.loads((out / "summary.json").read_text())["searches"] == first["searches"]
    monkeypatch.undo()
    f = load_falsification(out)
    assert f.method == "modified-vortex" and set(f.results) == {"cmaes", "random"}
    hard = tmp_path / "h"
    assert main(["study", "hardest", "--methods", "modified-vortex,none", "--from", str(out), "--k", "4",
                 "--out", str(hard)]) == 0
    summary = json.loads((hard / "summary.json").read_text())
    assert summary["k"] == 4 and summary["methods"] == ["modified-vortex", "none"]
    assert len(summary["comparisons"]) == 1 and 0.0 <= summary["comparisons"][0]["p_value"] <= 1.0
    assert len(list((hard / "suite").glob("*.toml"))) == 4
    assert "| situation |" in (hard / "suite.md").read_text()


@pytest.mark.parametrize("argv, field", [
    (["--objective", "grounding"], "--objective"),
    (["--objective", "colregs"], "--search"),
    (["--objective", "speed"], "--objective"),
    (["--search", "gradient,annealing"], "--search"),
    (["--figures", "some"], "--figures"),
    (["--env", "9"], "--env"),
    (["--budget", "0"], "--budget"),
    (["--current", "0.2-0.1"], "--current"),
    (["--set", "targets=hold"], "targets"),
])
def test_cli_falsify_refuses_bad_input_before_any_work(tmp_path, capsys, argv, field):
    out = tmp_path / "out"
    assert main(["falsify", "--method", "modified-vortex", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mmg-casadi: error: ") and field in err[0]
    assert not out.exists() or not any(out.iterdir())


def test_falsify_from_python_in_the_study_envelope():
    f = falsify("none", 1, budget=6, searches=("random", "cmaes"))
    s = f.summary()
    assert s["searches"]["random"]["simulations"] == s["searches"]["cmaes"]["simulations"] == 6
    assert all(f.envelope.violation(e.theta) == 0.0 for r in f.results.values() for e in r.evaluations)


def test_an_interrupted_falsification_resumes_from_its_checkpoint(tmp_path, monkeypatch):
    """falsify(checkpoint=...) stopped in the middle of a search: the search's file holds what was simulated, marked
    unfinished; the rerun simulates only the rest and ends with the uninterrupted result."""
    import mmg_casadi.falsify.search as search_module

    whole = falsify("none", 1, budget=40, searches=("random",)).results["random"]
    real, simulated, limit = search_module.evaluate, [0], [35]

    def evaluate(envelope, thetas, *a, **k):
        if simulated[0] + len(thetas) > limit[0]:
            raise KeyboardInterrupt
        simulated[0] += len(thetas)
        return real(envelope, thetas, *a, **k)
    monkeypatch.setattr(search_module, "evaluate", evaluate)
    with pytest.raises(KeyboardInterrupt):
        falsify("none", 1, budget=40, searches=("random",), checkpoint=tmp_path)
    kept = json.loads((tmp_path / "search_random.json").read_text())
    assert kept["complete"] is False and len(kept["result"]["evaluations"]) == 32  # the first batch
    simulated[0], limit[0] = 0, math.inf
    resumed = falsify("none", 1, budget=40, searches=("random",), checkpoint=tmp_path).results["random"]
    assert simulated[0] == 8
    _same(whole, resumed)
    assert "complete" not in json.loads((tmp_path / "search_random.json").read_text())


@pytest.mark.slow
def test_environment_5_failures_reproduce_and_lie_inside(tmp_path):
    """A short search of the paper's densest environment: every failure it writes is inside the envelope and
    reproduced to the bit by simulate."""
    f = falsify("modified-vortex", 5, budget=80, searches=("cmaes", "random"))
    summary = f.save(tmp_path, figures="none")
    assert summary["failures_written"] >= 1
    assert summary["reproduced"] == summary["failures_written"]
    assert all(f.envelope.violation(e.theta) == 0.0 for _, _, e in f.failures())
