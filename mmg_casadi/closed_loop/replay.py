"""Replayed ships: ships that follow a recorded track interpolated in time instead of being simulated.

A replayed ship (``Layout.replay``) is not steered and not integrated by the MMG model. At every step its state
is set from its track at the step's clock time ``t + dt``: the position by piecewise-linear interpolation of the
track's samples ``(t_k, x_k, y_k)``, the velocity over the ground that of the track's segment containing that
time (the segment that starts at ``t_k`` for ``t_k <= t < t_{k+1}``), the heading the direction of that velocity
(held while the ship lies still), the speed through the water ``u, v`` the velocity's components in the body axes
(less the current in a disturbed layout, so that every other ship's guidance sees the recorded velocity over the
ground). Its status becomes 1 (done) at the step that reaches the track's last time; afterwards it leaves the
scenario, or stays at its last position as an obstacle if it ``stays``. Everything else treats it as any ship:
the other ships' guidance, the closest-approach and collision bookkeeping, the scorer.

The tracks are numeric inputs of the step (:func:`track_values`), padded to ``Layout.max_track`` columns
(:func:`track_columns`), so the generated code depends on the number of columns only, not on the recorded data.

Examples
--------
>>> t, x, y = [0.0, 10.0, 20.0], [0.0, 10.0, 10.0], [0.0, 0.0, 5.0]
>>> pos, vel = sample_track(t, x, y, 15.0)
>>> pos.tolist(), vel.tolist()
([10.0, 2.5], [0.0, 0.5])
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from mmg_casadi.vessel import environment

REPLAY = "replay"
"""The method a replayed ship is reported with (``metrics.json``: ``ships[].method``); in the layout it is ``"none"``,
which the replay never reads."""
TRACK_BLOCK = 8
"""A track's padded column count is a multiple of this (:func:`track_columns`), so that tracks of similar length
share one compiled step."""
STILL_SPEED = 1.0e-9
"""Below this speed over the ground (U) a replayed ship lies still and keeps its heading."""


def track_columns(n_points: int) -> int:
    """Padded columns of a track of ``n_points`` samples: at least one padding column (the ship lies still at
    its last position after the track's end), rounded up to a multiple of :data:`TRACK_BLOCK`.

    Parameters
    ----------
    n_points : int
        Samples of the longest track of a layout (>= 2).

    Returns
    -------
    int
        Columns of every padded track of the layout.

    Examples
    --------
    >>> track_columns(2), track_columns(7), track_columns(8)
    (8, 8, 16)
    """
    return TRACK_BLOCK * math.ceil((int(n_points) + 1) / TRACK_BLOCK)


def pad_track(t, x, y, columns: int) -> np.ndarray:
    """The ``3 × columns`` padded track: the samples, then the last position at the times ``t_end + 1, + 2, ...``.

    Parameters
    ----------
    t, x, y : sequence of float
        Sample times (L/U, strictly increasing) and positions (L).
    columns : int
        Columns of the padded track (more than the samples).

    Returns
    -------
    numpy.ndarray (3, columns)
        Rows t, x, y.
    """
    t, x, y = (np.asarray(v, float) for v in (t, x, y))
    k = len(t)
    if not 2 <= k < columns:
        raise ValueError(f"track: expected 2 to {columns - 1} samples, got {k}")
    pad = np.arange(1, columns - k + 1, dtype=float)
    return np.vstack([np.concatenate([t, t[-1] + pad]), np.concatenate([x, np.full(len(pad), x[-1])]),
                      np.concatenate([y, np.full(len(pad), y[-1])])])


def track_values(t, x, y, columns: int) -> list[float]:
    """One replayed ship's numeric inputs of the step: the track's last time, then the padded rows t, x, y.

    Parameters
    ----------
    t, x, y : sequence of float
        Sample times (L/U) and positions (L).
    columns : int
        Columns of the padded track (``Layout.max_track``).

    Returns
    -------
    list of float
        ``1 + 3 columns`` values.
    """
    return [float(t[-1])] + [float(v) for v in pad_track(t, x, y, columns).reshape(-1)]


def _segment(t, x, y, tq, if_else):
    """Start time, start position and velocity of the segment of a padded track that contains ``tq`` (the first
    segment before the track, the last one after it); ``if_else(cond, a, b)`` selects."""
    def velocity(k):
        dt = t[k + 1] - t[k]
        return (x[k + 1] - x[k]) / dt, (y[k + 1] - y[k]) / dt

    vx, vy = velocity(0)
    tk, xk, yk = t[0], x[0], y[0]
    for k in range(1, len(t) - 1):
        sel = tq >= t[k]
        wx, wy = velocity(k)
        tk, xk, yk = if_else(sel, t[k], tk), if_else(sel, x[k], xk), if_else(sel, y[k], yk)
        vx, vy = if_else(sel, wx, vx), if_else(sel, wy, vy)
    return tk, xk, yk, vx, vy


def sample_track(t, x, y, tq: float) -> tuple[np.ndarray, np.ndarray]:
    """Position (L) and velocity over the ground (U) of a track at time ``tq`` (L/U), as the compiled step
    computes them (the same operations, so the same bits).

    Parameters
    ----------
    t, x, y : sequence of float
        Sample times (strictly increasing) and positions; after the last sample the ship lies still there.
    tq : float
        Time.

    Returns
    -------
    (numpy.ndarray (2,), numpy.ndarray (2,))
        Position and velocity.
    """
    padded = pad_track(t, x, y, len(t) + 1)
    tk, xk, yk, vx, vy = _segment(*padded, float(tq), lambda c, a, b: a if c else b)
    return np.array([xk + (tq - tk) * vx, yk + (tq - tk) * vy]), np.array([vx, vy])


def track_heading(t, x, y, tq: float, default: float = 0.0) -> float:
    """Heading (rad, from x towards y) of a replayed ship at time ``tq``: the direction of its velocity, or the
    direction of the track's first movement (``default`` if it never moves) while it lies still.

    Parameters
    ----------
    t, x, y : sequence of float
        The track.
    tq : float
        Time (L/U).
    default : float
        Heading of a track without movement.

    Returns
    -------
    float
        Heading (rad, in [-π, π]).
    """
    _, v = sample_track(t, x, y, tq)
    if math.hypot(*v) > STILL_SPEED:
        return math.atan2(v[1], v[0])
    d = np.column_stack([np.diff(x), np.diff(y)])
    moving = np.flatnonzero(np.hypot(d[:, 0], d[:, 1]) > 0)
    return math.atan2(d[moving[0], 1], d[moving[0], 0]) if len(moving) else float(default)


def replay_update(layout, i: int, c: dict):
    """Replayed ship ``i``'s state after the step and its ``aux`` column (the replay counterpart of a sailing ship's
    update in :func:`~mmg_casadi.closed_loop.step.build_closed_loop_step`; the caller holds a ship that does not
    sail).

    Parameters
    ----------
    layout : Layout
        The closed loop's shape (``i`` in ``layout.replay``).
    i : int
        Ship index.
    c : dict
        The step's context: its named parameters, clock, ship states, positions and velocities (built inside
        :func:`~mmg_casadi.closed_loop.step.build_closed_loop_step`).

    Returns
    -------
    (SX, SX)
        The ship's ``layout.ns`` rows after the step and its ``aux`` column (rudder 0, desired heading = the
        heading, cross-track error 0, not reactive).
    """
    P, S_, Xi = c["P"], c["S"], c["X"][i]
    track = P["tracks"][i]
    t_next = c["t"] + P["dt"]
    tk, xk, yk, vx, vy = _segment(track["t"], track["x"], track["y"], t_next, ca.if_else)
    x_n, y_n = xk + (t_next - tk) * vx, yk + (t_next - tk) * vy
    still = ca.sqrt(vx ** 2 + vy ** 2) <= STILL_SPEED
    psi_n = ca.if_else(still, Xi[S_["psi"]], ca.atan2(vy, vx))
    wx, wy = vx, vy
    if layout.disturbed:  # the state's u, v are through the water: the recorded velocity less the current
        cx, cy = environment.velocity_over_ground(0.0, 0.0, psi_n, c["E"][0], c["E"][1])
        wx, wy = vx - cx, vy - cy
    u_n = ca.cos(psi_n) * wx + ca.sin(psi_n) * wy
    v_n = -ca.sin(psi_n) * wx + ca.cos(psi_n) * wy
    done = t_next >= track["t_end"] - 1e-9
    status = ca.if_else(done, 1, 0)
    goal = P["ships"][i]["path"][:, -1]
    gdist = ca.sqrt((x_n - goal[0]) ** 2 + (y_n - goal[1]) ** 2)
    better = gdist < Xi[S_["best_goal_dist"]] - 1e-9
    values = {"u": u_n, "v": v_n, "r": 0.0, "x": x_n, "y": y_n, "psi": psi_n, "status": status,
              "t_goal": ca.if_else(done, t_next, -1),
              "best_goal_dist": ca.if_else(better, gdist, Xi[S_["best_goal_dist"]]),
              "t_best": ca.if_else(better, t_next, Xi[S_["t_best"]]),
              "x_best": ca.if_else(better, x_n, Xi[S_["x_best"]]),
              "y_best": ca.if_else(better, y_n, Xi[S_["y_best"]])}
    values.update({k: psi_n for k in layout.memory})
    new = ca.vertcat(*[values.get(name, Xi[S_[name]]) for name in layout.ship_state])
    return new, ca.vertcat(0.0, psi_n, 0.0, 0.0)
