"""The flat public API: every public argument is documented (numpydoc), and the README's snippet works."""

from __future__ import annotations

import inspect
import re

import pytest

import mmg_casadi as mc


def _documented(doc: str) -> set[str]:
    """Names listed in the numpydoc ``Parameters`` section of ``doc``."""
    lines = inspect.cleandoc(doc or "").splitlines()
    names: set[str] = set()
    for k, line in enumerate(lines[:-1]):
        if line.strip() == "Parameters" and set(lines[k + 1].strip()) == {"-"}:
            for entry in lines[k + 2:]:
                if entry.strip() and set(entry.strip()) == {"-"}:
                    break
                if entry and not entry[0].isspace():
                    head = entry.split(" : ")[0] if " : " in entry else entry
                    names |= {n.strip().lstrip("*") for n in head.split(",")}
            names.discard(names and lines[-1].strip())
    return names


def _public_callables():
    for name in mc.__all__:
        obj = getattr(mc, name)
        if inspect.isfunction(obj):
            yield name, obj, obj.__doc__
        elif inspect.isclass(obj):
            yield name, obj, obj.__doc__
            for attr, member in vars(obj).items():
                if not attr.startswith("_") and inspect.isfunction(member):
                    yield f"{name}.{attr}", member, member.__doc__


def _arguments(obj) -> list[str]:
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    return [p for p in sig.parameters if p not in ("self", "cls")]


CASES = [(n, o, d) for n, o, d in _public_callables() if _arguments(o)]


@pytest.mark.parametrize("name,obj,doc", CASES, ids=[c[0] for c in CASES])
def test_every_public_argument_is_documented(name, obj, doc):
    missing = [a for a in _arguments(obj) if a not in _documented(doc)]
    assert not missing, f"{name}: undocumented arguments {missing}"


def test_parser_finds_parameters_and_detects_a_missing_one():
    def f(a, b, *, c=1):
        """Do.

        Parameters
        ----------
        a, b : int
            Numbers.
        """
    assert _documented(f.__doc__) == {"a", "b"}
    assert [x for x in _arguments(f) if x not in _documented(f.__doc__)] == ["c"]


def test_readme_snippet(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # "head_on.toml" is not a file here: the shipped scenario of that name is used
    r = mc.run_scenario("head_on.toml", params={"k_vor0": -15.0, "t_max": 30.0})
    assert r.scenario == mc.packaged_scenario("head_on")
    assert r.metrics["params"]["k_vor0"] == -15.0 and r.params["r_safe"] == 15.0
    frame = r.to_frame()
    assert list(frame.index) == ["ship1", "ship2"] and "mcte" in frame.columns
    fig = r.plot()
    assert len(fig.axes) >= 3
    from matplotlib.figure import Figure
    ax = Figure().add_subplot()
    assert r.plot(ax=ax) is ax.figure and ax.lines
    out = r.save(tmp_path / "run")
    assert {p.name for p in out.iterdir()} >= {"metrics.json", "trajectory.npz", "trajectory.csv", "scenario.png"}
    assert re.search(r'"k_vor0": -15.0', (out / "metrics.json").read_text())


def test_the_parameter_table_is_the_code_table_wherever_shown():
    """README points to the concepts page, whose table is generated from the code when the site is built (README
    showed a copy up to 0.3.0, kept in sync by this test)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    readme = (root / "README.md").read_text(encoding="utf-8")
    assert "| `dt` |" not in readme and "(docs/concepts.md)" in readme and "mmg-casadi params" in readme
    concepts = (root / "docs" / "concepts.md").read_text(encoding="utf-8")
    assert "```{include} _generated/parameters.md" in concepts
    ext = (root / "docs" / "_ext" / "mmg_docs.py").read_text(encoding="utf-8")
    assert 'markdown_table() + "\\n"' in ext


def test_core_package_does_not_import_studies_tuning_or_cli():
    import ast
    from pathlib import Path
    root = Path(mc.__file__).parent
    offenders = []
    for f in root.glob("*.py"):
        if f.name == "cli.py":
            continue
        for node in ast.walk(ast.parse(f.read_text(encoding="utf-8"))):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [("." * node.level) + (node.module or "")]
            offenders += [(f.name, n) for n in names
                          if n.split(".")[0] in ("studies", "tuning") or n in (".cli", "mmg_casadi.cli")]
    assert not offenders
