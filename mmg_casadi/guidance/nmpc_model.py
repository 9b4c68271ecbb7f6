"""The prediction model of ``nmpc``: a nonlinear Nomoto and surge model identified from the MMG model with CasADi.

The MMG model itself is not a good prediction model for an optimiser: its drift-angle hull polynomials are stiff at
low speed and large drift (a yaw acceleration of −12 rad/(L/U)² at u = 0.3, v = 0.2), so the iterates of a
multiple-shooting or single-shooting solver that stray there blow up, and its straight-run linearisation is nearly
unstable (the KCS's slow yaw pole is −0.016 per L/U, a steady yaw rate 50 times the MMG's at 35° rudder). The
planner therefore predicts with a reduced model whose every coefficient comes from the MMG model of the ship
(:func:`mmg_casadi.vessel.mmg.build_mmg`, in the scene's units):

* steering gear: the MMG model's own, ``δ̇ = (δ_c − δ)/T_δ`` (its rate limit never binds for commands within
  ±δ_max: the largest rate asked, 2 δ_max/T_δ, is below it for the library's hulls, :func:`identify` checks it);
* yaw (a first-order Nomoto model with the MMG's nonlinear steady turn):
  ``ṙ = (u κ(δ, ν) − r)/T_r(ν)``, ``κ = κ_max(ν) tanh(δ/δ_0(ν))``, ``ψ̇ = r``;
* surge: the MMG model's straight-run surge equation ``u̇ = f_u(u, n)`` (hull resistance, propeller thrust and rudder
  drag at zero rudder, exactly) less a loss in turns ``c_loss r²``;
* sway: the drift of a turning ship ``v = c_drift r`` (positions ``ẋ = u cos ψ − v sin ψ``,
  ``ẏ = u sin ψ + v cos ψ``);
* engine: the closed loop's engine (:func:`~mmg_casadi.vessel.actuators.engine_step`: a lag with a rate limit) as
  the smooth ``ν̇ = ρ tanh((ν_c − ν)/(T_e ρ))`` in the propeller loading ``ν = n/n_design``.

``κ_max, δ_0, T_r`` are fitted at two propeller loadings (:data:`LOADINGS`) and interpolated linearly in ν between
them (held outside); ``c_loss`` and ``c_drift`` are shared. :func:`identify` fits them by least squares (CasADi's
IPOPT) to the MMG model's responses to rudder steps of ±5°, ±10°, ±20°, ±35° held for 24 L/U from a steady straight
run at each loading (:data:`STEPS_DEG`); :attr:`ReducedModel.fit_rms` gives the residuals.

Examples
--------
>>> m = reduced_model("kcs")
>>> round(m.kappa_max[1], 2), round(m.t_yaw[1], 2)   # doctest: +SKIP
(0.68, 1.5)
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import casadi as ca
import numpy as np

from mmg_casadi.compiled import cache_dir
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import build_mmg, in_scene_units, rk4

LOADINGS: tuple[float, float] = (0.5, 1.0)
"""Propeller loadings ν = n/n_design at which the yaw coefficients are fitted."""
STEPS_DEG: tuple[float, ...] = (-35.0, -20.0, -10.0, -5.0, 5.0, 10.0, 20.0, 35.0)
"""Rudder steps (deg) of the identification."""
T_FIT = 24.0
"""Duration of each identification response (L/U): a 35° turn has settled."""
DT_FIT = 0.25
"""Sample interval of the responses (L/U), the closed loop's guidance step."""
SUB_FIT = 5
"""RK4 sub-steps of the MMG per sample."""


