"""Figures of a PD design: root locus, linear against nonlinear heading step, overshoot map over (K_p, K_d).

Each function draws on a new :class:`matplotlib.figure.Figure` (no pyplot state) and saves it when given a path.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.figure import Figure

from mmg_casadi.io import save_figure
from mmg_casadi.plotting import FIGURE_DPI
from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL, load_vessel

from ..linear import yaw_subsystem
from .analysis import _gain_row
from .design import PdDesign, _polys
from .gain_map import GainMap
from .verification import NonlinearCheck


def _hull(design: PdDesign) -> str:
    """``", <hull>"`` for a title of a design for another hull than the KCS, else nothing."""
    return "" if design.vessel == DEFAULT_VESSEL else f", {load_vessel(design.vessel).name}"


def _save(fig: Figure, path) -> Figure:
    if path is not None:
        save_figure(fig, path, dpi=FIGURE_DPI)
    return fig


def plot_root_locus(design: PdDesign, path=None, *, paper: PdDesign | None = None) -> Figure:
    """Root locus of the loop with the gain pair scaled by k ∈ [0.01, 100] (design at k = 1), on a Figure.

    Parameters
    ----------
    design : PdDesign
        The design whose gains are scaled.
    path : str or path-like, optional
        Where to save the figure (PNG, 150 dpi); not saved if None.
    paper : PdDesign, optional
        A second gain pair (the paper's) whose locus is drawn as well.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    model = design.model or yaw_subsystem(design.speed, design.side, vessel=design.vessel)
    fig = Figure(figsize=(7, 6))
    ax = fig.add_subplot(1, 1, 1)
    for d, color, label in ((design, "tab:blue", f"design K_p={design.kp:.3g}, K_d={design.kd:.3g}"),
                            (paper, "tab:red", None if paper is None else
                             f"paper K_p={paper.kp:g}, K_d={paper.kd:g}")):
        if d is None:
            continue
        ks = np.geomspace(1e-2, 1e2, 500)
        loci = np.array([np.linalg.eigvals(model.A - model.B @ _gain_row(k * d.kp, k * d.kd)) for k in ks])
        ax.plot(loci.real, loci.imag, ".", ms=1.5, color=color, alpha=0.5)
        p = np.array(d.loop.poles)
        ax.plot(p.real, p.imag, "s", color=color, ms=7, mfc="none", mew=1.5, label=label)
    ol = np.linalg.eigvals(model.A)
    ax.plot(ol.real, ol.imag, "kx", ms=8, label="open-loop poles")
    zeros = np.roots(np.polymul([design.kd, design.kp], _polys(model)[1]))
    ax.plot(zeros.real, zeros.imag, "ko", mfc="none", ms=7, label="loop zeros")
    lim = 1.2 * max(3.0, float(np.max(np.abs(np.array(design.loop.poles)))))
    rho = np.array([0.0, lim])
    th = math.acos(min(design.zeta, 1.0))
    for sgn in (1, -1):
        ax.plot(-rho * math.cos(th), sgn * rho * math.sin(th), "k:", lw=0.8)
    ax.set_xlim(-lim, 0.3 * lim)
    ax.set_ylim(-lim, lim)
    ax.axhline(0, color="k", lw=0.5)
    ax.axvline(0, color="k", lw=0.5)
    ax.set_xlabel("Re s [U/L]")
    ax.set_ylabel("Im s [U/L]")
    ax.set_title(f"Root locus (gains scaled by k), speed {design.speed:g}{_hull(design)}, {design.side} side; "
                 f"ζ = {design.zeta:g}")
    ax.legend(loc="upper left", fontsize=8)
    ax.grid(True, alpha=0.3)
    return _save(fig, path)


def plot_step(design: PdDesign, nonlinear: NonlinearCheck, path=None) -> Figure:
    """Linear vs nonlinear heading step: heading and rudder against time.

    Parameters
    ----------
    design : PdDesign
        The design (its gains label the plot).
    nonlinear : NonlinearCheck
        Nonlinear check of the design (:func:`~tuning.pd.verification.verify_nonlinear`) with the steps to draw.
    path : str or path-like, optional
        Where to save the figure (PNG, 150 dpi); not saved if None.

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    fig = Figure(figsize=(8, 6))
    ax1, ax2 = fig.add_subplot(2, 1, 1), fig.add_subplot(2, 1, 2)
    lin, nl, opp = nonlinear.linear, nonlinear.step, nonlinear.opposite
    s = math.copysign(1.0, nl.psi_d)
    ax1.plot(lin.t, s * np.degrees(lin.psi), "k--", label=f"linear (OS {lin.overshoot:.1f} %)")
    ax1.plot(nl.t, s * np.degrees(nl.psi), "tab:blue", label=f"nonlinear (OS {nl.overshoot:.1f} %)")
    ax1.plot(opp.t, -s * np.degrees(opp.psi), "tab:orange", lw=1,
             label=f"nonlinear, other side (OS {opp.overshoot:.1f} %)")
    ax1.axhline(abs(math.degrees(nl.psi_d)), color="gray", lw=0.6)
    ax1.set_ylabel("|ψ| [deg]")
    ax1.set_title(f"Heading step {abs(math.degrees(nl.psi_d)):g}°: K_p = {design.kp:.3g}, K_d = {design.kd:.3g} "
                  f"(speed {nonlinear.speed:g}{_hull(design)}, {'port' if s < 0 else 'starboard'} step)")
    ax1.legend(fontsize=8)
    ax2.plot(lin.t, s * np.degrees(lin.delta_c), "k--", label="δ_c linear")
    ax2.plot(nl.t, s * np.degrees(nl.delta_c), "tab:blue", lw=0.8, alpha=0.6, label="δ_c nonlinear")
    ax2.plot(nl.t, s * np.degrees(nl.delta), "tab:blue", label="δ nonlinear")
    ax2.set_xlabel("t [L/U_des]")
    ax2.set_ylabel("rudder (step side +) [deg]")
    ax2.legend(fontsize=8)
    for ax in (ax1, ax2):
        ax.grid(True, alpha=0.3)
        ax.set_xlim(0, nl.t[-1])
    fig.tight_layout()
    return _save(fig, path)


def plot_gain_map(gain_map: GainMap, path=None, *, design: PdDesign | None = None) -> Figure:
    """Overshoot contours over (K_p, K_d) with settling-time lines, the paper's gains and the design marked.

    Parameters
    ----------
    gain_map : GainMap
        The grid map (:func:`~tuning.pd.gain_map.paper_gains_map`).
    path : str or path-like, optional
        Where to save the figure (PNG, 150 dpi); not saved if None.
    design : PdDesign, optional
        A design to mark (with its first-order Nomoto gains for a placement design).

    Returns
    -------
    matplotlib.figure.Figure
        The figure (saved to ``path`` when given).
    """
    fig = Figure(figsize=(8, 6))
    ax = fig.add_subplot(1, 1, 1)
    KP, KD = np.meshgrid(gain_map.kp_grid, gain_map.kd_grid)
    os_ = np.ma.masked_invalid(gain_map.overshoot)
    cf = ax.contourf(KP, KD, os_, levels=[0, 0.5, 1, 2, 5, 10, 15, 20, 30, 50, 100], cmap="viridis", extend="max")
    fig.colorbar(cf, ax=ax, label="linear overshoot [%] (10° step)")
    ts = np.ma.masked_invalid(gain_map.settling_time)
    if ts.count():
        cs = ax.contour(KP, KD, ts, levels=[5, 7.5, 10, 15, 20, 30], colors="w", linewidths=0.8)
        ax.clabel(cs, fmt="t_s=%g", fontsize=7)
    p = gain_map.paper
    ax.plot(p.kp, p.kd, "r*", ms=14, mec="k", label=f"paper ({p.kp:g}, {p.kd:g}): OS {p.overshoot:.1f} %")
    if design is not None:
        ax.plot(design.kp, design.kd, "wo", ms=9, mec="k",
                label=f"design ({design.kp:.3g}, {design.kd:.3g}): OS {design.overshoot:.1f} %")
        if design.method == "placement":
            ax.plot(design.kp_nomoto, design.kd_nomoto, "w^", ms=8, mec="k",
                    label=f"Nomoto formula ({design.kp_nomoto:.3g}, {design.kd_nomoto:.3g})")
    ax.set_xlabel("K_p [-]")
    ax.set_ylabel("K_d [L/U]")
    ax.set_xlim(gain_map.kp_grid[0], gain_map.kp_grid[-1])
    ax.set_ylim(gain_map.kd_grid[0], gain_map.kd_grid[-1])
    ax.set_title(f"Linear heading step over (K_p, K_d), speed {p.speed:g}{_hull(p)}, {p.side} side")
    ax.legend(fontsize=8, loc="lower right")
    return _save(fig, path)
