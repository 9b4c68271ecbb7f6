"""Hand-labelled COLREG encounters at full scale: the verdicts a mariner gives, each with the rule text that decides
it, and how far each scoring profile agrees with them.

Every case is two or three KCS-sized ships (L = 230 m, 24 kn; 1 nautical mile = 8.05 L, 60 s = 3.2 L/U) that sail
scripted waypoints with the method ``none`` in the closed loop, so the waypoints script every manoeuvre. The
labels give, per ordered pair (own, other), the own ship's role and her verdict on every rule that applies
(:data:`~mmg_casadi.colregs.verdict.RULES`), or ``"n/a"`` where no risk of collision arises. They are a mariner's
reading of the rule texts (COLREG 1972 as amended) with the published readings of what the texts leave open, as
:func:`~mmg_casadi.colregs.profiles.published` cites them: a change of course is readily apparent from 30° and
detectable from 2° (Woerner et al. 2019; Hagen et al. 2023); close quarters, which a safe passing avoids, begins at
about 1 nautical mile between ships in sight, and a give-way ship that has not acted by about 2 nautical miles has
waited too long (Cockcroft & Lameijer pp. 52, 108). Each case also carries the sentence of the rules that decides it.

:func:`agreement` scores every case under a profile and counts the labelled verdicts it reproduces; the test suite
asserts that the published profile agrees with every case, and ``mmg-casadi study labelled`` reports the count
under every profile.

Examples
--------
>>> sorted(CASES)[:3]
['crossing_ahead', 'crossing_both_hold', 'crossing_give_way_early']
>>> CASES["stand_on_drifts"].point
'stand-on course keeping'
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mmg_casadi.colregs.scorer import score_encounters

N_A = "n/a"
"""The label of a pair without a risk of collision: no rule applies."""


@dataclass(frozen=True)
class Case:
    """One labelled encounter.

    Parameters
    ----------
    ships : tuple of dict
        The ships as scenario-file tables (name, start, heading, speed, waypoints; method ``none``).
    labels : dict
        ``{(own, other): "n/a" or (role, {rule: kept})}`` for every ordered pair.
    rule : str
        The rule text that decides the case.
    point : str
        What the case tests (one of the loose spots a profile may have, or a basic verdict).
    t_max : float
        Length of the run (L/U).
    """

    ships: tuple
    labels: dict
    rule: str
    point: str
    t_max: float = 110.0


def _ship(name, start, heading, waypoints, speed=1.0) -> dict:
    return {"name": name, "start": list(start), "heading": float(heading), "speed": float(speed),
            "waypoints": [list(w) for w in waypoints], "method": "none"}


def _own(waypoints) -> dict:
    return _ship("own", (0.0, 0.0), 0.0, waypoints)


#: the target of a crossing from starboard: meets the own ship's straight track at (50, 0) at t = 50
CROSSING = _ship("tgt", (50.0, 50.0), -90.0, [(50.0, -50.0)])
#: the target of a head-on meeting, 0.5 L to starboard of the own ship's track
HEAD_ON = _ship("tgt", (100.0, 0.5), 180.0, [(0.0, 0.5)])
#: the own ship's lawful give-way alteration in the crossing: 60° to starboard at 28 L (3.5 nm), astern of the target
GIVE_WAY = [(30.0, 0.0), (50.0, 35.0), (100.0, 35.0)]
#: a slow ship 20 L ahead of the own ship's track, 0.3 L to starboard
SLOW = _ship("tgt", (20.0, 0.3), 0.0, [(150.0, 0.3)], 0.5)

GW_KEPT = {"8": True, "16": True, "15": True}
GW_HELD = {"8": False, "16": False, "15": False}
SO_KEPT = {"17a_i": True, "8": True}

CASES: dict[str, Case] = {
    "head_on_both_starboard": Case(
        (_own([(30.0, 0.0), (45.0, 10.0), (100.0, 10.0)]),
         _ship("tgt", (100.0, 0.5), 180.0, [(70.0, 0.5), (55.0, -9.5), (0.0, -9.5)])),
        {("own", "tgt"): ("head-on", {"8": True, "14": True}), ("tgt", "own"): ("head-on", {"8": True, "14": True})},
        "Rule 14(a): each shall alter her course to starboard so that each shall pass on the port side of the other",
        "basic"),
    "head_on_both_hold": Case(
        (_own([(100.0, 0.0)]), HEAD_ON),
        {("own", "tgt"): ("head-on", {"8": False, "14": False}),
         ("tgt", "own"): ("head-on", {"8": False, "14": False})},
        "Rule 14(a): each shall alter her course to starboard; Rule 8(a): action in ample time", "basic"),
    "crossing_give_way_early": Case(
        (_own(GIVE_WAY), CROSSING),
        {("own", "tgt"): ("give-way", GW_KEPT), ("tgt", "own"): ("stand-on", SO_KEPT)},
        "Rule 16: take early and substantial action to keep well clear; Rule 15: avoid crossing ahead", "basic"),
    "crossing_both_hold": Case(
        (_own([(100.0, 0.0)]), CROSSING),
        {("own", "tgt"): ("give-way", GW_HELD),
         ("tgt", "own"): ("stand-on", {"17a_i": True, "17b": False, "8": True})},
        "Rule 17(b): when she finds herself so close that collision cannot be avoided by the action of the give-way "
        "vessel alone, she shall take such action as will best aid to avoid collision", "basic"),
    "crossing_give_way_late": Case(
        (_own([(40.0, 0.0), (55.0, 26.0), (100.0, 26.0)]), CROSSING),
        {("own", "tgt"): ("give-way", GW_HELD), ("tgt", "own"): ("stand-on", SO_KEPT)},
        "Rule 8(a): action shall be taken in ample time; a give-way ship that has not acted by about 2 nautical "
        "miles in a crossing has waited too long (Cockcroft & Lameijer p. 108): she alters 60° at 14 L, 1.7 nm",
        "ample time"),
    "crossing_not_apparent": Case(
        (_own([(30.0, 0.0), (100.0, 18.8)]), CROSSING),
        {("own", "tgt"): ("give-way", GW_HELD),
         ("tgt", "own"): ("stand-on", {"17a_i": True, "17b": False, "8": True})},
        "Rule 8(b): any alteration of course shall be large enough to be readily apparent to another vessel; "
        "alterations under 30° are not (Woerner et al.; Hagen et al.): she alters 20°, in ample time",
        "readily apparent"),
    "crossing_too_close": Case(
        (_own([(37.0, 0.0), (100.0, 36.4)]), CROSSING),
        {("own", "tgt"): ("give-way", GW_HELD), ("tgt", "own"): ("stand-on", SO_KEPT)},
        "Rule 8(d): action shall be such as to result in passing at a safe distance; close quarters begins at about "
        "1 nautical mile for ships in sight (Cockcroft & Lameijer p. 52): she alters 30° in ample time and passes "
        "at 0.65 nm", "safe passing distance"),
    "overtaking_keeps_clear": Case(
        (_own([(17.0, 0.0), (30.0, -11.0), (95.0, -11.0), (115.0, 0.3), (180.0, 0.3)]), SLOW),
        {("own", "tgt"): ("overtaking", {"8": True, "16": True, "13": True}),
         ("tgt", "own"): ("overtaken", SO_KEPT)},
        "Rule 13(a): any vessel overtaking any other shall keep out of the way of the vessel being overtaken",
        "basic", 150.0),
    "overtaking_holds": Case(
        (_own([(150.0, 0.0)]), SLOW),
        {("own", "tgt"): ("overtaking", {"8": False, "16": False, "13": False}),
         ("tgt", "own"): ("overtaken", {"17a_i": True, "17b": False, "8": True})},
        "Rule 13(a): the overtaking vessel shall keep out of the way; Rule 17(b)", "basic", 150.0),
    "overtaking_cuts_ahead": Case(
        (_own([(17.0, 0.0), (30.0, -11.0), (62.0, -11.0), (68.0, 0.3), (180.0, 0.3)]), SLOW),
        {("own", "tgt"): ("overtaking", {"8": False, "16": False, "13": False}),
         ("tgt", "own"): ("overtaken", SO_KEPT)},
        "Rule 13(d): any subsequent alteration of the bearing shall not make the overtaking vessel a crossing vessel "
        "or relieve her of the duty of keeping clear until she is finally past and clear: she passes 10.7 L abeam, "
        "then crosses the overtaken ship's bow 5 L (0.6 nm) ahead", "past and clear", 150.0),
    "wide_pass": Case(
        (_own([(100.0, 0.0)]), _ship("tgt", (100.0, 12.0), 180.0, [(0.0, 12.0)])),
        {("own", "tgt"): N_A, ("tgt", "own"): N_A},
        "Rule 7: no risk of collision, the ships pass 12 L (1.5 nm) apart on their courses; no rule applies",
        "basic"),
    "crossing_ahead": Case(
        (_own([(30.0, 0.0), (55.0, -43.0), (100.0, -43.0)]), CROSSING),
        {("own", "tgt"): ("give-way", {"8": True, "16": True, "15": False}), ("tgt", "own"): ("stand-on", SO_KEPT)},
        "Rule 15: the vessel which has the other on her own starboard side shall keep out of the way and shall, if "
        "the circumstances of the case admit, avoid crossing ahead of the other vessel", "basic"),
    "stand_on_drifts": Case(
        (_own(GIVE_WAY), _ship("tgt", (50.0, 50.0), -90.0, [(50.0, 15.0), (56.8, -50.0)])),
        {("own", "tgt"): ("give-way", GW_KEPT),
         ("tgt", "own"): ("stand-on", {"17a_i": False, "17a_ii": False, "17c": True, "8": False})},
        "Rule 17(a)(i): the other shall keep her course and speed; a course change from 2° is detectable "
        "(Woerner et al.; Hagen et al.): she drifts 6° to starboard while the give-way ship acts; Rule 8(b): as an "
        "action it is not readily apparent", "stand-on course keeping"),
    "give_way_clearance_not_hers": Case(
        (_own([(34.0, 0.0), (100.0, 38.1)]), _ship("tgt", (50.0, 50.0), -90.0, [(50.0, 17.0), (70.0, -17.6),
                                                                                (70.0, -50.0)])),
        {("own", "tgt"): ("give-way", GW_HELD),
         ("tgt", "own"): ("stand-on", {"17a_i": False, "17a_ii": False, "17c": True, "8": True})},
        "Rule 8(d) (and Cockcroft & Lameijer p. 72: it binds the give-way ship): action shall be such as to result "
        "in passing at a safe distance; her 30° alteration alone passes 6.3 L from the stand-on ship's track, and "
        "the 11.8 L they pass at comes from the stand-on ship's early turn, which breaks Rule 17(a)(i)",
        "own clearance"),
    "stand_on_acts_while_give_way_acts": Case(
        (_own([(36.0, 0.0), (50.0, 24.0), (100.0, 24.0)]), _ship("tgt", (50.0, 50.0), -90.0, [(50.0, 10.0),
                                                                                             (58.0, 0.0),
                                                                                             (58.0, -50.0)])),
        {("own", "tgt"): ("give-way", GW_KEPT),
         ("tgt", "own"): ("stand-on", {"17a_i": False, "17a_ii": False, "17c": True, "8": True})},
        "Rule 17(a)(ii): the stand-on vessel may take action as soon as it becomes apparent to her that the vessel "
        "required to keep out of the way is not taking appropriate action: the give-way ship's readily apparent "
        "turn is under way when the stand-on ship turns, after the give-way ship's ample time", "17(a)(ii)"),
    "stand_on_port_turn": Case(
        (_own([(100.0, 0.0)]), _ship("tgt", (50.0, 50.0), -90.0, [(50.0, 9.0), (20.0, -20.0)])),
        {("own", "tgt"): ("give-way", GW_HELD),
         ("tgt", "own"): ("stand-on", {"17a_i": True, "17a_ii": True, "17c": False, "8": True})},
        "Rule 17(c): a vessel which takes action in accordance with (a)(ii) shall, if the circumstances of the case "
        "admit, not alter course to port for a vessel on her own port side: her port turn swings the give-way ship "
        "from her port bow onto her starboard side", "17(c)"),
    "head_on_in_doubt": Case(
        (_own([(100.0, 0.0)]), _ship("tgt", (60.87, -19.78), 144.0, [(48.73, -10.96), (24.04, -14.87),
                                                                        (-24.5, 20.4)])),
        {("own", "tgt"): ("head-on", {"8": False, "14": False}), ("tgt", "own"): ("head-on", {"8": True, "14": True})},
        "Rule 14(c): when a vessel is in any doubt as to whether such a situation exists she shall assume that it "
        "does exist and act accordingly: each sees the other 18° on her bow on a collision course; the own ship "
        "holds on as if she were the stand-on ship of a crossing", "14(c)"),
    "route_turn_before_horizon": Case(
        (_own([(100.0, 0.0)]), _ship("tgt", (50.0, 50.0), -90.0, [(50.0, 30.0), (90.0, 10.0), (150.0, 10.0)])),
        {("own", "tgt"): N_A, ("tgt", "own"): N_A},
        "Rule 7: the target's route turns away 50 L/U (15 min) before the meeting and never brings them within "
        "23 L; a straight-line prediction that far ahead is no risk of collision (a 420 s horizon, Krasowski & "
        "Althoff)", "TCPA horizon"),
    "excuse_port_turn": Case(
        (_own([(30.0, 0.0), (60.0, -21.0), (100.0, -21.0)]), _ship("A", (50.0, 50.0), -90.0, [(50.0, -50.0)]),
         _ship("B", (54.5, -50.0), 90.0, [(54.5, 60.0)])),
        {("own", "A"): ("give-way", GW_HELD),
         ("own", "B"): ("stand-on", {"17a_i": False, "17a_ii": False, "17c": False, "8": True}),
         ("A", "own"): ("stand-on", SO_KEPT), ("A", "B"): ("head-on", {"8": False, "14": False}),
         ("B", "own"): ("give-way", GW_HELD), ("B", "A"): ("head-on", {"8": False, "14": False})},
        "Rule 17(a)(i) towards B, whom she must stand on for: her duty to give way to A (crossing from starboard) "
        "asks for a starboard turn (Rule 15: avoid crossing ahead), so her 35° port turn is not forced by it; it is "
        "also a port turn for a ship on her port side (17(c)); towards A she passes at 7.3 L, under 1 nm "
        "(Rule 8(d))", "multi-ship excuse"),
}
"""Every labelled case, by name."""


def simulate_case(case: Case):
    """The closed-loop run of a case: times, positions, headings, sailing flags and names.

    Parameters
    ----------
    case : Case
        The case.

    Returns
    -------
    tuple
        ``t`` (T,), ``pos`` (T, N, 2), ``psi`` (T, N), ``active`` (T, N) and the ship names.
    """
    from mmg_casadi.closed_loop.problem import build_problem
    from mmg_casadi.closed_loop.simulation import simulate
    from mmg_casadi.scenarios.scenario import scenario_from_dict

    d = {"settings": {"method": "none", "t_max": case.t_max, "goal_tolerance": 1.0}, "ships": list(case.ships)}
    problem = build_problem(scenario_from_dict(d))
    tr = simulate(problem.layout, problem.x0, problem.p)
    n = len(case.ships)
    pos = np.stack([np.column_stack([tr.state("x", i), tr.state("y", i)]) for i in range(n)], axis=1)
    return tr.t, pos, tr.state("psi"), tr.sailing_mask(), [s["name"] for s in case.ships]


def outcomes(track, profile) -> dict:
    """``{(own, other): "n/a" or (role, {rule: kept})}`` of a simulated case under ``profile`` (the first encounter
    of each pair; an unfinished one counts as ``"unfinished"``).

    Parameters
    ----------
    track : tuple
        :func:`simulate_case`'s output.
    profile : str or ScoringProfile
        The scoring profile.

    Returns
    -------
    dict
        The outcome of every ordered pair.
    """
    t, pos, psi, active, names = track
    out = {}
    for e in score_encounters(t, pos, psi, active=active, profile=profile, names=names):
        key = (e.own_name, e.other_name)
        if key in out:
            continue
        out[key] = N_A if not e.applicable else "unfinished" if e.unfinished else (
            e.role, {r: v.verdict for r, v in e.rules.items()})
    return out


def verdicts(labels: dict) -> dict:
    """The labels as ``{(own, other, item): value}``: the role (or ``n/a``) and each rule's verdict.

    Parameters
    ----------
    labels : dict
        A case's labels, or :func:`outcomes`.

    Returns
    -------
    dict
        One entry per labelled verdict; ``item`` is ``"role"`` or a rule key.
    """
    out = {}
    for (own, other), value in labels.items():
        if not isinstance(value, tuple):
            out[(own, other, "role")] = value
            continue
        out[(own, other, "role")] = value[0]
        out.update({(own, other, rule): kept for rule, kept in value[1].items()})
    return out


def agreement(profile, tracks=None) -> dict:
    """How many labelled verdicts of every case ``profile`` reproduces.

    Parameters
    ----------
    profile : str or ScoringProfile
        The scoring profile.
    tracks : dict, optional
        ``{name: simulate_case(...)}`` of the cases to judge (default: every case, simulated here).

    Returns
    -------
    dict
        ``{name: (agreed, labelled, disagreements)}``: the verdicts reproduced, those labelled, and the list of
        ``(own, other, item, label, got)`` where they differ (an item a profile gives that the labels do not, or
        the reverse, counts as a disagreement).
    """
    out = {}
    for name in (CASES if tracks is None else tracks):
        track = simulate_case(CASES[name]) if tracks is None else tracks[name]
        want, got = verdicts(CASES[name].labels), verdicts(outcomes(track, profile))
        wrong = [(*k, want.get(k), got.get(k)) for k in sorted(want.keys() | got.keys(), key=str)
                 if want.get(k) != got.get(k)]
        out[name] = (sum(1 for k in want if got.get(k) == want[k]), len(want), wrong)
    return out
