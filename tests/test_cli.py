"""Command-line interface: manoeuvres, simulate, bad input (one line, exit code 2, nothing written)."""

import json
import subprocess
import sys
from importlib import resources

import numpy as np
import pytest

from mmg_casadi.cli import main

SCENARIOS = resources.files("mmg_casadi").joinpath("data", "scenarios")


def test_turning_writes_metrics_and_figure(tmp_path):
    assert main(["maneuver", "turning", "--rudder", "35", "--port", "--out", str(tmp_path)]) == 0
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert {"advance", "transfer", "tactical_diameter"} <= set(m) and m["direction"] == "port"
    assert list(tmp_path.glob("*.png"))


@pytest.mark.parametrize("angle", ["10", "20"])
def test_zigzag_writes_overshoots(tmp_path, angle):
    assert main(["maneuver", "zigzag", "--angle", angle, "--out", str(tmp_path)]) == 0
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert m["overshoot_1"] > 0 and m["overshoot_2"] > 0


def test_port_first_zigzag_of_the_kvlcc2_and_port_refused_for_a_speed_change(tmp_path, capsys):
    """The KVLCC2's -10/-10 zig-zag (docs/howto/vessels.md: 8.3 / 10.0 deg, unlike +10/+10's 5.6 / 15.3)."""
    assert main(["maneuver", "zigzag", "--port", "--vessel", "kvlcc2", "--out", str(tmp_path)]) == 0
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert (round(m["overshoot_1"], 1), round(m["overshoot_2"], 1)) == (8.3, 10.0)
    assert (tmp_path / "zigzag_10_port.png").exists()
    capsys.readouterr()
    assert main(["maneuver", "speed", "--port", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--port" in err[0] and not (tmp_path / "s").exists()


@pytest.mark.parametrize("argv,field", [
    (["maneuver", "spin"], "maneuver"),
    (["maneuver", "turning", "--rudder", "40"], "rudder"),
    (["maneuver", "turning", "--speed", "-1"], "speed"),
    (["maneuver", "zigzag", "--angle", "abc"], "--angle"),
    (["study", "nowhere"], "study"),
])
def test_bad_input_is_one_line_exit_2_nothing_written(tmp_path, capsys, argv, field):
    out = tmp_path / "o"
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert not out.exists()


def test_console_script_exit_code_and_no_traceback(tmp_path):
    res = subprocess.run([sys.executable, "-m", "mmg_casadi.cli", "maneuver", "turning", "--rudder", "99",
                          "--out", str(tmp_path / "x")], capture_output=True, text=True)
    assert res.returncode == 2
    assert "Traceback" not in res.stderr and "rudder" in res.stderr


def test_simulate_writes_trajectories_metrics_and_figure(tmp_path):
    f = SCENARIOS / "head_on.toml"
    assert main(["simulate", str(f), "--method", "modified-vortex", "--out", str(tmp_path)]) == 0
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert m["method"] == "modified-vortex" and m["collision"] is False
    assert [s["name"] for s in m["ships"]] == ["ship1", "ship2"]
    npz = np.load(tmp_path / "trajectory.npz")
    assert npz["states"].shape[1] == 2
    header = (tmp_path / "trajectory.csv").read_text().splitlines()[0]
    assert header.startswith("t,ship,u,v,r,x,y,psi,delta")
    assert (tmp_path / "scenario.png").stat().st_size > 10000


@pytest.mark.parametrize("name", sorted(p.name for p in SCENARIOS.iterdir() if p.name.endswith(".toml")))
def test_every_shipped_scenario_simulates(tmp_path, name):
    assert main(["simulate", str(SCENARIOS / name), "--out", str(tmp_path)]) == 0
    m = json.loads((tmp_path / "metrics.json").read_text())
    assert all(np.isfinite(s["ce"]) for s in m["ships"])


@pytest.mark.parametrize("text,field", [
    ("[settings]\nmethod='warp'\n[[ships]]\nstart=[0,0]\nheading=0\nspeed=1\nwaypoints=[[5,0]]\n", "settings.method"),
    ("[settings]\nmethod='none'\n[[ships]]\nstart=[0,0]\nheading=0\nwaypoints=[[5,0]]\n", "ships[0].speed"),
    ("[settings]\nmethod='none'\n[[ships]]\nstart='here'\nheading=0\nspeed=1\nwaypoints=[[5,0]]\n", "ships[0].start"),
    ("[settings]\nmethod='none'\n[[ships]]\nstart=[25,0]\nheading=0\nspeed=1\nwaypoints=[[50,0]]\n"
     "[[obstacles]]\nposition=[25,0.2]\n", "ships[0].start"),
    ("[settings\n", "toml"),
])
def test_simulate_rejects_bad_scenario_files(tmp_path, capsys, text, field):
    f = tmp_path / "bad.toml"
    f.write_text(text)
    out = tmp_path / "out"
    assert main(["simulate", str(f), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert not out.exists()


def test_params_file_overrides_field_parameters(tmp_path):
    p = tmp_path / "params.toml"
    p.write_text("[params]\nk_vor0 = -20.0\nlam_sink = -100.0\n")
    f = SCENARIOS / "head_on.toml"
    assert main(["simulate", str(f), "--params", str(p), "--out", str(tmp_path / "a")]) == 0
    assert main(["simulate", str(f), "--out", str(tmp_path / "b")]) == 0
    da = json.loads((tmp_path / "a" / "metrics.json").read_text())["pairs"][0]["min_distance"]
    db = json.loads((tmp_path / "b" / "metrics.json").read_text())["pairs"][0]["min_distance"]
    assert da != pytest.approx(db, abs=1e-3)
    p.write_text("[params]\nwarp = 9\n")
    assert main(["simulate", str(f), "--params", str(p), "--out", str(tmp_path / "c")]) == 2


@pytest.mark.parametrize("text,field", [("kd = -1.0", "kd"), ("ilos_delta = 0.0", "ilos_delta"),
                                        ("lam_sink = 5.0", "lam_sink")])
def test_out_of_range_field_parameters_in_a_scenario_file_are_rejected(tmp_path, capsys, text, field):
    f = tmp_path / "bad.toml"
    f.write_text(f"[settings]\nmethod='modified-vortex'\n{text}\n[[ships]]\nstart=[0,0]\nheading=0\nspeed=1\n"
                 "waypoints=[[50,0]]\n")
    out = tmp_path / "out"
    assert main(["simulate", str(f), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0]
    assert not out.exists()


def test_params_file_with_r_safe_as_written_by_tune_apf(tmp_path):
    p = tmp_path / "params.toml"
    p.write_text("[params]\nk_vor0 = -20.0\nlam_sink = -150.0\nr_safe = 12.0\n")
    assert main(["simulate", str(SCENARIOS / "head_on.toml"), "--params", str(p), "--out", str(tmp_path / "a")]) == 0


def test_generated_traffic_simulates_with_the_fleet_step(tmp_path):
    f = tmp_path / "traffic.toml"
    assert main(["traffic", "24", "--seed", "3", "--t-max", "10", "--out", str(f)]) == 0
    assert main(["simulate", str(f), "--out", str(tmp_path / "run")]) == 0
    m = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert len(m["ships"]) == 24 and m["t_end"] == 10.0
    assert m["params"]["fleet_from_ships"] <= 24  # so the fleet step ran
    assert (tmp_path / "run" / "scenario.png").stat().st_size > 10_000
    # in a fleet scenario, pairs are those that came within R_safe
    assert all(p["min_distance"] <= m["params"]["r_safe"] for p in m["pairs"])


@pytest.mark.parametrize("argv, field", [
    (["traffic", "2001"], "ships"),
    (["traffic", "10", "--method", "vortex"], "--method"),
    (["traffic", "10", "--t-max", "-1"], "--t-max"),
])
def test_traffic_refuses_bad_input(tmp_path, capsys, argv, field):
    out = tmp_path / "t.toml"
    assert main([*argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and field in err[0] and not out.exists()


def test_more_steps_than_the_limit_are_refused_before_any_work(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", str(SCENARIOS / "head_on.toml"), "--set", "dt=1e-6", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "MAX_STEPS" in err and not out.exists()


@pytest.mark.parametrize("study", ["paper", "statistics"])
def test_too_many_runs_are_refused_before_any_work(tmp_path, capsys, study):
    out = tmp_path / "s"
    assert main(["study", study, "--runs", str(10**9), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--runs" in err[0] and "MAX_RUNS" in err[0] and not out.exists()
