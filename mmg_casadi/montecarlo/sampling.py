"""Random encounter scenarios of the paper's statistical analysis (Section "Statistical Analysis").

Five environments differ in the number of static obstacles and of dynamic ships besides the own ship
(:data:`ENVIRONMENTS`); a sixth, ours, is a strait with islands (:mod:`mmg_casadi.montecarlo.land_sampling`). In each run the own ship (ship 0), the static obstacles and the dynamic ships are
placed uniformly in a square of side ``area`` (in ship lengths L) with the paper's rules:

* all starting points (ships and obstacles alike) are at least ``min_start_separation`` apart;
* every ship's goal is uniform in the same square and at least ``min_goal_distance`` from its own start;
* initial headings are uniform in [-pi, pi) (radians from x=north towards y=east);
* the own ship sails at the design speed (1.0); dynamic ships at a speed uniform in ``speed_range``
  (fractions of the design speed);
* static obstacles are discs of radius ``obstacle_radius`` (L/2 in the paper).

A scenario depends only on ``(environment, run, base_seed)``: the random generator is
``np.random.default_rng(np.random.SeedSequence([base_seed, environment, run]))``, so every method of
collision avoidance is tested on the same scenarios and any run can be regenerated on its own.

The separation rule is implemented as sequential rejection: points are drawn one at a time in the order
own ship, static obstacles, dynamic ships; each point is re-drawn until it is at least
``min_start_separation`` from every point drawn before it. Goals are drawn afterwards, ship by ship, each
re-drawn until it is at least ``min_goal_distance`` from its ship's start. Then headings (own ship first),
then the dynamic ships' speeds. This order is part of the reproducibility contract.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.readers import is_finite
from mmg_casadi.guidance.methods import DEFAULT as DEFAULT_METHOD
from mmg_casadi.montecarlo.land_sampling import ENVIRONMENT as LAND_ENVIRONMENT, sample_strait
from mmg_casadi.params import PARAMETERS, TARGET_METHODS
from mmg_casadi.traffic.mix import is_mix
from mmg_casadi.traffic.sample import apply_behaviours, needs_waypoint

ENVIRONMENTS: dict[int, tuple[int, int]] = {1: (1, 2), 2: (2, 3), 3: (2, 5), 4: (3, 7), 5: (4, 9)}
"""Environment number -> (static obstacles, dynamic ships besides the own ship), from the paper's table."""

MAX_DRAWS_PER_POINT = 100_000
"""Rejection-sampling budget per point; exceeding it means the configuration leaves no room."""

ALL_ENVIRONMENTS: tuple[int, ...] = (*ENVIRONMENTS, LAND_ENVIRONMENT)
"""The paper's environments 1–5 and ours, 6: a strait with islands (:mod:`mmg_casadi.montecarlo.land_sampling`)."""

_ENV_ALLOWED = "an environment number in 1-6"
_ENVS_ALLOWED = "environment numbers in 1-6 as a range '1-5', a list '1,3,6' or both '1-2,6'"


