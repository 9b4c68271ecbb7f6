"""COLREG encounter scorer: per ordered ship pair, the encounters with a risk of collision and every rule's verdict
and graded score (numpy, vectorised over the stored trajectory).

:func:`score_encounters` is the entry point. For every ordered pair (own, other):

1. Rule 7 gate (:mod:`mmg_casadi.colregs.risk`): no risk of collision while both sail → one :class:`Encounter`
   with ``applicable = False`` (no rule applies: neither a violation nor a compliance); otherwise one applicable
   :class:`Encounter` per stretch of risk, from its onset to its release;
2. classification at the onset, fixed for the encounter (:mod:`mmg_casadi.colregs.roles`,
   :mod:`mmg_casadi.colregs.context`): type ``head-on``, ``crossing`` or ``overtaking`` and the own ship's role;
3. rules of the role (:mod:`mmg_casadi.colregs.give_way_rules`, :mod:`mmg_casadi.colregs.stand_on_rules`): Rules
   8, 13, 14, 15, 16, 17(a)(i), 17(a)(ii), 17(b), 17(c), each a :class:`~mmg_casadi.colregs.verdict.RuleResult`;
4. several ships (:mod:`mmg_casadi.colregs.duties`): conflicting duties flagged (Rule 2(b)); 17(a)(i) excused
   where a give-way duty to another ship forces the change (policy ``excuse``); an encounter records whether the
   excuse changed its verdict (``excuse_changed``);
5. an encounter that ends before its closest point of approach (:func:`unfinished`: a ship stopped sailing, or the
   run ended, while the range still closed) is ``unfinished``: its rules are not judged, since every rule's verdict
   and score is taken at the actual CPA, which it never reached.

An encounter's ``score`` is the mean of its rules' scores, ``compliant`` whether every applicable rule is kept.
Thresholds: a :class:`~mmg_casadi.colregs.profiles.ScoringProfile` (``published`` by default, ``iitm-lab`` or
``ntnu-2023``).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np

from mmg_casadi.colregs.context import encounter_context
from mmg_casadi.colregs.duties import Duty, conflicts, excused_samples
from mmg_casadi.colregs.geometry import wrap_to_pi
from mmg_casadi.colregs.give_way_rules import give_way_rules
from mmg_casadi.colregs.kinematics import PairGeometry, ground_velocity, pair_geometry
from mmg_casadi.colregs.profiles import scoring_profile
from mmg_casadi.colregs.risk import RiskEpisode, release_range, risk_episodes, risk_of_collision
from mmg_casadi.colregs.roles import ENCOUNTER_OF_ROLE, GIVE_WAY_ROLES, OVERTAKING_ROLES
from mmg_casadi.colregs.stand_on_rules import stand_on_rules
from mmg_casadi.colregs.verdict import RULES, json_value

SCORER_VERSION = 5
"""Version of the verdicts :func:`score_encounters` gives: a statistics table records it and is resumed only by the
same version. 2: a ship's speed at the sample she stops (reaches her goal) is a one-sided difference of her
positions (:func:`~mmg_casadi.colregs.kinematics.ground_velocity` with ``active``); version 1 halved it there, which
counted her arrival as a speed reduction. 3: a crossing of the other ship's course line (Rules 13 and 15) is the own
ship's change of side of the line as it was at the earlier sample
(:func:`~mmg_casadi.colregs.manoeuvre.course_line_crossings`); versions 1 and 2 also counted the other ship's turn
that swept her course line across the own ship as the own ship crossing ahead. 4: an encounter that ends before its
CPA (a ship reaches her goal, or the run ends, while the range still closes) is unfinished and not judged
(:func:`unfinished`); version 3 took the range at its end as the CPA. 5: the profile's policies
(:class:`~mmg_casadi.colregs.profiles.ScoringProfile`): a stand-on ship's change is excused only where a give-way
duty to another ship forces it; she may act alone once the give-way ship's inaction is apparent (no readily apparent
change of hers at or after her ample time), not at the end of that time alone; Rule 17(c) counts every port turn for
a ship on the port side at the onset; a give-way ship's own action must give the safe passing distance; the safety
score includes the pose at the CPA; Rule 14(c)'s doubt band and a reaction time after the onset where a profile
sets them. The policies of version 4 remain selectable for comparison."""


@dataclass(frozen=True)
class Encounter:
    """One encounter of an ordered ship pair, from the own ship's side.

    Parameters
    ----------
    own, other : int
        Ship indices.
    own_name, other_name : str
        Ship names.
    profile : str
        Name of the scoring profile.
    applicable : bool
        Whether a risk of collision existed (otherwise no rule applies and the fields below are empty).
    encounter : str or None
        ``"head-on"``, ``"crossing"`` or ``"overtaking"``.
    role : str or None
        The own ship's role: ``"head-on"``, ``"give-way"``, ``"stand-on"``, ``"overtaking"`` or ``"overtaken"``.
    onset, release, closest : dict or None
        Onset of risk (``t``, ``range``, ``cpa``, ``tcpa``), release (``t``, ``range``) and the actual closest point
        of approach (``t``, ``range``).
    rules : dict
        ``{rule: RuleResult}`` for the rules that apply (keys of :data:`~mmg_casadi.colregs.verdict.RULES`).
    conflicts_with : tuple of str
        Ships towards which the own ship had an open duty of the other kind at the same time (Rule 2(b)).
    quantities : dict
        The classification and timing quantities (bearings, speeds, baseline, ample time, must-act time, ...).
    unfinished : bool
        Whether the encounter ended before its CPA (:func:`unfinished`); then ``rules`` is empty and neither
        ``score`` nor ``compliant`` is given.
    excuse_changed : bool
        Whether a give-way duty to another ship excused a change of this stand-on encounter and so changed a rule's
        verdict (or which rules apply).

    Examples
    --------
    >>> e = Encounter(0, 1, "own", "target", "iitm-lab", False)
    >>> e.score, e.compliant, e.to_dict()["applicable"]
    (None, None, False)
    """

    own: int
    other: int
    own_name: str
    other_name: str
    profile: str
    applicable: bool
    encounter: str | None = None
    role: str | None = None
    onset: dict | None = None
    release: dict | None = None
    closest: dict | None = None
    rules: dict = field(default_factory=dict)
    conflicts_with: tuple = ()
    quantities: dict = field(default_factory=dict)
    unfinished: bool = False
    excuse_changed: bool = False

    @functools.cached_property
    def score(self) -> float | None:
        """Mean of the applicable rules' scores (``None`` if none applies)."""
        return float(np.mean([r.score for r in self.rules.values()])) if self.rules else None

    @functools.cached_property
    def compliant(self) -> bool | None:
        """Whether every applicable rule is kept (``None`` if none applies)."""
        return all(r.verdict for r in self.rules.values()) if self.rules else None

    @property
    def judged(self) -> bool:
        """Whether the encounter carries verdicts: a risk of collision, and not :func:`unfinished`."""
        return self.applicable and self.compliant is not None

    @property
    def conflicting_duties(self) -> bool:
        """Whether the own ship had conflicting duties during this encounter (Rule 2(b))."""
        return bool(self.conflicts_with)

    def to_dict(self) -> dict:
        """JSON-ready dict for ``metrics.json``: identity, applicable, onset, type, role, per-rule verdict/score
        (``None`` for a rule that does not apply), total score, compliance and the quantities.

        Returns
        -------
        dict
            Keys ``own``, ``other``, ``profile``, ``applicable``, ``unfinished``, ``encounter``, ``role``,
            ``onset``, ``release``, ``closest``, ``score``, ``compliant``, ``conflicting_duties``,
            ``conflicts_with``, ``excuse_changed``, ``rules`` and ``quantities``; NaN and infinities as None.
        """
        return json_value({
            "own": self.own_name, "other": self.other_name, "profile": self.profile, "applicable": self.applicable,
            "unfinished": self.unfinished, "excuse_changed": self.excuse_changed,
            "encounter": self.encounter, "role": self.role, "onset": self.onset, "release": self.release,
            "closest": self.closest, "score": self.score, "compliant": self.compliant,
            "conflicting_duties": self.conflicting_duties, "conflicts_with": list(self.conflicts_with),
            "rules": {r: (self.rules[r].to_dict() if r in self.rules else None) for r in RULES},
            "quantities": self.quantities})


