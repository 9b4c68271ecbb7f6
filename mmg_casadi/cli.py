"""Command-line interface ``mmg-casadi`` (thin: parse, validate, call the library, write results).

The only module that knows argparse, flags, the studies and the tuning. Every command that runs the closed loop
takes the same parameter options: ``--params FILE`` (a TOML file of parameters, e.g. from ``tune apf``) and
``--set NAME=VALUE`` (repeatable, wins over the file); ``mmg-casadi params`` lists them.

Bad input (unknown command or option, value out of range, malformed scenario or parameter file) prints one line
naming the field and the allowed values and exits with status 2; nothing is written in that case. An option the
chosen command does not use is refused the same way.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import tomllib
from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods as registry
from mmg_casadi.io import write_json, write_text
from mmg_casadi.limits import MAX_SHIPS, check_runs
from mmg_casadi.montecarlo.disturbance_sampling import parse_range
from mmg_casadi.montecarlo.sampling import parse_envs, sample_traffic
from mmg_casadi.params import PARAMETERS, check_value, help_text, load_file, markdown_table
from mmg_casadi.scenarios.interchange import convert_file
from mmg_casadi.scenarios.maritime_schema import load_traffic_situation
from mmg_casadi.scenarios.run import run_scenario
from mmg_casadi.scenarios.scenario import dump_scenario, load_scenario, scenario_from_dict, with_method
from mmg_casadi.signals import exit_status, signal_name, terminate_as_interrupt
from mmg_casadi.vessel.maneuvers import speed_change, turning_circle, validate_maneuver_args, zigzag

QUICK_STUDIES = ("waypoint-square", "static-obstacle", "colregs", "conflict", "narrow-channel")
STUDIES = QUICK_STUDIES + ("imazu", "disturbance", "statistics", "sweep", "paper", "all")
_FLAGS = {"base_seed": "--seed", "out_dir": "--out"}
"""Library argument names whose flag is not ``--`` + the name with dashes."""


class _CliError(InputError):
    def __str__(self):
        return f"{self.field}: {self.allowed}"


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line and exit status 2."""

    def error(self, message):
        raise _CliError(self.prog, message)