@dataclass(frozen=True)
class SamplerConfig:
    """Placement rules of the random scenarios.

    Parameters
    ----------
    area : float
        Side of the square [0, area]^2 holding starts and goals, in L (100 in the paper).
    min_start_separation : float
        Minimum distance between any two starting points, ships and static obstacles alike, in L (10).
    min_goal_distance : float
        Minimum distance of a ship's goal from its own start, in L (50). Must be below ``area / sqrt(2)``
        so that every start has room for a goal.
    speed_range : tuple of float
        ``(low, high)`` speed of the dynamic ships as a fraction of the design speed ((0.5, 1.0)).
    obstacle_radius : float
        Radius of the static obstacles, in L (0.5).

    Examples
    --------
    >>> SamplerConfig().speed_range
    (0.5, 1.0)
    >>> SamplerConfig(area=-1.0)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: area: expected a number > 0, got -1.0
    """

    area: float = 100.0
    min_start_separation: float = 10.0
    min_goal_distance: float = 50.0
    speed_range: tuple[float, float] = (0.5, 1.0)
    obstacle_radius: float = 0.5

    def __post_init__(self):
        for name in ("area", "min_start_separation", "min_goal_distance", "obstacle_radius"):
            value = getattr(self, name)
            if not _is_number(value) or not value >= 0 or (name == "area" and value == 0):
                allowed = "a number > 0" if name == "area" else "a number >= 0"
                raise InputError(name, allowed, value)
        if not self.min_goal_distance < self.area / math.sqrt(2.0):
            raise InputError("min_goal_distance", f"a number below area/sqrt(2) = {self.area / math.sqrt(2):.4g}",
                             self.min_goal_distance)
        speeds = self.speed_range
        ok = (isinstance(speeds, (tuple, list)) and len(speeds) == 2 and all(_is_number(s) for s in speeds)
              and 0 < speeds[0] <= speeds[1])
        if not ok:
            raise InputError("speed_range", "(low, high) with 0 < low <= high", speeds)
        object.__setattr__(self, "speed_range", (float(speeds[0]), float(speeds[1])))


def _is_number(value) -> bool:
    return is_finite(value)


def _readonly(values, shape_tail: tuple[int, ...]) -> np.ndarray:
    arr = np.array(values, dtype=float).reshape((-1, *shape_tail))
    arr.flags.writeable = False
    return arr


