"""A folder of encounter scenarios (e.g. a set written by ``mmg-casadi generate``) run for several own-ship
methods, the targets holding course or avoiding with the own ship's method; per situation and encounter the own
ship's safety, COLREG verdicts (:func:`mmg_casadi.colregs.scorer.score_encounters`, profile the parameter
``colregs_profile``), closest approach and delay, and the methods compared paired.

``mmg-casadi study encounters SET_DIR --out DIR [--methods a,b] [--targets hold|avoid] [PARAMS]`` runs every
``SET_DIR/*.toml`` (in name order) and writes

* ``DIR/situations.csv``: per situation and method (:data:`SITUATION_COLUMNS`): ``safe`` (the own ship reached
  her goal without a collision), ``status`` (her outcome, :data:`mmg_casadi.closed_loop.outcome.OUTCOMES`:
  ``grounded`` or ``collided`` when a contact ended her voyage), ``min_distance`` (L, to the nearest target),
  ``delay`` (L/U, time to goal minus
  the planned voyage time; empty if she did not arrive), the number of encounters with a risk of collision and of
  those kept, and ``wall_s``, the run's wall-clock time (the only column that differs between repeated runs);
* ``DIR/encounters.csv``: per situation, method and target (:data:`ENCOUNTER_COLUMNS`): the requested encounter
  type (from the set's ``generation.json``, if any), the own ship's role as the scorer classified the run, whether
  it is the generated one, ``applicable`` (a risk of collision arose and reached its CPA, so the scorer judged it;
  an unfinished encounter is not judged), ``compliant``, ``score``, the rules not kept
  and ``cpa`` (L, the closest approach to that target);
* ``DIR/summary.md``: per method the rates with Wilson 95 % intervals, and every pair of methods compared paired
  (:func:`mmg_casadi.montecarlo.stats.paired_comparison`, exact McNemar): the safe flag paired by situation, the
  compliance of encounters paired by situation and target (encounters with a risk of collision under both methods).
"""

from __future__ import annotations

import csv
import dataclasses
import io
import itertools
import math
import sys
import time
from pathlib import Path

import numpy as np

from mmg_casadi.errors import InputError
from mmg_casadi.colregs.scorer import judged_encounters
from mmg_casadi.guidance import methods as registry
from mmg_casadi.io import write_text
from mmg_casadi.montecarlo.stats import paired_comparison, wilson
from mmg_casadi.params import resolve
from mmg_casadi.readers import load_json
from mmg_casadi.scenarios.generate import ROLES, requested_types
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.scenarios.scenario import load_scenario, with_method

DEFAULT_METHODS = ("colregs-vortex", "modified-vortex", "velocity-obstacle")
TARGETS = ("hold", "avoid")
SITUATION_COLUMNS = ("situation", "method", "targets", "ships", "safe", "reached_goal", "collided", "status",
                     "min_distance", "delay", "encounters", "kept", "wall_s")
ENCOUNTER_COLUMNS = ("situation", "method", "target", "requested", "role", "as_generated", "applicable",
                     "compliant", "score", "rules_not_kept", "cpa")
TIMING_COLUMNS = ("wall_s",)
"""Columns that depend on the machine and the moment, not on the runs."""


def _with_targets(sc, method: str, targets: str):
    """``sc`` with the own ship's ``method`` and every target holding course (``"none"``) or avoiding with it."""
    sc = with_method(sc, method)
    ships = (dataclasses.replace(sc.ships[0], method=None),) + tuple(
        dataclasses.replace(s, method="none" if targets == "hold" else method) for s in sc.ships[1:])
    return dataclasses.replace(sc, ships=ships)


def _fmt(v) -> str:
    """A CSV cell: empty for None, 6 significant digits for floats, 0/1 for booleans."""
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return ""
    if isinstance(v, bool):
        return "1" if v else "0"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _csv(columns, rows) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([_fmt(r[c]) for c in columns])
    return buf.getvalue()


def _encounter_rows(res, situation: str, method: str, requested: list) -> list[dict]:
    """One row per target: the own ship's encounters with it (scorer) and the closest approach."""
    m = res.metrics
    own = m["ships"][0]["name"]
    rows = []
    for j, ship in enumerate(res.scenario.ships[1:]):
        pair = next((p for p in m["pairs"] if p["a"] == own and p["b"] == ship.name), None)
        found = judged_encounters(pair["encounters"]["a"] if pair else [])
        kind = requested[j] if j < len(requested) else None
        role = found[0]["role"] if found else None
        failed = sorted({r for e in found for r, v in e["rules"].items() if v is not None and not v["verdict"]})
        rows.append({"situation": situation, "method": method, "target": ship.name, "requested": kind,
                     "role": role, "as_generated": None if kind is None or role is None else role == ROLES[kind][0],
                     "applicable": bool(found), "compliant": all(e["compliant"] for e in found) if found else None,
                     "score": float(np.mean([e["score"] for e in found])) if found else None,
                     "rules_not_kept": " ".join(failed), "cpa": pair["min_distance"] if pair else None})
    return rows


