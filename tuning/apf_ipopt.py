"""Superseded IPOPT tuner of the modified sink-vortex field (K⁰_vor, Λ_sink, R_safe), kept for the notebook
``notebooks/apf_tuning.ipynb`` and ``tests/test_tuning_apf.py`` that use it.

This was the first version of the APF tuning: IPOPT on CE + MCTE with a soft-min separation constraint over a
dozen short scenarios. ``mmg-casadi tune apf`` now uses the safety-aware objective of :mod:`tuning.safety` over
hundreds of whole voyages, the grid + L-BFGS-B search of :mod:`tuning.search` and the paired held-out judgement of
:mod:`tuning.judge`; the training and held-out scenarios (:mod:`tuning.apf`) are shared. The VM-based problem
below and its measurements are what :mod:`tuning.safety` compares with.

The closed loop of every training scenario is rolled out with the *smooth* step
(``Layout(..., smooth=s)``: every switch — R_safe activation, reactive/ILOS blend, the modified vortex's
on/off and max(1, ·) — is a sigmoid/softplus of sharpness ``s``) over a fixed horizon with ``mapaccum``; the
parameter vector of the step is numeric except for the three tuned entries, which are decision variables
θ = (k_vor0, lam_sink, r_safe) (``p = p_num + E θ`` with a constant selection matrix ``E``). CasADi's
algorithmic differentiation gives the exact gradient of

    J(θ) = Σ_scenarios Σ_ships [ CE + w · MCTE ] + ρ Σ_k ((θ_k − θ⁰_k) / (ub_k − lb_k))²

    CE   = (1/(δ_max T)) Σ_k sailing_k · sqrt(δ_{k+1}² + ε_δ) · dt      (smoothed ∫|δ| dt)
    MCTE = (1/T)         Σ_k sailing_k · sqrt(y_e,k² + ε_y) · dt          (smoothed ∫|y_e| dt)

and of one safety constraint per scenario, computed from the rollout states (not from the ``d_min``
accumulator, whose ``if_else`` has a zero derivative between its switches):

    softmin_κ(d) = −(1/κ) log Σ_{pairs, k} exp(−κ d_pair,k)  ≥  min(collision_distance + margin, softmin at θ⁰)

over all ship–ship and ship–obstacle distances while both are in the scenario. The soft-min is below the true
minimum (by at most log(#terms)/κ; with κ = 4 /L about 0.4–0.7 L on the paper's encounters, up to ~2 L in
sampled multi-ship scenarios where several pairs stay close for a long time), so the constraint is
conservative; scenarios whose soft-min is already below ``collision_distance + margin`` at the paper's values
are only asked not to get worse. The problem is solved with IPOPT (L-BFGS Hessian, a few tens of iterations) from the paper's values
(−10, −100, 15).

Observations that shape the problem (see :func:`tune` and the report):

* The closed loop only uses the *direction* of the field (ψ_d = atan2 of the field vector), and without channel
  walls the modified sink-vortex field is linear in (K⁰_vor, Λ): scaling both by c > 0 leaves every
  trajectory unchanged. The objective is therefore constant along rays in the (k_vor0, lam_sink) plane — only
  the ratio K⁰_vor/Λ and R_safe matter. The small proximal term ρ (default 1e-3) pins the scale so that the
  NLP has an isolated solution; the report also gives the ratio.
* Training step: dt = 0.25 (the scenarios' own step). dt = 0.5 was measured in the exact loop and rejected:
  closest approaches and MCTE change by < 5 %, but the PD loop with the rudder command held over 0.5 time
  units chatters and CE grows by 2–88 % (static obstacle 0.145 → 0.228, head-on 0.155 → 0.189, crossing ship 1
  0.139 → 0.193, conflict ship 2 0.090 → 0.169). With dt = 0.25 the horizon cap of 300 steps is T = 75: the
  long scenarios (overtaking, conflict, most samples) are truncated after their main encounters.
* Derivatives: the natively compiled steps of :mod:`mmg_casadi.compiled` have no derivatives, so the rollout
  uses the SX step in CasADi's virtual machine (``step.mapaccum``, an MX graph); the objective with its
  gradient costs ~10–170 ms per scenario of ≤ 300 steps. CasADi's own ``jit`` of the NLP functions
  (``TuningConfig.jit``) makes IPOPT 6.5x faster but its compilation (gcc -O1 of the functions and their
  derivatives) takes longer than the whole VM solve at the default sizes, so the VM is the default; see
  :data:`MEASURED`. Exact and finite-difference gradients agree to ~1e-7 (relative, central differences with
  step ``1e-6 |θ|``); with step ``1e-4 |θ|`` the R_safe component is off by ~7 % because the differences straddle
  kinks of the loop (rudder saturation, goal reached), which the AD gradient does not see.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from mmg_casadi.closed_loop.simulation import simulate, simulate_batch
from mmg_casadi.closed_loop.layout import GLOBAL_PARAMS, Layout
from mmg_casadi.closed_loop.step import AUX, build_closed_loop_step
from mmg_casadi.errors import InputError, check_range
from mmg_casadi.io import write_text
from mmg_casadi.closed_loop.outcome import run_outcome
from mmg_casadi.montecarlo.results import wilson_interval
from mmg_casadi.params import PARAMETERS
from mmg_casadi.progress import say
from mmg_casadi.scenarios.run import build_problem, run_scenario

from .apf import HOLDOUT_SEED, sampled_scenario

THETA = ("k_vor0", "lam_sink", "r_safe")
"""Tuned parameters, in the order of θ."""
PAPER = (-10.0, -100.0, 15.0)
"""The paper's values of θ: K⁰_vor = −10, Λ_sink = −100, R_safe = 15 L."""
BOUNDS = ((-40.0, -2.0), (-300.0, -30.0), (8.0, 25.0))
"""Box bounds of θ (L²/unit time, L²/unit time, L)."""
THETA_INDEX = tuple(GLOBAL_PARAMS.index(k) for k in THETA)
FEAS_TOL = 1e-3
"""Tolerance (L) on the soft-min distance constraints when the best IPOPT iterate is picked."""

