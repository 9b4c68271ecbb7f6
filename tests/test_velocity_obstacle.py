"""Tests of the constant-speed linear velocity obstacle baseline (mmg_casadi.guidance.velocity_obstacle)."""

from __future__ import annotations

import math
from dataclasses import asdict

import casadi as ca
import numpy as np
import pytest

from mmg_casadi.errors import ParameterError
from mmg_casadi.guidance.velocity_obstacle import VelocityObstacleParams, velocity_obstacle, velocity_obstacle_terms

VO = asdict(VelocityObstacleParams())
N = VO["n_candidates"]


def wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def cpa(los: np.ndarray, w: np.ndarray) -> float:
    """Closest distance of the straight relative motion: neighbour at ``los``, own ship moving with ``w``."""
    t = max(0.0, float(los @ w) / float(w @ w))
    return float(np.linalg.norm(los - t * w))


def test_no_neighbours_heads_for_the_goal():
    psi = float(velocity_obstacle([0, 0], 1.0, [50, 10], np.zeros((2, 0)), np.zeros((2, 0)), np.zeros((1, 0)), **VO))
    assert abs(wrap(psi - math.atan2(10, 50))) <= 2 * math.pi / N


def test_static_obstacle_dead_ahead_leaves_the_cone_closest_to_goal():
    args = ([0, 0], 1.0, [50, 0], ca.DM([[10], [0]]), ca.DM.zeros(2, 1), [1])
    psi = float(velocity_obstacle(*args, **VO))
    t = velocity_obstacle_terms(*args, **VO)
    half = float(t["half_angle"])
    assert VO["cone"] == "huang"  # Huang et al.'s exact cone is the default
    assert half == pytest.approx(math.asin(2 / 10))
    assert abs(psi) >= half
    feasible = np.array(t["feasible"]).ravel().astype(bool)
    headings = np.array(t["headings"]).ravel()
    best = np.min(np.abs(headings[feasible]))
    assert abs(psi) == pytest.approx(best)
    assert psi > 0  # symmetric tie goes to starboard


def test_current_heading_breaks_ties():
    args = ([0, 0], 1.0, [50, 0], ca.DM([[10], [0]]), ca.DM.zeros(2, 1), [1])
    port = float(velocity_obstacle(*args, **VO, current_heading=-0.3))
    starboard = float(velocity_obstacle(*args, **VO, current_heading=0.3))
    assert port == pytest.approx(-starboard)
    assert port < 0 < starboard


@pytest.mark.parametrize("cone", ["huang", "wide"])
def test_head_on_neighbour_is_avoided(cone):
    nb, nb_vel = np.array([10.0, 0.0]), np.array([-1.0, 0.0])
    kw = {**VO, "cone": cone}
    psi = float(velocity_obstacle([0, 0], 1.0, [50, 0], nb.reshape(2, 1), nb_vel.reshape(2, 1), [1], **kw))
    w = np.array([math.cos(psi), math.sin(psi)]) - nb_vel
    assert cpa(nb, w) >= VO["collision_distance"] - 1e-9
    assert psi > 0


def test_inactive_neighbours_impose_nothing():
    nb = np.array([[10.0, 5.0], [0.0, 1.0]])
    args = ([0, 0], 1.0, [50, 0], nb, np.zeros((2, 2)), [0, 0])
    assert float(velocity_obstacle(*args, **VO)) == pytest.approx(0.0, abs=1e-12)
    assert np.all(np.array(velocity_obstacle_terms(*args, **VO)["forbidden"]) == 0)


def test_surrounded_ship_falls_back_to_least_penetration():
    angles = np.arange(8) * math.pi / 4 + 0.1
    nb = 2.5 * np.vstack([np.cos(angles), np.sin(angles)])
    args = ([0, 0], 1.0, [50, 0], nb, np.zeros((2, 8)), np.ones((1, 8)))
    t = velocity_obstacle_terms(*args, **VO)
    assert not np.any(np.array(t["feasible"]))
    psi = float(velocity_obstacle(*args, **VO))
    assert math.isfinite(psi)
    pen = np.array(t["penetration"]).ravel()
    headings = np.array(t["headings"]).ravel()
    j = int(np.argmin(np.abs(headings - psi)))
    assert pen[j] == pytest.approx(pen.min(), abs=1e-9)


def test_wide_cone_forbids_a_superset_of_huang():
    rng = np.random.default_rng(3)
    nb = rng.uniform(-12, 12, size=(2, 6))
    nb_vel = rng.uniform(-1, 1, size=(2, 6))
    args = ([0.5, -0.5], 0.9, [40, 20], nb, nb_vel, np.ones((1, 6)))
    huang = np.array(velocity_obstacle_terms(*args, **{**VO, "cone": "huang"})["forbidden"])
    wide = np.array(velocity_obstacle_terms(*args, **{**VO, "cone": "wide"})["forbidden"])
    assert huang.shape == wide.shape == (6, N)
    assert np.all(wide >= huang)
    assert wide.sum() > huang.sum()


