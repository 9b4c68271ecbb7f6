"""The paper's scenarios as :class:`~mmg_casadi.scenarios.scenario.Scenario` objects, shared by the studies and tuning.

The encounters are the files shipped in ``mmg_casadi/data/scenarios/`` (which double as examples); this module
adds the paper's variants of them (the static obstacle with its goal at 60 L, the obstacle off the starboard bow)
and the waypoint square.

Examples
--------
>>> sorted(static_obstacle_cases())
['goal-50', 'goal-60', 'starboard-bow']
>>> waypoint_square().ships[0].waypoints[-1]
(0.0, 0.0)
"""

from __future__ import annotations

import dataclasses

from mmg_casadi.scenarios.scenario import Scenario, scenario_from_dict
from mmg_casadi.scenarios.run import packaged_scenario

SQUARE_SIDE = 25.0
"""Side of the waypoint square (L): our choice, the paper gives no size (CE/MCTE then come closest to its)."""


def waypoint_square(side: float = SQUARE_SIDE) -> Scenario:
    """One ship from the origin heading north around a square of ``side`` L (four waypoints, the last one back
    at the start), ILOS + PD only, horizon 600 L/U (paper §Waypoint Tracking).

    Parameters
    ----------
    side : float
        Side length (L).

    Returns
    -------
    Scenario
        The waypoint-tracking scenario (method ``none``).
    """
    wps = [[side, 0.0], [side, side], [0.0, side], [0.0, 0.0]]
    d = {"settings": {"method": "none", "t_max": 600.0},
         "ships": [{"name": "own", "start": [0.0, 0.0], "heading": 0.0, "speed": 1.0, "waypoints": wps}]}
    return scenario_from_dict(d, source="waypoint-square")


def static_obstacle_cases() -> dict[str, Scenario]:
    """Own ship from the origin heading north, obstacle of radius L/2 at (25, 0) L, goal at (50, 0) L
    (``goal-50``, the shipped file) or (60, 0) L (``goal-60``); ``starboard-bow`` puts the obstacle at
    (25, 1.5) L, the paper's sink-vortex failure mode (its coordinates are not given).

    Returns
    -------
    dict of Scenario
        ``"goal-50"``, ``"goal-60"`` and ``"starboard-bow"``.
    """
    base = packaged_scenario("static_obstacle")
    own = base.ships[0]
    ob = base.obstacles[0]
    return {
        "goal-50": base,
        "goal-60": dataclasses.replace(base, ships=(dataclasses.replace(own, waypoints=((60.0, 0.0),)),)),
        "starboard-bow": dataclasses.replace(base, obstacles=(dataclasses.replace(ob, position=(25.0, 1.5)),)),
    }


def colregs_cases() -> dict[str, Scenario]:
    """COLREG rules 13–15: overtaking, head-on and crossing (the shipped files).

    Returns
    -------
    dict of Scenario
        ``"overtaking"``, ``"head-on"`` and ``"crossing"``.
    """
    return {"overtaking": packaged_scenario("overtaking"), "head-on": packaged_scenario("head_on"),
            "crossing": packaged_scenario("crossing")}


def conflict_cases() -> dict[str, Scenario]:
    """The three-ship conflicting-responsibility case (the shipped file).

    Returns
    -------
    dict of Scenario
        ``"three-ships"``.
    """
    return {"three-ships": packaged_scenario("conflict")}


def narrow_channel_cases() -> dict[str, Scenario]:
    """Head-on in a 10 L wide channel along the diagonal (the shipped file).

    Returns
    -------
    dict of Scenario
        ``"head-on"``.
    """
    return {"head-on": packaged_scenario("narrow_channel")}


def paper_encounters() -> dict[str, Scenario]:
    """The encounters the tuning trains on: static obstacle (goal 50 L), the three COLREG cases and the conflict.

    Returns
    -------
    dict of Scenario
        ``"static-obstacle"``, ``"overtaking"``, ``"head-on"``, ``"crossing"`` and ``"conflict"``.

    Examples
    --------
    >>> list(paper_encounters())
    ['static-obstacle', 'overtaking', 'head-on', 'crossing', 'conflict']
    """
    return {"static-obstacle": static_obstacle_cases()["goal-50"], **colregs_cases(),
            "conflict": conflict_cases()["three-ships"]}
