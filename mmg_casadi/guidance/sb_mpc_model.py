"""The own-ship prediction of ``sb-mpc``: a reduced model of the closed loop's heading and speed response,
identified from the MMG model with the toolkit's own simulation.

A control behaviour of the scenario-based MPC (:mod:`mmg_casadi.guidance.sb_mpc`) is a course and a propeller
speed held over the horizon. Johansen, Perez & Cristofaro (2016, IEEE T-ITS 17(12), §III) predict the own ship by
simulating her model under her autopilot; here the model is reduced to what decides a passing distance, the
heading and speed response under the closed loop's PD heading controller
(:func:`~mmg_casadi.guidance.heading_control.pd_heading`, the step's gains ``kp``, ``kd``, ``delta_max``):

* **Heading**, first-order Nomoto with the PD law and the rudder saturation (eq. nomoto)::

      δ = sat(−K_p wrap(ψ − χ_b) − K_d r τ, δ_max)
      ṙ = (K' u² δ / λ − u r) / (T' λ)

  K', T' are the Nomoto gain and time constant in the ship's own units at her design speed; a ship at speed u
  (scene U) turns u times as fast and answers the rudder with u² times the force (K = K' U/L, T = T' L/U);
  ``λ, μ`` are her length and design speed in the scene's units (:func:`~mmg_casadi.vessel.mmg.scene_scales`;
  1 and 1 for the scene's own hull) and ``τ = λ/μ`` her time unit, with which the closed loop's PD sees her yaw
  rate.
* **Speed**, first order towards the behaviour's steady speed with a loss in turns (eq. speed)::

      u̇ = (U_b − u) / (T_u τ) − a λ r²

  U_b is the steady speed of the behaviour's propeller speed (proportional to it in this model,
  :func:`~mmg_casadi.guidance.velocity_obstacle.speed_levels`); T_u lumps the engine's rate limit and lag with
  the hull's surge response; ``a`` the speed a turning ship loses (the KCS keeps 72 % of her speed in a 90°
  alteration under the PD).
* **Position**: ẋ = u cos ψ, ẏ = u sin ψ (the drift angle is neglected: the velocity is along the heading).

The equations are integrated with explicit Euler steps of ``h`` (the default prediction: 15 samples over 15 L/U,
two steps per sample, h = 0.5 L/U).

**Identification** (:func:`identify_reduced_model`): the MMG model of the vessel
(:func:`~mmg_casadi.vessel.mmg.build_mmg`, RK4 at the guidance step) under the PD heading controller with the table's
default gains and the engine
model (:func:`~mmg_casadi.vessel.actuators.engine_step`) sails, from steady running at her design speed, each
course alteration of 0°, ±30°, ±60°, ±90° at each propeller order of full, half and dead slow ahead for 20 L/U;
(K', T', T_u, a) are the least-squares fit (``scipy.optimize.least_squares``) of this module's predictor, with the
same Euler step as the default prediction (:data:`IDENTIFY_STEP`), to the simulated positions and headings every
0.5 L/U (a heading error of 1 rad weighted as 5 L). The fitted
constants of the library's hulls are stored (:data:`REDUCED_MODELS`, rounded to four significant digits, so a
compiled step never depends on the last bits of a fit) and a test identifies them again.

Examples
--------
>>> m = reduced_model("kcs")
>>> m.nomoto_k > 0 and m.nomoto_t > 0 and m.speed_t > 0
True
>>> out = predict(m, psi0=0.0, u0=1.0, course=math.radians(60.0), speed=1.0, horizon=20.0, samples=40)
>>> round(math.degrees(float(out["psi"][-1])), 1)  # the alteration is complete within the horizon
60.0
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mmg_casadi.guidance.heading_control import pd_heading
from mmg_casadi.guidance.ilos import wrap_angle
from mmg_casadi.params import PARAMETERS
from mmg_casadi.vessel.actuators import engine_step, saturate
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import build_mmg, propeller_rpm_for_speed, rk4

SUBSTEPS = 2
"""Euler steps per prediction sample (h = horizon / (samples · SUBSTEPS))."""

U_FLOOR = 0.05
"""Speed floor (U) of the predictor's turning terms (a ship at rest does not turn)."""

