"""The method registry: each collision-avoidance method's name, guidance builder and parameters.

The closed-loop step (:mod:`mmg_casadi.closed_loop.step`), the scenario loader, the studies, the Monte Carlo study,
the tuners, the benchmarks and the CLI all read the one live registry :data:`METHODS`; adding a method is one
:class:`Method` and one call of :func:`register` (a plugin module, :mod:`mmg_casadi.guidance.plugins`, does that
when it is loaded with ``--plugin`` or installed under the entry-point group ``mmg_casadi.methods``).

The contract of a method (what its builder sees and returns, when it is in charge, how it declares its
parameters, groups and memory) is written where it is defined, in :mod:`mmg_casadi.guidance.contract`
(:class:`Method`, :class:`GuidanceInputs`, :class:`Command`; re-exported here and by :mod:`mmg_casadi`).

Examples
--------
>>> NAMES
('inverse-square', 'sink-vortex', 'modified-vortex', 'velocity-obstacle', 'velocity-obstacle-speed', 'none', 'colregs-vortex', 'sb-mpc')
>>> METHODS["modified-vortex"].groups
('sink-vortex', 'modified-vortex')
"""

from __future__ import annotations

from typing import Callable

import contextlib
import contextvars
import dataclasses
import functools
import importlib.metadata
import re

import casadi as ca

from mmg_casadi.guidance import colregs_vortex

from mmg_casadi.guidance import fields

from mmg_casadi.guidance import sb_mpc
from mmg_casadi.guidance import velocity_obstacle
from mmg_casadi.guidance.colregs_encounters import giveway_open
from mmg_casadi.guidance.colregs_vortex import ColregsVortexParams
from mmg_casadi.errors import InputError, ParameterError
from mmg_casadi.guidance.contract import (Command, GuidanceInputs, Method, command_from_vector,  # noqa: F401 (re-exported)
                                         command_vector, input_name)
from mmg_casadi.params import (CLOSED_LOOP_GROUPS, PARAMETERS, Param, add_group, groups as param_groups,
                               on_unknown_parameter, remove_group)
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed


def _inverse_square(g: GuidanceInputs):
    P = g.P
    return Command(fields.inverse_square(g.pos, g.goal, g.nb_pos, g.nb_radius, g.active, k_att=P["k_att"],
                                         k_rep=P["k_rep"], d0=P["d0"]))


def _sink_vortex(g: GuidanceInputs):
    P = g.P
    return Command(fields.sink_vortex(g.pos, g.goal, g.nb_pos, g.active, lam_sink=P["lam_sink"], k_vor=P["k_vor"]))


def _modified_vortex(g: GuidanceInputs):
    P = g.P
    return Command(fields.modified_vortex(g.pos, g.psi, g.vel, g.goal, g.nb_pos, g.nb_vel, g.active,
                                          lam_sink=P["lam_sink"], k_vor0=P["k_vor0"], r_safe=P["r_safe"],
                                          r_tol=P["r_tol_vortex"], gamma_max=P["gamma_max"],
                                          smooth=g.layout.smooth))


_CV_FIELDS = tuple(f.name for f in dataclasses.fields(ColregsVortexParams))


def _cv_input(g: GuidanceInputs, name: str):
    """colregs-vortex's threshold ``name`` from the step inputs; the in-extremis cut is the number 0 in a layout
    without it (``Layout.cv_extremis``), so its test is not built."""
    if name == "speed_extremis" and not g.layout.cv_extremis:
        return 0.0
    return g.P[f"cv_{name}"]


def _colregs_vortex(g: GuidanceInputs):
    P = g.P
    heading, factor, memory = colregs_vortex.colregs_vortex_command(
        g.pos, g.psi, g.vel, g.goal, g.nb_pos, g.nb_vel, g.active, g.memory, lam_sink=P["lam_sink"],
        k_vor0=P["k_vor0"], r_safe=P["r_safe"], r_tol=P["r_tol_vortex"], gamma_max=P["gamma_max"],
        n_candidates=g.layout.vo_candidates, **{k: _cv_input(g, k) for k in _CV_FIELDS}, **land_test(g))
    return Command(heading, factor * g.service_rpm, memory)