def judged_encounters(encounters) -> list[dict]:
    """The encounters of ``metrics.json`` (:meth:`Encounter.to_dict`) that carry verdicts, as :attr:`Encounter.judged`.

    Parameters
    ----------
    encounters : iterable of dict
        Encounters as stored in ``metrics.json`` (``pairs[].encounters.a`` or ``.b``).

    Returns
    -------
    list of dict
        Those with a risk of collision that are not unfinished, in their order.

    Examples
    --------
    >>> rows = [{"applicable": False, "compliant": None}, {"applicable": True, "compliant": None},
    ...         {"applicable": True, "compliant": False}]
    >>> judged_encounters(rows)
    [{'applicable': True, 'compliant': False}]
    """
    return [e for e in encounters if e["applicable"] and e["compliant"] is not None]


def _as_arrays(t, pos, psi, speed, active):
    """Validated ``t`` (T,), ``pos`` (T, N, 2), ``psi`` (T, N), velocity, ``speed`` (T, N), ``active`` (T, N)."""
    t = np.asarray(t, dtype=float).ravel()
    pos = np.asarray(pos, dtype=float)
    n = pos.shape[1] if pos.ndim == 3 else -1
    if pos.shape != (t.size, n, 2):
        raise ValueError(f"pos: expected shape ({t.size}, N, 2) like t, got {pos.shape}")
    psi = np.asarray(psi, dtype=float)
    active = np.ones((t.size, n), dtype=bool) if active is None else np.asarray(active, dtype=bool)
    _check_shape(t.size, n, psi=psi, active=active)  # active before the velocities, which difference within it
    vel = ground_velocity(t, pos, active)
    speed = np.linalg.norm(vel, axis=2) if speed is None else np.asarray(speed, dtype=float)
    _check_shape(t.size, n, speed=speed)
    return t, pos, psi, vel, speed, active