MEASURED = {
    "note": "2-core machine, CasADi 3.8.2, VM unless stated",
    "head-on (2 ships, 220 steps) f / f+grad [ms]": (1.5, 12.0),
    "env-2 sample (4 ships, 2 obstacles, 300 steps) f / f+grad [ms]": (19.0, 44.0),
    "7 scenarios, 15 IPOPT iterations, VM: nlpsol build / solve [s]": (0.5, 13.6),
    "7 scenarios, 15 IPOPT iterations, jit (shell, -O1): compile / solve [s]": (65.2, 2.1),
    "13 scenarios (default), 30 IPOPT iterations, VM: solve [s]": 34.5,
}
"""Timings measured while writing this module (the reason the VM is the default)."""


@dataclass(frozen=True)
class TuningConfig:
    """Settings of the smoothed training problem.

    Parameters
    ----------
    smooth : float
        Sigmoid sharpness ``s`` of the smooth closed loop (1/L for distances, 1/rad for angles). 10 keeps the
        smooth loop close to the exact one (closest approaches within a few tenths of L) while the transitions
        still span several steps, so the objective is differentiable in practice, not only in theory.
    dt : float
        Guidance step of the training rollouts (0.25, see the module docstring for why not 0.5).
    max_steps : int
        Cap of the training horizon in steps (horizon T = min(exact time to finish + ``horizon_margin``,
        ``max_steps`` dt)).
    horizon_margin : float
        Time added to the exact loop's finishing time (non-dimensional).
    w_mcte : float
        Weight w of MCTE (L) against CE (dimensionless); 0.1 makes typical values (CE ~0.15, MCTE ~1.5 L)
        comparable.
    kappa : float
        Sharpness of the soft-min of distances (1/L).
    margin : float
        Safety margin above the collision distance in the constraint (L).
    eps_delta, eps_ye : float
        ε of the smoothed absolute values sqrt(x² + ε) (rad², L²).
    reg : float
        Weight ρ of the proximal term that fixes the scale of (K⁰_vor, Λ) (see the module docstring).
    max_iter : int
        IPOPT iterations.
    jit : bool
        Compile the NLP functions (with their derivatives) with CasADi's ``jit`` instead of the VM.
    hessian : {"lbfgs", "exact"}
        IPOPT's Hessian: limited-memory BFGS (default) or CasADi's exact second derivatives through the
        rollouts (measured: ~3x slower per iteration and, on this non-convex objective, no better).
    """

    smooth: float = 10.0
    dt: float = PARAMETERS["dt"].default
    max_steps: int = 300
    horizon_margin: float = 5.0
    w_mcte: float = 0.1
    kappa: float = 4.0
    margin: float = 1.0
    eps_delta: float = 1e-5
    eps_ye: float = 1e-4
    reg: float = 1e-3
    max_iter: int = 30
    jit: bool = False
    hessian: str = "lbfgs"

    def __post_init__(self):
        check_range("smooth", self.smooth, 0.0, None, low_open=True, cls=InputError)
        check_range("dt", self.dt, 0.0, None, low_open=True, cls=InputError)
        check_range("kappa", self.kappa, 0.0, None, low_open=True, cls=InputError)
        check_range("margin", self.margin, 0.0, None, cls=InputError)
        check_range("w_mcte", self.w_mcte, 0.0, None, cls=InputError)
        check_range("reg", self.reg, 0.0, None, cls=InputError)
        for name in ("max_steps", "max_iter"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise InputError(name, "an integer >= 1", v)
        if self.hessian not in ("lbfgs", "exact"):
            raise InputError("hessian", "one of: lbfgs, exact", self.hessian)


# ---------------------------------------------------------------------------------------------------------------
# the smoothed training problem


@dataclass
class TrainingCase:
    """One training scenario prepared for the smooth rollout.

    Parameters
    ----------
    name : str
        Scenario name.
    layout : Layout
        Smooth closed-loop layout (``smooth`` set from the configuration).
    x0 : ndarray
        Initial state of the closed loop.
    p : ndarray
        Numeric step parameters (``dt`` replaced, ``t_max`` beyond the horizon; θ entries are overwritten by E θ).
    steps : int
        Number of training steps.
    horizon : float
        Training horizon ``steps · dt`` (L/U).
    delta_max : float
        Rudder limit (rad), normalising CE.
    collision_distance : float
        Collision distance of the scenario (L).
    exact_t_end : float
        Finishing time of the exact loop at the paper's values (L/U).
    exact_d_min : float
        Closest approach of the exact loop at the paper's values (L).
    """

    name: str
    layout: Layout          # smooth layout
    x0: np.ndarray
    p: np.ndarray           # numeric parameters (dt replaced; θ entries are overwritten by E θ)
    steps: int
    horizon: float
    delta_max: float
    collision_distance: float
    exact_t_end: float
    exact_d_min: float


def _theta_params(p_num: np.ndarray, theta):
    """``p_num`` with the θ entries replaced by ``theta`` (symbolic or numeric), as p_num·mask + E θ."""
    n = len(p_num)
    keep = np.array(p_num, float)
    keep[list(THETA_INDEX)] = 0.0
    E = ca.DM(n, 3)
    for j, i in enumerate(THETA_INDEX):
        E[i, j] = 1.0
    return ca.DM(keep) + ca.mtimes(E, theta)


def prepare_case(name: str, sc, config: TuningConfig = TuningConfig()) -> TrainingCase:
    """Exact rollout at the paper's values (for the horizon), then the smooth layout and numeric parameters.

    Parameters
    ----------
    name : str
        Name given to the case.
    sc : Scenario
        The scenario (modified sink-vortex guidance).
    config : TuningConfig
        Settings of the smoothed training problem.

    Returns
    -------
    TrainingCase
        Smooth layout, initial state, numeric parameters, horizon and the exact rollout's end time and closest
        approach.
    """
    pr = build_problem(sc, dict(zip(THETA, PAPER)))
    layout, x0, p = pr.layout, pr.x0, pr.p
    g = pr.model.values
    tr = simulate(layout, x0, p)
    t_end = float(tr.t[-1])
    d_min = float(np.min(tr.state("d_min")[-1]))
    p = np.array(p, float)
    p[GLOBAL_PARAMS.index("dt")] = config.dt
    steps = int(min(math.ceil((t_end + config.horizon_margin) / config.dt), config.max_steps))
    # keep the step's own horizon out of the way: sailing must not stop at t_max inside the training horizon
    p[GLOBAL_PARAMS.index("t_max")] = max(g["t_max"], steps * config.dt + 1.0)
    return TrainingCase(name, dataclasses.replace(layout, smooth=float(config.smooth)), np.array(x0, float), p,
                        steps, steps * config.dt, g["delta_max"], g["collision_distance"], t_end, d_min)


def case_terms(case: TrainingCase, theta, config: TuningConfig = TuningConfig(), step: ca.Function | None = None):
    """Symbolic terms of one training case for ``theta`` (MX 3×1): ``(objective, softmin distance, ce, mcte)``
    where ``ce`` and ``mcte`` are per-ship rows (smoothed CE and MCTE over the horizon).

    Parameters
    ----------
    case : TrainingCase
        The prepared training case.
    theta : MX
        θ = (k_vor0, lam_sink, r_safe), 3×1 (symbolic or numeric).
    config : TuningConfig
        Settings of the smoothed training problem.
    step : casadi.Function, optional
        Closed-loop step of ``case.layout``; built if None.

    Returns
    -------
    J : casadi.MX
        CE + w MCTE summed over the ships (smoothed).
    softmin : casadi.MX
        Soft minimum of the pair and ship–obstacle distances while sailing (L).
    ce : casadi.MX (1, N)
        Smoothed CE per ship.
    mcte : casadi.MX (1, N)
        Smoothed MCTE per ship (L).
    """
    step = step or build_closed_loop_step(case.layout)
    n = case.steps
    p = _theta_params(case.p, theta)
    F = step.mapaccum(n)
    X, A = F(ca.DM(case.x0), ca.repmat(p, 1, n))
    Xall = ca.horzcat(ca.DM(case.x0), X)           # nx × (n+1): states at t_0 .. t_n
    N = case.layout.n_ships

    def row(i, name, M=Xall):
        return M[case.layout.row(name, i), :]

    dt, T = config.dt, case.horizon
    ce, mcte, sail = [], [], []
    for i in range(N):
        s_i = row(i, "status") == 0                # 1 while sailing (piecewise constant: zero derivative)
        sail.append(s_i)
        d_next = row(i, "delta")[:, 1:]
        y_e = A[AUX.index("y_e"), ca.Slice(i, A.size2(), N)]  # aux is NAUX × (N n): step-major
        ce.append(ca.sum2(s_i[:, :n] * ca.sqrt(d_next ** 2 + config.eps_delta)) * dt / (case.delta_max * T))
        mcte.append(ca.sum2(s_i[:, :n] * ca.sqrt(y_e ** 2 + config.eps_ye)) * dt / T)
    ce_row, mcte_row = ca.horzcat(*ce), ca.horzcat(*mcte)
    J = ca.sum2(ce_row) + config.w_mcte * ca.sum2(mcte_row)

    # soft-min of all pair distances while both agents are sailing (states after each step; obstacles always)
    big = 1.0e3
    pos = [(row(i, "x")[:, 1:], row(i, "y")[:, 1:]) for i in range(N)]
    on = [s[:, 1:] for s in sail]
    obs = np.array(case.layout.split_params(ca.DM(case.p))["obstacles"])
    dists = []
    for i in range(N):
        for j in range(i + 1, N):
            d = ca.sqrt((pos[i][0] - pos[j][0]) ** 2 + (pos[i][1] - pos[j][1]) ** 2)
            dists.append(d + big * (1 - on[i] * on[j]))
        for k in range(case.layout.n_obstacles):
            ox, oy = float(obs[0, k]), float(obs[1, k])
            d = ca.sqrt((pos[i][0] - ox) ** 2 + (pos[i][1] - oy) ** 2)
            dists.append(d + big * (1 - on[i]))
    D = ca.horzcat(*dists)
    m = ca.mmin(D)
    softmin = m - ca.log(ca.sum2(ca.exp(-config.kappa * (D - m)))) / config.kappa
    return J, softmin, ce_row, mcte_row


class SmoothProblem:
    """The smoothed training problem over a set of :class:`TrainingCase`: θ ↦ (J(θ), softmin per case).

    ``objective(θ)`` and ``constraints(θ)`` evaluate numerically; ``function`` is the CasADi Function
    ``θ -> (J, g)`` (J without the proximal term), ``gradient(θ)`` its exact gradient.

    Parameters
    ----------
    cases : list of TrainingCase
        Training cases (at least one).
    config : TuningConfig
        Settings of the smoothed training problem.
    """

    def __init__(self, cases: list[TrainingCase], config: TuningConfig = TuningConfig()):
        if not cases:
            raise InputError("training set", "at least one scenario", 0)
        self.cases = list(cases)
        self.config = config
        theta = ca.MX.sym("theta", 3)
        steps = {}
        J, G, CE, MCTE = 0, [], [], []
        for c in self.cases:
            if c.layout not in steps:
                steps[c.layout] = build_closed_loop_step(c.layout)
            j, g, ce, mc = case_terms(c, theta, config, steps[c.layout])
            J += j
            G.append(g)
            CE.append(ce)
            MCTE.append(mc)
        self.theta = theta
        self.J = J
        self.g = ca.vertcat(*G)
        self.function = ca.Function("apf_objective", [theta], [J, self.g], ["theta"], ["J", "g"])
        self.grad_function = ca.Function("apf_gradient", [theta], [ca.gradient(J, theta)], ["theta"], ["dJ"])
        self.terms_function = ca.Function("apf_terms", [theta], [ca.horzcat(*CE), ca.horzcat(*MCTE)],
                                          ["theta"], ["ce", "mcte"])

    def objective(self, theta) -> float:
        return float(self.function(np.asarray(theta, float))[0])

    def constraints(self, theta) -> np.ndarray:
        return np.array(self.function(np.asarray(theta, float))[1]).ravel()

    def gradient(self, theta) -> np.ndarray:
        return np.array(self.grad_function(np.asarray(theta, float))).ravel()

    def per_case(self, theta) -> list[dict]:
        """Smoothed CE / MCTE per ship and the soft-min distance of every case at ``theta``.

        Parameters
        ----------
        theta : array_like
            θ = (k_vor0, lam_sink, r_safe).

        Returns
        -------
        list of dict
            One per case: ``name``, ``ce`` and ``mcte`` (lists, one per ship; MCTE in L), ``softmin_distance`` (L).
        """
        ce, mc = (np.array(v).ravel() for v in self.terms_function(np.asarray(theta, float)))
        g = self.constraints(theta)
        out, k = [], 0
        for c, gi in zip(self.cases, g):
            n = c.layout.n_ships
            out.append({"name": c.name, "ce": ce[k:k + n].tolist(), "mcte": mc[k:k + n].tolist(),
                        "softmin_distance": float(gi)})
            k += n
        return out


def gradient_check(problem: SmoothProblem, theta=PAPER, rel_step: float = 1e-6) -> dict:
    """Exact (AD) gradient of the smoothed objective against central finite differences with steps
    ``rel_step · |θ_k|``. Returns both gradients and the relative error per component and overall
    (‖g_AD − g_FD‖ / ‖g_AD‖).

    Parameters
    ----------
    problem : SmoothProblem
        The smoothed training problem.
    theta : array_like
        θ = (k_vor0, lam_sink, r_safe) at which to compare; the paper's values by default.
    rel_step : float
        Relative finite-difference step (of ``max(|θ_k|, 1)``).

    Returns
    -------
    dict
        ``theta``, ``names``, ``ad`` and ``fd`` (the gradients), ``rel_step``, ``rel_error`` (per component),
        ``rel_error_norm``, ``ad_time_s`` (s) and ``scale_invariance`` (``g_0 θ_0 + g_1 θ_1``).
    """
    theta = np.asarray(theta, float)
    t0 = time.perf_counter()
    g = problem.gradient(theta)
    t_ad = time.perf_counter() - t0
    fd = np.zeros(3)
    for k in range(3):
        h = rel_step * max(abs(theta[k]), 1.0)
        e = np.zeros(3)
        e[k] = h
        fd[k] = (problem.objective(theta + e) - problem.objective(theta - e)) / (2 * h)
    comp = np.abs(g - fd) / np.maximum(np.abs(g), 1e-300)
    return {"theta": theta.tolist(), "names": list(THETA), "ad": g.tolist(), "fd": fd.tolist(),
            "rel_step": rel_step, "rel_error": comp.tolist(),
            "rel_error_norm": float(np.linalg.norm(g - fd) / max(np.linalg.norm(g), 1e-300)),
            "ad_time_s": t_ad,
            "scale_invariance": float(g[0] * theta[0] + g[1] * theta[1])}


@dataclass
class TuningResult:
    """Outcome of :func:`tune`.

    ``params_before`` / ``params_after``: θ as ``{name: value}``; ``objective_before`` / ``objective_after``:
    the smoothed training objective (without the proximal term); ``constraints_*``: soft-min distance per
    training scenario with its lower bound ``constraint_bounds``; ``iterations``: IPOPT's iterates
    (``iter``, ``objective``, ``theta``, ``min_slack``); ``gradient_check``: see :func:`gradient_check`.

    Parameters
    ----------
    params_before : dict
        Initial θ as ``{name: value}``.
    params_after : dict
        Tuned θ as ``{name: value}``.
    objective_before : float
        Smoothed training objective at the initial θ (without the proximal term).
    objective_after : float
        Smoothed training objective at the tuned θ.
    constraints_before : list of float
        Soft-min distance per training scenario at the initial θ (L).
    constraints_after : list of float
        Soft-min distance per training scenario at the tuned θ (L).
    constraint_bounds : list of float
        Lower bound of each soft-min distance (L).
    gradient_check : dict
        Result of :func:`gradient_check` (empty if not run).
    iterations : list of dict
        IPOPT's iterates.
    status : str
        IPOPT's return status (with a note if the initial values were kept).
    scenarios : list of str
        Names of the training scenarios.
    horizons : list of float
        Training horizon of each scenario (L/U).
    config : dict
        The :class:`TuningConfig` as a dict.
    timings : dict
        Wall-clock times of the stages (s).
    per_case_before : list of dict
        :meth:`SmoothProblem.per_case` at the initial θ.
    per_case_after : list of dict
        :meth:`SmoothProblem.per_case` at the tuned θ.
    """

    params_before: dict
    params_after: dict
    objective_before: float
    objective_after: float
    constraints_before: list
    constraints_after: list
    constraint_bounds: list
    gradient_check: dict
    iterations: list
    status: str
    scenarios: list
    horizons: list
    config: dict
    timings: dict = field(default_factory=dict)
    per_case_before: list = field(default_factory=list)
    per_case_after: list = field(default_factory=list)

    @property
    def theta_after(self) -> tuple:
        return tuple(self.params_after[k] for k in THETA)

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["ratio_before"] = self.params_before["k_vor0"] / self.params_before["lam_sink"]
        d["ratio_after"] = self.params_after["k_vor0"] / self.params_after["lam_sink"]
        return d


class _Progress(ca.Callback):
    """IPOPT iteration callback: records and reports the objective and θ of every iterate."""

    def __init__(self, nx: int, ng: int, to_theta, prox, lbg, report):
        ca.Callback.__init__(self)
        self.nx, self.ng = nx, ng
        self.to_theta = to_theta
        self.prox = prox
        self.lbg = np.asarray(lbg, float)
        self.report = report
        self.records = []
        self.construct("apf_progress", {})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name == "f":
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.nx)
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.ng)
        return ca.Sparsity(0, 0)

    def eval(self, arg):
        d = dict(zip([ca.nlpsol_out(i) for i in range(ca.nlpsol_n_out())], arg))
        z = np.array(d["x"]).ravel()
        theta = self.to_theta(z)
        slack = float(np.min(np.array(d["g"]).ravel() - self.lbg)) if self.ng else 0.0
        rec = {"iter": len(self.records), "objective": float(d["f"]) - self.prox(z), "theta": [float(v) for v in theta],
               "min_slack": slack}
        self.records.append(rec)
        if self.report:
            self.report(f"  ipopt iter {rec['iter']:3d}  J = {rec['objective']:.6f}  "
                        f"k_vor0 = {theta[0]:8.3f}  lam_sink = {theta[1]:9.3f}  r_safe = {theta[2]:7.3f}  "
                        f"min slack {slack:+.3f} L")
        return [0]


