"""Encounters of ``colregs-vortex`` with a memory: the role of every ship with a risk of collision, judged once at
the onset of risk against the own ship's actual heading and kept until the encounter is released (CasADi).

A watch officer judges the situation when the risk of collision begins and keeps that judgement for the encounter:
a give-way ship that turns to starboard does not make a crossing head-on, the own evasive turn does not make a
stand-on ship give way. The roles are those of the encounter scorer (:mod:`mmg_casadi.colregs.roles`, profile
``iitm-lab``), from the bearing β of the other ship from the own bow and the bearing α of the own ship from the
other's bow (her heading taken from her velocity over the ground), in this order:

1. **overtaking** (:data:`OVERTAKING`): the own ship lies more than ``γ_max`` (112.5°, COLREG Rule 13(b)) from
   the other's bow and is the faster ship;
2. **overtaken** (:data:`OVERTAKEN`): the mirror case;
3. **head-on** (:data:`HEAD_ON`): ``|α|`` and ``|β|`` below θ_ho. The scorer also asks for courses within θ_ho
   of reciprocal; a ship nearly ahead that has the own ship nearly ahead is taken as head-on whatever the course
   difference (Rule 14(c): in doubt, assume a head-on situation exists), since both ships may otherwise judge
   themselves stand-on in a fine crossing;
4. **give-way** (:data:`GIVE_WAY`) for a ship on the starboard side (β > 0), **stand-on** (:data:`STAND_ON`)
   otherwise (Rules 15 and 17).

**Risk of collision** (Rule 7), the onset: a ship within R_safe whose straight-line passing distance at the present
velocities is below ``d_risk`` while the range closes; with a lookout (``cv_r_look`` > 0) also a ship within
R_safe + ``cv_r_look`` that the own ship gives way to (:func:`giveway_open`).

**Memory** (:data:`MEMORY`, rows of the closed-loop state): :data:`SLOTS` encounter slots, each the position of its
ship at the last step and a code ``CODE + role`` (``+ ACTING`` once a stand-on ship acts alone, so her action is
kept once begun), plus two courses: ``cv_course`` (the course a stand-on ship keeps) and ``cv_base`` (the heading a
give-way ship's alteration is measured from). A slot follows its ship from step to step: the ship within
``match`` of the stored position (a ship moves about 0.25 L per guidance step, and two ships closer than twice
``match`` would have collided). The encounter is **released** when its ship leaves R_safe (as the scorer releases
it beyond ``r_risk`` = R_safe); the closed loop then writes the heading into every row once nothing is within
R_safe, which no code matches: every slot is free. A ship with a risk of collision and no free slot keeps the role
judged at the present step (the memoryless judgement).

Examples
--------
>>> import math
>>> import casadi as ca
>>> code = classify_role(ca.DM([0.0, 0.7, -0.7]), ca.DM([0.0, -0.7, 0.7]), 0.0, ca.DM([math.pi, -1.57, 1.57]),
...                      1.0, ca.DM([1.0, 1.0, 1.0]), theta_head_on=math.radians(22.5), stern=5 * math.pi / 8)
>>> [int(c) for c in ca.DM(code).full().ravel()]  # head-on, give-way, stand-on
[4, 3, 1]
"""

from __future__ import annotations

import casadi as ca

STAND_ON, OVERTAKEN, GIVE_WAY, HEAD_ON, OVERTAKING = 1, 2, 3, 4, 5
"""Role codes: stand-on (crossing, Rule 17), overtaken (Rule 13 / 17), give-way (crossing, Rule 15), head-on
(Rule 14), overtaking (Rule 13)."""
ACTING = 5
"""Added to a stand-on or overtaken ship's code once she acts alone (Rule 17(a)(ii))."""
CODE = 1000.0
"""Offset of a slot's code row: ``CODE + role (+ ACTING)``; any other value (a heading) is a free slot."""
SLOTS = 3
"""Encounter slots per ship (simultaneous encounters remembered; more are judged step by step)."""
MATCH = 1.0
"""A slot follows the ship within this distance (L) of its stored position: half the 2 L collision distance."""
MEMORY: tuple[str, ...] = ("cv_course", "cv_base") + tuple(f"cv_slot{k}_{c}" for k in range(SLOTS)
                                                         for c in ("x", "y", "code"))
