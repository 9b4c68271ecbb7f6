"""The vectorised environment :class:`ShipVectorEnv`: N episodes stepped by one call of the compiled step."""

from __future__ import annotations

import math

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from mmg_casadi.closed_loop.simulation import stepper
from mmg_casadi.errors import InputError
from mmg_casadi.gym import core
from mmg_casadi.gym.env import check_options, observation_size
from mmg_casadi.gym.sources import SEED_RANGE, as_source


class ShipVectorEnv(VectorEnv):
    """``num_envs`` episodes of :class:`~mmg_casadi.gym.env.ShipEnv`, stepped together by one call of the compiled
    closed-loop step mapped over them (every column runs the same compiled code as a single environment).

    Sub-environment ``j`` reset with seed ``s + j`` meets the episode of a :class:`~mmg_casadi.gym.env.ShipEnv`
    reset with seed ``s + j``, to the bit. Every episode must have the same scenario shape (ships, obstacles,
    walls, route length, methods: one compiled step); a scenario of another shape is refused. Finished
    sub-environments reset at the next call of :meth:`step` (Gymnasium's ``NEXT_STEP`` autoreset: that call returns
    their first observation with reward 0 and ignores their action).

    Parameters
    ----------
    scenario : Scenario, str, Path or callable
        As for :class:`~mmg_casadi.gym.env.ShipEnv` (a source of one scenario shape, e.g.
        :func:`~mmg_casadi.gym.sources.environment`).
    num_envs : int
        Episodes stepped together (>= 1).
    method, params, action, max_turn_deg, rpm, k_ships, k_hazards, reward
        As for :class:`~mmg_casadi.gym.env.ShipEnv`.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, scenario, num_envs: int, *, method: str | None = None, params: dict | None = None,
                 action: str = "relative", max_turn_deg: float = 45.0, rpm: bool = False, k_ships: int = 4,
                 k_hazards: int = 4, reward: core.RewardConfig | None = None):
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise InputError("num_envs", "an integer >= 1", num_envs)
        self.reward_config = check_options(action, max_turn_deg, k_ships, k_hazards, reward)
        self.source = as_source(scenario, method)
        self.params = dict(params) if params else None
        self.action_mode, self.max_turn = action, math.radians(max_turn_deg)
        self.rpm, self.k_ships, self.k_hazards = bool(rpm), k_ships, k_hazards
        self.num_envs = num_envs
        self.single_action_space = spaces.Box(-1.0, 1.0, shape=(1 + int(self.rpm),), dtype=np.float32)
        self.single_observation_space = spaces.Box(-np.inf, np.inf, shape=(observation_size(k_ships, k_hazards),),
                                                   dtype=np.float32)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self.layout = None
        self._rngs = [seeding.np_random(None)[0] for _ in range(num_envs)]
        self.episodes = [None] * num_envs

    def _new(self, j: int) -> None:
        """Draw sub-environment ``j``'s next scenario and put its initial state into column ``j``."""
        draw = int(self._rngs[j].integers(SEED_RANGE))
        sc = self.source(draw)
        pr = core.commanded_problem(sc, self.params, rpm=self.rpm)
        if self.layout is None:
            self.layout = pr.layout
            self.X = np.zeros((pr.layout.nx, self.num_envs))
            self.P = np.zeros((pr.layout.np, self.num_envs))
            self._step = stepper(pr.layout, self.num_envs)
        elif pr.layout != self.layout:
            raise InputError("scenario", f"scenarios of one shape in a vectorised environment ({self.layout.key()})",
                             pr.layout.key())
        self.X[:, j], self.P[:, j] = pr.x0, pr.p
        self.episodes[j] = core.Episode(sc, self.params, self.rpm, [], draw)

    def reset(self, *, seed=None, options=None):
        """Start an episode in every sub-environment.

        Parameters
        ----------
        seed : int or list of int, optional
            Seed ``s`` seeds sub-environment ``j`` with ``s + j``; a list gives each its own.
        options : dict, optional
            Not used.

        Returns
        -------
        observations : ndarray (num_envs, D) float32
            The first observations.
        infos : dict
            ``t`` and ``to_go`` per sub-environment (arrays).
        """
        if seed is not None:
            seeds = [seed + j for j in range(self.num_envs)] if isinstance(seed, int) else list(seed)
            if len(seeds) != self.num_envs:
                raise InputError("seed", f"an int or {self.num_envs} ints", seed)
            self._rngs = [seeding.np_random(s)[0] for s in seeds]
        for j in range(self.num_envs):
            self._new(j)
        self._statics = core.statics(self.layout, self.P)
        self._flags = core.events(self.layout, self.X)
        self._autoreset = np.zeros(self.num_envs, bool)
        obs, self._to_go, _ = core.observe(self.layout, self.X, self._statics, k_ships=self.k_ships,
                                           k_hazards=self.k_hazards)
        return obs.astype(np.float32), {"t": self.X[0].copy(), "to_go": self._to_go.copy()}

    def step(self, actions):
        """One guidance step of every sub-environment, one call of the mapped compiled step.

        Parameters
        ----------
        actions : array_like (num_envs, A)
            One action per sub-environment (as for :meth:`ShipEnv.step <mmg_casadi.gym.env.ShipEnv.step>`).

        Returns
        -------
        observations : ndarray (num_envs, D) float32
            After the step (the first observation of a sub-environment that reset).
        rewards : ndarray (num_envs,)
            Rewards (0 for one that reset).
        terminations, truncations : ndarray of bool (num_envs,)
            As for a single environment.
        infos : dict
            ``t``, ``to_go`` and ``event`` (str) per sub-environment.
        """
        lay = self.layout
        cmd = core.orders(lay, self.X, self._statics, np.asarray(actions, float).reshape(self.num_envs, -1),
                          mode=self.action_mode, max_turn=self.max_turn)
        core.write_orders(lay, self.X, cmd)
        for j in np.flatnonzero(~self._autoreset):
            self.episodes[j].commands.append(cmd[j].copy())
        X, _aux = self._step(self.X, self.P)
        restart = np.flatnonzero(self._autoreset)
        for j in restart:  # NEXT_STEP autoreset: their step is discarded, a new episode starts
            self._new(j)
            X[:, j] = self.X[:, j]
        self.X = X
        if len(restart):
            st = core.statics(lay, self.P[:, restart])
            for name in ("path", "to_go", "n_path", "stays", "obstacles", "walls", "current", "rpm_range", "t_max"):
                getattr(self._statics, name)[restart] = getattr(st, name)
            self._flags[restart] = core.events(lay, self.X[:, restart])
        after = core.events(lay, self.X)
        obs, to_go, nearest = core.observe(lay, self.X, self._statics, k_ships=self.k_ships,
                                           k_hazards=self.k_hazards)
        r = core.reward(self.reward_config, self._flags, after, self._to_go, to_go, nearest)
        names = np.array([core.event_name(f, self.reward_config.terminate_on) for f in after], dtype=object)
        terminated = names != ""
        truncated = ~terminated & (self.X[0] >= self._statics.t_max - 1e-9)
        r[restart] = 0.0
        terminated[restart] = False
        truncated[restart] = False
        names[restart] = ""
        names[truncated] = "timeout"
        self._flags, self._to_go = after, to_go
        self._autoreset = terminated | truncated
        return obs.astype(np.float32), r, terminated, truncated, {"t": self.X[0].copy(), "to_go": to_go.copy(),
                                                                   "event": names}
