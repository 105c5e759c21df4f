# Two entry points on a fresh machine: `make demo` and `make test` (`make test-fast` while editing).
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: demo test test-fast install install-dev lint bench docs

$(BIN)/python:
	@echo "make: creating the virtual environment $(VENV)/ (pokerirl and its libraries go there, not into your Python)"
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

# Not --quiet: on a fresh machine this is minutes of downloads, and pip's lines are the progress.
install: $(BIN)/python
	@echo "make: installing pokerirl (editable) with torch, RLCard, Gymnasium (Box2D, MuJoCo), SB3 and Ray into $(VENV)/"
	@echo "make: torch alone is about 2.6 GB with its CUDA libraries: the first install takes minutes, later ones seconds;"
	@echo "make: pip's last step, 'Installing collected packages', unpacks them and prints nothing for minutes: it is working"
	$(BIN)/python -m pip install -e ".[gym,ray]"
	@echo "make: installed; 'source $(VENV)/bin/activate' puts pokerirl on your PATH (or call $(BIN)/pokerirl)"

install-dev: $(BIN)/python
	$(BIN)/python -m pip install --quiet -e ".[dev,gym,ray]"

demo: install
	$(BIN)/pokerirl demo
	@echo ""
	@echo "make: pokerirl is installed in $(VENV)/: run 'source $(VENV)/bin/activate' to put it on your PATH"
	@echo "make: then, on real hands shipped with pokerirl: pokerirl study irc-199504 --preset quick --out study-real/"

# pytest-xdist workers; a test file runs on one of them (--dist loadfile), so that a module's
# fixtures are built once (loadgroup's groups are not honoured by pytest 9.2 with
# pytest-xdist 3.8, its issue 1386: module fixtures were built on both workers).
TEST_WORKERS ?= 2
PYTEST := $(BIN)/python -m pytest -q -n $(TEST_WORKERS) --dist loadfile

# Everything, slow tests included (CI: .ci/run); the timing-sensitive ones (serial) alone, last.
test: install-dev
	$(BIN)/ruff check pokerirl tests benchmarks
	$(BIN)/mypy pokerirl
	$(PYTEST) -m "not serial"
	$(BIN)/python -m pytest -q -m serial

# The edit-test loop: the tests not marked slow (and the doctests).
test-fast: install-dev
	$(PYTEST) -m "not slow and not serial"

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
