"""Rule-by-rule COLREG verdicts (mmg_casadi.colregs.score) on hand-built trajectories.

Ships sail at unit speed (1 L per unit of time) unless stated. The crossing: give-way ship a from (0, 0)
heading 0 (towards +x), stand-on ship b from (25, 25) heading -90 deg (towards -y); on unchanged courses
both reach (25, 0) at t = 25, so the range is sqrt(2) (25 - t), the closing speed sqrt(2) and TCPA = 25 - t.
The head-on: a from (0, 0) heading 0 against b from (50, 0) heading 180 deg, range 50 - 2 t, TCPA = 25 - t.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from mmg_casadi.colregs.assess import assess_pair
from mmg_casadi.colregs.classify import ColregProfile, classify_encounter, get_profile
from mmg_casadi.colregs.score import RULES, cpa_tcpa, score_pair, stand_on_should_act
from mmg_casadi.errors import InputError, ParameterError

T = np.arange(0.0, 80.0 + 1e-9, 0.1)
KW = {"r_safe": 15.0, "collision_distance": 2.0}
LAB = ColregProfile()
NTNU = ColregProfile.ntnu_2023()


def ramp(t0, t1, deg):
    """Heading change (rad) growing linearly from 0 at t0 to ``deg`` degrees at t1."""
    return np.radians(deg) * np.clip((T - t0) / (t1 - t0), 0.0, 1.0)


def track(p0, psi, speed=1.0):
    """Positions (T, 2) of a ship starting at ``p0`` sailing at ``speed`` (scalar or (T,)) along ``psi``."""
    v = np.reshape(speed, (-1, 1)) * np.column_stack([np.cos(psi), np.sin(psi)])
    steps = 0.5 * (v[1:] + v[:-1]) * np.diff(T)[:, None]
    return np.vstack([np.zeros(2), np.cumsum(steps, axis=0)]) + np.asarray(p0, dtype=float)


def const(value):
    return np.full_like(T, value)


def crossing(psi_a=None, psi_b=None, profile=LAB, **kw):
    psi_a = const(0.0) if psi_a is None else psi_a
    psi_b = const(-math.pi / 2) if psi_b is None else psi_b
    return score_pair(T, track((0, 0), psi_a), psi_a, track((25, 25), psi_b), psi_b, profile=profile, **KW, **kw)


def head_on(psi_a, psi_b, profile=LAB):
    return score_pair(T, track((0, 0), psi_a), psi_a, track((50, 0), psi_b), psi_b, profile=profile, **KW)


def verdicts(side):
    return {r: v for r, v in side.verdicts.items() if v is not None}


# --- head-on (Rule 14) ------------------------------------------------------------------------------------------

def test_head_on_both_turning_starboard_keep_rule_14():
    turn = ramp(18, 20, 30)
    s = head_on(turn, math.pi + turn)
    for side in (s.a, s.b):
        assert side.encounter == "head-on"
        assert verdicts(side) == {"8": True, "14": True} and side.compliant_all is True
        q = side.quantities
        assert q["other_side_at_cpa"] == "port"
        # 2 deg of a 30 deg-in-2 ramp from t = 18 is passed at 18.13: first sample 18.2, range 50 - 2*18.2
        assert q["t_action"] == pytest.approx(18.2) and q["action_side"] == "starboard"
        assert q["range_at_action"] == pytest.approx(13.6, abs=0.02)
        assert q["tcpa_at_action"] == pytest.approx(6.8, abs=0.05)
        assert q["heading_change_deg"] == pytest.approx(30.0)


def test_head_on_own_ship_turning_port_breaks_rule_14():
    psi_a = -ramp(18, 20, 30)
    s = head_on(psi_a, const(math.pi))
    assert s.a.verdicts["14"] is False and s.a.compliant_all is False
    assert s.a.quantities["action_side"] == "port" and s.a.quantities["other_side_at_cpa"] == "starboard"
    # the port turn is large and early, so Rule 8 itself holds; b never altered: Rules 8 and 14 broken
    assert s.a.verdicts["8"] is True
    assert s.b.verdicts["14"] is False and s.b.verdicts["8"] is False and s.b.quantities["t_action"] is None


def test_head_on_alteration_in_time_but_too_small_to_pass_clear_breaks_rule_8d():
    turn = ramp(20.5, 21.5, 10.5)  # 10.5 deg from TCPA 4.5: sideways about 2 x 4 sin(10.5 deg) = 1.5 L < 2 L
    s = head_on(turn, math.pi + turn)
    d8 = s.a.details["8"]
    assert d8["heading_change_deg"] >= LAB.apparent_deg and d8["tcpa_at_action"] >= LAB.act_tcpa
    assert d8["cpa_distance"] == pytest.approx(1.5, abs=0.15)
    assert s.a.verdicts["8"] is False  # Rule 8(d): not passing at a safe distance
    assert s.a.verdicts["14"] is True  # though to starboard and port to port


def test_late_alteration_without_risk_of_collision_is_not_late():
    turn = ramp(22, 23, 15)  # TCPA 3 < 4, but on courses 6 L apart there is no risk of collision to act on
    s = score_pair(T, track((0, 0), turn), turn, track((50, -6), math.pi + turn), math.pi + turn, **KW)
    d8 = s.a.details["8"]
    assert d8["tcpa_at_action"] < LAB.act_tcpa and d8["cpa_predicted_at_action"] > 2.0
    assert s.a.verdicts["8"] is True and s.a.verdicts["14"] is True


# --- crossing, give-way (Rules 8, 15, 16) -----------------------------------------------------------------------

def test_crossing_give_way_turning_30_deg_starboard_and_passing_astern():
    s = crossing(ramp(14.5, 16.5, 30))
    assert (s.a.encounter, s.b.encounter) == ("crossing-give-way", "crossing-stand-on")
    assert verdicts(s.a) == {"8": True, "15": True, "16": True} and s.a.compliant_all is True
    q = s.a.quantities
    assert q["crossed_other_course"] == "astern"
    assert q["t_enter"] == pytest.approx(14.4)  # sqrt(2) (25 - t) < 15 from t = 14.39
    assert q["tcpa_enter"] == pytest.approx(10.6, abs=1e-6) and q["cpa_predicted_enter"] == pytest.approx(0, abs=1e-6)
    assert q["tcpa_at_action"] > LAB.act_tcpa and q["cpa_distance"] > 2.0
    # the stand-on ship held her course; no risk of collision remained, so 17(a)(ii)/(b) do not arise
    assert verdicts(s.b) == {"17a": True} and s.b.quantities["t_may_act"] is None


def test_crossing_give_way_turning_3_deg_is_not_readily_apparent():
    s = crossing(ramp(14.5, 15.5, 3))
    d8 = s.a.details["8"]
    assert s.a.verdicts["8"] is False
    assert d8["heading_change_deg"] == pytest.approx(3.0) and d8["tcpa_at_action"] > LAB.act_tcpa  # in time, too small
    assert s.a.verdicts["15"] is False and s.a.verdicts["16"] is False


def test_crossing_give_way_acting_late_breaks_rules_8_and_16():
    s = crossing(ramp(22, 23, 60))
    q = s.a.quantities
    # 2 deg of a 60 deg-per-unit ramp from t = 22 is passed at 22.03: first sample 22.1, TCPA = 25 - 22.1
    assert q["t_action"] == pytest.approx(22.1)
    assert q["tcpa_at_action"] == pytest.approx(2.9, abs=0.15) and q["tcpa_at_action"] < LAB.act_tcpa
    assert q["range_at_action"] == pytest.approx(math.sqrt(2) * 2.9, abs=0.05)
    assert q["heading_change_deg"] == pytest.approx(60.0)  # large enough, but late
    assert s.a.verdicts["8"] is False and s.a.verdicts["16"] is False and s.a.compliant_all is False


# --- crossing, stand-on (Rule 17) -------------------------------------------------------------------------------

def test_stand_on_keeping_course_into_a_collision_breaks_rule_17b():
    s = crossing()
    assert s.a.quantities["cpa_distance"] < 2.0
    assert s.b.verdicts["17a"] is True  # she kept course and speed while she had to ...
    assert s.b.verdicts["17b"] is False  # ... but then never acted
    assert s.b.compliant_all is False
    # she may act from TCPA <= 4 (t = 21) and must from TCPA <= 2 (t = 23)
    assert s.b.quantities["t_may_act"] == pytest.approx(21.0, abs=0.11)
    assert s.b.quantities["t_must_act"] == pytest.approx(23.0, abs=0.11)
    r = assess_pair(T, track((0, 0), const(0.0)), const(0.0), track((25, 25), const(-math.pi / 2)),
                    const(-math.pi / 2), **KW)
    assert r.compliant_b is False and r.rules["b"]["17b"]["verdict"] is False


def test_stand_on_turning_starboard_at_close_range_when_give_way_does_nothing():
    psi_b = -math.pi / 2 + ramp(21.5, 22.5, 120)
    s = crossing(psi_b=psi_b)
    assert s.a.verdicts["15"] is False and s.a.verdicts["16"] is False
    assert s.b.quantities["t_may_act"] < s.b.quantities["t_action"] < 22.0
    assert verdicts(s.b) == {"8": True, "17a": True, "17b": True, "17c": True} and s.b.compliant_all is True
    assert s.b.quantities["cpa_distance"] > 2.0


def test_stand_on_turning_port_for_a_ship_on_her_port_side_breaks_rule_17c():
    psi_b = -math.pi / 2 - ramp(21.5, 22.5, 60)
    s = crossing(psi_b=psi_b)
    assert s.b.verdicts["17c"] is False and s.b.compliant_all is False
    assert s.b.verdicts["17b"] is True  # she did act; the direction is what 17(c) forbids
    assert s.b.details["17c"]["port_change_deg"] == pytest.approx(60.0)


def test_stand_on_altering_early_breaks_rule_17a():
    psi_b = -math.pi / 2 + ramp(16, 18, 30)
    s = crossing(ramp(14.5, 16.5, 30), psi_b)
    assert s.b.verdicts["17a"] is False and s.b.details["17a"]["heading_change_deg"] == pytest.approx(30.0)


def test_stand_on_halving_her_speed_breaks_rule_17a():
    speed_b = np.where(T < 16.0, 1.0, 0.5)
    psi_a, psi_b = ramp(14.5, 16.5, 30), const(-math.pi / 2)
    pos_a, pos_b = track((0, 0), psi_a), track((25, 25), psi_b, speed_b)
    s = score_pair(T, pos_a, psi_a, pos_b, psi_b, speed_a=const(1.0), speed_b=speed_b, **KW)
    assert s.b.verdicts["17a"] is False and s.b.details["17a"]["speed_change"] == pytest.approx(0.5)
    assert s.b.details["17a"]["heading_change_deg"] == 0.0


# --- overtaking (Rule 13) ---------------------------------------------------------------------------------------

def test_overtaking_ship_keeping_clear_keeps_rule_13():
    psi_a = ramp(12, 14, 25) - ramp(30, 34, 25)
    psi_b = const(0.0)
    s = score_pair(T, track((0, 0), psi_a), psi_a, track((20, 0), psi_b, 0.5), psi_b, **KW)
    assert (s.a.encounter, s.b.encounter) == ("overtaking", "overtaken")
    assert verdicts(s.a) == {"8": True, "13": True, "16": True}
    assert s.a.quantities["tcpa_enter"] == pytest.approx(30.0, abs=0.2)  # 15 L closed at 0.5 L per unit
    assert verdicts(s.b) == {"17a": True}


def test_overtaken_ship_holding_on_into_an_overtaking_collision_breaks_rule_17b():
    psi = const(0.0)
    s = score_pair(T, track((0, 0), psi), psi, track((20, 0.5), psi, 0.5), psi, **KW)
    assert s.a.verdicts["13"] is False and s.a.verdicts["16"] is False and s.a.verdicts["8"] is None
    assert s.b.verdicts["17a"] is True and s.b.verdicts["17b"] is False and s.b.verdicts["17c"] is None


# --- profiles ---------------------------------------------------------------------------------------------------

def test_20_deg_alteration_is_apparent_in_the_lab_profile_but_not_in_ntnu_2023():
    psi_a = ramp(14.5, 16.5, 20)
    lab, ntnu = crossing(psi_a, profile=LAB), crossing(psi_a, profile=NTNU)
    assert lab.a.verdicts["8"] is True and lab.a.verdicts["16"] is True
    assert ntnu.a.verdicts["8"] is False and ntnu.a.verdicts["16"] is False  # Δχ_app = 30 deg
    assert ntnu.a.verdicts["15"] is True  # the same passage astern


def test_small_stand_on_wobble_passes_the_lab_tolerance_but_not_ntnu_2023():
    psi_a, psi_b = ramp(14.5, 16.5, 30), -math.pi / 2 + ramp(15, 16, 5) - ramp(17, 18, 5)
    assert crossing(psi_a, psi_b, profile=LAB).b.verdicts["17a"] is True  # 5 deg <= 15 deg
    assert crossing(psi_a, psi_b, profile=NTNU).b.verdicts["17a"] is False  # 5 deg > 2 deg (detectable)


def test_ntnu_2023_head_on_needs_both_bearings_within_13_deg():
    own, other = ((0, 0), 0.0), ((50, 1), math.radians(200))  # relative heading 160 deg, other 20 deg off her bow
    assert classify_encounter(*own, *other, LAB) == "head-on"
    assert classify_encounter(*own, *other, NTNU) == "crossing-give-way"
    assert classify_encounter(*own, (50, 1), math.radians(185), NTNU) == "head-on"


def test_ntnu_2023_overtaking_needs_the_overtaken_ship_within_45_deg_of_the_bow():
    a = math.radians(120)  # the other 120 deg off own bow, same course: own sees her 60 deg off her bow
    other = ((10 * math.cos(a), 10 * math.sin(a)), 0.0)
    assert classify_encounter((0, 0), 0.0, *other, LAB) == "overtaken"
    assert classify_encounter((0, 0), 0.0, *other, NTNU) == "none"


def test_ntnu_2023_ranges_are_converted_to_kcs_lengths():
    assert NTNU.act_range == pytest.approx(1100.0 / 230.0) and NTNU.must_act_range == pytest.approx(200.0 / 230.0)
    assert ColregProfile.ntnu_2023(100.0).act_range == pytest.approx(11.0)
    with pytest.raises(ParameterError, match="metres_per_length"):
        ColregProfile.ntnu_2023(0.0)


def test_get_profile_and_validation():
    assert get_profile("ntnu-2023") == NTNU and get_profile(None) == get_profile("iitm-lab") == LAB
    assert get_profile(NTNU) is NTNU and get_profile("strict") == ColregProfile.strict()
    with pytest.raises(InputError, match="profile"):
        get_profile("woerner")
    with pytest.raises(ParameterError, match="act_tcpa"):
        ColregProfile(act_tcpa=-1.0)
    with pytest.raises(ParameterError, match="speed_apparent"):
        ColregProfile(speed_apparent=1.5)


# --- pure functions and output ----------------------------------------------------------------------------------

def test_cpa_tcpa():
    cpa, tcpa = cpa_tcpa(np.array([10.0, 3.0]), np.array([-1.0, 0.0]))
    assert (float(cpa), float(tcpa)) == pytest.approx((3.0, 10.0))
    cpa, tcpa = cpa_tcpa(np.array([3.0, 4.0]), np.zeros(2))
    assert float(cpa) == pytest.approx(5.0) and tcpa == math.inf


def test_stand_on_should_act_ranges_of_ntnu_2023():
    kw = {"collision_distance": 2.0, "profile": NTNU}
    assert stand_on_should_act(0.5, 9.0, 5.0, **kw) == (False, False)  # beyond stage 3 (4.78 L)
    assert stand_on_should_act(0.5, 9.0, 4.0, **kw) == (True, False)  # stage 3
    assert stand_on_should_act(0.5, 9.0, 0.8, **kw) == (True, True)  # stage 4 (0.87 L)
    assert stand_on_should_act(2.5, 9.0, 0.8, **kw) == (False, False)  # no risk: predicted CPA beyond 2 L
    assert stand_on_should_act(0.5, -1.0, 0.8, **kw) == (False, False)  # moving apart


def test_rules_output_is_plain_json_with_every_rule():
    r = assess_pair(T, track((0, 0), const(0.0)), const(0.0), track((25, 25), const(-math.pi / 2)),
                    const(-math.pi / 2), profile="ntnu-2023", **KW)
    text = json.dumps(r.rules, allow_nan=False)
    out = json.loads(text)
    assert out["profile"] == "ntnu-2023"
    for side in ("a", "b"):
        assert set(out[side]) == {"encounter", "compliant_all", "quantities", *RULES}
        assert all(out[side][rule]["verdict"] in (True, False, None) for rule in RULES)
    assert out["a"]["compliant_all"] is r.compliant and out["b"]["compliant_all"] is r.compliant_b
    assert out["a"]["quantities"]["tcpa_at_action"] is None  # never acted: null, not NaN


def test_no_encounter_has_no_verdicts():
    psi = const(0.0)
    s = score_pair(T, track((0, 0), psi), psi, track((0, 20), psi), psi, **KW)
    assert s.a.encounter == s.b.encounter == "none"
    assert set(s.a.verdicts.values()) == {None} and s.a.compliant_all is None


def test_lab_tcpa_thresholds_bracket_the_kcs_turning_times():
    from mmg_casadi.vessel.maneuvers import turning_circle
    r = turning_circle(35.0, t_end=40.0)
    psi = np.degrees(r.state("psi"))
    t30, t60 = (float(np.interp(d, psi, r.t)) for d in (30.0, 60.0))
    assert t60 < LAB.act_tcpa  # a 60 deg alteration started at TCPA 4 is complete before the CPA
    assert t30 > LAB.must_act_tcpa  # from TCPA 2 not even a 30 deg one is
