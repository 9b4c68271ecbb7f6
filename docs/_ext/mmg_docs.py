"""The project's Sphinx extension: what the docs build generates from code before Sphinx reads the sources.

On ``builder-inited`` it writes into ``docs/_generated/`` (not in git):

* ``parameters.md`` — the parameter table, :func:`mmg_casadi.params.markdown_table`;
* ``flat_api.rst`` — a table of ``mmg_casadi.__all__`` pointing at the modules that define the names;
* ``claims.md`` — ``docs/claims.md`` when it exists, else a placeholder;
* ``gallery.md`` and ``gallery/<script>/*.png`` — every script in ``docs/gallery/`` run in its own process
  (``python SCRIPT OUT_DIR``), its figures embedded under its docstring;

and copies ``notebooks/*.ipynb`` into ``docs/notebooks/`` so that myst-nb executes them. A gallery script that
fails is a build warning (an error under ``-W``). Gallery results are reused while neither the script nor any
source file of the packages changed (a hash stamp next to the figures). References to ``mmg_casadi.NAME`` of the
flat API resolve to the object where NAME is defined.
"""

from __future__ import annotations

import ast
import hashlib
import os
import shutil
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from sphinx.util import logging

logger = logging.getLogger(__name__)

DOCS = Path(__file__).resolve().parents[1]
ROOT = DOCS.parent
GENERATED = DOCS / "_generated"
PACKAGES = ("mmg_casadi", "studies", "tuning")

CLAIMS_PLACEHOLDER = """\
```{note}
The table of the paper's claims and what this code gets for each of them is not in this build yet
(`docs/claims.md` is missing). Until then, `make run` writes every study's numbers to `out/*/metrics.json`.
```
"""


def _write(path: Path, text: str) -> None:
    """Write ``text`` unless the file already holds it (so Sphinx does not see a changed source)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def write_parameters() -> None:
    from mmg_casadi.params import markdown_table
    _write(GENERATED / "parameters.md", markdown_table() + "\n")


def write_flat_api() -> None:
    """A table of ``mmg_casadi.__all__``: the flat name, the object where it is defined, its summary line."""
    import importlib
    import inspect

    from sphinx.pycode import ModuleAnalyzer

    import mmg_casadi
    rows = []
    for name, (module, original) in sorted(_flat_names().items(), key=lambda kv: kv[0].lower()):
        obj = getattr(importlib.import_module(module), original)
        if inspect.isfunction(obj) or inspect.isclass(obj):
            doc = inspect.getdoc(obj) or ""
        else:
            doc = "\n".join(ModuleAnalyzer.for_module(module).find_attr_docs().get(("", original), []))
        summary = doc.strip().split("\n\n")[0].replace("\n", " ")
        rows += [f"   * - ``mc.{name}``", f"     - :py:obj:`~{module}.{original}`", f"     - {summary}"]
    missing = sorted(set(mmg_casadi.__all__) - set(_flat_names()))
    if missing:
        logger.warning("mmg_casadi.__all__ names not imported from a submodule in __init__.py: %s", missing,
                       type="mmg_docs", subtype="flat_api")
    head = [".. list-table::", "   :header-rows: 1", "   :widths: 20 25 55", "",
            "   * - name", "     - defined as", "     - summary"]
    _write(GENERATED / "flat_api.rst", "\n".join(head + rows) + "\n")


def _flat_names() -> dict[str, tuple[str, str]]:
    """``mmg_casadi.__all__`` name → (defining module, name there), read from the package's relative imports."""
    import mmg_casadi
    tree = ast.parse(Path(mmg_casadi.__file__).read_text(encoding="utf-8"))
    out = {}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module:
            for alias in node.names:
                out[alias.asname or alias.name] = (f"mmg_casadi.{node.module}", alias.name)
    return {k: v for k, v in out.items() if k in mmg_casadi.__all__}


def write_claims() -> None:
    src = DOCS / "claims.md"
    _write(GENERATED / "claims.md", src.read_text(encoding="utf-8") if src.exists() else CLAIMS_PLACEHOLDER)


