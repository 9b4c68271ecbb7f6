"""colregs-vortex: Rule 17 stand-on behaviour, Rule 8, the near-goal fix, and its closed loop."""

import dataclasses
import math
from importlib.resources import files

import casadi as ca
import numpy as np
import pytest

from mmg_casadi.closed_loop.layout import default_globals
from mmg_casadi.guidance.colregs_encounters import GIVE_WAY
from mmg_casadi.guidance.colregs_vortex import (FLOOR_STEP, ColregsVortexParams, colregs_vortex,
                                               colregs_vortex_terms)
from mmg_casadi.errors import InputError, ParameterError
from mmg_casadi.guidance import methods
from mmg_casadi.guidance.fields import heading_of, modified_vortex
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.scenario import load_scenario, scenario_from_dict, with_method
from mmg_casadi.scenarios.run import run_scenario

CV = ColregsVortexParams()
MV_KW = dict(lam_sink=-100.0, k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=5 * math.pi / 8)
# the rules alone: the close-quarters filter, which may depart from them within r_cq (Rule 2(b) / 17(b)), is
# tested in test_colregs_vortex_close_quarters.py
KW = MV_KW | CV.as_dict() | {"r_cq": 0.0}
OWN = dict(own_pos=[0.0, 0.0], own_psi=0.0, own_vel=[1.0, 0.0])
FAR_GOAL = [50.0, 0.0]


def heading(goal, nb_pos, nb_vel, method="colregs"):
    """Desired heading (deg) of the own ship at the origin heading north at the design speed."""
    nb_pos, nb_vel = ca.DM(nb_pos).reshape((2, -1)), ca.DM(nb_vel).reshape((2, -1))
    ones = [1.0] * nb_pos.size2()
    if method == "colregs":
        v = colregs_vortex(goal=goal, nb_pos=nb_pos, nb_vel=nb_vel, active=ones, **OWN, **KW)
    else:
        v = modified_vortex(goal=goal, nb_pos=nb_pos, nb_vel=nb_vel, active=ones, **OWN, **MV_KW)
    return math.degrees(float(heading_of(v)))


def collision_course(course_deg, tcpa, offset=0.0):
    """Position and velocity of a design-speed ship on course ``course_deg`` that meets the own ship (north at
    speed 1 from the origin) after ``tcpa``, displaced by ``offset`` L across the relative velocity."""
    c = math.radians(course_deg)
    v_t = np.array([math.cos(c), math.sin(c)])
    rel = v_t - [1.0, 0.0]
    pos = -rel * tcpa + offset * np.array([-rel[1], rel[0]]) / np.linalg.norm(rel)
    return pos, v_t


def terms(nb_pos, nb_vel, goal=FAR_GOAL):
    kw = {k: v for k, v in KW.items() if k != "lam_sink"}
    return colregs_vortex_terms(goal=goal, nb_pos=ca.DM(nb_pos), nb_vel=ca.DM(nb_vel), **OWN, **kw)


# --- Rule 17 -------------------------------------------------------------------------------------------------

def test_stand_on_keeps_course_while_the_give_way_ship_still_has_time():
    # crossing from port on a collision course, TCPA 10 > t_act: 17(a)(i), no deviation
    pos, vel = collision_course(90.0, 10.0)
    assert pos[1] < 0 and 10.0 > CV.t_act
    assert heading(FAR_GOAL, pos, vel) == pytest.approx(0.0, abs=1e-9)
    # the paper's modified vortex acts on the same ship (the behaviour this method changes)
    assert heading(FAR_GOAL, pos, vel, method="modified") > 1.0


def test_stand_on_acts_alone_below_the_trigger_turning_to_starboard():
    pos, vel = collision_course(90.0, 3.5)  # TCPA below t_act, CPA 0 < d_cpa_act: 17(a)(ii)
    t = terms(pos, vel)
    assert int(t["stand_on"]) == 1 and int(t["act_alone"]) == 1
    assert heading(FAR_GOAL, pos, vel) >= math.degrees(CV.dpsi_min) - 1e-9


