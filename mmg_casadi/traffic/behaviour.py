"""Target behaviours inside the compiled step: holding, giving way late, turning the wrong way.

A ship listed in ``Layout.traffic`` keeps her method (the
layout's) and gets four numeric inputs (:data:`SHIP_INPUTS`) that select what she does with it, so that every run of
a study with a mix of behaviours shares one compiled step whatever each ship drew:

``hold`` = 1
    she holds course and speed: she steers her route by ILOS as a ship of the method ``"none"`` does (no method in
    charge, no turn limit, no goal capture of her method), whatever comes near.
``delay`` > 0 (giving way late)
    her method takes charge only once it has wanted to for ``delay`` (L/U): a clock (state row ``late_clock``) runs
    while her method would be in charge (a neighbour within R_safe or her method engaged) and is reset when it
    would not; before the clock reaches the delay she steers her route. With ``delay = 0`` she is a ship of her
    method exactly (:func:`mmg_casadi.closed_loop.behaviours.gate` selects her method's own values).
``wrong`` = 1 (turning the wrong way)
    she holds course and speed (``hold``) except in a head-on or crossing risk: when a ship within R_safe and
    forward of her beam (relative bearing within 112.5 deg) closes on her with a passing distance below
    ``target_wrong_dcpa``, she turns to port by ``turn`` (rad) from her heading at that moment (state rows
    ``wrong_on``, ``wrong_psi``) and holds that heading while any ship within R_safe still closes on her, then
    returns to her route.

A change of mind (intent) and a replayed AIS track need nothing in the step: the first is a route with a waypoint
and a leg speed (:mod:`mmg_casadi.traffic.sample`), the second a replayed ship (:mod:`mmg_casadi.closed_loop.replay`).
"""

from __future__ import annotations

import math


ROWS = ("late_clock", "wrong_on", "wrong_psi")
"""State rows of every ship of a layout with traffic ships."""
SHIP_INPUTS = ("hold", "delay", "wrong", "turn")
"""Numeric inputs of each traffic ship, in order: 0/1, L/U, 0/1, rad."""
INPUTS = ("target_wrong_dcpa",)
"""Global numeric inputs of a layout with traffic ships (L)."""
FORWARD_COS = math.cos(math.radians(112.5))
"""A ship is forward of the beam within 112.5 deg of the bow (COLREG Rule 22's sector of a masthead light)."""


def split(layout, p, i: int):
    """The traffic block of a parameter vector from row ``i``.

    Parameters
    ----------
    layout : Layout
        A layout with traffic ships.
    p : SX, MX, DM or ndarray
        The parameter vector.
    i : int
        The block's first row.

    Returns
    -------
    (dict, int)
        ``{ship: {name: value}, "target_wrong_dcpa": value}`` and the row after the block.
    """
    out = {}
    for ship in layout.traffic:
        out[ship] = {k: p[i + n] for n, k in enumerate(SHIP_INPUTS)}
        i += len(SHIP_INPUTS)
    for k in INPUTS:
        out[k] = p[i]
        i += 1
    return out, i


def values(layout, ships: list[dict], globals_: dict) -> list[float]:
    """The traffic block's values: per traffic ship ``ships[i]["behaviour"]`` (a dict of :data:`SHIP_INPUTS`,
    missing ones 0), then the global inputs.

    Parameters
    ----------
    layout : Layout
        A layout with traffic ships.
    ships : list of dict
        Per-ship inputs of :func:`~mmg_casadi.closed_loop.layout.pack_params`.
    globals_ : dict
        The step's numeric inputs (:func:`~mmg_casadi.closed_loop.layout.step_values`).

    Returns
    -------
    list of float
        The block.
    """
    out = []
    for i in layout.traffic:
        b = ships[i].get("behaviour") or {}
        out += [float(b.get(k, 0.0)) for k in SHIP_INPUTS]
    return out + [float(globals_[k]) for k in INPUTS]


