"""What a collision-avoidance method is: the inputs its guidance builder sees (:class:`GuidanceInputs`), the
:class:`Command` it returns and its declaration (:class:`Method`). The registry of methods is
:mod:`mmg_casadi.guidance.methods`; the how-to "Write your own method" (docs/howto/own_method.md) shows a whole one.

A method's **builder** is a pure function ``GuidanceInputs -> Command`` of CasADi expressions. It is called once,
when the closed-loop step of a scenario shape is built (symbolically, never per time step), and its expressions are
compiled into the step. It sees one ship (:class:`GuidanceInputs`: own position, velocity, heading, speed, the
waypoint being tracked, the neighbours' positions, velocities, radii and the 0/1 mask ``active`` of those within
R_safe, the step's named parameters ``P``) and returns a :class:`Command`: a 2×1 **desired-heading vector** (its
direction is the heading ordered; it need not be a unit vector), optionally a propeller speed and the next value of
its memory rows. Returning a bare vector is an error: wrap it, ``Command(vec)``.

When the builder is in charge: while any neighbour is within R_safe (or a wall within its range, or land within the
ship's look-ahead, :mod:`mmg_casadi.guidance.land_ahead`), or while the method's ``engaged`` says so. The closed loop adds the channel walls' field to the heading vector and steers along
the sum with the PD heading controller; outside R_safe the ship follows ILOS along her waypoints at her service
propeller speed (a method may limit ILOS's turn, ``turn_limit``). A method with ``commands_speed`` orders a propeller
speed (rev/min) that the engine (:func:`mmg_casadi.vessel.actuators.engine_step`) follows at its rate, clipped to
dead slow ahead .. maximum rpm; any other method keeps the service propeller speed exactly.

Numbers the builder reads come from ``g.P`` by name: the closed loop's parameters
(:data:`~mmg_casadi.closed_loop.layout.GLOBAL_PARAMS`: ``r_safe``, ``collision_distance``, ``lam_sink``, ...), the
``inputs`` the method lists (table parameters only this method reads) and the method's own parameters (``params``;
each a :class:`~mmg_casadi.param_spec.Param` with default, range, unit, meaning and source, named with the method's
``prefix``). Its own parameters join the one parameter table (:data:`mmg_casadi.params.PARAMETERS`, group = the
method's name) while the method is registered, so scenario files, ``--set``, ``--params``, ``mmg-casadi params``,
``study sweep`` and the tuners reach them, and a run none of whose ships uses the method refuses them
(:func:`~mmg_casadi.guidance.methods.check_used`). A numeric parameter is an input of the compiled step (changing it
does not recompile; a name ending in ``_deg`` reaches the builder in rad without the suffix); a ``structural`` one (an
int, choice or bool that changes the shape, e.g. a number of candidates) is a field of the step's shape, read with
``g.layout.option(name)``.

``groups`` lists the parameter groups (:func:`mmg_casadi.params.groups`) whose parameters the builder reads: they are
the method's parameters for :func:`~mmg_casadi.guidance.methods.check_used` (a method with ``params`` owns its own
group without listing it). ``memory`` names state rows the method carries from step to step (rad; each starts at the
ship's heading and is reset to the heading after a step in which the method was not in charge); the builder reads them
in ``g.memory`` and returns their next values in ``Command.memory``.

Examples
--------
>>> import casadi as ca
>>> def ahead(g):  # steer the present heading: a ship that keeps her course while anything is near
...     return Command(ca.vertcat(ca.cos(g.psi), ca.sin(g.psi)))
>>> m = Method("keep-course", ahead, (), "doctest")
>>> m.command_size(), m.step_inputs, m.param_prefix
(2, (), 'keep_course_')
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import Callable

import casadi as ca


def input_name(name: str) -> str:
    """The step input of table parameter ``name``: an angle ``*_deg`` enters in rad without the suffix.

    Parameters
    ----------
    name : str
        A parameter of the table.

    Returns
    -------
    str
        ``name`` without a trailing ``_deg``.

    Examples
    --------
    >>> input_name("cv_dpsi_free_deg"), input_name("r_safe")
    ('cv_dpsi_free', 'r_safe')
    """
    return name[:-4] if name.endswith("_deg") else name



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
    own : dict, optional
        Only for a method with ``own_state``: the ship's own state and engine, by name: ``u``, ``v`` (U, through
        the water), ``r`` (rad per L/U), ``delta`` (rudder angle, rad), ``n_prop`` (rev/min), ``rpm_min``,
        ``rpm_max`` (the propeller speeds a method may order), ``engine_rate`` (rev/min per L/U) and
        ``engine_lag`` (L/U); empty for every other method.
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
    own: dict = dataclasses.field(default_factory=dict)


OWN_STATE: tuple[str, ...] = ("u", "v", "r", "delta", "n_prop", "rpm_min", "rpm_max", "engine_rate", "engine_lag")
"""The entries of :attr:`GuidanceInputs.own`, in the order the sparse step passes them."""


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
    """One registered method (the contract is in the module notes of :mod:`mmg_casadi.guidance.methods`).

    Parameters
    ----------
    name : str
        Name in scenario files, ``--method`` and the Python API (letters, digits, ``-``, ``_``, ``.``).
    builder : callable or None
        ``GuidanceInputs -> Command`` (a :class:`Command`, never a bare vector), called once when a closed-loop
        step is built; ``None`` for pure ILOS waypoint tracking.
    groups : tuple of str
        Parameter groups (:func:`mmg_casadi.params.groups`) whose parameters the builder reads; a run may set those
        parameters only if one of its ships uses a method that lists the group
        (:func:`~mmg_casadi.guidance.methods.check_used`).
    source : str
        Where the method comes from (a paper and its equations, or "ours: ...").
    inputs : tuple of str
        Numeric step inputs only this method reads (names of :data:`GuidanceInputs.P`, table angles in rad
        without the ``_deg`` suffix); they enter the compiled step only of layouts where a ship uses the method,
        so adding a method leaves every other compiled closed loop unchanged. The method's own numeric
        ``params`` are inputs without being listed here (:attr:`step_inputs`).
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
    sensing : str or None
        One of the method's inputs: the builder gets the neighbours within this range (L) as active, whatever
        R_safe (a planner's own sensing range; with ``engaged`` it also stays in charge beyond R_safe); None: R_safe
        (or ``lookout``). At most one of ``lookout`` and ``sensing``.
    engaged : callable or None
        ``memory -> SX``, from the method's memory rows after the step (by name): 1 while the method steers although
        no neighbour is within R_safe (an encounter with a ship within its lookout), so the closed loop neither
        hands the ship to ILOS nor resets the memory; None: the method steers only with a neighbour within R_safe.
    params : tuple of Param
        The method's own parameters (:class:`~mmg_casadi.param_spec.Param`: name, default, range, unit, meaning, source),
        each named with ``prefix``; :func:`~mmg_casadi.guidance.methods.register` enters them into the parameter table
        as the group named after the method (their ``group`` may be left empty). Numeric ones are step inputs (in
        ``g.P``), ``structural`` ones fields of the step's shape (``g.layout.option(name)``).
    prefix : str or None
        The prefix of every name in ``params``; ``None``: the method's name with ``-`` and ``.`` as ``_``, plus
        ``_`` (``"starboard-rule"`` -> ``"starboard_rule_"``).
    land_test : bool or None
        Whether the builder keeps off land itself, from ``g.walls`` (a land test or a grounding cost). In layouts with
        land the closed loop puts every method in charge while the ship's path ahead reaches land
        (:mod:`mmg_casadi.guidance.land_ahead`); for a builder without a land test of its own it adds the paper's
        wall source at the point of land that path meets to the builder's vector, as it adds the channel walls'
        field. ``None``: true for a method with ``wall_inputs`` (it reads land inputs), false otherwise
        (:attr:`tests_land`).
    rule9 : bool
        The method keeps to the starboard side of a narrow channel or fairway (COLREG Rule 9(a)): in layouts with
        walls or land, ILOS and the builder's goal follow a lane ``bank_clearance`` from the starboard bank of a
        channel at most ``channel_width`` wide (:mod:`mmg_casadi.guidance.fairway`).
    own_state : bool
        The builder also gets the ship's own state and engine (:attr:`GuidanceInputs.own`), e.g. for a planner
        that predicts with a model of the ship.
    tallies : tuple of str
        Memory rows that count events over a run (e.g. solves and failures of a planner): they start at 0, take the
        builder's value while the method steers and keep their value otherwise (never reset to the heading); the
        run's outputs report them (:func:`~mmg_casadi.closed_loop.state.tallies`).
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
    params: tuple = ()
    sensing: str | None = None
    prefix: str | None = None
    land_test: bool | None = None
    rule9: bool = False
    own_state: bool = False
    tallies: tuple[str, ...] = ()

    @property
    def tests_land(self) -> bool:
        """Whether the builder keeps off land itself (``land_test``; by default, whether it has ``wall_inputs``)."""
        return bool(self.wall_inputs) if self.land_test is None else bool(self.land_test)

    @property
    def param_prefix(self) -> str:
        """The prefix of the method's own parameter names (``prefix``, or one made from the name)."""
        return self.prefix if self.prefix is not None else re.sub(r"[-.]", "_", self.name) + "_"

    @property
    def step_inputs(self) -> tuple[str, ...]:
        """Numeric step inputs of the method: ``inputs``, then its own numeric ``params`` (a ``_deg`` name without
        the suffix, in rad), each once."""
        own = tuple(input_name(p.name) for p in self.params if not p.structural)
        return tuple(dict.fromkeys(self.inputs + own))

    @property
    def options(self) -> tuple[str, ...]:
        """Names of the method's own structural parameters (fields of the step's shape,
        ``Layout.options``)."""
        return tuple(p.name for p in self.params if p.structural)

    def owns(self, group: str) -> bool:
        """Whether the method reads the parameters of ``group`` (it lists the group, or the group is its own).

        Parameters
        ----------
        group : str
            A parameter group.

        Returns
        -------
        bool
            True if ``group`` is in :attr:`groups` or is the method's name and it declares ``params``.
        """
        return group in self.groups or (bool(self.params) and group == self.name)

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
