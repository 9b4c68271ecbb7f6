"""``mmg-casadi explain``: one run of a statistics study re-run exactly, its verdicts reproduced cell for cell, and
a figure per encounter of its own ship."""

import json

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.montecarlo.explain import VERDICT_COLUMNS, explain_run, plot_encounter
from mmg_casadi.montecarlo.results import ResultsTable
from mmg_casadi.montecarlo.study import run_study

RUNS = 20


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    run_study(out, runs=RUNS, envs=(5,), methods=("colregs-vortex",), workers=1, progress=False, batch_size=8,
              params={"colregs_all_profiles": True})
    return out


def test_explain_reproduces_twenty_runs_verdicts_to_the_bit(study):
    stored = {r["run"]: r for r in ResultsTable(study / "runs.csv").read()}
    assert len(stored) == RUNS
    judged = 0
    for run in range(RUNS):
        ex = explain_run(study, run)
        assert set(ex.reproduced) == set(VERDICT_COLUMNS) and all(ex.reproduced.values()), (run, ex.reproduced)
        for c in VERDICT_COLUMNS:
            assert ex.row[c] == stored[run][c]
        assert (ex.row["success"], ex.row["failure"]) == (stored[run]["success"], stored[run]["failure"])
        judged += sum(1 for e in ex.encounters if e.judged)
    assert judged == sum(r["colregs_risky"] for r in stored.values())


def test_explain_writes_a_figure_per_encounter_and_a_replayable_scenario(study, tmp_path, capsys):
    run = next(r["run"] for r in ResultsTable(study / "runs.csv").read() if r["colregs_risky"] > 0)
    out = tmp_path / "explain"
    assert main(["explain", str(study), "--run", str(run), "--profile", "iitm-lab", "--out", str(out)]) == 0
    report = json.loads((out / "explain.json").read_text())
    assert report["profile"] == "iitm-lab" and all(report["reproduced"].values())
    figures = sorted(out.glob("encounter*.png"))
    assert len(figures) == len(report["encounters"]) > 0
    assert "verdicts reproduced" in capsys.readouterr().err
    # the written scenario replays the run: same own-ship outcome
    assert main(["simulate", str(out / "scenario.toml"), "--out", str(tmp_path / "replay")]) == 0
    replay = json.loads((tmp_path / "replay" / "metrics.json").read_text())
    assert replay["ships"][0]["collided"] == (report["row"]["failure"] == "collision")


def test_plot_encounter_marks_where_a_rule_broke(study):
    for run in range(RUNS):
        ex = explain_run(study, run)
        broken = [k for k, e in enumerate(ex.encounters) if e.judged and not e.compliant]
        if broken:
            fig = plot_encounter(ex, broken[0])
            texts = " ".join(t.get_text() for t in fig.axes[0].texts)
            assert "BROKEN" in texts and "broke at t =" in texts
            return
    pytest.fail("no broken encounter in the study's runs")


def test_explain_refuses_what_it_cannot_explain(study, tmp_path, capsys):
    assert main(["explain", str(tmp_path), "--run", "0", "--out", str(tmp_path / "x")]) == 2
    assert "STUDY_DIR" in capsys.readouterr().err
    assert main(["explain", str(study), "--run", str(RUNS + 5), "--out", str(tmp_path / "x")]) == 2
    assert "--run" in capsys.readouterr().err
    assert main(["explain", str(study), "--run", "0", "--profile", "strict", "--out", str(tmp_path / "x")]) == 2
    assert not (tmp_path / "x").exists()
