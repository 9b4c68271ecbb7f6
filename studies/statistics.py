"""The paper's statistical analysis (section "Statistical Analysis"): random encounters in five environments.

``mmg-casadi study statistics [--runs N] [--envs 1-5] [--methods a,b] [--params P.toml] [--backend local|ray]
[--address A] [--workers W] [--seed S] [--current LO-HI] [--wind LO-HI] --out DIR`` runs (or resumes) :func:`mmg_casadi.montecarlo.study.run_study`:
``N`` runs per environment and method (the paper: 5000), by default for the modified sink-vortex APF, the
inverse-square APF and the velocity obstacle. Outputs in ``DIR``: ``runs.csv``, ``study.json``, ``summary.csv``,
``summary.md``, ``statistics.png``, ``metrics.json`` and ``failures/*.toml`` (replayable with
``mmg-casadi simulate``).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from mmg_casadi.io import json_safe
from mmg_casadi.montecarlo.study import DEFAULT_METHODS, run_study


def run(out, *, runs: int = 200, envs="1-5", methods=None, base_seed: int = 0, params=None,
        backend: str = "local", address=None, workers=None, current=None, wind=None) -> dict:
    """Run the study (see :func:`mmg_casadi.montecarlo.study.run_study`); returns the config, parameters and summary.

    Parameters
    ----------
    out : str or Path
        Output directory (``runs.csv``, ``summary.md``, ``statistics.png``, ...; a study there is resumed).
    runs : int
        Runs per environment and method.
    envs : str or iterable of int
        Environments, e.g. ``"1-5"`` or ``(1, 3)``.
    methods : iterable of str, optional
        Methods (default: :data:`mmg_casadi.montecarlo.study.DEFAULT_METHODS`).
    base_seed : int
        Base seed of the scenario sampler.
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`) for every run.
    backend : {"local", "ray"}
        Local process pool or a Ray cluster.
    address : str, optional
        Ray cluster address (backend ``"ray"``).
    workers : int, optional
        Local worker processes / CPUs of a new local Ray cluster.
    current, wind : tuple of float, optional
        Ranges ``(low, high)`` of the per-run current speed (fraction of U) and wind speed (m/s), sampled
        uniformly with a uniform direction (calm water when omitted).

    Returns
    -------
    dict
        The contents of ``out/metrics.json``.
    """
    out = Path(out)
    summary = run_study(out, runs=runs, envs=envs, methods=methods or DEFAULT_METHODS, base_seed=base_seed,
                        params=params, backend=backend, address=address, workers=workers, current=current,
                        wind=wind)
    print(summary.to_markdown(), file=sys.stderr)
    return json_safe(json.loads((out / "metrics.json").read_text(encoding="utf-8")))
