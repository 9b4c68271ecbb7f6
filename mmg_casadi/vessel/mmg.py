"""3-DOF MMG manoeuvring model in the prime-II system, as CasADi expressions, for every hull of the library.

State ``x = [u, v, r, x, y, psi, delta]`` (velocities over U_des, yaw rate in U_des/L, positions in L, angles in
rad); inputs: commanded rudder ``delta_c`` (rad) and propeller speed ``n_rpm`` (rev/min). The force model follows
the ship's ``hull_form``: ``'beta'`` is the laboratory's form spelled out in the header of ``data/kcs_mmg.toml``
(drift-angle hull polynomial, design-speed scaling, constant wake; the KCS), ``'yy2015'`` the standard form of
Yasukawa & Yoshimura (2015) spelled out in the header of ``data/kvlcc2_mmg.toml`` (the KVLCC2). Both share the
equations of motion: the ``'yy2015'`` hull forces returned here include the added-mass Coriolis terms
``m_y' v' r'`` and ``-m_x' u' r'``, as the ``'beta'`` coefficients fold them in.

With a disturbance input ``env = [V_c, beta_c, U_w, psi_w]`` (:mod:`mmg_casadi.vessel.environment`) the state's
``u, v`` are velocities RELATIVE TO THE WATER; the position kinematics add the current and the wind load is added
to the forces. Without it (the default) the model is the calm-water model, expression for expression.
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np

from mmg_casadi.errors import ParameterError
from mmg_casadi.vessel.actuators import steering_rate
from mmg_casadi.vessel.environment import NENV, Windage, current_kinematics, ground_velocity, wind_forces
from mmg_casadi.vessel.ship import ShipParams, SteeringParams, load_kcs, load_steering

#: The MMG state vector: surge, sway, yaw rate, position, heading, rudder angle (prime-II, rad).
STATE_NAMES = ("u", "v", "r", "x", "y", "psi", "delta")
INPUT_NAMES = ("delta_c", "n_rpm")
NX = len(STATE_NAMES)


def mass_matrix(ship: ShipParams) -> np.ndarray:
    """Rigid-body plus added mass matrix of eq. (mmg_nd).

    Parameters
    ----------
    ship : ShipParams
        Ship parameters.

    Returns
    -------
    numpy.ndarray (3, 3)
        Non-dimensional mass matrix of the surge, sway and yaw equations, ``[[m + m_x, 0, 0], [0, m + m_y, m x_G],
        [0, m x_G, I_zz + J_zz]]`` (prime-II).
    """
    m, xg = ship.m, ship.xG_nd
    return np.array([
        [m + ship.mx, 0.0, 0.0],
        [0.0, m + ship.my, m * xg],
        [0.0, m * xg, ship.Izz + ship.Jzz],
    ])


def _yy_kinematics(u, v, r):
    """Speed U', drift angle β and yaw rate r'' = r'/U' of the ``'yy2015'`` form (U' guarded away from 0)."""
    U = ca.sqrt(u**2 + v**2 + 1e-12)
    return U, ca.atan2(-v, u), r / U


def wake_factor(ship: ShipParams, u, v, r):
    """``1 - w_P`` at the propeller.

    ``'beta'``: constant. ``'yy2015'``: ``(1 - w_P0)(1 + (1 - exp(-C1|β_P|))(C2 - 1))`` with
    ``β_P = β - x_P' r''`` and C2 = ``C2_pos`` for β_P > 0, ``C2_neg`` otherwise (Yasukawa & Yoshimura 2015).

    Parameters
    ----------
    ship : ShipParams
        Ship parameters.
    u, v, r : float or casadi.SX or casadi.MX
        Non-dimensional surge, sway velocity and yaw rate (units of U_des, U_des/L).

    Returns
    -------
    float or casadi.SX or casadi.MX
        ``1 - w_P``, the fraction of the inflow speed that reaches the propeller (dimensionless); a float for the
        ``'beta'`` hull form.
    """
    if ship.hull_form != "yy2015":
        return 1.0 - ship.wP
    _, b, rr = _yy_kinematics(u, v, r)
    beta_P = b - ship.xP * rr
    C2 = ca.if_else(beta_P > 0, ship.C2_pos, ship.C2_neg)
    return (1.0 - ship.wP) * (1.0 + (1.0 - ca.exp(-ship.C1 * ca.fabs(beta_P))) * (C2 - 1.0))


def propeller_terms(ship: ShipParams, u, n_rpm, v=0.0, r=0.0):
    """Advance ratio J, thrust coefficient K_T and non-dimensional propeller thrust X_P'.

    ``J = u' U_des (1 - w_P)/(n D_P)``, ``K_T = k0 + k1 J + k2 J²``, ``X_P = (1 - t_P) ρ K_T n² D_P⁴`` over
    ½ρU_des²Ld; the wake is :func:`wake_factor`.

    Parameters
    ----------
    ship : ShipParams
        Ship parameters.
    u : float or casadi.SX or casadi.MX
        Non-dimensional surge velocity u' (units of U_des).
    n_rpm : float or casadi.SX or casadi.MX
        Propeller speed (rev/min).
    v, r : float or casadi.SX or casadi.MX, optional
        Sway velocity and yaw rate (the ``'yy2015'`` wake depends on them; straight running if omitted).

    Returns
    -------
    J : float or casadi.SX or casadi.MX
        Advance ratio (dimensionless).
    K_T : float or casadi.SX or casadi.MX
        Thrust coefficient (dimensionless).
    X_P : float or casadi.SX or casadi.MX
        Non-dimensional propeller thrust X_P' (prime-II).
    """
    n = n_rpm / 60.0
    J = u * ship.U_design * wake_factor(ship, u, v, r) / (n * ship.DP)
    KT = ship.k0 + ship.k1 * J + ship.k2 * J**2
    XP = (1.0 - ship.tP) * KT * n**2 * ship.DP**4 / (0.5 * ship.L * ship.d * ship.U_design**2)
    return J, KT, XP


def hull_forces(ship: ShipParams, u, v, r):
    """Hull forces X_H', Y_H', N_H' as polynomials in the drift angle β = atan2(-v', u') and r' (``'beta'``), or
    in v/U and rL/U times U² with the added-mass Coriolis terms (``'yy2015'``, see :func:`_hull_forces_yy`).

    Parameters
    ----------
    ship : ShipParams
        Ship parameters.
    u : float or casadi.SX or casadi.MX
        Non-dimensional surge velocity u' (units of U_des).
    v : float or casadi.SX or casadi.MX
        Non-dimensional sway velocity v' (units of U_des).
    r : float or casadi.SX or casadi.MX
        Non-dimensional yaw rate r' (rad per unit time L/U).

    Returns
    -------
    X_H : float or casadi.SX or casadi.MX
        Non-dimensional hull surge force X_H' (prime-II).
    Y_H : float or casadi.SX or casadi.MX
        Non-dimensional hull sway force Y_H' (prime-II).
    N_H : float or casadi.SX or casadi.MX
        Non-dimensional hull yaw moment N_H' (prime-II).
    """
    if ship.hull_form == "yy2015":
        return _hull_forces_yy(ship, u, v, r)
    b = ca.atan2(-v, u)
    XH = ship.X0 * u**2 + ship.Xbb * b**2 + ship.Xbr_minus_my * b * r + ship.Xrr * r**2 + ship.Xbbbb * b**4
    YH = (ship.Yb * b + ship.Yr_minus_mx * r + ship.Ybbb * b**3 + ship.Ybbr * b**2 * r + ship.Ybrr * b * r**2
          + ship.Yrrr * r**3)
    NH = (ship.Nb * b + ship.Nr * r + ship.Nbbb * b**3 + ship.Nbbr * b**2 * r + ship.Nbrr * b * r**2
          + ship.Nrrr * r**3)
    return XH, YH, NH


def _hull_forces_yy(ship: ShipParams, u, v, r):
    """Hull forces of the ``'yy2015'`` form in design-speed prime units, added-mass Coriolis terms included.

    With U' = √(u'² + v'²), Yasukawa & Yoshimura's ``X_H = ½ρLdU² X_H'(v/U, rL/U)`` becomes
    ``X_H' = -R_0' U'² + X_vv' v'² + X_vr' v' r' + X_rr' r'² + X_vvvv' v'⁴/U'²`` and
    ``Y_H' = (Y_v' v' + Y_r' r') U' + (Y_vvv' v'³ + Y_vvr' v'² r' + Y_vrr' v' r'² + Y_rrr' r'³)/U'`` (N_H' alike).
    """
    U, _, _ = _yy_kinematics(u, v, r)
    XH = (-ship.R0 * U**2 + ship.Xvv * v**2 + ship.Xvr * v * r + ship.Xrr * r**2 + ship.Xvvvv * v**4 / U**2
          + ship.my * v * r)
    YH = ((ship.Yv * v + ship.Yr * r) * U + (ship.Yvvv * v**3 + ship.Yvvr * v**2 * r + ship.Yvrr * v * r**2
                                             + ship.Yrrr * r**3) / U - ship.mx * u * r)
    NH = ((ship.Nv * v + ship.Nr * r) * U + (ship.Nvvv * v**3 + ship.Nvvr * v**2 * r + ship.Nvrr * v * r**2
                                             + ship.Nrrr * r**3) / U)
    return XH, YH, NH


def _rudder_inflow_yy(ship: ShipParams, u, v, r, uR):
    """Lateral rudder inflow v_R' = U' γ_R β_R, β_R = β - l_R' r'', γ_R switched on β_R (Yasukawa & Yoshimura)."""
    U, b, rr = _yy_kinematics(u, v, r)
    beta_R = b - ship.lR * rr
    gammaR = ca.if_else(beta_R > 0, ship.gammaR_pos, ship.gammaR_neg)
    vR = U * gammaR * beta_R
    return vR, ca.atan2(vR, uR)


