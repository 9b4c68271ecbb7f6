"""A constructed envelope whose failing region is known in closed form: the check of a falsifier.

:class:`CrossingCase`: the own ship sails north from the origin to ``(length, 0)``; one target starts on a circle
of radius ``R`` about the own ship's start, at the bearing ``beta`` (the only coordinate), and sails due west
(heading −90°) at the speed ``v`` to a goal far beyond. With the method ``none`` both hold their courses and speeds
(they start on their routes at their steady speeds), so their relative motion is a straight line: the own ship at
``(t, 0)``, the target at ``(R cos beta, R sin beta − v t)``. Its closest approach is

    d_cpa(beta) = R abs(sin(beta − phi)),   phi = atan(v),   at t* = R (cos beta + v sin beta) / (1 + v²),

and the ships collide (``d_cpa`` below the collision distance ``c``, with ``t* > 0``) exactly for ``beta`` in

    (phi − asin(c/R), phi + asin(c/R)):

with ``R = 30 L``, ``v = 1`` and ``c = 2 L`` the bearings 45° ± 3.82°, 2.1 % of the circle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mmg_casadi.falsify.envelope import Envelope, wrap_angle
from mmg_casadi.montecarlo.sampling import SampledScenario


@dataclass(frozen=True)
class CrossingCase(Envelope):
    """One target crossing the own ship's route, the bearing of its start the only coordinate (module docstring).

    Parameters
    ----------
    environment : int, default 0
        A label (0: not one of the study's environments).
    radius : float, default 30
        Distance of the target's start from the own ship's start (L).
    target_speed : float, default 1
        The target's speed (fraction of the design speed).
    length : float, default 100
        Length of both ships' routes (L).
    config : SamplerConfig, optional
        As for :class:`~mmg_casadi.falsify.envelope.Envelope` (the sampler's settings; unused by the one coordinate).
    disturbance : DisturbanceRanges, optional
        As for :class:`~mmg_casadi.falsify.envelope.Envelope` (None: calm water).

    Examples
    --------
    >>> case = CrossingCase()
    >>> lo, hi = case.failing_bearings(2.0)
    >>> round(math.degrees(lo), 2), round(math.degrees(hi), 2)
    (41.18, 48.82)
    >>> s = case.decode([math.radians(45.0)])
    >>> s.starts.round(3).tolist(), round(float(np.degrees(s.headings[1])), 1)
    ([[0.0, 0.0], [21.213, 21.213]], -90.0)
    """

    environment: int = 0
    radius: float = 30.0
    target_speed: float = 1.0
    length: float = 100.0

    def _coordinates(self) -> list:
        return [("target.bearing", -math.pi, math.pi, True)]

    @property
    def n_ships(self) -> int:
        """The own ship and the target."""
        return 2

    @property
    def n_obstacles(self) -> int:
        """No obstacle."""
        return 0

    def sample(self, run: int, seed: int = 0) -> np.ndarray:
        """A bearing uniform on the circle (``SeedSequence([seed, 0, run])``).

        Parameters
        ----------
        run : int
            Run index.
        seed : int, default 0
            Base seed.

        Returns
        -------
        numpy.ndarray (1,)
            The bearing (rad).
        """
        rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0, int(run)]))
        return np.array([rng.uniform(-math.pi, math.pi)])

    def decode(self, theta, *, run: int = 0, seed: int = 0) -> SampledScenario:
        """The two ships of bearing ``theta[0]`` (module docstring).

        Parameters
        ----------
        theta : array (1,)
            The bearing (rad).
        run, seed : int, default 0
            Labels stored in the scenario.

        Returns
        -------
        SampledScenario
            The own ship and the target.
        """
        beta = float(wrap_angle(np.asarray(theta, float).ravel()[0]))
        start = self.radius * np.array([math.cos(beta), math.sin(beta)])
        starts = np.array([[0.0, 0.0], start])
        goals = np.array([[self.length, 0.0], start + [0.0, -self.length]])
        return SampledScenario(self.environment, run, seed, starts, goals, np.array([0.0, -math.pi / 2]),
                               np.array([1.0, self.target_speed]), np.zeros((0, 2)))

    def violation(self, theta) -> float:
        """0.0: every bearing is in the envelope.

        Parameters
        ----------
        theta : array (1,)
            The bearing (rad).

        Returns
        -------
        float
            0.0.
        """
        self._wrapped(theta)
        return 0.0

    def project(self, theta) -> tuple[np.ndarray, bool]:
        """The bearing wrapped to ``[-pi, pi)``.

        Parameters
        ----------
        theta : array (1,)
            The bearing (rad).

        Returns
        -------
        tuple
            The wrapped bearing and True.
        """
        return self._wrapped(theta), True

    def closest_approach(self, beta: float) -> tuple[float, float]:
        """The straight-line closest approach ``d_cpa`` (L) and its time ``t*`` (L/U) of bearing ``beta``.

        Parameters
        ----------
        beta : float
            The bearing (rad).

        Returns
        -------
        tuple of float
            ``(d_cpa, t*)``.
        """
        v, R = self.target_speed, self.radius
        return (R * abs(math.sin(beta - math.atan(v))),
                R * (math.cos(beta) + v * math.sin(beta)) / (1.0 + v * v))

    def failing_bearings(self, collision_distance: float) -> tuple[float, float]:
        """The interval of bearings (rad) for which the two ships collide (module docstring).

        Parameters
        ----------
        collision_distance : float
            The collision distance (L).

        Returns
        -------
        tuple of float
            ``(phi − asin(c/R), phi + asin(c/R))``.
        """
        phi = math.atan(self.target_speed)
        half = math.asin(collision_distance / self.radius)
        return phi - half, phi + half
