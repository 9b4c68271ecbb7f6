"""Rules 17(a)(i), 17(a)(ii), 17(b), 17(c) and 8 for a ship that keeps course and speed: stand-on and overtaken.

Her course and speed are measured from the onset of risk to the CPA against her heading and speed at the onset
(after a stretch excused by a give-way duty to another ship, against those at its end,
:mod:`mmg_casadi.colregs.duties`); only speed above the highest she sailed before the onset is an increase.
**Her action** is the first counted sample where the course changed by ``course_tolerance_deg`` or more or the speed
by ``speed_tolerance`` or more. She may act alone from ``apparent``, when the give-way ship's inaction is apparent,
and must act from ``must`` (:func:`mmg_casadi.colregs.context.timing`); her **free** sample is the first of the two
(policy ``inaction = "late"``, scorer version 4: ``late``).

* **17(a)(i)**, keep course and speed (applies while she must keep them, from the onset to the free sample or the
  CPA): S = max(0, 1 − w_so,χ·P_course − w_so,up·P_up − w_so,down·P_down), each P ramped from detectable to
  readily apparent (Hagen 2023). Verdict: course change below ``course_tolerance_deg`` and speed changes below
  ``speed_tolerance`` throughout.
* **17(a)(ii)**, action alone once the inaction is apparent (applies if she acted): verdict: she acted at or after
  the free sample; score 1, else how far into her stand-on time she waited, (t_action − t_onset)/(t_free −
  t_onset) (to the CPA if it never came).
* **17(b)**, action when collision cannot be avoided by the give-way ship alone (applies if ``must`` came):
  S = (1 − P_late)·(1 − P_na), P_late = ramp of the time of action from ``must`` to the CPA (0 for an action
  before ``must``), 0 without action. Verdict: she acted, with a readily apparent change, before the CPA.
* **17(c)** (crossing stand-on ship that acted): no alteration to port for a ship on her port side (at the onset;
  policy ``side_17c = "now"``, version 4: at each sample, which misses a port turn that swings the other ship onto
  the starboard side): S = 1 − ramp(port alteration, detectable, apparent). Verdict: the port alteration stays
  below ``course_tolerance_deg``.
* **Rule 8**: without action nothing is judged and she keeps it (score 1; a drift within tolerance is not action,
  so it passes Rule 8 as it passes 17(a)(i)); with action S = 1 − P_na, verdict: readily apparent. The timing of
  her action is Rule 17's; the passing distance is the give-way ship's (her Rules 8 and 16): a stand-on ship
  acting at the last moment cannot be blamed for how close the give-way ship let them come (Cockcroft & Lameijer
  p. 72: Rule 8(d) does not apply to action under 17(a)(ii) or 17(b)).

A rule not kept names ``t_broken``, the first sample at which it broke.
"""

from __future__ import annotations

import numpy as np

from mmg_casadi.colregs.manoeuvre import measure_manoeuvre
from mmg_casadi.colregs.penalties import non_apparent_penalty, ramp, stand_on_penalty
from mmg_casadi.colregs.verdict import RuleResult


def moving_reference(span, excused) -> np.ndarray:
    """Reference sample of every sample of ``span``: its first sample, then the first counted sample after each
    excused stretch.

    Parameters
    ----------
    span : array-like of int
        Consecutive samples.
    excused : array-like of bool
        Whether each sample of ``span`` is excused.

    Returns
    -------
    numpy.ndarray of int
        One reference sample per sample of ``span``.

    Examples
    --------
    >>> moving_reference(np.arange(10, 16), np.array([0, 0, 1, 1, 0, 0], bool)).tolist()
    [10, 10, 10, 10, 14, 14]
    """
    span, excused = np.asarray(span, dtype=int), np.asarray(excused, dtype=bool)
    starts = ~excused & np.concatenate([[True], excused[:-1]])
    return np.maximum.accumulate(np.where(starts, span, span[0]))


