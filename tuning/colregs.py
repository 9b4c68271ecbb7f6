"""``mmg-casadi tune colregs``: search colregs-vortex's thresholds for safety plus COLREG compliance, judge the best
set against the defaults on paired held-out runs; ``mmg-casadi tune search`` does the same for any registered
method (a plugin's included) and a box of its numeric parameters (``--method M --search NAME=LO:HI ...``).

The stand-on and give-way logic of colregs-vortex (:mod:`mmg_casadi.guidance.colregs_vortex`) switches on
thresholds (TCPA, passing distance, range, alteration) whose effect on the scorer's verdicts is a step function
of the parameters, so it has no useful gradient; the search is therefore derivative-free:

1. **design**: the table's defaults and ``candidates`` points of a Latin hypercube over :data:`SEARCH_BOX`
   (seed ``search_seed``), then ``refine`` coordinate sweeps around the best point (:func:`neighbours`), each
   candidate run as the statistics study of runs ``0..design-1`` in ``envs`` (``DIR/candidates/cNN``,
   resumable) and scored by :func:`objective`;
2. **held out**: the best candidate and the defaults on runs ``design..design+holdout-1`` of the same
   environments (the candidate studies extended, so the design runs are not rerun), judged paired by
   :func:`judge`: success by McNemar on the discordant runs, compliance by McNemar on the discordant risky
   encounters (:func:`mmg_casadi.montecarlo.encounter_summary.compare_encounters`).

Writes ``DIR/candidates.csv`` (one row per candidate), ``DIR/params.toml`` (the best set, its held-out verdict in
a comment), ``DIR/report.json`` and ``DIR/report.md``. Interrupt and rerun with the same ``--out`` to resume.

Budget, measured on 2 cores: a candidate on environment 5's 1000 design runs takes about 45 s once the
colregs-vortex step is compiled (the thresholds are inputs of the compiled step, so candidates share it).

Examples
--------
>>> rows = [{"environment": 5, "method": "colregs-vortex", "run": 0, "success": True,
...          "colregs_verdicts": "1:give-way:1:8=1/16=1"},
...         {"environment": 5, "method": "colregs-vortex", "run": 1, "success": False,
...          "colregs_verdicts": "2:stand-on:0.2:17a_i=0"}]
>>> s = objective(rows, failure_weight=10.0)
>>> s["success"], s["compliance"], s["objective"]
(0.5, 0.5, -4.5)
"""

from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np
from scipy.stats import qmc

from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods as registry
from mmg_casadi.io import atomic_open, write_json, write_text
from mmg_casadi.limits import check_runs
from mmg_casadi.montecarlo.encounter_summary import compare_encounters, summarize_encounters
from mmg_casadi.montecarlo.results import ResultsTable
from mmg_casadi.montecarlo.stats import paired_comparison, wilson
from mmg_casadi.montecarlo.study import check_resumable, check_study_args, run_study
from mmg_casadi.params import PARAMETERS
from mmg_casadi.progress import say

from .cli_apf import check_settings
from .judge import write_params as judge_params

METHOD = "colregs-vortex"

SEARCH_BOX = {
    "cv_t_act": (2.0, 8.0),
    "cv_d_cpa_act": (1.5, 4.5),
    "cv_r_act": (4.0, 12.0),
    "cv_t_close": (1.5, 5.0),
    "cv_k_standon": (0.3, 3.0),
    "cv_dpsi_min_deg": (15.0, 60.0),
    "cv_d_clear": (3.0, 10.0),
    "cv_d_risk": (2.5, 6.0),
}
"""Tuned thresholds and the box searched (inside each one's range in the parameter table): the stand-on trigger
and its strength (Rule 17), the give-way alteration and its release (Rules 8 and 16), the onset of risk (Rule 7).
The box spans about half to twice each default."""

FAILURE_WEIGHT = 10.0
"""Default weight of the failure rate in :func:`objective`: a success rate one percentage point lower costs as much
as ten percentage points of compliance (one run lost in a thousand, as one point of compliance)."""


