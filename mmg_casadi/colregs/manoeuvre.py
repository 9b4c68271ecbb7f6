"""What a ship did in an encounter: course and speed changes against a reference, the time of action, and where
she crossed the other ship's course line (numpy, vectorised over the samples of a window).

* Course change ``Δψ(k) = wrap(ψ(k) − ψ(ref(k)))`` (positive: to starboard), against a reference sample per
  sample (one sample for a give-way ship; for a stand-on ship the reference moves on after an excused stretch,
  :mod:`mmg_casadi.colregs.duties`).
* Speed: a reduction is measured against the reference speed (``1 − v/v_ref``); an increase only beyond the
  highest speed the ship sailed before the onset (``v/v_max − 1``), so speed regained after a manoeuvre is not a
  change.
* The time of action is the first sample where the course change or the speed change reaches a threshold.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from mmg_casadi.colregs.geometry import wrap_to_pi


@dataclass(frozen=True)
class Manoeuvre:
    """Course and speed changes of one ship over a window of samples, and her time of action.

    Parameters
    ----------
    window : numpy.ndarray of int
        The samples measured (counted ones only).
    course_change : numpy.ndarray
        Δψ at each sample of ``window`` (degrees, positive to starboard).
    speed_decrease, speed_increase : numpy.ndarray
        Relative speed reduction and increase at each sample of ``window`` (≥ 0).
    action : int or None
        First sample of ``window`` where the change reached the action threshold (``None``: none).

    Examples
    --------
    >>> m = measure_manoeuvre(np.radians([0.0, 1.0, 5.0, 12.0]), np.ones(4), np.arange(4), np.zeros(4, int),
    ...                       1.0, 1.0, course_threshold_deg=2.0, speed_threshold=0.2)
    >>> m.action, round(m.starboard_deg, 6), m.port_deg, round(m.max_course_change_deg, 6)
    (2, 12.0, 0.0, 12.0)
    """

    window: np.ndarray
    course_change: np.ndarray
    speed_decrease: np.ndarray
    speed_increase: np.ndarray
    action: int | None

    @functools.cached_property
    def starboard_deg(self) -> float:
        """Largest alteration to starboard (degrees, ≥ 0)."""
        return float(max(0.0, np.max(self.course_change, initial=0.0)))

    @functools.cached_property
    def port_deg(self) -> float:
        """Largest alteration to port (degrees, ≥ 0)."""
        return float(max(0.0, -np.min(self.course_change, initial=0.0)))

    @functools.cached_property
    def max_course_change_deg(self) -> float:
        """Largest alteration either way (degrees)."""
        return max(self.starboard_deg, self.port_deg)

    @functools.cached_property
    def max_speed_decrease(self) -> float:
        """Largest relative speed reduction."""
        return float(np.max(self.speed_decrease, initial=0.0))

    @functools.cached_property
    def max_speed_increase(self) -> float:
        """Largest relative speed increase."""
        return float(np.max(self.speed_increase, initial=0.0))


def measure_manoeuvre(psi, speed, window, reference, speed_ref, speed_max, *, course_threshold_deg,
                      speed_threshold) -> Manoeuvre:
    """Course and speed changes over ``window`` and the first sample where one reaches its threshold.

    Parameters
    ----------
    psi, speed : array-like (T,)
        Heading (rad) and speed over the ground of the ship.
    window : array-like of int
        Samples to measure.
    reference : array-like of int
        Reference sample of each sample of ``window`` (course change and speed reduction are measured from it).
    speed_ref : float or array-like
        Reference speed for the reduction (scalar, or one per sample of ``window``).
    speed_max : float
        Highest speed before the onset; only speed above it is an increase.
    course_threshold_deg, speed_threshold : float
        A course change of at least ``course_threshold_deg`` or a speed change of at least ``speed_threshold``
        marks the action.

    Returns
    -------
    Manoeuvre
        Course change (degrees), relative speed decrease and increase at each sample of ``window``, and the first
        sample of action (None without one).

    Examples
    --------
    A 25 % slowdown regained afterwards: a reduction, no increase; the action is the slowdown.

    >>> m = measure_manoeuvre(np.zeros(4), np.array([1.0, 0.75, 0.9, 1.0]), np.arange(4), np.zeros(4, int), 1.0,
    ...                       1.0, course_threshold_deg=2.0, speed_threshold=0.2)
    >>> m.action, m.max_speed_decrease, m.max_speed_increase
    (1, 0.25, 0.0)
    """
    psi, speed = np.asarray(psi, dtype=float), np.asarray(speed, dtype=float)
    window, reference = np.asarray(window, dtype=int), np.asarray(reference, dtype=int)
    course = np.degrees(np.asarray(wrap_to_pi(psi[window] - psi[reference]), dtype=float).reshape(window.shape))
    v = speed[window]
    ref = np.broadcast_to(np.asarray(speed_ref, dtype=float), v.shape)
    decrease = np.where(ref > 0.0, np.maximum(0.0, 1.0 - v / np.where(ref > 0.0, ref, 1.0)), 0.0)
    increase = np.maximum(0.0, v / speed_max - 1.0) if speed_max > 0.0 else np.zeros(v.shape)
    hit = (np.abs(course) >= course_threshold_deg) | (decrease >= speed_threshold) | (increase >= speed_threshold)
    first = np.flatnonzero(hit)
    return Manoeuvre(window, course, decrease, increase, int(window[first[0]]) if first.size else None)


def course_line_crossings(pos_own, pos_other, psi_other, window, *, with_samples: bool = False):
    """Where the own ship crossed the other ship's course line within ``window``: the distances ahead (L).

    The course line runs through the other ship along her heading. A crossing is the own ship's change of side
    between consecutive samples (zeros skipped), judged against the line as it was at the earlier sample
    (``h × (p_own − p_other)`` with that sample's heading ``h`` at both): a turn of the other ship that sweeps her
    line across the own ship is her manoeuvre, not a crossing by the own ship (scorer version 3). Its distance
    along that line is interpolated linearly, positive ahead of the other ship, negative astern.

    Parameters
    ----------
    pos_own, pos_other : array-like (T, 2)
        Positions (L).
    psi_other : array-like (T,)
        Heading of the other ship (rad).
    window : array-like of int
        Consecutive samples to search.
    with_samples : bool, default False
        Also return the sample at which each crossing was seen (the later sample of its pair).

    Returns
    -------
    numpy.ndarray or tuple of numpy.ndarray
        Distance along the other ship's course line of each crossing (L, positive ahead of her), in time order;
        empty without a crossing. With ``with_samples``, ``(distances, samples)``.

    Examples
    --------
    The other ship at the origin heading north; the own ship crosses 3 L ahead of her, west to east:

    >>> pos = np.column_stack([np.full(5, 3.0), np.linspace(-2.0, 2.0, 5)])
    >>> course_line_crossings(pos, np.zeros((5, 2)), np.zeros(5), np.arange(5)).tolist()
    [3.0]

    The own ship lies still, 3 L ahead of the other and 1.5 L to her starboard, while the other turns 40° to
    starboard, her course line sweeping through the own ship: no crossing by the own ship.

    >>> psi = np.radians(np.linspace(0.0, 40.0, 5))
    >>> course_line_crossings(np.tile([3.0, 1.5], (5, 1)), np.zeros((5, 2)), psi, np.arange(5)).tolist()
    []
    """
    window = np.asarray(window, dtype=int)
    if window.size < 2:
        return (np.zeros(0), np.zeros(0, dtype=int)) if with_samples else np.zeros(0)
    rel = np.asarray(pos_own, dtype=float)[window] - np.asarray(pos_other, dtype=float)[window]
    psi = np.asarray(psi_other, dtype=float)[window]
    h = np.column_stack([np.cos(psi), np.sin(psi)])
    side = h[:, 0] * rel[:, 1] - h[:, 1] * rel[:, 0]
    along = np.einsum("ij,ij->i", h, rel)
    k = np.arange(side.size)
    last = np.maximum.accumulate(np.where(side != 0.0, k, -1))
    prev = np.concatenate([[-1], last[:-1]])
    j0 = np.maximum(prev, 0)
    # the later sample against the earlier sample's line
    side_then = h[j0, 0] * rel[:, 1] - h[j0, 1] * rel[:, 0]
    along_then = np.einsum("ij,ij->i", h[j0], rel)
    cross = (side != 0.0) & (prev >= 0) & (np.sign(side_then) * np.sign(side[j0]) < 0.0)
    j, i = prev[cross], k[cross]
    f = side[j] / (side[j] - side_then[i])
    distances = along[j] + f * (along_then[i] - along[j])
    return (distances, window[i]) if with_samples else distances