def rudder_forces(ship: ShipParams, u, v, r, delta, n_rpm):
    """Rudder forces X_R', Y_R', N_R' and the rudder inflow (u_R', v_R', α_R).

    The propeller-slipstream factor is written as ``u'(1 + κ(√(1 + 8K_T/(πJ²)) - 1))
    = u'(1 - κ) + κ √(u'² + 8K_T (u'/J)²/π)`` so that it stays finite at u' = 0. The lateral inflow ``v_R'`` is
    ``γ_R (v' + l_R' r')`` for ``'beta'`` and Yasukawa & Yoshimura's ``U' γ_R β_R`` (opposite sign) for ``'yy2015'``.

    Parameters
    ----------
    ship : ShipParams
        Ship parameters.
    u : float or casadi.SX or casadi.MX
        Non-dimensional surge velocity u' (units of U_des).
    v : float or casadi.SX or casadi.MX
        Non-dimensional sway velocity v' (units of U_des).
    r : float or casadi.SX or casadi.MX
        Non-dimensional yaw rate r' (rad per unit time L/U).
    delta : float or casadi.SX or casadi.MX
        Rudder angle δ (rad).
    n_rpm : float or casadi.SX or casadi.MX
        Propeller speed (rev/min).

    Returns
    -------
    X_R : float or casadi.SX or casadi.MX
        Non-dimensional rudder surge force X_R' (prime-II).
    Y_R : float or casadi.SX or casadi.MX
        Non-dimensional rudder sway force Y_R' (prime-II).
    N_R : float or casadi.SX or casadi.MX
        Non-dimensional rudder yaw moment N_R' (prime-II).
    inflow : dict
        ``"uR"``, ``"vR"`` (rudder inflow velocities, units of U_des), ``"alphaR"`` (effective rudder angle, rad),
        ``"J"`` and ``"KT"`` (advance ratio and thrust coefficient of :func:`propeller_terms`).
    """
    J, KT, _ = propeller_terms(ship, u, n_rpm, v, r)
    one_minus_w = wake_factor(ship, u, v, r)
    u_over_J = (n_rpm / 60.0) * ship.DP / (ship.U_design * one_minus_w)
    slip = u * (1.0 - ship.kappa) + ship.kappa * ca.sqrt(u**2 + 8.0 * ca.fmax(KT, 0.0) * u_over_J**2 / math.pi)
    uR = ship.epsilon * one_minus_w * ca.sqrt(ship.eta * slip**2 + (1.0 - ship.eta) * u**2)
    if ship.hull_form == "yy2015":
        vR, inflow = _rudder_inflow_yy(ship, u, v, r, uR)
    else:
        b = ca.atan2(-v, u)
        beta_P = b - ship.xP * r
        gammaR = ca.if_else(beta_P > 0, ship.gammaR_pos, ship.gammaR_neg)  # flow straightening, asymmetric
        vR = gammaR * (v + ship.lR * r)
        inflow = ca.atan2(-vR, uR)
    UR2 = uR**2 + vR**2
    alphaR = delta - inflow
    FN = ship.AR_over_Ld * ship.f_alpha * UR2 * ca.sin(alphaR)
    XR = -(1.0 - ship.tR) * FN * ca.sin(delta)
    YR = -(1.0 + ship.aH) * FN * ca.cos(delta)
    NR = -(ship.xR + ship.aH * ship.xH) * FN * ca.cos(delta)
    return XR, YR, NR, {"uR": uR, "vR": vR, "alphaR": alphaR, "J": J, "KT": KT}