def objective(rows, *, failure_weight: float = FAILURE_WEIGHT) -> dict:
    """Safety plus compliance of one parameter set's runs: ``compliance − failure_weight · (1 − success)``.

    Parameters
    ----------
    rows : iterable of dict
        Rows of one method's ``runs.csv`` (``success`` and ``colregs_verdicts`` are read).
    failure_weight : float, default :data:`FAILURE_WEIGHT`
        Weight of the failure rate (≥ 0).

    Returns
    -------
    dict
        ``runs``, ``success`` (rate), ``encounters`` (risky encounters scored), ``compliance`` (share of them
        kept), ``stand_on`` and ``give_way`` (shares kept by role, ``nan`` without one) and ``objective``.
    """
    rows = [{**r, "environment": 0} for r in rows]  # pooled over the environments
    if not rows:
        raise InputError("rows", "at least one run")
    groups = {s["group"]: s for s in summarize_encounters(rows)}
    success = sum(bool(r["success"]) for r in rows) / len(rows)
    compliance = groups["all"]["rate"] if groups["all"]["n"] else 1.0
    return {"runs": len(rows), "success": success, "encounters": groups["all"]["n"], "compliance": compliance,
            "stand_on": groups["stand-on"]["rate"], "give_way": groups["give-way"]["rate"],
            "objective": compliance - failure_weight * (1.0 - success)}


def candidates(n: int, seed: int = 0, box: dict | None = None) -> list[dict]:
    """The defaults, then ``n`` points of a scrambled Latin hypercube over :data:`SEARCH_BOX` (or ``box``).

    Parameters
    ----------
    n : int
        Points besides the defaults (≥ 0).
    seed : int
        Seed of the hypercube.
    box : dict, optional
        Parameter name to ``(low, high)``; default :data:`SEARCH_BOX`.

    Returns
    -------
    list of dict
        ``n + 1`` parameter sets (name to value), the defaults first.

    Examples
    --------
    >>> c = candidates(3)
    >>> len(c), c[0]["cv_t_act"] == PARAMETERS["cv_t_act"].default
    (4, True)
    >>> all(SEARCH_BOX[k][0] <= v <= SEARCH_BOX[k][1] for p in c[1:] for k, v in p.items())
    True
    """
    box = SEARCH_BOX if box is None else box
    names = list(box)
    out = [{k: float(PARAMETERS[k].default) for k in names}]
    if n:
        lo, hi = np.array([box[k] for k in names]).T
        pts = qmc.scale(qmc.LatinHypercube(d=len(names), seed=seed).random(n), lo, hi)
        out += [{k: round(float(v), 4) for k, v in zip(names, p)} for p in pts]
    return out


def neighbours(point: dict, step: float, box: dict | None = None) -> list[dict]:
    """The coordinate neighbours of ``point``: each tuned threshold moved by ``±step`` of its box width (clipped to
    :data:`SEARCH_BOX` or ``box``), the others kept; a step that the box clips away entirely is left out.

    Parameters
    ----------
    point : dict
        Values of the box's parameters.
    step : float
        Fraction of each box width.
    box : dict, optional
        Parameter name to ``(low, high)``; default :data:`SEARCH_BOX`.

    Returns
    -------
    list of dict
        Up to two points per threshold, in the order of :data:`SEARCH_BOX`, minus first.

    Examples
    --------
    >>> p = candidates(0)[0]
    >>> [q["cv_t_act"] for q in neighbours(p, 0.25)[:2]]
    [2.5, 5.5]
    """
    out = []
    for k, (lo, hi) in (SEARCH_BOX if box is None else box).items():
        for sign in (-1.0, 1.0):
            v = round(min(max(point[k] + sign * step * (hi - lo), lo), hi), 4)
            if v != point[k]:
                out.append({**point, k: v})
    return out


def _best(table: list[dict]) -> dict:
    """The candidate with the highest objective; the earliest (the defaults first) among equals."""
    return max(table, key=lambda r: (r["objective"], -r["candidate"]))


def _rows(d: Path, envs, lo: int, hi: int, method: str = METHOD) -> list[dict]:
    return [r for r in ResultsTable(d / "runs.csv").read()
            if lo <= r["run"] < hi and r["environment"] in envs and r["method"] == method]


