"""Threshold profiles of the encounter scorer (:mod:`mmg_casadi.colregs.scorer`): every number with its source.

A :class:`ScoringProfile` holds the Rule 7 risk gate, the encounter sectors, what counts as a detectable, readily
apparent or tolerated change of course and speed, when a give-way ship is late and a stand-on ship may or must act,
the passing-distance score and the weights of the graded rule scores. Units: lengths in ship lengths L, times in
L/U (≈ 18.6 s for the 230 m KCS at its design speed), angles in degrees, speed changes as fractions of the speed.

Sources cited by the profiles (read as stated; "ours" marks a value this package chose, with its reason):

* COLREG 1972 as amended, Rule 13(b): overtaking is coming up from more than 22.5° abaft the beam, i.e. the
  bearing sector 112.5°–247.5°.
* Jadhav, Pandi & Somayajula, "Collision Avoidance for Autonomous Surface Vessels using Novel Artificial Potential
  Fields" (IIT Madras) and its laboratory code: R_safe = 15 L (Table 3), collision within 2 L (§Statistical
  Analysis), head-on sector 7π/8 ≤ ψ_r < 9π/8 (±22.5° about reciprocal courses).
* Hagen, Vassbotn, Skogvold, Johansen & Brekke, "Safety and COLREG evaluation for marine collision avoidance
  algorithms", Ocean Engineering 288 (2023) 115991, doi:10.1016/j.oceaneng.2023.115991; its numbers as configured
  in the NTNU group's simulator, github.com/NTNU-TTO/SFI-AutoShip-COLAV-simulator ``config/evaluator.yaml``
  (2023), and the group's earlier evaluator github.com/petterhangerhagen/AIS_processing (commit ff650e5,
  ``AutoVerification.py``), which re-implements K. Woerner, M. R. Benjamin, M. Novitzky & J. J. Leonard,
  "Quantifying protocol evaluation for autonomous collision avoidance", Autonomous Robots 43 (2019),
  doi:10.1007/s10514-018-9765-y. Cited below as *Hagen 2023 (evaluator.yaml)* and *AIS_processing*.
* A. N. Cockcroft & J. N. F. Lameijer, *A Guide to the Collision Avoidance Rules*: an alteration of course under
  10° is unlikely to be readily apparent (p. 51); close quarters begins at about 1 nautical mile for ships in
  sight of one another (p. 52); Rule 8(d)'s safe passing distance binds the give-way ship, not the stand-on ship's
  action under Rule 17(a)(ii) or 17(b) (p. 72); in open sea a give-way ship that has not acted by about 2 nautical
  miles in a crossing of two merchant ships has usually waited too long (p. 108).
* The re-implementation of Hagen 2023 at github.com/marinehdk/colav-simulator
  (``config/evaluator/oe2023_simulated-v1.yaml``, ``colav_simulator/evaluation/scoring.py``), cited as *MH*: the
  stand-on ship must act (Rule 17(b)) within 60 s of the CPA; passing-distance score r_pref = 2 r_min; safety score
  S_r + (1 − S_r)·S_θ.
* M. Krasowski & M. Althoff, "Temporal Logic Formalization of Marine Traffic Rules", IEEE IV 2021, and their
  rule monitor (CommonOcean), as re-implemented (their numbers read from arXiv 2402.08502 by a third party): a risk
  of collision is judged over a time horizon of 420 s, and a ship is given 60 s to react.
* MOOS-IvP ``uFldCollisionDetect`` (after K. Woerner): a near miss at twice the collision distance (6 m and 3 m).

The form of the graded scores (which term multiplies or subtracts which) follows AIS_processing and Hagen 2023;
:mod:`mmg_casadi.colregs.penalties` gives each formula.

Examples
--------
>>> lab = scoring_profile("iitm-lab")
>>> lab.d_risk, lab.r_risk, lab.head_on_deg, lab.course_apparent_deg
(4.0, 15.0, 22.5, 10.0)
>>> ntnu = scoring_profile("ntnu-2023")
>>> ntnu.head_on_deg, ntnu.overtaking_bow_deg, round(ntnu.late_range, 1), round(ntnu.must_range, 1)
(13.0, 45.0, 22.0, 4.0)
>>> pub = scoring_profile("published")
>>> round(pub.d_safe, 2), round(pub.late_range, 1), pub.course_apparent_deg, pub.course_tolerance_deg
(8.05, 16.1, 30.0, 2.0)
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

from mmg_casadi.errors import InputError, check_range


@dataclass(frozen=True)
class ScoringProfile:
    """Named thresholds of the encounter scorer; ``None`` (or ``inf`` for the gate) switches a criterion off.

    Parameters
    ----------
    name : str
        Name of the profile.
    d_risk : float
        Rule 7 gate: a risk of collision exists while the straight-line predicted CPA is below ``d_risk`` (L) ...
    t_risk : float
        ... and 0 < TCPA < ``t_risk`` (L/U; ``inf``: no time horizon) ...
    r_risk : float
        ... and the range is at most ``r_risk`` (L; ``inf``: no range horizon).
    head_on_deg : float
        Head-on if each ship sees the other within this angle of her bow, ``|β| < θ`` and ``|α| < θ`` (degrees).
    head_on_heading_deg : float or None
        If set, head-on also needs the courses within this angle of reciprocal (degrees).
    stern_deg : float
        The stern sector begins this far from the bow on either side (degrees): overtaking needs the overtaker
        at ``|α| > stern_deg`` from the overtaken ship's bow, and the higher speed.
    overtaking_bow_deg : float or None
        If set, overtaking also needs the overtaken ship within this angle of the overtaker's bow (degrees).
    t_lookback : float
        An alteration made up to this long before the onset of risk counts as action for the encounter (L/U).
    course_detectable_deg, course_apparent_deg : float
        Smallest detectable and smallest readily apparent alteration of course (degrees).
    speed_detectable, speed_apparent : float
        Smallest detectable and smallest readily apparent speed change (fractions of the reference speed).
    starboard_min_deg : float
        Smallest alteration to starboard that counts as a starboard manoeuvre (Rule 14; degrees).
    course_tolerance_deg, speed_tolerance : float
        Largest course (degrees) and relative speed change with which a stand-on ship still keeps her course and
        speed (Rule 17(a)(i)); larger changes are her action.
    late_tcpa, late_range : float or None
        With the risk still present, TCPA at or below ``late_tcpa`` (L/U) or range at or below ``late_range`` (L)
        ends the give-way ship's ample time (Rules 8, 16) and makes her inaction apparent (17(a)(ii)).
    must_tcpa, must_range : float or None
        The same for the point where the stand-on ship must act (Rule 17(b)).
    r_col, r_nm, r_min, r_pref : float
        Passing-distance score: 0 at a CPA ≤ ``r_col``, 1 at ≥ ``r_pref``, piecewise linear (L).
    gamma_col, gamma_nm, gamma_min : float
        The score gained from ``r_col`` to ``r_nm``, ``r_nm`` to ``r_min`` and ``r_min`` to ``r_pref`` (sum 1).
    d_safe : float
        Binary "passing at a safe distance": actual CPA at least ``d_safe`` (L).
    d_ahead : float or None
        Rule 13: crossing the overtaken ship's course line less than ``d_ahead`` ahead of her is crossing ahead (L).
    ahead_contact_deg : float or None
        Rule 13: the overtaker within this angle of the overtaken ship's bow at the CPA is crossing ahead (degrees).
    w_na_course, w_na_speed, na_cut : float
        Non-apparent penalty: weights of the course and speed parts; no penalty if either part is below ``na_cut``.
    w_sts, w_nsm : float
        Rule 14 weights of the passing-side and the non-starboard-manoeuvre penalties.
    w_ahead_15, w_ahead_13 : float
        Weights of the crossing-ahead penalties of Rules 15 and 13.
    w_so_course, w_so_up, w_so_down : float
        Rule 17(a)(i) weights of the course change, speed increase and speed decrease penalties.
    head_on_doubt_deg : float or None
        Rule 14(c), "in any doubt ... assume that it does exist": two ships that see each other within this angle
        of the bow meet head-on although ``head_on_deg`` alone would make it a crossing (degrees; None: no doubt
        band).
    late_after_onset : float
        The give-way ship's ample time ends no earlier than this long after the onset of risk (L/U): a ship is
        given time to react to a risk that arises inside the ``late_*`` range (0: the trigger alone).
    must_cpa : float or None
        Rule 17(b) needs the straight-line CPA below this (L) at ``must``: collision cannot then be avoided by the
        give-way ship alone (None: ``d_safe``).
    excuse : {"forced", "open-duty"}
        When a stand-on ship's change of course or speed is excused by a give-way duty to another ship
        (:mod:`mmg_casadi.colregs.duties`): ``"forced"`` only while that duty is active (risk, not past its CPA)
        and the change is in the direction the duty requires; ``"open-duty"`` (scorer version 4) while that duty
        is open at all.
    inaction : {"no-action", "late"}
        When the give-way ship's inaction becomes apparent to the stand-on ship (Rule 17(a)(ii)): ``"no-action"``
        at ``late`` or after, once she has still made no readily apparent change; ``"late"`` (version 4) at
        ``late`` whatever she did.
    side_17c : {"onset", "now"}
        Rule 17(c)'s "a vessel on her own port side": at the onset of risk (``"onset"``, so a port turn that
        swings the other ship onto the starboard side still counts) or at each sample (``"now"``, version 4).
    own_clearance : bool
        Rules 8, 16 (crossing, overtaking): the give-way ship's own action must produce the safe passing distance,
        i.e. her track must clear ``d_safe`` from the other ship's track had that ship held course and speed
        (version 4: the actual CPA only).
    w_pose_alpha, w_pose_beta : float
        Weights of the pose score S_θ at the CPA from the contact angle α and the bearing β (sum at most 1;
        0 and 0: the safety score is S_r alone, version 4).
    pose_cut_deg : float
        Pose cut-off: from this angle off the bow a ship's pose at the CPA is fully safe (degrees).
    past_clear : float or None
        Rule 13(d): an overtaking lasts until the overtaking ship is finally past and clear, the range opening
        beyond this (L); a later risk of the pair before then belongs to the same encounter, with its roles
        (None: the encounter ends at its release).
    rule9_width : float
        Rule 9(a): the widest channel or fairway (L, bank to bank across the ship's track) that counts as narrow
        (:mod:`mmg_casadi.colregs.narrow_channel`). 20 L in every profile, ours: the COLREGs leave "narrow" to the
        circumstances (Cockcroft & Lameijer, on Rule 9: a channel that a ship can navigate only within its
        limits); 20 L includes the paper's 10 L channel, environment 6's straits (8-16 L) and the fjord's 6 L
        channels, and excludes water wider than the 2 × R_safe (30 L) across which the guidance sees both banks.
    rule9_kept_share : float
        Rule 9(a) is kept when at least this share of the ship's time in a narrow channel is on its starboard side.
        0.9 in every profile, ours: most of the passage, leaving room for the brief excursions that overtaking
        (Rule 9(e)) and the avoidance of a ship or an obstacle demand.

    Examples
    --------
    >>> p = scoring_profile("iitm-lab")
    >>> p.name, p.late_tcpa, p.must_tcpa, p.d_safe
    ('iitm-lab', 4.0, 2.0, 2.0)
    """

    name: str
    d_risk: float
    t_risk: float
    r_risk: float
    head_on_deg: float
    head_on_heading_deg: float | None
    stern_deg: float
    overtaking_bow_deg: float | None
    t_lookback: float
    course_detectable_deg: float
    course_apparent_deg: float
    speed_detectable: float
    speed_apparent: float
    starboard_min_deg: float
    course_tolerance_deg: float
    speed_tolerance: float
    late_tcpa: float | None
    late_range: float | None
    must_tcpa: float | None
    must_range: float | None
    r_col: float
    r_nm: float
    r_min: float
    r_pref: float
    gamma_col: float
    gamma_nm: float
    gamma_min: float
    d_safe: float
    d_ahead: float | None
    ahead_contact_deg: float | None
    w_na_course: float
    w_na_speed: float
    na_cut: float
    w_sts: float
    w_nsm: float
    w_ahead_15: float
    w_ahead_13: float
    w_so_course: float
    w_so_up: float
    w_so_down: float
    head_on_doubt_deg: float | None = None
    late_after_onset: float = 0.0
    must_cpa: float | None = None
    excuse: str = "forced"
    inaction: str = "no-action"
    side_17c: str = "onset"
    own_clearance: bool = True
    w_pose_alpha: float = 0.25
    w_pose_beta: float = 0.75
    pose_cut_deg: float = 90.0
    past_clear: float | None = None
    rule9_width: float = 20.0
    rule9_kept_share: float = 0.9

    def __post_init__(self):
        for key in ("d_risk", "t_risk", "r_risk", "d_ahead", "late_tcpa", "late_range", "must_tcpa", "must_range"):
            if getattr(self, key) is not None:
                check_range(key, getattr(self, key), 0.0, None, low_open=True)
        for key in ("head_on_deg", "head_on_heading_deg", "stern_deg", "overtaking_bow_deg", "course_detectable_deg",
                    "course_apparent_deg", "starboard_min_deg", "course_tolerance_deg", "ahead_contact_deg"):
            if getattr(self, key) is not None:
                check_range(key, getattr(self, key), 0.0, 180.0, low_open=True, unit="degrees")
        for key in ("speed_detectable", "speed_apparent", "speed_tolerance", "na_cut", "gamma_col", "gamma_nm",
                    "gamma_min", "w_na_course", "w_na_speed", "w_sts", "w_nsm", "w_ahead_15", "w_ahead_13",
                    "w_so_course", "w_so_up", "w_so_down"):
            check_range(key, getattr(self, key), 0.0, 1.0)
        check_range("t_lookback", self.t_lookback, 0.0, None)
        check_range("course_apparent_deg", self.course_apparent_deg, self.course_detectable_deg, 180.0,
                    low_open=True, unit="degrees (above course_detectable_deg)")
        check_range("speed_apparent", self.speed_apparent, self.speed_detectable, 1.0, low_open=True)
        distances = (self.r_col, self.r_nm, self.r_min, self.r_pref)
        if not 0.0 <= distances[0] <= distances[1] <= distances[2] <= distances[3] or distances[0] == distances[3]:
            raise InputError("r_col, r_nm, r_min, r_pref", "0 ≤ r_col ≤ r_nm ≤ r_min ≤ r_pref, r_col < r_pref",
                             distances)
        if not math.isclose(self.gamma_col + self.gamma_nm + self.gamma_min, 1.0):
            raise InputError("gamma_col + gamma_nm + gamma_min", "1", self.gamma_col + self.gamma_nm + self.gamma_min)
        check_range("d_safe", self.d_safe, 0.0, self.d_risk, low_open=True, unit="L (at most d_risk)")
        if self.head_on_doubt_deg is not None:
            check_range("head_on_doubt_deg", self.head_on_doubt_deg, self.head_on_deg, 90.0,
                        unit="degrees (at least head_on_deg)")
        check_range("late_after_onset", self.late_after_onset, 0.0, None)
        if self.must_cpa is not None:
            check_range("must_cpa", self.must_cpa, 0.0, None, low_open=True)
        for key, allowed in POLICIES.items():
            if getattr(self, key) not in allowed:
                raise InputError(key, f"one of: {', '.join(allowed)}", getattr(self, key))
        if not isinstance(self.own_clearance, bool):
            raise InputError("own_clearance", "true or false", self.own_clearance)
        for key in ("w_pose_alpha", "w_pose_beta"):
            check_range(key, getattr(self, key), 0.0, 1.0)
        check_range("w_pose_alpha + w_pose_beta", self.w_pose_alpha + self.w_pose_beta, 0.0, 1.0 + 1e-12)
        check_range("pose_cut_deg", self.pose_cut_deg, 0.0, 180.0, low_open=True, unit="degrees")
        if self.past_clear is not None:
            check_range("past_clear", self.past_clear, 0.0, None, low_open=True)
        check_range("rule9_width", self.rule9_width, 0.0, None, low_open=True, unit="L")
        check_range("rule9_kept_share", self.rule9_kept_share, 0.0, 1.0)

    @property
    def must_distance(self) -> float:
        """The straight-line CPA below which the stand-on ship must act (L): ``must_cpa``, else ``d_safe``."""
        return self.d_safe if self.must_cpa is None else self.must_cpa


#: the allowed values of the scorer's policies (the first is version 5's and the published profile's)
POLICIES = {"excuse": ("forced", "open-duty"), "inaction": ("no-action", "late"), "side_17c": ("onset", "now")}


#: weights of the graded scores that Hagen 2023 (evaluator.yaml) and AIS_processing publish, shared by both profiles
_WEIGHTS = {
    "w_na_course": 0.5, "w_na_speed": 0.5,  # γ_na,χ = γ_na,u = 0.5, Hagen 2023 (evaluator.yaml)
    "na_cut": 0.3,                           # no non-apparent penalty if a part is below 0.3, AIS_processing
    "w_sts": 0.6, "w_nsm": 0.4,              # γ_sts, γ_nsm, Hagen 2023 (evaluator.yaml)
    "w_ahead_15": 0.5, "w_ahead_13": 0.3,    # S15 = S16 − 0.5 P_ahead, S13 = S16 − 0.3 P_ahead, both sources
    "w_so_course": 0.5, "w_so_up": 0.25, "w_so_down": 0.25,  # γ_so,Δχ, γ_so,up, γ_so,down, Hagen 2023
    "w_pose_alpha": 0.25, "w_pose_beta": 0.75,  # γ_α, γ_β of the pose score, Hagen 2023 (evaluator.yaml)
}

NAUTICAL_MILE = 1852.0
"""Metres per nautical mile."""

KCS_LENGTH = 230.0
"""Length between perpendiculars of the KCS (m), the unit ship length of the paper's scenes."""

KCS_TIME_UNIT = 230.0 / 12.347
"""The KCS's time unit L/U (s): its length over its design speed of 24 kn (12.347 m/s)."""


def iitm_lab() -> ScoringProfile:
    """The paper laboratory's profile: its sectors, safe radius and collision distance; published or our values
    for what the laboratory left open.

    * gate: ``r_risk`` = 15 L, the laboratory's R_safe (paper Table 3), inside which its ships react;
      ``d_risk`` = 4 L, ours: twice the laboratory's collision distance of 2 L (paper §Statistical Analysis), i.e.
      a straight-line passing with less than one collision distance of clearance; no time horizon;
    * sectors: head-on 22.5°, the half-width of the laboratory's head-on sector 7π/8 ≤ ψ_r < 9π/8, applied to
      both bearings (as Hagen 2023 does with its 13°) and kept for the courses; stern sector 112.5° (COLREG
      Rule 13(b), also the laboratory's); no bow condition for the overtaker (the laboratory has none);
    * ``t_lookback`` 4 L/U (≈ 75 s), ours: the time our KCS model takes for a 60° alteration at 35° rudder
      (3.7 L/U, :func:`mmg_casadi.vessel.maneuvers.turning_circle`), so a manoeuvre begun before the onset
      counts whole;
    * changes: detectable 2° and 20 % (Hagen 2023 ``delta_course_md``, ``delta_speed_md``); readily apparent
      10° (Cockcroft & Lameijer p. 51) and a speed cut of 50 % (Hagen 2023 ``delta_speed_reduction_app``);
      starboard manoeuvre 10° (Hagen 2023 ``theta_sm_lim``; Cockcroft & Lameijer p. 51); the stand-on ship
      keeps course within 10° (an alteration she makes below what is readily apparent cannot mislead the
      give-way ship, Cockcroft & Lameijer p. 51) and speed within 20 % (detectable, Hagen 2023);
    * timing, ours from our KCS model (10°, 30°, 60° alterations take 1.4, 2.5, 3.7 L/U): ample time ends at
      TCPA 4 (≈ 75 s; a 60° alteration still completes), the stand-on ship must act at TCPA 2 (≈ 37 s);
    * passing distance: 0 at the laboratory's collision distance 2 L, 1 from ``d_risk`` = 4 L (ours, as the gate),
      linear between; safe passing: no collision, CPA ≥ 2 L;
    * Rule 13: crossing the overtaken ship's course line less than 8 L ahead of her is crossing ahead: 1 nautical
      mile, where close quarters begins for ships in sight (Cockcroft & Lameijer p. 52), at the KCS's 230 m;
    * weights: Hagen 2023 and AIS_processing (module docstring).

    Returns
    -------
    ScoringProfile
        The profile ``"iitm-lab"`` (lengths in L, times in L/U, angles in degrees).

    Examples
    --------
    >>> p = iitm_lab()
    >>> p.head_on_heading_deg, p.stern_deg, p.t_lookback, round(p.d_ahead * 230.0 / 1852.0, 2)
    (22.5, 112.5, 4.0, 0.99)
    """
    return ScoringProfile(
        name="iitm-lab", d_risk=4.0, t_risk=math.inf, r_risk=15.0,
        head_on_deg=22.5, head_on_heading_deg=22.5, stern_deg=112.5, overtaking_bow_deg=None,
        t_lookback=4.0, course_detectable_deg=2.0, course_apparent_deg=10.0, speed_detectable=0.2,
        speed_apparent=0.5, starboard_min_deg=10.0, course_tolerance_deg=10.0, speed_tolerance=0.2,
        late_tcpa=4.0, late_range=None, must_tcpa=2.0, must_range=None,
        r_col=2.0, r_nm=2.0, r_min=2.0, r_pref=4.0, gamma_col=0.0, gamma_nm=0.0, gamma_min=1.0, d_safe=2.0,
        d_ahead=8.0, ahead_contact_deg=None, **_WEIGHTS)


def ntnu_2023(metres_per_length: float = 50.0) -> ScoringProfile:
    """The configuration of Hagen et al. (2023), its ranges in metres divided by ``metres_per_length``.

    Read in Hagen 2023 (evaluator.yaml): head-on ``theta_critical_ho`` 13° (each ship within 13° of the other's
    bow); overtaking ``theta_ot_min``/``theta_ot_max`` 112.5°/247.5° with the overtaken ship within
    ``theta_critical_ot`` 45° of the overtaker's bow; detectable changes ``delta_course_md`` 2° and
    ``delta_speed_md`` 20 %; readily apparent ``delta_course_app`` 30° and ``delta_speed_reduction_app`` 50 %;
    starboard manoeuvre ``theta_sm_lim`` 10°; stage 3 (close quarters) from ``r_colregs_3_max`` 1100 m and
    stage 4 (imminent danger) from ``r_colregs_4_max`` 200 m; the encounter is judged from stage 2, 1900 m (the
    early-2023 configuration; 2500 m in October 2023); passing-distance score r_pref/r_min/r_nm/r_col
    190/100/50/30 m with γ_min/γ_nm/γ_col 0.2/0.3/0.5. Rule 13's crossing ahead is the overtaker within 45° of
    the overtaken ship's bow at the CPA (Hagen 2023 and AIS_processing).

    Our readings: the gate is stage 2 (range ≤ 1900 m) with a straight-line CPA below r_pref (a passing the
    scheme would score less than fully safe) and no time horizon; ample time ends at stage 3 (a manoeuvre begun
    outside it has no delay penalty, as the re-implementation github.com/marinehdk/colav-simulator does), the
    stand-on ship must act in stage 4; she keeps course and speed while no detectable change is made (2°, 20 %);
    safe passing is a CPA of at least r_min. The crossing split ``theta_critical_cr`` (−10°) is not used: its sign
    convention differs between the group's codes, so crossings split at β = 0. ``t_lookback`` is the laboratory
    profile's (ours).

    ``metres_per_length``: the scheme's ranges are absolute and were tuned to its own ships. The group's earlier
    code puts stage 4 at "usually four ship lengths" (AIS_processing: 400 m for its traffic); the default reads
    Hagen 2023's 200 m the same way, 50 m per ship length, so the geometry is kept in ship lengths (stage 4 at
    4 L, r_min at 2 L, the laboratory's collision distance). 230 keeps the distances at the KCS's full scale
    instead (stage 4 at 0.87 L, inside a collision of two KCS).

    Parameters
    ----------
    metres_per_length : float, default 50.0
        Metres per ship length L used to convert the scheme's ranges.

    Returns
    -------
    ScoringProfile
        The profile ``"ntnu-2023"`` (lengths in L, angles in degrees).

    Examples
    --------
    >>> p = ntnu_2023()
    >>> round(p.r_risk, 1), round(p.d_risk, 1), p.r_min, p.d_safe, p.course_apparent_deg
    (38.0, 3.8, 2.0, 2.0, 30.0)
    >>> round(ntnu_2023(230.0).must_range, 2)
    0.87
    """
    m = check_range("metres_per_length", metres_per_length, 0.0, None, low_open=True, unit="m")
    return ScoringProfile(
        name="ntnu-2023", d_risk=190.0 / m, t_risk=math.inf, r_risk=1900.0 / m,
        head_on_deg=13.0, head_on_heading_deg=None, stern_deg=112.5, overtaking_bow_deg=45.0,
        t_lookback=4.0, course_detectable_deg=2.0, course_apparent_deg=30.0, speed_detectable=0.2,
        speed_apparent=0.5, starboard_min_deg=10.0, course_tolerance_deg=2.0, speed_tolerance=0.2,
        late_tcpa=None, late_range=1100.0 / m, must_tcpa=None, must_range=200.0 / m,
        r_col=30.0 / m, r_nm=50.0 / m, r_min=100.0 / m, r_pref=190.0 / m, gamma_col=0.5, gamma_nm=0.3,
        gamma_min=0.2, d_safe=100.0 / m, d_ahead=None, ahead_contact_deg=45.0, **_WEIGHTS)


def published(metres_per_length: float = KCS_LENGTH, seconds_per_unit: float = KCS_TIME_UNIT) -> ScoringProfile:
    """The published standard: the thresholds of Woerner et al. (2019) and Hagen et al. (2023) for angles, speeds,
    sectors and the graded scores, seamanship (Cockcroft & Lameijer) for distances and timing, converted to the
    scene's units with the own ship's length and time unit (the KCS's by default).

    * changes (Hagen 2023 evaluator.yaml, after Woerner et al.): detectable 2° and 20 %, readily apparent 30° and a
      50 % speed cut; a starboard manoeuvre from 10°; the stand-on ship keeps her course and speed while no
      detectable change is made (2°, 20 %; penalised from 2° to 30°);
    * sectors: head-on within 13° of each bow (Hagen 2023 ``theta_critical_ho``); Rule 14(c), in doubt assume
      head-on: each ship within 22.5° of the other's bow (ours: the widest head-on sector of the schemes compared,
      the paper laboratory's ±22.5°, inside AIS_processing's active 30°); overtaking from
      112.5° (COLREG Rule 13(b)) with the overtaken ship within 45° of the overtaker's bow (Hagen 2023);
    * risk of collision (Rule 7): a straight-line CPA below the safe passing distance within a time horizon of
      420 s (Krasowski & Althoff's rule monitor), no range horizon;
    * safe passing distance 1 nautical mile (8.05 L for the KCS): where close quarters begins for ships in sight
      (Cockcroft & Lameijer p. 52), which Rule 8(c) asks the give-way ship's action to avoid; it binds the give-way
      ship's own action (her track must clear it from the stand-on ship's track had she held on, p. 72);
    * timing: the give-way ship's ample time ends at 2 nautical miles (16.1 L; Cockcroft & Lameijer p. 108), but
      never less than 60 s after the risk arose (a ship's time to react, Krasowski & Althoff); her inaction is
      apparent once that has passed with no readily apparent change of hers (Rule 17(a)(ii)); the stand-on ship
      must act within 60 s of the CPA with the straight-line CPA below a near miss (MH's Rule 17(b) trigger);
    * passing-distance score: 0 at the collision distance 2 L (paper §Statistical Analysis), γ_col = 0.5 gained
      to a near miss at twice that, 4 L (MOOS-IvP's ratio), γ_nm = 0.3 to the safe distance of 1 nm and
      γ_min = 0.2 to twice it, 2 nm (MH's r_pref = 2 r_min; γ of Hagen 2023); pose score and weights Hagen 2023;
    * Rule 13: the overtaker within 45° of the overtaken ship's bow at the CPA crosses ahead (Hagen 2023), and so
      does one that crosses her course line less than 1 nautical mile ahead of her (close quarters, Cockcroft &
      Lameijer p. 52); the overtaking lasts until she is past and clear, 2 nautical miles off (Rule 13(d); ours:
      where the passing-distance score is full);
    * ``t_lookback`` 4 L/U, as the laboratory profile (ours).

    Parameters
    ----------
    metres_per_length : float, default 230.0
        The own ship's length (m): converts nautical miles to the scene's ship lengths.
    seconds_per_unit : float, default 230 / 12.347
        The scene's time unit L/U (s): converts seconds.

    Returns
    -------
    ScoringProfile
        The profile ``"published"`` (lengths in L, times in L/U, angles in degrees).

    Examples
    --------
    >>> p = published()
    >>> round(p.d_risk, 2), round(p.t_risk, 1), round(p.late_after_onset, 2), round(p.must_tcpa, 2)
    (8.05, 22.5, 3.22, 3.22)
    >>> p.head_on_deg, p.head_on_doubt_deg, p.excuse, p.inaction, p.side_17c, p.own_clearance
    (13.0, 22.5, 'forced', 'no-action', 'onset', True)
    """
    m = check_range("metres_per_length", metres_per_length, 0.0, None, low_open=True, unit="m")
    s = check_range("seconds_per_unit", seconds_per_unit, 0.0, None, low_open=True, unit="s")
    nm = NAUTICAL_MILE / m
    return ScoringProfile(
        name="published", d_risk=nm, t_risk=420.0 / s, r_risk=math.inf,
        head_on_deg=13.0, head_on_heading_deg=None, stern_deg=112.5, overtaking_bow_deg=45.0,
        t_lookback=4.0, course_detectable_deg=2.0, course_apparent_deg=30.0, speed_detectable=0.2,
        speed_apparent=0.5, starboard_min_deg=10.0, course_tolerance_deg=2.0, speed_tolerance=0.2,
        late_tcpa=None, late_range=2.0 * nm, must_tcpa=60.0 / s, must_range=None,
        r_col=2.0, r_nm=4.0, r_min=nm, r_pref=2.0 * nm, gamma_col=0.5, gamma_nm=0.3, gamma_min=0.2, d_safe=nm,
        d_ahead=nm, ahead_contact_deg=45.0, head_on_doubt_deg=22.5, late_after_onset=60.0 / s, must_cpa=4.0,
        excuse="forced", inaction="no-action", side_17c="onset", own_clearance=True, past_clear=2.0 * nm,
        **_WEIGHTS)


#: names accepted by :func:`scoring_profile`; the first is the default of every report
SCORING_PROFILES = {"published": published, "iitm-lab": iitm_lab, "ntnu-2023": ntnu_2023}

DEFAULT_PROFILE = "published"
"""The profile of every report unless another is asked for."""


def scoring_profile(profile=None) -> ScoringProfile:
    """A :class:`ScoringProfile` from its name (a key of :data:`SCORING_PROFILES`), itself, or ``None``
    (:data:`DEFAULT_PROFILE`, ``published``).

    Parameters
    ----------
    profile : str or ScoringProfile or None, optional
        Profile name, a profile, or ``None`` for the default.

    Returns
    -------
    ScoringProfile
        The profile.

    Examples
    --------
    >>> scoring_profile().name, scoring_profile("ntnu-2023").name
    ('published', 'ntnu-2023')
    >>> scoring_profile("strict")
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: profile: expected one of: published, iitm-lab, ntnu-2023, got 'strict'
    """
    if isinstance(profile, ScoringProfile):
        return profile
    if profile is not None and profile not in SCORING_PROFILES:
        raise InputError("profile", f"one of: {', '.join(SCORING_PROFILES)}", profile)
    return _named(DEFAULT_PROFILE if profile is None else profile)


@functools.lru_cache(maxsize=None)
def _named(name: str) -> ScoringProfile:
    """The profile of a name, built (and checked) once per process; profiles are frozen."""
    return SCORING_PROFILES[name]()
