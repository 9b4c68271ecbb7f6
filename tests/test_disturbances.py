"""Current and wind in the MMG model: drift by the current vector, wind-load signs, exact Jacobians, calm water
unchanged, Blendermann coefficients."""

import dataclasses
import math

import numpy as np
import pytest

from mmg_casadi.vessel.environment import (CONTAINER_SHIP_LOADED, NENV, Environment, Windage, blendermann_coefficients,
                                    crab_angle, ground_velocity, gust_speeds, velocity_over_ground,
                                    wind_forces)
from mmg_casadi.errors import ParameterError
from mmg_casadi.vessel.mmg import (NX, build_cvodes, build_mmg, build_rk4_step, linearise, mass_matrix,
                              propeller_rpm_for_speed)
from mmg_casadi.vessel.ship import load_kcs

KCS = load_kcs()
N_RPM = propeller_rpm_for_speed(1.0)
WIND_15MS = 15.0 / KCS.U_design  # 15 m/s (about 29 kn) in U_des units
FROM_PORT = -math.pi / 2  # for a ship heading along x (psi = 0)


def _f(fun, x, *args):
    return np.array(fun(x, *args)).ravel()


# (a) a uniform current carries the ship with it ------------------------------------------------------------


@pytest.mark.parametrize("V_c,beta_c", [(0.08, 2.0), (0.1, -math.pi / 2), (0.05, math.pi)])
def test_current_shifts_ground_track_by_current_vector(V_c, beta_c):
    # turning at zero rudder command: heading, drift and yaw rate change along the way
    x0 = [0.9, -0.03, 0.08, 1.0, -2.0, 0.3, 0.2]
    T = 20.0
    calm = np.array(build_cvodes(build_mmg(), [T], reltol=1e-12, abstol=1e-12)(x0=x0, p=[0.0, N_RPM])["xf"])
    fd = build_mmg(disturbed=True)
    env = [V_c, beta_c, 0.0, 0.0]
    dist = np.array(build_cvodes(fd, [T], reltol=1e-12, abstol=1e-12)(x0=x0, p=[0.0, N_RPM, *env])["xf"])
    shift = (dist - calm).ravel()
    assert shift[3:5] == pytest.approx([V_c * T * math.cos(beta_c), V_c * T * math.sin(beta_c)], abs=1e-8)
    # the motion through the water (u, v, r, psi, delta) does not see a uniform current
    assert np.max(np.abs(shift[[0, 1, 2, 5, 6]])) < 1e-8
    # RK4 reproduces the shift to round-off: the current enters the kinematics as a constant
    X_c = np.array(build_rk4_step().mapaccum(200)(x0, 0.0, N_RPM, 0.1))[:, -1]
    X_d = np.array(build_rk4_step(fd).mapaccum(200)(x0, 0.0, N_RPM, 0.1, env))[:, -1]
    assert (X_d - X_c)[3:5] == pytest.approx(shift[3:5], abs=1e-10)


def test_head_current_slows_ground_speed_not_water_speed():
    fd = build_mmg(disturbed=True)
    env = Environment(current_speed=0.1, current_direction=math.pi)  # flowing against a ship heading along x
    X = np.array(build_rk4_step(fd).mapaccum(400)([1.0, 0, 0, 0, 0, 0, 0], 0.0, N_RPM, 0.1, env.vector()))
    assert np.max(np.abs(X[0] - 1.0)) < 1e-3      # still at the self-propulsion speed through the water
    assert X[3, -1] == pytest.approx(0.9 * 40.0, rel=1e-3)  # 40 time units at 0.9 over the ground
    u_g, v_g = ground_velocity(X[0, -1], X[1, -1], X[5, -1], 0.1, math.pi)
    assert float(u_g) == pytest.approx(X[0, -1] - 0.1, abs=1e-12) and abs(float(v_g)) < 1e-12


# (b) a beam wind from port ---------------------------------------------------------------------------------


def test_beam_wind_on_ship_at_rest_pushes_to_starboard_and_turns_bow_towards_the_centroid_side():
    """Blendermann: at γ = 90° the centre of effort is the lateral centroid, C_N = (s_L/L_oa) C_Y. Our KCS
    windage has it aft of midships (s_L < 0), so the stern is pushed harder and the bow turns into the wind."""
    w = Windage()
    assert w.s_L < 0
    X, Y, N = (float(c) for c in wind_forces(KCS, w, 0.0, 0.0, 0.0, WIND_15MS, FROM_PORT))
    assert Y > 0                                  # to starboard, away from the wind
    assert N < 0                                  # bow to port: into the wind
    assert abs(X) < 1e-12 * abs(Y)
    assert N / Y == pytest.approx(w.s_L / KCS.L, rel=1e-12)  # centre of effort at the lateral centroid
    # a centroid forward of midships turns the bow away from the wind instead
    fwd = dataclasses.replace(w, s_L=+10.0)
    assert float(wind_forces(KCS, fwd, 0.0, 0.0, 0.0, WIND_15MS, FROM_PORT)[2]) > 0


