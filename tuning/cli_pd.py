"""``mmg-casadi tune pd``: design the PD heading controller at a speed, compare with the paper's gains.

Writes ``root_locus.png``, ``step.png`` (design), ``step_paper.png``, ``gain_map.png`` and ``metrics.json`` into
``--out``. Overshoots are in percent of the 10° heading step, times in L/U_des; the waypoint-square study runs at
the design speed whatever ``--speed`` is.

The pole-placement design (``kp``, ``kd``) is well damped but slow (it tracks the waypoint square far worse than
the paper's gains); the *recommended* gains (``recommended`` in ``metrics.json``, :mod:`tuning.pd_tracking`)
meet a specification that includes tracking: square CE and MCTE no worse than the paper's gains, then the
best damping (smallest 10° step overshoot) on a (K_p, K_d) grid. ``recommended.better_damped`` says where the
paper's gains sit: how many grid gains track as well and are better damped.

``--vessel`` designs for another hull (a name of ``mmg-casadi vessels`` or a vessel .toml file; the KCS by
default): its linearisation, Nomoto fits, nonlinear steps and waypoint square, the speed a fraction of its design
speed and times in its L/U_des; ``metrics.json`` then names it (``vessel``). The paper's gains are analysed on it
as they are. The waypoint square runs in the closed loop, which sails the library's hulls only: for a hull from a
file ``waypoint_square`` holds nulls and ``recommended`` is null.
"""

from __future__ import annotations

import math
from pathlib import Path

from mmg_casadi.io import write_json
from mmg_casadi.errors import InputError, check_range
from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL, VESSELS, load_vessel

from .linear import fit_nomoto_step
from .pd.design import PdSpec, analyse_gains, design_pd
from .pd.gain_map import paper_gains_map
from .pd.plots import plot_gain_map, plot_root_locus, plot_step
from .pd.verification import verify_nonlinear
from .pd_tracking import design_for_tracking


def _validate(out, speed, zeta, wn) -> tuple[float, float, float | None, Path]:
    speed = check_range("speed", speed, 0.2, 1.2, cls=InputError, unit="(fraction of the design speed)")
    zeta = 0.8 if zeta is None else check_range("zeta", zeta, 0.0, 2.0, low_open=True, cls=InputError)
    if wn is not None:
        wn = check_range("wn", wn, 0.0, None, low_open=True, cls=InputError, unit="(U_des/L)")
    if out is None:
        raise InputError("out", "an output directory")
    return speed, zeta, wn, Path(out)


