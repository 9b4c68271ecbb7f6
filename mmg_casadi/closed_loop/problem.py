"""The closed loop declared once: :class:`ClosedLoopModel` (layout + resolved parameters) and the :class:`Problem`
of a scenario, consumed by simulation, the Monte Carlo, Imazu's problems and tuning.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop import state as state_
from mmg_casadi.closed_loop.replay import track_columns
from mmg_casadi.closed_loop.layout import Layout, env_values, is_disturbed, pack_params, step_values
from mmg_casadi.closed_loop.outcome import ship_outcomes
from mmg_casadi.closed_loop.simulation import compiled_step
from mmg_casadi.closed_loop.step import build_closed_loop_step
from mmg_casadi.errors import ParameterError, ScenarioError
from mmg_casadi.guidance import methods
from mmg_casadi.limits import MAX_UNROLLED_OBSTACLE_PAIRS, check_size, check_steps, check_unrolled
from mmg_casadi.params import PARAMETERS, resolve
from mmg_casadi.perception.layer import unused_parameter
from mmg_casadi.traffic import behaviour as traffic_behaviour
from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL, load_vessel, ship_size
from mmg_casadi.vessel.mmg import propeller_rpm_for_speed

@dataclass(frozen=True)
class ClosedLoopModel:
    """The closed loop of one scenario shape, declared once and consumed by simulation, Monte Carlo and tuning.

    Parameters
    ----------
    layout : Layout
        Ships' methods, obstacles, walls, path length and the structural parameters.
    params : dict
        The resolved parameter set (every entry of :data:`mmg_casadi.params.PARAMETERS`).

    Examples
    --------
    >>> m = ClosedLoopModel(Layout(("none",)), resolve())
    >>> m.values["kp"], m.layout.nx == 1 + m.layout.ns
    (3.5, True)
    """

    layout: Layout
    params: dict = field(hash=False, compare=False)

    @property
    def values(self) -> dict:
        """The step's numeric inputs by name (:func:`step_values`)."""
        return step_values(self.params)

    def step(self, *, smooth: float | None = None) -> ca.Function:
        """The exact or smoothed symbolic step ``(x, p) -> (x_next, aux)``.

        Parameters
        ----------
        smooth : float, optional
            ``None`` for the exact switching logic, else the sigmoid sharpness of the smoothed step (tuning).

        Returns
        -------
        casadi.Function
            ``(x, p) -> (x_next, aux)`` of :func:`~mmg_casadi.closed_loop.step.build_closed_loop_step` (dense SX).
        """
        lay = self.layout if smooth is None else dataclasses.replace(self.layout, smooth=float(smooth))
        return build_closed_loop_step(lay)

    def compiled_step(self) -> ca.Function:
        """The natively compiled exact step the rollouts use (its sparse form, cached on disk).

        Returns
        -------
        casadi.Function
            :func:`~mmg_casadi.closed_loop.simulation.compiled_step` of the model's layout.
        """
        return compiled_step(self.layout)

    def pack(self, ships: list[dict], obstacles=(), walls=()) -> np.ndarray:
        """Numeric parameter vector (:func:`pack_params`) with this model's parameter values.

        Parameters
        ----------
        ships : list of dict
            Per ship ``n_rpm``, ``path`` (start then waypoints) and ``stays``.
        obstacles : sequence of (x, y, radius)
            Static obstacles.
        walls : sequence of (ax, ay, bx, by)
            Wall segments.

        Returns
        -------
        numpy.ndarray (np,)
            Parameter vector ``p`` of the layout.
        """
        return pack_params(self.layout, self.values, ships, obstacles, walls,
                           env_values(self.params) if self.layout.disturbed else None)

    def initial_state(self, ships: list[dict]) -> np.ndarray:
        """Scenario state at t = 0 (:func:`initial_state`).

        Parameters
        ----------
        ships : list of dict
            Per ship ``start``, ``heading`` (rad), ``speed`` and ``path``.

        Returns
        -------
        numpy.ndarray (nx,)
            Scenario state at t = 0.
        """
        return state_.initial_state(self.layout, ships, self.params)

    def ship_rows(self, X) -> np.ndarray:
        """Ship rows of scenario states: ``(N, NS)`` for one state, ``(T, N, NS)`` for columns ``(nx, T)``.

        Parameters
        ----------
        X : ndarray
            One scenario state ``(nx,)`` or states as columns ``(nx, T)``.

        Returns
        -------
        numpy.ndarray
            ``(N, NS)`` or ``(T, N, NS)``, the columns named by ``Layout.ship_state``.
        """
        return state_.ship_rows(self.layout, X)

    def state(self, x, name: str, ship: int | None = None):
        """One state variable of every ship (or of ``ship``) in the state(s) ``x``.

        Parameters
        ----------
        x : ndarray
            One scenario state ``(nx,)`` or states as columns ``(nx, T)``.
        name : str
            A name of :attr:`Layout.ship_state <mmg_casadi.closed_loop.layout.Layout.ship_state>`.
        ship : int, optional
            Ship index; all ships if omitted.

        Returns
        -------
        numpy.ndarray
            ``(N,)`` or ``(T, N)`` for all ships, a scalar or ``(T,)`` for ``ship``, in the state's units.
        """
        return state_.state_of(self.layout, x, name, ship)

    def outcomes(self, x_final) -> list[dict]:
        """Per ship: outcome, stalled position, time to goal, CE, MCTE, collision and closest approach.

        Every runner judges a run with this one method (:func:`~mmg_casadi.closed_loop.outcome.ship_outcomes`).

        Parameters
        ----------
        x_final : ndarray (nx,)
            Final scenario state.

        Returns
        -------
        list of dict
            One dict per ship, as :func:`~mmg_casadi.closed_loop.outcome.ship_outcomes` gives them.
        """
        return ship_outcomes(self.layout, x_final, self.params)