IDENTIFY_COURSES_DEG = (0.0, 30.0, -30.0, 60.0, -60.0, 90.0, -90.0)
"""Course alterations of the identification runs (degrees)."""

IDENTIFY_LEVELS = (1.0, 0.5, 0.0)
"""Propeller orders of the identification runs, fractions of the design rpm (0: dead slow ahead, the engine's
floor ``engine_dead_slow``)."""

IDENTIFY_HORIZON = 20.0
"""Duration of each identification run (L/U), the default prediction horizon."""

SIMULATION_STEP = 0.25
"""Step of the identification's MMG simulation (L/U), the closed loop's guidance step."""

IDENTIFY_STEP = 0.5
"""Euler step of the predictor in the fit (L/U), the default prediction's (15 L/U, 15 samples, 2 steps each); the
simulated runs are compared with it every 0.5 L/U."""

HEADING_WEIGHT = 5.0
"""Weight of a heading error (per rad) against a position error (per L) in the fit."""


@dataclass(frozen=True)
class ReducedModel:
    """Constants of the reduced own-ship model (module notes), in the ship's own units (L, U_des, L/U_des).

    Parameters
    ----------
    nomoto_k : float
        Nomoto gain K' (rad per L/U of steady yaw rate per rad of rudder, at the design speed).
    nomoto_t : float
        Nomoto time constant T' (L/U, at the design speed).
    speed_t : float
        Time constant T_u of the speed response to a propeller order (L/U).
    turn_loss : float
        Speed loss coefficient ``a`` in turns (U per (rad per L/U)² per L/U).
    source : str
        Where the numbers come from.
    """

    nomoto_k: float
    nomoto_t: float
    speed_t: float
    turn_loss: float
    source: str = ""

    def as_vector(self) -> list:
        """``[K', T', T_u, a]``, the order of :func:`predict_function`'s model input.

        Returns
        -------
        list of float
            The four constants.
        """
        return [self.nomoto_k, self.nomoto_t, self.speed_t, self.turn_loss]


REDUCED_MODELS: dict[str, ReducedModel] = {
    "kcs": ReducedModel(0.6437, 1.294, 9.826, 0.6346,
                        "identify_reduced_model('kcs'): MMG of data/kcs_mmg.toml under the default PD, 21 runs; "
                        "position error 0.36 L rms, 1.1 L at most over 20 L/U"),
    "kvlcc2": ReducedModel(0.7451, 1.55, 10.85, 0.7288,
                           "identify_reduced_model('kvlcc2'): MMG of data/kvlcc2_mmg.toml under the default PD, "
                           "21 runs; position error 0.36 L rms, 1.4 L at most over 20 L/U"),
}
"""The identified constants of the library's hulls (:func:`identify_reduced_model`, four significant digits)."""


def _round4(x: float) -> float:
    return float(f"{x:.4g}")


@functools.lru_cache(maxsize=None)
def reduced_model(vessel: str) -> ReducedModel:
    """The reduced model of ``vessel``: the stored constants of a library hull, else identified once per process.

    Parameters
    ----------
    vessel : str
        A vessel name or data file (:func:`~mmg_casadi.vessel.library.load_vessel`).

    Returns
    -------
    ReducedModel
        Its constants (four significant digits).
    """
    if vessel in REDUCED_MODELS:
        return REDUCED_MODELS[vessel]
    fit = identify_reduced_model(vessel)
    return ReducedModel(*(_round4(v) for v in fit["model"].as_vector()), source=f"identify_reduced_model({vessel!r})")


