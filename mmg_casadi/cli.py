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
import tomllib
from pathlib import Path

from mmg_casadi import __version__
from mmg_casadi import compiled
from mmg_casadi.errors import InputError, RunError
from mmg_casadi.guidance import methods as registry, plugins
from mmg_casadi.io import check_output, write_json, write_text
from mmg_casadi.limits import MAX_SHIPS, check_runs, check_steps
from mmg_casadi.montecarlo.disturbance_sampling import parse_range
from mmg_casadi.montecarlo.sampling import parse_envs, sample_traffic
from mmg_casadi.params import PARAMETERS, check_value, help_text, load_file, markdown_table
from mmg_casadi.determinism import compare_outputs
from mmg_casadi.scenarios.ais_replay import REPLAY_METHOD, TARGETS, ais_scenario, load_ais_csv, parse_time
from mmg_casadi.scenarios.generate import generate, load_description, override, standard_description, write_set
from mmg_casadi.scenarios.interchange import convert_file
from mmg_casadi.scenarios.maritime_schema import load_traffic_situation
from mmg_casadi.scenarios.run import packaged_names, packaged_scenario, packaged_scenarios, run_scenario
from mmg_casadi.scenarios.scenario import dump_scenario, load_scenario, scenario_from_dict, with_method
from mmg_casadi.signals import end_deferred_signals, exit_status, signal_name, terminate_as_interrupt
from mmg_casadi.vessel.library import load_vessel, vessel_table
from mmg_casadi.vessel.maneuvers import speed_change, turning_circle, validate_maneuver_args, zigzag

QUICK_STUDIES = ("waypoint-square", "static-obstacle", "colregs", "conflict", "narrow-channel")
STUDIES = QUICK_STUDIES + ("land", "imazu", "encounters", "disturbance", "statistics", "sweep", "labelled",
                           "profiles", "paper", "all")
STUDY_HELP = {
    "waypoint-square": "ILOS + PD heading control around the paper's waypoint square (CE, MCTE)",
    "static-obstacle": "the paper's static obstacle: goal at 50 L and 60 L, an obstacle off the starboard bow",
    "colregs": "the paper's head-on, crossing and overtaking encounters (COLREG Rules 13-15)",
    "conflict": "the paper's three ships with conflicting responsibilities",
    "narrow-channel": "the paper's head-on encounter in a channel 10 L wide",
    "land": "the shipped land scenarios (strait, fjord with an island, channel with land banks)",
    "imazu": "the 22 Imazu problems, targets holding course and/or avoiding",
    "encounters": "an encounter set of `mmg-casadi generate`, paired by situation",
    "disturbance": "ILOS integral action and the encounters in a beam current and wind",
    "statistics": "the Monte Carlo study of the paper's environments (resumable)",
    "sweep": "one parameter swept over values, paired against a baseline (resumable)",
    "labelled": "the hand-labelled COLREG cases under every scoring profile",
    "profiles": "one method's COLREG compliance under each step from the laboratory profile to the published one",
    "paper": "every study of the paper and a claim-by-claim report",
    "all": "the five quick studies (what `make run` runs)",
}
"""One line per study for ``mmg-casadi study --help``."""
_FLAGS = {"base_seed": "--seed", "out_dir": "--out", "n_candidates": "--candidates", "search_seed": "--search-seed",
          "failure_weight": "--failure-weight"}
"""Library argument names whose flag is not ``--`` + the name with dashes."""


class _CliError(InputError):
    """An argparse error of the parser named ``field`` (``mmg-casadi simulate``)."""

    def __str__(self):
        return f"{self.allowed} (see '{self.field} --help')"


_LINE_BREAKS = {c: c.encode("unicode_escape").decode("ascii")
                for c in "\n\r\v\f\x1c\x1d\x1e\x85\u2028\u2029"}


def _error_line(e) -> str:
    """``mmg-casadi: error: …`` as one line: a line break inside a given value (e.g. a file name) is escaped."""
    return "mmg-casadi: error: " + str(e).translate(str.maketrans(_LINE_BREAKS))


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


def _path(s):
    if "\0" in s:  # the operating system takes no NUL in a path; Python raises ValueError on opening one
        raise argparse.ArgumentTypeError(f"expected a path without NUL characters, got {s!r}")
    return Path(s)


def _methods(s):
    try:
        return registry.parse_list(s, "--methods")
    except InputError as e:  # argparse reports a type error as "argument --methods: <message>"
        raise argparse.ArgumentTypeError(f"expected {e.allowed}, got {e.got!r}") from None