LAND_INPUTS = ("vo_land_horizon", "vo_land_margin")
"""The step inputs of the land test (:func:`land_test`), read only in layouts with walls or land."""


def land_test(g: GuidanceInputs) -> dict:
    """The keyword arguments of the velocity obstacle's land test for one ship's guidance inputs.

    Parameters
    ----------
    g : GuidanceInputs
        The ship's guidance inputs.

    Returns
    -------
    dict
        ``walls``, ``clearance`` (half the beam plus ``vo_land_margin``) and ``horizon`` (``vo_land_horizon``)
        when the layout has walls or land; empty otherwise (no land test).
    """
    if g.walls is None or g.walls.size2() == 0:
        return {}
    return {"walls": g.walls, "clearance": g.half_beam + g.P["vo_land_margin"], "horizon": g.P["vo_land_horizon"]}


def _velocity_obstacle(g: GuidanceInputs):
    D = g.P["collision_distance"]
    land = land_test(g)
    psi_vo = velocity_obstacle.velocity_obstacle(
        g.pos, g.speed, g.goal, g.nb_pos, g.nb_vel, g.active, collision_distance=D,
        n_candidates=g.layout.vo_candidates, cone=g.layout.vo_cone, **land)
    if g.layout.vo_hold:
        psi_vo = velocity_obstacle.hold_heading(psi_vo, g.memory["held_heading"], g.pos, g.speed, g.nb_pos,
                                                g.nb_vel, g.active, collision_distance=D, cone=g.layout.vo_cone,
                                                **land)
    vec = ca.vertcat(ca.cos(psi_vo), ca.sin(psi_vo))
    return Command(vec, memory={"held_heading": ca.atan2(vec[1], vec[0])})


@functools.lru_cache(maxsize=None)
def _rpm_per_speed(vessel: str) -> float:
    """Propeller speed (rev/min) of the steady speed 1 U of ``vessel``, from the model's surge balance."""
    return propeller_rpm_for_speed(1.0, load_vessel(vessel).ship)


def _velocity_obstacle_speed(g: GuidanceInputs):
    lay = g.layout
    vessels = {lay.vessel(i) for i in range(lay.n_ships)}
    if len(vessels) != 1:
        raise ParameterError("vessels", "one vessel for every ship of a layout with velocity-obstacle-speed",
                             sorted(vessels))
    vessel = vessels.pop()
    dead_slow = g.P["engine_dead_slow"] * load_vessel(vessel).ship.n_design_rpm
    levels = velocity_obstacle.speed_levels(g.service_rpm, dead_slow, _rpm_per_speed(vessel), lay.vo_speed_levels)
    D = g.P["collision_distance"]
    land = land_test(g)
    psi, rpm, _ = velocity_obstacle.velocity_obstacle_speed(
        g.pos, g.goal, g.nb_pos, g.nb_vel, g.active, levels=levels, collision_distance=D,
        n_candidates=lay.vo_candidates, speed_weight=g.P["vo_speed_weight"], cone=lay.vo_cone, **land)
    if lay.vo_hold:  # keep the remembered heading, at the service speed, while it stays clear at that speed
        m = g.nb_pos.size2()
        hold = (ca.sum2(g.active) > 0 if m else 0) * velocity_obstacle.heading_feasible(
            g.pos, levels[0][1], g.memory["held_heading"], g.nb_pos, g.nb_vel, g.active, collision_distance=D,
            cone=lay.vo_cone, **land)
        psi = ca.if_else(hold, g.memory["held_heading"], psi)
        rpm = ca.if_else(hold, levels[0][0], rpm)
    vec = ca.vertcat(ca.cos(psi), ca.sin(psi))
    return Command(vec, rpm=rpm, memory={"held_heading": ca.atan2(vec[1], vec[0])})


