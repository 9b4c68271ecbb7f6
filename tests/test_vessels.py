"""The vessel library with a second hull: the KVLCC2 in the MMG standard form of Yasukawa & Yoshimura (2015).

References
----------
Y&Y 2015: H. Yasukawa, Y. Yoshimura, J. Mar. Sci. Technol. 20 (2015) 37-52, eqs. of Sect. 2 (motion equations at
midship, hull forces in v' = v/U and r' = rL/U, propeller wake, rudder inflow) and the KVLCC2 coefficient tables.
IMO MSC.137(76): standards for ship manoeuvrability (limits depend on L/V; L/V = 40.1 s for the KVLCC2).
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib

import numpy as np
import pytest

from mmg_casadi.errors import InputError, ParameterError
from mmg_casadi.vessel.library import VESSELS, data_path, load_vessel, vessel_table
from mmg_casadi.vessel.maneuvers import last_moment_manoeuvre, turning_circle, zigzag
from mmg_casadi.vessel.mmg import build_mmg, linearise, propeller_rpm_for_speed
from mmg_casadi.vessel.ship import required_coefficients

KV = load_vessel("kvlcc2")
KVS = KV.ship


def test_library_lists_both_hulls_and_loads_the_kvlcc2():
    assert VESSELS == ("kcs", "kvlcc2")
    assert KVS.hull_form == "yy2015" and load_vessel("kcs").ship.hull_form == "beta"
    # Y&Y 2015 principal particulars (full scale) and hull coefficients, as in the data file
    assert (KVS.L, KVS.B, KVS.d, KVS.displacement) == (320.0, 58.0, 20.8, 312600.0)
    assert (KVS.R0, KVS.Yv, KVS.Nr, KVS.Yvvv, KVS.Nvvr) == (0.022, -0.315, -0.049, -1.607, -0.294)
    assert KVS.m == pytest.approx(KVS.displacement / (0.5 * KVS.L**2 * KVS.d), abs=1e-6)
    assert KVS.Izz == pytest.approx(KVS.m * (KVS.kzz**2 + (KVS.xG / KVS.L) ** 2), abs=1e-6)
    assert KV.steering.rate_max_deg_per_s == 2.32  # SIMMAN KVLCC2 case instructions


def test_unknown_vessel_names_the_field_and_the_choices():
    with pytest.raises(InputError, match=r"^ships\[0\]\.vessel: expected one of: kcs, kvlcc2"):
        load_vessel("kvlcc9", "ships[0].vessel")


def test_a_data_file_missing_a_coefficient_is_refused(tmp_path):
    text = data_path("kvlcc2").read_text().replace("Nvrr = 0.055\n", "")
    f = tmp_path / "bad.toml"
    f.write_text(text)
    with pytest.raises(ParameterError, match="^Nvrr: expected a number"):
        load_vessel(f)
    assert "Nvrr" in required_coefficients("yy2015") and "Nb" not in required_coefficients("yy2015")


def test_a_data_file_is_loaded_by_path(tmp_path):
    f = tmp_path / "kvlcc2_copy.toml"
    f.write_text(data_path("kvlcc2").read_text())
    v = load_vessel(f)
    assert v.name == "kvlcc2_copy" and v.ship == KVS and v.steering == KV.steering


def test_vessel_table_rows():
    rows = {r["name"]: r for r in vessel_table()}
    assert rows["kvlcc2"]["U_design_kn"] == pytest.approx(15.5, abs=1e-3)  # SIMMAN approach speed
    assert rows["kcs"]["rpm_design"] == pytest.approx(115.5, abs=0.01)


def _yy_dimensional(s, u, vm, r, delta, n_rps):
    """Y&Y 2015 Sect. 2 written out in SI units, independently of the CasADi model: accelerations (u̇, v̇_m, ṙ)."""
    rho, L, d = s.rho, s.L, s.d
    U = math.hypot(u, vm)
    beta = math.atan2(-vm, u)
    vp, rp = vm / U, r * L / U
    q = 0.5 * rho * L * d * U**2
    XH = q * (-s.R0 + s.Xvv * vp**2 + s.Xvr * vp * rp + s.Xrr * rp**2 + s.Xvvvv * vp**4)
    YH = q * (s.Yv * vp + s.Yr * rp + s.Yvvv * vp**3 + s.Yvvr * vp**2 * rp + s.Yvrr * vp * rp**2 + s.Yrrr * rp**3)
    NH = q * L * (s.Nv * vp + s.Nr * rp + s.Nvvv * vp**3 + s.Nvvr * vp**2 * rp + s.Nvrr * vp * rp**2
                  + s.Nrrr * rp**3)
    beta_P = beta - s.xP * rp
    C2 = s.C2_pos if beta_P > 0 else s.C2_neg
    one_w = (1 - s.wP) * (1 + (1 - math.exp(-s.C1 * abs(beta_P))) * (C2 - 1))
    J = u * one_w / (n_rps * s.DP)
    KT = s.k0 + s.k1 * J + s.k2 * J**2
    XP = (1 - s.tP) * rho * n_rps**2 * s.DP**4 * KT
    uR = s.epsilon * one_w * u * math.sqrt(s.eta * (1 + s.kappa * (math.sqrt(1 + 8 * KT / (math.pi * J**2)) - 1))**2
                                           + 1 - s.eta)
    beta_R = beta - s.lR * rp
    vR = U * (s.gammaR_pos if beta_R > 0 else s.gammaR_neg) * beta_R
    FN = 0.5 * rho * s.AR_over_Ld * L * d * (uR**2 + vR**2) * s.f_alpha * math.sin(delta - math.atan2(vR, uR))
    XR = -(1 - s.tR) * FN * math.sin(delta)
    YR = -(1 + s.aH) * FN * math.cos(delta)
    NR = -(s.xR + s.aH * s.xH) * L * FN * math.cos(delta)
    m = s.m * 0.5 * rho * L**2 * d  # = rho * displacement, as rounded to 6 digits in the data file
    mx, my = s.mx * 0.5 * rho * L**2 * d, s.my * 0.5 * rho * L**2 * d
    Jz = s.Jzz * 0.5 * rho * L**4 * d
    Iz_mid = s.Izz * 0.5 * rho * L**4 * d  # I_zG + x_G² m
    xG = s.xG
    M = np.array([[m + mx, 0, 0], [0, m + my, xG * m], [0, xG * m, Iz_mid + Jz]])
    rhs = np.array([XH + XR + XP + (m + my) * vm * r + xG * m * r**2,
                    YH + YR - (m + mx) * u * r,
                    NH + NR - xG * m * u * r])
    return np.linalg.solve(M, rhs)


@pytest.mark.parametrize("u,v,r,delta", [(1.0, 0.0, 0.0, 0.0), (0.9, -0.08, 0.3, math.radians(35)),
                                         (0.7, 0.12, -0.45, math.radians(-20)), (0.5, -0.2, 0.5, 0.1)])
def test_model_equals_the_dimensional_standard_method(u, v, r, delta):
    """The prime-II (design speed) CasADi model is Y&Y 2015's dimensional model, state by state."""
    f = build_mmg(KVS, KV.steering)
    rpm = 105.0
    Ud, L = KVS.U_design, KVS.L
    xdot = np.array(f([u, v, r, 0, 0, 0.3, delta], delta, rpm)).ravel()
    acc = _yy_dimensional(KVS, u * Ud, v * Ud, r * Ud / L, delta, rpm / 60)
    scale = np.array([L / Ud**2, L / Ud**2, L**2 / Ud**2])
    np.testing.assert_allclose(xdot[:3], acc * scale, rtol=1e-6, atol=1e-12)


