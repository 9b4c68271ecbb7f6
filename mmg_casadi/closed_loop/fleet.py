"""The fleet step: one ship's step mapped over the fleet, each ship seeing a fixed number of neighbour slots.

The unrolled step (:func:`~mmg_casadi.closed_loop.step.build_closed_loop_step`) writes every ship and every pair
into one expression, so its code, compile time and compiler memory grow with the square of the fleet. The fleet
step writes one ship once and maps it over the ships with CasADi's ``map``: its code does not depend on the
number of ships. Each ship sees ``K = layout.neighbours`` neighbour slots, filled from a *neighbour list* (agent
indices, ``K × N``) that the rollout computes once per chunk of steps (:func:`neighbour_lists`, a k-d tree over
the positions, O(N log N)) and the compiled step gathers by index (parametric indexing) at every step.

Exactness. The list of a ship holds, in agent order, every ship and obstacle within the *candidate radius*
``R_safe + 2 V_max T_chunk`` at the chunk's start (``V_max`` bounds any speed over the ground, ``T_chunk`` the
chunk's duration), so every neighbour that can come within R_safe during the chunk is in it. A method ignores
an inactive neighbour (a masked term adds an exact zero), so a ship's guidance, rudder, engine and motion are
those of the unrolled step to the bit as long as no more than ``K`` agents are candidates. Two differences, both
documented: with more than ``K`` candidates the ship keeps its ``K`` nearest (:func:`neighbour_lists` counts the
overflows), and the closest approach ``d_min`` is recorded among the candidates only (a ship that never had
anyone within the candidate radius ends with no closest approach instead of a large one). Collisions (within
each pair's collision distance, from the two ships' lengths gathered with the slots, far inside R_safe) are
recorded exactly.

Examples
--------
>>> lay = Layout(("modified-vortex",) * 40, n_obstacles=3, neighbours=8)
>>> f = build_fleet_step(lay)
>>> f.name(), f.size_in(2)
('fleet_modifiedvortexx40_o3_w0_k2_v80huanghn8', (8, 40))
"""

from __future__ import annotations

import functools

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop.layout import GLOBAL_PARAMS, SHIP_PARAMS, STOPPED, Layout
from mmg_casadi.closed_loop.step import (_ROW, ENVELOPE, NAUX, _models, _ship_update, meet, ship_kinematics,
                                         stop_function)
from mmg_casadi.guidance.methods import forget_on_unregister
from mmg_casadi.vessel.library import pair_collision_distance

AGENT_ROWS = 6
"""Rows of the agent table the slots are gathered from: position (2), velocity over the ground (2), presence,
radius."""
FAR = 1.0e9
"""Position of the padding agent (index ``N + S``): never present, never near."""
V_MAX = float(np.hypot(ENVELOPE["speed"], ENVELOPE["speed"]))
"""Bound on a ship's speed through the water inside the model envelope (U): the candidate radius uses it."""


def candidate_radius(r_safe: float, dt: float, chunk: int) -> float:
    """Radius (L) within which an agent at a chunk's start can come within ``r_safe`` of a ship during the chunk.

    Two ships close at most at 2 :data:`V_MAX` (a uniform current carries both alike); a ship closes on a static
    obstacle at most at V_MAX plus the current, which the table bounds by 1 U < V_MAX, so the same radius covers it.

    Parameters
    ----------
    r_safe : float
        The safe radius R_safe (L).
    dt : float
        Guidance step (L/U).
    chunk : int
        Steps of the chunk.

    Returns
    -------
    float
        ``r_safe + 2 V_MAX dt chunk`` (L).

    Examples
    --------
    >>> round(candidate_radius(15.0, 0.25, 4), 3)
    23.485
    """
    return float(r_safe + 2.0 * V_MAX * dt * chunk)


