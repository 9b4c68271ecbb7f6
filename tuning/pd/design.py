"""PD gain design on the linear yaw model: pole placement or the first-order Nomoto formula, default ω_n.

The control law and the units are those of :mod:`tuning.pd.analysis`: ``δ_c = -K_p e - K_d r``, rudder
saturated at ±35°, time in L/U_des.

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

The paper's gains K_p = 3.5, K_d = 4 are exactly the ``"nomoto"`` design with ζ ≈ 0.8 and the no-saturation
ω_n at the design speed; on the full model their dominant pair has ζ ≈ 0.32
(:func:`~tuning.pd.gain_map.paper_gains_map`).

The numbers above are the KCS's; ``vessel`` designs for another hull of the library (or a vessel .toml file), at
a fraction of its design speed and in its L/U_des.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mmg_casadi.errors import ParameterError, check_range
from mmg_casadi.params import PARAMETERS
from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL

from ..linear import YawModel, nomoto_first_order, yaw_subsystem
from .analysis import LoopAnalysis, analyse_loop

METHODS = ("placement", "nomoto")
DOMINANCE = 1.5  #: remaining poles at least this many times faster than the designed pair's slowest pole
DELTA_MAX_DEG = PARAMETERS["delta_max_deg"].default
PAPER_GAINS = (PARAMETERS["kp"].default, PARAMETERS["kd"].default)


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

    Returns
    -------
    float
        Overshoot (%).

    Examples
    --------
    >>> round(second_order_overshoot(0.8), 2), second_order_overshoot(1.0)
    (1.52, 0.0)
    """
    return 0.0 if zeta >= 1.0 else 100.0 * math.exp(-math.pi * zeta / math.sqrt(1.0 - zeta**2))


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

    Returns
    -------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d (rad of rudder per U_des/L of yaw rate).

    Examples
    --------
    >>> from tuning.pd.analysis import closed_loop
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

    Returns
    -------
    dict
        ``"saturation"``, ``"dominance"`` and ``"both"``: the largest ω_n (U_des/L) meeting that limit, or None
        (``"dominance"`` is None for ``"nomoto"``).

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
    def vessel(self) -> str:
        """The hull designed for: the model's (:attr:`YawModel.vessel`), the KCS without a model."""
        return DEFAULT_VESSEL if self.model is None else self.model.vessel

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


def _as_model(model_or_speed, side: str = "port", vessel: str = DEFAULT_VESSEL) -> YawModel:
    if isinstance(model_or_speed, YawModel):
        return model_or_speed
    return yaw_subsystem(model_or_speed, side, vessel=vessel)


def design_pd(model_or_speed=1.0, spec: PdSpec | None = None, *, side: str = "port",
              vessel: str = DEFAULT_VESSEL) -> PdDesign:
    """Design the PD heading controller on the linear yaw model (a :class:`YawModel` or a speed).

    Parameters
    ----------
    model_or_speed : YawModel or float
        The linear model, or a speed (fraction of the hull's U_des) linearised on ``side``.
    spec : PdSpec
        Damping, natural frequency / settling time, method; defaults to ``PdSpec()``.
    side : {"port", "starboard", "mean"}
        Side of the linearisation when ``model_or_speed`` is a speed (ignored for a :class:`YawModel`).
    vessel : str or pathlib.Path
        Hull linearised when ``model_or_speed`` is a speed: a name of :data:`~mmg_casadi.vessel.library.VESSELS`
        or a vessel .toml file (default the KCS; ignored for a :class:`YawModel`, which carries its own).

    Returns
    -------
    PdDesign
        Gains, method, ζ, ω_n and its source, the Nomoto model and gains, the linear loop analysis and the ω_n
        limits.

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
    model = _as_model(model_or_speed, side, vessel)
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
                  step_deg: float = 10.0, vessel: str = DEFAULT_VESSEL) -> PdDesign:
    """Given gains as a :class:`PdDesign` (``method="given"``) with their Nomoto-equivalent ζ and ω_n.

    Parameters
    ----------
    kp : float
        Proportional gain K_p, > 0 (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d, ≥ 0, on the measured yaw rate (rad of rudder per U_des/L).
    model_or_speed : YawModel or float
        The linear model, or a speed (fraction of the hull's U_des) linearised on ``side``.
    side : {"port", "starboard", "mean"}
        Side of the linearisation when ``model_or_speed`` is a speed.
    step_deg : float
        Heading step (degrees) of the linear step response.
    vessel : str or pathlib.Path
        Hull linearised when ``model_or_speed`` is a speed (a name of :data:`~mmg_casadi.vessel.library.VESSELS`
        or a vessel .toml file; default the KCS; ignored for a :class:`YawModel`).

    Returns
    -------
    PdDesign
        The gains with ``method="given"``, their equivalent ζ and ω_n and the linear loop analysis.

    Examples
    --------
    >>> p = analyse_gains(3.5, 4.0, 1.0)
    >>> round(p.zeta, 2), round(p.wn, 2)
    (0.82, 1.43)
    """
    check_range("kp", kp, 0.0, None, low_open=True)
    check_range("kd", kd, 0.0, None)
    model = _as_model(model_or_speed, side, vessel)
    nom = nomoto_first_order(model)
    wn = math.sqrt(kp * nom.K / nom.T)
    zeta = (1.0 + nom.K * kd) / (2.0 * wn * nom.T)
    loop = analyse_loop(model, kp, kd, step_deg)
    return PdDesign(float(kp), float(kd), "given", zeta, wn, "gains", model.speed, model.side, nom.K, nom.T,
                    float(kp), float(kd), second_order_overshoot(zeta), loop, None, {}, model)
