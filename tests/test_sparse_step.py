"""The sparse closed-loop step (what rollouts compile) gives exactly the dense step's next state.

The sparse step skips ships that do not sail and shows each method only its neighbours within R_safe
(:func:`mmg_casadi.closed_loop.step.build_closed_loop_step`, ``sparse=True``). Random scenario states — ships spread
from all-within-R_safe to far apart, some finished (staying or not), some diverged — exercise every branch
(no, 1, 2, 3–4 and more active neighbours); both steps are evaluated by CasADi's virtual machine, no compiling.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from mmg_casadi.closed_loop.layout import default_globals, Layout, pack_params
from mmg_casadi.closed_loop.state import initial_state
from mmg_casadi.closed_loop.step import build_closed_loop_step, build_guidance
from mmg_casadi.errors import ParameterError
from mmg_casadi.guidance.methods import AVOIDING, PLANNERS
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed


def _states(layout: Layout, count: int, seed: int):
    """``count`` random scenario states and parameter vectors of ``layout``."""
    rng = np.random.default_rng(seed)
    n, g = layout.n_ships, default_globals()
    X, P = [], []
    for k in range(count):
        spread = (4.0, 12.0, 30.0, 80.0)[k % 4]  # R_safe = 15 L: from all neighbours active to none
        ships = []
        for _ in range(n):
            start = tuple(rng.uniform(-spread, spread, 2))
            goal = tuple(np.asarray(start) + rng.uniform(-60, 60, 2))
            ships.append({"n_rpm": propeller_rpm_for_speed(rng.uniform(0.5, 1.0)), "path": [start, goal],
                          "stays": bool(rng.integers(2)), "start": start,
                          "heading": rng.uniform(-math.pi, math.pi), "speed": rng.uniform(0.3, 1.0)})
        x = initial_state(layout, ships)
        for i in range(n):
            x[layout.row("v", i)] = rng.normal(0, 0.05)
            x[layout.row("r", i)] = rng.normal(0, 0.1)
            x[layout.row("delta", i)] = rng.normal(0, 0.2)
            for name in layout.memory:
                x[layout.row(name, i)] = rng.uniform(-math.pi, math.pi)
            x[layout.row("status", i)] = rng.choice([0, 0, 0, 1, 2])
        x[0] = rng.uniform(0, 50)
        obstacles = [tuple(rng.uniform(-spread, spread, 2)) + (0.5,) for _ in range(layout.n_obstacles)]
        walls = [(-100.0, 20.0 + 5 * w, 100.0, 20.0 + 5 * w) for w in range(layout.n_walls)]
        X.append(x)
        P.append(pack_params(layout, g, ships, obstacles, walls))
    return np.column_stack(X), np.column_stack(P)


LAYOUTS = [Layout((m,) * 6, n_obstacles=2) for m in AVOIDING + PLANNERS] + [
    Layout(("modified-vortex", "velocity-obstacle", "none", "colregs-vortex"), n_obstacles=1),
    Layout(("modified-vortex",) * 3, n_walls=2),
    Layout(("velocity-obstacle", "colregs-vortex", "velocity-obstacle-speed", "none"), n_obstacles=1, n_walls=2,
           n_land=2),  # the land test of the velocity obstacles and colregs-vortex
    Layout(("velocity-obstacle",) * 4, n_obstacles=1, vo_cone="wide", vo_hold=False),
    Layout(("colregs-vortex", "modified-vortex", "velocity-obstacle", "none"), n_obstacles=1,
           vessels=("kcs", "kvlcc2", "kcs", "kvlcc2")),  # mixed hulls: a KVLCC2 in the KCS's units
    Layout(("sb-mpc", "none", "colregs-vortex", "sb-mpc"), n_obstacles=1, n_walls=2, n_land=2),  # its grounding cost
]


@pytest.mark.parametrize("layout", LAYOUTS, ids=lambda lay: lay.key())
def test_sparse_step_is_the_dense_step(layout):
    X, P = _states(layout, 24, seed=len(layout.key()))
    dense = build_closed_loop_step(layout).map(X.shape[1])
    sparse = build_closed_loop_step(layout, sparse=True).map(X.shape[1])
    xd, ad = (np.array(v) for v in dense(X, P))
    xs, as_ = (np.array(v) for v in sparse(X, P))
    assert np.array_equal(xd, xs)  # bit for bit
    # aux: equal for every sailing ship, NaN for the others
    sailing = np.array([[X[layout.row("status", i), c] == 0 for c in range(X.shape[1])]
                        for i in range(layout.n_ships)]).T.reshape(-1)
    ad, as_ = ad.T.reshape(-1, ad.shape[0]), as_.T.reshape(-1, as_.shape[0])
    assert np.array_equal(ad[sailing], as_[sailing])
    assert np.isnan(as_[~sailing]).all()
    gs = np.array(build_guidance(layout, sparse=True).map(X.shape[1])(X, P)).T.reshape(-1)
    assert np.array_equal(gs[sailing], ad[sailing, 0]) and np.isnan(gs[~sailing]).all()


def test_the_random_states_cover_every_branch():
    layout = LAYOUTS[0]
    X, _ = _states(layout, 24, seed=1)
    counts = set()
    for c in range(X.shape[1]):
        pos = np.array([[X[layout.row("x", i), c], X[layout.row("y", i), c]] for i in range(layout.n_ships)])
        d = np.hypot(*(pos[:, None, :] - pos[None, :, :]).transpose(2, 0, 1))
        counts |= set((d < 15.0).sum(axis=1) - 1)
    assert {0, 1, 2, 3, 5} <= counts


def test_a_smooth_layout_has_no_sparse_step():
    layout = dataclasses.replace(LAYOUTS[0], smooth=10.0)
    with pytest.raises(ParameterError, match="sparse"):
        build_closed_loop_step(layout, sparse=True)
