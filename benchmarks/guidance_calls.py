"""Compiled time per guidance call per ship for each method with 1, 5 and 13 neighbours.

For every method (the reactive ones and the planner sb-mpc) and a scenario of 2, 6 or 14
ships (so each ship has 1, 5 or 13 neighbours, all inside R_safe), the natively compiled guidance Function
(:func:`mmg_casadi.closed_loop.simulation.compiled_guidance`: reactive field / velocity obstacle, ILOS and PD for every ship)
is mapped over many scenario states and timed; the time is divided by the number of states and ships (for sb-mpc
every call is a decision: its memory holds no behaviour, so the worst case of its decision interval). Printed
in nanoseconds and as a ratio to inverse-square with 1 neighbour (the paper's "computation effort" panel). Every
neighbour is within R_safe, so this is the worst case of the guidance the rollouts run (which evaluates a method
on the neighbours within R_safe only); the Monte Carlo study's ``guidance_call_us`` column times the same
guidance in the study's own configurations.

The first run compiles the Functions (the velocity obstacle with 14 ships takes several minutes with gcc -O2);
later runs load them from the cache (``$MMG_CASADI_CACHE`` or ``~/.cache/mmg-casadi``).

Usage: ``python benchmarks/guidance_calls.py [--ships 2,6,14] [--methods a,b] [--columns 512]``
"""

from __future__ import annotations

import argparse
import math
import sys
import time

import numpy as np

from mmg_casadi.closed_loop.layout import default_globals, Layout, pack_params
from mmg_casadi.closed_loop.state import initial_state
from mmg_casadi.guidance.methods import AVOIDING, PLANNERS
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed
from mmg_casadi.montecarlo.execution import time_guidance
from mmg_casadi.closed_loop.simulation import compiled_guidance

METHODS = AVOIDING + PLANNERS


def states(layout: Layout, columns: int, seed: int = 0):
    """``columns`` scenario states with all ships inside R_safe of each other, and their parameters."""
    rng = np.random.default_rng(seed)
    n = layout.n_ships
    X, P = [], []
    g = default_globals()
    for _ in range(columns):
        ang = 2 * math.pi * np.arange(n) / n + rng.uniform(-0.2, 0.2, n)
        radius = rng.uniform(5.0, 7.0)
        ships = []
        for i in range(n):
            start = (radius * math.cos(ang[i]), radius * math.sin(ang[i]))
            goal = (-3 * start[0], -3 * start[1])
            heading = math.atan2(goal[1] - start[1], goal[0] - start[0]) + rng.uniform(-0.3, 0.3)
            ships.append({"n_rpm": propeller_rpm_for_speed(1.0), "path": [start, goal], "stays": False,
                          "start": start, "heading": heading, "speed": rng.uniform(0.5, 1.0)})
        X.append(initial_state(layout, ships))
        P.append(pack_params(layout, g, ships))
    return np.column_stack(X), np.column_stack(P)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ships", default="2,6,14", help="ships per scenario (neighbours = ships - 1)")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--columns", type=int, default=512, help="scenario states per timed call")
    a = ap.parse_args(argv)
    ships = [int(s) for s in a.ships.split(",")]
    methods = [m.strip() for m in a.methods.split(",") if m.strip()]

    results = {}
    for m in methods:
        for n in ships:
            layout = Layout(methods=(m,) * n)
            t0 = time.perf_counter()
            compiled_guidance(layout)
            dt = time.perf_counter() - t0
            if dt > 5:
                print(f"  compiled guidance {m} x{n} in {dt:.0f} s (cached from now on)", file=sys.stderr)
            X, P = states(layout, a.columns)
            # best of 3 measurements (each ~0.1 s) to damp scheduler noise
            results[(m, n)] = 1e3 * min(time_guidance(layout, X, P, min_time=0.1, max_repeats=200)
                                        for _ in range(3))
    base_key = ("inverse-square", min(ships))
    base = results.get(base_key)
    head = f"{'method':>18s} " + " ".join(f"{f'{n - 1} nb [ns]':>12s} {'ratio':>6s}" for n in ships)
    print(f"Compiled time per guidance call per ship (ratio to {base_key[0]} with {base_key[1] - 1} neighbour)")
    print(head)
    for m in methods:
        cells = []
        for n in ships:
            ns = results[(m, n)]
            ratio = ns / base if base else math.nan
            cells.append(f"{ns:12.0f} {ratio:6.2f}")
        print(f"{m:>18s} " + " ".join(cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())
