"""The argument parser of the command line ``mmg-casadi`` (:func:`build_parser`): every command, its options and
their types; the checks of single values that argparse runs while it parses. Split from :mod:`mmg_casadi.cli`,
which runs the commands.
"""

from __future__ import annotations

import argparse

from mmg_casadi import __version__, cli_falsify
from mmg_casadi.cli_args import (  # noqa: F401  (_CliError, _methods, _setting: re-exported)
    _CliError, _Parser, _add_determinism, _add_methods, _add_params, _add_plugin, _add_quiet, _float, _int, _methods,
    _path, _setting)
from mmg_casadi.guidance import methods as registry
from mmg_casadi.params import PARAMETERS
from mmg_casadi.scenarios.ais_replay import REPLAY_METHOD

QUICK_STUDIES = ("waypoint-square", "static-obstacle", "colregs", "conflict", "narrow-channel")
STUDIES = QUICK_STUDIES + ("land", "imazu", "encounters", "disturbance", "statistics", "sweep", "labelled",
                           "profiles", "hardest", "paper", "all")
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
    "hardest": "the K hardest situations a falsification found for one method, every method run on them, paired",
    "paper": "every study of the paper and a claim-by-claim report",
    "all": "the five quick studies (what `make run` runs)",
}
"""One line per study for ``mmg-casadi study --help``."""


_PLUGIN_COMMANDS = ("simulate", "study", "falsify", "tune", "convert", "traffic", "replay", "generate", "params")
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
                           metavar="{maneuver,vessels,identify,simulate,scenarios,study,falsify,tune,convert,traffic,"
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
            sp.add_argument("--targets", default=None, help="avoid | hold | METHOD | mix:NAME=P,...: the sampled "
                            "targets use the study's method, hold, avoid with METHOD whatever the study's method, or "
                            "draw a behaviour each, e.g. mix:avoid=0.6,hold=0.3,wrong=0.1 (same as --set targets=VALUE)")
            sp.add_argument("--vessels", default=None, help="hulls of the sampled target ships: own (default, the "
                            "own ship's), a vessel name, or two separated by a comma that the targets take in turn, "
                            "e.g. kvlcc2,kcs (mixed traffic; same as --set target_vessels=VALUE)")
        if name == "profiles":
            sp.add_argument("--runs", type=_int, default=1000, help="runs (indices 0..N-1)")
            sp.add_argument("--envs", default="5", help="the environment, e.g. 5")
            sp.add_argument("--seed", type=_int, default=0, help="base seed of the scenario sampler")
            sp.add_argument("--workers", type=_int, default=None, help="local worker processes")
        if name == "hardest":
            sp.add_argument("--k", type=_int, default=20, help="size of the suite (default 20)")
            sp.add_argument("--from", dest="source", type=_path, default=None, metavar="FALSIFY_DIR",
                            help="take the situations from this output of `mmg-casadi falsify` (default: run it "
                            "for the first of --methods)")
            cli_falsify.add_search_options(sp)
        if name == "sweep":
            sp.add_argument("--param", required=True, help="the swept parameter (see `mmg-casadi params`)")
            sp.add_argument("--values", required=True, help="comma-separated values, e.g. 10,15,20,25")
            sp.add_argument("--baseline", default=None, help="value the others are paired against "
                            "(default: the parameter's default)")
            sp.add_argument("--runs", type=_int, default=200, help="runs per environment, method and value")
            sp.add_argument("--envs", default="5", help="environments, e.g. 5 or 3-5")
            sp.add_argument("--seed", type=_int, default=0, help="base seed of the scenario sampler")
            sp.add_argument("--workers", type=_int, default=None, help="local worker processes")

    cli_falsify.add_parser(sub)

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


