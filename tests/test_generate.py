"""Standard encounter sets (`mmg-casadi generate`): the geometry solved as asked, every situation classified as
requested from both sides, bad descriptions refused in one line with nothing written, byte-identical output for a
seed; and the encounters study over a generated set (`mmg-casadi study encounters`)."""

import json
import math

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.colregs.scorer import score_encounters
from mmg_casadi.errors import InputError
from mmg_casadi.scenarios.generate import (DEFAULT_RANGES, ENCOUNTER_TYPES, ROLES, classified, description_from_dict,
                                           generate, override, set_files, solve_target, standard_description,
                                           straight_lines)
from mmg_casadi.scenarios.maritime_schema import load_traffic_situation
from mmg_casadi.scenarios.scenario import Scenario, Settings, ShipSpec, load_scenario
from studies import encounters as study


def _relative(own_course, own_speed, bearing, course, speed, rng):
    """TCPA, signed-free CPA and bearing of a target at ``rng`` on ``bearing`` sailing ``course`` at ``speed``."""
    u = lambda deg: np.array([math.cos(math.radians(deg)), math.sin(math.radians(deg))])  # noqa: E731
    r0 = rng * u(own_course + bearing)
    vr = speed * u(course) - own_speed * u(own_course)
    tcpa = -float(r0 @ vr) / float(vr @ vr)
    return tcpa, float(np.hypot(*(r0 + tcpa * vr)))


@pytest.mark.parametrize("bearing,ratio,tcpa,cpa", [(0.0, 1.0, 30.0, 0.0), (5.0, 0.8, 35.0, 0.7),
                                                    (60.0, 1.2, 40.0, -0.5), (-45.0, 0.8, 30.0, 0.9),
                                                    (180.0, 1.6, 80.0, 0.3), (10.0, 0.4, 90.0, -1.0)])
def test_solved_targets_meet_the_own_ship_as_asked(bearing, ratio, tcpa, cpa):
    sols = solve_target(20.0, 0.7, bearing, ratio, tcpa, cpa)
    assert sols
    for course, rng in sols:
        t, d = _relative(20.0, 0.7, bearing, course, ratio * 0.7, rng)
        assert t == pytest.approx(tcpa, abs=1e-6) and d == pytest.approx(abs(cpa), abs=1e-6)


def test_head_on_at_equal_speed_starts_twice_the_meeting_distance_ahead():
    assert solve_target(0.0, 1.0, 0.0, 1.0, 30.0, 0.0) == [(-180.0, pytest.approx(60.0))]
    assert solve_target(0.0, 1.0, 90.0, 0.5, 30.0, 0.0) == []  # a slower target cannot come from the beam


def test_standard_description_is_the_sandvik_kind_of_set():
    d = standard_description()
    kinds = {tuple(t.type for t in g.targets) for g in d.groups}
    assert {(t,) for t in ENCOUNTER_TYPES} <= kinds
    assert sum(len(k) == 2 for k in kinds) == 10 and sum(len(k) == 3 for k in kinds) == 7
    assert (d.situations, d.seed, d.own_speed, d.own_leg) == (110, 2023, 0.7, 100.0)
    head_on = d.groups[0].targets[0]
    assert head_on.type == "head-on" and head_on.bearing == DEFAULT_RANGES["head-on"]["bearing"] == (-10.0, 10.0)