def test_stand_on_does_not_act_when_the_cpa_is_already_safe():
    pos, vel = collision_course(90.0, 3.5, offset=CV.d_cpa_act + 0.5)
    t = terms(pos, vel)
    assert int(t["stand_on"]) == 1 and int(t["act_alone"]) == 0
    assert float(t["dcpa"]) == pytest.approx(CV.d_cpa_act + 0.5, rel=1e-9)
    assert heading(FAR_GOAL, pos, vel) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("course", [30.0, 60.0, 90.0, 120.0, 135.0])
@pytest.mark.parametrize("tcpa", [1.5, 3.0, 3.9])
def test_stand_on_never_turns_to_port_for_a_ship_crossing_from_port(course, tcpa):
    pos, vel = collision_course(course, tcpa)  # 17(c)
    assert pos[1] < 0
    assert int(terms(pos, vel)["act_alone"]) == 1
    assert heading(FAR_GOAL, pos, vel) > 0.0


def test_fine_crossing_from_port_is_taken_as_head_on_rule_14c():
    # a ship on course 150° meeting the own ship (north): each within 22.5° of the other's bow but the courses
    # 30° from reciprocal; the scorer calls it a crossing (own stand-on), the method assumes head-on in doubt
    pos, vel = collision_course(150.0, 3.0)
    t = terms(pos, vel)
    assert int(t["role"]) == 4 and int(t["head_on"]) == 1 and int(t["stand_on"]) == 0
    assert heading(FAR_GOAL, pos, vel) >= math.degrees(CV.dpsi_min) - 1e-9


@pytest.mark.parametrize("side, turn", [(+0.5, -1), (-0.5, +1)])
def test_overtaken_ship_acts_for_an_overtaker_closing_from_astern(side, turn):
    # a faster ship 5 L astern, about to pass 0.5 L off: the modified vortex ignores the stern sector; here the
    # own ship turns away from the side the overtaker passes on, by more than the Rule 8 minimum
    pos, vel = [-5.0, side], [1.6, 0.0]
    assert heading(FAR_GOAL, pos, vel, method="modified") == pytest.approx(0.0, abs=1e-9)
    t = terms(pos, vel)
    assert int(t["stand_on"]) == 1 and int(t["act_alone"]) == 1
    assert turn * heading(FAR_GOAL, pos, vel) > math.degrees(CV.dpsi_min)


def test_overtaker_far_astern_is_left_alone():
    assert heading(FAR_GOAL, [-12.0, 0.5], [1.6, 0.0]) == pytest.approx(0.0, abs=1e-9)  # TCPA 20, 12 L


# --- Rule 8, near goal, roles --------------------------------------------------------------------------------

@pytest.mark.parametrize("rng", [14.0, 10.0])
def test_head_on_give_way_alteration_is_to_starboard_and_readily_apparent(rng):
    h = heading(FAR_GOAL, [rng, 0.0], [-1.0, 0.0])
    assert h >= math.degrees(CV.dpsi_min) - 1e-9
    assert h >= heading(FAR_GOAL, [rng, 0.0], [-1.0, 0.0], method="modified") - 1e-9


def test_give_way_alteration_is_substantial_rule_16():
    # environment 5, run 51 (seed 0), ship 7 at t = 46: she gives way to a ship 13.7 L nearly abeam to
    # starboard; Rule 8's 30° minimum from her heading at the onset (1°) passes 1.0 L from her, the field asks for
    # no more, and the stand-on ship's close-quarters filter then has to act at 8 L. The alteration is the
    # smallest in FLOOR_STEP steps whose straight line passes at d_risk or more
    pos, vel, speed, base = np.array([-1.0, 13.7]), np.array([0.8, -0.6]), 0.76, math.radians(1.0)

    def passing(deg):
        own = speed * np.array([math.cos(math.radians(deg)), math.sin(math.radians(deg))])
        rel = vel - own
        return float(np.linalg.norm(pos + rel * max(0.0, -(pos @ rel) / (rel @ rel))))

    ps = math.radians(15.0)
    v = colregs_vortex([0.0, 0.0], ps, [speed * math.cos(ps), speed * math.sin(ps)], [60.0, 0.0], ca.DM(pos),
                       ca.DM(vel), [1.0], code=[GIVE_WAY], course=0.0, base=base, **KW)
    h = math.degrees(float(heading_of(v)))
    minimum = math.degrees(base + CV.dpsi_min)
    assert passing(minimum) < 1.1
    assert h == pytest.approx(minimum + 4 * math.degrees(FLOOR_STEP), abs=1e-6)
    assert passing(h) >= CV.d_risk > passing(h - math.degrees(FLOOR_STEP))