@dataclass(frozen=True)
class ReducedModel:
    """The identified prediction model of one hull in the scene's units (module notes).

    Parameters
    ----------
    vessel, unit : str
        The hull and the scene's unit hull (the own ship's).
    n_design : float
        The hull's design propeller speed (rev/min): ``ν = n/n_design``.
    t_delta, delta_max : float
        The steering gear's time constant (L/U) and saturation (rad).
    kappa_max, delta_0, t_yaw : tuple of float
        ``κ_max`` (1/L), ``δ_0`` (rad) and ``T_r`` (L/U) at each of :data:`LOADINGS`.
    c_loss, c_drift : float
        Speed loss in turns (U per (L/U) per (rad/(L/U))²) and drift per yaw rate (U per rad/(L/U)).
    fit_rms : dict
        Root-mean-square residuals of the fit: ``r`` (rad/(L/U)), ``u`` and ``v`` (U).
    """

    vessel: str
    unit: str
    n_design: float
    t_delta: float
    delta_max: float
    kappa_max: tuple
    delta_0: tuple
    t_yaw: tuple
    c_loss: float
    c_drift: float
    fit_rms: dict

    def surge(self):
        """The MMG model's straight-run surge acceleration ``f_u(u, ν)`` (U per L/U).

        Returns
        -------
        casadi.Function
            ``(u, nu) -> u_dot``.
        """
        return _surge_function(self.vessel, self.unit)

    def coefficients(self, nu):
        """``κ_max, δ_0, T_r`` at the propeller loading ``nu`` (linear between :data:`LOADINGS`, held outside).

        Parameters
        ----------
        nu : SX or float
            Propeller loading n/n_design.

        Returns
        -------
        tuple
            ``(κ_max, δ_0, T_r)``.
        """
        lo, hi = LOADINGS
        a = ca.fmin(ca.fmax((nu - lo) / (hi - lo), 0.0), 1.0)
        return tuple(c[0] + a * (c[1] - c[0]) for c in (self.kappa_max, self.delta_0, self.t_yaw))

    def rhs(self, s, delta_c, nu_c, engine_lag, engine_rate):
        """Right-hand side of the prediction model (CasADi expressions).

        Parameters
        ----------
        s : SX (7×1)
            State ``[x, y, ψ, r, δ, u, ν]`` (L, rad, rad/(L/U), rad, U, n/n_design).
        delta_c, nu_c : SX
            Rudder command (rad) and propeller command (n/n_design).
        engine_lag, engine_rate : SX or float
            The engine's time constant (L/U) and largest rate (n/n_design per L/U).

        Returns
        -------
        SX (7×1)
            ``ṡ``.
        """
        x, y, psi, r, delta, u, nu = (s[i] for i in range(7))
        k_max, d0, t_r = self.coefficients(nu)
        v = self.c_drift * r
        f_u = self.surge()(u, nu)
        rate = ca.fmax(engine_rate, 1e-6)
        return ca.vertcat(u * ca.cos(psi) - v * ca.sin(psi), u * ca.sin(psi) + v * ca.cos(psi), r,
                          (u * k_max * ca.tanh(delta / d0) - r) / t_r,
                          (delta_c - delta) / self.t_delta,
                          f_u - self.c_loss * r ** 2,
                          rate * ca.tanh((nu_c - nu) / (ca.fmax(engine_lag, 1e-3) * rate)))


NX = 7
"""Rows of the prediction model's state ``[x, y, ψ, r, δ, u, ν]``."""


def _mmg(vessel: str, unit: str) -> ca.Function:
    v = load_vessel(vessel)
    return in_scene_units(build_mmg(v.ship, v.steering), v.ship, load_vessel(unit).ship)


@functools.lru_cache(maxsize=None)
def _surge_function(vessel: str, unit: str) -> ca.Function:
    f = _mmg(vessel, unit)
    n_design = load_vessel(vessel).ship.n_design_rpm
    u, nu = ca.SX.sym("u"), ca.SX.sym("nu")
    xdot = f(ca.vertcat(u, 0, 0, 0, 0, 0, 0), 0.0, nu * n_design)
    return ca.Function(f"surge_{vessel}_{unit}", [u, nu], [xdot[0]], ["u", "nu"], ["udot"])


def steady_speed(vessel: str, unit: str, nu: float) -> float:
    """The straight-run steady speed (U of the scene) at propeller loading ``nu``, from the MMG surge equation.

    Parameters
    ----------
    vessel, unit : str
        The hull and the scene's unit hull.
    nu : float
        Propeller loading n/n_design.

    Returns
    -------
    float
        The speed at which ``f_u(u, ν) = 0``.

    Examples
    --------
    >>> round(steady_speed("kcs", "kcs", 1.0), 3)
    1.0
    """
    u = ca.SX.sym("u")
    g = ca.Function("g", [u], [_surge_function(vessel, unit)(u, nu)])
    return float(ca.rootfinder("speed", "newton", g, {"abstol": 1e-14})(nu))


def _responses(vessel: str, unit: str) -> list[dict]:
    """The MMG model's responses to the rudder steps at each loading (module notes)."""
    f = _mmg(vessel, unit)
    n_design = load_vessel(vessel).ship.n_design_rpm
    x, dc, n = ca.SX.sym("x", 7), ca.SX.sym("dc"), ca.SX.sym("n")
    xn = x
    for _ in range(SUB_FIT):
        xn = rk4(f, xn, (dc, n), DT_FIT / SUB_FIT)
    step = ca.Function("step", [x, dc, n], [xn])
    k = int(round(T_FIT / DT_FIT))
    roll = step.mapaccum(k)
    out = []
    for nu in LOADINGS:
        u0 = steady_speed(vessel, unit, nu)
        for deg in STEPS_DEG:
            X = np.array(roll(ca.DM([u0, 0, 0, 0, 0, 0, 0]), math.radians(deg), nu * n_design))
            out.append({"nu": nu, "u0": u0, "delta_c": math.radians(deg), "u": X[0], "v": X[1], "r": X[2],
                        "delta": X[6]})
    return out


