# Quick start: `make run` (the paper's encounter studies, figures + metrics.json under out/) and `make test`.
# Both create or reuse the local virtual environment .venv; nothing needs to be installed by hand.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed-$(shell cat pyproject.toml | cksum | cut -d' ' -f1)

.PHONY: run test test-all bench venv clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[test]"
	rm -f $(VENV)/.installed-* && touch $@

venv: $(STAMP)

run: $(STAMP)
	$(BIN)/mmg-casadi study all --out out

test: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow" tests mmg_casadi tuning --doctest-modules

test-all: $(STAMP)
	$(BIN)/python -m pytest -q tests mmg_casadi tuning --doctest-modules

bench: $(STAMP)
	$(BIN)/python benchmarks/guidance_calls.py
	$(BIN)/python benchmarks/statistics_throughput.py

clean:
	rm -rf out .pytest_cache
