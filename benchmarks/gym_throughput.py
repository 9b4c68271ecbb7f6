"""Environment steps per second of the Gymnasium environments on environment-5 traffic, against a plain Python loop.

Environment 5 of the statistical study (the own ship, 9 target ships with the modified sink-vortex, 4 static
obstacles; :func:`mmg_casadi.gym.sources.environment`), random actions, measured in one run:

* ``ShipEnv``: one environment, one call of the compiled closed-loop step per :meth:`step` (every ship's MMG model,
  engine, ILOS and the targets' guidance, the bookkeeping), plus the observation and the reward in numpy;
* ``ShipVectorEnv`` with 64 environments: one call of the compiled step mapped over 64 columns per step;
* the baseline, what a plain Python environment does: per step a Python loop over the 10 ships, each one PD heading
  command (numpy) and one call of the natively compiled MMG Function (the same KCS model and RK4 step as the
  closed loop's, ``rk4(build_mmg(), x, (delta, n), dt)``, compiled once), no guidance and no bookkeeping.

Printed: steps per second of each and the ratios to the baseline (environment steps; for the vectorised
environment ``64 ×`` its calls per second). Usage: ``python benchmarks/gym_throughput.py [--seconds 5] [--envs 64]``
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import casadi as ca
import numpy as np

from mmg_casadi.compiled import compile_function
from mmg_casadi.gym import ShipEnv, ShipVectorEnv, environment
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import NX, build_mmg, propeller_rpm_for_speed, rk4


def _rate(step, seconds: float) -> float:
    """Calls of ``step()`` per second, over about ``seconds`` after a warm-up of 20 calls."""
    for _ in range(20):
        step()
    n, t0 = 0, time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        for _ in range(50):
            step()
        n += 50
    return n / (time.perf_counter() - t0)


def baseline(ships: int, dt: float) -> tuple:
    """A plain Python step over ``ships`` ships calling the compiled MMG Function once per ship."""
    v = load_vessel()
    x, d, n = ca.SX.sym("x", NX), ca.SX.sym("delta"), ca.SX.sym("n")
    f = compile_function(ca.Function("mmg_rk4_bench", [x, d, n], [rk4(build_mmg(v.ship, v.steering), x, (d, n), dt)]))
    rpm = propeller_rpm_for_speed(1.0, v.ship)
    rng = np.random.default_rng(0)
    X = [np.array([1.0, 0, 0, 10.0 * i, 0, rng.uniform(-math.pi, math.pi), 0]) for i in range(ships)]
    psi_d = [s[5] for s in X]
    kp, kd, dmax = 3.5, 4.0, math.radians(35.0)

    def step():
        psi_d[0] += rng.uniform(-0.5, 0.5)  # the agent's order; the others hold their heading
        for i in range(ships):
            s = X[i]
            e = math.remainder(s[5] - psi_d[i], 2 * math.pi)
            delta = min(max(-kp * e - kd * s[2], -dmax), dmax)
            X[i] = np.asarray(f(s, delta, rpm)).ravel()
    return step


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=5.0, help="measuring time of each (s)")
    ap.add_argument("--envs", type=int, default=64, help="environments of the vectorised environment")
    ap.add_argument("--method", default="modified-vortex", help="the targets' method")
    a = ap.parse_args(argv)
    source = environment(5, a.method)
    params = {"t_max": 10000.0}  # no episode ends by time while measuring

    env = ShipEnv(source, params=params)
    env.reset(seed=0)
    env.action_space.seed(0)

    def one():
        _, _, term, trunc, _ = env.step(env.action_space.sample())
        if term or trunc:
            env.reset()
    print("compiling / loading the environment-5 closed loop ...", file=sys.stderr)
    single = _rate(one, a.seconds)

    vec = ShipVectorEnv(source, a.envs, params=params)
    vec.reset(seed=0)
    rng = np.random.default_rng(0)
    vec_rate = a.envs * _rate(lambda: vec.step(rng.uniform(-1, 1, (a.envs, 1)).astype(np.float32)), a.seconds)

    n_ships = env.problem.layout.n_ships
    base = _rate(baseline(n_ships, float(env.problem.params["dt"])), a.seconds)
    print(f"environment 5 ({n_ships} ships, {env.problem.layout.n_obstacles} obstacles, targets {a.method}), "
          f"random actions, {a.seconds:g} s each")
    print(f"  plain Python loop over the compiled MMG Function : {base:10.0f} steps/s (1.00)")
    print(f"  ShipEnv (1 environment)                          : {single:10.0f} steps/s ({single / base:.2f})")
    print(f"  ShipVectorEnv ({a.envs} environments)                  : {vec_rate:10.0f} steps/s "
          f"({vec_rate / base:.2f})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
