"""The closed loop's shape: which ships, methods, vessels and hazards, and how its state and parameters are laid out.

Scenario state (one column): ``[t, ship_0, ship_1, ...]``, each ship a block of :attr:`Layout.ns` rows named by
:attr:`Layout.ship_state` (the rows :data:`SHIP_STATE` of every ship, then the memory rows of the layout's methods).
Consumers read it through names only: :meth:`Layout.row`, :meth:`Layout.rows`, :meth:`Layout.ship_block` and
:func:`mmg_casadi.closed_loop.state.ship_rows`.

Numeric parameters (gains, field constants, speeds, paths, obstacles, walls) are an input vector ``p`` laid out by
:meth:`Layout.split_params` / :func:`pack_params`, so one compiled Function serves every scenario of the same shape.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mmg_casadi.guidance import methods
from mmg_casadi.guidance.ilos import validate_waypoints
from mmg_casadi.closed_loop.replay import track_values
from mmg_casadi.perception import layer as perception_layer
from mmg_casadi.traffic import behaviour as traffic_behaviour
from mmg_casadi.params import PARAMETERS, resolve
from mmg_casadi.vessel.library import DEFAULT as DEFAULT_VESSEL, load_vessel, ship_size
from mmg_casadi.vessel.ship import ShipParams

SHIP_STATE = (
    "u", "v", "r", "x", "y", "psi", "delta",  # MMG state
    "n_prop",       # propeller speed (rev/min), the engine's state
    "y_int",        # ILOS integrator state
    "idx",          # index of the waypoint being tracked (column of the path)
    "status",       # 0 sailing, 1 reached its goal, 2 diverged, 3 stopped by a collision or grounding
    "t_goal",       # time the goal was reached (-1 before)
    "ce_int",       # ∫|δ| dt while sailing
    "mcte_int",     # ∫|y_e| dt while sailing
    "d_min",        # closest approach to any other ship or obstacle
    "d_min_with",   # index of that agent (ships 0..N-1, obstacles N..N+S-1)
    "t_collision",  # first time closer than the collision distance (-1 if never)
    "collision_with",
    "best_goal_dist",  # smallest distance to the final goal so far
    "t_best",       # when it was reached
    "x_best", "y_best",
    "reactive_time",  # time spent under reactive guidance
)

STOPPED = 3
"""The ``status`` of a ship whose voyage a collision or grounding ended (:func:`mmg_casadi.closed_loop.step.stop_on_contact`):
she is held where she touched, engine stopped and rudder amidships, and stays in the scene as a static hazard."""


GLOBAL_PARAMS = (
    "dt", "r_safe", "collision_distance", "goal_tolerance",
    "ilos_delta", "ilos_k", "kp", "kd", "delta_max",
    "k_att", "k_rep", "d0", "lam_sink", "k_vor", "k_vor0", "r_tol_vortex", "gamma_max",
    "wall_lam", "wall_d_act", "ship_radius", "t_max",
)
"""Numeric inputs of the compiled step, in order: the table's parameters (:mod:`mmg_casadi.params`) with the
angles ``delta_max`` and ``gamma_max`` in rad (the table holds them in degrees); see :func:`step_values`."""
_DEG_INPUTS = {"delta_max": "delta_max_deg", "gamma_max": "gamma_max_deg"}
SHIP_PARAMS = ("n_rpm", "n_path", "stays", "engine_rate", "half_beam", "length", "engine_lag", "rpm_min",
               "rpm_max")
"""Per-ship numeric inputs: service propeller speed (rev/min), waypoint count, whether the ship stays as an obstacle
after its goal, the engine's largest rate (rev/min per L/U of the own ship), half its beam (L, the distance at
which its side touches a wall), its length (L; two ships collide within ``collision_distance`` times their mean
length, :func:`~mmg_casadi.vessel.library.pair_collision_distance`), the engine's time constant (L/U) and the
range of propeller speeds a method may command (rev/min). Length and beam are the ship's own (``length_m``,
``beam_m``) or its vessel's (:func:`~mmg_casadi.vessel.library.ship_size`)."""

COMMAND_ROWS = ("command_heading", "command_rpm")
"""State rows of a layout with commanded ships (:attr:`Layout.commanded`): the heading ordered (rad) and, with
:attr:`Layout.command_rpm`, the propeller speed ordered (rev/min); every ship has them, the step carries them
unchanged and only the commanded ships read them."""

LAND_INPUTS = ("land_lookahead", "land_clearance")
"""Step inputs of the land look-ahead (:mod:`mmg_casadi.guidance.land_ahead`), in layouts with land only."""