def mmg_rhs(ship: ShipParams, steering: SteeringParams, x, delta_c, n_rpm, env=None,
            windage: Windage | None = None):
    """Right-hand side ẋ of the MMG model with steering gear (CasADi expression, 7x1).

    Equations of motion # eq. (mmg_nd) with the forces of # eq. (tau), kinematics # eq. (kinematics) and the
    steering gear # eq. (delta_dot_equation). With ``env`` (4-vector ``[V_c, beta_c, U_w, psi_w]``) the wind
    load of ``windage`` (default :class:`~mmg_casadi.vessel.environment.Windage`) is added to the forces and the
    current to the kinematics; ``u, v`` are then velocities through the water.

    Parameters
    ----------
    ship : ShipParams
        Ship parameters.
    steering : SteeringParams
        Steering-gear parameters.
    x : casadi.SX or casadi.MX
        State vector (7) in :data:`STATE_NAMES` order (velocities in U_des, positions in L, angles rad).
    delta_c : float or casadi.SX or casadi.MX
        Commanded rudder angle (rad).
    n_rpm : float or casadi.SX or casadi.MX
        Propeller speed (rev/min).
    env : casadi.SX or casadi.MX or sequence, optional
        Disturbance ``[V_c, beta_c, U_w, psi_w]`` (speeds in U_des, directions rad); ``None`` for calm water.
    windage : Windage, optional
        Wind-load description; the default :class:`~mmg_casadi.vessel.environment.Windage` if ``None``.

    Returns
    -------
    casadi.SX or casadi.MX (7, 1)
        ``ẋ`` in :data:`STATE_NAMES` order: accelerations (U_des per L/U, rad per (L/U)²), velocities over ground
        (L per L/U) and yaw rate, rudder rate (rad per L/U).
    """
    u, v, r, psi, delta = x[0], x[1], x[2], x[5], x[6]
    XH, YH, NH = hull_forces(ship, u, v, r)
    _, _, XP = propeller_terms(ship, u, n_rpm, v, r)
    XR, YR, NR, _ = rudder_forces(ship, u, v, r, delta, n_rpm)
    m, xg = ship.m, ship.xG_nd
    X = XH + XP + XR + m * v * r + m * xg * r**2  # eq. (tau) + Coriolis terms of eq. (mmg_nd)
    Y = YH + YR - m * u * r
    N = NH + NR - m * xg * u * r
    if env is not None:
        u_g, v_g = ground_velocity(u, v, psi, env[0], env[1])
        XW, YW, NW = wind_forces(ship, windage or Windage(), u_g, v_g, psi, env[2], env[3])
        X, Y, N = X + XW, Y + YW, N + NW
    Minv = np.linalg.inv(mass_matrix(ship))
    acc = ca.mtimes(ca.DM(Minv), ca.vertcat(X, Y, N))
    xdot = u * ca.cos(psi) - v * ca.sin(psi)  # eq. (kinematics)
    ydot = u * ca.sin(psi) + v * ca.cos(psi)
    if env is not None:
        xdot_c, ydot_c = current_kinematics(env[0], env[1])
        xdot, ydot = xdot + xdot_c, ydot + ydot_c
    ddot = steering_rate(delta, delta_c, steering.T_delta, steering.rate_max_nd(ship), steering.delta_max)
    return ca.vertcat(acc, xdot, ydot, r, ddot)


