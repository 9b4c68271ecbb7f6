"""Desired-heading vector fields of the artificial potential field (APF) guidance (paper §4).

Conventions: positions in ship lengths L, velocities non-dimensional (L per unit non-dimensional time), x
forward/north, y to starboard/east, angles in rad measured from x towards y. The polar angle θ of a point about a
centre is atan2(dy, dx), with unit vectors e_r = (cos θ, sin θ) and e_θ = (−sin θ, cos θ); e_θ points clockwise
when drawn with x up and y to the right, so a vortex of negative strength K circulates counter-clockwise and
pushes a ship approaching it head-on to starboard.

Shapes: ``own_pos``, ``own_vel``, ``goal`` are 2×1; ``nb_pos``, ``nb_vel`` are 2×M (one column per neighbour,
velocities in the global frame); ``nb_radius`` and ``active`` are 1×M. ``active`` is the caller's 0/1 mask
(neighbour exists and lies within R_safe); every neighbour's contribution is multiplied by it. M may be 0. Each
field returns a 2×1 vector whose direction is the desired heading (see :func:`heading_of`).

Every function takes CasADi expressions (SX or MX) or plain numbers / numpy arrays / DM and returns CasADi
expressions (DM for numeric input); numeric parameters are arguments so they may be symbols, e.g. for tuning.
Distances used as divisors are clipped at ``R_MIN`` so that no field produces NaN or inf.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mmg_casadi.errors import ParameterError, check_range
from mmg_casadi.guidance.ilos import wrap_angle
from mmg_casadi.params import check_fields
from mmg_casadi.params import field as param_field

R_MIN = 1e-3
"""Smallest distance (L) used as a divisor; closer points are treated as being ``R_MIN`` away."""

_CASADI_TYPES = (ca.SX, ca.MX, ca.DM)
_ANY_REAL = dict(low=-math.inf, high=math.inf, low_open=True, high_open=True)


@dataclass(frozen=True)
class InverseSquareParams:
    """Inverse-square APF parameters (paper Table 3).

    ``k_att``: attractive gain (1/unit time, ≥ 0); ``k_rep``: repulsive gain (L³/unit time, ≥ 0); ``d0``:
    influence distance of an obstacle, measured from its rim (L, > 0). The paper does not state d0; the default
    8 L puts the stagnation point of its example (obstacle at (-10, 0), goal at (10, 0)) at 5.4 L from the
    obstacle, "around [-15, 0] ... merely 5L from the obstacle" as the paper reads it off its figure
    (d0 = R_safe = 15 L would put it at 6.2 L).

    Parameters
    ----------
    k_att : float
        Attractive gain (1/unit time, ≥ 0).
    k_rep : float
        Repulsive gain (L³/unit time, ≥ 0).
    d0 : float
        Influence distance of an obstacle from its rim (L, > 0).
    """

    k_att: float = param_field("k_att")
    k_rep: float = param_field("k_rep")
    d0: float = param_field("d0")

    def __post_init__(self):
        check_fields(self)


@dataclass(frozen=True)
class SinkVortexParams:
    """Sink-vortex APF parameters.

    ``lam_sink``: strength Λ of the sink at the goal (L²/unit time, < 0 so that it attracts); ``k_vor``: strength
    K of the vortex at every active neighbour (L²/unit time, any real; < 0 turns a head-on ship to starboard).

    Parameters
    ----------
    lam_sink : float
        Sink strength Λ at the goal (L²/unit time, < 0 attracts).
    k_vor : float
        Vortex strength K at every active neighbour (L²/unit time).
    """

    lam_sink: float = param_field("lam_sink")
    k_vor: float = param_field("k_vor")

    def __post_init__(self):
        check_fields(self)


@dataclass(frozen=True)
class ModifiedVortexParams:
    """Modified sink-vortex APF parameters.

    ``lam_sink``: sink strength Λ at the goal (L²/unit time, < 0); ``k_vor0``: nominal vortex strength K⁰_vor
    (L²/unit time, any real; the paper uses −10); ``r_safe``: detection radius R_safe, also the distance scale
    of the factor f (L, > 0); ``r_tol``: distance in the tangential-velocity threshold −2 R_tol v_r / d (L, ≥ 0).
    The paper writes R_tol there, but its laboratory code used the collision distance, 2 L, not the 3 L
    waypoint tolerance; 2 L is the default. ``gamma_max``: largest ``|γ|`` for which the vortex acts (rad,
    (0, π]); 5π/8 leaves the 112.5° stern sector (overtaking, stand-on) without vortex.

    Parameters
    ----------
    lam_sink : float
        Sink strength Λ at the goal (L²/unit time, < 0 attracts).
    k_vor0 : float
        Nominal vortex strength K⁰_vor (L²/unit time).
    r_safe : float
        Detection radius R_safe, the distance scale of the factor f (L, > 0).
    r_tol : float
        Distance in the tangential-velocity threshold (L, ≥ 0).
    gamma_max : float
        Largest ``|γ|`` for which the vortex acts (rad, in (0, π]).
    """

    lam_sink: float = param_field("lam_sink")
    k_vor0: float = param_field("k_vor0")
    r_safe: float = param_field("r_safe")
    r_tol: float = param_field("r_tol_vortex")
    gamma_max: float = param_field("gamma_max_deg", math.pi / 180.0)

    def __post_init__(self):
        check_fields(self)


@dataclass(frozen=True)
class WallParams:
    """Channel-wall (line source) parameters.

    ``lam``: source strength per wall (L²/unit time, ≥ 0, pushes away from the wall); ``d_act``: perpendicular
    distance below which a wall acts (L, > 0).

    Parameters
    ----------
    lam : float
        Source strength per wall (L²/unit time, ≥ 0).
    d_act : float
        Perpendicular distance below which a wall acts (L, > 0).
    """

    lam: float = param_field("wall_lam")
    d_act: float = param_field("wall_d_act")

    def __post_init__(self):
        check_fields(self)


def _matrix(x, rows):
    """``x`` as a CasADi matrix with ``rows`` rows (numbers, sequences and numpy arrays become DM)."""
    if isinstance(x, _CASADI_TYPES):
        return x if x.size1() == rows else ca.reshape(x, rows, x.numel() // rows)
    return ca.DM(np.asarray(x, dtype=float).reshape(rows, -1))


def _col2(x):
    """A 2-vector as a 2×1 CasADi column."""
    return _matrix(x, 2)


def _row(x, m):
    """A per-neighbour quantity as a 1×m row (a scalar is repeated)."""
    if isinstance(x, (int, float)) and not isinstance(x, bool):
        return ca.DM.ones(1, m) * float(x)
    x = _matrix(x, 1)
    return ca.repmat(x, 1, m) if x.numel() == 1 and m != 1 else x


def _strength(k, m):
    """A field strength: a Python number or CasADi scalar as is, anything else as a 1×m row."""
    if isinstance(k, (int, float)) and not isinstance(k, bool):
        return k
    if isinstance(k, _CASADI_TYPES) and k.numel() == 1:
        return k
    return _row(k, m)


def _bc2(row):
    """Repeat a 1×m row into two rows, to scale the columns of a 2×m matrix."""
    return ca.repmat(row, 2, 1)


def _offsets(pos, centres):
    """Offsets ``pos − centre`` (2×K), distances r (1×K) and distances clipped at ``R_MIN`` (1×K)."""
    d = ca.repmat(pos, 1, centres.size2()) - centres
    r = ca.sqrt(ca.sum1(d * d))
    return d, r, ca.fmax(r, R_MIN)


def _check_smooth(smooth):
    if smooth is None:
        return
    try:
        check_range("smooth", smooth, 0.0, None, low_open=True)
    except ParameterError:
        raise ParameterError("smooth", "None or a number in (0, inf)", smooth) from None


def _sigmoid(x, s):
    """Logistic function of ``s x``, written with tanh so it cannot overflow."""
    return 0.5 * (1 + ca.tanh(0.5 * s * x))


def _softplus(x, s):
    """log(1 + exp(s x)) / s, written as (max(s x, 0) + log1p(exp(−|s x|))) / s so it cannot overflow."""
    sx = s * x
    return (ca.fmax(sx, 0) + ca.log1p(ca.exp(-ca.fabs(sx)))) / s


def sink(pos, centre, lam):
    """Velocity of a source/sink of strength Λ, V = Λ / (2π r) e_r, at ``pos``.

    ``centre`` may hold K columns (K centres), giving one column per centre; ``lam`` is a scalar or 1×K.
    Λ < 0 (sink) points towards the centre.

    Parameters
    ----------
    pos : array_like or casadi.SX or casadi.MX
        Point (x, y) where the velocity is evaluated (L).
    centre : array_like or casadi.SX or casadi.MX
        Centre(s) of the source/sink, 2×K (L).
    lam : array_like or casadi.SX or casadi.MX
        Strength Λ, scalar or 1×K (L²/unit time).

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM (2, K)
        Velocity induced at ``pos`` by each centre (L per unit time L/U).

    Examples
    --------
    >>> import casadi as ca
    >>> v = sink(ca.DM([0, 10]), ca.DM([0, 0]), 2 * ca.pi)  # source: away from the centre
    >>> float(v[0]), round(float(v[1]), 6)
    (0.0, 0.1)
    >>> round(float(sink(ca.DM([0, 10]), ca.DM([0, 0]), -2 * ca.pi)[1]), 6)  # sink: towards it
    -0.1
    """
    pos, centre = _col2(pos), _matrix(centre, 2)
    m = centre.size2()
    d, _, rc = _offsets(pos, centre)
    return d * _bc2(_strength(lam, m) / (2 * ca.pi * rc * rc))  # eq. (Vsink equation), e_r = d / r


def vortex(pos, centre, k):
    """Velocity of a vortex of strength K, V = K / (2π r) e_θ, at ``pos``.

    ``centre`` may hold K columns, giving one column per centre; ``k`` is a scalar or 1×K. K < 0 circulates
    counter-clockwise (x up, y right), so a ship approaching the centre head-on is pushed to starboard.

    Parameters
    ----------
    pos : array_like or casadi.SX or casadi.MX
        Point (x, y) where the velocity is evaluated (L).
    centre : array_like or casadi.SX or casadi.MX
        Centre(s) of the vortex, 2×K (L).
    k : array_like or casadi.SX or casadi.MX
        Strength K, scalar or 1×K (L²/unit time).

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM (2, K)
        Velocity induced at ``pos`` by each centre (L per unit time L/U).

    Examples
    --------
    >>> import casadi as ca
    >>> v = vortex(ca.DM([0, 0]), ca.DM([25, 0]), -10.0)
    >>> float(v[0]), round(float(v[1]), 6)  # obstacle dead ahead: push to starboard (+y)
    (0.0, 0.063662)
    """
    pos, centre = _col2(pos), _matrix(centre, 2)
    m = centre.size2()
    d, _, rc = _offsets(pos, centre)
    e_th = ca.vertcat(-d[1, :], d[0, :])  # r e_θ = (−dy, dx)
    return e_th * _bc2(_strength(k, m) / (2 * ca.pi * rc * rc))  # eq. (Vvortex equation)


def inverse_square(own_pos, goal, nb_pos, nb_radius, active, *, k_att, k_rep, d0):
    """Negative gradient −∇φ of the inverse-square potential (attractive goal + repulsive obstacles).

    Implements the paper's expression literally: the attractive part is −k_att (X_n − X_g), i.e. the gradient
    of k_att/2 ‖X_n − X_g‖² (the paper's gradient drops the factor 2 of its φ_a = k_att ‖·‖²); the repulsive
    part is exactly −∇ of k_rep (1/ρ − 1/d0)² for ρ ≤ d0, else 0, with ρ = ‖X_n − X_o‖ − R_obs clipped at
    ``R_MIN``.

    Parameters
    ----------
    own_pos : array_like or casadi.SX or casadi.MX
        Own-ship position (x, y) (L).
    goal : array_like or casadi.SX or casadi.MX
        Goal position (x, y) (L).
    nb_pos : array_like or casadi.SX or casadi.MX
        Neighbour positions, 2×M, one column per neighbour (L).
    nb_radius : array_like or casadi.SX or casadi.MX
        1×M obstacle radii R_obs (L).
    active : array_like or casadi.SX or casadi.MX
        1×M flags, 1 where the neighbour is taken into account.
    k_att : float
        Attractive gain (1/unit time).
    k_rep : float
        Repulsive gain (L³/unit time).
    d0 : float
        Influence distance of an obstacle from its rim (L).

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM (2, 1)
        −∇φ at ``own_pos``, the field velocity whose direction is the desired heading (L per unit time L/U).

    Examples
    --------
    >>> import casadi as ca
    >>> v = inverse_square([0, 0], [10, 0], ca.DM([[5], [0]]), [0.5], [1], k_att=1.0, k_rep=0.0, d0=15.0)
    >>> v.T
    DM([[10, 0]])
    """
    own_pos, goal, nb_pos = _col2(own_pos), _col2(goal), _matrix(nb_pos, 2)
    m = nb_pos.size2()
    radius, active = _row(nb_radius, m), _row(active, m)
    att = -k_att * (own_pos - goal)  # eq. (grad_phi_inv_square), attractive part
    d, r, _ = _offsets(own_pos, nb_pos)
    rho = r - radius  # eq. (rho_xy)
    rho_c = ca.fmax(rho, R_MIN)
    gain = 2 * k_rep / (rho_c * rho_c * (rho_c + radius)) * (1 / rho_c - 1 / d0)  # eq. (grad_phi_inv_square)
    on = active * (rho <= d0)  # eq. (repulsive_potential)
    return att + ca.sum2(d * _bc2(on * gain))


def sink_vortex(own_pos, goal, nb_pos, active, *, lam_sink, k_vor):
    """Sink-vortex field: a sink of strength Λ at the goal plus a vortex of strength K at every active neighbour.

    Parameters
    ----------
    own_pos : array_like or casadi.SX or casadi.MX
        Own-ship position (x, y) (L).
    goal : array_like or casadi.SX or casadi.MX
        Goal position (x, y) (L).
    nb_pos : array_like or casadi.SX or casadi.MX
        Neighbour positions, 2×M, one column per neighbour (L).
    active : array_like or casadi.SX or casadi.MX
        1×M flags, 1 where the neighbour is taken into account.
    lam_sink : float
        Sink strength Λ at the goal (L²/unit time, < 0 attracts).
    k_vor : float
        Vortex strength K at every active neighbour (L²/unit time).

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM (2, 1)
        Field velocity at ``own_pos`` (L per unit time L/U).

    Examples
    --------
    >>> import casadi as ca
    >>> v = sink_vortex([0, 0], [50, 0], ca.DM([[25], [0]]), [1], lam_sink=-100.0, k_vor=-10.0)
    >>> float(v[0]) > 0, float(v[1]) > 0  # towards the goal, bent to starboard
    (True, True)
    """
    own_pos, goal, nb_pos = _col2(own_pos), _col2(goal), _matrix(nb_pos, 2)
    m = nb_pos.size2()
    active = _row(active, m)
    return sink(own_pos, goal, lam_sink) + ca.sum2(vortex(own_pos, nb_pos, active * k_vor))


def modified_vortex_terms(own_pos, own_psi, own_vel, nb_pos, nb_vel, *, k_vor0, r_safe, r_tol, gamma_max,
                          smooth=None):
    """Per-neighbour terms of the modified vortex (each a 1×M row).

    Returns a dict with ``gamma`` (relative bearing γ of the neighbour, (−π, π]), ``v_r`` and ``v_theta``
    (radial and tangential components of the neighbour's velocity relative to the own ship), ``d`` (distance),
    ``on`` (1 where the vortex acts), ``f`` (strength factor) and ``k_vor`` (vortex strength). The relative
    velocity V_rel = nb_vel − own_vel (global frame) is expressed in the own ship's body frame, V_b = R(ψ)ᵀ
    V_rel, and then rotated by γ onto the line of sight, so v_r < 0 means closing and v_θ > 0 means the
    neighbour draws to starboard. ``own_vel`` is the global velocity R(ψ) [u, v]ᵀ of the own ship.

    ``smooth``: None uses the exact switches of the paper. A positive number s replaces them by smooth
    surrogates for gradient-based tuning: every indicator 1(a > b) becomes the logistic σ(s (a − b)) and
    max(1, z) becomes 1 + softplus_s(z − 1), softplus_s(x) = log(1 + exp(s x)) / s (both overflow-safe); they
    tend to the exact switches as s → ∞ (s is in the units of the compared quantities, rad and L/unit time).

    Parameters
    ----------
    own_pos : array_like or casadi.SX or casadi.MX
        Own-ship position (x, y) (L).
    own_psi : float or casadi.SX or casadi.MX
        Own-ship heading ψ (rad).
    own_vel : array_like or casadi.SX or casadi.MX
        Own-ship global velocity R(ψ) [u, v]ᵀ (L per unit time L/U).
    nb_pos : array_like or casadi.SX or casadi.MX
        Neighbour positions, 2×M, one column per neighbour (L).
    nb_vel : array_like or casadi.SX or casadi.MX
        Neighbour global velocities, 2×M (L per unit time L/U).
    k_vor0 : float
        Nominal vortex strength K⁰_vor (L²/unit time).
    r_safe : float
        Detection radius R_safe, the distance scale of the factor f (L).
    r_tol : float
        Distance in the tangential-velocity threshold −2 R_tol v_r / d (L).
    gamma_max : float
        Largest relative bearing ``|γ|`` for which the vortex acts (rad).
    smooth : float or None, optional
        Sharpness of smooth surrogates of the switches; ``None`` for the exact ones.

    Returns
    -------
    dict
        ``gamma`` (rad), ``v_r``, ``v_theta`` (L per unit time L/U), ``d`` (L), ``on`` (0/1, or in (0, 1) when
        smoothed), ``f`` (≥ 1, dimensionless) and ``k_vor`` (L²/unit time), each 1×M.

    Examples
    --------
    >>> import casadi as ca
    >>> t = modified_vortex_terms([0, 0], 0.0, [1, 0], ca.DM([[25], [0.5]]), ca.DM.zeros(2, 1),
    ...                           k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=2.0)
    >>> round(float(t["v_r"]), 4), round(float(t["v_theta"]), 4), round(float(t["k_vor"]), 3)
    (-0.9998, 0.02, -13.328)
    """
    _check_smooth(smooth)
    own_pos, own_vel = _col2(own_pos), _col2(own_vel)
    nb_pos, nb_vel = _matrix(nb_pos, 2), _matrix(nb_vel, 2)
    m = nb_pos.size2()
    los = nb_pos - ca.repmat(own_pos, 1, m)
    d = ca.fmax(ca.sqrt(ca.sum1(los * los)), R_MIN)
    gamma = wrap_angle(ca.atan2(los[1, :], los[0, :]) - own_psi)  # eq. (gamma)
    v_rel = nb_vel - ca.repmat(own_vel, 1, m)  # eq. (rel_vel), global frame
    c, s = ca.cos(own_psi), ca.sin(own_psi)
    vb_x = c * v_rel[0, :] + s * v_rel[1, :]  # body frame: R(ψ)ᵀ V_rel
    vb_y = -s * v_rel[0, :] + c * v_rel[1, :]
    cg, sg = ca.cos(gamma), ca.sin(gamma)
    v_r = cg * vb_x + sg * vb_y
    v_theta = -sg * vb_x + cg * vb_y
    thr = -2 * r_tol * v_r / d  # eq. (modified_vortex), tangential threshold
    z = 2 - d / r_safe - v_r  # eq. (factor_f)
    if smooth is None:
        on = (v_theta <= thr) * (ca.fabs(gamma) <= gamma_max)
        f = ca.fmax(1, z)
    else:
        on = _sigmoid(thr - v_theta, smooth) * _sigmoid(gamma_max - ca.fabs(gamma), smooth)
        f = 1 + _softplus(z - 1, smooth)
    k_vor = on * f * k_vor0  # eq. (modified_vortex)
    return {"gamma": gamma, "v_r": v_r, "v_theta": v_theta, "d": d, "on": on, "f": f, "k_vor": k_vor}


def modified_vortex(own_pos, own_psi, own_vel, goal, nb_pos, nb_vel, active, *, lam_sink, k_vor0, r_safe, r_tol,
                    gamma_max, smooth=None):
    """Modified sink-vortex field: a sink at the goal plus, at every active neighbour, a vortex whose strength
    comes from :func:`modified_vortex_terms` (zero for neighbours drawing clear or astern).

    Parameters
    ----------
    own_pos : array_like or casadi.SX or casadi.MX
        Own-ship position (x, y) (L).
    own_psi : float or casadi.SX or casadi.MX
        Own-ship heading ψ (rad).
    own_vel : array_like or casadi.SX or casadi.MX
        Own-ship global velocity R(ψ) [u, v]ᵀ (L per unit time L/U).
    goal : array_like or casadi.SX or casadi.MX
        Goal position (x, y) (L).
    nb_pos : array_like or casadi.SX or casadi.MX
        Neighbour positions, 2×M, one column per neighbour (L).
    nb_vel : array_like or casadi.SX or casadi.MX
        Neighbour global velocities, 2×M (L per unit time L/U).
    active : array_like or casadi.SX or casadi.MX
        1×M flags, 1 where the neighbour is taken into account.
    lam_sink : float
        Sink strength Λ at the goal (L²/unit time, < 0 attracts).
    k_vor0 : float
        Nominal vortex strength K⁰_vor (L²/unit time).
    r_safe : float
        Detection radius R_safe, the distance scale of the factor f (L).
    r_tol : float
        Distance in the tangential-velocity threshold −2 R_tol v_r / d (L).
    gamma_max : float
        Largest relative bearing ``|γ|`` for which the vortex acts (rad).
    smooth : float or None, optional
        Sharpness of smooth surrogates of the switches; ``None`` for the exact ones.

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM (2, 1)
        Field velocity at ``own_pos`` (L per unit time L/U).

    Examples
    --------
    >>> import casadi as ca
    >>> kw = dict(lam_sink=-100.0, k_vor0=-10.0, r_safe=15.0, r_tol=2.0, gamma_max=2.0)
    >>> v = modified_vortex([0, 0], 0.0, [1, 0], [50, 0], ca.DM([[25], [5]]), ca.DM.zeros(2, 1), [1], **kw)
    >>> round(float(v[0]), 6), float(v[1])  # obstacle on the starboard bow: vortex off, pure sink
    (0.31831, 0.0)
    """
    own_pos, goal, nb_pos = _col2(own_pos), _col2(goal), _matrix(nb_pos, 2)
    m = nb_pos.size2()
    active = _row(active, m)
    terms = modified_vortex_terms(own_pos, own_psi, own_vel, nb_pos, nb_vel, k_vor0=k_vor0, r_safe=r_safe,
                                  r_tol=r_tol, gamma_max=gamma_max, smooth=smooth)
    return sink(own_pos, goal, lam_sink) + ca.sum2(vortex(own_pos, nb_pos, active * terms["k_vor"]))


def channel_walls(pos, wall_a, wall_b, *, lam, d_act):
    """Repulsion of straight channel walls (paper §5.2, narrow waterways), each a line source.

    Wall i is the segment from ``wall_a[:, i]`` to ``wall_b[:, i]`` (both 2×W; W may be 0, giving the zero
    vector). A wall acts when the foot of the perpendicular from ``pos`` lies on the segment and the
    perpendicular distance r is below ``d_act``; it then contributes V = Λ / (2π r) n (r clipped at ``R_MIN``),
    n the unit normal from the wall towards ``pos``.

    Parameters
    ----------
    pos : array_like or casadi.SX or casadi.MX
        Own-ship position (x, y) (L).
    wall_a : array_like or casadi.SX or casadi.MX
        Wall start points, 2×W (L).
    wall_b : array_like or casadi.SX or casadi.MX
        Wall end points, 2×W (L).
    lam : float
        Source strength per wall (L²/unit time).
    d_act : float
        Perpendicular distance below which a wall acts (L).

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM (2, 1)
        Sum of the acting walls' velocities at ``pos`` (L per unit time L/U; zero when none acts).

    Examples
    --------
    >>> import casadi as ca
    >>> v = channel_walls([10, 1], ca.DM([[0], [0]]), ca.DM([[50], [0]]), lam=2 * ca.pi, d_act=2.0)
    >>> v.T
    DM([[0, 1]])
    """
    pos, wall_a, wall_b = _col2(pos), _matrix(wall_a, 2), _matrix(wall_b, 2)
    w = wall_a.size2()
    ab = wall_b - wall_a
    ap = ca.repmat(pos, 1, w) - wall_a
    t = ca.sum1(ap * ab) / ca.fmax(ca.sum1(ab * ab), R_MIN**2)
    perp = ap - ab * _bc2(t)
    r = ca.sqrt(ca.sum1(perp * perp))
    rc = ca.fmax(r, R_MIN)
    on = (t >= 0) * (t <= 1) * (r < d_act)
    return ca.sum2(perp * _bc2(on * lam / (2 * ca.pi * rc * rc)))  # eq. (Vsink equation), line source, n = perp/r


def heading_of(vec):
    """Heading atan2(v_y, v_x) (rad) of a 2-vector, the desired heading ψ_d of a field.

    Parameters
    ----------
    vec : array_like or casadi.SX or casadi.MX
        2-vector (v_x, v_y), e.g. a field velocity.

    Returns
    -------
    casadi.SX or casadi.MX or casadi.DM
        Heading of ``vec`` (rad, in [-π, π]).

    Examples
    --------
    >>> round(float(heading_of([1.0, 1.0])), 6)
    0.785398
    """
    vec = _col2(vec)
    return ca.atan2(vec[1], vec[0])
