"""Property-based tests (Hypothesis) of the command line: any argv exits 0 or 2, never with a traceback.

Command lines are drawn from the parser itself (every command, study and tuning with its options and flags),
with values from a pool of good, bad, huge, non-finite, empty and random tokens, parameter settings, input
files (valid, malformed, nested too deep, missing, a directory) and output paths (new, an existing file, an
existing directory, unwritable). Properties:

* :func:`mmg_casadi.cli.main` returns 0 or 2 (``--help``: exit 0), or reaches the work (see below);
* exit 2 prints exactly one line ``mmg-casadi: error: ...`` on stderr and writes nothing at all;
* each command line takes bounded time, and the whole test bounded memory.

No simulation, compilation or study runs here: the first step of real work of every command is replaced by a
sentinel (:class:`_Work`) that ends the example. Reaching it means every input was accepted first, so the
property "refused before any work" is what is fuzzed. The default profile takes a few seconds; ``-m slow``
runs many more examples.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import resource
import shutil
import tempfile
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

import mmg_casadi.cli as cli
from mmg_casadi.guidance.methods import NAMES as METHODS
from mmg_casadi.params import PARAMETERS

DATA = Path(__file__).resolve().parents[1] / "mmg_casadi" / "data"
UNWRITABLE = "/proc/mmg-casadi-no-such-dir/out"
SECONDS_PER_COMMAND = 30.0
"""Bound on one command line (validation only; generous for a loaded 2-core machine and first imports)."""
RSS_GROWTH_BYTES = 1.5e9
"""Bound on the growth of the test process's peak memory over the whole property."""

FAST = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                        HealthCheck.function_scoped_fixture])
SLOW = settings(max_examples=1500, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                         HealthCheck.function_scoped_fixture])


class _Work(BaseException):
    """Raised where a command would start its real work (simulation, compilation, study, search)."""


def _work(*_args, **_kwargs):
    raise _Work


@pytest.fixture
def no_work(monkeypatch):
    """Replace the first step of real work of every command by :func:`_work` (validation still runs)."""
    import mmg_casadi.montecarlo.study as study
    import mmg_casadi.scenarios.run as run
    import mmg_casadi.vessel.maneuvers as maneuvers
    import tuning.cli_apf as cli_apf
    import tuning.cli_pd as cli_pd
    monkeypatch.setattr(run, "simulate", _work)  # simulate, the quick studies, imazu, disturbance
    monkeypatch.setattr(maneuvers, "compile_function", _work)  # maneuver
    monkeypatch.setattr(study, "_run_study", _work)  # statistics, sweep, paper, tune apf's held-out study
    monkeypatch.setattr(cli_apf, "training_set", _work)  # tune apf
    monkeypatch.setattr(cli_pd, "design_pd", _work)  # tune pd
    monkeypatch.setattr(cli, "generate", _work)  # generate (after its description and options are read)
    import mmg_casadi.montecarlo.explain as explain
    import studies.labelled as labelled
    import studies.profiles as profiles
    monkeypatch.setattr(labelled, "simulate_case", _work)  # study labelled
    monkeypatch.setattr(profiles, "prepare_layouts", _work)  # study profiles (after its arguments are checked)
    monkeypatch.setattr(explain, "run_batch", _work)  # explain (after the study's record is read)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Input files of every kind, in a directory of their own (absolute paths)."""
    d = tmp_path_factory.mktemp("inputs")
    shutil.copy(DATA / "scenarios" / "head_on.toml", d / "good.toml")
    shutil.copy(DATA / "traffic_situation.json", d / "good.json")
    (d / "bad.toml").write_text("[settings]\nmethod = 'bogus'\n[[ships]]\nname = 1\n")
    (d / "bad.json").write_text('{"ownShip": {"initial": {"sog": "fast"}}}')
    (d / "deep.toml").write_text("a = " + "[" * 3000 + "]" * 3000 + "\n")
    (d / "deep.json").write_text("[" * 100_000 + "]" * 100_000)
    (d / "notutf8.toml").write_bytes(b"x = '\xff'\n")
    (d / "params.toml").write_text("[params]\nr_safe = 12.0\n")
    (d / "badparams.toml").write_text("[params]\nr_safe = -1\nbogus = 2\n")
    (d / "dir.toml").mkdir()
    return d


def _commands() -> dict[tuple[str, ...], argparse.ArgumentParser]:
    """Every leaf command of the parser: ``("study", "sweep") -> its sub-parser``."""
    out = {}

    def walk(prefix, parser):
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs:
            out[prefix] = parser
            return
        for name, sub in subs[0].choices.items():
            walk(prefix + (name,), sub)

    walk((), cli.build_parser())
    return out


COMMANDS = _commands()
WORDS = ["0", "1", "-1", "2", "5", "7", "1-5", "1,3", "5,1", "9", "0-5", "0-0.1", "0.05", "0.1-0", "1e9",
         "99999999999999", "100000", "100001", "nan", "inf", "-inf", "", " ", "x", "-", "--", "true", "false",
         "none", "wide", "huang", "turning", "zigzag", "speed", "bogus", "r_safe", "vo_candidates", "vo_hold",
         "vo_cone", "dt", "t_max", "10,20", "40,80", "true,false", "10,,20", "10,10", "local", "ray", "hold",
         "avoid", "both", "kcs", "own-ship", "58.0,10.0", "91,0", "1.5", "35", "40", "0.2", "1.2", "-0",
         "\u00e9\u4e2d", "a\x00b", "1_000"]