def build_mmg(ship: ShipParams | None = None, steering: SteeringParams | None = None, *, disturbed: bool = False,
              windage: Windage | None = None) -> ca.Function:
    """Named CasADi Function ``mmg(x[7], delta_c, n_rpm) -> xdot[7]``, or with ``disturbed=True``
    ``mmg_env(x[7], delta_c, n_rpm, env[4]) -> xdot[7]`` with the disturbance ``env = [V_c, beta_c, U_w, psi_w]``
    as an input (see :mod:`mmg_casadi.vessel.environment`; ``windage`` defaults to the KCS estimate there).

    Parameters
    ----------
    ship : ShipParams, optional
        Ship parameters (default: the KCS).
    steering : SteeringParams, optional
        Steering gear (default: the KCS's).
    disturbed : bool, optional
        Add the disturbance input ``env``.
    windage : Windage, optional
        Wind-load description used when ``disturbed``.

    Returns
    -------
    casadi.Function
        ``mmg(x, delta_c, n_rpm) -> xdot``, or ``mmg_env(x, delta_c, n_rpm, env) -> xdot`` with ``disturbed``;
        ``xdot`` is :func:`mmg_rhs` (7x1).

    Examples
    --------
    >>> f = build_mmg()
    >>> xdot = f([1.0, 0, 0, 0, 0, 0, 0], 0.0, 115.5)
    >>> abs(float(xdot[0])) < 1e-3      # self-propulsion point: u' = 1 at 115.5 rpm
    True
    >>> fd = build_mmg(disturbed=True)
    >>> xdot = fd([1.0, 0, 0, 0, 0, 0, 0], 0.0, 115.5, [0.1, math.pi / 2, 0.0, 0.0])  # current to starboard
    >>> round(float(xdot[4]), 12)       # y_dot = the current
    0.1
    """
    ship = ship or load_kcs()
    steering = steering or load_steering()
    x = ca.SX.sym("x", NX)
    dc = ca.SX.sym("delta_c")
    n = ca.SX.sym("n_rpm")
    if not disturbed:
        return ca.Function("mmg", [x, dc, n], [mmg_rhs(ship, steering, x, dc, n)],
                           ["x", "delta_c", "n_rpm"], ["xdot"])
    env = ca.SX.sym("env", NENV)
    return ca.Function("mmg_env", [x, dc, n, env], [mmg_rhs(ship, steering, x, dc, n, env, windage)],
                       ["x", "delta_c", "n_rpm", "env"], ["xdot"])


