"""The behaviours of a study's sampled target ships, drawn per run (issue 48).

With ``targets`` a mix (:mod:`mmg_casadi.traffic.mix`), each target ship of a run draws its behaviour with the mix's
probabilities, then the behaviour's numbers from the table's uniform ranges (group ``traffic`` of
:mod:`mmg_casadi.params`): a late ship's delay, a wrong-way ship's turn, an intent ship's time of change and either
a course alteration (to either side) or a speed factor. Every ship draws six uniforms in a fixed order whatever it
becomes (behaviour, delay, turn, time, kind and side, size), from its own generator
``default_rng(SeedSequence([base_seed, environment, run, STREAM]))``, apart from the scenario sampler's and the
disturbance's: the encounters and any disturbance of a run are those of the study without the mix, every method meets
the same traffic, and the draws are recorded per ship in ``runs.csv`` (``target_behaviours``, :func:`describe`).

In a run every target carries a ``behaviour`` (so all runs share one compiled step, :mod:`mmg_casadi.traffic.behaviour`).
A change of mind is a route: her goal is kept, a waypoint is put where she is at the drawn time on her straight route
(plus the waypoint acceptance radius, at which ILOS switches) and the leg after it goes off at the new course (to a goal
as far away as the rest of her route, at least 20 L) or at the new speed (clipped to 0.2-1.2 U). With an intent in the
mix every target's route gets that waypoint (the others at the middle of their straight route), so that every run
has the same path length.

Examples
--------
>>> d = draw_behaviours(5, 0, 0, 9, {"targets": "mix:avoid=0.5,late=0.5", **RANGES})
>>> sorted({b["kind"] for b in d}), d == draw_behaviours(5, 0, 0, 9, {"targets": "mix:avoid=0.5,late=0.5", **RANGES})
(['avoid', 'late'], True)
"""

from __future__ import annotations

import math

import numpy as np

from mmg_casadi.traffic.mix import BEHAVIOURS, is_mix, mix_weights

STREAM = 0x747266
"""Last word of the behaviour generator's seed sequence (``"trf"`` in ASCII)."""
RANGES = {"target_late_delay_low": 2.0, "target_late_delay_high": 8.0, "target_wrong_turn_low_deg": 20.0,
          "target_wrong_turn_high_deg": 60.0, "target_intent_time_low": 10.0, "target_intent_time_high": 60.0,
          "target_intent_course_low_deg": 30.0, "target_intent_course_high_deg": 90.0,
          "target_intent_speed_low": 0.5, "target_intent_speed_high": 1.5}
"""The table's defaults of the ranges (for examples; a study reads its resolved parameters)."""
MIN_LEG = 20.0
"""Shortest leg (L) after a course change."""
SPEEDS = (0.2, 1.2)
"""Allowed ship speeds (:data:`mmg_casadi.scenarios.scenario.SPEED_RANGE`)."""


def _between(u: float, params: dict, name: str) -> float:
    """``u`` in (0, 1) mapped onto the table's range ``name_low .. name_high`` (``_deg`` names for angles)."""
    suffix = "_deg" if f"{name}_low_deg" in params else ""
    lo, hi = float(params[f"{name}_low{suffix}"]), float(params[f"{name}_high{suffix}"])
    return lo + (hi - lo) * float(u)


def draw_behaviours(environment: int, run: int, base_seed: int, n_targets: int, params: dict) -> list[dict]:
    """The behaviour of every target ship of a run.

    Parameters
    ----------
    environment, run, base_seed : int
        The run (as for :func:`mmg_casadi.montecarlo.sampling.sample_scenario`).
    n_targets : int
        Target ships (ships but the own ship).
    params : dict
        ``targets`` and the ranges of the table's group ``traffic`` (resolved).

    Returns
    -------
    list of dict
        Per target ``kind`` (a name of :data:`~mmg_casadi.traffic.mix.BEHAVIOURS`) and its numbers: ``delay`` (L/U),
        ``turn_deg``, ``time`` (L/U) and ``course_deg`` (signed, + to starboard) or ``speed_factor``.
    """
    w = mix_weights(params["targets"])
    names = list(BEHAVIOURS)
    cum = np.cumsum([w[k] for k in names])
    rng = np.random.default_rng(np.random.SeedSequence([int(base_seed), int(environment), int(run), STREAM]))
    out = []
    for _ in range(int(n_targets)):
        u = rng.uniform(size=6)
        kind = names[min(int(np.searchsorted(cum, u[0] * cum[-1], side="right")), len(names) - 1)]
        while w[kind] == 0.0:  # a boundary draw on a zero weight: the next behaviour with a weight
            kind = names[(names.index(kind) + 1) % len(names)]
        b = {"kind": kind}
        if kind == "late":
            b["delay"] = _between(u[1], params, "target_late_delay")
        elif kind == "wrong":
            b["turn_deg"] = _between(u[2], params, "target_wrong_turn")
        elif kind == "intent":
            b["time"] = _between(u[3], params, "target_intent_time")
            if u[4] < 0.5:
                side = 1.0 if u[4] < 0.25 else -1.0
                b["course_deg"] = side * _between(u[5], params, "target_intent_course")
            else:
                b["speed_factor"] = _between(u[5], params, "target_intent_speed")
        out.append(b)
    return out


