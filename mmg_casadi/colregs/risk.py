"""Rule 7, risk of collision: the gate that opens an encounter, its onset and release, and the timing triggers.

An encounter of an ordered ship pair exists only while a risk of collision exists (COLREG Rule 7): at a sample
where both ships sail, the straight-line predicted CPA is below ``d_risk`` with 0 < TCPA < ``t_risk`` and the
range is at most ``r_risk`` (:class:`~mmg_casadi.colregs.profiles.ScoringProfile`). The encounter begins at the
first such sample (the **onset**) and lasts until its **release**: the first later sample without risk at which
the ships draw apart (TCPA ≤ 0) beyond ``r_risk`` (``d_risk`` if the profile has no range horizon), or the last
sample both sail. Releasing only beyond the range where the gate opens (ours) keeps one encounter through a
manoeuvre that opens the range for a while (an overtaker sheering off and coming back) and while ships linger
close together; the **CPA** is the smallest range from onset to release. A later risk opens another encounter.
A pair that never has a risk has no encounter: no rule applies to it (neither a violation nor a compliance).

Within an encounter, :func:`first_trigger` finds where the give-way ship's ample time ends (``late_*``: her
inaction is then apparent and the stand-on ship may act, Rule 17(a)(ii)) and where the stand-on ship must act
(``must_*``, Rule 17(b)); both need the risk to persist, the second also a predicted CPA below ``d_safe``
(:mod:`mmg_casadi.colregs.context`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def risk_of_collision(cpa, tcpa, rng, both, profile) -> np.ndarray:
    """Rule 7 gate at every sample: ``both`` sail, CPA < ``d_risk``, 0 < TCPA < ``t_risk``, range ≤ ``r_risk``.

    Parameters
    ----------
    cpa, tcpa, rng : array-like
        Straight-line predicted CPA (L), TCPA (L/U) and range (L).
    both : array-like of bool
        Whether both ships sail.
    profile : ScoringProfile
        ``d_risk``, ``t_risk`` and ``r_risk``.

    Returns
    -------
    numpy.ndarray of bool
        The gate at every sample, the broadcast shape of the inputs.

    Examples
    --------
    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> risk_of_collision([0.5, 5.0, 0.5, 0.5], [3.0, 3.0, -1.0, 3.0], [6.0, 6.0, 6.0, 20.0], True,
    ...                   iitm_lab()).tolist()
    [True, False, False, False]
    """
    cpa, tcpa, rng = (np.asarray(a, dtype=float) for a in (cpa, tcpa, rng))
    return (np.asarray(both, dtype=bool) & (cpa < profile.d_risk) & (tcpa > 0.0) & (tcpa < profile.t_risk)
            & (rng <= profile.r_risk))


def release_range(profile) -> float:
    """Range beyond which an encounter is released: ``r_risk``, or ``d_risk`` without a range horizon (L).

    Parameters
    ----------
    profile : ScoringProfile
        ``r_risk`` and ``d_risk``.

    Returns
    -------
    float
        The release range (L).

    Examples
    --------
    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> release_range(iitm_lab())
    15.0
    """
    return float(profile.r_risk) if np.isfinite(profile.r_risk) else float(profile.d_risk)


@dataclass(frozen=True)
class RiskEpisode:
    """Sample indices of one encounter: ``onset`` (first risk), ``cpa`` (smallest range), ``release``.

    Parameters
    ----------
    onset : int
        First sample with a risk of collision.
    cpa : int
        Sample of the smallest range from onset to release.
    release : int
        Sample at which the encounter ends.

    Examples
    --------
    >>> RiskEpisode(3, 8, 10).onset
    3
    """

    onset: int
    cpa: int
    release: int


def risk_episodes(rng, tcpa, risk, both, clear_range) -> list[RiskEpisode]:
    """The encounters of one ordered pair: onset, CPA and release of every stretch of risk (module docstring).

    Parameters
    ----------
    rng, tcpa : array-like (T,)
        Range (L) and straight-line TCPA (L/U).
    risk : array-like of bool (T,)
        The gate, :func:`risk_of_collision`.
    both : array-like of bool (T,)
        Whether both ships sail.
    clear_range : float
        The encounter is released only beyond this range (L; :func:`release_range`).

    Returns
    -------
    list of RiskEpisode
        The episodes in time order, each with its ``onset``, ``cpa`` and ``release`` samples; empty without risk.

    Examples
    --------
    Closing at unit speed to a CPA of 1 L at sample 6, then opening; risk at samples 2–5; released beyond 3.5 L:

    >>> r = np.abs(np.arange(12.0) - 6.0) + 1.0
    >>> risk = (np.arange(12) >= 2) & (np.arange(12) <= 5)
    >>> risk_episodes(r, 6.0 - np.arange(12.0), risk, np.ones(12, bool), 3.5)
    [RiskEpisode(onset=2, cpa=6, release=9)]
    """
    rng, tcpa = np.asarray(rng, dtype=float), np.asarray(tcpa, dtype=float)
    risk, both = np.asarray(risk, dtype=bool), np.asarray(both, dtype=bool)
    out = []
    ends = np.flatnonzero((~risk & (tcpa <= 0.0) & (rng > clear_range)) | ~both)
    onsets = np.flatnonzero(risk)
    k = 0
    while True:
        later = onsets[onsets >= k]
        if later.size == 0:
            return out
        onset = int(later[0])
        after = ends[ends > onset]
        if after.size == 0:
            release = int(np.flatnonzero(both)[-1])
        else:
            release = int(after[0]) if both[after[0]] else int(after[0]) - 1
        span = np.arange(onset, release + 1)
        cpa = int(span[np.argmin(np.where(both[span], rng[span], np.inf))])
        out.append(RiskEpisode(onset, cpa, release))
        k = release + 1


def first_trigger(risk, tcpa, rng, start, stop, tcpa_limit=None, range_limit=None) -> int | None:
    """First sample in ``[start, stop]`` with risk and TCPA ≤ ``tcpa_limit`` or range ≤ ``range_limit``.

    Parameters
    ----------
    risk : array-like of bool (T,)
        The gate, :func:`risk_of_collision`.
    tcpa, rng : array-like (T,)
        Straight-line TCPA (L/U) and range (L).
    start, stop : int
        Sample window (inclusive).
    tcpa_limit, range_limit : float or None, optional
        Thresholds; ``None`` switches one off (both off: no trigger).

    Returns
    -------
    int or None
        The sample index, or None if no sample in the window triggers.

    Examples
    --------
    >>> first_trigger(np.ones(5, bool), np.array([5.0, 4.0, 3.0, 2.0, 1.0]), np.full(5, 9.0), 0, 4, tcpa_limit=2.5)
    3
    >>> first_trigger(np.ones(5, bool), np.full(5, 9.0), np.full(5, 9.0), 0, 4) is None
    True
    """
    span = slice(start, stop + 1)
    hit = np.zeros(stop + 1 - start, dtype=bool)
    if tcpa_limit is not None:
        hit |= np.asarray(tcpa, dtype=float)[span] <= tcpa_limit
    if range_limit is not None:
        hit |= np.asarray(rng, dtype=float)[span] <= range_limit
    hits = np.flatnonzero(hit & np.asarray(risk, dtype=bool)[span])
    return int(start + hits[0]) if hits.size else None