@dataclass(frozen=True)
class Problem:
    """A scenario ready to simulate.

    Parameters
    ----------
    model : ClosedLoopModel
        Its closed loop.
    x0 : ndarray (nx,)
        Initial state.
    p : ndarray (np,)
        Parameter vector.
    ships : tuple of dict
        The per-ship dicts given to :func:`pack_params` / :func:`initial_state`.
    """

    model: ClosedLoopModel
    x0: np.ndarray = field(compare=False)
    p: np.ndarray = field(compare=False)
    ships: tuple = field(default=(), compare=False)

    @property
    def layout(self) -> Layout:
        """The model's layout."""
        return self.model.layout

    @property
    def params(self) -> dict:
        """The resolved parameter set."""
        return self.model.params


def build_problem(sc, params: dict | None = None, *, error=None, commanded=(), command_rpm: bool = False) -> Problem:
    """The :class:`Problem` of a scenario: parameters resolved from the table, the scenario's settings and
    ``params`` (which win), the layout from its ships, obstacles and walls.

    Parameters
    ----------
    sc : Scenario
        A validated scenario (:func:`mmg_casadi.scenarios.scenario.load_scenario`).
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`).
    error : type, optional
        Error class for a bad override (default :class:`~mmg_casadi.errors.ParameterError`).
    commanded : iterable of int, optional
        Ships steered from outside (``Layout.commanded``;
        their methods are not used): the environment of :mod:`mmg_casadi.gym` and
        :func:`~mmg_casadi.closed_loop.simulation.simulate` with ``commands``.
    command_rpm : bool, default False
        The commanded ships also order their propeller speed.

    Returns
    -------
    Problem
        The model (layout and resolved parameters), initial state ``x0``, parameter vector ``p`` and per-ship inputs.

    Examples
    --------
    >>> from mmg_casadi.scenarios.scenario import Scenario, Settings, ShipSpec
    >>> sc = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 1, [[50, 0]])])
    >>> pr = build_problem(sc, {"kp": 2.0})
    >>> pr.layout.methods, pr.params["kp"], pr.params["t_max"]
    (('none',), 2.0, 300.0)
    """
    resolved = sc.settings.resolved(params, cls=error or ParameterError)
    methods_ = tuple(sc.method_of(i) for i in range(len(sc.ships)))
    replayed = tuple(i for i, s in enumerate(sc.ships) if getattr(s, "track", None) is not None)
    commanded = tuple(sorted({int(i) for i in commanded}))
    if any(not 0 <= i < len(sc.ships) or i in replayed for i in commanded):
        raise ScenarioError("commanded", f"indices of ships that are not replayed, in [0, {len(sc.ships)})",
                            list(commanded))
    methods_ = tuple("none" if i in replayed or i in commanded else m for i, m in enumerate(methods_))  # not steered
    for i, m in enumerate(methods_):
        methods.get(m, f"ships[{i}].method", ScenarioError)
    walls = []
    for w in sc.walls:
        pts = np.asarray(w.points, float)
        walls += [(a[0], a[1], b[0], b[1]) for a, b in zip(pts[:-1], pts[1:])]
    land = [(a[0], a[1], b[0], b[1]) for poly in sc.land for a, b in poly.edges]
    walls += land  # land edges are the last wall segments (Layout.n_land)
    check_size(len(sc.ships), len(sc.obstacles), len(walls), cls=ScenarioError)
    check_steps(resolved["t_max"], resolved["dt"], cls=error or ParameterError, ships=len(sc.ships))
    check_unrolled(len(sc.ships), resolved["fleet_from_ships"], cls=error or ParameterError)
    if commanded and len(sc.ships) >= resolved["fleet_from_ships"]:
        raise (error or ParameterError)("fleet_from_ships", f"more than the {len(sc.ships)} ships of a scenario "
                                        "with commanded ships (the fleet step takes no commands)",
                                        resolved["fleet_from_ships"])
    traffic = tuple(i for i, s in enumerate(sc.ships) if traffic_behaviour.ship_inputs(s) is not None)
    unused = unused_parameter(resolved)
    if unused is not None:
        raise (error or ParameterError)(unused, f"its default {PARAMETERS[unused].default!r} with perception = "
                                        f"{resolved['perception']!r} (a sensor it does not use)", resolved[unused])
    if not traffic and resolved["target_wrong_dcpa"] != PARAMETERS["target_wrong_dcpa"].default:
        raise (error or ParameterError)("target_wrong_dcpa", f"its default {PARAMETERS['target_wrong_dcpa'].default} "
                                        "without a target that turns the wrong way", resolved["target_wrong_dcpa"])
    if (traffic or resolved["perception"] != "off") and len(sc.ships) >= resolved["fleet_from_ships"]:
        raise (error or ParameterError)("fleet_from_ships", f"more than the {len(sc.ships)} ships of a scenario with "
                                        "target behaviours or perception (the fleet step has neither)",
                                        resolved["fleet_from_ships"])
    vessels = tuple(getattr(s, "vessel", None) or resolved["vessel"] for s in sc.ships)
    for i, v in enumerate(vessels):
        load_vessel(v, f"ships[{i}].vessel")
    fleet = (len(sc.ships) >= resolved["fleet_from_ships"]
             or len(sc.ships) * len(sc.obstacles) > MAX_UNROLLED_OBSTACLE_PAIRS)  # obstacles seen through slots
    if commanded and fleet and len(sc.ships) < resolved["fleet_from_ships"]:
        raise ScenarioError("obstacles", f"at most {MAX_UNROLLED_OBSTACLE_PAIRS // len(sc.ships)} obstacles with "
                            f"{len(sc.ships)} ships in a scenario with commanded ships (more run the fleet step, "
                            "which takes no commands)", len(sc.obstacles))
    layout = Layout(methods=methods_, n_obstacles=len(sc.obstacles), n_walls=len(walls),
                    max_path=max(1 + len(s.waypoints) for s in sc.ships),
                    vo_candidates=resolved["vo_candidates"], vo_cone=resolved["vo_cone"],
                    disturbed=is_disturbed(resolved), vo_hold=resolved["vo_hold"],
                    vo_speed_levels=resolved["vo_speed_levels"],
                    vessels=() if set(vessels) == {DEFAULT_VESSEL} else vessels,
                    neighbours=resolved["neighbour_slots"] if fleet else 0,
                    n_land=len(land), **_replay_layout(sc, replayed, resolved, error or ParameterError, fleet),
                    cv_extremis="colregs-vortex" in methods_ and resolved["cv_speed_extremis"] > 0,
                    options=_options(methods_, resolved), commanded=commanded, command_rpm=bool(command_rpm),
                    perception=resolved["perception"], traffic=traffic)
    model = ClosedLoopModel(layout, resolved)
    ships = tuple(_ship_inputs(_engine_speed(s), load_vessel(v).ship, v, unit=vessels[0])
                  for s, v in zip(sc.ships, vessels))
    ships = tuple(_with_track(s, d) for s, d in zip(sc.ships, ships))
    ships = tuple({**d, "behaviour": traffic_behaviour.ship_inputs(s)} if i in traffic else d
                  for i, (s, d) in enumerate(zip(sc.ships, ships)))
    obstacles = [(o.position[0], o.position[1], o.radius) for o in sc.obstacles]
    return Problem(model, model.initial_state(list(ships)), model.pack(list(ships), obstacles, walls), ships)


