"""Tests of the APF desired-heading vector fields (mmg_casadi.guidance.fields)."""

from __future__ import annotations

import math
from dataclasses import asdict

import casadi as ca
import numpy as np
import pytest
from scipy.optimize import brentq

from mmg_casadi.errors import ParameterError
from mmg_casadi.guidance.fields import (
    InverseSquareParams,
    ModifiedVortexParams,
    SinkVortexParams,
    WallParams,
    channel_walls,
    heading_of,
    inverse_square,
    modified_vortex,
    modified_vortex_terms,
    sink,
    sink_vortex,
    vortex,
)

MV = asdict(ModifiedVortexParams())
MV_TERMS = {k: v for k, v in MV.items() if k != "lam_sink"}
INV = asdict(InverseSquareParams())


def ev(x) -> np.ndarray:
    return np.array(ca.DM(x))


def rot(psi: float) -> np.ndarray:
    return np.array([[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]])


def col(*v) -> ca.DM:
    """Points (x0, y0, x1, y1, ...) as the columns of a 2×M DM."""
    return ca.DM(np.array(v, dtype=float).reshape(-1, 2).T)


# --- sink and vortex -------------------------------------------------------------------------------------------


def test_vortex_pushes_to_starboard_for_obstacle_dead_ahead():
    v = ev(vortex([0, 0], [25, 0], -10.0)).ravel()
    assert v[0] == pytest.approx(0.0, abs=1e-12)
    assert v[1] == pytest.approx(10 / (2 * math.pi * 25))
    assert v[1] > 0


def test_vortex_is_tangential_and_sink_radial():
    pos, centre = np.array([3.0, -4.0]), np.array([1.0, 2.0])
    d = pos - centre
    r = np.linalg.norm(d)
    vv = ev(vortex(pos, centre, 7.0)).ravel()
    vs = ev(sink(pos, centre, -7.0)).ravel()
    assert vv @ d == pytest.approx(0.0, abs=1e-12)
    assert np.linalg.norm(vv) == pytest.approx(7 / (2 * math.pi * r))
    np.testing.assert_allclose(vs, -7 / (2 * math.pi * r) * d / r)


def test_sink_and_vortex_accept_several_centres():
    centres = ca.DM([[10, 0, -5], [0, 10, 5]])
    out = ev(vortex([0, 0], centres, ca.DM([[1.0, 2.0, 3.0]])))
    assert out.shape == (2, 3)
    for j, k in enumerate([1.0, 2.0, 3.0]):
        np.testing.assert_allclose(out[:, j], ev(vortex([0, 0], centres[:, j], k)).ravel())


def test_sink_vortex_combines_the_two():
    nb = col(25, 0, 10, 30)
    v = ev(sink_vortex([0, 0], [50, 0], nb, [1, 0], **asdict(SinkVortexParams())))
    expected = ev(sink([0, 0], [50, 0], -100.0)) + ev(vortex([0, 0], [25, 0], -10.0))
    np.testing.assert_allclose(v, expected)


def test_fields_do_not_produce_nan_at_the_centre():
    for v in (sink([1, 1], [1, 1], -5.0), vortex([1, 1], [1, 1], -5.0)):
        assert np.all(np.isfinite(ev(v)))


# --- modified vortex -------------------------------------------------------------------------------------------


def test_static_obstacle_on_starboard_bow_switches_vortex_off():
    t = modified_vortex_terms([0, 0], 0.0, [1, 0], col(25, 5), col(0, 0), **MV_TERMS)
    assert float(t["v_theta"]) > 0
    assert float(t["k_vor"]) == 0.0
    v = modified_vortex([0, 0], 0.0, [1, 0], [50, 0], col(25, 5), col(0, 0), [1], **MV)
    np.testing.assert_allclose(ev(v), ev(sink([0, 0], [50, 0], MV["lam_sink"])))


