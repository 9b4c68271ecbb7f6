"""Several ships at once: conflicting duties (Rule 2(b)) and the attribution of a ship's actions to her encounters.

A ship's encounters are the risk episodes she has with every other ship (:mod:`mmg_casadi.colregs.risk`), each
with a role (:mod:`mmg_casadi.colregs.roles`). A **give-way duty** (roles head-on, give-way, overtaking: she must
act) is open from her baseline (where her action for it is counted from) to its release; a **stand-on duty**
(stand-on, overtaken) from its onset to its release.

* **Conflicting duties** (Rule 2(b), departure from the rules to avoid immediate danger): an encounter is flagged
  when another encounter of the same ship with a duty of the other kind is open at the same time: she must keep
  out of the way of one ship and keep her course and speed for another, and cannot do both.
* **Attribution**: a change of course or speed counts for every encounter whose window contains it — a give-way
  ship's alteration is her action towards each ship she gives way to. The exception: a stand-on ship's change is
  attributed to a give-way duty to another ship, and Rule 17(a)(i) of the stand-on encounter excused at that sample,
  only where that duty forces it (policy ``excuse = "forced"``): the duty is **active** (from its start to its
  CPA, with the risk of collision present once it has begun) and the change goes the way the duty requires (a
  head-on or crossing give-way ship turns to starboard, or slows without turning to port; an overtaking ship turns
  either way or slows). A sample at which she changes nothing needs no excuse and gets none. Afterwards she keeps the course and speed she then has
  (:func:`mmg_casadi.colregs.stand_on_rules.moving_reference`). Policy ``"open-duty"`` (scorer version 4) excuses
  every sample at which a give-way duty to another ship is open, whatever the change.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mmg_casadi.colregs.roles import GIVE_WAY_ROLES


@dataclass(frozen=True)
class Duty:
    """One encounter of a ship, as far as her duties go.

    Parameters
    ----------
    other : int
        Index of the other ship.
    role : str
        Her role (:data:`~mmg_casadi.colregs.roles.ROLES`).
    start : int
        First sample of the duty (baseline for a give-way duty, onset for a stand-on duty).
    onset, release : int
        Onset and release of the encounter.
    cpa : int, optional
        Sample of its CPA (default: the release).
    risk : numpy.ndarray of bool (T,), optional
        The Rule 7 gate of the pair (default: throughout).

    Examples
    --------
    >>> Duty(1, "give-way", 4, 6, 20).gives_way, Duty(2, "overtaken", 6, 6, 20).gives_way
    (True, False)
    """

    other: int
    role: str
    start: int
    onset: int
    release: int
    cpa: int | None = None
    risk: np.ndarray | None = None

    @property
    def gives_way(self) -> bool:
        """Whether she must act (head-on, give-way, overtaking)."""
        return self.role in GIVE_WAY_ROLES


def conflicts(duties) -> list[tuple[int, ...]]:
    """Per duty, the other ships towards which she has an open duty of the other kind at the same time (Rule 2(b)).

    Parameters
    ----------
    duties : sequence of Duty
        All encounters of one ship.

    Returns
    -------
    list of tuple of int
        One tuple per duty, in the order of ``duties``: the indices of those other ships, sorted (empty without a
        conflict).

    Examples
    --------
    Give way to ship 1 while standing on for ship 2 (overlapping), and a later, separate stand-on for ship 3:

    >>> d = [Duty(1, "give-way", 10, 12, 30), Duty(2, "stand-on", 15, 15, 35), Duty(3, "stand-on", 50, 50, 60)]
    >>> conflicts(d)
    [(2,), (1,), ()]
    """
    out = []
    for d in duties:
        out.append(tuple(sorted({o.other for o in duties if o.gives_way != d.gives_way and o.other != d.other
                                 and o.onset <= d.release and d.onset <= o.release})))
    return out


TURNING = 1e-4
"""A change of heading between two samples below this (rad) is no turn: the excuse needs a turn (or slowing)."""


def excused_samples(duties, index, n_samples, policy: str = "open-duty", turn=None, slowing=None) -> np.ndarray:
    """Samples at which duty ``index`` (a stand-on duty) is excused by a give-way duty to another ship (module
    docstring).

    Parameters
    ----------
    duties : sequence of Duty
        All encounters of one ship.
    index : int
        The stand-on duty.
    n_samples : int
        Number of samples T.
    policy : {"open-duty", "forced"}
        The profile's ``excuse`` policy.
    turn : array-like (T,), optional
        The ship's change of heading from each sample's predecessor (rad, positive to starboard; sample 0 any);
        needed by ``"forced"``.
    slowing : array-like of bool (T,), optional
        Whether her speed fell from each sample's predecessor (default: never).

    Returns
    -------
    numpy.ndarray of bool (T,)
        True at the excused samples.

    Examples
    --------
    A give-way duty to ship 1 open at samples 2–6 (risk at 4–5, CPA at 5) while standing on for ship 2; the ship
    turns to starboard at samples 3–5 and to port at 6:

    >>> d = [Duty(1, "give-way", 2, 4, 6, 5, np.arange(10) // 2 == 2), Duty(2, "stand-on", 3, 3, 9)]
    >>> excused_samples(d, 1, 10).astype(int).tolist()
    [0, 0, 1, 1, 1, 1, 1, 0, 0, 0]
    >>> turn = np.array([0, 0, 0, .1, .1, .1, -.1, 0, 0, 0])
    >>> excused_samples(d, 1, 10, "forced", turn).astype(int).tolist()
    [0, 0, 0, 1, 1, 1, 0, 0, 0, 0]
    """
    k = np.arange(n_samples)
    mask = np.zeros(n_samples, dtype=bool)
    me = duties[index]
    for d in duties:
        if not d.gives_way or d.other == me.other:
            continue
        if policy == "open-duty":
            mask |= (k >= d.start) & (k <= d.release)
            continue
        cpa = d.release if d.cpa is None else d.cpa
        risk = np.ones(n_samples, dtype=bool) if d.risk is None else np.asarray(d.risk, dtype=bool)
        active = (k >= d.start) & (k <= cpa) & ((k < d.onset) | risk)
        turn_ = np.asarray(turn, dtype=float)
        slows = np.zeros(n_samples, dtype=bool) if slowing is None else np.asarray(slowing, dtype=bool)
        if d.role == "overtaking":
            way = (np.abs(turn_) > TURNING) | slows
        else:
            way = (turn_ > TURNING) | (slows & (turn_ >= -TURNING))
        mask |= active & way
    return mask
