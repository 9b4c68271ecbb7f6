"""Encounter type and role of a ship at the onset of risk, from the bearing β and the contact angle α (numpy).

With β the bearing of the other ship from the own bow and α the bearing of the own ship from the other's bow
(both in [−π, π), positive to starboard) and the profile's sectors
(:class:`~mmg_casadi.colregs.profiles.ScoringProfile`), the own ship is, in this order:

1. **overtaking** if she lies in the other's stern sector (``|α| > stern_deg``, COLREG Rule 13(b): more than
   22.5° abaft her beam), is the faster ship and, if the profile sets ``overtaking_bow_deg``, has the other within
   that angle of her bow (``|β|``);
2. **overtaken** in the mirror case (``|β| > stern_deg``, the other faster, ``|α|`` within the bow angle);
3. **head-on** if ``|α| < head_on_deg`` and ``|β| < head_on_deg`` (and, if the profile sets
   ``head_on_heading_deg``, the courses are within that angle of reciprocal); or, Rule 14(c) ("when a vessel is
   in any doubt as to whether such a situation exists she shall assume that it does exist"), if the profile sets
   ``head_on_doubt_deg`` and each ship sees the other within it of her bow (:func:`in_doubt`; on a collision course
   at equal speeds the courses are then within twice that angle of reciprocal);
4. otherwise crossing: **give-way** with the other ship on her starboard side (β > 0; Rule 15),
   **stand-on** with the other on her port side (β ≤ 0; Rule 17). Crossings at small angles are crossings.

The roles of the two ships of a pair on a collision course are complementary (head-on/head-on, give-way/stand-on,
overtaking/overtaken): on a collision course β and α have opposite signs.
"""

from __future__ import annotations

import math

import numpy as np

from mmg_casadi.colregs.geometry import wrap_to_pi

#: the roles a ship can have in an encounter
ROLES = ("head-on", "give-way", "stand-on", "overtaking", "overtaken")
#: the encounter type of each role
ENCOUNTER_OF_ROLE = {"head-on": "head-on", "give-way": "crossing", "stand-on": "crossing",
                     "overtaking": "overtaking", "overtaken": "overtaking"}
#: roles that must keep out of the way or alter course (Rules 13, 14, 15, 16)
GIVE_WAY_ROLES = ("head-on", "give-way", "overtaking")
#: roles that keep course and speed (Rule 17)
STAND_ON_ROLES = ("stand-on", "overtaken")
#: the roles of an overtaking (Rule 13)
OVERTAKING_ROLES = ("overtaking", "overtaken")


def classify_roles(beta, alpha, psi_own, psi_other, speed_own, speed_other, profile) -> np.ndarray:
    """The own ship's role (one of :data:`ROLES`), elementwise over arrays of one shape (module docstring).

    Parameters
    ----------
    beta, alpha : array-like
        Bearing of the other ship from the own bow and contact angle (rad, positive to starboard).
    psi_own, psi_other : array-like
        Headings (rad).
    speed_own, speed_other : array-like
        Speeds over the ground.
    profile : ScoringProfile
        ``head_on_deg``, ``head_on_heading_deg``, ``stern_deg`` and ``overtaking_bow_deg``.

    Returns
    -------
    numpy.ndarray of str
        A name of :data:`ROLES` per element, the shape of the inputs.

    Examples
    --------
    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> d = np.radians
    >>> classify_roles(d([0, 45, -45, 0, 170, 10]), d([0, -45, 45, 170, 0, -8]), d([0, 0, 0, 0, 0, 0]),
    ...                d([180, -90, 90, 0, 0, -20]), [1, 1, 1, 1, 0.5, 1], [1, 1, 1, 0.5, 1, 1], iitm_lab()).tolist()
    ['head-on', 'give-way', 'stand-on', 'overtaking', 'overtaken', 'give-way']
    """
    beta, alpha = np.asarray(beta, dtype=float), np.asarray(alpha, dtype=float)
    shape = np.broadcast(beta, alpha, np.asarray(psi_own), np.asarray(psi_other), np.asarray(speed_own),
                         np.asarray(speed_other)).shape
    faster = np.asarray(speed_own, dtype=float) > np.asarray(speed_other, dtype=float)
    slower = np.asarray(speed_own, dtype=float) < np.asarray(speed_other, dtype=float)
    stern = np.radians(profile.stern_deg)
    bow = np.inf if profile.overtaking_bow_deg is None else np.radians(profile.overtaking_bow_deg)
    overtaking = (np.abs(alpha) > stern) & faster & (np.abs(beta) < bow)
    overtaken = (np.abs(beta) > stern) & slower & (np.abs(alpha) < bow)
    head_on = head_on_sector(beta, alpha, psi_own, psi_other, profile) | in_doubt(beta, alpha, psi_own, psi_other,
                                                                               profile)
    crossing = np.where(beta > 0.0, "give-way", "stand-on")
    role = np.select([overtaking, overtaken, head_on], ["overtaking", "overtaken", "head-on"], crossing)
    return np.broadcast_to(role, shape).astype(str)


