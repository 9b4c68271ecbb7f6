"""Command-line interface ``mmg-casadi`` (thin: parse, validate, call the library, write results).

The only module that knows argparse, flags, the studies and the tuning. Every command that runs the closed loop
takes the same parameter options: ``--params FILE`` (a TOML file of parameters, e.g. from ``tune apf``) and
``--set NAME=VALUE`` (repeatable, wins over the file); ``mmg-casadi params`` lists them. Every command that runs or
names methods takes ``--plugin MODULE_OR_FILE.py`` (repeatable): a module that registers methods
(:mod:`mmg_casadi.guidance.plugins`), loaded before anything else, with the installed plugins (entry-point group
``mmg_casadi.methods``); their names and parameters are then accepted everywhere.

Bad input (unknown command or option, value out of range, malformed scenario or parameter file) prints one line
naming the field and the allowed values and exits with status 2; nothing is written in that case. An option the
chosen command does not use is refused the same way. A study that cannot finish (a Ray batch whose worker died
more often than Ray retries it) prints one line and exits with status 1; its finished runs are kept.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

from mmg_casadi import cli_falsify, compiled
from mmg_casadi.cli_args import _error_line
from mmg_casadi.cli_parser import (QUICK_STUDIES, STUDIES, STUDY_HELP, _PLUGIN_COMMANDS, _CliError,  # noqa: F401
                                   _path, _plugin_specs, _setting, build_parser)
from mmg_casadi.errors import InputError, RunError
from mmg_casadi.guidance import methods as registry, plugins
from mmg_casadi.io import StagedFiles, check_output, write_json, write_text
from mmg_casadi.limits import MAX_SHIPS, check_runs, check_steps
from mmg_casadi.montecarlo.disturbance_sampling import parse_range
from mmg_casadi.montecarlo.sampling import parse_envs, sample_traffic
from mmg_casadi.params import PARAMETERS, check_value, group, help_text, load_file, markdown_table
from mmg_casadi.determinism import compare_outputs
from mmg_casadi.scenarios.ais_replay import TARGETS, ais_scenario, load_ais_csv, parse_time
from mmg_casadi.scenarios.generate import generate, load_description, override, standard_description, write_set
from mmg_casadi.scenarios.interchange import convert_file
from mmg_casadi.scenarios.maritime_schema import load_traffic_situation
from mmg_casadi.scenarios.run import packaged_names, packaged_scenario, packaged_scenarios, run_scenario
from mmg_casadi.scenarios.routes import warning_line
from mmg_casadi.scenarios.scenario import dump_scenario, load_scenario, scenario_from_dict, with_method
from mmg_casadi.signals import (CLI_SIGNALS, end_deferred_signals, exit_status, is_program, settle, signal_name,
                                terminate_as_interrupt)
from mmg_casadi.vessel.library import load_vessel, vessel_table
from mmg_casadi.vessel.maneuvers import speed_change, turning_circle, validate_maneuver_args, zigzag

_FLAGS = {"base_seed": "--seed", "out_dir": "--out", "n_candidates": "--candidates", "search_seed": "--search-seed",
          "failure_weight": "--failure-weight"}
"""Library argument names whose flag is not ``--`` + the name with dashes."""




def _params_of(a) -> dict | None:
    """Parameters from ``--params`` and ``--set`` (and the waypoint-square gain flags), later ones winning."""
    out = dict(load_file(a.params)) if getattr(a, "params", None) else {}
    for key in ("ilos_delta", "ilos_k", "kp", "kd"):
        if getattr(a, key, None) is not None and getattr(a, "study", None) == "waypoint-square":
            out[key] = check_value(key, getattr(a, key), field="--" + key.replace("_", "-"), cls=InputError)
    out.update(dict(_setting(s) for s in getattr(a, "settings", [])))
    if getattr(a, "study", None) == "statistics" and a.targets is not None:
        out["targets"] = check_value("targets", a.targets, field="--targets", cls=InputError)
    if getattr(a, "study", None) == "statistics" and a.vessels is not None:
        out["target_vessels"] = check_value("target_vessels", a.vessels, field="--vessels", cls=InputError)
    for key in ("targets", "target_slowdown", "target_vessels", *group("traffic")):
        if key in out and (a.command, getattr(a, "study", None)) not in _TARGETS_APPLY:
            raise InputError(key, "nothing outside `study statistics` and `study sweep` (it sets what their "
                             "sampled target ships do)", out[key])
    return out or None


_TARGETS_APPLY = {("study", "statistics"), ("study", "sweep")}
"""Commands whose sampled scenarios read the parameters ``targets``, ``target_slowdown`` and ``target_vessels``."""


def _maneuver(a) -> dict:
    from mmg_casadi.plotting import plot_maneuver  # matplotlib: only for the figure
    validate_maneuver_args(a.kind)
    if a.to_speed is not None and a.kind != "speed":
        raise InputError("--to-speed", "only with the 'speed' manoeuvre", a.to_speed)
    if a.port and a.kind == "speed":
        raise InputError("--port", "only with the 'turning' and 'zigzag' manoeuvres", a.kind)
    v = load_vessel(a.vessel)
    hull = {"ship": v.ship, "steering": v.steering}
    if a.kind == "speed":
        to = 0.5 if a.to_speed is None else a.to_speed
        r = speed_change(to, speed=a.speed, **hull)
        name = f"speed_{a.speed:g}_to_{to:g}"
    elif a.kind == "turning":
        r = turning_circle(a.rudder, port=a.port, speed=a.speed, **hull)
        name = f"turning_{a.rudder:g}_{'port' if a.port else 'starboard'}"
    else:
        r = zigzag(a.angle, port=a.port, speed=a.speed, **hull)
        name = f"zigzag_{a.angle:g}" + ("_port" if a.port else "")
    if a.vessel != "kcs":
        r.metrics["vessel"] = v.name
    with StagedFiles() as st:  # the figure and metrics.json: both or neither, each complete
        plot_maneuver(r, st.path(a.out / f"{name}.png"))
        write_json(st.path(a.out / "metrics.json"), r.metrics)
    print(json.dumps({k: v for k, v in r.metrics.items() if not isinstance(v, dict)}, indent=1))
    return r.metrics


def _simulate(a) -> dict:
    if a.file.suffix.lower() == ".json":
        sc = load_traffic_situation(a.file)[0]
    elif not a.file.exists() and a.file.parent == Path(".") and (not a.file.suffix or (
            a.file.suffix == ".toml" and a.file.stem in packaged_names())):  # a packaged scenario, as run_scenario
        try:
            sc = packaged_scenario(a.file.stem if a.file.suffix else str(a.file))
        except InputError as e:
            raise InputError("scenario", f"a scenario file or a packaged scenario, {e.allowed}", e.got) from None
    else:
        sc = load_scenario(a.file)
    if a.method:
        sc = with_method(sc, a.method)
    from mmg_casadi.units import Units
    Units.of(a.units)  # refused before any work
    if a.animate is not None:
        from mmg_casadi.animation import check_animation_path
        check_animation_path(a.animate)
    res = run_scenario(sc, params=_params_of(a))
    for w in res.metrics["route_warnings"]:  # legs across land or within the grounding clearance: one line each
        print(f"mmg-casadi: warning: {warning_line(w)}", file=sys.stderr)
    units = Units.of(a.units, res.trajectory.layout.unit_vessel())  # the own ship's hull sets L and U
    res.save(a.out, units=units if units.si else None)
    if a.animate is not None:
        from mmg_casadi.animation import animate
        path = animate(res, a.out / a.animate, units=units)
        if not a.quiet:
            print(f"animation: {path}", file=sys.stderr)
    if not a.quiet:
        from mmg_casadi.scenarios.summary import ship_lines
        print("\n".join(ship_lines(res.metrics, units)))
    return res.metrics


def _study(a) -> dict:
    params = _params_of(a)
    if getattr(a, "runs", None) is not None:  # before any work (study paper runs the quick studies first)
        check_runs(a.runs)
    names = QUICK_STUDIES if a.study == "all" else (a.study,)
    if a.study == "all":  # one run of every quick study: a parameter of any method they run applies
        with registry.run_of((*(getattr(a, "methods", None) or registry.AVOIDING), "none"), params):
            return _studies(a, names, params)
    return _studies(a, names, params)


def _studies(a, names, params) -> dict:
    out = {}
    for n in names:
        mod = importlib.import_module(f"studies.{n.replace('-', '_')}")
        target = a.out / n if a.study == "all" else a.out
        if a.study == "all":
            print(f"study {n} -> {target}", file=sys.stderr)
        if n == "labelled":
            out[n] = mod.run(target)
            continue
        kw = {"params": params}
        if n != "waypoint-square" and getattr(a, "methods", None):
            kw["methods"] = a.methods
        if n == "statistics":
            kw.update(runs=a.runs, envs=a.envs, base_seed=a.seed, backend=a.backend, address=a.address,
                      workers=a.workers, current=a.current and parse_range(a.current, "current"),
                      wind=a.wind and parse_range(a.wind, "wind"))
        if n == "disturbance":
            kw.update(current=a.current, wind=a.wind)
        if n == "imazu":
            kw.update(targets=a.targets)
        if n == "encounters":
            kw.update(set_dir=a.set_dir, targets=a.targets)
        if n == "paper":
            kw.update(runs=a.runs, base_seed=a.seed, workers=a.workers)
        if n == "profiles":
            kw.update(runs=a.runs, envs=a.envs, base_seed=a.seed, workers=a.workers)
        if n == "hardest":
            kw.update(k=a.k, source=a.source, **cli_falsify.search_arguments(a))
        if n == "sweep":
            kw.update(param=a.param, values=a.values, baseline=a.baseline, runs=a.runs, envs=a.envs,
                      base_seed=a.seed, workers=a.workers)
        out[n] = mod.run(target, **kw)
    return out


def _explain(a) -> dict:
    from mmg_casadi.colregs.profiles import scoring_profile
    from mmg_casadi.montecarlo.explain import explain_run, write_explanation  # matplotlib only when drawing

    profile = None if a.profile is None else scoring_profile(a.profile)  # checked before any work
    ex = explain_run(a.study_dir, a.run, environment=a.env, method=a.method, profile=profile)
    write_explanation(ex, a.out)
    same = ex.reproduced
    print(f"env {ex.environment} {ex.method} run {ex.run}: " + ("verdicts reproduced" if same and all(same.values())
          else "no stored row" if not same else "VERDICTS DIFFER: " + ", ".join(c for c, ok in same.items() if not ok)),
          file=sys.stderr)
    for e in ex.encounters:
        state = "unfinished" if e.unfinished else ("kept" if e.compliant else "broken: " + ", ".join(
            r for r, v in e.rules.items() if not v.verdict))
        print(f"  {e.other_name}: {e.role}, onset t = {e.onset['t']:.1f}, CPA {e.closest['range']:.2f} L, {state}",
              file=sys.stderr)
    return ex.to_dict()


def _tune(a) -> dict:
    if a.what == "pd":
        from tuning import cli_pd  # python-control and the tuning stack: only for 'tune'
        return cli_pd.run(a.out, speed=a.speed, zeta=a.zeta, wn=a.wn, tracking_tolerance=a.tracking_tolerance,
                          vessel=a.vessel)
    if a.what in ("colregs", "search"):
        from tuning import colregs  # the tuning stack: only for 'tune'
        kw = {} if a.what == "colregs" else {"method": a.method, "box": _search_box(a.search)}
        return colregs.run(a.out, design=a.design, holdout=a.holdout, n_candidates=a.candidates, envs=a.envs,
                           params=_params_of(a), failure_weight=a.failure_weight, seed=a.seed,
                           search_seed=a.search_seed, refine=a.refine, workers=a.workers, **kw)
    from tuning import cli_apf  # the tuning stack: only for 'tune'
    try:
        envs = tuple(parse_envs(a.holdout_envs))
    except InputError as e:
        raise InputError("--holdout-envs", e.allowed, e.got) from None
    return cli_apf.run(a.out, train=a.train, holdout=a.holdout, params=_params_of(a), envs=envs,
                       target=(5,) if 5 in envs else envs[-1:], starts=a.starts, grid=a.grid,
                       max_iter=a.max_iter, workers=a.workers)


def _search_box(items) -> dict:
    """``NAME=LOW:HIGH`` items of ``--search`` as ``{name: (low, high)}`` (checked by the tuner)."""
    box = {}
    for item in items:
        name, sep, rng = item.partition("=")
        lo, sep2, hi = rng.partition(":")
        try:
            box[name.strip()] = (float(lo), float(hi))
        except ValueError:
            raise InputError("--search", "NAME=LOW:HIGH with numbers LOW < HIGH", item) from None
        if not sep or not sep2:
            raise InputError("--search", "NAME=LOW:HIGH with numbers LOW < HIGH", item)
    return box


def _convert(a) -> dict:
    out = convert_file(a.file, a.out, method=a.method, target_method=a.target_method,
                       length_scale=a.length_scale, reference=a.reference)
    for line in out.get("hulls", []):
        print(line)
    return out


def _generate(a) -> dict:
    d = standard_description() if a.description is None else load_description(a.description)
    es = generate(override(d, situations=a.situations, seed=a.seed))
    write_set(es, a.out)
    st = es.stats
    print(f"{a.out}: {len(es.situations)} situations from {d.source}; {st['accepted']}/{st['checked']} classified "
          f"situations passed the encounter check ({100 * st['acceptance_share']:.1f} %)")
    return st


def _replay(a) -> dict:
    if a.out.suffix.lower() != ".toml":
        raise InputError("--out", "a scenario file name ending in .toml", str(a.out))
    start = None if a.start is None else parse_time(a.start, "--start")
    if a.targets not in TARGETS:
        raise InputError("--targets", f"one of: {', '.join(TARGETS)}", a.targets)
    sc, report = ais_scenario(load_ais_csv(a.file), a.own, step_s=a.step, method=a.method, targets=a.targets,
                              start=start)
    write_text(a.out, dump_scenario(sc))
    gone = ", ".join(f"{k} ({v})" for k, v in report["left_out"].items())
    print(f"{a.out}: {len(sc.ships)} ships over {report['duration']:g} s" + (f"; left out: {gone}" if gone else "")
          + (f"; {report['clipped_legs']} legs clipped to the allowed speeds" if report["clipped_legs"] else ""))
    return report


def _check_determinism(a, handler) -> int:
    """Run the parsed command ``a`` a second time into a temporary folder beside ``a.out`` and compare the two
    outputs (:func:`mmg_casadi.determinism.compare_outputs`); returns the exit status (0 identical, 1 not)."""
    parent = a.out.resolve().parent
    tmp = Path(tempfile.mkdtemp(prefix=".determinism-", dir=parent if parent.is_dir() else None))
    try:
        print(f"determinism: running the command again into {tmp}", file=sys.stderr)
        handler(argparse.Namespace(**{**vars(a), "out": tmp}))
        diff, n = compare_outputs(a.out, tmp)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    if diff:
        print(f"mmg-casadi: determinism: the two runs differ: {diff}", file=sys.stderr)
        return 1
    print(f"determinism: the two runs wrote identical outputs ({n} files compared; timing columns excluded)")
    return 0


def _traffic(a) -> dict:
    if a.out.suffix.lower() != ".toml":
        raise InputError("--out", "a scenario file name ending in .toml", str(a.out))
    if not 1 <= a.ships <= MAX_SHIPS:
        raise InputError("ships", f"an integer in [1, {MAX_SHIPS}] (MAX_SHIPS)", a.ships)
    if a.seed < 0:
        raise InputError("--seed", "an integer >= 0", a.seed)
    registry.get(a.method, "--method")
    check_value("t_max", a.t_max, field="--t-max", cls=InputError)
    check_steps(a.t_max, PARAMETERS["dt"].default, cls=InputError, ships=a.ships)  # simulate would refuse it
    sc = scenario_from_dict(sample_traffic(a.ships, a.seed).to_scenario_dict(method=a.method, t_max=a.t_max))
    write_text(a.out, dump_scenario(sc))
    print(f"{a.out}: {len(sc.ships)} ships, {len(sc.obstacles)} obstacles")
    return {"ships": len(sc.ships), "obstacles": len(sc.obstacles)}


def _scenarios(a) -> list[dict]:
    rows = packaged_scenarios()
    head = {k: k for k in ("name", "ships", "obstacles", "method", "description")}
    width = {k: max(len(str(r[k])) for r in [head, *rows]) for k in head}
    for r in [head, *rows]:
        print("  ".join(str(r[k]).ljust(width[k]) for k in head).rstrip())
    return rows


def _vessels(a) -> list[dict]:
    rows = vessel_table()
    cols = {"name": "{}", "L_m": "{:g}", "B_m": "{:g}", "d_m": "{:g}", "U_design_kn": "{:.1f}",
            "rpm_design": "{:.1f}", "hull_form": "{}", "source": "{}"}
    head = {"name": "name", "L_m": "L [m]", "B_m": "B [m]", "d_m": "d [m]", "U_design_kn": "U design [kn]",
            "rpm_design": "rpm", "hull_form": "form", "source": "source"}
    cells = [head] + [{k: f.format(r[k]) for k, f in cols.items()} for r in rows]
    width = {k: max(len(c[k]) for c in cells) for k in cols}
    for c in cells:
        print("  ".join(c[k].ljust(width[k]) for k in cols).rstrip())
    return rows


def _identify(a) -> dict:
    from mmg_casadi.identify import identify_to_dir  # IPOPT: only for this command
    res = identify_to_dir(a.data, a.vessel, [n.strip() for n in a.free.split(",") if n.strip()], a.out)
    print(json.dumps(res["summary"], indent=1, ensure_ascii=False))
    for w in res["warnings"]:  # also in identification.json and the vessel file's header
        print(f"mmg-casadi: warning: identify: {w}", file=sys.stderr)
    return res


def _params(a) -> dict:
    print(markdown_table() if a.markdown else help_text())
    return {n: p.default for n, p in PARAMETERS.items()}


_FILE_OUTPUT = ("convert", "traffic", "replay")
"""Commands whose ``--out`` is a file (the others write into a directory)."""


def _check_out(a) -> None:
    """Refuse an ``--out`` that cannot be written before any work (:func:`mmg_casadi.io.check_output`)."""
    if getattr(a, "out", None) is not None:
        check_output(a.out, kind="file" if a.command in _FILE_OUTPUT else "dir", field="--out")


def _resumable(a) -> bool:
    """Whether the parsed command resumes from the files it has written when it is run again."""
    return (a is not None and (a.command, getattr(a, "study", None) or getattr(a, "what", None)) in
            {("study", "statistics"), ("study", "sweep"), ("study", "paper"), ("tune", "apf"),
             ("tune", "colregs"), ("tune", "search"), ("falsify", None), ("study", "hardest")})


def _flag(field: str, a) -> str:
    """The command-line name of a library argument the parsed command took, else ``field`` as it is."""
    if field in _FLAGS:
        return _FLAGS[field]
    dest = field.split(".")[0]
    return "--" + dest.replace("_", "-") if dest in vars(a) and dest not in ("params", "settings") else field


@contextlib.contextmanager
def _silenced(quiet: bool):
    """With ``quiet``, what the command writes on stderr (notices, progress bars, study lines) goes nowhere;
    errors are printed by :func:`main` after it."""
    if not quiet:
        yield
        return
    with open(os.devnull, "w") as null, contextlib.redirect_stderr(null):
        yield


def main(argv=None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments without the program name (default ``sys.argv[1:]``).

    Returns
    -------
    int
        0 on success, 2 for invalid input, 1 for a run error, and the signal's status after an interruption.
    """
    seen: dict = {}  # the parsed arguments, for the line of an interruption
    # SIGINT, SIGTERM, SIGHUP: the first raises (one line, 128 + signal), any more are ignored; in the program
    # they stay ignored while it exits (a late Ctrl-C must not print a traceback from the interpreter's exit)
    with terminate_as_interrupt(CLI_SIGNALS, ignore_on_exit=is_program()):
        try:
            return _main(argv, seen)
        except KeyboardInterrupt as e:  # a signal that came while the outcome was being reported: its line only
            return _interrupted(e, seen.get("a"))
        finally:
            compiled.NOTICES["stream"] = None  # the library stays silent after a command (e.g. in tests)