def test_near_the_goal_avoidance_wins_over_the_goal():
    # goal 6 L ahead, a ship from starboard on a collision course 4 time units away
    pos, vel = collision_course(-90.0, 4.0)
    goal = [6.0, 0.0]
    h_cv = heading(goal, pos, vel)
    assert h_cv >= math.degrees(CV.dpsi_min) - 1e-9
    assert h_cv > heading(goal, pos, vel, method="modified") + 10.0


def test_static_obstacle_near_the_goal_is_passed_wider():
    goal, obstacle = [8.0, 0.0], [5.0, -0.3]
    t = terms(obstacle, [0.0, 0.0], goal=goal)
    assert int(t["ship"]) == 0 and int(t["stand_on"]) == 0 and float(t["k_vor"]) < 0
    h_cv, h_mv = heading(goal, obstacle, [0.0, 0.0]), heading(goal, obstacle, [0.0, 0.0], method="modified")
    assert h_mv > 0 and h_cv > h_mv + 10.0


@pytest.mark.parametrize("pos, vel, pushes", [
    ([2.0, 4.5], [-1.0, 0.0], False),  # reciprocal course, passing clear at 4.5 L > d_risk, 4.9 L off
    ([2.0, 3.5], [-1.0, 0.0], True),  # the same ship passing at 3.5 L: a risk of collision
    ([-1.0, 1.5], [-1.0, 0.0], True),  # opening, but within the collision distance (1.8 L)
    ([4.0, 2.5], [0.0, 0.0], True),  # a static obstacle
])
def test_the_guard_pushes_only_what_is_a_risk_or_within_the_collision_distance(pos, vel, pushes):
    t = terms(pos, vel)
    d = math.hypot(*pos)
    assert d < CV.r_guard
    assert float(t["guard"]) == pytest.approx(CV.lam_guard * (1 / d - 1 / CV.r_guard) if pushes else 0.0)


def test_a_ship_passing_clear_within_the_guard_range_does_not_turn_the_own_ship():
    # on the starboard bow, 4.9 L off, passing at 4.5 L: the goal bearing (a push would turn her to port)
    assert heading(FAR_GOAL, [2.0, 4.5], [-1.0, 0.0]) == pytest.approx(0.0, abs=1e-9)


def test_no_neighbours_means_straight_to_the_goal():
    v = colregs_vortex(goal=[3.0, 4.0], nb_pos=ca.DM(2, 0), nb_vel=ca.DM(2, 0), active=ca.DM(1, 0), **OWN, **KW)
    assert float(heading_of(v)) == pytest.approx(math.atan2(4.0, 3.0))


def test_symbolic_function_matches_numeric_call():
    x = ca.SX.sym("x", 2)
    nb = ca.SX.sym("nb", 2, 2)
    nv = ca.SX.sym("nv", 2, 2)
    f = ca.Function("cv", [x, nb, nv], [colregs_vortex(x, 0.3, [0.9, 0.2], FAR_GOAL, nb, nv, [1, 1], **KW)])
    args = (ca.DM([1.0, -2.0]), ca.DM([[9.0, -4.0], [3.0, 1.0]]), ca.DM([[-1.0, 1.5], [0.0, 0.1]]))
    np.testing.assert_allclose(np.array(f(*args)),
                               np.array(colregs_vortex(args[0], 0.3, [0.9, 0.2], FAR_GOAL, args[1], args[2],
                                                       [1, 1], **KW)), rtol=1e-12)


@pytest.mark.parametrize("field, name, value, table_value", [
    ("t_act", "cv_t_act", 0.0, 0.0), ("d_cpa_act", "cv_d_cpa_act", -1.0, -1.0),
    ("dpsi_min", "cv_dpsi_min_deg", 2.0, math.degrees(2.0)),
    ("theta_head_on", "cv_theta_head_on_deg", math.pi / 2, 90.0), ("lam_guard", "cv_lam_guard", -1.0, -1.0)])
def test_parameters_are_range_checked(field, name, value, table_value):
    # the dataclass holds rad, the parameter table (scenario files, --params, default_globals) degrees
    with pytest.raises(ParameterError, match=name):
        ColregsVortexParams(**{field: value})
    with pytest.raises(ParameterError, match=name):
        default_globals(**{name: table_value})


