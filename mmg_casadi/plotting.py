"""Figures in the style of the paper, drawn from result objects (never inside the numeric code).

Trajectories use the marine view: x (north) up, y (east) right, so a starboard turn looks like a right turn.
Figures are built with :class:`matplotlib.figure.Figure` directly (no pyplot state, no display needed), in the
one style of :mod:`mmg_casadi.figstyle` (journal sizes at 300 dpi, a colour per ship, start ○ and goal ☆, time
ticks along the tracks, the closest approach marked). Every figure function takes ``units`` (non-dimensional by
default, or :class:`~mmg_casadi.units.Units` ``"si"`` for m, s and kn); a ``path`` ending in ``.svg`` or ``.pdf``
saves vector graphics.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.colors import hsv_to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Polygon

from mmg_casadi import figstyle as fs
from mmg_casadi.units import Units

FIGURE_DPI = fs.DPI
"""Resolution of every saved raster figure (PNG, dots per inch): the figures of the studies, the tuning and the
site (:data:`mmg_casadi.figstyle.DPI`)."""

COLORS = fs.SHIP_COLORS
"""Ship colours in order (:data:`mmg_casadi.figstyle.SHIP_COLORS`)."""

LAND_COLOR = fs.LAND
"""Fill colour of land (the buff of a paper chart's land tint)."""


def _units(units, result=None) -> Units:
    if isinstance(units, Units):
        return units
    vessel = result.trajectory.layout.unit_vessel() if result is not None else "kcs"
    return Units.of(units or "nd", vessel)


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


def draw_ship(ax, x, y, psi, color, *, length: float = 1.0, beam: float = 0.14, units=None, **kw):
    """Draw a filled ship outline (:func:`ship_outline`, to scale) on ``ax``.

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
    length, beam : float
        Ship length and beam (L).
    units : Units, optional
        Units of the axes (default L).
    **kw : dict
        Further keyword arguments of :class:`matplotlib.patches.Polygon`.

    Returns
    -------
    matplotlib.patches.Polygon
        The outline.
    """
    pts = ship_outline(x, y, psi, length, beam)
    if units is not None:
        pts = units.length(pts)
    kw.setdefault("lw", 0.4)
    kw.setdefault("zorder", 5)
    poly = Polygon(pts, closed=True, facecolor=color, edgecolor="k", **kw)
    ax.add_patch(poly)
    return poly


def _outline_indices(x, y, psi, n: int, *, min_gap: float = 1.5) -> list[int]:
    """Up to ``n`` indices evenly spread along the track's length (the last one included), skipping any within
    ``min_gap`` L of one already chosen (so a ship circling is not drawn over itself), and none after the
    heading has turned through 360°."""
    if len(x) < 2 or n <= 0:
        return [0] if len(x) and n > 0 else []
    turned = np.abs(np.unwrap(psi) - psi[0])
    end = int(np.argmax(turned >= 2 * math.pi)) if np.any(turned >= 2 * math.pi) else len(x) - 1
    s = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x[:end + 1]), np.diff(y[:end + 1])))])
    chosen: list[int] = []
    for target in np.linspace(0.0, s[-1], n):
        k = int(np.searchsorted(s, target))
        k = min(k, end)
        if all(math.hypot(x[k] - x[j], y[k] - y[j]) >= min_gap for j in chosen):
            chosen.append(k)
    return chosen