def prepare_cases(scenarios: dict, config: TuningConfig = TuningConfig(), report=None) -> list[TrainingCase]:
    """:func:`prepare_case` for every scenario, optionally reporting each case's size and horizon.

    Parameters
    ----------
    scenarios : dict
        Scenario name -> Scenario.
    config : TuningConfig
        Settings of the smoothed training problem.
    report : callable, optional
        Takes one progress line per case; None for silence.

    Returns
    -------
    list of TrainingCase
        One per scenario, in the order of ``scenarios``.
    """
    out = []
    for name, sc in scenarios.items():
        c = prepare_case(name, sc, config)
        if report:
            report(f"  {name:>16s}: {c.layout.n_ships} ships, {c.layout.n_obstacles} obstacles, "
                   f"{c.steps} steps (T = {c.horizon:g}; exact loop finishes at {c.exact_t_end:g}, "
                   f"closest approach {c.exact_d_min:.2f} L)")
        out.append(c)
    return out


def tune(scenarios, config: TuningConfig = TuningConfig(), *, theta0=PAPER, report=say,
         check_gradient: bool = True) -> TuningResult:
    """Tune θ = (k_vor0, lam_sink, r_safe) on ``scenarios`` (a dict name -> Scenario, or prepared
    :class:`TrainingCase` list) with IPOPT; ``report`` (a callable taking a line, or None) gets the progress.

    Parameters
    ----------
    scenarios : dict or list of TrainingCase
        Scenario name -> Scenario, or cases already prepared.
    config : TuningConfig
        Settings of the smoothed training problem.
    theta0 : array_like
        Initial θ = (k_vor0, lam_sink, r_safe); the paper's values by default.
    report : callable, optional
        Takes one progress line; None for silence.
    check_gradient : bool
        Whether to compare the AD gradient with finite differences at ``theta0`` first.

    Returns
    -------
    TuningResult
        θ and objective before and after, constraints, IPOPT iterates and status, gradient check, timings and the
        per-case terms.
    """
    timings = {}
    t0 = time.perf_counter()
    if isinstance(scenarios, dict):
        cases = prepare_cases(scenarios, config, report)
    else:
        cases = list(scenarios)
    timings["prepare_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    prob = SmoothProblem(cases, config)
    timings["build_s"] = time.perf_counter() - t0
    theta0 = np.asarray(theta0, float)
    lb = np.array([b[0] for b in BOUNDS])
    ub = np.array([b[1] for b in BOUNDS])
    span = ub - lb

    t0 = time.perf_counter()
    J0, g0 = (np.array(v).ravel() for v in prob.function(theta0))
    J0 = float(J0[0])
    timings["objective_eval_s"] = time.perf_counter() - t0
    gc = {}
    if check_gradient:
        gc = gradient_check(prob, theta0)
        if report:
            report(f"  gradient check at {tuple(theta0.tolist())}: AD {np.round(gc['ad'], 6).tolist()}  "
                   f"FD {np.round(gc['fd'], 6).tolist()}  relative error {gc['rel_error_norm']:.2e}")
    safe = [c.collision_distance + config.margin for c in cases]
    lbg = np.minimum(safe, g0)

    # decision variables scaled to the unit box: θ = lb + span z
    z = ca.MX.sym("z", 3)
    th = ca.DM(lb) + ca.DM(span) * z
    z0 = (theta0 - lb) / span
    Jz, gz = prob.function(th)
    prox = config.reg * ca.sumsqr(z - ca.DM(z0))
    nlp = {"x": z, "f": Jz + prox, "g": gz}
    cb = _Progress(3, len(cases), lambda zz: lb + span * zz,
                   lambda zz: config.reg * float(np.sum((zz - z0) ** 2)), lbg, report)
    opts = {"ipopt.max_iter": int(config.max_iter), "ipopt.print_level": 0, "print_time": False,
            "ipopt.tol": 1e-6, "ipopt.acceptable_tol": 1e-4, "ipopt.acceptable_iter": 5, "ipopt.sb": "yes",
            "iteration_callback": cb}
    if config.hessian == "lbfgs":
        opts["ipopt.hessian_approximation"] = "limited-memory"
    if config.jit:
        opts.update({"jit": True, "compiler": "shell", "jit_options": {"flags": ["-O1"], "verbose": False}})
    t0 = time.perf_counter()
    solver = ca.nlpsol("apf_tuning", "ipopt", nlp, opts)
    timings["nlpsol_build_s"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    sol = solver(x0=z0, lbx=0, ubx=1, lbg=lbg, ubg=np.inf)
    timings["solve_s"] = time.perf_counter() - t0
    stats = solver.stats()
    status = str(stats.get("return_status", "unknown"))
    # IPOPT may stop (iteration limit) at an iterate that is worse than an earlier one or slightly infeasible:
    # take the best iterate (smoothed objective without the proximal term) whose constraints hold to FEAS_TOL
    cands = [(r["objective"], r["min_slack"], np.array(r["theta"])) for r in cb.records]
    theta_end = lb + span * np.array(sol["x"]).ravel()
    J_end, g_end = (np.array(v).ravel() for v in prob.function(theta_end))
    cands.append((float(J_end[0]), float(np.min(g_end - lbg)), theta_end))
    ok = [c for c in cands if c[1] >= -FEAS_TOL]
    best = min(ok, key=lambda c: c[0]) if ok else (J0, 0.0, theta0)
    theta1 = best[2]
    J1, g1 = (np.array(v).ravel() for v in prob.function(theta1))
    J1 = float(J1[0])
    if J1 >= J0:
        theta1, J1, g1 = theta0, J0, g0
        status += " (no feasible improvement: initial values kept)"
    if report:
        report(f"  IPOPT: {status}, {len(cb.records)} iterates, J {J0:.6f} -> {J1:.6f} in {timings['solve_s']:.1f} s")
    return TuningResult(
        params_before=dict(zip(THETA, map(float, theta0))), params_after=dict(zip(THETA, map(float, theta1))),
        objective_before=J0, objective_after=J1, constraints_before=g0.tolist(), constraints_after=g1.tolist(),
        constraint_bounds=lbg.tolist(), gradient_check=gc, iterations=cb.records, status=status,
        scenarios=[c.name for c in cases], horizons=[c.horizon for c in cases],
        config=dataclasses.asdict(config), timings=timings,
        per_case_before=prob.per_case(theta0), per_case_after=prob.per_case(theta1))


def write_params_toml(result: TuningResult | dict, path) -> None:
    """Write the tuned values as ``[params]`` (read by ``mmg-casadi simulate/study --params``).

    Parameters
    ----------
    result : TuningResult or dict
        The tuning result (its ``params_after``), or θ as ``{name: value}``.
    path : str or path-like
        TOML file to write (parent directories are created).
    """
    params = result.params_after if isinstance(result, TuningResult) else dict(result)
    lines = ["# modified sink-vortex parameters tuned by `mmg-casadi tune apf` (tuning/apf.py)", "[params]"]
    lines += [f"{k} = {float(params[k])!r}" for k in THETA]
    write_text(path, "\n".join(lines) + "\n")


# ---------------------------------------------------------------------------------------------------------------
# evaluation with the exact closed loop


def evaluate(param_sets: dict, *, envs=(1, 2, 3, 4, 5), runs: int = 40, base_seed: int = HOLDOUT_SEED,
             report=say) -> dict:
    """Exact closed loop on the held-out scenarios: for every environment, ``runs`` scenarios drawn with
    ``base_seed`` and every parameter set of ``param_sets`` (name -> {k_vor0, lam_sink, r_safe}) in one batch
    (:func:`mmg_casadi.closed_loop.simulation.simulate_batch`). Returns ``{env: {name: summary}}`` with success rate and
    its Wilson 95 % interval, failures by kind, and mean CE / MCTE of the own ship over its successful runs.

    Parameters
    ----------
    param_sets : dict
        Name -> ``{k_vor0, lam_sink, r_safe}``.
    envs : sequence of int
        Monte Carlo environments to evaluate.
    runs : int
        Scenarios per environment, >= 1.
    base_seed : int
        Base seed of the held-out scenarios.
    report : callable, optional
        Takes one progress line; None for silence.

    Returns
    -------
    dict
        ``{env: {name: summary}}``, each summary with ``runs``, ``successes``, ``success_rate``, ``success_ci``,
        ``failures`` (count by kind), ``ce_mean`` and ``mcte_mean`` (L).
    """
    if isinstance(runs, bool) or not isinstance(runs, int) or runs < 1:
        raise InputError("holdout", "an integer >= 1", runs)
    out = {}
    names = list(param_sets)
    for env in envs:
        t0 = time.perf_counter()
        layout, X0, P, models = None, [], [], []
        for name in names:
            for run in range(runs):
                pr = build_problem(sampled_scenario(env, run, base_seed), dict(param_sets[name]))
                if layout is None:
                    layout = pr.layout
                elif pr.layout != layout:
                    raise RuntimeError(f"environment {env}: scenarios of different shape")
                X0.append(pr.x0)
                P.append(pr.p)
                models.append(pr.model)
        if report:
            report(f"  env {env}: {len(X0)} runs ({layout.n_ships} ships, {layout.n_obstacles} obstacles) ...")
        XF, busy = simulate_batch(layout, np.column_stack(X0), np.column_stack(P))
        res = {}
        for a, name in enumerate(names):
            rows = [run_outcome(models[a * runs + r].layout, XF[:, a * runs + r], models[a * runs + r].params)
                    for r in range(runs)]
            k = sum(r["success"] for r in rows)
            lo, hi = wilson_interval(int(k), int(runs))
            ok = [r for r in rows if r["success"]]
            ce = float(np.mean([r["ce"] for r in ok])) if ok else float("nan")
            mcte = float(np.mean([r["mcte"] for r in ok])) if ok else float("nan")
            fails = {}
            for r in rows:
                if r["failure"]:
                    fails[r["failure"]] = fails.get(r["failure"], 0) + 1
            res[name] = {"runs": runs, "successes": int(k), "success_rate": k / runs, "success_ci": [lo, hi],
                         "failures": fails, "ce_mean": ce, "mcte_mean": mcte}
        out[env] = res
        if report:
            txt = "; ".join(f"{n}: success {r['success_rate']:.0%} [{r['success_ci'][0]:.2f}, "
                            f"{r['success_ci'][1]:.2f}] CE {r['ce_mean']:.4f} MCTE {r['mcte_mean']:.3f}"
                            for n, r in res.items())
            report(f"  env {env} ({time.perf_counter() - t0:.1f} s): {txt}")
    return out


def exact_training(scenarios: dict, params: dict, w_mcte: float = TuningConfig.w_mcte) -> dict:
    """The training scenarios in the exact (switching) closed loop over their whole voyages, with ``params``:
    per scenario Σ_ships (CE + w MCTE), the closest approach and whether anything collided; ``total`` sums
    the objective terms.

    Parameters
    ----------
    scenarios : dict
        Scenario name -> Scenario.
    params : dict
        Guidance parameters (θ as ``{name: value}``) for every scenario.
    w_mcte : float
        Weight of MCTE against CE in the objective.

    Returns
    -------
    dict
        ``total`` (sum of the objectives) and ``scenarios``: per name ``objective``, ``collision``,
        ``min_distance`` (L), ``reached`` (ships at their goal) and ``ships``.
    """
    out, total = {}, 0.0
    for name, sc in scenarios.items():
        m = run_scenario(sc, dict(params)).metrics
        obj = sum(s["ce"] + w_mcte * s["mcte"] for s in m["ships"])
        total += obj
        out[name] = {"objective": obj, "collision": m["collision"],
                     "min_distance": min((p["min_distance"] for p in m["pairs"]), default=float("nan")),
                     "reached": sum(s["reached_goal"] for s in m["ships"]), "ships": len(m["ships"])}
    return {"total": total, "scenarios": out}