def _setting(s: str) -> tuple[str, object]:
    """``NAME=VALUE`` of ``--set``: VALUE read as a TOML value (bare words are strings)."""
    name, sep, text = s.partition("=")
    name = name.strip()
    if not sep or not name:
        raise InputError("--set", "NAME=VALUE with NAME a parameter (see `mmg-casadi params`)", s)
    try:
        value = tomllib.loads(f"v = {text.strip()}")["v"]
    except (tomllib.TOMLDecodeError, RecursionError):  # not a TOML value (or nested too deep): a bare word
        value = text.strip()
    return name, check_value(name, value, field=f"--set {name}", cls=InputError)


def _add_params(p: argparse.ArgumentParser) -> None:
    p.add_argument("--params", type=_path, help="TOML file of parameters (e.g. params.toml from `tune apf`); "
                   "see `mmg-casadi params`")
    p.add_argument("--set", dest="settings", action="append", default=[], metavar="NAME=VALUE",
                   help="one parameter (repeatable; wins over --params), e.g. --set r_safe=10")


def _add_quiet(p: argparse.ArgumentParser, default) -> None:
    p.add_argument("-q", "--quiet", action="store_true", default=default, help="say nothing on stderr but errors "
                   "(no compile notices, progress or summary)")


def _add_determinism(p: argparse.ArgumentParser) -> None:
    p.add_argument("--check-determinism", action="store_true", help="run a second time into a temporary folder "
                   "and compare the outputs (.csv, .json, .toml, .npz) outside the timing columns: print the "
                   "first difference and exit 1, or say they are identical")


def _add_methods(p: argparse.ArgumentParser) -> None:
    p.add_argument("--methods", type=_methods, help=f"comma-separated methods: {', '.join(registry.offered())} "
                   "(default: those the study compares)")


def _add_plugin(p: argparse.ArgumentParser) -> None:
    p.add_argument("--plugin", action="append", default=[], metavar="MODULE_OR_FILE",
                   help="a Python file or module that registers methods (repeatable; see the how-to 'Write your "
                   "own method')")


_PLUGIN_COMMANDS = ("simulate", "study", "tune", "convert", "traffic", "replay", "generate", "params")
"""Commands that take ``--plugin`` (those that run or name methods, and the parameter list)."""


def _plugin_specs(argv) -> list[str]:
    """The values of ``--plugin`` in ``argv`` (``--plugin X`` or ``--plugin=X``), in order."""
    out = []
    for k, arg in enumerate(argv):
        if arg == "--plugin" and k + 1 < len(argv):
            out.append(argv[k + 1])
        elif arg.startswith("--plugin="):
            out.append(arg.partition("=")[2])
    return out


def _add_search(tunes, what: str) -> None:
    """``tune colregs`` (colregs-vortex's thresholds) and ``tune search`` (any method's parameters, --search)."""
    helps = {"colregs": "search colregs-vortex's thresholds for safety plus COLREG compliance, judged on paired "
             "held-out runs", "search": "the same search for any method (--method) over a box of its parameters "
             "(--search NAME=LOW:HIGH, repeatable)"}
    tc = tunes.add_parser(what, help=helps[what])
    if what == "search":
        tc.add_argument("--method", required=True, help="the tuned method (a plugin's too)")
        tc.add_argument("--search", action="append", required=True, metavar="NAME=LOW:HIGH",
                        help="a numeric parameter of the method and the interval searched (repeatable)")
    tc.add_argument("--design", type=_int, default=1000, help="design runs per environment (run ids 0..N-1)")
    tc.add_argument("--holdout", type=_int, default=4000, help="held-out runs per environment (the run ids after "
                    "the design runs)")
    tc.add_argument("--candidates", type=_int, default=16, help="Latin-hypercube candidates besides the defaults")
    tc.add_argument("--envs", default="5", help="environments of the design and held-out runs, e.g. 5 or 1-5")
    tc.add_argument("--failure-weight", dest="failure_weight", type=_float, default=10.0,
                    help="objective = compliance - W x failure rate (default 10)")
    tc.add_argument("--seed", type=_int, default=0, help="base seed of the scenario sampler")
    tc.add_argument("--search-seed", dest="search_seed", type=_int, default=0, help="seed of the Latin hypercube")
    tc.add_argument("--refine", type=_int, default=1, help="coordinate sweeps around the best point after the "
                    "hypercube (each threshold moved by 1/4, then 1/8, ... of its box width; 0: none)")
    tc.add_argument("--workers", type=_int, default=None, help="local worker processes")
    _add_params(tc)
    _add_plugin(tc)
    tc.add_argument("--out", type=_path, required=True, help="output directory (rerun it to resume)")