FAIRWAY_INPUTS = ("channel_width", "bank_clearance")
"""Step inputs of the Rule 9 lane (:mod:`mmg_casadi.guidance.fairway`), in layouts with walls or land and a method
that keeps Rule 9 (``Method.rule9``) only."""

ENV_INPUTS = ("V_c", "beta_c", "U_w", "psi_w", "crab")
"""Trailing numeric inputs of a disturbed step (:attr:`Layout.disturbed`): the model's disturbance ``env =
[V_c, beta_c, U_w, psi_w]`` (:mod:`mmg_casadi.vessel.environment`, prime-II units, rad) and the crab-angle switch (0/1);
see :func:`env_values`."""



@dataclass(frozen=True)
class Layout:
    """Shape of a closed-loop step: per-ship methods, number of obstacles and walls, path length.

    Parameters
    ----------
    methods : tuple of str
        Guidance method of each ship (a name in :data:`mmg_casadi.guidance.methods.METHODS`); the first ship is the own
        ship.
    n_obstacles, n_walls : int
        Static circular obstacles and straight wall segments.
    max_path : int
        Columns of each ship's padded path (start + waypoints).
    vo_candidates : int
        Candidate headings of the velocity obstacle.
    vo_cone : str
        ``"wide"`` or ``"huang"`` (see :mod:`mmg_casadi.guidance.velocity_obstacle`).
    vo_hold : bool
        The velocity obstacle keeps its chosen heading while it stays feasible (``vo_heading`` state).
    vo_speed_levels : int
        Speed levels searched by ``velocity-obstacle-speed`` (service rpm down to dead slow ahead).
    smooth : float or None
        ``None`` for the exact switching logic; a sharpness ``s > 0`` replaces every switch by a sigmoid of
        that sharpness (for gradient-based tuning).
    disturbed : bool
        Current / wind / crab-angle compensation present (:func:`is_disturbed`): the step takes the inputs
        :data:`ENV_INPUTS` after the others. Calm layouts keep the calm-water step exactly.
    vessels : tuple of str
        Vessel of each ship (names of :data:`mmg_casadi.vessel.library.VESSELS`); empty: every ship is the
        default vessel.
    neighbours : int
        0 for the unrolled step (every ship and pair written out); ``K > 0`` for the fleet step, one ship's step
        mapped over the fleet with ``K`` neighbour slots (:mod:`mmg_casadi.closed_loop.fleet`).
    n_land : int
        How many of the ``n_walls`` segments, the last ones, are edges of land polygons: they are walls to the
        step (field and contact alike, so the compiled code is the same), and touching one is a grounding
        (:func:`mmg_casadi.closed_loop.outcome.collision_kind`).
    replay : tuple of int
        Indices of the replayed ships, increasing (:mod:`mmg_casadi.closed_loop.replay`): they follow a recorded
        track given as numeric inputs after all the others (:meth:`split_params`); empty for none, which leaves
        the layout's step and key as without this field. Not with the fleet step (``neighbours``).
    max_track : int
        Columns of each replayed ship's padded track (:func:`mmg_casadi.closed_loop.replay.track_columns`); 0
        without replayed ships.
    cv_extremis : bool
        colregs-vortex's in-extremis speed test is part of the step (``cv_speed_extremis > 0``); without it the
        cut it would weigh is zero, so the step leaves the test out (it is the costliest part of the method's
        guidance).
    options : tuple of (str, object)
        The structural parameters declared by the layout's methods (``Method.params`` with ``structural``), as
        ``(name, value)`` pairs in registry order; a builder reads them with :meth:`option`. Empty for the
        shipped methods, which leaves the layout's step and key as without this field.
    commanded : tuple of int
        Indices of the ships steered from outside, increasing (:mod:`mmg_casadi.gym`,
        :func:`~mmg_casadi.closed_loop.simulation.simulate` with ``commands``): at every step such a ship's PD
        controller steers the heading in her state row ``command_heading`` (rad) and, with ``command_rpm``, her
        engine follows the propeller speed in ``command_rpm`` (rev/min, clipped to dead slow ahead .. maximum
        rpm), else her leg's service speed exactly; the step carries both rows unchanged, the caller writes them. No ILOS, no method, no walls'
        field. Empty: the layout's step and key are as without this field. Not with replayed ships' indices nor
        the fleet step.
    command_rpm : bool
        The commanded ships also order their propeller speed (the state row ``command_rpm``).
    perception : str
        What the own ship's method knows of the other ships (:mod:`mmg_casadi.perception`): ``"off"`` (the truth;
        the layout's step and key as without this field), ``"ais"``, ``"radar"`` or ``"ais-radar"``: every ship has
        the rows :func:`mmg_casadi.perception.layer.rows` after her others, the step the inputs
        :data:`~mmg_casadi.perception.layer.INPUTS` after the others. Not with the fleet step nor a smooth layout.
    traffic : tuple of int
        Indices of the target ships with a behaviour (:mod:`mmg_casadi.traffic`), increasing, not the own ship:
        each has the numeric inputs :data:`~mmg_casadi.traffic.behaviour.SHIP_INPUTS` and every ship the rows
        :data:`~mmg_casadi.traffic.behaviour.ROWS`. Empty: the layout's step and key are as without this field.
        Not with the fleet step nor a smooth layout.
    """

    methods: tuple
    n_obstacles: int = 0
    n_walls: int = 0
    max_path: int = 2
    vo_candidates: int = PARAMETERS["vo_candidates"].default
    vo_cone: str = PARAMETERS["vo_cone"].default
    vo_hold: bool = PARAMETERS["vo_hold"].default
    vo_speed_levels: int = PARAMETERS["vo_speed_levels"].default
    smooth: float | None = None
    disturbed: bool = False
    vessels: tuple = ()
    neighbours: int = 0
    n_land: int = 0
    replay: tuple = ()
    max_track: int = 0
    cv_extremis: bool = False
    options: tuple = ()
    commanded: tuple = ()
    command_rpm: bool = False
    perception: str = "off"
    traffic: tuple = ()

    def __post_init__(self):
        if not 0 <= self.n_land <= self.n_walls:
            raise ValueError(f"n_land: expected 0 to n_walls = {self.n_walls} land edges, got {self.n_land}")
        self._check_replay()
        object.__setattr__(self, "options", tuple((str(k), v) for k, v in self.options))
        object.__setattr__(self, "commanded", tuple(int(i) for i in self.commanded))
        c = self.commanded
        if list(c) != sorted(set(c)) or any(not 0 <= i < self.n_ships for i in c) or set(c) & set(self.replay):
            raise ValueError(f"commanded: expected increasing ship indices in [0, {self.n_ships}) that are not "
                             f"replayed, got {c}")
        if c and self.neighbours:
            raise ValueError("commanded: expected no neighbour slots (the fleet step takes no commands)")
        if self.command_rpm and not c:
            raise ValueError("command_rpm: expected False without commanded ships")
        object.__setattr__(self, "traffic", tuple(int(i) for i in self.traffic))
        tr = self.traffic
        if list(tr) != sorted(set(tr)) or any(not 0 < i < self.n_ships for i in tr) or set(tr) & set(self.replay):
            raise ValueError(f"traffic: expected increasing indices of target ships in [1, {self.n_ships}) that are "
                             f"not replayed, got {tr}")
        perception_layer.rows(self.perception)  # checks the mode
        if (tr or self.perception != "off") and (self.neighbours or self.smooth is not None):
            raise ValueError("perception, traffic: expected an exact unrolled layout (no neighbour slots, no smoothing)")

    def option(self, name: str):
        """The value of the structural method parameter ``name`` in this layout (:attr:`options`).

        Parameters
        ----------
        name : str
            A structural parameter declared by one of the layout's methods.

        Returns
        -------
        object
            Its value.
        """
        for k, v in self.options:
            if k == name:
                return v
        raise KeyError(f"{name}: not a structural parameter of this layout's methods ({dict(self.options)})")

    def _check_replay(self) -> None:
        """The replayed ships are distinct ship indices in increasing order, with a padded track of at least two
        columns, and the layout is not a fleet layout."""
        object.__setattr__(self, "replay", tuple(int(i) for i in self.replay))
        if list(self.replay) != sorted(set(self.replay)) or any(not 0 <= i < self.n_ships for i in self.replay):
            raise ValueError(f"replay: expected increasing ship indices in [0, {self.n_ships}), got {self.replay}")
        if self.replay and (self.max_track < 2 or self.neighbours):
            raise ValueError(f"replay: expected max_track >= 2 and no neighbour slots, got max_track="
                             f"{self.max_track}, neighbours={self.neighbours}")
        if not self.replay and self.max_track:
            raise ValueError(f"max_track: expected 0 without replayed ships, got {self.max_track}")

    @property
    def n_ships(self) -> int:
        """Number of ships."""
        return len(self.methods)

    def vessel(self, i: int) -> str:
        """Vessel name of ship ``i``.

        Parameters
        ----------
        i : int
            Ship index.

        Returns
        -------
        str
            A name of :data:`~mmg_casadi.vessel.library.VESSELS` (the default vessel when :attr:`vessels` is empty).
        """
        return self.vessels[i] if self.vessels else DEFAULT_VESSEL

    def unit_vessel(self) -> str:
        """The hull whose length L and design speed U_des are the scene's units: the own ship's (ship 0).

        Every other hull sails in these units (:func:`~mmg_casadi.vessel.mmg.in_scene_units`): positions in the
        own ship's L, speeds in her U_des, time in her L/U_des.

        Returns
        -------
        str
            The vessel name of ship 0.

        Examples
        --------
        >>> Layout(("none", "none"), vessels=("kvlcc2", "kcs")).unit_vessel()
        'kvlcc2'
        """
        return self.vessel(0)

    @functools.cached_property
    def memory(self) -> tuple[str, ...]:
        """Memory rows of the methods this layout uses (``Method.memory``), in
        registry order; every ship of the layout has them (an on-demand method is registered first,
        :func:`~mmg_casadi.guidance.methods.load_on_demand`)."""
        used = set(self.methods)
        for name in sorted(used):
            methods.load_on_demand(name)
        out = []
        for n, m in methods.METHODS.items():
            out += [k for k in m.memory if n in used and k not in out]
        if self.commanded:
            out += [k for k in COMMAND_ROWS[:1 + int(self.command_rpm)] if k not in out]
        return tuple(out)

    @functools.cached_property
    def tallies(self) -> tuple[str, ...]:
        """The memory rows of the layout's methods that are tallies (``Method.tallies``: counts over a run that
        start at 0 and are never reset), in :attr:`memory` order; empty for the shipped methods."""
        memory = self.memory  # registers an on-demand method first
        used = set(self.methods)
        names = {k for n, m in methods.METHODS.items() if n in used for k in m.tallies}
        return tuple(k for k in memory if k in names)

    @functools.cached_property
    def ship_state(self) -> tuple[str, ...]:
        """Names of one ship's rows of the scenario state: :data:`SHIP_STATE`, then :attr:`memory`, the traffic rows
        (with :attr:`traffic`) and the perception rows (with :attr:`perception`)."""
        return (SHIP_STATE + self.memory + (traffic_behaviour.ROWS if self.traffic else ())
                + perception_layer.rows(self.perception))

    @property
    def ns(self) -> int:
        """Rows of one ship's block of the scenario state."""
        return len(self.ship_state)

    @property
    def nx(self) -> int:
        """Rows of the scenario state."""
        return 1 + self.n_ships * self.ns

    def row(self, name: str, ship: int) -> int:
        """Index of state row ``name`` of ship ``ship`` in the scenario state (row 0 is the time).

        Parameters
        ----------
        name : str
            A name of :attr:`ship_state`.
        ship : int
            Ship index.

        Returns
        -------
        int
            Row index in the scenario state vector.

        Examples
        --------
        >>> lay = Layout(("none", "none"))
        >>> lay.row("psi", 1) == 1 + lay.ns + SHIP_STATE.index("psi")
        True
        """
        return 1 + ship * self.ns + self._columns[name]

    def column(self, name: str) -> int:
        """Index of state row ``name`` within a ship's block (a column of :func:`~mmg_casadi.closed_loop.state.ship_rows`).

        Parameters
        ----------
        name : str
            A name of :attr:`ship_state`.

        Returns
        -------
        int
            Column index within a ship's block.
        """
        return self._columns[name]

    @functools.cached_property
    def _columns(self) -> dict:
        return {name: k for k, name in enumerate(self.ship_state)}

    def rows(self, name: str) -> list[int]:
        """Index of state row ``name`` of every ship, in ship order.

        Parameters
        ----------
        name : str
            A name of :attr:`ship_state`.

        Returns
        -------
        list of int
            One row index per ship.
        """
        first = self.row(name, 0)
        return list(range(first, first + self.n_ships * self.ns, self.ns))

    def ship_block(self, ship: int) -> slice:
        """The rows of ship ``ship``'s block of the scenario state.

        Parameters
        ----------
        ship : int
            Ship index.

        Returns
        -------
        slice
            Rows ``1 + ship ns`` to ``1 + (ship + 1) ns`` (exclusive) of the scenario state.
        """
        return slice(1 + ship * self.ns, 1 + (ship + 1) * self.ns)

    @property
    def n_agents(self) -> int:
        return self.n_ships + self.n_obstacles

    @property
    def method_inputs(self) -> tuple[str, ...]:
        """Numeric step inputs of the methods this layout uses (the ``inputs`` of each
        :class:`mmg_casadi.guidance.methods.Method`, then, with walls, its ``wall_inputs``; with land
        ``grounding_margin`` and the look-ahead's :data:`LAND_INPUTS`; with walls and a method that keeps Rule 9,
        :data:`FAIRWAY_INPUTS`; each once), after the others in the parameter vector."""
        used = set(self.methods)
        names = [k for n, m in methods.METHODS.items() if n in used for k in m.step_inputs]
        if self.n_walls:
            names += [k for n, m in methods.METHODS.items() if n in used for k in m.wall_inputs]
        if self.n_land:
            names += ["grounding_margin", *LAND_INPUTS]
        if self.n_walls and any(methods.METHODS[n].rule9 for n in used if n in methods.METHODS):
            names += [*LAND_INPUTS[:1], *FAIRWAY_INPUTS]
        return tuple(dict.fromkeys(names))

    @property
    def np(self) -> int:
        """Rows of the parameter vector."""
        return (len(GLOBAL_PARAMS) + self.n_ships * (self.ship_params_size)
                + 3 * self.n_obstacles + 4 * self.n_walls + (len(ENV_INPUTS) if self.disturbed else 0)
                + len(self.method_inputs) + self.track_params_size + self.extra_params_size)

    @property
    def extra_params_size(self) -> int:
        """Rows of the parameter vector after the tracks: the traffic ships' inputs and the perception inputs."""
        size = len(self.traffic) * len(traffic_behaviour.SHIP_INPUTS) + (len(traffic_behaviour.INPUTS) if self.traffic
                                                                          else 0)
        return size + (len(perception_layer.INPUTS) if self.perception != "off" else 0)

    @property
    def track_params_size(self) -> int:
        """Rows of the parameter vector holding the replayed ships' tracks, its last block: per replayed ship the
        track's last time and the padded rows t, x, y (:func:`mmg_casadi.closed_loop.replay.track_values`)."""
        return len(self.replay) * (1 + 3 * self.max_track)

    def key(self) -> str:
        """Short identifier used in Function names.

        Returns
        -------
        str
            Methods, obstacle, wall and path counts, VO settings and any smoothing, disturbance, vessel, neighbour and
            speed-level tags, e.g. ``'vox2_o0_w0_k2_v80huangh'``; equal layouts give equal keys.
        """
        meth = "_".join(m.replace("-", "") for m in self.methods)
        if len(set(self.methods)) == 1:
            meth = f"{self.methods[0].replace('-', '')}x{self.n_ships}"
        elif self.n_ships > 16:  # long fleets: runs of one method as name x count
            meth = "_".join(f"{m.replace('-', '')}x{n}" for m, n in _runs(self.methods))
        s = "" if self.smooth is None else f"_s{self.smooth:g}".replace(".", "p")
        s += "_env" if self.disturbed else ""
        if any(v != DEFAULT_VESSEL for v in self.vessels):  # the hulls in ship order, run-length encoded
            s += "_" + "_".join(f"{v}{n}" for v, n in _runs(self.vessels))
        if self.neighbours:
            s += f"n{self.neighbours}"
        if self.vo_speed_levels != PARAMETERS["vo_speed_levels"].default:
            s += f"_l{self.vo_speed_levels}"
        if self.replay:
            s += "".join(f"_r{i}" for i in self.replay) + f"t{self.max_track}"
        if self.cv_extremis:
            s += "_cx"
        if self.options:
            s += "_m" + hashlib.sha256(repr(self.options).encode()).hexdigest()[:8]
        if self.commanded:
            s += "".join(f"_c{i}" for i in self.commanded) + ("rpm" if self.command_rpm else "")
        if self.traffic:
            s += "_t" + ("all" if self.traffic == tuple(range(1, self.n_ships)) else "_".join(map(str, self.traffic)))
        if self.perception != "off":
            s += "_p" + self.perception.replace("-", "")
        return (f"{meth}_o{self.n_obstacles}_w{self.n_walls}_k{self.max_path}_v{self.vo_candidates}{self.vo_cone}"
                f"{'h' if self.vo_hold else ''}{s}")

    def param_index(self, name: str) -> int:
        """Index of the global numeric input ``name`` (:data:`GLOBAL_PARAMS`) in the parameter vector.

        Parameters
        ----------
        name : str
            A name of :data:`GLOBAL_PARAMS`.

        Returns
        -------
        int
            Row in the parameter vector.
        """
        return GLOBAL_PARAMS.index(name)

    @property
    def ship_params_size(self) -> int:
        """Rows of one ship's block of the parameter vector: :data:`SHIP_PARAMS`, the padded path (2 per column)
        and the propeller speed of each leg (one per column, ``leg_rpm[k]`` on the way to column ``k``)."""
        return len(SHIP_PARAMS) + 3 * self.max_path

    def param_block(self, name: str) -> slice:
        """Rows of the parameter vector holding block ``name``: ``"ships"``, ``"obstacles"`` (3 per obstacle),
        ``"walls"`` (4 per segment) or ``"env"``.

        Parameters
        ----------
        name : str
            One of ``"ships"``, ``"obstacles"``, ``"walls"``, ``"env"``.

        Returns
        -------
        slice
            The rows of the block (empty for ``"env"`` in an undisturbed layout).

        Examples
        --------
        >>> lay = Layout(("none",), n_obstacles=2)
        >>> sl = lay.param_block("obstacles")
        >>> sl.stop - sl.start
        6
        """
        sizes = {"ships": self.n_ships * (self.ship_params_size), "obstacles": 3 * self.n_obstacles,
                 "walls": 4 * self.n_walls, "env": len(ENV_INPUTS) if self.disturbed else 0}
        start = len(GLOBAL_PARAMS)
        for key, size in sizes.items():
            if key == name:
                return slice(start, start + size)
            start += size
        raise ValueError(f"name: expected one of {', '.join(sizes)}, got {name!r}")

    def split_params(self, p):
        """Split a parameter vector (symbolic or numeric) into named pieces.

        Parameters
        ----------
        p : SX, MX, DM or ndarray
            A parameter vector of this layout (:attr:`np` rows).

        Returns
        -------
        dict
            Each name of :data:`GLOBAL_PARAMS` and of :attr:`method_inputs` to its entry of ``p``; ``"ships"``, a list
            of per-ship dicts (:data:`SHIP_PARAMS`, ``"path"`` 2 x max_path, ``"leg_rpm"``); ``"obstacles"``
            (3 x n_obstacles), ``"walls"`` (4 x n_walls) and, when disturbed, ``"env"``. Entries have the type of ``p``.
        """
        out = {}
        i = 0
        for name in GLOBAL_PARAMS:
            out[name] = p[i]
            i += 1
        ships = []
        for _ in range(self.n_ships):
            d = {}
            for name in SHIP_PARAMS:
                d[name] = p[i]
                i += 1
            d["path"] = ca.reshape(p[i:i + 2 * self.max_path], 2, self.max_path)
            i += 2 * self.max_path
            d["leg_rpm"] = p[i:i + self.max_path]
            i += self.max_path
            ships.append(d)
        out["ships"] = ships
        out["obstacles"] = ca.reshape(p[i:i + 3 * self.n_obstacles], 3, self.n_obstacles)
        i += 3 * self.n_obstacles
        out["walls"] = ca.reshape(p[i:i + 4 * self.n_walls], 4, self.n_walls)
        i += 4 * self.n_walls
        if self.disturbed:
            out["env"] = p[i:i + len(ENV_INPUTS)]
            i += len(ENV_INPUTS)
        for name in self.method_inputs:
            out[name] = p[i]
            i += 1
        if self.replay:
            out["tracks"] = {}
            T = self.max_track
            for ship in self.replay:
                out["tracks"][ship] = {"t_end": p[i], "t": [p[i + 1 + k] for k in range(T)],
                                       "x": [p[i + 1 + T + k] for k in range(T)],
                                       "y": [p[i + 1 + 2 * T + k] for k in range(T)]}
                i += 1 + 3 * T
        if self.traffic:
            out["traffic"], i = traffic_behaviour.split(self, p, i)
        if self.perception != "off":
            out["perception"] = {k: p[i + n] for n, k in enumerate(perception_layer.INPUTS)}
            i += len(perception_layer.INPUTS)
        assert i == self.np
        return out