def judge(tuned_rows, default_rows, *, alpha: float = 0.05) -> dict:
    """Paired verdict of the tuned set against the defaults over the same runs.

    ``"improvement"`` only when compliance per risky encounter is significantly higher (McNemar on the discordant
    encounters, p < ``alpha``) and success is not significantly lower (McNemar on the discordant runs);
    anything else is ``"no improvement"`` with the reasons.

    Parameters
    ----------
    tuned_rows, default_rows : list of dict
        ``runs.csv`` rows of the two sets over the same (environment, run) keys.
    alpha : float
        Level of both tests.

    Returns
    -------
    dict
        ``verdict``, ``reasons``, ``success`` (rates, difference tuned − default with Newcombe's interval,
        discordant counts and p) and ``compliance`` (the same over the paired encounters).
    """
    key = {(r["environment"], r["run"]): r for r in default_rows}
    tuned = {(r["environment"], r["run"]): r for r in tuned_rows}
    common = sorted(key.keys() & tuned.keys())
    if not common:
        raise InputError("rows", "paired runs of both sets")
    s = paired_comparison([bool(tuned[k]["success"]) for k in common], [bool(key[k]["success"]) for k in common])
    success = {"runs": len(common), "tuned": s.rate_a, "default": s.rate_b, "difference": s.difference,
               "ci": list(s.ci), "tuned_only": s.a_only, "default_only": s.b_only, "p_value": s.p_value,
               "tuned_ci": list(wilson(s.both + s.a_only, len(common))),
               "default_ci": list(wilson(s.both + s.b_only, len(common)))}
    pooled = [{**tuned[k], "environment": 0, "method": "tuned"} for k in common] + \
        [{**key[k], "environment": 0, "method": "default"} for k in common]
    c = compare_encounters(pooled, ["tuned", "default"])[0]
    compliance = {k: c[k] for k in ("pairs", "rate_a", "rate_b", "difference", "ci_low", "ci_high", "a_only",
                                    "b_only", "p_value")}
    reasons = []
    if not (c["pairs"] and c["difference"] > 0 and c["p_value"] < alpha):
        reasons.append(f"compliance not significantly higher ({c['rate_a']:.4f} vs {c['rate_b']:.4f}, "
                       f"p = {c['p_value']:.3g})")
    if s.difference < 0 and s.p_value < alpha:
        reasons.append(f"success significantly lower ({s.rate_a:.4f} vs {s.rate_b:.4f}, p = {s.p_value:.3g})")
    return {"verdict": "no improvement" if reasons else "improvement", "reasons": reasons, "success": success,
            "compliance": compliance}


def _write_candidates(path: Path, table: list[dict], box: dict) -> None:
    cols = ["candidate", *box, "runs", "success", "encounters", "compliance", "stand_on", "give_way",
            "objective"]
    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=cols)
        w.writeheader()
        w.writerows({c: row[c] for c in cols} for row in table)


def write_params(path: Path, best: dict, *, verdict: str, summary: str, method: str = METHOD) -> None:
    """``params.toml`` with the best thresholds and, as comments, the held-out verdict against the defaults.

    Parameters
    ----------
    path : pathlib.Path
        Output file.
    best : dict
        The tuned parameters (those of :data:`SEARCH_BOX` for colregs-vortex).
    verdict : str
        ``"improvement"``, ``"no improvement"`` or ``"not judged"``.
    summary : str
        Comment lines.
    method : str, default 'colregs-vortex'
        The tuned method.
    """
    title = ("colregs-vortex thresholds from `mmg-casadi tune colregs` (tuning/colregs.py)" if method == METHOD
             else f"{method} parameters from `mmg-casadi tune search` (tuning/colregs.py)")
    judge_params(path, dict(best),
                 title=title,
                 baseline="the defaults", caveat="the defaults; keep the defaults unless you have another reason",
                 verdict=verdict, summary=summary)


def _markdown(report: dict) -> str:
    j = report["judgement"]
    verdict = j["verdict"] if j else "no improvement (the search kept the defaults)"
    lines = [f"# tune colregs: verdict **{verdict}**", "",
             f"Design: runs 0-{report['design'] - 1} of environments {report['envs']}, seed {report['seed']}; "
             f"{len(report['candidates'])} candidates (the defaults, a Latin hypercube of seed "
             f"{report['search_seed']}, {report['refine']} coordinate sweep(s)); objective = compliance − "
             f"{report['failure_weight']:g} × failure rate.", "",
             "| candidate | success | compliance | stand-on | give-way | objective |", "|---|---|---|---|---|---|"]
    for c in report["candidates"]:
        lines.append(f"| {c['candidate']} | {c['success']:.4f} | {c['compliance']:.4f} | {c['stand_on']:.4f} | "
                     f"{c['give_way']:.4f} | {c['objective']:.4f} |")
    lines += ["", f"Best: candidate {report['best']} {report['params_best']}", ""]
    if j:
        s, c = j["success"], j["compliance"]
        lines += [f"Held out: runs {report['design']}-{report['design'] + report['holdout'] - 1}, paired.", "",
                  "| | default | tuned | tuned − default [95 % CI] | discordant (tuned only / default only) | "
                  "McNemar p |", "|---|---|---|---|---|---|",
                  f"| success ({s['runs']} runs) | {s['default']:.4f} | {s['tuned']:.4f} | {s['difference']:+.4f} "
                  f"[{s['ci'][0]:+.4f}, {s['ci'][1]:+.4f}] | {s['tuned_only']} / {s['default_only']} | "
                  f"{s['p_value']:.3g} |",
                  f"| compliance ({c['pairs']} encounters) | {c['rate_b']:.4f} | {c['rate_a']:.4f} | "
                  f"{c['difference']:+.4f} [{c['ci_low']:+.4f}, {c['ci_high']:+.4f}] | {c['a_only']} / "
                  f"{c['b_only']} | {c['p_value']:.3g} |"]
        if j["reasons"]:
            lines += ["", "Reasons for 'no improvement':", *[f"- {x}" for x in j["reasons"]]]
    return "\n".join(lines) + "\n"