def _interrupted(e: BaseException, a) -> int:
    what = ("finished results are kept; rerun the same command to resume" if _resumable(a) else
            "this command does not resume: rerun it to start again")
    print(f"mmg-casadi: interrupted by {signal_name(e)} ({what})", file=sys.stderr)
    return exit_status(e)


def _main(argv, seen: dict) -> int:
    a = None
    try:
        argv = list(sys.argv[1:] if argv is None else argv)
        plugins.load_installed()
        if argv and argv[0] in _PLUGIN_COMMANDS:  # before parsing: --methods, --set and the help know them
            for spec in _plugin_specs(argv):
                plugins.load(spec)
        parser = build_parser()
        a, extra = parser.parse_known_args(argv)
        seen["a"] = a
        end_deferred_signals()  # a signal received while the package loaded (mmg_casadi/__init__.py)
        if extra:
            prog = "mmg-casadi " + " ".join(x for x in (a.command, getattr(a, "study", None),
                                                         getattr(a, "what", None)) if x)
            raise InputError(extra[0], f"an option of '{prog}' (see '{prog} --help')")
        _check_out(a)
        compiled.NOTICES["stream"] = None if a.quiet else "stderr"
        handlers = {"maneuver": _maneuver, "simulate": _simulate, "study": _study, "tune": _tune,
                    "convert": _convert, "traffic": _traffic, "generate": _generate, "replay": _replay,
                    "params": _params, "explain": _explain, "falsify": lambda a: cli_falsify.run(a, _params_of(a)),
                    "scenarios": _scenarios, "vessels": _vessels, "identify": _identify}
        with _silenced(a.quiet):
            handlers[a.command](a)
            if getattr(a, "check_determinism", False):
                status = _check_determinism(a, handlers[a.command])
                settle()
                return status
        settle()
    except _CliError as e:
        settle()
        print(_error_line(e), file=sys.stderr)
        return 2
    except InputError as e:
        settle()
        if a is not None and not isinstance(e, _CliError):
            e = InputError(_flag(e.field, a), e.allowed, e.got)
        print(_error_line(e), file=sys.stderr)
        return 2
    except RunError as e:
        settle()
        print(_error_line(e), file=sys.stderr)
        return 1
    except KeyboardInterrupt as e:
        return _interrupted(e, a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
