"""The Gymnasium environments: the checker, determinism, the episode equal to the closed-loop rollout of the same
orders to the bit, the vectorised environment equal to single ones, rewards and ends of episodes."""

from __future__ import annotations

import math

import numpy as np
import pytest

gymnasium = pytest.importorskip("gymnasium")

from gymnasium.utils.env_checker import check_env  # noqa: E402

from mmg_casadi import simulate  # noqa: E402
from mmg_casadi.closed_loop.state import ship_rows  # noqa: E402
from mmg_casadi.errors import InputError  # noqa: E402
from mmg_casadi.gym import RewardConfig, ShipEnv, ShipVectorEnv, environment, traffic  # noqa: E402
from mmg_casadi.gym.core import commanded_problem  # noqa: E402
from mmg_casadi.scenarios.run import packaged_scenario  # noqa: E402

ENV1 = environment(1, "modified-vortex")  # 3 ships and an obstacle: a small compiled step
SHORT = {"t_max": 20.0}


def _episode(env, seed, policy, steps=None):
    """Observations, rewards, ends and states of one episode."""
    obs, _ = env.reset(seed=seed)
    out = {"obs": [obs], "r": [], "end": [], "x": [env.state.copy()]}
    k = 0
    while steps is None or k < steps:
        obs, r, term, trunc, info = env.step(policy(obs, k))
        out["obs"].append(obs)
        out["r"].append(r)
        out["end"].append((term, trunc, info["event"]))
        out["x"].append(env.state.copy())
        k += 1
        if term or trunc:
            break
    return {k: np.array(v, dtype=object if k == "end" else float) for k, v in out.items()}


def test_check_env_passes():
    env = ShipEnv(ENV1, params=SHORT)
    check_env(env, skip_render_check=True)
    env = ShipEnv("narrow_channel", params=SHORT, rpm=True, action="absolute", k_ships=2, k_hazards=6)
    check_env(env, skip_render_check=True)


def test_the_same_seed_gives_the_same_episode():
    env = ShipEnv(ENV1, params=SHORT)
    env.action_space.seed(5)
    acts = [env.action_space.sample() for _ in range(200)]
    a = _episode(env, 11, lambda o, k: acts[k])
    b = _episode(env, 11, lambda o, k: acts[k])
    c = _episode(env, 12, lambda o, k: acts[k])
    assert a["x"].tobytes() == b["x"].tobytes() and a["obs"].tobytes() == b["obs"].tobytes()
    assert a["r"].tobytes() == b["r"].tobytes() and (a["end"] == b["end"]).all()
    assert a["x"].shape != c["x"].shape or a["x"].tobytes() != c["x"].tobytes()  # another scenario


@pytest.mark.parametrize("rpm", [False, True])
def test_an_episode_equals_the_closed_loop_rollout_of_its_orders_to_the_bit(rpm):
    env = ShipEnv(ENV1, params=SHORT, rpm=rpm)
    env.action_space.seed(1)
    ep = _episode(env, 3, lambda o, k: env.action_space.sample())
    tr = env.episode.rollout()
    lay = env.problem.layout
    states = ship_rows(lay, ep["x"].T)
    assert len(env.episode.commands) == len(ep["r"]) == tr.states.shape[0] - 1
    assert tr.states.tobytes() == states.tobytes()  # every state of every ship, every step
    rows = [lay.column("command_heading")] + ([lay.column("command_rpm")] if rpm else [])
    assert np.array_equal(tr.states[1:, 0, rows], np.array(env.episode.commands))  # each step carries its order


def test_a_constant_order_equals_the_plain_rollout_of_the_compiled_step():
    """Holding one order, the environment's steps equal simulate's mapaccum chunks (no per-step writes)."""
    env = ShipEnv(ENV1, params=SHORT, action="absolute")
    ep = _episode(env, 4, lambda o, k: np.array([0.25], np.float32))
    pr = commanded_problem(env.episode.scenario, SHORT)
    x0 = pr.x0.copy()
    x0[pr.layout.row("command_heading", 0)] = env.episode.commands[0][0]
    tr = simulate(pr.layout, x0, pr.p)
    n = len(ep["r"])
    assert math.isclose(env.episode.commands[0][0], math.pi * 0.25, rel_tol=1e-7)
    assert tr.states[1:n + 1].tobytes() == ship_rows(pr.layout, ep["x"].T)[1:].tobytes()


