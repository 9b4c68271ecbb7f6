"""Tracking metrics from sampled trajectories — the test check of the closed loop's exact CE/MCTE.

The one definition of CE and MCTE is :func:`mmg_casadi.closed_loop.outcome.voyage_metrics`, from integrals the
compiled step accumulates; the tests compare it with these trajectory integrals (paper §3.4).

Time is non-dimensional, cross-track errors are in ship lengths L, rudder angles in rad. Integrals use the
trapezoidal rule over the samples and T = t[-1] − t[0]. A trajectory with fewer than two samples (or T ≤ 0) has
no duration, and its CE and MCTE are ``nan``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from mmg_casadi.errors import check_range
from mmg_casadi.params import PARAMETERS

DELTA_MAX_DEFAULT = float(np.radians(PARAMETERS["delta_max_deg"].default))


def _mean_abs(t, x, name):
    """(1/T) ∫|x| dt by the trapezoidal rule; ``nan`` without a positive duration."""
    t = np.asarray(t, dtype=float).ravel()
    x = np.asarray(x, dtype=float).ravel()
    if t.shape != x.shape:
        raise ValueError(f"{name}: expected {t.size} samples like t, got {x.size}")
    if t.size < 2 or not t[-1] > t[0]:
        return float("nan")
    return float(np.trapezoid(np.abs(x), t) / (t[-1] - t[0]))


def control_effort(t, delta, delta_max=DELTA_MAX_DEFAULT):
    """Controller effort CE = (1/(δ_max T)) ∫|δ| dt of the actual rudder ``delta`` (rad); ``delta_max`` in rad.

    Parameters
    ----------
    t : array_like
        Sample times (L/U).
    delta : array_like
        Actual rudder angle at each sample (rad).
    delta_max : float, optional
        Rudder saturation used for normalisation (rad, > 0); 35° by default.

    Examples
    --------
    >>> round(control_effort([0.0, 1.0, 2.0], [0.1, -0.1, 0.1], delta_max=0.2), 6)
    0.5
    """
    dmax = check_range("delta_max", delta_max, 0.0, None, low_open=True, unit="rad")
    return _mean_abs(t, delta, "delta") / dmax  # eq. (controller_effort_equation)


def mean_cross_track_error(t, y_e):
    """Mean cross-track error MCTE = (1/T) ∫|y_e| dt, with ``y_e`` already in ship lengths (L).

    Parameters
    ----------
    t : array_like
        Sample times (L/U).
    y_e : array_like
        Cross-track error at each sample (L).

    Examples
    --------
    >>> mean_cross_track_error([0.0, 1.0, 2.0], [1.0, 1.0, -1.0])
    1.0
    """
    return _mean_abs(t, y_e, "y_e")  # eq. (crosstrack_metric_equation)


def _goal_index(t, reached):
    """Index of the first sample where ``reached`` is true (> 0.5), or ``None``."""
    hit = np.asarray(reached, dtype=float).ravel() > 0.5
    if hit.shape != t.shape:
        raise ValueError(f"reached: expected {t.size} samples like t, got {hit.size}")
    i = np.flatnonzero(hit)
    return int(i[0]) if i.size else None


def time_to_goal(t, reached):
    """First time at which ``reached`` is true (nonzero), or ``None`` if it never is.

    Parameters
    ----------
    t : array_like
        Sample times (L/U).
    reached : array_like
        Goal-reached flag at each sample (true where > 0.5).

    Examples
    --------
    >>> time_to_goal([0.0, 1.0, 2.0], [0, 0, 1]), time_to_goal([0.0, 1.0], [False, False])
    (2.0, None)
    """
    t = np.asarray(t, dtype=float).ravel()
    i = _goal_index(t, reached)
    return None if i is None else float(t[i])


@dataclass(frozen=True)
class TrackingMetrics:
    """Tracking metrics of one trajectory: ``ce`` (dimensionless), ``mcte`` (L) and ``time_to_goal``
    (non-dimensional time, ``None`` if the goal was never reached).

    Parameters
    ----------
    ce : float
        Controller effort CE (dimensionless).
    mcte : float
        Mean cross-track error MCTE (L).
    time_to_goal : float or None
        Time at which the goal was first reached (L/U), ``None`` if never.
    """

    ce: float
    mcte: float
    time_to_goal: float | None

    def to_dict(self) -> dict:
        """The metrics as a plain dict.

        Examples
        --------
        >>> TrackingMetrics(0.1, 0.2, None).to_dict()
        {'ce': 0.1, 'mcte': 0.2, 'time_to_goal': None}
        """
        return asdict(self)


def tracking_metrics(t, delta, y_e, reached=None, *, delta_max=DELTA_MAX_DEFAULT, until_goal=True):
    """CE, MCTE and time to goal of one trajectory.

    With ``until_goal`` the integrals run only up to the first sample where ``reached`` is true (the voyage's
    total time T); if the goal is never reached (or ``reached`` is None) the whole trajectory is used.

    Parameters
    ----------
    t : array_like
        Sample times (L/U).
    delta : array_like
        Actual rudder angle at each sample (rad).
    y_e : array_like
        Cross-track error at each sample (L).
    reached : array_like or None, optional
        Goal-reached flag at each sample (true where > 0.5); ``None`` if unknown.
    delta_max : float, optional
        Rudder saturation used for the CE normalisation (rad, > 0); 35° by default.
    until_goal : bool, optional
        Integrate only up to the first sample where the goal is reached.

    Examples
    --------
    >>> m = tracking_metrics([0, 1, 2, 3], [0.1, 0.1, 0.1, 0.9], [1, 1, 1, 5], [0, 0, 1, 1], delta_max=0.2)
    >>> m.ce, m.mcte, m.time_to_goal
    (0.5, 1.0, 2.0)
    """
    t = np.asarray(t, dtype=float).ravel()
    delta = np.asarray(delta, dtype=float).ravel()
    y_e = np.asarray(y_e, dtype=float).ravel()
    i_goal = None if reached is None else _goal_index(t, reached)
    t_goal = None if i_goal is None else float(t[i_goal])
    if until_goal and i_goal is not None:
        t, delta, y_e = t[: i_goal + 1], delta[: i_goal + 1], y_e[: i_goal + 1]
    return TrackingMetrics(control_effort(t, delta, delta_max), mean_cross_track_error(t, y_e), t_goal)
