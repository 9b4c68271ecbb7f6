"""Numeric scenario states: the initial state of a scenario and its ship rows read by name.

Every consumer outside the closed loop reads states through these functions and the accessors of
:class:`~mmg_casadi.closed_loop.layout.Layout` (:meth:`~mmg_casadi.closed_loop.layout.Layout.row`,
:meth:`~mmg_casadi.closed_loop.layout.Layout.column`); no one else computes a state index.
"""

from __future__ import annotations

import numpy as np

from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.guidance import methods
from mmg_casadi.perception import layer as perception_layer
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed, scene_scales


def initial_state(layout: Layout, ships: list[dict], params: dict | None = None) -> np.ndarray:
    """Scenario state at t = 0: each ship at ``start`` with ``heading`` (rad) and surge speed ``speed`` × U_des
    (the ship's own design speed; the state holds it in the own ship's, :meth:`Layout.unit_vessel`).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the scenario.
    ships : list of dict
        Per ship ``start`` (L), ``heading`` (rad), ``speed`` (fraction of U_des), ``path`` (L) and optionally
        ``n_rpm`` (rev/min, the engine's starting speed; default the propeller speed of a steady ``speed``).
    params : dict, optional
        The resolved parameter set (default the table's): with perception, its ``perception_seed`` seeds every
        ship's noise generator and its AIS parameters give each ship's first report time
        (:func:`mmg_casadi.perception.layer.initial_rows`).

    Returns
    -------
    numpy.ndarray (nx,)
        The scenario state: the time (0), then each ship's row of ``Layout.ship_state``.

    Examples
    --------
    >>> lay = Layout(("none",))
    >>> x = initial_state(lay, [{"start": (0, 0), "heading": 0.5, "speed": 1.0, "path": [(0, 0), (9, 0)],
    ...                          "n_rpm": 115.5}])
    >>> float(x[lay.row("psi", 0)]), float(x[lay.row("n_prop", 0)]), float(x[lay.row("best_goal_dist", 0)])
    (0.5, 115.5, 9.0)
    """
    x = np.zeros(layout.nx)
    col = layout.column
    unit = load_vessel(layout.unit_vessel()).ship
    for i, s in enumerate(ships):
        row = np.zeros(layout.ns)
        _, mu = scene_scales(load_vessel(layout.vessel(i)).ship, unit)
        row[col("u")] = float(s["speed"]) * mu  # in the own ship's U_des (μ = 1.0 exactly for her hull)
        row[col("x")], row[col("y")] = s["start"]
        row[col("psi")] = float(s["heading"])
        row[col("n_prop")] = float(s["n_rpm"]) if "n_rpm" in s else propeller_rpm_for_speed(
            float(s["speed"]), load_vessel(layout.vessel(i)).ship)
        row[col("idx")] = 1.0
        row[col("t_goal")] = -1.0
        row[col("d_min")] = 1.0e6
        row[col("d_min_with")] = -1.0
        row[col("t_collision")] = -1.0
        row[col("collision_with")] = -1.0
        goal = np.asarray(s["path"], float).reshape(-1, 2)[-1]
        row[col("best_goal_dist")] = float(np.hypot(*(goal - np.asarray(s["start"], float))))
        row[col("x_best")], row[col("y_best")] = s["start"]
        for name in layout.memory:  # every memory row starts at the heading, a tally at 0
            row[col(name)] = 0.0 if name in layout.tallies else float(s["heading"])
        if "command_rpm" in layout.memory:  # a commanded ship's propeller order starts at her engine's speed
            row[col("command_rpm")] = row[col("n_prop")]
        x[layout.ship_block(i)] = row
    if layout.perception != "off":
        if params is None:
            from mmg_casadi.params import resolve
            params = resolve()
        for i, s in enumerate(ships):
            _, mu = scene_scales(load_vessel(layout.vessel(i)).ship, unit)
            T = perception_layer.initial_interval(params, unit, float(s["speed"]) * mu)
            for name, v in perception_layer.initial_rows(layout.perception, params["perception_seed"], i, T).items():
                x[layout.row(name, i)] = v
    return x


def ship_rows(layout: Layout, X) -> np.ndarray:
    """Reshape scenario states ``(nx, T)`` (or ``(nx,)``) to ``(T, N, ns)`` (or ``(N, ns)``).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the scenario.
    X : numpy.ndarray
        Scenario states, ``(nx, T)`` or ``(nx,)``.

    Returns
    -------
    numpy.ndarray
        ``(T, N, ns)`` for ``(nx, T)`` states, ``(N, ns)`` for one state.
    """
    X = np.asarray(X)
    if X.ndim == 1:
        return X[1:].reshape(layout.n_ships, layout.ns)
    return X[1:, :].T.reshape(X.shape[1], layout.n_ships, layout.ns)


def state_of(layout: Layout, X, name: str, ship: int | None = None) -> np.ndarray:
    """One state variable of every ship (or of ``ship``) in the state(s) ``X``.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout of the states.
    X : numpy.ndarray
        Scenario states ``(nx, T)`` or one state ``(nx,)``.
    name : str
        A name of :attr:`Layout.ship_state <mmg_casadi.closed_loop.layout.Layout.ship_state>`.
    ship : int, optional
        Ship index; all ships if omitted.

    Returns
    -------
    numpy.ndarray
        ``(N,)`` or ``(T, N)`` for all ships, a scalar or ``(T,)`` for ``ship``, in the state's units.

    Examples
    --------
    >>> lay = Layout(("none", "none"))
    >>> x = np.arange(lay.nx, dtype=float)
    >>> state_of(lay, x, "psi").tolist() == [float(lay.row("psi", 0)), float(lay.row("psi", 1))]
    True
    """
    col = ship_rows(layout, X)[..., layout.column(name)]
    return col if ship is None else col[..., ship]


def tallies(layout: Layout, x) -> list[dict]:
    """The tallies (``Method.tallies``: counts over a run) of every ship in the scenario state ``x``.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout of the state.
    x : numpy.ndarray (nx,)
        A scenario state (e.g. the final one).

    Returns
    -------
    list of dict
        Per ship, ``{name: count}`` of the tallies of her own method (empty for a method without tallies).

    Examples
    --------
    >>> tallies(Layout(("none",)), np.zeros(Layout(("none",)).nx))
    [{}]
    """
    rows = ship_rows(layout, np.asarray(x, float))
    return [{k: float(rows[i, layout.column(k)]) for k in methods.get(m).tallies}
            for i, m in enumerate(layout.methods)]
