"""PD heading-controller design (tuning.linear, tuning.pd.*, tuning.cli_pd)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.errors import ParameterError
from mmg_casadi.vessel.mmg import STATE_NAMES, linearise, propeller_rpm_for_speed
from tuning.linear import fit_nomoto_step, nomoto_first_order, nomoto_second_order, yaw_subsystem
from tuning.pd.design import PdSpec, analyse_gains, design_pd, place_pair
from tuning.pd.gain_map import grid_step_metrics, paper_gains_map
from tuning.pd.verification import verify_nonlinear

METRIC_KEYS = {"kp", "kd", "nomoto_K", "nomoto_T", "overshoot_linear", "overshoot_nonlinear", "zeta", "wn",
               "margins", "settling_time_linear", "settling_time_nonlinear", "paper_gains", "waypoint_square"}


@pytest.fixture(scope="module")
def design_1():
    return design_pd(1.0, PdSpec(zeta=0.8))


# ---------------------------------------------------------------- linear model and Nomoto


@pytest.mark.parametrize("speed", [1.0, 0.5])
@pytest.mark.parametrize("rudder_deg", [0.1, -0.01])
def test_linear_nomoto_matches_nonlinear_step(speed, rudder_deg):
    """The issue's requirement: linear K, T within 10 % of a first-order fit to a nonlinear rudder step.

    A starboard step is compared with the starboard-side (γ_R⁺) linearisation, a port step with the exact
    straight-running Jacobian (γ_R⁻); small rudder angles because the yaw response is strongly nonlinear at the
    design speed.
    """
    fit = fit_nomoto_step(speed, rudder_deg)
    assert fit.side == ("starboard" if rudder_deg > 0 else "port")
    assert abs(fit.K_error) < 0.10 and abs(fit.T_error) < 0.10, fit.to_dict()
    assert fit.K_own == pytest.approx(fit.K / speed) and fit.T_own == pytest.approx(fit.T * speed)


def test_nomoto_values_and_sides():
    port, star = nomoto_second_order(yaw_subsystem(1.0)), nomoto_second_order(yaw_subsystem(1.0, "starboard"))
    assert port.K == pytest.approx(35.10, abs=0.01) and port.T == pytest.approx(60.38, abs=0.01)
    assert star.K == pytest.approx(4.092, abs=0.001) and star.T == pytest.approx(6.842, abs=0.001)
    assert port.T3 == pytest.approx(star.T3)          # the zero does not involve γ_R
    first = nomoto_first_order(yaw_subsystem(0.5))
    assert first.T == pytest.approx(first.T1) and first.T2 == 0.0
    mean = yaw_subsystem(1.0, "mean")
    assert np.allclose(mean.A, (yaw_subsystem(1.0).A + yaw_subsystem(1.0, "starboard").A) / 2)


@pytest.mark.parametrize("speed", [1.0, 0.5, 0.2])
def test_surge_decouples_at_straight_running(speed):
    """Jacobian entries coupling u (and n_rpm) with v, r, delta vanish exactly at straight running, and no yaw
    row depends on x, y, psi; so (v, r, psi, delta) is an exact linear subsystem."""
    A, B = linearise([speed, 0, 0, 0, 0, 0, 0], [0.0, propeller_rpm_for_speed(speed)])
    i = {s: STATE_NAMES.index(s) for s in STATE_NAMES}
    yaw = [i["v"], i["r"], i["delta"]]
    assert np.all(A[i["u"], yaw] == 0.0) and np.all(A[yaw, i["u"]] == 0.0) and np.all(B[yaw, 1] == 0.0)
    assert np.all(A[np.ix_(yaw, [i["x"], i["y"], i["psi"]])] == 0.0)
    m = yaw_subsystem(speed)
    assert m.surge_coupling == 0.0
    assert yaw_subsystem(speed, "starboard").surge_coupling < 1e-8
    assert np.allclose(m.A, A[np.ix_([1, 2, 5, 6], [1, 2, 5, 6])])


def test_transfer_functions():
    m = yaw_subsystem(1.0, "starboard")
    g_r, g_psi = m.tf_yaw_rate(), m.tf_heading()
    n = nomoto_second_order(m)
    assert float(np.real(g_r.dcgain())) == pytest.approx(n.K, rel=1e-8)   # steering gear has unit gain
    assert np.min(np.abs(g_psi.poles())) < 1e-9                        # heading integrates r
    assert m.ss().nstates == 4


def test_bad_inputs():
    with pytest.raises(ParameterError) as e:
        yaw_subsystem(2.0)
    assert e.value.field == "speed"
    with pytest.raises(ParameterError):
        yaw_subsystem(1.0, "aft")
    with pytest.raises(ParameterError):
        PdSpec(zeta=0.0)
    with pytest.raises(ParameterError):
        PdSpec(wn=1.0, settling_time=5.0)
    with pytest.raises(ParameterError):
        PdSpec(method="lqr")
    with pytest.raises(ParameterError):
        fit_nomoto_step(1.0, 0.0)


# ---------------------------------------------------------------- design on the linear model


@pytest.mark.parametrize("speed", [1.0, 0.5])
@pytest.mark.parametrize("zeta", [0.8, 1.0])
def test_design_meets_spec_on_linear_model(speed, zeta):
    d = design_pd(speed, PdSpec(zeta=zeta))
    assert d.loop.stable
    assert abs(d.loop.dominant_zeta - zeta) <= 0.02
    assert d.loop.dominant_wn == pytest.approx(d.wn, rel=0.02)
    assert d.loop.gain_margin > 1.0 and d.loop.phase_margin > 0.0
    assert not d.saturates and d.loop.step.peak_rudder_deg == pytest.approx(d.kp * 10.0, rel=1e-6)
    assert d.kp > 0 and d.kd >= 0
    assert d.overshoot <= d.predicted_overshoot + 0.5


def test_spec_variants():
    m = yaw_subsystem(1.0)
    d = design_pd(m, PdSpec(zeta=0.8, settling_time=12.0))
    assert d.wn_source == "settling_time" and d.wn == pytest.approx(4.0 / (0.8 * 12.0))
    d = design_pd(m, PdSpec(zeta=0.8, wn=0.3))
    assert d.wn_source == "spec" and abs(d.loop.dominant_zeta - 0.8) < 1e-6
    assert (d.kp, d.kd) == pytest.approx(place_pair(m, 0.8, 0.3))
    assert design_pd(m, PdSpec(zeta=0.5, max_overshoot=1.0)).zeta == pytest.approx(0.826, abs=1e-3)


def test_nomoto_formula_misses_damping_with_steering_gear():
    """The first-order Nomoto design at the no-saturation ω_n is the paper's K_p = 3.5; ignoring the steering gear
    it ends with a dominant pair of ζ ≈ 0.31 instead of 0.8, which is why placement is the default."""
    n = design_pd(1.0, PdSpec(zeta=0.8, method="nomoto"))
    assert n.wn_source == "saturation" and n.kp == pytest.approx(3.5)
    assert n.loop.dominant_zeta < 0.4


# ---------------------------------------------------------------- nonlinear checks


def test_nonlinear_step_close_to_linear(design_1):
    """10° heading step (to port, the side the straight-running Jacobian describes): overshoot within 3
    percentage points and settling time within 10 % of the linear prediction."""
    c = verify_nonlinear(design_1, square=False)
    assert c.step.psi_d == pytest.approx(-math.radians(10.0))
    assert abs(c.step.overshoot - c.linear.overshoot) <= 3.0
    assert c.step.settling_time == pytest.approx(c.linear.settling_time, rel=0.10)
    assert c.step.peak_rudder_deg < 35.0
    assert abs(math.degrees(c.step.psi[-1] - c.step.psi_d)) < 0.1 and abs(math.degrees(c.opposite.psi[-1])) > 9.9


def test_paper_gains(design_1):
    """K_p = 3.5, K_d = 4 at the design speed: stable, dominant pair ζ ≈ 0.32, linear overshoot ≈ 10.9 %, close to
    the nonlinear step; equivalent to a first-order Nomoto design with ζ ≈ 0.82, ω_n ≈ 1.43."""
    g = paper_gains_map(1.0, kp_grid=[1.0, 3.5], kd_grid=[4.0])
    p = g.paper
    assert p.loop.stable and p.loop.phase_margin > 20.0 and p.loop.gain_margin > 1.0
    assert 9.0 <= p.overshoot <= 13.0
    assert 0.28 <= p.loop.dominant_zeta <= 0.36
    assert p.zeta == pytest.approx(0.82, abs=0.01) and p.wn == pytest.approx(1.43, abs=0.01)
    assert g.overshoot[0, 1] == pytest.approx(p.overshoot, abs=0.5)
    c = verify_nonlinear(p, square=True)
    assert abs(c.step.overshoot - p.overshoot) <= 3.0
    assert c.square["status"] == "reached" and c.square["mcte"] < 0.5
    assert 0.0 < c.square["ce"] < 0.3
    assert analyse_gains(3.5, 4.0, 0.5).loop.stable


def test_gain_grid_matches_single_analysis():
    m = yaw_subsystem(0.5)
    os_, ts, zeta = grid_step_metrics(m, [3.5], [4.0])
    p = analyse_gains(3.5, 4.0, m)
    assert os_[0, 0] == pytest.approx(p.overshoot, abs=0.3)
    assert ts[0, 0] == pytest.approx(p.settling_time, abs=0.3)
    assert zeta[0, 0] == pytest.approx(p.loop.dominant_zeta, abs=1e-6)


# ---------------------------------------------------------------- CLI


def test_cli_tune_pd(tmp_path):
    out = tmp_path / "pd"
    assert main(["tune", "pd", "--speed", "1", "--zeta", "0.8", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert METRIC_KEYS <= set(m)
    assert {"kp", "kd", "zeta", "wn", "overshoot_linear", "overshoot_nonlinear"} <= set(m["paper_gains"])
    assert {"ce", "mcte"} <= set(m["waypoint_square"]["design"]) and {"ce", "mcte"} <= set(
        m["waypoint_square"]["paper_gains"])
    assert abs(m["overshoot_nonlinear"] - m["overshoot_linear"]) <= 3.0
    for png in ("root_locus.png", "step.png", "step_paper.png", "gain_map.png"):
        assert (out / png).stat().st_size > 10_000


@pytest.mark.parametrize("argv", [["--zeta", "0"], ["--zeta", "2.5"], ["--speed", "1.5"], ["--wn", "-1"]])
def test_cli_bad_input_exits_2(tmp_path, argv, capsys):
    out = tmp_path / "bad"
    assert main(["tune", "pd", *argv, "--out", str(out)]) == 2
    assert not out.exists()
    assert argv[0] in capsys.readouterr().err


# ---------------------------------------------------------------- another hull (--vessel)


def test_kvlcc2_design_differs_from_kcs(design_1):
    """The KVLCC2's own linearisation, Nomoto model and nonlinear steps: a stable design whose dominant pair has
    the requested damping, on a Nomoto model unlike the KCS's (the tanker is course-unstable to port: K, T < 0)."""
    d = design_pd(1.0, PdSpec(zeta=0.8), vessel="kvlcc2")
    assert d.vessel == "kvlcc2" and d.model.vessel == "kvlcc2"
    assert d.loop.stable and abs(d.loop.dominant_zeta - 0.8) <= 0.02 and not d.saturates
    assert abs(d.nomoto_K - design_1.nomoto_K) > 1.0 and abs(d.nomoto_T - design_1.nomoto_T) > 1.0
    assert (d.kp, d.kd) != pytest.approx((design_1.kp, design_1.kd), rel=0.05)
    kcs_rpm = yaw_subsystem(1.0).n_rpm
    assert yaw_subsystem(1.0, vessel="kvlcc2").n_rpm == pytest.approx(105.0, abs=0.5) != pytest.approx(kcs_rpm)
    c = verify_nonlinear(d, square=False)
    assert abs(c.step.overshoot - c.linear.overshoot) <= 3.0 and c.step.peak_rudder_deg <= 35.0 + 1e-9
    fit = fit_nomoto_step(1.0, 0.1, vessel="kvlcc2")
    assert fit.linear.K == pytest.approx(nomoto_first_order(yaw_subsystem(1.0, "starboard", vessel="kvlcc2")).K)
    assert abs(fit.K_error) < 0.10 and abs(fit.T_error) < 0.10
    assert paper_gains_map(1.0, kp_grid=[3.5], kd_grid=[4.0], vessel="kvlcc2").paper.vessel == "kvlcc2"


