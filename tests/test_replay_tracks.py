"""Replayed ships (issue 26): a target follows its recorded track, interpolated in time inside the compiled closed
loop, to the last bits; the own ship avoids it and the scorer judges the pair; bad tracks are one line, exit 2,
nothing written; layouts without replayed ships are unchanged."""

import json
import math
from importlib import resources

import numpy as np
import pytest
import tomli_w

from mmg_casadi.cli import main
from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.replay import sample_track, track_columns
from mmg_casadi.closed_loop.step import build_closed_loop_step
from mmg_casadi.errors import ScenarioError
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.ais_replay import ais_scenario, load_ais_csv, parse_time
from mmg_casadi.scenarios.run import packaged_scenario, run_scenario
from mmg_casadi.scenarios.scenario import dump_scenario, load_scenario, scenario_from_dict

# a target crossing from starboard on a collision course with an own ship sailing north (x) at about 1 U,
# bending to port on the way; times in L/U (the first before the start), positions in L
T = [-2.0, 6.0, 13.5, 22.0, 30.0, 41.0, 55.0]
X = [31.0, 31.4, 31.2, 30.6, 29.4, 27.0, 22.5]
Y = [32.0, 24.0, 16.5, 8.0, 0.0, -10.5, -23.0]
OWN = {"name": "own", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[60.0, 0.0]]}


def _scenario(method="modified-vortex", track=None, t_max=90.0):
    return {"settings": {"method": method, "t_max": t_max},
            "ships": [dict(OWN), {"name": "target", "track": track or {"t": T, "x": X, "y": Y}}]}


@pytest.fixture(scope="module")
def avoided():
    return run_scenario(scenario_from_dict(_scenario()))


def test_the_target_is_where_its_track_is_at_every_step(avoided):
    tr = avoided.trajectory
    sailing = tr.sailing_mask()[:, 1]
    pos = np.column_stack([tr.state("x", 1), tr.state("y", 1)])[sailing]
    want = np.array([sample_track(T, X, Y, t)[0] for t in tr.t[sailing]])
    assert np.max(np.abs(pos - want)) < 1e-12
    # at the recorded samples (every one after the start lies on the step's clock, 0.25 apart)
    for tk, xk, yk in zip(T[1:], X[1:], Y[1:]):
        k = int(np.flatnonzero(tr.t == tk)[0])
        assert abs(pos[k, 0] - xk) < 1e-12 and abs(pos[k, 1] - yk) < 1e-12
    # between samples: linear in time
    k = int(np.flatnonzero(tr.t == 10.0)[0])
    w = (10.0 - 6.0) / (13.5 - 6.0)
    assert pos[k] == pytest.approx([X[1] + w * (X[2] - X[1]), Y[1] + w * (Y[2] - Y[1])], abs=1e-12)
    # the velocity the other ships see is the segment's, the heading its direction
    u, v, psi = (tr.state(n, 1)[k] for n in ("u", "v", "psi"))
    seg = np.array([X[2] - X[1], Y[2] - Y[1]]) / (T[2] - T[1])
    vel = [u * math.cos(psi) - v * math.sin(psi), u * math.sin(psi) + v * math.cos(psi)]
    assert vel == pytest.approx(seg, abs=1e-12) and psi == pytest.approx(math.atan2(seg[1], seg[0]), abs=1e-12)


def test_the_target_is_not_steered_and_is_done_at_the_track_end(avoided):
    tr = avoided.trajectory
    assert np.all(tr.state("delta", 1) == 0.0) and np.all(np.nan_to_num(tr.auxiliary("reactive", 1)) == 0.0)  # NaN: held after its end
    status = tr.state("status", 1)
    first_done = tr.t[int(np.argmax(status == 1))]
    assert first_done == 55.0 and tr.state("t_goal", 1)[-1] == 55.0
    ship = avoided.metrics["ships"][1]
    assert ship["method"] == "replay" and ship["status"] == "reached" and ship["delay"] is None