def scene_scales(ship: ShipParams, unit: ShipParams) -> tuple[float, float]:
    """Length and speed ratios ``(λ, μ) = (L/L_unit, U_des/U_des,unit)`` of ``ship`` in a scene whose units are
    ``unit``'s length and design speed (its time unit is ``unit``'s L/U_des; ``λ/μ`` is the ship's time unit in it).

    Parameters
    ----------
    ship, unit : ShipParams
        The hull sailed and the hull whose L and U_des are the scene's units (a scenario's own ship).

    Returns
    -------
    tuple of float
        ``(λ, μ)``; ``(1.0, 1.0)`` exactly when both hulls have the same L and U_des.

    Examples
    --------
    >>> from mmg_casadi.vessel.library import load_vessel
    >>> lam, mu = scene_scales(load_vessel("kvlcc2").ship, load_vessel("kcs").ship)
    >>> round(lam, 4), round(mu, 4)
    (1.3913, 0.6458)
    """
    return ship.L / unit.L, ship.U_design / unit.U_design


def in_scene_units(f: ca.Function, ship: ShipParams, unit: ShipParams) -> ca.Function:
    """The model ``f`` (:func:`build_mmg` of ``ship``) with its state and time in the units of another hull.

    With ``(λ, μ) =`` :func:`scene_scales` and ``τ = λ/μ`` (the ship's time unit in scene time units), the scene
    state is ``S x`` with ``S = diag(μ, μ, 1/τ, λ, λ, 1, 1)`` (velocities in the scene's U, yaw rate per scene time,
    positions in the scene's L, angles unchanged) and ``ẋ_scene = S f(S⁻¹ x_scene, ...) / τ``. A disturbed
    model's current and wind speeds (``env[0]``, ``env[2]``, in the scene's U) are divided by μ. The ship sails
    exactly as in its own units: the same trajectory in metres and seconds (a test checks it).

    Parameters
    ----------
    f : casadi.Function
        ``mmg(x, delta_c, n_rpm)`` or ``mmg_env(x, delta_c, n_rpm, env)`` of ``ship``.
    ship, unit : ShipParams
        The hull of ``f`` and the hull whose L and U_des are the scene's units.

    Returns
    -------
    casadi.Function
        ``f`` itself when the two hulls have the same L and U_des, else a Function of the same inputs named
        ``<f>_scene``.
    """
    lam, mu = scene_scales(ship, unit)
    if lam == 1.0 and mu == 1.0:
        return f
    tau = lam / mu
    scale = ca.DM([mu, mu, 1.0 / tau, lam, lam, 1.0, 1.0])
    ins = [ca.SX.sym(f.name_in(k), f.size_in(k)) for k in range(f.n_in())]
    args = [ins[0] / scale, *ins[1:3]]
    if f.n_in() > 3:  # the disturbance: speeds in the ship's own U_des
        env = ins[3]
        args.append(ca.vertcat(env[0] / mu, env[1], env[2] / mu, env[3:]))
    xdot = scale * f(*args) / tau
    return ca.Function(f"{f.name()}_scene", ins, [xdot], [f.name_in(k) for k in range(f.n_in())], ["xdot"])


