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


def _obstacle_field(n: int, ships: int = 2) -> dict:
    """``ships`` ships passing each other in a lane kept free of ``n`` obstacles scattered around it."""
    rng = np.random.default_rng(0)
    obstacles = []
    while len(obstacles) < n:
        p = rng.uniform(-300, 300, 2)
        if abs(p[1]) > 12 or not -10 <= p[0] <= 70:
            obstacles.append({"position": [float(p[0]), float(p[1])]})
    return {"settings": {"method": "modified-vortex", "t_max": 40.0},
            "ships": [{"name": f"s{i}", "start": [60.0 * (i % 2), 5.0 * i], "heading": 180.0 * (i % 2),
                       "speed": 1.0, "waypoints": [[60.0 * (1 - i % 2), 5.0 * i]]} for i in range(ships)],
            "obstacles": obstacles}


def test_obstacle_heavy_layouts_run_the_fleet_step_whose_code_does_not_grow_with_the_obstacles():
    # the unrolled step writes every ship-obstacle pair: 2 ships with 500 obstacles made cc1 grow past 6 GB;
    # beyond MAX_UNROLLED_OBSTACLE_PAIRS the obstacles reach a ship through the fleet step's slots
    from mmg_casadi.compiled import generate_source
    from mmg_casadi.limits import MAX_UNROLLED_OBSTACLE_PAIRS
    few = build_problem(scenario_from_dict(_obstacle_field(MAX_UNROLLED_OBSTACLE_PAIRS // 2))).layout
    many = [build_problem(scenario_from_dict(_obstacle_field(n))).layout for n in (100, 2000)]
    assert few.neighbours == 0 and all(lay.neighbours == PARAMETERS["neighbour_slots"].default for lay in many)
    sizes = [len(generate_source(build_fleet_step(lay))) for lay in many]
    assert abs(sizes[1] - sizes[0]) < 0.01 * sizes[0], sizes  # the same code but for the obstacle count


def test_commanded_ships_among_many_obstacles_are_refused_in_one_line():
    # the fleet step, which obstacle-heavy scenarios run, takes no commands (the Gymnasium env commands ship 0)
    from mmg_casadi.errors import ScenarioError
    from mmg_casadi.limits import MAX_UNROLLED_OBSTACLE_PAIRS
    n = MAX_UNROLLED_OBSTACLE_PAIRS // 2
    assert build_problem(scenario_from_dict(_obstacle_field(n)), commanded=[0]).layout.commanded == (0,)
    with pytest.raises(ScenarioError, match=r"obstacles: expected at most 32 obstacles with 2 ships in a scenario "
                                            r"with commanded ships .* got 33"):
        build_problem(scenario_from_dict(_obstacle_field(n + 1)), commanded=[0])


@pytest.mark.slow
def test_two_ships_and_2000_obstacles_compile_and_run_within_60_s_and_1_gb(tmp_path):
    # measured on the 2-core machine: 17 s and 229 MiB (whole process tree) with an empty cache
    import os
    import subprocess
    import sys
    import time
    import tomli_w
    scenario = tmp_path / "obstacles.toml"
    scenario.write_text(tomli_w.dumps(_obstacle_field(2000)))
    env = {**os.environ, "MMG_CASADI_CACHE": str(tmp_path / "cache")}
    t0 = time.monotonic()
    proc = subprocess.Popen([sys.executable, "-m", "mmg_casadi.cli", "simulate", str(scenario), "--out",
                             str(tmp_path / "out")], env=env, stderr=subprocess.PIPE, text=True)
    peak = 0
    while proc.poll() is None:  # the whole tree's resident memory: the program, the watchdog and the compiler
        peak = max(peak, _tree_rss(proc.pid))
        time.sleep(0.05)
    assert proc.returncode == 0, proc.stderr.read()
    assert time.monotonic() - t0 < 60.0 and peak < 1 << 30, (time.monotonic() - t0, peak)


def _tree_rss(root: int) -> int:
    """Resident bytes of ``root`` and its descendants (from /proc)."""
    import os
    from mmg_casadi._watchdog import descendants
    total = 0
    for pid in descendants([root]):
        try:
            total += int(open(f"/proc/{pid}/statm").read().split()[1]) * os.sysconf("SC_PAGE_SIZE")
        except OSError:
            pass
    return total