def test_static_obstacle_dead_ahead_switches_vortex_on_with_factor():
    u = 1.0
    t = modified_vortex_terms([0, 0], 0.0, [u, 0], col(25, 0.5), col(0, 0), **MV_TERMS)
    gamma = math.atan2(0.5, 25)
    d = math.hypot(25, 0.5)
    v_r, v_th = -u * math.cos(gamma), u * math.sin(gamma)
    assert float(t["gamma"]) == pytest.approx(gamma)
    assert float(t["v_r"]) == pytest.approx(v_r)
    assert float(t["v_theta"]) == pytest.approx(v_th)
    assert v_th <= -2 * MV["r_tol"] * v_r / d
    f = max(1.0, 2 - d / MV["r_safe"] - v_r)
    assert float(t["f"]) == pytest.approx(f)
    assert float(t["k_vor"]) == pytest.approx(f * MV["k_vor0"])
    v = ev(modified_vortex([0, 0], 0.0, [u, 0], [50, 0], col(25, 0.5), col(0, 0), [1], **MV)).ravel()
    assert v[1] > 0  # pushed to starboard


def test_factor_f_is_at_least_one():
    t = modified_vortex_terms([0, 0], 0.0, [0.2, 0], col(20, 0), col(0, 0), **MV_TERMS)
    assert 2 - 20 / 15 + 0.2 < 1
    assert float(t["f"]) == 1.0
    assert float(t["k_vor"]) == MV["k_vor0"]


def test_overtaking_neighbour_astern_has_no_vortex():
    nb, nb_vel = col(-10, 0.3), col(1.0, 0.0)
    t = modified_vortex_terms([0, 0], 0.0, [0.5, 0], nb, nb_vel, **MV_TERMS)
    assert abs(float(t["gamma"])) > 5 * math.pi / 8
    d = float(t["d"])
    assert float(t["v_theta"]) <= -2 * MV["r_tol"] * float(t["v_r"]) / d  # only the sector rule switches it off
    assert float(t["k_vor"]) == 0.0
    wide = modified_vortex_terms([0, 0], 0.0, [0.5, 0], nb, nb_vel, **{**MV_TERMS, "gamma_max": math.pi})
    assert float(wide["k_vor"]) != 0.0


@pytest.mark.parametrize("psi", [0.0, 1.0, -2.5, 3.0])
def test_relative_velocity_is_taken_in_the_body_frame(psi):
    u, v = 0.8, 0.1
    own = np.array([3.0, -2.0])
    heading = np.array([math.cos(psi), math.sin(psi)])
    nb = own + 25 * heading
    t = modified_vortex_terms(own, psi, rot(psi) @ [u, v], nb, [0, 0], **MV_TERMS)
    assert float(t["gamma"]) == pytest.approx(0.0, abs=1e-12)
    assert float(t["v_r"]) == pytest.approx(-u)
    assert float(t["v_theta"]) == pytest.approx(-v)
    t0 = modified_vortex_terms(own, psi, rot(psi) @ [u, 0], nb, [0, 0], **MV_TERMS)
    assert float(t0["v_theta"]) == pytest.approx(0.0, abs=1e-12)
    assert float(t0["v_r"]) == pytest.approx(-u)
    assert float(t0["k_vor"]) != 0.0


def test_modified_vortex_terms_are_rotation_invariant():
    own, nb = np.array([1.0, 2.0]), np.array([[9.0, -4.0], [6.0, 3.0]])
    own_vel, nb_vel = np.array([0.9, 0.2]), np.array([[-0.5, 0.3], [0.1, 0.6]])
    base = modified_vortex_terms(own, 0.3, own_vel, nb, nb_vel, **MV_TERMS)
    a = 1.2
    R = rot(a)
    turned = modified_vortex_terms(R @ own, 0.3 + a, R @ own_vel, R @ nb, R @ nb_vel, **MV_TERMS)
    for key in ("gamma", "v_r", "v_theta", "f", "k_vor"):
        np.testing.assert_allclose(ev(turned[key]), ev(base[key]), atol=1e-12)


