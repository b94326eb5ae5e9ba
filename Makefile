# Two commands: `make run` (set up + run the main job), `make test` (set up + run the tests).
# `make run` installs what the main job needs (cramlite, its default backend, matplotlib
# for the report's plots); `make test` adds the test and learning tools (.[dev]).
# `make test-quick` runs the tests not marked slow (about 2.5 minutes on 2 cores).
# `make package-check` builds the wheel and smoke-tests it in a throw-away venv (CI runs it).
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.cramlite-installed
RUN_STAMP := $(VENV)/.cramlite-run

.PHONY: run test test-quick package-check clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(RUN_STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[plots]'
	touch $(RUN_STAMP)

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

# Exit code 1 of a bench means some trials failed: those are results (the report shows
# them), so `make run` goes on and its last line is the path of results/report.html.
# --traces: the report shows replays of the first trial of each setup and strategy.
run: $(RUN_STAMP)
	$(BIN)/cramlite bench --traces --out results || [ $$? -eq 1 ]

# The tests run on every core (pytest-xdist; at most 4 workers: each loads the robot).
TEST_WORKERS ?= -n auto --maxprocesses 4

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q $(TEST_WORKERS)

test-quick: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q $(TEST_WORKERS) -m "not slow"

package-check:
	PYTHON=$(PYTHON) bash .ci/package-check

clean:
	rm -rf $(VENV) results *.png
