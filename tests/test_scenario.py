"""Scenario files (mmg_casadi.scenarios.scenario)."""

from __future__ import annotations

import copy
import dataclasses
import datetime
import tomllib
from importlib.resources import files

import pytest

from mmg_casadi.errors import InputError, ScenarioError
from mmg_casadi.guidance.methods import NAMES as METHODS
from mmg_casadi.scenarios.scenario import (
    ObstacleSpec,
    Scenario,
    Settings,
    ShipSpec,
    WallSpec,
    dump_scenario,
    load_scenario,
    scenario_from_dict,
    scenario_to_dict,
    with_method,
)

FULL = """
[settings]
method = "sink-vortex"
dt = 0.5
t_max = 120
r_safe = 12.0
collision_distance = 2.5
goal_tolerance = 4.0
k_vor = -10
lam_sink = -100.0
vo_candidates = 80
vo_cone = "wide"

[[ships]]
name = "own"
start = [0, 0]
heading = 0.0
speed = 1.0
waypoints = [[25.0, 5.0], [50.0, 0.0]]

[[ships]]
start = [50.0, 0.0]
heading = 180
speed = 0.5
waypoints = [[0.0, 0.0]]
method = "none"
stays = true

[[obstacles]]
position = [25.0, -10.0]
radius = 1.5

[[obstacles]]
position = [30, 10]

[[walls]]
points = [[0.0, 5.0], [50.0, 55.0], [60, 55]]
"""

SCENARIO_DIR = files("mmg_casadi") / "data" / "scenarios"
SHIPPED = ("head_on", "crossing", "overtaking", "static_obstacle", "conflict", "narrow_channel", "channel_crossing",
           "narrow_channel_land", "strait_crossing", "fjord_island", "ais_replay", "land_island_on_track",
           "land_island_off_track", "land_headland", "land_strait_traffic", "land_channel_bend")
SHIPPED_METHOD = {"channel_crossing": "velocity-obstacle-speed", "strait_crossing": "colregs-vortex",
                  "fjord_island": "colregs-vortex", "ais_replay": "colregs-vortex"} | {
    f"land_{n}": "colregs-vortex" for n in ("island_on_track", "island_off_track", "headland", "strait_traffic",
                                           "channel_bend")}
"""Shipped scenarios whose method is not the paper's modified vortex (the speed-action demonstration, the land
scenarios written for colregs-vortex, the AIS replay)."""


def _base() -> dict:
    return tomllib.loads(FULL)


def test_valid_file_loads_every_field(tmp_path):
    path = tmp_path / "full.toml"
    path.write_text(FULL)
    s = load_scenario(path)
    assert s.settings == Settings("sink-vortex", dt=0.5, t_max=120.0, r_safe=12.0, collision_distance=2.5,
                                  goal_tolerance=4.0,
                                  params={"k_vor": -10.0, "lam_sink": -100.0, "vo_candidates": 80, "vo_cone": "wide"})
    assert isinstance(s.settings.t_max, float) and isinstance(s.settings.params["k_vor"], float)
    assert s.ships == (
        ShipSpec("own", (0.0, 0.0), 0.0, 1.0, ((25.0, 5.0), (50.0, 0.0))),
        ShipSpec("ship1", (50.0, 0.0), 180.0, 0.5, ((0.0, 0.0),), method="none", stays=True),
    )
    assert s.obstacles == (ObstacleSpec((25.0, -10.0), 1.5), ObstacleSpec((30.0, 10.0), 0.5))
    assert s.walls == (WallSpec(((0.0, 5.0), (50.0, 55.0), (60.0, 55.0))),)
    assert len(s.walls[0].segments) == 2
    assert s.method_of(0) == "sink-vortex" and s.method_of(1) == "none"
    assert s.ships[1].goal == (0.0, 0.0)
    hash(s)


def test_defaults():
    d = {"settings": {"method": "none"},
         "ships": [{"start": [0, 0], "heading": 0, "speed": 1, "waypoints": [[50, 0]]}]}
    s = scenario_from_dict(d)
    assert s.settings == Settings("none", 0.25, 300.0, 15.0, 2.0, 3.0, {})
    assert s.ships[0].name == "ship0" and s.ships[0].method is None and s.ships[0].stays is False
    assert s.obstacles == () and s.walls == ()


