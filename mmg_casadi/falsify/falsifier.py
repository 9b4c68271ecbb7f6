"""``falsify``: run the searches for one method and write what they found.

``mmg-casadi falsify --method M --env 5 --budget N --objective collision --out DIR`` and :func:`falsify` run the
searches of :mod:`~mmg_casadi.falsify.search` at the same budget and write into DIR:

``summary.json``
    per search: simulations, failures, distinct failures (:mod:`~mmg_casadi.falsify.report`), the least
    robustness, wall time; the search that found the most distinct failures; the envelope and the settings.
``failures.csv``
    every failure: search, simulation index, robustness, kind, agent, time, geometry, its group among the search's
    failures (``cluster``) and among every search's (``pooled``), its scenario file, and whether ``simulate``
    reproduced it (the own ship's closest approach and collision time equal to the bit).
``distinct.csv``
    one row per pooled group of failures (a distinct encounter geometry): its least robust member, how many
    failures of each search fell in it.
``failures/<search>_<index>.toml`` and ``.png``
    every failure as a scenario file that ``mmg-casadi simulate`` replays exactly, and its figure.
``trace.csv``, ``trace.png``
    the robustness of every simulation of every search and its running minimum.
``search_<name>.json``
    every simulation of a search (its parameter vector, robustness, outcome): the checkpoint a rerun resumes from,
    and what ``mmg-casadi study hardest --from DIR`` reads (:func:`load_falsification`).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.falsify.envelope import Envelope
from mmg_casadi.falsify.report import cluster, distinct, plot_failure, plot_trace
from mmg_casadi.falsify.robustness import Evaluation, scenario_of
from mmg_casadi.falsify.search import SEARCHES, SearchConfig, SearchResult, run_search
from mmg_casadi.montecarlo.disturbance_sampling import DisturbanceRanges
from mmg_casadi.params import PARAMETERS

FIGURES = ("all", "distinct", "none")
"""Which failures get a figure: every one, the least robust of each distinct group, none."""


@dataclass
class Falsification:
    """The searches' results for one method (module docstring).

    Parameters
    ----------
    method : str
        The method searched.
    envelope : Envelope
        The envelope searched.
    objective : str
        The objective.
    config : SearchConfig
        Budget and settings of every search.
    results : dict
        Search name to :class:`~mmg_casadi.falsify.search.SearchResult`.
    params : dict
        Parameter overrides of every run.
    """

    method: str
    envelope: Envelope
    objective: str
    config: SearchConfig
    results: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)

    def failures(self) -> list[tuple[str, int, Evaluation]]:
        """Every failure of every search as ``(search, simulation index, evaluation)``.

        Returns
        -------
        list of tuple
            In the order of :attr:`results`, then of the simulations.
        """
        return [(s, k, e) for s, r in self.results.items() for k, e in enumerate(r.evaluations) if e.failure]

    def summary(self) -> dict:
        """Per search: ``simulations``, ``failures``, ``distinct``, ``least_robustness``, ``seconds``; and ``best``,
        the search with the most distinct failures.

        Returns
        -------
        dict
            ``{"searches": {name: {...}}, "best": name, "pooled_distinct": int}``.
        """
        out = {}
        for s, r in self.results.items():
            out[s] = {"simulations": len(r.evaluations), "failures": len(r.failures),
                      "distinct": distinct([e.geometry for e in r.failures]),
                      "least_robustness": r.best.robustness if r.evaluations else math.nan,
                      "seconds": round(r.seconds, 1)}
        best = max(out, key=lambda s: (out[s]["distinct"], out[s]["failures"])) if out else None
        return {"searches": out, "best": best,
                "pooled_distinct": distinct([e.geometry for _, _, e in self.failures()])}

    def hardest(self, k: int = 20) -> list[Evaluation]:
        """The ``k`` hardest situations found: the least robust failure of each pooled distinct group, least
        robust first; then (if fewer) the other failures and then the simulations that did not fail, least robust
        first; each situation once.

        Parameters
        ----------
        k : int, default 20
            How many.

        Returns
        -------
        list of Evaluation
            At most ``k`` evaluations.
        """
        fails = [e for _, _, e in self.failures()]
        labels = cluster([e.geometry for e in fails])
        reps = {}
        for e, c in zip(fails, labels):
            if c not in reps or e.robustness < reps[c].robustness:
                reps[c] = e
        out = sorted(reps.values(), key=lambda e: e.robustness)[:k]
        seen = {e.theta.tobytes() for e in out}
        rest = sorted((e for e in fails if all(e is not r for r in reps.values())), key=lambda e: e.robustness)
        rest += sorted((e for r in self.results.values() for e in r.evaluations if not e.failure),
                       key=lambda e: e.robustness)
        for e in rest:
            if len(out) >= k:
                break
            if e.theta.tobytes() not in seen:
                seen.add(e.theta.tobytes())
                out.append(e)
        return out

    def scenario(self, evaluation: Evaluation, label: str = ""):
        """The scenario of an evaluation (every ship with the method and the parameter overrides).

        Parameters
        ----------
        evaluation : Evaluation
            One of the searches' evaluations.
        label : str, optional
            The scenario's source label.

        Returns
        -------
        Scenario
            The scenario ``mmg-casadi simulate`` replays.
        """
        return scenario_of(self.envelope, evaluation.theta, self.method, self.params, label=label)

    def plot(self, ax=None):
        """The robustness trace of every search (:func:`~mmg_casadi.falsify.report.plot_trace`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Axes to draw in.

        Returns
        -------
        matplotlib.figure.Figure
            The figure.
        """
        return plot_trace(self.results, ax=ax)

    def to_pandas(self):
        """Every failure as a table (the columns of ``failures.csv`` without the files).

        Returns
        -------
        pandas.DataFrame
            One row per failure.
        """
        import pandas as pd

        return pd.DataFrame(_failure_rows(self))

    def save(self, out, *, figures: str = "all") -> dict:
        """Write the outputs (module docstring) into ``out``.

        Parameters
        ----------
        out : str or Path
            Output directory.
        figures : {"all", "distinct", "none"}
            Which failures get a figure.

        Returns
        -------
        dict
            The summary written to ``summary.json``.
        """
        return write_outputs(self, out, figures=figures)


def load_falsification(directory) -> Falsification:
    """The falsification an output directory of :func:`falsify` / ``mmg-casadi falsify`` holds (its
    ``summary.json`` and the searches' ``search_<name>.json``).

    Parameters
    ----------
    directory : str or Path
        The output directory.

    Returns
    -------
    Falsification
        The searches' results as they were written.
    """
    directory = Path(directory)
    try:
        summary = json.loads((directory / "summary.json").read_text(encoding="utf-8"))
        env = Envelope(summary["environment"], disturbance=None if summary["envelope"]["disturbance"] is None else
                       DisturbanceRanges(**summary["envelope"]["disturbance"]))
        f = Falsification(summary["method"], env, summary["objective"], SearchConfig(**summary["config"]),
                          params=summary["params"] or {})
        for s in summary["searches"]:
            d = json.loads((directory / f"search_{s}.json").read_text(encoding="utf-8"))
            f.results[s] = SearchResult.from_dict(d["result"], env)
    except (OSError, KeyError, TypeError, ValueError) as e:
        raise InputError("--from", "an output directory of `mmg-casadi falsify` (summary.json and "
                         "search_<name>.json)", f"{directory} ({type(e).__name__}: {e})") from None
    return f


def falsify(method: str, environment: int = 5, *, budget: int = 2000, objective: str = "collision",
            searches=SEARCHES, seed: int = 0, params: dict | None = None,
            disturbance: DisturbanceRanges | None = None, config: SearchConfig | None = None,
            report=None, checkpoint=None) -> Falsification:
    """Search environment ``environment``'s envelope for the situations that break ``method``.

    Parameters
    ----------
    method : str
        Every ship's method (as in the study).
    environment : int, default 5
        Environment 1–6.
    budget : int, default 2000
        Simulations per search.
    objective : str, default "collision"
        ``collision``, ``colregs`` or ``grounding`` (:mod:`~mmg_casadi.falsify.robustness`).
    searches : sequence of str
        Searches to run (:data:`~mmg_casadi.falsify.search.SEARCHES`).
    seed : int, default 0
        Base seed of the random sample and CMA-ES.
    params : dict, optional
        Parameter overrides of every run (table names).
    disturbance : DisturbanceRanges, optional
        Also search the current and the wind within these ranges.
    config : SearchConfig, optional
        Settings of the searches (its ``budget`` and ``seed`` are replaced by the arguments).
    report : callable, optional
        Called with a progress line every few simulations and after each search.
    checkpoint : str or Path, optional
        A directory where each search is kept (``search_<name>.json``): when finished, and every
        :data:`~mmg_casadi.falsify.search.CHECKPOINT_EVERY` simulations and at an interruption while it runs. A
        finished search kept there with the same settings is read instead of run again; an unfinished one is
        replayed up to where it stopped and continued, so an interrupted run loses no simulation it kept and
        ends with the result of an uninterrupted one.

    Returns
    -------
    Falsification
        Every search's result.

    Examples
    --------
    >>> f = falsify("none", 1, budget=4, searches=("random",))
    >>> f.summary()["searches"]["random"]["simulations"]
    4
    """
    import dataclasses

    searches = tuple(searches)
    if not searches or any(s not in SEARCHES for s in searches) or len(set(searches)) != len(searches):
        raise InputError("searches", f"one or more of: {', '.join(SEARCHES)}", ",".join(map(str, searches)))
    for name in ("targets", "target_slowdown", "target_vessels"):
        if params and name in params and params[name] != PARAMETERS[name].default:
            raise InputError(f"params.{name}", f"the default {PARAMETERS[name].default!r} (the envelope is the "
                             "study's own: every ship sails the method on one leg, the own ship's hull)",
                             params[name])
    config = dataclasses.replace(config or SearchConfig(), budget=budget, seed=seed)
    env = Envelope(environment, disturbance=disturbance)
    f = Falsification(method, env, objective, config, params=dict(params or {}))
    for s in searches:
        kept, complete, gradients = _read_checkpoint(checkpoint, s, f)
        if complete:
            f.results[s] = kept
            continue
        if kept is not None and report:
            report(f"  {method} {s}: resuming after simulation {len(kept.evaluations)}")
        save = None if checkpoint is None else (
            lambda r, g: _write_checkpoint(checkpoint, r, f, complete=False, gradients=g))
        f.results[s] = run_search(s, method, env, objective, config, f.params, progress=report, save=save,
                                  resume=kept, gradients=gradients)
        if checkpoint is not None:
            _write_checkpoint(checkpoint, f.results[s], f)
        if report:
            r = f.results[s]
            report(f"{method} {s}: {len(r.evaluations)} simulations, {len(r.failures)} failures, "
                   f"{distinct([e.geometry for e in r.failures])} distinct, {r.seconds:.0f} s")
    return f


def _settings(f: Falsification) -> dict:
    """What a checkpoint must match to be read: method, environment, envelope, objective, settings, overrides."""
    d = f.envelope.disturbance
    return {"method": f.method, "environment": f.envelope.environment, "names": list(f.envelope.names),
            "disturbance": d.to_dict() if d else None, "objective": f.objective, "config": vars(f.config).copy(),
            "params": f.params}


def _read_checkpoint(directory, search: str, f: Falsification) -> tuple:
    """``(result, complete, gradients)`` of the search kept in ``directory`` with ``f``'s settings, or Nones."""
    path = None if directory is None else Path(directory) / f"search_{search}.json"
    if path is None or not path.exists():
        return None, False, None
    d = json.loads(path.read_text(encoding="utf-8"))
    if d.get("settings") != json.loads(json.dumps(_settings(f))):
        return None, False, None
    return SearchResult.from_dict(d["result"], f.envelope), d.get("complete", True), d.get("gradients")


def _write_checkpoint(directory, result: SearchResult, f: Falsification, *, complete: bool = True,
                      gradients: dict | None = None) -> None:
    """A finished search, or (``complete=False``) one so far with the gradients its replay needs."""
    from mmg_casadi.io import write_text

    d = {"settings": _settings(f), "result": result.to_dict()}
    if not complete:
        d.update(complete=False, gradients=gradients or {})
    text = json.dumps(d)
    write_text(Path(directory) / f"search_{result.search}.json", text)


def _failure_rows(f: Falsification) -> list[dict]:
    pooled = cluster([e.geometry for _, _, e in f.failures()])
    rows, k = [], 0
    for s, r in f.results.items():
        labels = cluster([e.geometry for e in r.failures])
        for c, (idx, e) in zip(labels, [(i, e) for i, e in enumerate(r.evaluations) if e.failure]):
            g = e.geometry
            rows.append({"search": s, "index": idx, "robustness": e.robustness, "kind": e.detail.get("kind"),
                         "agent": e.detail.get("agent"), "time": e.detail.get("time"),
                         "rule": g.get("rule") or "", "role": g.get("role") or "",
                         "bearing_deg": round(g["bearing_deg"], 2),
                         "relative_heading_deg": round(g["relative_heading_deg"], 2)
                         if math.isfinite(g["relative_heading_deg"]) else math.nan,
                         "progress": round(g["progress"], 4), "outcome": e.row["failure"],
                         "cluster": int(c), "pooled": int(pooled[k])})
            k += 1
    return rows


def write_outputs(f: Falsification, out, *, figures: str = "all") -> dict:
    """Write a falsification's outputs (module docstring) into ``out``.

    Parameters
    ----------
    f : Falsification
        The searches' results.
    out : str or Path
        Output directory.
    figures : {"all", "distinct", "none"}
        Which failures get a figure.

    Returns
    -------
    dict
        The summary written to ``summary.json``.
    """
    from mmg_casadi import figstyle as fs
    from mmg_casadi.io import write_json, write_text
    from mmg_casadi.scenarios.run import run_scenario
    from mmg_casadi.scenarios.scenario import dump_scenario, load_scenario

    if figures not in FIGURES:
        raise InputError("figures", f"one of: {', '.join(FIGURES)}", figures)
    out = Path(out)
    (out / "failures").mkdir(parents=True, exist_ok=True)
    rows = _failure_rows(f)
    evs = [e for _, _, e in f.failures()]
    drawn = set()
    for row, e in zip(rows, evs):
        if figures == "distinct" and row["pooled"] in drawn:
            figures_for_row = False
        else:
            figures_for_row = figures != "none"
        name = f"{row['search']}_{row['index']:05d}"
        path = out / "failures" / f"{name}.toml"
        write_text(path, dump_scenario(f.scenario(e, label=name)))
        res = run_scenario(load_scenario(path))  # exactly what `mmg-casadi simulate` runs
        own = res.metrics["ships"][0]
        row["file"] = f"failures/{name}.toml"
        row["reproduced"] = bool(own["min_distance"] == e.row["min_distance"] and (
            e.row["failure"] not in ("collision", "grounding") or own["collision_time"] == e.row["failure_time"]))
        if figures_for_row:
            drawn.add(row["pooled"])
            title = (f"env {f.envelope.environment}, {f.method}: {row['search']} #{row['index']}, "
                     f"robustness {e.robustness:.3f}")
            fs.save(plot_failure(res, e, title=title), out / "failures" / f"{name}.png")
    _write_csv(out / "failures.csv", rows)
    _write_csv(out / "distinct.csv", _distinct_rows(rows, f.results))
    trace = [{"search": s, **t} for s, r in f.results.items() for t in r.trace]
    _write_csv(out / "trace.csv", trace)
    fs.save(f.plot(), out / "trace.png")
    summary = {"method": f.method, "environment": f.envelope.environment, "objective": f.objective,
               "budget": f.config.budget, "seed": f.config.seed, "config": vars(f.config).copy(),
               "envelope": {"names": list(f.envelope.names), "low": f.envelope.low.tolist(),
                            "high": f.envelope.high.tolist(),
                            "disturbance": f.envelope.disturbance.to_dict() if f.envelope.disturbance else None},
               "params": f.params, **f.summary(),
               "reproduced": sum(r["reproduced"] for r in rows), "failures_written": len(rows)}
    write_json(out / "summary.json", summary)
    return summary


def _distinct_rows(rows: list[dict], results: dict) -> list[dict]:
    groups: dict = {}
    for r in rows:
        groups.setdefault(r["pooled"], []).append(r)
    out = []
    for c, members in sorted(groups.items()):
        rep = min(members, key=lambda r: r["robustness"])
        out.append({"pooled": c, "kind": rep["kind"], "rule": rep["rule"], "role": rep["role"],
                    "bearing_deg": rep["bearing_deg"], "relative_heading_deg": rep["relative_heading_deg"],
                    "progress": rep["progress"], "least_robustness": rep["robustness"], "file": rep["file"],
                    **{f"found_by_{s}": sum(m["search"] == s for m in members) for s in results}})
    return out


def _write_csv(path: Path, rows: list[dict]) -> None:
    from mmg_casadi.io import write_text
    import io

    buf = io.StringIO()
    if rows:
        w = csv.DictWriter(buf, fieldnames=list(rows[0]), lineterminator="\n")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if isinstance(v, float) and math.isnan(v) else v) for k, v in r.items()})
    write_text(path, buf.getvalue())