def _finite(obj):
    """``obj`` with non-finite floats (unsettled or unstable responses, infinite margins) replaced by None."""
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def run(out, *, speed: float = 1.0, zeta: float | None = None, wn: float | None = None,
        tracking_tolerance: float = 0.0, vessel: str = DEFAULT_VESSEL) -> dict:
    """Design, verify and plot; return (and write to ``out/metrics.json``) the metrics.

    Non-finite numbers are written as null.

    Parameters
    ----------
    out : str or Path
        Output directory.
    speed : float
        Speed of the design (fraction of the hull's design speed).
    zeta : float, optional
        Damping ratio (default 0.8).
    wn : float, optional
        Natural frequency (U/L; default: the rule of :mod:`tuning.pd.design`).
    tracking_tolerance : float
        Relative excess of the square's CE and MCTE over the paper gains' that the recommended gains may have
        (0: at least as good; see :mod:`tuning.pd_tracking`).
    vessel : str or pathlib.Path
        The hull: a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel .toml file (default the KCS).

    Returns
    -------
    dict
        The metrics written to ``metrics.json``: the design's gains, ζ, ω_n, Nomoto model and fits, poles, margins,
        overshoots (%), settling times (L/U_des), the paper gains' analysis, the waypoint square and the gains
        recommended for tracking, and ``vessel`` (the hull's name) for another hull than the KCS; non-finite
        numbers as None.
    """
    speed, zeta, wn, out = _validate(out, speed, zeta, wn)
    tracking_tolerance = check_range("tracking_tolerance", tracking_tolerance, 0.0, 1.0, cls=InputError)
    hull = load_vessel(vessel)
    vessel = str(vessel)
    try:
        design = design_pd(speed, PdSpec(zeta=zeta, wn=wn), vessel=vessel)
    except InputError as e:
        if e.field != "wn" or wn is not None:
            raise
        # no --wn was given: the hull, not the option, leaves no natural frequency to place the poles at
        raise InputError("vessel", "a hull whose yaw dynamics leave a natural frequency within the limits of its "
                         "steering gear (or give --wn)", vessel) from None
    gmap = paper_gains_map(speed, vessel=vessel)
    paper = gmap.paper
    square = vessel in VESSELS  # the closed loop sails library hulls only
    check = verify_nonlinear(design, square=square)
    check_paper = verify_nonlinear(paper, square=square)
    fits = {"starboard": fit_nomoto_step(speed, 0.1, vessel=vessel),
            "port": fit_nomoto_step(speed, -0.01, vessel=vessel)}

    out.mkdir(parents=True, exist_ok=True)
    plot_root_locus(design, out / "root_locus.png", paper=paper)
    plot_step(design, check, out / "step.png")
    plot_step(paper, check_paper, out / "step_paper.png")
    plot_gain_map(gmap, out / "gain_map.png", design=design)

    d = design.to_dict()
    metrics = {
        **({} if vessel == DEFAULT_VESSEL else {"vessel": hull.name}),
        "speed": speed,
        "side": design.side,
        "kp": design.kp,
        "kd": design.kd,
        "method": design.method,
        "zeta": design.zeta,
        "wn": design.wn,
        "wn_source": design.wn_source,
        "wn_limits": design.limits,
        "nomoto_K": design.nomoto_K,
        "nomoto_T": design.nomoto_T,
        "nomoto_K_own": d["nomoto_K_own"],
        "nomoto_T_own": d["nomoto_T_own"],
        "nomoto_fit": {side: f.to_dict() for side, f in fits.items()},
        "dominant_zeta": design.loop.dominant_zeta,
        "dominant_wn": design.loop.dominant_wn,
        "poles": d["poles"],
        "margins": {"gain_margin": d["gain_margin"], "gain_margin_db": d["gain_margin_db"],
                    "phase_margin_deg": d["phase_margin"], "w_gain_crossover": d["w_gain_crossover"],
                    "w_phase_crossover": d["w_phase_crossover"]},
        "predicted_overshoot": design.predicted_overshoot,
        "overshoot_linear": design.overshoot,
        "overshoot_nonlinear": check.step.overshoot,
        "overshoot_nonlinear_opposite": check.opposite.overshoot,
        "settling_time_linear": design.settling_time,
        "settling_time_nonlinear": check.step.settling_time,
        "settling_time_nonlinear_opposite": check.opposite.settling_time,
        "step_deg": abs(check.to_dict()["step_deg"]),
        "step_direction": "port" if check.step.psi_d < 0 else "starboard",
        "peak_rudder_deg": design.loop.step.peak_rudder_deg,
        "saturates": design.saturates,
        "nomoto_formula": d.get("nomoto_formula"),
        "paper_gains": {
            "kp": paper.kp, "kd": paper.kd, "zeta": paper.zeta, "wn": paper.wn,
            "dominant_zeta": paper.loop.dominant_zeta, "dominant_wn": paper.loop.dominant_wn,
            "overshoot_linear": paper.overshoot, "overshoot_nonlinear": check_paper.step.overshoot,
            "overshoot_nonlinear_opposite": check_paper.opposite.overshoot,
            "settling_time_linear": paper.settling_time, "settling_time_nonlinear": check_paper.step.settling_time,
            "stable": paper.loop.stable,
            "margins": {"gain_margin": paper.to_dict()["gain_margin"],
                        "phase_margin_deg": paper.loop.phase_margin},
        },
        "waypoint_square": {"design": check.square, "paper_gains": check_paper.square},
    }
    track = design_for_tracking(speed, tolerance=tracking_tolerance, vessel=vessel) if square else None
    metrics["recommended"] = None
    if track is not None:
        rec = verify_nonlinear(analyse_gains(track.kp, track.kd, speed, vessel=vessel), square=False)
        metrics["recommended"] = {**track.to_dict(), "overshoot_nonlinear": rec.step.overshoot,
                                  "overshoot_nonlinear_opposite": rec.opposite.overshoot,
                                  "specification": f"waypoint-square CE and MCTE <= (1 + {tracking_tolerance:g}) x "
                                                   "the paper gains', then the smallest linear 10-degree step "
                                                   "overshoot (tuning/pd_tracking.py)"}
    metrics = _finite(metrics)
    write_json(out / "metrics.json", metrics)
    of = "" if vessel == DEFAULT_VESSEL else f" of the {hull.name}"
    print(f"PD design at speed {speed:g}{of} ({design.method}, zeta {design.zeta:g}, wn {design.wn:.4g} "
          f"from {design.wn_source}): kp = {design.kp:.4g}, kd = {design.kd:.4g}")
    print(f"  Nomoto K = {design.nomoto_K:.4g}, T = {design.nomoto_T:.4g} (design-speed units, {design.side} side); "
          f"overshoot linear {design.overshoot:.2f} %, nonlinear {check.step.overshoot:.2f} %")
    print(f"  paper gains kp = {paper.kp:g}, kd = {paper.kd:g}: dominant zeta {paper.loop.dominant_zeta:.3f}, "
          f"overshoot linear {paper.overshoot:.2f} %, nonlinear {check_paper.step.overshoot:.2f} %")
    if track is None:
        print(f"  waypoint square and recommended gains: not run (the closed loop sails the library's hulls only: "
              f"{', '.join(VESSELS)})")
        print(f"  -> {out}")
        return metrics
    sq, sqp = check.square, check_paper.square
    print(f"  waypoint square: design CE {sq['ce']:.4f} MCTE {sq['mcte']:.4f} ({sq['status']}); "
          f"paper gains CE {sqp['ce']:.4f} MCTE {sqp['mcte']:.4f} ({sqp['status']})")
    print(f"  recommended (square CE, MCTE <= (1 + {tracking_tolerance:g}) x the paper gains', best damped): "
          f"kp = {track.kp:g}, kd = {track.kd:g}: overshoot {track.overshoot:.2f} % "
          f"(paper {track.reference['overshoot']:.2f} %), "
          f"square CE {track.square['ce']:.4f} MCTE {track.square['mcte']:.4f}; {track.better_damped} of "
          f"{track.feasible} grid gains that track as well are better damped than the paper's")
    print(f"  -> {out}")
    return metrics