def _set(d, path, value):
    """Set (or, with value ``...``, delete) the entry at ``path`` (a tuple of keys / indices)."""
    *head, last = path
    for key in head:
        d = d[key]
    if value is ...:
        del d[last]
    else:
        d[last] = value


BAD = [
    # (path to change, new value or ... to delete, expected error field)
    (("settings",), ..., "settings"),
    (("ships",), ..., "ships"),
    (("ships",), [], "ships"),
    (("ships",), 3, "ships"),
    (("settings",), 3, "settings"),
    (("settings", "method"), ..., "settings.method"),
    (("settings", "method"), "potential", "settings.method"),
    (("settings", "method"), 1, "settings.method"),
    (("settings", "dt"), 0.0, "settings.dt"),
    (("settings", "dt"), 2.5, "settings.dt"),
    (("settings", "dt"), "0.25", "settings.dt"),
    (("settings", "t_max"), 20000, "settings.t_max"),
    (("settings", "t_max"), True, "settings.t_max"),
    (("settings", "r_safe"), -1.0, "settings.r_safe"),
    (("settings", "collision_distance"), 0, "settings.collision_distance"),
    (("settings", "goal_tolerance"), float("inf"), "settings.goal_tolerance"),
    (("settings", "k_att"), "fifty", "settings.k_att"),
    (("settings", "vo_cone"), "narrow", "settings.vo_cone"),
    (("settings", "vo_candidates"), 0, "settings.vo_candidates"),
    (("settings", "vo_candidates"), 8.5, "settings.vo_candidates"),
    (("settings", "speed"), 1.0, "settings.speed"),
    (("extra",), 1, "extra"),
    (("ships", 1, "start"), ..., "ships[1].start"),
    (("ships", 1, "heading"), ..., "ships[1].heading"),
    (("ships", 1, "speed"), ..., "ships[1].speed"),
    (("ships", 1, "waypoints"), ..., "ships[1].waypoints"),
    (("ships", 1, "start"), [1.0], "ships[1].start"),
    (("ships", 1, "start"), [1.0, 2.0, 3.0], "ships[1].start"),
    (("ships", 1, "start"), ["a", 2.0], "ships[1].start"),
    (("ships", 1, "start"), "0,0", "ships[1].start"),
    (("ships", 1, "heading"), "north", "ships[1].heading"),
    (("ships", 1, "heading"), False, "ships[1].heading"),
    (("ships", 1, "heading"), float("nan"), "ships[1].heading"),
    (("ships", 1, "speed"), 1.3, "ships[1].speed"),
    (("ships", 1, "speed"), 0.1, "ships[1].speed"),
    (("ships", 1, "speed"), True, "ships[1].speed"),
    (("ships", 1, "waypoints"), [], "ships[1].waypoints"),
    (("ships", 1, "waypoints"), [[0.0, 0.0], [1.0]], "ships[1].waypoints[1]"),
    (("ships", 1, "method"), "vortex", "ships[1].method"),
    (("ships", 1, "stays"), "yes", "ships[1].stays"),
    (("ships", 1, "name"), "own", "ships[1].name"),
    (("ships", 1, "name"), "", "ships[1].name"),
    (("ships", 1, "colour"), "red", "ships[1].colour"),
    (("ships", 1, "start"), [25.5, -9.0], "ships[1].start"),  # inside obstacles[0] (radius 1.5 + 0.5)
    (("ships", 1, "start"), [1.0, 1.0], "ships[1].start"),  # closer than collision_distance to ships[0]
    (("obstacles", 0, "position"), ..., "obstacles[0].position"),
    (("obstacles", 0, "position"), [1, "x"], "obstacles[0].position"),
    (("obstacles", 1, "radius"), 0.0, "obstacles[1].radius"),
    (("obstacles", 1, "size"), 1.0, "obstacles[1].size"),
    (("obstacles",), {"position": [1, 1]}, "obstacles"),
    (("walls", 0, "points"), ..., "walls[0].points"),
    (("walls", 0, "points"), [[0.0, 5.0]], "walls[0].points"),
    (("walls", 0, "points"), [[0.0, 5.0], [0.0, 5.0]], "walls[0].points[1]"),
    (("walls", 0, "points"), [[0.0, 5.0], [1.0, True]], "walls[0].points[1]"),
    (("ships", 1, "length_m"), 0.0, "ships[1].length_m"),
    (("ships", 1, "length_m"), "122 m", "ships[1].length_m"),
    (("ships", 1, "beam_m"), -20.0, "ships[1].beam_m"),
    (("ships", 1, "metadata"), "BASTO VI", "ships[1].metadata"),
    (("ships", 1, "metadata"), {"sogMax": float("inf")}, "ships[1].metadata.sogMax"),
    (("ships", 1, "metadata"), {"a": {"b c": [1, None]}}, 'ships[1].metadata.a."b c"[1]'),
    (("ships", 1, "metadata"), {"t": datetime.datetime(2025, 1, 1)}, "ships[1].metadata.t"),
    (("ships", 1, "metadata"), {"id": 2 ** 64}, "ships[1].metadata.id"),
]


