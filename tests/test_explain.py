"""Monte Carlo that explains itself: the own ship's COLREG compliance per run, the batch history it is computed
from, comparisons.csv, and the refusal of a results table of the older version."""

import csv

import numpy as np
import pytest
from scipy.stats import binomtest

from mmg_casadi.cli import main
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.montecarlo.comparisons import COMPARISON_COLUMNS, compare_methods, read_csv
from mmg_casadi.scenarios.encounters import colregs_cases
from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.execution import own_ship_encounters, run_scenarios
from mmg_casadi.montecarlo.study import run_study
from mmg_casadi.montecarlo.results import RUN_COLUMNS, ResultsTable, summarize
from mmg_casadi.scenarios.scenario import scenario_from_dict, with_method
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.closed_loop.simulation import simulate, simulate_batch_history


def _head_on(offset, method="none"):
    d = {"settings": {"method": method, "t_max": 60.0},
         "ships": [{"name": "a", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[50.0, 0.0]]},
                   {"name": "b", "start": [50.0, offset], "heading": 180.0, "speed": 1.0,
                    "waypoints": [[0.0, offset]]}]}
    return scenario_from_dict(d)


def test_batch_history_is_the_single_rollout_decimated():
    pr = build_problem(_head_on(4.0))
    X0, P = np.column_stack([pr.x0, pr.x0]), np.column_stack([pr.p, pr.p])
    xf, _, hist = simulate_batch_history(pr.layout, X0, P, chunk=20, every=2)
    tr = simulate(pr.layout, pr.x0, pr.p)
    t, st = hist.column(1)
    n = min(len(t), (len(tr.t) + 1) // 2)
    assert np.allclose(t[:n], tr.t[::2][:n])
    assert np.allclose(st[:n, :, 0], tr.state("x")[::2][:n]) and np.allclose(st[:n, :, 2], tr.state("psi")[::2][:n])
    assert np.allclose(xf[:, 0], xf[:, 1])
    with pytest.raises(ValueError, match="every"):
        simulate_batch_history(pr.layout, X0, P, chunk=20, every=3)


def test_constructed_encounters_give_the_compliance_column():
    # head-on, 2.5 L apart abeam (< d_risk = 4 L), nobody alters course: Rule 14 (starboard alteration) is broken
    # far apart (60 L abeam): no encounter, compliance undefined
    far = _head_on(60.0)
    rows = run_scenarios([_head_on(2.5), far], time_guidance_calls=False)
    assert (rows[0]["colregs_compliant"], rows[0]["colregs_risky"]) == (False, 1)
    assert (rows[1]["colregs_compliant"], rows[1]["colregs_risky"], rows[1]["colregs_verdicts"]) == (None, 0, "")
    assert rows[0]["success"] and rows[0]["failure_mechanism"] == ""


@pytest.mark.parametrize("case", ["head-on", "crossing"])
def test_compliance_agrees_with_the_single_run_assessment(case):
    sc = with_method(colregs_cases()[case], "modified-vortex")
    pair = run_scenario(sc).metrics["pairs"][0]
    single = [e for e in pair["encounters"]["a"] if e["applicable"]]
    row = run_scenarios([sc], chunk=101, time_guidance_calls=False)[0]  # odd chunk: every step kept
    assert row["colregs_risky"] == len(single) == 1
    assert row["colregs_compliant"] == single[0]["compliant"]
    assert row["colregs_verdicts"].split(":")[1] == single[0]["role"]


def test_compliance_needs_both_ships_sailing():
    t = np.linspace(0.0, 40.0, 161)
    own = np.column_stack([t, 0 * t, 0 * t, 0 * t])
    other = np.column_stack([50.0 - t, 2.0 + 0 * t, np.pi + 0 * t, np.where(t > 10, 1, 0)])  # stops at t = 10
    stopped = own_ship_encounters(t, np.stack([own, other], axis=1))
    assert (stopped["colregs_risky"], stopped["colregs_compliant"], stopped["colregs_verdicts"]) == (0, None, "")
    other[:, 3] = 0  # the same ship sailing on: a risky head-on
    assert own_ship_encounters(t, np.stack([own, other], axis=1))["colregs_risky"] == 1


def test_compare_methods_is_the_exact_mcnemar_test_on_paired_runs():
    # run r: a succeeds unless r % 7 == 0, b succeeds unless r % 3 == 0 (runs 0..41; b's run 41 missing)
    rows = [{"environment": 2, "method": "a", "run": r, "success": r % 7 != 0} for r in range(42)]
    rows += [{"environment": 2, "method": "b", "run": r, "success": r % 3 != 0} for r in range(41)]
    c = compare_methods(rows)[0]
    a_only = sum(1 for r in range(41) if r % 7 and not r % 3)
    b_only = sum(1 for r in range(41) if not r % 7 and r % 3)
    assert (c["n"], c["a_only"], c["b_only"]) == (41, a_only, b_only)
    assert c["p_value"] == pytest.approx(binomtest(a_only, a_only + b_only, 0.5).pvalue)
    assert c["difference"] == pytest.approx((a_only - b_only) / 41) and c["ci_low"] < c["difference"] < c["ci_high"]


def test_study_writes_comparisons_summary_and_refuses_an_old_table(tmp_path):
    out = tmp_path / "s"
    run_study(out, runs=3, envs=(1,), methods=("modified-vortex", "none"), workers=1, progress=False)
    runs = ResultsTable(out / "runs.csv").read()
    comp = read_csv(out / "comparisons.csv")
    with open(out / "comparisons.csv") as f:
        assert tuple(next(csv.reader(f))) == COMPARISON_COLUMNS
    assert len(comp) == 1 and comp[0]["method_a"] == "modified-vortex" and comp[0]["n"] == 3
    sa = {r["run"]: r["success"] for r in runs if r["method"] == "modified-vortex"}
    sb = {r["run"]: r["success"] for r in runs if r["method"] == "none"}
    assert comp[0]["a_only"] == sum(sa[k] and not sb[k] for k in range(3))
    assert comp[0]["success_a"] == pytest.approx(sum(sa.values()) / 3)
    md = (out / "summary.md").read_text()
    assert "Paired comparisons" in md and "Failure mechanisms" in md and "COLREG-compliant" in md
    for r in runs:
        assert (r["failure_mechanism"] == "") == r["success"]
    s = summarize(runs).rows[0]
    judged = [r["colregs_compliant"] for r in runs if r["method"] == "modified-vortex"
              and r["colregs_compliant"] is not None]
    assert s["compliance_runs"] == len(judged)

    old = tmp_path / "old"
    old.mkdir()
    (old / "runs.csv").write_text(",".join(RUN_COLUMNS[:-3]) + "\n1,none,0,0,True,True,,,,,,,,,,,,3,1\n")
    with pytest.raises(InputError, match="older version"):
        run_study(old, runs=1, envs=(1,), methods=("none",), workers=1, progress=False)
    assert main(["study", "statistics", "--runs", "1", "--envs", "1", "--methods", "none", "--out", str(old)]) == 2
