"""Double-run determinism (issue 26): ``--check-determinism`` runs a command twice and compares the outputs outside
the timing columns; identical runs exit 0, a difference is printed and exits 1; commands without the option
refuse it (one line, exit 2)."""

import json
import shutil
from importlib import resources

import numpy as np
import pytest

from mmg_casadi import cli
from mmg_casadi.cli import main
from mmg_casadi.determinism import compare_outputs, is_timing

SCENARIOS = resources.files("mmg_casadi").joinpath("data", "scenarios")


def _no_leftovers(folder):
    return not any(p.name.startswith(".determinism-") for p in folder.iterdir())


def test_simulate_twice_gives_identical_outputs(tmp_path, capsys):
    assert main(["simulate", "head_on", "--set", "t_max=20", "--out", str(tmp_path / "o"),
                 "--check-determinism"]) == 0
    out = capsys.readouterr().out
    assert "determinism: the two runs wrote identical outputs (3 files compared" in out
    assert _no_leftovers(tmp_path)


def test_study_encounters_twice_gives_identical_outputs(tmp_path, capsys):
    (tmp_path / "set").mkdir()
    for name in ("head_on", "crossing"):
        shutil.copy(SCENARIOS / f"{name}.toml", tmp_path / "set" / f"{name}.toml")
    assert main(["study", "encounters", str(tmp_path / "set"), "--methods", "modified-vortex", "--set", "t_max=30",
                 "--out", str(tmp_path / "o"), "--check-determinism"]) == 0
    assert "identical outputs (2 files compared; timing columns excluded)" in capsys.readouterr().out
    assert _no_leftovers(tmp_path)


@pytest.mark.slow
def test_study_statistics_twice_gives_identical_runs(tmp_path, capsys):
    assert main(["study", "statistics", "--runs", "2", "--envs", "1", "--methods", "modified-vortex",
                 "--workers", "1", "--out", str(tmp_path / "o"), "--check-determinism"]) == 0
    assert "identical outputs" in capsys.readouterr().out


@pytest.mark.slow
def test_study_statistics_with_two_workers_twice_is_identical_whatever_the_order_of_the_rows(tmp_path, capsys):
    # two workers append batches in the order they finish: the second run's runs.csv rows may come in another
    # order; --check-determinism matches them by (environment, method, run)
    assert main(["study", "statistics", "--runs", "40", "--envs", "1,2", "--methods", "inverse-square,none",
                 "--workers", "2", "--out", str(tmp_path / "o"), "--check-determinism"]) == 0
    assert "identical outputs" in capsys.readouterr().out


def test_a_second_run_that_differs_is_reported_and_exits_1(tmp_path, capsys, monkeypatch):
    real, calls = cli.run_scenario, []

    def drifting(sc, params=None):  # a planted difference in the second run
        res = real(sc, params=params)
        calls.append(1)
        if len(calls) == 2:
            res.metrics["ships"][0]["ce"] += 1e-12
        return res

    monkeypatch.setattr(cli, "run_scenario", drifting)
    assert main(["simulate", "head_on", "--set", "t_max=20", "--out", str(tmp_path / "o"),
                 "--check-determinism"]) == 1
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("mmg-casadi: determinism: the two runs differ: metrics.json.ships[0].ce: ")
    assert _no_leftovers(tmp_path)


def _write(d, runs, metrics):
    d.mkdir()
    (d / "runs.csv").write_text(runs)
    (d / "metrics.json").write_text(json.dumps(metrics))


def test_the_comparison_skips_timings_and_finds_a_planted_difference(tmp_path):
    runs = "run,ce,guidance_call_us\n0,0.125,{}\n1,0.25,{}\n"
    metrics = {"elapsed_s": 1.0, "summary": [{"ce_mean": 0.1875, "guidance_call_us_mean": 3.0}]}
    _write(tmp_path / "a", runs.format(0.61, 0.62), metrics)
    _write(tmp_path / "b", runs.format(0.93, 0.71), {**metrics, "elapsed_s": 7.0,
                                                    "summary": [{"ce_mean": 0.1875, "guidance_call_us_mean": 9.0}]})
    assert compare_outputs(tmp_path / "a", tmp_path / "b") == (None, 2)
    (tmp_path / "b" / "runs.csv").write_text(runs.format(0.93, 0.71).replace("1,0.25,", "1,0.2500001,"))
    assert compare_outputs(tmp_path / "a", tmp_path / "b")[0] == "runs.csv row 2 column ce: '0.25' vs '0.2500001'"
    (tmp_path / "b" / "runs.csv").write_text(runs.format(0.61, 0.62))
    (tmp_path / "b" / "metrics.json").write_text(json.dumps({**metrics, "summary": [{"ce_mean": 0.2}]}))
    assert compare_outputs(tmp_path / "a", tmp_path / "b")[0] == "metrics.json.summary[0].ce_mean: 0.1875 vs 0.2"
    (tmp_path / "b" / "metrics.json").write_text(json.dumps(metrics))
    np.savez_compressed(tmp_path / "a" / "t.npz", x=np.array([1.0, 2.0]))
    np.savez_compressed(tmp_path / "b" / "t.npz", x=np.array([1.0, np.nextafter(2.0, 3.0)]))
    assert compare_outputs(tmp_path / "a", tmp_path / "b")[0].startswith("t.npz: array x entry (1,)")
    (tmp_path / "b" / "t.npz").unlink()
    assert compare_outputs(tmp_path / "a", tmp_path / "b")[0] == "t.npz: written by the first run only"
    assert is_timing("wall_s") and not is_timing("walls")


@pytest.mark.parametrize("argv", [["generate", "--out", "x"], ["vessels"], ["params"]])
def test_commands_without_the_option_refuse_it(tmp_path, capsys, argv):
    assert main(argv + ["--check-determinism"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("mmg-casadi: error: --check-determinism: expected an option of") and "\n" not in err


def test_tables_of_runs_are_compared_by_key_not_by_row_order(tmp_path):
    # runs.csv rows follow the order in which batches finish: two identical studies may store them in another
    # order (before, `study statistics --check-determinism` reported a difference between identical runs)
    from mmg_casadi.determinism import compare_outputs
    head = "environment,method,run,success,guidance_call_us\n"
    rows = ["1,a,0,True,0.5\n", "1,a,1,False,0.6\n", "2,a,0,True,0.7\n"]
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir(), b.mkdir()
    (a / "runs.csv").write_text(head + "".join(rows))
    (b / "runs.csv").write_text(head + "".join(reversed(rows)).replace("0.5", "9.9"))  # timing differs too
    assert compare_outputs(a, b) == (None, 1)
    (b / "runs.csv").write_text(head + "".join(reversed(rows)).replace("1,a,1,False", "1,a,1,True"))
    diff, _n = compare_outputs(a, b)
    assert diff == "runs.csv run {'environment': '1', 'method': 'a', 'run': '1'} column success: 'False' vs 'True'"
    (b / "runs.csv").write_text(head + "".join(rows[:2]))
    assert compare_outputs(a, b)[0] == "runs.csv: run {'environment': '2', 'method': 'a', 'run': '0'} only in the " \
                                       "first run"
    (b / "runs.csv").write_text(head + "".join(rows + rows[:1]))
    assert "twice in the second run" in compare_outputs(a, b)[0]
