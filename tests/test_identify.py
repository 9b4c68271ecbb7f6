"""Identification of MMG coefficients: recovery from noisy synthetic KCS manoeuvres, the written vessel file, and
the `identify` command's input errors.

The synthetic data are the library's own KCS 20/20 zig-zag and 35° turning circle (mmg_casadi.vessel.maneuvers),
sampled every 0.1 L/U (1.86 s) with white Gaussian noise of standard deviation 0.02 m/s on u and v, 2e-4 rad/s on
r and 2e-3 rad (0.11°) on ψ, seed 1. Rudder angle and propeller speed are taken as measured without noise.
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.identify import POLISHED, identify, maneuver_timeseries, read_timeseries, split_runs
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.maneuvers import turning_circle, zigzag
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed

KCS = load_vessel("kcs")
RPM = propeller_rpm_for_speed(1.0, KCS.ship)
SIGMA = {"u": 0.02, "v": 0.02, "r": 2e-4, "psi": 2e-3}
FREE = ("Yb", "Yr_minus_mx", "Nb", "Nr")


def _noisy_runs(seed: int = 1, every: int = 2) -> list[dict]:
    rng = np.random.default_rng(seed)
    runs = []
    for res in (zigzag(20), turning_circle(35, t_end=20)):
        d = {k: a[::every] for k, a in maneuver_timeseries(res, KCS, RPM).items()}
        for c, s in SIGMA.items():
            d[c] = d[c] + rng.normal(0.0, s, len(d[c]))
        runs.append(d)
    return runs


@pytest.fixture(scope="module")
def fit():
    return identify(_noisy_runs(), KCS, FREE, sigma=SIGMA)


def test_freed_coefficients_are_recovered_within_their_95_percent_intervals(fit):
    truth = np.array([getattr(KCS.ship, n) for n in FREE])
    lo, hi = fit.interval().T
    assert fit.status == "Solve_Succeeded"
    assert np.all((lo <= truth) & (truth <= hi)), (fit.estimate, fit.std_error, truth)
    assert np.all(fit.std_error < 0.01 * np.abs(truth))  # these data pin the linear derivatives to 1 %


@pytest.fixture(scope="module")
def twenty_seeds():
    """Fits of the test's data with noise seeds 1-20: whether every freed coefficient's 95 % interval holds the
    truth (one by one, and simultaneous), and the relative error of the identified model's 35° tactical diameter
    (about 45 s)."""
    import dataclasses
    truth = np.array([getattr(KCS.ship, n) for n in FREE])
    td_true = turning_circle(35.0).metrics["tactical_diameter"]
    inside, together, td_err = [], [], []
    for seed in range(1, 21):
        f = identify(_noisy_runs(seed), KCS, FREE, sigma=SIGMA)
        for out, ci in ((inside, f.interval()), (together, f.interval(simultaneous=True))):
            out.append(bool(np.all((ci[:, 0] <= truth) & (truth <= ci[:, 1]))))
        ship = dataclasses.replace(KCS.ship, **dict(zip(FREE, f.estimate)))
        td_err.append(turning_circle(35.0, ship=ship).metrics["tactical_diameter"] / td_true - 1.0)
    return np.array(inside), np.array(td_err), np.array(together)


@pytest.mark.slow
def test_identified_model_predicts_the_tactical_diameter_within_3_percent(twenty_seeds):
    """Measured: within 0.016 % in every one of the 20 seeds."""
    assert np.max(np.abs(twenty_seeds[1])) < 0.03


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="measured: the four 95 % intervals hold the truth all at once in 17 of seeds "
                   "1-20 and in 266 of seeds 1-300 (88.7 %, Wilson [84.6, 91.8]); one by one in 94.7, 94.0, 92.7, "
                   "92.7 % of the 300. Exactly calibrated 95 % intervals of four estimates correlated like these "
                   "hold all at once in 91 % of fits, so 9 in 10 is at the limit of what one-by-one intervals give; "
                   "the simultaneous intervals below are the ones for that statement")
def test_intervals_hold_the_truth_in_nine_of_ten_seeds(twenty_seeds):
    assert twenty_seeds[0].sum() >= 18


@pytest.mark.slow
def test_simultaneous_intervals_hold_every_coefficient_in_nine_of_ten_seeds(twenty_seeds):
    """Bonferroni's 95 % intervals for all four at once. Measured: 18 of seeds 1-20, 287 of seeds 1-300 (95.7 %,
    Wilson [92.7, 97.5])."""
    assert twenty_seeds[2].sum() >= 18


def test_rudder_between_samples_is_shape_preserving_so_noise_free_data_give_the_truth():
    """Noise-free trials sampled every 0.1 L/U: the fit with the rudder angle a PCHIP between samples recovers the
    coefficients within 0.04 %; with the rudder linear between samples Y_β and Y_r - m_x came out 0.32 % and
    -0.64 % off (about one standard error at the test's noise)."""
    runs = [{k: a[::2] for k, a in maneuver_timeseries(res, KCS, RPM).items()}
            for res in (zigzag(20), turning_circle(35, t_end=20))]
    f = identify(runs, KCS, FREE, sigma=SIGMA)
    truth = np.array([getattr(KCS.ship, n) for n in FREE])
    assert np.max(np.abs(f.estimate / truth - 1.0)) < 4e-4


def test_a_fit_ipopt_leaves_short_of_its_tolerance_is_finished_by_gauss_newton(fit):
    """IPOPT stopped after 3 iterations: Gauss-Newton steps take the estimate to the full fit's."""
    short = identify(_noisy_runs(), KCS, FREE, sigma=SIGMA, max_iter=3)
    assert short.status == POLISHED
    np.testing.assert_allclose(short.estimate, fit.estimate, rtol=1e-7)
    np.testing.assert_allclose(short.std_error, fit.std_error, rtol=1e-5)
    assert short.residual_rms == pytest.approx(fit.residual_rms, rel=1e-5)


def test_residuals_match_the_stated_noise_and_correlations_are_a_correlation_matrix(fit):
    s = KCS.ship
    stated = {"u": SIGMA["u"] / s.U_design, "v": SIGMA["v"] / s.U_design, "r": SIGMA["r"] * s.L / s.U_design,
              "psi": SIGMA["psi"]}
    for c, rms in fit.residual_rms.items():
        assert rms == pytest.approx(stated[c], rel=0.15), c
    C = fit.correlation
    np.testing.assert_allclose(np.diag(C), 1.0, atol=1e-12)
    np.testing.assert_allclose(C, C.T, atol=1e-12)
    assert np.all(np.abs(C) <= 1.0 + 1e-9)
    assert C[0, 1] < -0.9  # Y_β and Y_r - m_x trade off in these manoeuvres (a known identifiability limit)


def _write_csv(path, runs):
    cols = ("run", "t", "u", "v", "r", "psi", "delta", "rpm")
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for k, d in enumerate(runs):
            for i in range(len(d["t"])):
                w.writerow([k] + [repr(float(d[c][i])) for c in cols[1:]])


def test_identify_command_writes_a_loadable_vessel_file(tmp_path, capsys):
    data = tmp_path / "kcs_trials.csv"
    _write_csv(data, _noisy_runs(seed=2))
    assert len(split_runs(read_timeseries(data))) == 2
    out = tmp_path / "fit"
    assert main(["identify", str(data), "--vessel", "kcs", "--free", "Nb,Nr", "--out", str(out)]) == 0
    v = load_vessel(out / "kcs_identified.toml")
    assert v.ship.Nb == pytest.approx(KCS.ship.Nb, rel=0.02) and v.ship.Nr == pytest.approx(KCS.ship.Nr, rel=0.02)
    assert v.ship.Yb == KCS.ship.Yb and v.steering == KCS.steering  # everything else is the base vessel's
    text = (out / "kcs_identified.toml").read_text()
    assert text.startswith("# IDENTIFIED by mmg_casadi.identify from kcs_trials.csv")
    assert "Nb = " in text and "# identified: s.e." in text
    assert (out / "identification.json").is_file()


@pytest.mark.parametrize("args,message", [
    (["--free", "Yv"], "--free: expected coefficients of the 'beta' form"),
    (["--free", "m"], "--free: expected coefficients of the 'beta' form"),
    (["--free", "Nr", "--vessel", "kvlcc9"], "--vessel: expected one of: kcs, kvlcc2"),
])
def test_identify_refuses_bad_input_in_one_line(tmp_path, capsys, args, message):
    data = tmp_path / "d.csv"
    _write_csv(data, _noisy_runs(seed=3, every=20)[:1])
    assert main(["identify", str(data), "--out", str(tmp_path / "o"), *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]


def test_identify_names_a_missing_column(tmp_path, capsys):
    data = tmp_path / "d.csv"
    data.write_text("t,u,v,r,psi,delta\n0,1,0,0,0,0\n")
    assert main(["identify", str(data), "--free", "Nr", "--out", str(tmp_path / "o")]) == 2
    assert "data column 'rpm': expected columns t, u, v, r, psi, delta, rpm" in capsys.readouterr().err


def _constant_rudder_csv(path, n: int) -> None:
    """Straight running at a constant rudder angle with no yaw: nothing in these data separates the coefficients."""
    rng = np.random.default_rng(1)
    t = np.arange(n) * 1.0
    d = {"t": t, "u": 12.0 + rng.normal(0, 0.02, n), "v": rng.normal(0, 0.02, n), "r": rng.normal(0, 2e-4, n),
         "psi": rng.normal(0, 1e-3, n), "delta": np.full(n, 0.1), "rpm": np.full(n, 115.5)}
    _write_csv(path, [d])


def test_identify_warns_and_marks_its_output_when_the_data_cannot_separate_the_coefficients(tmp_path, capsys):
    # the case: a constant rudder gave "Solved_To_Acceptable_Level" with coefficients on their bounds
    # (correlation -0.986) and no word of it
    data = tmp_path / "constant.csv"
    _constant_rudder_csv(data, 200)
    out = tmp_path / "fit"
    assert main(["identify", str(data), "--free", "Yb,Nb,Nr", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    report = json.loads((out / "identification.json").read_text())
    assert report["warnings"] and err == [f"mmg-casadi: warning: identify: {w}" for w in report["warnings"]]
    assert any("sits on its" in w and "bound" in w for w in report["warnings"])
    assert any("correlate at" in w and "cannot separate" in w for w in report["warnings"])
    header = (out / "kcs_identified.toml").read_text().splitlines()[:2 + len(report["warnings"])]
    assert header[2:] == [f"# WARNING: {w}" for w in report["warnings"]]


def test_a_fit_of_separable_data_has_no_bound_warning(fit):
    assert not any("bound" in w for w in fit.warnings())
    assert all("correlate" in w for w in fit.warnings())  # only the known Y_beta / Y_r - m_x trade-off, if at all


def test_identify_refuses_more_samples_than_it_can_fit_before_reading_them_all(tmp_path, capsys):
    from mmg_casadi.identify import MAX_SAMPLES
    data = tmp_path / "long.csv"
    _constant_rudder_csv(data, MAX_SAMPLES + 1)
    assert main(["identify", str(data), "--free", "Nr", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"mmg-casadi: error: data file: expected an identification data file of at most {MAX_SAMPLES} "
                   f"rows, got '{data}: more'"]
    assert not (tmp_path / "o").exists()