def test_beam_wind_at_speed_drifts_to_starboard_with_bow_pushed_off():
    """Under way the apparent wind comes from forward of the beam, γ = atan(U_w/U) = 50.5° for 15 m/s, and
    Blendermann's centre of effort moves forward by 0.18(π/2 - γ) L_oa: the wind moment turns the bow away
    from the wind (to starboard) although the lateral centroid is aft."""
    w = Windage()
    gamma = math.atan2(WIND_15MS, 1.0)
    lever = w.s_L / w.L_oa - 0.18 * (gamma - math.pi / 2)
    assert lever > 0
    x0 = [1.0, 0, 0, 0, 0, 0, 0]
    env = [0.0, 0.0, WIND_15MS, FROM_PORT]
    dx = _f(build_mmg(disturbed=True), x0, 0.0, N_RPM, env) - _f(build_mmg(), x0, 0.0, N_RPM)
    XW, YW, NW = (float(c) for c in wind_forces(KCS, w, 1.0, 0.0, 0.0, WIND_15MS, FROM_PORT))
    assert NW / YW == pytest.approx(lever * w.L_oa / KCS.L, rel=1e-12)
    assert dx[:3] == pytest.approx(np.linalg.solve(mass_matrix(KCS), [XW, YW, NW]), rel=1e-9)
    assert dx[1] > 0 and dx[2] > 0               # sway to starboard, yaw to starboard
    assert dx[0] < 0                             # and a little resistance from the bow quarter
    X = np.array(build_rk4_step(build_mmg(disturbed=True)).mapaccum(20)(x0, 0.0, N_RPM, 0.1, env))
    assert X[4, -1] > 0 and X[1, -1] > 0         # ground track pushed to starboard after 2 time units


def test_wind_from_starboard_mirrors_wind_from_port():
    port = np.array([float(c) for c in wind_forces(KCS, Windage(), 0.95, 0.02, 0.4, 1.1, 0.4 - 1.2)])
    stbd = np.array([float(c) for c in wind_forces(KCS, Windage(), 0.95, -0.02, -0.4, 1.1, -0.4 + 1.2)])
    assert stbd == pytest.approx(port * np.array([1, -1, -1]), rel=1e-12)


def test_wind_load_is_increment_over_still_air():
    # no wind: nothing, whatever the motion; following wind at the ship's own speed: the still-air drag is removed
    assert [float(c) for c in wind_forces(KCS, Windage(), 0.8, -0.1, 1.0, 0.0, 2.0)] == [0.0, 0.0, 0.0]
    X, Y, N = (float(c) for c in wind_forces(KCS, Windage(), 1.0, 0.0, 0.0, 1.0, math.pi))
    still_air_drag = (1.225 / KCS.rho) * Windage().A_F / (KCS.L * KCS.d) * 0.55  # C_X(0) = -0.55, V' = 1
    assert X == pytest.approx(still_air_drag, rel=1e-12) and Y == 0.0 and N == 0.0


# (c) exact Jacobians with a current ------------------------------------------------------------------------


@pytest.mark.parametrize("state,inp,env", [
    ([0.9, 0.05, 0.02, 3.0, -1.0, 0.4, 0.1], [0.2, 110.0], [0.1, 0.7, 0.0, 0.0]),
    ([0.7, -0.04, -0.03, 0.0, 0.0, -1.0, -0.2], [-0.25, 100.0], [0.08, -2.5, 1.2, 0.3]),
    ([0.95, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 115.5], [0.0, 0.0, 1.5, -1.3]),
])
def test_disturbed_linearisation_matches_finite_differences(state, inp, env):
    A, B = linearise(state, inp, env=env)
    f = build_mmg(disturbed=True)
    x0, u0 = np.array(state, float), np.array(inp, float)

    def F(x, u):
        return _f(f, x, u[0], u[1], env)

    for j in range(NX):
        h = 1e-6 * max(1.0, abs(x0[j]))
        e = np.zeros(NX)
        e[j] = h
        fd = (F(x0 + e, u0) - F(x0 - e, u0)) / (2 * h)
        assert np.allclose(A[:, j], fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(A))), j
    for j in range(2):
        h = 1e-6 * max(1.0, abs(u0[j]))
        e = np.zeros(2)
        e[j] = h
        fd = (F(x0, u0 + e) - F(x0, u0 - e)) / (2 * h)
        assert np.allclose(B[:, j], fd, rtol=1e-6, atol=1e-6 * np.max(np.abs(B))), j


