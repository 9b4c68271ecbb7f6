"""One parameter swept over values in the statistics study, every value paired against a baseline value.

``mmg-casadi study sweep --param NAME --values v1,v2,... [--baseline V] [--runs N] [--envs 5] [--methods ...]
[--seed S] [--workers W] --out DIR`` runs :func:`mmg_casadi.montecarlo.study.run_study` once per value (into
``DIR/NAME=VALUE``, resumable) on the *same* sampled scenarios (same environments, runs and seed), so each
value is compared with the baseline (default: the parameter's table default) run by run: the success rates
with the exact McNemar test and Newcombe's interval of the difference (:func:`mmg_casadi.montecarlo.stats.paired_comparison`),
CE and MCTE as means over each value's successful runs and as paired differences over the runs where both
succeeded (:func:`tuning.judge.paired_mean`). Outputs: ``DIR/metrics.json``, ``DIR/sweep.csv``,
``DIR/sweep.md`` and ``DIR/sweep.png`` (success with 95 % intervals and failure counts per value).

This answers questions such as the paper's open one (§Limitations): does a larger safe radius R_safe give a
significantly higher success rate in congested environments?
"""

from __future__ import annotations

import csv
import math
import sys
import tomllib
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mmg_casadi.guidance import methods as registry
from mmg_casadi.errors import InputError
from mmg_casadi.io import atomic_open, save_figure, write_json, write_text
from mmg_casadi.limits import check_study_size
from mmg_casadi.montecarlo.study import check_resumable, check_study_args, run_study
from mmg_casadi.params import PARAMETERS, check_value
from mmg_casadi.plotting import FIGURE_DPI
from mmg_casadi.montecarlo.results import FAILURES, ResultsTable
from mmg_casadi.montecarlo.stats import paired_comparison, wilson

DEFAULT_METHODS = (registry.DEFAULT,)


def parse_values(param: str, text, field: str = "values") -> list:
    """The swept values: a comma-separated string or a sequence, each checked against the parameter table.

    Each text item is read as a TOML value, like ``--set`` (``40`` an integer, ``2.5`` a number, ``true`` a
    boolean, a bare word a string), so integer, boolean and choice parameters can be swept too.

    Parameters
    ----------
    param : str
        Parameter name (:data:`mmg_casadi.params.PARAMETERS`).
    text : str or sequence
        Values, e.g. ``"10,15,20"``.
    field : str, default 'values'
        Name of the input field, used in the error message (e.g. ``"baseline"``).

    Returns
    -------
    list
        The checked values (int, float, bool or str), in the order given.

    Examples
    --------
    >>> parse_values("r_safe", "10, 15,20")
    [10.0, 15.0, 20.0]
    >>> parse_values("vo_candidates", "40,80"), parse_values("vo_hold", "true,false")
    ([40, 80], [True, False])
    """
    if param not in PARAMETERS:
        raise InputError("param", "a parameter name (see `mmg-casadi params`)", param)
    items = [v.strip() for v in text.split(",")] if isinstance(text, str) else list(text)
    if not items or any(v == "" for v in items):
        raise InputError(field, "a comma-separated list of values", text)
    out = [check_value(param, _toml_value(v) if isinstance(v, str) else v, field=field, cls=InputError)
           for v in items]
    if len(set(out)) != len(out):
        raise InputError(field, "distinct values", text)
    return out


def _toml_value(text: str):
    """``text`` read as a TOML value; text that is not one (a bare word) is kept as the string."""
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except (tomllib.TOMLDecodeError, RecursionError):  # not a TOML value (or nested too deep)
        return text


def _fmt(value) -> str:
    """A swept value as text: ``:g`` for a number, else as written (``true``/``false`` for a boolean)."""
    if isinstance(value, bool):
        return str(value).lower()
    return f"{value:g}" if isinstance(value, (int, float)) else str(value)


def _label(param: str, value) -> str:
    return f"{param}={_fmt(value)}"


def _outcomes(rows, env: int, method: str, runs: int) -> dict:
    rs = sorted((r for r in rows if r["environment"] == env and r["method"] == method and r["run"] < runs),
                key=lambda r: r["run"])
    return {"run": np.array([r["run"] for r in rs]), "success": np.array([bool(r["success"]) for r in rs]),
            "ce": np.array([r["ce"] for r in rs], float), "mcte": np.array([r["mcte"] for r in rs], float),
            "failure": [r["failure"] for r in rs]}