def test_huang_cone_is_the_exact_collision_cone():
    nb, nb_vel = np.array([8.0, 3.0]), np.array([-0.4, 0.2])
    args = ([0, 0], 1.0, [50, 0], nb.reshape(2, 1), nb_vel.reshape(2, 1), [1])
    t = velocity_obstacle_terms(*args, **{**VO, "cone": "huang"})
    forb = np.array(t["forbidden"]).ravel()
    for th, f in zip(np.array(t["headings"]).ravel(), forb):
        closest = cpa(nb, np.array([math.cos(th), math.sin(th)]) - nb_vel)
        assert bool(f) == (closest < VO["collision_distance"])


@pytest.mark.parametrize("sym", [ca.SX, ca.MX])
def test_builds_a_function_with_symbols(sym):
    m = 3
    own, speed, goal = sym.sym("own", 2), sym.sym("U"), sym.sym("goal", 2)
    nb, nb_vel, active, dist = sym.sym("nb", 2, m), sym.sym("nbv", 2, m), sym.sym("a", 1, m), sym.sym("D")
    kw = {"n_candidates": 40, "cone": "wide"}
    f = ca.Function("vo", [own, speed, goal, nb, nb_vel, active, dist],
                    [velocity_obstacle(own, speed, goal, nb, nb_vel, active, collision_distance=dist, **kw)])
    num = ([1.0, 0.0], 0.8, [40.0, 5.0], np.array([[9.0, 4.0, 20.0], [1.0, -3.0, 2.0]]),
           np.array([[-0.5, 0.0, 0.1], [0.0, 0.3, 0.0]]), np.array([[1.0, 1.0, 0.0]]), 2.0)
    expected = float(velocity_obstacle(*num[:-1], collision_distance=2.0, **kw))
    assert float(f(*num)) == pytest.approx(expected, abs=1e-12)


def test_parameter_validation():
    assert VelocityObstacleParams() == VelocityObstacleParams(2.0, 80, "huang")
    for bad in (dict(collision_distance=0.0), dict(n_candidates=1), dict(n_candidates=8.0), dict(cone="narrow")):
        with pytest.raises(ParameterError):
            VelocityObstacleParams(**bad)
    with pytest.raises(ParameterError):
        velocity_obstacle([0, 0], 1.0, [1, 0], np.zeros((2, 0)), np.zeros((2, 0)), np.zeros((1, 0)),
                          collision_distance=2.0, n_candidates=80, cone="cone")


# ---------------------------------------------------------------------------------------------------------------
# Equivalence with the direct (trigonometric) implementation that the module keeps for its fallback
# ---------------------------------------------------------------------------------------------------------------

from mmg_casadi.guidance.velocity_obstacle import (  # noqa: E402
    _velocity_obstacle_reference as _reference_velocity_obstacle,
)


def _vo_functions(impl, m, cone, with_heading):
    own, speed, goal = ca.SX.sym("own", 2), ca.SX.sym("U"), ca.SX.sym("goal", 2)
    nb, nbv, act, dist, h = (ca.SX.sym("nb", 2, m), ca.SX.sym("nbv", 2, m), ca.SX.sym("a", 1, m),
                             ca.SX.sym("D"), ca.SX.sym("h"))
    out = impl(own, speed, goal, nb, nbv, act, collision_distance=dist, n_candidates=N, cone=cone,
               current_heading=h if with_heading else None)
    return ca.Function("f", [own, speed, goal, nb, nbv, act, dist, h], [out])


