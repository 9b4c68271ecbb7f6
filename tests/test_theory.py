"""The Theory page (docs/theory.md) agrees with the code: each field it displays, written here as displayed, is the
code's CasADi expression at random points; the potential's gradient is taken by CasADi's automatic
differentiation of the potential as displayed (so the factor ½ of the attraction is checked, not assumed); the
MMG equations of motion as displayed, with the added-mass terms folded into the hull forces, give the code's
accelerations.

Each check first asserts that the page still displays the formula it transcribes (a changed page fails here).
"""

from __future__ import annotations

import math
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from mmg_casadi.guidance import fields

THEORY = (Path(__file__).resolve().parents[1] / "docs" / "theory.md").read_text(encoding="utf-8")
RNG = np.random.default_rng(46)
N_POINTS = 200


def _shown(*latex: str) -> None:
    for text in latex:
        assert text in THEORY, f"docs/theory.md no longer displays {text!r}: update this test with the page"


def _points(n=N_POINTS, scale=30.0):
    return RNG.uniform(-scale, scale, size=(n, 2))


def test_inverse_square_is_minus_the_gradient_of_the_displayed_potential():
    _shown(r"\phi_a = \tfrac{1}{2}\, k_{att}\, \lVert \boldsymbol X_n - \boldsymbol X_g \rVert_2^2",
           r"k_{rep}\left(\dfrac{1}{\rho} - \dfrac{1}{d_0}\right)^2 & \rho \le d_0",
           r"\rho(x, y) = \sqrt{(x_n - x_o)^2 + (y_n - y_o)^2} - R_{obs}")
    X = ca.SX.sym("X", 2)
    goal, obs, r_obs = ca.DM([12.0, -3.0]), ca.DM([1.0, 2.0]), 0.5
    k_att, k_rep, d0 = 50.0, 2e5, 8.0
    rho = ca.norm_2(X - obs) - r_obs  # eq. (rho_xy)
    phi = 0.5 * k_att * ca.sumsqr(X - goal) + ca.if_else(rho <= d0, k_rep * (1 / rho - 1 / d0) ** 2, 0)
    minus_grad = ca.Function("g", [X], [-ca.gradient(phi, X)])
    checked = 0
    for p in _points():
        if np.linalg.norm(p - np.array([1.0, 2.0])) - r_obs < 0.2:  # at the rim the code clips ρ (R_MIN)
            continue
        code = fields.inverse_square(p, goal, obs, [r_obs], [1], k_att=k_att, k_rep=k_rep, d0=d0)
        np.testing.assert_allclose(np.asarray(code).ravel(), np.asarray(minus_grad(p)).ravel(), rtol=1e-9,
                                   atol=1e-9)
        checked += 1
    assert checked > 150
    # the potential as the paper prints it (no ½) has twice the attraction: not the code's field
    phi_printed = k_att * ca.sumsqr(X - goal)
    p = np.array([20.0, 20.0])  # outside d0: attraction only
    assert float(ca.norm_2(ca.Function("h", [X], [-ca.gradient(phi_printed, X)])(p))) == pytest.approx(
        2 * float(ca.norm_2(fields.inverse_square(p, goal, obs, [r_obs], [1], k_att=k_att, k_rep=k_rep, d0=d0))))


