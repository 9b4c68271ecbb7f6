"""The optimal control problem of ``nmpc`` and its solver (CasADi ``sqpmethod`` with ``qrqp``, code-generated).

**Problem.** Over a horizon of ``N`` intervals of ``h`` (L/U) the own ship's rudder commands ``δ_c,0..N-1`` and
``B`` propeller commands ``ν_c`` (n/n_design, each held over ``N/B`` intervals) are chosen; the state follows the
prediction model of :mod:`mmg_casadi.guidance.nmpc_model` (RK4, two sub-steps per interval) from the present state,
and the targets their present velocity. Single shooting: the only decision variables are the commands, so every
constraint of the problem is a bound on them (``|δ_c| ≤ δ_max``, ``ν_min ≤ ν_c ≤ ν_max``) and every other
requirement is a **soft constraint**, a penalty on its violation, written as a residual of a least-squares cost
``½ Σ ρ_i²``:

* route: ``(cos ψ_k, sin ψ_k) − e_k`` with ``e_k`` the unit line of sight from the predicted position to the
  waypoint (weight ``w_route``); effort: ``δ_c,k`` (``w_rudder``), ``δ_c,k − δ_c,k−1`` (``w_rate``), ``ν_c − ν_ref``
  (``w_speed``);
* separation from each target ship ``j`` predicted at constant velocity: ``sp(d_pass,j − d_kj)`` (``w_pass``) and
  ``sp(d_close,j − d_kj)`` (``w_close``), with ``sp(x) = σ log(1 + e^{x/σ})`` a smooth ``max(0, x)`` of scale σ
  (:data:`SP_DIST`); each is switched per target and limited to the nodes before ``t_lim,j`` (a smooth step); static
  obstacles ``sp(r_clear − d)`` (``w_close``); land and walls ``sp(clearance − dist(p_k, segment))`` (``w_land``);
* COLREG (weight ``w_colreg``, each switched per target and active while the target is still closing, a smooth
  step in ``r·v_rel``): a give-way ship keeps her heading to starboard of ``ψ_min`` (her heading at the onset plus
  the planner's alteration), ``sp(ψ_min − ψ_k)``; a stand-on ship holds her course and speed, ``ψ_k − ψ_hold`` and
  ``ν_c − ν_ref`` at every node (while any of her stand-on encounters holds); a stand-on ship that acts does not turn to port of her course, ``sp(ψ_hold − ψ_k)``; and, while
  the own ship is ahead of a target along the target's course (a smooth step), she stays on her side of that
  course line, ``sp(−s ℓ)`` with ``ℓ`` her lateral offset and ``s`` its sign now (Rules 13 and 15: a give-way or
  overtaking ship does not cross ahead).

**Solver.** ``sqpmethod`` with the QP solver ``qrqp``, the combination CasADi generates C code for, so the solve is
part of the compiled closed-loop step (:mod:`mmg_casadi.guidance.nmpc`). The Hessian is the Gauss–Newton one
``JᵀJ`` of the residuals with Levenberg–Marquardt damping (:data:`MARQUARDT`, positive definite): each QP is a
convex box-constrained QP of ``N + B`` variables. The residuals' Jacobian is chained interval by interval in MX
(forward sensitivities), so the generated code grows with ``N``. Tolerances and the iteration cap are :data:`SOLVER_OPTIONS`. The wrapper
:func:`solver_function` returns, beside the solution, the cost at the starting plan and at the solution and the
solution's projected-gradient norm, from which the planner judges whether a solve failed.

Examples
--------
>>> shape = OcpShape("kcs", "kcs", horizon=4, ships=1, obstacles=0, land=0, blocks=1)
>>> layout_p = param_layout(shape)
>>> layout_p["ships"].stop - layout_p["ships"].start
13
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import casadi as ca

from mmg_casadi.guidance.nmpc_model import NX, reduced_model

SP_DIST = 0.5
"""Scale σ (L) of the smooth ``max(0, x)`` of the distance penalties."""
SP_ANGLE = 0.05
"""Scale σ (rad) of the smooth ``max(0, x)`` of the heading penalties."""
CLOSING_SCALE = 2.0
"""Scale of the smooth step in ``r·v_rel`` (L²/(L/U)) that tells a closing target from an opening one."""
WINDOW_SCALE = 0.5
"""Scale (L/U) of the smooth step that ends a target's separation penalties at ``t_lim``."""
HESSIAN_REGULARISATION = 1e-4
"""Added to the Gauss–Newton Hessian's diagonal, so each QP is strictly convex."""
MARQUARDT = 0.1
"""Levenberg–Marquardt damping: the Hessian is ``JᵀJ + μ diag(JᵀJ) + 10⁻⁴ I`` with this ``μ``. Undamped, a
Gauss–Newton step of a near passing (curvature the model ignores) often led nowhere: of 271 solves re-posed from
environment 5 run 32 (a close-quarters situation), 49 ended worse than their start, 9 with this damping."""
SOLVER_OPTIONS = {"max_iter": 10, "tol_pr": 1e-6, "tol_du": 1e-2, "min_step_size": 1e-10, "max_iter_ls": 10,
                  "merit_memory": 1}