@pytest.mark.parametrize("path, value, field", BAD, ids=[f"{b[2]}-{i}" for i, b in enumerate(BAD)])
def test_malformed_entries_name_the_key(path, value, field):
    d = _base()
    _set(d, path, value)
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, source="test.toml")
    err = info.value
    assert err.field == field
    assert str(err).startswith(f"{field}: expected ")
    assert err.source == "test.toml"
    assert isinstance(err, InputError)


def test_messages_list_the_allowed_values():
    d = _base()
    d["settings"]["method"] = "potential"
    with pytest.raises(ScenarioError, match="inverse-square, sink-vortex, modified-vortex"):
        scenario_from_dict(d)
    d = _base()
    d["settings"]["foo"] = 1
    with pytest.raises(ScenarioError, match=r"settings\.foo: expected a known key \(one of: method, dt.*k_att"):
        scenario_from_dict(d)
    d = _base()
    d["ships"][1]["speed"] = 2
    with pytest.raises(ScenarioError, match=r"ships\[1\]\.speed: expected a number in \[0\.2, 1\.2\]"):
        scenario_from_dict(d)
    d = _base()
    d["ships"][1]["start"] = [25.5, -9.0]
    with pytest.raises(ScenarioError, match=r"ships\[1\]\.start: .*obstacles\[0\]"):
        scenario_from_dict(d)