def _options(methods_used, resolved: dict) -> tuple:
    """The structural parameters of the registered methods the ships use, ``(name, value)`` in registry order
    (``Layout.options``)."""
    used = set(methods_used)
    return tuple((k, resolved[k]) for n, m in methods.METHODS.items() if n in used for k in m.options)


def _replay_layout(sc, replayed: tuple, resolved: dict, error, fleet: bool = False) -> dict:
    """The :class:`Layout` fields of the replayed ships (none: no field, so the layout is as without them)."""
    if not replayed:
        return {}
    if fleet and len(sc.ships) * len(sc.obstacles) > MAX_UNROLLED_OBSTACLE_PAIRS:
        raise ScenarioError("obstacles", f"at most {MAX_UNROLLED_OBSTACLE_PAIRS // len(sc.ships)} obstacles for "
                            f"{len(sc.ships)} ships with replayed ones (MAX_UNROLLED_OBSTACLE_PAIRS; more run the "
                            "fleet step, which replays no track)", len(sc.obstacles))
    if len(sc.ships) >= resolved["fleet_from_ships"]:
        raise error("fleet_from_ships", f"more than the {len(sc.ships)} ships of a scenario with replayed ships "
                    "(the fleet step replays no track)", resolved["fleet_from_ships"])
    return {"replay": replayed, "max_track": track_columns(max(len(sc.ships[i].track) for i in replayed))}