def _check_shape(samples: int, ships: int, **arrays) -> None:
    """Raise ValueError naming the first of ``arrays`` whose shape is not ``(samples, ships)``."""
    for name, a in arrays.items():
        if a.shape != (samples, ships):
            raise ValueError(f"{name}: expected shape ({samples}, {ships}), got {a.shape}")


def unfinished(episode, both, rng, tcpa, d_safe) -> bool:
    """Whether an encounter ended before its closest point of approach.

    It did when it ends at the last sample of the pair's stretch of sailing (a ship stops there, or the run ends),
    its smallest range is that last one, the straight-line TCPA there is still positive (the range closes) and no
    range below ``d_safe`` was seen. The published schemes take every verdict and score at the actual CPA, which
    such an encounter never reached: its rules are not judged.

    Parameters
    ----------
    episode : RiskEpisode
        The encounter's onset, CPA and release samples.
    both : array-like of bool (T,)
        Whether both ships sail.
    rng, tcpa : array-like (T,)
        Range (L) and straight-line TCPA (L/U).
    d_safe : float
        The profile's safe passing distance (L): an encounter that came closer is judged, whatever its end.

    Returns
    -------
    bool
        True if the encounter is unfinished.

    Examples
    --------
    Closing at unit speed; the other ship reaches her goal at sample 4, 3 L off; then the same with the range
    opening there:

    >>> from mmg_casadi.colregs.risk import RiskEpisode
    >>> r, both = 7.0 - np.arange(6.0), np.arange(6) <= 4
    >>> unfinished(RiskEpisode(1, 4, 4), both, r, r - 1.0, 2.0), unfinished(RiskEpisode(1, 4, 4), both, r, 1 - r, 2.0)
    (True, False)
    """
    k = episode.release
    last = k == len(both) - 1 or not both[k + 1]
    return bool(last and episode.cpa == k and tcpa[k] > 0.0 and rng[k] >= d_safe)