def test_self_propulsion_at_design_speed():
    n = propeller_rpm_for_speed(1.0, KVS)
    xdot = np.array(build_mmg(KVS, KV.steering)([1.0, 0, 0, 0, 0, 0, 0], 0.0, n)).ravel()
    assert abs(xdot[0]) < 1e-12 and n == pytest.approx(105.0, abs=0.1)
    assert propeller_rpm_for_speed(0.5, KVS) == pytest.approx(n / 2, rel=1e-3)  # thrust and R0 both ~ speed²


def test_jacobians_are_exact_for_the_kvlcc2():
    x0, u0 = np.array([0.9, -0.05, 0.2, 0, 0, 0.1, 0.3]), np.array([0.3, 100.0])
    A, B = linearise(x0, u0, KVS, KV.steering)
    f = build_mmg(KVS, KV.steering)
    h = 1e-6
    for j in (0, 1, 2, 6):
        e = np.zeros(7)
        e[j] = h
        fd = (np.array(f(x0 + e, *u0)) - np.array(f(x0 - e, *u0))).ravel() / (2 * h)
        np.testing.assert_allclose(A[:, j], fd, rtol=1e-5, atol=1e-7)
    assert B.shape == (7, 2)


def test_kcs_turning_circle_is_unchanged_to_the_bit():
    """The second hull form did not touch the KCS path: the 35° turn of before the change, digit for digit."""
    m = turning_circle(35).metrics
    assert m["advance"] == 3.5577707089754096
    assert m["tactical_diameter"] == 3.3657471451791006


