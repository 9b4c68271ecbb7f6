"""Identification of MMG coefficients from measured manoeuvres, by multiple shooting with CasADi and IPOPT.

Some coefficients of a base vessel (``free``) are fitted to one or more measured time series of ``t, u, v, r,
psi, delta, rpm`` (SI units: s, m/s, rad/s, rad, rad, rev/min); everything else stays at the base vessel's value.
The model is the library's MMG model (:func:`mmg_casadi.vessel.mmg.mmg_rhs`) with the coefficients as CasADi
symbols, so every derivative is exact; the measured rudder angle and propeller speed are the inputs and the
steering gear is not part of the fit. Between samples the rudder angle is the shape-preserving cubic (PCHIP)
through its samples: flat where the rudder holds, the rate where it moves, no overshoot at the corners of a
rate-limited movement (linear interpolation cuts those corners and biased Y_β and Y_r − m_x by about one standard
error in the recovery test); the propeller speed is linear between samples.

Problem, in the design-speed prime units of the base vessel (states ``s = [u', v', r', ψ]``)::

    minimise    Σ_k Σ_c ((y_kc - s_kc) / σ_c)²                 over the node states s_k and the coefficients θ
    subject to  s_{k+1} = Φ(s_k, δ_k..δ_{k+1}, n_k..n_{k+1}; θ)   (RK4 over each sample interval)
                θ_i between 0.2 and 5 times its base value       (same sign: the physics of the derivative)

``σ_c`` is the noise standard deviation of channel ``c`` (given, or estimated from the second differences of the
measurement). The covariance of the estimate is the Gauss-Newton one of the equivalent single-shooting problem
in (initial states, θ), ``cov = s² (JᵀJ)⁻¹`` with ``s² = SSR/(N_obs - N_par)``; the report gives standard
errors, 95 % intervals (± 1.96 standard errors, and simultaneous ones for all free coefficients at once, see
:meth:`Identification.interval`), the correlation matrix and the residuals per channel. If IPOPT stops short of
its tolerance (it can cycle within 1e-6 of the optimum of these least-squares problems), Gauss-Newton steps on the
single-shooting problem finish the fit (status :data:`POLISHED`).

Examples
--------
>>> from mmg_casadi.identify import FREEABLE
>>> "Yb" in FREEABLE["beta"] and "Yv" in FREEABLE["yy2015"]
True
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np
from scipy.interpolate import PchipInterpolator
from scipy.stats import norm

from mmg_casadi.errors import InputError
from mmg_casadi.io import StagedFiles, write_text
from mmg_casadi.readers import csv_rows
from mmg_casadi.vessel.library import Vessel, data_path, load_vessel
from mmg_casadi.vessel.mmg import mmg_rhs
from mmg_casadi.vessel.ship import ShipParams, required_coefficients

COLUMNS = ("t", "u", "v", "r", "psi", "delta", "rpm")
"""Columns a measured time series must have (SI: s, m/s, m/s, rad/s, rad, rad, rev/min)."""

CHANNELS = ("u", "v", "r", "psi")
"""Measured channels that enter the fit."""

_NOT_FREE = {"L", "B", "d", "Cb", "displacement", "xG", "kzz", "rho", "g", "Fn_design", "U_design", "m", "mx", "my",
             "Jzz", "Izz", "DP", "n_design_rpm", "aspect_ratio"}
FREEABLE = {form: tuple(n for n in required_coefficients(form) if n not in _NOT_FREE)
            for form in ("beta", "yy2015")}
"""Coefficients that may be fitted, per hull form: the hull, propeller and rudder coefficients (not particulars,
masses or added masses, which the mass matrix needs as numbers)."""

POLISHED = "Solved_By_Gauss_Newton"
"""Status of a fit whose IPOPT run stopped short of its tolerance (typically cycling within 1e-6 of the optimum)
and whose Gauss-Newton polish converged (:func:`identify`)."""

BOUND_FACTORS = (0.2, 5.0)
"""A fitted coefficient stays between these multiples of its base value (so it keeps its sign)."""
BOUND_TOLERANCE = 1e-3
"""An estimate within this fraction of its bound sits on the bound (:meth:`Identification.warnings`): the data
pushed it there, and the bound, not the data, sets its value."""
MAX_CORRELATION = 0.95
"""Largest absolute correlation of two estimates the fit accepts without a warning: beyond it the data determine a
combination of the two, not each one (a common rule for identifiability in parameter estimation)."""
MAX_SAMPLES = 2000
"""Most samples of one identification (all runs together). The fit's memory and time grow faster than the samples
where the data cannot separate the coefficients: 2000 samples at a constant rudder took 133 s and 0.6 GB, 5000
reached 3.9 GB and kept rising; 2000 samples of a 20/20 zig-zag fit in 4 s and 0.18 GB."""


def read_timeseries(path: str | Path) -> dict[str, np.ndarray]:
    """A measured time series from a CSV file with a header row naming at least :data:`COLUMNS`.

    An optional column ``run`` (integer) splits the file into separate experiments (see :func:`split_runs`).

    Parameters
    ----------
    path : str or pathlib.Path
        CSV file.

    Returns
    -------
    dict of numpy.ndarray
        Each column of :data:`COLUMNS` (and ``run`` if present) to its values, one per data row, in SI units.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("data file", "an existing CSV file", str(path))
    cols: dict[str, list[float]] | None = None
    for _line, r in csv_rows(path, "identification data", max_rows=MAX_SAMPLES, field="data file"):  # streamed
        if cols is None:
            missing = [c for c in COLUMNS if c not in r]
            if missing:
                raise InputError(f"data column '{missing[0]}'", f"columns {', '.join(COLUMNS)} (SI units)", str(path))
            cols = {c: [] for c in (*COLUMNS, "run") if c in r}
        for c, values in cols.items():
            try:
                v = float(r[c])
            except (TypeError, ValueError):
                raise InputError(f"data column '{c}'", "numbers in every row", str(path)) from None
            if not math.isfinite(v) or abs(v) > MAX_VALUE:
                raise InputError(f"data column '{c}'", f"finite numbers of magnitude at most {MAX_VALUE:g} in every "
                                 "row", str(path))
            values.append(v)
    if cols is None:
        raise InputError("data file", "a CSV file with a header row and data rows", str(path))
    return {c: np.array(v) for c, v in cols.items()}


