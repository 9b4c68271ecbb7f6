"""The one judgement of a run: each ship's outcome and CE/MCTE from its final state.

Every runner (single scenarios, the Monte Carlo, Imazu's problems, tuning) judges a run with these functions,
through :meth:`mmg_casadi.closed_loop.problem.ClosedLoopModel.outcomes`.
"""

from __future__ import annotations

import math

import numpy as np

from mmg_casadi.closed_loop.layout import SHIP_STATE, STOPPED, Layout
from mmg_casadi.closed_loop.state import ship_rows
from mmg_casadi.guidance import hazards

S_ = {name: i for i, name in enumerate(SHIP_STATE)}
"""Column of each common row in a ship's row (:data:`SHIP_STATE`; the memory rows follow them)."""

RUN_FAILURES = ("collision", "grounding", "timeout", "diverged", "stalled")
"""How a run fails (:func:`run_outcome`); ``""`` when it succeeds."""

OUTCOMES = ("reached", "diverged", "stalled", "timeout", "grounded", "collided")
"""A ship's outcome: reached its goal, left the model envelope, made no progress (``stall_window``), none of
these by the end, or her voyage ended by touching land (``grounded``) or a ship, an obstacle or a channel wall
(``collided``; :data:`~mmg_casadi.closed_loop.layout.STOPPED`). A grounded or collided ship never reached her
goal."""


def ship_outcome(row, t_end: float, stall_window: float, kind: str | None = None
                 ) -> tuple[str, tuple[float, float] | None]:
    """Outcome of one ship from its final state row (:data:`SHIP_STATE`) — the one judgement every runner uses.

    Returns the outcome (one of :data:`OUTCOMES`) and, for ``"stalled"``, the position closest to the goal.

    Parameters
    ----------
    row : numpy.ndarray (ns,)
        Final state row of the ship (:data:`SHIP_STATE`, then any memory rows).
    t_end : float
        End time of the run (L/U).
    stall_window : float
        A ship that has not come closer to its goal for this long is stalled (L/U).
    kind : str, optional
        What she first touched (:func:`collision_kind`), for a ship whose voyage a contact ended: ``"land"``
        makes her ``"grounded"``, anything else ``"collided"``.

    Returns
    -------
    outcome : str
        One of :data:`OUTCOMES`.
    stalled_at : tuple of float or None
        For ``"stalled"``, the position (x, y) closest to the goal (L); else None.

    Examples
    --------
    >>> row = np.zeros(len(SHIP_STATE)); row[S_["status"]] = 1
    >>> ship_outcome(row, 80.0, 50.0)
    ('reached', None)
    >>> row[S_["status"]] = 0; row[S_["t_best"]] = 20.0; row[S_["x_best"]] = 3.0
    >>> ship_outcome(row, 300.0, 50.0)
    ('stalled', (3.0, 0.0))
    >>> row[S_["status"]] = STOPPED; ship_outcome(row, 300.0, 50.0, "land")
    ('grounded', None)
    """
    status = row[S_["status"]]
    if status == 1:
        return "reached", None
    if status == 2:
        return "diverged", None
    if status == STOPPED:
        return ("grounded" if kind == "land" else "collided"), None
    if t_end - row[S_["t_best"]] >= stall_window:
        return "stalled", (float(row[S_["x_best"]]), float(row[S_["y_best"]]))
    return "timeout", None