@dataclass(frozen=True, eq=False)
class SampledScenario:
    """One random encounter: the own ship (index 0), dynamic ships and static obstacles.

    Arrays are read-only numpy arrays; lengths in L, headings in radians, speeds as fractions of the
    design speed. Two scenarios compare equal when all fields are equal.

    Parameters
    ----------
    environment, run, seed : int
        Environment number (1-6), run index and the base seed the scenario was drawn with.
    starts, goals : ndarray, shape (N, 2)
        Start and goal positions of the N ships (own ship first).
    headings : ndarray, shape (N,)
        Initial headings in [-pi, pi).
    speeds : ndarray, shape (N,)
        Speeds; ``speeds[0] == 1.0`` (design speed).
    obstacles : ndarray, shape (S, 2)
        Centres of the static obstacles.
    obstacle_radius : float
        Radius of every static obstacle.
    land : tuple of ndarray, shape (K, 2) each
        Land polygons (environment 6, :mod:`mmg_casadi.montecarlo.land_sampling`); empty in environments 1–5.

    Examples
    --------
    >>> s = sample_scenario(2, run=7)
    >>> s.n_ships, s.n_obstacles, float(s.speeds[0])
    (4, 2, 1.0)
    >>> s == sample_scenario(2, run=7)
    True
    """

    environment: int
    run: int
    seed: int
    starts: np.ndarray
    goals: np.ndarray
    headings: np.ndarray
    speeds: np.ndarray
    obstacles: np.ndarray
    obstacle_radius: float = 0.5
    land: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "land", tuple(_readonly(poly, (2,)) for poly in self.land))
        object.__setattr__(self, "starts", _readonly(self.starts, (2,)))
        object.__setattr__(self, "goals", _readonly(self.goals, (2,)))
        object.__setattr__(self, "headings", _readonly(self.headings, ()))
        object.__setattr__(self, "speeds", _readonly(self.speeds, ()))
        object.__setattr__(self, "obstacles", _readonly(self.obstacles, (2,)))
        n = self.starts.shape[0]
        for name in ("goals", "headings", "speeds"):
            if getattr(self, name).shape[0] != n:
                raise InputError(name, f"{n} entries (one per ship)", getattr(self, name).shape[0])

    def __eq__(self, other):
        if not isinstance(other, SampledScenario):
            return NotImplemented
        scalars = ("environment", "run", "seed", "obstacle_radius")
        arrays = ("starts", "goals", "headings", "speeds", "obstacles")
        return (all(getattr(self, k) == getattr(other, k) for k in scalars)
                and all(np.array_equal(getattr(self, k), getattr(other, k)) for k in arrays)
                and len(self.land) == len(other.land)
                and all(np.array_equal(a, b) for a, b in zip(self.land, other.land)))

    __hash__ = None

    @property
    def n_ships(self) -> int:
        """Number of ships including the own ship."""
        return int(self.starts.shape[0])

    @property
    def n_obstacles(self) -> int:
        """Number of static obstacles."""
        return int(self.obstacles.shape[0])

    def to_dict(self) -> dict:
        """Plain-Python dictionary of all fields (lists instead of arrays), e.g. for JSON.

        Returns
        -------
        dict
            ``environment``, ``run``, ``seed``, ``starts``, ``goals`` (L), ``headings`` (rad), ``speeds`` (fractions of
            U_des), ``obstacles`` (L), ``obstacle_radius`` (L) and, with land, ``land`` (polygons in L).

        Examples
        --------
        >>> sorted(sample_scenario(1, 0).to_dict())[:3]
        ['environment', 'goals', 'headings']
        """
        return {
            "environment": int(self.environment),
            "run": int(self.run),
            "seed": int(self.seed),
            "starts": self.starts.tolist(),
            "goals": self.goals.tolist(),
            "headings": self.headings.tolist(),
            "speeds": self.speeds.tolist(),
            "obstacles": self.obstacles.tolist(),
            "obstacle_radius": float(self.obstacle_radius),
            **({"land": [poly.tolist() for poly in self.land]} if self.land else {}),
        }

    def to_scenario_dict(self, method: str = DEFAULT_METHOD, dt: float = PARAMETERS["dt"].default,
                         t_max: float = PARAMETERS["t_max"].default, r_safe: float = PARAMETERS["r_safe"].default,
                         collision_distance: float = PARAMETERS["collision_distance"].default,
                         targets: str = PARAMETERS["targets"].default,
                         target_slowdown: float = PARAMETERS["target_slowdown"].default,
                         target_vessels: str = PARAMETERS["target_vessels"].default, behaviours=None) -> dict:
        """The scenario in the shape of a TOML scenario file, so a run can be replayed on its own.

        Ships are named ``agent0`` (own ship), ``agent1``, ...; headings are written in degrees; every ship
        has a single waypoint, its goal.

        Parameters
        ----------
        method : str
            Collision-avoidance method written to ``settings.method``.
        dt, t_max : float
            Time step and time limit (non-dimensional time L/U).
        r_safe, collision_distance : float
            Safe radius and collision distance in L.
        targets : str
            ``"avoid"`` (every ship the study's method), ``"hold"``: every ship but the own ship gets the method
            ``"none"`` (holds course and speed), or a method that every ship but the own ship gets (parameter
            ``targets``).
        target_slowdown : float, default 0
            Fraction of its speed every ship but the own ship takes off halfway along its route: its waypoints
            become the midpoint and the goal, with the speeds ``[v, (1 - target_slowdown) v]`` (parameter
            ``target_slowdown``); 0 keeps one waypoint at constant speed, the scenario unchanged.
        target_vessels : str, default "own"
            Hulls of the ships but the own ship (parameter ``target_vessels``): ``"own"`` writes none (every ship
            the table's ``vessel``, the scenario unchanged); a vessel name or two separated by a comma, taken in
            turn. Each ship's ``speed`` is a fraction of its own hull's design speed.
        behaviours : list of dict, optional
            With ``targets`` a mix: the drawn behaviour of every target
            (:func:`mmg_casadi.traffic.sample.draw_behaviours`), written into each target's ship table
            (:func:`~mmg_casadi.traffic.sample.apply_behaviours`); required with a mix, refused otherwise.

        Returns
        -------
        dict
            ``{"settings": {...}, "ships": [...], "obstacles": [...], "walls": []}``.

        Examples
        --------
        >>> d = sample_scenario(1, 0).to_scenario_dict()
        >>> sorted(d), d["settings"]["method"], d["ships"][0]["name"], d["ships"][0]["speed"]
        (['obstacles', 'settings', 'ships', 'walls'], 'modified-vortex', 'agent0', 1.0)
        >>> len(d["ships"]), d["obstacles"][0]["radius"]
        (3, 0.5)
        >>> [s.get("method") for s in sample_scenario(1, 0).to_scenario_dict(targets="hold")["ships"]]
        [None, 'none', 'none']
        >>> t = sample_scenario(1, 0).to_scenario_dict(target_slowdown=0.5)["ships"][1]
        >>> len(t["waypoints"]), t["speeds"][1] == 0.5 * t["speed"] == 0.5 * t["speeds"][0]
        (2, True)
        >>> [s.get("vessel") for s in sample_scenario(2, 0).to_scenario_dict(target_vessels="kvlcc2,kcs")["ships"]]
        [None, 'kvlcc2', 'kcs', 'kvlcc2']
        """
        if not isinstance(method, str) or not method:
            raise InputError("method", "a non-empty method name", method)
        targets = PARAMETERS["targets"].check(targets, cls=InputError)
        target_slowdown = PARAMETERS["target_slowdown"].check(target_slowdown, cls=InputError)
        target_vessels = PARAMETERS["target_vessels"].check(target_vessels, cls=InputError)
        if is_mix(targets) != (behaviours is not None):
            raise InputError("behaviours", "the drawn behaviours of the targets with a mix of targets, and nothing "
                             "otherwise", targets)
        if is_mix(targets) and target_slowdown > 0 and needs_waypoint(targets):
            raise InputError("target_slowdown", "0 with a mix of targets that changes its mind (intent)",
                             target_slowdown)
        settings = {"method": method}
        for name, value in (("dt", dt), ("t_max", t_max), ("r_safe", r_safe),
                            ("collision_distance", collision_distance)):
            if not _is_number(value) or not value > 0:
                raise InputError(name, "a number > 0", value)
            settings[name] = float(value)
        ships = [
            {
                "name": f"agent{i}",
                "start": [float(x) for x in self.starts[i]],
                "heading": math.degrees(float(self.headings[i])),
                "speed": float(self.speeds[i]),
                "waypoints": [[float(x) for x in self.goals[i]]],
            }
            for i in range(self.n_ships)
        ]
        if targets == "hold" or targets in TARGET_METHODS:  # hold course and speed ("none"), or avoid with the
            for ship in ships[1:]:  # method named (a mix: apply_behaviours below)
                ship["method"] = "none" if targets == "hold" else targets
        if target_vessels != "own":
            hulls = target_vessels.split(",")
            for k, ship in enumerate(ships[1:]):
                ship["vessel"] = hulls[k % len(hulls)]
        if target_slowdown > 0:
            for i, ship in enumerate(ships[1:], start=1):
                mid = 0.5 * (self.starts[i] + self.goals[i])
                ship["waypoints"].insert(0, [float(x) for x in mid])
                ship["speeds"] = [ship["speed"], (1.0 - target_slowdown) * ship["speed"]]
        if behaviours is not None:
            apply_behaviours(ships, behaviours, goal_tolerance=PARAMETERS["goal_tolerance"].default,
                             waypoint=needs_waypoint(targets))
        obstacles = [{"position": [float(x) for x in p], "radius": float(self.obstacle_radius)}
                     for p in self.obstacles]
        out = {"settings": settings, "ships": ships, "obstacles": obstacles, "walls": []}
        if self.land:
            out["land"] = [{"points": poly.tolist()} for poly in self.land]
        return out