def check_box(method: str, box) -> dict:
    """A search box for ``method``: each name a numeric, non-structural parameter the method reads, each interval
    inside the parameter's range with ``low < high`` and the default inside it.

    Parameters
    ----------
    method : str
        A registered method.
    box : dict
        Parameter name to ``(low, high)``.

    Returns
    -------
    dict
        The box, floats.

    Examples
    --------
    >>> check_box("colregs-vortex", {"cv_t_act": (2, 8)})
    {'cv_t_act': (2.0, 8.0)}
    >>> check_box("modified-vortex", {"cv_t_act": (2, 8)})  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: search.cv_t_act: expected a numeric parameter that modified-vortex reads (...), got 'cv_t_act'
    """
    registry.get(method, "method")
    if not isinstance(box, dict) or not box:
        raise InputError("search", "at least one NAME=LOW:HIGH", box)
    out = {}
    for k, bounds in box.items():
        p = PARAMETERS.get(k)
        if p is None or p.structural or p.kind != "float" or method not in registry.owners(k):
            reads = [n for n, q in PARAMETERS.items() if method in registry.owners(n) and not q.structural
                     and q.kind == "float"]
            raise InputError(f"search.{k}", f"a numeric parameter that {method} reads ({', '.join(reads)})", k)
        lo, hi = (p.check(float(v), field=f"search.{k}", cls=InputError) for v in bounds)
        if not lo < hi or not lo <= p.default <= hi:
            raise InputError(f"search.{k}", f"LOW < HIGH around the default {p.default:g}", f"{lo:g}:{hi:g}")
        out[k] = (lo, hi)
    return out


