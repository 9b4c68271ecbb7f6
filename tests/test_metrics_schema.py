"""The JSON Schema of a scenario run's ``metrics.json`` (mmg_casadi/data/metrics.schema.json): it is the one the code
builds, real outputs of the CLI validate against it, and it refuses a missing key, a wrong type or an unknown key.

The default run validates the outputs of ``simulate`` (three packaged scenarios on short horizons: a head-on
encounter, a static obstacle, three ships) and of a shortened ``study colregs``; the slow test validates every
scenario ``study all`` writes.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from mmg_casadi.cli import main
from mmg_casadi.scenarios.metrics_schema import load_metrics_schema, metrics_schema, schema_text

jsonschema = pytest.importorskip("jsonschema")

ROOT = Path(__file__).resolve().parents[1]
SCHEMA_PATH = ROOT / "mmg_casadi" / "data" / "metrics.schema.json"


def validator():
    return jsonschema.Draft202012Validator(load_metrics_schema())


def scenario_metrics(out: Path) -> dict[Path, dict]:
    """Every scenario run's metrics a command wrote under ``out``: each ``metrics.json`` next to a
    ``trajectory.npz`` (waypoint-square's holds the study summary, with the scenario's metrics under ``scenario``)."""
    found = {}
    for f in sorted(out.rglob("metrics.json")):
        if (f.parent / "trajectory.npz").exists():
            data = json.loads(f.read_text(encoding="utf-8"))
            found[f] = data["scenario"] if "scenario" in data and "ships" not in data else data
    return found


def assert_valid(found: dict[Path, dict]) -> None:
    v = validator()
    bad = {str(f): [f"{list(e.absolute_path)}: {e.message[:200]}" for e in v.iter_errors(d)][:3]
           for f, d in found.items()}
    assert not any(bad.values()), {f: e for f, e in bad.items() if e}


@pytest.fixture(scope="module")
def outputs(tmp_path_factory) -> dict[Path, dict]:
    out = tmp_path_factory.mktemp("metrics")
    for name, t_max in (("head_on", 35), ("static_obstacle", 35), ("conflict", 50)):
        assert main(["simulate", name, "--set", f"t_max={t_max}", "--out", str(out / name)]) == 0
    assert main(["study", "colregs", "--methods", "modified-vortex,colregs-vortex", "--set", "t_max=40",
                 "--out", str(out / "colregs")]) == 0
    return scenario_metrics(out)


def test_packaged_schema_is_the_one_the_code_builds():
    """After a change of the format, a method, a status or a parameter, rewrite the file:
    ``python -m mmg_casadi.scenarios.metrics_schema``."""
    assert SCHEMA_PATH.read_text(encoding="utf-8") == schema_text(), \
        "mmg_casadi/data/metrics.schema.json is stale: run python -m mmg_casadi.scenarios.metrics_schema"
    jsonschema.Draft202012Validator.check_schema(metrics_schema())


def test_real_outputs_validate(outputs):
    assert len(outputs) == 3 + 3 * 2
    kinds = {p["b"].startswith("obstacle") for d in outputs.values() for p in d["pairs"]}
    applicable = {e["applicable"] for d in outputs.values() for p in d["pairs"] if "encounters" in p
                  for side in "ab" for e in p["encounters"][side]}
    assert kinds == {True, False} and applicable == {True, False}, "outputs cover ship and obstacle pairs, " \
        "applicable and non-applicable encounters"
    assert_valid(outputs)


def _first_encounter(d):
    return next(e for p in d["pairs"] if "encounters" in p for e in p["encounters"]["a"] if e["applicable"])


BREAKS = {
    "missing top-level key": lambda d: d.pop("t_end"),
    "missing ship key": lambda d: d["ships"][0].pop("status"),
    "missing parameter": lambda d: d["params"].pop("r_safe"),
    "missing encounter key": lambda d: _first_encounter(d).pop("role"),
    "missing rule": lambda d: _first_encounter(d)["rules"].pop("8"),
    "wrong type: collision": lambda d: d.__setitem__("collision", "no"),
    "wrong type: ce": lambda d: d["ships"][0].__setitem__("ce", "0.1"),
    "wrong type: parameter": lambda d: d["params"].__setitem__("neighbour_slots", 16.5),
    "wrong type: stalled_at": lambda d: d["ships"][0].__setitem__("stalled_at", [1.0]),
    "unknown status": lambda d: d["ships"][0].__setitem__("status", "arrived"),
    "unknown method": lambda d: d.__setitem__("method", "magic"),
    "unknown key": lambda d: d["ships"][0].__setitem__("colour", "red"),
    "score above 1": lambda d: _first_encounter(d).__setitem__("score", 1.5),
    "applicable without role": lambda d: _first_encounter(d).__setitem__("role", None),
    "pair without encounters": lambda d: next(p for p in d["pairs"] if "encounters" in p).pop("encounters"),
}


@pytest.mark.parametrize("name", BREAKS)
def test_schema_refuses_broken_metrics(outputs, name):
    good = next(d for f, d in outputs.items() if f.parent.name == "head_on")
    assert validator().is_valid(good)
    bad = copy.deepcopy(good)
    BREAKS[name](bad)
    assert not validator().is_valid(bad), name


@pytest.mark.slow
def test_every_scenario_of_study_all_validates(tmp_path):
    assert main(["study", "all", "--out", str(tmp_path)]) == 0
    found = scenario_metrics(tmp_path)
    studies = {f.relative_to(tmp_path).parts[0] for f in found}
    assert studies == {"waypoint-square", "static-obstacle", "colregs", "conflict", "narrow-channel"}
    assert_valid(found)