def rk4(f, x, args, h):
    """One classical Runge–Kutta step of ``ẋ = f(x, *args)`` with step ``h`` (inputs held over the step).

    Parameters
    ----------
    f : casadi.Function or callable
        Right-hand side ``f(x, *args)``.
    x : casadi.SX or casadi.MX or casadi.DM
        State at the start of the step.
    args : tuple
        Further inputs of ``f``, held constant over the step.
    h : float or casadi.SX or casadi.MX
        Step size (L/U).

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM
        State at the end of the step, ``x + h/6 (k1 + 2 k2 + 2 k3 + k4)``.
    """
    k1 = f(x, *args)
    k2 = f(x + 0.5 * h * k1, *args)
    k3 = f(x + 0.5 * h * k2, *args)
    k4 = f(x + h * k3, *args)
    return x + h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)


def build_rk4_step(f: ca.Function | None = None, n_sub: int = 1) -> ca.Function:
    """Fixed-step RK4 Function ``rk4_step(x, delta_c, n_rpm, dt) -> x_next`` with ``n_sub`` sub-steps.

    For a disturbed model (``build_mmg(disturbed=True)``) the Function is
    ``rk4_step_env(x, delta_c, n_rpm, dt, env) -> x_next``, the disturbance held over the step.

    Parameters
    ----------
    f : casadi.Function, optional
        Model from :func:`build_mmg` (default: the calm-water KCS model).
    n_sub : int, optional
        Number of RK4 sub-steps per step ``dt``.

    Returns
    -------
    casadi.Function
        ``rk4_step(x, delta_c, n_rpm, dt) -> x_next``, or ``rk4_step_env(x, delta_c, n_rpm, dt, env) -> x_next``
        for a disturbed model (``dt`` in L/U, ``x_next`` the 7-state after ``dt``).

    Examples
    --------
    >>> step = build_rk4_step()
    >>> xn = step([1.0, 0, 0, 0, 0, 0, 0], 0.0, 115.5, 0.25)
    >>> round(float(xn[3]), 3)      # 0.25 L travelled at u' = 1
    0.25
    >>> step_env = build_rk4_step(build_mmg(disturbed=True))
    >>> xn = step_env([1.0, 0, 0, 0, 0, 0, 0], 0.0, 115.5, 0.25, [0.1, 0.0, 0.0, 0.0])
    >>> round(float(xn[3]), 3)      # plus 0.1 x 0.25 L of following current
    0.275
    """
    f = f or build_mmg()
    x = ca.SX.sym("x", NX)
    dc, n, dt = ca.SX.sym("delta_c"), ca.SX.sym("n_rpm"), ca.SX.sym("dt")
    disturbed = f.n_in() == 4
    env = ca.SX.sym("env", NENV)
    args = (dc, n, env) if disturbed else (dc, n)
    h = dt / n_sub
    xn = x
    for _ in range(n_sub):
        xn = rk4(f, xn, args, h)
    if disturbed:
        return ca.Function("rk4_step_env", [x, dc, n, dt, env], [xn], ["x", "delta_c", "n_rpm", "dt", "env"],
                           ["x_next"])
    return ca.Function("rk4_step", [x, dc, n, dt], [xn], ["x", "delta_c", "n_rpm", "dt"], ["x_next"])


