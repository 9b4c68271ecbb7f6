"""Distinct failures, their figures and the robustness trace of a falsification.

Distinct failures: two failures are the *same* when their encounter geometries
(:func:`~mmg_casadi.falsify.robustness.failure_geometry`) agree: the same kind of agent (ship, obstacle, land; for a
COLREG failure the same broken rule and role), and at the onset (the agent entering R_safe; the onset of risk)
the agent's relative bearing within :data:`BEARING_TOL`, for a ship its relative heading within
:data:`HEADING_TOL`, and the own ship's progress along her route at the failure within :data:`PROGRESS_TOL`.
:func:`cluster` groups failures by complete linkage under that distance (:func:`geometry_distance` ≤ 1): every two
failures of a group are the same, so a group is one encounter geometry of bounded spread (30° of bearing is one of
the twelve clock sectors a watch officer reports, 30° of relative heading separates head-on, crossing and overtaking
aspects, 0.2 of the route separates the start, the middle and the approach to the goal). The number of groups is the
number of distinct failures.
"""

from __future__ import annotations

import math

import numpy as np

from mmg_casadi import figstyle as fs

BEARING_TOL = 30.0
"""Relative bearings (deg) within which two failures' encounter geometries agree."""
HEADING_TOL = 30.0
"""Relative headings (deg) within which two ship encounters agree."""
PROGRESS_TOL = 0.2
"""Shares of the own route within which two failures happened at the same stage of the voyage."""


