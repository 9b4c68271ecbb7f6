"""Steering gear: rudder saturation and first-order response with a rate limit."""

from __future__ import annotations

import casadi as ca


def saturate(x, limit):
    """Clip ``x`` to ``[-limit, limit]`` (CasADi expression).

    Parameters
    ----------
    x : float or casadi.SX or casadi.MX
        Value to clip.
    limit : float or casadi.SX or casadi.MX
        Non-negative bound of the symmetric interval.

    Returns
    -------
    float or casadi.SX or casadi.MX
        ``x`` clipped to ``[-limit, limit]``.
    """
    return ca.fmin(ca.fmax(x, -limit), limit)


def steering_rate(delta, delta_c, T_delta, rate_max, delta_max):
    """Rudder rate δ̇ of the steering gear.

    The command is first saturated at ±``delta_max``; the rudder then follows a first-order lag with time constant
    ``T_delta`` whose rate is clipped to ±``rate_max`` (all angles in rad, time non-dimensional).

    Parameters
    ----------
    delta : float or casadi.SX or casadi.MX
        Actual rudder angle δ (rad).
    delta_c : float or casadi.SX or casadi.MX
        Commanded rudder angle δ_c (rad), saturated at ±``delta_max``.
    T_delta : float
        Time constant of the first-order steering lag (L/U).
    rate_max : float
        Maximum rudder rate (rad per unit time L/U).
    delta_max : float
        Rudder-angle saturation (rad).

    Returns
    -------
    float or casadi.SX or casadi.MX
        Rudder rate δ̇ (rad per unit time L/U), within ±``rate_max``.

    Examples
    --------
    >>> import math
    >>> float(steering_rate(0.0, math.radians(10), 1.0, 1.6256, math.radians(35)))  # unsaturated: (δc-δ)/T
    0.17453292519943295
    >>> float(steering_rate(0.0, 1.0, 1.0, 0.1, math.radians(35)))  # rate limited
    0.1
    """
    dc = saturate(delta_c, delta_max)
    return saturate((dc - delta) / T_delta, rate_max)  # eq. (delta_dot_equation)


def engine_step(n, n_c, rate_max, dt, lag=0.0):
    """Propeller speed after one guidance step: a first-order lag towards the command with a bounded rate.

    ``n_next = n + sat((n_c - n)(1 - exp(-dt / lag)), rate_max dt)`` (``lag = 0``: no lag, the rate limit
    alone); a command equal to the present speed leaves it exactly unchanged.

    Parameters
    ----------
    n : float or casadi.SX or casadi.MX
        Propeller speed at the start of the step (rev/min).
    n_c : float or casadi.SX or casadi.MX
        Commanded propeller speed (rev/min).
    rate_max : float or casadi.SX or casadi.MX
        Largest change of propeller speed per unit time (rev/min per L/U).
    dt : float or casadi.SX or casadi.MX
        Guidance step (L/U).
    lag : float or casadi.SX or casadi.MX, default 0
        Time constant of the engine's first-order response (L/U).

    Returns
    -------
    float or casadi.SX or casadi.MX
        Propeller speed at the end of the step (rev/min).

    Examples
    --------
    >>> float(engine_step(100.0, 50.0, 10.0, 0.25)), float(engine_step(100.0, 99.0, 10.0, 0.25))
    (97.5, 99.0)
    >>> round(float(engine_step(100.0, 99.0, 10.0, 0.25, lag=0.5)), 4)  # 1 - exp(-0.5) of the way
    99.6065
    """
    return n + saturate((n_c - n) * (1 - ca.exp(-dt / ca.fmax(lag, 1e-12))), rate_max * dt)
