"""``mmg-casadi tune apf [--train N] [--holdout N] --out DIR``: tune the modified sink-vortex field.

Stages (progress on stderr): build the training set (the paper's five encounters plus ``--train`` sampled
scenarios of environments 1-2, base seed 1000), prepare the smooth rollouts, check the gradient against finite
differences, run IPOPT, compare the training scenarios in the exact closed loop, and evaluate the paper's and
the tuned values on ``--holdout`` held-out scenarios per environment 1-5 (base seed 2000) in the exact closed
loop. Writes ``DIR/params.toml`` (for ``simulate/study --params``) and ``DIR/report.json``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.io import write_json
from mmg_casadi.params import PARAMETERS, resolve
from mmg_casadi.scenario import with_params

from . import apf


def _say(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def _count(name: str, value, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise InputError(name, f"an integer >= {low}", value)
    return value


def _non_default(params: dict | None) -> dict:
    return {k: v for k, v in (params or {}).items() if v != PARAMETERS[k].default}


def run(out, *, train: int = 8, holdout: int = 40, params: dict | None = None,
        config: apf.TuningConfig | None = None, envs=(1, 2, 3, 4, 5)) -> dict:
    """Run the tuning and the held-out evaluation; return the report (also written to ``out``).

    Parameters
    ----------
    out : str or Path
        Output directory (``params.toml``, ``report.json``).
    train : int
        Sampled training scenarios (plus the paper's five encounters).
    holdout : int
        Held-out scenarios per environment.
    params : dict, optional
        Parameter overrides every run uses (the tuned entries are replaced by the tuning's values).
    config : TuningConfig, optional
        Settings of the smoothed training problem.
    envs : tuple of int
        Environments of the held-out evaluation.
    """
    train = _count("train", train, 0)
    holdout = _count("holdout", holdout, 1)
    base = resolve(params, prefix="params.")
    out = Path(out)
    config = config or apf.TuningConfig()
    t_start = time.perf_counter()

    _say(f"[1/5] training set: 5 paper encounters + {train} sampled scenarios (environments 1-2, "
         f"seed {apf.TRAIN_SEED})")
    scenarios = {k: with_params(v, _non_default(params)) for k, v in apf.training_scenarios(train).items()}
    _say("[2/5] smooth rollouts (exact loop at the paper's values sets each horizon)")
    t0 = time.perf_counter()
    cases = apf.prepare_cases(scenarios, config, _say)
    t_prep = time.perf_counter() - t0
    _say(f"[3/5] IPOPT on θ = (k_vor0, lam_sink, r_safe) from {apf.PAPER}, smooth s = {config.smooth:g}, "
         f"≤ {config.max_iter} iterations")
    result = apf.tune(cases, config, report=_say)
    result.timings["prepare_s"] = t_prep
    out.mkdir(parents=True, exist_ok=True)
    apf.write_params_toml(result, out / "params.toml")
    paper = dict(zip(apf.THETA, apf.PAPER))
    tuned = result.params_after
    _say("[4/5] training scenarios in the exact closed loop (paper vs tuned)")
    t0 = time.perf_counter()
    exact = {"paper": apf.exact_training(scenarios, paper, config.w_mcte),
             "tuned": apf.exact_training(scenarios, tuned, config.w_mcte)}
    _say(f"  exact training objective: paper {exact['paper']['total']:.4f}, tuned {exact['tuned']['total']:.4f}")
    t_exact = time.perf_counter() - t0
    _say(f"[5/5] held-out evaluation: {holdout} scenarios per environment {envs[0]}-{envs[-1]} "
         f"(seed {apf.HOLDOUT_SEED}), exact closed loop")
    t0 = time.perf_counter()
    heldout = apf.evaluate({"paper": {**_non_default(params), **paper}, "tuned": {**_non_default(params), **tuned}},
                           envs=envs, runs=holdout, report=_say)
    t_eval = time.perf_counter() - t0
    report = {
        "command": "tune apf",
        "params": base, "params_tuned_full": {**base, **tuned},
        "train": train, "holdout": holdout, "train_seed": apf.TRAIN_SEED, "holdout_seed": apf.HOLDOUT_SEED,
        "params_paper": paper, "params_tuned": tuned,
        "objective_before": result.objective_before, "objective_after": result.objective_after,
        "gradient_check": result.gradient_check,
        "tuning": result.to_dict(),
        "training_exact": exact,
        "heldout": {str(e): v for e, v in heldout.items()},
        "timings": {**result.timings, "exact_training_s": t_exact, "heldout_s": t_eval,
                    "total_s": time.perf_counter() - t_start},
        "files": {"params": str(out / "params.toml"), "report": str(out / "report.json")},
    }
    write_json(out / "report.json", report)
    _say(f"wrote {out / 'params.toml'} and {out / 'report.json'} ({report['timings']['total_s']:.0f} s)")
    return report
