"""``mmg-casadi tune apf``: tune the modified sink-vortex field for safety, judge it on paired held-out runs.

Stages (progress with ETA on stderr; interrupt and rerun with the same ``--out`` to resume):

1. training set: the paper's five encounters plus ``--train`` sampled scenarios drawn in turn from
   environments 3, 4, 5 (base seed :data:`tuning.apf.TRAIN_SEED`);
2. exact rollouts at the paper's values (horizons), compilation of the augmented steps (once per layout,
   cached on disk), gradient check against central differences on the paper's encounters;
3. the search (:func:`tuning.search.search`): the paper's values and a ``--grid``² sweep of the box, then
   L-BFGS-B from the best ``--starts`` points, every evaluation kept in ``DIR/evaluations.jsonl``;
4. the statistics study (:func:`mmg_casadi.montecarlo.study.run_study`) of the paper's and the tuned values on
   ``--holdout`` runs per environment with the held-out seed :data:`tuning.apf.HOLDOUT_SEED`
   (``DIR/heldout/paper``, ``DIR/heldout/tuned``; resumable), judged by :func:`tuning.judge.judge`.

Writes ``DIR/params.toml`` (with the verdict in a comment), ``DIR/report.json`` and ``DIR/report.md``.

Default budget, measured on 2 cores shared with other work: 5 + 195 training scenarios; 10 grid evaluations +
10 L-BFGS-B evaluations at 60 s per objective+gradient over the 200 scenarios (46–84 s), 18 min of search;
one-off compilation of the augmented steps ~8 min the first time (environment 5: 285 s), then loaded from
the disk cache; 2 × 2000 held-out runs in each of the five environments, 21 min. Total 40 min.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.io import write_json, write_text
from mmg_casadi.montecarlo.results import ResultsTable
from mmg_casadi.limits import MAX_RUNS, check_runs
from mmg_casadi.montecarlo.study import check_resumable, check_study_args, run_study
from mmg_casadi.params import PARAMETERS, resolve
from mmg_casadi.progress import say
from mmg_casadi.scenarios.scenario import with_params

from . import apf, judge, safety, search

METHOD = "modified-vortex"
TRAIN_ENVS = (3, 4, 5)
"""Environments the sampled training scenarios come from."""


def _count(name: str, value, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise InputError(name, f"an integer >= {low}", value)
    return value


def _non_default(params: dict | None) -> dict:
    return {k: v for k, v in (params or {}).items() if v != PARAMETERS[k].default}


def training_set(train: int) -> dict:
    """The paper's encounters plus ``train`` sampled scenarios, environments 3, 4, 5 in turn.

    Parameters
    ----------
    train : int
        Sampled scenarios (≥ 0).

    Returns
    -------
    dict of Scenario
        Name to scenario (:func:`tuning.apf.training_scenarios`).
    """
    return apf.training_scenarios(train, envs=TRAIN_ENVS)


def write_params(path, theta: dict, *, verdict: str, summary: str) -> None:
    """``params.toml`` with the tuned values and, as comments, the verdict of the held-out comparison.

    Parameters
    ----------
    path : str or Path
        Output file.
    theta : dict
        ``k_vor0``, ``lam_sink``, ``r_safe``.
    verdict : str
        ``"improvement"``, ``"no improvement"`` or ``"not judged"``.
    summary : str
        One line per environment (comment lines).
    """
    judge.write_params(path, {k: theta[k] for k in ("k_vor0", "lam_sink", "r_safe")},
                       title="modified sink-vortex parameters from `mmg-casadi tune apf` (tuning/cli_apf.py)",
                       baseline="the paper's values", caveat="the paper's (K0_vor -10, Lambda -100, R_safe 15); keep "
                       "the paper's unless you have another reason", verdict=verdict, summary=summary)


def heldout(out, sets: dict, *, runs: int, envs, base_seed: int, workers=None) -> dict:
    """The statistics study of every parameter set (``name -> params``) into ``out/name``; returns
    ``name -> outcomes`` (see :func:`tuning.judge.outcomes_from_rows`).

    Parameters
    ----------
    out : str or Path
        Parent directory of the studies.
    sets : dict
        Name → full parameter overrides.
    runs : int
        Runs per environment.
    envs : tuple of int
        Environments.
    base_seed : int
        Seed of the held-out scenarios.
    workers : int, optional
        Local worker processes.

    Returns
    -------
    dict
        Set name to its outcomes: environment to ``{"run", "success", "ce", "mcte", "failure"}`` arrays.
    """
    res = {}
    for name, params in sets.items():
        d = Path(out) / name
        say(f"  held-out study '{name}' -> {d}")
        run_study(d, runs=runs, envs=envs, methods=(METHOD,), base_seed=base_seed, params=params, workers=workers)
        rows = [r for r in ResultsTable(d / "runs.csv").read() if r["run"] < runs and r["environment"] in envs]
        res[name] = judge.outcomes_from_rows(rows, METHOD)
    return res


def check_settings(path: Path, settings: dict) -> None:
    """Refuse to resume a directory whose stored results were made with other settings (the evaluation log and
    the candidate studies are keyed by their parameters only); writes nothing.

    Parameters
    ----------
    path : pathlib.Path
        The settings file (``tuning.json``) in the output directory.
    settings : dict
        The settings of this call (JSON-ready).
    """
    if path.exists():
        try:
            stored = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            raise InputError("out", f"a directory whose {path.name} is readable (or a new directory)",
                             str(path.parent)) from None
        if stored != json.loads(json.dumps(settings)):
            key = next((k for k in settings if not isinstance(stored, dict)
                        or stored.get(k) != json.loads(json.dumps(settings[k]))), "config")
            raise InputError("out", f"a new directory, or the {key!r} that {path} records", str(path.parent))


def _markdown(report: dict) -> str:
    j = report["judgement"]
    lines = [f"# tune apf: verdict **{j['verdict']}**", "",
             f"Training: {report['train_cases']} scenarios (5 paper encounters + {report['train']} sampled, "
             f"environments 3-5, seed {report['train_seed']}); search {report['search']['evaluations']}, "
             f"{report['timings'].get('search_s', 0):.0f} s; "
             f"{report['search'].get('seconds_per_evaluation') or float('nan'):.1f} s per objective+gradient.", "",
             f"Paper: {report['params_paper']}  tuned: {report['params_tuned']}", "",
             f"Held-out: {report['holdout']} runs per environment, seed {report['holdout_seed']}, paired.", "",
             "| env | paper success [95 % CI] | tuned success [95 % CI] | difference [95 % CI] | McNemar p | "
             "ΔCE (joint) | ΔMCTE (joint) |", "|---|---|---|---|---|---|---|"]
    for e, r in j["environments"].items():
        s = r["success"]
        lines.append(f"| {e} | {r['success_baseline']:.4f} [{r['success_baseline_ci'][0]:.4f}, "
                     f"{r['success_baseline_ci'][1]:.4f}] | {r['success_candidate']:.4f} "
                     f"[{r['success_candidate_ci'][0]:.4f}, {r['success_candidate_ci'][1]:.4f}] | "
                     f"{s['difference']:+.4f} [{s['ci'][0]:+.4f}, {s['ci'][1]:+.4f}] | {s['p_value']:.3g} | "
                     f"{r['ce']['mean']:+.4f} | {r['mcte']['mean']:+.4f} |")
    if j["reasons"]:
        lines += ["", "Reasons for 'no improvement':", *[f"- {x}" for x in j["reasons"]]]
    return "\n".join(lines) + "\n"


def run(out, *, train: int = 195, holdout: int = 2000, params: dict | None = None,
        config: safety.SafetyConfig | None = None, envs=(1, 2, 3, 4, 5), starts: int = 1, grid: int = 3,
        max_iter: int = 8, target=(5,), workers: int | None = None) -> dict:
    """Tune, then judge on paired held-out runs; return the report (also written to ``out``).

    Parameters
    ----------
    out : str or Path
        Output directory (``params.toml``, ``report.json``, ``report.md``, ``evaluations.jsonl``,
        ``heldout/``); rerun with the same directory to resume.
    train : int
        Sampled training scenarios (plus the paper's five encounters), in [0, MAX_RUNS].
    holdout : int
        Held-out runs per environment and parameter set, in [1, MAX_RUNS].
    params : dict, optional
        Parameter overrides every run uses (the tuned entries are replaced).
    config : SafetyConfig, optional
        Weights and smoothing of the training objective.
    envs : tuple of int
        Environments of the held-out study.
    starts : int
        L-BFGS-B starts (from the best grid points).
    grid : int
        Grid points per tuned parameter of the coarse sweep, in [1, :data:`tuning.search.MAX_GRID`].
    max_iter : int
        L-BFGS-B iterations per start.
    target : tuple of int
        Environments where the tuned set must be significantly better to be called an improvement.
    workers : int, optional
        Worker processes of the held-out study.

    Returns
    -------
    dict
        The report written to ``report.json``: parameters (base, paper, tuned), training set, held-out study,
        configuration, gradient check, search, judgement, timings (s) and the files written.

    Notes
    -----
    Every argument, the held-out study's included, is checked before any work (and before ``out`` is made).
    """
    train = _count("train", train, 0)
    if train > MAX_RUNS:
        raise InputError("train", f"an integer in [0, {MAX_RUNS}] (MAX_RUNS)", train)
    holdout = check_runs(_count("holdout", holdout, 1), "holdout")
    starts = _count("starts", starts, 1)
    grid = _count("grid", grid, 1)
    search.grid(grid)  # its bound (MAX_GRID)
    max_iter = _count("max_iter", max_iter, 1)
    base = resolve(params, prefix="params.")
    extra = {k: v for k, v in _non_default(params).items() if k not in ("k_vor0", "lam_sink", "r_safe")}
    paper = {"k_vor0": safety.PAPER[0], "lam_sink": safety.LAM_SINK, "r_safe": safety.PAPER[1]}
    # the held-out study's arguments, checked before the search (which takes minutes)
    args = check_study_args(runs=holdout, envs=envs, methods=(METHOD,), base_seed=apf.HOLDOUT_SEED,
                            params={**extra, **paper}, workers=workers)
    envs = args["envs"]
    if not set(target) <= set(envs):
        raise InputError("target", f"environments among the held-out ones {list(envs)}", list(target))
    out = Path(out)
    check_resumable(out / "heldout" / "paper", runs=holdout, envs=envs, methods=(METHOD,),
                    base_seed=apf.HOLDOUT_SEED, params=args["params"])
    config = config or safety.SafetyConfig()
    settings = {"config": {**config.__dict__}, "train": train, "train_envs": list(TRAIN_ENVS),
                "train_seed": apf.TRAIN_SEED, "params": extra}
    check_settings(out / "tuning.json", settings)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "tuning.json", settings)
    timings = {}
    t_start = time.perf_counter()

    say(f"[1/4] training set: 5 paper encounters + {train} sampled scenarios (environments "
        f"{','.join(map(str, TRAIN_ENVS))}, seed {apf.TRAIN_SEED})")
    t0 = time.perf_counter()
    scenarios = {k: with_params(v, extra) for k, v in training_set(train).items()}
    cases = [safety.prepare_case(k, sc, config) for k, sc in scenarios.items()]
    timings["prepare_s"] = time.perf_counter() - t0
    n_fail = sum(not c.exact_success for c in cases)
    say(f"  {len(cases)} cases prepared in {timings['prepare_s']:.0f} s; at the paper's values the own ship "
        f"fails in {n_fail} (exact loop)")
    objective = safety.SafetyObjective(cases, config)
    say("[2/4] augmented steps (compiled once per layout, cached) and gradient check")
    timings["compile_s"] = objective.compile(say)
    paper_idx = list(range(min(5, len(cases))))
    t0 = time.perf_counter()
    gc = safety.gradient_check(objective, safety.PAPER, subset=paper_idx)
    timings["gradient_check_s"] = time.perf_counter() - t0
    say(f"  gradient check on the paper encounters: AD {gc['ad']} FD {gc['fd']} relative error "
        f"{gc['rel_error_norm']:.2e}")

    say(f"[3/4] search: paper + {grid}x{grid} grid, then L-BFGS-B from the best {starts} (<= {max_iter} "
        "iterations each)")
    t0 = time.perf_counter()
    found = search.search(objective, out, grid_n=grid, starts=starts, max_iter=max_iter, report=say)
    timings["search_s"] = time.perf_counter() - t0
    best = dict(zip(safety.THETA, found["best"]["theta"]))
    tuned = {"k_vor0": best["k_vor0"], "lam_sink": safety.LAM_SINK, "r_safe": best["r_safe"]}
    say(f"  best: {tuned} objective {found['best']['objective']:.6f} (paper {found['paper']['objective']:.6f})")
    write_params(out / "params.toml", tuned, verdict="not judged", summary="held-out study not finished")

    say(f"[4/4] held-out statistics study: {holdout} runs per environment {list(envs)}, seed "
        f"{apf.HOLDOUT_SEED}, paper vs tuned (paired)")
    t0 = time.perf_counter()
    same = all(abs(tuned[k] - paper[k]) < 1e-12 for k in paper)
    sets = {"paper": {**extra, **paper}} if same else {"paper": {**extra, **paper}, "tuned": {**extra, **tuned}}
    outcomes = heldout(out / "heldout", sets, runs=holdout, envs=envs, base_seed=apf.HOLDOUT_SEED, workers=workers)
    if same:
        outcomes["tuned"] = outcomes["paper"]
    judgement = judge.judge(outcomes["tuned"], outcomes["paper"], target=tuple(target))
    if same:
        judgement["verdict"] = "no improvement"
        judgement["reasons"].insert(0, "the search kept the paper's values")
    timings["heldout_s"] = time.perf_counter() - t0
    summary = "\n".join(
        f"env {e}: paper {r['success_baseline']:.4f}, tuned {r['success_candidate']:.4f}, difference "
        f"{r['success']['difference']:+.4f} [{r['success']['ci'][0]:+.4f}, {r['success']['ci'][1]:+.4f}], "
        f"McNemar p = {r['success']['p_value']:.3g} ({holdout} paired runs, seed {apf.HOLDOUT_SEED})"
        for e, r in judgement["environments"].items())
    write_params(out / "params.toml", tuned, verdict=judgement["verdict"], summary=summary)
    timings["total_s"] = time.perf_counter() - t_start
    report = {
        "command": "tune apf", "params": base, "params_paper": paper, "params_tuned": tuned,
        "train": train, "train_cases": len(cases), "train_envs": list(TRAIN_ENVS), "train_seed": apf.TRAIN_SEED,
        "train_exact_failures_at_paper": n_fail,
        "holdout": holdout, "holdout_seed": apf.HOLDOUT_SEED, "envs": list(envs),
        "config": {**config.__dict__}, "gradient_check": gc, "search": found, "judgement": judgement,
        "timings": timings,
        "files": {"params": str(out / "params.toml"), "report": str(out / "report.json")},
    }
    write_json(out / "report.json", report)
    write_text(out / "report.md", _markdown(report))
    say(_markdown(report))
    say(f"wrote {out / 'params.toml'}, {out / 'report.json'}, {out / 'report.md'} ({timings['total_s']:.0f} s)")
    return report
