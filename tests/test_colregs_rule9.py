"""COLREG Rule 9(a) scored (issue 24): the share of a ship's time in a narrow channel (banks on both sides across
her track, at most the profile's rule9_width apart) on the starboard side of its centre line for her direction of travel."""

import math

import numpy as np
import pytest

from mmg_casadi.colregs.narrow_channel import channel_sides, rule9
from mmg_casadi.colregs.profiles import scoring_profile

CHANNEL_WIDTH = scoring_profile().rule9_width
KEPT_SHARE = scoring_profile().rule9_kept_share
from mmg_casadi.montecarlo.execution import run_scenarios
from mmg_casadi.scenarios.run import packaged_scenario, run_scenario
from mmg_casadi.scenarios.scenario import with_method

BANKS = [((-50.0, -5.0), (150.0, -5.0)), ((-50.0, 5.0), (150.0, 5.0))]  # a channel 10 L wide along x
T = np.linspace(0.0, 50.0, 101)
ON = np.ones(T.size, bool)


def _track(y, psi=0.0):
    x = T if psi == 0.0 else 100.0 - T
    return np.column_stack([x, np.full(T.size, y)]), np.full(T.size, psi)


def test_channel_sides_are_measured_across_the_heading():
    d_port, d_stbd = channel_sides([[0.0, 2.0], [0.0, 2.0]], [0.0, math.pi], BANKS)
    assert d_port == pytest.approx([7.0, 3.0]) and d_stbd == pytest.approx([3.0, 7.0])


@pytest.mark.parametrize("y, psi, kept", [(2.0, 0.0, True), (-2.0, 0.0, False), (-2.0, math.pi, True),
                                          (2.0, math.pi, False)])
def test_starboard_side_is_for_the_direction_of_travel(y, psi, kept):
    r = rule9(T, *_track(y, psi), ON, BANKS)
    assert r.verdict is kept and r.score == (1.0 if kept else 0.0)
    assert r.terms["channel_time"] == pytest.approx(50.0) and r.terms["min_width"] == pytest.approx(10.0)
    assert r.terms["mean_offset"] == pytest.approx(2.0 if kept else -2.0)


def test_the_share_is_time_weighted_and_only_while_sailing():
    xy, psi = _track(2.0)
    xy[T >= 40.0, 1] = -2.0  # the last 10 L/U on the port half
    r = rule9(T, xy, psi, ON, BANKS)
    assert r.score == pytest.approx(0.8) and r.verdict is (0.8 >= KEPT_SHARE)
    sailing = T < 40.0  # arrived before she crossed: only the starboard stretch counts
    assert rule9(T, xy, psi, sailing, BANKS).score == 1.0


def test_open_water_a_single_coast_and_a_wide_channel_have_no_verdict():
    xy, psi = _track(2.0)
    assert rule9(T, xy, psi, ON, []) is None
    assert rule9(T, xy, psi, ON, BANKS[:1]) is None
    wide = [((-50.0, -CHANNEL_WIDTH), (150.0, -CHANNEL_WIDTH)), ((-50.0, 5.0), (150.0, 5.0))]
    assert rule9(T, xy, psi, ON, wide) is None


def test_metrics_json_and_runs_csv_carry_rule9():
    sc = with_method(packaged_scenario("narrow_channel"), "modified-vortex")
    ships = run_scenario(sc).metrics["ships"]
    for s in ships:  # the paper's ships follow the channel's centre line: about half the time on each side
        assert s["rule9"]["channel_time"] > 40.0 and 0.0 <= s["rule9"]["score"] <= 1.0
        assert s["rule9"]["verdict"] is False
    (row,) = run_scenarios([sc], time_guidance_calls=False)
    assert row["colregs_rule9"] == pytest.approx(ships[0]["rule9"]["score"], abs=0.1)
    (open_water,) = run_scenarios([with_method(packaged_scenario("head_on"), "modified-vortex")],
                                  time_guidance_calls=False)
    assert math.isnan(open_water["colregs_rule9"])
    assert run_scenario(with_method(packaged_scenario("head_on"), "modified-vortex")).metrics["ships"][0]["rule9"] \
        is None
