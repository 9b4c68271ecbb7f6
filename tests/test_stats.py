"""Paired comparison: exact McNemar p-value and Newcombe's interval."""

import numpy as np
import pytest
from scipy.stats import binomtest

from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.stats import paired_comparison, wilson


def test_mcnemar_uses_only_discordant_runs():
    # 30 runs where A wins, 10 where B wins, plus 960 concordant runs: p = binomtest(30, 40)
    a = np.r_[np.ones(30), np.zeros(10), np.ones(900), np.zeros(60)].astype(bool)
    b = np.r_[np.zeros(30), np.ones(10), np.ones(900), np.zeros(60)].astype(bool)
    c = paired_comparison(a, b)
    assert (c.a_only, c.b_only, c.both, c.neither) == (30, 10, 900, 60)
    assert c.p_value == pytest.approx(binomtest(30, 40, 0.5).pvalue)
    assert c.difference == pytest.approx(0.02) and c.ci[0] < 0.02 < c.ci[1]
    assert c.significant() and c.verdict() == "A better"
    # adding concordant runs leaves the p-value unchanged but narrows nothing about the sign
    assert paired_comparison(b, a).verdict() == "B better"


def test_no_discordance_is_no_difference():
    a = np.r_[np.ones(95), np.zeros(5)].astype(bool)
    c = paired_comparison(a, a)
    assert c.p_value == 1.0 and c.difference == 0.0 and c.verdict() == "no significant difference"
    assert c.ci[0] <= 0.0 <= c.ci[1]


def test_interval_is_narrower_than_unpaired_when_outcomes_correlate():
    rng = np.random.default_rng(0)
    base = rng.random(2000) < 0.95
    flip = rng.random(2000) < 0.01
    c = paired_comparison(base, base ^ flip)
    la, ua = wilson(int(base.sum()), 2000)
    lb, ub = wilson(int((base ^ flip).sum()), 2000)
    unpaired_half = np.hypot(ua - la, ub - lb) / 2
    assert (c.ci[1] - c.ci[0]) / 2 < unpaired_half


def test_coverage_of_the_interval_is_near_nominal():
    rng = np.random.default_rng(1)
    hits, trials = 0, 400
    for _ in range(trials):
        u = rng.random(300)
        a, b = u < 0.95, (u < 0.93) | ((u > 0.97) & (u < 0.975))
        c = paired_comparison(a, b)
        hits += c.ci[0] <= 0.95 - 0.935 <= c.ci[1]
    assert 0.92 <= hits / trials <= 0.99


def test_bad_input():
    with pytest.raises(InputError):
        paired_comparison([True, False], [True])
