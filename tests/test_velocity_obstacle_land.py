"""The velocity obstacle's land test (issue 24): a heading whose straight path at the present speed over
``vo_land_horizon`` comes within half the beam plus ``vo_land_margin`` of a wall or land edge is inadmissible, for
``velocity-obstacle``, ``velocity-obstacle-speed`` and colregs-vortex's stand-on action and close-quarters
filter; layouts without walls compile the very same code as before."""

import math

import casadi as ca
import numpy as np
import pytest

from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.closed_loop.step import build_closed_loop_step
from mmg_casadi.compiled import generate_source
from mmg_casadi.guidance import velocity_obstacle as vo
from mmg_casadi.guidance.colregs_vortex import ColregsVortexParams, colregs_vortex
from mmg_casadi.guidance.fields import heading_of
from mmg_casadi.scenarios.run import packaged_scenario, run_scenario
from mmg_casadi.scenarios.scenario import with_method

SHORE = [[20.0], [-50.0], [20.0], [50.0]]  # a coast across the way, along x = 20 L


def _segment_distance(p, a, b):
    e = b - a
    t = np.clip(np.dot(p - a, e) / max(np.dot(e, e), 1e-12), 0.0, 1.0)
    return float(np.linalg.norm(p - a - t * e))


def test_land_blocked_matches_a_sampled_path():
    rng = np.random.default_rng(24)
    checked = 0
    for _ in range(150):
        own, wall = rng.uniform(-5, 5, 2), rng.uniform(-12, 12, (4, 1))
        r, horizon = rng.uniform(0.1, 2.0), rng.uniform(0.5, 15.0)
        headings = rng.uniform(-math.pi, math.pi, 6)
        got = np.array(vo.land_blocked(own, 1.0, headings, wall, clearance=r, horizon=horizon)).ravel()
        a, b = wall[0:2, 0], wall[2:4, 0]
        d0 = _segment_distance(own, a, b)
        for k, h in enumerate(headings):
            u = np.array([math.cos(h), math.sin(h)])
            d = np.array([_segment_distance(own + s * u, a, b) for s in np.linspace(0, horizon, 801)])
            expected = d[1] < d0 if d0 < r else d.min() < r
            if abs(d.min() - r) > 1e-2:  # away from the sampling's resolution
                assert bool(got[k]) == bool(expected), (own, wall.ravel(), r, horizon, h)
                checked += 1
    assert checked > 800


def test_a_ship_within_the_clearance_may_still_turn_away():
    # 0.5 L off a coast along x = 20 L, clearance 1 L: heading into it is blocked, heading away is not
    got = vo.land_blocked([19.5, 0.0], 1.0, [0.0, math.pi, math.pi / 2], SHORE, clearance=1.0, horizon=10.0)
    assert np.array(got).ravel().tolist() == [1, 0, 1]


@pytest.mark.parametrize("seed", range(4))
def test_the_fast_velocity_obstacle_with_land_is_the_direct_one(seed):
    rng = np.random.default_rng(seed)
    for trial in range(40):
        m, w = int(rng.integers(0, 4)), int(rng.integers(1, 5))
        own, goal = rng.uniform(-5, 5, 2), rng.uniform(-40, 40, 2)
        nb, nbv = rng.uniform(-15, 15, (2, m)), rng.uniform(-1, 1, (2, m))
        act = (rng.uniform(size=m) < 0.8).astype(float)
        kw = dict(collision_distance=2.0, n_candidates=36, walls=rng.uniform(-20, 20, (4, w)), clearance=0.6,
                  horizon=10.0, current_heading=float(rng.uniform(-3, 3)) if trial % 2 else None)
        fast = float(vo.velocity_obstacle(own, 1.0, goal, nb, nbv, act, **kw))
        direct = float(vo._velocity_obstacle_reference(own, 1.0, goal, nb, nbv, act, **kw))
        assert math.remainder(fast - direct, 2 * math.pi) == pytest.approx(0.0, abs=1e-9)


def test_the_velocity_obstacle_steers_clear_of_land():
    kw = dict(collision_distance=2.0, n_candidates=80)
    free = float(vo.velocity_obstacle([0, 0], 1.0, [50, 0], ca.DM.zeros(2, 0), ca.DM.zeros(2, 0), [], **kw))
    assert free == pytest.approx(0.0)
    land = dict(walls=SHORE, clearance=1.0, horizon=25.0)
    psi = float(vo.velocity_obstacle([0, 0], 1.0, [50, 0], ca.DM.zeros(2, 0), ca.DM.zeros(2, 0), [], **kw, **land))
    assert int(vo.land_blocked([0, 0], 1.0, [psi], **land)) == 0
    # the goal-closest heading clear of the coast: its path ends short of x = 19 L
    assert 25.0 * math.cos(psi) < 19.0 and 25.0 * math.cos(abs(psi) - 2 * math.pi / 80) >= 19.0 - 1e-9
    # no walls (None or none at all) is the velocity obstacle without the land test
    for none in (None, np.zeros((4, 0))):
        assert float(vo.velocity_obstacle([0, 0], 1.0, [50, 0], ca.DM.zeros(2, 0), ca.DM.zeros(2, 0), [], **kw,
                                          walls=none, clearance=1.0, horizon=25.0)) == free


