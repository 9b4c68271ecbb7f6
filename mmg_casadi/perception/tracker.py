"""The tracker: a constant-velocity Kalman filter per target, as CasADi expressions.

Each target's track is a state ``[x, y, vx, vy]`` (position in L, velocity over the ground in U) with its
covariance ``P`` (4×4, the ten values of its upper triangle kept in state rows). Between two guidance steps the
track is predicted with the constant-velocity model driven by white acceleration noise of spectral density ``q``
(Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to Tracking and Navigation*, 2001, §6.2.2):

    F = [[I, dt I], [0, I]],   Q = q [[dt³/3 I, dt²/2 I], [dt²/2 I, dt I]].

A measurement of the position (a radar plot, an AIS position) or of the velocity (an AIS speed and course) updates
the track (:func:`update`). The measured components are written as ``z + R S⁻¹ (x − z)`` and their covariance rows as
``R S⁻¹ P``, which equal the textbook ``x + K (z − x)`` and ``(I − K H) P`` and make a noise-free measurement
(``R = 0``) set them to the measurement exactly, bit for bit, which the test of perfect sensors relies on.

Association (:func:`nearest`): a radar plot carries no identity, so each track takes the plot nearest to it in the
Mahalanobis distance of its innovation, ``ν^T S⁻¹ ν``, if that is inside the gate (global nearest neighbour without
exclusivity: two tracks may take one plot, as happens with a simple nearest-neighbour tracker in close
quarters). AIS reports carry the sender's identity (MMSI), so they update their own target's track.

Examples
--------
>>> import casadi as ca
>>> x, P = predict([0.0, 0.0, 1.0, 0.0], ca.DM.eye(4), 0.5, 0.0)
>>> [float(v) for v in x], float(P[0, 2])
([0.5, 0.0, 1.0, 0.0], 0.5)
>>> x2, P2 = update(x, P, (0, 1), [0.7, 0.1], ca.DM.zeros(2, 2))
>>> [float(v) for v in x2[:2]], float(P2[0, 0])
([0.7, 0.1], 0.0)
"""

from __future__ import annotations

import casadi as ca

EPS = 1e-12
"""Added to the diagonal of an innovation covariance before it is inverted (L² or U²): keeps a noise-free update of a
component whose variance is already zero finite; far below any variance the filter meets otherwise."""
UPPER = ((0, 0), (0, 1), (0, 2), (0, 3), (1, 1), (1, 2), (1, 3), (2, 2), (2, 3), (3, 3))
"""The covariance entries kept in state rows (``trk_p00`` ... ``trk_p33``), in order."""


def inv2(S):
    """Inverse of a 2×2 matrix (closed form).

    Parameters
    ----------
    S : SX or DM (2×2)
        The matrix.

    Returns
    -------
    SX or DM (2×2)
        Its inverse, ``adj(S) / det(S)``.
    """
    a, b, c, d = S[0, 0], S[0, 1], S[1, 0], S[1, 1]
    det = a * d - b * c
    return ca.vertcat(ca.horzcat(d, -b), ca.horzcat(-c, a)) / det


def unpack(values):
    """The 4×4 symmetric covariance from its ten upper-triangle values (:data:`UPPER`).

    Parameters
    ----------
    values : sequence of 10
        The values, in the order of :data:`UPPER`.

    Returns
    -------
    SX or DM (4×4)
        The covariance.
    """
    P = ca.SX.zeros(4, 4) if not isinstance(values[0], ca.DM) else ca.DM.zeros(4, 4)
    for (i, j), v in zip(UPPER, values):
        P[i, j] = v
        P[j, i] = v
    return P


def pack(P) -> list:
    """The ten upper-triangle values of a covariance (:data:`UPPER`).

    Parameters
    ----------
    P : SX or DM (4×4)
        The covariance.

    Returns
    -------
    list
        Its entries in the order of :data:`UPPER`.
    """
    return [P[i, j] for i, j in UPPER]


def predict(x, P, dt, q):
    """The track after ``dt`` of constant velocity: mean and covariance.

    Parameters
    ----------
    x : sequence of 4
        ``[x, y, vx, vy]``.
    P : SX or DM (4×4)
        Covariance.
    dt, q : number or expression
        Time step and the acceleration noise's spectral density.

    Returns
    -------
    (list, SX or DM)
        The predicted mean and covariance.
    """
    F = ca.SX.eye(4) if isinstance(P, ca.SX) or isinstance(dt, ca.SX) else ca.DM.eye(4)
    F[0, 2] = dt
    F[1, 3] = dt
    a, b, c = q * dt ** 3 / 3.0, q * dt ** 2 / 2.0, q * dt
    Q = ca.vertcat(ca.horzcat(a, 0, b, 0), ca.horzcat(0, a, 0, b), ca.horzcat(b, 0, c, 0), ca.horzcat(0, b, 0, c))
    Pn = ca.mtimes(ca.mtimes(F, P), F.T) + Q
    return [x[0] + dt * x[2], x[1] + dt * x[3], x[2], x[3]], Pn


