"""COLREG encounter classification: which situation two ships are in, by named sector profiles (numpy).

Conventions: positions in ship lengths L, x forward/north and y to starboard/east, headings psi in rad measured
from x towards y (clockwise in the marine view, x up and y right), times non-dimensional. A positive change of
heading is a turn to starboard.

Angles used by the sectors of a :class:`ColregProfile`, both in [0, 2π):

* relative bearing of the other ship, ``beta = atan2(dy, dx) - psi_own``: 0 dead ahead, π/2 starboard beam,
  π dead astern;
* relative heading ``psi_r = psi_own - psi_other``.

The seed paper's laboratory sector table (head-on 7π/8 ≤ ψ_r < 9π/8, give-way 3π/8 ≤ ψ_r < 7π/8, stand-on
9π/8 ≤ ψ_r < 13π/8, stern sector 112.5°–247.5° of bearing, i.e. COLREG Rule 13(b)'s "more than 22.5 degrees abaft
her beam"; the paper's §Dynamic Obstacle Avoidance and its laboratory code) was written for counter-clockwise angles, where the
relative heading is ψ_other − ψ_own. Our headings are clockwise (a mirror image), so the same physical relative
heading is ψ_own − ψ_other. With this sign the paper's crossing (own ship at (0, 0) heading 0; the other at
(25, 25), on own's starboard side, heading −90°) gives ``psi_r = π/2`` (crossing, give way) for the own ship and
``psi_r = 3π/2`` (crossing, stand on) for the other, as Rule 15 demands. The stern sector is symmetric about π,
so the sign of ``beta`` does not matter for it.

The rules a classified encounter brings into play are checked from trajectories by
:func:`mmg_casadi.colregs.assess.assess_pair` and :func:`mmg_casadi.colregs.score.score_pair`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mmg_casadi.colregs.geometry import TWO_PI, bearing
from mmg_casadi.errors import InputError, ParameterError, check_range

#: COLREG situations from one ship's side (``encounter`` in the metrics).
ENCOUNTERS = ("overtaking", "overtaken", "head-on", "crossing-give-way", "crossing-stand-on", "none")


def _in_sector(angle: float, sector: tuple[float, float]) -> bool:
    """True if ``angle`` (in [0, 2π)) lies in ``[lo, hi)``; a sector with ``lo > hi`` wraps through 0."""
    lo, hi = sector
    if lo <= hi:
        return lo <= angle < hi
    return angle >= lo or angle < hi


@dataclass(frozen=True)
class ColregProfile:
    """Named COLREG thresholds: encounter sectors and the tolerances of the rule-by-rule scorer.

    Encounter sectors (rad, sectors ``[lo, hi)``; a sector with ``lo > hi`` wraps through 0):

    * ``head_on``, ``give_way``, ``stand_on``: sectors of the relative heading ψ_r in [0, 2π);
    * ``stern_sector``: sector of the relative bearing β that counts as "astern" (overtaking, Rule 13: more than
      22.5° abaft the beam);
    * ``head_on_bearing_deg`` (degrees or ``None``): if set, head-on is decided by bearings instead of ``head_on``:
      each ship sees the other within this angle of her bow; the other (non-astern) encounters with ψ_r inside
      ``give_way`` or ``stand_on`` or ``head_on`` are then crossings, give-way if the other ship is on the own
      starboard side (β in (0, π)), stand-on otherwise;
    * ``overtaking_bow_deg`` (degrees or ``None``): if set, an overtaking also needs the overtaken ship within
      this angle of the overtaking ship's bow.

    Tolerances (degrees, ship lengths L, non-dimensional time L/U, or fractions of the speed at ``t_enter``):

    * ``course_tolerance_deg``: the largest heading change a stand-on or overtaken ship may make and still keep
      her course (Rule 17(a)(i)); ``speed_tolerance``: the largest relative speed change she may make;
    * ``starboard_min_deg``: the smallest alteration that counts as "altering course" (to starboard for Rules
      14 and 15, either way for the stand-on ship's action under 17(b) and the port turn of 17(c));
    * ``action_deg``: the heading change (from the heading at ``t_enter``) whose first excess marks the time of
      action;
    * ``apparent_deg``, ``speed_apparent``: an alteration of course of at least ``apparent_deg`` or a speed
      reduction of at least ``speed_apparent`` is "large enough to be readily apparent" (Rules 8, 16);
    * ``act_range`` (L), ``act_tcpa``: action is "in ample time" (Rules 8, 16) if it starts with the range at
      least ``act_range`` and the time to the closest point of approach (TCPA) at least ``act_tcpa``; past that
      point (range ≤ ``act_range`` or 0 < TCPA ≤ ``act_tcpa``) with a risk of collision, the stand-on ship may
      act alone (Rule 17(a)(ii));
    * ``must_act_range`` (L), ``must_act_tcpa``: with a risk of collision and range ≤ ``must_act_range`` or
      0 < TCPA ≤ ``must_act_tcpa``, collision can no longer be avoided by the give-way ship alone and the
      stand-on ship must act (Rule 17(b)). A zero range or time switches that criterion off.

    "Risk of collision" is a straight-line prediction: closing (TCPA > 0) to a closest point of approach (CPA)
    nearer than the collision distance.

    The default, ``iitm-lab``, is the paper's laboratory profile: head-on 7π/8 ≤ ψ_r < 9π/8 (±22.5°), give-way
    3π/8 ≤ ψ_r < 7π/8, stand-on 9π/8 ≤ ψ_r < 13π/8, stern sector 5π/8 ≤ β < 11π/8 (112.5° to 247.5°, Rule 13's
    22.5° abaft the beam; the sector the modified vortex also uses). Its tolerances are ours: course 15°,
    starboard 5°, action 2°, apparent 10°, speed 20 % (tolerance) and 50 % (apparent, as NTNU below), ample
    time TCPA ≥ 4 (≈ 75 s at full scale, L/U = 18.6 s for the KCS) with no range criterion (so that slow
    overtakings are not judged late), and 17(b) at TCPA ≤ 2 (≈ 37 s). The two times come from our KCS model
    (:func:`~mmg_casadi.vessel.maneuvers.turning_circle` at design speed, 35° rudder from midships): 10°, 30° and 60°
    alterations take 1.4, 2.5 and 3.7 L/U; at TCPA 4 a 60° alteration can still be completed before the CPA,
    at TCPA 2 not even a 30° one. :meth:`ntnu_2023` is a published scheme, :meth:`strict` a narrow head-on
    sector.

    Parameters
    ----------
    name : str, default 'iitm-lab'
        Name of the profile.
    head_on : tuple of float
        Head-on sector of the relative heading (rad).
    give_way : tuple of float
        Give-way (crossing) sector of the relative heading (rad).
    stand_on : tuple of float
        Stand-on (crossing) sector of the relative heading (rad).
    stern_sector : tuple of float
        Sector of the relative bearing that counts as astern (rad).
    course_tolerance_deg : float, default 15.0
        Largest heading change that still keeps the course (degrees).
    starboard_min_deg : float, default 5.0
        Smallest alteration that counts as altering course (degrees).
    head_on_bearing_deg : float or None, optional
        Bearing half-angle that decides head-on instead of ``head_on`` (degrees).
    overtaking_bow_deg : float or None, optional
        Bow half-angle within which the overtaken ship must lie (degrees).
    action_deg : float, default 2.0
        Heading change that marks the time of action (degrees).
    apparent_deg : float, default 10.0
        Smallest readily apparent alteration of course (degrees).
    speed_apparent : float, default 0.5
        Smallest readily apparent speed reduction (fraction of the speed at ``t_enter``).
    speed_tolerance : float, default 0.2
        Largest speed change that still keeps the speed (fraction of the speed at ``t_enter``).
    act_range : float, default 0.0
        Smallest range for action in ample time (L; 0 switches it off).
    act_tcpa : float, default 4.0
        Smallest TCPA for action in ample time (L/U; 0 switches it off).
    must_act_range : float, default 0.0
        Range at or below which the stand-on ship must act (L; 0 switches it off).
    must_act_tcpa : float, default 2.0
        TCPA at or below which the stand-on ship must act (L/U; 0 switches it off).

    Examples
    --------
    >>> p = ColregProfile()
    >>> p.name, round(math.degrees(p.head_on[1] - p.head_on[0]), 1), p.apparent_deg, p.act_tcpa
    ('iitm-lab', 45.0, 10.0, 4.0)
    """

    name: str = "iitm-lab"
    head_on: tuple[float, float] = (7 * math.pi / 8, 9 * math.pi / 8)
    give_way: tuple[float, float] = (3 * math.pi / 8, 7 * math.pi / 8)
    stand_on: tuple[float, float] = (9 * math.pi / 8, 13 * math.pi / 8)
    stern_sector: tuple[float, float] = (5 * math.pi / 8, 11 * math.pi / 8)
    course_tolerance_deg: float = 15.0
    starboard_min_deg: float = 5.0
    head_on_bearing_deg: float | None = None
    overtaking_bow_deg: float | None = None
    action_deg: float = 2.0
    apparent_deg: float = 10.0
    speed_apparent: float = 0.5
    speed_tolerance: float = 0.2
    act_range: float = 0.0
    act_tcpa: float = 4.0
    must_act_range: float = 0.0
    must_act_tcpa: float = 2.0

    def __post_init__(self):
        for key in ("head_on", "give_way", "stand_on", "stern_sector"):
            sector = tuple(float(a) for a in getattr(self, key))
            if len(sector) != 2 or not all(0.0 <= a <= TWO_PI for a in sector) or sector[0] == sector[1]:
                raise ParameterError(key, "a sector (lo, hi) of two different angles in [0, 2π] rad", sector)
            object.__setattr__(self, key, sector)
        for key in ("course_tolerance_deg", "starboard_min_deg", "action_deg", "apparent_deg"):
            check_range(key, getattr(self, key), 0.0, 180.0, unit="degrees")
        for key in ("head_on_bearing_deg", "overtaking_bow_deg"):
            if getattr(self, key) is not None:
                check_range(key, getattr(self, key), 0.0, 180.0, low_open=True, unit="degrees")
        for key in ("speed_apparent", "speed_tolerance"):
            check_range(key, getattr(self, key), 0.0, 1.0, unit="(fraction of the speed)")
        for key in ("act_range", "must_act_range"):
            check_range(key, getattr(self, key), 0.0, None, unit="L")
        for key in ("act_tcpa", "must_act_tcpa"):
            check_range(key, getattr(self, key), 0.0, None, unit="(time, L/U)")

    @classmethod
    def strict(cls) -> ColregProfile:
        """A profile with a narrow head-on sector, ψ_r within ±5° of π.

        Published schemes differ: head-on tolerances range from ±5° (nearly reciprocal courses only) to ±22.5°
        (the laboratory's). The give-way and stand-on sectors grow to meet the narrower head-on sector, so
        relative headings from 67.5° to 292.5° are still all classified; the stern sector and tolerances are
        the laboratory's.

        Returns
        -------
        ColregProfile
            The profile ``"strict"``.

        Examples
        --------
        >>> p = ColregProfile.strict()
        >>> p.name, [round(math.degrees(a), 1) for a in p.head_on]
        ('strict', [175.0, 185.0])
        """
        half = math.radians(5.0)
        return cls(name="strict", head_on=(math.pi - half, math.pi + half), give_way=(3 * math.pi / 8, math.pi - half),
                   stand_on=(math.pi + half, 13 * math.pi / 8))

    @classmethod
    def ntnu_2023(cls, metres_per_length: float = 230.0) -> ColregProfile:
        """The NTNU evaluation scheme of Hagen et al. (2023), binarised.

        Source: Hagen et al., "Safety and COLREG evaluation for marine collision avoidance algorithms", Ocean
        Engineering (2023), doi:10.1016/j.oceaneng.2023.115991 (title, DOI and abstract read at
        ntnuopen.ntnu.no, handle 11250/3104668; the paper body was not available), a scheme in the line of
        K. Woerner, M. R. Benjamin, M. Novitzky, J. J. Leonard, "Quantifying protocol evaluation for autonomous
        collision avoidance", Autonomous Robots, doi:10.1007/s10514-018-9765-y. The numbers were read in the
        NTNU group's public simulator, github.com/NTNU-TTO/SFI-AutoShip-COLAV-simulator,
        ``config/evaluator.yaml`` (commit 2232044):
        ``theta_critical_ho`` 13° (head-on: each ship within 13° of the other's bow), ``theta_critical_ot`` 45°,
        ``theta_ot_min``/``theta_ot_max`` 112.5°/247.5° (overtaking), ``theta_sm_lim`` 10° (a starboard
        manoeuvre), ``delta_course_md`` 2° (smallest detectable course change), ``delta_course_app`` 30°
        (readily apparent), ``delta_speed_reduction_app`` 0.5 and ``delta_speed_md`` 0.2 (apparent and
        detectable relative speed changes), ``r_colregs_3_max`` 1100 m and ``r_colregs_4_max`` 200 m (the
        ranges where stages 3, close quarters, and 4, imminent collision, begin).

        Binarisation (ours; the scheme scores continuously): the stand-on ship keeps course if no detectable
        change (2°) is made, the give-way ship acts in ample time if she starts before stage 3 (range
        ≥ 1100 m), and the stand-on ship may act from stage 3 and must act in stage 4 (range ≤ 200 m), each
        with a risk of collision. The scheme's crossing split ``theta_critical_cr`` (−10°) is not used (its sign
        convention is not defined in the file); crossings split at β = 0. No time criteria (TCPA) are used.

        Ranges in metres are divided by ``metres_per_length``: the default 230 m, the KCS length, keeps the
        full-scale distances (1100 m = 4.78 L, 200 m = 0.87 L). The scheme was tuned on smaller ships; a
        length-scaled reading would pass the length of the ship the ranges were meant for instead.

        Parameters
        ----------
        metres_per_length : float, default 230.0
            Metres per ship length L used to convert the scheme's ranges.

        Returns
        -------
        ColregProfile
            The profile ``"ntnu-2023"`` (ranges in L, angles in degrees, sectors in rad).

        Examples
        --------
        >>> p = ColregProfile.ntnu_2023()
        >>> p.name, p.head_on_bearing_deg, p.apparent_deg, round(p.act_range, 2), round(p.must_act_range, 2)
        ('ntnu-2023', 13.0, 30.0, 4.78, 0.87)
        """
        m = check_range("metres_per_length", metres_per_length, 0.0, None, low_open=True, unit="m")
        return cls(name="ntnu-2023", head_on=(7 * math.pi / 8, 9 * math.pi / 8), give_way=(3 * math.pi / 8, math.pi),
                   stand_on=(math.pi, 13 * math.pi / 8), head_on_bearing_deg=13.0, overtaking_bow_deg=45.0,
                   course_tolerance_deg=2.0, starboard_min_deg=10.0, action_deg=2.0, apparent_deg=30.0,
                   speed_apparent=0.5, speed_tolerance=0.2, act_range=1100.0 / m, act_tcpa=0.0,
                   must_act_range=200.0 / m, must_act_tcpa=0.0)


LAB_PROFILE = ColregProfile()
PROFILES = ("iitm-lab", "ntnu-2023", "strict")  #: names accepted by :func:`get_profile`


def get_profile(profile=None) -> ColregProfile:
    """A :class:`ColregProfile` from its name (one of :data:`PROFILES`), itself, or ``None`` (the laboratory's).

    Parameters
    ----------
    profile : str or ColregProfile or None, optional
        Profile name, a profile, or ``None`` for ``iitm-lab``.

    Returns
    -------
    ColregProfile
        The profile.

    Examples
    --------
    >>> get_profile().name, get_profile("ntnu-2023").name, get_profile(ColregProfile.strict()).name
    ('iitm-lab', 'ntnu-2023', 'strict')
    """
    if profile is None:
        return LAB_PROFILE
    if isinstance(profile, ColregProfile):
        return profile
    makers = {"iitm-lab": ColregProfile, "ntnu-2023": ColregProfile.ntnu_2023, "strict": ColregProfile.strict}
    if profile not in makers:
        raise InputError("profile", f"one of: {', '.join(PROFILES)}", profile)
    return makers[profile]()



def classify_encounter(own_pos, own_psi, other_pos, other_psi, profile: ColregProfile = LAB_PROFILE) -> str:
    """The encounter type from the own ship's point of view, by the profile's sectors.

    First the stern sector: if the other ship lies in the own ship's stern sector the own ship is being
    overtaken (``"overtaken"``); if the own ship lies in the other's stern sector the own ship is overtaking
    (``"overtaking"``); if both hold, the ships lie stern to stern and are moving apart (``"none"``). Otherwise
    the relative heading decides: ``"head-on"``, ``"crossing-give-way"`` or ``"crossing-stand-on"``. Relative
    headings outside all three sectors (courses within 67.5° of each other, e.g. ships abeam or diverging on
    similar courses) give ``"none"``: no rule applies. Only positions and headings are used, so a ship in the
    other's stern sector counts as overtaking whatever the speeds (as in the laboratory's table). A profile with
    ``overtaking_bow_deg`` also needs the overtaken ship within that angle of the overtaker's bow (else
    ``"none"``); one with ``head_on_bearing_deg`` decides head-on by bearings and the crossing side by the side
    the other ship is on (see :class:`ColregProfile`).

    Parameters
    ----------
    own_pos, other_pos : sequence of 2 floats
        Positions (L).
    own_psi, other_psi : float
        Headings (rad, from x towards y).
    profile : ColregProfile
        Sector thresholds.

    Returns
    -------
    str
        ``"head-on"``, ``"crossing-give-way"``, ``"crossing-stand-on"``, ``"overtaking"``, ``"overtaken"`` or
        ``"none"``.

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
    beta = bearing(own_pos, own_psi, other_pos)
    alpha = bearing(other_pos, other_psi, own_pos)
    other_astern = _in_sector(beta % TWO_PI, profile.stern_sector)
    own_astern = _in_sector(alpha % TWO_PI, profile.stern_sector)
    if other_astern or own_astern:
        if other_astern and own_astern:
            return "none"
        bow = profile.overtaking_bow_deg
        if bow is not None and abs(beta if own_astern else alpha) >= math.radians(bow):
            return "none"
        return "overtaken" if other_astern else "overtaking"
    psi_r = (own_psi - other_psi) % TWO_PI
    if profile.head_on_bearing_deg is not None:
        if not any(_in_sector(psi_r, sec) for sec in (profile.head_on, profile.give_way, profile.stand_on)):
            return "none"
        limit = math.radians(profile.head_on_bearing_deg)
        if abs(alpha) < limit and abs(beta) < limit:
            return "head-on"
        return "crossing-give-way" if beta > 0.0 else "crossing-stand-on"
    if _in_sector(psi_r, profile.head_on):
        return "head-on"
    if _in_sector(psi_r, profile.give_way):
        return "crossing-give-way"
    if _in_sector(psi_r, profile.stand_on):
        return "crossing-stand-on"
    return "none"