@functools.lru_cache(maxsize=None)
def predict_function(samples: int, substeps: int = SUBSTEPS) -> ca.Function:
    """The predictor of one behaviour as a Function (module notes, eqs. nomoto and speed).

    ``sbmpc_predict_n<samples>(state, order, model, gains) -> (x, y, vx, vy, psi)``:

    * ``state`` = [ψ0, r0, u0] (rad, rad per scene time, scene U), the own ship at the decision;
    * ``order`` = [χ_b, U_b, h] the course (rad) and steady speed (scene U) of the behaviour and the Euler step
      (scene time; a sample every ``substeps`` steps);
    * ``model`` = [K', T', T_u, a, λ, μ] (:class:`ReducedModel` and :func:`~mmg_casadi.vessel.mmg.scene_scales`);
    * ``gains`` = [K_p, K_d, δ_max] of the closed loop's PD;

    the outputs are rows (1 × samples) of the positions relative to the start, the velocity, the heading and the
    speed at the end of each sample.

    Parameters
    ----------
    samples : int
        Prediction samples.
    substeps : int, default SUBSTEPS
        Euler steps per sample.

    Returns
    -------
    casadi.Function
        The predictor (SX, one behaviour).
    """
    state, order, model, gains = ca.SX.sym("state", 3), ca.SX.sym("order", 3), ca.SX.sym("model", 6), \
        ca.SX.sym("gains", 3)
    psi0, r, u = state[0], state[1], state[2]
    chi, u_b, h = order[0], order[1], order[2]
    k, t, t_u, a, lam, mu = (model[i] for i in range(6))
    kp, kd, dmax = gains[0], gains[1], gains[2]
    tau = lam / mu
    e = wrap_angle(psi0 - chi)  # heading error, continuous from here on
    c, s = ca.cos(psi0), ca.sin(psi0)  # heading direction, turned by each step's rotation (no trigonometry)
    x = y = ca.SX(0)
    xs, ys, vxs, vys, psis, us = [], [], [], [], [], []
    for _ in range(samples):
        for _ in range(substeps):
            uf = ca.fmax(u, U_FLOOR)
            delta = saturate(-kp * e - kd * r * tau, dmax)  # the closed loop's PD
            r_dot = (k * uf * uf * delta / lam - uf * r) / (t * lam)  # eq. nomoto
            u_dot = (u_b - u) / (t_u * tau) - a * lam * r * r  # eq. speed
            x = x + h * u * c
            y = y + h * u * s
            th = h * r
            th2 = th * th
            cos_th, sin_th = 1 - th2 / 2 + th2 * th2 / 24, th * (1 - th2 / 6 + th2 * th2 / 120)
            c, s = c * cos_th - s * sin_th, s * cos_th + c * sin_th
            e = e + th
            r = r + h * r_dot
            u = ca.fmax(u + h * u_dot, 0)
        xs.append(x)
        ys.append(y)
        vxs.append(u * c)
        vys.append(u * s)
        psis.append(chi + e)
        us.append(u)
    rows = [ca.horzcat(*v) for v in (xs, ys, vxs, vys, psis, us)]
    return ca.Function(f"sbmpc_predict_n{samples}_s{substeps}", [state, order, model, gains], rows,
                       ["state", "order", "model", "gains"], ["x", "y", "vx", "vy", "psi", "u"], {"cse": True})


def _default_gains() -> list:
    return [PARAMETERS["kp"].default, PARAMETERS["kd"].default, math.radians(PARAMETERS["delta_max_deg"].default)]


def predict(model: ReducedModel, *, psi0: float, u0: float, course: float, speed: float, horizon: float,
            samples: int, r0: float = 0.0, scales=(1.0, 1.0), gains=None) -> dict:
    """The predicted track of one behaviour, as numbers (:func:`predict_function`).

    Parameters
    ----------
    model : ReducedModel
        The own ship's reduced model.
    psi0, u0 : float
        Heading (rad) and speed (scene U) at the decision.
    course, speed : float
        The behaviour's course (rad) and steady speed (scene U).
    horizon : float
        Prediction horizon (scene time).
    samples : int
        Samples over the horizon.
    r0 : float, default 0
        Yaw rate at the decision (rad per scene time).
    scales : tuple of float, default (1, 1)
        ``(λ, μ)`` of the hull in the scene.
    gains : sequence of float, optional
        ``[K_p, K_d, δ_max]`` (default: the table's).

    Returns
    -------
    dict
        ``t`` (samples,), ``x``, ``y`` (relative to the start), ``vx``, ``vy``, ``psi``, ``u`` as numpy arrays.
    """
    f = predict_function(int(samples))
    h = float(horizon) / (int(samples) * SUBSTEPS)
    out = f([psi0, r0, u0], [course, speed, h], model.as_vector() + list(scales),
            list(gains) if gains is not None else _default_gains())
    res = {k: np.array(v).ravel() for k, v in zip(("x", "y", "vx", "vy", "psi", "u"), out)}
    res["t"] = float(horizon) / int(samples) * np.arange(1, int(samples) + 1)
    return res


