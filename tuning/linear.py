"""Linear yaw dynamics of the MMG model about straight running, and Nomoto models from them.

The ship plus steering gear is linearised with CasADi's exact Jacobians
(:func:`mmg_casadi.vessel.mmg.linearise`) about straight running at a fraction ``speed`` of the design speed, the
propeller turning at the self-propulsion rpm for that speed. At straight running the surge equation decouples
from the yaw subsystem (the Jacobian entries coupling ``u`` with ``v``, ``r``, ``delta`` and the
``n_rpm`` column of the yaw rows are exactly zero, see :attr:`YawModel.surge_coupling`), and nothing in the sway
and yaw rows depends on ``x``, ``y`` or ``psi``, so the states ``(v, r, psi, delta)`` with input ``delta_c`` form
an exact linear subsystem.

The rudder's flow-straightening coefficient switches at β_P = 0 (γ_R⁺ for β_P > 0, which is a starboard turn,
γ_R⁻ otherwise), so the model has a kink at straight running and two one-sided linearisations:

``side="port"``
    the exact Jacobian at straight running, which is the γ_R⁻ branch; it describes small *port* turns.
``side="starboard"``
    the Jacobian just off straight running at β_P = +1e-10 (v' = -1e-10), the γ_R⁺ branch; it describes small
    *starboard* turns.
``side="mean"``
    the average of the two.

Every function takes the hull as ``vessel`` (a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel
.toml file, :func:`~mmg_casadi.vessel.library.load_vessel`; the KCS by default): its ship and steering
parameters are linearised and simulated, the speed is a fraction of *its* design speed and times are in *its*
L/U_des.

On the KCS the two differ strongly at the design speed (first-order Nomoto K' = 35, T' = 60 to port, nearly
course-unstable, against K' = 4.1, T' = 6.8 to starboard) and little at half speed. A small nonlinear rudder
step reproduces the side its sign selects (:func:`fit_nomoto_step`).

All quantities are in the prime-II system of the design speed: time in L/U_des, yaw rate in U_des/L. At another
speed U the usual "own-speed" non-dimensional values are ``K' U_des/U`` and ``T' U/U_des``
(:attr:`Nomoto.K_own`, :attr:`Nomoto.T_own`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import control as ct
import numpy as np
from scipy.optimize import curve_fit

from mmg_casadi.errors import ParameterError, check_range
from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL, load_vessel
from mmg_casadi.vessel.mmg import STATE_NAMES, build_cvodes, build_mmg, linearise, propeller_rpm_for_speed

YAW_STATES = ("v", "r", "psi", "delta")
SIDES = ("port", "starboard", "mean")
SPEED_RANGE = (0.2, 1.2)
EPS_BETA = 1e-10  #: drift angle (rad) used to evaluate the starboard-side (γ_R⁺) Jacobian
_IDX = [STATE_NAMES.index(s) for s in YAW_STATES]
_U = STATE_NAMES.index("u")


def _check_speed(speed) -> float:
    return check_range("speed", speed, *SPEED_RANGE, unit="(fraction of the design speed)")


def _check_side(side: str) -> str:
    if side not in SIDES:
        raise ParameterError("side", f"one of: {', '.join(SIDES)}", side)
    return side


@dataclass(frozen=True)
class YawModel:
    """Linear yaw subsystem ``ẋ = A x + B δ_c``, ``y = C x`` with ``x = (v, r, psi, delta)`` and ``y = (r, psi)``.

    Parameters
    ----------
    speed : float
        Speed of the straight-running operating point, fraction of the design speed.
    n_rpm : float
        Propeller speed at that point (rev/min).
    side : str
        Which side of the γ_R switch was linearised (``"port"``, ``"starboard"`` or ``"mean"``).
    A, B, C : ndarray
        State (4x4), input (4x1) and output (2x4) matrices.
    surge_coupling : float
        Largest magnitude of the Jacobian entries that couple surge (``u``, ``n_rpm``) with the yaw states; exactly
        0.0 for ``side="port"`` (the Jacobian at straight running), of order 1e-10 for the others.
    vessel : str
        The hull linearised: a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel .toml file
        (``speed``, the matrices and their units are that hull's).
    """

    speed: float
    n_rpm: float
    side: str
    A: np.ndarray = field(repr=False)
    B: np.ndarray = field(repr=False)
    C: np.ndarray = field(repr=False)
    surge_coupling: float = 0.0
    vessel: str = DEFAULT_VESSEL

    def ss(self) -> ct.StateSpace:
        """``control.ss`` of the subsystem (input ``delta_c``, outputs ``r``, ``psi``).

        Returns
        -------
        control.StateSpace
            The subsystem (states v, r, psi, delta; design-speed units).
        """
        return ct.ss(self.A, self.B, self.C, np.zeros((2, 1)), inputs=["delta_c"], outputs=["r", "psi"],
                     states=list(YAW_STATES), name=f"yaw_{self.side}_{self.speed:g}")

    def tf_yaw_rate(self) -> ct.TransferFunction:
        """Transfer function δ_c → r (steering gear included), from the (v, r, delta) states (ψ does not feed
        back).

        Returns
        -------
        control.TransferFunction
            r/δ_c (yaw rate in U_des/L per rad; time in L/U_des).

        Examples
        --------
        >>> round(float(yaw_subsystem(1.0).tf_yaw_rate().dcgain()), 2)     # K' of the port side
        35.1
        """
        k = [0, 1, 3]
        return _siso_tf(self.A[np.ix_(k, k)], self.B[k], np.array([0.0, 1.0, 0.0]), "r")

    def tf_heading(self) -> ct.TransferFunction:
        """Transfer function δ_c → ψ (steering gear included).

        Returns
        -------
        control.TransferFunction
            ψ/δ_c (rad per rad; time in L/U_des).
        """
        return _siso_tf(self.A, self.B, self.C[1], "psi")

    def to_dict(self) -> dict:
        return {"speed": self.speed, "n_rpm": self.n_rpm, "side": self.side, "states": list(YAW_STATES),
                "A": self.A.tolist(), "B": self.B.tolist(), "C": self.C.tolist(),
                "surge_coupling": self.surge_coupling, "vessel": self.vessel}


def _siso_tf(A, B, c, output: str) -> ct.TransferFunction:
    """``c (sI - A)⁻¹ B`` with numerator ``det(sI - A + B c) - det(sI - A)``, rounding-level terms dropped."""
    den = np.real(np.poly(A))
    num = np.real(np.poly(A - B @ c[None, :])) - den
    num = np.trim_zeros(np.where(np.abs(num) < 1e-12 * np.max(np.abs(num)), 0.0, num), "f")
    return ct.tf(num, den, inputs="delta_c", outputs=output)


def _jacobians(speed: float, n_rpm: float, v: float, hull):
    A, B = linearise([speed, v, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0, n_rpm], hull.ship, hull.steering)
    yaw = np.asarray(_IDX)
    coupling = np.concatenate([A[_U, yaw], A[yaw, _U], B[yaw, 1]])
    return A[np.ix_(yaw, yaw)], B[yaw, :1], float(np.max(np.abs(coupling)))


def yaw_subsystem(speed: float = 1.0, side: str = "port", *, vessel: str = DEFAULT_VESSEL) -> YawModel:
    """Linear yaw subsystem about straight running at ``speed`` × U_des (exact CasADi Jacobians).

    Parameters
    ----------
    speed : float
        Fraction of the hull's design speed, in [0.2, 1.2].
    side : {"port", "starboard", "mean"}
        Branch of the flow-straightening switch (module docstring); ``"port"`` is the Jacobian exactly at
        straight running.
    vessel : str or pathlib.Path
        The hull: a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel .toml file (default the KCS).

    Returns
    -------
    YawModel
        Operating point, side and the matrices A (4x4), B (4x1), C (2x4) in design-speed units.

    Examples
    --------
    >>> m = yaw_subsystem(1.0)
    >>> m.A.shape, m.B.shape, m.surge_coupling
    ((4, 4), (4, 1), 0.0)
    >>> round(float(m.B[3, 0]), 6)          # steering gear: δ̇ = (δ_c - δ)/T_δ with T_δ = 1
    1.0
    >>> yaw_subsystem(1.0, vessel="kvlcc2").vessel
    'kvlcc2'
    """
    speed = _check_speed(speed)
    _check_side(side)
    hull = load_vessel(vessel)
    n = propeller_rpm_for_speed(speed, hull.ship)
    port = _jacobians(speed, n, 0.0, hull)
    if side == "port":
        A, B, c = port
    else:
        star = _jacobians(speed, n, -speed * math.tan(EPS_BETA), hull)
        if side == "starboard":
            A, B, c = star
        else:
            A, B, c = (port[0] + star[0]) / 2, (port[1] + star[1]) / 2, max(port[2], star[2])
    C = np.array([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    return YawModel(speed, n, side, A, B, C, c, str(vessel))


class _OwnSpeedUnits:
    """``K`` and ``T`` (design-speed units) converted to the ship's own speed ``speed`` (fraction of U_des)."""

    @property
    def K_own(self) -> float:
        """Gain in own-speed units (yaw rate over U/L): ``K U_des/U``."""
        return self.K / self.speed

    @property
    def T_own(self) -> float:
        """Time constant in own-speed units (L/U): ``T U/U_des``."""
        return self.T * self.speed


@dataclass(frozen=True)
class Nomoto(_OwnSpeedUnits):
    """Nomoto model of ``r/δ`` in design-speed units: ``K(1 + T3 s)/((1 + T1 s)(1 + T2 s))``, first-order
    ``K/(1 + T s)`` with ``T = T1 + T2 - T3``.

    For the first-order model only ``K`` and ``T`` are set (``T1 = T``, ``T2 = T3 = 0``).

    Parameters
    ----------
    K : float
        Static gain of ``r/δ`` (yaw rate in U_des/L per rad of rudder).
    T : float
        Equivalent first-order time constant ``T1 + T2 - T3`` (L/U_des).
    T1 : float
        Larger pole time constant (L/U_des).
    T2 : float
        Smaller pole time constant (L/U_des); 0 for the first-order model.
    T3 : float
        Zero time constant (L/U_des); 0 for the first-order model.
    speed : float
        Speed of the operating point, fraction of the design speed.
    side : str
        Linearised side of the γ_R switch (``"port"``, ``"starboard"`` or ``"mean"``).
    vessel : str
        The hull of the model (a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel .toml file).
    """

    K: float
    T: float
    T1: float
    T2: float
    T3: float
    speed: float
    side: str
    vessel: str = DEFAULT_VESSEL

    def T_seconds(self, ship=None) -> float:
        """Time constant in seconds at full scale.

        Parameters
        ----------
        ship : ShipParams, optional
            Ship whose ``time_scale_s`` (seconds per L/U_des) converts the time; the model's hull by default.

        Returns
        -------
        float
            ``T`` (s).
        """
        return self.T * (ship or load_vessel(self.vessel).ship).time_scale_s

    def to_dict(self) -> dict:
        return {"K": self.K, "T": self.T, "T1": self.T1, "T2": self.T2, "T3": self.T3, "speed": self.speed,
                "side": self.side, "K_own": self.K_own, "T_own": self.T_own, "T_seconds": self.T_seconds()}


def _ship_subsystem(m: YawModel):
    """(v, r) subsystem with the rudder angle δ as input (steering gear left out)."""
    return m.A[:2, :2], m.A[:2, 3:4]


def nomoto_second_order(yaw_model: YawModel) -> Nomoto:
    """Second-order Nomoto model from the poles and zero of ``r/δ`` of the (v, r) subsystem.

    ``T1 ≥ T2`` are minus the reciprocals of the poles, ``T3`` minus the reciprocal of the zero, ``K`` the static
    gain; the poles of this ship are real over the speed range.

    Parameters
    ----------
    yaw_model : YawModel
        Linear yaw subsystem (:func:`yaw_subsystem`); its (v, r) part with the rudder angle as input is used.

    Returns
    -------
    Nomoto
        ``K``, ``T1``, ``T2``, ``T3`` and the equivalent ``T`` (L/U_des).

    Examples
    --------
    >>> n = nomoto_second_order(yaw_subsystem(0.5))
    >>> round(n.K, 3), round(n.T1, 3), round(n.T2, 3), round(n.T3, 3)
    (0.496, 1.685, 0.307, 0.365)
    """
    A2, b2 = _ship_subsystem(yaw_model)
    poles = np.linalg.eigvals(A2)
    # r/δ = (b_r s + a_rv b_v - a_vv b_r)/det(sI - A2): zero at s = (a_vv b_r - a_rv b_v)/b_r
    zero = (A2[0, 0] * b2[1, 0] - A2[1, 0] * b2[0, 0]) / b2[1, 0]
    K = float(-(np.linalg.solve(A2, b2))[1, 0])
    T1, T2 = sorted(np.real(-1.0 / poles), reverse=True)
    T3 = float(-1.0 / zero)
    return Nomoto(K, float(T1 + T2 - T3), float(T1), float(T2), T3, yaw_model.speed, yaw_model.side,
                  yaw_model.vessel)


def nomoto_first_order(yaw_model: YawModel) -> Nomoto:
    """First-order Nomoto model ``r/δ = K/(1 + T s)`` with ``T = T1 + T2 - T3`` (design-speed units).

    Parameters
    ----------
    yaw_model : YawModel
        Linear yaw subsystem (:func:`yaw_subsystem`); reduced through :func:`nomoto_second_order`.

    Returns
    -------
    Nomoto
        ``K`` and ``T`` (L/U_des), ``T1 = T``, ``T2 = T3 = 0``.

    Examples
    --------
    >>> n = nomoto_first_order(yaw_subsystem(1.0, "starboard"))
    >>> round(n.K, 2), round(n.T, 2)
    (4.09, 6.84)
    """
    n2 = nomoto_second_order(yaw_model)
    return Nomoto(n2.K, n2.T, n2.T, 0.0, 0.0, n2.speed, n2.side, n2.vessel)


@dataclass(frozen=True)
class NomotoFit(_OwnSpeedUnits):
    """First-order Nomoto model fitted to a nonlinear rudder step, with the linear model of the same side.

    ``t`` and ``r`` are the simulated yaw-rate history (design-speed units); ``rms`` the fit's RMS residual.

    Parameters
    ----------
    K : float
        Fitted gain of ``r/δ`` (yaw rate in U_des/L per rad of rudder).
    T : float
        Fitted time constant (L/U_des).
    speed : float
        Speed of the straight-running start, fraction of the design speed.
    rudder_deg : float
        Rudder step (degrees; positive is starboard).
    side : str
        Side the step's sign selects (``"port"`` or ``"starboard"``).
    rms : float
        RMS residual of the fit (U_des/L).
    linear : Nomoto
        First-order Nomoto model of the linearisation on the same side.
    t : ndarray
        Sample times of the simulated step (L/U_des).
    r : ndarray
        Simulated yaw rate at ``t`` (U_des/L).
    """

    K: float
    T: float
    speed: float
    rudder_deg: float
    side: str
    rms: float
    linear: Nomoto
    t: np.ndarray = field(repr=False)
    r: np.ndarray = field(repr=False)

    @property
    def K_error(self) -> float:
        """Relative difference of the linear K from the fitted one."""
        return (self.linear.K - self.K) / self.K

    @property
    def T_error(self) -> float:
        """Relative difference of the linear T from the fitted one."""
        return (self.linear.T - self.T) / self.T

    def to_dict(self) -> dict:
        return {"K": self.K, "T": self.T, "K_own": self.K_own, "T_own": self.T_own, "speed": self.speed,
                "rudder_deg": self.rudder_deg, "side": self.side, "rms": self.rms,
                "K_linear": self.linear.K, "T_linear": self.linear.T,
                "K_error": self.K_error, "T_error": self.T_error}


def fit_nomoto_step(speed: float = 1.0, rudder_deg: float = 0.1, n_points: int = 2001, *,
                    vessel: str = DEFAULT_VESSEL) -> NomotoFit:
    """Fit ``r(t) = K δ (1 - exp(-t/T))`` to a rudder step on the NONLINEAR model (CVODES, tight tolerances).

    The step starts from straight running with the rudder already at ``rudder_deg`` and the command equal to it,
    so the steering gear plays no part. Positive ``rudder_deg`` (starboard) is compared with the starboard-side
    linear model, negative with the port side. The horizon is ten linear time constants (at least 20; just 20
    for a course-unstable branch, T < 0, as the port side above the design speed, where the fit is of a
    diverging response and agrees only roughly).

    The linear and fitted models agree only for small rudder angles: at the design speed this ship's yaw response
    is strongly nonlinear (fitted K' ≈ 3.5 at 1°, 1.9 at 5° against the linear 4.09 to starboard; to port the
    nearly course-unstable linear branch holds only below about 0.02°). Hence the small default.

    Parameters
    ----------
    speed : float
        Fraction of the hull's design speed, in [0.2, 1.2].
    rudder_deg : float
        Rudder step in degrees, nonzero with magnitude at most 35; its sign selects the side (positive starboard).
    n_points : int
        Number of sample times over the horizon used for the fit.
    vessel : str or pathlib.Path
        The hull: a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel .toml file (default the KCS).

    Returns
    -------
    NomotoFit
        Fitted ``K`` and ``T``, the fit's RMS residual, the linear model of the same side and the simulated history.

    Examples
    --------
    >>> f = fit_nomoto_step(0.5, 0.1)
    >>> abs(f.K_error) < 0.05 and abs(f.T_error) < 0.05
    True
    """
    speed = _check_speed(speed)
    check_range("rudder_deg", abs(rudder_deg), 0.0, 35.0, low_open=True, unit="degrees (sign = side)")
    side = "starboard" if rudder_deg > 0 else "port"
    hull = load_vessel(vessel)
    lin = nomoto_first_order(yaw_subsystem(speed, side, vessel=vessel))
    t = np.linspace(0.0, max(20.0, 10.0 * lin.T), n_points)
    n = propeller_rpm_for_speed(speed, hull.ship)
    d = math.radians(rudder_deg)
    F = build_cvodes(build_mmg(hull.ship, hull.steering), t[1:])
    X = np.array(F(x0=[speed, 0, 0, 0, 0, 0, d], p=[d, n])["xf"])
    r = np.concatenate([[0.0], X[STATE_NAMES.index("r")]])

    def model(tt, K, T):
        return K * d * (1.0 - np.exp(-tt / T))

    (K, T), _ = curve_fit(model, t, r, p0=[lin.K, lin.T])
    rms = float(np.sqrt(np.mean((model(t, K, T) - r) ** 2)))
    return NomotoFit(float(K), float(T), speed, float(rudder_deg), side, rms, lin, t, r)
