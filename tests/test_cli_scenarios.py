"""``mmg-casadi scenarios`` lists the packaged scenarios; ``mmg-casadi simulate NAME`` runs one by name."""

from __future__ import annotations

import json
import os
from pathlib import Path
from importlib import resources

import pytest

from mmg_casadi.cli import main
from mmg_casadi.scenarios.run import packaged_scenario

SCENARIOS = resources.files("mmg_casadi").joinpath("data", "scenarios")
NAMES = sorted(p.name[:-5] for p in SCENARIOS.iterdir() if p.name.endswith(".toml"))


def test_scenarios_lists_every_packaged_scenario(capsys):
    assert main(["scenarios"]) == 0
    head, *lines = capsys.readouterr().out.splitlines()
    columns = ["name", "ships", "obstacles", "method", "description"]
    assert head.split() == columns
    starts = [head.index(c) for c in columns] + [None]
    rows = {}
    for line in lines:
        cells = [line[a:b].strip() for a, b in zip(starts, starts[1:])]
        rows[cells[0]] = cells
    assert sorted(rows) == NAMES
    for name, (_, ships, obstacles, method, description) in rows.items():
        sc = packaged_scenario(name)
        assert (int(ships), int(obstacles)) == (len(sc.ships), len(sc.obstacles))
        own = [f"{s.name}: {s.method}" for s in sc.ships if s.method not in (None, sc.settings.method)]
        assert method == sc.settings.method + (f" ({', '.join(own)})" if own else "")  # ships that override it
        assert description
    assert rows["head_on"][4] == "Head-on encounter (COLREG Rule 14)"
    assert rows["head_on"][3] == "modified-vortex"


def test_scenarios_takes_no_options(capsys):
    assert main(["scenarios", "--out", "x"]) == 2
    assert capsys.readouterr().err.count("\n") == 1


@pytest.mark.parametrize("arg", ["head_on", "head_on.toml"])
def test_simulate_runs_a_packaged_scenario_by_name(tmp_path, monkeypatch, arg):
    monkeypatch.chdir(tmp_path)  # no head_on.toml here: the packaged one runs
    assert main(["simulate", arg, "--set", "t_max=5", "--out", "run"]) == 0
    m = json.loads((tmp_path / "run" / "metrics.json").read_text())
    assert [s["name"] for s in m["ships"]] == [s.name for s in packaged_scenario("head_on").ships]
    assert m["params"]["t_max"] == 5.0 and m["params"]["r_safe"] == 15.0


def test_a_local_file_wins_over_a_packaged_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    text = SCENARIOS.joinpath("head_on.toml").read_text().replace('name = "ship1"', 'name = "local"')
    assert 'name = "local"' in text
    (tmp_path / "head_on.toml").write_text(text)
    assert main(["simulate", "head_on.toml", "--set", "t_max=5", "--out", "run"]) == 0
    assert json.loads((tmp_path / "run" / "metrics.json").read_text())["ships"][0]["name"] == "local"


def test_unknown_scenario_name_lists_the_names(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "head-on", "--out", "run"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("mmg-casadi: error: scenario: ")
    assert all(name in err for name in NAMES) and "'head-on'" in err
    assert not os.path.exists(tmp_path / "run")


def test_a_missing_file_is_still_a_missing_file(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "sub/head_on.toml", "--out", "run"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "sub/head_on.toml" in err and "existing" in err


def test_hostile_ship_names_reach_every_output_format_intact(tmp_path, capsys):
    # a name matplotlib would read as mathtext, names a spreadsheet would read as formulas, a comma and a quote
    # that split an unquoted CSV row: the figure is drawn, trajectory.csv has one row per sample and ship with
    # each name as written (a formula one behind an apostrophe), metrics.json keeps them
    import csv
    import json
    from mmg_casadi.cli import main
    names = ["$\\frac{$", '=HYPERLINK("x"),"a"']
    text = (Path(__file__).resolve().parents[1] / "mmg_casadi" / "data" / "scenarios" / "head_on.toml").read_text()
    text = text.replace('name = "ship1"', f"name = {json.dumps(names[0])}").replace(
        'name = "ship2"', f"name = {json.dumps(names[1])}")
    scenario = tmp_path / "names.toml"
    scenario.write_text(text)
    out = tmp_path / "out"
    assert main(["simulate", str(scenario), "--set", "t_max=10", "--out", str(out)]) == 0, capsys.readouterr().err
    assert any(p.suffix == ".png" and p.stat().st_size > 1000 for p in out.iterdir())
    with open(out / "trajectory.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    header, rows = rows[0], rows[1:]
    assert all(len(r) == len(header) for r in rows)
    assert {r[header.index("ship")] for r in rows} == {names[0], "'" + names[1]}
    metrics = json.loads((out / "metrics.json").read_text())
    assert [s["name"] for s in metrics["ships"]] == names
