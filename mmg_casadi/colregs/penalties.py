"""The penalty terms of the graded rule scores, each a small numpy formula in [0, 1] (elementwise).

The forms follow the NTNU evaluator (Hagen et al. 2023, Ocean Engineering 288, 115991, and the group's earlier
code AIS_processing, commit ff650e5, after Woerner et al. 2019; see :mod:`mmg_casadi.colregs.profiles`), with one
sign convention: angles positive to starboard.

* :func:`ramp`: 0 up to ``lo``, 1 from ``hi``, linear between (a step at ``lo = hi``);
* :func:`passing_distance_score` S_r: piecewise linear in the CPA, ``γ_col`` gained from ``r_col`` to ``r_nm``,
  ``γ_nm`` from ``r_nm`` to ``r_min``, ``γ_min`` from ``r_min`` to ``r_pref``;
* :func:`delay_penalty` P_delay = clip((r_late − r_man)/(r_late − r_cpa), 0, 1): 0 for a manoeuvre begun in ample
  time, 1 for none. AIS_processing measures from the range at detection; we measure from ``r_late``, the range where
  ample time ends (:mod:`mmg_casadi.colregs.risk`), so that the graded score and the binary verdict agree;
* :func:`non_apparent_penalty` P_na = γ_χ·p_χ + γ_u·p_u with p_χ = max(0, 1 − (Δχ/Δχ_app)²) (AIS_processing,
  Hagen 2023), p_u the same form for the speed reduction (ours), and no penalty if either part is below
  ``na_cut`` (AIS_processing);
* :func:`port_to_port_score` ((1 − sin α)/2)²·((1 − sin β)/2)² (AIS_processing's form, positive to port there):
  1 when each ship passes the other abeam on her port side;
* :func:`stand_on_penalty`: the course change ramped from detectable to readily apparent (Hagen 2023, after
  Woerner et al.), the speed increase and decrease ramped between the speed thresholds the same way (ours);
* :func:`pose_score` ``S_θ = γ_α·(1 − cos min(|α|, cut)) + γ_β·(1 − cos min(|β|, cut))`` at the CPA (AIS_processing's
  terms, Hagen 2023's weights γ_α = 0.25, γ_β = 0.75, cut-off 90°): 1 when each ship passes abeam of or abaft the
  other's beam, 0 when both bows point at each other;
* :func:`safety_score` S_safety = S_r + (1 − S_r)·S_θ (the form of github.com/marinehdk/colav-simulator's
  reading of Hagen 2023), 0 at a CPA within ``r_col`` (ours: a collision is never safe, whatever the pose).
"""

from __future__ import annotations

import numpy as np


def ramp(x, lo, hi):
    """0 for ``x ≤ lo``, 1 for ``x ≥ hi``, linear between; with ``lo == hi`` a step (``x ≥ hi`` gives 1).

    Parameters
    ----------
    x : float or array-like
        Value(s).
    lo, hi : float
        Ends of the ramp, ``lo ≤ hi``.

    Returns
    -------
    numpy.ndarray
        Values in [0, 1], the shape of ``x``.

    Examples
    --------
    >>> ramp(np.array([1.0, 2.0, 3.0, 5.0]), 2.0, 4.0).tolist(), float(ramp(2.0, 2.0, 2.0))
    ([0.0, 0.0, 0.5, 1.0], 1.0)
    """
    if isinstance(x, float):  # a plain number: the same arithmetic without numpy's overhead
        if hi <= lo:
            return np.float64(1.0 if x >= hi else 0.0)
        return np.float64(min(max((x - lo) / (hi - lo), 0.0), 1.0))
    x = np.asarray(x, dtype=float)
    if hi <= lo:
        return (x >= hi).astype(float)
    return np.clip((x - lo) / (hi - lo), 0.0, 1.0)


