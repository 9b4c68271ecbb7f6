"""Target behaviours inside the compiled step (:mod:`mmg_casadi.traffic.behaviour` describes them): the gate a
traffic ship's method passes through.
"""

from __future__ import annotations

import casadi as ca

from mmg_casadi.traffic.behaviour import FORWARD_COS


def gate(c: dict, i: int, Xi, S_: dict, *, psi_d, w_react, psi_route, psi_plain, nb_pos, nb_vel, active, n_ships):
    """A traffic ship's desired heading, reactive weight and traffic rows after the step.

    Parameters
    ----------
    c : dict
        The step's context (``P`` with ``P["traffic"]``, ``t``, ``pos``, ``vel``, ``psi``).
    i : int
        The ship.
    Xi : SX
        Her rows at the start of the step.
    S_ : dict
        Row name -> index into ``Xi``.
    psi_d, w_react : SX
        Her method's desired heading and reactive weight (as a ship of her method).
    psi_route, psi_plain : SX
        Her method's route heading (ILOS with the method's turn limit and goal capture) and the plain ILOS heading
        of a ship of the method ``"none"``.
    nb_pos, nb_vel, active : SX
        Her neighbours (other ships first, ``n_ships - 1`` of them) and the mask of those within R_safe.
    n_ships : int
        Ships of the layout.

    Returns
    -------
    (SX, SX, list of SX)
        Desired heading, reactive weight and the rows :data:`ROWS` after the step.
    """
    P = c["P"]
    b = P["traffic"][i]
    dt = P["dt"]
    hold, delay, wrong, turn = b["hold"], b["delay"], b["wrong"], b["turn"]
    wants = w_react > 0.5
    clock = Xi[S_["late_clock"]]
    acts = ca.logic_and(ca.logic_and(wants, clock >= delay), hold < 0.5)
    psi_base = ca.if_else(hold > 0.5, psi_plain, psi_route)
    out_psi = ca.if_else(acts, psi_d, psi_base)
    out_w = ca.if_else(acts, w_react, 0.0)
    clock_next = ca.if_else(wants, clock + dt, 0.0)
    # the wrong way: a head-on or crossing risk forward of the beam starts a turn to port, held while ships close
    pos, vel, psi = c["pos"][i], c["vel"][i], c["psi"][i]
    bow = ca.vertcat(ca.cos(psi), ca.sin(psi))
    risk, closing = ca.SX(0), ca.SX(0)
    for k in range(n_ships - 1):
        d = nb_pos[:, k] - pos
        w = nb_vel[:, k] - vel
        dw = ca.dot(d, w)
        near = active[k] > 0.5
        closes = ca.logic_and(near, dw < 0)
        w2 = ca.fmax(ca.dot(w, w), 1e-12)
        dcpa2 = ca.dot(d, d) - dw * dw / w2
        ahead = ca.dot(d, bow) > FORWARD_COS * ca.norm_2(d)
        risk = ca.logic_or(risk, ca.logic_and(ca.logic_and(closes, ahead), dcpa2 < P["traffic"]["target_wrong_dcpa"] ** 2))
        closing = ca.logic_or(closing, closes)
    on = Xi[S_["wrong_on"]] > 0.5
    on_next = ca.logic_and(wrong > 0.5, ca.if_else(on, closing, risk))
    psi_w = ca.if_else(ca.logic_and(ca.logic_not(on), on_next), psi - turn, Xi[S_["wrong_psi"]])
    out_psi = ca.if_else(on_next, psi_w, out_psi)
    out_w = ca.if_else(on_next, 1.0, out_w)
    return out_psi, out_w, [clock_next, ca.if_else(on_next, 1.0, 0.0), psi_w]
