"""The paper's encounter studies with the paper's parameters (static obstacle, COLREGs, conflict, channel).

Where our numbers differ from the paper's, the test is marked expected-to-fail with the measured value.
"""

import json
import math

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.scenarios.scenario import with_method
from mmg_casadi.scenarios import encounters
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.scenarios.run import assess, run_scenario
from studies import narrow_channel

static_obstacle, colregs, conflict = (encounters.static_obstacle_cases, encounters.colregs_cases,
                                      encounters.conflict_cases)
narrow = encounters.narrow_channel_cases

_CACHE = {}


def result(study, case, method):
    key = (study.__name__, case, method)
    if key not in _CACHE:
        _CACHE[key] = run_scenario(with_method(study()[case], method))
    return _CACHE[key]


def min_distance(r, a=None, b=None):
    return min(p["min_distance"] for p in r.metrics["pairs"] if (a is None or p["a"] == a) and (b is None or p["b"] == b))


def pair(r, a, b):
    return next(p for p in r.metrics["pairs"] if p["a"] == a and p["b"] == b)


# --- static obstacle -----------------------------------------------------------------------------------------

@pytest.mark.parametrize("harmonic", ["sink-vortex", "modified-vortex"])
def test_harmonic_fields_clear_static_obstacle_wider_and_cheaper_than_inverse_square(harmonic):
    inv = result(static_obstacle, "goal-50", "inverse-square")
    h = result(static_obstacle, "goal-50", harmonic)
    assert not h.metrics["collision"] and h.metrics["ships"][0]["reached_goal"]
    assert min_distance(h) > min_distance(inv) + 0.5
    assert h.metrics["ships"][0]["ce"] < inv.metrics["ships"][0]["ce"]


def test_inverse_square_passes_goal_50_but_collides_with_goal_60():
    r50 = result(static_obstacle, "goal-50", "inverse-square")
    r60 = result(static_obstacle, "goal-60", "inverse-square")
    assert 2.0 <= min_distance(r50) < 3.0          # paper: "comes close to the collision threshold of 2L"
    assert min_distance(r60) < 2.0 and r60.metrics["collision"]
    assert r60.metrics["ships"][0]["collided"]


def test_modified_vortex_keeps_a_wider_berth_than_sink_vortex_off_the_starboard_bow():
    sv = result(static_obstacle, "starboard-bow", "sink-vortex")
    mv = result(static_obstacle, "starboard-bow", "modified-vortex")
    assert min_distance(mv) > min_distance(sv) + 1.0


# --- COLREGs -------------------------------------------------------------------------------------------------

def test_head_on_modified_vortex_both_turn_starboard_and_pass_port_to_port():
    r = result(colregs, "head-on", "modified-vortex")
    p = pair(r, "ship1", "ship2")
    assert 4.0 < p["min_distance"] < 9.0            # paper ≈ 6 L
    assert p["encounter"] == p["encounter_b"] == "head-on"
    assert p["compliant"] is True and p["compliant_b"] is True
    # both ships' first heading change is to starboard (ψ increases)
    for i in (0, 1):
        psi = np.unwrap(r.trajectory.state("psi", i))
        dev = psi - psi[0]
        k = int(np.argmax(np.abs(dev) > math.radians(2)))
        assert dev[k] > 0


def test_crossing_modified_vortex_give_way_turns_starboard_and_passes_astern():
    r = result(colregs, "crossing", "modified-vortex")
    p = pair(r, "ship1", "ship2")
    assert 4.0 < p["min_distance"] < 9.0            # paper ≈ 6 L
    assert p["encounter"] == "crossing-give-way" and p["encounter_b"] == "crossing-stand-on"
    assert p["compliant"] is True


@pytest.mark.xfail(strict=True, reason="the stand-on ship's own modified vortex is on at first (v_θ = 0 < the "
                   "threshold from its side too) and turns it 19.5° to starboard before CPA; our stated course "
                   "tolerance is 15° (the paper: 'does not deviate significantly')")
def test_crossing_modified_vortex_stand_on_keeps_course():
    assert pair(result(colregs, "crossing", "modified-vortex"), "ship1", "ship2")["compliant_b"] is True


@pytest.mark.parametrize("case", ["head-on", pytest.param("crossing", marks=pytest.mark.xfail(
    strict=True, reason="inverse-square crossing: closest approach 2.15 L here, the paper reports < 2 L"))])
