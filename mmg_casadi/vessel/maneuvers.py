"""Standard manoeuvres of the model: turning circle, zig-zag and speed change, rolled out with ``mapaccum`` in
compiled code.

All start from straight running at the requested speed (propeller speed from
:func:`~mmg_casadi.vessel.mmg.propeller_rpm_for_speed`); the rudder command goes through the steering gear, a
propeller-speed order through the engine (:func:`~mmg_casadi.vessel.actuators.engine_step`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from mmg_casadi.compiled import compile_function
from mmg_casadi.errors import ParameterError, check_range
from mmg_casadi.params import PARAMETERS
from mmg_casadi.vessel.actuators import engine_step
from mmg_casadi.vessel.mmg import NX, STATE_NAMES, build_mmg, propeller_rpm_for_speed, rk4
from mmg_casadi.vessel.ship import ShipParams, SteeringParams, load_kcs, load_steering

DT = 0.05  #: integration step of the manoeuvres (non-dimensional time)

IMO = {
    # IMO MSC.137(76) for L/V = 18.6 s (see data/kcs_mmg.toml)
    "advance_max": 4.5,
    "tactical_diameter_max": 5.0,
    "zigzag10_overshoot1_max": 14.3,
    "zigzag10_overshoot2_max": 31.5,
    "zigzag20_overshoot1_max": 25.0,
}


@dataclass
class ManeuverResult:
    """Time history and metrics of a manoeuvre.

    ``states`` is ``(T, 7)`` in :data:`~mmg_casadi.vessel.mmg.STATE_NAMES` order, ``delta_c`` the commanded rudder
    (rad), ``metrics`` the dictionary written to ``metrics.json``.

    Parameters
    ----------
    kind : str
        Manoeuvre name: ``'turning'``, ``'zigzag'``, ``'speed'`` or ``'last-moment'``.
    t : numpy.ndarray
        Sample times, shape ``(T,)`` (L/U).
    states : numpy.ndarray
        State history, shape ``(T, 7)``.
    delta_c : numpy.ndarray
        Commanded rudder angle at each sample, shape ``(T,)`` (rad).
    metrics : dict, optional
        Manoeuvre metrics (empty by default).
    """

    kind: str
    t: np.ndarray
    states: np.ndarray
    delta_c: np.ndarray
    metrics: dict = field(default_factory=dict)

    def state(self, name: str) -> np.ndarray:
        return self.states[:, STATE_NAMES.index(name)]


def _zigzag_step(ship: ShipParams, steering: SteeringParams) -> ca.Function:
    """Step of the zig-zag: the rudder command reverses once the heading passes ±angle (state ``sign``)."""
    f = build_mmg(ship, steering)
    x = ca.SX.sym("x", NX + 1)
    p = ca.SX.sym("p", 4)  # angle (rad), n_rpm, dt, initial heading
    angle, n, dt, psi0 = p[0], p[1], p[2], p[3]
    sgn = x[NX]
    dc = sgn * angle
    xn = rk4(f, x[:NX], (dc, n), dt)
    dpsi = xn[5] - psi0
    sgn_n = ca.if_else(ca.logic_and(sgn > 0, dpsi >= angle), -1,
                       ca.if_else(ca.logic_and(sgn < 0, dpsi <= -angle), 1, sgn))
    return ca.Function("zigzag_step", [x, p], [ca.vertcat(xn, sgn_n), dc])


def _turning_step(ship: ShipParams, steering: SteeringParams) -> ca.Function:
    f = build_mmg(ship, steering)
    x = ca.SX.sym("x", NX)
    p = ca.SX.sym("p", 3)  # delta_c, n_rpm, dt
    return ca.Function("turning_step", [x, p], [rk4(f, x, (p[0], p[1]), p[2]), p[0]])


def _speed_step(ship: ShipParams, steering: SteeringParams) -> ca.Function:
    """Step of the speed change: rudder amidships, the propeller speed (state row ``NX``) follows the order."""
    f = build_mmg(ship, steering)
    x = ca.SX.sym("x", NX + 1)
    p = ca.SX.sym("p", 4)  # ordered rpm, rate (rpm per L/U), lag (L/U), dt
    n = x[NX]
    xn = rk4(f, x[:NX], (0.0, n), p[3])
    return ca.Function("speed_step", [x, p], [ca.vertcat(xn, engine_step(n, p[0], p[1], p[3], p[2])), n])


def _roll(step: ca.Function, x0, p, n_steps: int):
    return _run(compile_function(step, label=f"the manoeuvre ({step.name()})").mapaccum(n_steps), x0, p)


def _run(F: ca.Function, x0, p):
    """States (initial column first) and commands of a rolled-out step ``F`` from ``x0`` with parameters ``p``."""
    X, U = F(x0, p)
    X = np.hstack([np.asarray(x0, float)[:, None], np.array(X)])
    return X, np.array(U).ravel()


def turning_circle(rudder_deg: float = 35.0, *, port: bool = False, speed: float = 1.0, t_end: float = 60.0,
                   ship: ShipParams | None = None, steering: SteeringParams | None = None) -> ManeuverResult:
    """Turning circle with ``rudder_deg`` (magnitude, ≤ 35°) to starboard, or to port with ``port=True``.

    Metrics (lengths in L): ``advance`` (forward travel at 90° heading change), ``transfer`` (sideways travel at
    90°), ``tactical_diameter`` (sideways travel at 180°), ``x_min`` (smallest x after the 180° point),
    ``steady_diameter``, ``final_speed`` (U/U_des), ``direction``.

    Parameters
    ----------
    rudder_deg : float
        Rudder angle magnitude (degrees, (0, 35]).
    port : bool
        Turn to port instead of starboard.
    speed : float
        Approach speed (fraction of the design speed, [0.2, 1.2]).
    t_end : float
        Duration (L/U).
    ship, steering : ShipParams, SteeringParams, optional
        Ship and steering gear (default: the KCS).

    Returns
    -------
    ManeuverResult
        Time history (t in L/U, states, rudder command) with ``metrics`` from :func:`turning_metrics`.

    Examples
    --------
    >>> r = turning_circle(15)
    >>> round(r.metrics["advance"], 1), round(r.metrics["tactical_diameter"], 1)
    (5.2, 5.7)
    """
    ship = ship or load_kcs()
    steering = steering or load_steering()
    check_range("rudder", rudder_deg, 0.0, steering.delta_max_deg, low_open=True, unit="degrees")
    check_range("speed", speed, 0.2, 1.2, unit="(fraction of design speed)")
    n = propeller_rpm_for_speed(speed, ship)
    sign = -1.0 if port else 1.0
    x0 = [speed, 0, 0, 0, 0, 0, 0]
    steps = int(round(t_end / speed / DT))
    X, U = _roll(_turning_step(ship, steering), x0, [sign * math.radians(rudder_deg), n, DT], steps)
    t = np.arange(X.shape[1]) * DT
    res = ManeuverResult("turning", t, X.T, np.append(U, U[-1]))
    res.metrics = turning_metrics(res, rudder_deg, port, speed)
    return res


@functools.lru_cache(maxsize=8)
def _last_moment_rollout(ship: ShipParams, steering: SteeringParams, n_steps: int) -> ca.Function:
    """The last-moment manoeuvre's step, compiled and rolled over ``n_steps``: rudder amidships until the turn
    (state row ``NX``: time), then hard over. Built once per ship, steering gear and length, because
    :func:`~mmg_casadi.scenarios.imazu.stand_on_bound` tries many times of the turn."""
    f = build_mmg(ship, steering)
    x = ca.SX.sym("x", NX + 1)
    p = ca.SX.sym("p", 4)  # delta_c after the turn, n_rpm, dt, time of the turn
    dc = ca.if_else(x[NX] >= p[3] - p[2] / 2, p[0], 0.0)
    step = ca.Function("last_moment_step", [x, p], [ca.vertcat(rk4(f, x[:NX], (dc, p[1]), p[2]), x[NX] + p[2]), dc])
    return compile_function(step, label="the last-moment manoeuvre").mapaccum(n_steps)


def last_moment_manoeuvre(target_start, target_velocity, t_turn: float, *, port: bool = False,
                          rudder_deg: float = 35.0, speed: float = 1.0, t_end: float | None = None,
                          ship: ShipParams | None = None, steering: SteeringParams | None = None) -> ManeuverResult:
    """Course and speed kept until ``t_turn``, then the rudder hard over: the closest approach to a ship that holds
    course and speed.

    The own ship starts at the origin heading along x at ``speed``; the target starts at ``target_start`` and
    sails at ``target_velocity`` (both in that frame: L, U). What a stand-on ship can still do once she may act
    alone (Rule 17(a)(ii)) against a give-way ship that never acts; the propeller speed stays at its approach
    value. Metrics: ``min_distance`` (L) and ``t_min`` (L/U), the closest approach from the start to ``t_end``,
    ``t_turn``, ``rudder_deg`` and ``side``.

    Parameters
    ----------
    target_start, target_velocity : sequence of 2 floats
        The target's position at t = 0 (L) and her constant velocity over the ground (U).
    t_turn : float
        Time the rudder is put over (L/U, ≥ 0).
    port : bool, default False
        Hard over to port instead of starboard.
    rudder_deg : float
        Rudder angle magnitude (degrees, (0, 35]).
    speed : float
        Approach speed (fraction of the design speed, [0.2, 1.2]).
    t_end : float, optional
        Duration (L/U, > ``t_turn``); default ``t_turn`` + 20.
    ship, steering : ShipParams, SteeringParams, optional
        Ship and steering gear (default: the KCS).

    Returns
    -------
    ManeuverResult
        Time history (t in L/U, states, rudder command) with ``metrics``.

    Examples
    --------
    A ship crossing from 45° on the port bow at the same speed, met at (40, 0) at t = 40; turning hard to starboard
    at t = 30 passes her, at t = 38 does not:

    >>> start, v = (40 - 40 * 0.5 ** 0.5, -40 * 0.5 ** 0.5), (0.5 ** 0.5, 0.5 ** 0.5)
    >>> round(last_moment_manoeuvre(start, v, 30.0).metrics["min_distance"], 1)
    5.8
    >>> last_moment_manoeuvre(start, v, 38.0).metrics["min_distance"] < 2.0
    True
    """
    ship = ship or load_kcs()
    steering = steering or load_steering()
    check_range("rudder", rudder_deg, 0.0, steering.delta_max_deg, low_open=True, unit="degrees")
    check_range("speed", speed, 0.2, 1.2, unit="(fraction of design speed)")
    check_range("t_turn", t_turn, 0.0, None, unit="L/U")
    t_end = t_turn + 20.0 if t_end is None else check_range("t_end", t_end, t_turn, None, low_open=True, unit="L/U")
    n = propeller_rpm_for_speed(speed, ship)
    sign = -1.0 if port else 1.0
    steps = int(math.ceil(t_end / DT))
    X, U = _run(_last_moment_rollout(ship, steering, steps), [speed, 0, 0, 0, 0, 0, 0, 0.0],
                [sign * math.radians(rudder_deg), n, DT, t_turn])
    t = np.arange(X.shape[1]) * DT
    res = ManeuverResult("last-moment", t, X[:NX].T, np.append(U, U[-1]))
    target = np.asarray(target_start, dtype=float)[None, :] + t[:, None] * np.asarray(target_velocity, dtype=float)
    dist = np.hypot(res.state("x") - target[:, 0], res.state("y") - target[:, 1])
    k = int(np.argmin(dist))
    res.metrics = {"maneuver": "last-moment", "min_distance": float(dist[k]), "t_min": float(t[k]),
                   "t_turn": float(t_turn), "rudder_deg": float(rudder_deg), "side": "port" if port else "starboard",
                   "units": {"distances": "L", "times": "L/U_des", "angles": "deg"}}
    return res


def _crossing(t, y, level):
    """Time and index where ``y`` first reaches ``level`` (linear interpolation)."""
    k = int(np.argmax(y >= level))
    if y[k] < level:
        return None, None
    if k == 0:
        return t[0], 0
    a = (level - y[k - 1]) / (y[k] - y[k - 1])
    return t[k - 1] + a * (t[k] - t[k - 1]), k - 1 + a


def _interp(arr, fidx):
    k = int(fidx)
    a = fidx - k
    return arr[k] if a == 0 else (1 - a) * arr[k] + a * arr[k + 1]


def turning_metrics(res: ManeuverResult, rudder_deg: float, port: bool, speed: float) -> dict:
    """Advance, transfer, tactical diameter and steady turning of a turning-circle history.

    Parameters
    ----------
    res : ManeuverResult
        Turning-circle history (must reach 180° of heading change).
    rudder_deg : float
        Rudder angle of the turn (deg), recorded in the metrics.
    port : bool
        True for a turn to port, False to starboard.
    speed : float
        Approach speed (fraction of the design speed), recorded in the metrics.

    Returns
    -------
    dict
        ``advance``, ``transfer``, ``tactical_diameter``, ``x_min``, ``steady_diameter`` (L), ``time_to_90``,
        ``time_to_180`` (L/U_des), ``final_speed`` (U/U_des), the inputs ``rudder_deg``, ``direction`` and ``speed``,
        ``maneuver`` (``'turning'``) and ``units``.
    """
    psi = np.abs(res.state("psi"))
    x, y = res.state("x"), res.state("y")
    _, k90 = _crossing(res.t, psi, math.pi / 2)
    _, k180 = _crossing(res.t, psi, math.pi)
    if k90 is None or k180 is None:
        raise RuntimeError("the turn did not reach 180 degrees of heading change; increase t_end")
    k360 = _crossing(res.t, psi, 2 * math.pi)[1]
    after = slice(int(k180), int(k360) if k360 is not None else len(psi))
    u, v = res.state("u"), res.state("v")
    return {
        "maneuver": "turning",
        "rudder_deg": float(rudder_deg),
        "direction": "port" if port else "starboard",
        "speed": float(speed),
        "advance": float(_interp(x, k90)),
        "transfer": float(abs(_interp(y, k90))),
        "tactical_diameter": float(abs(_interp(y, k180))),
        "x_min": float(np.min(x[after])),
        "steady_diameter": float(np.max(x[after]) - np.min(x[after])),
        "time_to_90": float(_interp(res.t, k90)),
        "time_to_180": float(_interp(res.t, k180)),
        "final_speed": float(np.hypot(u[-1], v[-1])),
        "units": {"lengths": "L", "times": "L/U_des", "speed": "U/U_des"},
    }


def zigzag(angle_deg: float = 10.0, *, port: bool = False, speed: float = 1.0, t_end: float = 40.0,
           ship: ShipParams | None = None, steering: SteeringParams | None = None) -> ManeuverResult:
    """Zig-zag ``angle_deg``/``angle_deg``, first to starboard, or first to port with ``port=True``.

    Metrics (degrees): ``overshoot_1`` and ``overshoot_2`` — how far the heading goes beyond ±angle after the
    first and second rudder reversals; times non-dimensional.

    Parameters
    ----------
    angle_deg : float
        Rudder angle and heading-change trigger (degrees, (0, 35]).
    port : bool, default False
        First rudder to port (the −angle/−angle zig-zag); the overshoots are then measured to port first.
    speed : float
        Approach speed (fraction of the design speed, [0.2, 1.2]).
    t_end : float
        Duration (L/U).
    ship, steering : ShipParams, SteeringParams, optional
        Ship and steering gear (default: the KCS).

    Returns
    -------
    ManeuverResult
        Time history (t in L/U, states, rudder command) with ``metrics`` from :func:`zigzag_metrics`.

    Examples
    --------
    >>> r = zigzag(10)
    >>> 0 < r.metrics["overshoot_1"] < 14.3
    True
    """
    ship = ship or load_kcs()
    steering = steering or load_steering()
    check_range("angle", angle_deg, 0.0, steering.delta_max_deg, low_open=True, unit="degrees")
    check_range("speed", speed, 0.2, 1.2, unit="(fraction of design speed)")
    n = propeller_rpm_for_speed(speed, ship)
    a = math.radians(angle_deg)
    steps = int(round(t_end / speed / DT))
    X, U = _roll(_zigzag_step(ship, steering), [speed, 0, 0, 0, 0, 0, 0, -1.0 if port else 1.0], [a, n, DT, 0.0],
                 steps)
    t = np.arange(X.shape[1]) * DT
    res = ManeuverResult("zigzag", t, X[:NX].T, np.append(U, U[-1]))
    res.metrics = zigzag_metrics(res, X[NX], angle_deg)
    return res


def zigzag_metrics(res: ManeuverResult, sign: np.ndarray, angle_deg: float) -> dict:
    """Overshoot angles and times of a zig-zag history with rudder-sign history ``sign``.

    Parameters
    ----------
    res : ManeuverResult
        Zig-zag history.
    sign : numpy.ndarray
        Rudder-command sign (±1) at each sample; needs three reversals. A history that starts with −1 (first to
        port) is measured mirrored, so its overshoots are positive like a starboard-first one's.
    angle_deg : float
        Zig-zag rudder angle and heading trigger (deg).

    Returns
    -------
    dict
        ``overshoot_1``, ``overshoot_2`` (deg), ``time_first_reversal``, ``time_overshoot_1``,
        ``time_overshoot_2`` (L/U_des), ``angle_deg``, ``maneuver`` (``'zigzag'``) and ``units``.
    """
    psi = np.degrees(res.state("psi")) * (1.0 if sign[0] > 0 else -1.0)
    rev = np.flatnonzero(np.diff(sign) != 0) + 1  # samples after each rudder reversal
    if len(rev) < 3:
        raise RuntimeError("fewer than three rudder reversals; increase t_end")
    seg1 = psi[rev[0]:rev[1] + 1]
    seg2 = psi[rev[1]:rev[2] + 1]
    return {
        "maneuver": "zigzag",
        "angle_deg": float(angle_deg),
        "overshoot_1": float(seg1.max() - angle_deg),
        "overshoot_2": float(-seg2.min() - angle_deg),
        "time_first_reversal": float(res.t[rev[0]]),
        "time_overshoot_1": float(res.t[rev[0] + int(np.argmax(seg1))]),
        "time_overshoot_2": float(res.t[rev[1] + int(np.argmin(seg2))]),
        "units": {"angles": "deg", "times": "L/U_des"},
    }


SPEED_BAND = 0.05
"""A speed change is complete when the speed is within this fraction of the change from the new steady speed."""


def speed_change(to_speed: float = 0.5, *, speed: float = 1.0, t_end: float = 120.0,
                 ship: ShipParams | None = None, steering: SteeringParams | None = None) -> ManeuverResult:
    """Speed change on a straight course: from steady running at ``speed``, the propeller speed is ordered to that
    of a steady ``to_speed`` and follows it through the engine (rate ``engine_rate_rpm_s``, lag
    ``engine_lag_s``, the table's defaults); the rudder stays amidships.

    Metrics: ``rpm_from``/``rpm_to`` (rev/min), ``final_speed`` (U/U_des at ``t_end``), ``t_engine``
    (time until the propeller reaches the order within 1 %), ``t_change`` and ``reach_change`` (time and distance
    run until the speed is within :data:`SPEED_BAND` of the change from ``to_speed``), in L/U and L and in s and m.

    Parameters
    ----------
    to_speed : float
        New speed (fraction of the design speed, [0.2, 1.2]).
    speed : float
        Approach speed (fraction of the design speed, [0.2, 1.2]).
    t_end : float
        Duration (L/U).
    ship, steering : ShipParams, SteeringParams, optional
        Ship and steering gear (default: the KCS).

    Returns
    -------
    ManeuverResult
        Time history (t in L/U, states, rudder command zero) with ``metrics`` from :func:`speed_metrics`.

    Examples
    --------
    >>> r = speed_change(0.5)
    >>> round(r.metrics["final_speed"], 3), r.metrics["t_change"] > r.metrics["t_engine"]
    (0.5, True)
    """
    ship = ship or load_kcs()
    steering = steering or load_steering()
    check_range("speed", speed, 0.2, 1.2, unit="(fraction of design speed)")
    check_range("to_speed", to_speed, 0.2, 1.2, unit="(fraction of design speed)")
    check_range("t_end", t_end, 0.0, 1000.0, low_open=True, unit="L/U")
    n0, n1 = propeller_rpm_for_speed(speed, ship), propeller_rpm_for_speed(to_speed, ship)
    rate = PARAMETERS["engine_rate_rpm_s"].default * ship.time_scale_s
    lag = PARAMETERS["engine_lag_s"].default / ship.time_scale_s
    steps = int(round(t_end / DT))
    X, _ = _roll(_speed_step(ship, steering), [speed, 0, 0, 0, 0, 0, 0, n0], [n1, rate, lag, DT], steps)
    t = np.arange(X.shape[1]) * DT
    res = ManeuverResult("speed", t, X[:NX].T, np.zeros(X.shape[1]))
    res.metrics = speed_metrics(res, X[NX], speed, to_speed, n0, n1, ship)
    return res


def speed_metrics(res: ManeuverResult, n: np.ndarray, speed: float, to_speed: float, n0: float, n1: float,
                  ship: ShipParams) -> dict:
    """Metrics of :func:`speed_change` (see there).

    Parameters
    ----------
    res : ManeuverResult
        The manoeuvre's time history.
    n : numpy.ndarray
        Propeller speed at each sample (rev/min).
    speed, to_speed : float
        Approach and new speed (fractions of the design speed).
    n0, n1 : float
        Approach and ordered propeller speed (rev/min).
    ship : ShipParams
        The ship (its length and time scale convert to m and s).

    Returns
    -------
    dict
        ``rpm_from``, ``rpm_to`` (rev/min), ``final_speed`` (U/U_des), ``t_engine``, ``t_change`` (L/U_des),
        ``reach_change`` (L), ``t_engine_s``, ``t_change_s`` (s), ``reach_change_m`` (m), the inputs ``speed`` and
        ``to_speed``, ``kind`` (``'speed'``) and ``units``.
    """
    u = res.state("u")
    band = SPEED_BAND * abs(speed - to_speed)
    out_of_band = np.flatnonzero(np.abs(u - to_speed) > band)
    k = min(len(u) - 1, out_of_band[-1] + 1) if len(out_of_band) else 0
    k_engine = int(np.argmax(np.abs(n - n1) <= 0.01 * abs(n1 - n0) + 1e-12))
    reach = float(res.state("x")[k])
    ts = ship.time_scale_s
    return {"kind": "speed", "speed": speed, "to_speed": to_speed, "rpm_from": n0, "rpm_to": n1,
            "final_speed": float(u[-1]), "t_engine": float(res.t[k_engine]), "t_change": float(res.t[k]),
            "reach_change": reach, "t_change_s": float(res.t[k]) * ts, "reach_change_m": reach * ship.L,
            "t_engine_s": float(res.t[k_engine]) * ts, "units": {"times": "L/U_des", "lengths": "L"}}


def validate_maneuver_args(kind: str) -> None:
    """Raise :class:`ParameterError` for an unknown manoeuvre name.

    Parameters
    ----------
    kind : str
        Manoeuvre name; ``'turning'``, ``'zigzag'`` or ``'speed'`` is accepted.
    """
    if kind not in ("turning", "zigzag", "speed"):
        raise ParameterError("maneuver", "one of: turning, zigzag, speed", kind)