def passing_distance_score(cpa, profile):
    """Passing-distance score S_r of an actual CPA (module docstring), in [0, 1].

    Parameters
    ----------
    cpa : float or array-like
        Closest point of approach (L).
    profile : ScoringProfile
        ``r_col``, ``r_nm``, ``r_min``, ``r_pref`` and ``gamma_col``, ``gamma_nm``, ``gamma_min``.

    Returns
    -------
    numpy.ndarray
        S_r in [0, 1], the shape of ``cpa``.

    Examples
    --------
    Hagen 2023 at 50 m per L (r 0.6/1/2/3.8 L, γ 0.5/0.3/0.2): 0.8 at r_min, 0.5 at r_nm.

    >>> from mmg_casadi.colregs.profiles import ntnu_2023, iitm_lab
    >>> np.round(passing_distance_score([0.5, 1.0, 2.0, 2.9, 4.0], ntnu_2023()), 3).tolist()
    [0.0, 0.5, 0.8, 0.9, 1.0]
    >>> passing_distance_score([1.0, 3.0, 5.0], iitm_lab()).tolist()
    [0.0, 0.5, 1.0]
    """
    p = profile
    return (p.gamma_col * ramp(cpa, p.r_col, p.r_nm) + p.gamma_nm * ramp(cpa, p.r_nm, p.r_min)
            + p.gamma_min * ramp(cpa, p.r_min, p.r_pref))


def delay_penalty(r_late, r_man, r_cpa) -> float:
    """P_delay of a manoeuvre begun at range ``r_man`` (module docstring); ``None`` for no manoeuvre gives 1.

    Parameters
    ----------
    r_late : float or None
        Range where ample time ended (``None``: it never ended while the risk lasted, no delay).
    r_man : float or None
        Range at the start of the manoeuvre (``None``: no manoeuvre).
    r_cpa : float
        Actual CPA (L).

    Returns
    -------
    float
        P_delay in [0, 1]: 1 for no manoeuvre, 0 for one begun before ample time ended.

    Examples
    --------
    Ample time ended at 8 L, the manoeuvre began at 5 L, the ships passed at 2 L: (8 − 5)/(8 − 2) = 0.5.

    >>> delay_penalty(8.0, 5.0, 2.0), delay_penalty(8.0, 9.0, 2.0), delay_penalty(None, 5.0, 2.0)
    (0.5, 0.0, 0.0)
    >>> delay_penalty(8.0, None, 2.0)
    1.0
    """
    if r_man is None:
        return 1.0
    if r_late is None or r_late <= r_cpa:
        return 0.0 if r_late is None or r_man >= r_late else 1.0
    return float(np.clip((r_late - r_man) / (r_late - r_cpa), 0.0, 1.0))


def non_apparent_penalty(course_change_deg, speed_reduction, profile) -> float:
    """P_na of the largest course change (degrees, either side) and speed reduction (module docstring).

    Parameters
    ----------
    course_change_deg : float
        Largest course change of the manoeuvre (degrees).
    speed_reduction : float
        Largest relative speed reduction (fraction of the reference speed).
    profile : ScoringProfile
        ``course_apparent_deg``, ``speed_apparent``, ``w_na_course``, ``w_na_speed``, ``na_cut``.

    Returns
    -------
    float
        P_na: 0 when either change is below ``na_cut``, else the weighted sum of the course and speed terms.

    Examples
    --------
    Laboratory profile (apparent 10°, 50 %): a 5° alteration at full speed gives
    p_χ = 1 − (5/10)² = 0.75, p_u = 1, P_na = 0.5·0.75 + 0.5·1 = 0.875; at 9° p_χ = 0.19 < 0.3, no penalty.

    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> non_apparent_penalty(5.0, 0.0, iitm_lab()), non_apparent_penalty(9.0, 0.0, iitm_lab())
    (0.875, 0.0)
    """
    p_course = max(0.0, 1.0 - (abs(course_change_deg) / profile.course_apparent_deg) ** 2)
    p_speed = max(0.0, 1.0 - (max(0.0, speed_reduction) / profile.speed_apparent) ** 2)
    if min(p_course, p_speed) < profile.na_cut:
        return 0.0
    return float(profile.w_na_course * p_course + profile.w_na_speed * p_speed)


def port_to_port_score(alpha, beta):
    """How nearly two ships pass port to port: ((1 − sin α)/2)²·((1 − sin β)/2)², in [0, 1] (elementwise).

    Parameters
    ----------
    alpha, beta : float or array-like
        Contact angle and bearing at the CPA (rad, positive to starboard).

    Returns
    -------
    numpy.ndarray
        Score in [0, 1], the broadcast shape of ``alpha`` and ``beta``.

    Examples
    --------
    Each abeam on the other's port side: 1; starboard to starboard: 0; one dead ahead of the other's port beam:

    >>> d = np.radians
    >>> port_to_port_score(d([-90.0, 90.0, -90.0]), d([-90.0, 90.0, 0.0])).tolist()
    [1.0, 0.0, 0.25]
    """
    a, b = np.asarray(alpha, dtype=float), np.asarray(beta, dtype=float)
    return ((1.0 - np.sin(a)) / 2.0) ** 2 * ((1.0 - np.sin(b)) / 2.0) ** 2


