"""The 22 Imazu encounters (:mod:`mmg_casadi.scenarios.imazu`), own ship with each method, targets holding course or
avoiding with the same method: per case own-ship safety, closest approach and the own ship's COLREG rule verdicts.

``mmg-casadi study imazu [--targets hold|avoid|both] [--methods a,b] [PARAMS] --out DIR`` writes
``DIR/<targets>_<method>.png`` (all 22 cases) and ``DIR/metrics.json``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mmg_casadi.guidance import methods as registry
from mmg_casadi.scenarios.imazu import CASES, plot_imazu, run_imazu
from mmg_casadi.io import write_json
from mmg_casadi.params import resolve
from mmg_casadi.errors import InputError

DEFAULT_METHODS = ("colregs-vortex", "modified-vortex", "velocity-obstacle")
TARGETS = ("hold", "avoid")


def _own_rules(res) -> dict:
    """The own ship's rule verdicts in its ship pairs (``rules`` of metrics.json), by target name."""
    own = res.metrics["ships"][0]["name"]
    out = {}
    for p in res.metrics["pairs"]:
        if "rules" in p and own in (p["a"], p["b"]):
            side = p["rules"]["a" if p["a"] == own else "b"]
            other = p["b"] if p["a"] == own else p["a"]
            out[other] = {"encounter": side.get("encounter"), "compliant": side.get("compliant_all"),
                          "verdicts": {k: v.get("verdict") for k, v in side.items() if isinstance(v, dict)
                                       and "verdict" in v}}
    return out


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
    """
    if targets not in TARGETS + ("both",):
        raise InputError("targets", "one of: hold, avoid, both", targets)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    methods = registry.parse_list(methods or DEFAULT_METHODS)
    metrics = {"params": resolve(params, prefix="params."), "cases": list(CASES), "results": {}}
    for tg in (TARGETS if targets == "both" else (targets,)):
        for m in methods:
            rows = run_imazu(m, tg, params=params)
            plot_imazu(rows, out / f"{tg}_{m}.png", title=f"Imazu problems, {m}, targets {tg}")
            metrics["results"].setdefault(tg, {})[m] = {
                "safe": sum(r["safe"] for r in rows),
                "cases": [{"case": r["case"], "safe": r["safe"], "reached_goal": r["reached_goal"],
                           "min_distance": r["min_distance"], "collided": r["collided"],
                           "rules": _own_rules(r["result"])} for r in rows]}
            unsafe = [r["case"] for r in rows if not r["safe"]]
            print(f"  imazu targets {tg:5s} {m:>18s}: own ship safe in {len(rows) - len(unsafe)}/{len(rows)}"
                  + (f" (not: {unsafe})" if unsafe else ""), file=sys.stderr)
    write_json(out / "metrics.json", metrics)
    return metrics
