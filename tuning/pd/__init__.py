"""PD heading-controller design from the linear yaw model, checked on the nonlinear model.

Control law (paper, section "Heading control"): ``δ_c = -K_p e - K_d r`` with ``e = ψ - ψ_d``, saturated at
±35°, derivative on the measured yaw rate; the rudder follows through the first-order steering gear
(T_δ = 1). Everything is non-dimensional in design-speed units (time L/U_des, r in U_des/L).

Modules, one job each:

:mod:`tuning.pd.analysis`
    the linear closed loop: poles, damping, stability margins, linear heading step.
:mod:`tuning.pd.design`
    the gain design: specification, pole placement or first-order Nomoto, default ω_n, given gains analysed.
:mod:`tuning.pd.gain_map`
    linear step metrics over a (K_p, K_d) grid and where the paper's gains sit.
:mod:`tuning.pd.verification`
    a design checked on the nonlinear model: heading steps and the waypoint square.
:mod:`tuning.pd.plots`
    figures: root locus, linear against nonlinear step, overshoot map.

The public names of these modules are re-exported here, so ``from tuning.pd import design_pd`` keeps working;
code in this repository imports from the module that defines each name.
"""

from .analysis import (DT, PHASE_CROSSOVER_MAX, SETTLING, LoopAnalysis, StepResponse, analyse_loop, closed_loop,
                       linear_step)
from .design import (DELTA_MAX_DEG, DOMINANCE, METHODS, PAPER_GAINS, PdDesign, PdSpec, analyse_gains, design_pd,
                     place_pair, second_order_overshoot, wn_limits)
from .gain_map import GainMap, grid_step_metrics, paper_gains_map
from .plots import plot_gain_map, plot_root_locus, plot_step
from .verification import NonlinearCheck, nonlinear_step, verify_nonlinear, waypoint_square

__all__ = [
    "DELTA_MAX_DEG", "DOMINANCE", "DT", "METHODS", "PAPER_GAINS", "PHASE_CROSSOVER_MAX", "SETTLING",
    "GainMap", "LoopAnalysis", "NonlinearCheck", "PdDesign", "PdSpec", "StepResponse",
    "analyse_gains", "analyse_loop", "closed_loop", "design_pd", "grid_step_metrics", "linear_step",
    "nonlinear_step", "paper_gains_map", "place_pair", "plot_gain_map", "plot_root_locus", "plot_step",
    "second_order_overshoot", "verify_nonlinear", "waypoint_square", "wn_limits",
]