L_OVER_V = KVS.L / KVS.U_design  # 40.1 s >= 30 s: the IMO overshoot limits are the flat upper ones


@pytest.mark.parametrize("port", [False, True])
def test_kvlcc2_turning_meets_imo(port):
    """IMO MSC.137(76) 5.3.1: advance <= 4.5 L, tactical diameter <= 5 L in the 35° turning test."""
    m = turning_circle(35, port=port, ship=KVS, steering=KV.steering).metrics
    assert m["advance"] <= 4.5 and m["tactical_diameter"] <= 5.0
    assert m["advance"] == pytest.approx(3.09, abs=0.02)  # measured, see the validation table of docs/howto
    assert (m["direction"] == "port") == port


@pytest.mark.parametrize("angle,limit1,limit2", [(10, 20.0, 40.0), (20, 25.0, None)])
def test_kvlcc2_zigzag_meets_imo(angle, limit1, limit2):
    """IMO MSC.137(76) 5.3.3 for L/V >= 30 s: 10/10 first overshoot <= 20°, second <= 40°; 20/20 first <= 25°."""
    assert L_OVER_V >= 30.0
    m = zigzag(angle, ship=KVS, steering=KV.steering).metrics
    assert 0.0 < m["overshoot_1"] <= limit1
    if limit2 is not None:
        assert m["overshoot_2"] <= limit2


def _published_references() -> list:
    raw = tomllib.loads(data_path("kvlcc2").read_text())
    return [pytest.param(k, v, id=k, marks=pytest.mark.xfail(strict=True, reason=OUTSIDE_10_PERCENT[k]))
            if k in OUTSIDE_10_PERCENT else pytest.param(k, v, id=k) for k, v in sorted(raw["reference"].items())]


OUTSIDE_10_PERCENT = {
    "zigzag_port_10": "measured 8.30 deg / 9.98 deg against 9.5 / 15.0 (-13 %, -33 %); Source K's own MMG "
                      "simulation gives 7.2 / 9.1",
    "zigzag_starboard_10": "measured 5.57 deg / 15.26 deg against 8.2 / 21.9 (-32 %, -30 %); Source K's own MMG "
                           "simulation gives 5.0 / 14.0",
    "zigzag_starboard_20": "measured 10.81 deg against 13.7 (-21 %); Source K's own MMG simulation gives 10.4",
}
"""Published free-running results the model misses by more than 10 %, with the measured values: the MMG model
with captive-test coefficients under-predicts the zig-zag overshoots of the free-running model, as the MMG
simulation published next to those tests does (docs/howto/vessels.md)."""


@pytest.mark.parametrize("name,ref", _published_references())
def test_kvlcc2_against_published_manoeuvres(name, ref):
    """Each ``[reference.NAME]`` table of the data file (a published result with its ``source``) within 10 %."""
    port = ref["direction"] == "port"
    if name.startswith("turning"):
        m = turning_circle(float(ref["rudder_deg"]), port=port, ship=KVS, steering=KV.steering).metrics
    else:
        m = zigzag(float(ref["angle_deg"]), port=port, ship=KVS, steering=KV.steering).metrics
    keys = [k for k in ("advance", "tactical_diameter", "overshoot_1", "overshoot_2") if k in ref]
    assert keys and ref["source"]
    for key in keys:
        assert m[key] == pytest.approx(ref[key], rel=0.10), (name, key, m[key], ref["source"])


def test_a_port_first_zigzag_mirrors_a_starboard_first_one_of_a_symmetric_hull():
    """The KCS's hull forces are symmetric; only its propeller's side force and wake break the symmetry, so the
    port-first overshoots are close to but not equal to the starboard-first ones; the heading goes to port first."""
    s, p = zigzag(10), zigzag(10, port=True)
    assert p.state("psi")[np.argmax(np.abs(p.state("psi")) > 0.01)] < 0 < s.state("psi")[
        np.argmax(np.abs(s.state("psi")) > 0.01)]
    for k in ("overshoot_1", "overshoot_2"):
        assert 0 < p.metrics[k] and p.metrics[k] == pytest.approx(s.metrics[k], rel=0.5)