def test_the_own_ship_avoids_the_replayed_target_it_would_hit(avoided):
    m = avoided.metrics
    assert not m["collision"] and m["ships"][0]["status"] == "reached"
    pair = m["pairs"][0]
    assert pair["min_distance"] > 4.0
    enc = pair["encounters"]["a"][0]
    assert enc["applicable"] and enc["encounter"] == "crossing" and enc["role"] == "give-way"
    blind = run_scenario(scenario_from_dict(_scenario(method="none")))
    assert blind.metrics["pairs"][0]["min_distance"] < 2.0 and blind.metrics["collision"]
    assert blind.metrics["ships"][0]["collision_with"] == "target"


def test_a_track_file_is_read_relative_to_the_scenario_and_round_trips(tmp_path, monkeypatch):
    (tmp_path / "tracks").mkdir()
    rows = ["t,x,y,sog"] + [f"{t!r},{x!r},{y!r},9" for t, x, y in zip(T, X, Y)]
    (tmp_path / "tracks" / "target.csv").write_text("\n".join(rows) + "\n")
    inline = scenario_from_dict(_scenario())
    f = tmp_path / "s.toml"
    f.write_text(dump_scenario(inline))
    assert "[ships.track]" in f.read_text() and load_scenario(f) == inline
    f.write_text(tomli_w.dumps(_scenario(track="tracks/target.csv")))
    monkeypatch.chdir(tmp_path / "tracks")  # a relative track file is relative to the scenario's folder
    from_file = load_scenario(f)
    assert from_file == inline
    target = from_file.ships[1]
    assert target.start == tuple(sample_track(T, X, Y, 0.0)[0]) and target.goal == (X[-1], Y[-1])
    assert target.heading_deg == pytest.approx(math.degrees(math.atan2(Y[1] - Y[0], X[1] - X[0])), abs=1e-12)


def _bad(key, value):
    d = _scenario()
    d["ships"][1] = {"name": "target", "track": {"t": T, "x": X, "y": Y}}
    if key == "ships[0].track":
        d["ships"][0]["track"] = {"t": T, "x": X, "y": Y}
    elif key == "ships[1].start":
        d["ships"][1]["start"] = [30.0, 30.0]
    else:
        d["ships"][1]["track"] = value
    return d


@pytest.mark.parametrize("value,field", [
    ({"t": [0.0, 5.0, 5.0], "x": [1, 2, 3], "y": [5, 5, 5]}, "ships[1].track.t[2]"),     # not increasing
    ({"t": [1.0, 5.0], "x": [1, 2], "y": [5, 5]}, "ships[1].track.t[0]"),                # starts after t = 0
    ({"t": [-5.0, 0.0], "x": [1, 2], "y": [5, 5]}, "ships[1].track.t[1]"),               # ends at the start
    ({"t": [0.0, 5.0], "x": [1, 2, 3], "y": [5, 5]}, "ships[1].track"),                  # lengths differ
    ({"t": [0.0, 5.0], "x": [1, "a"], "y": [5, 5]}, "ships[1].track.x[1]"),              # not a number
    ({"t": [0.0, 1.0], "x": [1, 9], "y": [5, 5]}, "ships[1].track.x[1]"),                # 8 U: a bad record
    ({"t": [0.0, 1.0], "x": [1, 2], "z": [5, 5]}, "ships[1].track"),                     # unknown key
    ("missing.csv", "ships[1].track"),                                                   # no such file
    (None, "ships[0].track"),                                                            # the own ship
    (None, "ships[1].start"),                                                            # the track gives it
])
def test_bad_tracks_are_one_line_exit_2_nothing_written(tmp_path, capsys, value, field):
    key = field if value is None else "track"
    d = _bad(key, value)
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(d)
    assert err.value.field == field
    f = tmp_path / "bad.toml"
    f.write_text(tomli_w.dumps(d))
    out = tmp_path / "out"
    assert main(["simulate", str(f), "--out", str(out)]) == 2
    msg = capsys.readouterr().err.strip()
    assert msg.startswith(f"mmg-casadi: error: {field}") and "\n" not in msg
    assert not out.exists()