"""``sqpmethod`` options: at most ``max_iter`` SQP iterations per solve (the planner's ``nmpc_max_iter``; a solve that
reaches it returns its last iterate, which the next step's solve continues from), stationarity to 1e-2 (the cost is
O(1) per interval), no primal tolerance to speak of (the only constraints are bounds), and a monotone line search of
up to ten halvings: the Gauss–Newton step of a strongly curved residual (a near passing) often overshoots, and
sqpmethod's default (three halvings, then the step is taken anyway, non-monotone over four iterations) returned a
plan worse than its start in 36 of 331 solves re-posed from environment 5 (none with these options)."""
WEIGHTS = ("route", "rudder", "rate", "speed", "pass", "close", "colreg", "land", "hold")
"""The weights of the cost, in the order of the parameter vector."""
SHIP_FIELDS = ("px", "py", "vx", "vy", "d_pass", "d_close", "a_pass", "a_close", "t_lim", "give_way",
               "starboard", "no_ahead", "side")
"""Per target ship: relative position (L), velocity (U), the two separation distances (L), their switches (0/1),
the end of its separation penalties (L/U), its COLREG switches (give-way alteration, stand-on acting to starboard
only, no crossing ahead of her) and the side of her course line the own ship is on (+1 starboard,
−1 port)."""


@dataclass(frozen=True)
class OcpShape:
    """The structure of one planner's problem (what changes the compiled code).

    Parameters
    ----------
    vessel, unit : str
        The own hull and the scene's unit hull.
    horizon : int
        Intervals ``N``.
    ships, obstacles, land : int
        Target-ship slots, static-obstacle slots and land/wall segment slots.
    blocks : int
        Propeller commands over the horizon (``N`` a multiple of it).
    """

    vessel: str
    unit: str
    horizon: int
    ships: int
    obstacles: int
    land: int
    blocks: int

    def key(self) -> str:
        """Short identifier for Function names.

        Returns
        -------
        str
            Hulls, horizon, slots and blocks, e.g. ``kcs_kcs_n20_k4_s2_w0_b4``.
        """
        return (f"{self.vessel}_{self.unit}_n{self.horizon}_k{self.ships}_s{self.obstacles}_w{self.land}"
                f"_b{self.blocks}")

    @property
    def n_w(self) -> int:
        """Decision variables: ``N`` rudder commands, then ``B`` propeller commands."""
        return self.horizon + self.blocks


def param_layout(shape: OcpShape) -> dict:
    """The slices of the problem's parameter vector, by name.

    Parameters
    ----------
    shape : OcpShape
        The problem's structure.

    Returns
    -------
    dict
        ``state`` (7: [x, y, ψ, r, δ, u, ν] with the own ship at the origin), ``goal`` (2, relative), ``h``,
        ``engine`` (lag, rate), ``nu_ref``, ``weights`` (:data:`WEIGHTS`), ``colreg`` (ψ_min, ψ_hold, hold: 1 while a
        stand-on encounter holds the course and speed),
        ``clearance`` (land), ``ships`` (:data:`SHIP_FIELDS` per slot), ``obstacles`` (x, y, r_clear, on per slot),
        ``land`` (ax, ay, bx, by, on per slot), and ``size``.
    """
    sizes = [("state", NX), ("goal", 2), ("h", 1), ("engine", 2), ("nu_ref", 1), ("weights", len(WEIGHTS)),
             ("colreg", 3), ("clearance", 1), ("ships", len(SHIP_FIELDS) * shape.ships),
             ("obstacles", 4 * shape.obstacles), ("land", 5 * shape.land)]
    out, i = {}, 0
    for name, n in sizes:
        out[name] = slice(i, i + n)
        i += n
    out["size"] = i
    return out


def _sp(x, scale):
    """Smooth ``max(0, x)``: ``scale log(1 + exp(x/scale))``, evaluated without overflow."""
    z = x / scale
    return scale * (ca.fmax(z, 0) + ca.log1p(ca.exp(-ca.fabs(z))))


