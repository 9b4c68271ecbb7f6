"""Animations of a simulated scenario: who turned first, and why.

:func:`animate` draws every ship's hull to scale (its vessel's length and beam) on its track, an R_safe circle
about each ship, the heading the active method commands (an arrow from the bow: the ILOS heading while nothing is
within R_safe, the avoiding method's inside it), and the COLREG role of each of the ship's scored encounters
(the encounter scorer of ``metrics.json``) from the onset of risk until it is released. It writes a GIF (Pillow,
which matplotlib brings) or an MP4 (ffmpeg from the optional ``imageio-ffmpeg``: ``pip install
mmg-casadi[video]``); frames are taken at even times, at most ``max_frames`` of them, so a run of any length
gives a file of a few hundred kB.

Examples
--------
>>> check_animation_path("run.gif"), check_animation_path("run.mp4")
('gif', 'mp4')
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, Polygon
from matplotlib.transforms import Affine2D

from mmg_casadi import figstyle as fs
from mmg_casadi.errors import InputError
from mmg_casadi.units import Units

FORMATS = {".gif": "gif", ".mp4": "mp4"}
"""File extensions :func:`animate` writes and their formats."""


def check_animation_path(path) -> str:
    """The format of an animation file name, or an :class:`~mmg_casadi.errors.InputError` (before any work).

    Parameters
    ----------
    path : str or Path
        File name ending in ``.gif`` or ``.mp4``.

    Returns
    -------
    str
        ``"gif"`` or ``"mp4"``.
    """
    fmt = FORMATS.get(Path(path).suffix.lower())
    if fmt is None:
        raise InputError("animate", "a file name ending in .gif or .mp4", str(path))
    if fmt == "mp4":
        try:
            import imageio_ffmpeg  # noqa: F401
        except ImportError:
            raise InputError("animate", "a .gif, or an .mp4 with the extra mmg-casadi[video] (imageio-ffmpeg) "
                             "installed", str(path)) from None
    return fmt


def _write(images: list, path: Path, fmt: str, fps: int) -> None:
    """Write RGB frames as a GIF (one 64-colour palette without dithering, so unchanged pixels stay unchanged and
    Pillow stores only what moves) or an H.264 MP4 (imageio-ffmpeg)."""
    if fmt == "gif":
        from PIL import Image
        picks = [images[k] for k in np.linspace(0, len(images) - 1, min(6, len(images))).astype(int)]
        palette = Image.fromarray(np.concatenate(picks, axis=0)).quantize(colors=96, method=Image.Quantize.MEDIANCUT,
                                                                          dither=Image.Dither.NONE)
        frames = [Image.fromarray(a).quantize(palette=palette, dither=Image.Dither.NONE) for a in images]
        frames[0].save(path, save_all=True, append_images=frames[1:], duration=int(1000 / fps), loop=0,
                       optimize=True)
        return
    import imageio_ffmpeg
    h, w = images[0].shape[:2]
    images = [np.pad(a, ((0, h % 2), (0, w % 2), (0, 0)), mode="edge") for a in images]  # H.264: even sizes
    writer = imageio_ffmpeg.write_frames(str(path), (w + w % 2, h + h % 2), fps=fps, codec="libx264",
                                         quality=None, output_params=["-crf", "28"], macro_block_size=1)
    writer.send(None)
    for a in images:
        writer.send(np.ascontiguousarray(a))
    writer.close()


def encounter_roles(metrics: dict) -> list[tuple[str, str, str, float, float]]:
    """Every scored encounter of a run as ``(ship, other, role, onset, release)`` (times in L/U), from both sides.

    Parameters
    ----------
    metrics : dict
        The run's ``metrics.json`` (:func:`mmg_casadi.scenarios.run.run_scenario`).

    Returns
    -------
    list of tuple
        One entry per applicable encounter; ``release`` is the end of the run when the encounter was not released.

    Examples
    --------
    >>> m = {"t_end": 50.0, "pairs": [{"a": "own", "b": "t1", "encounters": {"a": [{"applicable": True,
    ...      "role": "give-way", "onset": {"t": 10.0}, "release": {"t": 30.0}}], "b": []}}]}
    >>> encounter_roles(m)
    [('own', 't1', 'give-way', 10.0, 30.0)]
    """
    out = []
    for p in metrics.get("pairs", []):
        for side, me, other in (("a", p.get("a"), p.get("b")), ("b", p.get("b"), p.get("a"))):
            for e in (p.get("encounters") or {}).get(side, []):
                if not isinstance(e, dict) or not e.get("applicable") or not e.get("onset"):
                    continue
                release = (e.get("release") or {}).get("t")
                out.append((me, other, e.get("role", "?"), float(e["onset"]["t"]),
                            float(metrics.get("t_end", math.inf) if release is None else release)))
    return out


def animate(result, path, *, fps: int = 10, max_frames: int = 80, units=None, dpi: int = 80) -> Path:
    """Write an animation of ``result`` to ``path`` (``.gif`` or ``.mp4``; module notes).

    Parameters
    ----------
    result : mmg_casadi.scenarios.run.ScenarioResult
        A simulated scenario (:func:`mmg_casadi.scenarios.run.run_scenario`).
    path : str or Path
        Output file, ``.gif`` or ``.mp4``.
    fps : int
        Frames per second.
    max_frames : int
        Largest number of frames (the run is sampled at even times).
    units : Units or str, optional
        ``"nd"`` (default) or ``"si"`` for the axes and the clock.
    dpi : int
        Resolution (the figure is 19 cm wide: 598 pixels at 80 dpi).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    fmt = check_animation_path(path)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    traj, sc = result.trajectory, result.scenario
    u = units if isinstance(units, Units) else Units.of(units or "nd", traj.layout.unit_vessel())
    names = result.names()
    n = traj.layout.n_ships
    mask = traj.sailing_mask()
    t = traj.t
    frames = np.unique(np.linspace(0, len(t) - 1, min(max_frames, len(t))).astype(int))
    r_safe = result.params["r_safe"]
    roles = encounter_roles(result.metrics)
    from mmg_casadi.plotting import _ship_size, marine_axes, ship_outline

    with fs.style():
        fig = Figure(figsize=(fs.PAGE, 0.5 * fs.PAGE), layout="constrained", dpi=dpi)
        FigureCanvasAgg(fig)
        overview, ax = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1, 1]})
        xs = np.concatenate([traj.state("x", i)[mask[:, i]] for i in range(n)])
        ys = np.concatenate([traj.state("y", i)[mask[:, i]] for i in range(n)])
        cx, cy = (xs.min() + xs.max()) / 2, (ys.min() + ys.max()) / 2
        half = 0.5 * max(xs.max() - xs.min(), ys.max() - ys.min(), 2 * r_safe) + 3.0
        for a in (overview, ax):
            fs.draw_hazards(a, sc, None, units=u)
            marine_axes(a, u)
            a.set_aspect("equal", adjustable="box")
        overview.set_xlim(u.length(cy - half), u.length(cy + half))
        overview.set_ylim(u.length(cx - half), u.length(cx + half))
        overview.set_title("the whole run")
        window = r_safe + 3.0
        ax.set_xlim(-u.length(window), u.length(window))
        ax.set_ylim(-u.length(window), u.length(window))
        ax.set_title(f"about {names[0]} (hulls to scale)")
        ax.set_xlabel(f"east of {names[0]} [{u.length_unit}]")
        ax.set_ylabel(f"north of {names[0]} [{u.length_unit}]")
        shift = Affine2D()  # the close-up follows the own ship: everything in it is drawn shifted by her position
        follow = shift + ax.transData
        for artist in (*ax.patches, *ax.lines, *ax.collections):
            artist.set_transform(follow)
        ships = []
        for i in range(n):
            c = fs.ship_color(i)
            length, beam = _ship_size(result, i)
            route = np.vstack([sc.ships[i].start, np.asarray(sc.ships[i].waypoints)]) if sc.ships[i].waypoints \
                else None
            if route is not None:
                overview.plot(u.length(route[-1, 1]), u.length(route[-1, 0]), color=c, **fs.GOAL_MARKER)
                ax.plot(u.length(route[-1, 1]), u.length(route[-1, 0]), color=c, transform=follow, **fs.GOAL_MARKER)
            trail, = overview.plot([], [], color=c, lw=1.0)
            dot, = overview.plot([], [], "o", color=c, ms=3)
            near, = ax.plot([], [], color=c, lw=0.8, alpha=0.7, transform=follow)
            hull = Polygon(np.zeros((5, 2)), closed=True, facecolor=c, edgecolor="k", lw=0.4, zorder=6,
                           transform=follow)
            ax.add_patch(hull)
            ring = Circle((0, 0), u.length(r_safe), fill=False, ls="--", lw=0.6, color=c, alpha=0.6, transform=follow)
            ax.add_patch(ring)
            cmd, = ax.plot([], [], color=c, lw=1.0, ls=(0, (1.5, 1)), zorder=5, transform=follow)
            label = ax.text(0, 0, "", fontsize=6, color=c, zorder=7, clip_on=True, transform=follow,
                            bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.75))
            ships.append((trail, dot, near, hull, ring, cmd, label, length, beam))
        clock = fig.suptitle("")
        overview.legend(handles=[Line2D([], [], color=fs.ship_color(i), label=names[i]) for i in range(n)]
                        + [Line2D([], [], color="k", ls=(0, (1.5, 1)), lw=1.0, label="heading ordered"),
                           Line2D([], [], color="k", ls="--", lw=0.6, label="R_safe")], loc="best", fontsize=6)
        try:
            ordered = [traj.auxiliary("psi_d", i) for i in range(n)]
        except (KeyError, ValueError, IndexError):  # a trajectory without the auxiliary outputs
            ordered = None

        def draw(k):
            ox, oy = traj.state("x", 0)[k], traj.state("y", 0)[k]
            shift.clear().translate(-u.length(oy), -u.length(ox))
            for i, (trail, dot, near, hull, ring, cmd, label, length, beam) in enumerate(ships):
                on = mask[:k + 1, i]
                x, y = traj.state("x", i)[:k + 1][on], traj.state("y", i)[:k + 1][on]
                sailing = bool(mask[k, i])
                trail.set_data(u.length(y), u.length(x))
                near.set_data(u.length(y), u.length(x))
                for artist in (dot, hull, ring, cmd):
                    artist.set_visible(sailing)
                label.set_visible(False)
                if not sailing:
                    continue
                xk, yk, psi = traj.state("x", i)[k], traj.state("y", i)[k], traj.state("psi", i)[k]
                dot.set_data([u.length(yk)], [u.length(xk)])
                hull.set_xy(u.length(ship_outline(xk, yk, psi, length, beam)))
                ring.center = (u.length(yk), u.length(xk))
                if ordered is not None and k < len(t) - 1:
                    psi_d = ordered[i][k]
                    cmd.set_data(u.length([yk, yk + 4 * math.sin(psi_d)]), u.length([xk, xk + 4 * math.cos(psi_d)]))
                else:
                    cmd.set_visible(False)
                now = [f"{role} ({other})" for me, other, role, t0, t1 in roles
                       if me == names[i] and t0 <= t[k] <= t1]
                if now:
                    label.set_text("\n".join(now))
                    label.set_position((u.length(yk + 1.2), u.length(xk + 1.2)))
                    label.set_visible(True)
            clock.set_text(f"{result.metrics['method']}: t = {u.fmt_time(t[k])}")
            return []

        draw(frames[0])
        fig.canvas.draw()
        fig.set_layout_engine("none")  # the layout is fixed after the first frame (constrained layout is slow)
        images = []
        for k in frames:
            draw(k)
            fig.canvas.draw()
            images.append(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy())
    _write(images, path, fmt, fps)
    return path
