"""Motion over the ground and the relative geometry of ship pairs, vectorised over a stored trajectory (numpy).

Conventions as in :mod:`mmg_casadi.colregs.geometry`: positions in L, x north and y east, headings ψ in rad from
x towards y, times in L/U; a positive angle is to starboard. For a pair (own, other):

* range ``r = |p_other − p_own|``;
* bearing ``β``: of the other ship from the own bow, ``atan2(dy, dx) − ψ_own`` in [−π, π) (positive: starboard);
* contact angle ``α``: of the own ship from the other ship's bow, ``atan2(−dy, −dx) − ψ_other``;
* straight-line closest point of approach: distance ``cpa`` and time ``tcpa`` from the velocities over the ground
  (:func:`mmg_casadi.colregs.score.cpa_tcpa`: TCPA < 0 when opening, ``inf`` with no relative motion).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mmg_casadi.colregs.geometry import wrap_to_pi
from mmg_casadi.colregs.score import cpa_tcpa


def ground_velocity(t, pos, active=None) -> np.ndarray:
    """Velocity over the ground from positions: the time derivative along the first axis (central differences).

    With ``active``, a ship's velocity is differenced within each stretch in which she sails: at the last sample
    before she stops (and the first after she starts) the difference is one-sided, so the positions she keeps
    after reaching her goal do not halve her speed at the sample she arrives.

    Parameters
    ----------
    t : array-like (T,)
        Sample times (L/U), increasing, at least two.
    pos : array-like (T, ..., 2)
        Positions (L).
    active : array-like of bool (T, ...), optional
        Whether each ship sails at each sample (default: throughout).

    Returns
    -------
    numpy.ndarray (T, ..., 2)
        Velocities (L per L/U).

    Examples
    --------
    >>> t = np.array([0.0, 1.0, 2.0])
    >>> ground_velocity(t, np.array([[0.0, 0.0], [1.0, 0.5], [2.0, 1.0]])).tolist()
    [[1.0, 0.5], [1.0, 0.5], [1.0, 0.5]]

    A ship that arrives at sample 2 and keeps her position after it:

    >>> t = np.arange(5.0)
    >>> pos = np.array([[0.0], [1.0], [2.0], [2.0], [2.0]])[:, :, None] * [1.0, 0.0]
    >>> ground_velocity(t, pos)[:, 0, 0].tolist(), ground_velocity(t, pos, [[1], [1], [1], [0], [0]])[:3, 0, 0].tolist()
    ([1.0, 1.0, 0.5, 0.0, 0.0], [1.0, 1.0, 1.0])
    """
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise ValueError(f"t: expected at least two sample times, got {t.size}")
    pos = np.asarray(pos, dtype=float)
    vel = np.gradient(pos, t, axis=0)
    if active is None or t.size < 3:
        return vel
    a = np.asarray(active, dtype=bool)
    dt = np.diff(t).reshape((-1,) + (1,) * (pos.ndim - 1))
    step = np.diff(pos, axis=0) / dt  # step[k]: from sample k to k + 1
    inner = a[1:-1]
    last = inner & a[:-2] & ~a[2:]  # sails at k and k - 1, not at k + 1
    first = inner & a[2:] & ~a[:-2]
    vel[1:-1] = np.where(last[..., None], step[:-1], np.where(first[..., None], step[1:], vel[1:-1]))
    return vel


@dataclass(frozen=True)
class PairGeometry:
    """Relative geometry of ordered ship pairs at every sample; arrays of one shape ``(T, ...)``.

    Parameters
    ----------
    range : numpy.ndarray
        Distance between the ships (L).
    beta : numpy.ndarray
        Bearing of the other ship from the own bow (rad, positive to starboard).
    alpha : numpy.ndarray
        Contact angle: bearing of the own ship from the other ship's bow (rad, positive to starboard).
    cpa : numpy.ndarray
        Straight-line predicted closest point of approach (L).
    tcpa : numpy.ndarray
        Time to it (L/U; negative when the ships draw apart).

    Examples
    --------
    >>> g = pair_geometry(np.zeros(2), 0.0, np.array([10.0, 0.0]), np.pi, np.array([1.0, 0.0]),
    ...                   np.array([-1.0, 0.0]))
    >>> float(g.range), float(g.beta), float(g.alpha), float(g.cpa), float(g.tcpa)
    (10.0, 0.0, 0.0, 0.0, 5.0)
    """

    range: np.ndarray
    beta: np.ndarray
    alpha: np.ndarray
    cpa: np.ndarray
    tcpa: np.ndarray


def pair_geometry(pos_own, psi_own, pos_other, psi_other, vel_own, vel_other) -> PairGeometry:
    """Range, bearing, contact angle and straight-line CPA/TCPA of (own, other), elementwise.

    Parameters
    ----------
    pos_own, pos_other : array-like (..., 2)
        Positions (L).
    psi_own, psi_other : array-like (...)
        Headings (rad).
    vel_own, vel_other : array-like (..., 2)
        Velocities over the ground (L per L/U).

    Returns
    -------
    PairGeometry
        ``range`` (L), ``beta``, ``alpha`` (rad), ``cpa`` (L) and ``tcpa`` (L/U), each of the inputs' shape
        ``(...)``.

    Examples
    --------
    The paper's crossing at t = 0: the other ship 45° on the own starboard bow, the own ship 45° on her port bow.

    >>> g = pair_geometry(np.zeros(2), 0.0, np.array([25.0, 25.0]), -np.pi / 2, np.array([1.0, 0.0]),
    ...                   np.array([0.0, -1.0]))
    >>> round(float(np.degrees(g.beta)), 1), round(float(np.degrees(g.alpha)), 1), round(float(g.tcpa), 1)
    (45.0, -45.0, 25.0)
    """
    d = np.asarray(pos_other, dtype=float) - np.asarray(pos_own, dtype=float)
    rng = np.hypot(d[..., 0], d[..., 1])
    direction = np.arctan2(d[..., 1], d[..., 0])
    beta = wrap_to_pi(direction - np.asarray(psi_own, dtype=float))
    alpha = wrap_to_pi(direction + np.pi - np.asarray(psi_other, dtype=float))
    cpa, tcpa = cpa_tcpa(d, np.asarray(vel_other, dtype=float) - np.asarray(vel_own, dtype=float))
    return PairGeometry(rng, np.asarray(beta), np.asarray(alpha), cpa, tcpa)
