"""The architecture holds: no import circle, no state index computed outside the closed loop, a method added in
its own module reaches the model (heading and speed)."""

from __future__ import annotations

import ast
import math
import re
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from mmg_casadi import errors as mc_errors
from mmg_casadi.closed_loop.problem import build_problem
from mmg_casadi.closed_loop.simulation import simulate
from mmg_casadi.guidance import methods
from mmg_casadi.scenarios.scenario import Scenario, Settings, ShipSpec
from mmg_casadi.vessel.library import load_vessel

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("mmg_casadi", "tuning", "studies")


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for f in (ROOT / pkg).rglob("*.py"):
            parts = f.relative_to(ROOT).with_suffix("").parts
            out[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = f
    return out


def _imports(name: str, path: Path, known: set[str]) -> set[str]:
    """Project modules that ``name`` imports at module level or in a function (both make a circle)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    pkg = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = pkg.split(".")[:len(pkg.split(".")) - node.level + 1]
                base = ".".join(anchor + ([base] if base else []))
            targets = [f"{base}.{a.name}" for a in node.names] + [base]
        else:
            continue
        for t in targets:
            while t and t not in known:
                t = t.rpartition(".")[0]
            if t and t != name and not name.startswith(t + "."):
                out.add(t)
    return out


def test_no_import_circle():
    mods = _modules()
    graph = {m: _imports(m, p, set(mods)) for m, p in mods.items()}
    # a package's __init__ that only has a docstring imports nothing; strongly connected components of size > 1
    index, low, stack, on, comps, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                comps.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    assert not comps, f"import circles: {comps}"


def test_the_core_package_never_imports_tuning_or_studies():
    mods = _modules()
    for m, p in mods.items():
        if m.startswith("mmg_casadi") and m != "mmg_casadi.cli":
            bad = {t for t in _imports(m, p, set(mods)) if t.split(".")[0] in ("tuning", "studies")}
            assert not bad, f"{m} imports {bad}"


_INDEX = re.compile(r"\b(NS|S_)\b|\[\s*1\s*\+\s*\w+\s*\*|xm_next\[\d|ship_state\.index|SHIP_STATE\.index")


def test_no_state_index_outside_the_closed_loop():
    offenders = []
    for m, p in _modules().items():
        if m.startswith("mmg_casadi.closed_loop"):
            continue
        for k, line in enumerate(p.read_text(encoding="utf-8").splitlines(), 1):
            code = line.split("#")[0]
            if _INDEX.search(code):
                offenders.append(f"{p.relative_to(ROOT)}:{k}: {line.strip()}")
    assert not offenders, "state indices computed outside mmg_casadi.closed_loop:\n" + "\n".join(offenders)


TOY = "toy-slow"


def _toy_builder(g: methods.GuidanceInputs) -> methods.Command:
    """30° to starboard of the present heading and half the service rpm, while anything is within R_safe."""
    turn = g.psi + math.radians(30)
    return methods.Command(ca.vertcat(ca.cos(turn), ca.sin(turn)), rpm=0.5 * g.service_rpm)


@pytest.fixture
def toy_method():
    """A method written as a user would: its builder and one registry call, nothing else touched."""
    m = methods.register(methods.Method(TOY, _toy_builder, (), "test: turn 30° to starboard and halve the rpm",
                                        commands_speed=True))
    yield m
    methods.unregister(m.name)


@pytest.mark.parametrize("n_targets", [1, 3])  # one neighbour: the builder inline; several: the gathered slots
def test_a_registered_method_commands_heading_and_speed(toy_method, n_targets):
    own = ShipSpec("own", [0.0, 0.0], 0.0, 1.0, [[80.0, 0.0]])
    targets = [ShipSpec(f"t{k}", [30.0, 6.0 * k], 180.0, 0.5, [[-40.0, 6.0 * k]], method="none")
               for k in range(n_targets)]
    pr = build_problem(Scenario(Settings(TOY), [own, *targets]), {"t_max": 40.0})
    tr = simulate(pr.layout, pr.x0, pr.p)
    rpm0, rate = pr.ships[0]["n_rpm"], pr.model.params["engine_rate_rpm_s"]
    sailing = tr.state("status", 0) == 0  # a collision ends her voyage, engine stopped (stop_on_contact)
    n = tr.state("n_prop", 0)[sailing]
    react = tr.auxiliary("reactive", 0)[sailing[:-1]] > 0.5
    k = int(np.argmax(react))
    assert react.any() and n[k] == rpm0                   # full service rpm until the method takes charge
    dt_s = pr.model.params["dt"] * load_vessel().ship.time_scale_s
    assert np.min(np.diff(n)) >= -rate * dt_s * (1 + 1e-12)  # the engine follows at its rate ...
    assert n.min() == pytest.approx(0.5 * rpm0)           # ... down to the command
    u = tr.state("u", 0)[sailing]
    assert u[-1] < 0.8 * u[0]                             # the speed command reached the model: the ship slows
    assert tr.state("psi", 0)[k + 8] > 0.2                # and it turned to starboard
    for i in range(1, 1 + n_targets):                     # a method without a speed command: rpm exactly kept
        assert np.all(tr.state("n_prop", i)[tr.state("status", i) == 0] == pr.ships[i]["n_rpm"])


def test_register_refuses_a_shipped_name():
    with pytest.raises(mc_errors.InputError, match="method.name"):
        methods.register(methods.METHODS["none"])
    with pytest.raises(mc_errors.InputError, match="method"):
        methods.unregister("none")