def test_a_track_csv_without_its_columns_is_refused(tmp_path):
    (tmp_path / "t.csv").write_text("time,x,y\n0,1,2\n5,2,2\n")
    with pytest.raises(ScenarioError, match=r"ships\[1\].track: expected a CSV file with the columns t, x, y"):
        scenario_from_dict(_scenario(track="t.csv"), base_dir=tmp_path)


def test_layouts_without_replayed_ships_keep_their_step_and_key():
    plain = Layout(("modified-vortex", "none"), n_obstacles=1)
    assert plain.key() == "modifiedvortex_none_o1_w0_k2_v80huangh" and plain.track_params_size == 0
    replayed = Layout(("modified-vortex", "none"), n_obstacles=1, replay=(1,), max_track=8)
    assert replayed.key() == plain.key() + "_r1t8" and replayed.np == plain.np + 1 + 3 * 8
    assert build_closed_loop_step(replayed).name() == "closed_loop_" + replayed.key()
    with pytest.raises(ValueError, match="no neighbour slots"):
        Layout(("none",) * 3, replay=(1,), max_track=8, neighbours=2)
    assert track_columns(len(T)) == 8
    pr = build_problem(scenario_from_dict(_scenario()))
    assert pr.layout.replay == (1,) and pr.layout.methods == ("modified-vortex", "none")
    dense, sparse = build_closed_loop_step(pr.layout), build_closed_loop_step(pr.layout, sparse=True)
    x = pr.x0
    for _ in range(3):  # the dense step (the one differentiated) replays the track as the sparse one does
        x_dense, x = np.array(dense(x, pr.p)[0]).ravel(), np.array(sparse(x, pr.p)[0]).ravel()
        assert np.array_equal(x_dense, x)
    assert x[pr.layout.row("x", 1)] == sample_track(T, X, Y, 0.75)[0][0]


SAMPLE = resources.files("mmg_casadi").joinpath("data", "ais", "synthetic_ais.csv")


def test_the_shipped_ais_sample_is_synthetic_and_replays_exactly(tmp_path, capsys):
    tracks = load_ais_csv(SAMPLE)
    assert sorted(tracks) == ["999000001", "999000002", "999000003"]  # fictitious MMSIs
    out = tmp_path / "replay.toml"
    assert main(["replay", str(SAMPLE), "--own", "999000001", "--start", "2026-05-04T10:02:00",
                 "--method", "colregs-vortex", "--out", str(out)]) == 0
    assert "left out: 999000003" in capsys.readouterr().out
    sc = load_scenario(out)
    own, target = sc.ships
    assert own.start == (0.0, 0.0) and own.heading_deg == pytest.approx(2.0, abs=0.01)  # her recorded course
    assert own.speed == pytest.approx(14 * 1852 / 3600 / 12.347, abs=1e-3)  # 14 kn of a 230 m KCS (Froude)
    assert target.track is not None and target.track.t[0] <= 0.0 < target.track.t[1]
    packaged = packaged_scenario("ais_replay")
    assert packaged.ships[1].track == target.track and packaged.ships[0] == own
    t0 = parse_time("2026-05-04T10:02:00", "start")
    _, report = ais_scenario(tracks, "999000001", targets="track", start=t0)
    assert report["t0"] == t0 and report["duration"] == 1680.0 and report["targets"] == "track"
    assert main(["replay", str(SAMPLE), "--own", "999000001", "--start", "2026-05-04T11:00:00",
                 "--out", str(tmp_path / "late.toml")]) == 2
    assert "--start: expected a time within the own ship's recording" in capsys.readouterr().err
    assert main(["replay", str(SAMPLE), "--own", "999000001", "--targets", "ghost",
                 "--out", str(tmp_path / "ghost.toml")]) == 2
    assert not (tmp_path / "late.toml").exists() and not (tmp_path / "ghost.toml").exists()