def neighbour_lists(layout: Layout, x: np.ndarray, p: np.ndarray, radius: float) -> tuple[np.ndarray, int]:
    """The ``K × N`` neighbour list of every ship (agent indices in increasing order, padded with ``N + S``) and
    the number of ships that had more than ``K`` candidates within ``radius`` (each keeps its ``K`` nearest).

    Parameters
    ----------
    layout : Layout
        A fleet layout (``layout.neighbours > 0``).
    x : ndarray (nx,)
        Scenario state at the chunk's start.
    p : ndarray (np,)
        Parameter vector.
    radius : float
        Candidate radius (L; :func:`candidate_radius`).

    Returns
    -------
    neighbours : numpy.ndarray (K, N)
        Agent indices of each ship's neighbours (floats, increasing, padded with ``N + S``).
    overflow : int
        Number of ships with more than ``K`` candidates.
    """
    N, S, K = layout.n_ships, layout.n_obstacles, layout.neighbours
    pts = np.column_stack([x[layout.rows("x")], x[layout.rows("y")]])
    if S:
        obs = np.asarray(p, float)[layout.param_block("obstacles")].reshape(S, 3)
        pts = np.vstack([pts, obs[:, 0:2]])
    n_agents = len(pts)
    from scipy.spatial import cKDTree  # about 0.2 s to import: only for fleet layouts
    _, idx = cKDTree(pts).query(pts[:N], k=min(K + 2, n_agents), distance_upper_bound=radius)
    idx = np.asarray(idx).reshape(N, -1)
    idx = np.where(idx == np.arange(N)[:, None], n_agents, idx)  # drop the ship itself (pad = N + S)
    valid = idx < n_agents
    # nearest first, self removed: keep the first K valid entries of each row (the tree sorts by distance)
    order = np.argsort(~valid, axis=1, kind="stable")
    idx = np.take_along_axis(idx, order, axis=1)
    overflow = int(np.count_nonzero(valid.sum(axis=1) > K))
    out = np.sort(idx[:, :K], axis=1).T.astype(float)
    if out.shape[0] < K:
        out = np.vstack([out, np.full((K - out.shape[0], N), float(n_agents))])
    return out, overflow


def _ship_symbols(layout: Layout) -> dict:
    """Symbols of one ship's inputs to the fleet step."""
    G = len(GLOBAL_PARAMS) + len(layout.method_inputs)
    return {"x": ca.SX.sym("x", layout.ns), "sp": ca.SX.sym("sp", layout.ship_params_size),
            "g": ca.SX.sym("g", G), "walls": ca.SX.sym("walls", 4 * layout.n_walls),
            "env": ca.SX.sym("env", 5 if layout.disturbed else 0), "t": ca.SX.sym("t"),
            "nb": ca.SX.sym("nb", AGENT_ROWS * layout.neighbours)}


def _ship_context(layout: Layout, sym: dict) -> tuple[dict, dict]:
    """The one-ship context of :func:`~mmg_casadi.closed_loop.step._ship_update` (the same expressions as the
    unrolled step's for that ship)."""
    names = GLOBAL_PARAMS + layout.method_inputs
    P = {name: sym["g"][k] for k, name in enumerate(names)}
    sp = sym["sp"]
    Pi = {name: sp[k] for k, name in enumerate(SHIP_PARAMS)}
    k0 = len(SHIP_PARAMS)
    Pi["path"] = ca.reshape(sp[k0:k0 + 2 * layout.max_path], 2, layout.max_path)
    Pi["leg_rpm"] = sp[k0 + 2 * layout.max_path:]
    P["ships"] = [Pi]
    P["obstacles"] = ca.SX(3, 0)
    P["walls"] = ca.reshape(sym["walls"], 4, layout.n_walls)
    S_ = {name: layout.column(name) for name in layout.ship_state}
    Xi, t = sym["x"], sym["t"]
    E, env_args = (sym["env"], (sym["env"][0:4],)) if layout.disturbed else (None, ())
    if layout.disturbed:
        P["env"] = E
    pos, vel, present = ship_kinematics(Xi, S_, E, Pi["stays"])
    running = t < P["t_max"] - 1e-9
    c = {"P": P, "S": S_, "t": t, "X": [Xi], "pos": [pos], "psi": [Xi[S_["psi"]]],
         "vel": [vel], "E": E, "env_args": env_args, "running": running,
         "sailing": [ca.logic_and(Xi[S_["status"]] == 0, running)], "present": [present]}
    return c, S_