METHODS: dict[str, Method] = {m.name: m for m in (
    Method("inverse-square", _inverse_square, ("inverse-square",), "paper §4.1, eqs. (attractive)–(repulsive)"),
    Method("sink-vortex", _sink_vortex, ("sink-vortex",), "paper §4.2, eqs. (sink)–(vortex)"),
    Method("modified-vortex", _modified_vortex, ("sink-vortex", "modified-vortex"),
           "paper §4.3, eqs. (modified_vortex)–(factor_f)"),
    Method("velocity-obstacle", _velocity_obstacle, ("velocity-obstacle",),
           "Huang et al. 2018 (Ocean Eng. 151), the paper's baseline: headings at constant speed",
           memory=("held_heading",), wall_inputs=LAND_INPUTS),
    Method("velocity-obstacle-speed", _velocity_obstacle_speed, ("velocity-obstacle",),
           "Huang et al. 2018 (Ocean Eng. 151) with speed changes: the heading search at each of vo_speed_levels "
           "steady speeds, the admissible velocity closest to the preferred one (plus vo_speed_weight per unit of "
           "slowing); the paper's baseline keeps its speed",
           inputs=("vo_speed_weight", "engine_dead_slow"), memory=("held_heading",), commands_speed=True,
           wall_inputs=LAND_INPUTS),
    Method("none", None, (), "ILOS waypoint tracking only (a ship that holds its course)"),
    Method("colregs-vortex", _colregs_vortex, ("sink-vortex", "modified-vortex", "colregs-vortex", "velocity-obstacle"),
           "ours: the modified vortex with COLREG Rules 8, 13 and 17 (mmg_casadi.guidance.colregs_vortex)",
           inputs=(*(f"cv_{k}" for k in _CV_FIELDS), "cv_r_look"), goal_capture=True, memory=colregs_vortex.MEMORY,
           commands_speed=True, wall_inputs=LAND_INPUTS, turn_limit="cv_dpsi_free", lookout="cv_r_look",
           engaged=giveway_open, rule9=True),
    Method(sb_mpc.NAME, sb_mpc.sb_mpc_command, (),
           "Johansen, Perez & Cristofaro 2016 (IEEE T-ITS 17(12)): scenario-based MPC over course offsets and "
           "propulsion levels, with the transitional (Hagen et al. 2018) and grounding (Tengesdal et al. 2022) "
           "costs (mmg_casadi.guidance.sb_mpc)",
           inputs=("engine_dead_slow",), goal_capture=True, memory=sb_mpc.MEMORY, commands_speed=True,
           engaged=sb_mpc.engaged, params=sb_mpc.PARAMS, sensing="sb_mpc_range"),
)}
"""Every method, by name (:func:`register` adds one)."""

NAMES: tuple[str, ...] = tuple(METHODS)
"""Method names in registry order (the shipped methods)."""

PLANNERS: tuple[str, ...] = ("sb-mpc",)
"""Shipped predictive planners: methods that the quick studies (``mmg-casadi study all``) do not run unless asked
(``--methods``); their place is the Monte Carlo study."""

AVOIDING: tuple[str, ...] = tuple(n for n, m in METHODS.items() if m.builder is not None and n not in PLANNERS)
"""Shipped reactive methods that avoid collisions (all but ``"none"`` and the :data:`PLANNERS`): the quick
studies' default."""

PAPER_STATISTICS: tuple[str, ...] = ("modified-vortex", "inverse-square", "velocity-obstacle")
"""Methods compared by the paper's statistical analysis."""

PAPER: tuple[str, ...] = ("inverse-square", "sink-vortex", "modified-vortex", "velocity-obstacle")
"""The methods of the paper (the studies' defaults compare these)."""

DEFAULT = "modified-vortex"
"""The method of a scenario that names none: the paper's proposed modified sink-vortex field."""


_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]*")
"""A method name: what scenario files, ``--methods`` lists (comma-separated) and file names can carry."""


