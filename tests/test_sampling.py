"""Property and reproducibility tests of the paper's scenario sampler (mmg_casadi.montecarlo.sampling)."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.sampling import ENVIRONMENTS, SampledScenario, SamplerConfig, parse_envs, sample_scenario

N_SEEDS = 500


def _pairwise_min(points: np.ndarray) -> float:
    d = np.linalg.norm(points[:, None, :] - points[None, :, :], axis=-1)
    d[np.diag_indices_from(d)] = np.inf
    return float(d.min())


def test_environment_table_matches_paper():
    assert ENVIRONMENTS == {1: (1, 2), 2: (2, 3), 3: (2, 5), 4: (3, 7), 5: (4, 9)}


@pytest.mark.parametrize("environment", sorted(ENVIRONMENTS))
def test_placement_rules_hold_for_many_seeds(environment):
    n_static, n_dynamic = ENVIRONMENTS[environment]
    cfg = SamplerConfig()
    for run in range(N_SEEDS):
        s = sample_scenario(environment, run)
        assert (s.environment, s.run, s.seed) == (environment, run, 0)
        assert s.n_ships == 1 + n_dynamic and s.n_obstacles == n_static
        assert s.starts.shape == (1 + n_dynamic, 2) and s.goals.shape == (1 + n_dynamic, 2)
        assert s.headings.shape == (1 + n_dynamic,) and s.speeds.shape == (1 + n_dynamic,)
        assert s.obstacles.shape == (n_static, 2)
        everything = np.vstack([s.starts, s.obstacles])
        assert _pairwise_min(everything) >= cfg.min_start_separation
        assert np.all(np.linalg.norm(s.goals - s.starts, axis=1) >= cfg.min_goal_distance)
        for pts in (s.starts, s.goals, s.obstacles):
            assert np.all((pts >= 0.0) & (pts <= cfg.area))
        assert np.all((s.headings >= -math.pi) & (s.headings < math.pi))
        assert s.speeds[0] == 1.0
        assert np.all((s.speeds[1:] >= 0.5) & (s.speeds[1:] <= 1.0))
        assert s.obstacle_radius == 0.5


def test_distributions_are_not_degenerate():
    heads = np.concatenate([sample_scenario(5, r).headings for r in range(200)])
    speeds = np.concatenate([sample_scenario(5, r).speeds[1:] for r in range(200)])
    assert heads.min() < -2.8 and heads.max() > 2.8
    assert speeds.min() < 0.55 and speeds.max() > 0.95
    assert abs(speeds.mean() - 0.75) < 0.03


def test_reproducible_from_triple_alone():
    a = sample_scenario(3, 42, base_seed=7)
    b = sample_scenario(3, 42, base_seed=7)
    assert a == b
    for name in ("starts", "goals", "headings", "speeds", "obstacles"):
        assert np.array_equal(getattr(a, name), getattr(b, name))


@pytest.mark.parametrize("other", [(3, 43, 7), (3, 42, 8), (4, 42, 7)])
def test_different_triple_gives_different_scenario(other):
    a = sample_scenario(3, 42, base_seed=7)
    b = sample_scenario(*other[:2], base_seed=other[2])
    assert a != b
    assert not np.array_equal(a.starts[0], b.starts[0])


def test_arrays_are_read_only_and_dataclass_frozen():
    s = sample_scenario(1, 0)
    with pytest.raises(ValueError):
        s.starts[0, 0] = 0.0
    with pytest.raises(AttributeError):
        s.run = 3


def test_custom_config_is_respected():
    cfg = SamplerConfig(area=50.0, min_start_separation=5.0, min_goal_distance=20.0, speed_range=(0.2, 0.3),
                        obstacle_radius=1.0)
    for run in range(50):
        s = sample_scenario(4, run, config=cfg)
        assert _pairwise_min(np.vstack([s.starts, s.obstacles])) >= 5.0
        assert np.all(np.linalg.norm(s.goals - s.starts, axis=1) >= 20.0)
        assert np.all((s.starts <= 50.0) & (s.goals <= 50.0))
        assert np.all((s.speeds[1:] >= 0.2) & (s.speeds[1:] <= 0.3))
        assert s.obstacle_radius == 1.0


def test_to_scenario_dict_shape():
    s = sample_scenario(2, 5)
    d = s.to_scenario_dict(method="apf", dt=0.5, t_max=100.0, r_safe=12.0, collision_distance=1.5)
    assert list(d) == ["settings", "ships", "obstacles", "walls"]
    assert d["settings"] == {"method": "apf", "dt": 0.5, "t_max": 100.0, "r_safe": 12.0,
                             "collision_distance": 1.5}
    assert d["walls"] == []
    assert len(d["ships"]) == s.n_ships and len(d["obstacles"]) == s.n_obstacles
    for i, ship in enumerate(d["ships"]):
        assert list(ship) == ["name", "start", "heading", "speed", "waypoints"]
        assert ship["name"] == f"agent{i}"
        assert ship["start"] == s.starts[i].tolist()
        assert ship["heading"] == pytest.approx(math.degrees(s.headings[i]))
        assert -180.0 <= ship["heading"] < 180.0
        assert ship["speed"] == float(s.speeds[i])
        assert ship["waypoints"] == [s.goals[i].tolist()]
        assert all(type(x) is float for x in ship["start"] + ship["waypoints"][0])
    for j, obs in enumerate(d["obstacles"]):
        assert obs == {"position": s.obstacles[j].tolist(), "radius": 0.5}
    assert d["ships"][0]["speed"] == 1.0


def test_to_scenario_dict_defaults_and_bad_values():
    d = sample_scenario(1, 0).to_scenario_dict()
    assert d["settings"] == {"method": "modified-vortex", "dt": 0.25, "t_max": 300.0, "r_safe": 15.0,
                             "collision_distance": 2.0}
    with pytest.raises(InputError) as err:
        sample_scenario(1, 0).to_scenario_dict(dt=0.0)
    assert err.value.field == "dt"


def _to_toml(d: dict) -> str:
    def val(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return repr(v)

    lines = ["walls = []", "[settings]"] + [f"{k} = {val(v)}" for k, v in d["settings"].items()]
    for table in ("ships", "obstacles"):
        for entry in d[table]:
            lines.append(f"[[{table}]]")
            lines += [f"{k} = {val(v)}" for k, v in entry.items()]
    return "\n".join(lines) + "\n"


def test_to_scenario_dict_round_trips_through_toml():
    d = sample_scenario(5, 11).to_scenario_dict()
    assert tomllib.loads(_to_toml(d)) == d


def test_to_dict_is_plain_python():
    d = sample_scenario(3, 1).to_dict()
    assert d["environment"] == 3 and d["run"] == 1 and d["seed"] == 0
    assert isinstance(d["starts"], list) and len(d["starts"]) == 6


@pytest.mark.parametrize("env", [0, 7, -1, "1", 1.0, True, None])
def test_invalid_environment(env):
    with pytest.raises(InputError) as err:
        sample_scenario(env, 0)
    assert err.value.field == "environment"
    assert "1-6" in err.value.allowed


@pytest.mark.parametrize("field, kwargs", [("run", {"run": -1}), ("run", {"run": 1.5}),
                                           ("base_seed", {"run": 0, "base_seed": -3})])
def test_invalid_run_or_seed(field, kwargs):
    with pytest.raises(InputError) as err:
        sample_scenario(1, **kwargs)
    assert err.value.field == field


@pytest.mark.parametrize("kwargs, field", [
    ({"area": 0.0}, "area"),
    ({"min_start_separation": -1.0}, "min_start_separation"),
    ({"min_goal_distance": 80.0}, "min_goal_distance"),
    ({"speed_range": (1.0, 0.5)}, "speed_range"),
    ({"speed_range": (0.0, 0.5)}, "speed_range"),
    ({"obstacle_radius": float("nan")}, "obstacle_radius"),
])
def test_invalid_config(kwargs, field):
    with pytest.raises(InputError) as err:
        SamplerConfig(**kwargs)
    assert err.value.field == field


def test_impossible_separation_raises_input_error():
    cfg = SamplerConfig(area=10.0, min_start_separation=9.0, min_goal_distance=1.0)
    with pytest.raises(InputError) as err:
        sample_scenario(5, 0, config=cfg)
    assert err.value.field == "min_start_separation"


def test_sampled_scenario_validates_lengths():
    with pytest.raises(InputError):
        SampledScenario(environment=1, run=0, seed=0, starts=[[0, 0], [1, 1]], goals=[[1, 1]],
                        headings=[0, 0], speeds=[1, 1], obstacles=np.zeros((0, 2)))


@pytest.mark.parametrize("text, expected", [
    ("1-5", (1, 2, 3, 4, 5)), ("1,3,5", (1, 3, 5)), ("3", (3,)), ("1-2,5", (1, 2, 5)), (" 2 , 2-3 ", (2, 3)),
])
def test_parse_envs(text, expected):
    assert parse_envs(text) == expected


@pytest.mark.parametrize("text", ["", "0", "7", "1-7", "5-1", "a", "1,,2", "1-", "1.5", None])
def test_parse_envs_rejects(text):
    with pytest.raises(InputError) as err:
        parse_envs(text)
    assert err.value.field == "envs"
