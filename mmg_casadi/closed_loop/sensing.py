"""The perception layer's update inside the compiled step (:mod:`mmg_casadi.perception.layer` describes it).

:func:`perceive` reads the true states of the step's context and the perception rows of every ship and returns what
the own ship's method sees and the rows after the step; the step (:mod:`mmg_casadi.closed_loop.step`) gives the own
ship's update that view instead of the truth.
"""

from __future__ import annotations

import casadi as ca

from mmg_casadi.perception import rng, sensors, tracker
from mmg_casadi.perception.layer import NEVER, RNG_ROWS, SIGMA_V0, rows


def perceive(layout, c: dict):
    """The perception update of one step: what the own ship's method sees and every ship's new perception rows.

    Parameters
    ----------
    layout : Layout
        A layout with perception (``layout.perception != "off"``).
    c : dict
        The step's context (``mmg_casadi.closed_loop.step._step_context``): named parameters ``P`` (with
        ``P["perception"]``, the :data:`INPUTS`), clock ``t``, ship states ``X``, true positions, velocities and
        presence.

    Returns
    -------
    seen : SX (5 N)
        Per ship ``[x, y, vx, vy, present]`` as the own ship's method sees it (ship 0 her own true values), in the
        layout of the sparse step's shared vector.
    new_rows : list of SX
        Per ship its perception rows (:func:`rows`) after the step.
    """
    mode = layout.perception
    P, t, X, S_ = c["P"], c["t"], c["X"], c["S"]
    I = P["perception"]
    dt = P["dt"]
    own = c["pos"][0]
    names = rows(mode)
    seen = [ca.vertcat(c["pos"][0], c["vel"][0], c["present"][0])]
    out = [ca.vertcat(*[X[0][S_[k]] for k in names])]
    draws, Rs = {}, {}
    for j in range(1, layout.n_ships):  # every target's draws first: a track may take any target's plot
        R = {k: X[j][S_[k]] for k in names}
        g = [R[k] for k in RNG_ROWS]
        u = []
        for _ in range(5 + (3 if "radar" in mode else 0)):
            g, uk = rng.mrg_next(g)
            u.append(uk)
        draws[j] = u
        R.update(dict(zip(RNG_ROWS, g)))
        Rs[j] = R
    plots = None
    if "radar" in mode:
        plots = [_radar(c["pos"][k] - own, c["present"][k], draws[k][5:], I, own) for k in range(1, layout.n_ships)]
    for j in range(1, layout.n_ships):
        R, u = Rs[j], draws[j]
        c_j = {"pos": c["pos"][j], "vel": c["vel"][j], "present": c["present"][j], "r": X[j][S_["r"]]}
        if "ais" in mode:
            report = _ais(R, c_j, u[:5], t, I)
        if mode == "ais":
            known = R["ais_t"] > NEVER / 2
            age = t - R["ais_t"]
            est = [R["ais_x"] + age * R["ais_vx"], R["ais_y"] + age * R["ais_vy"], R["ais_vx"], R["ais_vy"]]
        else:
            est, known = _track(R, c_j, plots, j - 1, dt, I, report if "ais" in mode else None)
        R.update(dict(zip(("seen_x", "seen_y", "seen_vx", "seen_vy"), est)))
        R["seen_known"] = known
        present = ca.logic_and(c["present"][j], known)
        err = ca.sqrt((est[0] - c["pos"][j][0]) ** 2 + (est[1] - c["pos"][j][1]) ** 2)
        near = ca.logic_and(ca.logic_and(present, c["sailing"][0]),
                            ca.sumsqr(c["pos"][j] - own) <= P["r_safe"] ** 2)
        R["seen_err_int"] = R["seen_err_int"] + ca.if_else(near, err * dt, 0.0)
        R["seen_err_time"] = R["seen_err_time"] + ca.if_else(near, dt, 0.0)
        seen.append(ca.vertcat(est[0], est[1], est[2], est[3], present))
        out.append(ca.vertcat(*[R[k] for k in names]))
    return ca.vertcat(*seen), out


