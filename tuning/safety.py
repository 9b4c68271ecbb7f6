"""Safety-aware training objective of the modified sink-vortex tuning, batched and with exact gradients.

The objective sees what the statistics study judges: closest approaches over whole voyages of hundreds of
sampled scenarios. For one training scenario rolled out with the *smooth* closed loop (``Layout.smooth``, as in
:mod:`tuning.apf`) over ``n`` steps of ``dt``:

    E_own   = Σ_k Σ_j on_j,k exp(−κ d_0j,k)                   (own ship to every ship and obstacle present)
    m_own   = −(1/κ) log(E_own + exp(−κ D_cap))                 (soft-min closest approach, ≤ D_cap)
    safety  = softplus_β(d_safe − m_own) = (1/β) log(1 + exp(β (d_safe − m_own)))
    CE      = (1/(δ_max T)) Σ_k sailing_0,k sqrt(δ_0,k+1² + ε_δ) dt
    MCTE    = (1/T)         Σ_k sailing_0,k sqrt(y_e,0,k² + ε_y) dt

(``fleet`` adds the same margin term over every pair of ships and ship–obstacle), and the training objective is
the mean over scenarios of ``w_safety · safety + w_fleet · safety_fleet + w_ce · CE + w_mcte · MCTE``
(:class:`SafetyConfig`). ``d_safe`` is the collision distance plus ``margin``: a scenario adds to the
objective only when its soft-min approach comes within roughly ``d_safe + 2/β`` — the failures that the
Monte Carlo study counts — while CE and MCTE are small secondary terms that break ties among safe sets.

Gradients are exact: the rollout carries forward sensitivities. One *augmented step*
``z = [x; acc; ∂x/∂θ; ∂acc/∂θ] ↦ z⁺`` is built symbolically (CasADi forward AD, ``jtimes`` with one
direction per tuned parameter), compiled to native code once per layout (disk cache of :mod:`mmg_casadi.compiled`),
``map``-ped over the scenarios of a layout and ``mapaccum``-ed over steps in chunks; the soft-min, softplus
and normalisations are applied in closed form to the final accumulators and their sensitivities.

Measured (2 cores, shared): objective + gradient of 8 environment-5 voyages (10 ships, 4 obstacles) in 0.86 s
for 2952 scenario-steps, 0.29 ms per scenario-step with ``threads=2``; the reverse-mode gradient of the MX
rollout in CasADi's virtual machine (:class:`tuning.apf_ipopt.SmoothProblem`, the same 8 scenarios) took 12.4 s for
5411 scenario-steps, 2.3 ms per scenario-step (single thread). Over the default 200-scenario training set one
evaluation takes 26–84 s depending on the load. The one-off compilation of an augmented step takes 68 s
(environment 3) to 285 s (environment 5).

The tuned parameters are θ = (k_vor0, r_safe); Λ_sink stays at the paper's −100 because without channel
walls the closed loop only sees the direction of the field, which is linear in (K⁰_vor, Λ): only the ratio
K⁰_vor/Λ matters (see :mod:`tuning.apf_ipopt`), so searching K⁰_vor at fixed Λ covers the same trajectories.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop.layout import GLOBAL_PARAMS, Layout
from mmg_casadi.closed_loop.step import AUX, build_closed_loop_step
from mmg_casadi.compiled import compile_function
from mmg_casadi.closed_loop.outcome import run_outcome
from mmg_casadi.errors import InputError, check_range
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.run import build_problem
from mmg_casadi.closed_loop.simulation import simulate_batch

THETA = ("k_vor0", "r_safe")
"""Tuned parameters, in the order of θ (Λ_sink is held at the paper's value, see the module docstring)."""
PAPER = (-10.0, 15.0)
"""The paper's values of θ (K⁰_vor = −10 L²/(L/U), R_safe = 15 L) with Λ_sink = −100."""
LAM_SINK = -100.0
"""Λ_sink held fixed during the search (the paper's value)."""
BOUNDS = ((-40.0, -2.0), (8.0, 25.0))
"""Box of θ: K⁰_vor/Λ from 0.02 to 0.4 (paper 0.1), R_safe from 8 to 25 L."""
_IDX = tuple(GLOBAL_PARAMS.index(k) for k in THETA)
NACC = 4
"""Accumulators of the augmented step: E_own, E_fleet, ∫CE integrand, ∫MCTE integrand."""
FLAGS = ("-O1", "-fPIC", "-shared")
"""Compiler flags of the augmented steps (-O1: the sensitivity code is ~4x the step; -O2 compiles much longer)."""


@dataclass(frozen=True)
class SafetyConfig:
    """Weights and smoothing of the safety-aware training objective (see the module docstring).

    Parameters
    ----------
    smooth : float
        Sigmoid sharpness ``s`` of the smooth closed loop (as ``smooth`` of :class:`tuning.apf_ipopt.TuningConfig`).
    dt : float
        Guidance step of the training rollouts (the scenarios' own 0.25).
    max_steps : int
        Horizon cap in steps (800 · 0.25 = 200 L/U: every successful own ship of environments 3–5 arrives
        before ~160).
    horizon_margin : float
        Time added to the own ship's finishing time in the exact loop at the paper's values.
    kappa : float
        Sharpness of the soft-min over pairs and time (1/L).
    beta : float
        Sharpness of the softplus margin (1/L).
    margin : float
        ``d_safe`` = collision distance + ``margin`` (L).
    d_cap : float
        Cap of the soft-min (L); keeps the logarithm finite when nothing comes near.
    w_safety, w_fleet, w_ce, w_mcte : float
        Weights of the own-ship margin, the fleet margin, CE and MCTE (L⁻¹) in the objective.
    eps_delta, eps_ye : float
        ε of the smoothed absolute values sqrt(x² + ε) (rad², L²).
    threads : int
        Threads of the ``map`` over scenarios.
    batch : int
        Scenarios per compiled ``map`` call.
    chunk : int
        Steps per ``mapaccum`` call (memory: only the chunk's states are stored).
    """

    smooth: float = 10.0
    dt: float = PARAMETERS["dt"].default
    max_steps: int = 800
    horizon_margin: float = 10.0
    kappa: float = 4.0
    beta: float = 2.0
    margin: float = 1.0
    d_cap: float = 30.0
    w_safety: float = 1.0
    w_fleet: float = 0.0
    w_ce: float = 0.1
    w_mcte: float = 0.01
    eps_delta: float = 1e-5
    eps_ye: float = 1e-4
    threads: int = 2
    batch: int = 64
    chunk: int = 50

    def __post_init__(self):
        for name in ("smooth", "dt", "kappa", "beta", "d_cap"):
            check_range(name, getattr(self, name), 0.0, None, low_open=True, cls=InputError)
        for name in ("margin", "w_safety", "w_fleet", "w_ce", "w_mcte", "horizon_margin"):
            check_range(name, getattr(self, name), 0.0, None, cls=InputError)
        for name in ("max_steps", "threads", "batch", "chunk"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise InputError(name, "an integer >= 1", v)


# ------------------------------------------------------------------------------------------ augmented step


def build_augmented_step(layout: Layout, config: SafetyConfig = SafetyConfig()) -> ca.Function:
    """``z ↦ z⁺`` for one step of ``layout`` (smooth) with accumulators and their sensitivities to θ.

    ``z = [x; acc; vec(∂x/∂θ); vec(∂acc/∂θ)]`` (``acc`` = E_own, E_fleet, ∫CE, ∫MCTE integrands, see the
    module docstring); inputs ``(z, p)`` with ``p`` the layout's parameter vector holding θ at its entries.

    Parameters
    ----------
    layout : Layout
        A smooth layout (``smooth`` set).
    config : SafetyConfig
        ``kappa``, ``eps_delta``, ``eps_ye`` are used.

    Returns
    -------
    casadi.Function
        ``safety_aug_<key>(z, p) -> z_next``, ``z`` of :func:`augmented_size` rows.
    """
    if layout.smooth is None:
        raise InputError("layout.smooth", "a sharpness > 0 (the augmented step differentiates the smooth loop)",
                         None)
    step = build_closed_loop_step(layout)
    nx, npar, nt = layout.nx, layout.np, len(THETA)
    N, S = layout.n_ships, layout.n_obstacles
    x = ca.SX.sym("x", nx)
    acc = ca.SX.sym("acc", NACC)
    p = ca.SX.sym("p", npar)
    x_next, aux = step(x, p)
    P = layout.split_params(p)
    obs = P["obstacles"]
    kap = config.kappa

    def st(xv, i, name):
        return xv[layout.row(name, i)]

    def pos(xv, i):
        return ca.vertcat(st(xv, i, "x"), st(xv, i, "y"))

    # present after the step: ships sailing (status 0 at the start of the step, so the flags are piecewise
    # constant and carry no derivative), obstacles always
    sail = [st(x, i, "status") == 0 for i in range(N)]
    e_own, e_fleet = 0, 0
    for i in range(N):
        for j in range(i + 1, N):
            d = ca.norm_2(pos(x_next, i) - pos(x_next, j))
            term = sail[i] * sail[j] * ca.exp(-kap * d)
            e_fleet += term
            if i == 0:
                e_own += term
        for k in range(S):
            d = ca.norm_2(pos(x_next, i) - obs[0:2, k])
            term = sail[i] * ca.exp(-kap * d)
            e_fleet += term
            if i == 0:
                e_own += term
    dt = P["dt"]
    ce_inc = sail[0] * ca.sqrt(st(x_next, 0, "delta") ** 2 + config.eps_delta) * dt
    mcte_inc = sail[0] * ca.sqrt(aux[AUX.index("y_e"), 0] ** 2 + config.eps_ye) * dt
    acc_next = acc + ca.vertcat(e_own, e_fleet, ce_inc, mcte_inc)

    Sx = ca.SX.sym("Sx", nx, nt)
    Sa = ca.SX.sym("Sa", NACC, nt)
    E = ca.DM(npar, nt)
    for j, i in enumerate(_IDX):
        E[i, j] = 1.0
    w = ca.vertcat(x, acc, p)
    out = ca.vertcat(x_next, acc_next)
    seeds = ca.vertcat(Sx, Sa, ca.SX(E))
    dout = ca.jtimes(out, w, seeds)
    z = ca.vertcat(x, acc, ca.vec(Sx), ca.vec(Sa))
    z_next = ca.vertcat(out, ca.vec(dout[:nx, :]), ca.vec(dout[nx:, :]))
    return ca.Function(f"safety_aug_{layout.key()}", [z, p], [z_next], ["z", "p"], ["z_next"])


def augmented_size(layout: Layout) -> int:
    """Rows of the augmented state ``z`` of :func:`build_augmented_step`.

    Parameters
    ----------
    layout : Layout
        The closed-loop layout (its state size ``nx`` sets the size).

    Returns
    -------
    int
        ``(nx + NACC) · (1 + nθ)``: the state, the accumulators and their sensitivities to θ.
    """
    return (layout.nx + NACC) * (1 + len(THETA))


@lru_cache(maxsize=16)
def compiled_augmented_step(layout: Layout, config: SafetyConfig = SafetyConfig()) -> ca.Function:
    """:func:`build_augmented_step` compiled natively (memoised in-process, cached on disk).

    Parameters
    ----------
    layout : Layout
        A smooth layout (``smooth`` set).
    config : SafetyConfig
        ``kappa``, ``eps_delta``, ``eps_ye`` are used (part of the memo key).

    Returns
    -------
    casadi.Function
        The compiled ``(z, p) ↦ z_next``.
    """
    return compile_function(build_augmented_step(layout, config), FLAGS,
                            label=f"smoothed closed loop with sensitivities for {layout.n_ships} ships")


@lru_cache(maxsize=32)
def _rollout(layout: Layout, config: SafetyConfig, batch: int, chunk: int) -> ca.Function:
    f = compiled_augmented_step(layout, config)
    if batch > 1:
        f = f.map(batch, "thread", config.threads) if config.threads > 1 else f.map(batch)
    F = f.mapaccum(chunk)
    nz = augmented_size(layout)
    z = ca.MX.sym("z", nz, batch)
    p = ca.MX.sym("p", layout.np, batch)
    Z = F(z, p)
    return ca.Function("chunk", [z, p], [Z[:, -batch:]])


# ------------------------------------------------------------------------------------------ training cases


@dataclass
class SafetyCase:
    """One training scenario prepared for the smooth augmented rollout (made by :func:`prepare_case`).

    Parameters
    ----------
    name : str
        Case name.
    layout : Layout
        The scenario's closed-loop layout with ``smooth`` set.
    x0 : ndarray
        Initial closed-loop state.
    p : ndarray
        Numeric parameter vector of ``layout`` (``dt``, ``t_max`` and Λ_sink replaced; the θ entries are set
        per evaluation).
    steps : int
        Rollout horizon in steps of ``dt``.
    delta_max : float
        Maximum rudder angle (rad), the normalisation of CE.
    collision_distance : float
        Collision distance (L); ``d_safe`` adds ``margin`` of :class:`SafetyConfig` to it.
    exact_success : bool
        Whether the own ship succeeds in the exact loop at the paper's values.
    exact_d_min : float
        The own ship's closest approach there (L).
    """

    name: str
    layout: Layout          # smooth layout
    x0: np.ndarray
    p: np.ndarray           # numeric parameters (dt and t_max replaced; θ entries set per evaluation)
    steps: int
    delta_max: float
    collision_distance: float
    exact_success: bool     # own ship's outcome in the exact loop at the paper's values
    exact_d_min: float      # own ship's closest approach there


def prepare_case(name: str, sc, config: SafetyConfig = SafetyConfig()) -> SafetyCase:
    """Exact rollout at the paper's values (sets the horizon: own ship's finishing time + margin, capped),
    then the smooth layout and the numeric parameter vector.

    Parameters
    ----------
    name : str
        Case name.
    sc : Scenario
        The scenario (every ship with the modified sink-vortex).
    config : SafetyConfig
        ``dt``, ``max_steps``, ``horizon_margin``, ``smooth``.

    Returns
    -------
    SafetyCase
        Smooth layout, initial state, numeric parameters, number of steps and the exact rollout's success and
        closest approach (L).
    """
    pr = build_problem(sc, {"k_vor0": PAPER[0], "r_safe": PAPER[1], "lam_sink": LAM_SINK})
    xf, _ = simulate_batch(pr.layout, pr.x0[:, None], pr.p[:, None])
    row = run_outcome(pr.layout, xf[:, 0], pr.params)
    t_own = row["time_to_goal"] if row["success"] else float(xf[0, 0])
    g = pr.model.values
    p = np.array(pr.p, float)
    p[GLOBAL_PARAMS.index("dt")] = config.dt
    steps = int(min(math.ceil((t_own + config.horizon_margin) / config.dt), config.max_steps))
    p[GLOBAL_PARAMS.index("t_max")] = max(g["t_max"], steps * config.dt + 1.0)
    p[GLOBAL_PARAMS.index("lam_sink")] = LAM_SINK
    return SafetyCase(name, dataclasses.replace(pr.layout, smooth=float(config.smooth)), np.array(pr.x0, float), p,
                      steps, g["delta_max"], g["collision_distance"], bool(row["success"]),
                      float(row["min_distance"]))


# ------------------------------------------------------------------------------------------ evaluation


def _softplus(v, beta):
    return np.logaddexp(0.0, beta * v) / beta


def _sigmoid(v):
    return 0.5 * (1.0 + np.tanh(0.5 * v))


def case_terms(acc: np.ndarray, dacc: np.ndarray, cases: list[SafetyCase], config: SafetyConfig) -> dict:
    """Per-case terms and their θ-gradients from the final accumulators ``acc`` (NACC, K) and their
    sensitivities ``dacc`` (NACC, nθ, K).

    Parameters
    ----------
    acc : ndarray
        Final accumulators per case (columns).
    dacc : ndarray
        Their derivatives with respect to θ.
    cases : list of SafetyCase
        The cases (columns' order).
    config : SafetyConfig
        Weights and smoothing.

    Returns
    -------
    dict
        Arrays over the cases (K,): ``softmin_own``, ``softmin_fleet`` (L), ``safety_own``, ``safety_fleet``,
        ``ce``, ``mcte`` (L) and ``objective``; and their θ-gradients (nθ, K) under the same names prefixed ``d_``.
    """
    kap, beta = config.kappa, config.beta
    floor = math.exp(-kap * config.d_cap)
    T = np.array([c.steps * config.dt for c in cases])
    dsafe = np.array([c.collision_distance + config.margin for c in cases])
    dmax = np.array([c.delta_max for c in cases])
    out = {}
    for k, key in ((0, "own"), (1, "fleet")):
        m = -np.log(acc[k] + floor) / kap
        dm = -dacc[k] / (kap * (acc[k] + floor))
        out[f"softmin_{key}"] = m
        out[f"safety_{key}"] = _softplus(dsafe - m, beta)
        out[f"d_safety_{key}"] = -_sigmoid(beta * (dsafe - m)) * dm
    out["ce"] = acc[2] / (dmax * T)
    out["d_ce"] = dacc[2] / (dmax * T)
    out["mcte"] = acc[3] / T
    out["d_mcte"] = dacc[3] / T
    w = {"safety_own": config.w_safety, "safety_fleet": config.w_fleet, "ce": config.w_ce, "mcte": config.w_mcte}
    out["objective"] = sum(wk * out[k] for k, wk in w.items())
    out["d_objective"] = sum(wk * out["d_" + k] for k, wk in w.items())
    return out


class SafetyObjective:
    """θ ↦ (J(θ), ∇J(θ)) over a list of :class:`SafetyCase` (mean over cases), grouped by layout.

    Parameters
    ----------
    cases : list of SafetyCase
        Training cases.
    config : SafetyConfig
        Weights, smoothing and batching.
    """

    def __init__(self, cases: list[SafetyCase], config: SafetyConfig = SafetyConfig()):
        if not cases:
            raise InputError("train", "at least one training scenario", 0)
        self.cases = list(cases)
        self.config = config
        self.groups: dict[Layout, list[int]] = {}
        for i, c in enumerate(self.cases):
            self.groups.setdefault(c.layout, []).append(i)
        self.evaluations = 0
        self.eval_time = 0.0

    def compile(self, report=None) -> float:
        """Compile (or load) the augmented step of every layout; returns the seconds it took.

        Parameters
        ----------
        report : callable, optional
            Called with a progress line (str) after each layout's step is ready; ``None`` for silence.

        Returns
        -------
        float
            Wall-clock seconds.
        """
        t0 = time.perf_counter()
        for lay in self.groups:
            compiled_augmented_step(lay, self.config)
            if report:
                report(f"  augmented step {lay.key()} ready ({time.perf_counter() - t0:.0f} s)")
        return time.perf_counter() - t0

    def terms(self, theta, subset=None) -> dict:
        """Per-case terms and gradients (see :func:`case_terms`) at ``theta`` for all cases or ``subset``
        (case indices); keys also ``index`` (the case indices, in the order of the arrays).

        Parameters
        ----------
        theta : sequence of float
            (k_vor0, r_safe).
        subset : sequence of int, optional
            Case indices (default all).

        Returns
        -------
        dict
            The dict of :func:`case_terms` plus ``index``.
        """
        t0 = time.perf_counter()
        theta = np.asarray(theta, float).ravel()
        want = set(range(len(self.cases))) if subset is None else set(int(i) for i in subset)
        cfg = self.config
        nt = len(THETA)
        idx_all, acc_all, dacc_all = [], [], []
        for lay, members in self.groups.items():
            members = [i for i in members if i in want]
            for b0 in range(0, len(members), cfg.batch):
                part = members[b0:b0 + cfg.batch]
                B = len(part)
                nx = lay.nx
                Z = np.zeros((augmented_size(lay), B))
                P = np.column_stack([self.cases[i].p for i in part])
                for j, i in enumerate(part):
                    Z[:nx, j] = self.cases[i].x0
                for k, name in enumerate(THETA):
                    P[_IDX[k], :] = theta[k]
                steps = max(self.cases[i].steps for i in part)
                done = 0
                while done < steps:
                    n = min(cfg.chunk, steps - done)
                    Z = np.array(_rollout(lay, cfg, B, n)(Z, P))
                    done += n
                acc = Z[nx:nx + NACC, :]
                sens = Z[nx + NACC:, :]
                dacc = sens[nx * nt:, :].reshape(nt, NACC, B).transpose(1, 0, 2)  # vec is column-major
                idx_all += part
                acc_all.append(acc)
                dacc_all.append(dacc)
        order = np.argsort(idx_all)
        acc = np.concatenate(acc_all, axis=1)[:, order]
        dacc = np.concatenate(dacc_all, axis=2)[:, :, order]
        out = case_terms(acc, dacc, [self.cases[i] for i in sorted(idx_all)], cfg)
        out["index"] = np.array(sorted(idx_all))
        self.evaluations += 1
        self.eval_time += time.perf_counter() - t0
        return out

    def __call__(self, theta, subset=None) -> tuple[float, np.ndarray]:
        """Mean objective over the cases (or ``subset``) and its exact gradient.

        Parameters
        ----------
        theta : sequence of float
            (k_vor0, r_safe).
        subset : sequence of int, optional
            Case indices (default all).
        """
        t = self.terms(theta, subset)
        return float(np.mean(t["objective"])), np.mean(t["d_objective"], axis=1)


def gradient_check(objective: SafetyObjective, theta=PAPER, rel_step: float = 1e-6, subset=None) -> dict:
    """Exact gradient of the objective against central finite differences with steps ``rel_step · |θ_k|``.

    Parameters
    ----------
    objective : SafetyObjective
        The objective.
    theta : sequence of float
        Where to check.
    rel_step : float
        Relative finite-difference step.
    subset : sequence of int, optional
        Case indices (default all).

    Returns
    -------
    dict
        ``theta``, ``names``, ``objective``, ``ad`` and ``fd`` (the gradients), ``rel_step`` and ``rel_error_norm``
        (``‖g_AD − g_FD‖ / ‖g_AD‖``).
    """
    theta = np.asarray(theta, float)
    J, g = objective(theta, subset)
    fd = np.zeros(len(theta))
    for k in range(len(theta)):
        h = rel_step * max(abs(theta[k]), 1.0)
        e = np.zeros(len(theta))
        e[k] = h
        fd[k] = (objective(theta + e, subset)[0] - objective(theta - e, subset)[0]) / (2 * h)
    return {"theta": theta.tolist(), "names": list(THETA), "objective": J, "ad": g.tolist(), "fd": fd.tolist(),
            "rel_step": rel_step,
            "rel_error_norm": float(np.linalg.norm(g - fd) / max(np.linalg.norm(g), 1e-300))}