def build_parser() -> argparse.ArgumentParser:
    """The ``mmg-casadi`` argument parser (one sub-parser per command, study and tuning).

    Returns
    -------
    argparse.ArgumentParser
        The parser, with a required sub-command.
    """
    p = _Parser(prog="mmg-casadi", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", parser_class=_Parser,
                           metavar="{maneuver,vessels,identify,simulate,scenarios,study,tune,convert,traffic,"
                                   "generate,replay,params}")
    sub.required = True
    p.add_argument("--version", action="version", version=f"mmg-casadi {__version__}")
    _add_quiet(p, False)

    m = sub.add_parser("maneuver", help="standard manoeuvres: turning circle, zig-zag, speed change")
    m.add_argument("kind", help="turning | zigzag | speed")
    m.add_argument("--rudder", type=_float, default=35.0, help="turning rudder angle [deg], (0, 35]")
    m.add_argument("--port", action="store_true", help="turning: turn to port; zigzag: first rudder to port "
                   "(default starboard)")
    m.add_argument("--angle", type=_float, default=10.0, help="zig-zag angle [deg], (0, 35]")
    m.add_argument("--speed", type=_float, default=1.0, help="approach speed / design speed, [0.2, 1.2]")
    m.add_argument("--to-speed", type=_float, default=None,
                   help="speed change: the new speed / design speed, [0.2, 1.2] (default 0.5)")
    m.add_argument("--vessel", default="kcs", help="hull: a name of `mmg-casadi vessels` or a vessel .toml file "
                   "(default kcs)")
    m.add_argument("--out", type=_path, required=True, help="output directory")

    sub.add_parser("vessels", help="list the hulls of the vessel library (particulars, design speed, source)")

    idf = sub.add_parser("identify", help="fit MMG coefficients of a vessel to a measured time series")
    idf.add_argument("data", type=_path, help="CSV with columns t, u, v, r, psi, delta, rpm (SI: s, m/s, rad/s, "
                     "rad, rad, rev/min); an integer column 'run' separates experiments")
    idf.add_argument("--vessel", default="kcs", help="base hull: a name of `mmg-casadi vessels` or a vessel .toml "
                     "file (default kcs)")
    idf.add_argument("--free", required=True, help="comma-separated coefficients to fit, e.g. Yb,Nb,Nr")
    idf.add_argument("--out", type=_path, required=True, help="output directory (vessel TOML and report)")

    s = sub.add_parser("simulate", help="run a scenario file or a packaged scenario by name")
    s.add_argument("file", type=_path, help="scenario TOML file, maritime-schema traffic situation (.json) or the "
                   "name of a packaged scenario (see `mmg-casadi scenarios`), e.g. head_on")
    s.add_argument("--method", help=f"override settings.method: {', '.join(registry.offered())}")
    _add_params(s)
    _add_plugin(s)
    s.add_argument("--out", type=_path, required=True, help="output directory")
    s.add_argument("--units", default="nd", help="units of the figure and the summary: nd (L, L/U, U; default) "
                   "or si (m, s, kn)")
    s.add_argument("--animate", nargs="?", const="animation.gif", default=None, metavar="FILE",
                   help="also write an animation into the output directory: a .gif (default animation.gif) or "
                   ".mp4 (needs the extra mmg-casadi[video])")
    _add_determinism(s)

    sub.add_parser("scenarios", help="list the packaged scenarios (name, ships, method, description)")

    ex = sub.add_parser("explain", help="re-run one run of a statistics study exactly and draw every COLREG "
                        "encounter of its own ship, rule by rule")
    ex.add_argument("study_dir", type=_path, metavar="STUDY_DIR", help="output directory of `study statistics`")
    ex.add_argument("--run", type=_int, required=True, help="the run index")
    ex.add_argument("--env", type=_int, default=None, help="its environment (only if the study has the run in "
                    "more than one cell)")
    ex.add_argument("--method", default=None, help="its method (only if the study has the run in more than one "
                    "cell)")
    ex.add_argument("--profile", default=None, help="scoring profile of the figures and explain.json (default: the "
                    "study's colregs_profile)")
    ex.add_argument("--out", type=_path, required=True, help="output directory")
    _add_plugin(ex)

    st = sub.add_parser("study", help="the paper's studies")
    studies = st.add_subparsers(dest="study", parser_class=_Parser, metavar="{" + ",".join(STUDIES) + "}")
    studies.required = True
    for name in STUDIES:
        sp = studies.add_parser(name, help=STUDY_HELP[name])
        sp.add_argument("--out", type=_path, required=True, help="output directory")
        _add_determinism(sp)
        if name == "labelled":  # scripted cases at the table's defaults, judged under every profile
            continue
        _add_params(sp)
        _add_plugin(sp)
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
        if name == "encounters":
            sp.add_argument("set_dir", type=_path, metavar="SET_DIR", help="directory of scenario files (*.toml), "
                            "e.g. written by `mmg-casadi generate`")
            sp.add_argument("--targets", default="hold", help="hold | avoid: the targets hold course and speed "
                            "(default) or avoid with the own ship's method")
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
            sp.add_argument("--targets", default=None, help="avoid | hold | METHOD: the sampled target ships avoid "
                            "with the study's method (default), hold course and speed, or avoid with METHOD whatever "
                            "the study's method (same as --set targets=VALUE)")
            sp.add_argument("--vessels", default=None, help="hulls of the sampled target ships: own (default, the "
                            "own ship's), a vessel name, or two separated by a comma that the targets take in turn, "
                            "e.g. kvlcc2,kcs (mixed traffic; same as --set target_vessels=VALUE)")
        if name == "profiles":
            sp.add_argument("--runs", type=_int, default=1000, help="runs (indices 0..N-1)")
            sp.add_argument("--envs", default="5", help="the environment, e.g. 5")
            sp.add_argument("--seed", type=_int, default=0, help="base seed of the scenario sampler")
            sp.add_argument("--workers", type=_int, default=None, help="local worker processes")
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
    tunes = t.add_subparsers(dest="what", parser_class=_Parser, metavar="{pd,apf,colregs,search}")
    tunes.required = True
    tp = tunes.add_parser("pd", help="PD heading-gain design (pole placement on the linearised model)")
    tp.add_argument("--speed", type=_float, default=1.0, help="speed / design speed, [0.2, 1.2]")
    tp.add_argument("--zeta", type=_float, default=None, help="damping ratio (default 0.8)")
    tp.add_argument("--wn", type=_float, default=None, help="natural frequency [U/L] (default: from the gear)")
    tp.add_argument("--tracking-tolerance", dest="tracking_tolerance", type=_float, default=0.0,
                    help="recommended gains may track the waypoint square this much worse (relative CE, MCTE) "
                    "than the paper's gains (default 0)")
    tp.add_argument("--vessel", default="kcs", help="hull: a name of `mmg-casadi vessels` or a vessel .toml file "
                    "(default kcs); speeds are fractions of its design speed, times in its L/U_des")
    tp.add_argument("--out", type=_path, required=True, help="output directory")
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
    _add_plugin(ta)
    ta.add_argument("--out", type=_path, required=True, help="output directory")

    for what in ("colregs", "search"):
        _add_search(tunes, what)

    c = sub.add_parser("convert", help="maritime-schema traffic situation (.json) <-> scenario file (.toml)")
    c.add_argument("file", type=_path, help="input .json (maritime-schema) or .toml (scenario)")
    c.add_argument("--out", type=_path, required=True, help="output .toml or .json")
    c.add_argument("--method", default=registry.DEFAULT, help="json->toml: the own ship's method")
    c.add_argument("--target-method", default="none", help="json->toml: the target ships' method")
    c.add_argument("--length-scale", default="kcs", help="json->toml: kcs (230 m) | own-ship")
    c.add_argument("--reference", default=None,
                   help="toml->json: LAT,LON of the scenario origin [deg] (default: from the file's header)")
    _add_plugin(c)

    tr = sub.add_parser("traffic", help="generate N ships on random crossing routes at environment 5's density")
    tr.add_argument("ships", type=int, help="number of ships (the first is the own ship)")
    tr.add_argument("--seed", type=int, default=0, help="seed of the generator")
    tr.add_argument("--method", default=registry.DEFAULT, help="every ship's method")
    tr.add_argument("--t-max", type=float, default=PARAMETERS["t_max"].default, help="horizon [L/U]")
    tr.add_argument("--out", type=_path, required=True, help="output scenario file (.toml)")
    _add_plugin(tr)

    ge = sub.add_parser("generate", help="standard encounter sets: situations with targets in requested COLREG "
                        "encounters, as scenario files and maritime-schema traffic situations")
    ge.add_argument("description", nargs="?", type=_path, default=None, help="description file (.toml); default: "
                    "the shipped standard set (110 situations, one to three targets)")
    ge.add_argument("--situations", type=_int, default=None, help="number of situations (replaces set.situations)")
    ge.add_argument("--seed", type=_int, default=None, help="seed of the set (replaces set.seed)")
    ge.add_argument("--out", type=_path, required=True, help="output directory")
    _add_plugin(ge)

    rp = sub.add_parser("replay", help="AIS tracks (.csv) as a scenario file: the targets replay their recorded "
                        "tracks, the own ship sails hers with a method from a chosen moment")
    rp.add_argument("file", type=_path, help="CSV of AIS reports with the columns mmsi, time, lat, lon (or a .json "
                    "list of report objects with these keys)")
    rp.add_argument("--own", required=True, help="MMSI of the own ship")
    rp.add_argument("--step", type=_float, default=60.0, help="resampling step of the routes [s] (default 60)")
    rp.add_argument("--method", default=REPLAY_METHOD, help=f"the own ship's method (default {REPLAY_METHOD}: a "
                    "replayed route has a waypoint every --step, and the paper's fields, whose sink sits at the next "
                    "waypoint, cannot give way so close to it)")
    rp.add_argument("--targets", default="track", help="track | route: the targets replay their recorded tracks "
                    "exactly, interpolated in time (default), or retrace their routes by waypoint tracking")
    rp.add_argument("--start", default=None, help="time at which the own ship starts from her recorded state "
                    "(seconds or ISO 8601 as in the file; default her first report)")
    rp.add_argument("--out", type=_path, required=True, help="output scenario file (.toml)")
    _add_plugin(rp)

    pp = sub.add_parser("params", help="list every parameter (default, allowed values, unit, meaning, source)")
    pp.add_argument("--markdown", action="store_true", help="as a Markdown table")
    _add_plugin(pp)
    for leaf in _leaves(p):
        _add_quiet(leaf, argparse.SUPPRESS)  # also after the command: mmg-casadi simulate ... --quiet
    return p