MAX_VALUE = 1e6
"""Largest magnitude of a measured value (SI units: a time of 11 days, a speed of 1000 km/s are no trial)."""


def split_runs(data: dict[str, np.ndarray]) -> list[dict[str, np.ndarray]]:
    """The experiments of a time series: one per value of its ``run`` column (the whole series without one).

    Parameters
    ----------
    data : dict of numpy.ndarray
        Columns as from :func:`read_timeseries`.

    Returns
    -------
    list of dict of numpy.ndarray
        One dict of columns per experiment (without ``run``), in increasing ``run`` order.
    """
    if "run" not in data:
        runs = [data]
    else:
        runs = [{c: v[data["run"] == k] for c, v in data.items() if c != "run"} for k in np.unique(data["run"])]
    for r in runs:
        if len(r["t"]) < 10 or np.any(np.diff(r["t"]) <= 0):
            raise InputError("data column 't'", "at least 10 samples per run, strictly increasing", len(r["t"]))
    return runs


def noise_estimate(y: np.ndarray) -> float:
    """Standard deviation of white noise on a smooth signal: median absolute second difference / (0.6745·√6).

    Parameters
    ----------
    y : numpy.ndarray
        Uniformly sampled signal.

    Returns
    -------
    float
        The standard deviation, in the units of ``y`` (at least 1e-9).
    """
    d2 = np.diff(y, 2)
    return float(max(np.median(np.abs(d2 - np.median(d2))) / (0.6745 * math.sqrt(6.0)), 1e-9))