def _check_int(name: str, value, allowed: str, low: int = 0) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise InputError(name, allowed, value)
    return int(value)


def _draw_separated(rng: np.random.Generator, n: int, area: float, separation: float) -> np.ndarray:
    points = np.empty((n, 2))
    for i in range(n):
        for _ in range(MAX_DRAWS_PER_POINT):
            p = rng.uniform(0.0, area, size=2)
            if i == 0 or np.min(np.hypot(*(points[:i] - p).T)) >= separation:
                points[i] = p
                break
        else:
            raise InputError("min_start_separation", f"a separation leaving room for {n} points in the area",
                             separation)
    return points


def _draw_goal(rng: np.random.Generator, start: np.ndarray, area: float, min_distance: float) -> np.ndarray:
    for _ in range(MAX_DRAWS_PER_POINT):
        g = rng.uniform(0.0, area, size=2)
        if math.hypot(*(g - start)) >= min_distance:
            return g
    raise InputError("min_goal_distance", "a distance leaving room for a goal in the area", min_distance)


def sample_scenario(environment: int, run: int, base_seed: int = 0,
                    config: SamplerConfig = SamplerConfig()) -> SampledScenario:
    """Draw the random encounter number ``run`` of an environment (see the module docstring for the rules).

    Parameters
    ----------
    environment : int
        Environment number: a key of :data:`ENVIRONMENTS` (1-5, the paper's) or 6 (a strait with islands,
        :func:`~mmg_casadi.montecarlo.land_sampling.sample_strait`).
    run : int
        Run index (>= 0).
    base_seed : int
        Base seed of the study (>= 0); the generator is seeded with
        ``SeedSequence([base_seed, environment, run])``.
    config : SamplerConfig
        Placement rules.

    Returns
    -------
    SampledScenario
        Starts, goals (L), headings (rad), speeds (fractions of U_des), obstacles (L) and, for environment 6, land.

    Raises
    ------
    InputError
        If ``environment`` is not 1-6 or ``run``/``base_seed`` is not a non-negative integer.

    Examples
    --------
    >>> s = sample_scenario(5, run=0, base_seed=1)
    >>> s.n_ships, s.n_obstacles
    (10, 4)
    >>> bool(np.all(np.linalg.norm(s.goals - s.starts, axis=1) >= 50))
    True
    >>> sample_scenario(7, 0)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: environment: expected an environment number in 1-6, got 7
    """
    if isinstance(environment, bool) or not isinstance(environment, (int, np.integer)) \
            or environment not in ALL_ENVIRONMENTS:
        raise InputError("environment", _ENV_ALLOWED, environment)
    environment = int(environment)
    run = _check_int("run", run, "an integer >= 0")
    base_seed = _check_int("base_seed", base_seed, "an integer >= 0")
    if not isinstance(config, SamplerConfig):
        raise InputError("config", "a SamplerConfig", type(config).__name__)
    if environment == LAND_ENVIRONMENT:
        return SampledScenario(**sample_strait(run, base_seed, config.speed_range),
                               obstacle_radius=float(config.obstacle_radius))
    n_static, n_dynamic = ENVIRONMENTS[environment]
    n_ships = 1 + n_dynamic
    rng = np.random.default_rng(np.random.SeedSequence([base_seed, environment, run]))

    points = _draw_separated(rng, 1 + n_static + n_dynamic, config.area, config.min_start_separation)
    starts = np.vstack([points[:1], points[1 + n_static:]])
    obstacles = points[1:1 + n_static]
    goals = np.array([_draw_goal(rng, s, config.area, config.min_goal_distance) for s in starts])
    headings = rng.uniform(-math.pi, math.pi, size=n_ships)
    speeds = np.concatenate([[1.0], rng.uniform(*config.speed_range, size=n_dynamic)])
    return SampledScenario(environment=environment, run=run, seed=base_seed, starts=starts, goals=goals,
                           headings=headings, speeds=speeds, obstacles=obstacles,
                           obstacle_radius=float(config.obstacle_radius))