def head_on_sector(beta, alpha, psi_own, psi_other, profile) -> np.ndarray:
    """Whether two ships meet head-on by the profile's sector alone (``head_on_deg``, ``head_on_heading_deg``),
    elementwise; Rule 14(c)'s doubt band is :func:`in_doubt`.

    Parameters
    ----------
    beta, alpha : array-like
        Bearing of the other ship from the own bow and contact angle (rad).
    psi_own, psi_other : array-like
        Headings (rad).
    profile : ScoringProfile
        ``head_on_deg`` and ``head_on_heading_deg``.

    Returns
    -------
    numpy.ndarray of bool
        True inside the head-on sector.

    Examples
    --------
    >>> from mmg_casadi.colregs.profiles import published
    >>> d = np.radians
    >>> head_on_sector(d([5.0, 18.0]), d([-5.0, -18.0]), 0.0, d(170.0), published()).tolist()
    [True, False]
    """
    limit = np.radians(profile.head_on_deg)
    out = (np.abs(np.asarray(alpha, dtype=float)) < limit) & (np.abs(np.asarray(beta, dtype=float)) < limit)
    if profile.head_on_heading_deg is not None:
        reciprocal = np.abs(wrap_to_pi(np.asarray(psi_own, dtype=float) - np.asarray(psi_other, dtype=float) - np.pi))
        out = out & (reciprocal < np.radians(profile.head_on_heading_deg))
    return out


def in_doubt(beta, alpha, psi_own, psi_other, profile) -> np.ndarray:
    """Rule 14(c): whether two ships are in doubt whether they meet head-on: each sees the other within
    ``head_on_doubt_deg`` of her bow (elementwise; module docstring).

    Parameters
    ----------
    beta, alpha : array-like
        Bearing of the other ship from the own bow and contact angle (rad).
    psi_own, psi_other : array-like
        Headings (rad; they only set the shape).
    profile : ScoringProfile
        ``head_on_doubt_deg`` (None: never in doubt).

    Returns
    -------
    numpy.ndarray of bool
        True where both bearings are within ``head_on_doubt_deg``.

    Examples
    --------
    Ships on a collision course 36° off reciprocal, each 18° on the other's bow, are in doubt under ``published``
    (its certain head-on sector is 13°):

    >>> from mmg_casadi.colregs.profiles import published, iitm_lab
    >>> d = np.radians
    >>> bool(in_doubt(d(-18.0), d(18.0), 0.0, d(144.0), published())), bool(in_doubt(d(-18.0), d(18.0), 0.0,
    ...                                                                               d(144.0), iitm_lab()))
    (True, False)
    """
    shape = np.broadcast(np.asarray(beta), np.asarray(alpha), np.asarray(psi_own), np.asarray(psi_other)).shape
    if profile.head_on_doubt_deg is None:
        return np.zeros(shape, dtype=bool)
    limit = np.radians(profile.head_on_doubt_deg)
    return np.broadcast_to((np.abs(np.asarray(beta, dtype=float)) < limit)
                           & (np.abs(np.asarray(alpha, dtype=float)) < limit), shape)


def classify_role(beta: float, alpha: float, psi_own: float, psi_other: float, speed_own: float, speed_other: float,
                  profile) -> str:
    """:func:`classify_roles` of one encounter, in scalar arithmetic (the scorer's classification at an onset).

    Parameters
    ----------
    beta, alpha : float
        Bearing of the other ship from the own bow and contact angle (rad).
    psi_own, psi_other : float
        Headings (rad).
    speed_own, speed_other : float
        Speeds over the ground.
    profile : ScoringProfile
        The sectors.

    Returns
    -------
    str
        A name of :data:`ROLES`, the same as :func:`classify_roles` gives.

    Examples
    --------
    >>> from mmg_casadi.colregs.profiles import iitm_lab
    >>> classify_role(math.radians(45), math.radians(-45), 0.0, math.radians(-90), 1.0, 1.0, iitm_lab())
    'give-way'
    """
    stern = math.radians(profile.stern_deg)
    bow = math.inf if profile.overtaking_bow_deg is None else math.radians(profile.overtaking_bow_deg)
    if abs(alpha) > stern and speed_own > speed_other and abs(beta) < bow:
        return "overtaking"
    if abs(beta) > stern and speed_own < speed_other and abs(alpha) < bow:
        return "overtaken"
    if head_on_scalar(beta, alpha, psi_own, psi_other, profile):
        return "head-on"
    return "give-way" if beta > 0.0 else "stand-on"


def head_on_scalar(beta: float, alpha: float, psi_own: float, psi_other: float, profile, *, doubt: bool = True) -> bool:
    """:func:`head_on_sector` (or, with ``doubt``, that or :func:`in_doubt`) of one encounter, in scalar
    arithmetic.

    Parameters
    ----------
    beta, alpha : float
        Bearing of the other ship from the own bow and contact angle (rad).
    psi_own, psi_other : float
        Headings (rad).
    profile : ScoringProfile
        ``head_on_deg``, ``head_on_heading_deg`` and ``head_on_doubt_deg``.
    doubt : bool, default True
        Include Rule 14(c)'s doubt band.

    Returns
    -------
    bool
        Whether the ships meet head-on.
    """
    limit = math.radians(profile.head_on_deg)
    out = abs(alpha) < limit and abs(beta) < limit
    if out and profile.head_on_heading_deg is not None:
        reciprocal = abs(wrap_to_pi(psi_own - psi_other - math.pi))
        out = reciprocal < math.radians(profile.head_on_heading_deg)
    if not out and doubt and profile.head_on_doubt_deg is not None:
        wide = math.radians(profile.head_on_doubt_deg)
        out = abs(beta) < wide and abs(alpha) < wide
    return out