def _ais(R: dict, c_j: dict, u, t, I):
    """Ship j's AIS rows after the step (updated in ``R``) and the report received in it: ``(received, z, age)``
    with ``z = [x, y, vx, vy]`` the report brought to the present along its own velocity."""
    vx, vy = c_j["vel"][0], c_j["vel"][1]
    speed_kn = ca.sqrt(vx * vx + vy * vy) * I["kn_per_u"]
    turning = ca.fabs(c_j["r"]) > I["turn_rate"]
    T = I["ais_scale"] * sensors.ais_interval_s(speed_kn, turning, I["ais_class_b"]) / I["s_per_t"]
    due = t - I["ais_latency"] >= R["ais_next"]
    n = ca.if_else(T > 0, ca.floor((t - I["ais_latency"] - R["ais_next"]) / ca.fmax(T, 1e-300)), 0.0)
    t_tx = ca.if_else(T > 0, R["ais_next"] + n * T, t - I["ais_latency"])
    age = t - t_tx
    n1, n2 = rng.normals(u[0], u[1])
    n3, n4 = rng.normals(u[2], u[3])
    got = ca.logic_and(ca.logic_and(due, u[4] >= I["ais_dropout"]), c_j["present"] > 0.5)
    x_tx = c_j["pos"][0] - vx * age + I["ais_sigma_p"] * n1
    y_tx = c_j["pos"][1] - vy * age + I["ais_sigma_p"] * n2
    rvx, rvy = sensors.ais_velocity(vx, vy, n3, n4, I["ais_sigma_sog"], I["ais_sigma_cog"])
    R["ais_next"] = ca.if_else(due, t_tx + T, R["ais_next"])
    for k, v in zip(("ais_t", "ais_x", "ais_y", "ais_vx", "ais_vy"), (t_tx, x_tx, y_tx, rvx, rvy)):
        R[k] = ca.if_else(got, v, R[k])
    z = [x_tx + age * rvx, y_tx + age * rvy, rvx, rvy]
    return got, z


def _radar(d, present, u, I, own):
    """A radar plot of a target at offset ``d`` from the own ship: ``(detected, z, R)`` (position in the scene)."""
    n1, n2 = rng.normals(u[0], u[1])
    zx, zy, rxx, rxy, ryy = sensors.radar_plot(d[0], d[1], n1, n2, I["radar_sigma_r"], I["radar_sigma_b"])
    seen = ca.logic_and(ca.logic_and(present > 0.5, ca.sumsqr(d) <= I["radar_range"] ** 2),
                        u[2] < I["radar_p_detect"])
    Rm = ca.vertcat(ca.horzcat(rxx, rxy), ca.horzcat(rxy, ryy))
    return seen, [own[0] + zx, own[1] + zy], Rm


def _track(R: dict, c_j: dict, plots, own_plot: int, dt, I, report):
    """Ship j's track after the step (updated in ``R``): predict, the nearest radar plot, then its AIS report."""
    known = R["trk_known"] > 0.5
    x = [R[k] for k in ("trk_x", "trk_y", "trk_vx", "trk_vy")]
    Pm = tracker.unpack([R[f"trk_p{i}{j}"] for i, j in tracker.UPPER])
    xp, Pp = tracker.predict(x, Pm, dt, I["tracker_q"])
    x, Pm = tracker.select(known, xp, x), tracker.select(known, Pp, Pm)
    d2, z, Rz = tracker.nearest(x, Pm, plots)
    xu, Pu = tracker.update(x, Pm, (0, 1), z, Rz)
    take = ca.logic_and(known, d2 <= I["tracker_gate"])
    x, Pm = tracker.select(take, xu, x), tracker.select(take, Pu, Pm)
    det, z0, R0 = plots[own_plot]
    start = ca.logic_and(ca.logic_not(known), det)  # a track starts at its target's first detection
    P0 = ca.diagcat(R0, SIGMA_V0 ** 2 * ca.DM.eye(2))
    x = tracker.select(start, [z0[0], z0[1], 0.0, 0.0], x)
    Pm = tracker.select(start, P0, Pm)
    known = ca.logic_or(known, start)
    if report is not None:
        got, za = report
        sp, sv, sc = I["ais_sigma_p"], I["ais_sigma_sog"], I["ais_sigma_cog"]
        Rp = sp * sp * ca.DM.eye(2)
        vx, vy = za[2], za[3]
        speed = ca.sqrt(vx * vx + vy * vy)
        ex, ey = vx / ca.fmax(speed, 1e-12), vy / ca.fmax(speed, 1e-12)
        a, b = sv * sv, (sc * speed) ** 2  # along and across the reported velocity
        Rv = ca.vertcat(ca.horzcat(a * ex * ex + b * ey * ey, (a - b) * ex * ey),
                        ca.horzcat((a - b) * ex * ey, a * ey * ey + b * ex * ex))
        x1, P1 = tracker.update(x, Pm, (0, 1), za[:2], Rp)
        x1, P1 = tracker.update(x1, P1, (2, 3), za[2:], Rv)
        x0 = za
        P0 = ca.diagcat(Rp, Rv)
        xa = tracker.select(known, x1, x0)
        Pa = tracker.select(known, P1, P0)
        x, Pm = tracker.select(got, xa, x), tracker.select(got, Pa, Pm)
        known = ca.logic_or(known, got)
    R.update(dict(zip(("trk_x", "trk_y", "trk_vx", "trk_vy"), x)))
    R["trk_known"] = ca.if_else(known, 1.0, 0.0)
    R.update({f"trk_p{i}{j}": v for (i, j), v in zip(tracker.UPPER, tracker.pack(Pm))})
    return x, known