def _num(v, digits: int) -> str:
    return "n/a" if v is None else f"{v:.{digits}f}"


def _rate(k: int, n: int) -> str:
    if not n:
        return "n/a"
    lo, hi = wilson(k, n)
    return f"{k}/{n} = {100 * k / n:.1f} % [{100 * lo:.1f}, {100 * hi:.1f}]"


def _comparison(name: str, a: str, b: str, xa, xb) -> str:
    if not len(xa):
        return f"| {name} | {a} vs {b} | 0 | | | | | |"
    c = paired_comparison(xa, xb)
    return (f"| {name} | {a} vs {b} | {c.n} | {100 * c.rate_a:.1f} / {100 * c.rate_b:.1f} | {c.a_only} / {c.b_only} "
            f"| {100 * c.difference:+.1f} [{100 * c.ci[0]:+.1f}, {100 * c.ci[1]:+.1f}] | {c.p_value:.3g} | "
            f"{c.verdict()} |")


def summarize(situations: list[dict], encounters: list[dict], methods, *, targets: str,
              generation: dict | None = None) -> dict:
    """Per method the rates, and every pair of methods compared paired (module docstring).

    Parameters
    ----------
    situations, encounters : list of dict
        Rows of ``situations.csv`` and ``encounters.csv`` (Python values).
    methods : sequence of str
        The methods, in order.
    targets : str
        ``"hold"`` or ``"avoid"`` (for the text).
    generation : dict, optional
        The set's draw statistics (``generation.json``'s ``stats``).

    Returns
    -------
    dict
        ``methods``: per method ``situations``, ``safe``, ``encounters``, ``kept``, ``as_generated``,
        ``compliant_situations``, ``min_distance_median``, ``delay_mean``; ``comparisons``: per pair ``safe`` and
        ``compliant`` as :meth:`~mmg_casadi.montecarlo.stats.PairedComparison.to_dict` (``None`` without pairs);
        ``markdown``: the text of ``summary.md``.
    """
    per = {}
    lines = [f"# Encounter set: {len({r['situation'] for r in situations})} situations, targets {targets}", ""]
    if generation:
        lines += [f"Generated set: {generation['accepted']} situations accepted of {generation['checked']} "
                  f"classified ({100 * generation['acceptance_share']:.1f} % passed the classification check; "
                  f"{generation['attempts']} draws of whole situations, {generation['target_draws']} of single "
                  "targets).", ""]
    lines += ["| Method | Safe | Encounters kept | Role as generated | Situations all kept | Median min distance "
              "[L] | Mean delay [L/U] |", "|:---|:---|:---|:---|:---|---:|---:|"]
    for m in methods:
        s = [r for r in situations if r["method"] == m]
        e = [r for r in encounters if r["method"] == m and r["applicable"]]
        gen = [r for r in e if r["as_generated"] is not None]
        delays = [r["delay"] for r in s if r["delay"] is not None]
        d = {"situations": len(s), "safe": sum(r["safe"] for r in s), "encounters": len(e),
             "kept": sum(bool(r["compliant"]) for r in e), "as_generated": sum(r["as_generated"] for r in gen),
             "classified": len(gen),
             "compliant_situations": sum(r["encounters"] > 0 and r["kept"] == r["encounters"] for r in s),
             "min_distance_median": float(np.median([r["min_distance"] for r in s])) if s else None,
             "delay_mean": float(np.mean(delays)) if delays else None}
        per[m] = d
        lines.append(f"| {m} | {_rate(d['safe'], d['situations'])} | {_rate(d['kept'], d['encounters'])} | "
                     f"{_rate(d['as_generated'], d['classified'])} | {d['compliant_situations']}/{d['situations']} | "
                     f"{_num(d['min_distance_median'], 2)} | {_num(d['delay_mean'], 1)} |")
    lines += ["", "Paired comparisons (A vs B: rates, discordant pairs A only / B only, difference with Newcombe's "
              "95 % interval, exact McNemar p-value).", "",
              "| Flag | Methods | Pairs | Rate A / B [%] | A only / B only | Difference [pp] | p | Verdict |",
              "|:---|:---|---:|:---|:---|:---|---:|:---|"]
    comparisons = {}
    safe = {(r["situation"], r["method"]): r["safe"] for r in situations}
    kept = {(r["situation"], r["target"], r["method"]): bool(r["compliant"]) for r in encounters if r["applicable"]}
    keys = sorted({(r["situation"], r["target"]) for r in encounters})
    for a, b in itertools.combinations(methods, 2):
        sits = sorted({r["situation"] for r in situations if (r["situation"], a) in safe
                       and (r["situation"], b) in safe})
        xa, xb = [safe[(s, a)] for s in sits], [safe[(s, b)] for s in sits]
        both = [k for k in keys if (*k, a) in kept and (*k, b) in kept]
        ea, eb = [kept[(*k, a)] for k in both], [kept[(*k, b)] for k in both]
        comparisons[f"{a} vs {b}"] = {
            "safe": paired_comparison(xa, xb).to_dict() if sits else None,
            "compliant": paired_comparison(ea, eb).to_dict() if both else None}
        lines += [_comparison("safe", a, b, xa, xb), _comparison("encounter kept", a, b, ea, eb)]
    lines.append("")
    return {"methods": per, "comparisons": comparisons, "markdown": "\n".join(lines)}