@dataclass
class Identification:
    """Result of :func:`identify` (coefficients in the prime-II units of the base vessel's data file).

    Parameters
    ----------
    free : tuple of str
        Names of the fitted coefficients.
    base : numpy.ndarray
        Their base values.
    estimate : numpy.ndarray
        Estimates.
    std_error : numpy.ndarray
        Gauss-Newton standard errors.
    correlation : numpy.ndarray
        Correlation matrix of the estimates.
    residual_rms : dict
        Root mean square of the residual per channel (prime-II units; ψ in rad).
    sigma : dict
        Noise standard deviation used as weight per channel (prime-II units).
    status : str
        IPOPT return status, or :data:`POLISHED` when IPOPT stopped short and Gauss-Newton steps converged.
    ship : ShipParams
        Base ship with the estimates in place.
    fits : list of numpy.ndarray
        Fitted node states ``(N, 4)`` per run.
    """

    free: tuple[str, ...]
    base: np.ndarray
    estimate: np.ndarray
    std_error: np.ndarray
    correlation: np.ndarray
    residual_rms: dict
    sigma: dict
    status: str
    ship: ShipParams
    fits: list = field(default_factory=list)

    def interval(self, level_z: float = 1.96, *, simultaneous: bool = False) -> np.ndarray:
        """``(p, 2)`` confidence intervals, estimate ± ``level_z`` standard errors (95 % by default).

        Each interval holds its own coefficient with the stated confidence; all ``p`` of them hold at once less
        often (for four weakly correlated estimates about 0.95⁴ ≈ 81 % of the time). With ``simultaneous=True``
        the intervals are widened by Bonferroni's rule so that they hold **all at once** with at least that
        confidence: ``z = Φ⁻¹(1 − (1 − c)/(2p))`` with ``c = 2Φ(level_z) − 1`` (2.50 for four coefficients at
        95 %).

        Parameters
        ----------
        level_z : float, default 1.96
            Number of standard errors of a single interval (1.96: 95 %).
        simultaneous : bool, default False
            Intervals for a statement about every free coefficient at once.

        Returns
        -------
        numpy.ndarray (p, 2)
            Lower and upper ends for each free coefficient (prime-II, like :attr:`estimate`).

        Examples
        --------
        >>> fit = Identification(("a", "b", "c", "d"), np.ones(4), np.ones(4), np.full(4, 0.1), np.eye(4), {}, {},
        ...                      "Solve_Succeeded", None)
        >>> np.round(fit.interval()[0], 3), np.round(fit.interval(simultaneous=True)[0], 3)
        (array([0.804, 1.196]), array([0.75, 1.25]))
        """
        z = level_z
        if simultaneous:
            z = float(norm.ppf(1.0 - (1.0 - (2.0 * norm.cdf(level_z) - 1.0)) / (2.0 * len(self.free))))
        return np.column_stack([self.estimate - z * self.std_error, self.estimate + z * self.std_error])

    def warnings(self) -> list[str]:
        """Why the estimates may not be what the data say: a coefficient on its bound (within
        :data:`BOUND_TOLERANCE` of :data:`BOUND_FACTORS` times its base value: the bound set it) and every pair
        of coefficients whose estimates correlate beyond :data:`MAX_CORRELATION` (the data cannot separate them).

        Returns
        -------
        list of str
            One sentence per finding; empty for a fit without either.

        Examples
        --------
        >>> fit = Identification(("a", "b"), np.ones(2), np.array([5.0, 1.3]), np.full(2, 0.1),
        ...                      np.array([[1.0, -0.986], [-0.986, 1.0]]), {}, {}, "Solve_Succeeded", None)
        >>> for w in fit.warnings():
        ...     print(w)
        a sits on its upper bound (5 x its base value 1): the bound, not the data, sets it
        a and b correlate at -0.986 (beyond 0.95): the data cannot separate them
        """
        out = []
        for n, e, b in zip(self.free, self.estimate, self.base):
            ends = sorted((f * b, f) for f in BOUND_FACTORS)  # (bound, factor), the lower bound first
            for side, (bound, factor) in zip(("lower", "upper"), ends):
                if abs(e - bound) <= BOUND_TOLERANCE * abs(bound):
                    out.append(f"{n} sits on its {side} bound ({factor:g} x its base value {b:g}): the bound, not "
                               "the data, sets it")
        for i in range(len(self.free)):
            for j in range(i + 1, len(self.free)):
                c = float(self.correlation[i, j])
                if abs(c) > MAX_CORRELATION:
                    out.append(f"{self.free[i]} and {self.free[j]} correlate at {c:.3f} (beyond {MAX_CORRELATION:g}): "
                               "the data cannot separate them")
        return out

    def report(self) -> dict:
        """JSON-ready summary: estimates, standard errors, 95 % intervals, correlation, residuals, warnings.

        Returns
        -------
        dict
            ``status``, ``warnings`` (:meth:`warnings`), ``coefficients`` (per name ``base``, ``estimate``,
            ``std_error``, ``ci95`` and ``ci95_simultaneous``, see :meth:`interval`), ``correlation``
            (``names`` and ``matrix``), ``residual_rms`` and ``sigma`` per channel, and ``units``.
        """
        ci, cis = self.interval(), self.interval(simultaneous=True)
        return {
            "status": self.status,
            "warnings": self.warnings(),
            "coefficients": {n: {"base": float(b), "estimate": float(e), "std_error": float(s),
                                 "ci95": [float(lo), float(hi)], "ci95_simultaneous": [float(a), float(b2)]}
                             for n, b, e, s, (lo, hi), (a, b2) in zip(self.free, self.base, self.estimate,
                                                                      self.std_error, ci, cis)},
            "correlation": {"names": list(self.free), "matrix": np.round(self.correlation, 6).tolist()},
            "residual_rms": self.residual_rms,
            "sigma": self.sigma,
            "units": "prime-II of the base vessel (u, v over U_design; r over U_design/L; psi rad)",
        }