TRAFFIC_DENSITY = ENVIRONMENTS[5]
"""Static obstacles and dynamic ships per own ship of :func:`sample_traffic`: environment 5's, in its
``area`` (4 obstacles and 10 ships in 100 L × 100 L)."""


def sample_traffic(n_ships: int, seed: int = 0, config: SamplerConfig = SamplerConfig()) -> SampledScenario:
    """``n_ships`` ships on random crossing routes at environment 5's density, for fleet-scale runs.

    The square's side grows as ``area × sqrt(n_ships / 10)`` so that ships (and ``round(0.4 n_ships)`` static
    obstacles) have environment 5's density; starts, goals, headings and speeds follow the rules of
    :func:`sample_scenario` (the same separation, goal distance and speed range), so routes cross everywhere.
    The result has ``environment = 0`` (generated traffic, not one of the paper's environments).

    Parameters
    ----------
    n_ships : int
        Number of ships (>= 1), the own ship first.
    seed : int
        Seed of the generator (``SeedSequence([seed, 0, n_ships])``).
    config : SamplerConfig
        Placement rules; ``area`` is the side for 10 ships.

    Returns
    -------
    SampledScenario
        The traffic, ``environment = 0`` and ``run = 0``.

    Examples
    --------
    >>> s = sample_traffic(40, seed=1)
    >>> s.n_ships, s.n_obstacles, bool(np.all(s.starts <= 200.0))
    (40, 16, True)
    """
    n_ships = _check_int("n_ships", n_ships, "an integer >= 1", low=1)
    seed = _check_int("seed", seed, "an integer >= 0")
    n_static_env, n_dynamic_env = TRAFFIC_DENSITY
    per_ship = n_static_env / (1 + n_dynamic_env)
    n_static = int(round(per_ship * n_ships))
    area = config.area * math.sqrt(n_ships / (1 + n_dynamic_env))
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0, n_ships]))
    points = _draw_separated(rng, n_ships + n_static, area, config.min_start_separation)
    starts = np.vstack([points[:1], points[1 + n_static:]])
    obstacles = points[1:1 + n_static]
    goals = np.array([_draw_goal(rng, s, area, config.min_goal_distance) for s in starts])
    headings = rng.uniform(-math.pi, math.pi, size=n_ships)
    speeds = np.concatenate([[1.0], rng.uniform(*config.speed_range, size=n_ships - 1)])
    return SampledScenario(environment=0, run=0, seed=seed, starts=starts, goals=goals, headings=headings,
                           speeds=speeds, obstacles=obstacles, obstacle_radius=float(config.obstacle_radius))


