"""The single-ship Gymnasium environment :class:`ShipEnv` (documented in :mod:`mmg_casadi.gym`)."""

from __future__ import annotations

import math

import gymnasium
import numpy as np
from gymnasium import spaces

from mmg_casadi.closed_loop.simulation import stepper
from mmg_casadi.errors import InputError
from mmg_casadi.gym import core
from mmg_casadi.gym.sources import SEED_RANGE, as_source

ACTION_MODES = ("relative", "absolute")
"""How the heading action is read: an alteration from the present heading, or a heading."""


def observation_size(k_ships: int, k_hazards: int) -> int:
    """Length of the observation vector.

    Parameters
    ----------
    k_ships, k_hazards : int
        Slots of other ships and of hazards.

    Returns
    -------
    int
        ``6 + 4 + 6 k_ships + 4 k_hazards``.
    """
    return (len(core.OWN_FEATURES) + len(core.WAYPOINT_FEATURES) + k_ships * len(core.SHIP_FEATURES)
            + k_hazards * len(core.HAZARD_FEATURES))


def check_options(action: str, max_turn_deg: float, k_ships: int, k_hazards: int, reward) -> core.RewardConfig:
    """Check the options of an environment; returns the reward configuration.

    Parameters
    ----------
    action : str
        One of :data:`ACTION_MODES`.
    max_turn_deg : float
        Largest alteration of a relative action (deg, (0, 180]).
    k_ships, k_hazards : int
        Observation slots (>= 0).
    reward : RewardConfig or None
        The reward (None: the defaults).

    Returns
    -------
    RewardConfig
        ``reward`` or the default one.
    """
    if action not in ACTION_MODES:
        raise InputError("action", f"one of: {', '.join(ACTION_MODES)}", action)
    if isinstance(max_turn_deg, bool) or not isinstance(max_turn_deg, (int, float)) or not 0 < max_turn_deg <= 180:
        raise InputError("max_turn_deg", "a number in (0, 180] deg", max_turn_deg)
    for name, k in (("k_ships", k_ships), ("k_hazards", k_hazards)):
        if isinstance(k, bool) or not isinstance(k, int) or k < 0:
            raise InputError(name, "an integer >= 0", k)
    reward = core.RewardConfig() if reward is None else reward
    if not isinstance(reward, core.RewardConfig):
        raise InputError("reward", "a mmg_casadi.gym.RewardConfig", type(reward).__name__)
    return reward


