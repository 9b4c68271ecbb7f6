"""`mmg-casadi tune colregs`: the objective, the candidates, the paired held-out judgement, the outputs, resume and
the refused arguments."""

from __future__ import annotations

import json

import pytest

from mmg_casadi.cli import main
from mmg_casadi.montecarlo.results import ResultsTable
from mmg_casadi.params import PARAMETERS
from mmg_casadi.params import load_file as load_params_file
from tuning import colregs


def _rows(method, outcomes):
    """Rows of runs 0.. with (success, compliant) per run; one give-way encounter per run."""
    return [{"environment": 5, "method": method, "run": i, "success": s,
             "colregs_verdicts": f"1:give-way:1:8={int(c)}/16={int(c)}"} for i, (s, c) in enumerate(outcomes)]


def test_objective_weighs_failures_against_compliance():
    rows = _rows("m", [(True, True)] * 90 + [(True, False)] * 9 + [(False, True)])
    s = colregs.objective(rows, failure_weight=10.0)
    assert (s["runs"], s["encounters"]) == (100, 100)
    assert s["success"] == pytest.approx(0.99) and s["compliance"] == pytest.approx(0.91)
    assert s["objective"] == pytest.approx(0.91 - 10 * 0.01)
    assert colregs.objective(rows, failure_weight=0.0)["objective"] == pytest.approx(0.91)


def test_candidates_are_the_defaults_then_a_reproducible_hypercube_inside_the_box():
    a, b = colregs.candidates(8, seed=3), colregs.candidates(8, seed=3)
    assert a == b and a != colregs.candidates(8, seed=4)
    assert a[0] == {k: PARAMETERS[k].default for k in colregs.SEARCH_BOX}
    for k, (lo, hi) in colregs.SEARCH_BOX.items():
        values = sorted(c[k] for c in a[1:])
        assert lo <= values[0] and values[-1] <= hi
        # a Latin hypercube: one point in each eighth of every axis
        assert sorted(int((v - lo) / (hi - lo) * 8) for v in values) == list(range(8))
        p = PARAMETERS[k]
        assert p.low is None or p.low <= lo
        assert p.high is None or hi <= p.high


def test_judge_needs_significantly_more_compliance_and_no_significant_loss_of_safety():
    default = _rows("d", [(True, i % 2 == 0) for i in range(200)])
    better = _rows("t", [(True, i % 2 == 0 or i < 100) for i in range(200)])
    j = colregs.judge(better, default)
    assert j["verdict"] == "improvement" and not j["reasons"]
    assert (j["compliance"]["a_only"], j["compliance"]["b_only"]) == (50, 0)
    assert j["compliance"]["difference"] == pytest.approx(0.25)
    assert j["success"]["difference"] == 0.0 and j["success"]["runs"] == 200
    unsafe = _rows("t", [(i >= 20, i % 2 == 0 or i < 100) for i in range(200)])
    j = colregs.judge(unsafe, default)
    assert j["verdict"] == "no improvement"
    assert j["success"]["default_only"] == 20 and j["success"]["p_value"] < 1e-5
    assert any("success significantly lower" in r for r in j["reasons"])
    same = colregs.judge(default, default)
    assert same["verdict"] == "no improvement" and "compliance not significantly higher" in same["reasons"][0]


def test_tune_colregs_writes_its_outputs_and_resumes_without_rerunning(tmp_path, capsys):
    out = tmp_path / "t"
    argv = ["tune", "colregs", "--envs", "1", "--design", "6", "--holdout", "4", "--candidates", "1",
            "--workers", "1", "--out", str(out)]
    assert main(argv) == 0
    report = json.loads((out / "report.json").read_text())
    points = [{k: c[k] for k in colregs.SEARCH_BOX} for c in report["candidates"]]
    first = max(report["candidates"][:2], key=lambda c: (c["objective"], -c["candidate"]))
    sweep = [p for p in colregs.neighbours(points[first["candidate"]], 0.25) if p not in points[:2]]
    assert points == colregs.candidates(1) + sweep  # the hypercube, then one coordinate sweep around its best
    assert [c["candidate"] for c in report["candidates"]] == list(range(len(points)))
    for c in report["candidates"]:
        rows = [r for r in ResultsTable(out / "candidates" / f"c{c['candidate']:02d}" / "runs.csv").read()
                if r["run"] < 6]
        assert len(rows) == 6
        score = {k: None if v != v else v for k, v in colregs.objective(rows, failure_weight=10.0).items()}
        assert c == {"candidate": c["candidate"], **{k: c[k] for k in colregs.SEARCH_BOX}, **score}  # nan: null
    best = max(report["candidates"], key=lambda c: (c["objective"], -c["candidate"]))
    assert report["best"] == best["candidate"]
    assert load_params_file(out / "params.toml") == {k: best[k] for k in colregs.SEARCH_BOX}
    if report["best"]:
        assert report["judgement"]["success"]["runs"] == 4
    else:
        assert report["judgement"] is None
        assert "NO IMPROVEMENT" in (out / "params.toml").read_text()
    sizes = {p: p.stat().st_size for p in out.rglob("runs.csv")}
    capsys.readouterr()
    assert main(argv) == 0  # resumed: every run is on disk
    assert {p: p.stat().st_size for p in out.rglob("runs.csv")} == sizes
    assert json.loads((out / "report.json").read_text())["candidates"] == report["candidates"]
    capsys.readouterr()
    assert main([*argv, "--failure-weight", "3"]) == 2  # other settings: refused, nothing written
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "failure_weight" in err[0]


@pytest.mark.parametrize("argv,field", [(["--design", "0"], "--design"), (["--holdout", "-1"], "--holdout"),
                                        (["--candidates", "-1"], "--candidates"), (["--refine", "-1"], "--refine"),
                                        (["--failure-weight", "-1"], "--failure-weight"),
                                        (["--envs", "9"], "--envs"),
                                        (["--set", "cv_t_act=5"], "cv_t_act")])
def test_bad_arguments_exit_2_in_one_line_before_any_work(tmp_path, capsys, argv, field):
    out = tmp_path / "o"
    assert main(["tune", "colregs", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0], err
    assert not out.exists()
