"""Wind and current (issue 16): the ILOS integral, the PD gains and the modified vortex under a steady beam
current and a beam wind.

``mmg-casadi study disturbance [--current V] [--wind W] [--methods m,...] [--params P.toml] --out DIR``. "Beam"
is perpendicular to the own ship's initial heading, both disturbances setting it to starboard: the current flows
towards heading + 90°, the wind comes from heading - 90°. Defaults: current 0.1 U_des, wind 15 m/s (1.21 U_des).
The model is :mod:`mmg_casadi.vessel.environment`: guidance sees velocities over the ground, ILOS and the waypoint
switching positions, so the ILOS integral is what compensates the drift (crab-angle compensation off).

Cases:

* **straight leg** (``straight_leg.png``): :data:`LEG_LENGTH` L north with ILOS k = 0 and k = 0.05 (the paper's),
  and k = 0 with crab-angle compensation (``crab_compensation = "on"``), under each disturbance. The steady
  cross-track offset is the mean cross-track error over :data:`STEADY_WINDOW` (the leg is long enough for the
  integral to have settled there: its time constant is about Δ/(k U) = 40 L/U_des); the fraction the integral
  removes is ``1 - offset(k=0.05)/offset(k=0)``, also reported at t = 100 and t = 200.
* **waypoint square** (``square.png``): the paper's square with the paper's PD gains (3.5, 4) and with those of
  ``tune pd`` (:func:`tuning.pd.design.design_pd` at the design speed with the default specification), calm, in the
  current and in the wind: CE and MCTE.
* **encounters** (``encounters/``): the head-on and crossing encounters (COLREG rules 14, 15) in the current and
  in the wind with ``methods`` (default: the modified vortex), as the COLREG study writes them.

``metrics.json`` holds every number and the resolved parameters.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mmg_casadi.scenarios.encounters import colregs_cases, waypoint_square
from mmg_casadi.io import save_figure, write_json
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.errors import InputError
from mmg_casadi.guidance.methods import DEFAULT as DEFAULT_METHOD
from mmg_casadi.guidance.methods import parse_list as parse_methods
from mmg_casadi.params import PARAMETERS, check_value, resolve
from mmg_casadi.plotting import COLORS, FIGURE_DPI, draw_path, marine_axes
from mmg_casadi.scenarios.scenario import scenario_from_dict, with_params
from mmg_casadi.scenarios.run import run_scenario, write_outputs
from tuning.pd.design import PdSpec, design_pd

from ._common import run_cases

LEG_LENGTH = 250.0
"""Straight leg (L): the ship is still sailing at t = 200 L/U_des, five integral time constants."""
STEADY_WINDOW = (150.0, 200.0)
"""Time window (L/U_des) over which the steady cross-track offset is averaged."""
PAPER_GAINS = (PARAMETERS["kp"].default, PARAMETERS["kd"].default)
ILOS_K = PARAMETERS["ilos_k"].default
"""The paper's ILOS integral ratio."""


def beam(current: float, wind: float, heading_deg: float = 0.0) -> dict:
    """The two disturbances, each setting a ship heading ``heading_deg`` to starboard, as table parameters.

    Parameters
    ----------
    current : float
        Current speed (fraction of the design speed).
    wind : float
        True wind speed (m/s).
    heading_deg : float
        The ship's heading (degrees).

    Returns
    -------
    dict
        ``"current"``: ``current_speed`` and ``current_direction_deg`` (heading + 90°); ``"wind"``: ``wind_speed``
        and ``wind_direction_deg`` (heading − 90°, the direction it comes from).

    Examples
    --------
    >>> beam(0.1, 15.0)["wind"]
    {'wind_speed': 15.0, 'wind_direction_deg': -90.0}
    """
    return {"current": {"current_speed": float(current), "current_direction_deg": heading_deg + 90.0},
            "wind": {"wind_speed": float(wind), "wind_direction_deg": heading_deg - 90.0}}


def straight_leg(disturbance: dict, *, ilos_k: float, crab: bool = False, params: dict | None = None):
    """The own ship alone on a straight leg of :data:`LEG_LENGTH` L north from the origin (ILOS + PD).

    Parameters
    ----------
    disturbance : dict
        Environment parameters (e.g. one entry of :func:`beam`).
    ilos_k : float
        ILOS integral ratio k.
    crab : bool
        Crab-angle compensation.
    params : dict, optional
        Further parameter overrides (the case's own values win).

    Returns
    -------
    ScenarioResult
        The simulated leg (:func:`mmg_casadi.scenarios.run.run_scenario`) with its trajectory and metrics.
    """
    d = {"settings": {"method": "none", "t_max": LEG_LENGTH + 20.0},
         "ships": [{"name": "own", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0,
                    "waypoints": [[LEG_LENGTH, 0.0]]}]}
    sc = scenario_from_dict(d, source="straight-leg")
    values = {**(params or {}), **disturbance, "ilos_k": float(ilos_k), "crab_compensation": "on" if crab else "off"}
    return run_scenario(with_params(sc, values))