def test_sink_and_vortex_are_the_gradients_of_their_potentials():
    _shown(r"\boldsymbol V_{sink} = \frac{\Lambda}{2\pi r}\,\boldsymbol e_r",
           r"\boldsymbol V_{vortex} = \frac{K}{2\pi r}\,\boldsymbol e_\theta")
    X = ca.SX.sym("X", 2)
    centre, lam, k = ca.DM([4.0, -7.0]), -100.0, -10.0
    d = X - centre
    # V = ∇(Λ/2π ln r) and V = ∇(K/2π θ), θ the polar angle about the centre (the displayed e_r, e_θ)
    sink_pot = lam / (2 * math.pi) * ca.log(ca.norm_2(d))
    vortex_pot = k / (2 * math.pi) * ca.atan2(d[1], d[0])
    g_sink = ca.Function("s", [X], [ca.gradient(sink_pot, X)])
    g_vortex = ca.Function("v", [X], [ca.gradient(vortex_pot, X)])
    for p in _points():
        if np.linalg.norm(p - np.array([4.0, -7.0])) < 0.1:
            continue
        np.testing.assert_allclose(np.asarray(fields.sink(p, centre, lam)).ravel(), np.asarray(g_sink(p)).ravel(),
                                   rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(np.asarray(fields.vortex(p, centre, k)).ravel(),
                                   np.asarray(g_vortex(p)).ravel(), rtol=1e-10, atol=1e-12)


def test_modified_vortex_terms_as_displayed():
    _shown(r"\gamma = \tan^{-1}\frac{y_o - y_n}{x_o - x_n} - \psi",
           r"\begin{bmatrix} \cos\gamma & \sin\gamma \\ -\sin\gamma & \cos\gamma \end{bmatrix} \boldsymbol V_{rel}",
           r"0 & \text{if } v_\theta > -\dfrac{2 R_{tol}}{d}\, v_r \ \text{ or } \ |\gamma| > \dfrac{5\pi}{8}",
           r"f = \max\left\{1,\ 2 - \frac{d}{R_{safe}} - v_r\right\}")
    k0, r_safe, r_tol, gamma_max = -10.0, 15.0, 2.0, 5 * math.pi / 8
    for _ in range(N_POINTS):
        own, nb = RNG.uniform(-20, 20, 2), RNG.uniform(-20, 20, 2)
        psi, psi_o = RNG.uniform(-math.pi, math.pi, 2)
        nu, nu_o = RNG.uniform([0.3, -0.2], [1.2, 0.2]), RNG.uniform([0.3, -0.2], [1.2, 0.2])
        rot = lambda a: np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])  # noqa: E731
        v_own, v_nb = rot(psi) @ nu, rot(psi_o) @ nu_o
        # the page: γ (gamma) wrapped to (−π, π]; V_rel in the own ship's body frame, then onto the line of sight
        gamma = math.remainder(math.atan2(nb[1] - own[1], nb[0] - own[0]) - psi, 2 * math.pi)
        v_rel_body = rot(psi).T @ (v_nb - v_own)
        v_r, v_t = np.array([[math.cos(gamma), math.sin(gamma)], [-math.sin(gamma), math.cos(gamma)]]) @ v_rel_body
        d = float(np.linalg.norm(nb - own))
        off = v_t > -2 * r_tol / d * v_r or abs(gamma) > gamma_max
        f = max(1.0, 2 - d / r_safe - v_r)
        k_vor = 0.0 if off else f * k0
        t = fields.modified_vortex_terms(own, psi, v_own, nb.reshape(2, 1), v_nb.reshape(2, 1), k_vor0=k0,
                                         r_safe=r_safe, r_tol=r_tol, gamma_max=gamma_max)
        assert float(t["gamma"]) == pytest.approx(gamma, abs=1e-12)
        assert (float(t["v_r"]), float(t["v_theta"])) == pytest.approx((v_r, v_t), abs=1e-12)
        assert float(t["f"]) == pytest.approx(f, abs=1e-12)
        assert float(t["k_vor"]) == pytest.approx(k_vor, abs=1e-12)