def test_inactive_neighbours_are_ignored():
    nb = col(25, 0.5, 10, 1)
    v = modified_vortex([0, 0], 0.0, [1, 0], [50, 0], nb, np.zeros((2, 2)), [0, 0], **MV)
    np.testing.assert_allclose(ev(v), ev(sink([0, 0], [50, 0], MV["lam_sink"])))


@pytest.mark.parametrize("nb", [(25.0, 0.5), (25.0, 5.0), (-10.0, 0.3), (8.0, -3.0)])
def test_smooth_surrogate_approaches_exact_switches(nb):
    args = ([0, 0], 0.0, [1, 0], [50, 0], col(*nb), col(-0.2, 0.0), [1])
    exact = ev(modified_vortex(*args, **MV))
    smooth = ev(modified_vortex(*args, **MV, smooth=200.0))
    coarse = ev(modified_vortex(*args, **MV, smooth=2.0))
    np.testing.assert_allclose(smooth, exact, atol=1e-2)
    assert np.linalg.norm(smooth - exact) <= np.linalg.norm(coarse - exact) + 1e-12


def test_smooth_surrogate_has_gradients_and_no_overflow():
    x = ca.SX.sym("x", 2)
    v = modified_vortex(x, 0.0, [1, 0], [50, 0], col(25, 0.5), col(0, 0), [1], **MV, smooth=1e4)
    jac = ca.Function("j", [x], [ca.jacobian(v, x)])
    assert np.all(np.isfinite(np.array(jac([0.0, 0.0]))))
    t = modified_vortex_terms([0, 0], 0.0, [1, 0], col(25, 0.5), col(0, 0), **MV_TERMS, smooth=1e6)
    assert np.isfinite(float(t["k_vor"]))


@pytest.mark.parametrize("bad", [0.0, -1.0, "fast"])
def test_smooth_must_be_positive(bad):
    with pytest.raises(ParameterError):
        modified_vortex_terms([0, 0], 0.0, [1, 0], col(25, 0), col(0, 0), **MV_TERMS, smooth=bad)


# --- inverse square --------------------------------------------------------------------------------------------


def test_inverse_square_matches_hand_computation():
    own, goal, obs, radius = np.array([0.0, 0.0]), np.array([50.0, 0.0]), np.array([10.0, 0.0]), 0.5
    k_att, k_rep, d0 = INV["k_att"], INV["k_rep"], 15.0
    rho = 10.0 - radius
    rep = 2 * k_rep * (own - obs) / (rho**2 * (rho + radius)) * (1 / rho - 1 / d0)
    expected = -k_att * (own - goal) + rep
    v = ev(inverse_square(own, goal, obs, [radius], [1], **{**INV, "d0": d0})).ravel()
    np.testing.assert_allclose(v, expected)
    assert v[0] == pytest.approx(2500 - 400000 * (1 / 9.5 - 1 / 15) / 9.5**2)


def test_inverse_square_parts_are_gradients():
    obs, radius, goal = np.array([10.0, 1.0]), 0.5, np.array([40.0, -3.0])
    k_att, k_rep, d0 = 3.0, 1000.0, 15.0
    p = np.array([3.0, 2.0])

    def phi_rep(x):
        rho = np.linalg.norm(x - obs) - radius
        return k_rep * (1 / rho - 1 / d0) ** 2 if rho <= d0 else 0.0

    h = 1e-5
    grad = np.array([(phi_rep(p + h * e) - phi_rep(p - h * e)) / (2 * h) for e in np.eye(2)])
    rep = ev(inverse_square(p, goal, obs, [radius], [1], k_att=0.0, k_rep=k_rep, d0=d0)).ravel()
    np.testing.assert_allclose(rep, -grad, rtol=1e-7)
    att = ev(inverse_square(p, goal, obs, [radius], [1], k_att=k_att, k_rep=0.0, d0=d0)).ravel()
    np.testing.assert_array_equal(att, -k_att * (p - goal))


