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

from mmg_casadi.guidance import methods as registry
from mmg_casadi.io import write_json
from mmg_casadi.params import resolve
from mmg_casadi.plotting import COLORS, FIGURE_DPI, draw_circle, draw_goal, draw_land, draw_path, marine_axes
from mmg_casadi.scenarios.scenario import with_method
from mmg_casadi.scenarios.routes import warning_line
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
            for w in r.metrics["route_warnings"]:
                print(f"  {case:>14s} {m:>18s}: {warning_line(w)}", file=sys.stderr)
            write_outputs(r, out / case / m)
            results[case][m] = r
            metrics["cases"][case][m] = r.metrics
            own = r.metrics["ships"][0]
            dmin = min((p["min_distance"] for p in r.metrics["pairs"]), default=float("nan"))
            print(f"  {case:>14s} {m:>18s}: collision={r.metrics['collision']!s:5s} min distance {dmin:6.2f} L"
                  f"  own CE {own['ce']:.4f} MCTE {own['mcte']:.3f} L", file=sys.stderr)
        plot_comparison(results[case], out / f"{case}.png", title=f"{title} {case}".strip())


def plot_comparison(by_method: dict, path, title="") -> Figure:
    """One panel per method: paths (marine view), R_safe circles around obstacles, goals; plus a distance panel."""
    n = len(by_method)
    fig = Figure(figsize=(4.2 * n, 8), layout="constrained")
    gs = fig.add_gridspec(2, n, height_ratios=[2.2, 1])
    for col, (m, r) in enumerate(by_method.items()):
        ax = fig.add_subplot(gs[0, col])
        tr, sc = r.trajectory, r.scenario
        mask = tr.sailing_mask()
        for i, s in enumerate(sc.ships):
            c = COLORS[i % len(COLORS)]
            k = mask[:, i]
            lab = s.name + (f" ({r.encounter_labels[i]})" if i in r.encounter_labels else "")
            draw_path(ax, tr.state("x", i)[k], tr.state("y", i)[k], tr.state("psi", i)[k], c, label=lab,
                      n_outlines=5)
            g = s.waypoints[-1]
            draw_goal(ax, g[0], g[1], c, tol=r.params["goal_tolerance"])
        for o in sc.obstacles:
            ax.plot(o.position[1], o.position[0], "ko", ms=4)
            draw_circle(ax, o.position[0], o.position[1], r.params["r_safe"], color="r", lw=0.8)
        for w in sc.walls:
            pts = np.asarray(w.points)
            ax.plot(pts[:, 1], pts[:, 0], "k-", lw=2)
        draw_land(ax, sc.land)
        marine_axes(ax)
        kinds = {s["collision_kind"] for s in r.metrics["ships"]}
        st = "GROUNDING" if "land" in kinds else "COLLISION" if r.metrics["collision"] else "no collision"
        ax.set_title(f"{m}: {st}", fontsize=9)
        ax.legend(fontsize=7, loc="best")
        a2 = fig.add_subplot(gs[1, col])
        for (a, b), d in r.pair_distances().items():
            inside = d <= r.params["r_safe"]
            if np.any(inside):
                a2.plot(tr.t, np.where(inside, d, np.nan), label=f"{a}–{b}")
        cd = r.params["collision_distance"]
        a2.axhline(cd, color="k", ls="--", lw=1, label=f"{cd:g} L")
        a2.set_xlabel("t [L/U]")
        a2.set_ylabel("distance inside R_safe [L]")
        a2.grid(True, alpha=0.3)
        a2.legend(fontsize=7)
    if title:
        fig.suptitle(title)
    fig.savefig(path, dpi=FIGURE_DPI)
    return fig
