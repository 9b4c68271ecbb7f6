# Quick start: `make run` (the paper's encounter studies, figures + metrics.json under out/) and `make test`.
# Both create or reuse the local virtual environment .venv; nothing needs to be installed by hand.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)

.PHONY: run test test-all bench docs venv clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test]"
	rm -f $(VENV)/.installed-* && touch $@

# The docs extra has its own stamp, so `make test` neither needs nor reinstalls it.
DOCS_STAMP := $(VENV)/.docs-installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)

$(DOCS_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e ".[docs]"
	rm -f $(VENV)/.docs-installed-* && touch $@

venv: $(STAMP)

run: $(STAMP)
	$(BIN)/mmg-casadi study all --out out

test: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow" tests mmg_casadi tuning --doctest-modules

test-all: $(STAMP)
	$(BIN)/python -m pytest -q tests mmg_casadi tuning --doctest-modules

# The documentation site (docs/_build/html): API reference, executed notebooks, gallery. Warnings are errors.
docs: $(DOCS_STAMP)
	rm -rf docs/_autosummary
	$(BIN)/sphinx-build -W --keep-going -q -b html docs docs/_build/html
	@echo "docs: open docs/_build/html/index.html"

bench: $(STAMP)
	$(BIN)/python benchmarks/guidance_calls.py
	$(BIN)/python benchmarks/statistics_throughput.py
	$(BIN)/python benchmarks/against_commit.py

clean:
	rm -rf out .pytest_cache docs/_build docs/_generated docs/_autosummary docs/notebooks