def _scenarios(set_dir) -> list[tuple[str, object]]:
    """``(id, Scenario)`` of every ``*.toml`` of ``set_dir``, in name order, all read before any run."""
    d = Path(set_dir)
    files = sorted(d.glob("*.toml")) if d.is_dir() else []
    if not files:
        raise InputError("SET_DIR", "a directory with scenario files (*.toml), e.g. written by `mmg-casadi "
                         "generate`", str(set_dir))
    out = []
    for f in files:
        sc = load_scenario(f)
        if len(sc.ships) < 2:
            raise InputError(str(f), "a scenario with an own ship and at least one target ship",
                             f"{len(sc.ships)} ship")
        out.append((f.stem, sc))
    return out


def run(out, *, set_dir, methods=None, targets: str = "hold", params=None) -> dict:
    """Run every scenario of ``set_dir`` for every method; write the CSVs and ``summary.md`` (module docstring).

    Parameters
    ----------
    out : str or Path
        Output directory.
    set_dir : str or Path
        Directory of scenario files (``*.toml``), with the ``generation.json`` of ``mmg-casadi generate`` if any.
    methods : iterable of str, optional
        Own-ship methods (default: colregs-vortex, modified-vortex, velocity-obstacle).
    targets : {"hold", "avoid"}
        The targets hold course and speed (method ``"none"``) or avoid with the own ship's method.
    params : dict, optional
        Parameter overrides for every run.

    Returns
    -------
    dict
        ``situations`` and ``encounters`` (the CSV rows) and the :func:`summarize` result (``summary``).
    """
    if targets not in TARGETS:
        raise InputError("targets", "one of: hold, avoid", targets)
    methods = registry.parse_list(methods or DEFAULT_METHODS)
    resolve(params, prefix="params.")
    cases = _scenarios(set_dir)
    requested = requested_types(set_dir)
    generation = None
    record = Path(set_dir) / "generation.json"
    if record.is_file():  # read by requested_types above: valid JSON
        generation = load_json(record, "generation record").get("stats")
    situations, encounters = [], []
    with registry.run_of((*methods, "none"), params):
        for m in methods:
            safe = 0
            for name, sc in cases:
                t0 = time.perf_counter()
                res = run_scenario(_with_targets(sc, m, targets), params)
                wall = time.perf_counter() - t0
                own = res.metrics["ships"][0]
                enc = _encounter_rows(res, name, m, requested.get(name, []))
                risky = [e for e in enc if e["applicable"]]
                row = {"situation": name, "method": m, "targets": targets, "ships": len(sc.ships),
                       "safe": bool(own["reached_goal"] and not own["collided"]),
                       "reached_goal": bool(own["reached_goal"]),
                       "collided": bool(own["collided"]), "status": own["status"],
                       "min_distance": float(np.min(res.own_distance())),
                       "delay": own["delay"], "encounters": len(risky),
                       "kept": sum(bool(e["compliant"]) for e in risky),
                       "wall_s": wall}
                safe += row["safe"]
                situations.append(row)
                encounters += enc
            print(f"  encounters targets {targets} {m:>18s}: own ship safe in {safe}/{len(cases)}", file=sys.stderr)
    summary = summarize(situations, encounters, methods, targets=targets, generation=generation)
    out = Path(out)
    write_text(out / "situations.csv", _csv(SITUATION_COLUMNS, situations))
    write_text(out / "encounters.csv", _csv(ENCOUNTER_COLUMNS, encounters))
    write_text(out / "summary.md", summary["markdown"])
    return {"situations": situations, "encounters": encounters, "summary": summary}
