"""Gymnasium environments of the closed loop, for learning methods (optional extra: ``pip install mmg-casadi[gym]``).

:class:`ShipEnv` hands the own ship (the scenario's first ship) to an agent; every other ship keeps its
registered method (any of :data:`mmg_casadi.guidance.methods.METHODS`, plugins included). :class:`ShipVectorEnv`
steps ``N`` episodes with one call of the compiled step mapped over them.

Step
    One guidance step ``dt`` of the compiled closed loop (:func:`~mmg_casadi.closed_loop.simulation.stepper`): the
    own ship is a *commanded* ship (``Layout.commanded``): her
    PD heading controller steers the heading the action orders (written into her ``command_heading`` state row)
    and her engine keeps her service propeller speed exactly, or follows the ordered rpm (``rpm=True``). No ILOS,
    no method, no walls' field for her; the MMG model, the engine, the other ships' guidance and the bookkeeping
    (waypoint switching, collisions, groundings) are those of every rollout.
Action
    ``Box(-1, 1)``: the heading, as an alteration of ``max_turn_deg`` × a from the present heading
    (``action="relative"``, default) or the heading π × a (rad from north towards east, ``"absolute"``); with
    ``rpm=True`` a second entry orders the propeller speed from dead slow ahead (-1) to the maximum rpm (+1)
    (``engine_dead_slow``, ``engine_rpm_max``).
Observation
    ``Box(-inf, inf)`` float32, in ship lengths L and U (the own ship's frame: ahead, starboard):
    :data:`~mmg_casadi.gym.core.OWN_FEATURES` (6), :data:`~mmg_casadi.gym.core.WAYPOINT_FEATURES` (4), then
    ``k_ships`` slots of :data:`~mmg_casadi.gym.core.SHIP_FEATURES` (6 each; the nearest present ships, zeros for
    an empty slot) and ``k_hazards`` slots of :data:`~mmg_casadi.gym.core.HAZARD_FEATURES` (4 each; static
    obstacles, channel walls and land edges by clearance).
Reward and end
    :class:`~mmg_casadi.gym.core.RewardConfig`: progress along the route, a cost per step, a bonus at the goal,
    penalties at the first collision, grounding or divergence (each once), optionally the nearness of the nearest
    ship. An episode terminates at an event of ``reward.terminate_on`` (goal, collision, grounding, diverged by
    default) and is truncated at the horizon ``t_max`` (``info["event"] == "timeout"``).
Scenarios
    :mod:`mmg_casadi.gym.sources`: a scenario, a file or a packaged scenario, or a generator: an environment of the
    Monte Carlo sampler (:func:`~mmg_casadi.gym.sources.environment`), random traffic
    (:func:`~mmg_casadi.gym.sources.traffic`), a standard encounter set (:func:`~mmg_casadi.gym.sources.encounters`).
    The reset's seed draws the scenario: the same seed, the same episode.
Replay
    ``env.episode`` (:class:`~mmg_casadi.gym.core.Episode`) records the scenario and the orders written into the
    state; :meth:`Episode.rollout <mmg_casadi.gym.core.Episode.rollout>` rolls them out with
    :func:`~mmg_casadi.closed_loop.simulation.simulate` (``commands=``), the same compiled step: equal to the
    episode to the bit.

Examples
--------
>>> from mmg_casadi.gym import ShipEnv
>>> env = ShipEnv("head_on", method="colregs-vortex", params={"t_max": 5.0})
>>> obs, info = env.reset(seed=0)
>>> obs.shape, env.action_space.shape
((50,), (1,))
>>> obs, r, terminated, truncated, info = env.step([0.5])   # 22.5 deg to starboard of the present heading
>>> terminated, truncated, info["t"]
(False, False, 0.25)
"""

from mmg_casadi.gym.core import EVENTS, Episode, RewardConfig
from mmg_casadi.gym.env import ShipEnv
from mmg_casadi.gym.sources import as_source, encounters, environment, traffic
from mmg_casadi.gym.vector import ShipVectorEnv

__all__ = ["EVENTS", "Episode", "RewardConfig", "ShipEnv", "ShipVectorEnv", "as_source", "encounters",
           "environment", "traffic"]