def _runs(items) -> list[tuple[str, int]]:
    """Runs of equal consecutive items as ``(item, count)`` (the run-length code of a layout's key)."""
    return [(k, len(list(g))) for k, g in itertools.groupby(items)]


def pack_params(layout: Layout, globals_: dict, ships: list[dict], obstacles=(), walls=(), env=None) -> np.ndarray:
    """Numeric parameter vector for ``layout``.

    ``ships[i]`` has ``n_rpm``, ``path`` (K_i x 2 array: start then waypoints), ``stays`` and optionally
    ``leg_rpm`` (K_i propeller speeds, entry k on the leg to path point k; default ``n_rpm`` on every leg),
    ``length`` and ``half_beam`` (L; default its vessel's, :func:`~mmg_casadi.vessel.library.ship_size`); paths
    are padded to ``layout.max_path`` columns by repeating the last waypoint. The engine's rate is the table's
    ``engine_rate_rpm_s`` (in ``globals_``) on the scene's time scale, the own ship's L/U_des. ``obstacles`` are
    ``(x, y, radius)``, walls ``(ax, ay, bx, by)``; ``env`` the :data:`ENV_INPUTS` of a disturbed layout (:func:`env_values`).

    Parameters
    ----------
    layout : Layout
        Closed-loop layout (ships, obstacles, walls, method) of the scenario.
    globals_ : dict
        The step's global numeric inputs (:func:`default_globals`, :func:`step_values`).
    ships : list of dict
        Per ship ``n_rpm``, ``path`` (L) and ``stays``.
    obstacles : sequence of (float, float, float), optional
        Static obstacles ``(x, y, radius)`` (L).
    walls : sequence of (float, float, float, float), optional
        Wall segments ``(ax, ay, bx, by)`` (L).
    env : dict, optional
        The :data:`ENV_INPUTS` of a disturbed layout (:func:`env_values`).

    Returns
    -------
    numpy.ndarray (np,)
        The parameter vector (lengths in L, times in L/U, angles in rad, propeller speeds in rev/min).
    """
    vals = [float(globals_[name]) for name in GLOBAL_PARAMS]
    scene_time_s = load_vessel(layout.unit_vessel()).ship.time_scale_s  # the own ship's L/U_des
    for i, s in enumerate(ships):
        path = np.asarray(validate_waypoints(s["path"], f"ships[{i}].path"))
        k = len(path)
        if k > layout.max_path:
            raise ValueError(f"path of {k} points exceeds layout.max_path={layout.max_path}")
        padded = np.vstack([path, np.repeat(path[-1:], layout.max_path - k, axis=0)])
        hull = load_vessel(layout.vessel(i)).ship
        rate = float(globals_["engine_rate_rpm_s"]) * scene_time_s
        lag = float(globals_["engine_lag_s"]) / scene_time_s
        rpm_range = [float(globals_[k]) * hull.n_design_rpm for k in ("engine_dead_slow", "engine_rpm_max")]
        length, half_beam = ship_size(layout.vessel(i), unit=layout.unit_vessel())
        length, half_beam = float(s.get("length", length)), float(s.get("half_beam", half_beam))
        vals += [float(s["n_rpm"]), float(k), float(bool(s.get("stays", False))), rate, half_beam, length, lag,
                 *rpm_range]
        vals += list(padded.reshape(-1))  # column-major (x0, y0, x1, y1, ...) = reshape(2, K)
        legs = [float(v) for v in s.get("leg_rpm", [s["n_rpm"]] * k)]
        if len(legs) != k:
            raise ValueError(f"ships[{i}].leg_rpm: expected {k} entries (one per path point), got {len(legs)}")
        vals += legs + [legs[-1]] * (layout.max_path - k)
    for o in obstacles:
        vals += [float(o[0]), float(o[1]), float(o[2])]
    for w in walls:
        vals += [float(v) for v in w]
    if layout.disturbed:
        if env is None or len(env) != len(ENV_INPUTS):
            raise ValueError(f"a disturbed layout needs env = {ENV_INPUTS}, got {env!r}")
        vals += [float(v) for v in env]
    vals += [float(globals_[name]) for name in layout.method_inputs]
    for i in layout.replay:  # replayed ships: ships[i]["track"] = (t, x, y), the parameter vector's last block
        vals += track_values(*ships[i]["track"], layout.max_track)
    if layout.traffic:  # then the traffic ships' behaviours and the perception inputs
        vals += traffic_behaviour.values(layout, ships, globals_)
    if layout.perception != "off":
        vals += perception_layer.input_values(globals_, load_vessel(layout.unit_vessel()).ship)
    p = np.array(vals)
    assert p.size == layout.np
    return p



