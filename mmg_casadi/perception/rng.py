"""Random numbers inside the compiled step: L'Ecuyer's MRG32k3a generator in floating-point arithmetic.

The sensor noise of :mod:`mmg_casadi.perception` is drawn inside the compiled closed-loop step, so that a Monte Carlo
rollout stays one ``mapaccum`` with no per-step input from Python. Each target ship carries the six state values of
its own MRG32k3a generator (L'Ecuyer 1999, "Good parameters and implementations for combined multiple recursive
random number generators", Operations Research 47(1):159-164) as state rows; a step advances it a fixed number of
times. The generator was designed for exactly this: its double-precision implementation is exact (every product is
below 2^53), so the same operations in CasADi's generated C code, in numpy and in Python integers give the same
numbers to the bit. The seeds are drawn per run from the study's seed (:func:`seed_state`).

Examples
--------
>>> s = [12345.0] * 6
>>> s, u = mrg_next(s)
>>> float(u)  # L'Ecuyer's first output from the seed 12345 x 6
0.12701112204657714
>>> s2, v = mrg_next_int([12345] * 6)
>>> bool(v == u)
True
"""

from __future__ import annotations

import math

import numpy as np

M1 = 4294967087.0
M2 = 4294944443.0
A12, A13N = 1403580.0, 810728.0
A21, A23N = 527612.0, 1370589.0
NORM = 2.328306549295728e-10
"""The constants of MRG32k3a (L'Ecuyer 1999, Table II): moduli, multipliers and the normalisation 1/(m1 + 1)."""


def _where(cond, a, b):
    """``a`` where ``cond`` else ``b``: numbers, numpy arrays or CasADi expressions."""
    if isinstance(cond, (bool, np.bool_)):
        return a if cond else b
    if isinstance(cond, np.ndarray):
        return np.where(cond, a, b)
    import casadi as ca
    return ca.if_else(cond, a, b)


def _floor(x):
    if isinstance(x, (float, int, np.floating, np.ndarray)):
        return np.floor(x)
    import casadi as ca
    return ca.floor(x)


def _reduce(p, m):
    """``p mod m`` for |p| < 2^53 (exact: ``floor`` then one correction each way)."""
    p = p - _floor(p / m) * m
    p = _where(p < 0.0, p + m, p)
    return _where(p >= m, p - m, p)


def mrg_next(s):
    """One step of MRG32k3a: the next state and a uniform number in (0, 1).

    Parameters
    ----------
    s : sequence of 6 numbers or CasADi expressions
        The state ``(s10, s11, s12, s20, s21, s22)``: the first three in [0, m1), the last three in [0, m2), neither
        triple all zero.

    Returns
    -------
    (list, number or expression)
        The next state and the uniform number ``u`` in (0, 1).
    """
    s10, s11, s12, s20, s21, s22 = s
    p1 = _reduce(A12 * s11 - A13N * s10, M1)
    p2 = _reduce(A21 * s22 - A23N * s20, M2)
    u = _where(p1 > p2, (p1 - p2) * NORM, (p1 - p2 + M1) * NORM)
    return [s11, s12, p1, s21, s22, p2], u


def mrg_next_int(s):
    """:func:`mrg_next` in Python integers (the reference the floating-point version is checked against).

    Parameters
    ----------
    s : sequence of 6 int
        The state.

    Returns
    -------
    (list of int, float)
        The next state and ``u``.
    """
    s10, s11, s12, s20, s21, s22 = (int(v) for v in s)
    p1 = (1403580 * s11 - 810728 * s10) % 4294967087
    p2 = (527612 * s22 - 1370589 * s20) % 4294944443
    u = ((p1 - p2) if p1 > p2 else (p1 - p2 + 4294967087)) * NORM
    return [s11, s12, p1, s21, s22, p2], u


def normals(u1, u2):
    """Two independent standard normal numbers from two uniforms in (0, 1) (Box & Muller 1958).

    Parameters
    ----------
    u1, u2 : number or expression
        Uniforms in (0, 1).

    Returns
    -------
    (number or expression, number or expression)
        ``sqrt(-2 ln u1) cos(2 pi u2)`` and ``sqrt(-2 ln u1) sin(2 pi u2)``.
    """
    if isinstance(u1, (float, int, np.floating)):
        r = math.sqrt(-2.0 * math.log(u1))
        return r * math.cos(2.0 * math.pi * u2), r * math.sin(2.0 * math.pi * u2)
    import casadi as ca
    r = ca.sqrt(-2.0 * ca.log(u1))
    return r * ca.cos(2.0 * ca.pi * u2), r * ca.sin(2.0 * ca.pi * u2)


def seed_state(entropy) -> list[float]:
    """A valid MRG32k3a state drawn from ``numpy.random.SeedSequence(entropy)``.

    Parameters
    ----------
    entropy : int or sequence of int
        The seed sequence's entropy, e.g. ``[seed, ship, STREAM]``.

    Returns
    -------
    list of float
        Six state values, integers stored as floats, neither triple all zero.

    Examples
    --------
    >>> s = seed_state([0, 1])
    >>> all(0 <= v < M1 for v in s[:3]) and all(0 <= v < M2 for v in s[3:]), s == seed_state([0, 1])
    (True, True)
    """
    words = np.random.SeedSequence(entropy).generate_state(6, dtype=np.uint32).astype(np.int64)
    first = [int(w) % int(M1) for w in words[:3]]
    second = [int(w) % int(M2) for w in words[3:]]
    if not any(first):
        first[0] = 1
    if not any(second):
        second[0] = 1
    return [float(v) for v in first + second]