"""Memory rows of ``colregs-vortex`` (module docstring)."""


def classify_role(beta, alpha, psi_own, chi_other, speed_own, speed_other, *, theta_head_on, stern):
    """Role code of the own ship towards each neighbour (1×M), as :func:`mmg_casadi.colregs.roles.classify_roles`.

    Parameters
    ----------
    beta, alpha : casadi.SX or casadi.DM (1×M)
        Bearing of the neighbour from the own bow and of the own ship from the neighbour's bow (rad, to starboard).
    psi_own : SX
        Own heading (rad; unused: the bearings carry the headings, kept for the scorer's signature).
    chi_other : SX (1×M)
        Neighbours' courses over the ground (rad; unused, as ``psi_own``).
    speed_own : SX
        Own speed over the ground.
    speed_other : SX (1×M)
        Neighbours' speeds over the ground.
    theta_head_on : float
        Head-on tolerance on both bearings and on the course difference from reciprocal (rad).
    stern : float
        Start of the stern sector from the bow (rad; 112.5°, Rule 13(b)).

    Returns
    -------
    SX (1×M)
        One of :data:`STAND_ON`, :data:`OVERTAKEN`, :data:`GIVE_WAY`, :data:`HEAD_ON`, :data:`OVERTAKING`.
    """
    overtaking = (ca.fabs(alpha) > stern) * (speed_own > speed_other)
    overtaken = (ca.fabs(beta) > stern) * (speed_own < speed_other)
    # Rule 14(c): in doubt whether the situation is head-on, assume it is: each ship within θ_ho of the other's bow
    # (whatever the course difference; on reciprocal courses the two bearings are nearly equal anyway)
    head_on = (ca.fabs(alpha) < theta_head_on) * (ca.fabs(beta) < theta_head_on)
    crossing = STAND_ON + (GIVE_WAY - STAND_ON) * (beta > 0)
    return overtaking * OVERTAKING + (1 - overtaking) * (overtaken * OVERTAKEN + (1 - overtaken) * (
        head_on * HEAD_ON + (1 - head_on) * crossing))


def recall(nb_pos, active, slots):
    """Which slot follows which neighbour: the 0/1 matrix (``SLOTS`` × M) and each neighbour's remembered code.

    Parameters
    ----------
    nb_pos : SX (2×M)
        Neighbour positions (L).
    active : SX (1×M)
        Neighbours within R_safe (0/1).
    slots : list of (x, y, code)
        The memory slots at the start of the step.

    Returns
    -------
    tuple
        ``link`` (list of 1×M rows, one per slot: 1 where the slot follows that neighbour, at most one per slot and
        per neighbour) and ``code`` (1×M: the remembered ``role (+ ACTING)``, 0 where none).
    """
    m = nb_pos.size2()
    taken = ca.SX.zeros(1, m)
    link, code = [], ca.SX.zeros(1, m)
    for x, y, c in slots:
        r = c - CODE
        valid = (r > 0.5) * (r < STAND_ON + OVERTAKING + ACTING)
        near = (ca.sqrt((nb_pos[0, :] - x) ** 2 + (nb_pos[1, :] - y) ** 2) < MATCH) * active * (1 - taken) * valid
        first = ca.SX.zeros(1, m)
        seen = ca.SX(0)
        for j in range(m):  # the first neighbour the slot matches (two within MATCH of one point have collided)
            first[j] = near[j] * (1 - seen)
            seen = seen + first[j]
        link.append(first)
        taken = taken + first
        code = code + first * r
    return link, code


def open_encounters(nb_pos, risk, role_now, link, code):
    """Give every neighbour with a risk of collision and no slot the first free slot (role ``role_now``).

    Parameters
    ----------
    nb_pos : SX (2×M)
        Neighbour positions (L).
    risk : SX (1×M)
        Risk of collision now (0/1).
    role_now : SX (1×M)
        Role judged now.
    link, code : list of SX (1×M), SX (1×M)
        From :func:`recall`.

    Returns
    -------
    tuple
        Updated ``link`` and ``code``; ``code`` is the role of the encounter each neighbour is in (0: none), the
        judgement of the present step for a ship with a risk of collision that found no free slot.
    """
    m = nb_pos.size2()
    link = [ca.SX(row) for row in link]
    has = sum(link) if link else ca.SX.zeros(1, m)
    need = risk * (1 - has)
    for j in range(m):
        placed = ca.SX(0)
        for k, row in enumerate(link):
            free = 1 - ca.sum2(row)
            take = need[j] * free * (1 - placed)
            row[j] = row[j] + take
            placed = placed + take
    return link, code + need * role_now


