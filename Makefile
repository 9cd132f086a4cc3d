# fieldtwin — every target sets itself up on a fresh machine.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
SPEED ?=
PLANT ?=

.PHONY: run test test-fast test-tools lint setup clean bench

$(STAMP): pyproject.toml
	@echo "fieldtwin: setting up .venv (first run only, about a minute)..."
	$(PY) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)
	@echo "fieldtwin: set up."

setup: $(STAMP)

run: $(STAMP)
	$(BIN)/fieldtwin run $(PLANT) $(if $(SPEED),--speed $(SPEED))

# The whole suite, in parallel (pytest-xdist), with its progress and the slowest tests.
test: $(STAMP) test-tools
	$(BIN)/python -m pytest -n auto --durations=5

# The inner loop: no test that starts a process, a browser or a socket server.
test-fast: $(STAMP)
	FIELDTWIN_FAST_EXAMPLES=25 $(BIN)/python -m pytest -m "not integration" -n auto

# tshark, curl, chromium for the tests that need them (installed as root on Debian).
test-tools:
	@.ci/test-tools

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/ruff format --check src tests benchmarks
	$(BIN)/mypy
	$(BIN)/lint-imports

bench: $(STAMP)
	for f in benchmarks/*.py; do $(BIN)/python $$f || exit 1; done

clean:
	rm -rf $(VENV) .mypy_cache .ruff_cache .pytest_cache
