"""The paper's statistical analysis (section "Statistical Analysis"): random encounters in five environments.

``mmg-casadi study statistics [--runs N] [--envs 1-5] [--methods a,b] [--backend local|ray] [--address A]
[--workers W] [--seed S] --out DIR`` runs (or resumes) :func:`mmg_casadi.montecarlo.run_study`: ``N`` runs per
environment and method (the paper: 5000), by default for the modified sink-vortex APF, the inverse-square APF
and the velocity obstacle. Outputs in ``DIR``: ``runs.csv``, ``summary.csv``, ``summary.md``,
``statistics.png``, ``metrics.json`` and ``failures/*.toml`` (replayable with ``mmg-casadi simulate``).
"""

from __future__ import annotations

import sys
from pathlib import Path

from mmg_casadi.montecarlo import DEFAULT_METHODS, run_study


def run(args, out) -> dict:
    """Run the study from parsed CLI arguments; returns ``{"config": ..., "summary": [rows]}``."""
    out = Path(out)
    methods = tuple(args.methods) if getattr(args, "methods", None) else DEFAULT_METHODS
    summary = run_study(
        out,
        runs=getattr(args, "runs", 200),
        envs=getattr(args, "envs", "1-5"),
        methods=methods,
        base_seed=getattr(args, "seed", 0),
        backend=getattr(args, "backend", "local"),
        address=getattr(args, "address", None),
        workers=getattr(args, "workers", None),
    )
    print(summary.to_markdown(), file=sys.stderr)
    import json
    return json.loads((out / "metrics.json").read_text(encoding="utf-8"))