def _check_method(method: Method) -> Method:
    """``method`` with its own parameters' group set to its name, or an InputError naming the first bad field."""
    if not isinstance(method, Method):
        raise InputError("method", "a mmg_casadi.Method", type(method).__name__)
    if not isinstance(method.name, str) or not _NAME.fullmatch(method.name):
        raise InputError("method.name", "letters, digits, '-', '_' or '.', starting with a letter or digit",
                         method.name)
    if method.builder is not None and not callable(method.builder):
        raise InputError("method.builder", "a callable GuidanceInputs -> Command, or None", method.builder)
    bad_group = [g for g in method.groups if g not in param_groups() and g != method.name]
    if bad_group:
        raise InputError("method.groups", f"parameter groups (one of: {', '.join(param_groups())})", bad_group[0])
    own = []
    prefix = method.param_prefix
    for p in method.params:
        if not isinstance(p, Param):
            raise InputError("method.params", "mmg_casadi.params.Param declarations", p)
        if not p.name.startswith(prefix) or len(p.name) == len(prefix):
            raise InputError("method.params", f"names that start with the method's prefix {prefix!r}", p.name)
        if p.group not in ("", method.name):
            raise InputError(f"method.params.{p.name}.group", f"empty or the method's name {method.name!r}", p.group)
        if p.kind in ("choice", "bool") and not p.structural:
            raise InputError(f"method.params.{p.name}.structural", "True for a choice or a bool (it selects the "
                             "compiled step's shape)", p.structural)
        try:
            p.check(p.default)
        except InputError as err:
            raise InputError(f"method.params.{p.name}.default", err.allowed, p.default) from None
        own.append(dataclasses.replace(p, group=method.name))
    names = [p.name for p in own]
    if len(set(names)) != len(names):
        raise InputError("method.params", "distinct names", names)
    numeric = {input_name(n) for n, q in {**PARAMETERS, **{p.name: p for p in own}}.items()
               if not q.structural and q.kind in ("float", "int")}
    for attr in ("inputs", "wall_inputs"):
        for k in getattr(method, attr):
            if k not in numeric:
                raise InputError(f"method.{attr}", "names of numeric table parameters (see `mmg-casadi params`; "
                                 "angles without _deg)", k)
    if method.lookout is not None and method.sensing is not None:
        raise InputError("method.sensing", "None when the method has a lookout (one of the two ranges)",
                         method.sensing)
    bad_tally = [k for k in method.tallies if k not in method.memory]
    if bad_tally:
        raise InputError("method.tallies", "names of the method's memory rows", bad_tally[0])
    for attr in ("turn_limit", "lookout", "sensing"):
        value = getattr(method, attr)
        if value is not None and value not in method.step_inputs:
            raise InputError(f"method.{attr}", "None or one of the method's inputs "
                             f"({', '.join(method.step_inputs)})", value)
    return dataclasses.replace(method, params=tuple(own))


def _enter_shipped() -> None:
    """Enter the own parameters of the shipped methods that declare some into the parameter table, as
    :func:`register` does for a plugin's."""
    for name, method in list(METHODS.items()):
        if method.params and not any(p.name in PARAMETERS for p in method.params):
            method = _check_method(method)
            add_group(name, method.params)
            METHODS[name] = method


_enter_shipped()


_FORGET: list[Callable] = []
"""Callables that drop in-process caches keyed by method names (the compiled steps of
:mod:`mmg_casadi.closed_loop`), called when a method leaves the registry."""


def forget_on_unregister(*fns: Callable) -> None:
    """Have :func:`unregister` call ``fns`` (e.g. ``functools.lru_cache`` ``cache_clear`` of caches keyed by
    layouts), so a name registered again with another builder never meets a step built for the old one.

    Parameters
    ----------
    *fns : callable
        Functions of no argument.
    """
    _FORGET.extend(fns)


