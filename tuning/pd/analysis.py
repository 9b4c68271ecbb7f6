"""Linear closed loop of the PD heading controller: poles, damping, stability margins and the heading step.

Control law (paper, section "Heading control"): ``δ_c = -K_p e - K_d r`` with ``e = ψ - ψ_d``, derivative on the
measured yaw rate; the rudder follows through the first-order steering gear (T_δ = 1), which is part of the linear
yaw model (:func:`~tuning.linear.yaw_subsystem`). Everything is non-dimensional in design-speed units (time
L/U_des, r in U_des/L).

Margins are those of the loop broken at the rudder command. Above the design speed the port-side model is
course-unstable (an open-loop pole at +0.048 at speed 1.2), so there the "gain margin" below 1 is the factor by
which the gains may be *reduced* before the loop goes unstable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control as ct
import numpy as np

from ..linear import YawModel

DT = 0.05  #: sample step of the linear, integration step of the nonlinear heading step (L/U_des)
SETTLING = 0.02  #: settling-time band (2 %)
PHASE_CROSSOVER_MAX = 1e4  #: phase crossovers beyond this (U_des/L) are numerical: the gain margin is infinite


def _gain_row(kp, kd) -> np.ndarray:
    return np.array([[0.0, kd, kp, 0.0]])


def closed_loop(model: YawModel, kp: float, kd: float) -> ct.StateSpace:
    """Linear closed loop ψ_d → (ψ, r, δ_c) of the yaw model with the PD (derivative on measured r).

    Parameters
    ----------
    model : YawModel
        Linear yaw subsystem (:func:`~tuning.linear.yaw_subsystem`).
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).

    Returns
    -------
    control.StateSpace
        The closed loop, input ``psi_d``, outputs ``psi``, ``r``, ``delta_c`` (design-speed units).

    Examples
    --------
    >>> from tuning.linear import yaw_subsystem
    >>> cl = closed_loop(yaw_subsystem(1.0), 3.5, 4.0)
    >>> bool(np.all(cl.poles().real < 0))
    True
    """
    K = _gain_row(kp, kd)
    return ct.ss(model.A - model.B @ K, model.B * kp, np.vstack([[0, 0, 1, 0], [0, 1, 0, 0], -K]),
                 [[0.0], [0.0], [kp]], inputs=["psi_d"], outputs=["psi", "r", "delta_c"], states=4)


def _loop_transfer(model: YawModel, kp: float, kd: float) -> ct.StateSpace:
    """Loop broken at the rudder command: δ_c → (K_p ψ + K_d r), steering gear included."""
    return ct.ss(model.A, model.B, _gain_row(kp, kd), 0.0)


@dataclass(frozen=True)
class StepResponse:
    """A heading step ``psi_d`` (rad): histories and the usual step metrics (overshoot in percent of the step,
    2 % settling and 10–90 % rise times in L/U_des, peak commanded rudder in degrees).

    Parameters
    ----------
    kind : str
        Model that produced the step, ``"linear"`` or ``"nonlinear"``.
    psi_d : float
        Heading step (rad; positive to starboard).
    t : ndarray
        Sample times (L/U_des).
    psi : ndarray
        Heading at ``t`` (rad).
    r : ndarray
        Yaw rate at ``t`` (U_des/L).
    delta_c : ndarray
        Commanded rudder angle at ``t`` (rad).
    delta : ndarray, optional
        Actual rudder angle at ``t`` (rad); None for the linear step.
    overshoot : float
        Overshoot in percent of the step (NaN if not computed).
    settling_time : float
        2 % settling time (L/U_des).
    rise_time : float
        10–90 % rise time (L/U_des).
    peak_rudder_deg : float
        Largest commanded rudder magnitude (degrees).
    """

    kind: str
    psi_d: float
    t: np.ndarray = field(repr=False)
    psi: np.ndarray = field(repr=False)
    r: np.ndarray = field(repr=False)
    delta_c: np.ndarray = field(repr=False)
    delta: np.ndarray | None = field(default=None, repr=False)
    overshoot: float = float("nan")
    settling_time: float = float("nan")
    rise_time: float = float("nan")
    peak_rudder_deg: float = float("nan")

    def to_dict(self) -> dict:
        return {"kind": self.kind, "step_deg": math.degrees(self.psi_d), "overshoot": self.overshoot,
                "settling_time": self.settling_time, "rise_time": self.rise_time,
                "peak_rudder_deg": self.peak_rudder_deg}


def _step_metrics(t, psi, psi_d) -> dict:
    try:
        info = ct.step_info(np.asarray(psi) / psi_d, timepts=t, final_output=1.0, SettlingTimeThreshold=SETTLING)
    except IndexError:  # the heading never rises through python-control's rise-time band: no step metrics
        return {"overshoot": math.nan, "settling_time": math.nan, "rise_time": math.nan}
    return {"overshoot": float(info["Overshoot"]), "settling_time": float(info["SettlingTime"]),
            "rise_time": float(info["RiseTime"])}


def _horizon(model: YawModel, kp: float, kd: float) -> float:
    slow = -np.max(np.linalg.eigvals(model.A - model.B @ _gain_row(kp, kd)).real)
    return float(np.clip(12.0 / slow, 30.0, 400.0)) if slow > 0 else 100.0


def linear_step(model: YawModel, kp: float, kd: float, step_deg: float = 10.0, t_end: float | None = None
                ) -> StepResponse:
    """Heading step of ``step_deg`` on the linear closed loop (steering gear included, no saturation).

    Parameters
    ----------
    model : YawModel
        Linear yaw subsystem (:func:`~tuning.linear.yaw_subsystem`).
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    step_deg : float
        Heading step (degrees; signed, positive to starboard).
    t_end : float, optional
        Horizon (L/U_des); by default 12 times the slowest closed-loop time constant, clipped to [30, 400]
        (100 if the loop is unstable).

    Returns
    -------
    StepResponse
        Heading, yaw rate and commanded rudder histories over time (L/U_des) with the step metrics (no actual
        rudder).
    """
    t_end = t_end or _horizon(model, kp, kd)
    t = np.arange(0.0, t_end + DT / 2, DT)
    psi_d = math.radians(step_deg)
    y = ct.step_response(closed_loop(model, kp, kd), timepts=t).outputs[:, 0, :] * psi_d
    dc = y[2]
    return StepResponse("linear", psi_d, t, y[0], y[1], dc, None, **_step_metrics(t, y[0], psi_d),
                        peak_rudder_deg=float(np.degrees(np.max(np.abs(dc)))))


@dataclass(frozen=True)
class LoopAnalysis:
    """Closed-loop properties of the linear yaw model under a PD.

    Poles with their natural frequencies and damping ratios (``control.damp``); the dominant pole or pair (largest
    real part); gain margin (absolute, ``inf`` when the phase never reaches -180°) and phase margin (deg) of the
    loop broken at the rudder command, steering gear included; metrics of a linear heading step of ``step_deg``.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    poles : tuple of complex
        Closed-loop poles (U_des/L), largest real part first.
    wn : tuple of float
        Natural frequency of each pole (U_des/L).
    zeta : tuple of float
        Damping ratio of each pole.
    dominant_wn : float
        Natural frequency of the dominant pole or pair (U_des/L).
    dominant_zeta : float
        Damping ratio of the dominant pole or pair, capped at 1.
    gain_margin : float
        Gain margin (absolute factor; ``inf`` when the phase never reaches -180°).
    phase_margin : float
        Phase margin (degrees).
    w_phase_crossover : float
        Phase-crossover frequency (U_des/L); NaN when there is none.
    w_gain_crossover : float
        Gain-crossover frequency (U_des/L).
    stable : bool
        Whether every closed-loop pole has a negative real part.
    step : StepResponse
        Linear heading step of ``step_deg`` (empty histories when the loop is unstable).
    """

    kp: float
    kd: float
    poles: tuple
    wn: tuple
    zeta: tuple
    dominant_wn: float
    dominant_zeta: float
    gain_margin: float
    phase_margin: float
    w_phase_crossover: float
    w_gain_crossover: float
    stable: bool
    step: StepResponse = field(repr=False)

    @property
    def overshoot(self) -> float:
        return self.step.overshoot

    @property
    def settling_time(self) -> float:
        return self.step.settling_time

    def to_dict(self) -> dict:
        def fin(x):
            return None if not np.isfinite(x) else float(x)
        return {"kp": self.kp, "kd": self.kd, "poles": [[float(p.real), float(p.imag)] for p in self.poles],
                "pole_wn": list(self.wn), "pole_zeta": list(self.zeta), "dominant_wn": self.dominant_wn,
                "dominant_zeta": self.dominant_zeta, "gain_margin": fin(self.gain_margin),
                "gain_margin_db": fin(20 * math.log10(self.gain_margin)) if self.gain_margin > 0 else None,
                "phase_margin": fin(self.phase_margin), "w_phase_crossover": fin(self.w_phase_crossover),
                "w_gain_crossover": fin(self.w_gain_crossover), "stable": self.stable,
                "overshoot": self.step.overshoot, "settling_time": self.step.settling_time,
                "rise_time": self.step.rise_time, "peak_rudder_deg": self.step.peak_rudder_deg}


def analyse_loop(model: YawModel, kp: float, kd: float, step_deg: float = 10.0) -> LoopAnalysis:
    """Poles, damping, margins and linear step of the PD loop on ``model``.

    Parameters
    ----------
    model : YawModel
        Linear yaw subsystem (:func:`~tuning.linear.yaw_subsystem`).
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    step_deg : float
        Heading step (degrees) of the linear step response.

    Returns
    -------
    LoopAnalysis
        Poles, natural frequencies (U_des/L), damping ratios, the dominant ones, gain and phase margins (deg),
        crossover frequencies, stability and the linear step (empty when unstable).

    Examples
    --------
    >>> from tuning.linear import yaw_subsystem
    >>> a = analyse_loop(yaw_subsystem(1.0), 3.5, 4.0)
    >>> a.stable, round(a.dominant_zeta, 2), round(a.overshoot, 1)
    (True, 0.32, 10.9)
    """
    cl = closed_loop(model, kp, kd)
    wn, zeta, poles = ct.damp(cl, doprint=False)
    order = np.argsort(-poles.real)
    poles, wn, zeta = poles[order], wn[order], zeta[order]
    gm, pm, _, wpc, wgc, _ = ct.stability_margins(_loop_transfer(model, kp, kd), returnall=False)
    if wpc > PHASE_CROSSOVER_MAX:  # the loop's phase only tends to -180° as ω → ∞: no finite crossover
        gm, wpc = float("inf"), float("nan")
    stable = bool(np.all(poles.real < 0))
    step = linear_step(model, kp, kd, step_deg) if stable else StepResponse(
        "linear", math.radians(step_deg), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0))
    return LoopAnalysis(float(kp), float(kd), tuple(complex(p) for p in poles), tuple(float(w) for w in wn),
                        tuple(float(z) for z in zeta), float(wn[0]), float(min(zeta[0], 1.0)), float(gm),
                        float(pm), float(wpc), float(wgc), stable, step)