def _check_free(ship: ShipParams, free) -> tuple[str, ...]:
    allowed = FREEABLE[ship.hull_form]
    free = tuple(free)
    if not free:
        raise InputError("free", f"one or more of: {', '.join(allowed)}")
    for n in free:
        if n not in allowed:
            raise InputError("free", f"coefficients of the '{ship.hull_form}' form: {', '.join(allowed)}", n)
        if getattr(ship, n) == 0.0:
            raise InputError("free", "coefficients whose base value is not 0 (the bounds are multiples of it)", n)
    if len(set(free)) != len(free):
        raise InputError("free", "each coefficient once", ",".join(free))
    return free


def _prime(run: dict, ship: ShipParams) -> dict:
    U, L = ship.U_design, ship.L
    return {"t": run["t"] * U / L, "y": np.column_stack([run["u"] / U, run["v"] / U, run["r"] * L / U, run["psi"]]),
            "delta": run["delta"], "rpm": run["rpm"]}


def _step_function(ship: ShipParams, vessel: Vessel, free: tuple[str, ...], n_sub: int) -> ca.Function:
    """RK4 over one sample interval: ``step(s, δa, δb, ma, mb, na, nb, h, θ) -> s_next``, the rudder angle a cubic
    Hermite between its samples ``δa``, ``δb`` with slopes ``ma``, ``mb`` (per unit time), the propeller speed
    linear."""
    theta = ca.SX.sym("theta", len(free))
    sym_ship = dataclasses.replace(ship, **{n: theta[i] for i, n in enumerate(free)})
    s = ca.SX.sym("s", 4)
    dl, nn = ca.SX.sym("delta"), ca.SX.sym("n")
    full = ca.vertcat(s[0], s[1], s[2], 0, 0, s[3], dl)
    rhs = mmg_rhs(sym_ship, vessel.steering, full, dl, nn)
    f = ca.Function("f_id", [s, dl, nn, theta], [ca.vertcat(rhs[0], rhs[1], rhs[2], rhs[5])])
    da, db, ma, mb, na, nb, h = (ca.SX.sym(k) for k in ("da", "db", "ma", "mb", "na", "nb", "h"))

    def rudder(a):  # cubic Hermite on [0, 1]
        return ((2 * a ** 3 - 3 * a ** 2 + 1) * da + (a ** 3 - 2 * a ** 2 + a) * h * ma
                + (-2 * a ** 3 + 3 * a ** 2) * db + (a ** 3 - a ** 2) * h * mb)

    x = s
    for j in range(n_sub):
        a0, a1 = j / n_sub, (j + 1) / n_sub
        d0, dm, d1 = (rudder(a) for a in (a0, 0.5 * (a0 + a1), a1))
        n0, nm, n1 = (na + (nb - na) * a for a in (a0, 0.5 * (a0 + a1), a1))
        hh = h / n_sub
        k1 = f(x, d0, n0, theta)
        k2 = f(x + 0.5 * hh * k1, dm, nm, theta)
        k3 = f(x + 0.5 * hh * k2, dm, nm, theta)
        k4 = f(x + hh * k3, d1, n1, theta)
        x = x + hh / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ca.Function("step_id", [s, da, db, ma, mb, na, nb, h, theta], [x])


