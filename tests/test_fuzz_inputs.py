"""Property-based tests (Hypothesis) of every user-input path: scenario files, ``--params`` files, traffic situations.

Whatever the input — random TOML values and types, wrong shapes, NaN/inf, huge numbers, unicode, dates,
missing and extra keys, text that is not TOML at all — loading either succeeds with a valid scenario (it
passes the validation-only :func:`~mmg_casadi.closed_loop.problem.build_problem` and survives a dump/load round trip)
or raises the project's :class:`~mmg_casadi.errors.InputError` with a one-line message; and the CLI exits
with status 2 and writes nothing. No simulation runs here (inputs the CLI would accept are skipped).

The default profile keeps the whole file well under a minute; ``-m slow`` runs the same properties with many
more examples.
"""

from __future__ import annotations

import datetime as dt
import math
import tomllib

import pytest
from hypothesis import HealthCheck, assume, event, given, settings
from hypothesis import strategies as st

from mmg_casadi.cli import main
from mmg_casadi.errors import InputError
from mmg_casadi.scenarios.maritime_schema import traffic_situation_to_scenario
from mmg_casadi.scenarios.scenario import (
    OBSTACLE_KEYS,
    SETTINGS_KEYS,
    SHIP_KEYS,
    SPEED_RANGE,
    WALL_KEYS,
    Scenario,
    dump_scenario,
    load_scenario,
    scenario_from_dict,
)
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.params import load_file as load_params_file

FAST = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                        HealthCheck.function_scoped_fixture])
SLOW = settings(max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                         HealthCheck.function_scoped_fixture])

# ---------------------------------------------------------------------------------------------- strategies

scalars = st.one_of(
    st.booleans(),
    st.integers(),
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0, 1, -1, 0.0, -0.0, 0.2, 1.2, 1e308, -1e308, 5e-324, 2**53 + 1, 10**30, float("nan"),
                     float("inf"), float("-inf")]),
    st.text(max_size=12),
    st.sampled_from(["none", "inverse-square", "sink-vortex", "modified-vortex", "velocity-obstacle", "wide",
                     "huang", "", " ", "\u00e9\u4e2d\U0001f6a2", "nan", "1.0"]),
    st.datetimes(), st.dates(), st.times(),
)
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                       st.dictionaries(st.text(max_size=8), inner, max_size=4)),
                      max_leaves=12)
points = st.lists(st.one_of(st.floats(-1e3, 1e3), values), min_size=0, max_size=3)

