"""A method's thresholds are its own: no method parameter defaults to a number of the COLREG scorer's profiles.

The scorer (:mod:`mmg_casadi.colregs`) grades a method; a method built from the grader's numbers would be graded on
its homework. Three checks: every method parameter's default in the parameter table is a literal, no guidance
module imports the scorer, and changing every profile's numbers before the table is built leaves every default as
it was.
"""

import ast
import json
import subprocess
import sys
from pathlib import Path

import mmg_casadi
from mmg_casadi.params import GROUPS, PARAMETERS

PACKAGE = Path(mmg_casadi.__file__).parent
METHOD_GROUPS = {g for g in GROUPS if g not in ("simulation", "vessel", "outcome", "environment")}


def _param_calls(tree):
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and getattr(node.func, "id", None) == "_P" and node.args:
            yield node


def test_every_method_parameter_default_is_a_literal():
    tree = ast.parse((PACKAGE / "params.py").read_text(encoding="utf-8"))
    seen = 0
    for call in _param_calls(tree):
        name = call.args[0].value
        if PARAMETERS[name].group in METHOD_GROUPS:
            default = call.args[1]
            if isinstance(default, ast.UnaryOp):  # a negative number
                default = default.operand
            assert isinstance(default, ast.Constant), f"{name}: default is not a literal"
            seen += 1
    assert seen >= 30 and any(n.startswith("cv_") for n in PARAMETERS)


def test_no_guidance_module_imports_the_scorer():
    for path in sorted((PACKAGE / "guidance").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            assert not any(n.startswith("mmg_casadi.colregs") for n in names), f"{path.name} imports {names}"


def test_method_defaults_do_not_move_with_the_profiles():
    """Every profile's numbers multiplied by 1.37 before the table is built: no method parameter changes."""
    code = """
import dataclasses, json, math
import mmg_casadi.colregs.profiles as pr
for name, build in list(pr.SCORING_PROFILES.items()):
    p = build()
    scaled = {f.name: getattr(p, f.name) * 1.37 for f in dataclasses.fields(p)
              if isinstance(getattr(p, f.name), float) and math.isfinite(getattr(p, f.name))
              and not f.name.startswith(("w_", "gamma_", "na_cut", "speed_"))}
    pr.SCORING_PROFILES[name] = (lambda p=p, s=scaled: dataclasses.replace(p, **s))
pr._named.cache_clear()
from mmg_casadi.params import PARAMETERS
import mmg_casadi.guidance.methods
print(json.dumps({n: p.default for n, p in PARAMETERS.items()}))
"""
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    moved = json.loads(out.stdout.splitlines()[-1])
    assert moved == {n: p.default for n, p in PARAMETERS.items()}