def voyage_metrics(rows: np.ndarray, t_end: float, delta_max: float) -> tuple[np.ndarray, np.ndarray]:
    """CE and MCTE of every ship from final state rows ``(N, ns)`` — the one definition every runner uses.

    ``CE = ∫|δ| dt / (δ_max T)`` (eq. (controller_effort_equation)) and ``MCTE = ∫|y_e| dt / T`` (eq.
    (crosstrack_metric_equation)) with the integrals accumulated by the compiled step while the ship sails
    (trapezoidal in δ, the cross-track error sampled at each step's start) and ``T`` the time to goal, the time
    of the collision or grounding that ended her voyage, or the end time for a ship still sailing; ``nan`` for a
    diverged ship (its voyage time is not in the state).

    Parameters
    ----------
    rows : numpy.ndarray (N, ns)
        Final state rows of the ships.
    t_end : float
        End time of the run (L/U).
    delta_max : float
        Largest rudder angle δ_max (rad).

    Returns
    -------
    ce : numpy.ndarray (N,)
        Controller effort CE (dimensionless; nan for a diverged ship).
    mcte : numpy.ndarray (N,)
        Mean cross-track error MCTE (L; nan for a diverged ship).

    Examples
    --------
    >>> rows = np.zeros((1, len(SHIP_STATE))); rows[0, S_["status"]] = 1; rows[0, S_["t_goal"]] = 10.0
    >>> rows[0, S_["ce_int"]] = 1.0; rows[0, S_["mcte_int"]] = 5.0
    >>> ce, mcte = voyage_metrics(rows, 10.0, 0.5)
    >>> float(ce[0]), float(mcte[0])
    (0.2, 0.5)
    """
    rows = np.atleast_2d(np.asarray(rows, float))
    status = rows[:, S_["status"]]
    T = np.where(status == 1, rows[:, S_["t_goal"]], np.where(status == 0, t_end, np.where(
        status == STOPPED, rows[:, S_["t_collision"]], np.nan)))
    with np.errstate(invalid="ignore", divide="ignore"):
        T = np.where(T > 0, T, np.nan)
        return rows[:, S_["ce_int"]] / (delta_max * T), rows[:, S_["mcte_int"]] / T


def collision_kind(layout: Layout, agent: int) -> str:
    """What agent index ``agent`` of a ship's ``collision_with`` / ``d_min_with`` row is: ``"ship"`` or a hazard
    kind of :data:`~mmg_casadi.guidance.hazards.KINDS` (``"obstacle"``, ``"wall"``, ``"land"``: the last
    ``Layout.n_land`` (:class:`~mmg_casadi.closed_loop.layout.Layout`) wall segments).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout of the run.
    agent : int
        Agent index: ships ``0..N-1``, then obstacles, then wall segments.

    Returns
    -------
    str
        ``"ship"``, ``"obstacle"``, ``"wall"`` or ``"land"``.

    Examples
    --------
    >>> lay = Layout(("none", "none"), n_obstacles=1, n_walls=3, n_land=1)
    >>> [collision_kind(lay, j) for j in range(6)]
    ['ship', 'ship', 'obstacle', 'wall', 'wall', 'land']
    """
    if agent < layout.n_ships:
        return "ship"
    k = agent - layout.n_ships
    for name, count in (("obstacle", layout.n_obstacles), ("wall", layout.n_walls - layout.n_land),
                        ("land", layout.n_land)):
        if k < count:
            return hazards.KINDS[name].name
        k -= count
    raise ValueError(f"agent {agent} is not in a layout of {layout.n_agents + layout.n_walls} agents")


def ship_outcomes(layout: Layout, x_final, params: dict) -> list[dict]:
    """Per ship: outcome, stalled position, time to goal, CE, MCTE, collision (when, with whom, which kind) and
    closest approach, from the final scenario state — what every runner reports.

    Parameters
    ----------
    layout : Layout
        Closed-loop layout of the run.
    x_final : ndarray (nx,)
        Final scenario state.
    params : dict
        The resolved parameter set (reads ``delta_max_deg`` and ``stall_window``).

    Returns
    -------
    list of dict
        One dict per ship: ``status``, ``stalled_at`` (L) and ``stalled_time``, ``time_to_goal``, ``ce``, ``mcte``
        (L), ``collision_time`` (L/U), ``collision_with``, ``collision_kind``, ``min_distance`` (L),
        ``min_distance_with`` and ``reactive_time`` (L/U); None where not applicable.
    """
    x = np.asarray(x_final, float).ravel()
    rows = ship_rows(layout, x)
    t_end = float(x[0])
    ce, mcte = voyage_metrics(rows, t_end, math.radians(params["delta_max_deg"]))
    out = []
    for i, row in enumerate(rows):
        t_col = float(row[S_["t_collision"]])
        kind = collision_kind(layout, int(row[S_["collision_with"]])) if t_col >= 0 else None
        status, where = ship_outcome(row, t_end, float(params["stall_window"]), kind)
        d_min = float(row[S_["d_min"]])
        out.append({
            "status": status, "stalled_at": where,
            "stalled_time": float(row[S_["t_best"]]) if status == "stalled" else None,
            "time_to_goal": float(row[S_["t_goal"]]) if status == "reached" else None,
            "ce": float(ce[i]), "mcte": float(mcte[i]),
            "collision_time": t_col if t_col >= 0 else None,
            "collision_with": int(row[S_["collision_with"]]) if t_col >= 0 else None,
            "collision_kind": kind,
            "min_distance": d_min if d_min < 1e5 else None,
            "min_distance_with": int(row[S_["d_min_with"]]) if d_min < 1e5 else None,
            "reactive_time": float(row[S_["reactive_time"]]),
        })
    return out


