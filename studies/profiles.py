"""How much each reading of the rules moves a method's COLREG compliance: one simulation, many scorers.

``mmg-casadi study profiles [--runs 1000 --envs 5 --methods colregs-vortex --seed 0 --workers W] --out DIR``
simulates the runs of one (environment, method) once, keeps each run's history and scores the own ship's
encounters under every step of :data:`LADDER`: from the laboratory profile as scorer version 4 read it to the
published profile, one change at a time, each step keeping the changes before it. It writes ``ladder.csv`` and
``ladder.md`` (per step the risky encounters, the share kept with a Wilson interval, and the paired change from the
step before on the encounters both steps judged, with the exact McNemar test) and ``verdicts.csv`` (each run's
``colregs_verdicts`` under every step).
"""

from __future__ import annotations

import csv
import dataclasses
import math
import sys
from dataclasses import dataclass
from pathlib import Path

from mmg_casadi.colregs.profiles import iitm_lab, published
from mmg_casadi.guidance import methods as registry
from mmg_casadi.guidance.plugins import ensure
from mmg_casadi.io import atomic_open, write_json, write_text
from mmg_casadi.limits import check_runs
from mmg_casadi.montecarlo.batching import BatchTask, LocalExecutor, plan_batches, prepare_layouts
from mmg_casadi.montecarlo.encounter_summary import compare_encounters, summarize_encounters
from mmg_casadi.montecarlo.execution import layout_for, own_ship_encounters, run_batch
from mmg_casadi.montecarlo.sampling import parse_envs
from mmg_casadi.params import resolve
from mmg_casadi.progress import progress_bar

_PUB = published()
LADDER: tuple[tuple[str, dict], ...] = (
    ("iitm-lab as scorer version 4", {"excuse": "open-duty", "inaction": "late", "side_17c": "now",
                                      "own_clearance": False, "w_pose_alpha": 0.0, "w_pose_beta": 0.0}),
    ("+ excuse only where another give-way duty forces the change", {"excuse": "forced"}),
    ("+ the stand-on ship acts only once the give-way ship's inaction is apparent", {"inaction": "no-action"}),
    ("+ Rule 17(c) for any port turn, the other ship's side at the onset", {"side_17c": "onset"}),
    ("+ the give-way ship's own action gives the safe distance (iitm-lab, version 5)", {"own_clearance": True}),
    ("+ stand-on course kept within 2° (detectable)", {"course_tolerance_deg": 2.0}),
    ("+ readily apparent from 30°", {"course_apparent_deg": 30.0}),
    ("+ safe passing distance 1 nm (risk gate, passing score)",
     {f: getattr(_PUB, f) for f in ("d_risk", "d_safe", "r_col", "r_nm", "r_min", "r_pref", "gamma_col", "gamma_nm",
                                    "gamma_min", "must_cpa")}),
    ("+ risk of collision within 420 s, no range limit", {"t_risk": _PUB.t_risk, "r_risk": _PUB.r_risk}),
    ("+ ample time to 2 nm (60 s to react), stand-on acts within 60 s",
     {f: getattr(_PUB, f) for f in ("late_tcpa", "late_range", "late_after_onset", "must_tcpa", "must_range")}),
    ("+ sectors: head-on 13° (in doubt 22.5°), overtaking bow 45°, past and clear, crossing ahead",
     {f: getattr(_PUB, f) for f in ("head_on_deg", "head_on_heading_deg", "head_on_doubt_deg", "overtaking_bow_deg",
                                    "past_clear", "d_ahead", "ahead_contact_deg")}),
    ("= published (pose in the safety score)", {f.name: getattr(_PUB, f.name) for f in dataclasses.fields(_PUB)}),
)
"""The steps from the laboratory profile read as scorer version 4 to the published profile: ``(label, changes)``,
each applied on top of the steps before it."""


def ladder_profiles() -> list:
    """The :class:`~mmg_casadi.colregs.profiles.ScoringProfile` of every step of :data:`LADDER`.

    Returns
    -------
    list of (str, ScoringProfile)
        The steps in order; the last equals :func:`~mmg_casadi.colregs.profiles.published`.

    Examples
    --------
    >>> steps = ladder_profiles()
    >>> steps[0][1].excuse, steps[-1][1] == published()
    ('open-duty', True)
    """
    out, p = [], iitm_lab()
    for label, changes in LADDER:
        p = dataclasses.replace(p, **changes)
        out.append((label, p))
    return out


def step_column(k: int) -> str:
    """The ``verdicts.csv`` column of step ``k``.

    Parameters
    ----------
    k : int
        Index of the step in :data:`LADDER`.

    Returns
    -------
    str
        ``"step<k>"``.
    """
    return f"step{k}"


@dataclass(frozen=True)
class LadderTask(BatchTask):
    """A batch of runs simulated once and scored under every step of :data:`LADDER`.

    Parameters
    ----------
    environment : int
        Environment of the runs.
    method : str
        Method of every ship.
    runs : tuple of int
        Run indices.
    base_seed : int, default 0
        Base seed of the scenario sampling.
    params : tuple, optional
        Sorted ``(name, value)`` pairs of the parameter overrides.
    chunk : int, optional
        Steps per ``mapaccum`` chunk.
    disturbance : DisturbanceRanges or None, optional
        Ranges of the per-run disturbance.
    plugins : tuple, optional
        Plugins the workers load (:class:`~mmg_casadi.montecarlo.batching.BatchTask`).
    """

    def __call__(self) -> list[dict]:
        ensure(self.plugins)
        histories: dict = {}
        rows = run_batch(self.environment, self.method, list(self.runs), self.base_seed, params=dict(self.params),
                         chunk=self.chunk, disturbance=self.disturbance, histories=histories)
        out = []
        for k, row in enumerate(rows):
            _scenario, t, states = histories[k]
            cells = {step_column(i): own_ship_encounters(t, states, p)["colregs_verdicts"]
                     for i, (_, p) in enumerate(ladder_profiles())}
            out.append({"environment": row["environment"], "method": row["method"], "run": row["run"],
                        "success": row["success"], **cells})
        return out