def _simulated_runs(vessel: str, step: float = SIMULATION_STEP, horizon: float = IDENTIFY_HORIZON) -> list:
    """The identification runs of ``vessel`` (module notes): per run the course (rad), steady speed of the order
    (U) and the simulated positions and headings at every step after the start ((n, 3): x, y, ψ)."""
    v = load_vessel(vessel)
    ship = v.ship
    f = build_mmg(ship, v.steering)
    n0 = propeller_rpm_for_speed(1.0, ship)
    rate = PARAMETERS["engine_rate_rpm_s"].default * ship.time_scale_s
    lag = PARAMETERS["engine_lag_s"].default / ship.time_scale_s
    dead_slow = PARAMETERS["engine_dead_slow"].default * ship.n_design_rpm
    kp, kd, dmax = _default_gains()
    x, psi_d, n_c = ca.SX.sym("x", 8), ca.SX.sym("psi_d"), ca.SX.sym("n_c")
    dc = pd_heading(x[5], psi_d, x[2], kp, kd, dmax)
    nxt = ca.vertcat(rk4(f, x[:7], (dc, x[7]), step), engine_step(x[7], n_c, rate, step, lag))
    n_steps = int(round(horizon / step))
    roll = ca.Function("sbmpc_identify_step", [x, psi_d, n_c], [nxt]).mapaccum(n_steps)
    runs = []
    for course_deg in IDENTIFY_COURSES_DEG:
        for level in IDENTIFY_LEVELS:
            order = max(level * n0, dead_slow)
            X = np.array(roll([1.0, 0, 0, 0, 0, 0, 0, n0], math.radians(course_deg), order))
            runs.append((math.radians(course_deg), order / n0, X[[3, 4, 5], :].T))
    return runs


def identify_reduced_model(vessel: str = "kcs") -> dict:
    """Fit the reduced model of ``vessel`` to its MMG model under the closed loop's PD (module notes).

    Parameters
    ----------
    vessel : str, default "kcs"
        A vessel name or data file.

    Returns
    -------
    dict
        ``model`` (:class:`ReducedModel`, unrounded), ``rms_position`` (L), ``max_position`` (L) and
        ``max_heading_deg``: the fit's errors over every run and step.
    """
    from scipy.optimize import least_squares  # only the fit needs scipy

    every = int(round(IDENTIFY_STEP / SIMULATION_STEP))
    runs = [(c, v, sim[every - 1::every]) for c, v, sim in _simulated_runs(vessel)]
    n = runs[0][2].shape[0]
    f = predict_function(n, 1)
    gains = _default_gains()

    def track(theta, course, speed):
        out = f([0.0, 0.0, 1.0], [course, speed, IDENTIFY_STEP], list(theta) + [1.0, 1.0], gains)
        return np.column_stack([np.array(out[0]).ravel(), np.array(out[1]).ravel(), np.array(out[4]).ravel()])

    def residuals(theta):
        res = []
        for course, speed, sim in runs:
            d = track(theta, course, speed) - sim
            res += [d[:, 0], d[:, 1], HEADING_WEIGHT * d[:, 2]]
        return np.concatenate(res)

    sol = least_squares(residuals, [0.5, 1.5, 10.0, 0.5], bounds=([1e-3, 1e-2, 0.1, 0.0], [10.0, 50.0, 200.0, 10.0]),
                        x_scale="jac")
    pos, head = [], []
    for course, speed, sim in runs:
        d = track(sol.x, course, speed) - sim
        pos.append(np.hypot(d[:, 0], d[:, 1]))
        head.append(np.abs(d[:, 2]))
    pos, head = np.concatenate(pos), np.concatenate(head)
    return {"model": ReducedModel(*map(float, sol.x), source=f"identify_reduced_model({vessel!r})"),
            "rms_position": float(np.sqrt(np.mean(pos ** 2))), "max_position": float(pos.max()),
            "max_heading_deg": float(np.degrees(head.max()))}