def step_values(resolved: dict) -> dict:
    """The step's numeric inputs (:data:`GLOBAL_PARAMS` and the ``inputs`` of every
    :class:`~mmg_casadi.guidance.methods.Method`) from a resolved parameter set (table angles in degrees to rad).

    Parameters
    ----------
    resolved : dict
        A resolved parameter set (table names and units).

    Returns
    -------
    dict
        Name to float: every :data:`GLOBAL_PARAMS` entry, every method input and the engine parameters, angles in
        rad.

    Examples
    --------
    >>> g = step_values(resolve())
    >>> round(g["gamma_max"], 6), g["kp"]
    (1.963495, 3.5)
    """
    out = {}
    for name in GLOBAL_PARAMS:
        src = _DEG_INPUTS.get(name)
        out[name] = math.radians(float(resolved[src])) if src else float(resolved[name])
    for m in methods.METHODS.values():
        for name in m.step_inputs + m.wall_inputs:
            out[name] = math.radians(float(resolved[name + "_deg"])) if name not in resolved else float(resolved[name])
    for name in ("engine_rate_rpm_s", "engine_lag_s", "engine_dead_slow", "engine_rpm_max", "grounding_margin",
                 *LAND_INPUTS, *FAIRWAY_INPUTS):
        out[name] = float(resolved[name])
    for name in PERCEPTION_VALUES + ("target_wrong_dcpa",):  # in the table's units; pack_params converts them
        out[name] = resolved[name] if name == "ais_class" else float(resolved[name])
    return out


