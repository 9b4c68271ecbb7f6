"""The fleet step (one ship's step mapped over the fleet) gives exactly the unrolled step's next state.

With every other agent in each ship's neighbour list, the fleet step is the unrolled step to the bit (closest
approach included); with lists from the candidate radius, every ship whose neighbours within R_safe are all
listed moves exactly as in the unrolled step.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mmg_casadi.closed_loop.fleet import V_MAX, build_fleet_step, candidate_radius, neighbour_lists
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import FLEET_CHUNK, simulate
from mmg_casadi.closed_loop.step import build_closed_loop_step
from mmg_casadi.montecarlo.sampling import sample_traffic
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.scenario import scenario_from_dict
from test_sparse_step import LAYOUTS, _states


def _all_agents(layout):
    N, S = layout.n_ships, layout.n_obstacles
    nbr = np.full((layout.neighbours, N), float(N + S))
    for i in range(N):
        others = [j for j in range(N + S) if j != i]
        nbr[:len(others), i] = others
    return nbr


@pytest.mark.parametrize("layout", LAYOUTS, ids=lambda lay: lay.key())
def test_fleet_step_with_every_agent_listed_is_the_unrolled_step(layout):
    fleet = dataclasses.replace(layout, neighbours=layout.n_ships - 1 + layout.n_obstacles + 1)  # one pad slot
    X, P = _states(layout, 24, seed=len(layout.key()))
    unrolled = build_closed_loop_step(layout, sparse=True).map(X.shape[1])
    xu, au = (np.array(v) for v in unrolled(X, P))
    f = build_fleet_step(fleet)
    nbr = _all_agents(fleet)
    for c in range(X.shape[1]):
        xf, af = (np.array(v) for v in f(X[:, c], P[:, c], nbr))
        assert np.array_equal(xf.ravel(), xu[:, c])  # bit for bit
        a_u = au[:, c * layout.n_ships:(c + 1) * layout.n_ships]
        assert np.array_equal(np.isnan(af), np.isnan(a_u)) and np.array_equal(af[~np.isnan(af)], a_u[~np.isnan(a_u)])


def test_candidate_lists_keep_every_ship_exact_within_r_safe():
    layout = dataclasses.replace(LAYOUTS[0], neighbours=3)
    X, P = _states(LAYOUTS[0], 24, seed=3)
    unrolled = build_closed_loop_step(LAYOUTS[0], sparse=True)
    f = build_fleet_step(layout)
    radius = candidate_radius(15.0, 0.25, 1)
    checked = 0
    for c in range(X.shape[1]):
        nbr, overflow = neighbour_lists(layout, X[:, c], P[:, c], radius)
        xu = np.array(unrolled(X[:, c], P[:, c])[0]).ravel()
        xf = np.array(f(X[:, c], P[:, c], nbr)[0]).ravel()
        pos = np.column_stack([X[layout.rows("x"), c], X[layout.rows("y"), c]])
        for i in range(layout.n_ships):
            d = np.hypot(*(pos - pos[i]).T)
            listed = set(nbr[:, i].astype(int))
            if all(j in listed for j in np.flatnonzero((d < radius) & (np.arange(len(d)) != i))):
                blk = layout.ship_block(i)
                cols = [layout.column(k) for k in ("u", "v", "r", "x", "y", "psi", "delta", "t_collision")]
                assert np.array_equal(xf[blk][cols], xu[blk][cols])
                checked += 1
    assert checked >= 60  # of 24 × 8 ships; the others had more than 3 candidates


def test_neighbour_lists_are_sorted_padded_and_count_overflows():
    layout = dataclasses.replace(LAYOUTS[0], neighbours=2)
    X, P = _states(LAYOUTS[0], 4, seed=5)
    nbr, overflow = neighbour_lists(layout, X[:, 0], P[:, 0], 1e6)  # everyone is a candidate: 7 others > 2 slots
    assert nbr.shape == (2, layout.n_ships) and overflow == layout.n_ships
    assert np.all(np.diff(nbr, axis=0) > 0)
    nbr, overflow = neighbour_lists(layout, X[:, 0], P[:, 0], 0.0)
    assert overflow == 0 and np.all(nbr == layout.n_ships + layout.n_obstacles)


def test_a_fleet_rollout_has_the_unrolled_outcomes():
    """Ten ships at environment 5's density for 40 L/U: every state row but the closest approach is the same to
    the bit, and a closest approach differs only where the unrolled one lies beyond the candidate radius."""
    sc = scenario_from_dict(sample_traffic(10, seed=0).to_scenario_dict(t_max=40.0))
    unrolled = build_problem(sc)
    fleet = build_problem(sc, {"fleet_from_ships": 2})
    assert unrolled.layout.neighbours == 0 and fleet.layout.neighbours == PARAMETERS["neighbour_slots"].default
    tu = simulate(unrolled.layout, unrolled.x0, unrolled.p)
    tf = simulate(fleet.layout, fleet.x0, fleet.p)
    assert tf.neighbour_overflows == 0 and np.array_equal(tu.t, tf.t)
    lay = unrolled.layout
    same = [k for k in lay.ship_state if k not in ("d_min", "d_min_with")]
    for k in same:
        assert np.array_equal(tu.state(k), tf.state(k)), k
    du, df = tu.state("d_min")[-1], tf.state("d_min")[-1]
    radius = candidate_radius(15.0, 0.25, FLEET_CHUNK)
    assert np.all((du == df) | (du > radius - 2 * V_MAX * 0.25 * FLEET_CHUNK))
    final = [np.concatenate([[tr.t[-1]], tr.states[-1].ravel()]) for tr in (tu, tf)]
    ou, of = unrolled.model.outcomes(final[0]), fleet.model.outcomes(final[1])
    for a, b in zip(ou, of):
        assert {k: v for k, v in a.items() if "min_distance" not in k} == \
            {k: v for k, v in b.items() if "min_distance" not in k}
