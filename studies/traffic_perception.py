"""Traffic that behaves like traffic, seen as a ship sees it (issue 48): the statistics study under five conditions.

``python -m studies.traffic_perception [--runs 1000] [--envs 5] [--methods a,b,...] [--mix MIX] [--seed 0]
[--workers W] --out DIR`` runs :func:`mmg_casadi.montecarlo.study.run_study` once per condition of :data:`CONDITIONS`
into ``DIR/<condition>`` (each resumable) on the *same* sampled encounters (same environments, runs and seed):

``perfect``
    every target avoids with the study's method, the own ship knows their true states (the paper's study);
``ais``, ``ais-radar``
    the same traffic, the own ship's method sees the targets through AIS only, or through AIS and radar fused by
    the tracker (:mod:`mmg_casadi.perception`, the table's sensor defaults);
``mix``, ``hold``
    perfect knowledge, the targets draw their behaviours from ``--mix`` (:mod:`mmg_casadi.traffic`), or all hold
    course and speed.

Each condition is paired with ``perfect`` run by run (:data:`BASELINE`): success with the exact McNemar test and
Newcombe's interval of the difference (:func:`mmg_casadi.montecarlo.stats.paired_comparison`), and the run-level
COLREG flag (every risky encounter of the own ship kept) on the runs where both had a risky encounter; the
per-encounter compliance (Wilson interval) is given per condition (its encounters are not the same in two
conditions, so it is not paired). Outputs: ``DIR/table.csv``, ``DIR/table.md``, ``DIR/traffic_perception.png`` and
``DIR/metrics.json``. The COLREG scorer always judges the true states.
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from mmg_casadi import figstyle as fs
from mmg_casadi.io import write_json
from mmg_casadi.montecarlo.results import ResultsTable
from mmg_casadi.montecarlo.stats import paired_comparison, wilson
from mmg_casadi.montecarlo.study import check_study_args, run_study
from mmg_casadi.params import resolve
from mmg_casadi.traffic.mix import parse_targets
from mmg_casadi.vessel.library import load_vessel

MIX = "mix:avoid=0.5,hold=0.2,late=0.15,wrong=0.1,intent=0.05"
"""The default mix of target behaviours: half follow the rules with the study's method, the rest hold, give way
late, turn the wrong way or change their minds (our choice: every behaviour of :mod:`mmg_casadi.traffic` present)."""
BASELINE = "perfect"
METHODS = ("colregs-vortex", "modified-vortex", "velocity-obstacle")


def conditions(mix: str = MIX) -> dict[str, dict]:
    """The study's conditions: name -> the parameters it sets.

    Parameters
    ----------
    mix : str
        The ``targets`` mix of the condition ``mix``.

    Returns
    -------
    dict
        ``perfect``, ``ais``, ``ais-radar``, ``mix``, ``hold``.

    Examples
    --------
    >>> list(conditions())
    ['perfect', 'ais', 'ais-radar', 'mix', 'hold']
    """
    return {"perfect": {}, "ais": {"perception": "ais"}, "ais-radar": {"perception": "ais-radar"},
            "mix": {"targets": parse_targets(mix)}, "hold": {"targets": "hold"}}


CONDITIONS = tuple(conditions())
"""Names of the conditions, in order."""


def run(out, *, runs: int = 1000, envs="5", methods=METHODS, base_seed: int = 0, workers=None, params=None,
        mix: str = MIX, progress: bool = True) -> dict:
    """Run (or resume) every condition and write the paired table and the figure.

    Parameters
    ----------
    out : str or Path
        Output directory.
    runs : int
        Runs per environment, method and condition.
    envs : str
        Environments, e.g. ``"5"``.
    methods : sequence of str or str
        Methods of the own ship (and of the targets that avoid).
    base_seed : int
        Seed of the scenario sampler (and of the behaviours and the sensor noise drawn per run).
    workers : int, optional
        Local worker processes.
    params : dict, optional
        Further parameter values of every condition.
    mix : str
        The mix of the condition ``mix``.
    progress : bool
        Show progress bars.

    Returns
    -------
    dict
        ``{"table": rows}`` as written to ``table.csv``.
    """
    out = Path(out)
    conds = conditions(mix)
    for extra in conds.values():  # every condition's arguments checked before any work
        check_study_args(runs=runs, envs=envs, methods=methods, base_seed=base_seed, params={**(params or {}),
                                                                                            **extra}, workers=workers)
    for name, extra in conds.items():
        if progress:
            print(f"condition {name}", file=sys.stderr)
        run_study(out / name, runs=runs, envs=envs, methods=methods, base_seed=base_seed, workers=workers,
                  params={**(params or {}), **extra}, progress=progress)
    rows = {n: ResultsTable(out / n / "runs.csv").read() for n in conds}
    table = summarize(rows, runs, length_m=load_vessel(resolve(params)["vessel"]).ship.L)
    _write(out, table, mix)
    return {"table": table}


def _cells(rows: dict) -> list:
    return list(dict.fromkeys((r["environment"], r["method"]) for r in rows[BASELINE]))


def summarize(rows: dict, runs: int, *, length_m: float = 230.0) -> list[dict]:
    """One row per (environment, method, condition): success, compliance and the paired change from the baseline.

    Parameters
    ----------
    rows : dict
        Condition -> the rows of its ``runs.csv``.
    runs : int
        Runs per cell (indices ``0..runs-1``).
    length_m : float
        The own ship's length (m), for the perception error in metres.

    Returns
    -------
    list of dict
        The table.
    """
    table = []
    for env, method in _cells(rows):
        base = _by_run(rows[BASELINE], env, method, runs)
        for cond, rs in rows.items():
            cur = _by_run(rs, env, method, runs)
            keys = sorted(set(base) & set(cur))
            ok = [cur[k]["success"] for k in keys]
            lo, hi = wilson(sum(ok), len(ok))
            risky = sum(cur[k]["colregs_risky"] or 0 for k in keys)
            lawful = sum(cur[k]["colregs_lawful"] or 0 for k in keys)
            c_lo, c_hi = wilson(lawful, risky) if risky else (math.nan, math.nan)
            err = [cur[k]["perception_error"] for k in keys if not math.isnan(cur[k]["perception_error"] or math.nan)]
            r = {"environment": env, "method": method, "condition": cond, "runs": len(keys),
                 "success_rate": sum(ok) / len(ok), "success_ci_low": lo, "success_ci_high": hi,
                 "colregs_risky": risky, "colregs_lawful": lawful,
                 "compliance_rate": lawful / risky if risky else math.nan, "compliance_ci_low": c_lo,
                 "compliance_ci_high": c_hi,
                 "perception_error_m": float(np.mean(err)) * length_m if err else math.nan}
            if cond != BASELINE:
                pc = paired_comparison([cur[k]["success"] for k in keys], [base[k]["success"] for k in keys])
                r.update(success_diff=pc.difference, success_diff_low=pc.ci[0], success_diff_high=pc.ci[1],
                         success_p=pc.p_value)
                both = [k for k in keys if cur[k]["colregs_compliant"] is not None
                        and base[k]["colregs_compliant"] is not None]
                if both:
                    pk = paired_comparison([cur[k]["colregs_compliant"] for k in both],
                                           [base[k]["colregs_compliant"] for k in both])
                    r.update(kept_runs=len(both), kept_rate=pk.rate_a, kept_rate_baseline=pk.rate_b,
                             kept_diff=pk.difference, kept_diff_low=pk.ci[0], kept_diff_high=pk.ci[1],
                             kept_p=pk.p_value)
            table.append(r)
    return table


def _by_run(rows, env, method, runs) -> dict:
    return {r["run"]: r for r in rows if r["environment"] == env and r["method"] == method and r["run"] < runs}


COLUMNS = ("environment", "method", "condition", "runs", "success_rate", "success_ci_low", "success_ci_high",
           "success_diff", "success_diff_low", "success_diff_high", "success_p", "colregs_risky", "colregs_lawful",
           "compliance_rate", "compliance_ci_low", "compliance_ci_high", "kept_runs", "kept_rate", "kept_rate_baseline",
           "kept_diff", "kept_diff_low", "kept_diff_high", "kept_p", "perception_error_m")
"""Columns of ``table.csv``."""


def _pct(x) -> str:
    return "" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{100 * x:.1f}"


def markdown(table: list, mix: str = MIX) -> str:
    """The table as Markdown: per method and condition, success and compliance with their intervals and the paired
    change from the baseline.

    Parameters
    ----------
    table : list of dict
        :func:`summarize`.
    mix : str
        The mix of the condition ``mix`` (named under the table).

    Returns
    -------
    str
        Markdown text.
    """
    lines = ["| env | method | condition | success % [95 % CI] | Δ success pp [CI], McNemar p | encounters kept % "
             "[CI] (risky) | runs with every encounter kept: % vs perfect, Δ pp [CI], p | perception error m |",
             "|---|---|---|---|---|---|---|---|"]
    for r in table:
        d = "" if "success_diff" not in r else (f"{100 * r['success_diff']:+.1f} [{100 * r['success_diff_low']:+.1f}, "
                                                f"{100 * r['success_diff_high']:+.1f}], p = {r['success_p']:.2g}")
        k = "" if "kept_diff" not in r else (f"{_pct(r['kept_rate'])} vs {_pct(r['kept_rate_baseline'])}, "
                                             f"{100 * r['kept_diff']:+.1f} [{100 * r['kept_diff_low']:+.1f}, "
                                             f"{100 * r['kept_diff_high']:+.1f}], p = {r['kept_p']:.2g} "
                                             f"({r['kept_runs']} runs)")
        e = "" if math.isnan(r["perception_error_m"]) else f"{r['perception_error_m']:.1f}"
        lines.append(f"| {r['environment']} | {r['method']} | {r['condition']} | {_pct(r['success_rate'])} "
                     f"[{_pct(r['success_ci_low'])}, {_pct(r['success_ci_high'])}] | {d} | "
                     f"{_pct(r['compliance_rate'])} [{_pct(r['compliance_ci_low'])}, {_pct(r['compliance_ci_high'])}] "
                     f"({r['colregs_risky']}) | {k} | {e} |")
    lines.append("")
    lines.append(f"Conditions: perfect = targets avoid with the method, true states; ais / ais-radar = the same "
                 f"traffic seen through the sensors; mix = `{mix}`, true states; hold = targets hold course and speed. "
                 "Every condition paired with perfect on the same runs.")
    return "\n".join(lines) + "\n"


def plot(table: list, path) -> Figure:
    """Success and per-encounter compliance per method and condition, with 95 % intervals.

    Parameters
    ----------
    table : list of dict
        :func:`summarize`.
    path : str or Path
        The image.

    Returns
    -------
    matplotlib.figure.Figure
        The figure, saved to ``path``.
    """
    with fs.style():
        fig = Figure(figsize=(fs.PAGE, 0.45 * fs.PAGE), layout="constrained")
        axes = fig.subplots(1, 2)
        cells = list(dict.fromkeys((r["environment"], r["method"]) for r in table))
        conds = list(dict.fromkeys(r["condition"] for r in table))
        width = 0.8 / len(conds)
        for ax, key, label in ((axes[0], "success", "success rate [%]"),
                               (axes[1], "compliance", "encounters kept, published profile [%]")):
            for c, cond in enumerate(conds):
                rs = [next(r for r in table if (r["environment"], r["method"]) == cell and r["condition"] == cond)
                      for cell in cells]
                y = np.array([r[f"{key}_rate"] for r in rs]) * 100
                err = np.array([[r[f"{key}_rate"] - r[f"{key}_ci_low"] for r in rs],
                                [r[f"{key}_ci_high"] - r[f"{key}_rate"] for r in rs]]) * 100
                x = np.arange(len(cells)) + (c - (len(conds) - 1) / 2) * width
                ax.bar(x, y, width, yerr=err, capsize=2, label=cond, color=fs.SHIP_COLORS[c % len(fs.SHIP_COLORS)])
            ax.set_xticks(range(len(cells)), [m if len({e for e, _ in cells}) == 1 else f"env {e}\n{m}"
                                              for e, m in cells])
            ax.set_ylabel(label)
            ax.grid(True, axis="y", alpha=0.3)
        lo = min(r["success_ci_low"] for r in table) * 100
        axes[0].set_ylim(max(0.0, 5 * math.floor(lo / 5) - 5), 100)
        fig.legend(*axes[0].get_legend_handles_labels(), loc="outside upper center", ncol=len(conds), fontsize=7)
        fs.save(fig, path)
    return fig


def _write(out: Path, table: list, mix: str) -> None:
    with open(out / "table.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.DictWriter(fh, fieldnames=COLUMNS, restval="")
        w.writeheader()
        for r in table:
            w.writerow({k: r.get(k, "") for k in COLUMNS})
    (out / "table.md").write_text(markdown(table, mix), encoding="utf-8")
    plot(table, out / "traffic_perception.png")
    write_json(out / "metrics.json", {"mix": mix, "conditions": conditions(mix), "table": table})


def main(argv=None) -> int:
    """Command line: ``python -m studies.traffic_perception --out DIR [...]`` (see the module).

    Parameters
    ----------
    argv : list of str, optional
        Arguments (default: the command line's).

    Returns
    -------
    int
        Exit status 0.
    """
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, type=Path)
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--envs", default="5")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--mix", default=MIX)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=None)
    a = ap.parse_args(argv)
    run(a.out, runs=a.runs, envs=a.envs, methods=a.methods, base_seed=a.seed, workers=a.workers, mix=a.mix)
    print((a.out / "table.md").read_text(encoding="utf-8"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
