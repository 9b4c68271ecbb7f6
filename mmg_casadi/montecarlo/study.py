"""The paper's statistical study at scale: plan → sampler → executor → results handler (resumable).

A study is the cross product *environments × methods × runs*. Each (environment, method, run) is one random
encounter drawn by :func:`~mmg_casadi.montecarlo.sampling.sample_scenario` (so every method meets the same scenarios),
simulated by the compiled closed loop and reduced to one row of :data:`~mmg_casadi.montecarlo.results.RUN_COLUMNS`.

* **Plan** – :func:`~mmg_casadi.montecarlo.batching.plan_batches` splits the runs that are not yet in ``runs.csv``
  into batches (tasks) of ``batch_size`` runs of one (environment, method), interleaved over the cells.
* **Sampler / batch** – :func:`~mmg_casadi.montecarlo.execution.run_batch` samples the batch's scenarios and rolls
  them out together, one compiled step per (environment, method); each run is classified from its *final* state
  only (:func:`~mmg_casadi.closed_loop.outcome.run_outcome`; the outcome of a run is defined in
  :mod:`mmg_casadi.montecarlo.execution`).
* **Executors** – :class:`~mmg_casadi.montecarlo.batching.LocalExecutor` (a process pool, ``fork``) or
  :class:`~mmg_casadi.montecarlo.batching.RayExecutor` (a Ray cluster) run the batches and yield their rows as they
  complete. Workers never compile: :func:`~mmg_casadi.montecarlo.batching.prepare_layouts` builds every needed
  native library in the parent first (in parallel), workers load it from the disk cache (``$MMG_CASADI_CACHE``,
  forwarded to Ray workers).
* **Results** – :func:`run_study` appends each finished batch to ``runs.csv`` (durably; keys already stored are
  skipped, so an interrupted study resumes where it stopped and nothing is counted twice), then writes
  ``summary.csv``, ``summary.md``, ``statistics.png``, ``metrics.json`` and replayable TOML files of the first
  failures of every cell. A lock file keeps a second study from writing into the same directory at once.

The summary adds the per-encounter COLREG compliance per cell (Wilson 95 % interval over the encounters with a
risk of collision) and the failure counts per mechanism; ``comparisons.csv`` holds the paired comparison of every
two methods per environment (:mod:`mmg_casadi.montecarlo.comparisons`). ``colregs.csv`` gives the per-encounter
compliance by role and by rule, ``colregs_comparisons.csv`` the paired comparison of every two methods encounter
by encounter (:mod:`mmg_casadi.montecarlo.encounter_summary`); ``summary.md`` shows both.

Every run uses the same resolved parameter set (``params`` of :func:`run_study`: the table's defaults with the
user's overrides), recorded with its :func:`fingerprint` in ``runs.params.json`` (:data:`PARAMS_FILE`, the side file of
``runs.csv``, written before its first row) and in ``study.json``; a study is resumed only with the same
parameters, and a ``runs.csv`` whose side file is missing is not resumed at all.

With ``current``/``wind`` ranges (:mod:`mmg_casadi.montecarlo.disturbance_sampling`) every run meets its own steady
current and wind, drawn from ``(environment, run, seed)`` by a generator of its own (the same for every method;
the encounters are those of the calm study); the columns ``current_speed``, ``current_direction_deg``,
``wind_speed``, ``wind_direction_deg`` of ``runs.csv`` record it (or the fixed values of ``params``), and
``runs.params.json`` (and ``study.json``) the ranges: a study is resumed only with the same ranges.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import importlib.util
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from mmg_casadi.colregs.scorer import SCORER_VERSION
from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods as method_registry, plugins
from mmg_casadi.io import StagedFiles, json_safe, write_json, write_text
from mmg_casadi.limits import check_runs, check_study_size
from mmg_casadi.montecarlo.batching import (BACKENDS, DEFAULT_BATCH, LocalExecutor, RayExecutor, _check_workers,
                                            check_ray_address, plan_batches, prepare_layouts)
from mmg_casadi.montecarlo import encounter_summary
from mmg_casadi.montecarlo.disturbance_sampling import ENV_COLUMNS, DisturbanceRanges
from mmg_casadi.montecarlo.execution import (DEFAULT_CHUNK, _non_default, _run_disturbances, layout_for,
                                             profile_columns, sampled_scenario)
from mmg_casadi.montecarlo.results import ResultsTable, summarize
from mmg_casadi.montecarlo.tallies import TallyTable, summarize as tally_summary, to_markdown as tallies_markdown
from mmg_casadi.montecarlo.sampling import ALL_ENVIRONMENTS, parse_envs
from mmg_casadi.params import PARAMETERS, TARGET_METHODS, diff, resolve
from mmg_casadi.perception.layer import unused_parameter
from mmg_casadi.traffic.mix import is_mix
from mmg_casadi.traffic.sample import RANGES as TRAFFIC_RANGES
from mmg_casadi.progress import progress_bar
from mmg_casadi.scenarios.scenario import dump_scenario

DEFAULT_METHODS: tuple[str, ...] = method_registry.PAPER_STATISTICS
"""Methods compared by the paper's statistical analysis."""
MAX_FAILURE_FILES = 20
"""Replayable scenario files written per (environment, method) cell."""
PARAMS_FILE = "runs.params.json"
"""Side file of ``runs.csv``: the resolved parameters and disturbance ranges its rows were made with and their
:func:`fingerprint`, written (atomically) before the table's first row; a table with rows is resumed only with
the same parameters and ranges, and not at all without its record."""