@pytest.mark.parametrize("vessel", ["kvlcc9", "hull.toml"])
def test_cli_tune_pd_bad_vessel(tmp_path, vessel, capsys):
    out = tmp_path / "bad"
    assert main(["tune", "pd", "--vessel", str(tmp_path / vessel) if vessel.endswith(".toml") else vessel,
                 "--out", str(out)]) == 2
    assert not out.exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--vessel" in err[0] and "kcs, kvlcc2" in err[0]


def test_cli_tune_pd_vessel_file(tmp_path):
    """A hull from a file: designed and stepped on its own model; the closed loop of the waypoint square (and so
    the recommended gains) sails library hulls only, written as nulls."""
    from mmg_casadi.vessel.library import data_path
    hull = tmp_path / "tanker.toml"
    hull.write_bytes(data_path("kvlcc2").read_bytes())
    out = tmp_path / "pd"
    assert main(["tune", "pd", "--vessel", str(hull), "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["vessel"] == "tanker" and m["recommended"] is None
    assert m["waypoint_square"] == {"design": None, "paper_gains": None}
    d = design_pd(1.0, PdSpec(zeta=0.8), vessel="kvlcc2")
    assert (m["kp"], m["kd"], m["nomoto_K"], m["nomoto_T"]) == (d.kp, d.kd, d.nomoto_K, d.nomoto_T)


@pytest.mark.slow
def test_cli_tune_pd_vessel_kvlcc2(tmp_path):
    out = tmp_path / "pd"
    assert main(["tune", "pd", "--vessel", "kvlcc2", "--out", str(out)]) == 0
    m = json.loads((out / "metrics.json").read_text())
    assert m["vessel"] == "kvlcc2" and METRIC_KEYS <= set(m)
    assert abs(m["dominant_zeta"] - 0.8) <= 0.02 and m["poles"] and all(p[0] < 0 for p in m["poles"])
    kcs = design_pd(1.0, PdSpec(zeta=0.8))
    assert abs(m["nomoto_K"] - kcs.nomoto_K) > 1.0 and abs(m["nomoto_T"] - kcs.nomoto_T) > 1.0
    assert m["waypoint_square"]["design"]["status"] == "reached"
    assert m["recommended"]["square"]["status"] == "reached"


def test_cli_tune_pd_a_hull_without_a_default_natural_frequency_names_vessel_not_wn(tmp_path, capsys):
    # a yaw damping of the wrong sign: no natural frequency meets the limits, and the user gave no --wn; the
    # error used to name --wn
    text = (Path(__file__).resolve().parents[1] / "mmg_casadi" / "data" / "kcs_mmg.toml").read_text()
    hull = tmp_path / "unstable.toml"
    hull.write_text("\n".join("Nr = 0.05" if line.startswith("Nr = ") else line for line in text.splitlines()))
    out = tmp_path / "o"
    assert main(["tune", "pd", "--vessel", str(hull), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mmg-casadi: error: --vessel: expected a hull whose yaw dynamics")
    assert "--wn" not in err[0].split("(or give --wn)")[0] and not out.exists()