def remember(nb_pos, link, code_next, own_psi):
    """The slot rows after the step: each slot's ship's position and code, or the heading for a free slot.

    Parameters
    ----------
    nb_pos : SX (2×M)
        Neighbour positions (L).
    link : list of SX (1×M)
        Which neighbour each slot follows (:func:`open_encounters`).
    code_next : SX (1×M)
        Every neighbour's code after the step (``role (+ ACTING)``).
    own_psi : SX
        Own heading (the value of a free slot, as the closed loop writes it).

    Returns
    -------
    dict
        The ``cv_slot*`` rows of :data:`MEMORY` by name.
    """
    out = {}
    for k, row in enumerate(link):
        used = ca.sum2(row)
        out[f"cv_slot{k}_x"] = ca.if_else(used > 0.5, ca.sum2(row * nb_pos[0, :]), own_psi)
        out[f"cv_slot{k}_y"] = ca.if_else(used > 0.5, ca.sum2(row * nb_pos[1, :]), own_psi)
        out[f"cv_slot{k}_code"] = ca.if_else(used > 0.5, CODE + ca.sum2(row * code_next), own_psi)
    return out


def slots_of(memory: dict) -> list:
    """The ``(x, y, code)`` rows of every slot in ``memory`` (by name, :data:`MEMORY`).

    Parameters
    ----------
    memory : dict
        The method's memory rows by name (:data:`MEMORY`).

    Returns
    -------
    list of tuple
        One ``(x, y, code)`` triple of memory entries per slot, ``SLOTS`` of them in slot order.
    """
    return [(memory[f"cv_slot{k}_x"], memory[f"cv_slot{k}_y"], memory[f"cv_slot{k}_code"]) for k in range(SLOTS)]


def gives_way(role):
    """1 where ``role`` (a role code, or a slot's code less :data:`CODE`) is one in which the own ship gives way:
    give-way, head-on or overtaking (not a stand-on or overtaken code, with or without :data:`ACTING`).

    Parameters
    ----------
    role : SX, DM or float
        Role codes.

    Returns
    -------
    SX, DM or bool
        1 or 0 per element.

    Examples
    --------
    >>> [bool(gives_way(r)) for r in (STAND_ON, OVERTAKEN, GIVE_WAY, HEAD_ON, OVERTAKING, STAND_ON + ACTING)]
    [False, False, True, True, True, False]
    """
    return (role > GIVE_WAY - 0.5) * (role < OVERTAKING + 0.5)


def giveway_open(memory: dict):
    """1 while a slot of ``memory`` (by name, :data:`MEMORY`) holds an encounter in which the own ship gives way
    (give-way, head-on, overtaking), else 0: the ``engaged`` test of ``colregs-vortex``
    (:class:`~mmg_casadi.guidance.methods.Method`), which keeps her in the method's charge while such a ship is
    within R_safe + ``cv_r_look``.

    Parameters
    ----------
    memory : dict
        The method's memory rows after the step, by name.

    Returns
    -------
    SX or bool
        1 or 0 (a bool for numbers).

    Examples
    --------
    >>> rows = {f"cv_slot{k}_{c}": 0.3 for k in range(SLOTS) for c in ("x", "y", "code")}  # free slots (a heading)
    >>> int(giveway_open(rows)), int(giveway_open({**rows, "cv_slot1_code": CODE + GIVE_WAY}))
    (0, 1)
    >>> int(giveway_open({**rows, "cv_slot0_code": CODE + STAND_ON + ACTING}))
    0
    """
    return sum(gives_way(memory[f"cv_slot{k}_code"] - CODE) for k in range(SLOTS)) > 0.5