def draw_path(ax, x, y, psi, color, label=None, n_outlines=6, start=True, *, t=None, tick_step=None, units=None,
              length: float = 1.0, beam: float = 0.14, lw: float | None = None):
    """Path in the marine view with ship outlines (to scale), its start ○ and time ticks.

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
        Largest number of ship outlines drawn along the path (0: none); outlines closer than 1.5 L to another
        are left out.
    start : bool, default True
        Whether to mark the start with an open circle.
    t : array-like, optional
        Times of the positions (L/U), for the ticks.
    tick_step : float, optional
        Time between ticks along the path (L/U); none without it.
    units : Units, optional
        Units of the axes (default L).
    length, beam : float
        Ship length and beam (L) of the outlines.
    lw : float, optional
        Line width.
    """
    x, y, psi = np.asarray(x), np.asarray(y), np.asarray(psi)
    u = units or Units.of("nd")
    ax.plot(u.length(y), u.length(x), color=color, lw=lw or 1.1, label=label, zorder=3)
    for k in _outline_indices(x, y, psi, n_outlines):
        draw_ship(ax, x[k], y[k], psi[k], color, length=length, beam=beam, units=u, alpha=0.9)
    if start and len(x):
        ax.plot(u.length(y[0]), u.length(x[0]), color=color, zorder=6, **fs.START_MARKER)
    if t is not None and tick_step:
        fs.time_ticks(ax, np.asarray(t), x, y, color, tick_step, units=u)


def draw_goal(ax, gx, gy, color, tol=None, *, units=None):
    """Mark a goal with an open star on ``ax``, with its tolerance circle (dotted) when ``tol`` is given.

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
    units : Units, optional
        Units of the axes (default L).
    """
    u = units or Units.of("nd")
    ax.plot(u.length(gy), u.length(gx), color=color, zorder=6, **fs.GOAL_MARKER)
    if tol:
        ax.add_patch(Circle((u.length(gy), u.length(gx)), u.length(tol), fill=False, ls=":", lw=0.7, color=color))


def draw_circle(ax, x, y, radius, color=fs.R_SAFE, ls="--", *, units=None, **kw):
    """Draw an unfilled circle on ``ax`` in the marine view (by default an R_safe circle: grey, dashed).

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
    color : color, default grey
        Line colour.
    ls : str, default '--'
        Line style.
    units : Units, optional
        Units of the axes (default L).
    **kw : dict
        Further keyword arguments of :class:`matplotlib.patches.Circle`.
    """
    u = units or Units.of("nd")
    kw.setdefault("lw", 0.7)
    ax.add_patch(Circle((u.length(y), u.length(x)), u.length(radius), fill=False, ls=ls, color=color, **kw))


def marine_axes(ax, units=None):
    """Set up ``ax`` for the marine view: equal aspect, east along the abscissa, north up, grid.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to set up.
    units : Units, optional
        Units of the axes (default L).
    """
    unit = (units or Units.of("nd")).length_unit
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"y (east) [{unit}]")
    ax.set_ylabel(f"x (north) [{unit}]")
    ax.grid(True)


def draw_land(ax, land, *, units=None) -> None:
    """Fill land polygons on ``ax`` in the chart style: buff land, a dark coastline (marine axes: x up, y right).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes to draw into.
    land : sequence of LandSpec
        Land polygons (``points`` in L).
    units : Units, optional
        Units of the axes (default L).
    """
    u = units or Units.of("nd")
    for k, poly in enumerate(land):
        pts = u.length(np.asarray(poly.points, float))
        ax.fill(pts[:, 1], pts[:, 0], facecolor=fs.LAND, edgecolor=fs.COAST, lw=0.8, zorder=0,
                label="land" if k == 0 else None)


def tick_step(t_end: float, units=None) -> float:
    """The time between ticks along the tracks of a run lasting ``t_end`` (L/U): a round number of the units
    shown, about ten ticks over the run (every other one labelled).

    Parameters
    ----------
    t_end : float
        Duration of the run (L/U).
    units : Units, optional
        Units shown (default L/U).

    Returns
    -------
    float
        The step in L/U.
    """
    u = units or Units.of("nd")
    return fs.nice_step(u.time(max(t_end, 1e-9)), 10) / u.time(1.0)