def cross_track(result) -> tuple[np.ndarray, np.ndarray]:
    """Times and cross-track errors (L, positive to starboard of the path) of the own ship while it sails.

    Parameters
    ----------
    result : ScenarioResult
        A run.

    Returns
    -------
    t : numpy.ndarray
        Times of the guidance steps while the own ship sails (L/U).
    y_e : numpy.ndarray
        Cross-track error at those times (L).
    """
    tr = result.trajectory
    m = tr.sailing_mask()[:-1, 0]
    return tr.t[:-1][m], tr.auxiliary("y_e", 0)[m]


def steady_offset(result, window=STEADY_WINDOW) -> float:
    """Mean cross-track error (L) over the time ``window``.

    Parameters
    ----------
    result : ScenarioResult
        A straight-leg run still sailing at the end of ``window``.
    window : (float, float)
        Start and end time (L/U_des).

    Returns
    -------
    float
        The mean cross-track error (L, positive to starboard).
    """
    t, ye = cross_track(result)
    k = (t >= window[0]) & (t <= window[1])
    if not np.any(k) or t[-1] < window[1]:
        raise ValueError(f"the run does not sail through the window {window}")
    return float(np.mean(ye[k]))


def _at(result, time: float) -> float:
    t, ye = cross_track(result)
    return float(ye[np.searchsorted(t, time)])


def tuned_gains() -> tuple[float, float]:
    """PD gains of ``tune pd`` at the design speed with the default specification (pole placement, ζ = 0.8).

    Returns
    -------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d (rad of rudder per U_des/L of yaw rate).
    """
    d = design_pd(1.0, PdSpec())
    return float(d.kp), float(d.kd)


def _leg_metrics(runs: dict) -> dict:
    out = {}
    for name, r in runs.items():
        out[name] = {"steady_offset_L": steady_offset(r), "y_e_t100_L": _at(r, 100.0), "y_e_t200_L": _at(r, 200.0),
                     "mcte": r.metrics["ships"][0]["mcte"], "ce": r.metrics["ships"][0]["ce"]}
    k0, ki = out["k=0"], out[f"k={ILOS_K:g}"]
    out["integral_removes"] = {
        "steady": 1.0 - ki["steady_offset_L"] / k0["steady_offset_L"],
        "t100": 1.0 - ki["y_e_t100_L"] / k0["y_e_t100_L"],
        "t200": 1.0 - ki["y_e_t200_L"] / k0["y_e_t200_L"]}
    return out


