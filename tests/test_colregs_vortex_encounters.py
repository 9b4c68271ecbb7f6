"""colregs-vortex with a memory: roles judged at the onset of risk and kept, Rule 17 in the closed loop (a scripted
give-way ship and a target that holds course), the memory rows, and the study's held targets."""

import math
from importlib.resources import files

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.colregs.profiles import iitm_lab
from mmg_casadi.colregs.roles import classify_roles
from mmg_casadi.guidance.colregs_encounters import CODE, GIVE_WAY, HEAD_ON, MEMORY, STAND_ON, classify_role
from mmg_casadi.guidance.colregs_vortex import ColregsVortexParams
from mmg_casadi.guidance.methods import METHODS
from mmg_casadi.montecarlo.execution import layout_for, sampled_scenario
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.scenarios.scenario import scenario_from_dict

CV = ColregsVortexParams()


def crossing(method, target_waypoints, *, start=(20.0, -20.0), heading=90.0, t_max=150.0):
    """Own ship north from the origin at the design speed to (60, 0); a target (method none) from ``start`` on
    ``heading`` following ``target_waypoints``; from (20, −20) heading east it meets the own ship at (20, 0)."""
    return scenario_from_dict({
        "settings": {"method": method, "t_max": t_max},
        "ships": [{"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[60, 0]]},
                  {"name": "target", "start": list(start), "heading": heading, "speed": 1.0,
                   "waypoints": target_waypoints, "method": "none"}]})


def history(res):
    """Own heading (deg), surge speed, range to the target and the straight-line TCPA at every step."""
    tr = res.trajectory
    t = tr.t
    x0, y0, x1, y1 = (tr.state(k, i) for i in (0, 1) for k in ("x", "y"))
    rx, ry = x1 - x0, y1 - y0
    wx, wy = np.gradient(x1 - x0, t), np.gradient(y1 - y0, t)
    tcpa = -(rx * wx + ry * wy) / np.maximum(wx * wx + wy * wy, 1e-12)
    return t, np.degrees(tr.state("psi", 0)), tr.state("u", 0), np.hypot(rx, ry), tcpa, tr


# the target crosses from port, holds course until she is 14 L off (inside R_safe, on a collision course: the own
# ship is stand-on), then turns 53° to starboard and passes 12 L astern of the own ship
GIVES_WAY = [[20, -10], [12, -4], [12, 40]]


def test_stand_on_keeps_course_and_speed_while_the_give_way_ship_acts():
    res = run_scenario(crossing("colregs-vortex", GIVES_WAY))
    t, psi, u, rng, _, tr = history(res)
    assert not res.metrics["collision"] and res.metrics["ships"][0]["status"] == "reached"
    within = rng < 15.0
    assert within.any()
    assert np.max(np.abs(psi[within])) < 0.5  # 17(a)(i): course kept (measured: 0.00°)
    assert np.min(u[within]) > 0.999  # and speed
    # the encounter is remembered as stand-on from the onset until the target leaves R_safe
    codes = tr.state("cv_slot0_code", 0)
    assert np.any(codes == CODE + STAND_ON)
    assert set(np.unique(codes[codes > CODE / 2])) == {CODE + STAND_ON}
    assert codes[-1] < CODE / 2
    # the paper's modified vortex turns away from the same ship (measured: 23°)
    _, psi_mv, *_ = history(run_scenario(crossing("modified-vortex", GIVES_WAY)))
    assert np.max(np.abs(psi_mv[within[: psi_mv.size]])) > 10.0


def test_stand_on_acts_alone_to_starboard_when_the_target_holds_course():
    res = run_scenario(crossing("colregs-vortex", [[20, 40]]))
    t, psi, u, rng, tcpa, _ = history(res)
    k_cpa = int(np.argmin(rng))
    assert not res.metrics["collision"] and rng[k_cpa] > 2.0  # measured: 2.62 L
    assert res.metrics["ships"][0]["status"] == "reached"
    # course kept exactly until the close-quarters filter's range r_cq (8 L, TCPA 5.7 here): in this crossing
    # the filter, not the TCPA cue t_act (range 5.7 L), begins the action
    k_cq = int(np.flatnonzero(rng < CV.r_cq)[0])
    assert tcpa[k_cq] == pytest.approx(8.0 / math.sqrt(2.0), abs=0.2)
    assert np.max(np.abs(psi[:k_cq])) < 1e-6
    assert np.max(np.abs(psi[: k_cq + 4])) > 0.5
    # then a readily apparent alteration to starboard and none to port before the CPA (17(c))
    assert np.max(psi[: k_cpa + 1]) > 90.0  # measured: 129°
    assert np.min(psi[: k_cpa + 1]) > -1.0  # measured: 0.00°


def test_role_is_kept_after_the_other_ship_manoeuvres():
    # a ship from starboard (own give-way) that the own ship's starboard turn brings onto its port bow: the
    # remembered role stays give-way for the whole encounter
    res = run_scenario(crossing("colregs-vortex", [[20, -40]], start=(20.0, 20.0), heading=-90.0))
    t, psi, u, rng, _, tr = history(res)
    codes = tr.state("cv_slot0_code", 0)
    held = codes > CODE / 2
    assert held.any() and set(np.unique(codes[held])) == {CODE + GIVE_WAY}
    assert np.max(psi[rng < 15.0]) > math.degrees(CV.dpsi_min) - 1.0  # Rule 8 / 15: starboard, apparent
    assert np.min(rng) > 4.0 and not res.metrics["collision"]


def test_roles_match_the_scorer_except_in_doubt_of_head_on():
    d = np.radians
    beta = d([0.0, 45.0, -45.0, 0.0, 170.0, 10.0])
    alpha = d([0.0, -45.0, 45.0, 170.0, 0.0, -8.0])
    chi = d([180.0, -90.0, 90.0, 0.0, 0.0, -20.0])
    speed_other = np.array([1.0, 1.0, 1.0, 0.5, 1.2, 1.0])
    ours = np.array(classify_role(beta, alpha, 0.0, chi, np.full(6, 1.0), speed_other,
                                  theta_head_on=CV.theta_head_on, stern=d(112.5))).ravel()
    scorer = classify_roles(beta, alpha, 0.0, chi, 1.0, speed_other, iitm_lab()).tolist()
    assert scorer == ["head-on", "give-way", "stand-on", "overtaking", "overtaken", "give-way"]
    # the last: each ship within 22.5° of the other's bow, courses 20° from reciprocal: a crossing to the scorer,
    # head-on to the method (Rule 14(c))
    assert ours.tolist() == [HEAD_ON, GIVE_WAY, STAND_ON, 5, 2, HEAD_ON]


def test_method_declares_its_memory_and_commands_speed():
    m = METHODS["colregs-vortex"]
    assert m.memory == MEMORY and m.commands_speed
    assert len(MEMORY) == 11


# --- the study's held targets --------------------------------------------------------------------------------

def test_held_targets_sail_without_a_method():
    sc = sampled_scenario(2, "colregs-vortex", 3, params={"targets": "hold"})
    assert [sc.method_of(i) for i in range(len(sc.ships))] == ["colregs-vortex"] + ["none"] * (len(sc.ships) - 1)
    assert layout_for(2, "modified-vortex", {"targets": "hold"}).methods == ("modified-vortex",) + ("none",) * 3
    assert layout_for(2, "modified-vortex").methods == ("modified-vortex",) * 4


@pytest.mark.parametrize("argv", [
    ["study", "statistics", "--runs", "2", "--envs", "1", "--targets", "drift"],
    ["study", "imazu", "--set", "targets=hold"],
    ["study", "sweep", "--param", "r_safe", "--values", "10", "--targets", "hold"],
    ["simulate", str(files("mmg_casadi") / "data" / "scenarios" / "head_on.toml"), "--set", "targets=hold"]])
def test_targets_option_is_refused_where_it_does_not_apply(argv, tmp_path, capsys):
    assert main(argv + ["--out", str(tmp_path / "out")]) == 2
    assert "targets" in capsys.readouterr().err


def _speed_factor(nb_pos, nb_vel, **cv):
    """The propeller-speed factor of colregs-vortex for one ship (own at the origin heading x at speed 1, goal
    ahead), with the role judged now."""
    import casadi as ca
    from mmg_casadi.guidance.colregs_vortex import _field
    kw = dict(lam_sink=-100.0, k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=5 * math.pi / 8, n_candidates=80)
    _, factor, t = _field([0, 0], 0.0, [1, 0], [50, 0], ca.DM(nb_pos), ca.DM(nb_vel), ca.DM([[1]]), code=None,
                          course=None, base=None, **kw, **ColregsVortexParams(**cv).as_dict())
    return float(factor), int(t["escalate"])


def test_speed_actions_of_rule_8e_and_17b():
    # give-way to a ship 3 L off on the starboard bow crossing on a collision course (TCPA 3 < t_act): the
    # alteration alone still leads into close quarters, so the give-way cut applies (off by default)
    give_way = ([[3], [3]], [[0], [-1]])
    assert _speed_factor(*give_way) == (1.0, 1)
    assert _speed_factor(*give_way, speed_giveway=0.5) == (0.5, 1)
    # in extremis: a ship crossing 4 L ahead; no heading within 45° clears her at full speed, one does at dead
    # slow (she passes ahead), so the way is taken off; 5 L ahead a heading still clears her: no cut
    assert _speed_factor([[4], [2]], [[0], [-1]], speed_extremis=1.0)[0] == 0.0
    assert _speed_factor([[4], [2]], [[0], [-1]], speed_extremis=0.5)[0] == 0.5
    assert _speed_factor([[5], [2]], [[0], [-1]], speed_extremis=1.0)[0] == 1.0
    # the largest applicable cut wins
    assert _speed_factor([[4], [2]], [[0], [-1]], speed_extremis=1.0, speed_giveway=0.5)[0] == 0.0


def test_give_way_speed_cut_acts_through_the_engine():
    # a ship crossing from starboard 5.6 L off at the start: late for a give-way turn alone
    sc = crossing("colregs-vortex", [[5.0, -40.0]], start=(5.0, 2.5), heading=270.0)
    n_off = run_scenario(sc).trajectory.state("n_prop", 0)
    on = run_scenario(sc, {"cv_speed_giveway": 0.5})
    n_on = on.trajectory.state("n_prop", 0)
    assert np.ptp(n_off) == 0.0  # off by default: the service propeller speed throughout
    # measured: down to 60.5 rpm of the 115.5 service (the engine's rate limit and lag), then back to service
    assert n_on.min() < 0.6 * n_off[0] and n_on[-1] == pytest.approx(n_off[0])
    assert not on.metrics["collision"] and on.metrics["ships"][0]["status"] == "reached"


def test_in_extremis_test_is_in_the_step_only_with_a_cut():
    """A zero in-extremis cut weighs nothing, so the step leaves its test out (a smaller step); only a
    colregs-vortex layout carries it."""
    from mmg_casadi.closed_loop.problem import build_problem
    from mmg_casadi.scenarios.scenario import with_method
    from mmg_casadi.closed_loop.step import build_closed_loop_step
    sc = crossing("colregs-vortex", [[5.0, -40.0]], start=(5.0, 2.5), heading=270.0)
    off, on = build_problem(sc), build_problem(sc, {"cv_speed_extremis": 1.0})
    assert not off.layout.cv_extremis and on.layout.cv_extremis and on.layout.key() == off.layout.key() + "_cx"
    assert not build_problem(with_method(sc, "modified-vortex"), {"cv_speed_extremis": 1.0}).layout.cv_extremis
    assert build_closed_loop_step(off.layout).n_instructions() < build_closed_loop_step(on.layout).n_instructions()