@fs.styled
def plot_maneuver(result, path=None, *, units=None) -> Figure:
    """Trajectory (marine view) and time histories of heading, rudder and speed of a manoeuvre.

    Parameters
    ----------
    result : mmg_casadi.vessel.maneuvers.ManeuverResult
        Result of the manoeuvre simulation.
    path : str or path-like, optional
        File to save the figure to (PNG at 300 dpi, or ``.svg`` / ``.pdf``).
    units : Units or str, optional
        ``"nd"`` (default) or ``"si"``.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    u = _units(units)
    fig = Figure(figsize=(fs.PAGE, 0.48 * fs.PAGE), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=[1.0, 1.15])
    ax = fig.add_subplot(gs[:, 0])
    x, y, psi, t = result.state("x"), result.state("y"), result.state("psi"), result.t
    draw_path(ax, x, y, psi, fs.OWN_SHIP, label="track", n_outlines=8, t=t, tick_step=tick_step(t[-1], u),
              units=u)
    marine_axes(ax, u)
    ax.legend(handles=[Line2D([], [], color=fs.OWN_SHIP, label="track"),
                       Line2D([], [], color=fs.OWN_SHIP, label="start", **fs.START_MARKER),
                       Line2D([], [], marker="o", color=fs.OWN_SHIP, ms=2.2, ls="none",
                              label=f"every {u.time(tick_step(t[-1], u)):g} {u.time_unit}")], loc="best")
    m = result.metrics
    if result.kind == "turning":
        ax.set_title(f"Turning circle, {m['rudder_deg']:g}° {m['direction']}: advance {u.fmt_length(m['advance'])}, "
                     f"tactical diameter {u.fmt_length(m['tactical_diameter'])}")
    elif result.kind == "speed":
        ax.set_title(f"Speed change {m['speed']:g} → {m['to_speed']:g} U: {m['t_change_s'] / 60:.1f} min, "
                     f"{m['reach_change_m'] / 1000:.2f} km to within 5 % of the change")
    else:
        ax.set_title(f"Zig-zag {m['angle_deg']:g}/{m['angle_deg']:g}: overshoots {m['overshoot_1']:.1f}°, "
                     f"{m['overshoot_2']:.1f}°")
    tt = u.time(t)
    a1 = fig.add_subplot(gs[0, 1])
    a1.plot(tt, np.degrees(psi), color=fs.OWN_SHIP)
    a1.set_ylabel("heading [deg]")
    a2 = fig.add_subplot(gs[1, 1], sharex=a1)
    a2.plot(tt, np.degrees(result.delta_c), "--", color="k", lw=0.8, label="commanded")
    a2.plot(tt, np.degrees(result.state("delta")), color=fs.OWN_SHIP, label="actual")
    a2.set_ylabel("rudder [deg]")
    a2.legend(loc="best")
    a3 = fig.add_subplot(gs[2, 1], sharex=a1)
    a3.plot(tt, u.speed(np.hypot(result.state("u"), result.state("v"))), color=fs.OWN_SHIP)
    a3.set_ylabel(f"speed [{u.speed_unit}]")
    a3.set_xlabel(f"t [{u.time_unit}]")
    for a in (a1, a2, a3):
        a.grid(True)
    for a in (a1, a2):
        a.tick_params(labelbottom=False)
    if path:
        fs.save(fig, path)
    return fig


def _ship_size(result, i: int) -> tuple[float, float]:
    """(length, beam) of ship ``i`` in L, for its outline."""
    from mmg_casadi.vessel.library import ship_size
    s = result.scenario.ships[i]
    lay = result.trajectory.layout
    try:
        length, half = ship_size(lay.vessel(i), getattr(s, "length_m", None), getattr(s, "beam_m", None),
                                 unit=lay.unit_vessel())
    except Exception:  # a vessel file that moved since the run: draw the KCS's shape
        return 1.0, 0.14
    return length, 2 * half


def _cpa_marks(result, r_safe: float) -> list[tuple[int, int, float, float]]:
    """(own index, other index, distance, time) of the own ship's closest approach to every ship that came
    within R_safe (at most three, closest first)."""
    names = result.names()
    out = []
    for p in result.metrics.get("pairs", []):
        if p.get("a") == names[0] and p.get("b") in names and p.get("min_distance") is not None \
                and p.get("t_min") is not None and p["min_distance"] <= r_safe:
            out.append((0, names.index(p["b"]), p["min_distance"], p["t_min"]))
    return sorted(out, key=lambda c: c[2])[:3]


@fs.styled
def plot_paths(result, ax, *, title=None, units=None, legend: bool = True, n_outlines: int = 5,
               ticks: float | None = None):
    """Paths of all ships (marine view) with start ○ and goal ☆, hull outlines to scale and time ticks; static
    obstacles with their R_safe, walls and land; R_safe about the own ship at her closest approach to another ship,
    the closest approach to every
    ship that came within R_safe joined and labelled; drawn into ``ax``; returns ``ax``.

    Parameters
    ----------
    result : ScenarioResult
        A simulated scenario (:func:`mmg_casadi.scenarios.run.run_scenario`).
    ax : matplotlib Axes
        Where to draw.
    title : str, optional
        Axes title (default: method, collision, own ship CE and MCTE).
    units : Units or str, optional
        ``"nd"`` (default) or ``"si"``.
    legend : bool
        Draw the legend (ships and every symbol used).
    n_outlines : int
        Largest number of hull outlines per ship.
    ticks : float, optional
        Time between the ticks along the tracks (L/U); default :func:`tick_step` of the run.

    Returns
    -------
    matplotlib.axes.Axes
        ``ax``.
    """
    u = _units(units, result)
    traj, sc = result.trajectory, result.scenario
    N = traj.layout.n_ships
    names = [s.name for s in sc.ships]
    mask = traj.sailing_mask()
    r_safe = result.params["r_safe"]
    step = ticks or tick_step(float(traj.t[-1]), u)
    handles = []
    for i in range(N):
        c = fs.ship_color(i)
        m = mask[:, i]
        x, y, psi = traj.state("x", i)[m], traj.state("y", i)[m], traj.state("psi", i)[m]
        lab = names[i] + (" (own)" if i == 0 and N > 1 else "")
        enc = result.encounter_labels.get(i)
        if enc:
            lab += f": {enc}"
        length, beam = _ship_size(result, i)
        draw_path(ax, x, y, psi, c, label=lab, n_outlines=n_outlines, t=traj.t[m], tick_step=step, units=u,
                  length=length, beam=beam)
        handles.append(Line2D([], [], color=c, label=lab))
        route = np.vstack([sc.ships[i].start, np.asarray(sc.ships[i].waypoints)]) if sc.ships[i].waypoints else None
        if route is not None:
            if len(route) > 2:
                ax.plot(u.length(route[:, 1]), u.length(route[:, 0]), ls=":", lw=0.6, color=c, alpha=0.7, zorder=2)
            g = route[-1]
            draw_goal(ax, g[0], g[1], c, tol=result.params["goal_tolerance"], units=u)
    drawn = fs.draw_hazards(ax, sc, r_safe, units=u)
    marks = _cpa_marks(result, r_safe)
    if N > 1:  # R_safe about the own ship where she came closest (about an obstacle: drawn with the obstacle)
        k = int(np.argmin(result.own_distance()))
        draw_circle(ax, traj.state("x", 0)[k], traj.state("y", 0)[k], r_safe, units=u)
        drawn["r_safe"] = True
    for a, b, d, t in marks:
        k = int(np.argmin(np.abs(traj.t - t)))
        fs.mark_cpa(ax, (traj.state("x", a)[k], traj.state("y", a)[k]), (traj.state("x", b)[k], traj.state("y", b)[k]),
                    d, t, units=u)
    collided = False
    for s in result.metrics["ships"]:
        if s.get("collided") and s.get("collision_time") is not None:
            i = names.index(s["name"])
            k = min(int(np.searchsorted(traj.t, s["collision_time"])), len(traj.t) - 1)
            ax.plot(u.length(traj.state("y", i)[k]), u.length(traj.state("x", i)[k]), "x", color=fs.COLLISION,
                    ms=7, mew=1.6, zorder=8)
            collided = True
    marine_axes(ax, u)
    if legend:
        handles += fs.legend_handles(r_safe=drawn["r_safe"], obstacle=drawn["obstacle"], wall=drawn["wall"],
                                     land=drawn["land"], cpa=bool(marks), ticks=u.time(step),
                                     collision=collided, time_unit=u.time_unit)
        ax.legend(handles=handles, loc="best")
    own = result.metrics["ships"][0]
    status = "collision" if result.metrics["collision"] else "no collision"
    ce = "–" if own["ce"] is None else f"{own['ce']:.3f}"
    mcte = "–" if own["mcte"] is None else u.fmt_length(own["mcte"])
    ax.set_title(title or f"{result.metrics['method']}: {status}; own ship CE {ce}, MCTE {mcte}")
    return ax


@fs.styled
def plot_scenario(result, path=None, *, title=None, units=None) -> Figure:
    """Paths (:func:`plot_paths`); each ship's rudder, commanded (dashed) and actual, in a panel of its own (the
    own ship's only beyond four ships); the distance between agents while inside R_safe with the collision
    threshold. ``result`` is a :class:`~mmg_casadi.scenarios.run.ScenarioResult`; the figure is saved to ``path``
    when given.

    Parameters
    ----------
    result : mmg_casadi.scenarios.run.ScenarioResult
        Result of the scenario run.
    path : str or path-like, optional
        File to save the figure to (PNG at 300 dpi, or ``.svg`` / ``.pdf``).
    title : str, optional
        Figure title.
    units : Units or str, optional
        ``"nd"`` (default) or ``"si"``.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    u = _units(units, result)
    traj, sc = result.trajectory, result.scenario
    N = traj.layout.n_ships
    names = [s.name for s in sc.ships]
    mask = traj.sailing_mask()
    r_safe = result.params["r_safe"]
    cd = result.params["collision_distance"]
    rudders = [i for i in range(N) if not traj.layout.replay or i not in traj.layout.replay][:4 if N <= 4 else 1]
    fig = Figure(figsize=(fs.PAGE, 0.55 * fs.PAGE), layout="constrained")
    gs = fig.add_gridspec(1, 2, width_ratios=[1.05, 1])
    plot_paths(result, fig.add_subplot(gs[0, 0]), title=title, units=u)
    right = gs[0, 1].subgridspec(len(rudders) + 1, 1, height_ratios=[1] * len(rudders) + [1.6])
    tt, t_aux = u.time(traj.t), u.time(traj.t[:-1])
    first = None
    for row, i in enumerate(rudders):
        a = fig.add_subplot(right[row, 0], sharex=first)
        first = first or a
        c = fs.ship_color(i)
        m = mask[:-1, i]
        a.plot(t_aux[m], np.degrees(traj.auxiliary("delta_c", i)[m]), "--", color="k", lw=0.6, label="commanded")
        a.plot(tt[mask[:, i]], np.degrees(traj.state("delta", i)[mask[:, i]]), color=c, lw=1.0, label="actual")
        a.set_ylim(-40, 40)
        a.set_yticks([-35, 0, 35])
        a.set_ylabel(f"δ {names[i]}\n[deg]")
        a.grid(True)
        a.tick_params(labelbottom=False)
        if row == 0:
            a.legend(loc="upper right", ncols=2)
    a2 = fig.add_subplot(right[len(rudders), 0], sharex=first)
    for k, ((a, b), d) in enumerate(result.pair_distances().items()):
        inside = d <= r_safe
        if inside.any():
            i = names.index(b) if b in names else None
            color = fs.ship_color(i) if (a == names[0] and i is not None) else None
            a2.plot(tt, u.length(np.where(inside, d, np.nan)), color=color, label=f"{a}–{b}")
    a2.axhline(u.length(cd), color=fs.COLLISION, ls="--", lw=0.8, label=f"collision ({u.fmt_length(cd)})")
    a2.set_ylabel(f"distance inside R_safe [{u.length_unit}]")
    a2.set_xlabel(f"t [{u.time_unit}]")
    a2.legend(loc="best")
    a2.grid(True)
    if path:
        fs.save(fig, path)
    return fig


