"""The documentation site: the list of known docstring debt only shrinks, and a built site shows what it must.

``make docs`` builds ``docs/_build/html`` with warnings as errors. The slow test builds the whole site into a
temporary directory (about 5 minutes on 2 cores: the notebooks and the gallery scripts run) and checks the HTML;
``MMG_DOCS_HTML=docs/_build/html`` checks an existing build instead (``.ci/run`` does that after ``make docs``).
"""

from __future__ import annotations

import importlib
import inspect
import os
import pkgutil
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PACKAGES = ("mmg_casadi", "tuning", "studies")
CHECKS = {"PR01", "PR02", "GL08"}
GALLERY_MIN = ("waypoint-square", "colreg-encounters", "conflicting-responsibilities", "narrow-channel",
               "monte-carlo-statistics")
"""Gallery sections (heading anchors) that must show a figure."""


def _debt() -> list[str]:
    lines = (DOCS / "api_debt.txt").read_text(encoding="utf-8").splitlines()
    return [x.strip() for x in lines if x.strip() and not x.startswith("#")]


def _flat_api() -> set[str]:
    """Qualified names of the flat public API (``mmg_casadi.__all__``) and of its classes' public methods."""
    import mmg_casadi as mc
    names = set()
    for name in mc.__all__:
        obj = getattr(mc, name)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            names.add(f"{obj.__module__}.{obj.__qualname__}")
        if inspect.isclass(obj):
            names |= {f"{obj.__module__}.{obj.__qualname__}.{a}" for a in vars(obj) if not a.startswith("_")}
    return names


def public_modules():
    """Every public module of :data:`PACKAGES` (no part of its name starts with ``_``), the packages first."""
    for pkg in PACKAGES:
        root = importlib.import_module(pkg)
        yield root
        yield from (importlib.import_module(m.name) for m in pkgutil.walk_packages(root.__path__, f"{pkg}.")
                    if not any(part.startswith("_") for part in m.name.split(".")))


def public_functions():
    """(qualified name, function) of every public function of every public module, as the API pages list them."""
    for mod in public_modules():
        for name, obj in vars(mod).items():
            if not name.startswith("_") and inspect.isfunction(obj) and obj.__module__ == mod.__name__:
                yield f"{mod.__name__}.{name}", obj


def test_debt_list_only_shrinks():
    """Each entry still fails numpydoc's check (remove fixed ones) and none is part of the flat public API."""
    validate = pytest.importorskip("numpydoc.validate").validate
    debt = _debt()
    assert len(debt) == len(set(debt)), "duplicate entries"
    assert not set(debt) & _flat_api(), "the flat public API must document every argument"
    fixed, gone = [], []
    for name in debt:
        try:
            codes = {code for code, _ in validate(name)["errors"]}
        except (ImportError, AttributeError):
            gone.append(name)
            continue
        if not codes & CHECKS:
            fixed.append(name)
    assert not gone, f"no longer exist, remove from docs/api_debt.txt: {gone}"
    assert not fixed, f"documented now, remove from docs/api_debt.txt: {fixed}"


def test_public_function_finder_sees_the_flat_api():
    found = {name for name, _ in public_functions()}
    assert {"mmg_casadi.scenarios.run.run_scenario", "mmg_casadi.params.markdown_table",
            "tuning.pd.design.design_pd", "studies.waypoint_square.run"} <= found
    assert not any(".".join(n.split(".")[:-1]).split(".")[-1].startswith("_") for n in found)


def public_methods():
    """(qualified name, function) of every documented public method (static and class methods included) of every
    public class of every public module, as the API pages list them (``:members:``: those with a docstring)."""
    for mod in public_modules():
        for name, cls in vars(mod).items():
            if name.startswith("_") or not inspect.isclass(cls) or cls.__module__ != mod.__name__:
                continue
            for attr, member in vars(cls).items():
                func = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
                if not attr.startswith("_") and inspect.isfunction(func) and func.__doc__:
                    yield f"{mod.__name__}.{cls.__qualname__}.{attr}", func