def register(method: Method) -> Method:
    """Add ``method`` to :data:`METHODS` under a new name, with its own parameters in the parameter table.

    A user's method is its builder, its :class:`Method` and this one call; the closed loop, the scenario files,
    the studies on both backends, the tuners and the CLI then accept its name (from a plugin module,
    :mod:`mmg_casadi.guidance.plugins`). Nothing is registered when the method is refused.

    Parameters
    ----------
    method : Method
        The method to add: a name not yet registered (a clash is refused), parameters named with its prefix and
        not yet in the table.

    Returns
    -------
    Method
        The registered entry (``method`` with its parameters' ``group`` set to its name).

    Examples
    --------
    >>> m = register(Method("hold-left", None, (), "doctest", params=(
    ...     Param("hold_left_gain", 1.0, 0.0, None, "", "a gain", "doctest"),)))
    >>> PARAMETERS["hold_left_gain"].group, m.step_inputs
    ('hold-left', ('hold_left_gain',))
    >>> register(m)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: method.name: expected a name not yet registered (not one of: ...), got 'hold-left'
    >>> unregister("hold-left"); "hold_left_gain" in PARAMETERS
    False
    """
    if isinstance(method, Method) and method.name in METHODS:
        raise InputError("method.name", f"a name not yet registered (not one of: {', '.join(METHODS)})",
                         method.name)
    method = _check_method(method)
    if method.params:
        add_group(method.name, method.params)
    METHODS[method.name] = method
    return method


def unregister(name: str) -> None:
    """Remove a method added by :func:`register`, and its parameters from the table (the shipped methods stay).

    Parameters
    ----------
    name : str
        Name of a method added by :func:`register`.
    """
    if name in NAMES:
        raise InputError("method", f"a method added by register (not one of: {', '.join(NAMES)})", name)
    if METHODS.pop(name, None) is not None:
        remove_group(name)
        for forget in _FORGET:
            forget()


ON_DEMAND: dict[str, str] = {"nmpc": "mmg_casadi.guidance.nmpc"}
"""Methods shipped with the package that are registered the first time a run names them or one of their
parameters (:func:`load_on_demand`), by name: the module whose ``METHOD`` is registered. Their parameters enter the
table only then, so the records (``metrics.json``, ``runs.params.json``) of runs that never name them stay exactly
as they were."""


def on_demand_method(name: str) -> Method:
    """The declaration of the on-demand method ``name`` (:data:`ON_DEMAND`), without registering it.

    Parameters
    ----------
    name : str
        A key of :data:`ON_DEMAND`.

    Returns
    -------
    Method
        Its module's ``METHOD``.
    """
    return importlib.import_module(ON_DEMAND[name]).METHOD


def load_on_demand(name) -> bool:
    """Register the on-demand method ``name`` (:data:`ON_DEMAND`) if it is not yet registered.

    Parameters
    ----------
    name : str
        A method name.

    Returns
    -------
    bool
        Whether ``name`` is registered now (False for a name that is neither registered nor on demand).

    Examples
    --------
    >>> load_on_demand("no-such-method")
    False
    """
    if not isinstance(name, str):
        return False
    if name not in METHODS and name in ON_DEMAND:
        register(on_demand_method(name))
    return name in METHODS


def _load_for_parameter(name: str) -> bool:
    """Register the on-demand method whose parameter prefix ``name`` carries (the parameter table's hook)."""
    for method, module in ON_DEMAND.items():
        if method not in METHODS and name.startswith(re.sub(r"[-.]", "_", method) + "_"):
            return load_on_demand(method) and name in PARAMETERS
    return False


on_unknown_parameter(_load_for_parameter)


ENTRY_POINTS = "mmg_casadi.methods"
"""The entry-point group of installed plugins (:mod:`mmg_casadi.guidance.plugins`)."""
_INSTALLED_DONE = False