# --- closed loop ---------------------------------------------------------------------------------------------

def near_goal_head_on(method):
    # the paper's second failure mechanism: the own ship 10 L from its goal when a ship holding course meets it
    return scenario_from_dict({
        "settings": {"method": method, "t_max": 120.0},
        "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[20, 0]]},
                  {"name": "other", "start": [34, 0], "heading": 180, "speed": 1.0, "waypoints": [[0, 0]],
                   "method": "none"}]})


def test_near_goal_meeting_ends_without_collision():
    cv = run_scenario(near_goal_head_on("colregs-vortex")).metrics
    assert not cv["collision"] and cv["ships"][0]["status"] == "reached"
    # the same meeting defeats the paper's modified vortex
    assert run_scenario(near_goal_head_on("modified-vortex")).metrics["collision"]


@pytest.mark.parametrize("name", ["head_on", "crossing", "overtaking", "conflict", "static_obstacle",
                                  "narrow_channel"])
def test_paper_encounters_stay_collision_free(name):
    sc = with_method(load_scenario(files("mmg_casadi") / "data" / "scenarios" / f"{name}.toml"), "colregs-vortex")
    m = run_scenario(sc).metrics
    assert not m["collision"]
    assert all(s["status"] == "reached" for s in m["ships"])



@pytest.mark.parametrize("goal, nb_pos, nb_vel, dpsi_free, expected", [
    ([0.0, 50.0], [6.0, 6.0], [0.1, 0.0], math.radians(15.0), 15.0),  # nothing avoided: a moderate turn
    ([0.0, 50.0], [6.0, 6.0], [0.1, 0.0], math.pi, 90.0),  # no limit (the direct call's default)
    (FAR_GOAL, [12.0, 0.0], [-1.0, 0.0], math.radians(15.0), 53.0),  # head-on at 12 L: the give-way turn as before
])
def test_a_ship_free_of_encounters_turns_at_a_moderate_rate(goal, nb_pos, nb_vel, dpsi_free, expected):
    """Own ship at the origin heading 0 at speed 1. Goal 50 L on her starboard beam and a slow ship at (6, 6), no
    risk of collision and no encounter: the field turns her towards the goal, at most cv_dpsi_free_deg from her
    present heading. A ship head-on at 12 L: the give-way duty turns her as without the limit."""
    v = colregs_vortex([0.0, 0.0], 0.0, [1.0, 0.0], goal, ca.DM(nb_pos).reshape((2, 1)),
                       ca.DM(nb_vel).reshape((2, 1)), [1.0], **(KW | {"dpsi_free": dpsi_free}))
    assert math.degrees(float(heading_of(v))) == pytest.approx(expected, abs=0.5)


def test_the_kcs_checks_a_moderate_turn_within_ten_degrees():
    """The source of cv_dpsi_free_deg = 15°: the KCS under the closed loop's PD (its kp, kd and rudder limit) in the
    steady turn of an order that stays 15° ahead of her heading turns at about 11.4°/(L/U); ordered to check her
    swing (the order becomes her heading then) she swings on by less than 10°, the smallest alteration that is
    readily apparent; from an order 20° ahead by 10° or more, and at full rate (90° ahead) by about 18°."""
    from mmg_casadi.guidance.heading_control import pd_heading
    from mmg_casadi.vessel.mmg import build_mmg, propeller_rpm_for_speed, rk4
    from mmg_casadi.vessel.ship import load_kcs

    ship = load_kcs()
    dt = 0.05
    x, order = ca.SX.sym("x", 7), ca.SX.sym("order")
    rudder = pd_heading(x[5], order, x[2], PARAMETERS["kp"].default, PARAMETERS["kd"].default,
                        math.radians(PARAMETERS["delta_max_deg"].default))
    step = ca.Function("step", [x, order], [rk4(build_mmg(ship), x, (rudder, propeller_rpm_for_speed(1.0, ship)),
                                                    dt)])

    def swing_on(ahead_deg):
        state = np.array([1.0, 0, 0, 0, 0, 0, 0])
        for _ in range(int(15.0 / dt)):  # the steady turn
            state = np.array(step(state, state[5] + math.radians(ahead_deg))).ravel()
        rate, start, swing = state[2], state[5], 0.0
        for _ in range(int(15.0 / dt)):  # checked
            state = np.array(step(state, start)).ravel()
            swing = max(swing, state[5] - start)
        return math.degrees(rate), math.degrees(swing)

    rate, swing = swing_on(PARAMETERS["cv_dpsi_free_deg"].default)
    assert rate == pytest.approx(11.4, abs=0.3) and 5.0 < swing < 10.0
    assert swing_on(20.0)[1] > 9.9 and swing_on(90.0)[1] > 17.0