def stand_on_penalty(course_change_deg, speed_increase, speed_decrease, profile) -> dict:
    """Rule 17(a)(i) penalties: course change, speed increase and decrease, each ramped detectable → apparent.

    Parameters
    ----------
    course_change_deg : float
        Largest course change while she must keep her course (degrees, either side).
    speed_increase, speed_decrease : float
        Largest relative speed increase and decrease in that time.
    profile : ScoringProfile
        Detectable and apparent thresholds and the weights ``w_so_*``.

    Returns
    -------
    dict
        ``P_course``, ``P_up``, ``P_down`` and ``score`` = max(0, 1 − Σ w·P).

    Examples
    --------
    Laboratory profile (2° → 10°): a 6° change is half penalised, 1 − 0.5·0.5 = 0.75.

    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> stand_on_penalty(6.0, 0.0, 0.0, iitm_lab())
    {'P_course': 0.5, 'P_up': 0.0, 'P_down': 0.0, 'score': 0.75}
    """
    p = profile
    out = {"P_course": float(ramp(abs(course_change_deg), p.course_detectable_deg, p.course_apparent_deg)),
           "P_up": float(ramp(speed_increase, p.speed_detectable, p.speed_apparent)),
           "P_down": float(ramp(speed_decrease, p.speed_detectable, p.speed_apparent))}
    total = p.w_so_course * out["P_course"] + p.w_so_up * out["P_up"] + p.w_so_down * out["P_down"]
    out["score"] = max(0.0, 1.0 - total)
    return out


def pose_score(alpha, beta, profile):
    """Pose score S_θ at the CPA from the contact angle α and the bearing β (module docstring), elementwise.

    Parameters
    ----------
    alpha, beta : float or array-like
        Contact angle and bearing at the CPA (rad).
    profile : ScoringProfile
        ``w_pose_alpha``, ``w_pose_beta`` and ``pose_cut_deg``.

    Returns
    -------
    numpy.ndarray
        S_θ in [0, 1] (0 for weights 0).

    Examples
    --------
    >>> from mmg_casadi.colregs.profiles import published
    >>> d = np.radians
    >>> np.round(pose_score(d([0.0, -90.0, 0.0]), d([0.0, -90.0, -90.0]), published()), 3).tolist()
    [0.0, 1.0, 0.75]
    """
    cut = np.radians(profile.pose_cut_deg)
    a = 1.0 - np.cos(np.minimum(np.abs(np.asarray(alpha, dtype=float)), cut))
    b = 1.0 - np.cos(np.minimum(np.abs(np.asarray(beta, dtype=float)), cut))
    return profile.w_pose_alpha * a + profile.w_pose_beta * b


def safety_score(cpa, alpha, beta, profile):
    """Safety score S_safety of a passing: range score S_r and pose score S_θ (module docstring), elementwise.

    Parameters
    ----------
    cpa : float or array-like
        Actual CPA (L).
    alpha, beta : float or array-like
        Contact angle and bearing at the CPA (rad).
    profile : ScoringProfile
        The passing-distance and pose thresholds and weights.

    Returns
    -------
    numpy.ndarray
        S_safety in [0, 1]; S_r alone when the pose weights are 0.

    Examples
    --------
    Passing abeam 6 L apart is safer than passing 6 L apart bow to bow, and no collision is safe:

    >>> from mmg_casadi.colregs.profiles import published
    >>> d = np.radians
    >>> np.round(safety_score([6.0, 6.0, 1.5], d([90.0, 0.0, 90.0]), d([-90.0, 0.0, -90.0]), published()), 3).tolist()
    [1.0, 0.648, 0.0]
    """
    s_r = passing_distance_score(cpa, profile)
    s = s_r + (1.0 - s_r) * pose_score(alpha, beta, profile)
    return np.where(np.asarray(cpa, dtype=float) <= profile.r_col, 0.0, s)
