"""Sensor models of the own ship: AIS position reports and radar plots of the target ships.

**AIS** (Automatic Identification System). A target transmits a position report (position, speed and course over
the ground) at the nominal reporting interval of ITU-R M.1371-5 (Recommendation ITU-R M.1371-5, 2014, Annex 1,
Table 1 for Class A shipborne equipment, Table 2 for Class B "CS"), :func:`ais_interval_s`:

=========================================  ==================
Class A, under way                          interval
=========================================  ==================
0-14 kn                                     10 s
0-14 kn and changing course                 3 1/3 s
14-23 kn                                    6 s
14-23 kn and changing course                2 s
over 23 kn (changing course or not)         2 s
Class B "CS", not faster than 2 kn          3 min
Class B "CS", faster than 2 kn              30 s
=========================================  ==================

"Changing course" is read as a rate of turn above 5 degrees per 30 s (:data:`TURNING_DEG_PER_S`), the threshold of
the rate-of-turn field of the position report (M.1371-5 Annex 8, message 1). The model ships are all under way
(the table's rows for a ship at anchor or moored are not used). A report is received ``ais_latency_s`` after it was
sent, unless it is lost (probability ``ais_dropout``, independently per report); its position carries the
GNSS error (``ais_position_sigma_m`` per axis), its speed and course the errors ``ais_sog_sigma_kn`` and
``ais_cog_sigma_deg`` (the course error applied to first order, so that zero noise reports the velocity exactly).

**Radar** measures range and bearing from the own ship with Gaussian errors (``radar_range_sigma_m``,
``radar_bearing_sigma_deg``) once per guidance step (an antenna turns in 2.5-3 s, shorter than the step) and
detects a target within ``radar_range_nm`` with probability ``radar_p_detect`` per step; the defaults are those of the
IMO performance standard for radar equipment, resolution MSC.192(79) (range accuracy 30 m, bearing accuracy 1 deg,
both 95 %; ships over 5000 GT detected at 11 NM), see :mod:`mmg_casadi.params`.

Every function here takes CasADi expressions (the compiled step) and plain numbers alike.

Examples
--------
>>> ais_interval_s(12.0, 0.0, 0.0), ais_interval_s(12.0, 1.0, 0.0), ais_interval_s(18.0, 0.0, 0.0)
(10.0, 3.3333333333333335, 6.0)
>>> ais_interval_s(25.0, 0.0, 0.0), ais_interval_s(12.0, 0.0, 1.0), ais_interval_s(1.0, 0.0, 1.0)
(2.0, 30.0, 180.0)
"""

from __future__ import annotations

import math

from mmg_casadi.perception.rng import _where

TURNING_DEG_PER_S = 5.0 / 30.0
"""A ship "changing course" in the sense of ITU-R M.1371's reporting table turns faster than this (deg/s)."""

CLASS_A = ((14.0, 10.0, 10.0 / 3.0), (23.0, 6.0, 2.0), (math.inf, 2.0, 2.0))
"""ITU-R M.1371-5 Annex 1 Table 1, a Class A ship under way: (speed up to, kn; interval, s; interval while changing
course, s)."""
CLASS_B_CS = ((2.0, 180.0), (math.inf, 30.0))
"""ITU-R M.1371-5 Annex 1 Table 2, Class B "CS": (speed up to, kn; interval, s)."""


def ais_interval_s(speed_kn, turning, class_b):
    """Nominal AIS reporting interval (s) of a ship (ITU-R M.1371-5 Annex 1, Tables 1 and 2).

    Parameters
    ----------
    speed_kn : number or expression
        Speed over the ground (kn).
    turning : number or expression
        1 while changing course (rate of turn above :data:`TURNING_DEG_PER_S`), else 0.
    class_b : number or expression
        1 for Class B "CS" equipment, 0 for Class A.

    Returns
    -------
    number or expression
        The interval (s).
    """
    (v1, a1, t1), (v2, a2, t2), (_, a3, t3) = CLASS_A
    a = _where(speed_kn <= v1, _where(turning > 0.5, t1, a1),
               _where(speed_kn <= v2, _where(turning > 0.5, t2, a2), _where(turning > 0.5, t3, a3)))
    b = _where(speed_kn <= CLASS_B_CS[0][0], CLASS_B_CS[0][1], CLASS_B_CS[1][1])
    return _where(class_b > 0.5, b, a)


def ais_velocity(vx, vy, n_sog, n_cog, sigma_sog, sigma_cog):
    """A reported velocity: the true one with a speed error along it and a course error across it (first order).

    Parameters
    ----------
    vx, vy : number or expression
        True velocity over the ground.
    n_sog, n_cog : number or expression
        Standard normal numbers.
    sigma_sog, sigma_cog : number or expression
        Standard deviations of the speed (velocity units) and of the course (rad).

    Returns
    -------
    (number or expression, number or expression)
        ``v + sigma_sog n_sog e + sigma_cog n_cog (-vy, vx)``, ``e`` the unit vector along ``v``: the true velocity
        exactly when both deviations are zero.
    """
    speed = _sqrt(vx * vx + vy * vy)
    ex, ey = vx / _fmax(speed, 1e-12), vy / _fmax(speed, 1e-12)
    return vx + sigma_sog * n_sog * ex - sigma_cog * n_cog * vy, vy + sigma_sog * n_sog * ey + sigma_cog * n_cog * vx


def radar_plot(dx, dy, n_r, n_b, sigma_r, sigma_b):
    """A radar plot of a target at ``(dx, dy)`` from the own ship: the measured offset and its covariance.

    Parameters
    ----------
    dx, dy : number or expression
        True offset of the target from the own ship.
    n_r, n_b : number or expression
        Standard normal numbers.
    sigma_r, sigma_b : number or expression
        Standard deviations of range and bearing (rad).

    Returns
    -------
    tuple
        ``(zx, zy, rxx, rxy, ryy)``: the measured offset (range ``r + sigma_r n_r`` at bearing
        ``b + sigma_b n_b``) and the covariance of the converted measurement, ``J diag(sigma_r^2, sigma_b^2) J^T``
        with ``J`` the Jacobian of the polar-to-Cartesian map at the measurement (the converted-measurement Kalman
        filter, Bar-Shalom, Li & Kirubarajan 2001, §10.4).
    """
    r = _sqrt(dx * dx + dy * dy) + sigma_r * n_r
    b = _atan2(dy, dx) + sigma_b * n_b
    c, s = _cos(b), _sin(b)
    vr, vb = sigma_r * sigma_r, r * r * sigma_b * sigma_b
    return r * c, r * s, vr * c * c + vb * s * s, (vr - vb) * s * c, vr * s * s + vb * c * c


def _fn(name):
    def f(*a):
        if all(isinstance(v, (float, int)) for v in a):
            return getattr(math, name)(*a)
        import casadi as ca
        return getattr(ca, name)(*a)
    return f


_sqrt, _cos, _sin, _atan2 = _fn("sqrt"), _fn("cos"), _fn("sin"), _fn("atan2")


def _fmax(a, b):
    if isinstance(a, (float, int)):
        return max(a, b)
    import casadi as ca
    return ca.fmax(a, b)