def _step(x, scale):
    """Smooth step from 0 (x ≪ 0) to 1 (x ≫ 0)."""
    return 0.5 * (1 + ca.tanh(x / scale))


def _segment_distance(p, a, b):
    ab = b - a
    t = ca.fmin(ca.fmax(ca.dot(p - a, ab) / ca.fmax(ca.dot(ab, ab), 1e-9), 0.0), 1.0)
    return ca.sqrt(ca.sumsqr(p - (a + t * ab)) + 1e-9)


def _interval(model, shape: OcpShape) -> ca.Function:
    """One interval of the prediction (RK4, two sub-steps, commands held) and its Jacobians ``A = ∂s⁺/∂s``,
    ``B = ∂s⁺/∂[δ_c, ν_c]``."""
    s, dc, nc, h = ca.SX.sym("s", NX), ca.SX.sym("dc"), ca.SX.sym("nc"), ca.SX.sym("h")
    lag, rate = ca.SX.sym("lag"), ca.SX.sym("rate")
    x = s
    hh = h / 2
    for _ in range(2):
        k1 = model.rhs(x, dc, nc, lag, rate)
        k2 = model.rhs(x + hh / 2 * k1, dc, nc, lag, rate)
        k3 = model.rhs(x + hh / 2 * k2, dc, nc, lag, rate)
        k4 = model.rhs(x + hh * k3, dc, nc, lag, rate)
        x = x + hh / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    u = ca.vertcat(dc, nc)
    ins = [s, dc, nc, h, lag, rate]
    key = shape.key()
    return (ca.Function(f"nmpc_interval_{key}", ins, [x], {"cse": True}),
            ca.Function(f"nmpc_interval_jac_{key}", ins, [x, ca.jacobian(x, s), ca.jacobian(x, u)], {"cse": True}))


def _node(shape: OcpShape, n_p: int) -> ca.Function:
    """The residuals of one node (the state after interval k, its rudder command and the one before, the time)
    and their Jacobians with respect to the state and the two commands."""
    lay = param_layout(shape)
    K = shape.ships
    s, dk, dp, t = ca.SX.sym("s", NX), ca.SX.sym("dk"), ca.SX.sym("dp"), ca.SX.sym("t")
    p = ca.SX.sym("p", n_p)
    goal = p[lay["goal"]]
    wt = {k: ca.sqrt(ca.fmax(p[lay["weights"]][i], 0)) for i, k in enumerate(WEIGHTS)}
    psi_min, psi_hold, hold = p[lay["colreg"]][0], p[lay["colreg"]][1], p[lay["colreg"]][2]
    clearance = p[lay["clearance"]][0]
    ships = ca.reshape(p[lay["ships"]], len(SHIP_FIELDS), K) if K else ca.SX(len(SHIP_FIELDS), 0)
    obst = ca.reshape(p[lay["obstacles"]], 4, shape.obstacles) if shape.obstacles else ca.SX(4, 0)
    land = ca.reshape(p[lay["land"]], 5, shape.land) if shape.land else ca.SX(5, 0)
    f = {name: i for i, name in enumerate(SHIP_FIELDS)}
    pos, psi, u = s[0:2], s[2], s[5]
    to_goal = goal - pos
    e = to_goal / ca.sqrt(ca.sumsqr(to_goal) + 1.0)
    res = [wt["route"] * (ca.cos(psi) - e[0]), wt["route"] * (ca.sin(psi) - e[1]),  # route
           wt["rudder"] * dk, wt["rate"] * (dk - dp),  # effort
           wt["hold"] * hold * (psi - psi_hold)]  # a stand-on ship holds her course
    vel = ca.vertcat(u * ca.cos(psi), u * ca.sin(psi))
    for j in range(K):
        q = ships[f["px"]:f["py"] + 1, j] + t * ships[f["vx"]:f["vy"] + 1, j]
        rel = pos - q
        dist = ca.sqrt(ca.sumsqr(rel) + 1e-6)
        window = _step(ships[f["t_lim"], j] - t, WINDOW_SCALE)
        closing = _step(-ca.dot(rel, vel - ships[f["vx"]:f["vy"] + 1, j]), CLOSING_SCALE)
        c_j = ships[f["vx"]:f["vy"] + 1, j] / ca.sqrt(ca.sumsqr(ships[f["vx"]:f["vy"] + 1, j]) + 1e-9)
        along = ca.dot(rel, c_j)  # ahead of her (> 0) along her course
        lateral = c_j[0] * rel[1] - c_j[1] * rel[0]  # > 0: on the starboard side of her course line
        res += [wt["colreg"] * ships[f["no_ahead"], j] * _step(along, 1.0)
                * _sp(-ships[f["side"], j] * lateral, SP_DIST)]
        res += [wt["pass"] * ships[f["a_pass"], j] * window * _sp(ships[f["d_pass"], j] - dist, SP_DIST),
                wt["close"] * ships[f["a_close"], j] * window * _sp(ships[f["d_close"], j] - dist, SP_DIST),
                wt["colreg"] * ships[f["give_way"], j] * closing * _sp(psi_min - psi, SP_ANGLE),
                wt["colreg"] * ships[f["starboard"], j] * closing * _sp(psi_hold - psi, SP_ANGLE)]
    for j in range(shape.obstacles):
        dist = ca.sqrt(ca.sumsqr(pos - obst[0:2, j]) + 1e-6)
        res.append(wt["close"] * obst[3, j] * _sp(obst[2, j] - dist, SP_DIST))
    for j in range(shape.land):
        dist = _segment_distance(pos, land[0:2, j], land[2:4, j])
        res.append(wt["land"] * land[4, j] * _sp(clearance - dist, SP_DIST))
    r = ca.vertcat(*res)
    ins, key = [s, dk, dp, t, p], shape.key()
    return (ca.Function(f"nmpc_node_{key}", ins, [r], {"cse": True}),
            ca.Function(f"nmpc_node_jac_{key}", ins, [r, ca.jacobian(r, s), ca.jacobian(r, dk), ca.jacobian(r, dp)],
                        {"cse": True}))