def run(out, *, runs: int = 1000, envs="5", methods=("colregs-vortex",), base_seed: int = 0, params=None,
        workers: int | None = None) -> dict:
    """Simulate the runs once and score them under every step of :data:`LADDER` (module docstring).

    Parameters
    ----------
    out : str or Path
        Output directory.
    runs : int
        Runs (indices 0..runs-1).
    envs : str or iterable of int
        One environment.
    methods : str or iterable of str
        One method.
    base_seed : int
        Base seed of the scenario sampler.
    params : dict, optional
        Parameter overrides for every run.
    workers : int, optional
        Local worker processes.

    Returns
    -------
    dict
        ``{"steps": [...]}``: per step its label, encounters, kept, rate, interval and the paired change.
    """
    out = Path(out)
    check_runs(runs)
    env = parse_envs(envs)
    method = registry.parse_list(methods)
    if len(env) != 1 or len(method) != 1:
        from mmg_casadi.errors import InputError
        raise InputError("--envs/--methods", "one environment and one method", f"{list(env)}/{list(method)}")
    resolved = resolve(params, prefix="params.")
    targets = {"avoid": (), "hold": ("none",)}.get(resolved["targets"], (resolved["targets"],))
    registry.check_used(params, (method[0], *targets), prefix="params.")
    tasks = [LadderTask(**{f.name: getattr(t, f.name) for f in dataclasses.fields(t)})
             for t in plan_batches(env, method, runs, base_seed=base_seed, params=params, batch_size=50)]
    prepare_layouts([layout_for(env[0], method[0], params)], workers or 1, log=sys.stderr)
    rows = []
    with LocalExecutor(workers) as executor:
        bar = progress_bar(runs, desc="profiles")
        try:
            for _task, got in executor.run(tasks):
                rows += got
                bar.update(len(got))
        finally:
            bar.close()
    rows.sort(key=lambda r: r["run"])
    steps = ladder_profiles()
    table = []
    for i, (label, _) in enumerate(steps):
        s = next(r for r in summarize_encounters(rows, step_column(i), label) if r["group"] == "all")
        entry = {"step": i, "change": label, "encounters": s["n"], "kept": s["kept"], "rate": s["rate"],
                 "ci_low": s["ci_low"], "ci_high": s["ci_high"], "excused": s["excused"]}
        if i:
            pair = [{"environment": r["environment"], "method": name, "run": r["run"], "colregs_verdicts": r[col]}
                    for name, col in (("after", step_column(i)), ("before", step_column(i - 1))) for r in rows]
            c = compare_encounters(pair, ["after", "before"])[0]
            entry.update({"paired": c["pairs"], "difference": c["difference"], "diff_low": c["ci_low"],
                          "diff_high": c["ci_high"], "p_value": c["p_value"]})
        table.append(entry)
    out.mkdir(parents=True, exist_ok=True)
    columns = ("step", "change", "encounters", "kept", "rate", "ci_low", "ci_high", "excused", "paired", "difference",
               "diff_low", "diff_high", "p_value")
    with atomic_open(out / "ladder.csv", "w", encoding="utf-8", newline="") as f:
        w = csv.DictWriter(f, columns, lineterminator="\n")
        w.writeheader()
        w.writerows({c: e.get(c, "") for c in columns} for e in table)
    with atomic_open(out / "verdicts.csv", "w", encoding="utf-8", newline="") as f:
        cols = ("environment", "method", "run", "success", *(step_column(i) for i in range(len(steps))))
        w = csv.DictWriter(f, cols, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    lines = [f"Environment {env[0]}, {method[0]}, runs 0–{runs - 1}, seed {base_seed}: the own ship's risky "
             "encounters kept under each step (each keeps the changes above it).", "",
             "| step | change | risky encounters | kept [%] (95 % CI) | paired change from the step above [pp] "
             "(95 % CI), McNemar p |", "|---:|:---|---:|:---|:---|"]
    for e in table:
        kept = ("n/a" if not e["encounters"] else
                f"{100 * e['rate']:.1f} [{100 * e['ci_low']:.1f}, {100 * e['ci_high']:.1f}]")
        change = "" if not e["step"] or not e.get("paired") else (
            f"{100 * e['difference']:+.1f} [{100 * e['diff_low']:+.1f}, {100 * e['diff_high']:+.1f}] on "
            f"{e['paired']} paired, p = {e['p_value']:.2g}")
        lines.append(f"| {e['step']} | {e['change']} | {e['encounters']} | {kept} | {change} |")
    write_text(out / "ladder.md", "\n".join(lines) + "\n")
    write_json(out / "metrics.json", {"environment": env[0], "method": method[0], "runs": runs, "seed": base_seed,
                                      "params": resolved, "steps": table})
    for e in table:
        rate = "n/a" if math.isnan(e["rate"]) else f"{100 * e['rate']:.1f} %"
        print(f"  step {e['step']:2d}: {rate:>8s} of {e['encounters']:5d}  {e['change']}", file=sys.stderr)
    return {"steps": table}
