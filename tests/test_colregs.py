"""COLREG bookkeeping (mmg_casadi.colregs.classify, .assess, .geometry) on hand-built trajectories."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mmg_casadi.colregs.assess import PairAssessment, assess_obstacle, assess_pair
from mmg_casadi.colregs.classify import ENCOUNTERS, ColregProfile, classify_encounter
from mmg_casadi.colregs.geometry import wrap_to_pi
from mmg_casadi.errors import ParameterError

T = np.arange(0.0, 80.0 + 1e-9, 0.1)
KW = {"r_safe": 15.0, "collision_distance": 2.0}


def ramp(t0, t1, deg):
    """Heading change (rad) growing linearly from 0 at t0 to ``deg`` degrees at t1."""
    return np.radians(deg) * np.clip((T - t0) / (t1 - t0), 0.0, 1.0)


def track(p0, psi, speed=1.0):
    """Positions (T, 2) of a ship starting at ``p0`` sailing at ``speed`` along headings ``psi``."""
    v = speed * np.column_stack([np.cos(psi), np.sin(psi)])
    steps = 0.5 * (v[1:] + v[:-1]) * np.diff(T)[:, None]
    return np.vstack([np.zeros(2), np.cumsum(steps, axis=0)]) + np.asarray(p0, dtype=float)


def const(value):
    return np.full_like(T, value)


# --- classification -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("own, other, expected_own, expected_other", [
    # the paper's head-on: (0,0) -> (50,0) against (50,0) -> (0,0)
    (((0, 0), 0.0), ((50, 0), math.pi), "head-on", "head-on"),
    # the paper's crossing: the other at (25,25) heading -90 deg comes from own's starboard side
    (((0, 0), 0.0), ((25, 25), -math.pi / 2), "crossing-give-way", "crossing-stand-on"),
    # mirror image: the other comes from own's port side, so own stands on
    (((0, 0), 0.0), ((25, -25), math.pi / 2), "crossing-stand-on", "crossing-give-way"),
    # overtaking set-up: faster own ship 12 L behind on the same course
    (((0, 0), 0.0), ((12, 0), 0.0), "overtaking", "overtaken"),
    # the paper's narrow channel: head-on along the diagonal
    (((0, 0), math.radians(45)), ((50, 50), math.radians(-135)), "head-on", "head-on"),
    # abeam on parallel courses, and stern to stern (diverging): no rule
    (((0, 0), 0.0), ((0, 10), 0.0), "none", "none"),
    (((0, 0), 0.0), ((-10, 0), math.pi), "none", "none"),
])
def test_classification_from_both_perspectives(own, other, expected_own, expected_other):
    assert classify_encounter(*own, *other) == expected_own
    assert classify_encounter(*other, *own) == expected_other


def test_conflict_scenario_responsibilities():
    ship1, ship2, ship3 = ((0, 0), 0.0), ((-20, 0), 0.0), ((60, 0), math.pi)
    assert classify_encounter(*ship1, *ship2) == "overtaken"  # ship 1 stands on towards ship 2
    assert classify_encounter(*ship2, *ship1) == "overtaking"
    assert classify_encounter(*ship1, *ship3) == "head-on"  # and gives way to ship 3
    assert classify_encounter(*ship3, *ship1) == "head-on"


def test_classification_is_invariant_to_heading_wrapping():
    assert classify_encounter((0, 0), 2 * math.pi, (25, 25), 3 * math.pi / 2) == "crossing-give-way"
    assert classify_encounter((25, 25), -5 * math.pi / 2, (0, 0), -2 * math.pi) == "crossing-stand-on"


def test_stern_sector_edges():
    # other ship 112.5 deg and 247.5 deg off the bow lie inside the lab's [5pi/8, 11pi/8) stern sector
    for deg, inside in ((110.0, False), (115.0, True), (245.0, True), (250.0, False)):
        a = math.radians(deg)
        other = (10 * math.cos(a), 10 * math.sin(a))
        assert (classify_encounter((0, 0), 0.0, other, 0.0) == "overtaken") is inside


def test_strict_profile_narrows_head_on():
    other_psi = math.pi + math.radians(10)  # psi_r = -10 deg from reciprocal, i.e. 170 deg
    assert classify_encounter((0, 0), 0.0, (50, 0), other_psi) == "head-on"
    strict = ColregProfile.strict()
    assert classify_encounter((0, 0), 0.0, (50, 0), other_psi, strict) == "crossing-give-way"
    assert classify_encounter((0, 0), 0.0, (50, 0), math.pi + math.radians(3), strict) == "head-on"
    assert classify_encounter((0, 0), 0.0, (50, 0), math.pi - math.radians(10), strict) == "crossing-stand-on"


def test_profile_validation():
    with pytest.raises(ParameterError, match="head_on"):
        ColregProfile(head_on=(1.0, 1.0))
    with pytest.raises(ParameterError, match="stern_sector"):
        ColregProfile(stern_sector=(1.0, 7.0))
    with pytest.raises(ParameterError, match="course_tolerance_deg"):
        ColregProfile(course_tolerance_deg=-1.0)


def test_wrap_to_pi():
    assert wrap_to_pi(math.pi) == pytest.approx(-math.pi)
    np.testing.assert_allclose(wrap_to_pi(np.array([0.0, 2 * math.pi + 0.1, -0.1])), [0.0, 0.1, -0.1], atol=1e-12)


# --- compliance -------------------------------------------------------------------------------------------------

def test_head_on_both_turning_starboard_is_compliant():
    turn = ramp(18, 22, 40) - ramp(30, 34, 40)
    psi_a, psi_b = turn, math.pi + turn
    r = assess_pair(T, track((0, 0), psi_a), psi_a, track((50, 0), psi_b), psi_b, **KW)
    assert (r.encounter, r.encounter_b) == ("head-on", "head-on")
    assert r.compliant is True and r.compliant_b is True
    assert r.t_enter == pytest.approx(17.6)
    assert 2.0 < r.min_distance < 15.0 and r.t_enter < r.t_min


def test_head_on_one_turning_port_is_not_compliant():
    psi_a = -ramp(18, 22, 40)
    psi_b = const(math.pi)
    r = assess_pair(T, track((0, 0), psi_a), psi_a, track((50, 0), psi_b), psi_b, **KW)
    assert r.encounter == "head-on" and r.compliant is False
    assert r.compliant_b is False  # b held her course: no starboard alteration either


def test_crossing_give_way_starboard_and_astern_is_compliant():
    psi_a = ramp(15, 17, 60) - ramp(21, 25, 100)  # starboard, then back to port behind the stand-on ship
    psi_b = const(-math.pi / 2)
    pos_a, pos_b = track((0, 0), psi_a), track((25, 25), psi_b)
    r = assess_pair(T, pos_a, psi_a, pos_b, psi_b, **KW)
    assert (r.encounter, r.encounter_b) == ("crossing-give-way", "crossing-stand-on")
    assert r.compliant is True and r.compliant_b is True
    k = np.flatnonzero(np.diff(np.sign(pos_a[:, 0] - 25.0)))[0]  # a crosses b's course line x = 25 ...
    assert np.linalg.norm(pos_a[k] - pos_b[k]) < 15.0  # ... inside r_safe ...
    assert pos_a[k, 1] > pos_b[k, 1]  # ... behind b, who sails towards -y


def test_crossing_give_way_crossing_ahead_is_not_compliant():
    psi_a = ramp(11, 12, 10)  # a small starboard turn, but fast enough to cross ahead
    psi_b = const(-math.pi / 2)
    pos_a, pos_b = track((0, 0), psi_a, speed=2.0), track((25, 25), psi_b)
    r = assess_pair(T, pos_a, psi_a, pos_b, psi_b, **KW)
    assert r.encounter == "crossing-give-way" and r.t_enter < 11.0
    assert r.compliant is False
    assert r.compliant_b is True


def test_crossing_give_way_holding_course_is_not_compliant():
    psi_a, psi_b = const(0.0), const(-math.pi / 2)
    r = assess_pair(T, track((0, 0), psi_a), psi_a, track((25, 25), psi_b), psi_b, **KW)
    assert r.compliant is False and r.min_distance < 2.0
    # the stand-on ship held her course into the collision: Rule 17(a)(i) kept, but 17(b) (act when collision
    # cannot be avoided by the give-way ship alone) broken, so she is not compliant either
    assert r.compliant_b is False
    assert r.rules["b"]["17a"]["verdict"] is True and r.rules["b"]["17b"]["verdict"] is False


def test_stand_on_altering_course_is_not_compliant():
    psi_a = ramp(15, 17, 60) - ramp(21, 25, 100)
    psi_b = -math.pi / 2 + ramp(16, 18, 30)  # the stand-on ship turns 30 deg
    r = assess_pair(T, track((0, 0), psi_a), psi_a, track((25, 25), psi_b), psi_b, **KW)
    assert r.encounter_b == "crossing-stand-on" and r.compliant_b is False


def test_overtaking_keeps_clear_and_overtaken_stands_on():
    psi_a = ramp(10, 12, 20) - ramp(20, 24, 20)
    psi_b = const(0.0)
    r = assess_pair(T, track((0, 0), psi_a), psi_a, track((12, 0), psi_b, speed=0.5), psi_b, **KW)
    assert (r.encounter, r.encounter_b) == ("overtaking", "overtaken")
    assert r.t_enter == 0.0  # starts 12 L apart, already inside r_safe
    assert r.compliant is True and r.compliant_b is True


def test_overtaking_collision_is_not_compliant():
    psi = const(0.0)
    r = assess_pair(T, track((0, 0), psi), psi, track((12, 0), psi, speed=0.5), psi, **KW)
    assert r.encounter == "overtaking" and r.compliant is False and r.min_distance < 2.0


def test_no_encounter_outside_r_safe():
    psi = const(0.0)
    r = assess_pair(T, track((0, 0), psi), psi, track((0, 20), psi), psi, **KW)
    assert r == PairAssessment(pytest.approx(20.0), 0.0, "none", None, "none", None, None)


def test_active_masks_limit_the_distances():
    psi_a, psi_b = const(0.0), const(math.pi)
    pos_a, pos_b = track((0, 0), psi_a), track((50, 0), psi_b)
    r = assess_pair(T, pos_a, psi_a, pos_b, psi_b, active_b=T <= 10.0, **KW)
    assert r.encounter == "none" and r.min_distance == pytest.approx(30.0) and r.t_min == pytest.approx(10.0)
    r = assess_pair(T, pos_a, psi_a, pos_b, psi_b, active_a=T >= 90.0, **KW)
    assert r.min_distance == math.inf and r.t_min is None and r.encounter == "none"


def test_continuous_and_wrapped_headings_agree():
    turn = ramp(18, 22, 40) - ramp(30, 34, 40)
    psi_a, psi_b = turn, math.pi + turn
    pos_a, pos_b = track((0, 0), psi_a), track((50, 0), psi_b)
    r1 = assess_pair(T, pos_a, psi_a, pos_b, psi_b, **KW)
    r2 = assess_pair(T, pos_a, wrap_to_pi(psi_a + 4 * math.pi), pos_b, wrap_to_pi(psi_b), **KW)
    assert r1 == r2


def test_encounters_are_from_the_documented_set():
    psi = const(0.0)
    r = assess_pair(T, track((0, 0), psi), psi, track((12, 0), psi, speed=0.5), psi, **KW)
    assert {r.encounter, r.encounter_b} <= set(ENCOUNTERS)
    assert r.to_dict()["encounter_b"] == "overtaken"


def test_bad_input():
    psi = const(0.0)
    pos = track((0, 0), psi)
    with pytest.raises(ValueError, match="pos_b"):
        assess_pair(T, pos, psi, pos[:-1], psi, **KW)
    with pytest.raises(ValueError, match="psi_a"):
        assess_pair(T, pos, psi[:-1], pos, psi, **KW)
    with pytest.raises(ParameterError, match="r_safe"):
        assess_pair(T, pos, psi, pos, psi, r_safe=0.0, collision_distance=2.0)


# --- static obstacles -------------------------------------------------------------------------------------------

@pytest.mark.parametrize("offset, radius, clear", [(3.0, 0.5, True), (1.0, 0.5, False), (3.0, 3.0, False)])
def test_assess_obstacle(offset, radius, clear):
    pos = track((0, offset), const(0.0))
    r = assess_obstacle(T, pos, (25.0, 0.0), radius, 2.0)
    assert r.min_distance == pytest.approx(offset, abs=1e-9) and r.t_min == pytest.approx(25.0)
    assert r.encounter == "static" and r.compliant is clear and r.compliant_b is None


def test_assess_obstacle_inactive_ship():
    pos = track((0, 0), const(0.0))
    r = assess_obstacle(T, pos, (25.0, 0.0), 0.5, 2.0, active_a=T <= 10.0)
    assert r.min_distance == pytest.approx(15.0) and r.t_min == pytest.approx(10.0) and r.compliant is True