def rollout(shape: OcpShape):
    """The predicted states ``(7, N+1)`` for the commands ``w`` and parameters ``p``.

    Parameters
    ----------
    shape : OcpShape
        The problem's structure.

    Returns
    -------
    casadi.Function
        ``nmpc_rollout_<key>(w, p) -> S``.
    """
    return _problem(shape)["rollout"]


@functools.lru_cache(maxsize=None)
def _problem(shape: OcpShape) -> dict:
    """The residuals and their Jacobian (forward sensitivities chained interval by interval, so the generated
    code grows with ``N``, not ``N²``) and the rollout of ``shape`` as MX Functions."""
    model = reduced_model(shape.vessel, shape.unit)
    lay = param_layout(shape)
    N, B, n_w = shape.horizon, shape.blocks, shape.n_w
    (interval, interval_jac), (node, node_jac) = _interval(model, shape), _node(shape, lay["size"])
    w = ca.MX.sym("w", n_w)
    p = ca.MX.sym("p", lay["size"])
    h = p[lay["h"]][0]
    lag, rate = p[lay["engine"]][0], p[lay["engine"]][1]
    nu_ref = p[lay["nu_ref"]][0]
    wt_speed = ca.sqrt(ca.fmax(p[lay["weights"]][WEIGHTS.index("speed")], 0))
    wt_colreg = ca.sqrt(ca.fmax(p[lay["weights"]][WEIGHTS.index("hold")], 0))
    hold_speed = p[lay["colreg"]][2]  # a stand-on ship holds her speed too
    speed_res = [r for j in range(B) for r in (wt_speed * (w[N + j] - nu_ref),
                                               wt_colreg * hold_speed * (w[N + j] - nu_ref))]
    # the cost's residuals alone (what the solver differentiates for the gradient) ...
    s = p[lay["state"]]
    states, res = [s], []
    for k in range(N):
        s = interval(s, w[k], w[N + (k * B) // N], h, lag, rate)
        states.append(s)
        res.append(node(s, w[k], w[k - 1] if k else p[lay["state"]][4], (k + 1) * h, p))
    R = ca.vertcat(*res, *speed_res)
    # ... and with their Jacobian, chained interval by interval (the Gauss-Newton Hessian's)
    s = p[lay["state"]]
    sens = ca.MX(NX, n_w)  # ∂s/∂w
    res, jac = [], []
    for k in range(N):
        b = N + (k * B) // N
        s, A, Bk = interval_jac(s, w[k], w[b], h, lag, rate)
        sel = ca.DM(2, n_w)
        sel[0, k], sel[1, b] = 1.0, 1.0
        sens = ca.mtimes(A, sens) + ca.mtimes(Bk, sel)
        r, js, jdk, jdp = node_jac(s, w[k], w[k - 1] if k else p[lay["state"]][4], (k + 1) * h, p)
        e_k = ca.DM(1, n_w)
        e_k[0, k] = 1.0
        jk = ca.mtimes(js, sens) + ca.mtimes(jdk, e_k)
        if k:
            e_p = ca.DM(1, n_w)
            e_p[0, k - 1] = 1.0
            jk = jk + ca.mtimes(jdp, e_p)
        res.append(r)
        jac.append(jk)
    for j in range(B):
        e_b = ca.DM(1, n_w)
        e_b[0, N + j] = 1.0
        jac += [wt_speed * e_b, wt_colreg * hold_speed * e_b]
    RJ, J = ca.vertcat(*res, *speed_res), ca.vertcat(*jac)
    key = shape.key()
    return {"residuals": ca.Function(f"nmpc_residuals_{key}", [w, p], [RJ, J], ["w", "p"], ["r", "jac"]),
            "cost": ca.Function(f"nmpc_cost_{key}", [w, p], [R], ["w", "p"], ["r"]),
            "rollout": ca.Function(f"nmpc_rollout_{key}", [w, p], [ca.horzcat(*states)], ["w", "p"], ["s"]),
            "n_r": R.numel(), "n_p": lay["size"]}


@functools.lru_cache(maxsize=None)
def nlp_solver(shape: OcpShape, max_iter: int = SOLVER_OPTIONS["max_iter"]) -> ca.Function:
    """The ``sqpmethod`` solver of ``shape`` (Gauss–Newton Hessian, ``qrqp``), an ``nlpsol`` Function.

    Parameters
    ----------
    shape : OcpShape
        The problem's structure.
    max_iter : int, optional
        SQP iteration cap.

    Returns
    -------
    casadi.Function
        ``nlpsol`` with inputs ``x0, p, lbx, ubx`` (no constraints ``g``).
    """
    pr = _problem(shape)
    w = ca.MX.sym("w", shape.n_w)
    p = ca.MX.sym("p", pr["n_p"])
    r = pr["cost"](w, p)
    _, jac = pr["residuals"](w, p)
    f = 0.5 * ca.dot(r, r)
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", 0)
    jj = ca.mtimes(jac.T, jac)
    hess = lam_f * (jj + MARQUARDT * ca.diag(ca.diag(jj)) + HESSIAN_REGULARISATION * ca.MX.eye(shape.n_w))
    hess_fn = ca.Function("nlp_hess_l", [w, p, lam_f, lam_g], [ca.densify(hess)],
                          ["x", "p", "lam_f", "lam_g"], ["hess_gamma_x_x"])
    opts = {"qpsol": "qrqp", "hess_lag": hess_fn, "print_time": False, "print_header": False,
            "print_iteration": False, "print_status": False, "error_on_fail": False,
            "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False,
                              "error_on_fail": False},
            **{**SOLVER_OPTIONS, "max_iter": int(max_iter)}}
    return ca.nlpsol(f"nmpc_sqp_{shape.key()}_i{int(max_iter)}", "sqpmethod", {"x": w, "p": p, "f": f}, opts)


@functools.lru_cache(maxsize=None)
def solver_function(shape: OcpShape, max_iter: int = SOLVER_OPTIONS["max_iter"]) -> ca.Function:
    """``nmpc_solve_<key>(w0, p, lbw, ubw) -> (w, f0, f, kkt)``: the solve and what tells a failed one.

    ``f0`` and ``f`` are the cost at the starting plan and at the solution, ``kkt`` the infinity norm of the
    solution's projected gradient ``w − clip(w − ∇f, lbw, ubw)`` (0 at a stationary point).

    Parameters
    ----------
    shape : OcpShape
        The problem's structure.
    max_iter : int, optional
        SQP iteration cap.

    Returns
    -------
    casadi.Function
        An MX Function that CasADi generates C code for (``sqpmethod`` + ``qrqp``).
    """
    pr = _problem(shape)
    S = nlp_solver(shape, max_iter)
    w0, p = ca.MX.sym("w0", shape.n_w), ca.MX.sym("p", pr["n_p"])
    lb, ub = ca.MX.sym("lbw", shape.n_w), ca.MX.sym("ubw", shape.n_w)
    sol = S(x0=w0, p=p, lbx=lb, ubx=ub)
    w = sol["x"]
    r0 = pr["cost"](w0, p)
    r, jac = pr["residuals"](w, p)
    grad = ca.mtimes(jac.T, r)
    kkt = ca.mmax(ca.fabs(w - ca.fmin(ca.fmax(w - grad, lb), ub)))
    return ca.Function(f"nmpc_solve_{shape.key()}_i{int(max_iter)}", [w0, p, lb, ub],
                       [w, 0.5 * ca.dot(r0, r0), 0.5 * ca.dot(r, r), kkt], ["w0", "p", "lbw", "ubw"],
                       ["w", "f0", "f", "kkt"], {"never_inline": True})