def _engine_speed(s):
    """``s``, or for a replayed ship ``s`` at the design speed: the speed sets only the engine's propeller speed,
    which a replayed ship does not use (its recorded speed may be zero)."""
    if getattr(s, "track", None) is None:
        return s
    return dataclasses.replace(s, speed=1.0)


def _with_track(s, inputs: dict) -> dict:
    """The per-ship inputs of scenario ship ``s``, with its track and its recorded speed at t = 0 if it is
    replayed (:mod:`mmg_casadi.closed_loop.replay`)."""
    track = getattr(s, "track", None)
    if track is None:
        return inputs
    return {**inputs, "track": (track.t, track.x, track.y), "speed": s.speed}


def _ship_inputs(s, hull, vessel=None, unit=None) -> dict:
    """The per-ship dict of :func:`~mmg_casadi.closed_loop.layout.pack_params` and
    :func:`~mmg_casadi.closed_loop.state.initial_state` for scenario ship ``s`` of vessel ``hull`` (named
    ``vessel``): its collision geometry (``length``, ``half_beam`` in L, the own ship's hull ``unit``) from its own
    ``length_m`` and ``beam_m``, else its vessel's (:func:`~mmg_casadi.vessel.library.ship_size`)."""
    n_rpm = propeller_rpm_for_speed(s.speed, hull)
    legs = [n_rpm] * (1 + len(s.waypoints))
    if getattr(s, "speeds", None) is not None:
        legs = [n_rpm] + [propeller_rpm_for_speed(v, hull) for v in s.speeds]
    length, half_beam = ship_size(vessel, getattr(s, "length_m", None), getattr(s, "beam_m", None), unit=unit)
    return {"n_rpm": n_rpm, "path": [s.start, *s.waypoints], "stays": s.stays, "start": s.start,
            "heading": s.heading_rad, "speed": s.speed, "leg_rpm": legs, "length": length, "half_beam": half_beam}