def test_flow_straightening_switch_is_on_beta_R_for_the_standard_form():
    """Y&Y 2015 switch γ_R on the sign of β_R: with γ_R⁻ = γ_R⁺ the port and starboard turns differ only
    through the β_P-dependent wake."""
    sym = dataclasses.replace(KVS, gammaR_neg=KVS.gammaR_pos, C2_neg=KVS.C2_pos)
    s = turning_circle(35, ship=sym, steering=KV.steering).metrics["tactical_diameter"]
    p = turning_circle(35, port=True, ship=sym, steering=KV.steering).metrics["tactical_diameter"]
    assert s == pytest.approx(p, rel=0.02)


def test_kvlcc2_sails_a_closed_loop_scenario_with_its_rudder_in_its_limits():
    """The hull is a scenario vessel like the KCS: the crossing encounter with both ships KVLCC2s finishes without
    collision, and the steering gear's lag (0.1 L/U) integrates stably at the default guidance step (no rudder
    angle past the 35° saturation)."""
    from mmg_casadi.scenarios.run import run_scenario
    res = run_scenario("crossing.toml", params={"vessel": "kvlcc2"})
    delta = res.trajectory.state("delta")
    assert res.metrics["collision"] is False
    assert np.all(np.isfinite(delta)) and np.max(np.abs(delta)) <= math.radians(35.0) + 1e-9