def _interval_inputs(d: dict) -> tuple:
    """The step's inputs over every sample interval of one run, as rows: ``δa, δb, ma, mb, na, nb, h``, the slopes
    ``m`` those of the shape-preserving (PCHIP) interpolant of the rudder samples (flat where the rudder holds, the
    rate where it moves, no overshoot at the corners of a rate-limited movement)."""
    t, dl, n = d["t"], d["delta"][None, :], d["rpm"][None, :]
    m = PchipInterpolator(t, d["delta"]).derivative()(t)[None, :]
    return dl[:, :-1], dl[:, 1:], m[:, :-1], m[:, 1:], n[:, :-1], n[:, 1:], np.diff(t)[None, :]


def identify(runs: list[dict], vessel: str | Path | Vessel, free, *, sigma: dict | None = None, n_sub: int = 2,
             max_iter: int = 100) -> Identification:
    """Fit the coefficients ``free`` of ``vessel`` to the measured ``runs`` (see the module docstring).

    Parameters
    ----------
    runs : list of dict
        Experiments, each with the arrays of :data:`COLUMNS` in SI units (see :func:`read_timeseries`).
    vessel : str, pathlib.Path or Vessel
        Base vessel (a library name or a data file).
    free : sequence of str
        Coefficients to fit (:data:`FREEABLE` of the vessel's hull form).
    sigma : dict, optional
        Noise standard deviation per channel of :data:`CHANNELS` in SI units; estimated from the data if omitted.
    n_sub : int, default 2
        RK4 steps per sample interval.
    max_iter : int, default 100
        IPOPT iteration limit (a fit that reaches it is finished by Gauss-Newton steps, status
        :data:`POLISHED`).

    Returns
    -------
    Identification
        Estimates, standard errors, correlation, residual RMS, noise levels, IPOPT status, the fitted ship and the
        fitted state histories.
    """
    v = vessel if isinstance(vessel, Vessel) else load_vessel(vessel)
    ship = v.ship
    free = _check_free(ship, free)
    n_samples = sum(len(r["t"]) for r in runs)
    if n_samples > MAX_SAMPLES:
        raise InputError("data file", f"at most {MAX_SAMPLES} samples in all runs (MAX_SAMPLES; decimate the series)",
                         n_samples)
    theta0 = np.array([getattr(ship, n) for n in free], float)
    lo = np.minimum(BOUND_FACTORS[0] * theta0, BOUND_FACTORS[1] * theta0)
    hi = np.maximum(BOUND_FACTORS[0] * theta0, BOUND_FACTORS[1] * theta0)
    data = [_prime(r, ship) for r in runs]
    scale = np.array([1 / ship.U_design, 1 / ship.U_design, ship.L / ship.U_design, 1.0])
    if sigma is None:
        sig = np.array([np.median([noise_estimate(d["y"][:, c]) for d in data]) for c in range(4)])
    else:
        sig = np.array([float(sigma[c]) for c in CHANNELS]) * scale
    step = _step_function(ship, v, free, n_sub)
    theta = ca.MX.sym("theta", len(free))
    w, w0, lbw, ubw, g, J = [theta], [theta0], [lo], [hi], [], 0
    nodes = []
    for k, d in enumerate(data):
        N = len(d["t"])
        X = ca.MX.sym(f"X{k}", 4, N)
        nodes.append(X)
        w.append(ca.vec(X))
        w0.append(d["y"].T.ravel(order="F"))
        lbw.append(np.full(4 * N, -np.inf))
        ubw.append(np.full(4 * N, np.inf))
        Xn = step.map(N - 1)(X[:, :-1], *_interval_inputs(d), ca.repmat(theta, 1, N - 1))
        g.append(ca.vec(Xn - X[:, 1:]))
        J += ca.sumsqr((X - ca.DM(d["y"].T)) / ca.repmat(ca.DM(sig), 1, N))
    nlp = {"x": ca.vertcat(*w), "f": J, "g": ca.vertcat(*g)}
    solver = ca.nlpsol("identify", "ipopt", nlp, {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False,
                                                  "ipopt.max_iter": max_iter, "ipopt.tol": 1e-10,
                                                  "ipopt.acceptable_tol": 1e-8, "ipopt.acceptable_iter": 10})
    sol = solver(x0=np.concatenate(w0), lbx=np.concatenate(lbw), ubx=np.concatenate(ubw), lbg=0, ubg=0)
    status = solver.stats()["return_status"]
    wopt = np.array(sol["x"]).ravel()
    est = wopt[:len(free)]
    fits, off = [], len(free)
    for d in data:
        N = len(d["t"])
        fits.append(wopt[off:off + 4 * N].reshape(N, 4))
        off += 4 * N
    est, fits, cov, resid, polished = _gauss_newton(step, data, fits, est, sig, lo, hi,
                                                    polish=status != "Solve_Succeeded")
    if polished:
        status = POLISHED
    se = np.sqrt(np.diag(cov))
    corr = cov / np.outer(se, se)
    return Identification(free, theta0, est, se, corr,
                          {c: float(np.sqrt(np.mean(resid[:, i] ** 2))) for i, c in enumerate(CHANNELS)},
                          {c: float(sig[i]) for i, c in enumerate(CHANNELS)}, status,
                          dataclasses.replace(ship, **dict(zip(free, map(float, est)))), fits)


