"""Bad input is refused before any work and without writing anything (issue 29, second pass).

Covers: output paths that cannot be written (refused by a probe before any work), arguments checked before
the work that precedes their use (``study paper``, ``study sweep``, ``tune apf``), the memory limits
(``mmg_casadi.limits``), the resume record of ``runs.csv`` (its side file ``runs.params.json``), and the wording
of the messages (the flag the user typed, the allowed values).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

import mmg_casadi.cli as cli
from mmg_casadi.cli import main
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.errors import InputError, ParameterError
from mmg_casadi.io import check_output
from mmg_casadi.limits import (MAX_SHIP_STEPS, MAX_STUDY_RUNS, MAX_UNROLLED_SHIPS, check_steps, check_study_size,
                               max_workers)
from mmg_casadi.montecarlo.results import FAILURES, ResultsTable
from mmg_casadi.colregs.scorer import SCORER_VERSION
from mmg_casadi.montecarlo.study import PARAMS_FILE, check_study_args, fingerprint, run_study
from mmg_casadi.params import resolve
from mmg_casadi.scenarios.scenario import scenario_from_dict
from studies.sweep import _fmt, markdown, parse_values, plot_sweep

DATA = Path(__file__).resolve().parents[1] / "mmg_casadi" / "data"
SCENARIO = DATA / "scenarios" / "head_on.toml"
SITUATION = DATA / "traffic_situation.json"
UNWRITABLE = "/proc/mmg-casadi-no-such-dir/out"  # /proc accepts no new entries, also for root


def _files(root: Path) -> list[str]:
    return sorted(str(p.relative_to(root)) for p in root.rglob("*"))


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mmg-casadi: error: "), err
    return err[0]


# ------------------------------------------------------------------------------------------- output paths

@pytest.mark.parametrize("argv", [
    ["simulate", str(SCENARIO)], ["maneuver", "turning"], ["study", "statistics", "--runs", "1", "--envs", "1"],
    ["study", "colregs"], ["tune", "pd"], ["tune", "apf"], ["study", "paper", "--runs", "1"],
])
def test_out_naming_an_existing_file_is_refused_before_any_work(tmp_path, capsys, argv, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("keep")
    assert main([*argv, "--out", "afile"]) == 2
    line = _one_error_line(capsys)
    assert "--out: expected a directory (or a new path), not an existing file, got 'afile'" in line
    assert _files(tmp_path) == ["afile"] and (tmp_path / "afile").read_text() == "keep"


@pytest.mark.parametrize("argv", [["convert", str(SITUATION)], ["traffic", "3"]])
def test_file_out_naming_a_directory_is_refused_and_leaves_no_tmp_file(tmp_path, capsys, argv, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "o.toml").mkdir()
    assert main([*argv, "--out", "o.toml"]) == 2
    assert "--out: expected a file name, not an existing directory, got 'o.toml'" in _one_error_line(capsys)
    assert _files(tmp_path) == ["o.toml"]


@pytest.mark.parametrize("argv,out", [
    (["simulate", str(SCENARIO)], UNWRITABLE), (["maneuver", "turning"], UNWRITABLE),
    (["study", "statistics", "--runs", "1"], UNWRITABLE), (["convert", str(SITUATION)], UNWRITABLE + ".toml"),
    (["traffic", "3"], UNWRITABLE + ".toml"), (["tune", "pd"], UNWRITABLE),
])
def test_unwritable_out_is_one_line_and_exit_2(capsys, argv, out):
    assert main([*argv, "--out", out]) == 2
    line = _one_error_line(capsys)
    assert "--out: expected a writable" in line and out in line


def test_the_probe_removes_every_directory_it_made(tmp_path):
    assert check_output(tmp_path / "a" / "b" / "c") == tmp_path / "a" / "b" / "c"
    assert check_output(tmp_path / "x" / "y.toml", kind="file") == tmp_path / "x" / "y.toml"
    assert _files(tmp_path) == []
    (tmp_path / "f").write_text("")
    with pytest.raises(InputError, match="a path in directories only .*f is a file or a broken link"):
        check_output(tmp_path / "f" / "sub")
    with pytest.raises(InputError, match="File name too long"):
        check_output(tmp_path / ("x" * 300))
    with pytest.raises(InputError, match="valid path"):
        check_output(tmp_path / "nul\0byte")
    assert _files(tmp_path) == ["f"]


def test_refused_scenario_leaves_no_directory_from_the_probe(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[settings]\nmethod = 'bogus'\n")
    assert main(["simulate", str(bad), "--out", str(tmp_path / "deep" / "er" / "out")]) == 2
    _one_error_line(capsys)
    assert _files(tmp_path) == ["bad.toml"]


# -------------------------------------------------------------------------- validated before earlier work

@pytest.mark.parametrize("argv,message", [
    (["study", "paper", "--workers", "0"], "--workers: expected an integer in [1, "),
    (["study", "paper", "--seed", "-1"], "--seed: expected an integer >= 0, got -1"),
    (["study", "paper", "--runs", "40000"], "--runs: expected at most 33333 runs for 15 cells"),
    (["tune", "apf", "--workers", "0"], "--workers: expected an integer in [1, "),
    (["tune", "apf", "--holdout-envs", "9"], "--holdout-envs: expected environment numbers in 1-6"),
    (["tune", "apf", "--grid", "101"], "--grid: expected an integer in [1, 100] (MAX_GRID), got 101"),
    (["tune", "apf", "--train", "100001"], "--train: expected an integer in [0, 100000] (MAX_RUNS)"),
    (["tune", "apf", "--holdout", "100001"], "--holdout: expected an integer in [1, 100000] (MAX_RUNS)"),
    (["study", "sweep", "--param", "r_safe", "--values", "10,20", "--workers", "0"], "--workers"),
    (["study", "sweep", "--param", "r_safe", "--values", "10,20", "--baseline", "x"],
     "--baseline: expected a number in (0, inf) L, got 'x'"),
    (["study", "sweep", "--param", "r_safe", "--values", ",".join(str(v) for v in range(1, 12)), "--runs",
      "50000", "--envs", "1"], "--runs: expected at most 41666 runs for 12 cells"),
    (["study", "statistics", "--runs", "100000"], "--runs: expected at most 33333 runs for 15 cells"),
    (["study", "statistics", "--workers", str(max_workers() + 1)], f"[1, {max_workers()}]"),
    (["study", "disturbance", "--wind", "100"], "--wind"),
    # the square (t_max 600) comes after the straight legs (t_max 220) in the disturbance study
    (["study", "disturbance", "--set", "dt=0.005"],
     "t_max / dt: expected at most 100000 steps (MAX_STEPS), got 120000"),
    (["study", "paper", "--set", "dt=0.005"],
     "t_max / dt: expected at most 100000 steps (MAX_STEPS), got 120000"),
    (["study", "imazu", "--targets", "x"], "--targets: expected one of: hold, avoid, both"),
    (["traffic", "2000", "--t-max", "400"], "ships × t_max / dt: expected at most 2400000 ship-steps"),
    (["traffic", "0"], "ships: expected an integer in [1, 2000]"),
    (["traffic", "3", "--seed", "-1"], "--seed: expected an integer >= 0, got -1"),
    # a Ray address nobody answers at: refused by a probe, not minutes later after the compile (issue 29)
    (["study", "statistics", "--runs", "2", "--envs", "1", "--backend", "ray", "--address", "127.0.0.1:1"],
     "--address: expected the host:port of a running Ray cluster (ray start --head; connecting to 127.0.0.1:1"),
    (["study", "statistics", "--backend", "ray", "--address", "head"],
     "--address: expected host:port, ray://host:port, auto or local, got 'head'"),
    (["study", "statistics", "--backend", "ray", "--address", "ray://127.0.0.1:1"],
     "--address: expected the host:port of a running Ray cluster"),
])
def test_bad_input_is_refused_before_any_work_and_writes_nothing(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    out = "o.toml" if argv[0] == "traffic" else "out"
    assert main([*argv, "--out", out]) == 2
    assert message in _one_error_line(capsys)
    assert _files(tmp_path) == []


def test_study_all_refuses_before_its_first_study(tmp_path, capsys):
    assert main(["study", "all", "--set", "dt=0.005", "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == "mmg-casadi: error: t_max / dt: expected at most 100000 steps (MAX_STEPS), got 120000"
    assert len(err) == 2 and err[0].startswith("study waypoint-square -> ")  # the first study's progress line
    assert _files(tmp_path) == []


def test_methods_error_lists_the_allowed_methods(tmp_path, capsys):
    assert main(["study", "statistics", "--methods", "bogus", "--out", str(tmp_path / "o")]) == 2
    line = _one_error_line(capsys)
    assert "argument --methods: expected a non-empty list of: inverse-square, " in line and "got 'bogus'" in line
    assert "_methods" not in line


# ----------------------------------------------------------------------------------------- interruptions

@pytest.mark.parametrize("handler,argv,resumes", [
    ("_simulate", ["simulate", str(SCENARIO)], False), ("_maneuver", ["maneuver", "turning"], False),
    ("_study", ["study", "statistics"], True), ("_study", ["study", "colregs"], False),
    ("_tune", ["tune", "apf"], True),
])
def test_interruption_message_says_whether_the_command_resumes(tmp_path, capsys, monkeypatch, handler, argv,
                                                               resumes):
    def interrupted(_a):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, handler, interrupted)
    assert main([*argv, "--out", str(tmp_path / "o")]) == 130
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert "interrupted by SIGINT" in last
    assert ("rerun the same command to resume" in last) == resumes
    assert ("does not resume" in last) == (not resumes)


# --------------------------------------------------------------------------------------------- memory

def _ships(n):
    return [{"name": f"s{i}", "start": [0.0, 10.0 * i], "heading": 0.0, "speed": 1.0,
             "waypoints": [[50.0, 10.0 * i]]} for i in range(n)]


def test_ship_steps_are_bounded():
    assert check_steps(300.0, 0.25, ships=2000) == 1200
    assert check_steps(300.0, 0.003, ships=2) == 100_000
    with pytest.raises(ParameterError) as err:
        check_steps(300.0, 0.25, ships=2001)
    assert err.value.field == "ships × t_max / dt" and err.value.got == 2001 * 1200 > MAX_SHIP_STEPS
    sc = scenario_from_dict({"settings": {"method": "none", "t_max": 300.0}, "ships": _ships(30)})
    with pytest.raises(ParameterError, match="t_max / dt <= 80000"):
        build_problem(sc, {"dt": 0.003})


def test_a_large_scenario_cannot_be_forced_onto_the_unrolled_step():
    sc = scenario_from_dict({"settings": {"method": "none"}, "ships": _ships(MAX_UNROLLED_SHIPS + 1)})
    with pytest.raises(ParameterError) as err:
        build_problem(sc, {"fleet_from_ships": 1000})
    assert err.value.field == "fleet_from_ships" and "MAX_UNROLLED_SHIPS = 40" in str(err.value)
    assert build_problem(sc, {"fleet_from_ships": MAX_UNROLLED_SHIPS + 1}).layout.neighbours > 0


def test_study_size_is_bounded():
    check_study_size(MAX_STUDY_RUNS // 15, 15)
    with pytest.raises(InputError, match="at most 33333 runs for 15 cells"):
        check_study_size(MAX_STUDY_RUNS // 15 + 1, 15)
    assert check_study_args(runs=100_000, envs="1-5", methods="none")["runs"] == 100_000  # 500 000 runs
    with pytest.raises(InputError) as err:
        check_study_args(runs=100_000, envs="1-5", methods="none,inverse-square")
    assert err.value.field == "runs" and err.value.got == 100_000


# ------------------------------------------------------------------------------------- resume records

KW = dict(runs=1, envs=(1,), methods=("none",), workers=1, progress=False)


def test_runs_csv_has_a_parameter_record_and_a_missing_study_json_cannot_mix_studies(tmp_path):
    run_study(tmp_path, params={"r_safe": 15.0}, **KW)
    record = json.loads((tmp_path / PARAMS_FILE).read_text())
    assert record["fingerprint"] == fingerprint(resolve({"r_safe": 15.0}))
    assert record["params"]["r_safe"] == 15.0 and record["disturbance"] == {"current": None, "wind": None}
    (tmp_path / "study.json").unlink()
    before = (tmp_path / "runs.csv").read_bytes()
    with pytest.raises(InputError) as err:
        run_study(tmp_path, params={"r_safe": 20.0}, **{**KW, "runs": 2})
    assert err.value.field == "params.r_safe" and "15.0" in str(err.value) and err.value.got == 20.0
    assert (tmp_path / "runs.csv").read_bytes() == before
    # the same parameters resume
    run_study(tmp_path, params={"r_safe": 15.0}, **{**KW, "runs": 2})
    assert len(ResultsTable(tmp_path / "runs.csv").read()) == 2


def test_rows_without_their_record_are_not_resumed(tmp_path):
    run_study(tmp_path, **KW)
    (tmp_path / PARAMS_FILE).unlink()
    (tmp_path / "study.json").unlink()
    with pytest.raises(InputError) as err:
        run_study(tmp_path, **{**KW, "runs": 2})
    assert err.value.field == "out_dir" and "runs.params.json" in str(err.value)
    assert len(ResultsTable(tmp_path / "runs.csv").read()) == 1


def test_a_table_scored_by_another_scorer_version_is_not_resumed(tmp_path):
    """A table made before its record named the scorer (only a study.json), or by scorer version 1, would mix
    verdicts of two scorers: refused in one message naming both versions, nothing written."""
    run_study(tmp_path, **KW)
    assert json.loads((tmp_path / PARAMS_FILE).read_text())["scorer"] == SCORER_VERSION
    record = json.loads((tmp_path / PARAMS_FILE).read_text())
    before = (tmp_path / "runs.csv").read_bytes()
    for older in ({**record, "scorer": 1}, None):
        if older is None:
            (tmp_path / PARAMS_FILE).unlink()  # an older table, checked against its study.json
        else:
            (tmp_path / PARAMS_FILE).write_text(json.dumps(older))
        with pytest.raises(InputError, match=f"scorer of version {SCORER_VERSION} .this one was scored by version 1"):
            run_study(tmp_path, **{**KW, "runs": 2})
        assert (tmp_path / "runs.csv").read_bytes() == before


def test_range_mismatch_on_resume_names_both_ranges(tmp_path, capsys):
    run_study(tmp_path, **KW)
    assert main(["study", "statistics", "--runs", "1", "--envs", "1", "--methods", "none", "--workers", "1",
                 "--current", "0-0.1", "--out", str(tmp_path)]) == 2
    line = _one_error_line(capsys)
    assert "--current: expected no range (calm water), what" in line and "got 'the range 0-0.1'" in line
    assert "None" not in line


def test_a_refused_resume_creates_no_lock_file(tmp_path):
    run_study(tmp_path / "a", **KW)
    (tmp_path / "a" / ".study.lock").unlink()
    with pytest.raises(InputError, match="base_seed"):
        run_study(tmp_path / "a", base_seed=1, **KW)
    assert not (tmp_path / "a" / ".study.lock").exists()


# ----------------------------------------------------------------------------------------------- sweep

def test_integer_boolean_and_choice_parameters_can_be_swept():
    assert parse_values("vo_candidates", "40,80") == [40, 80]
    assert parse_values("vo_hold", "true, false") == [True, False]
    assert parse_values("vo_cone", "wide,huang") == ["wide", "huang"]
    with pytest.raises(InputError) as err:
        parse_values("vo_candidates", "40.5")
    assert err.value.field == "values" and "an integer in [1, 720]" in str(err.value)
    with pytest.raises(InputError) as err:
        parse_values("vo_hold", ["maybe"], "baseline")
    assert err.value.field == "baseline"
    assert [_fmt(v) for v in (15.0, 40, True, "wide")] == ["15", "40", "true", "wide"]


def test_sweep_report_of_a_choice_parameter(tmp_path):
    rows = [{"environment": 5, "method": "m", "value": v, "baseline": "wide", "runs": 10, "success_rate": s,
             "success_ci_low": s - 0.1, "success_ci_high": s + 0.05, "difference": s - 0.8,
             "difference_ci_low": -0.2, "difference_ci_high": 0.2, "value_only": 1, "baseline_only": 2,
             "p_value": 0.5, "ce_mean": 0.1, "mcte_mean": 1.0, "ce_paired_diff": 0.0, "mcte_paired_diff": 0.0,
             **{f"failures_{f}": 1 for f in FAILURES[1:]}}
            for v, s in (("wide", 0.8), ("huang", 0.6))]
    md = markdown(rows, "vo_cone")
    assert "Δ vs wide" in md and "| 5 | m | huang | 0.6000 " in md
    fig = plot_sweep(rows, "vo_cone", tmp_path / "s.png")
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()] == ["huang", "wide"]
    assert (tmp_path / "s.png").stat().st_size > 0


def test_probe_in_an_existing_directory_leaves_nothing(tmp_path):
    """The probe's temporary file is removed also when the directory existed before."""
    check_output(tmp_path)
    assert os.listdir(tmp_path) == []