def load_installed() -> tuple[str, ...]:
    """Load every installed plugin (entry points of the group :data:`ENTRY_POINTS`), once per process.

    An entry point names a module that registers its methods when imported, or a :class:`Method` (or a list of
    them) that is registered here.

    Returns
    -------
    tuple of str
        The methods registered by this call (empty after the first).
    """
    global _INSTALLED_DONE
    if _INSTALLED_DONE:
        return ()
    _INSTALLED_DONE = True
    before = tuple(METHODS)
    for ep in importlib.metadata.entry_points(group=ENTRY_POINTS):
        field = f"entry point {ep.name} ({ep.value})"
        try:
            obj = ep.load()
            for m in [obj] if isinstance(obj, Method) else list(obj) if isinstance(obj, (list, tuple)) else []:
                register(m)
        except InputError as err:
            raise InputError(f"{field}: {err.field}", err.allowed, err.got) from None
        except Exception as err:  # noqa: BLE001 - an installed plugin's own failure, on one line
            raise InputError(field, f"a module that registers methods, or a Method ({type(err).__name__}: {err})",
                             ep.value) from None
    return tuple(n for n in METHODS if n not in before)


def names() -> tuple[str, ...]:
    """The names of every registered method, after loading the installed plugins once (:func:`load_installed`).

    Returns
    -------
    tuple of str
        The shipped methods, then the registered ones, in registration order.

    Examples
    --------
    >>> names()[:2]
    ('inverse-square', 'sink-vortex')
    """
    load_installed()
    return tuple(METHODS)


def get(name, field: str = "method", cls=InputError) -> Method:
    """The registered method ``name``, or ``cls`` (an :class:`~mmg_casadi.errors.InputError`) naming ``field``.

    Parameters
    ----------
    name : str
        Name of the method.
    field : str, default 'method'
        Name of the input field, used in the error message.
    cls : type, default InputError
        Error class for an unknown name (e.g. :class:`~mmg_casadi.errors.ScenarioError` in a file reader).

    Returns
    -------
    Method
        The entry of :data:`METHODS`.

    Examples
    --------
    >>> get("none").builder is None
    True
    >>> get("vortex")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: method: expected one of: inverse-square, sink-vortex, modified-vortex, velocity-obstacle, velocity-obstacle-speed, none, colregs-vortex, sb-mpc, nmpc, got 'vortex'
    """
    if not isinstance(name, str) or (name not in names() and not load_on_demand(name)):
        raise cls(field, f"one of: {', '.join(offered())}", name)
    return METHODS[name]


def offered(name=None) -> tuple[str, ...]:
    """The method names a run may name: the registered ones, then the on-demand ones not yet registered; with
    ``name``, the on-demand method of that name is registered first (:func:`load_on_demand`).

    Parameters
    ----------
    name : object, optional
        A name about to be checked against the result.

    Returns
    -------
    tuple of str
        The names, registered first.

    Examples
    --------
    >>> "nmpc" in offered()
    True
    """
    load_on_demand(name)
    names()
    return tuple(METHODS) + tuple(n for n in ON_DEMAND if n not in METHODS)


def parse_list(value, field: str = "methods") -> tuple[str, ...]:
    """Method names from a comma-separated string or an iterable, checked and deduplicated.

    Parameters
    ----------
    value : str or iterable of str
        Method names, comma-separated or as an iterable.
    field : str, default 'methods'
        Name of the input field, used in the error message.

    Returns
    -------
    tuple of str
        The names in the order given, each once.

    Examples
    --------
    >>> parse_list("none, inverse-square,none")
    ('none', 'inverse-square')
    """
    names()
    allowed = f"a non-empty list of: {', '.join(offered())}"
    if isinstance(value, str):
        value = [m.strip() for m in value.split(",") if m.strip()]
    try:
        items = list(value)
    except TypeError:
        raise InputError(field, allowed, value) from None
    if not items:
        raise InputError(field, allowed, value)
    for m in items:
        if not isinstance(m, str) or (m not in METHODS and not load_on_demand(m)):
            raise InputError(field, allowed, m)
    return tuple(dict.fromkeys(items))


