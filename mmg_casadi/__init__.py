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
    # the command line program: a signal that arrives while the package loads is acted on by its main(); recorded
    # from here on with the signal module alone, then by mmg_casadi.signals (its imports take tens of ms)
    import signal as _signal
    _early: tuple[dict, list] = ({}, [])
    for _s in (_signal.SIGTERM, _signal.SIGHUP, _signal.SIGINT):
        if _signal.getsignal(_s) in (_signal.SIG_DFL, _signal.default_int_handler):
            _early[0][_s] = _signal.getsignal(_s)
            _signal.signal(_s, lambda signum, _frame: _early[1].append(signum))
    from mmg_casadi.signals import defer_startup_signals as _defer
    _defer(program=True, early=_early)

_PUBLIC = {
    "Layout": ("mmg_casadi.closed_loop.layout", "Layout"),
    "Command": ("mmg_casadi.guidance.contract", "Command"),
    "GuidanceInputs": ("mmg_casadi.guidance.contract", "GuidanceInputs"),
    "Method": ("mmg_casadi.guidance.contract", "Method"),
    "ClosedLoopModel": ("mmg_casadi.closed_loop.problem", "ClosedLoopModel"),
    "Problem": ("mmg_casadi.closed_loop.problem", "Problem"),
    "build_problem": ("mmg_casadi.closed_loop.problem", "build_problem"),
    "Trajectory": ("mmg_casadi.closed_loop.simulation", "Trajectory"),
    "simulate": ("mmg_casadi.closed_loop.simulation", "simulate"),
    "METHODS": ("mmg_casadi.guidance.methods", "METHODS"),
    "register": ("mmg_casadi.guidance.methods", "register"),
    "unregister": ("mmg_casadi.guidance.methods", "unregister"),
    "load_plugin": ("mmg_casadi.guidance.plugins", "load"),
    "run_study": ("mmg_casadi.montecarlo.study", "run_study"),
    "PARAMETERS": ("mmg_casadi.params", "PARAMETERS"),
    "Param": ("mmg_casadi.param_spec", "Param"),
    "load_params": ("mmg_casadi.params", "load_file"),
    "resolve_params": ("mmg_casadi.params", "resolve"),
    "ScenarioResult": ("mmg_casadi.scenarios.run", "ScenarioResult"),
    "packaged_scenario": ("mmg_casadi.scenarios.run", "packaged_scenario"),
    "run_scenario": ("mmg_casadi.scenarios.run", "run_scenario"),
    "Scenario": ("mmg_casadi.scenarios.scenario", "Scenario"),
    "load_scenario": ("mmg_casadi.scenarios.scenario", "load_scenario"),
    "turning_circle": ("mmg_casadi.vessel.maneuvers", "turning_circle"),
    "zigzag": ("mmg_casadi.vessel.maneuvers", "zigzag"),
    "linearise": ("mmg_casadi.vessel.mmg", "linearise"),
}
"""The flat public API: name -> (module, attribute). Imported on first use (PEP 562), so ``import mmg_casadi``
loads no CasADi, NumPy or SciPy until a name is used (0.02 s instead of about 1 s)."""

__all__ = sorted(_PUBLIC, key=lambda n: (not n[0].isupper(), n))


def __getattr__(name: str):
    if name not in _PUBLIC:
        raise AttributeError(f"module 'mmg_casadi' has no attribute {name!r}")
    import importlib
    module, attribute = _PUBLIC[name]
    value = getattr(importlib.import_module(module), attribute)
    globals()[name] = value  # later uses are plain attribute lookups
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


__version__ = "0.3.0"
