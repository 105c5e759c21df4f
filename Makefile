# Two entry points on a fresh machine: `make demo` and `make test`.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: demo test install install-dev lint bench docs

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

install: $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[gym,ray]"

install-dev: $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[dev,gym,ray]"

demo: install
	$(BIN)/pokerirl demo

test: install-dev
	$(BIN)/ruff check pokerirl tests benchmarks
	$(BIN)/mypy pokerirl
	$(BIN)/python -m pytest -q

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
