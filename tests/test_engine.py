"""The engine (propeller-speed response) and the speed-change manoeuvre.

Reference values, derived: the steady speed at the ordered rpm is the model's own (the rpm is solved from the surge
balance X_H(u') + X_P(u', n) = 0, :func:`mmg_casadi.vessel.mmg.propeller_rpm_for_speed`), so the speed change
must settle at the ordered speed; the engine reaches an order of Δn no sooner than Δn / rate (rate limit) and no
later than that plus a few lag time constants.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mmg_casadi.errors import ParameterError
from mmg_casadi.params import PARAMETERS
from mmg_casadi.vessel.actuators import engine_step
from mmg_casadi.vessel.maneuvers import speed_change
from mmg_casadi.vessel.ship import load_kcs


def test_engine_step_keeps_an_order_equal_to_the_present_speed_exactly():
    for n in (23.1015612589, 115.5078062947404, 138.6):
        assert float(engine_step(n, n, 0.7, 0.25, 0.53)) == n


def test_engine_step_is_rate_limited_then_first_order():
    # large order: the rate limit binds
    assert float(engine_step(100.0, 0.0, 8.0, 0.25, 0.5)) == pytest.approx(98.0)
    # small order: the first-order lag, 1 - exp(-dt / lag) of the way
    assert float(engine_step(100.0, 99.0, 8.0, 0.25, 0.5)) == pytest.approx(100.0 - (1 - math.exp(-0.5)))


@pytest.mark.parametrize("to_speed", [0.5, 0.25, 0.8])
def test_speed_change_settles_at_the_model_steady_speed_within_the_engine_bounds(to_speed):
    r = speed_change(to_speed, t_end=150.0)
    m = r.metrics
    assert m["final_speed"] == pytest.approx(to_speed, abs=1e-3)
    dn = abs(m["rpm_from"] - m["rpm_to"])
    rate = PARAMETERS["engine_rate_rpm_s"].default
    lag = PARAMETERS["engine_lag_s"].default
    assert dn / rate <= m["t_engine_s"] <= dn / rate + 5 * lag
    # the hull follows more slowly than the propeller, and the speed falls monotonically
    assert m["t_change"] > m["t_engine"]
    assert np.all(np.diff(r.state("u")) <= 1e-12)
    assert m["reach_change_m"] == pytest.approx(m["reach_change"] * load_kcs().L)


def test_full_to_half_ahead_takes_minutes_and_kilometres():
    m = speed_change(0.5).metrics
    # about 7 minutes and 3.4 km for the 230 m KCS with the table's engine; well above the engine's own minute
    assert 300.0 < m["t_change_s"] < 600.0 and 2000.0 < m["reach_change_m"] < 5000.0


def test_speed_change_refuses_a_speed_outside_the_scenario_range():
    with pytest.raises(ParameterError, match="to_speed"):
        speed_change(0.1)