def run(out, *, design: int = 1000, holdout: int = 4000, n_candidates: int = 16, envs="5", params=None,
        failure_weight: float = FAILURE_WEIGHT, seed: int = 0, search_seed: int = 0, refine: int = 1,
        workers: int | None = None, method: str = METHOD, box: dict | None = None) -> dict:
    """Search, then judge on paired held-out runs; return the report (also written to ``out``).

    Parameters
    ----------
    out : str or Path
        Output directory; rerun with the same directory to resume.
    design : int
        Design runs per environment (run ids ``0..design-1``), ≥ 1.
    holdout : int
        Held-out runs per environment (run ids ``design..design+holdout-1``), ≥ 1.
    n_candidates : int
        Latin-hypercube candidates besides the defaults, ≥ 0.
    envs : str or iterable of int
        Environments of both stages, e.g. ``"5"`` or ``"1-5"``.
    params : dict, optional
        Overrides every run uses; the tuned thresholds may not be among them.
    failure_weight : float
        Weight of the failure rate in :func:`objective`, ≥ 0.
    seed : int
        Base seed of the scenario sampler.
    search_seed : int
        Seed of the Latin hypercube.
    refine : int
        Coordinate sweeps after the hypercube (≥ 0): the best point so far with each threshold moved by ±1/4 of
        its box width (then 1/8, ...) one at a time (:func:`neighbours`).
    workers : int, optional
        Local worker processes.
    method : str, default 'colregs-vortex'
        The tuned method (every ship of the sampled scenarios uses it).
    box : dict, optional
        The searched parameters, name to ``(low, high)`` (:func:`check_box`); default :data:`SEARCH_BOX`.

    Returns
    -------
    dict
        The report written to ``report.json``: the candidates with their scores, the best, the judgement and
        the timings (s).

    Notes
    -----
    Every argument is checked before any work and before ``out`` is made.
    """
    for name, value, low in (("design", design, 1), ("holdout", holdout, 1), ("candidates", n_candidates, 0),
                             ("search_seed", search_seed, 0), ("refine", refine, 0)):
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise InputError(name, f"an integer >= {low}", value)
    check_runs(design + holdout, "design + holdout")
    if not (isinstance(failure_weight, (int, float)) and np.isfinite(failure_weight) and failure_weight >= 0):
        raise InputError("failure_weight", "a finite number >= 0", failure_weight)
    box = SEARCH_BOX if box is None and method == METHOD else check_box(method, box)
    fixed = {k: v for k, v in (params or {}).items() if v != PARAMETERS[k].default}
    clash = sorted(set(fixed) & set(box))
    if clash:
        raise InputError("params", f"no tuned threshold ({', '.join(box)}); drop --set {clash[0]}",
                         clash[0])
    args = check_study_args(runs=design + holdout, envs=envs, methods=(method,), base_seed=seed, params=fixed,
                            workers=workers)
    envs = tuple(args["envs"])
    out = Path(out)
    sets = candidates(n_candidates, search_seed, box)
    for i, cand in enumerate(sets):
        full = check_study_args(runs=design, envs=envs, methods=(method,), base_seed=seed,
                                params={**fixed, **cand})["params"]
        check_resumable(out / "candidates" / f"c{i:02d}", runs=design, envs=envs, methods=(method,),
                        base_seed=seed, params=full)
    settings = {"design": design, "envs": list(envs), "seed": seed, "params": fixed, "search_seed": search_seed,
                "failure_weight": failure_weight, "candidates": n_candidates, "refine": refine}
    if method != METHOD or box != SEARCH_BOX:  # tune colregs keeps its settings file as it was
        settings.update(method=method, search_box={k: list(v) for k, v in box.items()})
    check_settings(out / "tuning.json", settings)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "tuning.json", settings)
    t_start = time.perf_counter()

    say(f"[1/2] design: {len(sets)} candidates x {design} runs of environments {list(envs)} ({method}, seed "
        f"{seed}), then {refine} coordinate sweep(s) around the best")
    table = []

    def evaluate(cand: dict) -> None:
        i = len(table)
        d = out / "candidates" / f"c{i:02d}"
        say(f"  candidate {i}: {cand}")
        run_study(d, runs=design, envs=envs, methods=(method,), base_seed=seed, params={**fixed, **cand},
                  workers=workers)
        score = objective(_rows(d, envs, 0, design, method), failure_weight=failure_weight)
        table.append({"candidate": i, **cand, **score})
        say(f"    success {score['success']:.4f}, compliance {score['compliance']:.4f} (stand-on "
            f"{score['stand_on']:.4f}), objective {score['objective']:.4f}")

    for cand in sets:
        evaluate(cand)
    for k in range(refine):
        best = _best(table)
        seen = [{n: row[n] for n in box} for row in table]
        for cand in neighbours(seen[best["candidate"]], 0.25 / 2 ** k, box):
            if cand not in seen:
                evaluate(cand)
    _write_candidates(out / "candidates.csv", table, box)
    best = _best(table)
    best_params = {k: best[k] for k in box}
    t_design = time.perf_counter() - t_start

    judgement, summary = None, "the search kept the defaults"
    if best["candidate"]:
        write_params(out / "params.toml", best_params, verdict="not judged", summary="held-out runs not finished",
                     method=method)
        say(f"[2/2] held out: runs {design}-{design + holdout - 1}, defaults vs candidate {best['candidate']}")
        rows = {}
        for i in (0, best["candidate"]):
            d = out / "candidates" / f"c{i:02d}"
            run_study(d, runs=design + holdout, envs=envs, methods=(method,), base_seed=seed,
                      params={**fixed, **{k: table[i][k] for k in box}}, workers=workers)
            rows[i] = _rows(d, envs, design, design + holdout, method)
        judgement = judge(rows[best["candidate"]], rows[0])
        s, c = judgement["success"], judgement["compliance"]
        summary = (f"held out {s['runs']} runs: success {s['default']:.4f} -> {s['tuned']:.4f} (p = "
                   f"{s['p_value']:.3g}); compliance over {c['pairs']} encounters {c['rate_b']:.4f} -> "
                   f"{c['rate_a']:.4f} (p = {c['p_value']:.3g})")
    write_params(out / "params.toml", best_params,
                 verdict=judgement["verdict"] if judgement else "no improvement", summary=summary, method=method)
    report = {"command": "tune colregs" if method == METHOD and box == SEARCH_BOX else "tune search",
              "method": method, "envs": list(envs), "seed": seed, "design": design,
              "holdout": holdout, "search_seed": search_seed, "refine": refine, "failure_weight": failure_weight,
              "params": fixed,
              "search_box": {k: list(v) for k, v in box.items()}, "candidates": table,
              "best": best["candidate"], "params_best": best_params, "judgement": judgement,
              "timings": {"design_s": t_design, "total_s": time.perf_counter() - t_start},
              "files": {"params": str(out / "params.toml"), "candidates": str(out / "candidates.csv"),
                        "report": str(out / "report.json")}}
    write_json(out / "report.json", report)
    write_text(out / "report.md", _markdown(report))
    say(_markdown(report))
    return report