def run_outcome(layout: Layout, x_final, params: dict) -> dict:
    """The run-level verdict of the own ship (ship 0) and the fleet from the final scenario state: whether the run
    succeeded, how it failed (:data:`RUN_FAILURES`), with whom and when, and the own and fleet metrics.

    The own ship succeeds when it reached its goal without a collision (with a ship or any hazard); the fleet when
    every ship did. A collision wins over every other failure; a collision partner is labelled ``0-j`` for ship
    ``j``, ``0-obs<k>`` for obstacle ``k`` and ``0-wall<k>`` for wall segment ``k``. Touching land is the failure
    ``"grounding"``, its partner ``0-land<k>`` for land edge ``k``.

    Parameters
    ----------
    layout : Layout
        The run's closed-loop layout.
    x_final : array (nx,)
        Final scenario state ``[t, ship_0, ship_1, ...]``.
    params : dict
        The resolved parameter set (:func:`ship_outcomes` reads it).

    Returns
    -------
    dict
        ``success``, ``fleet_success``, ``failure`` (``""`` or one of :data:`RUN_FAILURES`), ``failure_pair``,
        ``failure_time``, the own ship's ``time_to_goal``, ``ce``, ``mcte`` and ``min_distance``, the fleet means
        over the ships that reached their goals, ``n_ships`` and ``n_obstacles``.
    """
    x = np.asarray(x_final, float).ravel()
    N = layout.n_ships
    ships = ship_outcomes(layout, x, params)
    own = ships[0]
    reached = np.array([s["status"] == "reached" for s in ships])
    collided = np.array([s["collision_time"] is not None for s in ships])
    if collided[0]:
        j, kind = own["collision_with"], own["collision_kind"]
        walls = N + layout.n_obstacles
        label = {"ship": str(j), "obstacle": f"obs{j - N}", "wall": f"wall{j - walls}",
                 "land": f"land{j - walls - (layout.n_walls - layout.n_land)}"}[kind]
        failure = "grounding" if kind == "land" else "collision"
        pair, failure_time = f"0-{label}", own["collision_time"]
    elif reached[0]:
        failure, pair, failure_time = "", "", math.nan
    elif own["status"] == "stalled":
        failure, pair, failure_time = "stalled", "", own["stalled_time"]
    elif own["status"] == "diverged":
        failure, pair, failure_time = "diverged", "", math.nan
    else:
        failure, pair, failure_time = "timeout", "", float(x[0])

    def fleet_mean(key):
        v = [s[key] for s, r in zip(ships, reached) if r]
        return float(np.mean(v)) if v else math.nan

    return {
        "success": bool(reached[0] and not collided[0]),
        "fleet_success": bool(np.all(reached) and not np.any(collided)),
        "failure": failure,
        "failure_pair": pair,
        "failure_time": failure_time,
        "time_to_goal": own["time_to_goal"] if reached[0] else math.nan,
        "ce": own["ce"],
        "mcte": own["mcte"],
        "fleet_time_to_goal": fleet_mean("time_to_goal"),
        "fleet_ce": fleet_mean("ce"),
        "fleet_mcte": fleet_mean("mcte"),
        "min_distance": math.nan if own["min_distance"] is None else own["min_distance"],
        "n_ships": N,
        "n_obstacles": layout.n_obstacles,
    }
