"""An environment's sampling envelope as a parameter vector: the space a falsifier searches.

The Monte Carlo sampler (:func:`~mmg_casadi.montecarlo.sampling.sample_scenario`) draws a scenario from uniform
distributions under a few rules; the *envelope* is the set of every scenario it can draw. :class:`Envelope` writes a
scenario as a vector ``theta`` of named coordinates in their own units, each with its interval, and the rules as
constraints:

Environments 1–5 (:class:`~mmg_casadi.montecarlo.sampling.SamplerConfig`)
    the start and the goal of every ship and the centre of every static obstacle in ``[0, area]²`` (L); the initial
    heading of every ship in ``[-pi, pi)`` (rad, periodic); the speed of every target in ``speed_range`` (the own
    ship sails at the design speed). Constraints: every two starting points (ships and obstacles) at least
    ``min_start_separation`` apart; every goal at least ``min_goal_distance`` from its ship's start.
Environment 6 (:mod:`~mmg_casadi.montecarlo.land_sampling`)
    the strait's width; per island its side, the x of its centre, its gap to the fairway and the side of the
    fairway it lies on (a uniform draw: east below 0.5, as the sampler); per ship the x of its start and goal in
    their end zones, their places across the fairway's band (fractions 0–1), the heading's offset from the goal's
    bearing (±20°) and the target speeds. Constraints: starts at least ``START_SEPARATION`` apart, every route at
    least ``ROUTE_CLEARANCE`` from each island.
Current and wind (optional, :class:`~mmg_casadi.montecarlo.disturbance_sampling.DisturbanceRanges`)
    speed in its range and direction in ``[-180, 180)`` degrees (periodic), as the study draws them per run.

The search works in the unit cube: :meth:`Envelope.to_unit` maps each coordinate to ``[0, 1]`` (periodic ones
wrap). :meth:`Envelope.project` moves a vector into the envelope (boxes clipped, periodic coordinates wrapped,
starting points pushed apart, goals pushed out from their starts) and says whether it got there;
:meth:`Envelope.violation` measures how far a vector is outside (0 inside, the test of a reported failure).
:meth:`Envelope.sample` is the environment's own sampler, so random sampling in the envelope *is* the Monte Carlo
study's sample.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo import land_sampling as strait
from mmg_casadi.montecarlo.disturbance_sampling import ENV_COLUMNS, DisturbanceRanges, sample_disturbance
from mmg_casadi.montecarlo.sampling import ALL_ENVIRONMENTS, ENVIRONMENTS, SampledScenario, SamplerConfig, \
    sample_scenario

PUSH = 1.0 + 1e-9
"""A projected distance lands this factor beyond its bound (inside the envelope after rounding)."""
PROJECTION_SWEEPS = 60
"""Sweeps of pushing starting points apart and goals out before :meth:`Envelope.project` gives up."""


def wrap_angle(a):
    """Angle(s) in rad wrapped to ``[-pi, pi)``.

    Parameters
    ----------
    a : float or array
        Angles (rad).

    Returns
    -------
    float or numpy.ndarray
        The same angles in ``[-pi, pi)``.

    Examples
    --------
    >>> round(float(wrap_angle(3 * math.pi / 2)), 6)
    -1.570796
    """
    return (np.asarray(a, float) + math.pi) % (2 * math.pi) - math.pi


@dataclass(frozen=True)
class Envelope:
    """The sampling envelope of one environment (module docstring) as named coordinates.

    Parameters
    ----------
    environment : int
        Environment 1–6.
    config : SamplerConfig, optional
        The sampler's placement rules (environments 1–5; environment 6 takes only its ``speed_range``).
    disturbance : DisturbanceRanges, optional
        Ranges of the current and the wind searched as well (``None``: calm water, as the paper's study).

    Examples
    --------
    >>> env = Envelope(5)
    >>> env.dimension, env.names[:3]
    (67, ('ship0.start_x', 'ship0.start_y', 'ship1.start_x'))
    >>> theta = env.sample(0)
    >>> env.violation(theta)
    0.0
    >>> env.decode(theta) == sample_scenario(5, 0)
    True
    """

    environment: int
    config: SamplerConfig = SamplerConfig()
    disturbance: DisturbanceRanges | None = None
    names: tuple = field(init=False)
    low: np.ndarray = field(init=False, repr=False, compare=False)
    high: np.ndarray = field(init=False, repr=False, compare=False)
    periodic: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        if self.disturbance is not None and not isinstance(self.disturbance, DisturbanceRanges):
            raise InputError("disturbance", "a DisturbanceRanges or None", type(self.disturbance).__name__)
        coords = self._coordinates()
        dist = self.disturbance
        if dist is not None and dist.current is not None:
            coords += [("current_speed", *dist.current, False), ("current_direction_deg", -180.0, 180.0, True)]
        if dist is not None and dist.wind is not None:
            coords += [("wind_speed", *dist.wind, False), ("wind_direction_deg", -180.0, 180.0, True)]
        object.__setattr__(self, "names", tuple(c[0] for c in coords))
        object.__setattr__(self, "low", np.array([c[1] for c in coords], float))
        object.__setattr__(self, "high", np.array([c[2] for c in coords], float))
        object.__setattr__(self, "periodic", np.array([c[3] for c in coords], bool))

    # ------------------------------------------------------------------------------------------ layout

    @property
    def n_ships(self) -> int:
        """Ships including the own ship."""
        return 1 + (ENVIRONMENTS[self.environment][1] if self.environment in ENVIRONMENTS
                    else strait.NORTHBOUND + strait.SOUTHBOUND)

    @property
    def n_obstacles(self) -> int:
        """Static obstacles (none in environment 6)."""
        return ENVIRONMENTS[self.environment][0] if self.environment in ENVIRONMENTS else 0

    @property
    def dimension(self) -> int:
        """Number of coordinates."""
        return len(self.names)

    def index(self, name: str) -> int:
        """Position of coordinate ``name`` in ``theta``.

        Parameters
        ----------
        name : str
            A name of :attr:`names`.

        Returns
        -------
        int
            Its index.
        """
        return self.names.index(name)

    def _coordinates(self) -> list:
        """``(name, low, high, periodic)`` of every coordinate but the disturbance's (a subclass may define its
        own, with :meth:`decode`, :meth:`sample`, :meth:`violation` and :meth:`project`)."""
        if isinstance(self.environment, bool) or self.environment not in ALL_ENVIRONMENTS:
            raise InputError("environment", "an environment number in 1-6", self.environment)
        return self._square_coords() if self.environment in ENVIRONMENTS else self._strait_coords()

    def _square_coords(self) -> list:
        a, (v0, v1) = self.config.area, self.config.speed_range
        n, s = self.n_ships, self.n_obstacles
        out = []
        for i in range(n):
            out += [(f"ship{i}.start_x", 0.0, a, False), (f"ship{i}.start_y", 0.0, a, False)]
        for i in range(n):
            out += [(f"ship{i}.goal_x", 0.0, a, False), (f"ship{i}.goal_y", 0.0, a, False)]
        out += [(f"ship{i}.heading", -math.pi, math.pi, True) for i in range(n)]
        out += [(f"ship{i}.speed", v0, v1, False) for i in range(1, n)]
        for k in range(s):
            out += [(f"obstacle{k}.x", 0.0, a, False), (f"obstacle{k}.y", 0.0, a, False)]
        return out

    def _strait_coords(self) -> list:
        (w0, w1), (s0, s1), (g0, g1) = strait.WIDTH_RANGE, strait.ISLAND_SIDE, strait.ISLAND_GAP
        spread = math.radians(strait.HEADING_SPREAD_DEG)
        out = [("width", w0, w1, False)]
        for k, x_lo in enumerate((10.0, 75.0)):
            out += [(f"island{k}.side", s0, s1, False), (f"island{k}.x", x_lo, x_lo + 15.0, False),
                    (f"island{k}.gap", g0, g1, False), (f"island{k}.side_draw", 0.0, 1.0, False)]
        for i in range(self.n_ships):
            north = i <= strait.NORTHBOUND
            x0, x1 = (0.0, 90.0) if north else (90.0, 0.0)
            out += [(f"ship{i}.start_x", x0, x0 + 10.0, False), (f"ship{i}.start_band", 0.0, 1.0, False),
                    (f"ship{i}.goal_x", x1, x1 + 10.0, False), (f"ship{i}.goal_band", 0.0, 1.0, False),
                    (f"ship{i}.heading_offset", -spread, spread, False)]
        v0, v1 = self.config.speed_range
        out += [(f"ship{i}.speed", v0, v1, False) for i in range(1, self.n_ships)]
        return out

    # ------------------------------------------------------------------------------------------ unit cube

    def to_unit(self, theta) -> np.ndarray:
        """``theta`` in the unit cube: ``(theta - low) / (high - low)``, periodic coordinates wrapped to [0, 1).

        Parameters
        ----------
        theta : array (dimension,)
            A parameter vector.

        Returns
        -------
        numpy.ndarray (dimension,)
            Its unit coordinates.
        """
        u = (np.asarray(theta, float) - self.low) / (self.high - self.low)
        u[self.periodic] %= 1.0
        return u

    def from_unit(self, u) -> np.ndarray:
        """The parameter vector of unit coordinates ``u`` (periodic ones wrapped, the others not clipped).

        Parameters
        ----------
        u : array (dimension,)
            Unit coordinates.

        Returns
        -------
        numpy.ndarray (dimension,)
            ``low + u (high - low)``.
        """
        u = np.array(u, float)
        u[self.periodic] %= 1.0
        return self.low + u * (self.high - self.low)

    # ------------------------------------------------------------------------------------------ sampling

    def sample(self, run: int, seed: int = 0) -> np.ndarray:
        """The parameter vector of the Monte Carlo study's run ``run`` (its sampler, its disturbance).

        Parameters
        ----------
        run : int
            Run index.
        seed : int, default 0
            Base seed of the sampler.

        Returns
        -------
        numpy.ndarray (dimension,)
            ``encode`` of :func:`~mmg_casadi.montecarlo.sampling.sample_scenario` (and of
            :func:`~mmg_casadi.montecarlo.disturbance_sampling.sample_disturbance` with a disturbance).
        """
        s = sample_scenario(self.environment, run, seed, self.config if self.environment in ENVIRONMENTS
                            else SamplerConfig(speed_range=self.config.speed_range))
        d = sample_disturbance(self.environment, run, seed, self.disturbance) if self._disturbed else None
        return self.encode(s, d)

    @property
    def _disturbed(self) -> bool:
        return self.disturbance is not None and self.disturbance.active

    # ------------------------------------------------------------------------------------------ encode

    def encode(self, s: SampledScenario, disturbance: dict | None = None) -> np.ndarray:
        """The parameter vector of a sampled scenario (and its disturbance).

        Parameters
        ----------
        s : SampledScenario
            A scenario of this environment.
        disturbance : dict, optional
            Its :data:`~mmg_casadi.montecarlo.disturbance_sampling.ENV_COLUMNS` values (needed with a disturbance).

        Returns
        -------
        numpy.ndarray (dimension,)
            The coordinates in the order of :attr:`names`.
        """
        if s.n_ships != self.n_ships or s.n_obstacles != self.n_obstacles:
            raise InputError("scenario", f"{self.n_ships} ships and {self.n_obstacles} obstacles (environment "
                             f"{self.environment})", f"{s.n_ships} ships and {s.n_obstacles} obstacles")
        values = self._encode_square(s) if self.environment in ENVIRONMENTS else self._encode_strait(s)
        for name in self.names[len(values):]:
            if disturbance is None:
                raise InputError("disturbance", f"the values of {', '.join(ENV_COLUMNS)}", None)
            values.append(float(disturbance[name]))
        theta = np.array(values, float)
        theta[self.periodic] = self.low[self.periodic] + (theta[self.periodic] - self.low[self.periodic]) % (
            self.high[self.periodic] - self.low[self.periodic])
        return theta

    def _encode_square(self, s: SampledScenario) -> list:
        return [*s.starts.ravel(), *s.goals.ravel(), *s.headings, *s.speeds[1:], *s.obstacles.ravel()]

    def _encode_strait(self, s: SampledScenario) -> list:
        west, east = s.land[0], s.land[1]
        width = float(east[:, 1].min() - west[:, 1].max())
        lo, hi = _band(width)
        out = [width]
        for poly in s.land[2:4]:
            side = float(poly[:, 0].max() - poly[:, 0].min())
            cx, cy = poly.mean(axis=0)
            east_side = cy > strait.CENTRE_Y
            gap = (cy - hi if east_side else lo - cy) - 0.5 * side
            out += [side, float(cx), float(gap), 0.25 if east_side else 0.75]
        bearing = np.arctan2(s.goals[:, 1] - s.starts[:, 1], s.goals[:, 0] - s.starts[:, 0])
        offsets = wrap_angle(s.headings - bearing)
        for i in range(s.n_ships):
            out += [float(s.starts[i, 0]), float((s.starts[i, 1] - lo) / (hi - lo)), float(s.goals[i, 0]),
                    float((s.goals[i, 1] - lo) / (hi - lo)), float(offsets[i])]
        return out + [float(v) for v in s.speeds[1:]]

    # ------------------------------------------------------------------------------------------ decode

    def decode(self, theta, *, run: int = 0, seed: int = 0) -> SampledScenario:
        """The sampled scenario of a parameter vector (the inverse of :meth:`encode`).

        Parameters
        ----------
        theta : array (dimension,)
            A parameter vector (periodic coordinates are wrapped).
        run, seed : int, default 0
            Labels stored in the scenario.

        Returns
        -------
        SampledScenario
            Starts, goals, headings, speeds, obstacles (and land in environment 6).
        """
        theta = self._wrapped(theta)
        if self.environment in ENVIRONMENTS:
            n, s = self.n_ships, self.n_obstacles
            k = 0
            starts = theta[k:k + 2 * n].reshape(n, 2)
            k += 2 * n
            goals = theta[k:k + 2 * n].reshape(n, 2)
            k += 2 * n
            headings = theta[k:k + n]
            k += n
            speeds = np.concatenate([[1.0], theta[k:k + n - 1]])
            k += n - 1
            obstacles = theta[k:k + 2 * s].reshape(s, 2)
            return SampledScenario(self.environment, run, seed, starts, goals, headings, speeds, obstacles,
                                   float(self.config.obstacle_radius))
        return SampledScenario(**self._strait_fields(theta, run, seed), obstacle_radius=float(
            self.config.obstacle_radius))

    def _strait_fields(self, theta, run, seed) -> dict:
        g = dict(zip(self.names, theta))
        width = g["width"]
        lo, hi = _band(width)
        islands = []
        for k in range(2):
            side, gap = g[f"island{k}.side"], g[f"island{k}.gap"] + 0.5 * g[f"island{k}.side"]
            cy = hi + gap if g[f"island{k}.side_draw"] < 0.5 else lo - gap
            islands.append(strait._square(g[f"island{k}.x"], cy, side))
        n = self.n_ships
        starts = np.array([[g[f"ship{i}.start_x"], lo + g[f"ship{i}.start_band"] * (hi - lo)] for i in range(n)])
        goals = np.array([[g[f"ship{i}.goal_x"], lo + g[f"ship{i}.goal_band"] * (hi - lo)] for i in range(n)])
        bearing = np.arctan2(goals[:, 1] - starts[:, 1], goals[:, 0] - starts[:, 0])
        headings = wrap_angle(bearing + np.array([g[f"ship{i}.heading_offset"] for i in range(n)]))
        speeds = np.concatenate([[1.0], [g[f"ship{i}.speed"] for i in range(1, n)]])
        return {"environment": self.environment, "run": run, "seed": seed, "starts": starts, "goals": goals,
                "headings": headings, "speeds": speeds, "obstacles": np.zeros((0, 2)),
                "land": (*strait.shores(width), *islands)}

    def disturbance_of(self, theta) -> dict:
        """The :data:`~mmg_casadi.montecarlo.disturbance_sampling.ENV_COLUMNS` values of ``theta`` (zero for a
        quantity without a range; empty without a disturbance).

        Parameters
        ----------
        theta : array (dimension,)
            A parameter vector.

        Returns
        -------
        dict
            Table parameter name to value; empty in calm water.
        """
        if not self._disturbed:
            return {}
        theta = self._wrapped(theta)
        return {c: float(theta[self.index(c)]) if c in self.names else 0.0 for c in ENV_COLUMNS}

    def _wrapped(self, theta) -> np.ndarray:
        theta = np.array(theta, float).ravel()
        if theta.shape != (self.dimension,) or not np.all(np.isfinite(theta)):
            raise InputError("theta", f"{self.dimension} finite numbers (the envelope's coordinates)", theta.shape)
        p = self.periodic
        theta[p] = self.low[p] + (theta[p] - self.low[p]) % (self.high[p] - self.low[p])
        return theta

    # ------------------------------------------------------------------------------------------ constraints

    def violation(self, theta) -> float:
        """How far ``theta`` lies outside the envelope: the largest shortfall of a bound or a rule (L or the
        coordinate's unit); 0.0 inside.

        Parameters
        ----------
        theta : array (dimension,)
            A parameter vector.

        Returns
        -------
        float
            0.0 when every coordinate is in its interval and every rule of the sampler holds.
        """
        theta = self._wrapped(theta)
        box = float(np.max(np.concatenate([[0.0], self.low - theta, theta - self.high])))
        s = self.decode(theta)
        if self.environment in ENVIRONMENTS:
            c = self.config
            pts = np.vstack([s.starts[:1], s.obstacles, s.starts[1:]])
            d = np.linalg.norm(pts[:, None] - pts[None], axis=2) + np.eye(len(pts)) * 1e9
            sep = max(0.0, c.min_start_separation - float(d.min())) if len(pts) > 1 else 0.0
            goal = max(0.0, c.min_goal_distance - float(np.min(np.linalg.norm(s.goals - s.starts, axis=1))))
            return max(box, sep, goal)
        d = np.linalg.norm(s.starts[:, None] - s.starts[None], axis=2) + np.eye(self.n_ships) * 1e9
        sep = max(0.0, strait.START_SEPARATION - float(d.min()))
        clear = max([0.0] + [strait.ROUTE_CLEARANCE - strait.route_clearance(a, b, poly)
                             for a, b in zip(s.starts, s.goals) for poly in s.land[2:]])
        return max(box, sep, clear)

    def project(self, theta) -> tuple[np.ndarray, bool]:
        """Move ``theta`` into the envelope: clip to the intervals, wrap periodic coordinates, push starting points
        that are too close apart (both by half the shortfall) and goals that are too close out from their starts
        (radially, else to the nearest admissible point of the square), repeated until every rule holds; points
        still crowded after :data:`PROJECTION_SWEEPS` sweeps are placed one by one in the sampler's order, each
        at the nearest place clear of those before it.

        Parameters
        ----------
        theta : array (dimension,)
            A parameter vector (possibly outside).

        Returns
        -------
        theta : numpy.ndarray (dimension,)
            The projected vector (unchanged if it was inside).
        inside : bool
            Whether the result lies in the envelope (:meth:`violation` is 0); the rules of environment 6's
            islands are not repaired, only checked.
        """
        theta = np.clip(self._wrapped(theta), self.low, self.high)
        if self.violation(theta) == 0.0:
            return theta, True
        if self.environment in ENVIRONMENTS:
            theta = self._repair_square(theta)
        else:
            theta = self._repair_strait(theta)
        return theta, self.violation(theta) == 0.0

    def _repair_square(self, theta) -> np.ndarray:
        c, n, s = self.config, self.n_ships, self.n_obstacles
        start = [self.index(f"ship{i}.start_x") for i in range(n)]
        obst = [self.index(f"obstacle{k}.x") for k in range(s)]
        points = [start[0], *obst, *start[1:]]
        goals = [self.index(f"ship{i}.goal_x") for i in range(n)]
        for _ in range(PROJECTION_SWEEPS):
            moved = _push_apart(theta, points, c.min_start_separation, 0.0, c.area)
            for i in range(n):
                moved |= _push_goal(theta, start[i], goals[i], c.min_goal_distance, c.area)
            if not moved:
                return theta
        _place(theta, points, c.min_start_separation, c.area)  # crowded (e.g. in a corner): point by point
        for i in range(n):
            _push_goal(theta, start[i], goals[i], c.min_goal_distance, c.area)
        return theta

    def _repair_strait(self, theta) -> np.ndarray:
        g = dict(zip(self.names, theta))
        lo, hi = _band(g["width"])
        n = self.n_ships
        for _ in range(PROJECTION_SWEEPS):
            moved = False
            for i in range(n):
                for j in range(i + 1, n):
                    pi = np.array([theta[self.index(f"ship{i}.start_x")],
                                   lo + theta[self.index(f"ship{i}.start_band")] * (hi - lo)])
                    pj = np.array([theta[self.index(f"ship{j}.start_x")],
                                   lo + theta[self.index(f"ship{j}.start_band")] * (hi - lo)])
                    d = float(np.linalg.norm(pi - pj))
                    if d >= strait.START_SEPARATION:
                        continue
                    e = (pi - pj) / d if d > 1e-12 else np.array([0.0, 1.0])
                    shift = 0.5 * (strait.START_SEPARATION * PUSH - d) * e
                    for k, p in ((i, pi + shift), (j, pj - shift)):
                        ix, ib = self.index(f"ship{k}.start_x"), self.index(f"ship{k}.start_band")
                        theta[ix] = np.clip(p[0], self.low[ix], self.high[ix])
                        theta[ib] = np.clip((p[1] - lo) / (hi - lo), 0.0, 1.0)
                    moved = True
            if not moved:
                break
        return theta


def _band(width: float) -> tuple[float, float]:
    """The strait's fairway band (where routes run, 1.5 L inside the channel) for a channel ``width``."""
    return strait.CENTRE_Y - 0.5 * width + 1.5, strait.CENTRE_Y + 0.5 * width - 1.5


def _push_apart(theta, points, separation: float, lo: float, hi: float) -> bool:
    """Push every two points (x at ``theta[k]``, y at ``theta[k + 1]``) closer than ``separation`` apart, each by
    half the shortfall, clipped to ``[lo, hi]²``; returns whether anything moved."""
    moved = False
    for a in range(len(points)):
        for b in range(a + 1, len(points)):
            ka, kb = points[a], points[b]
            pa, pb = theta[ka:ka + 2].copy(), theta[kb:kb + 2].copy()
            d = float(np.linalg.norm(pa - pb))
            if d >= separation:
                continue
            e = (pa - pb) / d if d > 1e-12 else np.array([1.0, 0.0])
            shift = 0.5 * (separation * PUSH - d) * e
            theta[ka:ka + 2] = np.clip(pa + shift, lo, hi)
            theta[kb:kb + 2] = np.clip(pb - shift, lo, hi)
            moved = True
    return moved


def _place(theta, points, separation: float, area: float) -> None:
    """Place the points one by one, in the sampler's order: a point closer than ``separation`` to one placed
    before moves to the nearest place in ``[0, area]²`` that is not (on rings about it, 5° apart, radii growing
    by a tenth of the separation)."""
    placed: list[np.ndarray] = []
    ang = np.linspace(-math.pi, math.pi, 73)[:-1]
    ring = np.column_stack([np.cos(ang), np.sin(ang)])
    for k in points:
        p = theta[k:k + 2].copy()
        if placed and np.min(np.linalg.norm(np.array(placed) - p, axis=1)) < separation:
            for r in np.arange(0.1, 1.5 * area, 0.1) * separation:
                cands = p + r * ring
                cands = cands[np.all((cands >= 0.0) & (cands <= area), axis=1)]
                ok = [q for q in cands if np.min(np.linalg.norm(np.array(placed) - q, axis=1)) >= separation * PUSH]
                if ok:
                    p = ok[0]
                    break
        theta[k:k + 2] = p
        placed.append(p)


def _push_goal(theta, k_start: int, k_goal: int, distance: float, area: float) -> bool:
    """Move a goal closer than ``distance`` to its start out to that distance: radially if that stays in the
    square, else to the nearest admissible point (on the circle inside the square, or a corner)."""
    s, g = theta[k_start:k_start + 2], theta[k_goal:k_goal + 2]
    d = float(np.linalg.norm(g - s))
    if d >= distance:
        return False
    e = (g - s) / d if d > 1e-12 else np.array([1.0, 0.0])
    radial = s + distance * PUSH * e
    if np.all((radial >= 0.0) & (radial <= area)):
        theta[k_goal:k_goal + 2] = radial
        return True
    ang = np.linspace(-math.pi, math.pi, 721)[:-1]
    ring = s + distance * PUSH * np.column_stack([np.cos(ang), np.sin(ang)])
    corners = np.array([[0.0, 0.0], [0.0, area], [area, 0.0], [area, area]])
    cands = np.vstack([ring[np.all((ring >= 0.0) & (ring <= area), axis=1)],
                       corners[np.linalg.norm(corners - s, axis=1) >= distance]])
    theta[k_goal:k_goal + 2] = cands[int(np.argmin(np.linalg.norm(cands - g, axis=1)))]
    return True
