"""AIS replay (`mmg-casadi replay`): recorded tracks become waypoint routes with the recorded leg speeds; a target
retraces its track on time; bad files are one line, exit 2, nothing written."""

import math

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.scenarios.ais_replay import ais_scenario, load_ais_csv
from mmg_casadi.scenarios.geodesy import LocalPlane
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.scenarios.scenario import load_scenario

L, U = 230.0, 12.347  # the KCS: metres per ship length, design speed [m/s]
LAT0, LON0 = 58.6, 10.6


def _csv(tmp_path, ships, name="ais.csv"):
    """Straight tracks: {mmsi: (start x, y [L], course [deg], speed [U], first, last report [s])} every 30 s."""
    plane = LocalPlane(LAT0, LON0)
    lines = ["mmsi,time,lat,lon,sog"]
    for mmsi, (x, y, course, speed, first, last) in ships.items():
        for t in np.arange(first, last + 1e-9, 30.0):
            d = speed * U * t / L
            lat, lon = plane.to_geodetic((x + d * math.cos(math.radians(course))) * L,
                                         (y + d * math.sin(math.radians(course))) * L)
            stamp = f"2024-05-01T12:{int(t) // 60:02d}:{int(t) % 60:02d}"
            lines.append(f"{mmsi},{stamp},{lat:.7f},{lon:.7f},{speed * 24:.1f}")
    f = tmp_path / name
    f.write_text("\n".join(lines) + "\n")
    return f


SHIPS = {"257000001": (0.0, 0.0, 0.0, 0.8, 0.0, 1200.0),      # own ship: north at 0.8 U for 20 minutes
         "257000002": (40.0, 30.0, -90.0, 0.6, 0.0, 1200.0),  # crossing from starboard at 0.6 U
         "257000003": (-30.0, 5.0, 0.0, 0.5, 300.0, 1200.0)}  # appears 5 minutes later: left out


def test_tracks_become_routes_with_recorded_speeds(tmp_path):
    sc, report = ais_scenario(load_ais_csv(_csv(tmp_path, SHIPS)), "257000001", step_s=120.0)
    assert [s.name for s in sc.ships] == ["257000001", "257000002"]
    assert report["left_out"] == {"257000003": "no report at or before the own ship's first one"}
    assert report["duration"] == 1200.0 and report["clipped_legs"] == 0
    own, target = sc.ships
    assert own.start == pytest.approx((0.0, 0.0), abs=1e-6) and own.heading_deg == pytest.approx(0.0, abs=1e-3)
    assert len(own.waypoints) == 10 and own.speeds == pytest.approx([0.8] * 10, abs=1e-4)
    assert own.goal == pytest.approx((0.8 * U * 1200 / L, 0.0), abs=1e-3)
    assert target.method == "none" and target.heading_deg == pytest.approx(-90.0, abs=1e-3)
    assert target.start == pytest.approx((40.0, 30.0), abs=1e-3) and target.speeds == pytest.approx([0.6] * 10, abs=1e-4)
    assert sc.settings.t_max == pytest.approx(1.5 * 1200 * U / L, abs=1e-3)


def test_a_replayed_target_keeps_the_recorded_time(tmp_path):
    ships = {"1": (0.0, 0.0, 0.0, 0.8, 0.0, 1200.0), "2": (0.0, 20.0, 0.0, 0.8, 0.0, 1200.0)}
    sc, _ = ais_scenario(load_ais_csv(_csv(tmp_path, ships)), "1", step_s=120.0, method="none")
    res = run_scenario(sc)
    tr = res.trajectory
    t_rec = 600.0 * U / L  # 10 minutes in L/U
    k = int(np.argmin(np.abs(tr.t - t_rec)))
    x, y = tr.state("x", 1)[k], tr.state("y", 1)[k]
    assert x == pytest.approx(0.8 * t_rec, abs=1.5) and y == pytest.approx(20.0, abs=0.5)


@pytest.mark.parametrize("text,field", [
    ("mmsi,time,lat\n1,0,58\n", "columns"),
    ("mmsi,time,lat,lon\n1,0,95,10\n1,60,58,10\n", "row 2.lat"),
    ("mmsi,time,lat,lon\n1,yesterday,58,10\n", "row 2.time"),
    ("mmsi,time,lat,lon\n2,0,58,10\n2,60,58.01,10\n", "--own"),
])
def test_bad_ais_files_are_one_line_exit_2_nothing_written(tmp_path, capsys, text, field):
    f = tmp_path / "bad.csv"
    f.write_text(text)
    assert main(["replay", str(f), "--own", "1", "--out", str(tmp_path / "o.toml")]) == 2
    err = capsys.readouterr().err.strip()
    assert field in err and "\n" not in err and err.startswith("mmg-casadi: error:")
    assert not (tmp_path / "o.toml").exists()


def test_replay_command_writes_a_scenario_file(tmp_path, capsys):
    f = _csv(tmp_path, SHIPS)
    assert main(["replay", str(f), "--own", "257000001", "--step", "300", "--out", str(tmp_path / "s.toml")]) == 0
    assert "left out: 257000003" in capsys.readouterr().out
    sc = load_scenario(tmp_path / "s.toml")
    assert len(sc.ships) == 2 and len(sc.ships[0].waypoints) == 4
    assert main(["replay", str(f), "--own", "257000001", "--step", "0.01", "--out", str(tmp_path / "t.toml")]) == 2
    assert "--step: expected a step of at least 0.12 s" in capsys.readouterr().err
