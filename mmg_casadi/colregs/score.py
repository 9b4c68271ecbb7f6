"""Rule-by-rule COLREG scoring of one encounter from trajectories (numpy post-processing).

For each ship of a pair, :func:`score_pair` gives a verdict per rule — ``True``, ``False`` or ``None`` (not
applicable) — and the quantities behind it. The rules (COLREG, 1972, as amended):

* Rule 8: action to avoid collision is taken in ample time, is large enough to be readily apparent and results
  in passing at a safe distance (8(a), (b), (d));
* Rule 13: an overtaking vessel keeps out of the way of the vessel being overtaken;
* Rule 14: in a head-on situation each vessel alters course to starboard so that they pass port to port;
* Rule 15: in a crossing the vessel that has the other on her starboard side keeps out of the way and avoids
  crossing ahead of her;
* Rule 16: the give-way vessel takes early and substantial action to keep well clear;
* Rule 17: the stand-on vessel keeps her course and speed (17(a)(i)); she may act alone once it becomes
  apparent that the give-way vessel is not taking appropriate action (17(a)(ii)); when collision cannot be
  avoided by the give-way vessel alone she shall take such action as will best aid to avoid collision
  (17(b)); in a crossing she does not alter to port for a vessel on her own port side (17(c)).

The thresholds are those of a named :class:`~mmg_casadi.colregs.classify.ColregProfile`. Units as in
:mod:`mmg_casadi.colregs.classify`: positions in L, headings in rad (positive change = starboard), times L/U.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mmg_casadi.colregs.classify import LAB_PROFILE, ColregProfile, classify_encounter
from mmg_casadi.colregs.geometry import bearing, pair_series, wrap_to_pi
from mmg_casadi.errors import check_range

#: rule keys of a side's verdicts: 17a = 17(a)(i), 17b = 17(a)(ii) with 17(b), 17c = 17(c)
RULES = ("8", "13", "14", "15", "16", "17a", "17b", "17c")
_JUDGED = ("crossing-give-way", "head-on", "overtaking", "crossing-stand-on", "overtaken")


def cpa_tcpa(rel_pos, rel_vel):
    """Straight-line closest point of approach: distance (CPA) and time to it (TCPA).

    ``rel_pos`` = other − own position, ``rel_vel`` = other − own velocity, arrays (..., 2). TCPA is negative
    when the ships are moving apart (then CPA is the current range) and ``inf`` with no relative motion.

    Parameters
    ----------
    rel_pos : array-like (..., 2)
        Other minus own position (L).
    rel_vel : array-like (..., 2)
        Other minus own velocity (L per unit time).

    Returns
    -------
    cpa : numpy.ndarray (...)
        Closest point of approach (L).
    tcpa : numpy.ndarray (...)
        Time to it (in the time unit of ``rel_vel``, L/U for velocities in U); negative when opening, ``inf``
        without relative motion.

    Examples
    --------
    >>> cpa, tcpa = cpa_tcpa(np.array([[10.0, 0.0], [10.0, 1.0]]), np.array([[-2.0, 0.0], [-2.0, 0.0]]))
    >>> cpa.tolist(), tcpa.tolist()
    ([0.0, 1.0], [5.0, 5.0])
    >>> [float(v) for v in cpa_tcpa(np.array([3.0, 4.0]), np.array([1.0, 0.0]))]
    [5.0, -3.0]
    """
    p = np.asarray(rel_pos, dtype=float)
    v = np.asarray(rel_vel, dtype=float)
    vv = np.sum(v * v, axis=-1)
    pv = np.sum(p * v, axis=-1)
    moving = vv > 1e-12
    tcpa = np.where(moving, -pv / np.where(moving, vv, 1.0), np.inf)
    ahead = np.where(np.isfinite(tcpa) & (tcpa > 0.0), tcpa, 0.0)
    cpa = np.linalg.norm(p + v * ahead[..., None], axis=-1)
    return cpa, tcpa


def stand_on_should_act(cpa, tcpa, distance, *, collision_distance, profile: ColregProfile = LAB_PROFILE):
    """Rule 17 triggers for a stand-on ship: may she act alone (17(a)(ii)), must she act (17(b))?

    Both need a risk of collision: closing (TCPA > 0) to a predicted CPA below ``collision_distance``. She may
    act once the give-way ship's ample time is over (``distance <= profile.act_range`` or ``tcpa <=
    profile.act_tcpa``) and must act from ``distance <= profile.must_act_range`` or ``tcpa <=
    profile.must_act_tcpa`` (a zero threshold is not used). Scalars or arrays of the same shape.

    Parameters
    ----------
    cpa, tcpa : float or array
        Predicted closest point of approach (L) and time to it (L/U), e.g. from :func:`cpa_tcpa`.
    distance : float or array
        Current range (L).
    collision_distance : float
        Centre distance that counts as a collision (L).
    profile : ColregProfile
        Thresholds.

    Returns
    -------
    may_act : bool or numpy.ndarray of bool
        Rule 17(a)(ii): the stand-on ship may take action alone (a bool for scalar inputs).
    must_act : bool or numpy.ndarray of bool
        Rule 17(b): she must take action (a bool for scalar inputs).

    Examples
    --------
    Collision course, lab profile (may act at TCPA ≤ 4, must at TCPA ≤ 2):

    >>> [tuple(map(bool, stand_on_should_act(0.5, t, 2.0 * t, collision_distance=2.0))) for t in (6.0, 3.0, 1.5)]
    [(False, False), (True, False), (True, True)]

    Passing clear (predicted CPA 3 L) or moving apart: no trigger.

    >>> [bool(x) for x in stand_on_should_act(np.array([3.0, 0.5]), np.array([1.0, -1.0]), 2.0,
    ...                                       collision_distance=2.0)[1]]
    [False, False]
    """
    cpa, tcpa, distance = (np.asarray(a, dtype=float) for a in (cpa, tcpa, distance))
    risk = (cpa < collision_distance) & (tcpa > 0.0)

    def trigger(rng, time):
        hit = np.zeros(np.broadcast(cpa, tcpa, distance).shape, dtype=bool)
        if rng > 0.0:
            hit = hit | (distance <= rng)
        if time > 0.0:
            hit = hit | (tcpa <= time)
        return risk & hit

    may = trigger(profile.act_range, profile.act_tcpa)
    must = trigger(profile.must_act_range, profile.must_act_tcpa)
    if may.ndim == 0:
        return bool(may), bool(must)
    return may, must


@dataclass(frozen=True)
class SideScore:
    """The rule verdicts of one ship of a pair.

    ``encounter``: from this ship's point of view (:data:`~mmg_casadi.colregs.classify.ENCOUNTERS`); ``verdicts``:
    ``{rule: True | False | None}`` for every key of :data:`RULES`; ``details``: per applicable rule the
    quantities behind the verdict; ``quantities``: the encounter's quantities from this side (see
    :func:`score_pair`); ``compliant_all``: all applicable rules satisfied (``None`` if none applies).

    Parameters
    ----------
    encounter : str
        Encounter type from this ship's point of view.
    verdicts : dict
        ``{rule: True | False | None}`` for every key of :data:`RULES`.
    details : dict
        Per applicable rule, the quantities behind the verdict.
    quantities : dict
        The encounter's quantities from this side.
    compliant_all : bool or None
        Whether all applicable rules are satisfied (``None`` if none applies).

    Examples
    --------
    >>> s = SideScore("none", dict.fromkeys(RULES), {}, {}, None)
    >>> s.to_dict()["8"], s.to_dict()["compliant_all"]
    ({'verdict': None}, None)
    """

    encounter: str
    verdicts: dict
    details: dict
    quantities: dict
    compliant_all: bool | None

    def to_dict(self) -> dict:
        """JSON-ready dict: encounter, compliant_all, quantities and one entry per rule (NaN/inf → None).

        Returns
        -------
        dict
            ``encounter``, ``compliant_all``, ``quantities`` and per rule of :data:`RULES` ``{"verdict", ...details}``.
        """
        out = {"encounter": self.encounter, "compliant_all": self.compliant_all,
               "quantities": _clean(self.quantities)}
        for rule in RULES:
            out[rule] = {"verdict": self.verdicts.get(rule), **_clean(self.details.get(rule, {}))}
        return out


@dataclass(frozen=True)
class PairScore:
    """Rule verdicts of both ships of a pair under one profile (``a``, ``b``: :class:`SideScore`).

    Parameters
    ----------
    profile : str
        Name of the COLREG profile used.
    a : SideScore
        Verdicts of ship a.
    b : SideScore
        Verdicts of ship b.

    Examples
    --------
    >>> none = SideScore("none", dict.fromkeys(RULES), {}, {}, None)
    >>> sorted(PairScore("iitm-lab", none, none).to_dict())
    ['a', 'b', 'profile']
    """

    profile: str
    a: SideScore
    b: SideScore

    def to_dict(self) -> dict:
        """``{"profile", "a", "b"}`` with each side's :meth:`SideScore.to_dict`.

        Returns
        -------
        dict
            ``profile`` (its name) and ``a``, ``b`` (each side's dict).
        """
        return {"profile": self.profile, "a": self.a.to_dict(), "b": self.b.to_dict()}


def _clean(d: dict) -> dict:
    """``d`` with numpy scalars as Python values and NaN/±inf as ``None``."""
    out = {}
    for k, v in d.items():
        if isinstance(v, (bool, np.bool_)):
            out[k] = bool(v)
        elif isinstance(v, (int, float, np.integer, np.floating)):
            out[k] = float(v) if math.isfinite(float(v)) else None
        else:
            out[k] = v
    return out


def _empty_side(encounter: str) -> SideScore:
    return SideScore(encounter, dict.fromkeys(RULES), {}, {}, None)


def _course_line_crossing(pos, pos_o, psi_o, passage) -> str | None:
    """Where the ship crossed the other's course line within ``passage``: ``"ahead"``, ``"astern"`` or ``None``.

    The course line runs through the other ship along her current heading; a crossing is a sign change of
    ``cross(h_o, p - p_o)`` between consecutive nonzero samples, ahead if ``dot(h_o, p - p_o) >= 0`` there
    (linearly interpolated). Any crossing ahead makes the result ``"ahead"``.
    """
    rel = pos[passage] - pos_o[passage]
    h = np.column_stack([np.cos(psi_o[passage]), np.sin(psi_o[passage])])
    side = h[:, 0] * rel[:, 1] - h[:, 1] * rel[:, 0]
    along = np.einsum("ij,ij->i", h, rel)
    nz = np.flatnonzero(side != 0.0)
    where = None
    for k0, k1 in zip(nz[:-1], nz[1:]):
        if side[k0] * side[k1] < 0.0:
            f = side[k0] / (side[k0] - side[k1])
            if along[k0] + f * (along[k1] - along[k0]) >= 0.0:
                return "ahead"
            where = "astern"
    return where


def _first(mask, window):
    """First sample index of ``window`` where ``mask`` (aligned with ``window``) holds, or ``None``."""
    hits = np.flatnonzero(mask)
    return int(window[hits[0]]) if hits.size else None


def _side(enc, t, pos, psi, spd, pos_o, psi_o, cpa_pred, tcpa_pred, dist, k_enter, k_cpa, window, passage,
          min_distance, collision_distance, profile) -> SideScore:
    """Verdicts of the ship (pos, psi, spd) against the other (pos_o, psi_o) in encounter ``enc``."""
    if enc not in _JUDGED:
        return _empty_side(enc)
    deg = math.degrees
    dpsi = wrap_to_pi(psi[window] - psi[k_enter])
    dspd = spd[window] / spd[k_enter] - 1.0 if spd[k_enter] > 0.0 else np.zeros(window.size)
    k_act = _first(np.abs(dpsi) > math.radians(profile.action_deg), window)
    acted = k_act is not None
    stbd, port = max(0.0, deg(np.max(dpsi))), max(0.0, -deg(np.min(dpsi)))
    slow = max(0.0, -float(np.min(dspd)))
    bearing_cpa = bearing(pos[k_cpa], psi[k_cpa], pos_o[k_cpa])
    contact_cpa = bearing(pos_o[k_cpa], psi_o[k_cpa], pos[k_cpa])
    q = {
        "t_enter": t[k_enter], "range_enter": dist[k_enter],
        "cpa_distance": min_distance, "t_cpa": t[k_cpa], "tcpa_enter": tcpa_pred[k_enter],
        "cpa_predicted_enter": cpa_pred[k_enter],
        "t_action": t[k_act] if acted else None,
        "action_side": (None if not acted else "starboard" if dpsi[window == k_act][0] > 0 else "port"),
        "range_at_action": dist[k_act] if acted else None,
        "tcpa_at_action": tcpa_pred[k_act] if acted else None,
        "heading_change_deg": deg(dpsi[int(np.argmax(np.abs(dpsi)))]),
        "starboard_change_deg": stbd, "port_change_deg": port,
        "speed_change": float(dspd[int(np.argmax(np.abs(dspd)))]),
        "other_side_at_cpa": "starboard" if bearing_cpa >= 0.0 else "port",
        "bearing_at_cpa_deg": deg(bearing_cpa), "contact_angle_at_cpa_deg": deg(contact_cpa),
        "crossed_other_course": _course_line_crossing(pos, pos_o, psi_o, passage),
    }
    apparent = max(stbd, port) >= profile.apparent_deg or slow >= profile.speed_apparent
    tcpa_act = tcpa_pred[k_act] if acted else math.nan
    ample = acted and (cpa_pred[k_act] >= collision_distance
                       or (dist[k_act] >= profile.act_range and not 0.0 < tcpa_act < profile.act_tcpa))
    kept_clear = min_distance >= collision_distance
    turned_stbd = stbd >= profile.starboard_min_deg
    timing = {"t_action": q["t_action"], "range_at_action": q["range_at_action"], "tcpa_at_action": tcpa_act,
              "cpa_predicted_at_action": cpa_pred[k_act] if acted else None, "act_range": profile.act_range,
              "act_tcpa": profile.act_tcpa}
    size = {"heading_change_deg": max(stbd, port), "speed_reduction": slow, "apparent_deg": profile.apparent_deg,
            "speed_apparent": profile.speed_apparent}
    v: dict = {}
    d: dict = {}
    stand_on = enc in ("crossing-stand-on", "overtaken")
    if stand_on:
        may, must = stand_on_should_act(cpa_pred[window], tcpa_pred[window], dist[window],
                                        collision_distance=collision_distance, profile=profile)
        k_may, k_must = _first(may, window), _first(must, window)
        q["t_may_act"] = t[k_may] if k_may is not None else None
        q["t_must_act"] = t[k_must] if k_must is not None else None
        held = window < k_may if k_may is not None else np.ones(window.size, dtype=bool)
        if held.any():
            course = deg(float(np.max(np.abs(dpsi[held]))))
            speed = float(np.max(np.abs(dspd[held])))
            v["17a"] = course <= profile.course_tolerance_deg and speed <= profile.speed_tolerance
            d["17a"] = {"until": t[window[held][-1]], "heading_change_deg": course, "speed_change": speed,
                        "course_tolerance_deg": profile.course_tolerance_deg,
                        "speed_tolerance": profile.speed_tolerance}
        k0 = k_may if k_may is not None else k_enter
        after = window >= k0
        turn = deg(float(np.max(np.abs(wrap_to_pi(psi[window[after]] - psi[k0])))))
        cut = max(0.0, -float(np.min(spd[window[after]] / spd[k0] - 1.0))) if spd[k0] > 0.0 else 0.0
        altered = turn >= profile.starboard_min_deg or cut >= profile.speed_apparent
        if k_must is not None or not kept_clear or (k_may is not None and altered):
            v["17b"] = altered
            d["17b"] = {"from": t[k0], "heading_change_deg": turn, "speed_reduction": cut,
                        "t_must_act": q["t_must_act"], "cpa_distance": min_distance,
                        "collision_distance": collision_distance}
        if enc == "crossing-stand-on" and k_may is not None and altered:
            on_port = np.array([bearing(pos[k], psi[k], pos_o[k]) < 0.0 for k in window[after]])
            to_port = wrap_to_pi(psi[window[after]] - psi[k_may])
            v["17c"] = not bool(np.any(on_port & (to_port <= -math.radians(profile.starboard_min_deg))))
            d["17c"] = {"from": t[k_may], "port_change_deg": max(0.0, -deg(float(np.min(to_port)))),
                        "starboard_min_deg": profile.starboard_min_deg}
        if acted:
            v["8"] = apparent and kept_clear
            d["8"] = {**size, "cpa_distance": min_distance, "collision_distance": collision_distance}
    else:
        if acted or enc != "overtaking":
            v["8"] = bool(acted and apparent and ample and kept_clear)
            d["8"] = {**size, **timing, "cpa_distance": min_distance, "collision_distance": collision_distance}
        if enc == "crossing-give-way":
            v["15"] = turned_stbd and q["crossed_other_course"] != "ahead" and kept_clear
            d["15"] = {"starboard_change_deg": stbd, "starboard_min_deg": profile.starboard_min_deg,
                       "crossed_other_course": q["crossed_other_course"], "cpa_distance": min_distance,
                       "collision_distance": collision_distance}
        if enc == "head-on":
            v["14"] = turned_stbd and bearing_cpa < 0.0
            d["14"] = {"starboard_change_deg": stbd, "starboard_min_deg": profile.starboard_min_deg,
                       "other_side_at_cpa": q["other_side_at_cpa"]}
        if enc == "overtaking":
            v["13"] = kept_clear
            d["13"] = {"cpa_distance": min_distance, "collision_distance": collision_distance,
                       "contact_angle_at_cpa_deg": q["contact_angle_at_cpa_deg"]}
        if enc in ("crossing-give-way", "overtaking"):
            v["16"] = bool(acted and ample and apparent and kept_clear) if (acted or enc != "overtaking") \
                else kept_clear
            d["16"] = {**size, **timing, "cpa_distance": min_distance, "collision_distance": collision_distance}
    verdicts = {r: (bool(v[r]) if r in v else None) for r in RULES}
    judged = [x for x in verdicts.values() if x is not None]
    return SideScore(enc, verdicts, d, q, all(judged) if judged else None)


def score_pair(t, pos_a, psi_a, pos_b, psi_b, *, r_safe, collision_distance, profile=LAB_PROFILE, speed_a=None,
               speed_b=None, active_a=None, active_b=None, judge_b: bool = True) -> PairScore:
    """Rule-by-rule COLREG verdicts of ships a and b from their trajectories.

    The encounter begins at ``t_enter``, the first sample with both ships active and closer than ``r_safe``;
    it is classified from each side by :func:`~mmg_casadi.colregs.classify.classify_encounter` and judged on the window
    from ``t_enter`` to the closest point of approach (CPA, smallest distance while both are active). Velocities
    are the time derivatives of the positions; speeds are ``speed_a``/``speed_b`` if given, else their norms.
    Heading and speed changes are measured from their values at ``t_enter``; the time of action is the first
    sample where the heading differs by more than ``profile.action_deg``. TCPA and the predicted CPA are
    straight-line predictions (:func:`cpa_tcpa`) at each sample.

    Verdicts per side (``None`` where the rule does not apply):

    * give-way (crossing give-way, overtaking) and head-on ships — Rule 8: she acted, with a readily apparent
      alteration (``apparent_deg`` or ``speed_apparent``), in ample time (at the time of action, no risk of
      collision yet — predicted CPA ≥ ``collision_distance`` — or range ≥ ``act_range`` and not
      0 < TCPA < ``act_tcpa``), and passed at a safe distance (CPA ≥
      ``collision_distance``); for an overtaking ship that never altered, not applicable; Rule 16 (crossing,
      overtaking): the same (an overtaking ship that never altered: the CPA alone);
      Rule 15: a starboard alteration ≥ ``starboard_min_deg``, never crossing the other's course line ahead
      of her while within ``r_safe``, and a CPA of at least ``collision_distance``; Rule 14: a starboard
      alteration ≥ ``starboard_min_deg`` and the other on the port side at the CPA; Rule 13: CPA ≥
      ``collision_distance``;
    * stand-on ships (crossing stand-on, overtaken) — Rule 17(a)(i) (``"17a"``): heading within
      ``course_tolerance_deg`` and speed within ``speed_tolerance`` from ``t_enter`` until she may act
      (:func:`stand_on_should_act`; the whole window if she never may; not applicable if she may at once);
      Rules 17(a)(ii) and 17(b) (``"17b"``; applicable if she must act, if the CPA is below
      ``collision_distance`` — a stand-on ship that holds her course into a collision fails it — or if she
      altered after she may act): from the time she may act (else ``t_enter``), an alteration of at least
      ``starboard_min_deg`` or a speed cut of at least ``speed_apparent``; Rule 17(c)
      (crossing only, if she altered after she may act, as 17(c) is about action under 17(a)(ii)): from then
      on, no sample with the heading ``starboard_min_deg`` or more to port of its value at that time while
      the other ship is on her port side; Rule 8 (if she altered): readily apparent
      and passing at a safe distance (the timing of her action is Rule 17's).

    Parameters
    ----------
    t : array (T,)
        Sample times (L/U).
    pos_a, pos_b : array (T, 2)
        Positions (L).
    psi_a, psi_b : array (T,)
        Headings (rad, from x towards y; wrapped or continuous).
    r_safe, collision_distance : float
        Radius that starts the encounter and the centre distance counted as a collision (L).
    profile : ColregProfile
        Thresholds (:func:`~mmg_casadi.colregs.classify.get_profile`).
    speed_a, speed_b : array (T,), optional
        Speeds over ground (L/(L/U)); default: from the positions.
    active_a, active_b : array (T,) of bool, optional
        Whether each ship is still sailing (default: always).
    judge_b : bool, default True
        Judge ship b too; with False her side has her encounter type only (no verdicts), for callers that
        need ship a's verdicts alone.

    Returns
    -------
    PairScore
        ``to_dict()`` gives ``{"profile", "a": {...}, "b": {...}}``, each side with ``encounter``,
        ``compliant_all``, ``quantities`` and one ``{"verdict", ...}`` entry per rule of :data:`RULES`.

    Examples
    --------
    Crossing: the give-way ship a holds on, the stand-on ship b holds on too and they collide. Neither kept her
    rules: a did not act (Rules 8, 15, 16); b did not act when she had to (Rule 17(b)).

    >>> t = np.linspace(0.0, 40.0, 401)
    >>> a = np.column_stack([t, 0.0 * t]); b = np.column_stack([25.0 + 0.0 * t, 25.0 - t])
    >>> s = score_pair(t, a, 0.0 * t, b, -np.pi / 2 + 0.0 * t, r_safe=15.0, collision_distance=2.0)
    >>> s.a.encounter, s.a.verdicts["15"], s.a.verdicts["16"], s.a.compliant_all
    ('crossing-give-way', False, False, False)
    >>> s.b.encounter, s.b.verdicts["17a"], s.b.verdicts["17b"], s.b.compliant_all
    ('crossing-stand-on', True, False, False)
    """
    t, pos_a, psi_a, pos_b, psi_b, both = pair_series(t, pos_a, psi_a, pos_b, psi_b, active_a, active_b)
    r_safe = check_range("r_safe", r_safe, 0.0, None, low_open=True, unit="L")
    collision_distance = check_range("collision_distance", collision_distance, 0.0, None, low_open=True, unit="L")
    idx = np.flatnonzero(both)
    none = PairScore(profile.name, _empty_side("none"), _empty_side("none"))
    if idx.size < 2:
        return none
    d = np.linalg.norm(pos_a[idx] - pos_b[idx], axis=1)
    j_min = int(np.argmin(d))
    inside = np.flatnonzero(d < r_safe)
    if inside.size == 0:
        return none
    j_enter = int(inside[0])
    k_enter, k_cpa = int(idx[j_enter]), int(idx[j_min])
    outside_after = np.flatnonzero(d[j_min:] >= r_safe)
    j_exit = j_min + int(outside_after[0]) if outside_after.size else idx.size - 1
    window, passage = idx[j_enter:j_min + 1], idx[j_enter:j_exit + 1]
    vel_a, vel_b = np.gradient(pos_a, t, axis=0), np.gradient(pos_b, t, axis=0)
    spd = []
    for name, given, vel in (("speed_a", speed_a, vel_a), ("speed_b", speed_b, vel_b)):
        s = np.linalg.norm(vel, axis=1) if given is None else np.asarray(given, dtype=float).ravel()
        if s.shape != t.shape:
            raise ValueError(f"{name}: expected {t.size} samples like t, got {s.size}")
        spd.append(s)
    cpa_pred, tcpa_pred = cpa_tcpa(pos_b - pos_a, vel_b - vel_a)
    dist = np.linalg.norm(pos_b - pos_a, axis=1)
    min_distance = float(d[j_min])
    enc_a = classify_encounter(pos_a[k_enter], psi_a[k_enter], pos_b[k_enter], psi_b[k_enter], profile)
    enc_b = classify_encounter(pos_b[k_enter], psi_b[k_enter], pos_a[k_enter], psi_a[k_enter], profile)
    common = (cpa_pred, tcpa_pred, dist, k_enter, k_cpa, window, passage, min_distance, collision_distance, profile)
    side_a = _side(enc_a, t, pos_a, psi_a, spd[0], pos_b, psi_b, *common)
    side_b = _side(enc_b, t, pos_b, psi_b, spd[1], pos_a, psi_a, *common) if judge_b else _empty_side(enc_b)
    return PairScore(profile.name, side_a, side_b)