def _float(s):
    try:
        return float(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {s!r}") from None


def _int(s):
    try:
        return int(s)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {s!r}") from None


def _methods(s):
    return registry.parse_list(s, "--methods")


def _setting(s: str) -> tuple[str, object]:
    """``NAME=VALUE`` of ``--set``: VALUE read as a TOML value (bare words are strings)."""
    name, sep, text = s.partition("=")
    name = name.strip()
    if not sep or not name:
        raise InputError("--set", "NAME=VALUE with NAME a parameter (see `mmg-casadi params`)", s)
    try:
        value = tomllib.loads(f"v = {text.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = text.strip()
    return name, check_value(name, value, field=f"--set {name}", cls=InputError)


def _add_params(p: argparse.ArgumentParser) -> None:
    p.add_argument("--params", type=Path, help="TOML file of parameters (e.g. params.toml from `tune apf`); "
                   "see `mmg-casadi params`")
    p.add_argument("--set", dest="settings", action="append", default=[], metavar="NAME=VALUE",
                   help="one parameter (repeatable; wins over --params), e.g. --set r_safe=10")


def _add_methods(p: argparse.ArgumentParser) -> None:
    p.add_argument("--methods", type=_methods, help=f"comma-separated methods: {', '.join(registry.NAMES)} "
                   "(default: those the study compares)")


def build_parser() -> argparse.ArgumentParser:
    """The ``mmg-casadi`` argument parser (one sub-parser per command, study and tuning)."""
    p = _Parser(prog="mmg-casadi", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", parser_class=_Parser,
                           metavar="{maneuver,simulate,study,tune,convert,traffic,params}")
    sub.required = True

    m = sub.add_parser("maneuver", help="standard manoeuvres: turning circle, zig-zag, speed change")
    m.add_argument("kind", help="turning | zigzag | speed")
    m.add_argument("--rudder", type=_float, default=35.0, help="turning rudder angle [deg], (0, 35]")
    m.add_argument("--port", action="store_true", help="turn to port (default starboard)")
    m.add_argument("--angle", type=_float, default=10.0, help="zig-zag angle [deg], (0, 35]")
    m.add_argument("--speed", type=_float, default=1.0, help="approach speed / design speed, [0.2, 1.2]")
    m.add_argument("--to-speed", type=_float, default=None,
                   help="speed change: the new speed / design speed, [0.2, 1.2] (default 0.5)")
    m.add_argument("--out", type=Path, required=True, help="output directory")

    s = sub.add_parser("simulate", help="run a scenario file")
    s.add_argument("file", type=Path, help="scenario TOML file or maritime-schema traffic situation (.json)")
    s.add_argument("--method", help=f"override settings.method: {', '.join(registry.NAMES)}")
    _add_params(s)
    s.add_argument("--out", type=Path, required=True, help="output directory")

    st = sub.add_parser("study", help="the paper's studies")
    studies = st.add_subparsers(dest="study", parser_class=_Parser, metavar="{" + ",".join(STUDIES) + "}")
    studies.required = True
    for name in STUDIES:
        sp = studies.add_parser(name, help={"all": "every quick study", "paper": "every study of the paper and "
                                            "a claim-by-claim report"}.get(name, f"the {name} study"))
        sp.add_argument("--out", type=Path, required=True, help="output directory")
        _add_params(sp)
        if name not in ("waypoint-square", "all", "paper"):
            _add_methods(sp)
        if name == "paper":
            sp.add_argument("--runs", type=_int, default=5000, help="runs per environment and method of the "
                            "statistical analysis (the paper: 5000)")
            sp.add_argument("--seed", type=_int, default=0, help="base seed of the scenario sampler")
            sp.add_argument("--workers", type=_int, default=None, help="local worker processes")
        if name == "waypoint-square":
            for flag, key in (("--ilos-delta", "ilos_delta"), ("--ilos-k", "ilos_k"), ("--kp", "kp"),
                              ("--kd", "kd")):
                sp.add_argument(flag, type=_float, dest=key, help=f"same as --set {key}=VALUE")
        if name == "imazu":
            sp.add_argument("--targets", default="both", help="hold | avoid | both: the targets hold course and "
                            "speed, avoid with the own ship's method, or both in turn")
        if name == "disturbance":
            sp.add_argument("--current", type=_float, default=0.1, help="beam current speed (fraction of design "
                            "speed), default 0.1")
            sp.add_argument("--wind", type=_float, default=15.0, help="beam true wind speed (m/s), default 15")
        if name == "statistics":
            sp.add_argument("--runs", type=_int, default=200, help="runs per environment and method")
            sp.add_argument("--envs", default="1-5", help="environments, e.g. 1-5 or 1,3")
            sp.add_argument("--seed", type=_int, default=0, help="base seed of the scenario sampler")
            sp.add_argument("--backend", default="local", help="local | ray")
            sp.add_argument("--address", default=None, help="Ray cluster address (with --backend ray)")
            sp.add_argument("--workers", type=_int, default=None, help="local worker processes / Ray CPUs")
            sp.add_argument("--current", default=None, metavar="LO-HI", help="per-run current speed range "
                            "(fraction of design speed, direction uniform), e.g. 0-0.1")
            sp.add_argument("--wind", default=None, metavar="LO-HI", help="per-run true wind speed range (m/s, "
                            "direction uniform), e.g. 0-15")
        if name == "sweep":
            sp.add_argument("--param", required=True, help="the swept parameter (see `mmg-casadi params`)")
            sp.add_argument("--values", required=True, help="comma-separated values, e.g. 10,15,20,25")
            sp.add_argument("--baseline", default=None, help="value the others are paired against "
                            "(default: the parameter's default)")
            sp.add_argument("--runs", type=_int, default=200, help="runs per environment, method and value")
            sp.add_argument("--envs", default="5", help="environments, e.g. 5 or 3-5")
            sp.add_argument("--seed", type=_int, default=0, help="base seed of the scenario sampler")
            sp.add_argument("--workers", type=_int, default=None, help="local worker processes")

    t = sub.add_parser("tune", help="controller and field tuning")
    tunes = t.add_subparsers(dest="what", parser_class=_Parser, metavar="{pd,apf}")
    tunes.required = True
    tp = tunes.add_parser("pd", help="PD heading-gain design (pole placement on the linearised model)")
    tp.add_argument("--speed", type=_float, default=1.0, help="speed / design speed, [0.2, 1.2]")
    tp.add_argument("--zeta", type=_float, default=None, help="damping ratio (default 0.8)")
    tp.add_argument("--wn", type=_float, default=None, help="natural frequency [U/L] (default: from the gear)")
    tp.add_argument("--tracking-tolerance", dest="tracking_tolerance", type=_float, default=0.0,
                    help="recommended gains may track the waypoint square this much worse (relative CE, MCTE) "
                    "than the paper's gains (default 0)")
    tp.add_argument("--out", type=Path, required=True, help="output directory")
    ta = tunes.add_parser("apf", help="gradient-based tuning of the modified sink-vortex field")
    ta.add_argument("--train", type=_int, default=195, help="sampled training scenarios, environments 3-5 "
                    "(plus the paper's five)")
    ta.add_argument("--holdout", type=_int, default=2000, help="held-out runs per environment and parameter set")
    ta.add_argument("--holdout-envs", dest="holdout_envs", default="1-5", help="environments of the held-out study")
    ta.add_argument("--starts", type=_int, default=1, help="L-BFGS-B starts from the best grid points")
    ta.add_argument("--grid", type=_int, default=3, help="coarse grid points per tuned parameter")
    ta.add_argument("--max-iter", dest="max_iter", type=_int, default=8, help="L-BFGS-B iterations per start")
    ta.add_argument("--workers", type=_int, default=None, help="worker processes of the held-out study")
    _add_params(ta)
    ta.add_argument("--out", type=Path, required=True, help="output directory")

    c = sub.add_parser("convert", help="maritime-schema traffic situation (.json) <-> scenario file (.toml)")
    c.add_argument("file", type=Path, help="input .json (maritime-schema) or .toml (scenario)")
    c.add_argument("--out", type=Path, required=True, help="output .toml or .json")
    c.add_argument("--method", default=registry.DEFAULT, help="json->toml: the own ship's method")
    c.add_argument("--target-method", default="none", help="json->toml: the target ships' method")
    c.add_argument("--length-scale", default="kcs", help="json->toml: kcs (230 m) | own-ship")
    c.add_argument("--reference", default=None,
                   help="toml->json: LAT,LON of the scenario origin [deg] (default: from the file's header)")

    tr = sub.add_parser("traffic", help="generate N ships on random crossing routes at environment 5's density")
    tr.add_argument("ships", type=int, help="number of ships (the first is the own ship)")
    tr.add_argument("--seed", type=int, default=0, help="seed of the generator")
    tr.add_argument("--method", default=registry.DEFAULT, help="every ship's method")
    tr.add_argument("--t-max", type=float, default=PARAMETERS["t_max"].default, help="horizon [L/U]")
    tr.add_argument("--out", type=Path, required=True, help="output scenario file (.toml)")

    pp = sub.add_parser("params", help="list every parameter (default, allowed values, unit, meaning, source)")
    pp.add_argument("--markdown", action="store_true", help="as a Markdown table")
    return p


def _params_of(a) -> dict | None:
    """Parameters from ``--params`` and ``--set`` (and the waypoint-square gain flags), later ones winning."""
    out = dict(load_file(a.params)) if getattr(a, "params", None) else {}
    for key in ("ilos_delta", "ilos_k", "kp", "kd"):
        if getattr(a, key, None) is not None and getattr(a, "study", None) == "waypoint-square":
            out[key] = check_value(key, getattr(a, key), field="--" + key.replace("_", "-"), cls=InputError)
    out.update(dict(_setting(s) for s in getattr(a, "settings", [])))
    return out or None


def _maneuver(a) -> dict:
    from mmg_casadi.plotting import plot_maneuver  # matplotlib: only for the figure
    validate_maneuver_args(a.kind)
    if a.to_speed is not None and a.kind != "speed":
        raise InputError("--to-speed", "only with the 'speed' manoeuvre", a.to_speed)
    if a.kind == "speed":
        to = 0.5 if a.to_speed is None else a.to_speed
        r = speed_change(to, speed=a.speed)
        name = f"speed_{a.speed:g}_to_{to:g}"
    elif a.kind == "turning":
        r = turning_circle(a.rudder, port=a.port, speed=a.speed)
        name = f"turning_{a.rudder:g}_{'port' if a.port else 'starboard'}"
    else:
        r = zigzag(a.angle, speed=a.speed)
        name = f"zigzag_{a.angle:g}"
    a.out.mkdir(parents=True, exist_ok=True)
    plot_maneuver(r, a.out / f"{name}.png")
    write_json(a.out / "metrics.json", r.metrics)
    print(json.dumps({k: v for k, v in r.metrics.items() if not isinstance(v, dict)}, indent=1))
    return r.metrics


def _simulate(a) -> dict:
    if a.file.suffix.lower() == ".json":
        sc = load_traffic_situation(a.file)[0]
    else:
        sc = load_scenario(a.file)
    if a.method:
        sc = with_method(sc, a.method)
    res = run_scenario(sc, params=_params_of(a))
    res.save(a.out)
    return res.metrics


def _study(a) -> dict:
    params = _params_of(a)
    if getattr(a, "runs", None) is not None:  # before any work (study paper runs the quick studies first)
        check_runs(a.runs)
    names = QUICK_STUDIES if a.study == "all" else (a.study,)
    out = {}
    for n in names:
        mod = importlib.import_module(f"studies.{n.replace('-', '_')}")
        target = a.out / n if a.study == "all" else a.out
        if a.study == "all":
            print(f"study {n} -> {target}", file=sys.stderr)
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
        if n == "paper":
            kw.update(runs=a.runs, base_seed=a.seed, workers=a.workers)
        if n == "sweep":
            kw.update(param=a.param, values=a.values, baseline=a.baseline, runs=a.runs, envs=a.envs,
                      base_seed=a.seed, workers=a.workers)
        out[n] = mod.run(target, **kw)
    return out


def _tune(a) -> dict:
    if a.what == "pd":
        from tuning import cli_pd  # python-control and the tuning stack: only for 'tune'
        return cli_pd.run(a.out, speed=a.speed, zeta=a.zeta, wn=a.wn, tracking_tolerance=a.tracking_tolerance)
    from tuning import cli_apf  # the tuning stack: only for 'tune'
    envs = tuple(parse_envs(a.holdout_envs))
    return cli_apf.run(a.out, train=a.train, holdout=a.holdout, params=_params_of(a), envs=envs,
                       target=(5,) if 5 in envs else envs[-1:], starts=a.starts, grid=a.grid,
                       max_iter=a.max_iter, workers=a.workers)


def _convert(a) -> dict:
    return convert_file(a.file, a.out, method=a.method, target_method=a.target_method,
                        length_scale=a.length_scale, reference=a.reference)


def _traffic(a) -> dict:
    if a.out.suffix.lower() != ".toml":
        raise InputError("--out", "a scenario file name ending in .toml", str(a.out))
    if a.ships > MAX_SHIPS:
        raise InputError("ships", f"an integer in [1, {MAX_SHIPS}] (MAX_SHIPS)", a.ships)
    registry.get(a.method, "--method")
    check_value("t_max", a.t_max, field="--t-max", cls=InputError)
    sc = scenario_from_dict(sample_traffic(a.ships, a.seed).to_scenario_dict(method=a.method, t_max=a.t_max))
    write_text(a.out, dump_scenario(sc))
    print(f"{a.out}: {len(sc.ships)} ships, {len(sc.obstacles)} obstacles")
    return {"ships": len(sc.ships), "obstacles": len(sc.obstacles)}


def _params(a) -> dict:
    print(markdown_table() if a.markdown else help_text())
    return {n: p.default for n, p in PARAMETERS.items()}


def _flag(field: str, a) -> str:
    """The command-line name of a library argument the parsed command took, else ``field`` as it is."""
    if field in _FLAGS:
        return _FLAGS[field]
    dest = field.split(".")[0]
    return "--" + dest.replace("_", "-") if dest in vars(a) and dest not in ("params", "settings") else field


def main(argv=None) -> int:
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit status.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments without the program name (default ``sys.argv[1:]``).
    """
    parser = build_parser()
    a = None
    try:
        with terminate_as_interrupt():
            a, extra = parser.parse_known_args(argv)
            if extra:
                prog = "mmg-casadi " + " ".join(x for x in (a.command, getattr(a, "study", None),
                                                             getattr(a, "what", None)) if x)
                raise InputError(extra[0], f"an option of '{prog}' (see '{prog} --help')")
            handlers = {"maneuver": _maneuver, "simulate": _simulate, "study": _study, "tune": _tune,
                        "convert": _convert, "traffic": _traffic, "params": _params}
            handlers[a.command](a)
    except _CliError as e:
        print(f"mmg-casadi: error: {e}", file=sys.stderr)
        return 2
    except InputError as e:
        if a is not None and not isinstance(e, _CliError):
            e = InputError(_flag(e.field, a), e.allowed, e.got)
        print(f"mmg-casadi: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as e:
        print(f"mmg-casadi: interrupted by {signal_name(e)} (finished results are kept; rerun the same command "
              "to resume)", file=sys.stderr)
        return exit_status(e)
    return 0


if __name__ == "__main__":
    sys.exit(main())
