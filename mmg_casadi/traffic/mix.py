"""What the target ships of a sampled study do: one behaviour for all (``avoid``, ``hold``) or a mix drawn per ship.

A study's parameter ``targets`` is ``"avoid"`` (every ship uses the study's method, the paper's study), ``"hold"``
(the targets hold course and speed) or a mix ``"mix:avoid=0.6,hold=0.3,wrong=0.1"``: each target ship draws its
behaviour with these probabilities (:data:`BEHAVIOURS`; they must sum to 1). The draws are made per run from the
study's seed (:func:`mmg_casadi.traffic.sample.draw_behaviours`), so every method meets the same traffic.

Examples
--------
>>> parse_targets("mix:avoid=0.6, hold=0.3,wrong=0.1")
'mix:avoid=0.6,hold=0.3,wrong=0.1'
>>> mix_weights("mix:late=0.5,avoid=0.5")
{'avoid': 0.5, 'hold': 0.0, 'late': 0.5, 'wrong': 0.0, 'intent': 0.0}
>>> parse_targets("mix:avoid=0.5,sideways=0.5")
Traceback (most recent call last):
...
mmg_casadi.errors.InputError: targets: expected avoid, hold or mix:NAME=P,... with NAME one of avoid, hold, late, wrong, intent and the P summing to 1, got 'mix:avoid=0.5,sideways=0.5'
"""

from __future__ import annotations

import math
import re

from mmg_casadi.errors import InputError

BEHAVIOURS: dict[str, str] = {
    "avoid": "follows the rules with the study's method",
    "hold": "holds course and speed (method 'none')",
    "late": "gives way late: the study's method takes charge only after a neighbour has been within R_safe for a "
            "delay drawn from [target_late_delay_low, target_late_delay_high]",
    "wrong": "turns the wrong way: at the onset of a head-on or crossing risk she turns to port by an angle drawn "
             "from [target_wrong_turn_low_deg, target_wrong_turn_high_deg] and holds that heading while the risk lasts",
    "intent": "changes her mind once: at a time drawn from [target_intent_time_low, target_intent_time_high] she "
              "alters course by a drawn angle or changes speed by a drawn factor, holding course and speed otherwise",
}
"""The behaviours a target ship can draw, by name (the names of a mix and of the ``target_behaviours`` column)."""
PURE = ("avoid", "hold")
"""Values of ``targets`` that give every target one behaviour (the study's scenarios as before issue 48)."""
ALLOWED = (f"avoid, hold or mix:NAME=P,... with NAME one of {', '.join(BEHAVIOURS)} and the P summing to 1")
"""The allowed values of ``targets``, in words."""
_ITEM = re.compile(r"^\s*([a-z]+)\s*=\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*$")


def parse_targets(value, field: str = "targets", cls=InputError) -> str:
    """``value`` checked as a value of ``targets``, a mix in its canonical form (no spaces, the order given).

    Parameters
    ----------
    value : object
        ``"avoid"``, ``"hold"`` or ``"mix:NAME=P,..."``.
    field : str
        Name in the error message.
    cls : type
        Error raised (an :class:`~mmg_casadi.errors.InputError` subclass).

    Returns
    -------
    str
        The value.
    """
    if isinstance(value, str) and value in PURE:
        return value
    weights = _weights(value)
    if weights is None:
        raise cls(field, ALLOWED, value)
    return "mix:" + ",".join(f"{k}={_num(v)}" for k, v in weights.items())


def _num(v: float) -> str:
    return f"{v:g}" if float(f"{v:g}") == v else repr(v)


def _weights(value) -> dict | None:
    if not isinstance(value, str) or not value.startswith("mix:"):
        return None
    out = {}
    for item in value[4:].split(","):
        m = _ITEM.match(item)
        if m is None or m.group(1) not in BEHAVIOURS or m.group(1) in out:
            return None
        out[m.group(1)] = float(m.group(2))
    if not out or any(not 0.0 <= v <= 1.0 for v in out.values()) or not math.isclose(sum(out.values()), 1.0,
                                                                                       abs_tol=1e-9):
        return None
    return out


def mix_weights(value: str) -> dict[str, float]:
    """The probability of every behaviour (:data:`BEHAVIOURS` order) under a value of ``targets``.

    Parameters
    ----------
    value : str
        A checked value of ``targets``.

    Returns
    -------
    dict
        Behaviour name to probability (1 for the pure values' behaviour).
    """
    if value in PURE:
        return {k: float(k == value) for k in BEHAVIOURS}
    w = _weights(value)
    if w is None:
        raise InputError("targets", ALLOWED, value)
    return {k: w.get(k, 0.0) for k in BEHAVIOURS}


def is_mix(value: str) -> bool:
    """Whether a value of ``targets`` is a mix (its runs carry per-ship behaviours in the step).

    Parameters
    ----------
    value : str
        A checked value of ``targets``.

    Returns
    -------
    bool
        True for ``"mix:..."`` (not for ``avoid``, ``hold`` or a method's name).
    """
    return isinstance(value, str) and value.startswith("mix:")
