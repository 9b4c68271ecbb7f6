"""Several ships at once: conflicting duties (Rule 2(b)) and the attribution of a ship's actions to her encounters.

A ship's encounters are the risk episodes she has with every other ship (:mod:`mmg_casadi.colregs.risk`), each
with a role (:mod:`mmg_casadi.colregs.roles`). A **give-way duty** (roles head-on, give-way, overtaking: she must
act) is open from her baseline (where her action for it is counted from) to its release; a **stand-on duty**
(stand-on, overtaken) from its onset to its release.

* **Conflicting duties** (Rule 2(b), departure from the rules to avoid immediate danger): an encounter is flagged
  when another encounter of the same ship with a duty of the other kind is open at the same time: she must keep
  out of the way of one ship and keep her course and speed for another, and cannot do both.
* **Attribution**: a change of course or speed counts for every encounter whose window contains it — a give-way
  ship's alteration is her action towards each ship she gives way to. The exception: while a give-way duty to
  another ship is open, a stand-on ship's changes are attributed to that duty, and Rule 17(a)(i) of the stand-on
  encounter is excused at those samples; afterwards she keeps the course and speed she then has
  (:func:`mmg_casadi.colregs.stand_on_rules.moving_reference`).
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


def excused_samples(duties, index, n_samples) -> np.ndarray:
    """Samples at which duty ``index`` (a stand-on duty) is excused: a give-way duty to another ship is open.

    Parameters
    ----------
    duties : sequence of Duty
        All encounters of one ship.
    index : int
        The stand-on duty.
    n_samples : int
        Number of samples T.

    Returns
    -------
    numpy.ndarray of bool (T,)
        True at the excused samples.

    Examples
    --------
    >>> d = [Duty(1, "give-way", 2, 4, 6), Duty(2, "stand-on", 3, 3, 9)]
    >>> excused_samples(d, 1, 10).astype(int).tolist()
    [0, 0, 1, 1, 1, 1, 1, 0, 0, 0]
    """
    k = np.arange(n_samples)
    mask = np.zeros(n_samples, dtype=bool)
    me = duties[index]
    for d in duties:
        if d.gives_way and d.other != me.other:
            mask |= (k >= d.start) & (k <= d.release)
    return mask
