"""What a newcomer meets first (issue 46): --version, --quiet, one clear error prefix, a summary line per ship after
`simulate`, a notice while compiling (none when cached), the study and scenario listings, run_scenario by name,
the AIS replay's default method, the licence."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

import pytest

import mmg_casadi as mc
from mmg_casadi.cli import STUDIES, STUDY_HELP, build_parser, main
from mmg_casadi.scenarios.run import packaged_scenarios

ROOT = Path(__file__).resolve().parents[1]
ONE_SHIP = """
[settings]
method = "none"
t_max = 6.0
[[ships]]
name = "solo"
start = [0.0, 0.0]
heading = 0.0
speed = 1.0
waypoints = [[60.0, 0.0]]
"""


def test_version(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and capsys.readouterr().out.strip() == f"mmg-casadi {mc.__version__}"


@pytest.mark.parametrize("argv, text", [([], "the following arguments are required"),
                                         (["simulate"], "the following arguments are required: file, --out"),
                                         (["study", "nonsense", "--out", "x"], "invalid choice")])
def test_one_error_prefix(capsys, argv, text):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("mmg-casadi: error:") == 1 and "error: mmg-casadi" not in err and text in err
    assert len(err.splitlines()) == 1


def test_every_study_has_its_own_help():
    assert set(STUDY_HELP) == set(STUDIES)
    assert len(set(STUDY_HELP.values())) == len(STUDIES)
    text = build_parser()._subparsers._group_actions[0].choices["study"].format_help()
    assert "the imazu study" not in text and "22 Imazu problems" in text


def test_scenario_descriptions_are_whole():
    for row in packaged_scenarios():
        d = row["description"]
        assert d and d.count("(") == d.count(")"), row
    fjord = {r["name"]: r for r in packaged_scenarios()}["fjord_island"]["description"]
    assert fjord == "A fjord entrance with an island (our construction, for the land hazards)"


def test_run_scenario_takes_a_shipped_name_as_simulate_does():
    r = mc.run_scenario("head_on", params={"t_max": 2.0})
    assert r.names() == ["ship1", "ship2"] and r.metrics["params"]["t_max"] == 2.0


def test_simulate_prints_one_line_per_ship_and_quiet_prints_nothing(tmp_path, capsys):
    assert main(["simulate", "head_on", "--out", str(tmp_path / "a")]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2
    assert re.fullmatch(r"ship1  reached its goal at t = 51\.8 L/U; closest 5\.77 L to ship2 at t = 25\.2 L/U; "
                        r"COLREG \(published\): 0 of 1 risky encounters kept; broken: head-on with ship2: Rule 8", out[0]), out[0]
    assert main(["simulate", "head_on", "--units", "si", "--out", str(tmp_path / "b")]) == 0
    assert "closest 1326 m to ship2 at t = 470 s" in capsys.readouterr().out
    assert main(["simulate", "head_on", "--quiet", "--out", str(tmp_path / "c")]) == 0
    assert capsys.readouterr() == ("", "")
    assert main(["--quiet", "simulate", "head_on", "--out", str(tmp_path / "d")]) == 0
    assert capsys.readouterr() == ("", "")
    assert main(["simulate", "head_on", "--units", "imperial", "--out", str(tmp_path / "e")]) == 2
    assert "units: expected one of: nd, si, got 'imperial'" in capsys.readouterr().err
    assert not (tmp_path / "e").exists()


def test_a_compile_is_announced_once_and_a_cached_library_not(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("MMG_CASADI_CACHE", str(tmp_path / "cache"))
    scenario = tmp_path / "solo.toml"
    scenario.write_text(ONE_SHIP)
    from mmg_casadi.closed_loop import simulation

    def forget():  # the in-process memo of compiled steps and rollouts (an earlier test may have this layout)
        for f in vars(simulation).values():
            if hasattr(f, "cache_clear"):
                f.cache_clear()
    forget()
    assert main(["simulate", str(scenario), "--out", str(tmp_path / "a")]) == 0
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and re.fullmatch(r"compiling closed loop for 1 ship \(none\) … \d+ s \(cached for next time\)",
                                          err[0]), err
    forget()
    assert main(["simulate", str(scenario), "--out", str(tmp_path / "b")]) == 0
    assert capsys.readouterr().err == ""
    from mmg_casadi import compiled
    assert compiled.NOTICES["stream"] is None  # the library is silent again after the command


def test_the_ais_replay_sample_with_the_default_method(tmp_path, capsys):
    """The replayed route has a waypoint every 60 s (1.9 L): the modified vortex, whose sink sits at the next
    waypoint, cannot give way to the target and passes within the collision distance; the replay's default
    method, colregs-vortex, keeps clear (mmg_casadi.scenarios.ais_replay.REPLAY_METHOD)."""
    sample = ROOT / "mmg_casadi" / "data" / "ais" / "synthetic_ais.csv"
    out = tmp_path / "replay.toml"
    assert main(["replay", str(sample), "--own", "999000001", "--out", str(out)]) == 0
    assert tomllib.loads(out.read_text())["settings"]["method"] == "colregs-vortex"
    capsys.readouterr()
    assert main(["simulate", str(out), "--out", str(tmp_path / "cv")]) == 0
    own = capsys.readouterr().out.splitlines()[0]
    assert "closest 4.18 L to 999000002" in own and "collided" not in own
    r = mc.run_scenario(out, method="modified-vortex")
    assert r.metrics["collision"] and round(r.metrics["pairs"][0]["min_distance"], 2) == 0.74


def test_licence_and_citation():
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert meta["project"]["license"] == "BSD-3-Clause" and meta["project"]["license-files"] == ["LICENSE"]
    assert (ROOT / "LICENSE").read_text().startswith("BSD 3-Clause License")
    cff = (ROOT / "CITATION.cff").read_text()
    assert f"version: {mc.__version__}" in cff and "license: BSD-3-Clause" in cff and "Somayajula" in cff


@pytest.mark.parametrize("name", ["run.gif", "run.mp4"])
def test_animation_of_a_run(tmp_path, name):
    from mmg_casadi.animation import animate, encounter_roles
    if name.endswith(".mp4"):
        pytest.importorskip("imageio_ffmpeg")
    r = mc.run_scenario("crossing", params={"t_max": 30.0})
    path = animate(r, tmp_path / name, max_frames=12)
    assert path.stat().st_size > 1000
    if name.endswith(".gif"):
        from PIL import Image
        with Image.open(path) as im:
            assert im.n_frames == 12 and im.size == (598, 299)
    else:
        assert path.read_bytes()[4:8] == b"ftyp"  # an MP4 container
    roles = encounter_roles(r.metrics)
    assert ("ship1", "ship2", "give-way") in [x[:3] for x in roles]


def test_animate_refuses_other_files_before_any_work(tmp_path, capsys):
    assert main(["simulate", "head_on", "--animate", "run.avi", "--out", str(tmp_path / "x")]) == 2
    assert "--animate: expected a file name ending in .gif or .mp4" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()
