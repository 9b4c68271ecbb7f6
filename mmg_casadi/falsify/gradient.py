"""The smooth collision margin of a scenario and its exact gradient with respect to the envelope's parameters.

For one parameter vector ``theta`` (:class:`~mmg_casadi.falsify.envelope.Envelope`) the scenario's initial state
``x0(theta)`` and parameter vector ``p(theta)`` are rolled out by the study's compiled step; the own ship's margins
``m_kj`` to every agent (:func:`~mmg_casadi.falsify.robustness.own_margins`) give the exact robustness ``min m`` and
its smooth version, the soft-min over time and neighbours

    rho_s = −(1/κ) log Σ_(k,j) exp(−κ m_kj)        (≤ min m ≤ rho_s + log(n)/κ, n counted pairs)

whose derivative with respect to each margin is its soft-min weight. The gradient of ``rho_s`` with respect to the
rollout's inputs is the adjoint of the ``mapaccum`` rollout, computed by CasADi: the dense closed-loop step
(:func:`~mmg_casadi.closed_loop.step.build_closed_loop_step`, the one expression that is differentiated) is compiled
together with its reverse-mode derivative (``adj1_``, :data:`GRADIENT_FLAGS`) into one library, so that CasADi's
reverse mode of ``step.mapaccum(chunk)`` calls native code; chunk by chunk, from the last to the first, the seed
``∂rho_s/∂x_k`` of every state of the chunk and the adjoint carried from the next chunk are pulled back to the
chunk's first state and to ``p``. The chain to ``theta`` uses ``∂x0/∂theta`` and ``∂p/∂theta``, which are
affine in every coordinate but the target speeds (the propeller speed of a steady speed): forward differences of
the scenario's problem (:func:`~mmg_casadi.closed_loop.problem.build_problem`) with steps :data:`FD_STEP`.

The closed loop switches (a neighbour entering R_safe, roles, filters): the gradient is that of the branch the
rollout took, exact between switches and blind to a switch it would cross. That is why the gradient search is
compared with a derivative-free one (:mod:`~mmg_casadi.falsify.search`).
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop.layout import Layout
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import simulate
from mmg_casadi.closed_loop.step import build_closed_loop_step
from mmg_casadi.compiled import compile_function
from mmg_casadi.errors import InputError
from mmg_casadi.falsify.envelope import Envelope
from mmg_casadi.falsify.robustness import Evaluation, agent_reaches, judge, own_margins, scenario_of
from mmg_casadi.guidance.methods import forget_on_unregister, run_of
from mmg_casadi.montecarlo.sampling import ENVIRONMENTS

GRADIENT_FLAGS = ("-O1", "-fno-math-errno", "-fPIC", "-shared")
"""Compiler flags of the step with its adjoint (the adjoint is ~3x the step; -O2 compiles much longer)."""
KAPPA = 2.0
"""Sharpness of the soft-min (1/L): pairs within about 1/κ = 0.5 L of the closest one share the gradient."""
ADJOINT_CHUNK = 32
"""Steps per adjoint call (the adjoint of ``step.mapaccum(ADJOINT_CHUNK)``)."""
FD_STEP = 1e-6
"""Relative step of the forward differences of ``x0(theta)`` and ``p(theta)`` (times the coordinate's range)."""
SEED_FLOOR = 1e-12
"""Soft-min weights below this share of the largest are dropped (the adjoint then stops at the last that counts,
usually the closest approach, instead of the run's end)."""
STATE = ("x", "y", "psi", "status")
"""Ship state rows the margins read."""


@lru_cache(maxsize=16)
def compiled_step_with_adjoint(layout: Layout) -> ca.Function:
    """The dense closed-loop step of ``layout`` compiled with its reverse-mode derivative (memoised, cached on
    disk): CasADi's reverse mode of a rollout of it calls the compiled ``adj1_`` Function.

    Parameters
    ----------
    layout : Layout
        An exact closed-loop layout (not a fleet layout).

    Returns
    -------
    casadi.Function
        ``closed_loop_<key>(x, p) -> (x_next, aux)`` with a compiled reverse derivative.
    """
    if layout.neighbours:
        raise InputError("layout", "an unrolled layout (the fleet step is not differentiated)", layout.key())
    f = build_closed_loop_step(layout)
    return compile_function(f, GRADIENT_FLAGS, also=[f.reverse(1)],
                            label=f"closed loop with its adjoint for {layout.n_ships} ships "
                                  f"({', '.join(dict.fromkeys(layout.methods))})")[0]


@lru_cache(maxsize=16)
def adjoint_chunk(layout: Layout, chunk: int = ADJOINT_CHUNK, compiled: bool = True) -> ca.Function:
    """``(x, p, G) -> (∂J/∂x, ∂J/∂p)`` of ``J = Σ_k G[:, k] · x_(k+1)`` over ``chunk`` steps from ``x``: the
    reverse mode of ``step.mapaccum(chunk)``.

    Parameters
    ----------
    layout : Layout
        The closed-loop layout.
    chunk : int
        Steps.
    compiled : bool, default True
        Use the compiled step with its adjoint (:func:`compiled_step_with_adjoint`); False: the symbolic step in
        CasADi's virtual machine (no compilation; slower per call).

    Returns
    -------
    casadi.Function
        The pull-back of the seeds ``G`` (nx × chunk) to the chunk's first state and to ``p``.
    """
    step = compiled_step_with_adjoint(layout) if compiled else build_closed_loop_step(layout)
    x = ca.MX.sym("x", layout.nx)
    p = ca.MX.sym("p", layout.np)
    G = ca.MX.sym("G", layout.nx, chunk)
    X, _ = step.mapaccum(chunk)(x, p)
    J = ca.dot(G, X)
    gx, gp = ca.gradient(J, x), ca.gradient(J, p)
    return ca.Function(f"adjoint_{layout.key()}_{chunk}", [x, p, G], [gx, gp], ["x", "p", "G"], ["dx", "dp"])


def _param_index(layout: Layout) -> dict:
    """Indices of the obstacles' and walls' entries in the parameter vector (by name, through ``split_params``)."""
    P = layout.split_params(ca.DM(np.arange(layout.np, dtype=float)))
    return {"obstacles": np.array(P["obstacles"], int).reshape(3, -1),
            "walls": np.array(P["walls"], int).reshape(4, -1)}


def soft_min(margins: np.ndarray, kappa: float = KAPPA) -> tuple[float, np.ndarray]:
    """The soft-min of the counted margins (NaN: not counted) and its derivative with respect to each.

    Parameters
    ----------
    margins : numpy.ndarray
        Margins (L), NaN where a pair does not count.
    kappa : float
        Sharpness (1/L).

    Returns
    -------
    value : float
        ``−(1/κ) log Σ exp(−κ m)`` (inf when nothing counts).
    weights : numpy.ndarray
        Its derivative with respect to each margin (0 where NaN), summing to 1.

    Examples
    --------
    >>> v, w = soft_min(np.array([1.0, np.nan, 1.0]), kappa=2.0)
    >>> round(v, 4), w.tolist()
    (0.6534, [0.5, 0.0, 0.5])
    """
    valid = ~np.isnan(margins)
    if not valid.any():
        return math.inf, np.zeros_like(margins)
    m0 = float(np.min(margins[valid]))
    e = np.where(valid, np.exp(-kappa * (np.where(valid, margins, m0) - m0)), 0.0)
    total = float(e.sum())
    return m0 - math.log(total) / kappa, e / total


class MarginGradient:
    """The exact robustness, the smooth margin and its gradient with respect to ``theta`` (module docstring).

    Parameters
    ----------
    envelope : Envelope
        The envelope searched.
    method : str
        Every ship's method.
    objective : {"collision", "grounding"}
        The margin to every agent or to land only.
    params : dict, optional
        Parameter overrides of every run.
    kappa : float
        Sharpness of the soft-min (1/L).
    chunk : int
        Steps per adjoint call.
    compiled : bool, default True
        Compile the step with its adjoint (else CasADi's virtual machine).
    """

    def __init__(self, envelope: Envelope, method: str, objective: str = "collision", params: dict | None = None,
                 *, kappa: float = KAPPA, chunk: int = ADJOINT_CHUNK, compiled: bool = True):
        if objective not in ("collision", "grounding"):
            raise InputError("objective", "collision or grounding (the COLREG scorer has no derivative; search "
                             "colregs with cmaes or random)", objective)
        self.envelope, self.method, self.objective = envelope, method, objective
        self.params = dict(params or {})
        self.kappa, self.chunk, self.compiled = float(kappa), int(chunk), bool(compiled)
        self._affine = None  # Jacobians of the first call (environments 1-5: every column but the speeds is constant)
        self._varying = [envelope.index(n) for n in envelope.names if n.endswith(".speed")]

    def _inputs(self, theta):
        sc = scenario_of(self.envelope, theta, self.method, self.params)
        return sc, build_problem(sc)

    def jacobians(self, theta) -> tuple[np.ndarray, np.ndarray]:
        """``∂x0/∂theta`` (nx × d) and ``∂p/∂theta`` (np × d) by forward differences (module docstring).

        In environments 1–5 the map is affine in every coordinate but the target speeds (positions and angles are
        copied, the propeller speed of a steady speed is not linear), so after the first call only the speed
        columns are differenced again; in environment 6 the places across the fairway scale with its width and
        every column is.

        Parameters
        ----------
        theta : array (dimension,)
            The parameter vector.

        Returns
        -------
        tuple of numpy.ndarray
            The two Jacobians.
        """
        env = self.envelope
        theta = np.asarray(theta, float)
        _, pr = self._inputs(theta)
        if self._affine is None:
            Jx = np.zeros((pr.x0.size, env.dimension))
            Jp = np.zeros((pr.p.size, env.dimension))
            columns = range(env.dimension)
        else:  # the affine columns are those of the first call; only the others change with theta
            Jx, Jp = (J.copy() for J in self._affine)
            columns = self._varying
        for j in columns:
            h = FD_STEP * (env.high[j] - env.low[j])
            if theta[j] + h > env.high[j]:
                h = -h  # stay on this side of a bound (a periodic coordinate must not wrap)
            th = theta.copy()
            th[j] += h
            _, pj = self._inputs(th)
            Jx[:, j] = (pj.x0 - pr.x0) / h
            Jp[:, j] = (pj.p - pr.p) / h
        if self._affine is None and env.environment in ENVIRONMENTS:
            self._affine = (Jx.copy(), Jp.copy())
        return Jx, Jp

    def __call__(self, theta) -> tuple[Evaluation, float, np.ndarray]:
        """Roll out ``theta`` once forward (the study's step) and once backward (the adjoint).

        Parameters
        ----------
        theta : array (dimension,)
            The parameter vector.

        Returns
        -------
        evaluation : Evaluation
            The exact robustness of the rollout (as :func:`~mmg_casadi.falsify.robustness.evaluate`).
        smooth : float
            The soft-min margin (L).
        gradient : numpy.ndarray (dimension,)
            ``∂ smooth / ∂ theta``.
        """
        theta = np.asarray(theta, float)
        sc, pr = self._inputs(theta)
        lay = pr.layout
        with run_of([self.method], self.params):
            tr = simulate(lay, pr.x0, pr.p)
        cols = [lay.column(n) for n in STATE]
        states = tr.states[:, :, cols]
        X = np.vstack([tr.t[None, :], tr.states.reshape(len(tr.t), -1).T])
        ev = judge(pr, sc, theta, X[:, -1], tr.t, states, self.objective)
        margins, kinds = own_margins(pr, sc, tr.t, states)
        if self.objective == "grounding":
            margins = np.where(np.array(kinds) == "land", margins, np.nan)
        smooth, w = soft_min(margins, self.kappa)
        w[w < SEED_FLOOR * w.max(initial=0.0)] = 0.0  # the adjoint need not run past the last weight that counts
        if not math.isfinite(smooth):
            return ev, smooth, np.zeros(self.envelope.dimension)
        G, dp = self._seeds(lay, pr, sc, tr.states, w, kinds)
        dx0, dp = self._pull_back(lay, X, pr.p, G, dp)
        Jx, Jp = self.jacobians(theta)
        return ev, smooth, Jx.T @ dx0 + Jp.T @ dp

    def _seeds(self, lay: Layout, pr, sc, ship_states, w, kinds) -> tuple[np.ndarray, np.ndarray]:
        """``∂ smooth/∂x_k`` for every sample (nx × K) and the direct part of ``∂ smooth/∂p`` (hazards' places)."""
        K = ship_states.shape[0]
        _, _, where = agent_reaches(pr, sc)
        idx = _param_index(lay)
        G = np.zeros((lay.nx, K))
        dp = np.zeros(lay.np)
        pos = ship_states[1:, :, [lay.column("x"), lay.column("y")]]
        n_ships, n_obs = lay.n_ships, lay.n_obstacles
        gx, gy = np.zeros((K - 1, n_ships)), np.zeros((K - 1, n_ships))
        for a, kind in enumerate(kinds):
            wa = w[:, a]
            if not wa.any():
                continue
            if kind == "ship":
                rel = pos[:, 0] - pos[:, a + 1]
            elif kind == "obstacle":
                rel = pos[:, 0] - where[a, :2]
            else:
                seg = where[a]
                ab = seg[2:] - seg[:2]
                s = np.clip(((pos[:, 0] - seg[:2]) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
                rel = pos[:, 0] - (seg[:2] + s[:, None] * ab)
            d = np.linalg.norm(rel, axis=1)
            u = rel / np.maximum(d, 1e-12)[:, None] * wa[:, None]  # weight × ∂d/∂p_own
            gx[:, 0] += u[:, 0]
            gy[:, 0] += u[:, 1]
            if kind == "ship":
                gx[:, a + 1] -= u[:, 0]
                gy[:, a + 1] -= u[:, 1]
            elif kind == "obstacle":
                k = a - (n_ships - 1)
                dp[idx["obstacles"][0, k]] -= u[:, 0].sum()
                dp[idx["obstacles"][1, k]] -= u[:, 1].sum()
            else:
                k = a - (n_ships - 1) - n_obs
                for r, wt in ((0, 1.0 - s), (2, s)):
                    dp[idx["walls"][r, k]] -= float((u[:, 0] * wt).sum())
                    dp[idx["walls"][r + 1, k]] -= float((u[:, 1] * wt).sum())
        for i in range(n_ships):
            G[lay.row("x", i), 1:] = gx[:, i]
            G[lay.row("y", i), 1:] = gy[:, i]
        return G, dp

    def _pull_back(self, lay: Layout, X, p, G, dp) -> tuple[np.ndarray, np.ndarray]:
        """The adjoint of the rollout, chunk by chunk from the last seeded sample back to ``x0``."""
        C = self.chunk
        seeded = np.flatnonzero(np.any(G != 0.0, axis=0))
        last = int(seeded[-1]) if seeded.size else 0
        n_chunks = math.ceil(last / C)
        R = adjoint_chunk(lay, C, self.compiled)
        lam = np.zeros(lay.nx)
        dp = dp.copy()
        K = X.shape[1]
        for c in reversed(range(n_chunks)):
            k0 = c * C
            block = np.zeros((lay.nx, C))
            hi = min(k0 + C, K - 1)
            block[:, :hi - k0] = G[:, k0 + 1:hi + 1]
            block[:, C - 1] += lam  # the adjoint of the chunk's last state, carried from the next chunk
            gx, gp = R(X[:, k0], p, block)
            lam = np.array(gx).ravel()
            dp += np.array(gp).ravel()
        return lam + G[:, 0], dp


forget_on_unregister(compiled_step_with_adjoint.cache_clear, adjoint_chunk.cache_clear)