# ------------------------------------------------------------------------ parameters a run may set

_RUN: contextvars.ContextVar = contextvars.ContextVar("mmg_casadi_run_methods", default=None)
"""The methods of the outermost run being set up (:func:`run_of`); nested runs are not checked again."""


def owners(name: str) -> tuple[str, ...]:
    """The registered methods whose builders read parameter ``name``; empty for a parameter every run reads.

    Parameters
    ----------
    name : str
        A parameter of the table.

    Returns
    -------
    tuple of str
        Method names in registry order (empty for a parameter of :data:`~mmg_casadi.params.CLOSED_LOOP_GROUPS`).

    Examples
    --------
    >>> owners("cv_r_look"), owners("r_safe")
    (('colregs-vortex',), ())
    >>> owners("vo_candidates")
    ('velocity-obstacle', 'velocity-obstacle-speed', 'colregs-vortex')
    """
    group = PARAMETERS[name].group
    if group in CLOSED_LOOP_GROUPS:
        return ()
    return tuple(n for n, m in METHODS.items() if m.owns(group))


def check_used(params, methods_used, *, prefix: str = "") -> None:
    """Refuse a parameter of ``params`` that only methods outside ``methods_used`` read.

    A method's parameter (one of the groups it lists, or its own) does nothing in a run none of whose ships uses
    the method, so setting it is refused like any option that does not apply.

    Parameters
    ----------
    params : dict or None
        Parameter overrides by table name (already checked against the table).
    methods_used : iterable of str
        The methods of every ship of the run (own ships and targets; ``"none"`` may be among them).
    prefix : str, optional
        Prepended to the parameter name in the error (e.g. ``"params."``).

    Examples
    --------
    >>> check_used({"cv_r_look": 3.0, "r_safe": 10.0}, ["colregs-vortex"])
    >>> check_used({"cv_r_look": 3.0}, ["modified-vortex", "none"])
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ParameterError: cv_r_look: expected a parameter of a method the run uses (modified-vortex, none; cv_r_look is read by colregs-vortex only), got 3.0
    """
    used = tuple(dict.fromkeys(methods_used))
    for k, v in (params or {}).items():
        if k not in PARAMETERS:
            continue  # the table's check names unknown parameters
        by = owners(k)
        if by and not set(by) & set(used):
            raise ParameterError(f"{prefix}{k}", f"a parameter of a method the run uses ({', '.join(used)}; {k} is "
                                 f"read by {', '.join(by)} only)", v)


def check_run(methods_used, params, *, prefix: str = "") -> None:
    """:func:`check_used` for a run that checks its arguments first (a study), unless it is part of an outer run
    (:func:`run_of`), which checked them against all of its methods.

    Parameters
    ----------
    methods_used : iterable of str
        Every method the run's ships use.
    params : dict or None
        The overrides given to the run.
    prefix : str, optional
        Prepended to the parameter name in an error.
    """
    if _RUN.get() is None:
        check_used(params, methods_used, prefix=prefix)


@contextlib.contextmanager
def run_of(methods_used, params, *, prefix: str = ""):
    """The context of a run whose ships use ``methods_used``, given the overrides ``params``.

    The outermost run (a command, a study, a scenario run from Python) checks the overrides with
    :func:`check_used`; the runs it is made of (a study's scenarios, each with one of its methods) are not checked
    again, so a study of two methods may set a parameter of one of them.

    Parameters
    ----------
    methods_used : iterable of str
        Every method the run's ships use.
    params : dict or None
        The overrides given to the run.
    prefix : str, optional
        Prepended to the parameter name in an error.

    Yields
    ------
    tuple of str
        The methods of the outermost run.
    """
    outer = _RUN.get()
    if outer is not None:
        yield outer
        return
    used = tuple(dict.fromkeys(methods_used))
    check_used(params, used, prefix=prefix)
    token = _RUN.set(used)
    try:
        yield used
    finally:
        _RUN.reset(token)
