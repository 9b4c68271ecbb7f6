"""COLREG bookkeeping from trajectories: encounter classification and rule compliance (numpy post-processing).

Conventions: positions in ship lengths L, x forward/north and y to starboard/east, headings psi in rad measured
from x towards y (clockwise in the marine view, x up and y right), times non-dimensional. A positive change of
heading is a turn to starboard.

Angles used by the sectors of a :class:`ColregProfile`, both in [0, 2π):

* relative bearing of the other ship, ``beta = atan2(dy, dx) - psi_own``: 0 dead ahead, π/2 starboard beam,
  π dead astern;
* relative heading ``psi_r = psi_own - psi_other``.

The laboratory's sector table (``shared/data/README.md``) was written for counter-clockwise angles, where the
relative heading is ψ_other − ψ_own. Our headings are clockwise (a mirror image), so the same physical relative
heading is ψ_own − ψ_other. With this sign the paper's crossing (own ship at (0, 0) heading 0; the other at
(25, 25), on own's starboard side, heading −90°) gives ``psi_r = π/2`` (crossing, give way) for the own ship and
``psi_r = 3π/2`` (crossing, stand on) for the other, as Rule 15 demands. The stern sector is symmetric about π,
so the sign of ``beta`` does not matter for it.

The rules (COLREG, as quoted in the paper): Rule 13, the overtaking vessel keeps out of the way; Rule 14, in a
head-on situation each vessel alters course to starboard and they pass port to port; Rule 15, in a crossing the
vessel that has the other on her starboard side gives way and avoids crossing ahead; the other stands on
(Rule 17). :func:`assess_pair` checks these from trajectories, as described there.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .errors import ParameterError, check_range

TWO_PI = 2.0 * math.pi
ENCOUNTERS = ("overtaking", "overtaken", "head-on", "crossing-give-way", "crossing-stand-on", "none")


def wrap_to_pi(angle):
    """``angle`` (rad, scalar or array) wrapped into [-π, π).

    Examples
    --------
    >>> round(wrap_to_pi(3 * math.pi / 2), 6), round(wrap_to_pi(-0.5), 6)
    (-1.570796, -0.5)
    """
    wrapped = (np.asarray(angle, dtype=float) + math.pi) % TWO_PI - math.pi
    return float(wrapped) if wrapped.ndim == 0 else wrapped


def _in_sector(angle: float, sector: tuple[float, float]) -> bool:
    """True if ``angle`` (in [0, 2π)) lies in ``[lo, hi)``; a sector with ``lo > hi`` wraps through 0."""
    lo, hi = sector
    if lo <= hi:
        return lo <= angle < hi
    return angle >= lo or angle < hi


@dataclass(frozen=True)
class ColregProfile:
    """Named COLREG sector thresholds.

    ``head_on``, ``give_way``, ``stand_on``: sectors ``[lo, hi)`` of the relative heading ψ_r (rad, in
    [0, 2π)); ``stern_sector``: sector of the relative bearing β (rad) that counts as "astern" (overtaking,
    Rule 13: more than 22.5° abaft the beam); ``course_tolerance_deg``: the largest heading change (degrees) a
    stand-on or overtaken ship may make and still count as keeping her course; ``starboard_min_deg``: the
    smallest starboard alteration (degrees) that counts as "altering course to starboard". A sector with
    ``lo > hi`` wraps through 0.

    The default is the paper's laboratory profile (``shared/data/README.md``): head-on 7π/8 ≤ ψ_r < 9π/8
    (±22.5°), give-way 3π/8 ≤ ψ_r < 7π/8, stand-on 9π/8 ≤ ψ_r < 13π/8, stern sector 5π/8 ≤ β < 11π/8
    (112.5° to 247.5°, the sector the modified vortex also uses). The two tolerances are ours.

    Examples
    --------
    >>> p = ColregProfile()
    >>> p.name, round(math.degrees(p.head_on[1] - p.head_on[0]), 1)
    ('iitm-lab', 45.0)
    """

    name: str = "iitm-lab"
    head_on: tuple[float, float] = (7 * math.pi / 8, 9 * math.pi / 8)
    give_way: tuple[float, float] = (3 * math.pi / 8, 7 * math.pi / 8)
    stand_on: tuple[float, float] = (9 * math.pi / 8, 13 * math.pi / 8)
    stern_sector: tuple[float, float] = (5 * math.pi / 8, 11 * math.pi / 8)
    course_tolerance_deg: float = 15.0
    starboard_min_deg: float = 5.0

    def __post_init__(self):
        for key in ("head_on", "give_way", "stand_on", "stern_sector"):
            sector = tuple(float(a) for a in getattr(self, key))
            if len(sector) != 2 or not all(0.0 <= a <= TWO_PI for a in sector) or sector[0] == sector[1]:
                raise ParameterError(key, "a sector (lo, hi) of two different angles in [0, 2π] rad", sector)
            object.__setattr__(self, key, sector)
        check_range("course_tolerance_deg", self.course_tolerance_deg, 0.0, 180.0, unit="degrees")
        check_range("starboard_min_deg", self.starboard_min_deg, 0.0, 180.0, unit="degrees")

    @classmethod
    def strict(cls) -> ColregProfile:
        """A profile with a narrow head-on sector, ψ_r within ±5° of π.

        Published schemes differ: head-on tolerances range from ±5° (nearly reciprocal courses only) to ±22.5°
        (the laboratory's). The give-way and stand-on sectors grow to meet the narrower head-on sector, so
        relative headings from 67.5° to 292.5° are still all classified; the stern sector and tolerances are
        the laboratory's.

        Examples
        --------
        >>> p = ColregProfile.strict()
        >>> p.name, [round(math.degrees(a), 1) for a in p.head_on]
        ('strict', [175.0, 185.0])
        """
        half = math.radians(5.0)
        return cls(name="strict", head_on=(math.pi - half, math.pi + half), give_way=(3 * math.pi / 8, math.pi - half),
                   stand_on=(math.pi + half, 13 * math.pi / 8))


LAB_PROFILE = ColregProfile()


def _bearing(own_pos, own_psi, other_pos) -> float:
    """Relative bearing of ``other_pos`` from the own ship, wrapped into [-π, π) (negative: port side)."""
    dx, dy = other_pos[0] - own_pos[0], other_pos[1] - own_pos[1]
    return wrap_to_pi(math.atan2(dy, dx) - own_psi)


def classify_encounter(own_pos, own_psi, other_pos, other_psi, profile: ColregProfile = LAB_PROFILE) -> str:
    """The encounter type from the own ship's point of view, by the profile's sectors.

    First the stern sector: if the other ship lies in the own ship's stern sector the own ship is being
    overtaken (``"overtaken"``); if the own ship lies in the other's stern sector the own ship is overtaking
    (``"overtaking"``); if both hold, the ships lie stern to stern and are moving apart (``"none"``). Otherwise
    the relative heading decides: ``"head-on"``, ``"crossing-give-way"`` or ``"crossing-stand-on"``. Relative
    headings outside all three sectors (courses within 67.5° of each other, e.g. ships abeam or diverging on
    similar courses) give ``"none"``: no rule applies. Only positions and headings are used, so a ship in the
    other's stern sector counts as overtaking whatever the speeds (as in the laboratory's table).

    Parameters
    ----------
    own_pos, other_pos : sequence of 2 floats
        Positions (L).
    own_psi, other_psi : float
        Headings (rad, from x towards y).
    profile : ColregProfile
        Sector thresholds.

    Examples
    --------
    Head-on (the paper's: (0, 0) → (50, 0) against (50, 0) → (0, 0)):

    >>> classify_encounter((0, 0), 0.0, (50, 0), math.pi), classify_encounter((50, 0), math.pi, (0, 0), 0.0)
    ('head-on', 'head-on')

    Crossing (the paper's: the other comes from the own ship's starboard side):

    >>> classify_encounter((0, 0), 0.0, (25, 25), -math.pi / 2)
    'crossing-give-way'
    >>> classify_encounter((25, 25), -math.pi / 2, (0, 0), 0.0)
    'crossing-stand-on'

    Overtaking (faster own ship behind) and ships abeam on parallel courses:

    >>> classify_encounter((0, 0), 0.0, (12, 0), 0.0), classify_encounter((12, 0), 0.0, (0, 0), 0.0)
    ('overtaking', 'overtaken')
    >>> classify_encounter((0, 0), 0.0, (0, 10), 0.0)
    'none'
    """
    beta_other = _bearing(own_pos, own_psi, other_pos) % TWO_PI
    beta_own = _bearing(other_pos, other_psi, own_pos) % TWO_PI
    other_astern = _in_sector(beta_other, profile.stern_sector)
    own_astern = _in_sector(beta_own, profile.stern_sector)
    if other_astern or own_astern:
        if other_astern and own_astern:
            return "none"
        return "overtaken" if other_astern else "overtaking"
    psi_r = (own_psi - other_psi) % TWO_PI
    if _in_sector(psi_r, profile.head_on):
        return "head-on"
    if _in_sector(psi_r, profile.give_way):
        return "crossing-give-way"
    if _in_sector(psi_r, profile.stand_on):
        return "crossing-stand-on"
    return "none"


@dataclass(frozen=True)
class PairAssessment:
    """COLREG assessment of one pair of ships (a, b), or of a ship and a static obstacle.

    ``min_distance``: smallest centre distance while both are active (L; ``inf`` if never both active);
    ``t_min``: its time (time of the closest point of approach, CPA; ``None`` if never both active);
    ``encounter``: the encounter type from a's point of view when the distance first drops below ``r_safe``
    (one of :data:`ENCOUNTERS`, ``"none"`` if it never does, ``"static"`` for an obstacle); ``compliant``: whether
    a kept her rule (``None`` when there is no rule to check); ``encounter_b``, ``compliant_b``: the same from
    b's point of view; ``t_enter``: the time the distance first drops below ``r_safe`` (``None`` if never).

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

    def to_dict(self) -> dict:
        """The assessment as a plain dict."""
        return asdict(self)


def _series(t, pos_a, psi_a, pos_b, psi_b, active_a, active_b):
    """Validated arrays: t (T,), positions (T, 2), headings (T,), both-active mask (T,)."""
    t = np.asarray(t, dtype=float).ravel()
    n = t.size
    out = [t]
    for name, pos, psi in (("pos_a", pos_a, psi_a), ("pos_b", pos_b, psi_b)):
        pos = np.asarray(pos, dtype=float)
        psi = np.asarray(psi, dtype=float).ravel()
        if pos.shape != (n, 2):
            raise ValueError(f"{name}: expected shape ({n}, 2) like t, got {pos.shape}")
        if psi.shape != (n,):
            raise ValueError(f"psi_{name[-1]}: expected {n} samples like t, got {psi.size}")
        out += [pos, psi]
    both = np.ones(n, dtype=bool)
    for name, mask in (("active_a", active_a), ("active_b", active_b)):
        if mask is not None:
            mask = np.asarray(mask, dtype=bool).ravel()
            if mask.shape != (n,):
                raise ValueError(f"{name}: expected {n} samples like t, got {mask.size}")
            both &= mask
    return (*out, both)


def _turned_starboard(psi, k_enter, window, profile) -> bool:
    """True if the heading rose at least ``starboard_min_deg`` above its value at entry within ``window``."""
    change = wrap_to_pi(psi[window] - psi[k_enter])
    return bool(np.max(change) >= math.radians(profile.starboard_min_deg))


def _kept_course(psi, k_enter, window, profile) -> bool:
    """True if the heading stayed within ``course_tolerance_deg`` of its value at entry within ``window``."""
    change = np.abs(wrap_to_pi(psi[window] - psi[k_enter]))
    return bool(np.max(change) <= math.radians(profile.course_tolerance_deg))


def _heading_unit(psi):
    """Unit heading vectors (T, 2) of headings ``psi`` (rad)."""
    return np.column_stack([np.cos(psi), np.sin(psi)])


def _passed_astern(pos, pos_o, psi_o, passage) -> bool:
    """True if every crossing of the other's course line within ``passage`` happened astern of her.

    The course line is the line through the other ship along her current heading; a crossing is a sign change
    of ``cross(h_o, p - p_o)`` between consecutive nonzero samples, and it is astern if ``dot(h_o, p - p_o) < 0``
    there (linearly interpolated). No crossing at all counts as passing astern.
    """
    rel = pos[passage] - pos_o[passage]
    h = _heading_unit(psi_o[passage])
    side = h[:, 0] * rel[:, 1] - h[:, 1] * rel[:, 0]
    along = np.einsum("ij,ij->i", h, rel)
    nz = np.flatnonzero(side != 0.0)
    for k0, k1 in zip(nz[:-1], nz[1:]):
        if side[k0] * side[k1] < 0.0:
            f = side[k0] / (side[k0] - side[k1])
            if along[k0] + f * (along[k1] - along[k0]) >= 0.0:
                return False
    return True


def _compliance(encounter, pos, psi, pos_o, psi_o, k_enter, k_cpa, window, passage, min_distance,
                collision_distance, profile) -> bool | None:
    """Whether a ship with trajectory (pos, psi) kept her rule in ``encounter`` against (pos_o, psi_o)."""
    if encounter == "crossing-give-way":
        return _turned_starboard(psi, k_enter, window, profile) and _passed_astern(pos, pos_o, psi_o, passage)
    if encounter == "head-on":
        port_to_port = _bearing(pos[k_cpa], psi[k_cpa], pos_o[k_cpa]) < 0.0
        return _turned_starboard(psi, k_enter, window, profile) and bool(port_to_port)
    if encounter in ("crossing-stand-on", "overtaken"):
        return _kept_course(psi, k_enter, window, profile)
    if encounter == "overtaking":
        return bool(min_distance >= collision_distance)
    return None


def assess_pair(t, pos_a, psi_a, pos_b, psi_b, *, r_safe, collision_distance, profile: ColregProfile = LAB_PROFILE,
                active_a=None, active_b=None) -> PairAssessment:
    """Encounter type and rule compliance of ships a and b from their trajectories.

    Distances count only at samples where both ships are active (still sailing). The encounter is fixed at
    ``t_enter``, the first such sample with distance < ``r_safe``, by :func:`classify_encounter` from each
    ship's point of view; the closest point of approach (CPA) is at ``t_min``. Compliance, from each side,
    judged on the window [t_enter, t_min]:

    * crossing, give way (Rule 15): alters to starboard (the heading rises at least ``starboard_min_deg`` above
      its value at ``t_enter``) AND passes astern: every crossing of the other's course line while the ships
      are within ``r_safe`` (from ``t_enter`` until the distance is back at ``r_safe`` or more) happens behind
      her;
    * head-on (Rule 14): alters to starboard AND passes port to port (the other on the own ship's port side,
      bearing in [-π, 0), at the CPA);
    * crossing, stand on, or overtaken (Rules 13, 17): keeps her course, every heading within
      ``course_tolerance_deg`` of the heading at ``t_enter``;
    * overtaking (Rule 13): keeps clear, ``min_distance >= collision_distance``;
    * none: ``None``.

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
    profile : ColregProfile
        Sector thresholds and tolerances.
    active_a, active_b : array (T,) of bool, optional
        Whether each ship is still sailing (default: always).

    Examples
    --------
    Two ships on reciprocal courses that never turn: head-on, neither complies.

    >>> t = np.linspace(0.0, 40.0, 161)
    >>> a = np.column_stack([t, 0.0 * t]); b = np.column_stack([50.0 - t, 2.0 + 0.0 * t])
    >>> r = assess_pair(t, a, 0.0 * t, b, np.pi + 0.0 * t, r_safe=15.0, collision_distance=2.0)
    >>> r.encounter, r.compliant, r.encounter_b, r.compliant_b, r.t_enter, r.min_distance
    ('head-on', False, 'head-on', False, 17.75, 2.0)
    """
    t, pos_a, psi_a, pos_b, psi_b, both = _series(t, pos_a, psi_a, pos_b, psi_b, active_a, active_b)
    r_safe = check_range("r_safe", r_safe, 0.0, None, low_open=True, unit="L")
    collision_distance = check_range("collision_distance", collision_distance, 0.0, None, low_open=True, unit="L")
    idx = np.flatnonzero(both)
    if idx.size == 0:
        return PairAssessment(math.inf, None, "none", None, "none", None, None)
    d = np.linalg.norm(pos_a[idx] - pos_b[idx], axis=1)
    j_min = int(np.argmin(d))
    min_distance, k_cpa = float(d[j_min]), int(idx[j_min])
    inside = np.flatnonzero(d < r_safe)
    if inside.size == 0:
        return PairAssessment(min_distance, float(t[k_cpa]), "none", None, "none", None, None)
    j_enter = int(inside[0])
    k_enter = int(idx[j_enter])
    outside_after = np.flatnonzero(d[j_min:] >= r_safe)
    j_exit = j_min + int(outside_after[0]) if outside_after.size else idx.size - 1
    window = idx[j_enter:j_min + 1]
    passage = idx[j_enter:j_exit + 1]
    enc_a = classify_encounter(pos_a[k_enter], psi_a[k_enter], pos_b[k_enter], psi_b[k_enter], profile)
    enc_b = classify_encounter(pos_b[k_enter], psi_b[k_enter], pos_a[k_enter], psi_a[k_enter], profile)
    common = (k_enter, k_cpa, window, passage, min_distance, collision_distance, profile)
    ok_a = _compliance(enc_a, pos_a, psi_a, pos_b, psi_b, *common)
    ok_b = _compliance(enc_b, pos_b, psi_b, pos_a, psi_a, *common)
    return PairAssessment(min_distance, float(t[k_cpa]), enc_a, ok_a, enc_b, ok_b, float(t[k_enter]))


def assess_obstacle(t, pos_a, obstacle_pos, radius, collision_distance, *, active_a=None) -> PairAssessment:
    """Closest approach of ship a to a static circular obstacle (encounter ``"static"``).

    ``min_distance`` is the smallest centre distance (L) while a is active and ``t_min`` its time. ``compliant``
    is True if a kept clear: ``min_distance >= max(collision_distance, radius + 0.5)`` — the collision distance
    between centres, as for ships, widened for obstacles so large that half a ship length beyond their edge
    lies farther out (radius > collision_distance − 0.5 L). The obstacle side has ``encounter_b = "static"`` and
    ``compliant_b = None``; ``t_enter`` is ``None`` (no safe radius is involved).

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
    _, pos_a, _, _, _, active = _series(t, pos_a, np.zeros(t.size), stand_still, np.zeros(t.size), active_a, None)
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
