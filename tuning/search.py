"""Coarse sweep then quasi-Newton search of the safety-aware objective, resumable from the iterates on disk.

Every evaluation (θ, J, ∇J and per-case terms summary) is appended to ``evaluations.jsonl`` in the output
directory as soon as it is computed. The search is deterministic (a fixed grid, then L-BFGS-B from the best
``starts`` grid points), so a resumed search replays the stored evaluations instantly and continues with the
first one that is not on disk: interrupting loses at most the evaluation in progress.

Optimiser: L-BFGS-B (:func:`scipy.optimize.minimize`) on the full training set with the exact gradient of
:class:`tuning.safety.SafetyObjective`, in coordinates scaled to the unit box. With two parameters and a
training set of a few hundred scenarios a full-batch quasi-Newton step costs one objective+gradient
evaluation (measured and reported as ``seconds_per_evaluation``); a stochastic mini-batch method would need
many more (noisier) steps because the safety term is carried by a few rare close encounters per batch.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from mmg_casadi.errors import InputError
from mmg_casadi.progress import progress_bar

from .safety import BOUNDS, PAPER, THETA, SafetyObjective


class _Budget(Exception):
    """Raised inside the objective when a start has used its evaluations (L-BFGS-B's own ``maxfun`` is only
    checked between iterations, and its line searches may evaluate many more points)."""


class EvaluationLog:
    """Evaluations of the objective, kept in ``path`` (JSON lines) and replayed on resume.

    Parameters
    ----------
    path : str or Path
        The ``evaluations.jsonl`` file.
    """

    def __init__(self, path):
        self.path = Path(path)
        self.records: dict[tuple, dict] = {}
        if self.path.exists():
            for line in self.path.read_text(encoding="utf-8").splitlines():
                try:
                    rec = json.loads(line)
                except ValueError:
                    continue  # a line cut by an interruption
                self.records[self.key(rec["theta"])] = rec

    @staticmethod
    def key(theta) -> tuple:
        """Lookup key of ``theta`` (rounded to 1e-9 relative, the resolution of the replay).

        Parameters
        ----------
        theta : sequence of float
            Parameter values.

        Returns
        -------
        tuple of float
            The values rounded to 10 significant digits.
        """
        return tuple(float(f"{float(v):.10g}") for v in theta)

    def get(self, theta) -> dict | None:
        """The stored evaluation at ``theta``, if any.

        Parameters
        ----------
        theta : sequence of float
            Parameter values.

        Returns
        -------
        dict or None
            The stored record, or None.
        """
        return self.records.get(self.key(theta))

    def add(self, rec: dict) -> None:
        """Store one evaluation (appended and flushed to disk at once).

        Parameters
        ----------
        rec : dict
            ``{"theta", "objective", "gradient", ...}``.
        """
        self.records[self.key(rec["theta"])] = rec
        self.path.parent.mkdir(parents=True, exist_ok=True)
        with open(self.path, "a", encoding="utf-8") as fh:
            fh.write(json.dumps(rec) + "\n")
            fh.flush()


MAX_GRID = 100
"""Largest ``--grid`` of ``tune apf`` (points per tuned parameter): the sweep evaluates ``n²`` points, each a
rollout of the whole training set with its gradient (about a minute on 2 cores)."""


def grid(n: int) -> list[tuple[float, float]]:
    """The paper's values, then ``n × n`` evenly spaced points of the box (row-major; ``n = 1``: paper only).

    Parameters
    ----------
    n : int
        Points per parameter, in [1, :data:`MAX_GRID`].

    Returns
    -------
    list of tuple of (float, float)
        The paper's values first, then the grid points without them.

    Examples
    --------
    >>> len(grid(3)), grid(1)
    (10, [(-10.0, 15.0)])
    """
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_GRID:
        raise InputError("grid", f"an integer in [1, {MAX_GRID}] (MAX_GRID)", n)
    pts = [tuple(PAPER)]
    if n > 1:
        axes = [np.linspace(lo, hi, n) for lo, hi in BOUNDS]
        pts += [(float(a), float(b)) for a in axes[0] for b in axes[1] if (float(a), float(b)) != tuple(PAPER)]
    return pts


def search(objective: SafetyObjective, out, *, grid_n: int = 3, starts: int = 1, max_iter: int = 8,
           report=None) -> dict:
    """Sweep the grid, then run L-BFGS-B from the best ``starts`` grid points; resumable (module docstring).

    Parameters
    ----------
    objective : SafetyObjective
        The training objective.
    out : str or Path
        Directory of ``evaluations.jsonl``.
    grid_n : int
        Grid points per parameter (the paper's values are always evaluated first).
    starts : int
        Local searches, from the best grid points.
    max_iter : int
        L-BFGS-B iterations per start (each costs ≥ 1 evaluation; at most ``3 max_iter + 3`` evaluations per
        start).
    report : callable, optional
        Receives progress lines.

    Returns
    -------
    dict
        ``grid`` (evaluations of the sweep), ``starts`` (per start: from, to, objective, status), ``best``
        (θ, objective), ``evaluations`` (count, of which replayed), ``seconds_per_evaluation``.
    """
    for name, v, low in (("starts", starts, 1), ("max_iter", max_iter, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise InputError(name, f"an integer >= {low}", v)
    log = EvaluationLog(Path(out) / "evaluations.jsonl")
    pts = grid(grid_n)
    per_start = 3 * max_iter + 3
    budget = len(pts) + starts * per_start
    bar = progress_bar(budget, desc="tune apf evaluations", unit="eval")
    stats = {"new": 0, "replayed": 0, "seconds": 0.0}

    def evaluate(theta, phase):
        theta = [float(v) for v in theta]
        rec = log.get(theta)
        if rec is None:
            t0 = time.perf_counter()
            terms = objective.terms(theta)
            J = float(np.mean(terms["objective"]))
            g = np.mean(terms["d_objective"], axis=1)
            dt = time.perf_counter() - t0
            rec = {"theta": theta, "objective": J, "gradient": g.tolist(), "phase": phase, "seconds": dt,
                   "safety_own": float(np.mean(terms["safety_own"])), "ce": float(np.mean(terms["ce"])),
                   "mcte": float(np.mean(terms["mcte"])),
                   "softmin_own_min": float(np.min(terms["softmin_own"])),
                   "close_cases": int(np.sum(terms["softmin_own"] < 3.0))}
            log.add(rec)
            stats["new"] += 1
            stats["seconds"] += dt
            if report:
                report(f"  {phase}: k_vor0 = {theta[0]:8.3f}  r_safe = {theta[1]:7.3f}  J = {J:.6f}  "
                       f"(safety {rec['safety_own']:.5f}, CE {rec['ce']:.4f}, MCTE {rec['mcte']:.3f}, "
                       f"{rec['close_cases']} cases with soft-min < 3 L) {dt:.1f} s")
        else:
            stats["replayed"] += 1
        bar.update(1)
        return rec

    lb = np.array([b[0] for b in BOUNDS])
    span = np.array([b[1] - b[0] for b in BOUNDS])
    try:
        sweep = [evaluate(p, "grid") for p in pts]
        ranked = sorted(sweep, key=lambda r: r["objective"])
        results = []
        for s in range(min(starts, len(ranked))):
            z0 = (np.array(ranked[s]["theta"]) - lb) / span
            n_eval = [0]

            seen = []

            def fun(z):
                if n_eval[0] >= per_start:
                    raise _Budget
                n_eval[0] += 1
                rec = evaluate(lb + span * np.clip(z, 0.0, 1.0), f"start {s + 1} eval {n_eval[0]}")
                seen.append(rec)
                return rec["objective"], np.array(rec["gradient"]) * span

            try:
                res = minimize(fun, z0, jac=True, method="L-BFGS-B", bounds=[(0.0, 1.0)] * len(THETA),
                               options={"maxiter": max_iter, "maxfun": max_iter + 3})
                status = str(res.message)
            except _Budget:
                status = f"stopped after {per_start} evaluations (line searches)"
            end = min(seen, key=lambda r: r["objective"])
            results.append({"from": ranked[s]["theta"], "to": end["theta"], "objective": end["objective"],
                            "status": status, "evaluations": n_eval[0]})
    finally:
        bar.close()
    allrecs = list(log.records.values())
    best = min(allrecs, key=lambda r: r["objective"])
    n_new = max(stats["new"], 1)
    return {"grid": sweep, "starts": results, "best": {"theta": best["theta"], "objective": best["objective"]},
            "paper": log.get(PAPER),
            "evaluations": {"total": len(allrecs), "new": stats["new"], "replayed": stats["replayed"]},
            "seconds_per_evaluation": stats["seconds"] / n_new if stats["new"] else None,
            "cases": len(objective.cases)}