BASE = {
    "settings": {"method": "none", "t_max": 100.0},
    "ships": [{"name": "own", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": [[50.0, 0.0]]},
              {"name": "b", "start": [50.0, 10.0], "heading": 180.0, "speed": 0.8, "waypoints": [[0.0, 10.0]]}],
    "obstacles": [{"position": [25.0, -20.0], "radius": 0.5}],
    "walls": [{"points": [[0.0, 40.0], [50.0, 40.0]]}],
}
SECTIONS = {"settings": SETTINGS_KEYS, "ships": SHIP_KEYS, "obstacles": OBSTACLE_KEYS, "walls": WALL_KEYS}


@st.composite
def mutated_scenarios(draw):
    """The valid :data:`BASE` scenario with a few keys replaced, removed or added."""
    import copy
    d = copy.deepcopy(BASE)
    for _ in range(draw(st.integers(1, 4))):
        section = draw(st.sampled_from(sorted(SECTIONS) + ["<root>"]))
        action = draw(st.sampled_from(["set", "set", "set", "delete", "extra", "replace-table"]))
        if section == "<root>":
            key = draw(st.sampled_from(sorted(SECTIONS) + ["extra", "\u00fc"]))
            if action == "delete":
                d.pop(key, None)
            else:
                d[key] = draw(values)
            continue
        target = d.get(section)
        if isinstance(target, list):
            if not target or not isinstance(target[0], dict) or action == "replace-table":
                d[section] = draw(st.lists(st.one_of(values, st.dictionaries(
                    st.sampled_from(SECTIONS[section]), values, max_size=4)), max_size=3))
                continue
            target = target[draw(st.integers(0, len(target) - 1))]
        if not isinstance(target, dict):
            d[section] = draw(values)
            continue
        if action == "delete" and target:
            target.pop(draw(st.sampled_from(sorted(target))))
        elif action == "extra":
            target[draw(st.text(min_size=1, max_size=8))] = draw(values)
        else:
            key = draw(st.sampled_from(SECTIONS[section]))
            target[key] = draw(st.one_of(values, points, st.lists(points, max_size=3)))
    return d


finite = st.floats(-1e3, 1e3, allow_subnormal=False)
point = st.tuples(finite, finite).map(list)


@st.composite
def plausible_scenarios(draw):
    """Scenarios of 1-4 ships with values of the right types (mostly in range), obstacles and walls."""
    from mmg_casadi.guidance.methods import NAMES as METHODS
    from mmg_casadi.scenarios.scenario import PARAM_KEYS
    settings_ = {"method": draw(st.sampled_from(METHODS))}
    for key, strat in (("dt", st.floats(0.01, 2.5)), ("t_max", st.floats(1.0, 1e4)),
                       ("r_safe", st.floats(0.1, 50)), ("collision_distance", st.floats(0.1, 3)),
                       ("goal_tolerance", st.floats(0.1, 10))):
        if draw(st.booleans()):
            settings_[key] = draw(strat)
    for key in draw(st.lists(st.sampled_from(PARAM_KEYS), max_size=3, unique=True)):
        settings_[key] = draw(st.sampled_from(["wide", "huang"]) if key == "vo_cone" else
                              st.integers(1, 100) if key == "vo_candidates" else st.floats(-10, 100))
    ships = []
    for i in range(draw(st.integers(1, 4))):
        ship = {"start": [20.0 * i, draw(finite)], "heading": draw(st.floats(-720, 720)),
                "speed": draw(st.floats(0.1, 1.3)), "waypoints": draw(st.lists(point, min_size=1, max_size=3))}
        if draw(st.booleans()):
            ship["name"] = draw(st.text(min_size=1, max_size=10))
        if draw(st.booleans()):
            ship["method"] = draw(st.sampled_from(METHODS))
        if draw(st.booleans()):
            ship["stays"] = draw(st.booleans())
        ships.append(ship)
    d = {"settings": settings_, "ships": ships}
    if draw(st.booleans()):
        d["obstacles"] = [{"position": [draw(finite), -2000.0], "radius": draw(st.floats(0.01, 10))}
                          for _ in range(draw(st.integers(0, 2)))]
    if draw(st.booleans()):
        d["walls"] = [{"points": draw(st.lists(point, min_size=2, max_size=4))} for _ in range(draw(st.integers(0, 2)))]
    return d


random_documents = st.one_of(plausible_scenarios(), plausible_scenarios(), mutated_scenarios(), values,
                             st.dictionaries(st.sampled_from(sorted(SECTIONS) + ["x"]), values, max_size=4))


def _toml_key(k: str) -> str:
    return '"' + "".join(f"\\u{ord(c):04x}" if ord(c) < 0x20 or c in '"\\\x7f' else c for c in k) + '"'


def _toml(value) -> str:
    """Inline TOML for any value tomllib can produce (dates and times included)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(float(value)), repr(value)) \
            if isinstance(value, float) else str(value)
    if isinstance(value, str):
        return _toml_key(value)
    if isinstance(value, (dt.datetime, dt.date, dt.time)):
        return value.isoformat()
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml(v)}" for k, v in value.items()) + "}"
    raise TypeError(type(value))


def _document(d) -> str:
    """A TOML document for a top-level dict (any other value is put under the key ``value``)."""
    if not isinstance(d, dict):
        d = {"value": d}
    return "\n".join(f"{_toml_key(k)} = {_toml(v)}" for k, v in d.items()) + "\n"


# --------------------------------------------------------------------------------------------- properties

def _check_valid(sc: Scenario) -> None:
    """A loaded scenario is valid: numbers finite and in range, it builds, and it round-trips through TOML."""
    event("loaded")
    lo, hi = SPEED_RANGE
    for s in sc.ships:
        assert lo <= s.speed <= hi
        assert all(math.isfinite(v) for v in (*s.start, s.heading_deg, *sum(s.waypoints, ())))
    assert math.isfinite(sc.settings.t_max) and sc.settings.t_max > 0
    try:
        build_problem(sc)
    except InputError as err:  # field parameters are range-checked when the problem is built
        _check_error(err)
    assert scenario_from_dict(tomllib.loads(dump_scenario(sc))) == sc


def _check_error(err: InputError) -> None:
    event("InputError")
    assert isinstance(err, InputError)
    assert "\n" not in str(err) and err.field


def _scenario_property(d):
    try:
        sc = scenario_from_dict(d)
    except InputError as err:
        _check_error(err)
        return
    _check_valid(sc)


@FAST
@given(random_documents)
def test_scenario_dicts_load_or_raise_input_error(d):
    _scenario_property(d)


@FAST
@given(st.one_of(plausible_scenarios().map(_document), mutated_scenarios().map(_document), st.text(max_size=200),
                 st.binary(max_size=100).map(lambda b: b.decode("latin-1"))))
def test_scenario_files_load_or_raise_input_error(tmp_path_factory, text):
    path = tmp_path_factory.mktemp("fuzz") / "s.toml"
    path.write_text(text, encoding="utf-8")
    try:
        sc = load_scenario(path)
    except InputError as err:
        _check_error(err)
        return
    _check_valid(sc)


def test_scenario_file_errors_cover_unreadable_files(tmp_path):
    for path, content in ((tmp_path / "latin.toml", b"name = \"\xe9\"\n"), (tmp_path / "dir.toml", None)):
        if content is None:
            path.mkdir()
        else:
            path.write_bytes(content)
        with pytest.raises(InputError):
            load_scenario(path)


PARAM_NAMES = ["k_att", "k_rep", "d0", "lam_sink", "k_vor", "k_vor0", "r_tol_vortex", "gamma_max_deg",
               "wall_lam", "wall_d_act", "ilos_delta", "ilos_k", "kp", "kd", "vo_candidates", "vo_cone",
               "stall_window", "r_safe", "ship_radius", "params", "bogus"]
params_docs = st.one_of(
    st.dictionaries(st.sampled_from(PARAM_NAMES), values, max_size=5),
    st.dictionaries(st.just("params"), st.one_of(values, st.dictionaries(st.sampled_from(PARAM_NAMES), values,
                                                                          max_size=4)), min_size=1),
    values,
)


def _params_property(text, tmp):
    path = tmp / "p.toml"
    path.write_text(text, encoding="utf-8")
    try:
        params = load_params_file(path)
    except InputError as err:
        _check_error(err)
        return None
    sc = scenario_from_dict(BASE)
    try:
        build_problem(sc, params)
    except InputError as err:
        _check_error(err)
        return None
    event("accepted")
    return params


@FAST
@given(st.one_of(params_docs.map(_document), st.text(max_size=100)))
def test_params_files_load_or_raise_input_error(tmp_path_factory, text):
    _params_property(text, tmp_path_factory.mktemp("fuzz"))


def test_params_file_errors_cover_unreadable_files(tmp_path):
    (tmp_path / "dir.toml").mkdir()
    (tmp_path / "latin.toml").write_bytes(b"kp = \"\xe9\"\n")
    for name in ("dir.toml", "latin.toml", "missing.toml"):
        with pytest.raises(InputError):
            load_params_file(tmp_path / name)


def _situations(noisy: bool):
    """Traffic situations; with ``noisy`` every part is sometimes replaced by any value."""
    def maybe(good):
        return st.one_of(good, values) if noisy else good

    pos = st.fixed_dictionaries({"lat": maybe(st.floats(58.0, 59.0)), "lon": maybe(st.floats(10.0, 11.0))})
    initial = st.fixed_dictionaries({"position": maybe(pos), "sog": maybe(st.floats(4.0, 30.0)),
                                     "cog": maybe(st.floats(0, 360))},
                                    optional={"heading": maybe(st.floats(0, 360))})
    static = st.fixed_dictionaries({"id": st.integers(0, 9)},
                                   optional={"name": st.text(max_size=8),
                                             "dimensions": st.fixed_dictionaries({"length": maybe(
                                                 st.floats(1, 400))})})
    waypoints = st.lists(st.fixed_dictionaries({"position": pos}, optional={"leg": st.fixed_dictionaries(
        {"sog": maybe(st.floats(4.0, 30.0))})}), max_size=3)
    ship = st.fixed_dictionaries({"static": maybe(static), "initial": maybe(initial)},
                                 optional={"waypoints": maybe(waypoints)})
    bare = st.fixed_dictionaries({"static": static, "waypoints": maybe(waypoints)})  # no initial state
    return st.fixed_dictionaries({"version": st.just("0.2.0"), "ownShip": st.one_of(ship, bare),
                                  "targetShips": st.lists(st.one_of(ship, ship, bare), max_size=3)})


def _situation_values():
    return st.one_of(_situations(noisy=False), _situations(noisy=True), values)


@FAST
@given(_situation_values())
def test_traffic_situations_convert_or_raise_input_error(d):
    try:
        sc, _plane, _unit = traffic_situation_to_scenario(d)
    except InputError as err:
        _check_error(err)
        return
    _check_valid(sc)


# ---------------------------------------------------------------------------------------------------- CLI

@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(mutated_scenarios())
def test_cli_simulate_bad_scenario_writes_nothing(tmp_path_factory, capsys, d):
    try:
        scenario_from_dict(d)
        assume(False)  # a valid scenario would be simulated (slow); only bad input is checked here
    except InputError:
        pass
    tmp = tmp_path_factory.mktemp("cli")
    path = tmp / "s.toml"
    path.write_text(_document(d), encoding="utf-8")
    out = tmp / "out"
    assert main(["simulate", str(path), "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mmg-casadi: error: ")


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(params_docs.map(_document))
def test_cli_simulate_bad_params_writes_nothing(tmp_path_factory, capsys, text):
    tmp = tmp_path_factory.mktemp("cli")
    assume(_params_property(text, tmp) is None)  # valid parameters would be simulated (slow)
    scenario = tmp / "s.toml"
    scenario.write_text(dump_scenario(scenario_from_dict(BASE)), encoding="utf-8")
    out = tmp / "out"
    assert main(["simulate", str(scenario), "--params", str(tmp / "p.toml"), "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mmg-casadi: error: ")


# ------------------------------------------------------------------------------------------- slow profile

@pytest.mark.slow
@SLOW
@given(random_documents)
def test_scenario_dicts_many_examples(d):
    _scenario_property(d)


@pytest.mark.slow
@SLOW
@given(st.one_of(params_docs.map(_document), st.text(max_size=100)))
def test_params_files_many_examples(tmp_path_factory, text):
    _params_property(text, tmp_path_factory.mktemp("fuzz"))


@pytest.mark.slow
@SLOW
@given(_situation_values())
def test_traffic_situations_many_examples(d):
    test_traffic_situations_convert_or_raise_input_error.hypothesis.inner_test(d)
