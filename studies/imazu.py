"""The 22 Imazu encounters (:mod:`mmg_casadi.scenarios.imazu`), own ship with each method, targets holding course or
avoiding with the same method: per case own-ship safety, closest approach and the own ship's COLREG verdicts in
its encounters with a risk of collision (:func:`mmg_casadi.colregs.scorer.score_encounters`, profile the parameter
``colregs_profile``).

``mmg-casadi study imazu [--targets hold|avoid|both] [--methods a,b] [PARAMS] --out DIR`` writes
``DIR/<targets>_<method>.png`` (all 22 cases), ``DIR/imazu.md`` (the per-case table and, per method, the
per-encounter compliance with a Wilson 95 % interval) and ``DIR/metrics.json``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mmg_casadi.guidance import methods as registry
from mmg_casadi.scenarios.imazu import CASES, plot_imazu, run_imazu
from mmg_casadi.io import write_json, write_text
from mmg_casadi.params import resolve
from mmg_casadi.errors import InputError
from mmg_casadi.montecarlo.stats import wilson

DEFAULT_METHODS = ("colregs-vortex", "modified-vortex", "velocity-obstacle")
TARGETS = ("hold", "avoid")


def _verdict(e: dict) -> str:
    """One encounter in the table: ``target1 give-way kept`` or ``target2 stand-on not (17a_i, 8)``."""
    failed = [r for r, v in e["rules"].items() if v is not None and not v["verdict"]]
    return f"{e['other']} {e['role']} " + ("kept" if e["compliant"] else f"not ({', '.join(failed)})")


def _table(results: dict) -> str:
    """``imazu.md``: per targets and method, the per-encounter compliance and the per-case table."""
    lines = ["# Imazu problems: own ship's safety and COLREG verdicts", ""]
    for tg, by_method in results.items():
        for m, r in by_method.items():
            n, k = r["encounters"], r["kept"]
            low, high = wilson(k, n) if n else (float("nan"), float("nan"))
            rate = f"{100 * k / n:.1f} % [{100 * low:.1f}, {100 * high:.1f}]" if n else "n/a"
            lines += [f"## Targets {tg}, own ship {m}", "",
                      f"Safe in {r['safe']}/{len(r['cases'])} cases; risky encounters kept: {k}/{n} ({rate}); "
                      f"cases with every risky encounter kept: {r['compliant_cases']}/{len(r['cases'])}.", "",
                      "| Case | Safe | Min distance [L] | Encounters (own role, verdict, rules not kept) |",
                      "|---:|:---|---:|:---|"]
            for c in r["cases"]:
                lines.append(f"| {c['case']} | {'yes' if c['safe'] else 'no'} | {c['min_distance']:.2f} | "
                             + ("; ".join(_verdict(e) for e in c["encounters"]) or "no risk of collision") + " |")
            lines.append("")
    return "\n".join(lines)


def run(out, *, methods=None, params=None, targets: str = "both") -> dict:
    """Run the 22 cases for every method and target behaviour; write the figures and ``metrics.json``.

    Parameters
    ----------
    out : str or Path
        Output directory.
    methods : iterable of str, optional
        Own-ship methods (default: colregs-vortex, modified-vortex, velocity-obstacle).
    params : dict, optional
        Parameter overrides for every run.
    targets : {"hold", "avoid", "both"}
        Targets hold course and speed, avoid with the own ship's method, or both in turn.

    Returns
    -------
    dict
        The metrics written to ``metrics.json``: ``params``, ``cases`` and ``results`` (per target behaviour and
        method the safe cases, risky encounters and kept ones, and per case its outcome).
    """
    if targets not in TARGETS + ("both",):
        raise InputError("targets", "one of: hold, avoid, both", targets)
    methods = registry.parse_list(methods or DEFAULT_METHODS)
    resolved = resolve(params, prefix="params.")
    registry.check_run((*methods, "none"), params)  # before anything is written
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    metrics = {"params": resolved, "cases": list(CASES), "results": {}}
    with registry.run_of((*methods, "none"), params):
        for tg in (TARGETS if targets == "both" else (targets,)):
            for m in methods:
                rows = run_imazu(m, tg, params=params)
                plot_imazu(rows, out / f"{tg}_{m}.png", title=f"Imazu problems, {m}, targets {tg}")
                encounters = [e for r in rows for e in r["encounters"]]
                metrics["results"].setdefault(tg, {})[m] = {
                    "safe": sum(r["safe"] for r in rows), "encounters": len(encounters),
                    "kept": sum(1 for e in encounters if e["compliant"]),
                    "compliant_cases": sum(1 for r in rows if r["encounters"] and all(e["compliant"]
                                                                                     for e in r["encounters"])),
                    "cases": [{"case": r["case"], "safe": r["safe"], "reached_goal": r["reached_goal"],
                               "min_distance": r["min_distance"], "collided": r["collided"],
                               "encounters": r["encounters"]} for r in rows]}
                unsafe = [r["case"] for r in rows if not r["safe"]]
                res = metrics["results"][tg][m]
                print(f"  imazu targets {tg:5s} {m:>18s}: own ship safe in {len(rows) - len(unsafe)}/{len(rows)}"
                      + (f" (not: {unsafe})" if unsafe else "") + f", risky encounters kept {res['kept']}/"
                      f"{res['encounters']}", file=sys.stderr)
    write_text(out / "imazu.md", _table(metrics["results"]))
    write_json(out / "metrics.json", metrics)
    return metrics