def _leaves(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """The parsers of every command that takes no sub-command."""
    subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not subs:
        return [parser]
    return [leaf for a in subs for sub in dict.fromkeys(a.choices.values()) for leaf in _leaves(sub)]


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
    for key in ("targets", "target_slowdown", "target_vessels"):
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
    a.out.mkdir(parents=True, exist_ok=True)
    plot_maneuver(r, a.out / f"{name}.png")
    write_json(a.out / "metrics.json", r.metrics)
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
             ("tune", "colregs"), ("tune", "search")})


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
    a = None
    try:
        with terminate_as_interrupt():
            argv = list(sys.argv[1:] if argv is None else argv)
            plugins.load_installed()
            if argv and argv[0] in _PLUGIN_COMMANDS:  # before parsing: --methods, --set and the help know them
                for spec in _plugin_specs(argv):
                    plugins.load(spec)
            parser = build_parser()
            a, extra = parser.parse_known_args(argv)
            end_deferred_signals()  # a signal received while the package loaded (mmg_casadi/__init__.py)
            if extra:
                prog = "mmg-casadi " + " ".join(x for x in (a.command, getattr(a, "study", None),
                                                             getattr(a, "what", None)) if x)
                raise InputError(extra[0], f"an option of '{prog}' (see '{prog} --help')")
            _check_out(a)
            compiled.NOTICES["stream"] = None if a.quiet else "stderr"
            handlers = {"maneuver": _maneuver, "simulate": _simulate, "study": _study, "tune": _tune,
                        "convert": _convert, "traffic": _traffic, "generate": _generate, "replay": _replay,
                        "params": _params, "explain": _explain,
                        "scenarios": _scenarios, "vessels": _vessels, "identify": _identify}
            with _silenced(a.quiet):
                handlers[a.command](a)
                if getattr(a, "check_determinism", False):
                    return _check_determinism(a, handlers[a.command])
    except _CliError as e:
        print(_error_line(e), file=sys.stderr)
        return 2
    except InputError as e:
        if a is not None and not isinstance(e, _CliError):
            e = InputError(_flag(e.field, a), e.allowed, e.got)
        print(_error_line(e), file=sys.stderr)
        return 2
    except RunError as e:
        print(_error_line(e), file=sys.stderr)
        return 1
    except KeyboardInterrupt as e:
        what = ("finished results are kept; rerun the same command to resume" if _resumable(a) else
                "this command does not resume: rerun it to start again")
        print(f"mmg-casadi: interrupted by {signal_name(e)} ({what})", file=sys.stderr)
        return exit_status(e)
    finally:
        compiled.NOTICES["stream"] = None  # the library stays silent after a command (e.g. in tests)
    return 0


if __name__ == "__main__":
    sys.exit(main())