def test_channel_walls_as_displayed():
    _shown(r"\boldsymbol V_{wall} = \frac{\Lambda}{2\pi r}\,\boldsymbol n \quad (r < d_{act}")
    a, b, lam, d_act = np.array([0.0, 0.0]), np.array([40.0, 10.0]), 10.0, 2.0
    for p in RNG.uniform([-5, -6], [45, 16], size=(N_POINTS, 2)):
        t = np.dot(p - a, b - a) / np.dot(b - a, b - a)
        foot = a + t * (b - a)
        r = float(np.linalg.norm(p - foot))
        expected = lam / (2 * math.pi * r) * (p - foot) / r if (0 <= t <= 1 and 1e-3 < r < d_act) else np.zeros(2)
        code = np.asarray(fields.channel_walls(p, a.reshape(2, 1), b.reshape(2, 1), lam=lam, d_act=d_act)).ravel()
        np.testing.assert_allclose(code, expected, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("vessel", ["kcs", "kvlcc2"])
def test_mmg_equations_as_displayed_with_the_added_mass_terms_in_the_hull_forces(vessel):
    """The standard form (mmg_standard), fed with hull forces WITHOUT the added-mass Coriolis terms, the code's
    rudder and propeller forces and the rigid-body terms, gives the code's accelerations: exactly for the KVLCC2
    (Yasukawa & Yoshimura's polynomial, to which the code adds m_y v r and -m_x u r), and for the KCS's β form (hull
    coefficients X_βr - m_y, Y_r - m_x) up to the page's reading β ≈ -v', u' ≈ 1, whose remainder is computed."""
    _shown(r"(m' + m_x')\,\dot u' - (m' + m_y')\, v' r' - m' x_G' r'^2 &= X' \\",
           r"(m' + m_y')\,\dot v' + m' x_G'\,\dot r' + (m' + m_x')\, u' r' &= Y'",
           "`Xbr_minus_my` $= X_{\\beta r}' - m_y'$ and `Yr_minus_mx` $= Y_r' - m_x'$")
    from mmg_casadi.vessel.library import load_vessel
    from mmg_casadi.vessel.mmg import hull_forces, mmg_rhs, propeller_terms, rudder_forces
    vs = load_vessel(vessel)
    ship = vs.ship
    m, mx, my, xg = ship.m, ship.mx, ship.my, ship.xG_nd
    M = np.array([[m + mx, 0, 0], [0, m + my, m * xg], [0, m * xg, ship.Izz + ship.Jzz]])
    worst = 0.0
    for _ in range(40):
        u, v, r = RNG.uniform(0.6, 1.1), RNG.uniform(-0.1, 0.1), RNG.uniform(-0.3, 0.3)
        delta, n_rpm = float(RNG.uniform(-0.5, 0.5)), float(RNG.uniform(60, 120))
        acc = np.asarray(mmg_rhs(ship, vs.steering, ca.DM([u, v, r, 0.0, 0.0, 0.3, delta]), 0.0, n_rpm)).ravel()[:3]
        b = math.atan2(-v, u)
        if ship.hull_form == "yy2015":
            U = math.hypot(u, v)
            XH = -ship.R0 * U**2 + ship.Xvv * v**2 + ship.Xvr * v * r + ship.Xrr * r**2 + ship.Xvvvv * v**4 / U**2
            YH = ((ship.Yv * v + ship.Yr * r) * U
                  + (ship.Yvvv * v**3 + ship.Yvvr * v**2 * r + ship.Yvrr * v * r**2 + ship.Yrrr * r**3) / U)
            remainder = np.zeros(3)
        else:  # the β form with X_βr = Xbr_minus_my + m_y and Y_r = Yr_minus_mx + m_x restored
            XH0, YH0, _ = (float(q) for q in hull_forces(ship, u, v, r))
            XH, YH = XH0 + my * b * r, YH0 + mx * r
            remainder = np.linalg.solve(M, [my * r * (b + v), mx * r * (1 - u), 0.0])  # β + v' and 1 - u'
        NH = float(hull_forces(ship, u, v, r)[2])
        XP = float(propeller_terms(ship, u, n_rpm, v, r)[2])
        XR, YR, NR = (float(q) for q in rudder_forces(ship, u, v, r, delta, n_rpm)[:3])
        rhs = [XH + XP + XR + (m + my) * v * r + m * xg * r**2,  # (mmg_standard), solved for the accelerations
               YH + YR - (m + mx) * u * r,
               NH + NR - m * xg * u * r]
        np.testing.assert_allclose(np.linalg.solve(M, rhs) - remainder, acc, rtol=1e-9, atol=1e-12)
        worst = max(worst, float(np.max(np.abs(remainder))))
    # the KCS's reading is first order in β + v' and 1 - u': its remainder reaches 0.012 U/(L/U) at u' = 0.6
    assert worst == 0.0 if ship.hull_form == "yy2015" else worst < 0.02, worst