def _combos(layout: Layout) -> list[tuple[str, str]]:
    """The (method, vessel) pairs of the fleet, in first-appearance order."""
    return list(dict.fromkeys((layout.methods[i], layout.vessel(i)) for i in range(layout.n_ships)))


@functools.lru_cache(maxsize=16)
def _ship_functions(layout: Layout) -> dict:
    """Per-ship Functions of the fleet step: prelude, update (one per (method, vessel)), hold, bookkeeping."""
    K = layout.neighbours
    sym = _ship_symbols(layout)
    c, S_ = _ship_context(layout, sym)
    args = [sym[k] for k in ("x", "sp", "g", "walls", "env", "t", "nb")]
    key = layout.key()
    pre = ca.Function(f"fleet_pre_{key}", args[:6], [ca.vertcat(c["pos"][0], c["vel"][0], c["present"][0]),
                                                     c["sailing"][0]], {"cse": True})
    nb = ca.reshape(sym["nb"], AGENT_ROWS, K)
    slots = (nb[0:2, :], nb[2:4, :], nb[5:6, :], nb[4:5, :])
    mmgs = _models(layout)
    updates = []
    for n, (method, vessel) in enumerate(_combos(layout)):
        new, aux = _ship_update(layout, 0, c, mmgs[vessel], 1, sparse=True, nb=slots, method=method, vessel=vessel)
        updates.append(ca.Function(f"fleet_sail{n}_{key}", args, [new, aux], {"cse": True}))
    hold = ca.Function(f"fleet_hold_{key}", args, [sym["x"], ca.DM.nan(NAUX, 1)])
    # bookkeeping: closest approach among the slots and first collision with a slot or a wall, after the step
    xn, nb_vec, nb_idx = ca.SX.sym("xn", layout.ns), ca.SX.sym("nb_next", 4 * K), ca.SX.sym("nb_idx", K)
    nb_next = ca.reshape(nb_vec, 4, K)  # position, presence and length of each slot after the step
    P = c["P"]
    rows = tuple(xn[S_[k]] for k in _ROW)
    cd, ell, N = P["collision_distance"], P["ships"][0]["length"], layout.n_ships
    slots = [(nb_idx[k], nb_next[0:2, k], nb_next[2, k],
              ca.if_else(nb_idx[k] < N - 0.5, pair_collision_distance(cd, ell, nb_next[3, k]), cd))
             for k in range(K)]  # a slot below N is a ship, the others are obstacles or padding
    met = meet(layout, P, ca.vertcat(xn[S_["x"]], xn[S_["y"]]), rows, c["present"][0], c["running"], sym["t"],
               slots, P["ships"][0]["half_beam"])
    r0, r1 = layout.column(_ROW[0]), layout.column(_ROW[-1]) + 1
    book_args = [sym["x"], sym["sp"], sym["g"], sym["walls"], sym["t"], xn, nb_vec, nb_idx]
    update = ca.Function(f"fleet_meet_{key}", book_args, [met], {"cse": True})
    keep = ca.Function(f"fleet_keep_{key}", book_args, [xn[r0:r1]])
    return {"pre": pre, "updates": updates, "hold": hold, "meet": update, "keep": keep}


def _gather(table, nbr, rows: int):
    """Columns ``nbr`` (``K × N`` agent indices) of ``table`` (``rows × agents``) as ``(rows K) × N``."""
    K, N = nbr.size1(), nbr.size2()
    index = ca.repmat(rows * ca.reshape(nbr, 1, K * N), rows, 1) + ca.repmat(ca.DM(list(range(rows))), 1, K * N)
    return ca.reshape(ca.vec(table)[index], rows * K, N)


