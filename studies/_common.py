"""Shared plumbing of the paper's studies: run scenarios for several methods and write the outputs.

Each study writes ``<out>/<case>/<method>/`` (trajectory npz/CSV, figure, per-run metrics.json), a comparison
figure per case, and ``<out>/metrics.json`` shaped ``{"params": {...}, "cases": {CASE: {METHOD: <simulate
schema>}}}`` with the full resolved parameter set the study ran with.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from mmg_casadi.guidance import methods as registry
from mmg_casadi.io import write_json
from mmg_casadi.params import resolve
from mmg_casadi import figstyle as fs
from mmg_casadi.plotting import plot_paths, tick_step
from mmg_casadi.scenarios.scenario import with_method
from mmg_casadi.scenarios.run import run_scenario, write_outputs

ALL_METHODS = tuple(m for m in registry.AVOIDING)
"""Every avoiding method of the registry."""
APF_AND_VO = tuple(m for m in registry.AVOIDING if m != "sink-vortex")
"""The methods of the paper's conflict study."""


def run_cases(cases: dict, methods, out, params=None, *, title: str = "") -> dict:
    """Run every case for every method; write per-run outputs, a comparison figure per case and metrics.json.

    Parameters
    ----------
    cases : dict
        Case name → Scenario.
    methods : iterable of str
        Methods to run each case with.
    out : str or Path
        Output directory.
    params : dict, optional
        Parameter overrides for every run.
    title : str
        Figure title prefix.
    """
    out = Path(out)
    methods = registry.parse_list(methods)
    results = {}
    metrics = {"params": resolve(params, prefix="params."), "cases": {}}
    used = [with_method(sc, m).method_of(i) for sc in cases.values() for m in methods for i in range(len(sc.ships))]
    with registry.run_of(used, params):
        _run_cases(cases, methods, out, params, title, results, metrics)
    write_json(out / "metrics.json", metrics)
    return metrics


def _run_cases(cases: dict, methods, out: Path, params, title: str, results: dict, metrics: dict) -> None:
    for case, sc in cases.items():
        metrics["cases"][case] = {}
        results[case] = {}
        for m in methods:
            r = run_scenario(with_method(sc, m), params=params)
            write_outputs(r, out / case / m)
            results[case][m] = r
            metrics["cases"][case][m] = r.metrics
            own = r.metrics["ships"][0]
            dmin = min((p["min_distance"] for p in r.metrics["pairs"]), default=float("nan"))
            print(f"  {case:>14s} {m:>18s}: collision={r.metrics['collision']!s:5s} min distance {dmin:6.2f} L"
                  f"  own CE {own['ce']:.4f} MCTE {own['mcte']:.3f} L", file=sys.stderr)
        plot_comparison(results[case], out / f"{case}.png", title=f"{title} {case}".strip())


@fs.styled
def plot_comparison(by_method: dict, path, title="") -> Figure:
    """The encounter strip: one map per method (three to a row, the style of :mod:`mmg_casadi.figstyle`: start ○,
    goal ☆, hulls to scale, time ticks, R_safe and the closest approach marked), and below them one panel of the
    own ship's distance to its nearest ship or obstacle over time, one line per method, with the collision
    distance.

    Parameters
    ----------
    by_method : dict
        Method name → :class:`~mmg_casadi.scenarios.run.ScenarioResult` of the same case.
    path : str or Path
        File to save to (PNG at 300 dpi, or ``.svg`` / ``.pdf``).
    title : str
        Figure title.

    Returns
    -------
    matplotlib.figure.Figure
        The figure.
    """
    n = len(by_method)
    cols = min(3, n)
    rows = -(-n // cols)
    fig = Figure(figsize=(fs.PAGE, 0.42 * fs.PAGE * rows * 3 / cols + 0.3 * fs.PAGE), layout="constrained")
    gs = fig.add_gridspec(rows + 1, cols, height_ratios=[1.0] * rows + [0.55])
    spare = rows * cols > n  # an empty slot in the maps' grid holds the legends
    dist = fig.add_subplot(gs[rows, :] if spare or cols == 1 else gs[rows, :cols - 1])
    maps, flags = [], dict(collision=False, cpa=False)
    step = tick_step(max(float(r.trajectory.t[-1]) for r in by_method.values()))
    for k, (m, r) in enumerate(by_method.items()):
        ax = fig.add_subplot(gs[k // cols, k % cols])
        maps.append(ax)
        st = "COLLISION" if r.metrics["collision"] else "no collision"
        d_min = min((p["min_distance"] for p in r.metrics["pairs"]), default=float("nan"))
        plot_paths(r, ax, title=f"{m}\n{st}, closest {d_min:.2f} L", legend=False, n_outlines=3,
                   ticks=step)
        flags["collision"] |= bool(r.metrics["collision"])
        flags["cpa"] |= any(p["b"] in r.names() and p["min_distance"] <= r.params["r_safe"]
                            for p in r.metrics["pairs"] if p["a"] == r.names()[0])
        d = r.own_distance()
        inside = d <= r.params["r_safe"]
        style = _METHOD_STYLES[k % len(_METHOD_STYLES)]
        dist.plot(r.trajectory.t, np.where(inside, d, np.nan), label=m, **style)
    lims = np.array([[*a.dataLim.intervalx, *a.dataLim.intervaly] for a in maps])
    lo_x, hi_x, lo_y, hi_y = lims[:, 0].min(), lims[:, 1].max(), lims[:, 2].min(), lims[:, 3].max()
    pad = 0.04 * max(hi_x - lo_x, hi_y - lo_y)
    for a in maps:  # one scale for every method (axes sharing would refuse the equal aspect)
        a.set_xlim(lo_x - pad, hi_x + pad)
        a.set_ylim(lo_y - pad, hi_y + pad)
        a.set_aspect("equal", adjustable="box")
    cd = next(iter(by_method.values())).params["collision_distance"]
    dist.axhline(cd, color=fs.COLLISION, ls="--", lw=0.8, label=f"collision ({cd:g} L)")
    dist.set_xlabel("t [L/U]")
    dist.set_ylabel("own ship: nearest\ninside R_safe [L]")
    dist.grid(True)
    first = next(iter(by_method.values()))
    sc = first.scenario
    handles = [Line2D([], [], color=fs.ship_color(i), label=s.name + (" (own)" if i == 0 else ""))
               for i, s in enumerate(sc.ships)]
    handles += fs.legend_handles(r_safe=True, obstacle=bool(sc.obstacles), wall=bool(sc.walls), land=bool(sc.land),
                                 ticks=step, **flags)
    key = fig.add_subplot(gs[rows - 1, cols - 1] if spare else gs[rows, cols - 1]) if cols > 1 else None
    if key is None:
        dist.legend(loc="upper right")
    else:
        key.axis("off")
        lines = dist.get_legend_handles_labels()
        key.add_artist(key.legend(*lines, loc="upper center", ncols=1 if spare else 2, fontsize=5.5,
                                  title="own ship's distance"))
        key.legend(handles=handles, loc="lower center", ncols=2, fontsize=5.5)
    if title:
        fig.suptitle(title, fontsize=8.5)
    fs.save(fig, path)
    return fig


_METHOD_STYLES = tuple(dict(color=c, ls=ls) for c, ls in zip(
    ("#000000", "#666666", "#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#8C564B"),
    ("-", "--", "-", "-.", ":", "-", "--", "-.")))
"""Line style of each method in the distance panel (the maps keep the colour per ship)."""