PERCEPTION_VALUES = ("ais_class", "ais_interval_scale", "ais_latency_s", "ais_dropout", "ais_position_sigma_m",
                     "ais_sog_sigma_kn", "ais_cog_sigma_deg", "radar_range_sigma_m", "radar_bearing_sigma_deg",
                     "radar_range_nm", "radar_p_detect", "tracker_q", "tracker_gate")
"""Table parameters the perception inputs are made of (:func:`mmg_casadi.perception.layer.input_values`)."""


def is_disturbed(resolved: dict) -> bool:
    """Whether a resolved parameter set has a current, a wind or crab-angle compensation (a disturbed layout).

    Parameters
    ----------
    resolved : dict
        A full parameter set (:func:`mmg_casadi.params.resolve`); only ``current_speed``, ``wind_speed`` and
        ``crab_compensation`` are read (a direction without a speed does not count).

    Returns
    -------
    bool
        True if ``current_speed > 0``, ``wind_speed > 0`` or ``crab_compensation == "on"``.

    Examples
    --------
    >>> is_disturbed(resolve()), is_disturbed(resolve({"current_direction_deg": 90.0}))
    (False, False)
    >>> is_disturbed(resolve({"wind_speed": 15.0}))
    True
    """
    return (float(resolved["current_speed"]) > 0.0 or float(resolved["wind_speed"]) > 0.0
            or resolved["crab_compensation"] == "on")


