"""Integral line-of-sight (ILOS) guidance and waypoint switching (paper §3.1–3.2).

Conventions: positions in ship lengths L, x forward/north, y to starboard/east, angles in rad measured from x
towards y. The cross-track error ``y_e`` is positive when the ship lies to starboard of the path, and the ILOS law
then asks for a heading to port (``psi_d < pi_p``).

Every function takes CasADi expressions (SX or MX) or plain numbers / DM and returns CasADi expressions (plain
numbers in, plain numbers or DM out), so one definition serves simulation, linearisation and tuning.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from mmg_casadi.errors import ParameterError
from mmg_casadi.params import check_fields
from mmg_casadi.params import field as param_field

_CASADI_TYPES = (ca.SX, ca.MX, ca.DM)


@dataclass(frozen=True)
class IlosParams:
    """ILOS guidance parameters (paper Table 2).

    ``delta``: look-ahead distance Δ (L, > 0); ``k``: integral ratio, K_i^g = k K_p^g (dimensionless, ≥ 0);
    ``r_tol``: waypoint acceptance radius R_tol (L, > 0).

    Parameters
    ----------
    delta : float
        Look-ahead distance Δ (L, > 0).
    k : float
        Integral ratio k, with K_i^g = k K_p^g (dimensionless, ≥ 0).
    r_tol : float
        Waypoint acceptance radius R_tol (L, > 0).
    """

    delta: float = param_field("ilos_delta")
    k: float = param_field("ilos_k")
    r_tol: float = param_field("goal_tolerance")

    def __post_init__(self):
        check_fields(self)

    @property
    def kp_g(self) -> float:
        """Proportional guidance gain K_p^g = 1/Δ (1/L)."""
        return 1.0 / self.delta

    @property
    def ki_g(self) -> float:
        """Integral guidance gain K_i^g = k/Δ (1/L)."""
        return self.k / self.delta


def _xy(v):
    """The two components of a 2-vector (CasADi column, sequence or numpy array)."""
    if isinstance(v, np.ndarray):
        v = v.astype(float).ravel()
        return float(v[0]), float(v[1])
    return v[0], v[1]


def _as_matrix(path):
    """``path`` as a CasADi matrix (numpy arrays and nested lists become DM)."""
    return path if isinstance(path, _CASADI_TYPES) else ca.DM(np.asarray(path, dtype=float))


def wrap_angle(a):
    """Wrap an angle to (-π, π] via atan2(sin a, cos a).

    Parameters
    ----------
    a : float or casadi.SX or casadi.MX
        Angle to wrap (rad).

    Returns
    -------
    float or casadi.SX or casadi.MX
        The angle in (-π, π] (rad).

    Examples
    --------
    >>> import math
    >>> round(float(wrap_angle(3 * math.pi / 2)), 6), float(wrap_angle(-math.pi)) == math.pi
    (-1.570796, True)
    """
    w = ca.atan2(ca.sin(a), ca.cos(a))
    return w + 2 * ca.pi * (w <= -ca.pi)


def limit_turn(psi, target, limit):
    """The heading at most ``limit`` from ``psi`` on the shorter way to ``target`` (a limited turn).

    Parameters
    ----------
    psi : float or casadi.SX or casadi.MX
        Present heading (rad).
    target : float or casadi.SX or casadi.MX
        Heading to turn towards (rad).
    limit : float or casadi.SX or casadi.MX
        Largest turn (rad, ≥ 0; π or more: ``target`` itself, up to a multiple of 2π).

    Returns
    -------
    float or casadi.SX or casadi.MX
        ``psi`` plus the wrapped difference ``target − psi`` clipped to ±``limit`` (rad, not wrapped).

    Examples
    --------
    >>> import math
    >>> round(math.degrees(float(limit_turn(0.0, math.radians(170.0), math.radians(15.0)))), 6)
    15.0
    >>> round(math.degrees(float(limit_turn(0.0, math.radians(-170.0), math.pi))), 6)
    -170.0
    """
    return psi + ca.fmin(ca.fmax(wrap_angle(target - psi), -limit), limit)


def path_tangential_angle(wp_prev, wp_next):
    """Path tangential angle π_p of the segment ``wp_prev`` → ``wp_next`` (all four quadrants).

    Parameters
    ----------
    wp_prev : array_like or casadi.SX or casadi.MX
        Start point (x, y) of the segment (L).
    wp_next : array_like or casadi.SX or casadi.MX
        End point (x, y) of the segment (L).

    Returns
    -------
    float or casadi.SX or casadi.MX
        π_p (rad, in [-π, π]).

    Examples
    --------
    >>> round(float(path_tangential_angle([0, 0], [-1, -1])), 6)
    -2.356194
    """
    xk, yk = _xy(wp_prev)
    xk1, yk1 = _xy(wp_next)
    return ca.atan2(yk1 - yk, xk1 - xk)  # eq. (pi_p)


def path_errors(pos, wp_prev, wp_next):
    """Along-track distance ``x_e`` and cross-track error ``y_e`` of ``pos`` w.r.t. a path segment (L).

    ``y_e > 0`` when the ship is to starboard of the path (e.g. path along +x, ship at y = +1).

    Parameters
    ----------
    pos : array_like or casadi.SX or casadi.MX
        Ship position (x, y) (L).
    wp_prev : array_like or casadi.SX or casadi.MX
        Start point (x, y) of the segment (L).
    wp_next : array_like or casadi.SX or casadi.MX
        End point (x, y) of the segment (L).

    Returns
    -------
    x_e : casadi.SX or casadi.MX or casadi.DM
        Along-track distance from ``wp_prev`` (L).
    y_e : casadi.SX or casadi.MX or casadi.DM
        Cross-track error (L, > 0 to starboard of the path).

    Examples
    --------
    >>> x_e, y_e = path_errors([4.0, 1.0], [0.0, 0.0], [10.0, 0.0])
    >>> float(x_e), float(y_e)
    (4.0, 1.0)
    """
    xn, yn = _xy(pos)
    xk, yk = _xy(wp_prev)
    pi_p = path_tangential_angle(wp_prev, wp_next)
    rx, ry = xn - xk, yn - yk  # eq. (r_in_gcs)
    c, s = ca.cos(pi_p), ca.sin(pi_p)
    return c * rx + s * ry, -s * rx + c * ry  # eq. (crosstrack_error)


def ilos_heading(pi_p, y_e, y_int, delta, k):
    """ILOS desired heading ψ_d = π_p − atan(y_e/Δ + (k/Δ) y_int), wrapped to (-π, π].

    Parameters
    ----------
    pi_p : float or casadi.SX or casadi.MX
        Path tangential angle π_p (rad).
    y_e : float or casadi.SX or casadi.MX
        Cross-track error (L).
    y_int : float or casadi.SX or casadi.MX
        ILOS integral state (L·L/U).
    delta : float
        Look-ahead distance Δ (L, > 0).
    k : float
        Integral ratio k (dimensionless, ≥ 0).

    Returns
    -------
    float or casadi.SX or casadi.MX
        Desired heading ψ_d (rad, in (-π, π]).

    Examples
    --------
    >>> import math
    >>> round(math.degrees(float(ilos_heading(0.0, 2.0, 0.0, 2.0, 0.05))), 6)
    -45.0
    """
    return wrap_angle(pi_p - ca.atan(y_e / delta + (k / delta) * y_int))  # eq. (psi_desired)


def ilos_integrator_rate(y_e, y_int, delta, k):
    """Rate of the ILOS integral state, ẏ_int = Δ y_e / (Δ² + (y_e + k y_int)²).

    ``|ẏ_int| ≤ |y_e|/Δ``, so y_int stays bounded whenever ``∫|y_e| dt`` is.

    Parameters
    ----------
    y_e : float or casadi.SX or casadi.MX
        Cross-track error (L).
    y_int : float or casadi.SX or casadi.MX
        ILOS integral state (L·L/U).
    delta : float
        Look-ahead distance Δ (L, > 0).
    k : float
        Integral ratio k (dimensionless, ≥ 0).

    Returns
    -------
    float or casadi.SX or casadi.MX
        ẏ_int (L).

    Examples
    --------
    >>> float(ilos_integrator_rate(2.0, 0.0, 2.0, 0.05))
    0.5
    """
    return delta * y_e / (delta**2 + (y_e + k * y_int) ** 2)  # eq. (ype_int_dot)


def _one_hot(idx, j):
    """1 when the (integer-valued) float ``idx`` equals ``j``, else 0; tolerant to rounding."""
    return ca.lt(ca.fabs(idx - j), 0.5)


def select_segment(path, idx):
    """Segment endpoints (``path[:, idx-1]``, ``path[:, idx]``) of a 2×K waypoint matrix, for symbolic ``idx``.

    ``path`` holds the start position in column 0 and the waypoints in columns 1.. (padded to K columns by
    repeating the last waypoint). ``idx`` is the float index of the waypoint being tracked (1 ≤ idx ≤ K−1); the
    columns are picked by a one-hot sum, so ``idx`` may be a CasADi symbol.

    Parameters
    ----------
    path : array_like or casadi.DM or casadi.SX or casadi.MX
        2×K matrix of the start and waypoints (L).
    idx : float or casadi.SX or casadi.MX
        Float index of the tracked waypoint (1 ≤ idx ≤ K−1).

    Returns
    -------
    wp_prev : casadi.SX or casadi.MX or casadi.DM (2, 1)
        Start point of the segment (L).
    wp_next : casadi.SX or casadi.MX or casadi.DM (2, 1)
        End point of the segment, the tracked waypoint (L).

    Examples
    --------
    >>> prev, nxt = select_segment([[0, 10, 10], [0, 0, 10]], 2.0)
    >>> prev.T, nxt.T
    (DM([[10, 0]]), DM([[10, 10]]))
    """
    path = _as_matrix(path)
    n_cols = path.shape[1]
    wp_prev = sum(path[:, j] * _one_hot(idx, j + 1) for j in range(n_cols - 1))
    wp_next = sum(path[:, j] * _one_hot(idx, j) for j in range(1, n_cols))
    return wp_prev, wp_next


def switch_waypoint(pos, path, idx, n, r_tol):
    """Waypoint switching: the new index and a 0/1 flag for "final waypoint reached".

    When the ship is within ``r_tol`` of the tracked waypoint (boundary included), ``idx`` advances by one if
    ``idx < n - 1``; at the final waypoint (``idx == n - 1``) it stays and ``reached_final`` is 1. ``n`` is the
    number of real columns of ``path`` (start + waypoints, n ≥ 2). The flag is not latched: a closed loop should
    carry its own ``done`` state.

    Parameters
    ----------
    pos : array_like or casadi.SX or casadi.MX
        Ship position (x, y) (L).
    path : array_like or casadi.DM or casadi.SX or casadi.MX
        2×K matrix of the start and waypoints (L).
    idx : float or casadi.SX or casadi.MX
        Float index of the tracked waypoint.
    n : int or float
        Number of real columns of ``path`` (start + waypoints, ≥ 2).
    r_tol : float
        Waypoint acceptance radius R_tol (L).

    Returns
    -------
    idx : casadi.SX or casadi.MX or casadi.DM
        The new float index of the tracked waypoint.
    reached_final : casadi.SX or casadi.MX or casadi.DM
        1 if the final waypoint is within ``r_tol``, else 0.

    Examples
    --------
    >>> path = [[0, 10, 10], [0, 0, 10]]
    >>> [float(v) for v in switch_waypoint([7.0, 0.0], path, 1.0, 3, 3.0)]
    [2.0, 0.0]
    >>> [float(v) for v in switch_waypoint([10.0, 7.5], path, 2.0, 3, 3.0)]
    [2.0, 1.0]
    """
    _, wp_next = select_segment(path, idx)
    xn, yn = _xy(pos)
    dx, dy = wp_next[0] - xn, wp_next[1] - yn
    inside = ca.le(dx**2 + dy**2, r_tol**2)  # eq. (switch_waypoints), squared
    has_next = ca.lt(idx + 0.5, n - 1)
    return idx + inside * has_next, inside * (1 - has_next)


def ilos_step_terms(pos, path, idx, y_int, delta, k):
    """All ILOS guidance terms for one step: a dict with ``psi_d``, ``y_e``, ``x_e``, ``pi_p``, ``y_int_dot``,
    ``wp_prev`` and ``wp_next``.

    Parameters
    ----------
    pos : array_like or casadi.SX or casadi.MX
        Ship position (x, y) (L).
    path : array_like or casadi.DM or casadi.SX or casadi.MX
        2×K matrix of the start and waypoints (L).
    idx : float or casadi.SX or casadi.MX
        Float index of the tracked waypoint.
    y_int : float or casadi.SX or casadi.MX
        ILOS integral state (L·L/U).
    delta : float
        Look-ahead distance Δ (L, > 0).
    k : float
        Integral ratio k (dimensionless, ≥ 0).

    Returns
    -------
    dict
        ``psi_d``, ``pi_p`` (rad), ``y_e``, ``x_e`` (L), ``y_int_dot`` (L) and ``wp_prev``, ``wp_next`` (2x1, L).

    Examples
    --------
    >>> t = ilos_step_terms([5.0, 1.0], [[0, 10], [0, 0]], 1.0, 0.0, 2.0, 0.05)
    >>> round(float(t["psi_d"]), 6), float(t["y_e"]), float(t["y_int_dot"])
    (-0.463648, 1.0, 0.4)
    """
    wp_prev, wp_next = select_segment(path, idx)
    pi_p = path_tangential_angle(wp_prev, wp_next)
    x_e, y_e = path_errors(pos, wp_prev, wp_next)
    return {
        "psi_d": ilos_heading(pi_p, y_e, y_int, delta, k),
        "y_e": y_e,
        "x_e": x_e,
        "pi_p": pi_p,
        "y_int_dot": ilos_integrator_rate(y_e, y_int, delta, k),
        "wp_prev": wp_prev,
        "wp_next": wp_next,
    }


def validate_waypoints(points, field: str = "waypoints"):
    """Check a path given as a sequence of (x, y) points: at least two points (start and one waypoint).

    Parameters
    ----------
    points : sequence of (float, float)
        The start and the waypoints (x, y) (L).
    field : str, optional
        Name reported in the error if the path is invalid.

    Returns
    -------
    tuple of (float, float)
        The points as float pairs.

    Examples
    --------
    >>> validate_waypoints([(0, 0), (50, 0)])
    ((0.0, 0.0), (50.0, 0.0))
    """
    pts = tuple((float(p[0]), float(p[1])) for p in points)
    if len(pts) < 2:
        raise ParameterError(field, "at least two points (the start and one waypoint)", len(pts))
    return pts