def stand_on_rules(ctx, excused) -> dict:
    """Rule results of a stand-on or overtaken ship (module docstring).

    Parameters
    ----------
    ctx : EncounterContext
        The encounter (:func:`mmg_casadi.colregs.context.encounter_context`).
    excused : numpy.ndarray of bool (T,)
        Samples at which her changes are attributed to a give-way duty to another ship.

    Returns
    -------
    dict
        ``{rule: RuleResult}`` for the rules that apply.

    Examples
    --------
    The paper's crossing from the stand-on ship's side; the give-way ship holds her course and the stand-on ship
    turns 40° to starboard from t = 21.6, once the give-way ship's inaction is apparent (TCPA 4, t = 21):

    >>> from mmg_casadi.colregs.context import first_encounter
    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> t = np.arange(0.0, 40.0, 0.25)
    >>> psi = -np.pi / 2 + np.radians(40.0) * np.clip((t - 21.6) / 2.0, 0.0, 1.0)
    >>> v = np.column_stack([np.cos(psi), np.sin(psi)])
    >>> own = np.array([25.0, 25.0]) + np.vstack([[0.0, 0.0], np.cumsum(0.125 * (v[1:] + v[:-1]), axis=0)])
    >>> ctx = first_encounter(t, own, psi, np.column_stack([t, 0 * t]), 0 * t, iitm_lab())
    >>> {rule: r.verdict for rule, r in stand_on_rules(ctx, np.zeros(t.size, bool)).items()}
    {'17a_i': True, '17a_ii': True, '17b': True, '17c': True, '8': True}
    """
    p, e = ctx.profile, ctx.episode
    span = np.arange(e.onset, e.cpa + 1)
    counted = ~np.asarray(excused, dtype=bool)[span]
    reference = moving_reference(span, ~counted)
    window, ref = span[counted], reference[counted]
    m = measure_manoeuvre(ctx.psi, ctx.speed, window, ref, ctx.speed[ref], ctx.speed_max,
                          course_threshold_deg=p.course_tolerance_deg, speed_threshold=p.speed_tolerance)
    action = m.action
    free = free_sample(ctx)
    stop = e.cpa + 1 if free is None else free
    held = window < stop
    out = {}
    excused_time = float(np.sum(np.gradient(ctx.t)[span][~counted])) if not counted.all() else 0.0
    if held.any():
        course = float(np.max(np.abs(m.course_change[held])))
        up, down = float(np.max(m.speed_increase[held])), float(np.max(m.speed_decrease[held]))
        pen = stand_on_penalty(course, up, down, p)
        kept = course < p.course_tolerance_deg and up < p.speed_tolerance and down < p.speed_tolerance
        out["17a_i"] = RuleResult(kept, pen["score"], {
            "until": ctx.at(int(window[held][-1])), "course_change_deg": course, "speed_increase": up,
            "speed_decrease": down, "excused_time": excused_time, **{k: v for k, v in pen.items() if k != "score"},
            "t_broken": None if kept else ctx.at(int(window[held][np.argmax(_changed(m, held, p))]))})
    if action is not None:
        t_end = ctx.at(free if free is not None else e.cpa)
        waited = float(ramp(ctx.t[action], ctx.t[e.onset], t_end))
        permitted = free is not None and action >= free
        out["17a_ii"] = RuleResult(permitted, 1.0 if permitted else waited,
                                   {"t_action": ctx.at(action), "t_late": ctx.at(ctx.late),
                                    "t_apparent": ctx.at(ctx.apparent), "t_free": ctx.at(free),
                                    "t_broken": None if permitted else ctx.at(action)})
    apparent = m.max_course_change_deg >= p.course_apparent_deg or m.max_speed_decrease >= p.speed_apparent
    p_na = non_apparent_penalty(m.max_course_change_deg, m.max_speed_decrease, p)
    if ctx.must is not None:
        p_late = 1.0 if action is None else float(ramp(ctx.t[action], ctx.t[ctx.must], ctx.t[e.cpa]))
        score = 0.0 if action is None else (1.0 - p_late) * (1.0 - p_na)
        kept = action is not None and apparent
        out["17b"] = RuleResult(kept, score, {
            "t_must": ctx.at(ctx.must), "t_action": ctx.at(action), "course_change_deg": m.max_course_change_deg,
            "speed_reduction": m.max_speed_decrease, "readily_apparent": apparent, "P_late": p_late, "P_na": p_na,
            "t_broken": None if kept else ctx.at(ctx.must)})
    if ctx.role == "stand-on" and action is not None:
        side = ctx.bearing < 0.0 if p.side_17c == "onset" else ctx.beta[window] < 0.0
        after = (window >= action) & side
        port = float(max(0.0, -np.min(m.course_change[after], initial=0.0)))
        kept = port < p.course_tolerance_deg
        broke = None if kept else int(window[after][np.argmax(-m.course_change[after] >= p.course_tolerance_deg)])
        out["17c"] = RuleResult(kept, 1.0 - float(ramp(port, p.course_detectable_deg, p.course_apparent_deg)),
                                {"port_change_deg": port, "t_action": ctx.at(action), "t_broken": ctx.at(broke)})
    if action is None:
        out["8"] = RuleResult(True, 1.0, {"acted": False, "cpa": ctx.cpa})
    else:
        out["8"] = RuleResult(apparent, 1.0 - p_na, {
            "acted": True, "t_action": ctx.at(action), "course_change_deg": m.max_course_change_deg,
            "speed_reduction": m.max_speed_decrease, "readily_apparent": apparent, "cpa": ctx.cpa, "P_na": p_na,
            "t_broken": None if apparent else ctx.at(int(ctx.episode.cpa))})
    return out


def free_sample(ctx) -> int | None:
    """The sample from which a stand-on ship may act alone: the first of ``apparent`` (Rule 17(a)(ii)) and ``must``
    (17(b)); ``late`` under the policy ``inaction = "late"`` (scorer version 4).

    Parameters
    ----------
    ctx : EncounterContext
        The encounter.

    Returns
    -------
    int or None
        The sample, or None if neither comes before the CPA.
    """
    if ctx.profile.inaction == "late":
        return ctx.late
    times = [k for k in (ctx.apparent, ctx.must) if k is not None]
    return min(times) if times else None


def _changed(m, held, profile) -> np.ndarray:
    """Where, among the held samples of manoeuvre ``m``, the course or speed left the stand-on tolerance."""
    return ((np.abs(m.course_change[held]) >= profile.course_tolerance_deg)
            | (m.speed_increase[held] >= profile.speed_tolerance) | (m.speed_decrease[held] >= profile.speed_tolerance))