def test_under_ilos_the_ordered_heading_stays_within_the_moderate_turn():
    """No neighbour within R_safe, so ILOS steers: a colregs-vortex ship that starts 180° off her goal 30 L away is
    ordered at most cv_dpsi_free_deg from her heading (the limit is lifted only within R_safe of the goal, where she
    is already on course) and reaches the goal; the paper's modified vortex (no turn limit) orders the whole turn
    at once."""
    def alone(method):
        return scenario_from_dict({"settings": {"method": method, "t_max": 60.0}, "ships": [
            {"name": "own", "start": [0, 0], "heading": 180, "speed": 1.0, "waypoints": [[30, 0]]}]})

    def ordered(result):
        psi_d = result.trajectory.auxiliary("psi_d", 0)  # ordered during each step, from the state at its start
        return np.degrees(np.abs(np.angle(np.exp(1j * (psi_d - result.trajectory.state("psi", 0)[:psi_d.size])))))

    cv = run_scenario(alone("colregs-vortex"))
    assert cv.metrics["ships"][0]["status"] == "reached"
    assert ordered(cv).max() == pytest.approx(PARAMETERS["cv_dpsi_free_deg"].default, abs=1e-6)
    assert ordered(run_scenario(alone("modified-vortex"))).max() > 170.0