def run(out, *, methods=None, params=None, current: float = 0.1, wind: float = 15.0) -> dict:
    """Run the study (module docstring) and write figures and ``metrics.json`` into ``out``.

    Parameters
    ----------
    out : str or Path
        Output directory.
    methods : iterable of str, optional
        Methods of the encounters (default: the modified vortex).
    params : dict, optional
        Parameter overrides of every run (the cases' own ILOS, PD and environment values win).
    current : float
        Beam current speed (fraction of the design speed).
    wind : float
        Beam true wind speed (m/s).

    Returns
    -------
    dict
        The metrics written to ``metrics.json``: ``params``, ``current``, ``wind_m_s``, ``disturbances``,
        ``straight_leg``, ``square`` and ``encounters``.
    """
    check_value("current_speed", current, field="current", cls=InputError)
    check_value("wind_speed", wind, field="wind", cls=InputError)
    methods = parse_methods(methods or (DEFAULT_METHOD,))
    resolved = resolve(params, prefix="params.")
    # the square has the study's longest horizon: its steps (t_max / dt) are checked before the first run
    build_problem(with_params(waypoint_square(), {**(params or {}), "ilos_k": ILOS_K}))
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    dist = beam(current, wind)
    metrics = {"params": resolved, "current": current, "wind_m_s": wind,
               "disturbances": dist, "straight_leg": {}, "square": {}, "encounters": {}}

    legs = {}
    for dname, d in dist.items():
        legs[dname] = {"k=0": straight_leg(d, ilos_k=0.0, params=params),
                       f"k={ILOS_K:g}": straight_leg(d, ilos_k=ILOS_K, params=params),
                       "k=0, crab": straight_leg(d, ilos_k=0.0, crab=True, params=params)}
        metrics["straight_leg"][dname] = m = _leg_metrics(legs[dname])
        print(f"  straight leg, {dname}: steady offset k=0 {m['k=0']['steady_offset_L']:.4f} L, "
              f"k={ILOS_K:g} {m[f'k={ILOS_K:g}']['steady_offset_L']:.5f} L: the integral removes "
              f"{100 * m['integral_removes']['steady']:.1f} % (at t=100 {100 * m['integral_removes']['t100']:.1f} %)",
              file=sys.stderr)
    _plot_legs(legs, out / "straight_leg.png")

    gains = {"paper": PAPER_GAINS, "tune pd": tuned_gains()}
    metrics["square"]["gains"] = {k: {"kp": v[0], "kd": v[1]} for k, v in gains.items()}
    squares = {}
    for dname, d in {"calm": {}, **dist}.items():
        squares[dname] = {}
        metrics["square"][dname] = {}
        for gname, (kp, kd) in gains.items():
            sc = with_params(waypoint_square(), {**(params or {}), **d, "kp": kp, "kd": kd, "ilos_k": ILOS_K})
            r = run_scenario(sc)
            squares[dname][gname] = r
            own = r.metrics["ships"][0]
            metrics["square"][dname][gname] = {"ce": own["ce"], "mcte": own["mcte"],
                                               "time_to_goal": own["time_to_goal"], "status": own["status"]}
            write_outputs(r, out / "square" / f"{dname}-{gname.replace(' ', '-')}", figure_name="square.png",
                          tracking=True)
            print(f"  square, {dname}, {gname} gains ({kp:.3g}, {kd:.3g}): CE {own['ce']:.4f}, MCTE "
                  f"{own['mcte']:.4f} L, {own['status']}", file=sys.stderr)
    _plot_squares(squares, out / "square.png")

    cases = {}
    for case, sc in colregs_cases().items():
        if case in ("head-on", "crossing"):
            for dname, d in dist.items():
                cases[f"{case}-{dname}"] = with_params(sc, {**(params or {}), **d})
    enc = run_cases(cases, methods, out / "encounters", title="disturbance")
    metrics["encounters"] = {case: {m: {"collision": r["collision"],
                                        "min_distance": min((p["min_distance"] for p in r["pairs"]),
                                                            default=math.nan),
                                        "own": {k: r["ships"][0][k] for k in ("status", "ce", "mcte",
                                                                             "time_to_goal")}}
                                    for m, r in by_m.items()}
                             for case, by_m in enc["cases"].items()}
    write_json(out / "metrics.json", metrics)
    return metrics


def _plot_legs(legs: dict, path) -> Figure:
    fig = Figure(figsize=(6 * len(legs), 4), layout="constrained")
    for col, (dname, runs) in enumerate(legs.items()):
        ax = fig.add_subplot(1, len(legs), col + 1)
        for k, (name, r) in enumerate(runs.items()):
            t, ye = cross_track(r)
            ax.plot(t, ye, color=COLORS[k % len(COLORS)], label=name)
        ax.axvspan(*STEADY_WINDOW, color="0.9", zorder=0, label="steady window")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.set_xlabel("t [L/U]")
        ax.set_ylabel("cross-track error [L]")
        ax.set_title(f"straight leg, beam {dname}", fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    save_figure(fig, path, dpi=FIGURE_DPI)
    return fig


def _plot_squares(squares: dict, path) -> Figure:
    fig = Figure(figsize=(4.5 * len(squares), 4.8), layout="constrained")
    for col, (dname, by_gain) in enumerate(squares.items()):
        ax = fig.add_subplot(1, len(squares), col + 1)
        for k, (gname, r) in enumerate(by_gain.items()):
            tr = r.trajectory
            m = tr.sailing_mask()[:, 0]
            own = r.metrics["ships"][0]
            draw_path(ax, tr.state("x", 0)[m], tr.state("y", 0)[m], tr.state("psi", 0)[m], COLORS[k % len(COLORS)],
                      label=f"{gname}: CE {own['ce']:.3f}, MCTE {own['mcte']:.3f} L", n_outlines=0)
        sc = next(iter(by_gain.values())).scenario
        wps = np.vstack([sc.ships[0].start, np.asarray(sc.ships[0].waypoints)])
        ax.plot(wps[:, 1], wps[:, 0], "k--", lw=0.8)
        marine_axes(ax)
        ax.set_title(f"waypoint square, {dname}", fontsize=10)
        ax.legend(fontsize=7, loc="center")
    save_figure(fig, path, dpi=FIGURE_DPI)
    return fig
