"""mmg-casadi: the KCS MMG manoeuvring model and its collision-avoidance guidance, written in CasADi.

The flat public API::

    import mmg_casadi as mc
    r = mc.run_scenario("head_on.toml", params={"k_vor0": -15})
    r.metrics, r.plot(), r.to_pandas(), r.save("out")

A method of one's own is a builder, a :class:`Method` and :func:`register` (or a plugin file loaded with
:func:`load_plugin` / ``--plugin``); the contract is in :mod:`mmg_casadi.guidance.methods`.

Examples
--------
>>> import mmg_casadi as mc
>>> mc.PARAMETERS["kp"].default, "modified-vortex" in mc.METHODS
(3.5, True)
"""

import sys as _sys

_orig_argv = list(getattr(_sys, "orig_argv", ()))
if ((getattr(_sys, "argv", None) or [""])[0].endswith("mmg-casadi")
        or ("-m", "mmg_casadi.cli") in zip(_orig_argv, _orig_argv[1:])):
    # the command line program: a signal that arrives while the package loads (seconds) is acted on by its main()
    from mmg_casadi.signals import defer_startup_signals as _defer
    _defer()

from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.closed_loop.problem import ClosedLoopModel, Problem, build_problem
from mmg_casadi.closed_loop.simulation import Trajectory, simulate
from mmg_casadi.guidance.contract import Command, GuidanceInputs, Method
from mmg_casadi.guidance.methods import METHODS, register, unregister
from mmg_casadi.guidance.plugins import load as load_plugin
from mmg_casadi.montecarlo.study import run_study
from mmg_casadi.params import PARAMETERS, Param, load_file as load_params, resolve as resolve_params
from mmg_casadi.scenarios.run import ScenarioResult, packaged_scenario, run_scenario
from mmg_casadi.scenarios.scenario import Scenario, load_scenario
from mmg_casadi.vessel.maneuvers import turning_circle, zigzag
from mmg_casadi.vessel.mmg import linearise

__all__ = [
    "ClosedLoopModel", "Command", "GuidanceInputs", "Layout", "METHODS", "Method", "PARAMETERS", "Param", "Problem",
    "Scenario", "ScenarioResult", "Trajectory", "build_problem", "linearise", "load_params", "load_plugin",
    "load_scenario", "packaged_scenario", "register", "resolve_params", "run_scenario", "run_study", "simulate",
    "turning_circle", "unregister", "zigzag",
]
__version__ = "0.3.0"
