"""A PD design checked on the NONLINEAR model: heading steps to both sides and the paper's waypoint square.

The heading step runs the MMG model with the steering gear and the saturated PD (compiled closed-loop step,
rolled out with ``mapaccum``) from straight running; the linear step of :mod:`tuning.pd.analysis` is its
prediction. The waypoint square is the paper's study (:func:`mmg_casadi.scenarios.run.run_scenario`) with the
given gains.

Every function takes the hull as ``vessel`` (a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel
.toml file; the KCS by default): speeds are fractions of its design speed, times in its L/U_des, and the
waypoint square is sailed by that hull (the scenario's own ship, so the scene's units are its own). The closed loop
of the square sails the library's hulls only, so a hull from a file gets the heading steps and no square.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from mmg_casadi.compiled import compile_function
from mmg_casadi.errors import ParameterError, check_range
from mmg_casadi.guidance.heading_control import pd_heading
from mmg_casadi.scenarios.encounters import waypoint_square as square_scenario
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL, VESSELS, load_vessel
from mmg_casadi.vessel.mmg import NX, STATE_NAMES, build_mmg, propeller_rpm_for_speed, rk4

from ..linear import yaw_subsystem
from .analysis import DT, StepResponse, _step_metrics, linear_step
from .design import DELTA_MAX_DEG, PdDesign


@lru_cache(maxsize=4)
def _heading_loop_step(vessel: str = DEFAULT_VESSEL) -> ca.Function:
    """Compiled step of MMG + steering gear + PD: ``(x[7], p=[psi_d, kp, kd, n_rpm, dt]) -> (x_next, delta_c)``.

    The PD command is held over the RK4 step (sampled control, as in the closed loop of the simulations).
    """
    hull = load_vessel(vessel)
    f = build_mmg(hull.ship, hull.steering)
    x = ca.SX.sym("x", NX)
    p = ca.SX.sym("p", 5)
    psi, r = x[STATE_NAMES.index("psi")], x[STATE_NAMES.index("r")]
    dc = pd_heading(psi, p[0], r, p[1], p[2], math.radians(DELTA_MAX_DEG))
    return compile_function(ca.Function("pd_heading_loop_step", [x, p], [rk4(f, x, (dc, p[3]), p[4]), dc],
                                        ["x", "p"], ["x_next", "delta_c"]), label="the PD heading loop")


def nonlinear_step(kp: float, kd: float, speed: float = 1.0, step_deg: float = 10.0, t_end: float = 60.0, *,
                   vessel: str = DEFAULT_VESSEL) -> StepResponse:
    """Heading step of ``step_deg`` (signed; positive to starboard) on the NONLINEAR model with the PD.

    Straight running at ``speed`` (self-propulsion rpm) is the initial state; the rollout is a ``mapaccum`` of
    the compiled closed-loop step.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    speed : float
        Fraction of the hull's design speed of the initial straight running.
    step_deg : float
        Heading step (degrees; signed, positive to starboard).
    t_end : float
        Horizon (L/U_des), integrated in steps of :data:`~tuning.pd.analysis.DT`.
    vessel : str or pathlib.Path
        The hull: a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel .toml file (default the KCS).

    Returns
    -------
    StepResponse
        Histories of heading, yaw rate, commanded and actual rudder over time (L/U_des) with the step metrics
        (overshoot in %, settling and rise times in L/U_des, peak rudder in degrees).
    """
    n = int(round(t_end / DT))
    F = _heading_loop_step(str(vessel)).mapaccum(n)
    psi_d = math.radians(step_deg)
    x0 = [speed, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    X, U = F(x0, [psi_d, kp, kd, propeller_rpm_for_speed(speed, load_vessel(vessel).ship), DT])
    X = np.hstack([np.asarray(x0)[:, None], np.array(X)])
    dc = np.array(U).ravel()
    dc = np.append(dc, dc[-1])
    t = np.arange(n + 1) * DT
    col = {s: X[STATE_NAMES.index(s)] for s in ("psi", "r", "delta")}
    return StepResponse("nonlinear", psi_d, t, col["psi"], col["r"], dc, col["delta"],
                        **_step_metrics(t, col["psi"], psi_d),
                        peak_rudder_deg=float(np.degrees(np.max(np.abs(dc)))))


@dataclass(frozen=True)
class NonlinearCheck:
    """A design checked on the nonlinear model.

    ``step`` is the nonlinear heading step towards the side the linear model describes (port model: a port
    step, otherwise starboard), ``opposite`` the same step the other way, ``linear`` the linear prediction of
    ``step``; ``square`` holds CE, MCTE, status and time to goal of the waypoint-square study (design speed,
    ILOS defaults) with these gains, or is None.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    speed : float
        Speed of the check, fraction of the design speed.
    step : StepResponse
        Nonlinear heading step towards the side of the linear model.
    opposite : StepResponse
        Nonlinear heading step of the same size the other way.
    linear : StepResponse
        Linear prediction of ``step``.
    square : dict, optional
        CE, MCTE, status and time to goal of the waypoint-square study, or None.
    """

    kp: float
    kd: float
    speed: float
    step: StepResponse = field(repr=False)
    opposite: StepResponse = field(repr=False)
    linear: StepResponse = field(repr=False)
    square: dict | None = None

    def to_dict(self) -> dict:
        return {"kp": self.kp, "kd": self.kd, "speed": self.speed, "step_deg": math.degrees(self.step.psi_d),
                "overshoot_nonlinear": self.step.overshoot, "settling_time_nonlinear": self.step.settling_time,
                "overshoot_opposite": self.opposite.overshoot,
                "settling_time_opposite": self.opposite.settling_time,
                "overshoot_linear": self.linear.overshoot, "settling_time_linear": self.linear.settling_time,
                "peak_rudder_deg_nonlinear": self.step.peak_rudder_deg, "waypoint_square": self.square}


def waypoint_square(kp: float, kd: float, *, vessel: str = DEFAULT_VESSEL) -> dict:
    """CE, MCTE, status and time to goal of the paper's waypoint-square study with PD gains ``kp``, ``kd``.

    The square's own ship is ``vessel``, so the scene is in its units: the square's side and the errors in its
    L, the speed a fraction of its design speed, times in its L/U_des.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    vessel : str
        The hull: a name of :data:`~mmg_casadi.vessel.library.VESSELS` (default the KCS); the closed loop sails
        no hull from a file.

    Returns
    -------
    dict
        The own ship's ``ce``, ``mcte`` (L), ``status`` and ``time_to_goal`` (L/U, None unless reached).
    """
    if str(vessel) not in VESSELS:
        raise ParameterError("vessel", f"one of: {', '.join(VESSELS)} (the closed loop of the waypoint square "
                             "sails library hulls only)", str(vessel))
    sc = square_scenario()
    if str(vessel) != DEFAULT_VESSEL:
        sc = dataclasses.replace(sc, ships=(dataclasses.replace(sc.ships[0], vessel=str(vessel)),))
    own = run_scenario(sc, params={"kp": float(kp), "kd": float(kd)}).metrics["ships"][0]
    return {"ce": own["ce"], "mcte": own["mcte"], "status": own["status"], "time_to_goal": own["time_to_goal"]}


def verify_nonlinear(design: PdDesign, speed: float | None = None, step_deg: float = 10.0, *,
                     square: bool = True, vessel: str | None = None) -> NonlinearCheck:
    """Check ``design`` on the nonlinear model: a heading step both ways and (optionally) the waypoint square.

    Parameters
    ----------
    design : PdDesign
        The design (or analysed gains) to check.
    speed : float, optional
        Fraction of the design speed, in [0.2, 1.2]; the design's speed by default.
    step_deg : float
        Size of the heading step (degrees, in (0, 180]); taken towards the side of the design's model.
    square : bool
        Whether to run the waypoint-square study as well (library hulls only, :func:`waypoint_square`).
    vessel : str or pathlib.Path, optional
        The hull (a name of :data:`~mmg_casadi.vessel.library.VESSELS` or a vessel .toml file); the design's
        (:attr:`~tuning.pd.design.PdDesign.vessel`) by default.

    Returns
    -------
    NonlinearCheck
        Gains, speed, the nonlinear steps towards both sides, the linear step and the square's metrics (None
        without ``square``).

    Examples
    --------
    >>> from tuning.pd.design import PdSpec, design_pd
    >>> d = design_pd(1.0, PdSpec(zeta=0.8))
    >>> c = verify_nonlinear(d, square=False)
    >>> abs(c.step.overshoot - c.linear.overshoot) < 3.0
    True
    """
    speed = design.speed if speed is None else check_range("speed", speed, 0.2, 1.2)
    check_range("step_deg", step_deg, 0.0, 180.0, low_open=True, unit="degrees")
    vessel = design.vessel if vessel is None else str(vessel)
    model = design.model if (design.model is not None and design.model.speed == speed
                             and design.model.vessel == vessel) else yaw_subsystem(speed, design.side, vessel=vessel)
    sign = -1.0 if design.side == "port" else 1.0
    lin = linear_step(model, design.kp, design.kd, sign * step_deg)
    t_end = float(max(40.0, lin.t[-1], 4.0 * np.nan_to_num(lin.settling_time, nan=30.0)))
    if t_end > lin.t[-1] + DT:
        lin = linear_step(model, design.kp, design.kd, sign * step_deg, t_end)
    main = nonlinear_step(design.kp, design.kd, speed, sign * step_deg, t_end, vessel=vessel)
    other = nonlinear_step(design.kp, design.kd, speed, -sign * step_deg, t_end, vessel=vessel)
    sq = waypoint_square(design.kp, design.kd, vessel=vessel) if square else None
    return NonlinearCheck(design.kp, design.kd, speed, main, other, lin, sq)
