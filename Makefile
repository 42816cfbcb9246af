# Two commands do everything on a fresh machine:
#   make run    install into .venv, train a short run, evaluate it, write the figures
#   make test   install into .venv (with test extras), lint, type-check, run the test suite
# The install steps rerun only when pyproject.toml changed (stamp files in .venv).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
RUN_DIR ?= runs/quickstart
INSTALLED := $(VENV)/.installed
INSTALLED_TEST := $(VENV)/.installed-test

.PHONY: install install-test run test lint bench clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip

$(INSTALLED): pyproject.toml | $(BIN)/python
	$(BIN)/pip install --quiet torch==2.13.0
	$(BIN)/pip install --quiet -e ".[train,export]"
	touch $@

$(INSTALLED_TEST): $(INSTALLED) pyproject.toml
	$(BIN)/pip install --quiet -e ".[train,export,test]"
	touch $@

install: $(INSTALLED)

install-test: $(INSTALLED_TEST)

run: install
	$(BIN)/activevision quickstart --out $(RUN_DIR)

lint: install-test
	$(BIN)/ruff check src tests bench examples
	$(BIN)/lint-imports
	$(BIN)/mypy

test: install-test
	$(BIN)/ruff check src tests bench examples
	$(BIN)/lint-imports
	$(BIN)/mypy
	NUMBA_CACHE_DIR=$(CURDIR)/.numba_cache $(BIN)/python -m pytest -q tests

bench: install-test
	for b in bench/*.py; do $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) .numba_cache build *.egg-info src/*.egg-info