def test_bad_toml_syntax(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('[settings]\nmethod = "none\n')
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.field == "toml"
    assert str(path) in str(info.value) and "line 2" in str(info.value)


def test_nonexistent_file(tmp_path):
    path = tmp_path / "missing.toml"
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.field == str(path)
    assert str(info.value).startswith(f"{path}: expected an existing")


def test_malformed_file_reports_key_and_source(tmp_path):
    path = tmp_path / "bad_speed.toml"
    path.write_text(FULL.replace("speed = 0.5", "speed = 5"))
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    assert info.value.field == "ships[1].speed" and info.value.source == str(path)


def test_round_trip_full():
    s = scenario_from_dict(_base())
    text = dump_scenario(s)
    assert scenario_from_dict(tomllib.loads(text)) == s
    assert scenario_from_dict(scenario_to_dict(s)) == s
    assert 'vo_cone = "wide"' in text and "vo_candidates = 80" in text and "stays = true" in text


def test_round_trip_odd_values():
    ship = ShipSpec('a "quoted" \\ name, $x$ =1', (0.1, -1e-7), -135.123456789, 0.2, ((1e4, 1.0 / 3.0),))
    s = Scenario(Settings("none", dt=2.0, params={"k_rep": 2e5}), (ship,))
    assert scenario_from_dict(tomllib.loads(dump_scenario(s))) == s
    # a control character (a tab, a newline, a right-to-left override) is no part of a name
    for bad in ("name\t", "a\nb", "evil\u202egnp.exe", "x" * 65, ""):
        with pytest.raises(ScenarioError, match="expected a name of 1 to 64 characters"):
            scenario_from_dict(tomllib.loads(dump_scenario(dataclasses.replace(s, ships=(
                dataclasses.replace(ship, name=bad),)))))


def test_ship_size_and_metadata_round_trip(tmp_path):
    meta = {"id": "0f8c2d4e-5a6b-4c7d-9e0f-123456789abc", "mmsi": 257000123, "shipType": "Passenger",
            "sogMax": 17.0, "dimensions": {"height": 8.0}, "tags": ["ferry", 2, True], "crew": [{"n": 1}]}
    d = _base()
    d["ships"][1].update(length_m=122, beam_m=20.0, metadata=meta)
    s = scenario_from_dict(d)
    ship = s.ships[1]
    assert (ship.length_m, ship.beam_m, ship.metadata) == (122.0, 20.0, meta)
    assert isinstance(ship.length_m, float) and ship.metadata is not meta
    assert s.ships[0].length_m is None and s.ships[0].metadata == {}
    path = tmp_path / "s.toml"
    path.write_text(dump_scenario(s), encoding="utf-8")
    back = load_scenario(path)
    assert back == s and back.ships[1].metadata == meta
    assert type(back.ships[1].metadata["mmsi"]) is int and type(back.ships[1].metadata["sogMax"]) is float
    assert "[ships.metadata]" in path.read_text() and "length_m = 122.0" in path.read_text()
    # metadata is compared but not hashed: a changed value makes a different, equally hashable scenario
    other = scenario_from_dict({**d, "ships": [d["ships"][0], {**d["ships"][1], "metadata": {"mmsi": 1}}]})
    assert other != s and hash(other) == hash(s)


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_scenarios_load_and_round_trip(name):
    s = load_scenario(SCENARIO_DIR / f"{name}.toml")
    assert s.settings.method == SHIPPED_METHOD.get(name, "modified-vortex")
    assert scenario_from_dict(tomllib.loads(dump_scenario(s))) == s


def test_every_shipped_scenario_is_tested():
    shipped = sorted(p.name for p in SCENARIO_DIR.iterdir() if p.name.endswith(".toml"))
    assert shipped == sorted(f"{n}.toml" for n in SHIPPED)


def test_shipped_scenarios_match_the_paper():
    conflict = load_scenario(SCENARIO_DIR / "conflict.toml")
    assert [sh.start for sh in conflict.ships] == [(0.0, 0.0), (-20.0, 0.0), (60.0, 0.0)]
    assert [sh.speed for sh in conflict.ships] == [0.5, 1.0, 1.0]
    crossing = load_scenario(SCENARIO_DIR / "crossing.toml")
    assert crossing.ships[1].start == (25.0, 25.0) and crossing.ships[1].heading_deg == -90.0
    channel = load_scenario(SCENARIO_DIR / "narrow_channel.toml")
    for wall, side in zip(channel.walls, (-1.0, 1.0)):
        for x, y in wall.points:  # y - x = side * 5 sqrt(2): 5 L from the diagonal
            assert (y - x) / 2 ** 0.5 == pytest.approx(side * 5.0, abs=1e-3)
    obstacle = load_scenario(SCENARIO_DIR / "static_obstacle.toml")
    assert obstacle.obstacles == (ObstacleSpec((25.0, 0.0), 0.5),)


def test_with_method():
    s = scenario_from_dict(_base())
    for method in METHODS:
        t = with_method(s, method)
        assert t.settings.method == method
        assert t.ships == s.ships and t.obstacles == s.obstacles and t.walls == s.walls
        assert t.settings.params == s.settings.params
    assert with_method(s, "none").method_of(1) == "none"
    with pytest.raises(ScenarioError, match="method: expected one of: inverse-square"):
        with_method(s, "apf")


def test_dataclasses_frozen_and_hashable():
    s = scenario_from_dict(_base())
    assert isinstance(s.ships, tuple) and isinstance(s.ships[0].waypoints, tuple)
    assert len({s, copy.deepcopy(s)}) == 1
    with pytest.raises(AttributeError):
        s.settings.dt = 1.0  # type: ignore[misc]
