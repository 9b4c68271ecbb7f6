"""Sampled target ships that slow down (parameter ``target_slowdown``): opt-in, off by default, refused where
it does not apply."""

from __future__ import annotations

import numpy as np
import pytest

from mmg_casadi.cli import main
from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.execution import sampled_scenario
from mmg_casadi.montecarlo.sampling import sample_scenario


def test_off_by_default_leaves_the_scenario_unchanged():
    s = sample_scenario(3, 4)
    assert s.to_scenario_dict(target_slowdown=0.0) == s.to_scenario_dict()
    assert all(len(sh["waypoints"]) == 1 and "speeds" not in sh for sh in s.to_scenario_dict()["ships"])


def test_targets_slow_halfway_and_the_own_ship_does_not():
    s = sample_scenario(3, 4)
    ships = s.to_scenario_dict(target_slowdown=0.4)["ships"]
    assert len(ships[0]["waypoints"]) == 1 and "speeds" not in ships[0]
    for i, sh in enumerate(ships[1:], start=1):
        assert sh["waypoints"][0] == pytest.approx(list(0.5 * (s.starts[i] + s.goals[i])))
        assert sh["waypoints"][1] == pytest.approx(list(s.goals[i]))
        assert sh["speeds"] == pytest.approx([s.speeds[i], 0.6 * s.speeds[i]])
    sc = sampled_scenario(3, "velocity-obstacle", 4, params={"target_slowdown": 0.4})
    assert [sh.speeds for sh in sc.ships[1:]] == [tuple(sh["speeds"]) for sh in ships[1:]]
    assert np.all([sh.speed == s.speeds[i] for i, sh in enumerate(sc.ships)])  # same draws, same start speeds


def test_refused_out_of_range_and_outside_the_sampled_studies(capsys):
    with pytest.raises(InputError, match="target_slowdown"):
        sample_scenario(1, 0).to_scenario_dict(target_slowdown=0.7)
    assert main(["simulate", "head_on.toml", "--set", "target_slowdown=0.5", "--out", "x"]) == 2
    assert "target_slowdown: expected nothing outside `study statistics`" in capsys.readouterr().err