def test_inverse_square_has_no_repulsion_beyond_d0_and_no_nan_inside():
    v_far = ev(inverse_square([0, 0], [50, 0], [20, 0], [0.5], [1], **INV))
    np.testing.assert_array_equal(v_far.ravel(), [2500.0, 0.0])
    for p in ([20.0, 0.0], [20.2, 0.1]):
        assert np.all(np.isfinite(ev(inverse_square(p, [50, 0], [20, 0], [0.5], [1], **INV))))


def test_inverse_square_stagnation_point_lies_about_five_lengths_from_the_obstacle():
    obs, goal = [-10.0, 0.0], [10.0, 0.0]
    x = ca.SX.sym("x")
    fx = ca.Function("fx", [x], [inverse_square(ca.vertcat(x, 0), goal, obs, [0.5], [1], **INV)[0]])
    x_stag = brentq(lambda s: float(fx(s)), -25.0, -11.0)
    # paper: "around [-15, 0], merely 5L from the obstacle"; the default d0 = 8 L gives 5.4 L
    assert 5.0 <= -10.0 - x_stag <= 5.6


# --- channel walls ---------------------------------------------------------------------------------------------


def test_channel_walls_push_normal_within_activation_distance():
    wall_a, wall_b = col(0, 0), col(50, 0)
    lam = WallParams().lam
    v = ev(channel_walls([10, 1], wall_a, wall_b, **asdict(WallParams()))).ravel()
    np.testing.assert_allclose(v, [0.0, lam / (2 * math.pi)], atol=1e-12)
    v_port = ev(channel_walls([10, -1], wall_a, wall_b, **asdict(WallParams()))).ravel()
    np.testing.assert_allclose(v_port, [0.0, -lam / (2 * math.pi)], atol=1e-12)
    for far in ([10, 3], [60, 1], [-0.5, 1]):
        np.testing.assert_array_equal(ev(channel_walls(far, wall_a, wall_b, **asdict(WallParams()))), 0.0)


def test_channel_walls_oblique_wall_and_channel():
    a, b = np.array([0.0, 0.0]), np.array([50.0, 50.0])
    n = np.array([1.0, -1.0]) / math.sqrt(2)
    p = np.array([20.0, 20.0]) + 1.5 * n
    v = ev(channel_walls(p, a, b, lam=4.0, d_act=2.0)).ravel()
    np.testing.assert_allclose(v, 4.0 / (2 * math.pi * 1.5) * n)
    walls_a, walls_b = np.array([[0.0, 0.0], [0.0, 10.0]]).T, np.array([[50.0, 0.0], [50.0, 10.0]]).T
    np.testing.assert_array_equal(ev(channel_walls([25, 5], walls_a, walls_b, lam=10.0, d_act=2.0)), 0.0)
    v2 = ev(channel_walls([25, 9], walls_a, walls_b, lam=10.0, d_act=2.0)).ravel()
    assert v2[1] < 0  # pushed back towards the centre of the channel


def test_channel_walls_with_no_walls_is_zero():
    v = channel_walls([1, 2], np.zeros((2, 0)), ca.DM.zeros(2, 0), lam=10.0, d_act=2.0)
    assert v.shape == (2, 1)
    np.testing.assert_array_equal(ev(v), 0.0)


# --- common ----------------------------------------------------------------------------------------------------


def test_everything_works_without_neighbours():
    empty, row = ca.DM.zeros(2, 0), ca.DM.zeros(1, 0)
    own, goal = [0.0, 0.0], [30.0, 40.0]
    s = ev(sink(own, goal, -100.0))
    np.testing.assert_allclose(ev(sink_vortex(own, goal, empty, row, lam_sink=-100.0, k_vor=-10.0)), s)
    np.testing.assert_allclose(ev(modified_vortex(own, 0.0, [1, 0], goal, empty, np.zeros((2, 0)), row, **MV)), s)
    np.testing.assert_allclose(ev(inverse_square(own, goal, empty, row, row, **INV)).ravel(), [1500.0, 2000.0])
    t = modified_vortex_terms(own, 0.0, [1, 0], empty, empty, **MV_TERMS)
    assert t["k_vor"].shape == (1, 0)


