"""The paper's five-panel figure of the statistical analysis, plus the own ship's COLREG compliance, drawn from a
:class:`~mmg_casadi.montecarlo.results.Summary`.

Panels: success rate, computation time per guidance call, time to goal, control effort (CE), mean
cross-track error (MCTE) and the share of runs (with a classified encounter) in which the own ship kept the
COLREGs (not in the paper), each against the environment number, one series per method with 95 % confidence
intervals as error bars. The figure is built with :class:`matplotlib.figure.Figure` directly (no pyplot, no
global backend switch), so it works headless.
"""

from __future__ import annotations

import math
from pathlib import Path

from matplotlib.figure import Figure

from mmg_casadi.errors import InputError
from mmg_casadi.figstyle import PAGE, save, style
from mmg_casadi.montecarlo.results import Summary

PANELS: tuple[tuple[str, str, str, float], ...] = (
    ("success", "Success rate", "Success rate [%]", 100.0),
    ("guidance_call_us", "Computation effort", "Time per guidance call [µs]", 1.0),
    ("time_to_goal", "Time to reach the goal", "Time to goal [L/U]", 1.0),
    ("ce", "Control effort (CE)", "CE [-]", 1.0),
    ("mcte", "Mean cross-track error (MCTE)", "MCTE [L]", 1.0),
    ("colregs_encounter", "Own ship COLREG encounters kept (risky encounters)", "Kept [%]", 100.0),
)
"""(metric, title, y label, scale) of each panel; the success rate is shown in percent."""

_MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


def _columns(metric: str) -> tuple[str, str, str]:
    if metric in ("success", "colregs_encounter"):
        return f"{metric}_rate", f"{metric}_ci_low", f"{metric}_ci_high"
    return f"{metric}_mean", f"{metric}_ci_low", f"{metric}_ci_high"


def _nan_to_zero(x: float) -> float:
    return 0.0 if x is None or not math.isfinite(x) else x


def plot_statistics(summary, path=None) -> Figure:
    """Draw the six-panel statistics figure; save it if ``path`` is given.

    Parameters
    ----------
    summary : Summary or list of dict
        Output of :func:`mmg_casadi.montecarlo.results.summarize` (or its ``rows``).
    path : str or Path, optional
        File to save to; the format follows the extension (png, pdf, svg, ...).

    Returns
    -------
    matplotlib.figure.Figure
        The figure: six panels (success rate, guidance-call time, time to goal, CE, MCTE, COLREG encounters kept)
        over the environments, one line per method with its 95 % intervals.

    Examples
    --------
    >>> from mmg_casadi.montecarlo.results import summarize
    >>> rows = [{"environment": e, "method": m, "run": r, "success": r != 0, "time_to_goal": 60.0 + r,
    ...          "ce": 0.1, "mcte": 0.2, "guidance_call_us": 3.0}
    ...         for e in (1, 2) for m in ("apf", "modified-vortex") for r in range(5)]
    >>> fig = plot_statistics(summarize(rows))
    >>> len(fig.axes)
    6
    """
    if isinstance(summary, Summary):
        rows = summary.rows
    elif isinstance(summary, (list, tuple)) and all(isinstance(r, dict) for r in summary):
        rows = list(summary)
    else:
        raise InputError("summary", "a Summary or a list of summary rows", type(summary).__name__)
    if not rows:
        raise InputError("summary", "at least one (environment, method) row", "an empty summary")
    with style():
        return _plot(rows, path)


def _plot(rows, path) -> Figure:
    methods = list(dict.fromkeys(r["method"] for r in rows))
    envs = sorted({int(r["environment"]) for r in rows})
    by_method = len(envs) == 1  # one environment: the methods along the abscissa, not a lone tick
    fig = Figure(figsize=(PAGE, 1.05 * PAGE), layout="constrained")
    grid = fig.add_gridspec(3, 2)
    slots = [grid[0, 0], grid[1, 0], grid[1, 1], grid[2, 0], grid[2, 1], grid[0, 1]]
    width = 0.3
    offsets = [width * (i - (len(methods) - 1) / 2) / max(len(methods), 1) for i in range(len(methods))]
    for slot, (metric, title, ylabel, scale) in zip(slots, PANELS):
        ax = fig.add_subplot(slot)
        mean_col, low_col, high_col = _columns(metric)
        for i, method in enumerate(methods):
            by_env = {int(r["environment"]): r for r in rows if r["method"] == method}
            xs, ys, lo, hi = [], [], [], []
            for env in envs:
                r = by_env.get(env)
                if r is None or r.get(mean_col) is None or not math.isfinite(r[mean_col]):
                    continue
                y = scale * r[mean_col]
                xs.append(i if by_method else env + offsets[i])
                ys.append(y)
                lo.append(_nan_to_zero(y - scale * r[low_col]))
                hi.append(_nan_to_zero(scale * r[high_col] - y))
            ax.errorbar(xs, ys, yerr=[lo, hi], marker=_MARKERS[i % len(_MARKERS)], linestyle="-", capsize=2.5,
                        ms=3.5, color=SERIES[i % len(SERIES)], label=str(method))
        ax.set_title(title)
        ax.set_ylabel(ylabel)
        if by_method:
            ax.set_xticks(range(len(methods)), methods, rotation=20, ha="right")
            ax.set_xlim(-0.6, len(methods) - 0.4)
            ax.set_xlabel(f"method (environment {envs[0]})")
        else:
            ax.set_xticks(envs)
            ax.set_xlabel("environment (1-5 the paper's, 6 a strait)")
        ax.grid(True)
        if metric == "success" and not by_method:
            ax.legend(loc="best")
    if path is not None:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        save(fig, path)
    return fig


SERIES = ("#000000", "#0072B2", "#E69F00", "#009E73", "#CC79A7", "#56B4E9", "#8C564B", "#7F7F7F")
"""Colour of each method's series."""
