"""Three searches of the envelope at the same simulation budget: random sampling, CMA-ES and the gradient.

Every search spends at most ``budget`` simulations (one closed-loop rollout each; a gradient evaluation is one
rollout forward and its adjoint backward, counted as one simulation and timed apart) and records each in its trace.

``random``
    the Monte Carlo study's own sample (:meth:`~mmg_casadi.falsify.envelope.Envelope.sample`, runs ``0..budget-1``
    of the base seed): what a study of that size finds.
``cmaes``
    screening, then local searches. The first ``screen`` share of the budget is the same random sample; from its
    least robust runs that did not fail (each once, in order) a CMA-ES (the ``cma`` package, Hansen's reference
    implementation) searches the unit cube of the envelope with step ``sigma0``, each candidate projected onto the
    envelope, on the exact robustness, with a population of ``popsize`` (a local search), until a generation holds a
    failure or the local search has spent ``local_budget`` simulations; then the next start. CMA-ES rather than differential evolution: with ~70
    coordinates its population is ``4 + 3 ln d`` ≈ 17 candidates, where differential evolution's default is
    ``15 d`` ≈ 1000 — half the budget before its first generation.
``gradient``
    the same screening, then from the same starts (each skipped when its closest call has the geometry of a
    failure found already) a projected gradient descent on the smooth margin
    (:class:`~mmg_casadi.falsify.gradient.MarginGradient`): along the negative gradient (unit cube, Euclidean) a
    step of Polyak's length, the one at which the linearised robustness reaches ``-target`` (the value sought is
    known: below zero), at most ``step``, projected onto the envelope; a step that lowers the smooth margin is kept
    (and a halved step length doubled again, up to Polyak's), else the length is halved; a local search ends at a
    failure, after ``local_budget`` simulations or when the step falls below ``min_step``. Collision and grounding only: the COLREG scorer has no
    derivative.

Failures are those of the exact robustness (:mod:`~mmg_casadi.falsify.robustness`); a search keeps every one it
meets, the screening's included.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.falsify.envelope import Envelope
from mmg_casadi.falsify.robustness import Evaluation, check_objective, evaluate
from mmg_casadi.guidance import methods as registry

SEARCHES: tuple[str, ...] = ("gradient", "cmaes", "random")
"""The searches (module docstring)."""
BATCH = 32
"""Simulations rolled out together by the random sample and the screening."""
PROGRESS_EVERY = 100
"""A progress line every this many simulations."""
CHECKPOINT_EVERY = 100
"""A search's progress is handed to ``save`` (:func:`run_search`) after at least this many new simulations."""