def test_generated_situations_are_the_requested_encounters_from_both_sides():
    d = override(standard_description(), situations=22)
    es = generate(d)
    assert len(es.situations) == 22 and es.stats["accepted"] == 22
    assert es.stats["checked"] >= 22 and 0.0 < es.stats["acceptance_share"] <= 1.0
    for s in es.situations:
        sc, types = s.scenario, [t["type"] for t in s.targets]
        own = sc.ships[0]
        assert own.start == (0.0, 0.0) and own.heading_deg == 0.0 and own.speed == 0.7 and own.goal == (100.0, 0.0)
        assert all(t.method == "none" for t in sc.ships[1:]) and len(types) == len(sc.ships) - 1
        t, pos, psi, speed = straight_lines(sc, 100.0 / 0.7)
        enc = [e for e in score_encounters(t, pos, psi, speed) if e.applicable]
        for j, kind in enumerate(types, start=1):
            assert [e.role for e in enc if (e.own, e.other) == (0, j)] == [ROLES[kind][0]]
            assert [e.role for e in enc if (e.own, e.other) == (j, 0)] == [ROLES[kind][1]]
        specs = next(g for g in d.groups if g.name == s.group).targets
        for drawn, ship, spec in zip(s.targets, sc.ships[1:], specs):
            assert drawn["start_range"] >= 20.0 and math.dist(ship.start, own.start) >= 20.0 - 1e-6
            assert spec.cpa[0] <= abs(drawn["cpa"]) <= spec.cpa[1] and spec.tcpa[0] <= drawn["tcpa"] <= spec.tcpa[1]
            assert spec.speed_ratio[0] <= drawn["speed_ratio"] <= spec.speed_ratio[1]
            assert ship.speed == pytest.approx(0.7 * drawn["speed_ratio"], abs=1e-6)
            tcpa, cpa = _relative(0.0, 0.7, drawn["bearing"], ship.heading_deg, ship.speed, drawn["start_range"])
            assert tcpa == pytest.approx(drawn["tcpa"], abs=1e-3) and cpa == pytest.approx(abs(drawn["cpa"]), abs=1e-3)


def test_the_check_rejects_draws_outside_the_requested_encounter():
    # bearings from ahead to the beam and courses from reciprocal to crossing: some draws are head-on
    d = description_from_dict({"set": {"situations": 12, "seed": 3}, "groups": [{"targets": [
        {"type": "crossing-give-way", "bearing": [0.0, 60.0], "relative_course": [-190.0, -60.0]}]}]})
    es = generate(d)
    st = es.stats
    assert st["accepted"] == 12 and st["checked"] > 12 and st["acceptance_share"] == 12 / st["checked"]
    assert all(classified(s.scenario, ["crossing-give-way"]) for s in es.situations)
    assert not all(classified(s.scenario, ["head-on"]) for s in es.situations)


def test_classified_checks_both_sides():
    own = ShipSpec("own", [0, 0], 0, 1, [[80, 0]])
    head_on = Scenario(Settings("none"), [own, ShipSpec("t", [60, 0], 180, 1, [[-20, 0]])])
    crossing = Scenario(Settings("none"), [own, ShipSpec("t", [30, 30], -90, 1, [[30, -50]])])
    overtaking = Scenario(Settings("none"), [own, ShipSpec("t", [20, 0], 0, 0.5, [[80, 0]])])
    assert classified(head_on, ["head-on"]) and not classified(head_on, ["overtaking"])
    assert classified(crossing, ["crossing-give-way"]) and not classified(crossing, ["crossing-stand-on"])
    assert classified(overtaking, ["overtaking"]) and not classified(overtaking, ["overtaken"])
    # a target starting inside the risk range: the encounter does not begin after the start
    near = Scenario(Settings("none"), [own, ShipSpec("t", [10, 0], 180, 1, [[-20, 0]])])
    assert not classified(near, ["head-on"])


def test_generation_is_deterministic_and_a_prefix_of_a_longer_set(tmp_path):
    d = override(standard_description(), situations=12)
    assert set_files(generate(d)) == set_files(generate(d))
    longer = set_files(generate(override(d, situations=30)))
    short = set_files(generate(d))
    assert all(longer[k] == v for k, v in short.items() if k != "generation.json")
    other = set_files(generate(override(d, seed=7)))
    assert other["s000_HO.toml"] != short["s000_HO.toml"]
    for name in ("a", "b"):
        assert main(["generate", "--situations", "12", "--out", str(tmp_path / name)]) == 0
    files = sorted(p.relative_to(tmp_path / "a") for p in (tmp_path / "a").rglob("*") if p.is_file())
    assert len(files) == 25  # 12 scenario files, 12 traffic situations, generation.json
    assert all((tmp_path / "a" / f).read_bytes() == (tmp_path / "b" / f).read_bytes() for f in files)


