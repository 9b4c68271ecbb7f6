"""The one style of every figure: sizes for a journal column, colours, markers, legend entries, time ticks, CPA.

* Sizes: :data:`COLUMN` (one column of a two-column journal page, 90 mm) and :data:`PAGE` (the full text width,
  190 mm) at :data:`DPI` = 300 dots per inch; fonts of 7-8 pt (:data:`RC`), so a figure printed at its size
  reads like the text around it. A figure saved as ``.svg`` or ``.pdf`` is vector graphics (:func:`save`).
* Colours: one per ship (:func:`ship_color`, the colour-blind-safe Okabe-Ito palette without its red, kept in
  order: the own ship is always blue); hazards in greys (:data:`OBSTACLE`, :data:`WALL`), land in a chart's buff
  (:data:`LAND`), R_safe circles dashed grey (:data:`R_SAFE`); red only for a collision.
* Markers: start ○ and goal ☆ in the ship's colour (:data:`START_MARKER`, :data:`GOAL_MARKER`); ticks along each
  track at common times (:func:`time_ticks`), the closest point of approach (CPA) joined by a line and labelled
  with its time and distance (:func:`mark_cpa`); every symbol drawn has a legend entry (:func:`legend_handles`).

Examples
--------
>>> ship_color(0) == OWN_SHIP and ship_color(7) != ship_color(0)
True
>>> nice_step(100.0)
20.0
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
from matplotlib import rc_context
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Patch

MM = 1 / 25.4
"""One millimetre in inches."""
COLUMN = 90 * MM
"""Width of one column of a two-column journal page (in)."""
PAGE = 190 * MM
"""Width of the full text of a journal page (in)."""
DPI = 300
"""Resolution of saved raster figures (dots per inch)."""

OWN_SHIP = "#0072B2"
SHIP_COLORS = (OWN_SHIP, "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#8C564B", "#7F7F7F", "#BCBD22", "#17BECF",
               "#9467BD")
"""Ship colours in order: the Okabe-Ito palette without red and yellow (blue, orange, green, purple, sky blue), then
tableau colours; red is kept for collisions."""
OBSTACLE = "#4D4D4D"
"""Fill of a static obstacle (dark grey)."""
WALL = "#1A1A1A"
"""Channel walls (near black)."""
LAND = "#E8D9A8"
"""Fill of land (a chart's buff)."""
COAST = "#5A4A2A"
"""Coastline."""
R_SAFE = "#8A8A8A"
"""R_safe circles (grey, dashed)."""
COLLISION = "#D62728"
"""A collision (red cross)."""
START_MARKER = dict(marker="o", ms=5, mfc="white", mew=1.2, ls="none")
"""Start: an open circle in the ship's colour."""
GOAL_MARKER = dict(marker="*", ms=9, mfc="white", mew=1.0, ls="none")
"""Goal: an open star in the ship's colour."""

RC = {
    "font.size": 7.5, "axes.titlesize": 7.5, "axes.labelsize": 7.5, "xtick.labelsize": 6.5,
    "ytick.labelsize": 6.5, "legend.fontsize": 6.5, "legend.frameon": True, "legend.framealpha": 0.85,
    "legend.handlelength": 1.6, "lines.linewidth": 1.1, "axes.linewidth": 0.6, "grid.linewidth": 0.4,
    "grid.alpha": 0.35, "xtick.major.width": 0.6, "ytick.major.width": 0.6, "xtick.major.size": 2.5,
    "ytick.major.size": 2.5, "savefig.dpi": DPI, "figure.dpi": 100, "axes.titleweight": "normal",
    "mathtext.default": "regular",
}
"""Matplotlib settings of every figure (:func:`styled`)."""


def ship_color(i: int) -> str:
    """The colour of ship ``i`` (0: the own ship).

    Parameters
    ----------
    i : int
        Ship index in the scenario.

    Returns
    -------
    str
        A colour of :data:`SHIP_COLORS`.
    """
    return SHIP_COLORS[i % len(SHIP_COLORS)]


def styled(func):
    """Decorator: draw ``func``'s figure under :data:`RC`.

    Parameters
    ----------
    func : callable
        A function that builds a figure.

    Returns
    -------
    callable
        The same function, run inside ``matplotlib.rc_context(RC)``.
    """
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with rc_context(RC):
            return func(*args, **kwargs)
    return wrapper


def style():
    """A context in which figures take :data:`RC` (for figures of your own in the same style).

    Returns
    -------
    contextlib.AbstractContextManager
        ``matplotlib.rc_context(RC)``.
    """
    return rc_context(RC)


def save(fig, path) -> Path:
    """Save ``fig`` to ``path``: PNG at :data:`DPI`, or vector graphics for ``.svg`` and ``.pdf``.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        File name; its extension chooses the format.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    path = Path(path)
    with rc_context(RC):
        fig.savefig(path, dpi=DPI, metadata={"Software": None} if path.suffix.lower() == ".png" else None)
    return path


def nice_step(span: float, target: int = 5) -> float:
    """A round step (1, 2 or 5 times a power of ten) that divides ``span`` into about ``target`` parts.

    Parameters
    ----------
    span : float
        Length of the interval (> 0).
    target : int
        Wanted number of parts.

    Returns
    -------
    float
        The step.
    """
    raw = max(span, 1e-12) / max(target, 1)
    mag = 10 ** math.floor(math.log10(raw))
    return float(next(m * mag for m in (1, 2, 5, 10) if m * mag >= raw))


def time_ticks(ax, t, x, y, color, step: float, *, label: bool = True, units=None, size: float = 2.2) -> None:
    """Dots along a track (marine view) at the multiples of ``step``, labelled with their time.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes in the marine view (east along the abscissa).
    t, x, y : numpy.ndarray
        Times (L/U) and north, east positions (L) of the track.
    color : color
        Colour of the dots and labels.
    step : float
        Time between ticks (L/U).
    label : bool
        Write the time beside every other dot.
    units : mmg_casadi.units.Units, optional
        Units of the labels and positions (default L/U and L).
    size : float
        Dot size (points).
    """
    if len(t) < 2 or step <= 0:
        return
    sx = units.length if units else (lambda v: v)
    st = units.time if units else (lambda v: v)
    ticks = np.arange(math.ceil(t[0] / step) * step, t[-1] + 1e-9, step)
    ticks = ticks[ticks > t[0] + 1e-9]
    if not len(ticks):
        return
    xs, ys = np.interp(ticks, t, x), np.interp(ticks, t, y)
    ax.plot(sx(ys), sx(xs), "o", color=color, ms=size, mec="white", mew=0.4, ls="none", zorder=4)
    if label:
        for k, (tk, xk, yk) in enumerate(zip(ticks, xs, ys)):
            if k % 2:
                continue
            ax.annotate(f"{st(tk):.0f}", (sx(yk), sx(xk)), xytext=(3, 2), textcoords="offset points", fontsize=5.5,
                        color=color, zorder=5)


def mark_cpa(ax, a_xy, b_xy, distance: float, t: float, *, units=None, color="k") -> None:
    """Join two ships' positions at their closest approach and label it with its distance and time.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes in the marine view.
    a_xy, b_xy : tuple of float
        North, east positions (L) of the two ships at the CPA.
    distance : float
        The CPA distance (L).
    t : float
        Its time (L/U).
    units : mmg_casadi.units.Units, optional
        Units of the label and positions (default L and L/U).
    color : color
        Line and label colour.
    """
    sx = units.length if units else (lambda v: v)
    (ax_, ay_), (bx_, by_) = a_xy, b_xy
    ax.plot([sx(ay_), sx(by_)], [sx(ax_), sx(bx_)], ls=(0, (2, 1)), color=color, lw=0.8, zorder=6)
    ax.plot([sx(ay_), sx(by_)], [sx(ax_), sx(bx_)], "s", color=color, ms=2.5, zorder=6)
    d = units.fmt_length(distance) if units else f"{distance:.2f} L"
    tt = units.fmt_time(t) if units else f"{t:.1f} L/U"
    ax.annotate(f"CPA {d}\nt = {tt}", ((sx(ay_) + sx(by_)) / 2, (sx(ax_) + sx(bx_)) / 2), xytext=(6, -4),
                textcoords="offset points", fontsize=5.5, color=color, zorder=7, va="top",
                bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.75))


def legend_handles(*, r_safe: bool = False, obstacle: bool = False, wall: bool = False, land: bool = False,
                   cpa: bool = False, ticks: float | None = None, collision: bool = False,
                   time_unit: str = "L/U") -> list:
    """Legend entries of the symbols a track figure uses besides the ships' own lines.

    Parameters
    ----------
    r_safe, obstacle, wall, land, cpa, collision : bool
        Whether the figure shows R_safe circles, static obstacles, walls, land, a CPA mark or a collision.
    ticks : float, optional
        The time step of the ticks along the tracks, when drawn.
    time_unit : str
        Unit of ``ticks``.

    Returns
    -------
    list of matplotlib.artist.Artist
        Handles with labels: start ○, goal ☆, and each symbol asked for.
    """
    h = [Line2D([], [], color="k", label="start", **START_MARKER),
         Line2D([], [], color="k", label="goal (R_tol circle)", **GOAL_MARKER)]
    if ticks:
        h.append(Line2D([], [], marker="o", color="k", ms=2.2, ls="none", label=f"every {ticks:g} {time_unit} (t)"))
    if r_safe:
        h.append(Line2D([], [], color=R_SAFE, ls="--", lw=0.8, label="R_safe"))
    if obstacle:
        h.append(Patch(facecolor=OBSTACLE, edgecolor="k", lw=0.5, label="obstacle"))
    if wall:
        h.append(Line2D([], [], color=WALL, lw=2.0, label="wall"))
    if land:
        h.append(Patch(facecolor=LAND, edgecolor=COAST, lw=0.8, label="land"))
    if cpa:
        h.append(Line2D([], [], color="k", ls=(0, (2, 1)), marker="s", ms=2.5, lw=0.8, label="closest approach"))
    if collision:
        h.append(Line2D([], [], color=COLLISION, marker="x", ms=6, mew=1.5, ls="none", label="collision"))
    return h


def draw_hazards(ax, scenario, r_safe: float | None, *, units=None) -> dict:
    """Static obstacles (grey discs with their R_safe circle), walls and land of ``scenario``.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Axes in the marine view.
    scenario : mmg_casadi.scenarios.scenario.Scenario
        The scenario.
    r_safe : float or None
        R_safe (L) drawn around each obstacle; None for none.
    units : mmg_casadi.units.Units, optional
        Units of the positions (default L).

    Returns
    -------
    dict
        Which kinds were drawn: ``obstacle``, ``wall``, ``land``, ``r_safe`` (for :func:`legend_handles`).
    """
    sx = units.length if units else (lambda v: v)
    for o in scenario.obstacles:
        ax.add_patch(Circle((sx(o.position[1]), sx(o.position[0])), sx(max(o.radius, 0.25)), facecolor=OBSTACLE,
                            edgecolor="k", lw=0.5, zorder=3))
        if r_safe:
            ax.add_patch(Circle((sx(o.position[1]), sx(o.position[0])), sx(r_safe), fill=False, ls="--",
                                color=R_SAFE, lw=0.7, zorder=1))
    for w in scenario.walls:
        pts = np.asarray(w.points)
        ax.plot(sx(pts[:, 1]), sx(pts[:, 0]), "-", color=WALL, lw=2.0, zorder=3, solid_capstyle="butt")
    for k, poly in enumerate(scenario.land):
        pts = np.asarray(poly.points, float)
        ax.fill(sx(pts[:, 1]), sx(pts[:, 0]), facecolor=LAND, edgecolor=COAST, lw=0.8, zorder=0,
                label="land" if k == 0 else None)
    return {"obstacle": bool(scenario.obstacles), "wall": bool(scenario.walls), "land": bool(scenario.land),
            "r_safe": bool(scenario.obstacles and r_safe)}