def test_the_packaged_replay_gives_way_to_the_replayed_target(tmp_path):
    """The own ship (colregs-vortex) gives way to the replayed target and rejoins her track ahead: her route's
    waypoints are 1.9 L apart and those she passed abeam while giving way count as passed, so she never turns back
    (her heading stays within 90° of her northbound track; turning back to them she looped and arrived 17.5 L/U
    later). Her alteration is substantial (Rule 16): she passes at ``cv_d_risk`` or more (4.21 L; with Rule 8's
    minimum alone 3.96 L). Judged under the laboratory profile (its safe distance is 2 L; under the published
    profile's 1 nautical mile this passing is too close)."""
    assert main(["simulate", "ais_replay", "--set", "colregs_profile=iitm-lab", "--out", str(tmp_path)]) == 0
    m = json.loads((tmp_path / "metrics.json").read_text())
    own, target = m["ships"]
    assert not m["collision"] and own["status"] == "reached" and target["method"] == "replay"
    z = np.load(tmp_path / "trajectory.npz")
    psi = z["states"][:, 0, list(z["state_names"]).index("psi")]
    assert np.max(np.abs(psi)) < math.pi / 2
    pair = m["pairs"][0]
    assert pair["min_distance"] >= PARAMETERS["cv_d_risk"].default
    enc = pair["encounters"]["a"][0]
    assert (enc["encounter"], enc["role"], enc["compliant"]) == ("crossing", "give-way", True)


def test_a_replayed_target_exports_its_track_as_its_route():
    from mmg_casadi.scenarios.maritime_export import scenario_to_traffic_situation
    sc = packaged_scenario("ais_replay")
    target = scenario_to_traffic_situation(sc)["targetShips"][0]
    later = [t for t in sc.ships[1].track.t if t > 0]
    assert len(target["waypoints"]) == 1 + len(later)
    assert [w["leg"]["sog"] for w in target["waypoints"][1:]] == pytest.approx([12.0] * len(later), abs=0.01)


def test_in_a_current_the_target_keeps_its_recorded_velocity_over_the_ground():
    d = _scenario(t_max=8.0)
    d["environment"] = {"current_speed": 0.2, "current_direction": 90.0}
    tr = run_scenario(scenario_from_dict(d)).trajectory
    k = int(np.flatnonzero(tr.t == 7.0)[0])
    u, v, psi = (tr.state(n, 1)[k] for n in ("u", "v", "psi"))
    ground = [u * math.cos(psi) - v * math.sin(psi), u * math.sin(psi) + v * math.cos(psi) + 0.2]
    assert ground == pytest.approx(sample_track(T, X, Y, 7.0)[1], abs=1e-12)
    assert [tr.state("x", 1)[k], tr.state("y", 1)[k]] == pytest.approx(sample_track(T, X, Y, 7.0)[0], abs=1e-12)


def test_ais_reports_may_come_as_json(tmp_path, capsys):
    import csv
    with SAMPLE.open(encoding="utf-8") as f:
        reports = [{"mmsi": int(r["mmsi"]), "time": r["time"], "lat": float(r["lat"]), "lon": float(r["lon"]),
                    "sog": float(r["sog"])} for r in csv.DictReader(f)]
    (tmp_path / "ais.json").write_text(json.dumps({"reports": reports}))
    from_json, from_csv = load_ais_csv(tmp_path / "ais.json"), load_ais_csv(SAMPLE)
    assert sorted(from_json) == sorted(from_csv)
    assert all(np.array_equal(from_json[m], from_csv[m]) for m in from_csv)
    reports[3]["lat"] = None
    (tmp_path / "bad.json").write_text(json.dumps(reports))
    assert main(["replay", str(tmp_path / "bad.json"), "--own", "999000001", "--out", str(tmp_path / "o.toml")]) == 2
    assert "bad.json report 4.lat: expected degrees in [-90, 90]" in capsys.readouterr().err
