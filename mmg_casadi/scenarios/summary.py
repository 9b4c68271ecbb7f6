"""One line per ship of a simulated scenario: what ``mmg-casadi simulate`` prints when it is done.

A line says the ship's status (and when she reached her goal), her closest approach and to whom, and the
encounter scorer's verdicts on her risky encounters (kept / broken, with the broken rules), read from the run's
``metrics.json`` (:func:`mmg_casadi.scenarios.run.run_scenario`).

Examples
--------
>>> metrics = {"params": {"colregs_profile": "iitm-lab", "vessel": "kcs"},
...            "ships": [{"name": "own", "status": "reached", "time_to_goal": 51.75, "collided": False},
...                      {"name": "target", "status": "reached", "time_to_goal": 51.5, "collided": False}],
...            "pairs": [{"a": "own", "b": "target", "min_distance": 5.766, "t_min": 25.25,
...                       "encounters": {"a": [{"applicable": True, "unfinished": False, "role": "head-on",
...                                              "compliant": True, "rules": {}}], "b": []}}]}
>>> print(ship_lines(metrics)[0])
own     reached its goal at t = 51.8 L/U; closest 5.77 L to target at t = 25.2 L/U; COLREG (iitm-lab): 1 of 1 risky encounters kept
"""

from __future__ import annotations

import re

from mmg_casadi.units import Units


def _encounters(metrics: dict, name: str) -> list[tuple[str, dict]]:
    """(other ship, scored encounter) of every pair ``name`` is part of, from her side."""
    out = []
    for p in metrics.get("pairs", []):
        enc = p.get("encounters") or {}
        if p.get("a") == name:
            out += [(p["b"], e) for e in enc.get("a", []) if isinstance(e, dict)]
        elif p.get("b") == name:
            out += [(p["a"], e) for e in enc.get("b", []) if isinstance(e, dict)]
    return out


def _closest(metrics: dict, name: str) -> tuple[float, str, float] | None:
    """(distance, other, time) of ``name``'s closest approach over her pairs, or None without a pair."""
    best = None
    for p in metrics.get("pairs", []):
        if name in (p.get("a"), p.get("b")) and p.get("min_distance") is not None:
            other = p["b"] if p["a"] == name else p["a"]
            if best is None or p["min_distance"] < best[0]:
                best = (p["min_distance"], other, p.get("t_min"))
    return best


def rule_label(key: str) -> str:
    """The COLREG rule of a verdict key of ``metrics.json``, as the Rules are cited: ``"17a_ii"`` → ``"17(a)(ii)"``.

    Parameters
    ----------
    key : str
        A key of an encounter's ``rules`` (``"8"``, ``"14"``, ``"17a_i"``, ``"17b"``, ...).

    Returns
    -------
    str
        The rule as cited.

    Examples
    --------
    >>> [rule_label(k) for k in ("8", "17a_ii", "17b")]
    ['8', '17(a)(ii)', '17(b)']
    """
    m = re.fullmatch(r"(\d+)([a-z])?(?:_([ivx]+))?", key)
    if not m:
        return key
    return m[1] + (f"({m[2]})" if m[2] else "") + (f"({m[3]})" if m[3] else "")


def _verdicts(found: list[tuple[str, dict]], profile: str) -> str:
    judged = [(o, e) for o, e in found if e.get("applicable") and not e.get("unfinished")]
    if not judged:
        return f"COLREG ({profile}): no risky encounter"
    broken = [(o, e) for o, e in judged if not e.get("compliant")]
    text = f"COLREG ({profile}): {len(judged) - len(broken)} of {len(judged)} risky encounters kept"
    if broken:
        parts = []
        for other, e in broken:
            rules = [rule_label(r) for r, v in (e.get("rules") or {}).items()
                     if isinstance(v, dict) and v.get("verdict") is False]
            parts.append(f"{e.get('role', '?')} with {other}" + (f": Rule {', '.join(rules)}" if rules else ""))
        text += "; broken: " + "; ".join(parts)
    return text


def ship_lines(metrics: dict, units: Units | None = None) -> list[str]:
    """One line per ship of ``metrics`` (the ``metrics.json`` of a run): status, time to goal, closest approach and
    to whom, and the COLREG verdicts of her risky encounters.

    Parameters
    ----------
    metrics : dict
        The metrics of :func:`mmg_casadi.scenarios.run.run_scenario` (``ships``, ``pairs``, ``params``).
    units : Units, optional
        Units of distances and times (default: the non-dimensional L and L/U).

    Returns
    -------
    list of str
        One line per ship, names padded to one width.
    """
    params = metrics.get("params", {})
    units = units or Units.of("nd", params.get("vessel", "kcs"))
    profile = params.get("colregs_profile", "?")
    ships = metrics.get("ships", [])
    width = max((len(s["name"]) for s in ships), default=0)
    lines = []
    for s in ships:
        status = s.get("status")
        if s.get("collided"):
            what = f"collided with {s.get('collision_with')}"
            if s.get("collision_time") is not None:
                what += f" at t = {units.fmt_time(s['collision_time'])}"
        elif s.get("method") == "replay":
            what = "replayed its recorded track"
        elif status == "reached" and s.get("time_to_goal") is not None:
            what = f"reached its goal at t = {units.fmt_time(s['time_to_goal'])}"
        elif status == "stalled":
            what = "stalled (no progress towards its goal)"
        else:
            what = {"diverged": "diverged (left the model's envelope)", "timeout": "did not reach its goal by t_max",
                    "replay": "replayed its recorded track"}.get(status, str(status))
        parts = [what]
        near = _closest(metrics, s["name"])
        if near is not None:
            d, other, t = near
            parts.append(f"closest {units.fmt_length(d)} to {other}"
                         + (f" at t = {units.fmt_time(t)}" if t is not None else ""))
        found = _encounters(metrics, s["name"])
        if s.get("method") not in ("replay",):
            parts.append(_verdicts(found, profile))
        lines.append(f"{s['name']:<{width}}  " + "; ".join(parts))
    return lines