def _until_past_and_clear(episodes, k, geometry, both, distance):
    """Rule 13(d): an overtaking encounter lasts until the overtaking ship is finally past and clear (the range
    opens beyond ``distance``); later stretches of risk of the pair before that belong to it. Returns the index of
    the last episode absorbed and the merged episode."""
    ep = episodes[k]
    while k + 1 < len(episodes):
        after = np.arange(ep.cpa + 1, len(both))
        clear = after[both[after] & (geometry.range[after] > distance) & (geometry.tcpa[after] <= 0.0)]
        if clear.size and episodes[k + 1].onset >= clear[0]:
            break
        k += 1
        span = np.arange(ep.onset, episodes[k].release + 1)
        cpa = int(span[np.argmin(np.where(both[span], geometry.range[span], np.inf))])
        ep = RiskEpisode(ep.onset, cpa, episodes[k].release)
    return k, ep


def _run_start(both, k) -> int:
    """First sample of the stretch of ``both`` that contains sample ``k``."""
    gaps = np.flatnonzero(~both[:k])
    return int(gaps[-1]) + 1 if gaps.size else 0


def _times(ctx) -> tuple[dict, dict, dict]:
    """Onset (time, range, predicted CPA and TCPA), release and actual CPA (time, range) of an encounter."""
    e = ctx.episode
    onset = {"t": ctx.at(e.onset), "range": ctx.range[e.onset], "cpa": ctx.cpa_pred[e.onset],
             "tcpa": ctx.tcpa_pred[e.onset]}
    return (onset, {"t": ctx.at(e.release), "range": ctx.range[e.release]},
            {"t": ctx.at(e.cpa), "range": ctx.range[e.cpa]})


def _quantities(ctx) -> dict:
    """Classification and timing quantities of an encounter (bearings in degrees, times in L/U)."""
    k0 = ctx.episode.onset
    return {"t_baseline": ctx.at(ctx.base), "t_baseline_other": ctx.at(ctx.base_other),
            "beta_deg": float(np.degrees(ctx.bearing)), "alpha_deg": float(np.degrees(ctx.contact)),
            "beta_onset_deg": float(np.degrees(ctx.beta[k0])), "alpha_onset_deg": float(np.degrees(ctx.alpha[k0])),
            "speed": float(ctx.speed[ctx.base]), "speed_other": float(ctx.speed_other[ctx.base_other]),
            "t_late": ctx.at(ctx.late), "t_apparent": ctx.at(ctx.apparent), "t_must": ctx.at(ctx.must),
            "speed_max_before": ctx.speed_max, "own_clearance": ctx.clearance, "head_on_in_doubt": ctx.doubt}