def run(out, *, param: str, values, baseline=None, runs: int = 200, envs="5", methods=None, base_seed: int = 0,
        params=None, workers=None, backend: str = "local", address=None) -> dict:
    """Run (or resume) the sweep and write its outputs; returns the metrics.

    Parameters
    ----------
    out : str or Path
        Output directory.
    param : str
        Swept parameter.
    values : str or sequence
        Its values.
    baseline : optional
        Value every other is paired against (default: the table default; added to the runs if absent).
    runs : int
        Runs per environment, method and value.
    envs : str or iterable of int
        Environments.
    methods : iterable of str, optional
        Methods (default: the modified sink-vortex).
    base_seed : int
        Seed of the sampled scenarios (the same for every value).
    params : dict, optional
        Other parameter overrides for every run (``param`` itself is replaced by each value).
    workers : int, optional
        Local worker processes.
    backend : {"local", "ray"}
        Executor of :func:`~mmg_casadi.montecarlo.study.run_study`.
    address : str, optional
        Ray address.

    Returns
    -------
    dict
        The metrics written to ``metrics.json``: ``param``, ``values``, ``baseline``, ``runs``, ``envs``,
        ``methods``, ``base_seed``, ``params`` and ``rows`` (the rows of ``sweep.csv``).
    """
    vals = parse_values(param, values)
    base_v = PARAMETERS[param].default if baseline is None else parse_values(param, [baseline], "baseline")[0]
    if base_v not in vals:
        vals = [base_v, *vals]
    others = {k: v for k, v in (params or {}).items() if k != param}
    out = Path(out)
    for v in vals:  # every value's study checked (and its stored runs) before the first one runs
        args = check_study_args(runs=runs, envs=envs, methods=methods or DEFAULT_METHODS, base_seed=base_seed,
                                params={**others, param: v}, workers=workers, backend=backend, address=address)
        check_resumable(out / _label(param, v), runs=args["runs"], envs=args["envs"], methods=args["methods"],
                        base_seed=args["base_seed"], params=args["params"], ranges=args["ranges"])
    envs, methods = args["envs"], args["methods"]
    check_study_size(args["runs"], len(envs) * len(methods) * len(vals))  # every value's rows are read at the end
    rows_by_value = {}
    for v in vals:
        d = out / _label(param, v)
        print(f"sweep {param} = {v}: -> {d}", file=sys.stderr)
        run_study(d, runs=runs, envs=envs, methods=methods, base_seed=base_seed, params={**others, param: v},
                  workers=workers, backend=backend, address=address)
        rows_by_value[v] = ResultsTable(d / "runs.csv").read()

    table = []
    for e in envs:
        for m in methods:
            base = _outcomes(rows_by_value[base_v], e, m, runs)
            for v in vals:
                o = _outcomes(rows_by_value[v], e, m, runs)
                n = len(o["success"])
                k = int(o["success"].sum())
                lo, hi = wilson(k, n)
                ok = o["success"]
                pc = paired_comparison(o["success"], base["success"])
                both = o["success"] & base["success"]
                row = {"environment": e, "method": m, "value": v, "baseline": base_v, "runs": n,
                       "success_rate": k / n, "success_ci_low": lo, "success_ci_high": hi,
                       "difference": pc.difference, "difference_ci_low": pc.ci[0], "difference_ci_high": pc.ci[1],
                       "value_only": pc.a_only, "baseline_only": pc.b_only, "p_value": pc.p_value,
                       "ce_mean": float(np.nanmean(o["ce"][ok])) if ok.any() else math.nan,
                       "mcte_mean": float(np.nanmean(o["mcte"][ok])) if ok.any() else math.nan,
                       "ce_paired_diff": float(np.nanmean(o["ce"][both] - base["ce"][both])) if both.any()
                       else math.nan,
                       "mcte_paired_diff": float(np.nanmean(o["mcte"][both] - base["mcte"][both])) if both.any()
                       else math.nan}
                for f in FAILURES[1:]:
                    row[f"failures_{f}"] = sum(x == f for x in o["failure"])
                table.append(row)
    out.mkdir(parents=True, exist_ok=True)
    with atomic_open(out / "sweep.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=list(table[0]))
        w.writeheader()
        w.writerows(table)
    md = markdown(table, param)
    write_text(out / "sweep.md", md)
    plot_sweep(table, param, out / "sweep.png")
    metrics = {"param": param, "values": vals, "baseline": base_v, "runs": runs, "envs": list(envs),
               "methods": list(methods), "base_seed": base_seed, "params": others, "rows": table}
    write_json(out / "metrics.json", metrics)
    print(md, file=sys.stderr)
    return metrics


def markdown(table: list, param: str) -> str:
    """The sweep's rows as a Markdown table.

    Parameters
    ----------
    table : list of dict
        Rows of :func:`run`.
    param : str
        Swept parameter (column title).

    Returns
    -------
    str
        The table, ending with a newline.
    """
    lines = [f"| env | method | {param} | success [95 % CI] | Δ vs {_fmt(table[0]['baseline'])} [95 % CI] | "
             "McNemar p | collision / stalled / timeout / diverged | CE | MCTE |",
             "|---|---|---|---|---|---|---|---|---|"]
    for r in table:
        lines.append(f"| {r['environment']} | {r['method']} | {_fmt(r['value'])} | {r['success_rate']:.4f} "
                     f"[{r['success_ci_low']:.4f}, {r['success_ci_high']:.4f}] | {r['difference']:+.4f} "
                     f"[{r['difference_ci_low']:+.4f}, {r['difference_ci_high']:+.4f}] | {r['p_value']:.3g} | "
                     f"{r['failures_collision']} / {r['failures_stalled']} / {r['failures_timeout']} / "
                     f"{r['failures_diverged']} | {r['ce_mean']:.4f} | {r['mcte_mean']:.3f} |")
    return "\n".join(lines) + "\n"


def plot_sweep(table: list, param: str, path) -> Figure:
    """Success rate with 95 % intervals per value (one line per environment and method) and failure counts.

    Parameters
    ----------
    table : list of dict
        Rows of :func:`run`.
    param : str
        Swept parameter (axis label).
    path : str or Path
        Output image.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, saved to ``path``.
    """
    fig = Figure(figsize=(10, 4), layout="constrained")
    ax, ax2 = fig.subplots(1, 2)
    cells = list(dict.fromkeys((r["environment"], r["method"]) for r in table))
    values = sorted({r["value"] for r in table})
    numeric = all(isinstance(v, (int, float)) for v in values)  # else (a choice parameter) one slot per value
    for e, m in cells:
        rs = sorted((r for r in table if r["environment"] == e and r["method"] == m), key=lambda r: r["value"])
        x = np.array([r["value"] if numeric else values.index(r["value"]) for r in rs], float)
        y = np.array([r["success_rate"] for r in rs])
        err = np.array([[r["success_rate"] - r["success_ci_low"] for r in rs],
                        [r["success_ci_high"] - r["success_rate"] for r in rs]])
        ax.errorbar(x, 100 * y, yerr=100 * err, marker="o", capsize=3, label=f"env {e} {m}")
        for i, r in enumerate(rs):
            if r["value"] != r["baseline"]:
                ax.annotate(f"p={r['p_value']:.2g}", (x[i], 100 * y[i]), textcoords="offset points",
                            xytext=(4, 6), fontsize=7)
        bottom = np.zeros(len(rs))
        for f in FAILURES[1:]:
            c = np.array([r.get(f"failures_{f}", 0) for r in rs], float)  # tables older than a kind: none
            if c.any():
                ax2.bar(x + 0.0, c, bottom=bottom, width=0.6 * (np.min(np.diff(x)) if len(x) > 1 else 1.0),
                        label=f"{f} (env {e} {m})" if len(cells) > 1 else f)
                bottom += c
    if not numeric:
        for a in (ax, ax2):
            a.set_xticks(range(len(values)), [_fmt(v) for v in values])
    unit = PARAMETERS[param].unit if param in PARAMETERS else ""
    xlabel = f"{param} [{unit or '-'}]"
    ax.set_xlabel(xlabel)
    ax.set_ylabel("success rate [%] (95 % Wilson CI)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax2.set_xlabel(xlabel)
    ax2.set_ylabel("failed runs [count]")
    ax2.grid(True, alpha=0.3)
    if ax2.get_legend_handles_labels()[0]:
        ax2.legend(fontsize=8)
    save_figure(fig, path, dpi=FIGURE_DPI)
    return fig