def test_maneuver_command_sails_a_hull_and_refuses_a_bad_vessel_file_in_one_line(tmp_path, capsys):
    from mmg_casadi.cli import main
    assert main(["maneuver", "zigzag", "--angle", "20", "--vessel", "kvlcc2", "--out", str(tmp_path / "z")]) == 0
    out = capsys.readouterr().out
    assert '"vessel": "kvlcc2"' in out and '"overshoot_1": 10.8' in out
    bad = tmp_path / "bad.toml"
    bad.write_text(data_path("kvlcc2").read_text().replace("Yv = -0.315", 'Yv = "fast"'))
    assert main(["maneuver", "turning", "--vessel", str(bad), "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"mmg-casadi: error: {bad}: hull.Yv: expected a finite number, got 'fast'"]
    assert not (tmp_path / "t").exists()


@pytest.mark.parametrize("disturbed", [False, True])
def test_a_hull_in_another_hulls_units_sails_the_same_metres_and_seconds(disturbed):
    """A KVLCC2 sailed in the KCS's units (length and time) follows the trajectory it follows in its own units."""
    import casadi as ca
    from mmg_casadi.vessel.mmg import in_scene_units, rk4, scene_scales
    kcs, vl = load_vessel("kcs"), load_vessel("kvlcc2")
    f = build_mmg(vl.ship, vl.steering, disturbed=disturbed)
    g = in_scene_units(f, vl.ship, kcs.ship)
    lam, mu = scene_scales(vl.ship, kcs.ship)
    tau = lam / mu
    scale = ca.DM([mu, mu, 1 / tau, lam, lam, 1, 1])
    x = ca.DM([1.0, 0, 0, 0, 0, 0, 0])
    xs = scale * x
    rpm = propeller_rpm_for_speed(1.0, vl.ship)
    env = ([ca.DM([0.1, 1.0, 0.3, 2.0])], [ca.DM([0.1 * mu, 1.0, 0.3 * mu, 2.0])]) if disturbed else ([], [])
    for _ in range(400):  # 35° rudder for 20 of its own time units (800 s)
        x = rk4(f, x, (math.radians(35), rpm, *env[0]), 0.05)
        xs = rk4(g, xs, (math.radians(35), rpm, *env[1]), 0.05 * tau)
    assert abs(float(x[5])) > 1.5 * math.pi  # it turned through more than 270°
    assert np.max(np.abs(np.array(scale * x - xs))) < 1e-12
    # the same hull is its own unit: the model itself, unchanged
    assert in_scene_units(f, vl.ship, vl.ship) is f


def test_mixed_traffic_targets_take_the_hulls_in_turn_and_sail_at_their_own_speed(tmp_path, capsys):
    """`study statistics --vessels kvlcc2,kcs`: agent1 a KVLCC2, agent2 a KCS, ...; a KVLCC2 at its design
    speed sails 15.5/24 of the own KCS's speed in the scene's units; a bad list is refused in one line."""
    from mmg_casadi.cli import main
    from mmg_casadi.montecarlo.execution import layout_for
    from mmg_casadi.scenarios.run import run_scenario
    from mmg_casadi.scenarios.scenario import scenario_from_dict
    lay = layout_for(2, "modified-vortex", {"target_vessels": "kvlcc2,kcs"})
    assert lay.vessels == ("kcs", "kvlcc2", "kcs", "kvlcc2") and lay.unit_vessel() == "kcs"
    sc = scenario_from_dict({"settings": {"method": "none", "t_max": 20.0}, "ships": [
        {"name": "own", "start": [0, 0], "heading": 0, "speed": 1.0, "waypoints": [[60, 0]]},
        {"name": "tanker", "start": [0, 20], "heading": 0, "speed": 1.0, "waypoints": [[60, 20]],
         "vessel": "kvlcc2"}]})
    tr = run_scenario(sc).trajectory
    mu = load_vessel("kvlcc2").ship.U_design / load_vessel("kcs").ship.U_design
    assert tr.state("u", 1)[-1] == pytest.approx(mu, rel=1e-3)  # steady at its design rpm
    assert tr.state("u", 0)[-1] == pytest.approx(1.0, rel=1e-3)
    out = tmp_path / "mixed"
    assert main(["study", "statistics", "--runs", "2", "--envs", "1", "--methods", "modified-vortex",
                 "--vessels", "kvlcc2,kcs", "--workers", "1", "--out", str(out)]) == 0
    assert json.loads((out / "study.json").read_text())["params"]["target_vessels"] == "kvlcc2,kcs"
    capsys.readouterr()
    assert main(["study", "statistics", "--runs", "2", "--envs", "1", "--vessels", "kcs,tug",
                 "--out", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "error: --vessels: expected one of: own, kcs, kvlcc2, kcs,kvlcc2" in err[0]
    assert not (tmp_path / "bad").exists()


# a ship crossing from 45° on the port bow at the own speed; both reach (40, 0) at t = 40 without manoeuvres
CROSSER = ((40 - 40 * 0.5 ** 0.5, -40 * 0.5 ** 0.5), (0.5 ** 0.5, 0.5 ** 0.5))


def test_last_moment_manoeuvre_keeps_course_and_speed_until_the_turn_then_turns_hard_over():
    stbd = last_moment_manoeuvre(*CROSSER, 30.0)
    port = last_moment_manoeuvre(*CROSSER, 30.0, port=True)
    before = stbd.t < 30.0 - 1e-9
    assert np.all(stbd.delta_c[before] == 0.0) and np.allclose(stbd.delta_c[~before], math.radians(35.0))
    assert np.allclose(port.delta_c[~before], -math.radians(35.0))
    assert np.allclose(stbd.state("psi")[before], 0.0) and np.allclose(stbd.state("y")[before], 0.0)
    k = int(np.searchsorted(stbd.t, 30.0))
    assert stbd.state("x")[k] == pytest.approx(30.0, abs=0.05)  # the approach speed kept
    assert stbd.state("psi")[-1] > math.radians(90) and port.state("psi")[-1] < -math.radians(90)
    # the closest approach is the minimum of the distance to the target's straight track
    target = np.array(CROSSER[0]) + stbd.t[:, None] * np.array(CROSSER[1])
    d = np.hypot(stbd.state("x") - target[:, 0], stbd.state("y") - target[:, 1])
    assert stbd.metrics["min_distance"] == pytest.approx(d.min()) and stbd.metrics["t_min"] == stbd.t[d.argmin()]


def test_last_moment_manoeuvre_passes_closer_the_later_the_turn():
    passing = [last_moment_manoeuvre(*CROSSER, t).metrics["min_distance"] for t in (28.0, 32.0, 35.0, 38.0, 40.0)]
    assert all(a > b for a, b in zip(passing, passing[1:]))
    assert passing[0] > 4.0 and passing[-1] < 1.0  # at the meeting time the turn comes too late


@pytest.mark.parametrize("kw, field", [(dict(rudder_deg=40.0), "rudder"), (dict(speed=0.1), "speed"),
                                       (dict(t_end=20.0), "t_end")])
def test_last_moment_manoeuvre_refuses_bad_input(kw, field):
    with pytest.raises(ParameterError, match=field):
        last_moment_manoeuvre(*CROSSER, 30.0, **kw)
    with pytest.raises(ParameterError, match="t_turn"):
        last_moment_manoeuvre(*CROSSER, -1.0)