def parse_envs(text: str) -> tuple[int, ...]:
    """Parse a CLI list of environments: ``"1-5"``, ``"1,3,5"`` or a mix such as ``"1-2,5"``.

    Returns the environments sorted and without duplicates.

    Parameters
    ----------
    text : str
        Environments as ranges and/or comma-separated numbers.

    Returns
    -------
    tuple of int
        The environments, sorted and without duplicates.

    Examples
    --------
    >>> parse_envs("1-5")
    (1, 2, 3, 4, 5)
    >>> parse_envs("5, 1,3")
    (1, 3, 5)
    >>> parse_envs("0-2")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: envs: expected environment numbers in 1-6 as a range '1-5', ..., got '0-2'
    """
    if not isinstance(text, str) or not text.strip():
        raise InputError("envs", _ENVS_ALLOWED, text)
    envs: set[int] = set()
    for item in text.split(","):
        m = re.fullmatch(r"\s*(\d+)\s*(?:-\s*(\d+)\s*)?", item)
        if m is None:
            raise InputError("envs", _ENVS_ALLOWED, text)
        lo = int(m.group(1))
        hi = int(m.group(2)) if m.group(2) is not None else lo
        if lo > hi or lo not in ALL_ENVIRONMENTS or hi not in ALL_ENVIRONMENTS:
            raise InputError("envs", _ENVS_ALLOWED, text)
        envs.update(range(lo, hi + 1))
    return tuple(sorted(envs))
