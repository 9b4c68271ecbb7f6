"""The give-way ship's substantial alteration (COLREG Rule 16) of ``colregs-vortex``
(:mod:`mmg_casadi.guidance.colregs_vortex`): the straight-line passing distance of a candidate alteration, and the
smallest alteration to starboard whose passing distance ends the risk of collision (:func:`giveway_floor`).
"""

from __future__ import annotations

import math

import casadi as ca

from mmg_casadi.guidance.fields import _col2, _matrix, _row

_BIG = 1.0e6
FLOOR_STEP = math.radians(10.0)
"""Step between the candidate alterations of :func:`giveway_floor` (rad, 10°)."""


def _cpa(rel_pos, rel_vel):
    """TCPA (1×M, negative when opening) and the relative position at the CPA (2×M, for TCPA clipped at 0)."""
    vv = ca.fmax(ca.sum1(rel_vel * rel_vel), 1e-9)
    tcpa = -ca.sum1(rel_pos * rel_vel) / vv
    p_cpa = rel_pos + rel_vel * ca.repmat(ca.fmax(tcpa, 0), 2, 1)
    return tcpa, p_cpa


def _crosses_ahead(los, nb_vel, v_own):
    """1 where the own ship, sailing at ``v_own``, would cross the neighbour's course line ahead of her (1×M)."""
    m = los.size2()
    speed_nb = ca.sqrt(ca.sum1(nb_vel * nb_vel))
    h = nb_vel / ca.repmat(ca.fmax(speed_nb, 1e-9), 2, 1)
    rel = -los  # own position relative to the neighbour
    side = h[0, :] * rel[1, :] - h[1, :] * rel[0, :]
    v = ca.repmat(v_own, 1, m)
    rate = h[0, :] * v[1, :] - h[1, :] * v[0, :]  # d(side)/dt (her own motion is along the line)
    t_x = -side / ca.if_else(ca.fabs(rate) > 1e-9, rate, 1e-9)
    along = ca.sum1(h * rel) + t_x * (ca.sum1(h * v) - speed_nb)
    return (t_x > 0) * (along > 0) * (ca.fabs(rate) > 1e-9)


def giveway_floor(own_pos, speed, ref, nb_pos, nb_vel, duty, *, dpsi_min, d_risk):
    """Smallest alteration to starboard of ``ref``, from ``dpsi_min`` in :data:`FLOOR_STEP` steps up to 90°, whose
    straight-line passing distance (own ship at ``speed``, neighbours at ``nb_vel``) to every neighbour with
    ``duty`` 1 is at least ``d_risk`` (a neighbour already past its CPA counts as clear); if none is, the
    candidate whose passing distance is the widest (Rule 16: the give-way ship's action alone removes the risk of
    collision, or comes as near to it as a course change can).

    Parameters
    ----------
    own_pos : array_like
        Own position (2×1, L).
    speed : float or casadi.SX
        Own speed (L/unit time).
    ref : float or casadi.SX
        Heading the alteration is measured from (rad): the heading at the onset of the duty.
    nb_pos, nb_vel : array_like
        Neighbour positions and velocities (2×M, L and L/unit time).
    duty : array_like
        1×M, 1 for the neighbours the floor is judged against (head-on and crossing give-way duties).
    dpsi_min : float or casadi.SX
        The smallest alteration (rad, Rule 8's readily apparent one).
    d_risk : float or casadi.SX
        Passing distance that ends the risk of collision (L).

    Returns
    -------
    casadi.DM or casadi.SX
        The alteration (rad, to starboard of ``ref``).

    Examples
    --------
    A ship 12 L ahead and 12 L to starboard crossing to port at the own speed, both heading for the same point:
    altering 30° passes 4.4 L from her, 40° 5.8 L, 50° 7.2 L; with a 6 L passing distance the floor is 50°, and
    with no duty it is the minimum itself. At 0.7 times the speed of a ship 2 L ahead and 12 L to starboard, no
    alteration up to 90° passes at 4 L; 30° passes widest (3.1 L; 70° 0.3 L, 90° 2.0 L).

    >>> import math, casadi as ca
    >>> kw = dict(dpsi_min=math.radians(30), d_risk=6.0)
    >>> pos, vel = ca.DM([[12], [12]]), ca.DM([[0], [-1]])
    >>> round(math.degrees(float(giveway_floor([0, 0], 1.0, 0.0, pos, vel, [1], **kw))))
    50
    >>> round(math.degrees(float(giveway_floor([0, 0], 1.0, 0.0, pos, vel, [0], **kw))))
    30
    >>> kw["d_risk"] = 4.0
    >>> round(math.degrees(float(giveway_floor([0, 0], 0.7, 0.0, ca.DM([[2], [12]]), vel, [1], **kw))))
    30
    """
    own_pos = _col2(own_pos)
    nb_pos, nb_vel = _matrix(nb_pos, 2), _matrix(nb_vel, 2)
    m = nb_pos.size2()
    duty = _row(duty, m)
    los = nb_pos - ca.repmat(own_pos, 1, m)
    steps = math.ceil((math.pi / 2) / FLOOR_STEP)  # enough steps to reach 90° from any dpsi_min >= 0
    alterations, passing = [], []
    for k in range(steps + 1):
        dk = ca.fmin(dpsi_min + k * FLOOR_STEP, math.pi / 2)
        v_k = speed * ca.vertcat(ca.cos(ref + dk), ca.sin(ref + dk))
        tcpa, p_cpa = _cpa(los, nb_vel - ca.repmat(v_k, 1, m))
        clear = (1 - duty) + duty * (tcpa <= 0)  # not judged, or already past the CPA
        alterations.append(dk)
        passing.append(ca.mmin(clear * _BIG + (1 - clear) * ca.sqrt(ca.sum1(p_cpa * p_cpa))))
    # none passes at d_risk: the one that passes widest (the first of equals)
    floor, widest = alterations[0], passing[0]
    for dk, pk in zip(alterations[1:], passing[1:]):
        floor, widest = ca.if_else(pk > widest, dk, floor), ca.fmax(pk, widest)
    for dk, pk in zip(reversed(alterations), reversed(passing)):
        floor = ca.if_else(pk >= d_risk, dk, floor)
    return floor
