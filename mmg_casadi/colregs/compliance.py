"""The own ship's COLREG compliance in one run, from a (decimated) history of positions and headings.

Each other ship is paired with the own ship (ship 0) and judged by :func:`mmg_casadi.colregs.assess.assess_pair` (the
rule-by-rule scorer) under a COLREG profile; static obstacles are not COLREG encounters. An encounter is
*classified* when the pair came within R_safe and the own ship's side of it is one of the COLREG encounter types
(not ``"none"``) with at least one applicable rule. The run is compliant when every classified encounter of the
own ship is; with no classified encounter its compliance is undefined (``None``).

Examples
--------
Head-on, the own ship holds her course (Rule 14 needs a starboard alteration): not compliant.

>>> t = np.linspace(0.0, 40.0, 161)
>>> own = np.column_stack([t, 0 * t, 0 * t, 0 * t])
>>> other = np.column_stack([50.0 - t, 2.0 + 0 * t, np.pi + 0 * t, 0 * t])
>>> own_ship_compliance(t, np.stack([own, other], axis=1), r_safe=15.0, collision_distance=2.0)
(False, 1)
"""

from __future__ import annotations

import numpy as np

from mmg_casadi.colregs.classify import get_profile
from mmg_casadi.colregs.score import score_pair
from mmg_casadi.closed_loop.simulation import sailing_mask


def own_ship_compliance(t, states, *, r_safe: float, collision_distance: float,
                        profile=None) -> tuple[bool | None, int]:
    """Whether the own ship kept the COLREGs in every classified encounter, and how many there were.

    Parameters
    ----------
    t : array (K,)
        Sample times (L/U).
    states : array (K, N, 4)
        ``x``, ``y`` (L), ``psi`` (rad) and ``status`` of every ship (ship 0 the own ship), as kept by
        :func:`mmg_casadi.closed_loop.simulation.simulate_batch_history`.
    r_safe, collision_distance : float
        Safe radius and collision distance (L).
    profile : ColregProfile or str, optional
        COLREG profile (default: the laboratory's, ``"iitm-lab"``).

    Returns
    -------
    tuple
        ``(compliant, encounters)``: ``compliant`` is ``None`` when ``encounters`` is 0.
    """
    profile = get_profile(profile)
    t = np.asarray(t, float)
    states = np.asarray(states, float)
    mask = sailing_mask(states[:, :, 3])
    pos0, psi0 = states[:, 0, :2], states[:, 0, 2]
    # a ship that never comes within R_safe of the own ship while both sail meets it in no encounter: skip the
    # scoring of that pair (the same verdicts, at a fraction of the cost in sparse traffic)
    dist = np.linalg.norm(states[:, 1:, :2] - pos0[:, None, :], axis=2)
    near = np.any((dist <= r_safe) & mask[:, :1] & mask[:, 1:], axis=0)
    verdicts = []
    for j in 1 + np.flatnonzero(near):
        # the own ship's side of assess_pair (the other ship's verdicts are not needed here)
        a = score_pair(t, pos0, psi0, states[:, j, :2], states[:, j, 2], r_safe=r_safe,
                       collision_distance=collision_distance, profile=profile, active_a=mask[:, 0],
                       active_b=mask[:, j], judge_b=False).a
        if a.encounter != "none" and a.compliant_all is not None:
            verdicts.append(bool(a.compliant_all))
    return (all(verdicts) if verdicts else None), len(verdicts)