@functools.lru_cache(maxsize=16)
def build_fleet_step(layout: Layout) -> ca.Function:
    """Named Function ``fleet_<key>(x, p, nbr) -> (x_next, aux)``: the closed-loop step of a fleet layout, one
    ship's step mapped over the ships (see the module docstring).

    ``nbr`` (``K × N``) is the neighbour list of :func:`neighbour_lists`; ``x``, ``p``, ``x_next`` and ``aux``
    are laid out as for the unrolled step.

    Parameters
    ----------
    layout : Layout
        A fleet layout (``layout.neighbours > 0``, exact: ``smooth`` is None).
    """
    if layout.neighbours < 1 or layout.smooth is not None:
        raise ValueError(f"a fleet step needs neighbours >= 1 and an exact layout, got {layout}")
    N, S, K, ns = layout.n_ships, layout.n_obstacles, layout.neighbours, layout.ns
    f = _ship_functions(layout)
    key = layout.key()
    x, p, nbr = ca.MX.sym("x", layout.nx), ca.MX.sym("p", layout.np), ca.MX.sym("nbr", K, N)
    G0, nsp = len(GLOBAL_PARAMS), layout.ship_params_size
    t, X = x[0], ca.reshape(x[1:], ns, N)
    SP = ca.reshape(p[G0:G0 + N * nsp], nsp, N)
    off = G0 + N * nsp
    obs = ca.reshape(p[off:off + 3 * S], 3, S)
    off += 3 * S
    walls = p[off:off + 4 * layout.n_walls]
    off += 4 * layout.n_walls
    env = p[off:off + 5] if layout.disturbed else ca.MX(0, 1)
    off += 5 if layout.disturbed else 0
    g = ca.vertcat(p[0:G0], p[off:])
    shared, sailing = f["pre"].map(N)(X, SP, g, walls, env, t)
    radius = p[GLOBAL_PARAMS.index("ship_radius")]
    pad = ca.DM([FAR, FAR, 0.0, 0.0, 0.0, 0.0])
    table = ca.horzcat(ca.vertcat(shared, ca.repmat(radius, 1, N)),
                       ca.vertcat(obs[0:2, :], ca.MX.zeros(2, S), ca.MX.ones(1, S), obs[2:3, :]), pad)
    NB = _gather(table, nbr, AGENT_ROWS)
    combo_of = {cv: n for n, cv in enumerate(_combos(layout))}
    combo = ca.DM([[combo_of[(layout.methods[i], layout.vessel(i))] for i in range(N)]])
    which = ca.if_else(sailing, ca.repmat(combo, 1, 1), -1)
    ship = ca.Function.conditional(f"fleet_ship_{key}", f["updates"], f["hold"])
    new, aux = ship.map(N)(which, X, SP, g, walls, env, t, NB)
    # closest approach and collisions, from the positions after the step, for ships present at its start
    rows_xy = [layout.column("x"), layout.column("y")]
    lengths = SP[SHIP_PARAMS.index("length"), :]
    after = ca.horzcat(ca.vertcat(new[rows_xy, :], shared[4, :], lengths),
                       ca.vertcat(obs[0:2, :], ca.MX.ones(1, S), ca.MX.zeros(1, S)), ca.DM([FAR, FAR, 0.0, 0.0]))
    NB4 = _gather(after, nbr, 4)
    running = t < p[GLOBAL_PARAMS.index("t_max")] - 1e-9
    counts = ca.logic_and(ca.logic_and(shared[4, :], running), X[layout.column("status"), :] != STOPPED)
    row = ca.Function.conditional(f"fleet_row_{key}", [f["keep"]], f["meet"])
    rows = row.map(N)(counts, X, SP, g, walls, t, new, NB4, nbr)
    r0, r1 = layout.column(_ROW[0]), layout.column(_ROW[-1]) + 1
    X_next = stop_function(layout).map(N)(X, ca.vertcat(new[:r0, :], rows, new[r1:, :]))
    clock = ca.if_else(running, t + p[GLOBAL_PARAMS.index("dt")], t)
    return ca.Function(f"fleet_{key}", [x, p, nbr], [ca.vertcat(clock, ca.vec(X_next)), aux],
                       ["x", "p", "nbr"], ["x_next", "aux"])


forget_on_unregister(_ship_functions.cache_clear, build_fleet_step.cache_clear)