def test_heading_feasible_and_hold_drop_a_heading_into_land():
    nb, v = ca.DM([[-10], [30]]), ca.DM.zeros(2, 1)  # a neighbour far away, active, forbids nothing ahead
    land = dict(walls=SHORE, clearance=1.0, horizon=25.0)
    assert int(vo.heading_feasible([0, 0], 1.0, 0.0, nb, v, [1], collision_distance=2.0)) == 1
    assert int(vo.heading_feasible([0, 0], 1.0, 0.0, nb, v, [1], collision_distance=2.0, **land)) == 0
    assert float(vo.hold_heading(1.2, 0.0, [0, 0], 1.0, nb, v, [1], collision_distance=2.0, **land)) == 1.2
    assert float(vo.hold_heading(1.2, 0.0, [0, 0], 1.0, nb, v, [1], collision_distance=2.0)) == 0.0


def test_the_speed_levels_test_land_over_the_service_path():
    # the coast 8 L ahead: at the service speed (path 10 L) the goal heading is blocked, and at a quarter of it too
    # (the ship does not shed her way at once: every level tests the service level's 10 L path), so slowing down
    # does not make the goal heading admissible: she turns to a heading whose 10 L path is clear (49.5°, at 0.75 U,
    # the velocity closest to the preferred one)
    shore = [[8.0], [-50.0], [8.0], [50.0]]
    lv = vo.speed_levels(100.0, 25.0, 100.0, 4)
    psi, rpm, k = vo.velocity_obstacle_speed([0, 0], [50, 0], ca.DM([[-30], [0]]), ca.DM.zeros(2, 1), [1],
                                             levels=lv, collision_distance=2.0, n_candidates=80, speed_weight=0.0,
                                             walls=shore, clearance=1.0, horizon=10.0)
    assert int(vo.land_blocked([0, 0], 1.0, [float(psi)], shore, clearance=1.0, horizon=10.0)) == 0
    assert abs(float(psi)) > 0.5 and int(k) == 1


def test_colregs_vortex_close_quarters_filter_keeps_off_land():
    cv = ColregsVortexParams()
    kw = dict(lam_sink=-100.0, k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=5 * math.pi / 8) | cv.as_dict()
    # a buoy on the starboard bow inside r_cq turns the field to starboard; a coast 3 L to starboard along y = 3 L
    args = dict(own_pos=[0.0, 0.0], own_psi=0.0, own_vel=[1.0, 0.0], goal=[50.0, 0.0], nb_pos=ca.DM([[2.0], [-1.0]]),
                nb_vel=ca.DM.zeros(2, 1), active=[1.0])
    coast = [[-50.0], [3.0], [50.0], [3.0]]
    land = dict(walls=coast, clearance=1.0, horizon=10.0)
    free = float(heading_of(colregs_vortex(**args, **kw)))
    near = float(heading_of(colregs_vortex(**args, **kw, **land)))
    assert int(vo.land_blocked([0, 0], 1.0, [free], **land)) == 1  # without the test it heads for the coast
    assert int(vo.land_blocked([0, 0], 1.0, [near], **land)) == 0


def test_open_water_layouts_compile_the_same_code_and_walls_add_the_land_test():
    for methods in (("velocity-obstacle",) * 2, ("colregs-vortex", "velocity-obstacle-speed")):
        src = generate_source(build_closed_loop_step(Layout(methods)))
        assert "vo_land" not in src
        assert "vo_land" in generate_source(build_closed_loop_step(Layout(methods, n_walls=2)))
    assert Layout(("velocity-obstacle",)).method_inputs == ()
    assert Layout(("velocity-obstacle",), n_walls=2).method_inputs == ("vo_land_horizon", "vo_land_margin")
    # land adds the grounding margin and the look-ahead; a method that keeps Rule 9 the fairway's lane
    assert Layout(("velocity-obstacle",), n_walls=2, n_land=2).method_inputs == (
        "vo_land_horizon", "vo_land_margin", "grounding_margin", "land_lookahead", "land_clearance")
    assert Layout(("velocity-obstacle", "colregs-vortex"), n_walls=2).method_inputs[-5:] == (
        "vo_land_horizon", "vo_land_margin", "land_lookahead", "channel_width", "bank_clearance")


def test_the_velocity_obstacle_keeps_off_the_narrow_channel_walls():
    # the paper's narrow channel (10 L wide): without the land test the VO passed 1.4 L from a wall
    run = run_scenario(with_method(packaged_scenario("narrow_channel"), "velocity-obstacle"))
    assert not run.metrics["collision"]
    walls = [(np.array([-3.5355, -10.6066]), np.array([60.6066, 53.5355])),
             (np.array([-10.6066, -3.5355]), np.array([53.5355, 60.6066]))]
    for i in range(2):
        xy = np.column_stack([run.trajectory.state("x", i), run.trajectory.state("y", i)])
        assert min(_segment_distance(p, a, b) for p in xy for a, b in walls) > 3.0