@functools.lru_cache(maxsize=None)
def reduced_model(vessel: str = "kcs", unit: str | None = None) -> ReducedModel:
    """The identified prediction model of ``vessel`` in the units of ``unit``.

    The fit (:func:`identify`, some seconds) runs once per hull pair and machine: its result is kept in the
    compile cache (:func:`mmg_casadi.compiled.cache_dir`) under a key made of the hulls' coefficients, this module's
    source and the CasADi version, so a changed hull or fit is fitted again.

    Parameters
    ----------
    vessel : str, default 'kcs'
        A library hull.
    unit : str, optional
        The scene's unit hull (default ``vessel``).

    Returns
    -------
    ReducedModel
        The model (:func:`identify`).
    """
    unit = unit or vessel
    text = "\0".join([repr(load_vessel(vessel)), repr(load_vessel(unit)), Path(__file__).read_text(encoding="utf-8"),
                      ca.__version__])
    path = cache_dir() / f"nmpc_model_{vessel}_{unit}_{hashlib.sha256(text.encode()).hexdigest()[:16]}.json"
    try:
        return ReducedModel(**{k: tuple(v) if isinstance(v, list) else v
                               for k, v in json.loads(path.read_text(encoding="utf-8")).items()})
    except (OSError, ValueError, TypeError):
        pass
    model = identify(vessel, unit)
    tmp = path.with_name(f".{path.name}.{os.getpid()}")
    tmp.write_text(json.dumps(dataclasses.asdict(model)), encoding="utf-8")
    os.replace(tmp, path)  # atomic: a concurrent reader sees the whole file or none
    return model


def identify(vessel: str, unit: str) -> ReducedModel:
    """Fit the reduced model to the MMG model's rudder-step responses by least squares (module notes).

    The reduced model is rolled out on the responses' time grid with the MMG's own rudder angles (so the
    steering gear is not part of the fit) and a fixed propeller loading; residuals of ``r`` (weight 1/0.01),
    ``u`` and ``v`` (1/0.01) over every sample; IPOPT from a fixed start, so the fit is deterministic.

    Parameters
    ----------
    vessel, unit : str
        The hull and the scene's unit hull.

    Returns
    -------
    ReducedModel
        The fitted model with its residuals.
    """
    v = load_vessel(vessel)
    steering = v.steering
    rate_needed = 2.0 * steering.delta_max / steering.T_delta
    lam_mu = load_vessel(vessel).ship.L / load_vessel(unit).ship.L / (
        load_vessel(vessel).ship.U_design / load_vessel(unit).ship.U_design)
    t_delta = steering.T_delta * lam_mu  # the steering lag in scene time
    if rate_needed > steering.rate_max_nd(v.ship):
        raise ValueError(f"{vessel}: the steering gear's rate limit binds within ±δ_max; the reduced model's "
                         "linear steering gear does not hold")
    data = _responses(vessel, unit)
    surge = _surge_function(vessel, unit)
    th = ca.SX.sym("theta", 8)  # κ_max, δ_0, T_r at each loading; c_loss, c_drift
    res = []
    for d in data:
        j = LOADINGS.index(d["nu"])
        k_max, d0, t_r = th[3 * j], th[3 * j + 1], th[3 * j + 2]
        r, u = ca.SX(0.0), ca.SX(d["u0"])
        for i in range(len(d["r"])):
            delta = 0.5 * (d["delta"][i - 1] + d["delta"][i]) if i else 0.5 * d["delta"][0]
            for _ in range(2):  # two explicit midpoint sub-steps per sample (the fit's own integrator)
                h = DT_FIT / 2
                rm = r + 0.5 * h * (u * k_max * ca.tanh(delta / d0) - r) / t_r
                um = u + 0.5 * h * (surge(u, d["nu"]) - th[6] * r ** 2)
                r, u = (r + h * (um * k_max * ca.tanh(delta / d0) - rm) / t_r,
                        u + h * (surge(um, d["nu"]) - th[6] * rm ** 2))
            res += [(r - d["r"][i]) / 0.01, (u - d["u"][i]) / 0.01, (th[7] * r - d["v"][i]) / 0.01]
    R = ca.vertcat(*res)
    solver = ca.nlpsol("fit", "ipopt", {"x": th, "f": 0.5 * ca.sumsqr(R)},
                       {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-10})
    x0 = [0.7, 0.15, 1.5, 0.5, 0.15, 2.0, 0.3, -0.2]
    lbx = [1e-3, 1e-2, 0.05] * 2 + [0.0, -5.0]
    sol = solver(x0=x0, lbx=lbx, ubx=[10.0, 2.0, 50.0] * 2 + [10.0, 5.0])
    th_v = np.array(sol["x"]).ravel()
    r_all = np.array(ca.Function("r", [th], [R])(th_v)).ravel().reshape(-1, 3) * 0.01
    rms = {k: float(np.sqrt(np.mean(r_all[:, i] ** 2))) for i, k in enumerate(("r", "u", "v"))}
    return ReducedModel(vessel, unit, float(v.ship.n_design_rpm), float(t_delta), float(steering.delta_max),
                        (float(th_v[0]), float(th_v[3])), (float(th_v[1]), float(th_v[4])),
                        (float(th_v[2]), float(th_v[5])), float(th_v[6]), float(th_v[7]), rms)