def inputs_of(kind: str, delay: float = 0.0, turn_rad: float = 0.0) -> dict:
    """The :data:`SHIP_INPUTS` of a behaviour.

    Parameters
    ----------
    kind : str
        ``"avoid"``, ``"hold"``, ``"late"``, ``"wrong"`` or ``"intent"`` (an intent ship holds her route).
    delay : float
        The late ship's delay (L/U).
    turn_rad : float
        The wrong-way ship's turn to port (rad).

    Returns
    -------
    dict
        Name to value.

    Examples
    --------
    >>> inputs_of("late", delay=3.0)
    {'hold': 0.0, 'delay': 3.0, 'wrong': 0.0, 'turn': 0.0}
    """
    return {"hold": float(kind in ("hold", "intent", "wrong")), "delay": float(delay) if kind == "late" else 0.0,
            "wrong": float(kind == "wrong"), "turn": float(turn_rad) if kind == "wrong" else 0.0}


FILE_BEHAVIOURS = ("avoid", "hold", "late", "wrong", "intent")
"""Values of a scenario file's per-ship ``behaviour`` (``intent``: she holds her route, whose waypoint is where she
changes her mind; a replayed AIS track is a ship with a ``track``)."""
FILE_KEYS = ("behaviour", "late_delay", "wrong_turn")
"""Keys of a ship table that give her behaviour."""


def file_behaviour(t: dict, p: str, i: int) -> dict:
    """The behaviour fields of ship table ``t`` (dotted name ``p``, index ``i``) of a scenario file.

    ``behaviour = "late"`` needs ``late_delay`` (L/U, >= 0), ``behaviour = "wrong"`` needs ``wrong_turn`` (deg, in
    (0, 90]); neither key is allowed otherwise, and the own ship (``i = 0``) has no behaviour (her method is hers).

    Parameters
    ----------
    t : dict
        The ship's table.
    p : str
        Its dotted name, e.g. ``"ships[1]"``.
    i : int
        Its index.

    Returns
    -------
    dict
        ``behaviour``, ``late_delay``, ``wrong_turn_deg`` (None where not given).
    """
    from mmg_casadi.errors import ScenarioError
    from mmg_casadi.scenarios.scenario_checks import _ranged, _string

    out = {"behaviour": None, "late_delay": None, "wrong_turn_deg": None}
    if "behaviour" not in t:
        for k in FILE_KEYS[1:]:
            if k in t:
                raise ScenarioError(f"{p}.{k}", f"nothing without behaviour = \"{'late' if k == 'late_delay' else 'wrong'}\"",
                                    t[k])
        return out
    if i == 0:
        raise ScenarioError(f"{p}.behaviour", "no behaviour for the own ship (the first ship sails with her method)",
                            t["behaviour"])
    kind = _string(t["behaviour"], f"{p}.behaviour", FILE_BEHAVIOURS)
    out["behaviour"] = kind
    for k, owner in (("late_delay", "late"), ("wrong_turn", "wrong")):
        if k in t and kind != owner:
            raise ScenarioError(f"{p}.{k}", f"nothing unless behaviour = \"{owner}\"", t[k])
        if kind == owner and k not in t:
            raise ScenarioError(f"{p}.{k}", f"a value for a ship with behaviour = \"{owner}\" (a required key, "
                                "missing here)")
    if kind == "late":
        out["late_delay"] = _ranged(t["late_delay"], f"{p}.late_delay", 0.0, None, unit="L/U")
    if kind == "wrong":
        out["wrong_turn_deg"] = _ranged(t["wrong_turn"], f"{p}.wrong_turn", 0.0, 90.0, low_open=True, unit="deg")
    return out


def ship_inputs(spec) -> dict | None:
    """The :data:`SHIP_INPUTS` of a scenario ship (:class:`~mmg_casadi.scenarios.scenario.ShipSpec`), None without a
    behaviour.

    Parameters
    ----------
    spec : ShipSpec
        The ship.

    Returns
    -------
    dict or None
        Name to value.
    """
    kind = getattr(spec, "behaviour", None)
    if kind is None:
        return None
    return inputs_of(kind, spec.late_delay or 0.0, math.radians(spec.wrong_turn_deg or 0.0))