def test_current_alone_leaves_jacobians_unchanged():
    state, inp = [0.9, 0.05, 0.02, 3.0, -1.0, 0.4, 0.1], [0.2, 110.0]
    A0, B0 = linearise(state, inp)
    A, B = linearise(state, inp, env=Environment(current_speed=0.1, current_direction=1.0))
    assert np.array_equal(A, A0) and np.array_equal(B, B0)


@pytest.mark.parametrize("state,env", [
    ([0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.3, math.pi, 0.0, 0.0]),  # stopped over the ground in still air
    ([1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, math.pi]),  # sailing with the wind: no apparent wind
])
def test_jacobians_finite_at_zero_air_speed(state, env):
    A, B = linearise(state, [0.0, 115.5], env=env)
    assert np.all(np.isfinite(A)) and np.all(np.isfinite(B))


def test_linearise_rejects_wrong_env_size():
    with pytest.raises(ParameterError, match="env"):
        linearise([1.0, 0, 0, 0, 0, 0, 0], [0.0, 115.5], env=[0.1, 0.0])


# (d) calm water unchanged ----------------------------------------------------------------------------------

# build_mmg() outputs recorded at commit 79ba6c0, before the disturbance input existed (CasADi 3.8.2).
CALM_REFERENCE = [
    ([0.8102, -0.0277, -0.2436, -1.5192, 1.2151, -2.8701, 0.4496], 0.2152, 107.18,
     [0.003062795388456083, 0.0517503476423869, 1.2633638254248285, -0.7879520404813236, -0.1905857074948659,
      -0.2436, -0.2344]),
    ([1.0686, -0.1823, 0.1815, -3.152, 1.9562, -2.07, 0.2299], 0.0982, 116.14,
     [-0.08031301349606138, 0.05267448236907569, 0.5119233310178667, -0.6716200337727398, -0.8509205487206802,
      0.1815, -0.13169999999999998]),
    ([1.1628, 0.194, 0.098, -3.3641, -1.0509, -1.332, 0.5468], -0.5082, 70.43,
     [-0.13186026452300015, -0.25433345122035306, -0.8020145949849491, 0.4635358363292673, -1.0839162183667734,
      0.098, -1.055]),
    ([0.5694, 0.0244, -0.0556, -3.6127, -1.1526, 1.6165, -0.1037], 0.2759, 128.21,
     [0.12461021257160108, -0.006297956671815692, -0.21826486657491884, -0.05038913341150621, 0.5676906333858587,
      -0.0556, 0.3796]),
]


@pytest.mark.parametrize("x,dc,n,xdot", CALM_REFERENCE)
def test_calm_build_reproduces_pre_disturbance_outputs(x, dc, n, xdot):
    assert _f(build_mmg(), x, dc, n) == pytest.approx(xdot, rel=1e-14, abs=1e-15)


def test_calm_build_has_no_disturbance_input():
    f = build_mmg()
    assert f.name() == "mmg" and f.n_in() == 3 and f.name_in() == ["x", "delta_c", "n_rpm"]


def test_zero_disturbance_equals_calm_water_exactly():
    f, fd = build_mmg(), build_mmg(disturbed=True)
    rng = np.random.default_rng(7)
    for _ in range(20):
        x = rng.uniform([0.0, -0.3, -0.4, -9, -9, -4, -0.6], [1.3, 0.3, 0.4, 9, 9, 4, 0.6])
        dc, n = rng.uniform(-0.7, 0.7), rng.uniform(40.0, 130.0)
        env = [0.0, rng.uniform(-4, 4), 0.0, rng.uniform(-4, 4)]  # zero speeds, any direction
        assert np.array_equal(_f(fd, x, dc, n, env), _f(f, x, dc, n), equal_nan=True)
    x0 = [1.0, 0, 0.01, 0, 0, 0, 0.05]
    X = np.array(build_rk4_step().mapaccum(50)(x0, 0.1, N_RPM, 0.2))
    Xd = np.array(build_rk4_step(build_mmg(disturbed=True)).mapaccum(50)(x0, 0.1, N_RPM, 0.2, np.zeros(NENV)))
    assert np.array_equal(X, Xd)


# (e) Blendermann coefficients ------------------------------------------------------------------------------


