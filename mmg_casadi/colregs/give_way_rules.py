"""Rules 8, 13, 14, 15 and 16 for a ship that must act: head-on, give-way (crossing) and overtaking.

Her manoeuvre is measured from her baseline (:mod:`mmg_casadi.colregs.context`) to the CPA: the time of action is
the first detectable change (``course_detectable_deg`` or ``speed_detectable``). Terms
(:mod:`mmg_casadi.colregs.penalties`): S_safety of the actual CPA (its range and the pose), P_delay from the range
where ample time ended, P_na of the largest course change and speed reduction.

* **Rules 8 and 16** (8: ample time, readily apparent, safe distance; 16: early and substantial action to keep well
  clear): S = S_safety·(1 − P_delay)·(1 − P_na) (AIS_processing's S16). Verdict: she acted, in ample time (before
  the ample time ended, or it never ended), with a readily apparent change (``course_apparent_deg`` or a reduction
  of ``speed_apparent``) and passed at ``d_safe`` or more; a give-way (crossing) or overtaking ship's own action
  must also give that clearance (``own_clearance``, :func:`mmg_casadi.colregs.context.own_clearance`). Rule 16
  applies to give-way and overtaking ships; for them the two rules coincide. A head-on ship has Rule 8 only.
* **Rule 14** (head-on): S = max(0, 1 − w_sts·P_sts − w_nsm·P_nsm), P_sts = 1 − port-to-port score at the CPA,
  P_nsm = 1 − min(1, starboard alteration/``starboard_min_deg``) (linear; Hagen 2023 names the term, its form
  here is ours). Verdict: a starboard alteration of at least ``starboard_min_deg``, none to port of that size,
  and each ship on the other's port side at the CPA (β < 0 and α < 0).
* **Rule 15** (give-way): S = max(0, S16 − w_ahead_15·P_ahead), P_ahead = 1 if she crossed the other's course line
  ahead of her between onset and release. Verdict: no crossing ahead, CPA ≥ ``d_safe``.
* **Rule 13** (overtaking): S = max(0, S16 − w_ahead_13·P_ahead), P_ahead = 1 if, from the onset until she is past
  and clear (the end of the pair's stretch: the next encounter or the end), she crossed the overtaken ship's
  course line less than ``d_ahead`` ahead of her, or (``ahead_contact_deg``) lay within that angle of her bow at
  the CPA. Verdict: no crossing ahead and a range of at least ``d_safe`` throughout.

A rule not kept names ``t_broken``, the first sample at which it broke (for Rules 8, 16: the end of ample time if
she had not acted by then, the first range below ``d_safe``, else the CPA).
"""

from __future__ import annotations

import numpy as np

from mmg_casadi.colregs.manoeuvre import course_line_crossings, measure_manoeuvre
from mmg_casadi.colregs.penalties import (delay_penalty, non_apparent_penalty, passing_distance_score,
                                          port_to_port_score, ramp, safety_score)
from mmg_casadi.colregs.verdict import RuleResult


