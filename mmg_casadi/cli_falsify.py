"""``mmg-casadi falsify``: the command that searches an environment's envelope for the traffic that breaks a method
(:mod:`mmg_casadi.falsify`), and the options of ``mmg-casadi study hardest``.
"""

from __future__ import annotations

import sys

from mmg_casadi.cli_args import _add_params, _add_plugin, _int, _path
from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods as registry
from mmg_casadi.limits import MAX_RUNS
from mmg_casadi.montecarlo.disturbance_sampling import DisturbanceRanges, parse_range
from mmg_casadi.montecarlo.sampling import ALL_ENVIRONMENTS

HELP = "search an environment's sampling envelope for the traffic that breaks a method (gradient, CMA-ES, random)"
"""The command's line in ``mmg-casadi --help``."""


def add_parser(sub) -> None:
    """Add ``falsify`` to the sub-parsers ``sub`` of ``mmg-casadi``.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The commands of the main parser.
    """
    f = sub.add_parser("falsify", help=HELP)
    f.add_argument("--method", required=True, help="the method every ship sails (as in the study)")
    add_search_options(f)
    f.add_argument("--figures", default="all", help="all | distinct | none: a figure for every failure "
                   "(default), for the least robust of each distinct one, or none")
    _add_params(f)
    _add_plugin(f)
    f.add_argument("--out", type=_path, required=True, help="output directory (each search is kept there every 100 "
                   "simulations and when interrupted: rerun the same command to resume)")


def add_search_options(p) -> None:
    """The options of a falsification (``falsify`` and ``study hardest``).

    Parameters
    ----------
    p : argparse.ArgumentParser
        The command's parser.
    """
    p.add_argument("--env", type=_int, default=5, help="the environment whose sampling envelope is searched "
                   "(1-6; default 5)")
    p.add_argument("--budget", type=_int, default=2000, help="simulations per search (default 2000)")
    p.add_argument("--objective", default="collision", help="collision | colregs | grounding: the least margin to "
                   "any ship, obstacle or land; the least COLREG rule score; the least margin to land (env 6)")
    p.add_argument("--search", default="gradient,cmaes,random", help="comma-separated searches: gradient, cmaes, "
                   "random (default all three, at the same budget)")
    p.add_argument("--seed", type=_int, default=0, help="base seed of the random sample and of CMA-ES")
    p.add_argument("--current", default=None, metavar="LO-HI", help="also search the current's speed in this range "
                   "(fraction of design speed) and its direction")
    p.add_argument("--wind", default=None, metavar="LO-HI", help="also search the true wind's speed in this range "
                   "(m/s) and its direction")


def search_arguments(a) -> dict:
    """The keyword arguments of :func:`~mmg_casadi.falsify.falsifier.falsify` from parsed options, checked before
    any work.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed options (:func:`add_search_options`).

    Returns
    -------
    dict
        ``environment``, ``budget``, ``objective``, ``searches``, ``seed`` and ``disturbance``.
    """
    from mmg_casadi.falsify.robustness import check_objective
    from mmg_casadi.falsify.search import SEARCHES

    if a.env not in ALL_ENVIRONMENTS:
        raise InputError("--env", "an environment number in 1-6", a.env)
    if not 1 <= a.budget <= MAX_RUNS:
        raise InputError("--budget", f"an integer in [1, {MAX_RUNS}]", a.budget)
    if a.seed < 0:
        raise InputError("--seed", "an integer >= 0", a.seed)
    try:
        check_objective(a.objective, a.env)
    except InputError as e:
        raise InputError("--objective", e.allowed, e.got) from None
    searches = tuple(s.strip() for s in a.search.split(","))
    if not searches or any(s not in SEARCHES for s in searches) or len(set(searches)) != len(searches):
        raise InputError("--search", f"distinct names among: {', '.join(SEARCHES)}", a.search)
    if "gradient" in searches and a.objective == "colregs":
        raise InputError("--search", "cmaes and/or random with --objective colregs (the COLREG scorer has no "
                         "derivative)", a.search)
    current = a.current and parse_range(a.current, "current")
    wind = a.wind and parse_range(a.wind, "wind")
    dist = DisturbanceRanges(current=current or None, wind=wind or None) if (current or wind) else None
    return {"environment": a.env, "budget": a.budget, "objective": a.objective, "searches": searches,
            "seed": a.seed, "disturbance": dist}


def run(a, params: dict | None) -> dict:
    """``mmg-casadi falsify``: run the searches, write the outputs, print one line per search.

    Parameters
    ----------
    a : argparse.Namespace
        Parsed options.
    params : dict or None
        The parameter overrides of ``--params`` and ``--set``.

    Returns
    -------
    dict
        The summary written to ``summary.json``.
    """
    from mmg_casadi.falsify.falsifier import FIGURES, falsify

    registry.get(a.method, "--method")
    if a.figures not in FIGURES:
        raise InputError("--figures", f"one of: {', '.join(FIGURES)}", a.figures)
    kw = search_arguments(a)

    def say(line):
        print(line, file=sys.stderr, flush=True)

    with registry.run_of([a.method], params):
        f = falsify(a.method, params=params, report=say, checkpoint=a.out, **kw)
        summary = f.save(a.out, figures=a.figures)
    for s, r in summary["searches"].items():
        print(f"{a.method} env {a.env} {s}: {r['simulations']} simulations, {r['failures']} failures, "
              f"{r['distinct']} distinct, least robustness {r['least_robustness']:.3f}")
    print(f"most distinct failures: {summary['best']}; {summary['reproduced']} of {summary['failures_written']} "
          f"failures reproduced by simulate; outputs in {a.out}")
    return summary