def test_inverse_square_collides_head_on_and_crossing(case):
    r = result(colregs, case, "inverse-square")
    assert r.metrics["collision"] and min_distance(r) < 2.0


def test_overtaking_modified_vortex_passes_the_slower_ship_with_margin():
    r = result(colregs, "overtaking", "modified-vortex")
    p = pair(r, "ship1", "ship2")
    assert p["encounter"] == "overtaking" and p["encounter_b"] == "overtaken"
    assert p["min_distance"] > 4.0                  # paper ≈ 8 L
    own, slow = r.metrics["ships"]
    assert own["reached_goal"] and own["time_to_goal"] < 110
    # the overtaking ship ends up ahead of the slower one
    k = int(np.argmax(r.trajectory.state("status", 0) == 1))
    assert r.trajectory.state("x", 0)[k] > r.trajectory.state("x", 1)[k]


# --- conflicting responsibility, narrow channel --------------------------------------------------------------

def test_conflict_modified_vortex_is_collision_free_and_inverse_square_is_not():
    mv = result(conflict, "three-ships", "modified-vortex")
    inv = result(conflict, "three-ships", "inverse-square")
    assert not mv.metrics["collision"] and all(s["reached_goal"] for s in mv.metrics["ships"])
    assert min_distance(mv) > 4.0                   # paper ≈ 6 L
    assert inv.metrics["collision"]


def test_narrow_channel_both_pass_without_collision_inside_the_channel():
    r = result(narrow, "head-on", "modified-vortex")
    assert not r.metrics["collision"]
    assert all(s["reached_goal"] for s in r.metrics["ships"])
    mask = r.trajectory.sailing_mask()
    for i in (0, 1):
        x, y = r.trajectory.state("x", i)[mask[:, i]], r.trajectory.state("y", i)[mask[:, i]]
        off = np.abs(y - x) / math.sqrt(2)          # distance from the channel's centre line (the diagonal)
        assert np.max(off) < narrow_channel.HALF_WIDTH


# --- velocity obstacle in every study, schema ------------------------------------------------------------------

@pytest.mark.parametrize("study,case", [(static_obstacle, "goal-50"), (colregs, "head-on"), (colregs, "crossing"),
                                        (conflict, "three-ships"), (narrow, "head-on")])
def test_velocity_obstacle_runs_and_metrics_say_what_happened(study, case):
    r = result(study, case, "velocity-obstacle")
    m = r.metrics
    assert m["method"] == "velocity-obstacle"
    assert set(m) >= {"method", "collision", "ships", "pairs"}
    for s in m["ships"]:
        assert set(s) >= {"name", "reached_goal", "time_to_goal", "ce", "mcte", "collided"}
    for p in m["pairs"]:
        assert set(p) >= {"a", "b", "min_distance", "t_min", "encounter", "compliant"}
    assert m["collision"] == any(p["min_distance"] < 2.0 for p in m["pairs"])


def test_study_cli_writes_cases_by_method(tmp_path):
    out = tmp_path / "colregs"
    assert main(["study", "colregs", "--methods", "modified-vortex,inverse-square", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert set(m["cases"]) == {"overtaking", "head-on", "crossing"}
    for case in m["cases"].values():
        assert set(case) == {"modified-vortex", "inverse-square"}
    assert (out / "head-on.png").exists() and (out / "head-on" / "modified-vortex" / "trajectory.npz").exists()


def test_ship_pairs_carry_rule_verdicts_under_the_chosen_profile():
    r = result(colregs, "crossing", "modified-vortex")
    p = pair(r, "ship1", "ship2")
    rules = p["rules"]
    assert rules["profile"] == "iitm-lab"
    assert rules["a"]["compliant_all"] is p["compliant"] and rules["b"]["compliant_all"] is p["compliant_b"]
    assert rules["a"]["15"]["verdict"] is True and rules["a"]["quantities"]["crossed_other_course"] == "astern"
    json.dumps(r.metrics, allow_nan=False)
    ntnu = pair(assess(r.scenario, r.trajectory, build_problem(r.scenario).params, profile="ntnu-2023"),
                "ship1", "ship2")
    assert ntnu["rules"]["profile"] == "ntnu-2023" and ntnu["min_distance"] == p["min_distance"]