def describe(draws: list[dict]) -> str:
    """The ``target_behaviours`` cell of a run: one entry per target ship, ``;``-separated, in ship order.

    Parameters
    ----------
    draws : list of dict
        :func:`draw_behaviours`.

    Returns
    -------
    str
        E.g. ``"avoid;late 3.21;wrong 41.0;intent 23.4 course +45.0;intent 30.1 speed 0.62;hold"`` (delay and time
        in L/U, angles in deg, + to starboard).

    Examples
    --------
    >>> describe([{"kind": "avoid"}, {"kind": "late", "delay": 3.2101}, {"kind": "intent", "time": 20.0,
    ...           "course_deg": -45.0}])
    'avoid;late 3.21;intent 20.0 course -45.0'
    """
    parts = []
    for b in draws:
        k = b["kind"]
        if k == "late":
            parts.append(f"late {b['delay']:.2f}")
        elif k == "wrong":
            parts.append(f"wrong {b['turn_deg']:.1f}")
        elif k == "intent" and "course_deg" in b:
            parts.append(f"intent {b['time']:.1f} course {b['course_deg']:+.1f}")
        elif k == "intent":
            parts.append(f"intent {b['time']:.1f} speed {b['speed_factor']:.2f}")
        else:
            parts.append(k)
    return ";".join(parts)


def apply_behaviours(ships: list[dict], draws: list[dict], *, goal_tolerance: float, waypoint: bool) -> None:
    """Write the drawn behaviours into the target ships of a scenario dict (in place).

    Parameters
    ----------
    ships : list of dict
        The scenario file's ships (own ship first), each with ``start``, ``heading``, ``speed`` and one waypoint.
    draws : list of dict
        :func:`draw_behaviours` of the targets.
    goal_tolerance : float
        The waypoint acceptance radius (L): a change of mind's waypoint lies this far beyond where the ship is at
        the drawn time.
    waypoint : bool
        Give every target a second waypoint (an intent in the mix): the change point, or the middle of the route.
    """
    for ship, b in zip(ships[1:], draws):
        kind = b["kind"]
        ship["behaviour"] = kind
        if kind == "late":
            ship["late_delay"] = float(b["delay"])
        if kind == "wrong":
            ship["wrong_turn"] = float(b["turn_deg"])
        start = np.asarray(ship["start"], float)
        goal = np.asarray(ship["waypoints"][-1], float)
        length = float(np.hypot(*(goal - start)))
        e = (goal - start) / length
        if kind == "intent":
            d = min(float(ship["speed"]) * b["time"] + goal_tolerance, 0.9 * length)
            change = start + d * e
            if "course_deg" in b:
                chi = math.atan2(e[1], e[0]) + math.radians(b["course_deg"])
                goal = change + max(length - d, MIN_LEG) * np.array([math.cos(chi), math.sin(chi)])
                ship["speeds"] = [float(ship["speed"])] * 2
            else:
                v = min(max(float(ship["speed"]) * b["speed_factor"], SPEEDS[0]), SPEEDS[1])
                ship["speeds"] = [float(ship["speed"]), v]
            ship["waypoints"] = [[float(x) for x in change], [float(x) for x in goal]]
        elif waypoint:
            ship["waypoints"] = [[float(x) for x in 0.5 * (start + goal)], [float(x) for x in goal]]


def needs_waypoint(targets: str) -> bool:
    """Whether a value of ``targets`` gives every target a second waypoint (a mix with an intent).

    Parameters
    ----------
    targets : str
        A checked value of ``targets``.

    Returns
    -------
    bool
        True for a mix in which ``intent`` has a positive probability.
    """
    return is_mix(targets) and mix_weights(targets)["intent"] > 0.0