def score_encounters(t, pos, psi, speed=None, active=None, profile=None, *, names=None, own=None) -> list[Encounter]:
    """Every encounter of every ordered ship pair, scored rule by rule (module docstring).

    Parameters
    ----------
    t : array-like (T,)
        Sample times (L/U), increasing.
    pos : array-like (T, N, 2)
        Positions of the N ships (L).
    psi : array-like (T, N)
        Headings (rad, from x towards y; wrapped or continuous).
    speed : array-like (T, N), optional
        Speeds over the ground; default: from the positions.
    active : array-like of bool (T, N), optional
        Whether each ship sails (default: always); a pair is judged only where both sail.
    profile : ScoringProfile or str, optional
        Thresholds or a profile name (default ``"iitm-lab"``).
    names : sequence of str, optional
        Ship names (default ``ship0``, ``ship1``, ...).
    own : int or sequence of int, optional
        Score only the encounters of these own ships (default: all).

    Returns
    -------
    list of Encounter
        Ordered by own ship, other ship and onset.

    Examples
    --------
    The paper's crossing with both ships holding course: the give-way ship fails Rules 8, 15 and 16; the stand-on
    ship keeps her course (17(a)(i)) but does not act when she must (17(b), from 60 s before the CPA). The published
    profile sees the risk from a TCPA of 420 s (t = 2.5), the laboratory's from R_safe = 15 L (t = 14.5).

    >>> t = np.arange(0.0, 40.0, 0.25)
    >>> pos = np.stack([np.column_stack([t, 0 * t]), np.column_stack([25 + 0 * t, 25 - t])], axis=1)
    >>> psi = np.column_stack([0 * t, -np.pi / 2 + 0 * t])
    >>> a, b = score_encounters(t, pos, psi)
    >>> a.role, a.onset["t"], {r: v.verdict for r, v in a.rules.items()}
    ('give-way', 2.5, {'8': False, '16': False, '15': False})
    >>> b.role, {r: (v.verdict, v.terms.get("t_broken")) for r, v in b.rules.items()}
    ('stand-on', {'17a_i': (True, None), '17b': (False, 22.0), '8': (True, None)})
    >>> score_encounters(t, pos, psi, profile="iitm-lab")[0].onset["t"]
    14.5
    """
    return score_prepared(prepare(t, pos, psi, speed, active, own=own), profile, names=names)


@dataclass(frozen=True)
class Prepared:
    """What every profile's scoring of one trajectory shares (:func:`prepare`): the validated arrays, the ships'
    series and the relative geometry of every scored ordered pair.

    Parameters
    ----------
    t : numpy.ndarray (T,)
        Sample times.
    psi, speed, active : numpy.ndarray (T, N)
        Headings, speeds over the ground and sailing flags.
    ships : list of dict
        Per ship ``pos``, ``psi``, ``vel``, ``speed``, ``active``.
    rows : list of int
        The own ships scored.
    geometry : PairGeometry
        Arrays ``(T, len(rows), N)``.
    """

    t: np.ndarray
    psi: np.ndarray
    speed: np.ndarray
    active: np.ndarray
    ships: list
    rows: list
    geometry: PairGeometry


def prepare(t, pos, psi, speed=None, active=None, *, own=None) -> Prepared:
    """The profile-independent part of :func:`score_encounters` (velocities over the ground, the pairs' geometry),
    computed once for scoring one trajectory under several profiles (:func:`score_prepared`).

    Parameters
    ----------
    t, pos, psi, speed, active, own
        As :func:`score_encounters`.

    Returns
    -------
    Prepared
        The arrays every profile's scoring reads.
    """
    t, pos, psi, vel, speed, active = _as_arrays(t, pos, psi, speed, active)
    n = pos.shape[1]
    rows = list(range(n)) if own is None else [int(i) for i in np.atleast_1d(own)]
    if any(not 0 <= i < n for i in rows):
        raise ValueError(f"own: expected ship indices in [0, {n}), got {own}")
    g = pair_geometry(pos[:, rows, None, :], psi[:, rows, None], pos[:, None, :, :], psi[:, None, :],
                      vel[:, rows, None, :], vel[:, None, :, :])
    ships = [{"pos": pos[:, i], "psi": psi[:, i], "vel": vel[:, i], "speed": speed[:, i], "active": active[:, i]}
             for i in range(n)]
    return Prepared(t, psi, speed, active, ships, rows, g)