def _gauss_newton(step: ca.Function, data, fits, est, sig, lo, hi, *, polish: bool):
    """Covariance of θ from the single-shooting residuals in (initial states of every run, θ), the fitted states
    and their residuals; with ``polish``, first Gauss-Newton steps (halved until the sum of squares falls) from
    IPOPT's point while θ stays inside its bounds. Returns ``(θ, fits, cov, residuals, polished)``, ``polished``
    when those steps converged (the last one below 1e-9 of each |θ_i| and 1e-9 in the node states)."""
    p = len(est)
    theta = ca.MX.sym("theta", p)
    x0s, res, preds = [], [], []
    for d in data:
        N = len(d["t"])
        x0 = ca.MX.sym("x0", 4)
        x0s.append(x0)
        X = step.mapaccum(N - 1)(x0, *_interval_inputs(d), ca.repmat(theta, 1, N - 1))
        pred = ca.horzcat(x0, X)
        preds.append(pred)
        res.append(ca.vec((ca.DM(d["y"].T) - pred) / ca.repmat(ca.DM(sig), 1, N)))
    z = ca.vertcat(*x0s, theta)
    r = ca.vertcat(*res)
    fn = ca.Function("gn", [z], [r, ca.jacobian(r, z)])
    residual = ca.Function("gn_r", [z], [r])  # the line search needs no Jacobian
    z0 = np.concatenate([f[0] for f in fits] + [est])
    rv, Jm = (np.array(a) for a in fn(z0))
    rv = rv.ravel()
    polished = False
    for _ in range(20 if polish else 0):
        dz = -np.linalg.lstsq(Jm, rv, rcond=None)[0]
        for _ in range(30):
            z1 = z0 + dz
            r1 = np.array(residual(z1)).ravel()
            if np.all((lo <= z1[-p:]) & (z1[-p:] <= hi)) and r1 @ r1 <= rv @ rv:
                break
            dz = 0.5 * dz
        else:
            break
        z0 = z1
        rv, Jm = (np.array(a) for a in fn(z0))
        rv = rv.ravel()
        if np.all(np.abs(dz[-p:]) <= 1e-9 * np.abs(z0[-p:])) and np.all(np.abs(dz[:-p]) <= 1e-9):
            polished = True
            break
    if polished:
        fits = [np.array(f).T for f in ca.Function("pred", [z], preds).call([z0])]
    dof = max(len(rv) - len(z0), 1)
    s2 = float(rv @ rv) / dof
    cov_all = s2 * np.linalg.pinv(Jm.T @ Jm)
    resid = np.vstack([(d["y"] - f) for d, f in zip(data, fits)])
    return z0[-p:], fits, cov_all[-p:, -p:], resid, polished


