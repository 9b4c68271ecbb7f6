"""Everything the rule checks need about one encounter of an ordered pair (own, other), in one object.

The **baseline** of each ship is the sample whose heading and speed describe her before any action for this
encounter. It is the onset of risk, unless the ship altered course or speed during the ``t_lookback`` before it in
a way that opened the predicted CPA (an avoiding manoeuvre already under way): then it is the sample
``t_lookback`` before the onset. The encounter is classified with the baselines' headings and speeds and the
positions at the onset (:func:`mmg_casadi.colregs.roles.classify_roles`), so a ship already turning for the other
when the risk begins keeps the role she had, and a give-way ship's action is measured from her baseline, so an
alteration made before the onset counts as action. A course change that closed the CPA (a turn onto a new leg that
created the risk) does not move the baseline.

The timing samples of an encounter (:func:`timing`): ``late``, where the give-way ship's ample time ends (the risk
persists at the profile's ``late_*`` trigger, and no earlier than ``late_after_onset`` after the onset);
``apparent``, where the give-way ship's inaction becomes apparent to the stand-on ship (from ``late``, the first
sample with the risk still present by which she has made no readily apparent change of course or speed since her
baseline; policy ``inaction = "late"``: ``late`` itself); ``must``, where the stand-on ship must act (Rule 17(b):
the risk persists with a straight-line CPA below ``must_cpa`` at the ``must_*`` trigger). A give-way ship's own
clearance (:func:`own_clearance`) is how far her track passed from the other ship's track had that ship held her
course and speed from her baseline.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import math

from mmg_casadi.colregs.geometry import bearing, wrap_to_pi
from mmg_casadi.colregs.kinematics import ground_velocity, pair_geometry
from mmg_casadi.colregs.risk import RiskEpisode, first_trigger, release_range, risk_episodes, risk_of_collision
from mmg_casadi.colregs.roles import classify_role, head_on_scalar
from mmg_casadi.colregs.score import cpa_tcpa

#: a counterfactual CPA must be this much smaller (L) for a pre-onset change to count as an avoiding manoeuvre
CPA_TOLERANCE = 1e-6


@dataclass(frozen=True)
class EncounterContext:
    """Arrays and sample indices of one encounter, as seen from the own ship.

    Parameters
    ----------
    t : numpy.ndarray (T,)
        Sample times (L/U).
    pos, psi, speed : numpy.ndarray
        Own positions (T, 2), headings (T,) and speeds over the ground (T,).
    pos_other, psi_other, speed_other : numpy.ndarray
        The other ship's positions (T, 2), headings (T,) and speeds over the ground (T,).
    range, beta, alpha, cpa_pred, tcpa_pred : numpy.ndarray (T,)
        Relative geometry (:class:`~mmg_casadi.colregs.kinematics.PairGeometry`).
    risk : numpy.ndarray of bool (T,)
        The Rule 7 gate.
    episode : RiskEpisode
        Onset, CPA and release samples.
    base, base_other : int
        Baseline samples of the own and the other ship (module docstring).
    end : int
        Last sample of the encounter's aftermath (before the next encounter of the pair or the end), for Rule 13.
    late, must : int or None
        Samples where the give-way ship's ample time ends and where the stand-on ship must act (:func:`timing`).
    apparent : int or None
        Sample where the give-way ship's inaction becomes apparent to the stand-on ship (:func:`timing`).
    clearance : float or None
        For a give-way or overtaking own ship, the clearance her own action gives (:func:`own_clearance`, L).
    doubt : bool
        Head-on only by Rule 14(c) (:func:`~mmg_casadi.colregs.roles.in_doubt`), not by ``head_on_deg``.
    role : str
        The own ship's role (:data:`~mmg_casadi.colregs.roles.ROLES`).
    bearing, contact : float
        β and α the role was classified with: positions at the onset, headings at the baselines (rad).
    speed_ref, speed_max : float
        Own speed reference for reductions (the highest from baseline to onset) and the highest speed she sailed
        before the onset (only speed above it is an increase).
    profile : ScoringProfile
        Thresholds.

    Examples
    --------
    The paper's crossing, both ships holding course (:func:`first_encounter`):

    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> t = np.arange(0.0, 40.0, 0.25)
    >>> ctx = first_encounter(t, np.column_stack([t, 0 * t]), 0 * t, np.column_stack([25 + 0 * t, 25 - t]),
    ...                       -np.pi / 2 + 0 * t, iitm_lab())
    >>> ctx.role, ctx.at(ctx.episode.onset), ctx.at(ctx.late), ctx.at(ctx.must), ctx.cpa
    ('give-way', 14.5, 21.0, 23.0, 0.0)
    """

    t: np.ndarray
    pos: np.ndarray
    psi: np.ndarray
    speed: np.ndarray
    pos_other: np.ndarray
    psi_other: np.ndarray
    speed_other: np.ndarray
    range: np.ndarray
    beta: np.ndarray
    alpha: np.ndarray
    cpa_pred: np.ndarray
    tcpa_pred: np.ndarray
    risk: np.ndarray
    episode: RiskEpisode
    base: int
    base_other: int
    end: int
    late: int | None
    must: int | None
    role: str
    bearing: float
    contact: float
    speed_ref: float
    speed_max: float
    profile: object
    apparent: int | None = None
    clearance: float | None = None
    doubt: bool = False

    @property
    def cpa(self) -> float:
        """The actual CPA (L): the smallest range from onset to release."""
        return float(self.range[self.episode.cpa])

    def at(self, k) -> float | None:
        """The time of sample ``k`` (``None`` for ``None``).

        Parameters
        ----------
        k : int or None
            Sample index.

        Returns
        -------
        float or None
            ``t[k]`` (L/U), or None.
        """
        return None if k is None else float(self.t[k])


def baselines(t, onset, run_start, pos, vel, pos_other, vel_other, t_lookback) -> tuple[int, int]:
    """Baseline samples of the own and the other ship (module docstring).

    Parameters
    ----------
    t : array-like (T,)
        Sample times.
    onset : int
        Onset of risk.
    run_start : int
        First sample of the stretch, ending at the onset, in which both ships sail.
    pos, pos_other : array-like (T, 2)
        Positions.
    vel, vel_other : array-like (T, 2)
        Velocities over the ground.
    t_lookback : float
        Look-back time (L/U).

    Returns
    -------
    base : int
        The own ship's baseline sample: the look-back sample if the own ship's velocity then gave a CPA smaller
        by more than the tolerance, else the onset.
    base_other : int
        The other ship's baseline sample, by the same test.

    Examples
    --------
    The own ship turned away during the look-back (the CPA opened), the other held her course:

    >>> t = np.arange(6.0)
    >>> vel = np.array([[1.0, 0.0]] * 3 + [[0.9, 0.4]] * 3); vel_o = np.tile([-1.0, 0.0], (6, 1))
    >>> baselines(t, 5, 0, np.zeros((6, 2)), vel, np.tile([20.0, 0.5], (6, 1)), vel_o, 4.0)
    (1, 5)
    """
    t = np.asarray(t, dtype=float)
    look = max(int(np.searchsorted(t, t[onset] - t_lookback - 1e-9)), run_start)
    rx, ry = (float(pos_other[onset][k]) - float(pos[onset][k]) for k in (0, 1))
    v, vo, v_look, vo_look = (tuple(float(x) for x in a[k]) for a, k in ((vel, onset), (vel_other, onset),
                                                                         (vel, look), (vel_other, look)))
    now = _cpa(rx, ry, vo[0] - v[0], vo[1] - v[1])
    own_before = _cpa(rx, ry, vo[0] - v_look[0], vo[1] - v_look[1])
    other_before = _cpa(rx, ry, vo_look[0] - v[0], vo_look[1] - v[1])
    return (look if own_before < now - CPA_TOLERANCE else onset,
            look if other_before < now - CPA_TOLERANCE else onset)


def _cpa(rx: float, ry: float, vx: float, vy: float) -> float:
    """:func:`~mmg_casadi.colregs.score.cpa_tcpa`'s CPA of one relative position and velocity, in scalar
    arithmetic with the same operations (the same result to the bit)."""
    vv = vx * vx + vy * vy
    ahead = 0.0
    if vv > 1e-12:
        tcpa = -(rx * vx + ry * vy) / vv
        if math.isfinite(tcpa) and tcpa > 0.0:
            ahead = tcpa
    x, y = rx + vx * ahead, ry + vy * ahead
    return math.sqrt(x * x + y * y)


def timing(t, geometry, risk, episode, psi_other, speed_other, base_other, profile) -> dict:
    """The samples ``late``, ``apparent`` and ``must`` of an encounter (module docstring); ``None`` where one never
    comes before the CPA.

    Parameters
    ----------
    t : numpy.ndarray (T,)
        Sample times (L/U).
    geometry : PairGeometry
        Relative geometry of (own, other).
    risk : numpy.ndarray of bool (T,)
        The Rule 7 gate.
    episode : RiskEpisode
        The encounter's samples.
    psi_other, speed_other : numpy.ndarray (T,)
        The other ship's headings (rad) and speeds over the ground.
    base_other : int
        The other ship's baseline sample.
    profile : ScoringProfile
        ``late_*``, ``late_after_onset``, ``inaction``, ``must_*``, ``must_distance`` and the apparent thresholds.

    Returns
    -------
    dict
        ``late``, ``apparent``, ``must`` (int or None).

    Examples
    --------
    Closing at unit speed from 30 L on a collision course, risk throughout; the other ship holds her course (her
    inaction is apparent at ``late``, 16.1 L under ``published``), then the same with the other ship turning 40°
    from range 25 L:

    >>> from mmg_casadi.colregs.profiles import published
    >>> from mmg_casadi.colregs.kinematics import PairGeometry
    >>> t = np.arange(0.0, 30.0, 0.5); r = 30.0 - t
    >>> g = PairGeometry(r, 0 * t, 0 * t, 0 * t, r)
    >>> held = timing(t, g, np.ones(t.size, bool), RiskEpisode(0, t.size - 1, t.size - 1), 0 * t, 1 + 0 * t, 0,
    ...               published())
    >>> float(t[held["late"]]), float(t[held["apparent"]]), round(float(t[held["must"]]), 1)
    (14.0, 14.0, 27.0)
    >>> turned = timing(t, g, np.ones(t.size, bool), RiskEpisode(0, t.size - 1, t.size - 1),
    ...                 np.radians(np.clip(4.0 * (t - 5.0), 0.0, 40.0)), 1 + 0 * t, 0, published())
    >>> float(t[turned["late"]]), turned["apparent"]
    (14.0, None)
    """
    p, e, g = profile, episode, geometry
    late = first_trigger(risk, g.tcpa, g.range, e.onset, e.cpa, p.late_tcpa, p.late_range)
    if late is not None and t[late] < t[e.onset] + p.late_after_onset - 1e-9:  # time to react to a new risk
        late = _first(risk, int(np.searchsorted(t, t[e.onset] + p.late_after_onset - 1e-9)), e.cpa)
    must = first_trigger(risk & (g.cpa < p.must_distance), g.tcpa, g.range, e.onset, e.cpa, p.must_tcpa,
                         p.must_range)
    apparent = late
    if late is not None and p.inaction == "no-action":
        # the largest change of the other ship's course and speed since her baseline, at every sample up to the CPA
        since = np.arange(min(base_other, late), e.cpa + 1)
        course = np.degrees(np.abs(wrap_to_pi(np.asarray(psi_other, dtype=float)[since] - psi_other[base_other])))
        ref = float(speed_other[base_other])
        slowed = (1.0 - np.asarray(speed_other, dtype=float)[since] / ref) if ref > 0.0 else np.zeros(since.size)
        acted = np.maximum.accumulate((course >= p.course_apparent_deg) | (slowed >= p.speed_apparent))
        later = since >= late
        inactive = ~acted[later] & risk[since[later]]
        apparent = int(since[later][np.argmax(inactive)]) if inactive.any() else None
    return {"late": late, "apparent": apparent, "must": must}


def _first(mask, start, stop) -> int | None:
    """First sample in ``[start, stop]`` where ``mask`` holds, or None."""
    hits = np.flatnonzero(np.asarray(mask, dtype=bool)[start:stop + 1])
    return int(start + hits[0]) if hits.size else None


def own_clearance(t, pos, pos_other, vel_other, base_other, window) -> float:
    """How far the own track passed from the other ship's track had she held her course and speed from her
    baseline: ``min_k |p_own(k) − p_other(b) − v_other(b)·(t_k − t_b)|`` over ``window`` (L).

    Rule 8(d) asks the give-way ship's own action to result in passing at a safe distance (Cockcroft & Lameijer,
    p. 72: the requirement binds her, not the stand-on ship's action under Rule 17); a clearance produced by the
    other ship's manoeuvre is not hers.

    Parameters
    ----------
    t : numpy.ndarray (T,)
        Sample times (L/U).
    pos, pos_other : numpy.ndarray (T, 2)
        Positions of the own and the other ship (L).
    vel_other : numpy.ndarray (T, 2)
        The other ship's velocities over the ground.
    base_other : int
        The other ship's baseline sample.
    window : array-like of int
        Samples to measure (onset to release).

    Returns
    -------
    float
        The clearance (L).

    Examples
    --------
    The other ship turns away and the own ship holds her course: they pass 5 L apart, but the own action alone
    would have passed through her:

    >>> t = np.arange(0.0, 20.0); own = np.column_stack([t, 0 * t])
    >>> other = np.column_stack([10 + 0 * t, np.where(t < 5, 10 - t, 5.0)])
    >>> vel = np.tile([0.0, -1.0], (t.size, 1))
    >>> own_clearance(t, own, other, vel, 0, np.arange(t.size))
    0.0
    """
    window = np.asarray(window, dtype=int)
    held = pos_other[base_other] + np.outer(t[window] - t[base_other], vel_other[base_other])
    return float(np.min(np.linalg.norm(pos[window] - held, axis=1)))


def encounter_context(t, own, other, geometry, risk, episode, run_start, end, profile) -> EncounterContext:
    """Build the :class:`EncounterContext` of one encounter.

    Parameters
    ----------
    t : numpy.ndarray (T,)
        Sample times.
    own, other : dict
        Per ship ``pos`` (T, 2), ``psi`` (T,), ``vel`` (T, 2), ``speed`` (T,) and ``active`` (T,) arrays.
    geometry : PairGeometry
        Relative geometry of (own, other) at every sample.
    risk : numpy.ndarray of bool (T,)
        The Rule 7 gate.
    episode : RiskEpisode
        The encounter's samples.
    run_start : int
        First sample of the both-sailing stretch that contains the onset.
    end : int
        Last sample of the aftermath (Rule 13).
    profile : ScoringProfile
        Thresholds.

    Returns
    -------
    EncounterContext
        The encounter's series, baselines, role, late and must-act samples and profile.

    Examples
    --------
    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> t = np.arange(0.0, 40.0, 0.25)
    >>> ships = [{"pos": p, "psi": np.full(t.size, h), "vel": ground_velocity(t, p), "speed": np.ones(t.size),
    ...           "active": np.ones(t.size, bool)}
    ...          for p, h in ((np.column_stack([t, 0 * t]), 0.0), (np.column_stack([50 - t, 0 * t + 1]), np.pi))]
    >>> g = pair_geometry(ships[0]["pos"], ships[0]["psi"], ships[1]["pos"], ships[1]["psi"], ships[0]["vel"],
    ...                   ships[1]["vel"])
    >>> risk = risk_of_collision(g.cpa, g.tcpa, g.range, True, iitm_lab())
    >>> episode = risk_episodes(g.range, g.tcpa, risk, np.ones(t.size, bool), 15.0)[0]
    >>> encounter_context(t, ships[0], ships[1], g, risk, episode, 0, t.size - 1, iitm_lab()).role
    'head-on'
    """
    k0 = episode.onset
    base, base_other = baselines(t, k0, run_start, own["pos"], own["vel"], other["pos"], other["vel"],
                                 profile.t_lookback)
    psi_own, psi_other = float(own["psi"][base]), float(other["psi"][base_other])
    beta = bearing(own["pos"][k0], psi_own, other["pos"][k0])
    alpha = bearing(other["pos"][k0], psi_other, own["pos"][k0])
    role = classify_role(beta, alpha, psi_own, psi_other, float(own["speed"][base]),
                         float(other["speed"][base_other]), profile)
    doubt = role == "head-on" and not head_on_scalar(beta, alpha, psi_own, psi_other, profile, doubt=False)
    before = np.flatnonzero(own["active"][:k0 + 1])
    g = geometry
    times = timing(t, g, risk, episode, other["psi"], other["speed"], base_other, profile)
    clearance = None
    if profile.own_clearance and role in ("give-way", "overtaking"):
        clearance = own_clearance(t, own["pos"], other["pos"], other["vel"], base_other,
                                  np.arange(k0, episode.release + 1))
    return EncounterContext(
        t=t, pos=own["pos"], psi=own["psi"], speed=own["speed"], pos_other=other["pos"], psi_other=other["psi"],
        speed_other=other["speed"],
        range=g.range, beta=g.beta, alpha=g.alpha, cpa_pred=g.cpa, tcpa_pred=g.tcpa, risk=risk, episode=episode,
        base=base, base_other=base_other, end=end, late=times["late"], must=times["must"], role=role,
        bearing=float(beta), contact=float(alpha),
        speed_ref=float(np.max(own["speed"][base:k0 + 1])), speed_max=float(np.max(own["speed"][before])),
        profile=profile, apparent=times["apparent"], clearance=clearance, doubt=doubt)


def first_encounter(t, pos_own, psi_own, pos_other, psi_other, profile) -> EncounterContext | None:
    """The first encounter of (own, other) sailing throughout, speeds over the ground from the positions; ``None``
    without a risk of collision. A shortcut for examples and checks; :func:`mmg_casadi.colregs.scorer.score_encounters`
    scores every encounter of every pair.

    Parameters
    ----------
    t : array-like (T,)
        Sample times (L/U).
    pos_own, pos_other : array-like (T, 2)
        Positions (L).
    psi_own, psi_other : array-like (T,)
        Headings (rad).
    profile : ScoringProfile
        Thresholds.

    Returns
    -------
    EncounterContext or None
        The context of the first risk episode, or None without one.

    Examples
    --------
    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> t = np.arange(0.0, 40.0, 0.25)
    >>> first_encounter(t, np.column_stack([t, 0 * t]), 0 * t, np.column_stack([t, 0 * t + 5]), 0 * t, iitm_lab())
    """
    t = np.asarray(t, dtype=float)
    ships = []
    for pos, psi in ((pos_own, psi_own), (pos_other, psi_other)):
        pos = np.asarray(pos, dtype=float)
        vel = ground_velocity(t, pos)
        ships.append({"pos": pos, "psi": np.asarray(psi, dtype=float), "vel": vel,
                      "speed": np.hypot(vel[:, 0], vel[:, 1]), "active": np.ones(t.size, dtype=bool)})
    g = pair_geometry(ships[0]["pos"], ships[0]["psi"], ships[1]["pos"], ships[1]["psi"], ships[0]["vel"],
                      ships[1]["vel"])
    both = np.ones(t.size, dtype=bool)
    risk = risk_of_collision(g.cpa, g.tcpa, g.range, both, profile)
    episodes = risk_episodes(g.range, g.tcpa, risk, both, release_range(profile))
    if not episodes:
        return None
    end = episodes[1].onset - 1 if len(episodes) > 1 else t.size - 1
    return encounter_context(t, ships[0], ships[1], g, risk, episodes[0], 0, end, profile)
