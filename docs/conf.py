"""Sphinx configuration of the mmg-casadi documentation (``make docs``).

Everything that is built from code happens at build time: the API reference (autosummary over the packages), the
parameter table (:func:`mmg_casadi.params.markdown_table`), the four notebooks (executed by myst-nb) and the
gallery (the scripts in ``docs/gallery/`` run with short horizons). Warnings are errors (``-W --keep-going``).
"""

from __future__ import annotations

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))  # the project's own Sphinx extension (docs/_ext/mmg_docs.py)

import mmg_casadi  # noqa: E402

project = "mmg-casadi"
author = "mmg-casadi contributors"
copyright = "the mmg-casadi contributors, BSD-3-Clause licence"
release = version = mmg_casadi.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax copied into _static: the equations render without a network
    "numpydoc",
    "myst_nb",
    "mmg_docs",
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "_generated", "claims.md", "results", "gallery/*.py", "**.ipynb_checkpoints", "Thumbs.db",
                    ".DS_Store"]
templates_path = ["_templates"]

# -- API reference: every public module of the three packages, found at build time ---------------------------
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True}
autodoc_typehints = "none"            # the numpydoc Parameters section carries the types
autodoc_member_order = "bysource"
autoclass_content = "class"

numpydoc_show_class_members = False   # the module page's summary table lists them
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
# Undocumented or unknown arguments, public objects without a docstring, a function that returns a value without a
# Returns section (a generator without Yields) and a return value without a description are build warnings (hence
# errors); tests/test_docs.py checks the return values without a build.
numpydoc_validation_checks = {"PR01", "PR02", "GL08", "RT01", "RT03", "YD01"}
# Known debt: objects that predate the docs build and do not document every argument yet. The list may only
# shrink (tests/test_docs.py checks that each entry still fails and that the flat public API is not on it).
numpydoc_validation_exclude = {
    rf"^{name.strip()}$".replace(".", r"\.") for name in (DOCS / "api_debt.txt").read_text().splitlines()
    if name.strip() and not name.startswith("#")
}

# -- cross-references: a reference into the project that does not resolve is an error -----------------------
nitpicky = True
nitpick_ignore_regex = [
    # Types of other libraries (no network at build time, so no intersphinx): only our own names must resolve.
    (r"py:.*", r"(?!(mmg_casadi|tuning|studies)\.).*"),
]

# -- notebooks: executed at every build; a cell that raises fails the build -----------------------------------
# (as a warning "Executing notebook failed: CellExecutionError" with the cell and traceback, an error under -W;
# raise_on_error=True would abort Sphinx with a crash report instead)
nb_execution_mode = "force"
nb_execution_timeout = 600
nb_execution_raise_on_error = False
nb_execution_allow_errors = False
nb_execution_show_tb = True
nb_merge_streams = True
myst_enable_extensions = ["colon_fence", "dollarmath"]
myst_heading_anchors = 3

# -- HTML ---------------------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = f"mmg-casadi {version}"
html_theme_options = {
    "navigation_with_keys": False,
    "header_links_before_dropdown": 8,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_show_sourcelink = False
