"""Safety-aware tuning objective (tuning/safety.py) and its resumable search (tuning/search.py)."""

import numpy as np
import pytest

from tuning import apf, safety, search

CFG = safety.SafetyConfig(max_steps=120)   # 30 time units: both encounters happen inside


@pytest.fixture(scope="module")
def objective():
    enc = apf.paper_encounters()
    cases = [safety.prepare_case(k, enc[k], CFG) for k in ("static-obstacle", "head-on")]
    return safety.SafetyObjective(cases, CFG)


def test_gradient_matches_central_differences(objective):
    gc = safety.gradient_check(objective, safety.PAPER, rel_step=1e-6)
    assert gc["rel_error_norm"] < 1e-5, gc
    assert all(abs(a) > 0 for a in gc["ad"])


def test_terms_follow_their_definitions(objective):
    t = objective.terms(safety.PAPER)
    for c, m in zip(objective.cases, t["softmin_own"]):
        # the soft-min is below the closest approach of the exact loop at the same values, by at most a few L
        assert m < c.exact_d_min + 0.5 and m > c.exact_d_min - 3.0
    d_safe = np.array([c.collision_distance + CFG.margin for c in objective.cases])
    expect = np.log1p(np.exp(CFG.beta * (d_safe - t["softmin_own"]))) / CFG.beta
    assert np.allclose(t["safety_own"], expect)
    J = CFG.w_safety * t["safety_own"] + CFG.w_ce * t["ce"] + CFG.w_mcte * t["mcte"]
    assert np.allclose(t["objective"], J)
    assert np.all((t["ce"] > 0) & (t["ce"] < 1)) and np.all(t["mcte"] > 0)


def test_smaller_safe_radius_brings_the_own_ship_closer(objective):
    near = objective.terms((safety.PAPER[0], 8.0))
    far = objective.terms((safety.PAPER[0], 20.0))
    assert np.all(near["softmin_own"] < far["softmin_own"])


class _Stub:
    """A quadratic 'objective' with the interface search() uses, counting evaluations."""

    def __init__(self, fail_after=None):
        self.cases = [0]
        self.calls = 0
        self.fail_after = fail_after

    def terms(self, theta):
        if self.fail_after is not None and self.calls >= self.fail_after:
            raise KeyboardInterrupt
        self.calls += 1
        th = np.asarray(theta, float)
        c = np.array([-20.0, 12.0])
        J = float(np.sum(((th - c) / [10.0, 5.0]) ** 2))
        g = 2 * (th - c) / np.array([100.0, 25.0])
        one = np.array([J])
        return {"objective": one, "d_objective": g[:, None], "safety_own": one, "ce": one, "mcte": one,
                "softmin_own": np.array([5.0])}


def test_search_finds_the_minimum_and_resumes_without_recomputing(tmp_path):
    full = _Stub()
    ref = search.search(full, tmp_path / "a", grid_n=3, starts=1, max_iter=20)
    assert np.allclose(ref["best"]["theta"], [-20.0, 12.0], atol=1e-3)
    # interrupted after 5 evaluations, then resumed: same result, no evaluation done twice
    first = _Stub(fail_after=5)
    with pytest.raises(KeyboardInterrupt):
        search.search(first, tmp_path / "b", grid_n=3, starts=1, max_iter=20)
    second = _Stub()
    res = search.search(second, tmp_path / "b", grid_n=3, starts=1, max_iter=20)
    assert first.calls + second.calls == full.calls
    assert res["best"] == ref["best"] and res["evaluations"]["new"] == second.calls
    assert res["evaluations"]["replayed"] >= 5   # the 5 stored ones (and the start point, found in the log)
    again = _Stub()
    search.search(again, tmp_path / "b", grid_n=3, starts=1, max_iter=20)
    assert again.calls == 0


def test_resume_refuses_other_objective_settings(tmp_path):
    from mmg_casadi.errors import InputError
    from mmg_casadi.io import write_json
    from tuning.cli_apf import check_settings
    f = tmp_path / "tuning.json"
    a = {"config": {**safety.SafetyConfig().__dict__}, "train": 10}
    check_settings(f, a)                      # nothing recorded yet: allowed, and nothing is written
    assert not f.exists()
    write_json(f, a)                           # what `tune apf` records once every argument is checked
    check_settings(f, a)                      # same settings: resume allowed
    b = {"config": {**safety.SafetyConfig(w_mcte=0.1).__dict__}, "train": 10}
    with pytest.raises(InputError, match="config"):
        check_settings(f, b)