def update(x, P, idx, z, R):
    """The track after a measurement of two of its components.

    Parameters
    ----------
    x : sequence of 4
        Mean.
    P : SX or DM (4×4)
        Covariance.
    idx : (int, int)
        The measured components: ``(0, 1)`` position, ``(2, 3)`` velocity.
    z : sequence of 2
        The measurement.
    R : SX or DM (2×2)
        Its covariance.

    Returns
    -------
    (list, SX or DM)
        The updated mean and covariance (the measured components ``z + R S⁻¹ (x − z)``, see the module).
    """
    o = [k for k in range(4) if k not in idx]
    idx = list(idx)
    xi = ca.vertcat(*[x[k] for k in idx])
    zi = ca.vertcat(*z)
    S = P[idx, idx] + R + EPS * ca.DM.eye(2)
    Si = inv2(S)
    RSi = ca.mtimes(R, Si)
    W = ca.mtimes(P[o, idx], Si)  # gain of the unmeasured components
    x_i = zi + ca.mtimes(RSi, xi - zi)
    x_o = ca.vertcat(*[x[k] for k in o]) + ca.mtimes(W, zi - xi)
    rows_i = ca.mtimes(RSi, P[idx, :])  # (I - K H) P on the measured rows
    P_oo = P[o, o] - ca.mtimes(W, P[idx, o])
    Pn = ca.SX.zeros(4, 4) if isinstance(P, ca.SX) or isinstance(R, ca.SX) else ca.DM.zeros(4, 4)
    for a, i in enumerate(idx):
        for k in range(4):
            Pn[i, k] = rows_i[a, k]
            Pn[k, i] = rows_i[a, k]
    for a, i in enumerate(idx):  # the measured block symmetric (R S⁻¹ P is, up to rounding)
        for b, j in enumerate(idx):
            Pn[i, j] = 0.5 * (rows_i[a, j] + rows_i[b, i])
    for a, i in enumerate(o):
        for b, j in enumerate(o):
            Pn[i, j] = P_oo[a, b]
    out = [None] * 4
    for a, k in enumerate(idx):
        out[k] = x_i[a]
    for a, k in enumerate(o):
        out[k] = x_o[a]
    return out, Pn


def select(cond, a, b):
    """``a`` where ``cond`` else ``b``, for a track (list of 4) and a covariance (4×4) alike.

    Parameters
    ----------
    cond : SX
        The condition (0/1).
    a, b : list or SX
        Two tracks or two covariances.

    Returns
    -------
    list or SX
        The selected one, element by element.
    """
    if isinstance(a, list):
        return [ca.if_else(cond, u, v) for u, v in zip(a, b)]
    return ca.if_else(cond, a, b)


def mahalanobis2(x, P, z, R):
    """Squared Mahalanobis distance of a position measurement ``z`` (covariance ``R``) from the track's position.

    Parameters
    ----------
    x, P : list, SX
        The track's mean and covariance.
    z : sequence of 2
        The measured position.
    R : SX or DM (2×2)
        Its covariance.

    Returns
    -------
    SX
        ``ν^T (P_pos + R)⁻¹ ν`` with the innovation ``ν = z − x_pos``.
    """
    nu = ca.vertcat(z[0] - x[0], z[1] - x[1])
    S = P[[0, 1], [0, 1]] + R + EPS * ca.DM.eye(2)
    return ca.mtimes(ca.mtimes(nu.T, inv2(S)), nu)


def nearest(x, P, plots):
    """The radar plot nearest to a track (Mahalanobis distance of the innovation) among the detected ones.

    Parameters
    ----------
    x, P : list, SX
        The track.
    plots : list of (detected, z, R)
        Every plot: 0/1 detected, measured position (2) and its covariance (2×2).

    Returns
    -------
    (SX, list, SX)
        The distance (``inf`` without any detection), the plot's position and covariance.
    """
    best_d = ca.inf
    best_z, best_R = [x[0], x[1]], ca.SX.zeros(2, 2)
    for det, z, R in plots:
        d = mahalanobis2(x, P, z, R)
        take = ca.logic_and(det > 0.5, d < best_d)
        best_d = ca.if_else(take, d, best_d)
        best_z = [ca.if_else(take, z[0], best_z[0]), ca.if_else(take, z[1], best_z[1])]
        best_R = ca.if_else(take, R, best_R)
    return best_d, best_z, best_R