def copy_notebooks() -> None:
    dest = DOCS / "notebooks"
    dest.mkdir(exist_ok=True)
    wanted = {p.name for p in (ROOT / "notebooks").glob("*.ipynb")}
    for stale in dest.glob("*.ipynb"):
        if stale.name not in wanted:
            stale.unlink()
    for name in wanted:
        src, dst = ROOT / "notebooks" / name, dest / name
        if not dst.exists() or dst.read_bytes() != src.read_bytes():
            shutil.copyfile(src, dst)


# -- gallery -------------------------------------------------------------------------------------------------

def _source_hash() -> str:
    h = hashlib.sha256()
    for pkg in PACKAGES:
        for f in sorted((ROOT / pkg).rglob("*")):
            if f.is_file() and f.suffix in (".py", ".toml"):
                h.update(f.relative_to(ROOT).as_posix().encode() + b"\0" + f.read_bytes())
    return h.hexdigest()


def _script_doc(script: Path) -> tuple[str, str]:
    """Title (first docstring line) and body (the rest, Markdown) of a gallery script."""
    doc = ast.get_docstring(ast.parse(script.read_text(encoding="utf-8"))) or ""
    title, _, body = doc.partition("\n")
    if not title.strip():
        raise ValueError(f"{script.name}: a gallery script starts with a docstring whose first line is its title")
    return title.strip(), body.strip()


def _run_script(script: Path, out: Path, stamp: str) -> tuple[Path, float, str | None]:
    """Run ``script`` into ``out`` unless the stamp says its figures are current; returns (script, seconds, error)."""
    done = out / ".stamp"
    if done.exists() and done.read_text() == stamp and any(out.glob("*.png")):
        return script, 0.0, None
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    t0 = time.perf_counter()
    env = dict(os.environ, MPLBACKEND="Agg")
    proc = subprocess.run([sys.executable, str(script), str(out)], cwd=ROOT, env=env, capture_output=True,
                          text=True)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        return script, seconds, (proc.stderr or proc.stdout)[-3000:]
    if not any(out.glob("*.png")):
        return script, seconds, "wrote no PNG into its output directory"
    done.write_text(stamp)
    return script, seconds, None


def build_gallery(workers: int) -> None:
    scripts = sorted((DOCS / "gallery").glob("*.py"))
    stamp_base = _source_hash()
    jobs = []
    for s in scripts:
        stamp = hashlib.sha256((stamp_base + s.read_text(encoding="utf-8")).encode()).hexdigest()
        jobs.append((s, GENERATED / "gallery" / s.stem, stamp))
    with ThreadPoolExecutor(max_workers=max(1, workers)) as pool:
        results = list(pool.map(lambda j: _run_script(*j), jobs))
    sections = []
    for (script, seconds, error), (_, out, _) in zip(results, jobs):
        if error:
            logger.warning("gallery script %s failed:\n%s", script.name, error, type="mmg_docs", subtype="gallery")
            continue
        if seconds:
            logger.info("gallery: %s ran in %.1f s", script.name, seconds)
        title, body = _script_doc(script)
        parts = [f"## {title}", "", body, ""]
        for png in sorted(out.glob("*.png")):
            rel = png.relative_to(DOCS).as_posix()
            parts += [f":::{{figure}} /{rel}", ":width: 100%", "", f"`{png.name}` (short run)", ":::", ""]
        parts += [f"Short-run script: `docs/gallery/{script.name}`", ""]
        sections.append("\n".join(parts))
    _write(GENERATED / "gallery.md", "\n".join(sections))


def resolve_flat_name(app, env, node, contnode):
    """Let ``mmg_casadi.NAME`` of the flat API resolve to the object where NAME is defined."""
    target = node.get("reftarget", "")
    if node.get("refdomain") != "py" or not target.startswith("mmg_casadi."):
        return None
    flat = _flat_names().get(target.split(".", 1)[1])
    if flat is None:
        return None
    node["reftarget"] = ".".join(flat)
    domain = env.get_domain("py")
    return domain.resolve_xref(env, node["refdoc"], app.builder, node["reftype"], ".".join(flat), node, contnode)


def generate(app) -> None:
    GENERATED.mkdir(exist_ok=True)
    write_parameters()
    write_flat_api()
    write_claims()
    copy_notebooks()
    build_gallery(app.config.mmg_gallery_workers)


def setup(app):
    app.add_config_value("mmg_gallery_workers", 2, "env")
    app.connect("builder-inited", generate)
    app.connect("missing-reference", resolve_flat_name)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
