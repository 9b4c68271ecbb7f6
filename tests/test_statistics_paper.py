"""The paper's results, claim by claim, at the paper's 5000 runs per Monte Carlo cell (slow: `make test-all`).

Runs ``study paper --runs 5000`` (about 5 minutes on two cores) into a temporary directory, or resumes the one
named by ``$MMG_PAPER_OUT`` (the study is resumable, so a finished directory only re-runs the quick studies and
re-evaluates the claims). Claims we reproduce are asserted; the others are ``xfail(strict=True)`` with what we
measured at 5000 runs (seed 0), so a change that makes one of them hold is noticed.
"""

import os
from pathlib import Path

import pytest

from mmg_casadi.montecarlo.study import run_study
from studies import paper

pytestmark = pytest.mark.slow

RUNS = 5000

REPRODUCED = ("W1", "W2", "S1", "C1", "C2", "C4", "T1", "T2", "T5", "T6", "T7", "T8", "T11", "T12", "T14", "T15",
              "T16", "T18", "L1")
"""Claims reproduced at 5000 runs (seed 0)."""

NOT_REPRODUCED = {
    "S2": "partly: the ship collides (1.81 L) but then reaches the 60 L goal",
    "S3": "partly: sink-vortex CE 0.051 (paper 0.0852), closest approach 1.68 x the inverse square's (paper ~2)",
    "S4": "partly: with the obstacle at (25, 1.5) L the sink-vortex does not collide (paper gives no coordinates)",
    "S5": "partly: modified vortex passes at 5.55 L, farther than both the inverse square (2.24) and sink-vortex (3.76)",
    "C3": "partly: crossing, the stand-on ship also turns to starboard (> 5 deg)",
    "C5": "partly: VO head-on, both ships turn to starboard (tie-break to starboard), min distance 3.34 L (paper 6)",
    "C6": "partly: VO crossing, both ships turn to starboard, min distance 3.77 L (paper 6)",
    "C7": "partly: inverse square overtakes on the overtaken ship's starboard side; crossing does not collide",
    "C8": "partly: the stand-on ships of overtaking and crossing alter course (Rule 17(a)(i))",
    "K1": "partly: with the inverse square ship 2 collides as well",
    "K2": "partly: VO min distance 2.93 L (paper 4 L)",
    "K3": "partly: modified vortex collision free at 5.67 L but not COLREG-compliant under the encounter scorer",
    "N1": "partly: narrow channel min distance 6.12 L (paper a little over 2 L)",
    "T3": "partly: modified vortex 99.44 % (env 1) but 98.76 % in env 2",
    "T4": "partly: env 5 success 96.0 % [95.4, 96.5] (paper 97 %)",
    "T9": "partly: modified-vortex call grows by 74 % from env 1 to env 5 (inverse square 47 %)",
    "T10": "partly: modified-vortex call costs 1.05-1.27 x the inverse square's (paper 1.25-1.30)",
    "T13": "partly: modified vortex faster than the VO by 4.2, 7.6, 9.5, 13.3, 17.8 % in env 1-5 (paper 10-30 %)",
    "T17": "not reproduced: modified-vortex MCTE 36-63 % above the inverse square's in env 3-5 (paper: marginally)",
}
"""Claim id -> what we measured at 5000 runs (seed 0): partly or not reproduced."""


@pytest.fixture(scope="module")
def claims(tmp_path_factory):
    out = Path(os.environ.get("MMG_PAPER_OUT") or tmp_path_factory.mktemp("paper"))
    return {c["id"]: c for c in paper.run(out, runs=RUNS, workers=2, progress=False)["claims"]}


@pytest.mark.parametrize("cid", REPRODUCED)
def test_claim_is_reproduced(claims, cid):
    assert claims[cid]["verdict"] == "reproduced", claims[cid]


@pytest.mark.parametrize("cid", [pytest.param(cid, marks=pytest.mark.xfail(strict=True, reason=why))
                                 for cid, why in NOT_REPRODUCED.items()])
def test_claim_not_yet_reproduced(claims, cid):
    assert claims[cid]["verdict"] == "reproduced", claims[cid]


def test_every_claim_is_listed_here(claims):
    assert set(claims) == set(REPRODUCED) | set(NOT_REPRODUCED) | {c for c in claims
                                                                     if claims[c]["verdict"] == "not testable"}


def test_modified_vortex_beats_inverse_square_in_every_environment(tmp_path):
    summary = run_study(tmp_path, runs=1000, envs=(1, 2, 3, 4, 5), methods=("modified-vortex", "inverse-square"),
                        progress=False)
    rate = {(r["environment"], r["method"]): r["success_rate"] for r in summary.rows}
    for env in range(1, 6):
        assert rate[(env, "modified-vortex")] > rate[(env, "inverse-square")]
    assert rate[(1, "modified-vortex")] >= 0.99 and rate[(2, "modified-vortex")] >= 0.99
    # success falls with congestion
    assert rate[(5, "modified-vortex")] < rate[(1, "modified-vortex")]
    assert rate[(5, "inverse-square")] < rate[(1, "inverse-square")]