def score_prepared(prep: Prepared, profile=None, *, names=None, applicable_only: bool = False) -> list[Encounter]:
    """:func:`score_encounters` of a trajectory from :func:`prepare` under ``profile``.

    Parameters
    ----------
    prep : Prepared
        The trajectory's shared arrays.
    profile : ScoringProfile or str, optional
        Thresholds or a profile name (default ``"published"``).
    names : sequence of str, optional
        Ship names (default ``ship0``, ``ship1``, ...).
    applicable_only : bool, default False
        Leave out the pairs without a risk of collision (they carry no verdict).

    Returns
    -------
    list of Encounter
        Ordered by own ship, other ship and onset.
    """
    profile = scoring_profile(profile)
    t, psi, speed, active, ships, g = prep.t, prep.psi, prep.speed, prep.active, prep.ships, prep.geometry
    n = len(ships)
    names = [f"ship{i}" for i in range(n)] if names is None else [str(x) for x in names]
    out = []
    # the Rule 7 gate of every scored pair at once; a pair without a single sample of risk has no encounter
    sailing = active[:, prep.rows, None] & active[:, None, :]
    gate = risk_of_collision(g.cpa, g.tcpa, g.range, sailing, profile)
    any_risk = gate.any(axis=0)
    for row, i in enumerate(prep.rows):
        contexts, plain = [], []
        for j in (j for j in range(n) if j != i):
            both = sailing[:, row, j]
            if not any_risk[row, j]:
                if not applicable_only:
                    plain.append(Encounter(i, j, names[i], names[j], profile.name, False, quantities=json_value({
                        "min_range": float(np.min(g.range[both, row, j])) if both.any() else None})))
                continue
            gij = PairGeometry(*(getattr(g, f)[:, row, j] for f in ("range", "beta", "alpha", "cpa", "tcpa")))
            risk = gate[:, row, j]
            episodes = risk_episodes(gij.range, gij.tcpa, risk, both, release_range(profile))
            if not episodes and not applicable_only:
                plain.append(Encounter(i, j, names[i], names[j], profile.name, False, quantities=json_value({
                    "min_range": float(np.min(gij.range[both])) if both.any() else None})))
            last = int(np.flatnonzero(both)[-1]) if both.any() else 0
            k = 0
            while k < len(episodes):
                ep = episodes[k]
                end = episodes[k + 1].onset - 1 if k + 1 < len(episodes) else last
                ctx = encounter_context(t, ships[i], ships[j], gij, risk, ep, _run_start(both, ep.onset), end, profile)
                if ctx.role in OVERTAKING_ROLES and profile.past_clear is not None:
                    k, ep = _until_past_and_clear(episodes, k, gij, both, profile.past_clear)
                    if ep is not ctx.episode:
                        end = episodes[k + 1].onset - 1 if k + 1 < len(episodes) else last
                        ctx = encounter_context(t, ships[i], ships[j], gij, risk, ep, _run_start(both, ep.onset),
                                                end, profile)
                contexts.append((j, ctx, unfinished(ep, both, gij.range, gij.tcpa, profile.d_safe)))
                k += 1
        duties = [Duty(j, c.role, c.base if c.role in GIVE_WAY_ROLES else c.episode.onset, c.episode.onset,
                       c.episode.release, c.episode.cpa, c.risk) for j, c, _ in contexts]
        clash = conflicts(duties)
        turn = slowing = None
        if profile.excuse == "forced":
            turn = np.concatenate([[0.0], wrap_to_pi(np.diff(psi[:, i]))])
            slowing = np.concatenate([[False], np.diff(speed[:, i]) < 0.0])
        for k, (j, c, cut) in enumerate(contexts):
            rules, changed = {}, False
            if not cut and c.role in GIVE_WAY_ROLES:
                rules = give_way_rules(c)
            elif not cut:
                excused = excused_samples(duties, k, t.size, profile.excuse, turn, slowing)
                rules = stand_on_rules(c, excused)
                if excused.any():
                    unexcused = stand_on_rules(c, np.zeros(t.size, bool))
                    changed = unexcused.keys() != rules.keys() or any(unexcused[r].verdict != v.verdict
                                                                      for r, v in rules.items())
            onset, release, closest = _times(c)
            out.append(Encounter(i, j, names[i], names[j], profile.name, True,
                                 ENCOUNTER_OF_ROLE[c.role], c.role, json_value(onset), json_value(release),
                                 json_value(closest), rules, tuple(names[x] for x in clash[k]),
                                 _quantities(c), cut, changed))
        out.extend(plain)
    return sorted(out, key=lambda e: (e.own, e.other, -1.0 if e.onset is None else e.onset["t"]))