def _angle(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


def _key(g: dict) -> tuple:
    return (g["kind"], g.get("rule"), g.get("role"))


def geometry_distance(a: dict, b: dict) -> float:
    """The distance of two failure geometries in units of the tolerances (inf for different kinds or rules).

    Parameters
    ----------
    a, b : dict
        Geometries (:func:`~mmg_casadi.falsify.robustness.failure_geometry`).

    Returns
    -------
    float
        ``max(|Δbearing| / BEARING_TOL, |Δrelative heading| / HEADING_TOL, |Δprogress| / PROGRESS_TOL)`` (angles on
        the circle; the heading term for ships only); two failures are the same when it is at most 1.

    Examples
    --------
    >>> a = {"kind": "ship", "bearing_deg": 170.0, "relative_heading_deg": 10.0, "progress": 0.5}
    >>> b = {"kind": "ship", "bearing_deg": -175.0, "relative_heading_deg": 25.0, "progress": 0.6}
    >>> round(geometry_distance(a, b), 3)
    0.5
    >>> geometry_distance(a, {**b, "kind": "obstacle"})
    inf
    """
    if _key(a) != _key(b):
        return math.inf
    d = max(_angle(a["bearing_deg"], b["bearing_deg"]) / BEARING_TOL,
            abs(a["progress"] - b["progress"]) / PROGRESS_TOL)
    ha, hb = a.get("relative_heading_deg"), b.get("relative_heading_deg")
    if ha is not None and hb is not None and math.isfinite(ha) and math.isfinite(hb):
        d = max(d, _angle(ha, hb) / HEADING_TOL)
    return d


def cluster(geometries) -> np.ndarray:
    """Group failure geometries into distinct failures (module docstring): complete linkage, threshold 1.

    Parameters
    ----------
    geometries : sequence of dict
        Failure geometries.

    Returns
    -------
    numpy.ndarray of int
        A group label per geometry, ``0..K-1`` numbered in order of first appearance.

    Examples
    --------
    >>> g = {"kind": "ship", "bearing_deg": 0.0, "relative_heading_deg": 180.0, "progress": 0.5}
    >>> cluster([g, {**g, "bearing_deg": 20.0}, {**g, "bearing_deg": 90.0}]).tolist()
    [0, 0, 1]
    """
    from scipy.cluster.hierarchy import fcluster, linkage

    geometries = list(geometries)
    n = len(geometries)
    if n < 2:
        return np.zeros(n, int)
    d = np.array([min(geometry_distance(geometries[i], geometries[j]), 1e6)
                  for i in range(n) for j in range(i + 1, n)])
    raw = fcluster(linkage(d, method="complete"), t=1.0, criterion="distance")
    order = {}
    return np.array([order.setdefault(c, len(order)) for c in raw], int)


def distinct(geometries) -> int:
    """The number of distinct failures among ``geometries`` (:func:`cluster`).

    Parameters
    ----------
    geometries : sequence of dict
        Failure geometries.

    Returns
    -------
    int
        The number of groups.
    """
    labels = cluster(geometries)
    return int(labels.max() + 1) if labels.size else 0


def plot_failure(result, evaluation, *, title: str = "", ax=None):
    """One failure: every ship's track (the own ship bold), starts and goals, obstacles and land, and where it
    failed (the own ship and the agent at the failure, joined in red).

    Parameters
    ----------
    result : ScenarioResult
        The failure's scenario simulated (:func:`~mmg_casadi.scenarios.run.run_scenario`).
    evaluation : Evaluation
        The failure (its ``detail`` says with whom and when).
    title : str, optional
        Figure title.
    ax : matplotlib Axes, optional
        Axes to draw in (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from matplotlib.figure import Figure
    from matplotlib.patches import Circle

    from mmg_casadi.plotting import draw_land, marine_axes

    with fs.style():
        if ax is None:
            fig = Figure(figsize=(fs.COLUMN * 1.6, fs.COLUMN * 1.6), layout="constrained")
            ax = fig.add_subplot()
        else:
            fig = ax.figure
        tr, sc = result.trajectory, result.scenario
        x, y = tr.state("x"), tr.state("y")
        mask = tr.sailing_mask()
        draw_land(ax, sc.land)
        for k, o in enumerate(sc.obstacles):
            ax.add_patch(Circle((o.position[1], o.position[0]), o.radius, color=fs.OBSTACLE,
                                label="obstacle" if k == 0 else None))
        for i, ship in enumerate(sc.ships):
            c = fs.ship_color(i)
            sel = mask[:, i]
            ax.plot(y[sel, i], x[sel, i], "-", color=c, lw=1.8 if i == 0 else 0.8, label=ship.name if i < 1 else None)
            ax.plot(ship.start[1], ship.start[0], color=c, **fs.START_MARKER)
            ax.plot(ship.waypoints[-1][1], ship.waypoints[-1][0], color=c, **fs.GOAL_MARKER)
        d = evaluation.detail
        if d.get("time") is not None:
            k = int(np.argmin(np.abs(tr.t - d["time"])))
            p0 = (x[k, 0], y[k, 0])
            if d["kind"] == "ship" or str(d["kind"]).startswith("rule"):
                p1 = (x[k, d["agent"] + 1], y[k, d["agent"] + 1])
            elif d["kind"] == "obstacle":
                p1 = sc.obstacles[d["agent"] - (len(sc.ships) - 1)].position
            else:
                p1 = p0
            ax.plot([p0[1], p1[1]], [p0[0], p1[0]], "-", color=fs.COLLISION, lw=1.5)
            ax.plot(p0[1], p0[0], "x", color=fs.COLLISION, ms=9, mew=2,
                    label=f"{d['kind']} at t = {d['time']:.1f}")
        marine_axes(ax)
        ax.legend(fontsize=6, loc="upper right")
        ax.set_title(title or f"robustness {evaluation.robustness:.3f}", fontsize=8)
        return fig


def plot_trace(results, *, ax=None):
    """The robustness of every simulation of each search and its running minimum (failures below 0).

    Parameters
    ----------
    results : dict
        Search name to :class:`~mmg_casadi.falsify.search.SearchResult`.
    ax : matplotlib Axes, optional
        Axes to draw in (default: a new figure).

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    from matplotlib.figure import Figure

    with fs.style():
        if ax is None:
            fig = Figure(figsize=(fs.PAGE, fs.COLUMN), layout="constrained")
            ax = fig.add_subplot()
        else:
            fig = ax.figure
        for k, (name, r) in enumerate(results.items()):
            rho = np.array([t["robustness"] for t in r.trace], float)
            rho = np.where(np.isfinite(rho), rho, np.nan)
            idx = np.arange(len(rho))
            c = fs.ship_color(k)
            ax.plot(idx, rho, ".", ms=1.5, color=c, alpha=0.4)
            fails = np.cumsum([t["failure"] for t in r.trace])
            ax.plot(idx, np.fmin.accumulate(np.nan_to_num(rho, nan=np.inf)), "-", color=c, lw=1.2,
                    label=f"{name}: {int(fails[-1]) if len(fails) else 0} failures")
        ax.axhline(0.0, color=fs.COLLISION, lw=0.8, ls="--")
        ax.set_xlabel("simulation")
        ax.set_ylabel("robustness (running minimum)")
        ax.legend(fontsize=7)
        return fig
