"""Monte Carlo rows are the same, run by run, as those of the code before the performance work (commit 79ba6c0).

``tests/data/runs_79ba6c0.csv`` holds runs 0-19 of every (environment, method) cell of ``mmg-casadi study
statistics --runs 200`` (seed 0) as that commit wrote them (repr of the floats, so equality is to the bit). The
batches, their width and chunking, and the compiled code have changed since; the outcome of every run must not.
Since issue 43 a collision ends the colliding ships' voyages: a run that failed by a collision is the same up to
the contact (success, failure, the pair and the time), and its own ship, held where she touched, never arrives.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np
import pytest

from mmg_casadi.closed_loop.layout import GLOBAL_PARAMS
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.montecarlo.execution import run_batch, sampled_scenario
from mmg_casadi.closed_loop.simulation import simulate_batch

DATA = Path(__file__).parent / "data" / "runs_79ba6c0.csv"
BEFORE = {"velocity-obstacle": {"vo_cone": "wide", "vo_hold": False}}
"""Parameters that select the algorithm the reference rows were made with (the velocity obstacle's defaults have
changed since: Huang's cone, holding the chosen heading)."""
COLUMNS = ("success", "failure", "failure_pair", "failure_time", "time_to_goal", "ce", "mcte", "fleet_success",
           "min_distance")
CONTACT_COLUMNS = ("success", "failure", "failure_pair", "failure_time", "fleet_success")
"""The columns a run that failed by a collision shares with the reference: those settled at the contact."""


def _reference(env: int, method: str) -> list[dict]:
    with open(DATA, newline="") as fh:
        return [r for r in csv.DictReader(fh) if int(r["environment"]) == env and r["method"] == method]


def _same(a, b) -> bool:
    if isinstance(a, bool) or isinstance(b, bool):
        return str(a) == str(b)
    if isinstance(a, float) and math.isnan(a):
        return b in ("", "nan")
    if isinstance(a, float):
        return b != "" and float(b) == a
    return str(a) == b


def _check(env: int, method: str):
    ref = _reference(env, method)
    assert len(ref) == 20
    rows = run_batch(env, method, [int(r["run"]) for r in ref], 0, params=BEFORE.get(method))
    for r, row in zip(ref, rows):
        contact = r["failure"] in ("collision", "grounding")
        for c in CONTACT_COLUMNS if contact else COLUMNS:
            assert _same(row[c], r[c]), f"env {env} {method} run {r['run']} {c}: {row[c]!r} != {r[c]!r}"
        if contact:  # her voyage ended at the contact: she never arrived
            assert math.isnan(row["time_to_goal"]), f"env {env} {method} run {r['run']} arrived after a contact"
        if r["failure"] == "collision":  # held within the collision distance (2 L) where she touched
            assert row["min_distance"] < 2.0


@pytest.mark.parametrize("method", ["modified-vortex", "inverse-square", "velocity-obstacle"])
def test_rows_identical_to_before_environment_1(method):
    _check(1, method)


@pytest.mark.slow
@pytest.mark.parametrize("env", [2, 3, 4, 5])
@pytest.mark.parametrize("method", ["modified-vortex", "inverse-square", "velocity-obstacle"])
def test_rows_identical_to_before(env, method):
    _check(env, method)


def test_batch_width_and_chunk_do_not_change_final_states():
    problems = [build_problem(sampled_scenario(2, "modified-vortex", r)) for r in range(7)]
    X0 = np.column_stack([p.x0 for p in problems])
    P = np.column_stack([p.p for p in problems])
    P[GLOBAL_PARAMS.index("t_max"), 3] = 40.0  # one scenario with a short horizon: it leaves the batch early
    ref, _ = simulate_batch(problems[0].layout, X0, P, width=None, chunk=100)
    for width, chunk in ((1, 100), (3, 7), (7, 25)):
        XF, _ = simulate_batch(problems[0].layout, X0, P, width=width, chunk=chunk)
        assert XF[0, 3] == pytest.approx(40.0)
        # only the time row of scenarios whose ships all finished before their horizon may differ (it keeps
        # counting while the batch runs on); every ship row is the same to the bit
        np.testing.assert_array_equal(XF[1:], ref[1:])
