"""Command-line interface ``mmg-casadi`` (thin: parse, validate, call the library, write results).

Bad input (unknown command, value out of range, malformed scenario file) prints one line naming the field and
the allowed values and exits with status 2; nothing is written in that case.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .errors import InputError

STUDIES = ("waypoint-square", "static-obstacle", "colregs", "conflict", "narrow-channel", "statistics", "all")
QUICK_STUDIES = ("waypoint-square", "static-obstacle", "colregs", "conflict", "narrow-channel")


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose errors are one line and exit status 2."""

    def error(self, message):
        raise _CliError(self.prog, message)


class _CliError(InputError):
    def __str__(self):
        return f"{self.field}: {self.allowed}"


def _float(field):
    def conv(s):
        try:
            return float(s)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {s!r}") from None
    return conv


def _methods(s):
    from .closed_loop import METHODS
    out = tuple(m.strip() for m in s.split(",") if m.strip())
    for m in out:
        if m not in METHODS:
            raise InputError("--methods", f"a comma-separated list of: {', '.join(METHODS)}", m)
    return out


def write_json(path: Path, obj) -> None:
    """Write ``obj`` as JSON atomically (temporary file, then rename)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    tmp.write_text(json.dumps(obj, indent=2, default=_json_default))
    tmp.replace(path)


def _json_default(o):
    import numpy as np
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, np.bool_):
        return bool(o)
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o)}")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="mmg-casadi", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", parser_class=_Parser,
                           metavar="{maneuver,simulate,study,tune,convert}")
    sub.required = True

    m = sub.add_parser("maneuver", help="standard manoeuvres: turning circle, zig-zag")
    m.add_argument("kind", help="turning | zigzag")
    m.add_argument("--rudder", type=_float("--rudder"), default=35.0, help="turning rudder angle [deg], (0, 35]")
    m.add_argument("--port", action="store_true", help="turn to port (default starboard)")
    m.add_argument("--angle", type=_float("--angle"), default=10.0, help="zig-zag angle [deg], (0, 35]")
    m.add_argument("--speed", type=_float("--speed"), default=1.0, help="approach speed / design speed, [0.2, 1.2]")
    m.add_argument("--out", type=Path, required=True, help="output directory")

    s = sub.add_parser("simulate", help="run a scenario file")
    s.add_argument("file", type=Path, help="scenario TOML file or maritime-schema traffic situation (.json)")
    s.add_argument("--method", help="override settings.method")
    s.add_argument("--params", type=Path, help="TOML file of field parameters (e.g. from `tune apf`)")
    s.add_argument("--out", type=Path, required=True)

    st = sub.add_parser("study", help="the paper's studies")
    st.add_argument("name", help=" | ".join(STUDIES))
    st.add_argument("--out", type=Path, required=True)
    st.add_argument("--params", type=Path, help="TOML file of field parameters (e.g. from `tune apf`)")
    st.add_argument("--methods", type=_methods, help="comma-separated methods (default: all the study compares)")
    st.add_argument("--runs", type=int, default=200, help="statistics: runs per environment and method")
    st.add_argument("--envs", default="1-5", help="statistics: environments, e.g. 1-5 or 1,3")
    st.add_argument("--seed", type=int, default=0, help="statistics: base seed")
    st.add_argument("--backend", default="local", help="statistics: local | ray")
    st.add_argument("--address", default=None, help="statistics: Ray cluster address")
    st.add_argument("--workers", type=int, default=None, help="statistics: local worker processes")
    st.add_argument("--ilos-delta", type=_float("--ilos-delta"), default=None, help="waypoint-square: Δ [L]")
    st.add_argument("--ilos-k", type=_float("--ilos-k"), default=None, help="waypoint-square: k")
    st.add_argument("--kp", type=_float("--kp"), default=None, help="waypoint-square: PD K_p")
    st.add_argument("--kd", type=_float("--kd"), default=None, help="waypoint-square: PD K_d")

    t = sub.add_parser("tune", help="controller and field tuning")
    t.add_argument("what", help="pd | apf")
    t.add_argument("--speed", type=_float("--speed"), default=1.0)
    t.add_argument("--zeta", type=_float("--zeta"), default=None)
    t.add_argument("--wn", type=_float("--wn"), default=None)
    t.add_argument("--train", type=int, default=8)
    t.add_argument("--holdout", type=int, default=40)
    t.add_argument("--out", type=Path, required=True)

    c = sub.add_parser("convert", help="maritime-schema traffic situation (.json) <-> scenario file (.toml)")
    c.add_argument("file", type=Path, help="input .json (maritime-schema) or .toml (scenario)")
    c.add_argument("--out", type=Path, required=True, help="output .toml or .json")
    c.add_argument("--method", default="modified-vortex", help="json->toml: the own ship's method")
    c.add_argument("--target-method", default="none", help="json->toml: the target ships' method")
    c.add_argument("--length-scale", default="kcs", help="json->toml: kcs (230 m) | own-ship")
    c.add_argument("--reference", default=None,
                   help="toml->json: LAT,LON of the scenario origin [deg] (default: from the file's header)")
    return p


def _maneuver(a) -> dict:
    from .maneuvers import turning_circle, validate_maneuver_args, zigzag
    from .plotting import plot_maneuver
    validate_maneuver_args(a.kind)
    if a.kind == "turning":
        r = turning_circle(a.rudder, port=a.port, speed=a.speed)
        name = f"turning_{a.rudder:g}_{'port' if a.port else 'starboard'}"
    else:
        r = zigzag(a.angle, speed=a.speed)
        name = f"zigzag_{a.angle:g}"
    a.out.mkdir(parents=True, exist_ok=True)
    plot_maneuver(r, a.out / f"{name}.png")
    write_json(a.out / "metrics.json", r.metrics)
    return r.metrics


def _simulate(a) -> dict:
    from .scenario import load_scenario, with_method
    from .scenario_run import load_params_file, run_scenario, write_outputs
    if a.file.suffix.lower() == ".json":
        from .interchange import load_traffic_situation
        sc = load_traffic_situation(a.file)[0]
    else:
        sc = load_scenario(a.file)
    if a.method:
        sc = with_method(sc, a.method)
    params = load_params_file(a.params) if a.params else None
    res = run_scenario(sc, params=params)
    write_outputs(res, a.out)
    return res.metrics


def _study(a) -> dict:
    import importlib
    if a.name not in STUDIES:
        raise InputError("study", f"one of: {', '.join(STUDIES)}", a.name)
    names = QUICK_STUDIES if a.name == "all" else (a.name,)
    out = {}
    for n in names:
        mod = importlib.import_module(f"studies.{n.replace('-', '_')}")
        target = a.out / n if a.name == "all" else a.out
        if a.name == "all":
            print(f"study {n} -> {target}", file=sys.stderr)
        out[n] = mod.run(a, target)
    return out


def _tune(a) -> dict:
    import importlib
    if a.what not in ("pd", "apf"):
        raise InputError("tune", "one of: pd, apf", a.what)
    return importlib.import_module(f"tuning.cli_{a.what}").run(a)


def _convert(a) -> dict:
    from .interchange import convert_file
    return convert_file(a.file, a.out, method=a.method, target_method=a.target_method,
                        length_scale=a.length_scale, reference=a.reference)


def main(argv=None) -> int:
    from .signals import exit_status, signal_name, terminate_as_interrupt
    try:
        with terminate_as_interrupt():
            a = build_parser().parse_args(argv)
            result = {"maneuver": _maneuver, "simulate": _simulate, "study": _study, "tune": _tune,
                      "convert": _convert}[a.command](a)
    except InputError as e:
        print(f"mmg-casadi: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt as e:
        print(f"mmg-casadi: interrupted by {signal_name(e)} (finished results are kept; rerun the same command "
              "to resume)", file=sys.stderr)
        return exit_status(e)
    if isinstance(result, dict) and a.command == "maneuver":
        print(json.dumps({k: v for k, v in result.items() if not isinstance(v, dict)}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
