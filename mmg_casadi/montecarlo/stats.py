"""Paired comparison of two methods (or parameter sets) that ran the same scenarios.

Every method of a Monte Carlo study meets the same sampled scenarios, so success rates are compared *paired*:
only the discordant runs (one succeeds, the other fails) carry information. The test is the exact McNemar test
(a two-sided binomial test of the discordant counts against 1/2, :func:`scipy.stats.binomtest`), and the
interval of the difference of success rates is Newcombe's hybrid score interval for paired proportions
(Newcombe 1998, Statistics in Medicine 17:2635–2650, method 10), built from Wilson intervals of the two rates.

Examples
--------
>>> c = paired_comparison([1, 1, 1, 0, 1] * 40, [1, 0, 1, 0, 1] * 40)
>>> c.n, c.a_only, c.b_only, round(c.difference, 3)
(200, 40, 0, 0.2)
>>> c.p_value < 1e-10, c.ci[0] > 0
(True, True)
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from mmg_casadi.errors import InputError


def wilson(k: int, n: int, confidence: float = 0.95) -> tuple[float, float]:
    """Wilson score interval of the proportion ``k / n`` (via :func:`scipy.stats.binomtest`).

    Parameters
    ----------
    k : int
        Successes, ``0 <= k <= n``.
    n : int
        Trials, ``n >= 1``.
    confidence : float
        Confidence level.

    Returns
    -------
    low : float
        Lower end of the interval, in [0, 1].
    high : float
        Upper end of the interval, in [0, 1].

    Examples
    --------
    >>> [round(v, 4) for v in wilson(95, 100)]
    [0.8882, 0.9785]
    """
    from scipy.stats import binomtest  # about 0.5 s to import: only when a summary is made
    ci = binomtest(int(k), int(n)).proportion_ci(confidence_level=confidence, method="wilson")
    return float(ci.low), float(ci.high)


@dataclass(frozen=True)
class PairedComparison:
    """Result of :func:`paired_comparison`.

    Parameters
    ----------
    n : int
        Paired runs.
    rate_a, rate_b : float
        Success rates.
    both, a_only, b_only, neither : int
        Runs by outcome pair (``a_only``: A succeeded and B failed).
    difference : float
        ``rate_a - rate_b``.
    ci : tuple of float
        Its confidence interval (Newcombe's hybrid score interval).
    p_value : float
        Exact two-sided McNemar p-value on the discordant runs (1.0 without any).
    confidence : float
        Confidence level of ``ci``.
    """

    n: int
    rate_a: float
    rate_b: float
    both: int
    a_only: int
    b_only: int
    neither: int
    difference: float
    ci: tuple[float, float]
    p_value: float
    confidence: float = 0.95

    def significant(self, alpha: float = 0.05) -> bool:
        """Whether the paired test rejects equal success rates at level ``alpha``.

        Parameters
        ----------
        alpha : float
            Significance level.

        Returns
        -------
        bool
            True if :attr:`p_value` is below ``alpha``.
        """
        return self.p_value < alpha

    def verdict(self, alpha: float = 0.05) -> str:
        """``"A better"``, ``"B better"`` or ``"no significant difference"`` at level ``alpha``.

        Parameters
        ----------
        alpha : float
            Significance level.

        Returns
        -------
        str
            One of ``"A better"``, ``"B better"``, ``"no significant difference"``.
        """
        if not self.significant(alpha):
            return "no significant difference"
        return "A better" if self.difference > 0 else "B better"

    def to_dict(self) -> dict:
        """The fields as a plain dict (``ci`` as a list).

        Returns
        -------
        dict
            The dataclass fields by name, ``ci`` as ``[low, high]``.
        """
        d = asdict(self)
        d["ci"] = list(self.ci)
        return d


def paired_comparison(success_a, success_b, confidence: float = 0.95) -> PairedComparison:
    """Paired comparison of two success vectors over the same runs.

    Parameters
    ----------
    success_a, success_b : sequence of bool
        Per run, whether A (and B) succeeded; same length, same run order.
    confidence : float
        Confidence level of the interval of the difference.

    Returns
    -------
    PairedComparison
        Rates, the outcome counts, the difference ``rate_a - rate_b`` with its interval and the McNemar p-value.
    """
    a = np.asarray(success_a, dtype=bool).ravel()
    b = np.asarray(success_b, dtype=bool).ravel()
    if a.shape != b.shape or a.size == 0:
        raise InputError("success_b", f"{a.size} paired outcomes like success_a (at least one)", b.size)
    n = int(a.size)
    n11, n10 = int(np.sum(a & b)), int(np.sum(a & ~b))
    n01, n00 = int(np.sum(~a & b)), int(np.sum(~a & ~b))
    pa, pb = (n11 + n10) / n, (n11 + n01) / n
    la, ua = wilson(n11 + n10, n, confidence)
    lb, ub = wilson(n11 + n01, n, confidence)
    # correlation of the paired outcomes (phi), Newcombe's method 10; 0 when a margin is empty
    den = (n11 + n10) * (n01 + n00) * (n11 + n01) * (n10 + n00)
    phi = (n11 * n00 - n10 * n01) / math.sqrt(den) if den > 0 else 0.0
    d = pa - pb
    lo = d - math.sqrt(max((pa - la) ** 2 - 2 * phi * (pa - la) * (ub - pb) + (ub - pb) ** 2, 0.0))
    hi = d + math.sqrt(max((ua - pa) ** 2 - 2 * phi * (ua - pa) * (pb - lb) + (pb - lb) ** 2, 0.0))
    discordant = n10 + n01
    from scipy.stats import binomtest
    p = float(binomtest(n10, discordant, 0.5).pvalue) if discordant else 1.0
    return PairedComparison(n, pa, pb, n11, n10, n01, n00, d, (max(lo, -1.0), min(hi, 1.0)), p, confidence)