def test_blendermann_reduces_to_published_container_ship_parameters():
    """Blendermann (1994) "container ship, loaded": CD_t = 0.90 (beam wind, on A_L), CD_lAF = 0.55 head and
    tail wind (on A_F), δ = 0.40. At 0°, 90° and 180° the cross-force denominator is 1 and the coefficients are
    the tabulated drag coefficients with the right signs."""
    w = Windage()
    kw = dict(A_F=w.A_F, A_L=w.A_L, s_L_over_Loa=w.s_L / w.L_oa)
    p = CONTAINER_SHIP_LOADED
    assert (p.CDt, p.CDl_AF_bow, p.CDl_AF_stern, p.delta) == (0.90, 0.55, 0.55, 0.40)
    cx, cy, cn = (float(c) for c in blendermann_coefficients(0.0, **kw))
    assert (cx, cy, cn) == (-0.55, 0.0, 0.0)
    cx, cy, cn = (float(c) for c in blendermann_coefficients(math.pi / 2, **kw))
    assert cx == pytest.approx(0.0, abs=1e-15) and cy == pytest.approx(0.90, rel=1e-15)
    assert cn == pytest.approx(0.90 * w.s_L / w.L_oa, rel=1e-12)
    cx, cy, cn = (float(c) for c in blendermann_coefficients(math.pi, **kw))
    assert cx == pytest.approx(0.55, rel=1e-15) and cy == pytest.approx(0.0, abs=1e-15)


def test_blendermann_quartering_value_and_symmetry():
    w = Windage()
    kw = dict(A_F=w.A_F, A_L=w.A_L, s_L_over_Loa=w.s_L / w.L_oa)
    # at 45°, sin²(2γ) = 1: D = 1 - δ/2 (1 - CD_l/CD_t) with CD_l = 0.55 A_F/A_L
    D = 1 - 0.2 * (1 - 0.55 * w.A_F / w.A_L / 0.90)
    cx, cy, cn = (float(c) for c in blendermann_coefficients(math.pi / 4, **kw))
    assert cx == pytest.approx(-0.55 * math.sqrt(0.5) / D, rel=1e-12)
    assert cy == pytest.approx(0.90 * math.sqrt(0.5) / D, rel=1e-12)
    assert cn == pytest.approx((w.s_L / w.L_oa + 0.18 * math.pi / 4) * cy, rel=1e-12)
    for g in np.linspace(0.05, 3.1, 12):
        a = np.array([float(c) for c in blendermann_coefficients(g, **kw)])
        b = np.array([float(c) for c in blendermann_coefficients(-g, **kw)])
        assert b == pytest.approx(a * np.array([1, -1, -1]), rel=1e-12)


# the parameter object ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("field,value", [("current_speed", -0.1), ("current_speed", 1.5), ("wind_speed", -1.0),
                                         ("wind_direction", float("nan"))])
def test_environment_rejects_out_of_range(field, value):
    with pytest.raises(ParameterError, match=field):
        Environment(**{field: value})


def test_environment_vector_and_si_conversion():
    env = Environment.from_si(current_speed=1.2347, current_direction=0.5, wind_speed=12.347, wind_direction=-1.0)
    assert env.vector() == pytest.approx([0.1, 0.5, 1.0, -1.0], rel=1e-12)
    assert Environment().calm and not env.calm


# crab angle and gusts ----------------------------------------------------------------------------------------


def test_crab_angle_is_course_minus_heading_in_a_beam_current():
    fd = build_mmg(disturbed=True)
    psi, env = 0.7, [0.1, 0.7 + math.pi / 2, 0.0, 0.0]  # current from port, across the heading
    x = [1.0, 0.0, 0.0, 0.0, 0.0, psi, 0.0]
    xd = _f(fd, x, 0.0, N_RPM, env)
    course = math.atan2(xd[4], xd[3])
    u_g, v_g = ground_velocity(1.0, 0.0, psi, env[0], env[1])
    assert float(crab_angle(u_g, v_g)) == pytest.approx(course - psi, abs=1e-12)
    assert float(crab_angle(u_g, v_g)) == pytest.approx(math.atan(0.1), abs=1e-12)
    assert [float(c) for c in velocity_over_ground(1.0, 0.0, psi, env[0], env[1])] == pytest.approx(xd[3:5],
                                                                                                 abs=1e-15)


def test_gusts_have_the_stated_mean_spread_and_correlation():
    dt, T, m, I = 0.1, 5.0, 1.2, 0.1
    g = gust_speeds(400_000, dt, m, intensity=I, time_constant=T, seed=11)
    # 400 000 samples with correlation time 50 steps: about 4000 independent samples, standard error of the
    # mean ~ 0.12/sqrt(4000) = 0.002; a 4-sigma band
    assert g.mean() == pytest.approx(m, abs=0.008)
    assert g.std() == pytest.approx(I * m, rel=0.05)
    d = g - g.mean()
    assert np.dot(d[:-50], d[50:]) / np.dot(d, d) == pytest.approx(math.exp(-50 * dt / T), abs=0.06)
    assert not np.array_equal(g[:100], gust_speeds(100, dt, m, intensity=I, time_constant=T, seed=12))


def test_gusts_reject_bad_input():
    with pytest.raises(ParameterError, match="intensity"):
        gust_speeds(10, 0.1, 1.0, intensity=0.9)
    with pytest.raises(ParameterError, match="n_steps"):
        gust_speeds(0, 0.1, 1.0)
