"""Writing a scenario (:class:`~mmg_casadi.scenarios.scenario.Scenario`) as a dict shaped like a scenario file or
as its TOML text, the inverse of :func:`~mmg_casadi.scenarios.scenario.scenario_from_dict` (re-exported by
:mod:`mmg_casadi.scenarios.scenario`).
"""

from __future__ import annotations

import copy

import tomli_w

from mmg_casadi.params import PARAMETERS

SETTINGS_FIELDS = ("dt", "t_max", "r_safe", "collision_distance", "goal_tolerance")
"""Table parameters that are fields of :class:`~mmg_casadi.scenarios.scenario.Settings` (the others are kept in its
``params``)."""
PARAM_KEYS = tuple(k for k in PARAMETERS if k not in SETTINGS_FIELDS)
"""Table parameters written from ``Settings.params``."""


def _ship_dict(ship) -> dict:
    """One ship as a scenario-file table (a replayed ship with its track inline)."""
    if ship.track is not None:
        d = {"name": ship.name, "track": ship.track.to_dict(), "stays": ship.stays}
        d.update({k: getattr(ship, k) for k in ("vessel", "length_m", "beam_m") if getattr(ship, k) is not None})
        if ship.metadata:
            d["metadata"] = copy.deepcopy(ship.metadata)
        return d
    d = {"name": ship.name, "start": list(ship.start), "heading": ship.heading_deg, "speed": ship.speed,
         "waypoints": [list(p) for p in ship.waypoints]}
    if ship.method is not None:
        d["method"] = ship.method
    d["stays"] = ship.stays
    if ship.vessel is not None:
        d["vessel"] = ship.vessel
    if ship.speeds is not None:
        d["speeds"] = list(ship.speeds)
    for k in ("length_m", "beam_m", "route"):
        if getattr(ship, k) is not None:
            d[k] = getattr(ship, k)
    for k, name in (("behaviour", "behaviour"), ("late_delay", "late_delay"), ("wrong_turn_deg", "wrong_turn")):
        if getattr(ship, k, None) is not None:
            d[name] = getattr(ship, k)
    if ship.metadata:
        d["metadata"] = copy.deepcopy(ship.metadata)
    return d


def scenario_to_dict(s) -> dict:
    """``s`` as a dict shaped like a scenario file (the inverse of :func:`scenario_from_dict`).

    Parameters
    ----------
    s : Scenario
        The scenario to convert.

    Returns
    -------
    dict
        ``settings``, ``ships``, ``obstacles``, ``walls`` and ``land`` as plain lists, dicts and numbers.

    Examples
    --------
    >>> from mmg_casadi.scenarios.scenario import Scenario, Settings, ShipSpec, scenario_from_dict
    >>> s = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 1, [[50, 0]])])
    >>> scenario_to_dict(s)["ships"][0]["waypoints"]
    [[50.0, 0.0]]
    >>> scenario_from_dict(scenario_to_dict(s)) == s
    True
    """
    st = s.settings
    settings = {"method": st.method, "dt": st.dt, "t_max": st.t_max, "r_safe": st.r_safe,
                "collision_distance": st.collision_distance, "goal_tolerance": st.goal_tolerance}
    settings.update({k: st.params[k] for k in PARAM_KEYS if k in st.params})
    return {
        "settings": settings,
        "ships": [_ship_dict(ship) for ship in s.ships],
        "obstacles": [{"position": list(ob.position), "radius": ob.radius} for ob in s.obstacles],
        "walls": [{"points": [list(p) for p in w.points]} for w in s.walls],
        "land": [{"points": [list(p) for p in a.points]} for a in s.land],
    }


def dump_scenario(s) -> str:
    """``s`` as scenario-file TOML text; ``scenario_from_dict(tomllib.loads(dump_scenario(s))) == s``.

    :func:`scenario_to_dict` without its empty ``obstacles``, ``walls`` and ``land``, written by ``tomli_w.dumps``.

    Parameters
    ----------
    s : Scenario
        The scenario to write.

    Returns
    -------
    str
        TOML text of a scenario file.

    Examples
    --------
    >>> import tomllib
    >>> from mmg_casadi.scenarios.scenario import Scenario, Settings, ShipSpec, scenario_from_dict
    >>> s = Scenario(Settings("none"), [ShipSpec("own", [0, 0], 0, 1, [[50, 0]])])
    >>> print(dump_scenario(s))
    [settings]
    method = "none"
    dt = 0.25
    t_max = 300.0
    r_safe = 15.0
    collision_distance = 2.0
    goal_tolerance = 3.0
    <BLANKLINE>
    [[ships]]
    name = "own"
    start = [
        0.0,
        0.0,
    ]
    heading = 0.0
    speed = 1.0
    waypoints = [
        [
            50.0,
            0.0,
        ],
    ]
    stays = false
    <BLANKLINE>
    >>> scenario_from_dict(tomllib.loads(dump_scenario(s))) == s
    True
    """
    return tomli_w.dumps({k: v for k, v in scenario_to_dict(s).items() if v})