def _random_configs(rng, m, k, degenerate=True):
    """``k`` random configurations with ``m`` neighbours, many of them degenerate in some way (if asked)."""
    cfgs = []
    for _ in range(k):
        own = rng.uniform(-5, 5, 2)
        speed = float(rng.choice([0.0, 1.0, rng.uniform(0, 1.5), rng.uniform(0, 1.5)]))
        goal = own + rng.uniform(-60, 60, 2)
        nb = own[:, None] + rng.uniform(-15, 15, (2, m))
        nbv = rng.uniform(-1, 1, (2, m))
        act = (rng.uniform(size=(1, m)) < 0.8).astype(float)
        dist = float(rng.choice([2.0, rng.uniform(0.5, 4.0)]))
        for i in range(m):
            kind = rng.integers(0, 12) if degenerate else 99
            if kind == 0:  # exactly ahead on the goal line (goal along +x)
                goal = own + np.array([50.0, 0.0])
                nb[:, i] = own + np.array([rng.uniform(1, 15), 0.0])
            elif kind == 1:  # still
                nbv[:, i] = 0.0
            elif kind == 2:  # same speed as the own ship
                a = rng.uniform(-math.pi, math.pi)
                nbv[:, i] = speed * np.array([math.cos(a), math.sin(a)])
            elif kind == 3:  # inside the collision distance
                nb[:, i] = own + rng.uniform(-1.5, 1.5, 2)
            elif kind == 4:  # exactly on top of the own ship
                nb[:, i] = own
            elif kind == 5:  # head-on, exactly ahead
                goal = own + np.array([50.0, 0.0])
                nb[:, i] = own + np.array([rng.uniform(3, 15), 0.0])
                nbv[:, i] = [-1.0, 0.0]
        if degenerate and m and rng.uniform() < 0.15:  # surrounded: nothing feasible, fallback
            ang = np.arange(m) * 2 * math.pi / m + rng.uniform(0, 1)
            nb = own[:, None] + rng.uniform(1.5, 3.0) * np.vstack([np.cos(ang), np.sin(ang)])
            act = np.ones((1, m))
        cfgs.append((own, speed, goal, nb, nbv, act, dist, rng.uniform(-math.pi, math.pi)))
    return cfgs


@pytest.mark.parametrize("cone", ["huang", "wide"])
@pytest.mark.parametrize("with_heading", [False, True])
def test_matches_the_direct_implementation_on_random_configurations(cone, with_heading):
    rng = np.random.default_rng(2024 + 2 * (cone == "wide") + with_heading)
    per_m = 80 if not with_heading else 20
    total = 0
    for m in range(14):
        new = _vo_functions(velocity_obstacle, m, cone, with_heading)
        ref = _vo_functions(_reference_velocity_obstacle, m, cone, with_heading)
        cfgs = _random_configs(rng, m, per_m)
        cols = [np.hstack([np.reshape(np.asarray(c[q], dtype=float), new.size_in(q), order="F") for c in cfgs])
                for q in range(8)]
        got = np.array(new.map(per_m)(*cols)).ravel()
        want = np.array(ref.map(per_m)(*cols)).ravel()
        diff = np.abs(np.arctan2(np.sin(got - want), np.cos(got - want)))
        bad = np.flatnonzero(diff > 1e-9)
        assert bad.size == 0, (m, [cfgs[b] for b in bad[:3]], got[bad[:3]], want[bad[:3]])
        total += per_m
    assert total >= (1120 if not with_heading else 280)


def test_matches_the_direct_implementation_with_numbers_and_degenerate_cases():
    cases = [
        ([0, 0], 0.0, [50, 0], np.zeros((2, 1)), np.zeros((2, 1)), [1]),  # zero speed, neighbour on top
        ([0, 0], 0.0, [50, 0], np.array([[10.0], [0.0]]), np.zeros((2, 1)), [1]),  # zero speed, dead ahead
        ([0, 0], 1.0, [50, 0], np.array([[10.0], [0.0]]), np.array([[1.0], [0.0]]), [1]),  # same velocity
        ([0, 0], 1.0, [50, 0], np.array([[1.0], [0.0]]), np.array([[-1.0], [0.0]]), [1]),  # inside, head-on
        ([0, 0], 1.0, [50, 0], np.array([[10.0, 0.0], [0.0, 0.0]]), np.zeros((2, 2)), [1, 0.5]),  # partial mask
        ([0, 0], 1.0, [50, 0], np.array([[1.0, -1.0], [0.0, 0.0]]), np.zeros((2, 2)), [1, 1]),  # fore and aft
    ]
    for cone in ("huang", "wide"):
        for args in cases:
            kw = {**VO, "cone": cone}
            got, want = float(velocity_obstacle(*args, **kw)), float(_reference_velocity_obstacle(*args, **kw))
            assert abs(wrap(got - want)) <= 1e-9, (cone, args, got, want)


@pytest.mark.parametrize("cone", ["huang", "wide"])
def test_matches_the_direct_implementation_with_many_generic_neighbours(cone):
    rng = np.random.default_rng(7 + (cone == "wide"))
    k = 400
    new = _vo_functions(velocity_obstacle, 13, cone, False)
    ref = _vo_functions(_reference_velocity_obstacle, 13, cone, False)
    cfgs = _random_configs(rng, 13, k, degenerate=False)
    cols = [np.hstack([np.reshape(np.asarray(c[q], dtype=float), new.size_in(q), order="F") for c in cfgs])
            for q in range(8)]
    got = np.array(new.map(k)(*cols)).ravel()
    want = np.array(ref.map(k)(*cols)).ravel()
    np.testing.assert_allclose(np.arctan2(np.sin(got - want), np.cos(got - want)), 0.0, atol=1e-9)