def build_cvodes(f: ca.Function | None = None, t_grid=None, *, reltol=1e-10, abstol=1e-10) -> ca.Function:
    """Adaptive CVODES integrator of the same model with constant inputs, outputs at ``t_grid``.

    Parameters ``p = [delta_c, n_rpm]``, or ``[delta_c, n_rpm, V_c, beta_c, U_w, psi_w]`` for a disturbed model.

    Parameters
    ----------
    f : casadi.Function, optional
        Model from :func:`build_mmg` (default: the calm-water KCS model).
    t_grid : sequence of float
        Output times (L/U).
    reltol : float, optional
        Relative tolerance of CVODES.
    abstol : float, optional
        Absolute tolerance of CVODES.

    Returns
    -------
    casadi.Function
        CasADi integrator ``cvodes_mmg``: called with ``x0`` (7) and ``p``, its output ``xf`` holds the state at each
        time of ``t_grid`` (7 x len(t_grid)).
    """
    f = f or build_mmg()
    x = ca.SX.sym("x", NX)
    disturbed = f.n_in() == 4
    p = ca.SX.sym("p", 2 + NENV if disturbed else 2)
    ode = f(x, p[0], p[1], p[2:]) if disturbed else f(x, p[0], p[1])
    dae = {"x": x, "p": p, "ode": ode}
    return ca.integrator("cvodes_mmg", "cvodes", dae, 0.0, list(t_grid),
                         {"reltol": reltol, "abstol": abstol, "max_num_steps": 100000})


@lru_cache(maxsize=8)
def _rpm_rootfinder(ship: ShipParams) -> ca.Function:
    n = ca.SX.sym("n_rpm")
    u = ca.SX.sym("u")
    XH, _, _ = hull_forces(ship, u, 0.0, 0.0)
    _, _, XP = propeller_terms(ship, u, n)
    g = ca.Function("surge_balance", [n, u], [XH + XP])
    return ca.rootfinder("rpm_for_speed", "newton", g, {"abstol": 1e-14})