def env_values(resolved: dict, ship: ShipParams | None = None) -> list[float]:
    """The :data:`ENV_INPUTS` of a resolved parameter set: speeds over ``ship``'s design speed (default the KCS,
    12.347 m/s; the table's current is already a fraction of it, its wind in m/s), directions in rad, crab 0/1.

    Parameters
    ----------
    resolved : dict
        A full parameter set (:func:`mmg_casadi.params.resolve`); reads ``current_speed`` (fraction of the
        design speed), ``current_direction_deg`` and ``wind_direction_deg`` (deg), ``wind_speed`` (m/s) and
        ``crab_compensation`` (``"on"`` or ``"off"``).
    ship : ShipParams, optional
        Ship whose design speed ``U_design`` [m/s] makes the wind speed non-dimensional; the default vessel
        (:func:`mmg_casadi.vessel.library.load_vessel`) if omitted.

    Returns
    -------
    list of float
        ``[V_c, beta_c, U_w, psi_w, crab]`` in the order of :data:`ENV_INPUTS`.

    Examples
    --------
    >>> [round(v, 4) for v in env_values(resolve({"current_speed": 0.1, "current_direction_deg": 90.0,
    ...                                          "wind_speed": 15.0, "crab_compensation": "on"}))]
    [0.1, 1.5708, 1.2149, 0.0, 1.0]
    """
    U = (ship or load_vessel().ship).U_design
    return [float(resolved["current_speed"]), math.radians(float(resolved["current_direction_deg"])),
            float(resolved["wind_speed"]) / U, math.radians(float(resolved["wind_direction_deg"])),
            1.0 if resolved["crab_compensation"] == "on" else 0.0]


def default_globals(**overrides) -> dict:
    """The step's numeric inputs for the table's defaults updated with ``overrides`` (table names), checked.

    Parameters
    ----------
    **overrides : float
        Parameter values by table name, replacing the defaults.

    Returns
    -------
    dict
        The step's numeric inputs, as :func:`step_values` gives them.

    Examples
    --------
    >>> g = default_globals(kp=2.0)
    >>> g["kp"], g["kd"], g["d0"]
    (2.0, 4.0, 8.0)
    >>> default_globals(ilos_delta=-1.0)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.ParameterError: ilos_delta: expected a number in (0, inf) L, got -1.0
    """
    return step_values(resolve(overrides))