def vessel_toml(base: str | Path, result: Identification, source: str) -> str:
    """The base vessel's data file with the fitted coefficients replaced, each commented with its standard error,
    95 % interval and base value; loadable by :func:`mmg_casadi.vessel.library.load_vessel`.

    Parameters
    ----------
    base : str or pathlib.Path
        Library name or data file of the base vessel.
    result : Identification
        The fit.
    source : str
        What the coefficients were fitted to (named in the header).

    Returns
    -------
    str
        The TOML text, a two-line ``# IDENTIFIED`` header first.
    """
    text = data_path(base).read_text() if isinstance(base, str) and not str(base).endswith(".toml") else \
        Path(base).read_text(encoding="utf-8")
    ci = result.interval()
    for n, e, s, b, (lo, hi) in zip(result.free, result.estimate, result.std_error, result.base, ci):
        pat = re.compile(rf"^(\s*{re.escape(n)}\s*=\s*)([^#\n]*?)(\s*#[^\n]*)?$", re.MULTILINE)
        if len(pat.findall(text)) != 1:
            raise InputError("free", "coefficients written once in the base data file", n)
        text = pat.sub(lambda m, e=e, s=s, b=b, lo=lo, hi=hi: f"{m.group(1)}{e:.6g}"
                       f"  # identified: s.e. {s:.2g}, 95 % [{lo:.6g}, {hi:.6g}]; base {b:g}", text)
    head = (f"# IDENTIFIED by mmg_casadi.identify from {source}: coefficients {', '.join(result.free)} fitted by\n"
            f"# multiple shooting (IPOPT status {result.status}); every other number and source is the base "
            f"vessel's ({base}).\n")
    head += "".join(f"# WARNING: {w}\n" for w in result.warnings())
    return head + text


def identify_to_dir(data: str | Path, vessel: str | Path, free, out: str | Path) -> dict:
    """Read ``data``, fit ``free`` of ``vessel``, write ``OUT/<vessel>_identified.toml`` and
    ``OUT/identification.json``; return the report with a short ``summary``.

    Parameters
    ----------
    data : str or pathlib.Path
        CSV time series (:func:`read_timeseries`).
    vessel : str or pathlib.Path
        Base vessel.
    free : sequence of str
        Coefficients to fit.
    out : str or pathlib.Path
        Output directory.

    Returns
    -------
    dict
        :meth:`Identification.report` with ``vessel_file`` (the TOML path) and ``summary`` (per coefficient
        ``"estimate ± s.e. (base b)"``, plus ``status`` and ``vessel_file``), as written to ``identification.json``.
    """
    v = load_vessel(vessel)
    runs = split_runs(read_timeseries(data))
    res = identify(runs, v, free)
    out = Path(out)
    toml_path = out / f"{v.name}_identified.toml"
    rep = res.report()
    rep["vessel_file"] = str(toml_path)
    rep["summary"] = {n: f"{c['estimate']:.6g} ± {c['std_error']:.2g} (base {c['base']:g})"
                      for n, c in rep["coefficients"].items()} | {"status": res.status, "vessel_file": str(toml_path)}
    if rep["warnings"]:
        rep["summary"]["warnings"] = rep["warnings"]
    with StagedFiles() as st:  # both files or neither, each complete
        write_text(st.path(toml_path), vessel_toml(vessel, res, Path(data).name))
        write_text(st.path(out / "identification.json"), json.dumps(rep, indent=1))
    return rep


def maneuver_timeseries(result, vessel: Vessel, rpm: float) -> dict[str, np.ndarray]:
    """A manoeuvre of :mod:`mmg_casadi.vessel.maneuvers` as a measured time series in SI units (no noise).

    Parameters
    ----------
    result : ManeuverResult
        The manoeuvre.
    vessel : Vessel
        Its vessel.
    rpm : float
        Its propeller speed (rev/min).

    Returns
    -------
    dict of numpy.ndarray
        ``t`` (s), ``u``, ``v`` (m/s), ``r`` (rad/s), ``psi``, ``delta`` (rad) and ``rpm`` (rev/min), one value per
        sample.
    """
    s = vessel.ship
    U, L = s.U_design, s.L
    X = result.states
    return {"t": result.t * L / U, "u": X[:, 0] * U, "v": X[:, 1] * U, "r": X[:, 2] * U / L, "psi": X[:, 5],
            "delta": X[:, 6], "rpm": np.full(len(result.t), float(rpm))}