def propeller_rpm_for_speed(speed: float, ship: ShipParams | None = None) -> float:
    """Propeller speed (rev/min) at which the ship's steady straight-line speed is ``speed`` × U_des.

    Solves the surge balance X_H(u', 0, 0) + X_P(u', n) = 0 for n with a CasADi Newton rootfinder.

    Parameters
    ----------
    speed : float
        Steady speed as a fraction of the design speed U_des (> 0).
    ship : ShipParams, optional
        Ship parameters (default: the KCS).

    Returns
    -------
    float
        Propeller speed (rev/min).

    Examples
    --------
    >>> round(propeller_rpm_for_speed(1.0), 1)
    115.5
    >>> round(propeller_rpm_for_speed(0.5) / propeller_rpm_for_speed(1.0), 4)
    0.5
    """
    ship = ship or load_kcs()
    if not speed > 0:
        raise ParameterError("speed", "a positive fraction of the design speed", speed)
    return float(_rpm_rootfinder(ship)(ship.n_design_rpm * speed, speed))


def linearise(state, inputs, ship: ShipParams | None = None, steering: SteeringParams | None = None, *,
              env=None, windage: Windage | None = None):
    """Exact Jacobians ``(A, B)`` of the model ``ẋ = f(x, u)`` at ``state`` (7) and ``inputs = [delta_c, n_rpm]``.

    The flow-straightening coefficient switches at β_P = 0; exactly on the switch (straight running) the
    starboard-side value γ_R⁻ is the one differentiated. With ``env = [V_c, beta_c, U_w, psi_w]`` (a sequence or
    an :class:`~mmg_casadi.vessel.environment.Environment`) the disturbed model is linearised, ``u, v`` being
    velocities through the water.

    Parameters
    ----------
    state : sequence of 7 floats
        ``[u, v, r, x, y, psi, delta]`` (prime-II).
    inputs : sequence of 2 floats
        ``[delta_c, n_rpm]`` (rad, rev/min).
    ship, steering : ShipParams, SteeringParams, optional
        Ship and steering gear (default: the KCS).
    env : sequence of 4 floats or Environment, optional
        Current and wind ``[V_c, beta_c, U_w, psi_w]``; calm water if omitted.
    windage : Windage, optional
        Projected areas for the wind load (default: the KCS estimate).

    Returns
    -------
    A : numpy.ndarray (7, 7)
        ``∂ẋ/∂x`` at the operating point (prime-II, per L/U).
    B : numpy.ndarray (7, 2)
        ``∂ẋ/∂[delta_c, n_rpm]`` at the operating point.

    Examples
    --------
    >>> A, B = linearise([1.0, 0, 0, 0, 0, 0, 0], [0.0, 115.5])
    >>> A.shape, B.shape
    ((7, 7), (7, 2))
    >>> A, _ = linearise([1.0, 0, 0, 0, 0, 0, 0], [0.0, 115.5], env=[0.1, 0.0, 0.0, 0.0])
    >>> round(float(A[4, 5]), 12)       # d(y_dot)/d(psi) = u through the water, the current adds none
    1.0
    """
    x = ca.SX.sym("x", NX)
    u = ca.SX.sym("u", 2)
    if env is None:
        xdot = build_mmg(ship, steering)(x, u[0], u[1])
        e = np.zeros(0)
    else:
        e = np.asarray(env.vector() if hasattr(env, "vector") else env, float).ravel()
        if e.size != NENV:
            raise ParameterError("env", f"{NENV} numbers [V_c, beta_c, U_w, psi_w]", e.size)
        xdot = build_mmg(ship, steering, disturbed=True, windage=windage)(x, u[0], u[1], ca.DM(e))
    jac = ca.Function("mmg_jacobians", [x, u], [ca.jacobian(xdot, x), ca.jacobian(xdot, u)])
    A, B = jac(np.asarray(state, float), np.asarray(inputs, float))
    return np.array(A), np.array(B)