def test_a_vectorised_environment_steps_each_column_as_a_single_environment():
    n, seed, steps = 3, 20, 30
    vec = ShipVectorEnv(ENV1, n, params=SHORT)
    rng = np.random.default_rng(0)
    acts = rng.uniform(-1, 1, size=(steps, n, 1)).astype(np.float32)
    obs, info = vec.reset(seed=seed)
    Xs, Rs = [vec.X.copy()], []
    for k in range(steps):
        obs, r, term, trunc, info = vec.step(acts[k])
        assert not (term | trunc).any()  # 30 steps of 0.25 L/U: nothing ends
        Xs.append(vec.X.copy())
        Rs.append(r)
    for j in range(n):
        single = ShipEnv(ENV1, params=SHORT)
        ep = _episode(single, seed + j, lambda o, k: acts[k, j], steps=steps)
        assert np.stack([x[:, j] for x in Xs]).tobytes() == ep["x"].tobytes()
        assert np.array([r[j] for r in Rs]).tobytes() == ep["r"].tobytes()
        assert obs[j].tobytes() == ep["obs"][-1].astype(np.float32).tobytes()


def test_a_vectorised_environment_resets_a_finished_one_at_the_next_step():
    vec = ShipVectorEnv(ENV1, 2, params={"t_max": 1.0})  # 4 steps
    vec.reset(seed=0)
    ends = []
    for k in range(6):
        obs, r, term, trunc, info = vec.step(np.zeros((2, 1), np.float32))
        ends.append((trunc.tolist(), r.tolist(), info["t"].tolist()))
    assert ends[3][0] == [True, True] and ends[3][2] == [1.0, 1.0]  # truncated at t_max
    assert ends[4][1] == [0.0, 0.0] and ends[4][2] == [0.0, 0.0]    # the next step restarts them
    assert ends[5][2] == [0.25, 0.25]


def test_a_vectorised_environment_refuses_scenarios_of_another_shape():
    shapes = {0: packaged_scenario("head_on"), 1: packaged_scenario("static_obstacle")}
    vec = ShipVectorEnv(lambda seed: shapes[seed % 2], 2)
    vec._rngs = [type("R", (), {"integers": staticmethod(lambda n, k=k: k)})() for k in range(2)]
    vec._new(0)
    with pytest.raises(InputError, match="scenarios of one shape"):
        vec._new(1)


def test_rewards_and_events():
    # head-on with the own ship ordered straight ahead: the other ship (colregs-vortex) gives way, both reach
    env = ShipEnv("head_on", method="colregs-vortex", action="relative", reward=RewardConfig(time=0.0))
    ep = _episode(env, 0, lambda o, k: np.zeros(1, np.float32))
    assert tuple(ep["end"][-1]) == (True, False, "goal")
    # progress: the route to go (observation entry 9) at the start minus at the end, plus the goal's bonus
    assert ep["r"].sum() == pytest.approx(ep["obs"][0][9] - ep["obs"][-1][9] + 100.0, abs=1e-4)
    # ordered into the other ship: a collision ends the episode with the penalty
    env = ShipEnv("head_on", method="none", action="absolute", reward=RewardConfig(progress=0.0, time=0.0))
    ep = _episode(env, 0, lambda o, k: np.zeros(1, np.float32))
    assert tuple(ep["end"][-1]) == (True, False, "collision")
    assert ep["r"][-1] == -100.0 and ep["r"][:-1].sum() == 0.0


def test_observation_of_the_nearest_ship_in_the_own_frame():
    env = ShipEnv("head_on", method="none", k_ships=1, k_hazards=1)
    obs, _ = env.reset(seed=0)
    sc = env.episode.scenario
    own, other = sc.ships[0], sc.ships[1]
    d = np.subtract(other.start, own.start)
    psi = own.heading_rad
    ahead, stb = d[0] * math.cos(psi) + d[1] * math.sin(psi), -d[0] * math.sin(psi) + d[1] * math.cos(psi)
    ship = obs[10:16]
    assert ship[0] == 1.0 and ship[1] == pytest.approx(ahead, rel=1e-6) and ship[2] == pytest.approx(stb, abs=1e-5)
    assert ship[5] == pytest.approx(np.hypot(*d), rel=1e-6)
    assert obs[16:20].tolist() == [0.0, 0.0, 0.0, 0.0]  # no hazard: an empty slot


def test_traffic_source_and_bad_options():
    env = ShipEnv(traffic(6, "velocity-obstacle", t_max=5.0))
    obs, info = env.reset(seed=2)
    assert env.problem.layout.methods == ("none",) + ("velocity-obstacle",) * 5
    assert env.problem.layout.commanded == (0,)
    for kw, field in (({"action": "turn"}, "action"), ({"max_turn_deg": 0}, "max_turn_deg"),
                      ({"k_ships": -1}, "k_ships"), ({"method": "nope"}, "method")):
        with pytest.raises(InputError, match=field):
            ShipEnv("head_on", **kw)
    with pytest.raises(InputError, match="terminate_on"):
        RewardConfig(terminate_on=("goal", "boredom"))
