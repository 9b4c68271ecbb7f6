"""Argument types and option groups shared by the commands of ``mmg-casadi`` (:mod:`mmg_casadi.cli` and the command
modules beside it): one-line errors with exit status 2, numbers, paths, method lists, ``--set``, ``--params``,
``--plugin``, ``--quiet`` and ``--check-determinism``.
"""

from __future__ import annotations

import argparse
import tomllib
from pathlib import Path

from mmg_casadi.errors import InputError
from mmg_casadi.guidance import methods as registry
from mmg_casadi.params import check_value


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