def test_written_files_read_back(tmp_path):
    d = override(standard_description(), situations=6)
    es = generate(d)
    assert main(["generate", "--situations", "6", "--out", str(tmp_path)]) == 0
    record = json.loads((tmp_path / "generation.json").read_text())
    assert record["stats"]["accepted"] == 6 and record["description"]["set"]["seed"] == 2023
    for s in es.situations:
        sc = load_scenario(tmp_path / f"{s.id}.toml")
        assert sc == s.scenario
        json_sc = load_traffic_situation(tmp_path / "maritime" / f"{s.id}.json")[0]
        assert len(json_sc.ships) == len(sc.ships)
        for a, b in zip(json_sc.ships, sc.ships):
            assert a.start == pytest.approx(b.start, abs=1e-3) and a.speed == pytest.approx(b.speed, abs=1e-3)


@pytest.mark.parametrize("text,field", [
    ('[[groups]]\ntargets = ["crossing"]\n', "groups[0].targets[0]"),
    ('[[groups]]\ntargets = []\n', "groups[0].targets"),
    ('[set]\nsituations = 0\n[[groups]]\ntargets = ["head-on"]\n', "set.situations"),
    ('[set]\nprofile = "strict"\n[[groups]]\ntargets = ["head-on"]\n', "set.profile"),
    ('[own_ship]\nspeed = 2.0\n[[groups]]\ntargets = ["head-on"]\n', "own_ship.speed"),
    ('[[groups]]\ntargets = [{type = "head-on", cpa = [0.0, 5.0]}]\n', "groups[0].targets[0].cpa"),
    ('[[groups]]\ntargets = [{type = "overtaken", speed_ratio = [1.5, 2.0]}]\n', "groups[0].targets[0].speed_ratio"),
    ('[[groups]]\ntargets = [{type = "overtaking", tcpa = [70.0, 200.0]}]\n', "groups[0].targets[0].tcpa"),
    ('[encounters.head-on]\nbearing = [10.0, -10.0]\n[[groups]]\ntargets = ["head-on"]\n', "encounters.head-on.bearing"),
    ('[set]\nmax_attempts = 1\n[[groups]]\ntargets = [{type = "head-on", bearing = [40.0, 50.0]}]\n',
     "groups[0].targets[0]"),
    ('[set]\nsituationz = 3\n', "set.situationz"),
    ('[set]\nmax_attempts = 5\n[encounters.head-on]\nbearing = [0.0, 0.0]\nrelative_course = [180.0, 180.0]\n'
     'speed_ratio = [1.0, 1.0]\ntcpa = [30.0, 30.0]\ncpa = [0.0, 0.0]\n[[groups]]\ntargets = ["head-on", "head-on"]\n',
     "groups[0]"),  # two targets on the same spot: never separated
    ('[[groups]\n', "toml"),
    ('[set]\nsituations = 1\nt_max = 1500.0\n[own_ship]\nleg = 1000.0\n[[groups]]\ntargets = ["head-on"]\n',
     "own_ship.leg"),  # 230 km: beyond the maritime-schema file's local plane
    ('[set]\nt_max = 100.0\n[[groups]]\ntargets = ["head-on"]\n', "set.t_max"),
])
def test_bad_descriptions_are_one_line_exit_2_nothing_written(tmp_path, capsys, text, field):
    f = tmp_path / "d.toml"
    f.write_text(text)
    out = tmp_path / "out"
    assert main(["generate", str(f), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"mmg-casadi: error: {field}: expected") and "\n" not in err
    assert not out.exists()


def test_bad_generate_options(tmp_path, capsys):
    assert main(["generate", "--situations", "0", "--out", str(tmp_path / "o")]) == 2
    assert "--situations: expected an integer in [1, 10000], got 0" in capsys.readouterr().err
    assert main(["generate", str(tmp_path / "missing.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "expected an existing, readable description file" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    with pytest.raises(InputError, match="seed"):
        override(standard_description(), seed=-1)


def test_study_encounters_pairs_methods_and_repeats_exactly(tmp_path):
    d = description_from_dict({"set": {"situations": 3, "seed": 11},
                               "groups": [{"targets": ["head-on"]}, {"targets": ["crossing-give-way"]},
                                          {"targets": ["crossing-stand-on"]}]})
    (tmp_path / "set").mkdir()
    for rel, text in set_files(generate(d)).items():
        (tmp_path / "set" / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "set" / rel).write_text(text)
    argv = ["study", "encounters", str(tmp_path / "set"), "--methods", "modified-vortex,velocity-obstacle"]
    assert main(argv + ["--out", str(tmp_path / "a")]) == 0
    assert main(argv + ["--out", str(tmp_path / "b")]) == 0
    rows = {}
    for name in ("a", "b"):
        lines = (tmp_path / name / "situations.csv").read_text().splitlines()
        head = lines[0].split(",")
        keep = [i for i, c in enumerate(head) if c not in study.TIMING_COLUMNS]
        rows[name] = [[r.split(",")[i] for i in keep] for r in lines]
        assert len(lines) == 1 + 2 * 3
    assert rows["a"] == rows["b"]
    assert (tmp_path / "a" / "encounters.csv").read_bytes() == (tmp_path / "b" / "encounters.csv").read_bytes()
    enc = (tmp_path / "a" / "encounters.csv").read_text().splitlines()
    assert enc[0] == ",".join(study.ENCOUNTER_COLUMNS) and len(enc) == 1 + 2 * 3
    requested = [line.split(",")[3] for line in enc[1:]]
    assert requested == ["head-on", "crossing-give-way", "crossing-stand-on"] * 2
    summary = (tmp_path / "a" / "summary.md").read_text()
    assert "modified-vortex vs velocity-obstacle" in summary and "passed the classification check" in summary


def test_study_encounters_summary_numbers():
    sit = [{"situation": s, "method": m, "safe": ok, "delay": 1.0, "min_distance": 3.0, "encounters": 1,
            "kept": int(kept)} for s, m, ok, kept in
           [("s0", "a", True, True), ("s1", "a", True, False), ("s0", "b", False, False), ("s1", "b", True, True)]]
    enc = [{"situation": r["situation"], "method": r["method"], "target": "target1", "applicable": True,
            "compliant": bool(r["kept"]), "as_generated": True} for r in sit]
    s = study.summarize(sit, enc, ("a", "b"), targets="hold")
    assert s["methods"]["a"]["safe"] == 2 and s["methods"]["b"]["safe"] == 1
    c = s["comparisons"]["a vs b"]
    assert (c["safe"]["n"], c["safe"]["a_only"], c["safe"]["b_only"]) == (2, 1, 0)
    assert (c["compliant"]["n"], c["compliant"]["a_only"], c["compliant"]["b_only"]) == (2, 1, 1)


def test_study_encounters_bad_input(tmp_path, capsys):
    assert main(["study", "encounters", str(tmp_path / "none"), "--out", str(tmp_path / "o")]) == 2
    assert "SET_DIR: expected a directory with scenario files" in capsys.readouterr().err
    (tmp_path / "s").mkdir()
    (tmp_path / "s" / "x.toml").write_text('[settings]\nmethod = "none"\n')
    assert main(["study", "encounters", str(tmp_path / "s"), "--out", str(tmp_path / "o")]) == 2
    assert "ships" in capsys.readouterr().err
    assert main(["study", "encounters", str(tmp_path / "s"), "--targets", "both", "--out", str(tmp_path / "o")]) == 2
    assert "--targets: expected one of: hold, avoid" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