@fs.styled
def plot_tracking(result, path=None, *, units=None) -> Figure:
    """Waypoint tracking: path with R_tol circles, commanded vs actual rudder, desired vs actual heading, and
    cross-track error over time (the paper's waypoint-tracking figure).

    Parameters
    ----------
    result : mmg_casadi.scenarios.run.ScenarioResult
        Result of the waypoint-tracking run.
    path : str or path-like, optional
        File to save the figure to (PNG at 300 dpi, or ``.svg`` / ``.pdf``).
    units : Units or str, optional
        ``"nd"`` (default) or ``"si"``.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    u = _units(units, result)
    traj, sc = result.trajectory, result.scenario
    m = traj.sailing_mask()[:, 0]
    ma = m[:-1]
    fig = Figure(figsize=(fs.PAGE, 0.6 * fs.PAGE), layout="constrained")
    gs = fig.add_gridspec(3, 2, width_ratios=[1.0, 1.1])
    ax = fig.add_subplot(gs[:, 0])
    x, y, psi = traj.state("x", 0)[m], traj.state("y", 0)[m], traj.state("psi", 0)[m]
    step = tick_step(float(traj.t[m][-1]), u)
    draw_path(ax, x, y, psi, fs.OWN_SHIP, label="track", n_outlines=9, t=traj.t[m], tick_step=step, units=u)
    wps = np.vstack([sc.ships[0].start, np.asarray(sc.ships[0].waypoints)])
    ax.plot(u.length(wps[:, 1]), u.length(wps[:, 0]), "k--", lw=0.6, label="waypoint path")
    for wp in sc.ships[0].waypoints:
        ax.plot(u.length(wp[1]), u.length(wp[0]), "k+", ms=5, mew=0.8)
        draw_circle(ax, wp[0], wp[1], sc.settings.goal_tolerance, color="k", ls=":", units=u)
    marine_axes(ax, u)
    ax.legend(handles=[Line2D([], [], color=fs.OWN_SHIP, label="track"),
                       Line2D([], [], color="k", ls="--", lw=0.6, marker="+", label="waypoints and path"),
                       Line2D([], [], color="k", ls=":", lw=0.7, label="R_tol"),
                       Line2D([], [], color=fs.OWN_SHIP, label="start", **fs.START_MARKER),
                       Line2D([], [], marker="o", color=fs.OWN_SHIP, ms=2.2, ls="none",
                              label=f"every {u.time(step):g} {u.time_unit}")], loc="center")
    own = result.metrics["ships"][0]
    mcte = u.fmt_length(own["mcte"]) if u.si else f"{own['mcte']:.4f} L"
    ax.set_title(f"Waypoint tracking: CE {own['ce']:.4f}, MCTE {mcte}")
    t = u.time(traj.t)
    a1 = fig.add_subplot(gs[0, 1])
    a1.plot(t[:-1][ma], np.degrees(traj.auxiliary("delta_c", 0)[ma]), "--", color="k", lw=0.7, label="commanded")
    a1.plot(t[m], np.degrees(traj.state("delta", 0)[m]), color=fs.OWN_SHIP, label="actual")
    a1.set_ylabel("rudder [deg]")
    a1.legend(loc="lower right", ncols=2)
    a2 = fig.add_subplot(gs[1, 1], sharex=a1)
    a2.plot(t[:-1][ma], np.degrees(np.unwrap(traj.auxiliary("psi_d", 0)[ma])), "--", color="k", lw=0.7,
            label="desired")
    a2.plot(t[m], np.degrees(np.unwrap(traj.state("psi", 0)[m])), color=fs.OWN_SHIP, label="actual")
    a2.set_ylabel("heading [deg]")
    a2.legend(loc="lower right", ncols=2)
    a3 = fig.add_subplot(gs[2, 1], sharex=a1)
    a3.plot(t[:-1][ma], u.length(traj.auxiliary("y_e", 0)[ma]), color=fs.OWN_SHIP)
    a3.set_ylabel(f"cross-track error [{u.length_unit}]")
    a3.set_xlabel(f"t [{u.time_unit}]")
    for a in (a1, a2, a3):
        a.grid(True)
    for a in (a1, a2):
        a.tick_params(labelbottom=False)
    if path:
        fs.save(fig, path)
    return fig


@fs.styled
def plot_fleet(result, path=None, *, title=None, ax=None, units=None) -> Figure:
    """Tracks of a large fleet (marine view): one colour per ship from a cyclic colour map, thin lines, a dot at
    each start, a cross at each collision, the static obstacles in grey. For scenarios of many ships, where
    :func:`plot_scenario`'s legends and pair panels do not scale.

    Parameters
    ----------
    result : mmg_casadi.scenarios.run.ScenarioResult
        Result of the scenario run.
    path : str or path-like, optional
        File to save the figure to (PNG at 300 dpi, or ``.svg`` / ``.pdf``).
    title : str, optional
        Axes title (default: ships, collisions, goals reached).
    ax : matplotlib Axes, optional
        Where to draw; a new figure when omitted.
    units : Units or str, optional
        ``"nd"`` (default) or ``"si"``.

    Returns
    -------
    matplotlib.figure.Figure
        The new figure, or the figure of ``ax`` (saved to ``path`` when given).
    """
    u = _units(units, result)
    traj, sc = result.trajectory, result.scenario
    N = traj.layout.n_ships
    if ax is None:
        fig = Figure(figsize=(fs.PAGE, fs.PAGE), layout="constrained")
        ax = fig.add_subplot()
    fig = ax.figure
    mask = traj.sailing_mask()
    colours = _cyclic_colours(N)
    for i in range(N):
        m = mask[:, i]
        ax.plot(u.length(traj.state("y", i)[m]), u.length(traj.state("x", i)[m]), color=colours[i], lw=0.5)
        ax.plot(u.length(sc.ships[i].start[1]), u.length(sc.ships[i].start[0]), "o", color=colours[i], ms=2)
    for s in result.metrics["ships"]:
        if s["collided"]:
            i = result.names().index(s["name"])
            k = int(np.searchsorted(traj.t, s["collision_time"]))
            k = min(k, len(traj.t) - 1)
            ax.plot(u.length(traj.state("y", i)[k]), u.length(traj.state("x", i)[k]), "x", color=fs.COLLISION,
                    ms=5, mew=1.2)
    for o in sc.obstacles:
        ax.plot(u.length(o.position[1]), u.length(o.position[0]), "s", color=fs.OBSTACLE, ms=2.5)
    draw_land(ax, sc.land, units=u)
    marine_axes(ax, u)
    ships = result.metrics["ships"]
    n_col = sum(s["collided"] for s in ships)
    n_goal = sum(s["reached_goal"] for s in ships)
    ax.set_title(title or f"{N} ships: {n_col} in a collision (×), {n_goal} reached their goals")
    if path is not None:
        fs.save(fig, path)
    return fig


def _cyclic_colours(n: int) -> list:
    """``n`` colours that neighbours in index order tell apart (a golden-ratio walk round the hue circle)."""
    return [hsv_to_rgb(((0.618033988749895 * i) % 1.0, 0.85, 0.8 - 0.25 * (i % 3) / 2)) for i in range(n)]
