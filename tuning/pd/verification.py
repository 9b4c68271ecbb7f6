"""A PD design checked on the NONLINEAR model: heading steps to both sides and the paper's waypoint square.

The heading step runs the MMG model with the steering gear and the saturated PD (compiled closed-loop step,
rolled out with ``mapaccum``) from straight running; the linear step of :mod:`tuning.pd.analysis` is its
prediction. The waypoint square is the paper's study (:func:`mmg_casadi.scenarios.run.run_scenario`) with the
given gains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import casadi as ca
import numpy as np

from mmg_casadi.compiled import compile_function
from mmg_casadi.errors import check_range
from mmg_casadi.guidance.heading_control import pd_heading
from mmg_casadi.scenarios.encounters import waypoint_square as square_scenario
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.vessel.mmg import NX, STATE_NAMES, build_mmg, propeller_rpm_for_speed, rk4
from mmg_casadi.vessel.ship import load_kcs, load_steering

from ..linear import yaw_subsystem
from .analysis import DT, StepResponse, _step_metrics, linear_step
from .design import DELTA_MAX_DEG, PdDesign


@lru_cache(maxsize=4)
def _heading_loop_step() -> ca.Function:
    """Compiled step of MMG + steering gear + PD: ``(x[7], p=[psi_d, kp, kd, n_rpm, dt]) -> (x_next, delta_c)``.

    The PD command is held over the RK4 step (sampled control, as in the closed loop of the simulations).
    """
    f = build_mmg(load_kcs(), load_steering())
    x = ca.SX.sym("x", NX)
    p = ca.SX.sym("p", 5)
    psi, r = x[STATE_NAMES.index("psi")], x[STATE_NAMES.index("r")]
    dc = pd_heading(psi, p[0], r, p[1], p[2], math.radians(DELTA_MAX_DEG))
    return compile_function(ca.Function("pd_heading_loop_step", [x, p], [rk4(f, x, (dc, p[3]), p[4]), dc],
                                        ["x", "p"], ["x_next", "delta_c"]))


def nonlinear_step(kp: float, kd: float, speed: float = 1.0, step_deg: float = 10.0, t_end: float = 60.0
                   ) -> StepResponse:
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
        Fraction of the design speed of the initial straight running.
    step_deg : float
        Heading step (degrees; signed, positive to starboard).
    t_end : float
        Horizon (L/U_des), integrated in steps of :data:`~tuning.pd.analysis.DT`.
    """
    n = int(round(t_end / DT))
    F = _heading_loop_step().mapaccum(n)
    psi_d = math.radians(step_deg)
    x0 = [speed, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    X, U = F(x0, [psi_d, kp, kd, propeller_rpm_for_speed(speed), DT])
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


def waypoint_square(kp: float, kd: float) -> dict:
    """CE, MCTE, status and time to goal of the paper's waypoint-square study with PD gains ``kp``, ``kd``.

    Parameters
    ----------
    kp : float
        Proportional gain K_p (rad of rudder per rad of heading error).
    kd : float
        Derivative gain K_d on the measured yaw rate (rad of rudder per U_des/L).
    """
    own = run_scenario(square_scenario(), params={"kp": float(kp), "kd": float(kd)}).metrics["ships"][0]
    return {"ce": own["ce"], "mcte": own["mcte"], "status": own["status"], "time_to_goal": own["time_to_goal"]}


def verify_nonlinear(design: PdDesign, speed: float | None = None, step_deg: float = 10.0, *,
                     square: bool = True) -> NonlinearCheck:
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
        Whether to run the waypoint-square study as well.

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
    model = design.model if design.model is not None and design.model.speed == speed else yaw_subsystem(
        speed, design.side)
    sign = -1.0 if design.side == "port" else 1.0
    lin = linear_step(model, design.kp, design.kd, sign * step_deg)
    t_end = float(max(40.0, lin.t[-1], 4.0 * np.nan_to_num(lin.settling_time, nan=30.0)))
    if t_end > lin.t[-1] + DT:
        lin = linear_step(model, design.kp, design.kd, sign * step_deg, t_end)
    main = nonlinear_step(design.kp, design.kd, speed, sign * step_deg, t_end)
    other = nonlinear_step(design.kp, design.kd, speed, -sign * step_deg, t_end)
    sq = waypoint_square(design.kp, design.kd) if square else None
    return NonlinearCheck(design.kp, design.kd, speed, main, other, lin, sq)
