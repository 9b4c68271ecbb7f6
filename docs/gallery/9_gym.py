"""Gymnasium environment

An environment-1 scenario of the Monte Carlo sampler as a Gymnasium episode (`mmg_casadi.gym.ShipEnv`): the own
ship (blue) under a random policy, under a scripted policy (head for the waypoint, 40° to starboard of it while a
ship ahead is within 10 L) and, for comparison, under the paper's modified sink-vortex as `simulate` runs the same
scenario; the targets (grey) use the modified sink-vortex throughout. The scripted episode is replayed with
`simulate` from its recorded orders (`Episode.rollout`), equal to the bit.

Full size: `python benchmarks/gym_throughput.py` (environment steps per second of 1 and 64 environments)
"""

import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mmg_casadi import build_problem, simulate
from mmg_casadi.closed_loop.state import ship_rows
from mmg_casadi.gym import ShipEnv, environment
from mmg_casadi.plotting import FIGURE_DPI, marine_axes

env = ShipEnv(environment(1, "modified-vortex"), action="absolute", k_ships=2)


def scripted(obs):
    """Head for the next waypoint; 40 deg to starboard of it while the nearest ship is ahead within 10 L."""
    psi = env.state[env.problem.layout.row("psi", 0)]
    heading = psi + np.arctan2(obs[7], obs[6])            # the waypoint's bearing (obs: ahead, starboard)
    present, ahead, starboard, dist = obs[10], obs[11], obs[12], obs[15]
    if present and ahead > 0 and dist < 10.0 and abs(starboard) < dist:
        heading += np.radians(40.0)
    return np.array([np.angle(np.exp(1j * heading)) / np.pi], np.float32)  # absolute action: heading / pi


def episode(policy, seed=7):
    """One episode: the layout, the ship rows of every state, the return and the event that ended it."""
    obs, _ = env.reset(seed=seed)
    env.action_space.seed(seed)
    states, total, done = [env.state.copy()], 0.0, False
    while not done:
        obs, r, term, trunc, info = env.step(policy(obs))
        states.append(env.state.copy())
        total, done = total + r, term or trunc
    return env.problem.layout, ship_rows(env.problem.layout, np.column_stack(states)), total, info["event"]


runs = {"random policy": episode(lambda obs: env.action_space.sample()), "scripted policy": episode(scripted)}
replay = env.episode.rollout()  # the scripted episode's orders, rolled out by simulate
same = replay.states.tobytes() == runs["scripted policy"][1].tobytes()
pr = build_problem(env.episode.scenario)  # the same scenario, the own ship with the method of its file
tr = simulate(pr.layout, pr.x0, pr.p)
reached = tr.states[-1, 0, pr.layout.column("status")] == 1
runs[f"{pr.layout.methods[0]} (simulate)"] = (pr.layout, tr.states, None, "goal" if reached else "no goal")

fig = Figure(figsize=(12, 4.4), layout="constrained")
for ax, (name, (lay, S, total, event)) in zip(fig.subplots(1, 3), runs.items()):
    for i in range(lay.n_ships):
        ax.plot(S[:, i, lay.column("y")], S[:, i, lay.column("x")], color="tab:blue" if i == 0 else "0.6",
                lw=2 if i == 0 else 1)
    for o in env.episode.scenario.obstacles:
        ax.plot(o.position[1], o.position[0], "ks", ms=5)
    goal = env.episode.scenario.ships[0].waypoints[-1]
    ax.plot(goal[1], goal[0], "b*", ms=10)
    marine_axes(ax)
    ax.set_title(f"{name}: {event}" + ("" if total is None else f", return {total:.1f}"), fontsize=9)
    ax.set_xlabel("y (east) [L]")
    ax.set_ylabel("x (north) [L]")
fig.savefig(Path(sys.argv[1]) / "gym_policies.png", dpi=FIGURE_DPI)
print(f"scripted episode replayed with simulate, equal to the bit: {same}")
assert same
