"""PD heading-controller design from the linear yaw model, checked on the nonlinear model.

Control law (paper, section "Heading control"): ``δ_c = -K_p e - K_d r`` with ``e = ψ - ψ_d``, saturated at
±35°, derivative on the measured yaw rate; the rudder follows through the first-order steering gear
(T_δ = 1). Everything is non-dimensional in design-speed units (time L/U_des, r in U_des/L).

Two design methods:

``"nomoto"``
    the textbook first-order Nomoto design ``ψ/δ = K/(s(1 + T s))``: ``K_p = T ω_n²/K``,
    ``K_d = (2 ζ ω_n T - 1)/K``. It ignores the steering gear and the second-order yaw dynamics, so the
    closed loop of the full model misses the specified damping (ζ = 0.31 instead of 0.8 at ω_n = 1.43, speed 1).
``"placement"`` (default)
    exact placement of the pair ``s² + 2ζω_n s + ω_n²`` on the full linear model (v, r, ψ, δ with the steering
    gear). The closed-loop characteristic polynomial is ``a(s) + (K_d s + K_p) n(s)`` (``a`` the open-loop
    polynomial, ``n`` the numerator of ψ/δ_c), affine in the gains, so requiring the remainder of its division
    by the pair's quadratic to vanish is a 2x2 linear system. The two remaining poles land where they land;
    the pair is *dominant* when they are at least :data:`DOMINANCE` times faster than its slowest pole.

Default ω_n (neither ``wn`` nor ``settling_time`` given): the largest ω_n for which the gains are admissible
(K_p > 0, K_d ≥ 0) and (a) a heading step of ``step_deg`` (10°) does not saturate the rudder and (b), for
``"placement"``, the designed pair stays dominant. With the derivative acting on the measured yaw rate the
command peaks at the instant of the step, ``|δ_c|max = K_p |Δψ_d|``, so (a) is ``K_p ≤ 35°/10° = 3.5`` (for
``"nomoto"``: ``ω_n = √(3.5 K/T)``); the peak is re-checked on the linear step response and reported as
``peak_rudder_deg``. For ``"placement"`` (b) binds at speeds from about 0.4 up: with a unit steering-gear lag a
PD cannot give a dominant, well-damped pair much faster than ω_n ≈ 0.5 (``wn_source`` says which limit bound,
``limits`` holds each limit alone). At very low speed (0.2) no ω_n meets both, the rudder is too weak for a
K_p ≤ 3.5 design with K_d ≥ 0; the dominance limit is used and :attr:`PdDesign.saturates` is true.

Margins are those of the loop broken at the rudder command. Above the design speed the port-side model is
course-unstable (an open-loop pole at +0.048 at speed 1.2), so there the "gain margin" below 1 is the factor by
which the gains may be *reduced* before the loop goes unstable.

The paper's gains K_p = 3.5, K_d = 4 are exactly the ``"nomoto"`` design with ζ ≈ 0.8 and the no-saturation
ω_n at the design speed; on the full model their dominant pair has ζ ≈ 0.32 (:func:`paper_gains_map`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import control as ct
import numpy as np
from matplotlib.figure import Figure

from mmg_casadi.closed_loop.compiled import compile_function
from mmg_casadi.guidance.heading_control import pd_heading
from mmg_casadi.errors import ParameterError, check_range
from mmg_casadi.vessel.mmg import NX, STATE_NAMES, build_mmg, propeller_rpm_for_speed, rk4
from mmg_casadi.vessel.ship import load_kcs, load_steering

from .linear import YawModel, nomoto_first_order, yaw_subsystem

METHODS = ("placement", "nomoto")
DOMINANCE = 1.5  #: remaining poles at least this many times faster than the designed pair's slowest pole
DELTA_MAX_DEG = 35.0
PAPER_GAINS = (3.5, 4.0)
DT = 0.05  #: integration step of the nonlinear heading step (L/U_des)
SETTLING = 0.02  #: settling-time band (2 %)
PHASE_CROSSOVER_MAX = 1e4  #: phase crossovers beyond this (U_des/L) are numerical: the gain margin is infinite


@dataclass(frozen=True)
class PdSpec:
    """Design specification.

    Parameters
    ----------
    zeta : float
        Damping ratio of the designed pair, in (0, 2].
    wn : float, optional
        Natural frequency (U_des/L). At most one of ``wn`` and ``settling_time``.
    settling_time : float, optional
        2 % settling time of the pair (L/U_des); ``wn = 4/(ζ t_s)``.
    max_overshoot : float, optional
        Percent; raises ζ to ``-ln(OS)/√(π² + ln²(OS))`` if that is larger than ``zeta``.
    method : {"placement", "nomoto"}
        Design method (module docstring).
    step_deg : float
        Heading step (deg) that must not saturate the rudder under the default ω_n.

    Examples
    --------
    >>> round(PdSpec(zeta=0.5, max_overshoot=1.0).effective_zeta, 3)
    0.826
    """

    zeta: float = 0.8
    wn: float | None = None
    settling_time: float | None = None
    max_overshoot: float | None = None
    method: str = "placement"
    step_deg: float = 10.0

    def __post_init__(self):
        check_range("zeta", self.zeta, 0.0, 2.0, low_open=True)
        if self.wn is not None and self.settling_time is not None:
            raise ParameterError("wn", "not together with settling_time (give at most one)", self.wn)
        if self.wn is not None:
            check_range("wn", self.wn, 0.0, None, low_open=True, unit="(U_des/L)")
        if self.settling_time is not None:
            check_range("settling_time", self.settling_time, 0.0, None, low_open=True, unit="(L/U_des)")
        if self.max_overshoot is not None:
            check_range("max_overshoot", self.max_overshoot, 0.0, 100.0, low_open=True, high_open=True,
                        unit="percent")
        if self.method not in METHODS:
            raise ParameterError("method", f"one of: {', '.join(METHODS)}", self.method)
        check_range("step_deg", self.step_deg, 0.0, 180.0, low_open=True, unit="degrees")

    @property
    def effective_zeta(self) -> float:
        """``zeta``, raised if needed so that the second-order overshoot stays below ``max_overshoot``."""
        if self.max_overshoot is None:
            return float(self.zeta)
        lo = math.log(self.max_overshoot / 100.0)
        return max(float(self.zeta), -lo / math.sqrt(math.pi**2 + lo**2))


def second_order_overshoot(zeta: float) -> float:
    """Percent overshoot of the standard second-order step, ``100 exp(-πζ/√(1-ζ²))`` (0 for ζ ≥ 1).

    Parameters
    ----------
    zeta : float
        Damping ratio.

    Examples
    --------
    >>> round(second_order_overshoot(0.8), 2), second_order_overshoot(1.0)
    (1.52, 0.0)
    """
    return 0.0 if zeta >= 1.0 else 100.0 * math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2))


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

    Examples
    --------
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
    info = ct.step_info(np.asarray(psi) / psi_d, timepts=t, final_output=1.0, SettlingTimeThreshold=SETTLING)
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

    Examples
    --------
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


def _polys(model: YawModel):
    """Open-loop characteristic polynomial ``a`` and numerator ``n`` of ψ/δ_c (highest power first)."""
    a = np.real(np.poly(model.A))
    n = np.real(np.poly(model.A - model.B @ np.array([[0.0, 0.0, 1.0, 0.0]]))) - a
    return a, np.trim_zeros(np.where(np.abs(n) < 1e-12 * np.max(np.abs(n)), 0.0, n), "f")


def place_pair(model: YawModel, zeta: float, wn: float) -> tuple[float, float]:
    """Gains ``(K_p, K_d)`` that put the pair ``s² + 2ζω_n s + ω_n²`` among the closed-loop poles of ``model``.

    Parameters
    ----------
    model : YawModel
        Linear yaw subsystem (:func:`~tuning.linear.yaw_subsystem`).
    zeta : float
        Damping ratio of the pair.
    wn : float
        Natural frequency of the pair (U_des/L).

    Examples
    --------
    >>> m = yaw_subsystem(1.0)
    >>> kp, kd = place_pair(m, 0.8, 0.4)
    >>> p = closed_loop(m, kp, kd).poles()
    >>> bool(np.min(np.abs(p - (-0.32 + 0.24j))) < 1e-9)
    True
    """
    a, n = _polys(model)
    return _place(a, n, zeta, wn)


def _place(a, n, zeta, wn) -> tuple[float, float]:
    q = [1.0, 2.0 * zeta * wn, wn**2]

    def rem(poly):
        r = np.polydiv(poly, q)[1]
        return np.concatenate([np.zeros(2 - len(r)), r])

    M = np.column_stack([rem(np.polymul(n, [1.0, 0.0])), rem(n)])
    try:
        kd, kp = np.linalg.solve(M, -rem(a))
    except np.linalg.LinAlgError:
        raise ParameterError("wn", "a natural frequency at which the pair can be placed", wn) from None
    return float(kp), float(kd)


def _remaining_poles(a, n, kp, kd, zeta, wn) -> np.ndarray:
    p = np.polyadd(a, np.polymul([kd, kp], n))
    return np.roots(np.polydiv(p, [1.0, 2.0 * zeta * wn, wn**2])[0])


def _slowest_designed(zeta, wn) -> float:
    return wn * (zeta - math.sqrt(max(zeta**2 - 1.0, 0.0)))


def _nomoto_gains(K, T, zeta, wn):
    return T * wn**2 / K, (2.0 * zeta * wn * T - 1.0) / K


def _largest(pred, lo=0.005, hi=5.0, n=160) -> float | None:
    """Largest ω_n of the first run of a grid on which ``pred`` holds, refined by bisection."""
    grid = np.geomspace(lo, hi, n)
    ok = np.array([pred(w) for w in grid])
    if not ok.any():
        return None
    first = int(np.argmax(ok))
    bad = np.nonzero(~ok[first:])[0]
    if bad.size == 0:
        return float(grid[-1])
    a, b = grid[first + bad[0] - 1], grid[first + bad[0]]
    for _ in range(40):
        m = 0.5 * (a + b)
        a, b = (m, b) if pred(m) else (a, m)
    return float(a)


def wn_limits(model: YawModel, zeta: float, method: str = "placement", step_deg: float = 10.0) -> dict:
    """Largest ω_n (of the first admissible run, K_p > 0 and K_d ≥ 0) meeting each default-ω_n limit.

    ``"saturation"``: no rudder saturation for a ``step_deg`` heading step (K_p ≤ 35°/step); ``"dominance"``
    (placement only): the remaining poles at least :data:`DOMINANCE` times faster than the designed pair;
    ``"both"``: both at once (None if none does).

    Parameters
    ----------
    model : YawModel
        Linear yaw subsystem (:func:`~tuning.linear.yaw_subsystem`).
    zeta : float
        Damping ratio of the designed pair.
    method : {"placement", "nomoto"}
        Design method (module docstring); ``"nomoto"`` has only the saturation limit.
    step_deg : float
        Heading step (degrees) that must not saturate the rudder.

    Examples
    --------
    >>> lim = wn_limits(yaw_subsystem(1.0), 0.8, "nomoto")
    >>> round(lim["saturation"], 3)                 # √(3.5 K/T)
    1.426
    """
    kp_max = DELTA_MAX_DEG / step_deg
    if method == "nomoto":
        nom = nomoto_first_order(model)
        w = math.sqrt(kp_max * nom.K / nom.T)
        return {"saturation": w, "dominance": None, "both": w}

    a, n = _polys(model)
    memo: dict = {}

    def flags(w):
        """(no saturation, dominant pair), both False when the gains are not admissible."""
        if w not in memo:
            kp, kd = _place(a, n, zeta, w)
            if kp > 0 and kd >= 0:
                rest = _remaining_poles(a, n, kp, kd, zeta, w)
                memo[w] = (kp <= kp_max, bool(np.all(-rest.real >= DOMINANCE * _slowest_designed(zeta, w))))
            else:
                memo[w] = (False, False)
        return memo[w]

    def sat(w):
        return flags(w)[0]

    def dom(w):
        return flags(w)[1]

    def both(w):
        return all(flags(w))

    return {"saturation": _largest(sat), "dominance": _largest(dom), "both": _largest(both)}


@dataclass(frozen=True)
class PdDesign:
    """A PD design (or an analysed pair of given gains) on the linear yaw model.

    ``zeta``/``wn`` are the specified (``"placement"``, ``"nomoto"``) or, for ``method="given"``, the
    first-order-Nomoto-equivalent values ``ω_n = √(K_p K/T)``, ``ζ = (1 + K K_d)/(2 ω_n T)``. ``wn_source`` says
    where ω_n came from (``"spec"``, ``"settling_time"``, ``"saturation"``, ``"dominance"``, ``"gains"``).
    ``kp_nomoto``/``kd_nomoto`` are the first-order Nomoto gains for the same ζ, ω_n and ``nomoto_loop`` their
    analysis on the full model. ``predicted_overshoot`` is the second-order formula for ``zeta``.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    method : str
        ``"placement"``, ``"nomoto"`` or ``"given"`` (gains analysed, not designed).
    zeta : float
        Damping ratio (specified, or Nomoto-equivalent for ``"given"``).
    wn : float
        Natural frequency (U_des/L).
    wn_source : str
        Where ω_n came from: ``"spec"``, ``"settling_time"``, ``"saturation"``, ``"dominance"`` or ``"gains"``.
    speed : float
        Speed of the linear model, fraction of the design speed.
    side : str
        Linearised side of the γ_R switch (``"port"``, ``"starboard"`` or ``"mean"``).
    nomoto_K : float
        First-order Nomoto gain K of the model (design-speed units, U_des/L per rad).
    nomoto_T : float
        First-order Nomoto time constant T of the model (L/U_des).
    kp_nomoto : float
        First-order Nomoto design's K_p for the same ζ and ω_n.
    kd_nomoto : float
        First-order Nomoto design's K_d for the same ζ and ω_n.
    predicted_overshoot : float
        Second-order overshoot for ``zeta`` (percent).
    loop : LoopAnalysis
        Analysis of the loop with ``kp``, ``kd`` on the full linear model.
    nomoto_loop : LoopAnalysis, optional
        Analysis of the loop with ``kp_nomoto``, ``kd_nomoto``; None for ``method="given"``.
    limits : dict
        Largest ω_n under each default-ω_n limit (:func:`wn_limits`); empty for ``method="given"``.
    model : YawModel, optional
        The linear yaw model designed on.
    """

    kp: float
    kd: float
    method: str
    zeta: float
    wn: float
    wn_source: str
    speed: float
    side: str
    nomoto_K: float
    nomoto_T: float
    kp_nomoto: float
    kd_nomoto: float
    predicted_overshoot: float
    loop: LoopAnalysis = field(repr=False)
    nomoto_loop: LoopAnalysis | None = field(default=None, repr=False)
    limits: dict = field(default_factory=dict, repr=False)
    model: YawModel | None = field(default=None, repr=False)

    @property
    def overshoot(self) -> float:
        return self.loop.overshoot

    @property
    def settling_time(self) -> float:
        return self.loop.settling_time

    @property
    def saturates(self) -> bool:
        """Whether the linear heading step of ``step_deg`` commands more than 35° of rudder."""
        return bool(self.loop.step.peak_rudder_deg > DELTA_MAX_DEG + 1e-9)

    def to_dict(self) -> dict:
        d = {"kp": self.kp, "kd": self.kd, "method": self.method, "zeta": self.zeta, "wn": self.wn,
             "saturates": self.saturates, "wn_source": self.wn_source, "speed": self.speed, "side": self.side, "nomoto_K": self.nomoto_K,
             "nomoto_T": self.nomoto_T, "nomoto_K_own": self.nomoto_K / self.speed,
             "nomoto_T_own": self.nomoto_T * self.speed, "predicted_overshoot": self.predicted_overshoot,
             "wn_limits": dict(self.limits)}
        d.update({f"closed_loop_{k}" if k in ("kp", "kd") else k: v for k, v in self.loop.to_dict().items()
                  if k not in ("kp", "kd")})
        d["overshoot_linear"] = self.loop.overshoot
        d["settling_time_linear"] = self.loop.settling_time
        if self.nomoto_loop is not None:
            d["nomoto_formula"] = {"kp": self.kp_nomoto, "kd": self.kd_nomoto,
                                   "dominant_zeta": self.nomoto_loop.dominant_zeta,
                                   "dominant_wn": self.nomoto_loop.dominant_wn,
                                   "overshoot_linear": self.nomoto_loop.overshoot,
                                   "settling_time_linear": self.nomoto_loop.settling_time}
        return d


def _as_model(model_or_speed, side: str = "port") -> YawModel:
    if isinstance(model_or_speed, YawModel):
        return model_or_speed
    return yaw_subsystem(model_or_speed, side)


def design_pd(model_or_speed=1.0, spec: PdSpec | None = None, *, side: str = "port") -> PdDesign:
    """Design the PD heading controller on the linear yaw model (a :class:`YawModel` or a speed).

    Parameters
    ----------
    model_or_speed : YawModel or float
        The linear model, or a speed (fraction of U_des) linearised on ``side``.
    spec : PdSpec
        Damping, natural frequency / settling time, method; defaults to ``PdSpec()``.
    side : {"port", "starboard", "mean"}
        Side of the linearisation when ``model_or_speed`` is a speed (ignored for a :class:`YawModel`).

    Examples
    --------
    >>> d = design_pd(1.0, PdSpec(zeta=0.8))
    >>> d.wn_source, round(d.wn, 3), round(d.kp, 3), round(d.kd, 3)
    ('dominance', 0.483, 0.211, 0.95)
    >>> round(d.loop.dominant_zeta, 6), d.loop.stable
    (0.8, True)
    >>> n = design_pd(1.0, PdSpec(zeta=0.8, method="nomoto"))
    >>> round(n.kp, 2), round(n.kd, 2), round(n.loop.dominant_zeta, 2)
    (3.5, 3.9, 0.31)
    """
    spec = spec or PdSpec()
    model = _as_model(model_or_speed, side)
    nom = nomoto_first_order(model)
    zeta = spec.effective_zeta
    limits = wn_limits(model, zeta, spec.method, spec.step_deg)
    if spec.wn is not None:
        wn, source = float(spec.wn), "spec"
    elif spec.settling_time is not None:
        wn, source = 4.0 / (zeta * spec.settling_time), "settling_time"
    elif limits["both"] is not None:
        wn = limits["both"]
        sat = limits["saturation"]
        source = "saturation" if sat is not None and abs(sat - wn) <= 1e-6 * wn else "dominance"
    elif limits["dominance"] is not None:
        wn, source = limits["dominance"], "dominance"
    else:
        raise ParameterError("wn", "a value (no default: no natural frequency meets the limits)", None)
    kp_n, kd_n = _nomoto_gains(nom.K, nom.T, zeta, wn)
    kp, kd = place_pair(model, zeta, wn) if spec.method == "placement" else (kp_n, kd_n)
    loop = analyse_loop(model, kp, kd, spec.step_deg)
    nloop = loop if spec.method == "nomoto" else analyse_loop(model, kp_n, kd_n, spec.step_deg)
    return PdDesign(kp, kd, spec.method, zeta, wn, source, model.speed, model.side, nom.K, nom.T, kp_n, kd_n,
                    second_order_overshoot(zeta), loop, nloop, limits, model)


def analyse_gains(kp: float, kd: float, model_or_speed=1.0, *, side: str = "port",
                  step_deg: float = 10.0) -> PdDesign:
    """Given gains as a :class:`PdDesign` (``method="given"``) with their Nomoto-equivalent ζ and ω_n.

    Parameters
    ----------
    kp : float
        Proportional gain K_p, > 0 (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d, ≥ 0, on the measured yaw rate (rad of rudder per U_des/L).
    model_or_speed : YawModel or float
        The linear model, or a speed (fraction of U_des) linearised on ``side``.
    side : {"port", "starboard", "mean"}
        Side of the linearisation when ``model_or_speed`` is a speed.
    step_deg : float
        Heading step (degrees) of the linear step response.

    Examples
    --------
    >>> p = analyse_gains(3.5, 4.0, 1.0)
    >>> round(p.zeta, 2), round(p.wn, 2)
    (0.82, 1.43)
    """
    check_range("kp", kp, 0.0, None, low_open=True)
    check_range("kd", kd, 0.0, None)
    model = _as_model(model_or_speed, side)
    nom = nomoto_first_order(model)
    wn = math.sqrt(kp * nom.K / nom.T)
    zeta = (1.0 + nom.K * kd) / (2.0 * wn * nom.T)
    loop = analyse_loop(model, kp, kd, step_deg)
    return PdDesign(float(kp), float(kd), "given", zeta, wn, "gains", model.speed, model.side, nom.K, nom.T,
                    float(kp), float(kd), second_order_overshoot(zeta), loop, None, {}, model)


@dataclass(frozen=True)
class GainMap:
    """The paper's gains analysed on the linear model, and linear step metrics over a (K_p, K_d) grid.

    ``overshoot`` (percent), ``settling_time`` and ``dominant_zeta`` are ``(len(kd_grid), len(kp_grid))``
    arrays, NaN where the loop is unstable or does not settle within the horizon.

    Parameters
    ----------
    paper : PdDesign
        The paper's gains K_p = 3.5, K_d = 4 analysed (:func:`analyse_gains`).
    kp_grid : ndarray
        Grid of K_p values.
    kd_grid : ndarray
        Grid of K_d values.
    overshoot : ndarray
        Linear step overshoot (percent).
    settling_time : ndarray
        2 % settling time of the linear step (L/U_des).
    dominant_zeta : ndarray
        Damping ratio of the dominant closed-loop pole or pair, capped at 1.
    """

    paper: PdDesign
    kp_grid: np.ndarray = field(repr=False)
    kd_grid: np.ndarray = field(repr=False)
    overshoot: np.ndarray = field(repr=False)
    settling_time: np.ndarray = field(repr=False)
    dominant_zeta: np.ndarray = field(repr=False)

    def to_dict(self) -> dict:
        return {"paper": self.paper.to_dict(), "kp_grid": self.kp_grid.tolist(), "kd_grid": self.kd_grid.tolist(),
                "overshoot": _nan_to_none(self.overshoot), "settling_time": _nan_to_none(self.settling_time),
                "dominant_zeta": _nan_to_none(self.dominant_zeta)}


def _nan_to_none(a) -> list:
    return [[None if not np.isfinite(v) else float(v) for v in row] for row in np.asarray(a)]


def _expm_batch(M: np.ndarray, order: int = 18) -> np.ndarray:
    """Matrix exponentials of a stack of small matrices: Taylor series with a common scaling and squaring.

    Examples
    --------
    >>> from scipy.linalg import expm
    >>> M = np.array([[[0.0, 1.0], [-4.0, -0.4]], [[-1.0, 0.0], [0.0, 3.0]]])
    >>> bool(np.allclose(_expm_batch(M), expm(M), rtol=1e-12, atol=1e-12))
    True
    """
    norm = float(np.max(np.sum(np.abs(M), axis=-1)))
    s = max(0, int(math.ceil(math.log2(norm))) + 1) if norm > 0 else 0
    X = M / 2.0**s
    E = np.broadcast_to(np.eye(M.shape[-1]), M.shape).copy()
    term = E.copy()
    for k in range(1, order + 1):
        term = term @ X / k
        E += term
    for _ in range(s):
        E = E @ E
    return E


def grid_step_metrics(model: YawModel, kp_grid, kd_grid, t_end: float = 150.0, dt: float = 0.1):
    """Overshoot (%), 2 % settling time and dominant damping of the linear unit heading step over a gain grid.

    All loops are stepped together with their exact zero-order-hold discretisation (batched ``expm``).

    Parameters
    ----------
    model : YawModel
        Linear yaw subsystem (:func:`~tuning.linear.yaw_subsystem`).
    kp_grid : array_like
        K_p values (columns of the result).
    kd_grid : array_like
        K_d values (rows of the result).
    t_end : float
        Horizon of the step (L/U_des).
    dt : float
        Discretisation step (L/U_des).
    """
    KP, KD = np.meshgrid(np.asarray(kp_grid, float), np.asarray(kd_grid, float))
    kp, kd = KP.ravel(), KD.ravel()
    G = kp.size
    Kr = np.zeros((G, 1, 4))
    Kr[:, 0, 1], Kr[:, 0, 2] = kd, kp
    Acl = model.A[None] - model.B[None] @ Kr
    M = np.zeros((G, 5, 5))
    M[:, :4, :4] = Acl
    M[:, :4, 4] = model.B[:, 0][None] * kp[:, None]
    E = _expm_batch(M * dt)
    Ad, bd = E[:, :4, :4], E[:, :4, 4]
    n = int(round(t_end / dt))
    x = np.zeros((G, 4))
    psi = np.empty((G, n + 1))
    psi[:, 0] = 0.0
    for k in range(n):
        x = np.einsum("gij,gj->gi", Ad, x) + bd
        psi[:, k + 1] = x[:, 2]
    t = np.arange(n + 1) * dt
    eig = np.linalg.eigvals(Acl)
    lead = eig[np.arange(G), np.argmax(eig.real, axis=1)]
    stable = np.all(eig.real < 0, axis=1)
    outside = np.abs(psi - 1.0) > SETTLING
    last = n - np.argmax(outside[:, ::-1], axis=1)
    settled = ~outside[:, -1] & stable
    ts = np.where(settled, t[np.minimum(last, n)], np.nan)
    os_ = np.where(settled, np.maximum(psi.max(axis=1) - 1.0, 0.0) * 100.0, np.nan)
    zeta = np.where(stable, np.minimum(-lead.real / np.abs(lead), 1.0), np.nan)
    shape = KP.shape
    return os_.reshape(shape), ts.reshape(shape), zeta.reshape(shape)


def paper_gains_map(speed: float = 1.0, *, side: str = "port", kp_grid=None, kd_grid=None) -> GainMap:
    """Where the paper's K_p = 3.5, K_d = 4 sit on the linear model at ``speed``, and a (K_p, K_d) grid map.

    Parameters
    ----------
    speed : float
        Fraction of the design speed, in [0.2, 1.2].
    side : {"port", "starboard", "mean"}
        Side of the linearisation.
    kp_grid : array_like, optional
        K_p values of the map; 40 points over [0.1, 6] by default.
    kd_grid : array_like, optional
        K_d values of the map; 41 points over [0, 8] by default.

    Examples
    --------
    >>> g = paper_gains_map(1.0, kp_grid=[1.0, 3.5], kd_grid=[2.0, 4.0])
    >>> g.paper.loop.stable, round(g.paper.loop.dominant_zeta, 2), round(float(g.overshoot[1, 1]), 1)
    (True, 0.32, 10.9)
    """
    model = yaw_subsystem(speed, side)
    paper = analyse_gains(*PAPER_GAINS, model)
    kp_grid = np.linspace(0.1, 6.0, 40) if kp_grid is None else np.asarray(kp_grid, float)
    kd_grid = np.linspace(0.0, 8.0, 41) if kd_grid is None else np.asarray(kd_grid, float)
    os_, ts, zeta = grid_step_metrics(model, kp_grid, kd_grid)
    return GainMap(paper, kp_grid, kd_grid, os_, ts, zeta)


@lru_cache(maxsize=4)
def _heading_loop_step() -> ca.Function:
    """Compiled step of MMG + steering gear + PD: ``(x[7], p=[psi_d, kp, kd, n_rpm, dt]) -> (x_next, delta_c)``.

    The PD command is held over the RK4 step (sampled control, as in the closed loop of the simulations).
    """
    f = build_mmg(load_kcs(), load_steering())
    x = ca.SX.sym("x", NX)
    p = ca.SX.sym("p", 5)
    psi, r = x[STATE_NAMES.index("psi")], x[STATE_NAMES.index("r")]
    dc = pd_heading(psi, p[0], r, p[1], p[2], math.radians(DELTA_MAX_DEG))
    return compile_function(ca.Function("pd_heading_loop_step", [x, p], [rk4(f, x, (dc, p[3]), p[4]), dc],
                                        ["x", "p"], ["x_next", "delta_c"]))


def nonlinear_step(kp: float, kd: float, speed: float = 1.0, step_deg: float = 10.0, t_end: float = 60.0
                   ) -> StepResponse:
    """Heading step of ``step_deg`` (signed; positive to starboard) on the NONLINEAR model with the PD.

    Straight running at ``speed`` (self-propulsion rpm) is the initial state; the rollout is a ``mapaccum`` of
    the compiled closed-loop step.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    speed : float
        Fraction of the design speed of the initial straight running.
    step_deg : float
        Heading step (degrees; signed, positive to starboard).
    t_end : float
        Horizon (L/U_des), integrated in steps of :data:`DT`.
    """
    n = int(round(t_end / DT))
    F = _heading_loop_step().mapaccum(n)
    psi_d = math.radians(step_deg)
    x0 = [speed, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    X, U = F(x0, [psi_d, kp, kd, propeller_rpm_for_speed(speed), DT])
    X = np.hstack([np.asarray(x0)[:, None], np.array(X)])
    dc = np.array(U).ravel()
    dc = np.append(dc, dc[-1])
    t = np.arange(n + 1) * DT
    col = {s: X[STATE_NAMES.index(s)] for s in ("psi", "r", "delta")}
    return StepResponse("nonlinear", psi_d, t, col["psi"], col["r"], dc, col["delta"],
                        **_step_metrics(t, col["psi"], psi_d),
                        peak_rudder_deg=float(np.degrees(np.max(np.abs(dc)))))


@dataclass(frozen=True)
class NonlinearCheck:
    """A design checked on the nonlinear model.

    ``step`` is the nonlinear heading step towards the side the linear model describes (port model: a port
    step, otherwise starboard), ``opposite`` the same step the other way, ``linear`` the linear prediction of
    ``step``; ``square`` holds CE, MCTE, status and time to goal of the waypoint-square study (design speed,
    ILOS defaults) with these gains, or is None.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    speed : float
        Speed of the check, fraction of the design speed.
    step : StepResponse
        Nonlinear heading step towards the side of the linear model.
    opposite : StepResponse
        Nonlinear heading step of the same size the other way.
    linear : StepResponse
        Linear prediction of ``step``.
    square : dict, optional
        CE, MCTE, status and time to goal of the waypoint-square study, or None.
    """

    kp: float
    kd: float
    speed: float
    step: StepResponse = field(repr=False)
    opposite: StepResponse = field(repr=False)
    linear: StepResponse = field(repr=False)
    square: dict | None = None

    def to_dict(self) -> dict:
        return {"kp": self.kp, "kd": self.kd, "speed": self.speed, "step_deg": math.degrees(self.step.psi_d),
                "overshoot_nonlinear": self.step.overshoot, "settling_time_nonlinear": self.step.settling_time,
                "overshoot_opposite": self.opposite.overshoot,
                "settling_time_opposite": self.opposite.settling_time,
                "overshoot_linear": self.linear.overshoot, "settling_time_linear": self.linear.settling_time,
                "peak_rudder_deg_nonlinear": self.step.peak_rudder_deg, "waypoint_square": self.square}


def waypoint_square(kp: float, kd: float) -> dict:
    """CE, MCTE, status and time to goal of the paper's waypoint-square study with PD gains ``kp``, ``kd``.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    """
    from mmg_casadi.scenarios.encounters import waypoint_square as square_scenario
    from mmg_casadi.scenarios.run import run_scenario
    own = run_scenario(square_scenario(), params={"kp": float(kp), "kd": float(kd)}).metrics["ships"][0]
    return {"ce": own["ce"], "mcte": own["mcte"], "status": own["status"], "time_to_goal": own["time_to_goal"]}


def verify_nonlinear(design: PdDesign, speed: float | None = None, step_deg: float = 10.0, *,
                     square: bool = True) -> NonlinearCheck:
    """Check ``design`` on the nonlinear model: a heading step both ways and (optionally) the waypoint square.

    Parameters
    ----------
    design : PdDesign
        The design (or analysed gains) to check.
    speed : float, optional
        Fraction of the design speed, in [0.2, 1.2]; the design's speed by default.
    step_deg : float
        Size of the heading step (degrees, in (0, 180]); taken towards the side of the design's model.
    square : bool
        Whether to run the waypoint-square study as well.

    Examples
    --------
    >>> d = design_pd(1.0, PdSpec(zeta=0.8))
    >>> c = verify_nonlinear(d, square=False)
    >>> abs(c.step.overshoot - c.linear.overshoot) < 3.0
    True
    """
    speed = design.speed if speed is None else check_range("speed", speed, 0.2, 1.2)
    check_range("step_deg", step_deg, 0.0, 180.0, low_open=True, unit="degrees")
    model = design.model if design.model is not None and design.model.speed == speed else yaw_subsystem(
        speed, design.side)
    sign = -1.0 if design.side == "port" else 1.0
    lin = linear_step(model, design.kp, design.kd, sign * step_deg)
    t_end = float(max(40.0, lin.t[-1], 4.0 * np.nan_to_num(lin.settling_time, nan=30.0)))
    if t_end > lin.t[-1] + DT:
        lin = linear_step(model, design.kp, design.kd, sign * step_deg, t_end)
    main = nonlinear_step(design.kp, design.kd, speed, sign * step_deg, t_end)
    other = nonlinear_step(design.kp, design.kd, speed, -sign * step_deg, t_end)
    sq = waypoint_square(design.kp, design.kd) if square else None
    return NonlinearCheck(design.kp, design.kd, speed, main, other, lin, sq)


def _save(fig: Figure, path) -> Figure:
    if path is not None:
        fig.savefig(path, dpi=110)
    return fig


def plot_root_locus(design: PdDesign, path=None, *, paper: PdDesign | None = None) -> Figure:
    """Root locus of the loop with the gain pair scaled by k ∈ [0.01, 100] (design at k = 1), on a Figure.

    Parameters
    ----------
    design : PdDesign
        The design whose gains are scaled.
    path : str or path-like, optional
        Where to save the figure (PNG, 110 dpi); not saved if None.
    paper : PdDesign, optional
        A second gain pair (the paper's) whose locus is drawn as well.
    """
    model = design.model or yaw_subsystem(design.speed, design.side)
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot(1, 1, 1)
    for d, color, label in ((design, "tab:blue", f"design K_p={design.kp:.3g}, K_d={design.kd:.3g}"),
                            (paper, "tab:red", None if paper is None else
                             f"paper K_p={paper.kp:g}, K_d={paper.kd:g}")):
        if d is None:
            continue
        ks = np.geomspace(1e-2, 1e2, 500)
        loci = np.array([np.linalg.eigvals(model.A - model.B @ _gain_row(k * d.kp, k * d.kd)) for k in ks])
        ax.plot(loci.real, loci.imag, ".", ms=1.5, color=color, alpha=0.5)
        p = np.array(d.loop.poles)
        ax.plot(p.real, p.imag, "s", color=color, ms=7, mfc="none", mew=1.5, label=label)
    ol = np.linalg.eigvals(model.A)
    ax.plot(ol.real, ol.imag, "kx", ms=8, label="open-loop poles")
    zeros = np.roots(np.polymul([design.kd, design.kp], _polys(model)[1]))
    ax.plot(zeros.real, zeros.imag, "ko", mfc="none", ms=7, label="loop zeros")
    lim = 1.2 * max(3.0, float(np.max(np.abs(np.array(design.loop.poles)))))
    rho = np.array([0.0, lim])
    th = math.acos(min(design.zeta, 1.0))
    for sgn in (1, -1):
        ax.plot(-rho * math.cos(th), sgn * rho * math.sin(th), "k:", lw=0.8)
    ax.set_xlim(-lim, 0.3 * lim)
    ax.set_ylim(-lim, lim)
    ax.axhline(0, color="k", lw=0.5)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("Re s [U/L]")
    ax.set_ylabel("Im s [U/L]")
    ax.set_title(f"Root locus (gains scaled by k), speed {design.speed:g}, {design.side} side; ζ = {design.zeta:g}")
    ax.legend(loc="upper left", fontsize=8)
    ax.grid(True, alpha=0.3)
    return _save(fig, path)


def plot_step(design: PdDesign, nonlinear: NonlinearCheck, path=None) -> Figure:
    """Linear vs nonlinear heading step: heading and rudder against time.

    Parameters
    ----------
    design : PdDesign
        The design (its gains label the plot).
    nonlinear : NonlinearCheck
        Nonlinear check of the design (:func:`verify_nonlinear`) with the steps to draw.
    path : str or path-like, optional
        Where to save the figure (PNG, 110 dpi); not saved if None.
    """
    fig = Figure(figsize=(8, 6))
    ax1, ax2 = fig.add_subplot(2, 1, 1), fig.add_subplot(2, 1, 2)
    lin, nl, opp = nonlinear.linear, nonlinear.step, nonlinear.opposite
    s = math.copysign(1.0, nl.psi_d)
    ax1.plot(lin.t, s * np.degrees(lin.psi), "k--", label=f"linear (OS {lin.overshoot:.1f} %)")
    ax1.plot(nl.t, s * np.degrees(nl.psi), "tab:blue", label=f"nonlinear (OS {nl.overshoot:.1f} %)")
    ax1.plot(opp.t, -s * np.degrees(opp.psi), "tab:orange", lw=1,
             label=f"nonlinear, other side (OS {opp.overshoot:.1f} %)")
    ax1.axhline(abs(math.degrees(nl.psi_d)), color="gray", lw=0.6)
    ax1.set_ylabel("|ψ| [deg]")
    ax1.set_title(f"Heading step {abs(math.degrees(nl.psi_d)):g}°: K_p = {design.kp:.3g}, K_d = {design.kd:.3g} "
                  f"(speed {nonlinear.speed:g}, {'port' if s < 0 else 'starboard'} step)")
    ax1.legend(fontsize=8)
    ax2.plot(lin.t, s * np.degrees(lin.delta_c), "k--", label="δ_c linear")
    ax2.plot(nl.t, s * np.degrees(nl.delta_c), "tab:blue", lw=0.8, alpha=0.6, label="δ_c nonlinear")
    ax2.plot(nl.t, s * np.degrees(nl.delta), "tab:blue", label="δ nonlinear")
    ax2.set_xlabel("t [L/U_des]")
    ax2.set_ylabel("rudder (step side +) [deg]")
    ax2.legend(fontsize=8)
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
        ax.set_xlim(0, nl.t[-1])
    fig.tight_layout()
    return _save(fig, path)


def plot_gain_map(gain_map: GainMap, path=None, *, design: PdDesign | None = None) -> Figure:
    """Overshoot contours over (K_p, K_d) with settling-time lines, the paper's gains and the design marked.

    Parameters
    ----------
    gain_map : GainMap
        The grid map (:func:`paper_gains_map`).
    path : str or path-like, optional
        Where to save the figure (PNG, 110 dpi); not saved if None.
    design : PdDesign, optional
        A design to mark (with its first-order Nomoto gains for a placement design).
    """
    fig = Figure(figsize=(8, 6))
    ax = fig.add_subplot(1, 1, 1)
    KP, KD = np.meshgrid(gain_map.kp_grid, gain_map.kd_grid)
    os_ = np.ma.masked_invalid(gain_map.overshoot)
    cf = ax.contourf(KP, KD, os_, levels=[0, 0.5, 1, 2, 5, 10, 15, 20, 30, 50, 100], cmap="viridis", extend="max")
    fig.colorbar(cf, ax=ax, label="linear overshoot [%] (10° step)")
    ts = np.ma.masked_invalid(gain_map.settling_time)
    if ts.count():
        cs = ax.contour(KP, KD, ts, levels=[5, 7.5, 10, 15, 20, 30], colors="w", linewidths=0.8)
        ax.clabel(cs, fmt="t_s=%g", fontsize=7)
    p = gain_map.paper
    ax.plot(p.kp, p.kd, "r*", ms=14, mec="k", label=f"paper ({p.kp:g}, {p.kd:g}): OS {p.overshoot:.1f} %")
    if design is not None:
        ax.plot(design.kp, design.kd, "wo", ms=9, mec="k",
                label=f"design ({design.kp:.3g}, {design.kd:.3g}): OS {design.overshoot:.1f} %")
        if design.method == "placement":
            ax.plot(design.kp_nomoto, design.kd_nomoto, "w^", ms=8, mec="k",
                    label=f"Nomoto formula ({design.kp_nomoto:.3g}, {design.kd_nomoto:.3g})")
    ax.set_xlabel("K_p")
    ax.set_ylabel("K_d")
    ax.set_xlim(gain_map.kp_grid[0], gain_map.kp_grid[-1])
    ax.set_ylim(gain_map.kd_grid[0], gain_map.kd_grid[-1])
    ax.set_title(f"Linear heading step over (K_p, K_d), speed {p.speed:g}, {p.side} side")
    ax.legend(fontsize=8, loc="lower right")
    return _save(fig, path)

