"""Tracking metrics (tests/trajectory_metrics.py, the check of the closed loop's exact CE/MCTE)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mmg_casadi.errors import ParameterError
from trajectory_metrics import (
    TrackingMetrics,
    control_effort,
    mean_cross_track_error,
    time_to_goal,
    tracking_metrics,
)


def test_ce_constant_rudder():
    t = np.linspace(0.0, 100.0, 1001)
    assert control_effort(t, np.full_like(t, 0.35)) == pytest.approx(0.35 / np.radians(35.0))
    assert control_effort(t, np.full_like(t, -0.35)) == pytest.approx(0.35 / np.radians(35.0))
    assert control_effort(t, np.full_like(t, 0.1), delta_max=0.2) == pytest.approx(0.5)


def test_ce_nonzero_start_time_and_uneven_samples():
    t = np.array([10.0, 10.5, 12.0, 20.0])
    assert control_effort(t, [0.2, 0.2, 0.2, 0.2], delta_max=0.4) == pytest.approx(0.5)


def test_mcte_sine_over_whole_periods():
    t = np.linspace(0.0, 6 * np.pi, 60001)
    assert mean_cross_track_error(t, np.sin(t)) == pytest.approx(2 / np.pi, rel=1e-6)
    assert mean_cross_track_error(t, 3.0 * np.sin(t)) == pytest.approx(6 / np.pi, rel=1e-6)


def test_time_to_goal():
    t = np.arange(5.0)
    assert time_to_goal(t, [0, 0, 0, 1, 1]) == 3.0
    assert time_to_goal(t, np.array([False, True, False, True, True])) == 1.0
    assert time_to_goal(t, np.zeros(5)) is None


def test_tracking_metrics_until_goal_cutoff():
    t = np.linspace(0.0, 20.0, 201)
    reached = t >= 10.0
    delta = np.where(t <= 10.0, 0.35, 0.0)  # rudder only during the voyage
    y_e = np.where(t <= 10.0, 2.0, 100.0)  # large errors after the goal must not count
    m = tracking_metrics(t, delta, y_e, reached)
    assert m.time_to_goal == pytest.approx(10.0)
    assert m.ce == pytest.approx(0.35 / np.radians(35.0))
    assert m.mcte == pytest.approx(2.0)
    full = tracking_metrics(t, delta, y_e, reached, until_goal=False)
    assert full.time_to_goal == pytest.approx(10.0)
    assert full.mcte > 40.0
    assert full.ce == pytest.approx(m.ce * 10.0 / 20.0, rel=0.02)  # 0.35 over half the time (+ one ramp)


def test_tracking_metrics_goal_never_reached_uses_whole_trajectory():
    t = np.linspace(0.0, 4.0, 41)
    for reached in (np.zeros_like(t), None):
        m = tracking_metrics(t, np.full_like(t, 0.1), np.ones_like(t), reached, delta_max=0.2)
        assert (m.ce, m.mcte, m.time_to_goal) == (pytest.approx(0.5), pytest.approx(1.0), None)


def test_short_trajectories_give_nan():
    assert math.isnan(control_effort([0.0], [0.1]))
    assert math.isnan(mean_cross_track_error([], []))
    assert math.isnan(mean_cross_track_error([1.0, 1.0], [0.5, 0.5]))  # zero duration
    m = tracking_metrics([0.0, 1.0, 2.0], [0.1, 0.1, 0.1], [1.0, 1.0, 1.0], [1, 1, 1])  # reached at t[0]
    assert m.time_to_goal == 0.0 and math.isnan(m.ce) and math.isnan(m.mcte)


def test_to_dict_and_frozen():
    m = TrackingMetrics(0.12, 0.27, 350.0)
    assert m.to_dict() == {"ce": 0.12, "mcte": 0.27, "time_to_goal": 350.0}
    with pytest.raises(AttributeError):
        m.ce = 0.0


def test_bad_inputs():
    with pytest.raises(ValueError):
        control_effort([0.0, 1.0, 2.0], [0.1, 0.1])
    with pytest.raises(ValueError):
        time_to_goal([0.0, 1.0], [0, 0, 1])
    with pytest.raises(ParameterError) as err:
        control_effort([0.0, 1.0], [0.1, 0.1], delta_max=0.0)
    assert err.value.field == "delta_max"