def give_way_rules(ctx) -> dict:
    """Rule results of a head-on, give-way or overtaking ship (module docstring).

    Parameters
    ----------
    ctx : EncounterContext
        The encounter (:func:`mmg_casadi.colregs.context.encounter_context`).

    Returns
    -------
    dict
        ``{rule: RuleResult}`` for the rules of her role.

    Examples
    --------
    The paper's crossing; the give-way ship turns 60° to starboard at t = 16 (TCPA 9) and passes astern:

    >>> from mmg_casadi.colregs.context import first_encounter
    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> t = np.arange(0.0, 40.0, 0.25)
    >>> psi = np.radians(60.0) * np.clip((t - 16.0) / 3.0, 0.0, 1.0)
    >>> v = np.column_stack([np.cos(psi), np.sin(psi)])
    >>> own = np.vstack([[0.0, 0.0], np.cumsum(0.125 * (v[1:] + v[:-1]), axis=0)])
    >>> ctx = first_encounter(t, own, psi, np.column_stack([25 + 0 * t, 25 - t]), -np.pi / 2 + 0 * t, iitm_lab())
    >>> {rule: (r.verdict, round(r.score, 2)) for rule, r in give_way_rules(ctx).items()}
    {'8': (True, 1.0), '16': (True, 1.0), '15': (True, 1.0)}
    """
    p, e = ctx.profile, ctx.episode
    window = np.arange(ctx.base, e.cpa + 1)
    m = measure_manoeuvre(ctx.psi, ctx.speed, window, np.full(window.size, ctx.base), ctx.speed_ref,
                          ctx.speed_max, course_threshold_deg=p.course_detectable_deg,
                          speed_threshold=p.speed_detectable)
    acted = m.action is not None
    ample = acted and (ctx.late is None or m.action <= ctx.late)
    r_late = None if ctx.late is None else float(ctx.range[ctx.late])
    r_man = None if not acted else float(ctx.range[m.action])
    if ample and r_late is not None:
        r_man = max(r_man, r_late)
    p_delay = delay_penalty(r_late, r_man, ctx.cpa)
    p_na = non_apparent_penalty(m.max_course_change_deg, m.max_speed_decrease, p)
    apparent = m.max_course_change_deg >= p.course_apparent_deg or m.max_speed_decrease >= p.speed_apparent
    k_cpa = e.cpa
    s_r = float(passing_distance_score(ctx.cpa, p))
    s_safety = float(safety_score(ctx.cpa, ctx.alpha[k_cpa], ctx.beta[k_cpa], p))
    own = ctx.clearance is None or ctx.clearance >= p.d_safe
    safe = ctx.cpa >= p.d_safe and own
    s16 = s_safety * (1.0 - p_delay) * (1.0 - p_na)
    terms = {"t_action": ctx.at(m.action), "range_at_action": None if not acted else float(ctx.range[m.action]),
             "t_late": ctx.at(ctx.late), "range_late": r_late, "in_ample_time": ample,
             "course_change_deg": m.max_course_change_deg, "speed_reduction": m.max_speed_decrease,
             "readily_apparent": apparent, "cpa": ctx.cpa, "own_clearance": ctx.clearance, "safe_distance": safe,
             "S_r": s_r, "S_safety": s_safety, "P_delay": p_delay, "P_na": p_na}
    kept = acted and ample and apparent and safe
    causes = ((ctx.late, not ample), (_first_below(ctx, window, p.d_safe), not safe), (k_cpa, True))
    broken = [] if kept else [k for k, bad in causes if bad and k is not None]
    terms["t_broken"] = ctx.at(min(broken)) if broken else None
    out = {"8": RuleResult(kept, s16, terms)}
    if ctx.role in ("give-way", "overtaking"):
        out["16"] = RuleResult(kept, s16, terms)
    if ctx.role == "head-on":
        out["14"] = _rule_14(ctx, m)
    if ctx.role == "give-way":
        ahead, at = course_line_crossings(ctx.pos, ctx.pos_other, ctx.psi_other, np.arange(e.onset, e.release + 1),
                                          with_samples=True)
        at = at[ahead >= 0.0]
        ahead = ahead[ahead >= 0.0]
        p_ahead = 1.0 if ahead.size else 0.0
        kept_15 = not ahead.size and safe
        broken = [k for k in (at[0] if at.size else None, None if safe else _first_below(ctx, window, p.d_safe))
                  if k is not None] or [k_cpa]
        out["15"] = RuleResult(kept_15, max(0.0, s16 - p.w_ahead_15 * p_ahead),
                               {"S16": s16, "P_ahead": p_ahead, "crossed_ahead_at": ahead.tolist(), "cpa": ctx.cpa,
                                "safe_distance": safe, "t_broken": None if kept_15 else ctx.at(int(min(broken)))})
    if ctx.role == "overtaking":
        out["13"] = _rule_13(ctx, s16)
    return out


def _first_below(ctx, window, distance) -> int | None:
    """First sample of ``window`` at which the range is below ``distance``, or None."""
    below = np.flatnonzero(ctx.range[window] < distance)
    return int(window[below[0]]) if below.size else None


def _rule_14(ctx, m) -> RuleResult:
    """Rule 14 of a head-on ship with manoeuvre ``m`` (module docstring)."""
    p, k = ctx.profile, ctx.episode.cpa
    alpha, beta = float(ctx.alpha[k]), float(ctx.beta[k])
    p_sts = 1.0 - float(port_to_port_score(alpha, beta))
    p_nsm = 1.0 - float(ramp(m.starboard_deg, 0.0, p.starboard_min_deg))
    kept = m.starboard_deg >= p.starboard_min_deg and m.port_deg < p.starboard_min_deg and alpha < 0.0 and beta < 0.0
    return RuleResult(kept, max(0.0, 1.0 - p.w_sts * p_sts - p.w_nsm * p_nsm),
                      {"starboard_deg": m.starboard_deg, "port_deg": m.port_deg,
                       "alpha_cpa_deg": float(np.degrees(alpha)), "beta_cpa_deg": float(np.degrees(beta)),
                       "P_sts": p_sts, "P_nsm": p_nsm, "in_doubt": ctx.doubt,
                       "t_broken": None if kept else ctx.at(k)})


def _rule_13(ctx, s16) -> RuleResult:
    """Rule 13 of an overtaking ship whose Rule 16 score is ``s16`` (module docstring)."""
    p, e = ctx.profile, ctx.episode
    span = np.arange(e.onset, ctx.end + 1)
    crossings, at = course_line_crossings(ctx.pos, ctx.pos_other, ctx.psi_other, span, with_samples=True)
    near = np.zeros(crossings.size, dtype=bool) if p.d_ahead is None else (crossings >= 0.0) & (crossings < p.d_ahead)
    ahead, at = crossings[near], at[near]
    alpha = float(np.degrees(ctx.alpha[e.cpa]))
    bow = p.ahead_contact_deg is not None and abs(alpha) < p.ahead_contact_deg
    p_ahead = 1.0 if ahead.size or bow else 0.0
    closest = float(np.min(ctx.range[span]))
    kept = closest >= p.d_safe and not p_ahead
    broken = [k for k in (at[0] if at.size else None, e.cpa if bow else None, _first_below(ctx, span, p.d_safe))
              if k is not None]
    return RuleResult(kept, max(0.0, s16 - p.w_ahead_13 * p_ahead),
                      {"S16": s16, "P_ahead": p_ahead, "crossed_ahead_at": ahead.tolist(), "alpha_cpa_deg": alpha,
                       "closest_until_clear": closest, "t_clear": ctx.at(ctx.end),
                       "t_broken": ctx.at(int(min(broken))) if not kept and broken else None})
