"""Stagnation points of the APF guidance fields (where the desired-heading vector field vanishes).

The fields of :mod:`mmg_casadi.guidance.fields` are evaluated for one ship at a free position ``pos`` and one static
obstacle, as a CasADi Function ``pos -> V(pos)``; a stagnation point is a root of V found with CasADi's Newton
``rootfinder`` from an initial guess. The paper's example (obstacle at (−10, 0) L of radius 0.5 L, goal at
(10, 0) L, inverse-square k_att = 50, k_rep = 200 000) has its stagnation point on the axis behind the obstacle,
"around [−15, 0] ... merely 5 L from the obstacle"; with the package's influence distance d0 = 8 L it is at
5.4 L.

For the modified sink-vortex the field also depends on the ship's heading and velocity (the vortex acts only on
obstacles ahead that are not drawing clear); ``heading`` (rad) and ``speed`` (fraction of the design speed)
fix them for the whole plane, as for the paper's field plots (ship heading +x towards the goal).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.guidance.fields import (InverseSquareParams, ModifiedVortexParams, SinkVortexParams, inverse_square,
                               modified_vortex, sink_vortex)

_DEFAULTS = {
    "inverse-square": {"k_att": InverseSquareParams.k_att, "k_rep": InverseSquareParams.k_rep,
                       "d0": InverseSquareParams.d0},
    "sink-vortex": {"lam_sink": SinkVortexParams.lam_sink, "k_vor": SinkVortexParams.k_vor},
    "modified-vortex": {"lam_sink": ModifiedVortexParams.lam_sink, "k_vor0": ModifiedVortexParams.k_vor0,
                        "r_safe": ModifiedVortexParams.r_safe, "r_tol": ModifiedVortexParams.r_tol,
                        "gamma_max": ModifiedVortexParams.gamma_max, "heading": 0.0, "speed": 1.0,
                        "smooth": None},
}
"""Field parameters by field: the defaults of the parameter dataclasses (themselves the table's), plus the
ship's heading, speed and the smoothing for the modified vortex's plane."""
FIELDS = tuple(_DEFAULTS)


def field_params(field: str, **params) -> dict:
    """Defaults of ``field`` updated with ``params`` (unknown names raise :class:`InputError`).

    Parameters
    ----------
    field : {"inverse-square", "sink-vortex", "modified-vortex"}
        The field.
    **params
        Overrides of its parameters by name (the keys of the returned dict).

    Returns
    -------
    dict
        Parameter name to value: the field's defaults with ``params`` applied.
    """
    if field not in FIELDS:
        raise InputError("field", f"one of: {', '.join(FIELDS)}", field)
    out = dict(_DEFAULTS[field])
    for k, v in params.items():
        if k not in out:
            raise InputError(k, f"a parameter of the {field} field: {', '.join(out)}", k)
        out[k] = v
    return out


def field_function(field: str = "inverse-square", goal=(10.0, 0.0), obstacle=(-10.0, 0.0), *, radius: float = 0.5,
                   **params) -> ca.Function:
    """CasADi Function ``V(pos)`` (2-vector in, 2-vector out) of ``field`` with one obstacle at ``obstacle``
    (radius ``radius``, always active) and the goal at ``goal``. Map it over a grid with
    ``F.map(n)(np.vstack([X.ravel(), Y.ravel()]))``.

    Parameters
    ----------
    field : {"inverse-square", "sink-vortex", "modified-vortex"}
        The field.
    goal, obstacle : (float, float)
        Goal and obstacle centre (L).
    radius : float
        Obstacle radius (L; used by the inverse-square field).
    **params
        Field parameters overriding the defaults (:func:`field_params`).

    Returns
    -------
    casadi.Function
        ``field_<name>(pos) -> v``: the field velocity (2x1) at ``pos`` (2x1, L).
    """
    prm = field_params(field, **params)
    pos = ca.SX.sym("pos", 2)
    goal = ca.DM(np.asarray(goal, float).reshape(2, 1))
    nb = ca.DM(np.asarray(obstacle, float).reshape(2, 1))
    if field == "inverse-square":
        v = inverse_square(pos, goal, nb, [radius], [1.0], k_att=prm["k_att"], k_rep=prm["k_rep"], d0=prm["d0"])
    elif field == "sink-vortex":
        v = sink_vortex(pos, goal, nb, [1.0], lam_sink=prm["lam_sink"], k_vor=prm["k_vor"])
    else:
        psi = float(prm["heading"])
        vel = ca.DM([prm["speed"] * math.cos(psi), prm["speed"] * math.sin(psi)])
        v = modified_vortex(pos, psi, vel, goal, nb, ca.DM.zeros(2, 1), [1.0], lam_sink=prm["lam_sink"],
                            k_vor0=prm["k_vor0"], r_safe=prm["r_safe"], r_tol=prm["r_tol"],
                            gamma_max=prm["gamma_max"], smooth=prm["smooth"])
    return ca.Function(f"field_{field.replace('-', '_')}", [pos], [v], ["pos"], ["v"])


def stagnation_point(field: str = "inverse-square", goal=(10.0, 0.0), obstacle=(-10.0, 0.0), guess=(-15.0, 0.0),
                     *, radius: float = 0.5, tol: float = 1e-9, **params) -> np.ndarray:
    """Stagnation point (L) of ``field`` nearest (in Newton's sense) to ``guess``: a root of V(pos) = 0 found
    with ``ca.rootfinder(..., "newton", ...)``. ``params`` override the field's defaults (see
    :func:`field_params`). Raises ``RuntimeError`` if Newton does not converge to ``|V| < tol · |V(guess)|``
    within ``10 (|goal − obstacle| + |guess − obstacle|)`` of the obstacle (the fields vanish at infinity).

    Parameters
    ----------
    field : {"inverse-square", "sink-vortex", "modified-vortex"}
        The field.
    goal, obstacle : (float, float)
        Goal and obstacle centre (L).
    guess : (float, float)
        Initial guess of Newton's method (L).
    radius : float
        Obstacle radius (L).
    tol : float
        Accepted residual relative to ``|V(guess)|``.
    **params
        Field parameters overriding the defaults (:func:`field_params`).

    Returns
    -------
    numpy.ndarray (2,)
        The point (x, y) where the field vanishes (L).

    Examples
    --------
    >>> p = stagnation_point()  # the paper's inverse-square example, d0 = 8 L
    >>> round(float(p[0]), 2), abs(round(float(p[1]), 6))
    (-15.44, 0.0)
    >>> round(distance_from_obstacle(p), 2)
    5.44
    """
    F = field_function(field, goal, obstacle, radius=radius, **params)
    z = ca.SX.sym("z", 2)
    G = ca.Function("residual", [z], [F(z)])
    rf = ca.rootfinder("stagnation", "newton", G, {"abstol": 1e-12, "max_iter": 200, "error_on_fail": False})
    sol = np.array(rf(ca.DM(np.asarray(guess, float)))).ravel()
    scale = float(np.linalg.norm(np.array(F(ca.DM(np.asarray(guess, float)))))) or 1.0
    res = float(np.linalg.norm(np.array(F(sol))))
    # the fields decay far away, so Newton can also "converge" towards infinity: accept only nearby roots
    reach = 10.0 * (float(np.hypot(*(np.asarray(goal, float) - np.asarray(obstacle, float))))
                    + distance_from_obstacle(guess, obstacle))
    far = not np.all(np.isfinite(sol)) or distance_from_obstacle(sol, obstacle) > reach
    if far or res > max(tol * scale, 1e-10):
        raise RuntimeError(f"no stagnation point of the {field} field found from {tuple(guess)} "
                           f"(Newton ended at {sol.tolist()} with |V| = {res:.3g})")
    return sol


def distance_from_obstacle(point, obstacle=(-10.0, 0.0)) -> float:
    """Distance (L) of ``point`` from the obstacle centre.

    Parameters
    ----------
    point, obstacle : (float, float)
        The two positions (L).

    Returns
    -------
    float
        The distance (L).
    """
    return float(np.hypot(*(np.asarray(point, float) - np.asarray(obstacle, float))))


# -- several obstacles, moving targets, classification and a brute-force check ---------------------------------

def scene_function(field: str = "inverse-square", goal=(10.0, 0.0), obstacles=((-10.0, 0.0),), *, targets=(),
                   radius: float = 0.5, **params) -> ca.Function:
    """CasADi Function ``V(pos)`` of ``field`` for several static ``obstacles`` and moving ``targets``.

    Every obstacle and target is an active neighbour. A target is ``((x, y), (vx, vy))``: a ship at that position
    with that velocity over the ground (fractions of U); only the modified vortex reads velocities (its vortex
    acts on a neighbour that is not drawing clear), the other fields see a target as an obstacle where it is.
    The plane is that of one instant: the own ship at every point with the heading and speed of ``params``.

    Parameters
    ----------
    field : {"inverse-square", "sink-vortex", "modified-vortex"}
        The field.
    goal : (float, float)
        Goal (L).
    obstacles : sequence of (float, float)
        Static obstacle centres (L).
    targets : sequence of ((float, float), (float, float))
        Moving ships: position (L) and velocity (U).
    radius : float
        Radius of every neighbour (L; the inverse-square field's R_obs).
    **params
        Field parameters overriding the defaults (:func:`field_params`).

    Returns
    -------
    casadi.Function
        ``scene_<name>(pos) -> v``.

    Examples
    --------
    >>> F = scene_function("sink-vortex", obstacles=[(-10, 0), (-10, 6)])
    >>> [round(float(c), 4) for c in F([0.0, -5.0]).nz]
    [1.1304, 0.4373]
    """
    prm = field_params(field, **params)
    pos = ca.SX.sym("pos", 2)
    goal = ca.DM(np.asarray(goal, float).reshape(2, 1))
    cols = [np.asarray(o, float) for o in obstacles] + [np.asarray(p, float) for p, _ in targets]
    vels = [np.zeros(2)] * len(obstacles) + [np.asarray(v, float) for _, v in targets]
    if not cols:
        raise InputError("obstacles", "at least one obstacle or target", "none")
    nb, nb_vel = ca.DM(np.column_stack(cols)), ca.DM(np.column_stack(vels))
    m = len(cols)
    on = [1.0] * m
    if field == "inverse-square":
        v = inverse_square(pos, goal, nb, [radius] * m, on, k_att=prm["k_att"], k_rep=prm["k_rep"], d0=prm["d0"])
    elif field == "sink-vortex":
        v = sink_vortex(pos, goal, nb, on, lam_sink=prm["lam_sink"], k_vor=prm["k_vor"])
    else:
        psi = float(prm["heading"])
        vel = ca.DM([prm["speed"] * math.cos(psi), prm["speed"] * math.sin(psi)])
        v = modified_vortex(pos, psi, vel, goal, nb, nb_vel, on, lam_sink=prm["lam_sink"], k_vor0=prm["k_vor0"],
                            r_safe=prm["r_safe"], r_tol=prm["r_tol"], gamma_max=prm["gamma_max"],
                            smooth=prm["smooth"])
    return ca.Function(f"scene_{field.replace('-', '_')}", [pos], [v], ["pos"], ["v"])


def _solve(F: ca.Function, guess, tol: float = 1e-10):
    z = ca.SX.sym("z", 2)
    rf = ca.rootfinder("stagnation", "newton", ca.Function("residual", [z], [F(z)]),
                       {"abstol": 1e-12, "max_iter": 100, "error_on_fail": False})
    sol = np.array(rf(ca.DM(np.asarray(guess, float)))).ravel()
    if not np.all(np.isfinite(sol)):
        return None
    scale = float(np.linalg.norm(np.array(F(ca.DM(np.asarray(guess, float)))))) or 1.0
    return sol if float(np.linalg.norm(np.array(F(sol)))) <= max(tol * scale, 1e-10) else None


def stagnation_points(F: ca.Function, box, *, starts: int = 20, exclude=(), min_gap: float = 0.05) -> np.ndarray:
    """Every stagnation point of ``F`` in ``box`` that Newton (CasADi's ``rootfinder``) reaches from a
    ``starts`` × ``starts`` grid of initial guesses, without repeats.

    Parameters
    ----------
    F : casadi.Function
        ``pos -> V(pos)`` (:func:`scene_function`, :func:`field_function`).
    box : (float, float, float, float)
        ``(x_min, x_max, y_min, y_max)`` (L): where guesses start and roots are kept.
    starts : int
        Guesses per axis.
    exclude : sequence of ((float, float), float)
        Discs ``(centre, radius)`` whose roots are dropped (the singular centres of sinks and vortices).
    min_gap : float
        Roots closer than this (L) are one.

    Returns
    -------
    numpy.ndarray (k, 2)
        The points, sorted by x then y.
    """
    x0, x1, y0, y1 = box
    found: list[np.ndarray] = []
    for gx in np.linspace(x0, x1, starts):
        for gy in np.linspace(y0, y1, starts):
            p = _solve(F, (gx, gy))
            if p is None or not (x0 <= p[0] <= x1 and y0 <= p[1] <= y1):
                continue
            if any(np.hypot(*(p - np.asarray(c, float))) < r for c, r in exclude):
                continue
            if all(np.hypot(*(p - q)) >= min_gap for q in found):
                found.append(p)
    return np.array(sorted(found, key=lambda p: (round(p[0], 6), round(p[1], 6)))).reshape(-1, 2)


def classify(F: ca.Function, point) -> tuple[np.ndarray, str]:
    """The eigenvalues of the field's Jacobian ∂V/∂pos at a stagnation point (CasADi's exact Jacobian) and the kind
    of point they make for a ship steered along V: ``"saddle"`` (real, opposite signs: ships are turned aside, one
    direction leads in), ``"stable node"`` / ``"unstable node"`` (real, both negative / positive: a trap / a
    source), ``"stable focus"`` / ``"unstable focus"`` / ``"centre"`` (complex).

    Parameters
    ----------
    F : casadi.Function
        ``pos -> V(pos)``.
    point : (float, float)
        A stagnation point (L).

    Returns
    -------
    eigenvalues : numpy.ndarray (2,)
        Eigenvalues of the Jacobian (1/(L/U)), complex.
    kind : str
        The kind of point.

    Examples
    --------
    >>> F = field_function("sink-vortex")
    >>> classify(F, stagnation_point("sink-vortex", guess=(-10, -2)))[1]
    'saddle'
    """
    z = ca.SX.sym("z", 2)
    J = ca.Function("J", [z], [ca.jacobian(F(z), z)])
    ev = np.linalg.eigvals(np.array(J(np.asarray(point, float))))
    re, im = ev.real, ev.imag
    if np.max(np.abs(im)) > 1e-9 * max(1.0, np.max(np.abs(ev))):
        kind = "centre" if abs(re[0]) < 1e-12 else ("stable focus" if re[0] < 0 else "unstable focus")
    elif re[0] * re[1] < 0:
        kind = "saddle"
    else:
        kind = "stable node" if re.max() < 0 else "unstable node"
    return ev, kind


def grid_stagnation_cells(F: ca.Function, box, *, n: int = 400, exclude=(), jumps: bool = False) -> np.ndarray:
    """Brute force: the cells of an ``n`` × ``n`` grid over ``box`` in which both components of the field change
    sign, neighbouring cells merged, kept where a 41 × 41 sampling of the group's cells (and one cell around) comes
    within 5 % of its largest ``|V|`` of zero (a stagnation point), or, with ``jumps``, where it does not (the field
    jumps across zero at a switch, as the modified vortex's does, without vanishing).

    Parameters
    ----------
    F : casadi.Function
        ``pos -> V(pos)``.
    box : (float, float, float, float)
        ``(x_min, x_max, y_min, y_max)`` (L).
    n : int
        Grid points per axis.
    exclude : sequence of ((float, float), float)
        Discs ``(centre, radius)`` left out (singular centres).
    jumps : bool
        Return the sign changes without a zero (jumps) instead of the stagnation points.

    Returns
    -------
    numpy.ndarray (k, 2)
        One point per group of neighbouring cells (the sample point of least ``|V|``), sorted by x then y.
    """
    x0, x1, y0, y1 = box
    xs, ys = np.linspace(x0, x1, n), np.linspace(y0, y1, n)
    X, Y = np.meshgrid(xs, ys)
    V = np.array(F.map(X.size)(np.vstack([X.ravel(), Y.ravel()])))
    U, W = V[0].reshape(X.shape), V[1].reshape(X.shape)

    def changes(A):
        c = np.stack([A[:-1, :-1], A[1:, :-1], A[:-1, 1:], A[1:, 1:]])
        return (c.max(axis=0) >= 0) & (c.min(axis=0) <= 0)
    cells = changes(U) & changes(W)
    cx, cy = (X[:-1, :-1] + X[1:, 1:]) / 2, (Y[:-1, :-1] + Y[1:, 1:]) / 2
    pts = [np.array([a, b]) for a, b in zip(cx[cells], cy[cells])
           if not any(np.hypot(a - c[0], b - c[1]) < r for c, r in exclude)]
    groups: list[list[np.ndarray]] = []
    step = 3.0 * np.hypot(xs[1] - xs[0], ys[1] - ys[0])
    for p in pts:
        for g in groups:
            if min(np.hypot(*(p - q)) for q in g) <= step:
                g.append(p)
                break
        else:
            groups.append([p])
    hx, hy = xs[1] - xs[0], ys[1] - ys[0]
    out = []
    for g in groups:
        g = np.array(g)
        sx = np.linspace(g[:, 0].min() - hx, g[:, 0].max() + hx, 41)
        sy = np.linspace(g[:, 1].min() - hy, g[:, 1].max() + hy, 41)
        SX, SY = np.meshgrid(sx, sy)
        S = np.array(F.map(SX.size)(np.vstack([SX.ravel(), SY.ravel()])))
        speed = np.hypot(S[0], S[1])
        k = int(np.argmin(speed))
        if (speed[k] <= 0.05 * speed.max()) != jumps:
            out.append(np.array([SX.ravel()[k], SY.ravel()[k]]))
    return np.array(sorted(out, key=lambda p: (round(p[0], 6), round(p[1], 6)))).reshape(-1, 2)