def _section(doc: str, title: str) -> list[tuple[str, list[str]]] | None:
    """Entries ``(head line, description lines)`` of the numpydoc section ``title`` of ``doc``; None without one."""
    lines = inspect.cleandoc(doc or "").splitlines()
    for k in range(len(lines) - 1):
        if lines[k].strip() == title and lines[k + 1].strip() and set(lines[k + 1].strip()) == {"-"}:
            entries: list[tuple[str, list[str]]] = []
            for j in range(k + 2, len(lines)):
                line = lines[j]
                if j + 1 < len(lines) and lines[j + 1].strip() and set(lines[j + 1].strip()) == {"-"}:
                    break  # the next section's title
                if line.strip() and not line[0].isspace():
                    entries.append((line.strip(), []))
                elif line.strip() and entries:
                    entries[-1][1].append(line.strip())
            return entries
    return None


def _returns_value(func) -> bool:
    """Whether ``func`` has a ``return`` with a value other than ``None`` outside nested functions (numpydoc's RT01
    rule, :meth:`numpydoc.validate.Validator.method_returns_something`)."""
    import ast
    import textwrap

    tree = ast.parse(textwrap.dedent(inspect.getsource(func))).body[0]

    def walk(node):
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.FunctionDef):
                continue
            if isinstance(child, ast.Return) and child.value is not None and not (
                    isinstance(child.value, ast.Constant) and child.value.value is None):
                yield child
            yield from walk(child)
    return any(True for _ in walk(tree))


def missing_returns(func) -> str | None:
    """What the docstring of ``func`` lacks (numpydoc RT01, RT03, YD01), or None: a ``Yields`` section for a
    generator, else a ``Returns`` section when it returns a value, and a description under every entry."""
    generator = inspect.isgeneratorfunction(func)
    title = "Yields" if generator else "Returns"
    entries = _section(func.__doc__, title)
    if entries is None:
        return f"no {title} section" if generator or _returns_value(func) else None
    bare = [head for head, desc in entries if not desc]
    return f"{title} entries without a description: {bare}" if bare or not entries else None


def test_every_public_function_documents_what_it_returns():
    """numpydoc RT01/RT03/YD01 over the functions and methods of the API pages, without building the docs."""
    found = list(public_functions()) + list(public_methods())
    assert any(n == "mmg_casadi.closed_loop.simulation.Trajectory.state" for n, _ in found)
    bad = [f"{name}: {why}" for name, func in found if (why := missing_returns(func))]
    assert not bad, "undocumented return values:\n" + "\n".join(bad)


def test_returns_check_detects_a_missing_section():
    def value(x):
        """Double.

        Parameters
        ----------
        x : float
            A number.
        """
        def inner():
            return 1
        return 2 * x

    def nothing(x):
        """Print.

        Parameters
        ----------
        x : float
            A number.
        """
        if x:
            return None
        print(x)

    def bare(x):
        """Double.

        Returns
        -------
        float

        Examples
        --------
        >>> bare(1)
        2
        """
        return 2 * x

    def documented(x):
        """Pairs.

        Yields
        ------
        int
            The numbers up to ``x``.
        """
        yield from range(x)

    def generator(x):
        """Pairs."""
        yield x

    assert missing_returns(value) == "no Returns section"
    assert missing_returns(nothing) is None
    assert missing_returns(bare) == "Returns entries without a description: ['float']"
    assert missing_returns(documented) is None
    assert missing_returns(generator) == "no Yields section"


def cli_command_paths(parser=None, path=("mmg-casadi",)) -> list[tuple[str, ...]]:
    """Every command path of the ``mmg-casadi`` parser (``("mmg-casadi", "study", "statistics")``, ...)."""
    import argparse

    from mmg_casadi.cli import build_parser
    parser = parser or build_parser()
    out = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out.append(path + (name,))
                out += cli_command_paths(sub, path + (name,))
    return out


def test_cli_command_paths():
    paths = cli_command_paths()
    assert ("mmg-casadi", "study", "statistics") in paths and ("mmg-casadi", "tune", "apf") in paths
    assert ("mmg-casadi", "convert") in paths


def _text(html_text: str) -> str:
    return re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", html_text))


def _page(html: Path, module: str) -> str:
    return (html / "_autosummary" / f"{module}.html").read_text(encoding="utf-8")


