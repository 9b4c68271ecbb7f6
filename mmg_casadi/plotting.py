"""Figures in the style of the paper, drawn from result objects (never inside the numeric code).

Trajectories use the marine view: x (north) up, y (east) right, so a starboard turn looks like a right turn.
Figures are built with :class:`matplotlib.figure.Figure` directly (no pyplot state, no display needed).
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.colors import hsv_to_rgb
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon

FIGURE_DPI = 150
"""Resolution of every saved figure (PNG, dots per inch): the figures of the studies, the tuning and the site."""

COLORS = ("tab:blue", "tab:red", "tab:green", "tab:orange", "tab:purple", "tab:brown", "tab:pink",
          "tab:gray", "tab:olive", "tab:cyan")


def ship_outline(x: float, y: float, psi: float, length: float = 1.0, beam: float = 0.14) -> np.ndarray:
    """Polygon (marine view coordinates: columns east, north) of a ship of ``length`` at (x, y) heading ``psi``.

    Parameters
    ----------
    x : float
        North position (L).
    y : float
        East position (L).
    psi : float
        Heading (rad).
    length : float, default 1.0
        Ship length (L).
    beam : float, default 0.14
        Ship beam (L).

    Returns
    -------
    numpy.ndarray (5, 2)
        Vertices of the outline, columns east (y) and north (x) (L), bow first.
    """
    body = np.array([[0.5, 0.0], [0.3, beam / 2], [-0.5, beam / 2], [-0.5, -beam / 2], [0.3, -beam / 2]]) * [
        length, 1.0]
    c, s = math.cos(psi), math.sin(psi)
    gx = x + c * body[:, 0] - s * body[:, 1]
    gy = y + s * body[:, 0] + c * body[:, 1]
    return np.column_stack([gy, gx])


def draw_ship(ax, x, y, psi, color, **kw):
    """Draw a filled ship outline (:func:`ship_outline`) on ``ax``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    x : float
        North position (L).
    y : float
        East position (L).
    psi : float
        Heading (rad).
    color : color
        Fill colour.
    **kw : dict
        Further keyword arguments of :class:`matplotlib.patches.Polygon`.
    """
    ax.add_patch(Polygon(ship_outline(x, y, psi), closed=True, facecolor=color, edgecolor="k", lw=0.5, **kw))


def draw_path(ax, x, y, psi, color, label=None, n_outlines=6, start=True):
    """Path in the marine view with ship outlines at ``n_outlines`` evenly spaced times.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    x : array-like
        North positions (L).
    y : array-like
        East positions (L).
    psi : array-like
        Headings (rad).
    color : color
        Line and outline colour.
    label : str, optional
        Legend label of the path.
    n_outlines : int, default 6
        Number of ship outlines drawn (0: none).
    start : bool, default True
        Whether to mark the start with a star.
    """
    ax.plot(y, x, color=color, lw=1.5, label=label)
    if len(x) > 1 and n_outlines:
        for k in np.linspace(0, len(x) - 1, n_outlines).astype(int):
            draw_ship(ax, x[k], y[k], psi[k], color, alpha=0.8)
    if start:
        ax.plot(y[0], x[0], marker="*", color=color, ms=10, ls="none")


def draw_goal(ax, gx, gy, color, tol=None):
    """Mark a goal with a star on ``ax``, with its tolerance circle when ``tol`` is given.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    gx : float
        North position of the goal (L).
    gy : float
        East position of the goal (L).
    color : color
        Marker colour.
    tol : float, optional
        Goal tolerance radius (L); no circle when ``None`` or 0.
    """
    ax.plot(gy, gx, marker="*", color=color, ms=12, mec="k", ls="none")
    if tol:
        ax.add_patch(Circle((gy, gx), tol, fill=False, ls=":", color=color))


def draw_circle(ax, x, y, radius, color="r", ls=":", **kw):
    """Draw an unfilled circle on ``ax`` in the marine view.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw on.
    x : float
        North position of the centre (L).
    y : float
        East position of the centre (L).
    radius : float
        Radius (L).
    color : color, default 'r'
        Line colour.
    ls : str, default ':'
        Line style.
    **kw : dict
        Further keyword arguments of :class:`matplotlib.patches.Circle`.
    """
    ax.add_patch(Circle((y, x), radius, fill=False, ls=ls, color=color, **kw))


def marine_axes(ax):
    """Set up ``ax`` for the marine view: equal aspect, east along the abscissa, north up, grid.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to set up.
    """
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("y (east) [L]")
    ax.set_ylabel("x (north) [L]")
    ax.grid(True, alpha=0.3)


LAND_COLOR = "#e8d9a8"
"""Fill colour of land (the buff of a paper chart's land tint)."""


def draw_land(ax, land) -> None:
    """Fill land polygons on ``ax`` in the chart style: buff land, a dark coastline (marine axes: x up, y right).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw into.
    land : sequence of LandSpec
        Land polygons (``points`` in L).
    """
    for k, poly in enumerate(land):
        pts = np.asarray(poly.points, float)
        ax.fill(pts[:, 1], pts[:, 0], facecolor=LAND_COLOR, edgecolor="#5a4a2a", lw=1.2, zorder=0,
                label="land" if k == 0 else None)


def plot_maneuver(result, path=None) -> Figure:
    """Trajectory (marine view) and time histories of heading, rudder and speed of a manoeuvre.

    Parameters
    ----------
    result : mmg_casadi.vessel.maneuvers.ManeuverResult
        Result of the manoeuvre simulation.
    path : str or path-like, optional
        File to save the figure to.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    fig = Figure(figsize=(11, 5.5), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=[1.1, 1])
    ax = fig.add_subplot(gs[:, 0])
    x, y, psi = result.state("x"), result.state("y"), result.state("psi")
    draw_path(ax, x, y, psi, COLORS[0], label="trajectory", n_outlines=8)
    marine_axes(ax)
    m = result.metrics
    if result.kind == "turning":
        ax.set_title(f"Turning circle, {m['rudder_deg']:g}° {m['direction']}: advance {m['advance']:.2f} L, "
                     f"tactical diameter {m['tactical_diameter']:.2f} L", fontsize=9)
    elif result.kind == "speed":
        ax.set_title(f"Speed change {m['speed']:g} → {m['to_speed']:g} U: {m['t_change_s'] / 60:.1f} min, "
                     f"{m['reach_change_m'] / 1000:.2f} km to within 5 % of the change", fontsize=9)
    else:
        ax.set_title(f"Zig-zag {m['angle_deg']:g}/{m['angle_deg']:g}: overshoots {m['overshoot_1']:.1f}°, "
                     f"{m['overshoot_2']:.1f}°", fontsize=9)
    a1 = fig.add_subplot(gs[0, 1])
    a1.plot(result.t, np.degrees(psi), label="ψ")
    a1.set_ylabel("heading [deg]")
    a2 = fig.add_subplot(gs[1, 1], sharex=a1)
    a2.plot(result.t, np.degrees(result.delta_c), "--", label="δ commanded")
    a2.plot(result.t, np.degrees(result.state("delta")), label="δ actual")
    a2.set_ylabel("rudder [deg]")
    a2.legend(fontsize=8)
    a3 = fig.add_subplot(gs[2, 1], sharex=a1)
    a3.plot(result.t, np.hypot(result.state("u"), result.state("v")))
    a3.set_ylabel("U/U_des [-]")
    a3.set_xlabel("t [L/U]")
    for a in (a1, a2, a3):
        a.grid(True, alpha=0.3)
    if path:
        fig.savefig(path, dpi=FIGURE_DPI)
    return fig


def plot_paths(result, ax, *, title=None):
    """Paths of all ships (marine view) with start/goal markers, static obstacles with their R_safe circles,
    walls and the own ship's R_safe circle at its closest approach, drawn into ``ax``; returns ``ax``.

    Parameters
    ----------
    result : ScenarioResult
        A simulated scenario (:func:`mmg_casadi.scenarios.run.run_scenario`).
    ax : matplotlib Axes
        Where to draw.
    title : str, optional
        Axes title (default: method, collision, own ship CE and MCTE).

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``.
    """
    traj, sc = result.trajectory, result.scenario
    N = traj.layout.n_ships
    names = [s.name for s in sc.ships]
    mask = traj.sailing_mask()
    r_safe = result.params["r_safe"]
    for i in range(N):
        c = COLORS[i % len(COLORS)]
        m = mask[:, i]
        x, y, psi = traj.state("x", i)[m], traj.state("y", i)[m], traj.state("psi", i)[m]
        lab = names[i]
        enc = result.encounter_labels.get(i)
        if enc:
            lab += f" ({enc})"
        draw_path(ax, x, y, psi, c, label=lab)
        route = result.metrics["ships"][i].get("route") or {}
        if route.get("planned"):  # the route planned around the land (mmg_casadi.scenarios.routes)
            pts = np.asarray([sc.ships[i].start, *route["waypoints"]])
            ax.plot(pts[:, 1], pts[:, 0], ls="--", color=c, lw=0.8, label=f"{names[i]}: planned route")
        g = sc.ships[i].waypoints[-1]
        draw_goal(ax, g[0], g[1], c, tol=result.params["goal_tolerance"])
        for wp in sc.ships[i].waypoints[:-1]:
            ax.plot(wp[1], wp[0], marker="o", color=c, ms=5, ls="none")
    for o in sc.obstacles:
        ax.plot(o.position[1], o.position[0], "ko", ms=4)
        draw_circle(ax, o.position[0], o.position[1], o.radius, color="k", ls="-")
        draw_circle(ax, o.position[0], o.position[1], r_safe, color="r", ls=":", lw=0.8)
    for w in sc.walls:
        pts = np.asarray(w.points)
        ax.plot(pts[:, 1], pts[:, 0], "k-", lw=2)
    draw_land(ax, sc.land)
    # R_safe circle around the own ship at its closest approach
    own = result.metrics["ships"][0]
    if N + len(sc.obstacles) > 1:
        k = int(np.argmin(result.own_distance()))
        draw_circle(ax, traj.state("x", 0)[k], traj.state("y", 0)[k], r_safe, color=COLORS[0], ls=":", lw=0.8)
    marine_axes(ax)
    ax.legend(fontsize=8, loc="best")
    kinds = {s["collision_kind"] for s in result.metrics["ships"]}
    status = "grounding" if "land" in kinds else "collision" if result.metrics["collision"] else "no collision"
    ce = "–" if own["ce"] is None else f"{own['ce']:.3f}"
    mcte = "–" if own["mcte"] is None else f"{own['mcte']:.3f}"
    ax.set_title(title or f"{result.metrics['method']}: {status}; own ship CE {ce}, MCTE {mcte} L", fontsize=9)
    return ax


def plot_scenario(result, path=None, *, title=None) -> Figure:
    """Paths (:func:`plot_paths`); rudder command vs actual; distance between agents while inside R_safe with
    the collision threshold. ``result`` is a :class:`~mmg_casadi.scenarios.run.ScenarioResult`; the figure is
    saved to ``path`` when given.

    Parameters
    ----------
    result : mmg_casadi.scenarios.run.ScenarioResult
        Result of the scenario run.
    path : str or path-like, optional
        File to save the figure to.
    title : str, optional
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    traj, sc = result.trajectory, result.scenario
    N = traj.layout.n_ships
    names = [s.name for s in sc.ships]
    mask = traj.sailing_mask()
    r_safe = result.params["r_safe"]
    cd = result.params["collision_distance"]
    fig = Figure(figsize=(13, 6.5), layout="constrained")
    gs = fig.add_gridspec(2, 2, width_ratios=[1.2, 1])
    plot_paths(result, fig.add_subplot(gs[:, 0]), title=title)

    a1 = fig.add_subplot(gs[0, 1])
    t_aux = traj.t[:-1]
    for i in range(N):
        c = COLORS[i % len(COLORS)]
        m = mask[:-1, i]
        a1.plot(t_aux[m], np.degrees(traj.auxiliary("delta_c", i)[m]), "--", color=c, lw=0.8)
        a1.plot(traj.t[mask[:, i]], np.degrees(traj.state("delta", i)[mask[:, i]]), color=c, lw=1.2,
                label=f"{names[i]} actual (dashed: commanded)")
    a1.set_ylabel("rudder [deg]")
    a1.legend(fontsize=7)
    a1.grid(True, alpha=0.3)
    a2 = fig.add_subplot(gs[1, 1], sharex=a1)
    for (a, b), d in result.pair_distances().items():
        inside = d <= r_safe
        if inside.any():
            dd = np.where(inside, d, np.nan)
            a2.plot(traj.t, dd, label=f"{a}–{b}")
    a2.axhline(cd, color="k", ls="--", lw=1, label=f"collision ({cd:g} L)")
    a2.set_ylabel("distance inside R_safe [L]")
    a2.set_xlabel("t [L/U]")
    a2.legend(fontsize=7)
    a2.grid(True, alpha=0.3)
    if path:
        fig.savefig(path, dpi=FIGURE_DPI)
    return fig


def plot_tracking(result, path=None) -> Figure:
    """Waypoint tracking: path with R_tol circles, commanded vs actual rudder, desired vs actual heading, and
    cross-track error over time (the paper's waypoint-tracking figure).

    Parameters
    ----------
    result : mmg_casadi.scenarios.run.ScenarioResult
        Result of the waypoint-tracking run.
    path : str or path-like, optional
        File to save the figure to.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    traj, sc = result.trajectory, result.scenario
    m = traj.sailing_mask()[:, 0]
    ma = m[:-1]
    fig = Figure(figsize=(12, 8), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=[1.1, 1])
    ax = fig.add_subplot(gs[:, 0])
    x, y, psi = traj.state("x", 0)[m], traj.state("y", 0)[m], traj.state("psi", 0)[m]
    draw_path(ax, x, y, psi, COLORS[0], label="path", n_outlines=10)
    wps = np.vstack([sc.ships[0].start, np.asarray(sc.ships[0].waypoints)])
    ax.plot(wps[:, 1], wps[:, 0], "k--", lw=0.8, label="waypoint path")
    for wp in sc.ships[0].waypoints:
        ax.plot(wp[1], wp[0], "ko", ms=4)
        draw_circle(ax, wp[0], wp[1], sc.settings.goal_tolerance, color="k", ls=":")
    marine_axes(ax)
    ax.legend(fontsize=8)
    own = result.metrics["ships"][0]
    ax.set_title(f"Waypoint tracking: CE {own['ce']:.4f}, MCTE {own['mcte']:.4f} L", fontsize=10)
    t = traj.t
    a1 = fig.add_subplot(gs[0, 1])
    a1.plot(t[:-1][ma], np.degrees(traj.auxiliary("delta_c", 0)[ma]), "--", label="commanded")
    a1.plot(t[m], np.degrees(traj.state("delta", 0)[m]), label="actual")
    a1.set_ylabel("rudder [deg]")
    a1.legend(fontsize=8)
    a2 = fig.add_subplot(gs[1, 1], sharex=a1)
    a2.plot(t[:-1][ma], np.degrees(np.unwrap(traj.auxiliary("psi_d", 0)[ma])), "--", label="desired")
    a2.plot(t[m], np.degrees(np.unwrap(traj.state("psi", 0)[m])), label="actual")
    a2.set_ylabel("heading [deg]")
    a2.legend(fontsize=8)
    a3 = fig.add_subplot(gs[2, 1], sharex=a1)
    a3.plot(t[:-1][ma], traj.auxiliary("y_e", 0)[ma])
    a3.set_ylabel("cross-track error [L]")
    a3.set_xlabel("t [L/U]")
    for a in (a1, a2, a3):
        a.grid(True, alpha=0.3)
    if path:
        fig.savefig(path, dpi=FIGURE_DPI)
    return fig


def plot_fleet(result, path=None, *, title=None, ax=None) -> Figure:
    """Tracks of a large fleet (marine view): one colour per ship from a cyclic colour map, thin lines, a dot at
    each start, a cross at each collision, the static obstacles in black. For scenarios of many ships, where
    :func:`plot_scenario`'s legends and pair panels do not scale.

    Parameters
    ----------
    result : mmg_casadi.scenarios.run.ScenarioResult
        Result of the scenario run.
    path : str or path-like, optional
        File to save the figure to.
    title : str, optional
        Axes title (default: ships, collisions, goals reached).
    ax : matplotlib Axes, optional
        Where to draw; a new figure when omitted.

    Returns
    -------
    matplotlib.figure.Figure
        The new figure, or the figure of ``ax`` (saved to ``path`` when given).
    """
    traj, sc = result.trajectory, result.scenario
    N = traj.layout.n_ships
    if ax is None:
        fig = Figure(figsize=(10, 10), layout="constrained")
        ax = fig.add_subplot()
    fig = ax.figure
    mask = traj.sailing_mask()
    colours = _cyclic_colours(N)
    for i in range(N):
        m = mask[:, i]
        ax.plot(traj.state("y", i)[m], traj.state("x", i)[m], color=colours[i], lw=0.6)
        ax.plot(sc.ships[i].start[1], sc.ships[i].start[0], "o", color=colours[i], ms=2.5)
    for s in result.metrics["ships"]:
        if s["collided"]:
            i = result.names().index(s["name"])
            k = int(np.searchsorted(traj.t, s["collision_time"]))
            k = min(k, len(traj.t) - 1)
            ax.plot(traj.state("y", i)[k], traj.state("x", i)[k], "kx", ms=6, mew=1.5)
    for o in sc.obstacles:
        ax.plot(o.position[1], o.position[0], "ks", ms=2.5)
    draw_land(ax, sc.land)
    marine_axes(ax)
    ships = result.metrics["ships"]
    n_col = sum(s["collided"] for s in ships)
    n_goal = sum(s["reached_goal"] for s in ships)
    ax.set_title(title or f"{N} ships: {n_col} in a collision (×), {n_goal} reached their goals")
    if path is not None:
        fig.savefig(path, dpi=FIGURE_DPI)
    return fig


def _cyclic_colours(n: int) -> list:
    """``n`` colours that neighbours in index order tell apart (a golden-ratio walk round the hue circle)."""
    return [hsv_to_rgb(((0.618033988749895 * i) % 1.0, 0.85, 0.8 - 0.25 * (i % 3) / 2)) for i in range(n)]