class ShipEnv(gymnasium.Env):
    """The own ship (the scenario's first) steered by an agent, one guidance step per :meth:`step`.

    Parameters
    ----------
    scenario : Scenario, str, Path or callable
        Where episodes come from (:func:`mmg_casadi.gym.sources.as_source`): a scenario, a scenario file, a packaged
        scenario's name or a source ``seed -> Scenario`` (:func:`~mmg_casadi.gym.sources.environment`,
        :func:`~mmg_casadi.gym.sources.traffic`, :func:`~mmg_casadi.gym.sources.encounters`).
    method : str, optional
        The other ships' method (default: the scenario's).
    params : dict, optional
        Parameter overrides (the table's names; e.g. ``dt``, ``t_max``, ``r_safe``).
    action : {"relative", "absolute"}, default 'relative'
        The heading action in [-1, 1]: ``max_turn_deg`` × a from the present heading, or the heading π × a.
    max_turn_deg : float, default 45.0
        Largest alteration of a relative action (deg).
    rpm : bool, default False
        A second action in [-1, 1] orders the propeller speed (dead slow ahead .. maximum rpm); without it the ship
        keeps her service speed exactly.
    k_ships, k_hazards : int, default 4
        Nearest other ships and hazards in the observation.
    reward : RewardConfig, optional
        Reward weights and the events that end an episode.
    """

    metadata = {"render_modes": []}

    def __init__(self, scenario, *, method: str | None = None, params: dict | None = None, action: str = "relative",
                 max_turn_deg: float = 45.0, rpm: bool = False, k_ships: int = 4, k_hazards: int = 4,
                 reward: core.RewardConfig | None = None):
        self.reward_config = check_options(action, max_turn_deg, k_ships, k_hazards, reward)
        self.source = as_source(scenario, method)
        self.params = dict(params) if params else None
        self.action_mode, self.max_turn = action, math.radians(max_turn_deg)
        self.rpm, self.k_ships, self.k_hazards = bool(rpm), k_ships, k_hazards
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1 + int(self.rpm),), dtype=np.float32)
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(observation_size(k_ships, k_hazards),),
                                            dtype=np.float32)
        self.problem = None
        self.state = None
        self.episode = None

    def _observe(self):
        obs, to_go, nearest = core.observe(self.problem.layout, self.state[:, None], self._statics,
                                           k_ships=self.k_ships, k_hazards=self.k_hazards)
        return obs[0].astype(np.float32), float(to_go[0]), nearest

    def _info(self, event: str) -> dict:
        return {"t": float(self.state[0]), "event": event, "to_go": self._to_go, "draw": self.episode.seed}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Start an episode: draw its scenario from the source with the environment's random generator.

        Parameters
        ----------
        seed : int, optional
            Seeds the random generator (the same seed, the same episode).
        options : dict, optional
            ``{"scenario": Scenario}`` runs that scenario instead of drawing one.

        Returns
        -------
        observation : ndarray (float32)
            The first observation.
        info : dict
            ``t``, ``event`` (``""``), ``to_go`` (L) and ``draw`` (the seed the scenario was drawn with).
        """
        super().reset(seed=seed)
        draw = int(self.np_random.integers(SEED_RANGE))
        sc = (options or {}).get("scenario") or self.source(draw)
        self.problem = core.commanded_problem(sc, self.params, rpm=self.rpm)
        self._step = stepper(self.problem.layout)
        self._statics = core.statics(self.problem.layout, self.problem.p[:, None])
        self.state = np.array(self.problem.x0, float)
        self.episode = core.Episode(sc, self.params, self.rpm, [], draw)
        obs, self._to_go, _ = self._observe()
        self._flags = core.events(self.problem.layout, self.state[:, None])
        return obs, self._info("")

    def step(self, action):
        """One guidance step with the own ship's orders from ``action``.

        Parameters
        ----------
        action : array_like
            In :attr:`action_space` (values outside [-1, 1] are clipped).

        Returns
        -------
        observation : ndarray (float32)
            After the step.
        reward : float
            :class:`~mmg_casadi.gym.core.RewardConfig`.
        terminated : bool
            An event of ``reward.terminate_on`` happened (goal, collision, grounding, diverged).
        truncated : bool
            The horizon ``t_max`` is reached.
        info : dict
            ``t``, ``event`` (the event that ends the episode or ``""``; ``"timeout"`` at truncation), ``to_go``
            and ``draw``.
        """
        if self.problem is None:
            raise InputError("step", "a call of reset() first")
        lay = self.problem.layout
        X = self.state[:, None].copy()
        cmd = core.orders(lay, X, self._statics, np.asarray(action, float)[None], mode=self.action_mode,
                          max_turn=self.max_turn)
        core.write_orders(lay, X, cmd)
        self.episode.commands.append(cmd[0].copy())
        x_next, _aux = self._step(X[:, 0], self.problem.p)
        self.state = x_next.ravel()
        after = core.events(lay, self.state[:, None])
        obs, to_go, nearest = self._observe()
        r = core.reward(self.reward_config, self._flags, after, np.array([self._to_go]), np.array([to_go]), nearest)
        self._to_go, self._flags = to_go, after
        event = core.event_name(after[0], self.reward_config.terminate_on)
        terminated = bool(event)
        truncated = bool(not terminated and self.state[0] >= self._statics.t_max[0] - 1e-9)
        return obs, float(r[0]), terminated, truncated, self._info("timeout" if truncated else event)