@pytest.mark.parametrize("sym", [ca.SX, ca.MX])
def test_fields_build_functions_with_symbols(sym):
    m = 3
    own, psi, vel, goal = sym.sym("own", 2), sym.sym("psi"), sym.sym("vel", 2), sym.sym("goal", 2)
    nb, nb_vel, radius, active = sym.sym("nb", 2, m), sym.sym("nbv", 2, m), sym.sym("R", 1, m), sym.sym("a", 1, m)
    k_vor0, lam, wa, wb = sym.sym("k0"), sym.sym("lam"), sym.sym("wa", 2, 2), sym.sym("wb", 2, 2)
    kw = {**MV, "k_vor0": k_vor0, "lam_sink": lam}
    outs = [
        modified_vortex(own, psi, vel, goal, nb, nb_vel, active, **kw),
        modified_vortex(own, psi, vel, goal, nb, nb_vel, active, **kw, smooth=20.0),
        sink_vortex(own, goal, nb, active, lam_sink=lam, k_vor=k_vor0),
        inverse_square(own, goal, nb, radius, active, **INV),
        channel_walls(own, wa, wb, lam=lam, d_act=2.0),
    ]
    f = ca.Function("f", [own, psi, vel, goal, nb, nb_vel, radius, active, k_vor0, lam, wa, wb], outs)
    num = dict(own=[1.0, 2.0], psi=0.4, vel=[0.9, 0.3], goal=[50.0, 10.0],
               nb=np.array([[20.0, 5.0, -3.0], [8.0, 2.0, 1.0]]), nb_vel=np.array([[-0.5, 0.0, 0.2], [0.0, 0.0, 0.1]]),
               radius=np.array([[0.5, 0.5, 1.0]]), active=np.array([[1.0, 1.0, 0.0]]), k_vor0=-10.0, lam=-100.0,
               wa=np.array([[0.0, 0.0], [0.0, 3.0]]), wb=np.array([[50.0, 0.0], [50.0, 3.0]]))
    got = f(*num.values())
    kw_num = {**MV, "k_vor0": -10.0, "lam_sink": -100.0}
    a = (num["own"], num["psi"], num["vel"], num["goal"], num["nb"], num["nb_vel"], num["active"])
    expected = [
        modified_vortex(*a, **kw_num),
        modified_vortex(*a, **kw_num, smooth=20.0),
        sink_vortex(num["own"], num["goal"], num["nb"], num["active"], lam_sink=-100.0, k_vor=-10.0),
        inverse_square(num["own"], num["goal"], num["nb"], num["radius"], num["active"], **INV),
        channel_walls(num["own"], num["wa"], num["wb"], lam=-100.0, d_act=2.0),
    ]
    for g, e in zip(got, expected):
        assert g.shape == (2, 1)
        np.testing.assert_allclose(ev(g), ev(e), rtol=1e-12, atol=1e-12)


def test_heading_of():
    assert float(heading_of([0.0, 2.0])) == pytest.approx(math.pi / 2)
    assert float(heading_of(ca.DM([-1.0, -1.0]))) == pytest.approx(-3 * math.pi / 4)


def test_parameter_defaults_and_validation():
    assert InverseSquareParams() == InverseSquareParams(50.0, 200000.0, 8.0)
    assert ModifiedVortexParams().gamma_max == pytest.approx(5 * math.pi / 8)
    assert ModifiedVortexParams().r_tol == 2.0
    bad = [
        lambda: InverseSquareParams(d0=0.0),
        lambda: InverseSquareParams(k_rep=-1.0),
        lambda: SinkVortexParams(lam_sink=5.0),
        lambda: SinkVortexParams(k_vor=float("nan")),
        lambda: ModifiedVortexParams(gamma_max=4.0),
        lambda: ModifiedVortexParams(r_safe=0.0),
        lambda: ModifiedVortexParams(r_tol=-1.0),
        lambda: ModifiedVortexParams(k_vor0=float("inf")),
        lambda: WallParams(d_act=-1.0),
        lambda: WallParams(lam="x"),
    ]
    for make in bad:
        with pytest.raises(ParameterError):
            make()
