"""APF tuning: the superseded IPOPT tuner (tuning/apf_ipopt.py) and `mmg-casadi tune apf`."""

from importlib import resources

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.params import load_file as load_params_file
from tuning import apf, apf_ipopt

SCENARIOS = resources.files("mmg_casadi").joinpath("data", "scenarios")
TINY = apf_ipopt.TuningConfig(max_steps=120, max_iter=6)  # 30 time units: both encounters happen inside


@pytest.fixture(scope="module")
def tiny_cases():
    enc = apf.paper_encounters()
    scs = {"static-obstacle": enc["static-obstacle"], "head-on": enc["head-on"]}
    return apf_ipopt.prepare_cases(scs, TINY)


def test_gradient_matches_central_differences(tiny_cases):
    prob = apf_ipopt.SmoothProblem(tiny_cases, TINY)
    gc = apf_ipopt.gradient_check(prob, apf_ipopt.PAPER, rel_step=1e-6)
    assert gc["rel_error_norm"] < 1e-4, gc
    assert all(abs(a) > 0 for a in gc["ad"])
    # only the direction of the field matters: J is invariant along (k_vor0, lam_sink) -> c (k_vor0, lam_sink)
    assert abs(gc["scale_invariance"]) < 1e-6 * abs(gc["ad"][0] * apf_ipopt.PAPER[0])


def test_optimiser_improves_training_objective(tiny_cases):
    res = apf_ipopt.tune(tiny_cases, TINY, report=None, check_gradient=False)
    assert res.objective_after < res.objective_before - 1e-3
    assert len(res.iterations) >= 2
    for (lo, hi), k in zip(apf_ipopt.BOUNDS, apf_ipopt.THETA):
        assert lo <= res.params_after[k] <= hi
    assert np.all(np.array(res.constraints_after) >= np.array(res.constraint_bounds) - apf_ipopt.FEAS_TOL)
    d = res.to_dict()
    assert d["objective_after"] == res.objective_after and "ratio_after" in d


def test_params_toml_round_trip_and_simulate_accepts_it(tmp_path):
    params = {"k_vor0": -12.5, "lam_sink": -140.25, "r_safe": 13.0}
    f = tmp_path / "params.toml"
    apf_ipopt.write_params_toml(params, f)
    assert load_params_file(f) == params
    out = tmp_path / "sim"
    assert main(["simulate", str(SCENARIOS / "head_on.toml"), "--params", str(f), "--out", str(out)]) == 0
    assert (out / "metrics.json").exists()


@pytest.mark.parametrize("argv,field", [(["--holdout", "0"], "--holdout"), (["--holdout", "-3"], "--holdout"),
                                        (["--train", "-1"], "--train"), (["--starts", "0"], "--starts"),
                                        (["--grid", "0"], "--grid"), (["--max-iter", "0"], "--max-iter")])
def test_bad_counts_exit_2(tmp_path, capsys, argv, field):
    out = tmp_path / "o"
    assert main(["tune", "apf", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert not out.exists()
