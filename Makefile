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
# numba checks a cached kernel against its own file only, not the files of the kernels it
# calls: after an edit to one of those, the cache would run the old code. So each state of
# the sources gets its own cache (the older ones are removed).
SOURCE_HASH := $(shell cat $$(find src -name '*.py' | LC_ALL=C sort) | sha1sum | cut -c1-16)
NUMBA_CACHE := $(CURDIR)/.numba_cache/$(SOURCE_HASH)

.PHONY: install install-test numba-cache run test lint bench clean

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

numba-cache:
	find .numba_cache -mindepth 1 -maxdepth 1 ! -name $(SOURCE_HASH) -exec rm -rf {} + 2>/dev/null || true
	mkdir -p $(NUMBA_CACHE)

run: install numba-cache
	NUMBA_CACHE_DIR=$(NUMBA_CACHE) $(BIN)/activevision quickstart --out $(RUN_DIR)

lint: install-test
	$(BIN)/ruff check src tests bench examples
	$(BIN)/lint-imports
	$(BIN)/mypy

test: install-test numba-cache
	$(BIN)/ruff check src tests bench examples
	$(BIN)/lint-imports
	$(BIN)/mypy
	NUMBA_CACHE_DIR=$(NUMBA_CACHE) $(BIN)/python -m pytest -q tests

# The benchmarks that need nothing but the package; continuous.py (scores trained runs:
# --runs) and reference_ppo.py (trains PPO for 11 minutes into runs/) are run by hand.
BENCH_SCRIPTS := render viewpoint env match vectorizers render_determinism train inference \
	inference_inputs match_student sweep reproducibility fuzz_inputs

bench: install-test numba-cache
	for b in $(BENCH_SCRIPTS); do echo "== bench/$$b.py"; \
		NUMBA_CACHE_DIR=$(NUMBA_CACHE) $(BIN)/python bench/$$b.py || exit 1; done

clean:
	rm -rf $(VENV) .numba_cache build *.egg-info src/*.egg-info
