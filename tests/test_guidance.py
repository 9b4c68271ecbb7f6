"""ILOS guidance and waypoint switching (mmg_casadi.guidance.ilos)."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mmg_casadi.guidance.heading_control import pd_heading
from mmg_casadi.errors import ParameterError
from mmg_casadi.guidance.ilos import (
    IlosParams,
    ilos_heading,
    ilos_integrator_rate,
    ilos_step_terms,
    path_errors,
    path_tangential_angle,
    select_segment,
    switch_waypoint,
    wrap_angle,
)

SQ2 = math.sqrt(2.0)


def padded_path(points, k):
    """2×k path matrix: the given columns, then the last one repeated."""
    cols = list(points) + [points[-1]] * (k - len(points))
    return np.array(cols, dtype=float).T


# --- parameters -----------------------------------------------------------------------------------------------

def test_ilos_params_defaults_and_gains():
    p = IlosParams()
    assert (p.delta, p.k, p.r_tol) == (2.0, 0.05, 3.0)
    assert p.kp_g == pytest.approx(0.5)
    assert p.ki_g == pytest.approx(0.025)


@pytest.mark.parametrize("kwargs, field", [
    ({"delta": 0.0}, "ilos_delta"), ({"delta": -1.0}, "ilos_delta"), ({"k": -0.01}, "ilos_k"),
    ({"r_tol": 0.0}, "goal_tolerance"), ({"delta": float("nan")}, "ilos_delta"),
])
def test_ilos_params_validation(kwargs, field):
    with pytest.raises(ParameterError) as err:
        IlosParams(**kwargs)
    assert err.value.field == field


# --- angles and path geometry ---------------------------------------------------------------------------------

@pytest.mark.parametrize("a, expected", [
    (0.0, 0.0), (math.pi, math.pi), (-math.pi, math.pi), (3 * math.pi / 2, -math.pi / 2),
    (-3 * math.pi / 2, math.pi / 2), (7.0, 7.0 - 2 * math.pi), (-7.0, -7.0 + 2 * math.pi),
])
def test_wrap_angle(a, expected):
    w = float(wrap_angle(a))
    assert w == pytest.approx(expected, abs=1e-12)
    assert -math.pi < w <= math.pi


@pytest.mark.parametrize("end, expected", [
    ((1, 0), 0.0), ((1, 1), math.pi / 4), ((0, 1), math.pi / 2), ((-1, 1), 3 * math.pi / 4),
    ((-1, 0), math.pi), ((-1, -1), -3 * math.pi / 4), ((0, -1), -math.pi / 2), ((1, -1), -math.pi / 4),
])
def test_path_tangential_angle_all_quadrants(end, expected):
    assert float(path_tangential_angle([2.0, 3.0], [2.0 + end[0], 3.0 + end[1]])) == pytest.approx(expected)


def test_path_errors_sign_along_x():
    x_e, y_e = path_errors([3.0, 1.0], [0.0, 0.0], [10.0, 0.0])
    assert float(x_e) == pytest.approx(3.0)
    assert float(y_e) == pytest.approx(1.0)  # starboard of the path → positive
    _, y_e = path_errors([3.0, -1.0], [0.0, 0.0], [10.0, 0.0])
    assert float(y_e) == pytest.approx(-1.0)


def test_path_errors_diagonal_hand_computed():
    x_e, y_e = path_errors([5.0, 3.0], [0.0, 0.0], [10.0, 10.0])
    assert float(y_e) == pytest.approx((3.0 - 5.0) / SQ2)  # = -√2
    assert float(x_e) == pytest.approx(8.0 / SQ2)  # = 4√2
    # the same ship with the path reversed, (10,10)->(0,0): r = (-5,-7); it now lies to starboard
    x_e, y_e = path_errors([5.0, 3.0], [10.0, 10.0], [0.0, 0.0])
    assert float(x_e) == pytest.approx(12.0 / SQ2)
    assert float(y_e) == pytest.approx(SQ2)


def test_path_errors_west_path():
    x_e, y_e = path_errors([-10.0, 0.5], [0.0, 0.0], [-50.0, 0.0])
    assert float(x_e) == pytest.approx(10.0)
    assert float(y_e) == pytest.approx(-0.5)  # heading west, +y lies to port


# --- ILOS heading and integrator ------------------------------------------------------------------------------

def test_ilos_heading_points_back_to_path():
    p = IlosParams()
    assert float(ilos_heading(0.0, 0.0, 0.0, p.delta, p.k)) == 0.0
    # starboard of a +x path → steer to port by atan(y_e/Δ)
    assert float(ilos_heading(0.0, 2.0, 0.0, p.delta, p.k)) == pytest.approx(-math.pi / 4)
    # the integral term adds (k/Δ) y_int
    assert float(ilos_heading(0.0, 0.0, 20.0, p.delta, p.k)) == pytest.approx(-math.atan(0.5))


def test_ilos_heading_wraps_on_west_path():
    p = IlosParams()
    pi_p = float(path_tangential_angle([0.0, 0.0], [-50.0, 0.0]))
    assert pi_p == pytest.approx(math.pi)
    for y in (0.3, -0.3):
        _, y_e = path_errors([-10.0, y], [0.0, 0.0], [-50.0, 0.0])
        psi_d = float(ilos_heading(pi_p, y_e, 0.0, p.delta, p.k))
        assert -math.pi < psi_d <= math.pi
        assert abs(abs(psi_d) - math.pi) == pytest.approx(math.atan(0.3 / p.delta))
        # pointing back towards y = 0: heading velocity sin(psi_d) has the sign of -y
        assert math.copysign(1.0, math.sin(psi_d)) == -math.copysign(1.0, y)
    assert float(pd_heading(math.radians(-179.5), math.radians(179.5), 0.0, 3.5, 4.0, math.radians(35))) \
        == pytest.approx(-3.5 * math.radians(1.0))


def test_ilos_integrator_rate_formula():
    assert float(ilos_integrator_rate(1.0, 10.0, 2.0, 0.05)) == pytest.approx(2.0 / (4.0 + 1.5**2))
    assert float(ilos_integrator_rate(0.0, 10.0, 2.0, 0.05)) == 0.0


def _integrate_y_int(y_e_of_t, t_end, p):
    sol = solve_ivp(lambda t, z: [float(ilos_integrator_rate(y_e_of_t(t), z[0], p.delta, p.k))],
                    (0.0, t_end), [0.0], rtol=1e-10, atol=1e-12, dense_output=True)
    assert sol.success
    return sol


def test_y_int_constant_cross_track_error_grows_like_cube_root():
    """With constant y_e, s = y_e + k·y_int obeys ds/dt = kΔy_e/(Δ² + s²), so
    Δ²s + s³/3 = Δ²s₀ + s₀³/3 + kΔy_e·t exactly (s₀ = y_e): y_int grows only like t^(1/3)."""
    p, y_e, t_end = IlosParams(), 5.0, 500.0
    sol = _integrate_y_int(lambda t: y_e, t_end, p)
    d2 = p.delta**2
    for t in (50.0, 200.0, 500.0):
        rhs = d2 * y_e + y_e**3 / 3 + p.k * p.delta * y_e * t
        s = [r.real for r in np.roots([1 / 3, 0.0, d2, -rhs]) if abs(r.imag) < 1e-9][0]
        assert sol.sol(t)[0] == pytest.approx((s - y_e) / p.k, rel=1e-6)
    y_int_end = sol.sol(t_end)[0]
    assert 80.0 < y_int_end < 90.0  # (s(500) - 5)/k with s(500) ≈ 9.37
    for t in np.linspace(0.0, t_end, 51):
        y_int = sol.sol(t)[0]
        psi_d = float(ilos_heading(0.0, y_e, y_int, p.delta, p.k))
        assert -math.pi / 2 < psi_d < 0.0  # always steering back, never past perpendicular


def test_y_int_converges_when_cross_track_error_decays():
    """|ẏ_int| ≤ |y_e|/Δ, so with y_e = 5 e^(-t/τ): |y_int(t)| ≤ 5τ/Δ and |y_int(∞) - y_int(t)| ≤ 5τ e^(-t/τ)/Δ."""
    p, tau = IlosParams(), 10.0
    sol = _integrate_y_int(lambda t: 5.0 * math.exp(-t / tau), 500.0, p)
    ts = np.linspace(0.0, 500.0, 501)
    y_int = sol.sol(ts)[0]
    assert np.all(np.abs(y_int) <= 5.0 * tau / p.delta + 1e-9)
    assert np.all(np.diff(y_int) >= -1e-9)  # monotone while y_e > 0
    assert abs(y_int[-1] - y_int[400]) < 5.0 * tau * math.exp(-40.0) / p.delta + 1e-8
    assert y_int[-1] > 1.0


# --- waypoint selection and switching -------------------------------------------------------------------------

SQUARE = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0)]


def test_select_segment_numeric():
    path = padded_path(SQUARE, 5)
    prev, nxt = select_segment(path, 1.0)
    assert np.allclose(np.array(prev).ravel(), [0, 0]) and np.allclose(np.array(nxt).ravel(), [10, 0])
    prev, nxt = select_segment(path, 2.0)
    assert np.allclose(np.array(prev).ravel(), [10, 0]) and np.allclose(np.array(nxt).ravel(), [10, 10])


def test_switch_at_exactly_r_tol():
    path, n, r_tol = padded_path(SQUARE, 5), 3, 3.0
    idx, done = switch_waypoint([7.0, 0.0], path, 1.0, n, r_tol)  # distance exactly 3
    assert (float(idx), float(done)) == (2.0, 0.0)
    idx, done = switch_waypoint([6.99, 0.0], path, 1.0, n, r_tol)  # distance 3.01
    assert (float(idx), float(done)) == (1.0, 0.0)
    idx, done = switch_waypoint([10.0 - 3.0 / SQ2, 3.0 / SQ2 - 1e-9], path, 1.0, n, r_tol)
    assert float(idx) == 2.0


def test_final_waypoint_sets_reached_and_keeps_idx():
    path, n, r_tol = padded_path(SQUARE, 5), 3, 3.0
    idx, done = switch_waypoint([10.0, 7.0], path, 2.0, n, r_tol)
    assert (float(idx), float(done)) == (2.0, 1.0)
    idx, done = switch_waypoint([10.0, 6.99], path, 2.0, n, r_tol)
    assert (float(idx), float(done)) == (2.0, 0.0)


def test_switching_with_symbols_matches_numeric():
    K = 5
    pos, path, idx = ca.SX.sym("pos", 2), ca.SX.sym("path", 2, K), ca.SX.sym("idx")
    n, r_tol = ca.SX.sym("n"), ca.SX.sym("r_tol")
    idx_new, done = switch_waypoint(pos, path, idx, n, r_tol)
    f = ca.Function("sw", [pos, path, idx, n, r_tol], [idx_new, done])
    P = padded_path(SQUARE, K)
    cases = [([7.0, 0.0], 1.0, (2.0, 0.0)), ([6.99, 0.0], 1.0, (1.0, 0.0)), ([10.0, 7.0], 2.0, (2.0, 1.0)),
             ([0.0, 0.0], 2.0, (2.0, 0.0))]
    for p_xy, i, expected in cases:
        out = f(p_xy, P, i, 3, 3.0)
        assert (float(out[0]), float(out[1])) == expected


def test_ilos_step_terms_symbolic_mx_and_gradient():
    K = 4
    pos, path, idx, y_int = ca.MX.sym("pos", 2), ca.MX.sym("path", 2, K), ca.MX.sym("idx"), ca.MX.sym("y_int")
    delta, k = ca.MX.sym("delta"), ca.MX.sym("k")
    terms = ilos_step_terms(pos, path, idx, y_int, delta, k)
    f = ca.Function("ilos", [pos, path, idx, y_int, delta, k],
                    [terms["psi_d"], terms["y_e"], terms["x_e"], terms["y_int_dot"],
                     ca.jacobian(terms["psi_d"], pos)])
    P = padded_path(SQUARE, K)
    psi_d, y_e, x_e, ydot, jac = f([12.0, 5.0], P, 2.0, 0.0, 2.0, 0.05)
    # segment (10,0)->(10,10) points along +y; the ship at x=12 is to port (y_e = -2)
    assert float(y_e) == pytest.approx(-2.0) and float(x_e) == pytest.approx(5.0)
    assert float(psi_d) == pytest.approx(math.pi / 2 + math.pi / 4)
    assert float(ydot) == pytest.approx(2.0 * -2.0 / (4.0 + 4.0))
    assert np.all(np.isfinite(np.array(jac)))
    numeric = ilos_step_terms([12.0, 5.0], P, 2.0, 0.0, 2.0, 0.05)
    assert float(numeric["psi_d"]) == pytest.approx(float(psi_d))


# --- closed loop on a path heading west (across ±π) -----------------------------------------------------------

def test_ilos_pd_unicycle_west_path_does_not_circle():
    """Kinematic ship: unit speed, first-order yaw response T ṙ + r = K δ, rudder = PD(ILOS)."""
    p = IlosParams()
    kp, kd, dmax, K_nom, T_nom = 3.5, 4.0, math.radians(35), 0.5, 1.0
    path = padded_path([(0.0, 0.0), (-50.0, 0.0)], 3)
    x, y, psi, r, y_int = 0.0, 1.0, math.radians(179.0), 0.0, 0.0
    dt, psi_total, psi_prev, y_es = 0.05, 0.0, psi, []
    for _ in range(800):
        terms = ilos_step_terms([x, y], path, 1.0, y_int, p.delta, p.k)
        delta = float(pd_heading(psi, terms["psi_d"], r, kp, kd, dmax))
        y_es.append(float(terms["y_e"]))
        x += dt * math.cos(psi)
        y += dt * math.sin(psi)
        psi = float(wrap_angle(psi + dt * r))
        r += dt * (K_nom * delta - r) / T_nom
        y_int += dt * float(terms["y_int_dot"])
        psi_total += float(wrap_angle(psi - psi_prev))
        psi_prev = psi
    assert abs(psi_total) < math.radians(90.0)
    assert x < -35.0  # made progress west
    assert max(abs(v) for v in y_es) < 1.1  # no excursion beyond the initial 1 L offset
    assert abs(y_es[-1]) < 0.05  # converged onto the path
