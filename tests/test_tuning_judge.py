"""The held-out judgement of a tuned parameter set (tuning/judge.py): never an improvement the paired test
does not support."""

import numpy as np
import pytest

from tuning.judge import compare_env, judge, outcomes_from_rows, paired_mean


def _outcomes(success, ce=0.1, mcte=1.0):
    s = np.asarray(success, bool)
    return {"success": s, "ce": np.where(s, ce, np.nan), "mcte": np.where(s, mcte, np.nan)}


def _pair(n, both, a_only, b_only):
    """Success vectors with the given numbers of concordant-success and discordant runs."""
    a = np.zeros(n, bool)
    b = np.zeros(n, bool)
    a[:both] = b[:both] = True
    a[both:both + a_only] = True
    b[both + a_only:both + a_only + b_only] = True
    return a, b


def test_worse_set_is_never_improved():
    # 2000 paired runs: the candidate loses 60 scenarios the baseline wins and wins 10 (95.0 % vs 97.5 %)
    cand, base = _pair(2000, 1890, 10, 60)
    j = judge({5: _outcomes(cand)}, {5: _outcomes(base)}, target=(5,))
    assert j["verdict"] == "no improvement"
    r = j["environments"][5]["success"]
    assert r["difference"] == pytest.approx(-0.025) and r["p_value"] < 1e-8
    assert any("not a significant gain" in x for x in j["reasons"])
    assert any("significantly lower" in x for x in j["reasons"])


def test_better_but_not_significant_is_not_improved():
    # 12 vs 5 discordant runs: exact McNemar p = 0.143 (two-sided binomial, 17 trials)
    cand, base = _pair(2000, 1950, 12, 5)
    j = judge({5: _outcomes(cand)}, {5: _outcomes(base)}, target=(5,))
    assert j["environments"][5]["success"]["difference"] > 0
    assert j["environments"][5]["success"]["p_value"] == pytest.approx(0.1435, abs=1e-3)
    assert j["verdict"] == "no improvement"


def test_significant_gain_is_improvement_unless_another_env_or_metric_is_worse():
    cand, base = _pair(2000, 1900, 40, 10)   # p ≈ 1.6e-5
    ok = judge({5: _outcomes(cand)}, {5: _outcomes(base)}, target=(5,))
    assert ok["verdict"] == "improvement" and ok["reasons"] == []
    # same gain in environment 5, but significantly lower success in environment 3
    c3, b3 = _pair(2000, 1900, 10, 40)
    worse_env = judge({3: _outcomes(c3), 5: _outcomes(cand)}, {3: _outcomes(b3), 5: _outcomes(base)}, target=(5,))
    assert worse_env["verdict"] == "no improvement"
    # same gain, but CE higher on every jointly successful run
    rng = np.random.default_rng(0)
    ce_b = 0.1 + 0.01 * rng.standard_normal(2000)
    worse_ce = judge({5: {"success": cand, "ce": ce_b + 0.01, "mcte": np.ones(2000)}},
                     {5: {"success": base, "ce": ce_b, "mcte": np.ones(2000)}}, target=(5,))
    assert worse_ce["verdict"] == "no improvement"
    assert any("CE significantly higher" in x for x in worse_ce["reasons"])


def test_paired_mean_and_rows():
    d = paired_mean([0.2, 0.4, np.nan], [0.1, 0.1, 0.5])
    assert d["n"] == 2 and d["mean"] == pytest.approx(0.2)
    rows = [{"environment": 5, "method": "m", "run": r, "success": r != 1, "ce": 0.1, "mcte": 1.0,
             "failure": "" if r != 1 else "collision"} for r in (2, 0, 1)]
    o = outcomes_from_rows(rows, "m")[5]
    assert o["run"].tolist() == [0, 1, 2] and o["success"].tolist() == [True, False, True]
    c = compare_env(o, o)
    assert c["success"]["p_value"] == 1.0 and c["verdict"] == "no significant difference"
