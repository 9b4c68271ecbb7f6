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
