# Two commands: `make run` (set up + run the main job), `make test` (set up + run the tests).
# `make package-check` builds the wheel and smoke-tests it in a throw-away venv (CI runs it).
PYTHON ?= $(shell command -v python3.11 || command -v python3)
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.cramlite-installed

.PHONY: run test package-check clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

# Exit code 1 of a bench means some trials failed: those are results (the report shows
# them), so `make run` goes on and its last line is the path of results/report.html.
run: $(STAMP)
	$(BIN)/cramlite bench --out results || [ $$? -eq 1 ]

test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -q

package-check:
	PYTHON=$(PYTHON) bash .ci/package-check

clean:
	rm -rf $(VENV) results *.png