# ----------------------------------------------------------------------------------------------- the study

def _check_envs(envs) -> tuple[int, ...]:
    if isinstance(envs, str):
        return parse_envs(envs)
    try:
        items = list(envs)
    except TypeError:
        raise InputError("envs", "environment numbers in 1-6", envs) from None
    if not items or any(isinstance(e, bool) or not isinstance(e, (int, np.integer))
                        or e not in ALL_ENVIRONMENTS for e in items):
        raise InputError("envs", "environment numbers in 1-6", envs)
    return tuple(sorted({int(e) for e in items}))


def _check_int(field: str, value, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low:
        raise InputError(field, f"an integer >= {low}", value)
    return int(value)


def check_study_args(*, runs=200, envs=(1, 2, 3, 4, 5), methods=DEFAULT_METHODS, base_seed=0, params=None,
                     backend="local", address=None, workers=None, batch_size=DEFAULT_BATCH, chunk=DEFAULT_CHUNK,
                     current=None, wind=None) -> dict:
    """Check every argument of :func:`run_study` without doing any work or writing anything.

    Callers that run other work first (``study paper``, ``study sweep``, ``tune apf``) call it before that work,
    so bad input is refused at once.

    Parameters
    ----------
    runs, envs, methods, base_seed, params, backend, address, workers, batch_size, chunk, current, wind
        As for :func:`run_study`.

    Returns
    -------
    dict
        The checked values: ``runs``, ``envs`` (tuple), ``methods`` (tuple), ``base_seed``, ``workers``,
        ``batch_size``, ``chunk``, ``params`` (the resolved set) and ``ranges``
        (:class:`~mmg_casadi.montecarlo.disturbance_sampling.DisturbanceRanges`).

    Examples
    --------
    >>> check_study_args(runs=10, envs="1-2", methods="none")["envs"]
    (1, 2)
    >>> check_study_args(workers=0)  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    mmg_casadi.errors.InputError: workers: expected an integer in [1, ...] (4 per core; or nothing for all cores), got 0
    """
    runs = check_runs(_check_int("runs", runs, 1), "runs")
    if backend not in BACKENDS:
        raise InputError("backend", f"one of: {', '.join(BACKENDS)}", backend)
    if address is not None and backend != "ray":
        raise InputError("address", "nothing unless backend is 'ray'", address)
    envs = _check_envs(envs)
    methods = method_registry.parse_list(methods)
    check_study_size(runs, len(envs) * len(methods), "runs")
    base_seed = _check_int("base_seed", base_seed, 0)
    workers = _check_workers("workers", workers)
    batch_size = _check_int("batch_size", batch_size, 1)
    chunk = _check_int("chunk", chunk, 1)
    resolved = resolve(params, prefix="params.")
    target_method = (resolved["targets"],) if resolved["targets"] in TARGET_METHODS else ()  # targets on a method
    method_registry.check_run((*methods, "none", *target_method), params)  # targets that hold use "none"
    _check_traffic_and_sensors(resolved)
    ranges = DisturbanceRanges(current=current, wind=wind)
    for name, rng in (("current", ranges.current), ("wind", ranges.wind)):
        for key in (f"{name}_speed", f"{name}_direction_deg"):
            if rng is not None and resolved[key] != PARAMETERS[key].default:
                raise InputError(name, f"nothing while params sets {key} (a fixed {name})", list(rng))
    if backend == "ray":  # last: it may wait for the network (a bad address used to fail after the compile)
        if importlib.util.find_spec("ray") is None:
            raise InputError("backend", "'local' (Ray is not installed; pip install 'mmg-casadi[ray]')", backend)
        check_ray_address(address)
    return {"runs": runs, "envs": envs, "methods": methods, "base_seed": base_seed, "workers": workers,
            "batch_size": batch_size, "chunk": chunk, "params": resolved, "ranges": ranges}


def _check_traffic_and_sensors(resolved: dict) -> None:
    """Refuse a behaviour range without a mix of targets and a sensor parameter the study's perception does not use."""
    if not is_mix(resolved["targets"]):
        for k in (*TRAFFIC_RANGES, "target_wrong_dcpa"):
            if resolved[k] != PARAMETERS[k].default:
                raise InputError(f"params.{k}", f"its default {PARAMETERS[k].default} unless targets is a mix "
                                 "(mix:NAME=P,...; it sets what the targets of a mix draw)", resolved[k])
    unused = unused_parameter(resolved)
    if unused is not None:
        raise InputError(f"params.{unused}", f"its default {PARAMETERS[unused].default!r} with perception = "
                         f"{resolved['perception']!r} (a sensor it does not use)", resolved[unused])


def run_study(out_dir, *, runs: int = 200, envs=(1, 2, 3, 4, 5), methods=DEFAULT_METHODS, base_seed: int = 0,
              params: dict | None = None, backend: str = "local", address: str | None = None,
              workers: int | None = None, progress: bool = True, batch_size: int = DEFAULT_BATCH,
              chunk: int = DEFAULT_CHUNK, executor=None, current=None, wind=None):
    """Run (or resume) the statistical study and write its outputs into ``out_dir``.

    Parameters
    ----------
    out_dir : str or Path
        Output directory: ``runs.csv`` (one row per run, appended as batches finish), ``runs.params.json``
        and ``study.json`` (the resolved parameter set and the disturbance ranges the table was made with),
        ``summary.csv``, ``summary.md`` (with the failure mechanisms and the paired comparisons), ``comparisons.csv``,
        ``statistics.png``, ``metrics.json`` (config, parameters and summary rows) and
        ``failures/env{e}_{method}_run{r}.toml`` (first ≤ 20 failures per cell, replayable with
        ``mmg-casadi simulate``).
    runs : int
        Runs per (environment, method), ≥ 1; run indices ``0..runs-1``.
    envs : str or iterable of int
        Environments, e.g. ``"1-5"`` or ``(1, 3)``.
    methods : str or iterable of str
        Collision-avoidance methods (names in :data:`mmg_casadi.guidance.methods.METHODS`).
    base_seed : int
        Base seed of the scenario sampler (≥ 0); a resumed table must have been made with the same seed.
    params : dict, optional
        Parameter overrides by name (:data:`mmg_casadi.params.PARAMETERS`) for every run, e.g. from
        ``tune apf``; a resumed table must have been made with the same resolved parameters.
    backend : {"local", "ray"}
        Local process pool or a Ray cluster.
    address : str, optional
        Ray cluster address (backend ``"ray"``).
    workers : int, optional
        Local worker processes (default: all cores); for Ray the CPUs of a new local cluster.
    progress : bool
        Show a progress bar on stderr (rate and ETA count only runs simulated by this call).
    batch_size : int
        Runs per task.
    chunk : int
        Steps per compiled chunk.
    executor : LocalExecutor or RayExecutor, optional
        Use this executor instead of one made from ``backend``/``address``/``workers`` (not closed here).
    current : (float, float), optional
        Range of a per-run current speed (fraction of U_des, in [0, 1]; direction uniform); a resumed table
        must have been made with the same range. Not together with a ``current_speed`` in ``params``.
    wind : (float, float), optional
        Range of a per-run true wind speed (m/s, in [0, 60]; direction uniform), likewise.

    Returns
    -------
    Summary
        The summary of the requested cells (rows already in ``runs.csv`` included).
    """
    args = check_study_args(runs=runs, envs=envs, methods=methods, base_seed=base_seed, params=params,
                            backend=backend, address=address, workers=workers, batch_size=batch_size, chunk=chunk,
                            current=current, wind=wind)
    runs, envs, methods, base_seed, workers = (args[k] for k in ("runs", "envs", "methods", "base_seed", "workers"))
    batch_size, chunk, resolved, ranges = args["batch_size"], args["chunk"], args["params"], args["ranges"]
    out = Path(out_dir)
    check_resumable(out, runs=runs, envs=envs, methods=methods, base_seed=base_seed, params=resolved,
                    ranges=ranges)  # before the directory and its lock file are made
    out.mkdir(parents=True, exist_ok=True)
    with _exclusive(out):
        return _run_study(out, runs, envs, methods, base_seed, resolved, backend, address, workers, progress,
                          batch_size, chunk, executor, ranges)


@contextlib.contextmanager
def _exclusive(out: Path):
    """Hold an exclusive lock on ``out/.study.lock`` so two studies never append to one ``runs.csv``."""
    fh = open(out / ".study.lock", "a+")
    try:
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            raise InputError("out_dir", "a directory no other running study is writing to", str(out)) from None
        yield
    finally:
        fh.close()


def _run_study(out, runs, envs, methods, base_seed, params, backend, address, workers, progress, batch_size,
               chunk, executor, ranges=DisturbanceRanges()):
    table = ResultsTable(out / "runs.csv")
    tally_table = TallyTable(out / "tallies.csv")
    planned = {(e, m, r) for e in envs for m in methods for r in range(runs)}
    done = check_resumable(out, runs=runs, envs=envs, methods=methods, base_seed=base_seed, params=params,
                           ranges=ranges)  # again, under the lock
    _record_study_params(out, params, ranges)
    tasks = plan_batches(envs, methods, runs, done=done, base_seed=base_seed, params=params,
                         batch_size=batch_size, chunk=chunk, disturbance=ranges, plugins=plugins.sources())
    log = sys.stderr if progress else None

    own_executor = executor is None
    if executor is None:
        executor = LocalExecutor(workers) if backend == "local" else RayExecutor(address, workers)
    started = time.perf_counter()
    new_runs = 0
    try:
        if tasks:
            cells = list(dict.fromkeys((t.environment, t.method) for t in tasks))
            n_compile = workers or os.cpu_count() or 1
            prepare_layouts([layout_for(e, m, _non_default({**params, **_run_disturbances(e, [0], base_seed, params,
                                                                                        ranges)[0]}))
                             for e, m in cells], n_compile, log=log)
            bar = None
            if progress:
                bar = progress_bar(len(planned), desc="statistics", initial=len(done))
            try:
                for _task, rows in executor.run(tasks):
                    tally_table.append(rows)  # first: a run's counts are never missing for a stored row
                    written = table.append(rows)
                    new_runs += written
                    if bar is not None:
                        bar.update(written)
            finally:
                if bar is not None:
                    bar.close()
    finally:
        if own_executor:
            executor.close()
    elapsed = time.perf_counter() - started

    order = {m: i for i, m in enumerate(methods)}
    rows = [row for row in table.read() if (row["environment"], row["method"], row["run"]) in planned]
    rows.sort(key=lambda r: (r["environment"], order[r["method"]], r["run"]))
    summary = summarize(rows)
    # scipy.stats (about 0.7 s to import): imported only when a study is written, not by `import mmg_casadi`
    from mmg_casadi.montecarlo.comparisons import compare_methods, to_markdown, write_csv  # scipy.stats: ~1 s
    comparisons = compare_methods(rows, methods)
    by_encounter = encounter_summary.summarize_profiles(rows, profile_columns(params))
    encounter_pairs = encounter_summary.compare_profiles(rows, profile_columns(params), methods)
    from mmg_casadi.montecarlo.plots import plot_statistics  # matplotlib: imported only when a study is written
    # the final files: each written under a temporary name, all renamed at the end with metrics.json last (an
    # interruption leaves the old set or the new, never a part of a file)
    counted = tally_summary([r for r in tally_table.read() if (r["environment"], r["method"], r["run"]) in planned])
    with StagedFiles() as st:
        summary.to_csv(st.path(out / "summary.csv"))
        write_csv(comparisons, st.path(out / "comparisons.csv"))
        encounter_summary.write_csv(by_encounter, st.path(out / "colregs.csv"), encounter_summary.ENCOUNTER_COLUMNS)
        encounter_summary.write_csv(encounter_pairs, st.path(out / "colregs_comparisons.csv"),
                                    encounter_summary.PAIR_COLUMNS)
        # a method with tallies (nmpc's solves and fallbacks): their sums, beside summary.md's tables
        tallied = ("\n## Tallies of the own ship (tallies.csv; mmg_casadi.montecarlo.tallies)\n\n"
                   + tallies_markdown(counted) + "\n") if counted else ""
        write_text(st.path(out / "summary.md"),
                   summary.to_markdown() + "\n\n## Failure mechanisms (own ship; mmg_casadi.montecarlo.failures)\n\n"
                   + summary.failures_markdown() + "\n\n## Paired comparisons (same runs; exact McNemar test)\n\n"
                   + to_markdown(comparisons) + "\n\n## COLREG encounters with a risk of collision (own ship; profile "
                   + ", ".join(profile_columns(params)) + "; mmg_casadi.montecarlo.encounter_summary)\n\n"
                   + encounter_summary.to_markdown(by_encounter, encounter_pairs) + "\n" + tallied)
        plot_statistics(summary, st.path(out / "statistics.png"))
        failures = write_failures(rows, out / "failures", params=params, staged=st)
        config = {"runs": runs, "envs": list(envs), "methods": list(methods), "base_seed": base_seed,
                  "backend": backend, "address": address, "workers": workers, "batch_size": batch_size,
                  "chunk": chunk, **ranges.to_dict()}
        write_json(st.path(out / "metrics.json"), {
            "config": config, "params": params, "summary": summary.rows, "comparisons": comparisons,
            **({"tallies": counted} if counted else {}),
            "colregs": {"by_encounter": by_encounter, "comparisons": encounter_pairs},
            "runs_total": len(rows),
            "runs_new": new_runs, "elapsed_s": elapsed,
            "failure_files": [str(p.relative_to(out)) for p in failures]})
    return summary


def fingerprint(params: dict, ranges: DisturbanceRanges = DisturbanceRanges()) -> str:
    """SHA-256 (hex) of a resolved parameter set and the disturbance ranges: what the rows of one ``runs.csv``
    share beyond their own columns.

    Parameters
    ----------
    params : dict
        A resolved parameter set (:func:`mmg_casadi.params.resolve`).
    ranges : DisturbanceRanges, optional
        Ranges of the per-run disturbance.

    Returns
    -------
    str
        64 hexadecimal digits.

    Examples
    --------
    >>> from mmg_casadi.params import resolve
    >>> fingerprint(resolve()) == fingerprint(resolve({"r_safe": 15.0}))
    True
    >>> fingerprint(resolve()) == fingerprint(resolve({"r_safe": 20.0}))
    False
    """
    text = json.dumps(json_safe({"params": params, "disturbance": ranges.to_dict()}), sort_keys=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def _range_text(rng) -> str:
    return "no range (calm water)" if rng is None else f"the range {rng[0]:g}-{rng[1]:g}"


def _stored_record(out: Path, table: ResultsTable) -> dict:
    """The parameters and ranges the rows of ``out/runs.csv`` were made with: its side file
    :data:`PARAMS_FILE`, else (a table of an older version) ``study.json``; a table without either is refused."""
    for name in (PARAMS_FILE, "study.json"):
        path = out / name
        if not path.exists():
            continue
        try:
            record = json.loads(path.read_text(encoding="utf-8"))
            if not isinstance(record["params"], dict):
                raise TypeError
            return record
        except (OSError, ValueError, KeyError, TypeError):
            raise InputError("out_dir", f"a directory whose {name} records the parameters of its runs.csv ({path} "
                             "is unreadable; use a new output directory)", str(out)) from None
    raise InputError("out_dir", f"a directory whose runs.csv has its parameter record {PARAMS_FILE} (it is "
                     f"missing, so the parameters of the stored runs are unknown; use a new output directory)",
                     str(out))


def check_resumable(out, *, runs: int, envs, methods, base_seed: int, params: dict,
                    ranges: DisturbanceRanges = DisturbanceRanges()) -> set:
    """Refuse to add runs to ``out/runs.csv`` that would not be comparable with the rows it holds (other seed,
    parameters, disturbance ranges or COLREG scorer version, :data:`~mmg_casadi.colregs.scorer.SCORER_VERSION`);
    writes nothing.

    The seed is a column of every row; the resolved parameters and the disturbance ranges are not, so they are
    compared with the table's side file :data:`PARAMS_FILE` (written before the table's first row): a table
    with rows but without its record is not resumed. The error names the first differing parameter.

    Parameters
    ----------
    out : str or Path
        The study directory (it need not exist).
    runs, envs, methods, base_seed
        The planned runs (checked values, see :func:`check_study_args`).
    params : dict
        The resolved parameter set.
    ranges : DisturbanceRanges, optional
        Ranges of the per-run disturbance.

    Returns
    -------
    set
        Keys ``(environment, method, run)`` of the planned runs already stored.
    """
    out = Path(out)
    table = ResultsTable(out / "runs.csv")
    if not table.path.exists():
        return set()
    rows = table.read()
    if not rows:
        return set()
    planned_envs, planned_methods = set(envs), set(methods)
    done = set()
    for row in rows:
        if row["environment"] in planned_envs and row["method"] in planned_methods and row["run"] < runs:
            if row["seed"] != base_seed:
                raise InputError("base_seed", f"the seed {row['seed']} that {table.path} was made with (or a new "
                                 "output directory)", base_seed)
            done.add((row["environment"], row["method"], row["run"]))
    record = _stored_record(out, table)
    if record.get("scorer", 1) != SCORER_VERSION:
        raise InputError(str(table.path), f"a table scored by the COLREG scorer of version {SCORER_VERSION} (this one "
                         f"was scored by version {record.get('scorer', 1)}; use a new output directory)",
                         record.get("scorer", 1))
    if record.get("fingerprint") == fingerprint(params, ranges):
        return done
    key = diff(record["params"], params)
    if key is not None:
        raise InputError(f"params.{key}", f"{record['params'].get(key)!r}, the value {table.path} was made "
                         "with (or a new output directory)", params[key])
    made = record.get("disturbance") or DisturbanceRanges().to_dict()
    for name, rng in ranges.to_dict().items():
        if made.get(name) != rng:
            raise InputError(name, f"{_range_text(made.get(name))}, what {table.path} was made with (or a new "
                             "output directory)", _range_text(rng))
    return done


def _record_study_params(out: Path, params: dict, ranges: DisturbanceRanges) -> None:
    """Write the record of a table that has no rows yet (its side file :data:`PARAMS_FILE`, atomically, before
    the first row is appended; and ``study.json``); a table with rows keeps the record it was made with."""
    table = ResultsTable(out / "runs.csv")
    if table.path.exists() and table.read():  # resumed: check_resumable accepted the record it has
        return
    record = {"fingerprint": fingerprint(params, ranges), "params": params, "disturbance": ranges.to_dict(),
              "scorer": SCORER_VERSION}
    write_json(out / PARAMS_FILE, record)
    write_json(out / "study.json", {"params": params, "disturbance": ranges.to_dict()})


def write_failures(rows, directory, *, params: dict | None = None, limit: int = MAX_FAILURE_FILES,
                   staged: StagedFiles | None = None) -> list[Path]:
    """Write the first ``limit`` failed runs (by run index) of every cell as replayable scenario TOML files.

    Files are named ``env{e}_{method}_run{r}.toml``; each holds the sampled scenario with that method and the
    study's non-default parameter values in its ``[settings]``. Every file is written atomically.

    Parameters
    ----------
    rows : list of dict
        Rows of ``runs.csv``.
    directory : str or Path
        Where to write.
    params : dict, optional
        The study's parameters.
    limit : int
        Files per (environment, method).
    staged : StagedFiles, optional
        Write the files with the other files of this set, when it is committed
        (:class:`mmg_casadi.io.StagedFiles`); by default at once.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    directory = Path(directory)
    by_cell: dict[tuple[int, str], list[dict]] = {}
    for r in rows:
        if r.get("failure"):
            by_cell.setdefault((r["environment"], r["method"]), []).append(r)
    paths = []
    overrides = _non_default(params)
    own = staged is None
    st = StagedFiles() if own else staged
    try:
        for (env, method), failed in by_cell.items():
            for r in sorted(failed, key=lambda r: r["run"])[:limit]:
                recorded = {c: r[c] for c in ENV_COLUMNS if r.get(c) is not None and r[c] == r[c]}
                sc = sampled_scenario(env, method, r["run"], r["seed"] or 0, params=_non_default({**overrides,
                                                                                                 **recorded}))
                path = directory / f"env{env}_{method}_run{r['run']}.toml"
                st.path(path).write_text(dump_scenario(sc), encoding="utf-8")
                paths.append(path)
    except BaseException:
        if own:
            st.discard()
        raise
    if own:
        st.commit()
    return paths
