"""Plane geometry shared by the COLREG classifier, scorer and assessment: angle wrapping, relative bearings and
the validated trajectory arrays of a ship pair (numpy).

Conventions: positions in ship lengths L, x forward/north and y to starboard/east, headings psi in rad measured
from x towards y (clockwise in the marine view, x up and y right), times non-dimensional. A positive bearing or
change of heading is to starboard.
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_to_pi(angle):
    """``angle`` (rad, scalar or array) wrapped into [-π, π).

    Parameters
    ----------
    angle : float or numpy.ndarray
        Angle(s) to wrap (rad).

    Returns
    -------
    float or numpy.ndarray
        The wrapped angle(s) (rad); a float for a scalar.

    Examples
    --------
    >>> round(wrap_to_pi(3 * math.pi / 2), 6), round(wrap_to_pi(-0.5), 6)
    (-1.570796, -0.5)
    """
    if isinstance(angle, float):  # a plain number: the same arithmetic without numpy's overhead
        return (angle + math.pi) % TWO_PI - math.pi
    wrapped = (np.asarray(angle, dtype=float) + math.pi) % TWO_PI - math.pi
    return float(wrapped) if wrapped.ndim == 0 else wrapped


def bearing(own_pos, own_psi, other_pos) -> float:
    """Relative bearing of ``other_pos`` from the own ship, wrapped into [-π, π) (negative: port side).

    Parameters
    ----------
    own_pos, other_pos : sequence of 2 floats
        Positions of the own ship and of the other point (L).
    own_psi : float
        Heading of the own ship (rad, from x towards y).

    Returns
    -------
    float
        ``atan2(dy, dx) - own_psi`` wrapped into [-π, π) (rad): 0 dead ahead, π/2 starboard beam.

    Examples
    --------
    >>> round(bearing((0, 0), 0.0, (10, 10)), 6), round(bearing((0, 0), math.pi / 2, (10, 0)), 6)
    (0.785398, -1.570796)
    """
    dx, dy = other_pos[0] - own_pos[0], other_pos[1] - own_pos[1]
    return wrap_to_pi(math.atan2(dy, dx) - own_psi)


def pair_series(t, pos_a, psi_a, pos_b, psi_b, active_a, active_b):
    """Validated arrays of a ship pair: t (T,), positions (T, 2), headings (T,), both-active mask (T,).

    Parameters
    ----------
    t : array-like (T,)
        Sample times (L/U).
    pos_a, pos_b : array-like (T, 2)
        Positions of ships a and b (L).
    psi_a, psi_b : array-like (T,)
        Headings of ships a and b (rad).
    active_a, active_b : array-like of bool (T,) or None
        Whether each ship is active at each sample (``None``: always).

    Returns
    -------
    tuple
        ``(t, pos_a, psi_a, pos_b, psi_b, both)`` as float arrays, ``both`` the mask where both ships are active.

    Raises
    ------
    ValueError
        An array whose length differs from ``t``'s.

    Examples
    --------
    >>> t, pa, ha, pb, hb, both = pair_series([0, 1], [[0, 0], [1, 0]], [0, 0], [[5, 0], [4, 0]], [3, 3],
    ...                                       None, [True, False])
    >>> pa.shape, both.tolist()
    ((2, 2), [True, False])
    """
    t = np.asarray(t, dtype=float).ravel()
    n = t.size
    out = [t]
    for name, pos, psi in (("pos_a", pos_a, psi_a), ("pos_b", pos_b, psi_b)):
        pos = np.asarray(pos, dtype=float)
        psi = np.asarray(psi, dtype=float).ravel()
        if pos.shape != (n, 2):
            raise ValueError(f"{name}: expected shape ({n}, 2) like t, got {pos.shape}")
        if psi.shape != (n,):
            raise ValueError(f"psi_{name[-1]}: expected {n} samples like t, got {psi.size}")
        out += [pos, psi]
    both = np.ones(n, dtype=bool)
    for name, mask in (("active_a", active_a), ("active_b", active_b)):
        if mask is not None:
            mask = np.asarray(mask, dtype=bool).ravel()
            if mask.shape != (n,):
                raise ValueError(f"{name}: expected {n} samples like t, got {mask.size}")
            both &= mask
    return (*out, both)