tokens = st.one_of(st.sampled_from(WORDS), st.sampled_from(METHODS), st.just(",".join(METHODS[:2])),
                   st.integers(-10, 10**15).map(str), st.floats(allow_nan=True, allow_infinity=True).map(repr),
                   st.text(max_size=8))
settings_ = st.builds(lambda k, v: f"{k}={v}", st.sampled_from(sorted(PARAMETERS) + ["bogus", ""]), tokens)
FILES = ["good.toml", "good.json", "bad.toml", "bad.json", "deep.toml", "deep.json", "notutf8.toml", "dir.toml",
         "missing.toml", "params.toml", "badparams.toml"]
OUTS = ["out", "out/sub", "afile", "adir", "o.toml", "o.json", "adir/o.toml", UNWRITABLE, UNWRITABLE + ".toml"]


def files(inputs: Path):
    """Absolute paths of the input files (and of a missing one)."""
    return st.sampled_from(FILES).map(lambda name: str(inputs / name))


@st.composite
def command_lines(draw, inputs: Path):
    path = draw(st.sampled_from(sorted(COMMANDS)))
    parser = COMMANDS[path]
    argv = list(path)
    for action in parser._actions:
        if action.option_strings or action.dest == "help":
            continue
        if draw(st.integers(0, 9)) > 0:  # usually give the positional argument
            argv.append(draw(st.one_of(files(inputs), tokens)) if action.type is cli._path else draw(tokens))
    options = [a for a in parser._actions if a.option_strings and a.dest not in ("help", "out")]
    for action in draw(st.lists(st.sampled_from(options), max_size=4)) if options else []:
        flag = draw(st.sampled_from(action.option_strings))
        if action.nargs == 0:
            argv.append(flag)
        elif action.dest == "settings":
            argv += [flag, draw(settings_)]
        elif action.dest == "params":
            argv += [flag, draw(st.one_of(files(inputs), tokens))]
        else:
            argv += [flag, draw(tokens)]
    if draw(st.integers(0, 9)) > 0:
        argv += ["--out", draw(st.sampled_from(OUTS))]
    if draw(st.integers(0, 19)) == 0:
        argv.insert(draw(st.integers(0, len(argv))), draw(st.sampled_from(["--bogus", "-h", "extra", "--out"])))
    return argv


def _snapshot(*roots: Path) -> dict:
    return {p: (p.stat().st_size if p.is_file() else None) for r in roots for p in r.rglob("*")}


def _property(argv, inputs: Path, capsys) -> None:
    capsys.readouterr()
    before_inputs = _snapshot(inputs)
    with tempfile.TemporaryDirectory() as cwd, contextlib.chdir(cwd):
        cwd = Path(cwd)
        (cwd / "afile").write_text("keep")
        (cwd / "adir").mkdir()
        before = _snapshot(cwd)
        started = time.perf_counter()
        try:
            status = cli.main(argv)
        except _Work:
            event("reached the work")
            return
        except SystemExit as e:  # --help
            status = e.code
        finally:
            assert time.perf_counter() - started < SECONDS_PER_COMMAND, argv
        event(f"exit {status}")
        assert status in (0, 2), argv
        if status == 2:
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and err[0].startswith("mmg-casadi: error: "), (argv, err)
            assert _snapshot(cwd) == before, argv
    assert _snapshot(inputs) == before_inputs, argv


def _peak_rss() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0  # kB on Linux


@pytest.fixture
def bounded_memory():
    start = _peak_rss()
    yield
    assert _peak_rss() - start < RSS_GROWTH_BYTES


def _run(data, inputs, capsys):
    _property(data.draw(command_lines(inputs), label="argv"), inputs, capsys)


@FAST
@given(data=st.data())
def test_any_command_line_exits_0_or_2_and_writes_nothing_on_2(no_work, bounded_memory, inputs, capsys, data):
    _run(data, inputs, capsys)


def test_every_command_is_drawn():
    """The strategy covers every leaf command of the parser (so a new command is fuzzed too)."""
    assert {p[0] for p in COMMANDS} >= {"maneuver", "simulate", "study", "tune", "convert", "traffic", "params"}
    assert len([p for p in COMMANDS if p[0] == "study"]) == len(cli.STUDIES)


@pytest.mark.parametrize("argv", [
    ["simulate", "{inputs}/deep.toml", "--out", "out"], ["convert", "{inputs}/deep.toml", "--out", "o.json"],
    ["convert", "{inputs}/deep.json", "--out", "o.toml"], ["simulate", "{inputs}/good.toml", "--params",
                                                          "{inputs}/deep.toml", "--out", "out"],
    ["simulate", "{inputs}/good.toml", "--set", "r_safe=" + "[" * 3000, "--out", "out"],
    ["study", "sweep", "--param", "r_safe", "--values", "[" * 3000, "--out", "out"],
    ["convert", "{inputs}/good.json", "--out", "a\x00b.toml"], ["simulate", "a\x00b.toml", "--out", "out"],
    ["simulate", "{inputs}/good.toml", "--params", "p\x00.toml", "--out", "out"],
])
def test_pathological_inputs_are_one_line_errors(no_work, inputs, capsys, argv):
    """Examples the strategy draws rarely: nesting deeper than the parsers' recursion, a NUL in a path."""
    argv = [a.replace("{inputs}", str(inputs)) for a in argv]
    with tempfile.TemporaryDirectory() as cwd, contextlib.chdir(cwd):
        capsys.readouterr()
        assert cli.main(argv) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("mmg-casadi: error: ")
        assert os.listdir(cwd) == []


@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_any_command_line_many_examples(no_work, bounded_memory, inputs, capsys, data):
    _run(data, inputs, capsys)