def check_site(html: Path) -> None:
    """Assertions on a built site (see the module docstring)."""
    # Notebooks: executed, figures embedded as images, no error output.
    for name in ("stagnation_points", "pd_gain_design", "apf_tuning"):
        text = (html / "notebooks" / f"{name}.html").read_text(encoding="utf-8")
        images = re.findall(r'<img[^>]+src="([^"]+\.(?:png|svg|jpg))"', text)
        assert len(images) >= 2, f"{name}: {len(images)} figures"
        assert all((html / "notebooks" / src).exists() for src in images), name
        assert "Traceback" not in text and "ipythontb" not in text, name
    # API: every public function has an entry, with a Parameters list when it takes arguments (except the debt).
    debt = set(_debt())
    for qualname, func in public_functions():
        module = qualname.rsplit(".", 1)[0]
        page = _page(html, module)
        start = page.find(f'id="{qualname}"')
        assert start >= 0, f"{qualname} is not on its module page"
        end = page.find('<dt class="sig sig-object', start + 1)
        entry = page[start:end if end > 0 else len(page)]
        args = [p for p in inspect.signature(func).parameters if p not in ("self", "cls")]
        if args and qualname not in debt:
            assert ">Parameters<" in entry, f"{qualname}: no Parameters section on its page"
    # Parameter table rendered from code.
    from mmg_casadi.params import PARAMETERS
    concepts = (html / "concepts.html").read_text(encoding="utf-8")
    assert all(f"<code class=\"docutils literal notranslate\"><span class=\"pre\">{n}</span></code>" in concepts
               for n in PARAMETERS)
    # Gallery: the figures of at least these studies, each with its full-size command.
    gallery = (html / "gallery.html").read_text(encoding="utf-8")
    sections = dict(re.findall(r'<section id="([^"]+)">(.*?)(?=<section id=|$)', gallery, flags=re.S))
    for anchor in GALLERY_MIN:
        assert anchor in sections, f"gallery: no section {anchor}"
        shown = re.findall(r'<img[^>]+src="([^"]+\.png)"', sections[anchor])
        assert shown and all((html / src).exists() for src in shown), f"gallery: no figure in {anchor}"
        text = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", "", sections[anchor]))
        assert re.search(r"Full size[^:]*: mmg-casadi study \S+", text), f"gallery: no full-size command in {anchor}"

    # CLI reference: a section for every command of the parser, each with its options.
    cli = (html / "cli.html").read_text(encoding="utf-8")
    for path in cli_command_paths():
        anchor = "-".join(path)
        assert f'id="{anchor}"' in cli, f"cli reference: no section for {' '.join(path)}"
    assert all(opt in cli for opt in ("--holdout-envs", "--target-method", "--tracking-tolerance"))
    # File formats: every scenario key, results column, status and failure mechanism.
    from mmg_casadi.closed_loop.outcome import OUTCOMES, RUN_FAILURES
    from mmg_casadi.montecarlo.failures import MECHANISMS
    from mmg_casadi.montecarlo.results import RUN_COLUMNS, SUMMARY_COLUMNS
    from mmg_casadi.scenarios.scenario import OBSTACLE_KEYS, SETTINGS_KEYS, SHIP_KEYS, WALL_KEYS
    formats = _text((html / "formats.html").read_text(encoding="utf-8"))
    for name in (*SHIP_KEYS, *SETTINGS_KEYS, *OBSTACLE_KEYS, *WALL_KEYS, *RUN_COLUMNS, *SUMMARY_COLUMNS,
                 *OUTCOMES, *RUN_FAILURES, *MECHANISMS):
        assert f" {name} " in formats, f"formats: {name} is not described"
    for key in ("collision_kind", "encounters", "reactive_time", "t_enter"):  # the metrics.json schema
        assert re.search(rf"\b{key}\b", formats), f"formats: metrics.json key {key} is not described"
    link = re.search(r'href="([^"]*metrics\.schema\.json)"', (html / "formats.html").read_text(encoding="utf-8"))
    assert link, "formats: no link to the JSON Schema of metrics.json"
    from mmg_casadi.scenarios.metrics_schema import schema_text
    assert (html / link.group(1)).read_text(encoding="utf-8") == schema_text(), "formats: stale JSON Schema"
    # How-to pages of the features beyond the paper: each gives its command.
    for page, command in (("colregs_vortex", "--methods colregs-vortex"), ("colregs_scoring", "colregs_profile"),
                          ("imazu", "mmg-casadi study imazu"), ("wind_current", "mmg-casadi study disturbance"),
                          ("sweep", "mmg-casadi study sweep"), ("study_paper", "mmg-casadi study paper"),
                          ("pd_gains", "--tracking-tolerance 0.03")):
        source = (html / "howto" / f"{page}.html").read_text(encoding="utf-8")
        text = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", "", source))
        assert command in text, f"{page}: no `{command}`"
        assert f'href="{page}.html"' in (html / "howto" / "index.html").read_text(encoding="utf-8"), page
    import dataclasses

    from mmg_casadi.colregs.profiles import ScoringProfile
    scoring = _text((html / "howto" / "colregs_scoring.html").read_text(encoding="utf-8"))
    assert all(f" {f.name} " in scoring for f in dataclasses.fields(ScoringProfile) if f.name != "name")
    # Figures: 150 dpi or more (the gallery, the notebooks, the how-to pages).
    from PIL import Image
    pages = [html / "gallery.html", *(html / "notebooks").glob("*.html"), *(html / "howto").glob("*.html")]
    shown = 0
    for page in pages:
        for src in re.findall(r'<img[^>]+src="([^"]+\.png)"', page.read_text(encoding="utf-8")):
            with Image.open(page.parent / src) as im:
                dpi = im.info.get("dpi", (0.0, 0.0))[0]
            assert dpi >= 149.5, f"{page.name}: {src} at {dpi:.0f} dpi"
            shown += 1
    assert shown >= 15, f"only {shown} figures checked"
    # Theory: equations rendered by MathJax, with the paper's labels and links to the functions.
    theory = (html / "theory.html").read_text(encoding="utf-8")
    assert theory.count('class="math notranslate nohighlight"') >= 15, "theory: too few equations"
    assert "mathjax" in theory.lower()
    scripts = re.findall(r'<script[^>]+src="([^"]*mathjax[^"]*)"', theory, flags=re.I)
    assert scripts and all(not s.startswith(("http:", "https:", "//")) for s in scripts), scripts  # offline
    assert all((html / s.split("?")[0]).exists() for s in scripts), scripts
    for label in ("mmg_nd", "psi_desired", "PD_control", "modified_vortex", "factor_f"):
        assert f'id="equation-{label.lower().replace("_", "-")}"' in theory, f"theory: no equation ({label})"
    assert "mmg_casadi.guidance.velocity_obstacle.velocity_obstacle" in theory
    # Results: the tables of the one results file, as README shows them; the figure-style page's before/after images.
    from studies.results import BLOCKS, load
    page = (html / "results.html").read_text(encoding="utf-8")
    data = load()
    for r in data.get("statistics", [])[:3]:
        assert f"{100 * r['success']:.1f} %" in page, r["method"]
    assert data["quick"]["cases"] and f"{data['quick']['waypoint_square']['ce']:.4f}" in page
    assert len(BLOCKS) >= 9
    figures = (html / "figures.html").read_text(encoding="utf-8")
    shown = re.findall(r'<img[^>]+src="([^"]+\.png)"', figures)
    assert len(shown) >= 16 and all((html / s).exists() for s in shown), shown  # eight figures, before and after
    assert re.search(r'<img[^>]+src="[^"]+\.gif"', gallery), "gallery: no animation"
    # References and changelog.
    refs = _text((html / "references.html").read_text(encoding="utf-8"))
    assert "Jadhav" in refs and "Somayajula" in refs
    import mmg_casadi
    changelog = _text((html / "changelog.html").read_text(encoding="utf-8"))
    assert mmg_casadi.__version__ in changelog


@pytest.mark.skipif(not os.environ.get("MMG_DOCS_HTML"), reason="set MMG_DOCS_HTML to a built site")
def test_built_site():
    check_site(Path(os.environ["MMG_DOCS_HTML"]))


@pytest.mark.slow
def test_docs_build(tmp_path):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    out = tmp_path / "html"
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                           "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
                          cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-5000:]
    check_site(out)
