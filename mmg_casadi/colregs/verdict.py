"""One rule's outcome in one encounter: a binary verdict, a graded score in [0, 1] and the terms behind them.

Rule keys (:data:`RULES`): ``"8"``, ``"13"``, ``"14"``, ``"15"``, ``"16"``, ``"17a_i"`` (Rule 17(a)(i)),
``"17a_ii"`` (17(a)(ii)), ``"17b"`` and ``"17c"``. A rule that does not apply to an encounter has no entry.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

#: rule keys, in COLREG order: 17a_i = 17(a)(i), 17a_ii = 17(a)(ii), 17b = 17(b), 17c = 17(c)
RULES = ("8", "13", "14", "15", "16", "17a_i", "17a_ii", "17b", "17c")


def json_value(value):
    """``value`` as a JSON-ready Python value: numpy scalars unwrapped, NaN and ±inf as ``None``, containers walked.

    Parameters
    ----------
    value : object
        A number, bool, string, ``None``, or a dict/list/tuple of them.

    Returns
    -------
    object
        The converted value: dicts with str keys, lists for lists, tuples and arrays, Python numbers, None for
        NaN and infinities.

    Examples
    --------
    >>> json_value({"a": np.float64(2.5), "b": np.inf, "c": (np.bool_(True), 1)})
    {'a': 2.5, 'b': None, 'c': [True, 1]}
    """
    if isinstance(value, dict):
        return {str(k): json_value(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [json_value(v) for v in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(float(value)) else None
    return value


@dataclass(frozen=True)
class RuleResult:
    """A rule's verdict (kept or not), its graded score in [0, 1] and the named terms behind them.

    Parameters
    ----------
    verdict : bool
        Whether the ship kept the rule.
    score : float
        Graded score in [0, 1] (1: fully kept).
    terms : dict, optional
        The penalties and quantities the verdict and score were computed from.

    Examples
    --------
    >>> RuleResult(True, 0.75, {"P_delay": 0.25}).to_dict()
    {'verdict': True, 'score': 0.75, 'P_delay': 0.25}
    """

    verdict: bool
    score: float
    terms: dict = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "verdict", bool(self.verdict))
        object.__setattr__(self, "score", float(min(1.0, max(0.0, self.score))))

    def to_dict(self) -> dict:
        """``{"verdict", "score", **terms}``, JSON-ready.

        Returns
        -------
        dict
            ``verdict``, ``score`` and the rule's terms, JSON-ready.
        """
        return {"verdict": self.verdict, "score": self.score, **json_value(self.terms)}
