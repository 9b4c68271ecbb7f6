"""COLREG assessment of ship pairs from trajectories: closest approach, encounter type and rule compliance (numpy).

The rules (COLREG, as quoted in the paper): Rule 13, the overtaking vessel keeps out of the way; Rule 14, in a
head-on situation each vessel alters course to starboard and they pass port to port; Rule 15, in a crossing the
vessel that has the other on her starboard side gives way and avoids crossing ahead; the other stands on
(Rule 17). :func:`assess_pair` checks these from trajectories rule by rule — with Rules 8 (ample time, readily
apparent), 16 (early and substantial action) and 17(a)(i), (a)(ii)/(b) and (c) — through
:func:`mmg_casadi.colregs.score.score_pair`, under a named :class:`~mmg_casadi.colregs.classify.ColregProfile`
(:data:`~mmg_casadi.colregs.classify.PROFILES`); :func:`assess_obstacle` measures the approach to a static
obstacle. Units as in :mod:`mmg_casadi.colregs.classify`.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from mmg_casadi.colregs.classify import LAB_PROFILE, ColregProfile, get_profile
from mmg_casadi.colregs.geometry import pair_series
from mmg_casadi.colregs.score import score_pair
from mmg_casadi.errors import check_range


@dataclass(frozen=True)
class PairAssessment:
    """COLREG assessment of one pair of ships (a, b), or of a ship and a static obstacle.

    ``min_distance``: smallest centre distance while both are active (L; ``inf`` if never both active);
    ``t_min``: its time (time of the closest point of approach, CPA; ``None`` if never both active);
    ``encounter``: the encounter type from a's point of view when the distance first drops below ``r_safe``
    (one of :data:`~mmg_casadi.colregs.classify.ENCOUNTERS`, ``"none"`` if it never does, ``"static"`` for an
    obstacle); ``compliant``: whether a kept every rule that applies to her (``None`` when there is none);
    ``encounter_b``, ``compliant_b``: the same from b's point of view; ``t_enter``: the time the distance first
    drops below ``r_safe`` (``None`` if never); ``rules``: the rule-by-rule verdicts behind
    ``compliant``/``compliant_b`` (:meth:`mmg_casadi.colregs.score.PairScore.to_dict`; ``None`` for an obstacle;
    not compared by ``==``).

    Parameters
    ----------
    min_distance : float
        Smallest centre distance while both are active (L).
    t_min : float or None
        Time of the smallest distance (L/U).
    encounter : str
        Encounter type from a's point of view.
    compliant : bool or None
        Whether a kept every rule that applies to her.
    encounter_b : str
        Encounter type from b's point of view.
    compliant_b : bool or None
        Whether b kept every rule that applies to her.
    t_enter : float or None
        Time the distance first drops below ``r_safe`` (L/U).
    rules : dict or None, optional
        Rule-by-rule verdicts behind ``compliant`` and ``compliant_b``.

    Examples
    --------
    >>> PairAssessment(6.0, 40.0, "head-on", True, "head-on", True, 17.5).to_dict()["encounter"]
    'head-on'
    """

    min_distance: float
    t_min: float | None
    encounter: str
    compliant: bool | None
    encounter_b: str
    compliant_b: bool | None
    t_enter: float | None
    rules: dict | None = field(default=None, compare=False)

    def to_dict(self) -> dict:
        """The assessment as a plain dict.

        Returns
        -------
        dict
            The dataclass fields by name (``dataclasses.asdict``).
        """
        return asdict(self)


def assess_pair(t, pos_a, psi_a, pos_b, psi_b, *, r_safe, collision_distance, profile: ColregProfile = LAB_PROFILE,
                active_a=None, active_b=None, speed_a=None, speed_b=None) -> PairAssessment:
    """Encounter type and rule compliance of ships a and b from their trajectories.

    Distances count only at samples where both ships are active (still sailing). The encounter is fixed at
    ``t_enter``, the first such sample with distance < ``r_safe``, by
    :func:`~mmg_casadi.colregs.classify.classify_encounter` from each ship's point of view; the closest point of
    approach (CPA) is at ``t_min``. ``compliant`` (a) and ``compliant_b`` (b): every rule that applies to the ship
    is satisfied, ``None`` if none applies; the verdicts, rule by rule (8, 13, 14, 15, 16, 17(a)(i), 17(b),
    17(c)), and the quantities behind them are in ``rules``, from :func:`mmg_casadi.colregs.score.score_pair` (see
    there for each rule's test).

    Parameters
    ----------
    t : array (T,)
        Sample times (non-dimensional).
    pos_a, pos_b : array (T, 2)
        Positions (L).
    psi_a, psi_b : array (T,)
        Headings (rad, from x towards y; wrapped or continuous).
    r_safe, collision_distance : float
        Safe radius and collision distance (L).
    profile : ColregProfile or str
        Sector thresholds and tolerances, or a profile name (:func:`~mmg_casadi.colregs.classify.get_profile`).
    active_a, active_b : array (T,) of bool, optional
        Whether each ship is still sailing (default: always).
    speed_a, speed_b : array (T,), optional
        Speeds (default: from the positions).

    Returns
    -------
    PairAssessment
        ``min_distance`` (L, ``inf`` if the ships are never both active), ``t_min`` (L/U), each ship's encounter
        and compliance, ``t_enter`` (L/U or None) and the rule-by-rule ``rules``.

    Examples
    --------
    Two ships on reciprocal courses that never turn: head-on, neither complies.

    >>> t = np.linspace(0.0, 40.0, 161)
    >>> a = np.column_stack([t, 0.0 * t]); b = np.column_stack([50.0 - t, 2.0 + 0.0 * t])
    >>> r = assess_pair(t, a, 0.0 * t, b, np.pi + 0.0 * t, r_safe=15.0, collision_distance=2.0)
    >>> r.encounter, r.compliant, r.encounter_b, r.compliant_b, r.t_enter, r.min_distance
    ('head-on', False, 'head-on', False, 17.75, 2.0)
    >>> r.rules["profile"], r.rules["a"]["14"]["verdict"], r.rules["a"]["8"]["verdict"]
    ('iitm-lab', False, False)
    """
    profile = get_profile(profile)
    t, pos_a, psi_a, pos_b, psi_b, both = pair_series(t, pos_a, psi_a, pos_b, psi_b, active_a, active_b)
    r_safe = check_range("r_safe", r_safe, 0.0, None, low_open=True, unit="L")
    collision_distance = check_range("collision_distance", collision_distance, 0.0, None, low_open=True, unit="L")
    idx = np.flatnonzero(both)
    if idx.size == 0:
        return PairAssessment(math.inf, None, "none", None, "none", None, None)
    d = np.linalg.norm(pos_a[idx] - pos_b[idx], axis=1)
    j_min = int(np.argmin(d))
    min_distance, k_cpa = float(d[j_min]), int(idx[j_min])
    inside = np.flatnonzero(d < r_safe)
    t_enter = float(t[idx[inside[0]]]) if inside.size else None
    score = score_pair(t, pos_a, psi_a, pos_b, psi_b, r_safe=r_safe, collision_distance=collision_distance,
                       profile=profile, speed_a=speed_a, speed_b=speed_b, active_a=active_a, active_b=active_b)
    return PairAssessment(min_distance, float(t[k_cpa]), score.a.encounter, score.a.compliant_all,
                          score.b.encounter, score.b.compliant_all, t_enter, score.to_dict())


def assess_obstacle(t, pos_a, obstacle_pos, radius, collision_distance, *, active_a=None) -> PairAssessment:
    """Closest approach of ship a to a static circular obstacle (encounter ``"static"``).

    ``min_distance`` is the smallest centre distance (L) while a is active and ``t_min`` its time. ``compliant``
    is True if a kept clear: ``min_distance >= max(collision_distance, radius + 0.5)`` — the collision distance
    between centres, as for ships, widened for obstacles so large that half a ship length beyond their edge
    lies farther out (radius > collision_distance − 0.5 L). The obstacle side has ``encounter_b = "static"`` and
    ``compliant_b = None``; ``t_enter`` is ``None`` (no safe radius is involved).

    Parameters
    ----------
    t : array-like (T,)
        Sample times (L/U).
    pos_a : array-like (T, 2)
        Positions of ship a (L).
    obstacle_pos : array-like (2,)
        Centre of the obstacle (L).
    radius : float
        Radius of the obstacle (L).
    collision_distance : float
        Collision distance between centres (L).
    active_a : array-like of bool (T,), optional
        Whether ship a is active at each time (default: always).

    Returns
    -------
    PairAssessment
        ``min_distance`` (L, ``inf`` if a is never active), ``t_min`` (L/U), encounters ``"static"``, ``compliant``
        as above.

    Examples
    --------
    >>> t = np.linspace(0.0, 50.0, 201)
    >>> r = assess_obstacle(t, np.column_stack([t, 0.0 * t + 3.0]), (25.0, 0.0), 0.5, 2.0)
    >>> r.min_distance, r.t_min, r.encounter, r.compliant
    (3.0, 25.0, 'static', True)
    """
    t = np.asarray(t, dtype=float).ravel()
    center = np.asarray(obstacle_pos, dtype=float).ravel()
    if center.shape != (2,):
        raise ValueError(f"obstacle_pos: expected 2 coordinates, got {center.size}")
    stand_still = np.broadcast_to(center, (t.size, 2))
    _, pos_a, _, _, _, active = pair_series(t, pos_a, np.zeros(t.size), stand_still, np.zeros(t.size), active_a, None)
    radius = check_range("radius", radius, 0.0, None, unit="L")
    collision_distance = check_range("collision_distance", collision_distance, 0.0, None, low_open=True, unit="L")
    idx = np.flatnonzero(active)
    if idx.size == 0:
        return PairAssessment(math.inf, None, "static", None, "static", None, None)
    d = np.linalg.norm(pos_a[idx] - center, axis=1)
    j = int(np.argmin(d))
    min_distance = float(d[j])
    return PairAssessment(min_distance, float(t[idx[j]]), "static",
                          bool(min_distance >= max(collision_distance, radius + 0.5)), "static", None, None)
