# Two entry points on a fresh machine: `make demo` and `make test` (`make test-fast` while editing).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: demo test test-fast install install-dev lint bench docs

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

install: $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[gym,ray]"

install-dev: $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[dev,gym,ray]"

demo: install
	$(BIN)/pokerirl demo

# pytest-xdist workers; the tests that share a module or session fixture run on one of them
# (--dist loadgroup, groups set in tests/conftest.py), to build it once.
TEST_WORKERS ?= 2
PYTEST := $(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadgroup

# Everything, slow tests included (CI: .ci/run).
test: install-dev
	$(BIN)/ruff check pokerirl tests benchmarks
	$(BIN)/mypy pokerirl
	$(PYTEST)

# The edit-test loop: the tests not marked slow (and the doctests).
test-fast: install-dev
	$(PYTEST) -m "not slow"

lint: install-dev
	$(BIN)/ruff check pokerirl tests benchmarks
	$(BIN)/mypy pokerirl

# The API reference (HTML, from the docstrings, pdoc) of the curated surface, into docs/api/.
docs: install-dev
	$(BIN)/python docs/build_api.py docs/api

bench: install
	$(BIN)/python benchmarks/ingest.py
	$(BIN)/python benchmarks/engine.py
	$(BIN)/python benchmarks/train.py
	$(BIN)/python benchmarks/agents.py
	$(BIN)/python benchmarks/tournament.py