@pytest.mark.parametrize("r_safe, status", [(15.0, "reached"), (3.0, "timeout")])
def test_within_r_safe_of_a_waypoint_ilos_turns_at_full_rate(r_safe, status):
    """A waypoint 5 L on the starboard beam lies inside the moderate turning circle (radius about 5 L at
    11.4°/(L/U)): within R_safe of it the limit is lifted and the ship reaches it; with an R_safe of 3 L the limit
    still applies 5 L off and she circles the waypoint until the run ends."""
    sc = scenario_from_dict({"settings": {"method": "colregs-vortex", "t_max": 80.0, "r_safe": r_safe}, "ships": [
        {"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[0, 5]]}]})
    assert run_scenario(sc).metrics["ships"][0]["status"] == status


def mid_turn_crossing(method):
    # the own ship starts heading east (090°) for a goal due north, a port turn of 90° that ILOS steers; a ship
    # from her port side, also colregs-vortex, enters R_safe on a collision course with her new course mid-turn
    return scenario_from_dict({"settings": {"method": method, "t_max": 80.0, "colregs_profile": "iitm-lab"}, "ships": [
        {"name": "own", "start": [0, 0], "heading": 90, "speed": 1.0, "waypoints": [[60, 0]]},
        {"name": "other", "start": [10, -14], "heading": 90, "speed": 1.0, "waypoints": [[10, 40]]}]})


def test_a_stand_on_encounter_that_opens_mid_turn_finds_a_swing_she_can_check():
    """The mid-turn crossing (judged under the laboratory profile): turning at the moderate rate she checks her
    swing within the 10° of Rule 17(a)(i) and keeps every rule; the same method turning at full rate (no turn limit under ILOS) swings on past 20° to
    port at the onset of risk and breaks 17(a)(i), 17(a)(ii) and 17(c)."""
    (e,) = run_scenario(mid_turn_crossing("colregs-vortex")).metrics["pairs"][0]["encounters"]["a"]
    assert e["role"] == "stand-on" and e["compliant"]
    assert e["rules"]["17a_i"]["course_change_deg"] < 10.0
    full = methods.register(dataclasses.replace(methods.METHODS["colregs-vortex"], name="cv-full-rate",
                                                turn_limit=None))
    try:
        (e,) = run_scenario(mid_turn_crossing(full.name)).metrics["pairs"][0]["encounters"]["a"]
    finally:
        methods.unregister(full.name)
    assert e["role"] == "stand-on" and not e["compliant"]
    assert e["rules"]["17a_i"]["course_change_deg"] > 20.0
    assert not any(e["rules"][k]["verdict"] for k in ("17a_i", "17a_ii", "17c"))


@pytest.mark.parametrize("attr", ["turn_limit", "lookout"])
def test_a_turn_limit_or_lookout_must_be_one_of_the_method_inputs(attr):
    bad = dataclasses.replace(methods.METHODS["colregs-vortex"], name="cv-bad-input", **{attr: "kp"})
    with pytest.raises(InputError, match=f"method.{attr}"):
        methods.register(bad)
    assert "cv-bad-input" not in methods.METHODS


def crossing_that_holds(side, r_look):
    """A target crossing at 90° from starboard (+1) or port (−1) that holds course and speed, on a collision course:
    both ships 40 L from the meeting point, so the range begins at 56.6 L."""
    return scenario_from_dict({"settings": {"method": "colregs-vortex", "t_max": 120.0, "cv_r_look": r_look},
                               "ships": [
        {"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[80, 0]]},
        {"name": "target", "start": [40, 40 * side], "heading": 270 if side > 0 else 90, "speed": 1.0,
         "waypoints": [[40, -40 * side]], "method": "none"}]})


def first_alteration_range(result, deg=5.0):
    """Range to the target when the own heading first differs from her initial one by ``deg``."""
    psi = np.degrees(result.trajectory.state("psi", 0))
    k = int(np.argmax(np.abs(psi - psi[0]) > deg))
    assert k > 0
    return float(result.own_distance()[k])


@pytest.mark.parametrize("r_look", [3.0, 7.0])
def test_the_lookout_gives_way_beyond_r_safe_to_a_ship_crossing_from_starboard(r_look):
    """Rules 7(b) and 16: with cv_r_look the own ship begins her give-way alteration once the target is within
    R_safe + cv_r_look, not at R_safe (15 L), and passes her wider, at least cv_d_risk off."""
    base = run_scenario(crossing_that_holds(+1, 0.0))
    look = run_scenario(crossing_that_holds(+1, r_look))
    r_safe = PARAMETERS["r_safe"].default
    assert first_alteration_range(base) <= r_safe
    assert r_safe < first_alteration_range(look) <= r_safe + r_look
    assert look.metrics["ships"][0]["status"] == "reached"
    assert look.own_distance().min() > max(base.own_distance().min(), PARAMETERS["cv_d_risk"].default)
    psi = np.degrees(look.trajectory.state("psi", 0))
    assert psi[np.argmax(np.abs(psi) > 5.0)] > 0.0  # the alteration is to starboard (from x towards y)


def test_the_lookout_leaves_a_stand_on_encounter_to_r_safe():
    """A target crossing from port, which the own ship stands on for, is not seen earlier with a lookout: the
    run is the same to the bit."""
    base = run_scenario(crossing_that_holds(-1, 0.0)).trajectory
    look = run_scenario(crossing_that_holds(-1, 7.0)).trajectory
    np.testing.assert_array_equal(look.state("psi", 0), base.state("psi", 0))
    np.testing.assert_array_equal(look.state("x", 0), base.state("x", 0))


@pytest.mark.parametrize("drift, holding", [(0.02, 0.0), (0.2, 1.0)])
def test_a_ship_alongside_that_hardly_closes_is_past(drift, holding):
    """A ship 10 L abeam to port on a parallel course, closing at ``drift`` (U): at 0.02 U (below cv_v_ship_min)
    her CPA lies 500 L/U ahead and never comes, so she is past and no longer held for (without this two ships
    stood on for each other alongside for ever: Imazu case 10, all ships avoiding); at 0.2 U she is still a risk
    and the stand-on ship keeps her course."""
    from mmg_casadi.guidance.colregs_encounters import STAND_ON

    t = colregs_vortex_terms([0.0, 0.0], 0.0, [1.0, 0.0], FAR_GOAL, ca.DM([[0.0], [-10.0]]),
                             ca.DM([[1.0], [drift]]), code=[STAND_ON],
                             **({k: v for k, v in MV_KW.items() if k != "lam_sink"} | CV.as_dict()))
    assert float(t["holding"]) == holding and float(t["risk"]) == holding