@dataclass(frozen=True)
class SearchConfig:
    """Budget and settings of the searches (module docstring).

    Parameters
    ----------
    budget : int
        Simulations per search.
    seed : int
        Base seed of the random sample (the study's sampler) and of CMA-ES.
    screen : float
        Share of the budget spent on the random screening of the local searches.
    local_budget : int
        Simulations per local search.
    sigma0 : float
        CMA-ES's initial step in the unit cube.
    popsize : int
        CMA-ES's population (a local search: smaller than its default of ``4 + 3 ln d``).
    step : float
        The gradient search's longest step in the unit cube.
    target : float
        The robustness a gradient step aims at, below zero (Polyak's step; the coordinate's unit, L).
    min_step : float
        The step length below which a gradient search stops.

    Examples
    --------
    >>> SearchConfig(budget=100).screened
    25
    >>> SearchConfig(budget=0)
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: budget: expected an integer >= 1, got 0
    """

    budget: int = 2000
    seed: int = 0
    screen: float = 0.25
    local_budget: int = 24
    sigma0: float = 0.05
    popsize: int = 8
    step: float = 0.1
    target: float = 0.5
    min_step: float = 1e-3

    def __post_init__(self):
        for name, low in (("budget", 1), ("seed", 0), ("local_budget", 2), ("popsize", 2)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < low:
                raise InputError(name, f"an integer >= {low}", v)
        for name in ("screen", "sigma0", "step", "min_step", "target"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v <= 1:
                raise InputError(name, "a number in (0, 1]", v)

    @property
    def screened(self) -> int:
        """Simulations of the screening."""
        return max(1, int(round(self.screen * self.budget)))


@dataclass
class SearchResult:
    """What one search found.

    Parameters
    ----------
    search : str
        One of :data:`SEARCHES`.
    method : str
        The method searched.
    envelope : Envelope
        The envelope searched.
    objective : str
        The objective.
    config : SearchConfig
        Budget and settings.
    evaluations : list of Evaluation
        Every simulation, in order.
    trace : list of dict
        Per simulation: ``index``, ``phase`` (``sample``, ``screen`` or ``local``), ``start`` (local search number,
        -1 outside one), ``robustness``, ``smooth`` (the gradient search's soft-min; NaN elsewhere), ``failure``
        and ``seconds`` since the search began.
    seconds : float
        Wall time of the search.
    """

    search: str
    method: str
    envelope: Envelope
    objective: str
    config: SearchConfig
    evaluations: list = field(default_factory=list)
    trace: list = field(default_factory=list)
    seconds: float = 0.0

    @property
    def failures(self) -> list[Evaluation]:
        """The evaluations that failed, in order."""
        return [e for e in self.evaluations if e.failure]

    @property
    def best(self) -> Evaluation:
        """The least robust evaluation."""
        return min(self.evaluations, key=lambda e: e.robustness)

    def to_dict(self) -> dict:
        """Everything but the envelope as plain values (JSON with NaN and Infinity), for a checkpoint.

        Returns
        -------
        dict
            ``search``, ``method``, ``objective``, ``config``, ``seconds``, ``trace`` and ``evaluations``.
        """
        return {"search": self.search, "method": self.method, "objective": self.objective,
                "config": vars(self.config).copy(), "seconds": self.seconds, "trace": self.trace,
                "evaluations": [{"theta": e.theta.tolist(), "robustness": e.robustness, "failure": e.failure,
                                 "row": e.row, "detail": e.detail, "geometry": e.geometry}
                                for e in self.evaluations]}

    @classmethod
    def from_dict(cls, d: dict, envelope: Envelope) -> "SearchResult":
        """The result :meth:`to_dict` wrote.

        Parameters
        ----------
        d : dict
            What :meth:`to_dict` returned.
        envelope : Envelope
            The envelope searched.

        Returns
        -------
        SearchResult
            The same result.
        """
        evs = [Evaluation(np.array(e["theta"], float), float(e["robustness"]), bool(e["failure"]), e["row"],
                          e["detail"], e["geometry"]) for e in d["evaluations"]]
        return cls(d["search"], d["method"], envelope, d["objective"], SearchConfig(**d["config"]), evs,
                   list(d["trace"]), float(d["seconds"]))


class _Run:
    """Bookkeeping of one search: the budget, the trace and the evaluations, its checkpoints, and the replay of an
    interrupted search (``resume``): while the search asks for the parameter vectors the interrupted one simulated,
    in the same order, their stored evaluations (and gradients) are taken instead of simulating again."""

    def __init__(self, result: SearchResult, params: dict | None, progress=None, save=None,
                 resume: SearchResult | None = None, gradients: dict | None = None):
        self.r, self.params, self.progress, self.save = result, params, progress, save
        self.old = resume if resume is not None and resume.evaluations else None
        self.gradients = {int(k): v for k, v in (gradients or {}).items()}
        self.saved = len(resume.evaluations) if resume is not None else 0
        self.t0 = time.perf_counter() - (resume.seconds if resume is not None else 0.0)

    @property
    def left(self) -> int:
        return self.r.config.budget - len(self.r.evaluations)

    def replayed(self, theta) -> tuple | None:
        """The interrupted search's evaluation and trace row of the next simulation if it was of ``theta``."""
        n = len(self.r.evaluations)
        if self.old is None or n >= len(self.old.evaluations):
            return None
        ev = self.old.evaluations[n]
        if not np.array_equal(ev.theta, theta):
            self.old = None  # the search went another way: everything from here is simulated
            return None
        return ev, self.old.trace[n]

    def checkpoint(self, force: bool = False) -> None:
        """Hand the search so far to ``save`` every :data:`CHECKPOINT_EVERY` new simulations (or now)."""
        n = len(self.r.evaluations)
        if self.save is not None and n > self.saved and (force or n - self.saved >= CHECKPOINT_EVERY):
            self.r.seconds = time.perf_counter() - self.t0
            self.save(self.r, self.gradients)
            self.saved = n

    def record(self, ev: Evaluation, phase: str, start: int = -1, smooth: float = math.nan,
               row: dict | None = None) -> Evaluation:
        self.r.evaluations.append(ev)
        self.r.trace.append(dict(row) if row is not None else {
            "index": len(self.r.trace), "phase": phase, "start": start, "robustness": ev.robustness,
            "smooth": smooth, "failure": ev.failure, "seconds": time.perf_counter() - self.t0})
        n = len(self.r.evaluations)
        if self.progress is not None and (n % PROGRESS_EVERY == 0 or n == self.r.config.budget):
            fails = sum(t["failure"] for t in self.r.trace)
            self.progress(f"  {self.r.method} {self.r.search}: {n}/{self.r.config.budget} simulations, {fails} "
                          f"failures, {time.perf_counter() - self.t0:.0f} s")
        return ev

    def simulate(self, thetas, phase: str, start: int = -1) -> list[Evaluation]:
        thetas = list(thetas)[:self.left]
        out = []
        while thetas and (old := self.replayed(thetas[0])) is not None:
            out.append(self.record(old[0], phase, start, row=old[1]))
            thetas.pop(0)
        for b in range(0, len(thetas), BATCH):
            evs = evaluate(self.r.envelope, thetas[b:b + BATCH], self.r.method, self.r.objective, self.params)
            out += [self.record(ev, phase, start) for ev in evs]
            self.checkpoint()
        return out


def _random(run: _Run, n: int, phase: str) -> list[Evaluation]:
    env, cfg = run.r.envelope, run.r.config
    return run.simulate((env.sample(k, cfg.seed) for k in range(n)), phase)


def _starts(run: _Run, screened: list[Evaluation]):
    """The local searches' starts: the screened runs that did not fail, least robust first, each skipped when its
    closest call has the geometry of a failure the search has already found (:mod:`~mmg_casadi.falsify.report`):
    a local search from there would most likely find that failure again."""
    from mmg_casadi.falsify.report import geometry_distance

    for e in sorted((e for e in screened if not e.failure), key=lambda e: e.robustness):
        if e.geometry is not None and any(geometry_distance(e.geometry, f.geometry) <= 1.0
                                          for f in run.r.failures):
            continue
        yield e.theta


def _cmaes(run: _Run) -> None:
    import cma  # the derivative-free search's dependency, loaded when it runs

    env, cfg = run.r.envelope, run.r.config
    lo = [None if p else 0.0 for p in env.periodic]
    hi = [None if p else 1.0 for p in env.periodic]
    for k, theta0 in enumerate(_starts(run, _random(run, cfg.screened, "screen"))):
        if run.left <= 0:
            break
        es = cma.CMAEvolutionStrategy(env.to_unit(theta0), cfg.sigma0,
                                      {"bounds": [lo, hi], "seed": cfg.seed * 100_003 + k + 1, "verbose": -9,
                                       "popsize": cfg.popsize})
        spent = 0
        while spent < cfg.local_budget and run.left > 0:
            U = es.ask()
            if len(U) > run.left:
                break
            thetas, values, keep = [], [], []
            for u in U:
                th, inside = env.project(env.from_unit(u))
                keep.append(inside)
                if inside:
                    thetas.append(th)
            evs = iter(run.simulate(thetas, "local", k))
            values = [next(evs).robustness if inside else 1e3 for inside in keep]
            spent += len(thetas)
            es.tell(U, values)
            if min(values) < 0.0:
                break


def _gradient(run: _Run) -> None:
    from mmg_casadi.falsify.gradient import MarginGradient

    env, cfg = run.r.envelope, run.r.config
    grad = MarginGradient(env, run.r.method, run.r.objective, run.params)
    span = env.high - env.low

    def step(theta, k):
        """Evaluate and record ``theta`` with its gradient in unit coordinates (stored for a replay)."""
        n = len(run.r.evaluations)
        old = run.replayed(theta)
        if old is not None and n in run.gradients:
            ev, row = old
            run.record(ev, "local", k, row=row)
            return ev, row["smooth"], np.array(run.gradients[n], float)
        ev, smooth, g = grad(theta)
        g = g * span
        run.gradients[n] = g.tolist()
        run.record(ev, "local", k, smooth)
        run.checkpoint()
        return ev, smooth, g

    for k, theta in enumerate(_starts(run, _random(run, cfg.screened, "screen"))):
        if run.left <= 0:
            break
        ev, smooth, g = step(theta, k)
        spent, shrink = 1, 1.0
        while not ev.failure and spent < cfg.local_budget and run.left > 0:
            norm = float(np.linalg.norm(g))
            if not math.isfinite(smooth) or norm == 0.0:
                break
            # Polyak's step: the length at which the linearised robustness reaches -target, at most `step`
            alpha = shrink * min(cfg.step, (ev.robustness + cfg.target) / norm)
            if alpha < cfg.min_step:
                break
            trial, inside = env.project(env.from_unit(env.to_unit(theta) - alpha * g / norm))
            if not inside:
                shrink *= 0.5
                continue
            ev_t, smooth_t, g_t = step(trial, k)
            spent += 1
            if ev_t.failure or smooth_t < smooth:
                theta, ev, smooth, g, shrink = trial, ev_t, smooth_t, g_t, min(1.0, 2.0 * shrink)
            else:
                shrink *= 0.5


def run_search(search: str, method: str, envelope: Envelope, objective: str = "collision",
               config: SearchConfig = SearchConfig(), params: dict | None = None, progress=None, save=None,
               resume: SearchResult | None = None, gradients: dict | None = None) -> SearchResult:
    """Run one search (module docstring) and return what it found.

    Parameters
    ----------
    search : str
        One of :data:`SEARCHES`.
    method : str
        Every ship's method.
    envelope : Envelope
        The envelope searched.
    objective : str, default "collision"
        One of :data:`~mmg_casadi.falsify.robustness.OBJECTIVES`.
    config : SearchConfig
        Budget and settings.
    params : dict, optional
        Parameter overrides of every run.
    progress : callable, optional
        Called with a line every :data:`PROGRESS_EVERY` simulations.
    save : callable, optional
        Called as ``save(result, gradients)`` with the search so far every :data:`CHECKPOINT_EVERY` simulations
        and when interrupted (``KeyboardInterrupt``); ``gradients`` maps a simulation's index to its gradient in the
        unit cube (the gradient search's local steps), what a replay needs besides the evaluations.
    resume : SearchResult, optional
        The search so far that ``save`` was given (an interrupted run): its simulations are replayed, not
        simulated again, as long as the search asks for the same parameter vectors in the same order (it does:
        every search is deterministic given its seed), so the result equals an uninterrupted run's.
    gradients : dict, optional
        The ``gradients`` given to ``save`` with ``resume``.

    Returns
    -------
    SearchResult
        Every evaluation and the trace.
    """
    if search not in SEARCHES:
        raise InputError("search", f"one of: {', '.join(SEARCHES)}", search)
    check_objective(objective, envelope.environment)
    registry.get(method, "method")
    if search == "gradient" and objective == "colregs":
        raise InputError("search", "cmaes or random for the colregs objective (the COLREG scorer has no "
                         "derivative)", search)
    result = SearchResult(search, method, envelope, objective, config)
    run = _Run(result, params, progress, save, resume, gradients)
    try:
        if search == "random":
            _random(run, config.budget, "sample")
        elif search == "cmaes":
            _cmaes(run)
        else:
            _gradient(run)
        if run.left > 0 and search != "random":  # every start used: the rest of the budget samples on
            more = [envelope.sample(k, config.seed) for k in range(config.screened, config.screened + run.left)]
            run.simulate(more, "screen")
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM (the command line's): keep what was simulated
        run.checkpoint(force=True)
        raise
    result.seconds = time.perf_counter() - run.t0
    return result
