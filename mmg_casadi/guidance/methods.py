"""The method registry: each collision-avoidance method's name, guidance builder and parameter groups.

The closed-loop step (:mod:`mmg_casadi.closed_loop.step`), the scenario loader, the studies, the Monte Carlo study,
the benchmarks and the CLI all read :data:`METHODS`; adding a method is one entry here plus its builder.

A builder takes a :class:`GuidanceInputs` (CasADi expressions of one ship and its neighbours inside the
closed-loop step) and returns a :class:`Command`: the 2×1 desired-heading vector of the method and, if the method
declares ``commands_speed``, a desired propeller speed (rev/min), which the closed loop passes through the engine
(:func:`mmg_casadi.vessel.actuators.engine_step`). The closed loop adds the hazards' field (channel walls) and steers
along the sum while any neighbour is within R_safe (or a wall within its range); outside it the ship follows ILOS
at its service propeller speed. A method that needs memory across steps declares its rows (``memory``); the
closed loop adds them to the state of every ship of a layout that uses the method.

Examples
--------
>>> NAMES
('inverse-square', 'sink-vortex', 'modified-vortex', 'velocity-obstacle', 'velocity-obstacle-speed', 'none', 'colregs-vortex')
>>> METHODS["modified-vortex"].groups
('sink-vortex', 'modified-vortex')
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import dataclasses
import functools

import casadi as ca

from mmg_casadi.guidance import colregs_vortex

from mmg_casadi.guidance import fields

from mmg_casadi.guidance import velocity_obstacle
from mmg_casadi.guidance.colregs_encounters import giveway_open
from mmg_casadi.guidance.colregs_vortex import ColregsVortexParams
from mmg_casadi.errors import InputError, ParameterError
from mmg_casadi.vessel.library import load_vessel
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed


@dataclass(frozen=True)
class GuidanceInputs:
    """What a method's builder sees of one ship inside the closed-loop step (CasADi expressions).

    Parameters
    ----------
    pos, vel : SX (2×1)
        Own position (L) and global velocity over the ground (U; through the water plus any current).
    psi, speed : SX
        Own heading (rad) and speed over ground (U).
    goal : SX (2×1)
        The waypoint being tracked (L).
    nb_pos, nb_vel : SX (2×M)
        Neighbours' positions and global velocities over the ground (other ships, then static obstacles with
        zero velocity).
    nb_radius, active : SX (1×M)
        Neighbours' radii (L) and the 0/1 (or smooth) mask of neighbours present within R_safe.
    P : dict
        The step's named numeric parameters (:data:`~mmg_casadi.closed_loop.layout.GLOBAL_PARAMS`, angles in rad).
    layout : Layout
        The closed loop's shape (structural parameters such as the velocity obstacle's candidates and cone).
    memory : dict
        The method's memory rows (:attr:`Method.memory`) at the start of the step, by name.
    service_rpm : SX, optional
        The ship's service propeller speed (rev/min), the speed it sails at when no method commands another.
    walls : SX (4×W), optional
        The layout's wall and land segments (L), given only when it has some (``None`` otherwise, so a method's
        land test exists only in layouts with walls).
    half_beam : SX, optional
        Half the ship's beam (L), given with ``walls``.
    """

    pos: object
    vel: object
    psi: object
    speed: object
    goal: object
    nb_pos: object
    nb_vel: object
    nb_radius: object
    active: object
    P: dict
    layout: object
    memory: dict = dataclasses.field(default_factory=dict)
    service_rpm: object = None
    walls: object = None
    half_beam: object = None


@dataclass(frozen=True)
class Command:
    """What a method commands for one step.

    Parameters
    ----------
    heading : SX (2×1)
        Desired-heading vector (its direction is the desired heading; the closed loop adds the hazards' field).
    rpm : SX, optional
        Desired propeller speed (rev/min); only read for a method with ``commands_speed``; ``None`` keeps the
        ship's service propeller speed.
    memory : dict, optional
        Next value of each of the method's memory rows while it is in charge (by name); when no neighbour is within
        R_safe the closed loop resets every memory row to the ship's heading after the step.
    """

    heading: object
    rpm: object = None
    memory: dict = dataclasses.field(default_factory=dict)


@dataclass(frozen=True)
class Method:
    """One registered method.

    Parameters
    ----------
    name : str
        Name in scenario files, ``--method`` and the Python API.
    builder : callable or None
        ``GuidanceInputs -> 2×1 desired-heading vector``; ``None`` for pure ILOS waypoint tracking.
    groups : tuple of str
        Parameter groups (:data:`mmg_casadi.params.GROUPS`) the builder reads.
    source : str
        Where the method comes from.
    inputs : tuple of str
        Numeric step inputs only this method reads (names of :data:`GuidanceInputs.P`, table angles in rad
        without the ``_deg`` suffix); they enter the compiled step only of layouts where a ship uses the method,
        so adding a method leaves every other compiled closed loop unchanged.
    goal_capture : bool
        A ship that passed its final waypoint outside the acceptance radius turns back to it (the paper's ILOS
        follows the extended last leg for ever; kept for the paper's methods), and an earlier waypoint she passed
        abeam outside it counts as passed (the paper switches only within the radius, so a ship that avoided
        something near a waypoint turns back to it).
    memory : tuple of str
        Names of the method's memory rows (state rows of each ship, rad; see :class:`Command`).
    commands_speed : bool
        The builder's :class:`Command` carries a propeller speed.
    wall_inputs : tuple of str
        Numeric step inputs the method reads only in layouts with walls or land (its land test); they enter the
        compiled step only of such layouts.
    turn_limit : str or None
        One of ``inputs``: while ILOS steers the ship (no neighbour within R_safe) and she is farther than R_safe
        from her next waypoint, the heading ordered is at most this far from her present heading (rad), so she
        turns at a moderate rate; None: ILOS's heading as it is.
    lookout : str or None
        One of ``inputs``: the builder also gets the neighbours within R_safe plus this range (L) as active, and
        ignores those beyond R_safe it has no use for; None: R_safe.
    engaged : callable or None
        ``memory -> SX``, from the method's memory rows after the step (by name): 1 while the method steers although
        no neighbour is within R_safe (an encounter with a ship within its lookout), so the closed loop neither
        hands the ship to ILOS nor resets the memory; None: the method steers only with a neighbour within R_safe.
    """

    name: str
    builder: Callable | None
    groups: tuple[str, ...]
    source: str
    inputs: tuple[str, ...] = ()
    goal_capture: bool = False
    memory: tuple[str, ...] = ()
    commands_speed: bool = False
    wall_inputs: tuple[str, ...] = ()
    turn_limit: str | None = None
    lookout: str | None = None
    engaged: Callable | None = None

    def command_size(self) -> int:
        """Rows of the flat command vector (:func:`command_vector`): heading, rpm if any, memory rows.

        Returns
        -------
        int
            ``2 + commands_speed + len(memory)``.
        """
        return 2 + int(self.commands_speed) + len(self.memory)


def command_vector(method: Method, command) -> ca.SX:
    """A builder's :class:`Command` as one column (heading, then rpm if the method commands speed, then memory).

    Parameters
    ----------
    method : Method
        The method whose builder made ``command``.
    command : Command
        The builder's output.

    Returns
    -------
    casadi.SX
        The column, :meth:`Method.command_size` rows.
    """
    parts = [command.heading]
    if method.commands_speed:
        parts.append(command.rpm)
    parts += [command.memory[k] for k in method.memory]
    return ca.vertcat(*parts)


def command_from_vector(method: Method, v) -> Command:
    """The :class:`Command` of a column made by :func:`command_vector`.

    Parameters
    ----------
    method : Method
        The method whose builder made the column.
    v : SX or MX
        The column (:meth:`Method.command_size` rows).

    Returns
    -------
    Command
        Desired-heading vector (rows 0-1), rpm (None unless the method commands speed) and the memory rows by name.
    """
    k = 2 + int(method.commands_speed)
    return Command(v[0:2], v[2] if method.commands_speed else None,
                   {name: v[k + j] for j, name in enumerate(method.memory)})


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
    Method("colregs-vortex", _colregs_vortex, ("sink-vortex", "modified-vortex", "colregs-vortex"),
           "ours: the modified vortex with COLREG Rules 8, 13 and 17 (mmg_casadi.guidance.colregs_vortex)",
           inputs=(*(f"cv_{k}" for k in _CV_FIELDS), "cv_r_look"), goal_capture=True, memory=colregs_vortex.MEMORY,
           commands_speed=True, wall_inputs=LAND_INPUTS, turn_limit="cv_dpsi_free", lookout="cv_r_look",
           engaged=giveway_open),
)}
"""Every method, by name (:func:`register` adds one)."""

NAMES: tuple[str, ...] = tuple(METHODS)
"""Method names in registry order (the shipped methods)."""

AVOIDING: tuple[str, ...] = tuple(n for n, m in METHODS.items() if m.builder is not None)
"""Shipped methods that avoid collisions (all but ``"none"``)."""

PAPER_STATISTICS: tuple[str, ...] = ("modified-vortex", "inverse-square", "velocity-obstacle")
"""Methods compared by the paper's statistical analysis."""

PAPER: tuple[str, ...] = ("inverse-square", "sink-vortex", "modified-vortex", "velocity-obstacle")
"""The methods of the paper (the studies' defaults compare these)."""

DEFAULT = "modified-vortex"
"""The method of a scenario that names none: the paper's proposed modified sink-vortex field."""


def register(method: Method) -> Method:
    """Add ``method`` to :data:`METHODS` under a new name (the shipped ones cannot be replaced).

    A user's method is its builder and this one call; the closed loop, the scenario files and the studies then
    accept its name.

    Parameters
    ----------
    method : Method
        The method to add.

    Returns
    -------
    Method
        ``method``.
    """
    if method.name in METHODS:
        raise InputError("method.name", f"a name not yet registered (not one of: {', '.join(METHODS)})",
                         method.name)
    for attr in ("turn_limit", "lookout"):
        value = getattr(method, attr)
        if value is not None and value not in method.inputs:
            raise InputError(f"method.{attr}", f"None or one of the method's inputs ({', '.join(method.inputs)})",
                             value)
    METHODS[method.name] = method
    return method


def unregister(name: str) -> None:
    """Remove a method added by :func:`register` (the shipped methods stay).

    Parameters
    ----------
    name : str
        Name of a method added by :func:`register`.
    """
    if name in NAMES:
        raise InputError("method", f"a method added by register (not one of: {', '.join(NAMES)})", name)
    METHODS.pop(name, None)


def get(name, field: str = "method") -> Method:
    """The registered method ``name``, or an :class:`~mmg_casadi.errors.InputError` naming ``field``.

    Parameters
    ----------
    name : str
        Name of the method.
    field : str, default 'method'
        Name of the input field, used in the error message.

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
    mmg_casadi.errors.InputError: method: expected one of: inverse-square, sink-vortex, modified-vortex, velocity-obstacle, velocity-obstacle-speed, none, colregs-vortex, got 'vortex'
    """
    if not isinstance(name, str) or name not in METHODS:
        raise InputError(field, f"one of: {', '.join(METHODS)}", name)
    return METHODS[name]


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
    allowed = f"a non-empty list of: {', '.join(NAMES)}"
    if isinstance(value, str):
        value = [m.strip() for m in value.split(",") if m.strip()]
    try:
        items = list(value)
    except TypeError:
        raise InputError(field, allowed, value) from None
    if not items:
        raise InputError(field, allowed, value)
    for m in items:
        if not isinstance(m, str) or m not in METHODS:
            raise InputError(field, allowed, m)
    return tuple(dict.fromkeys(items))
