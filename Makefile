# slipwave: `make run` runs the workflow on the default campaign, `make test` the tests.
PYTHON ?= python3
VENV := .venv
BIN := $(CURDIR)/$(VENV)/bin
STAMP := $(VENV)/.installed
# Rules call the `slipwave` command: the venv goes first on PATH.
export PATH := $(BIN):$(PATH)

.PHONY: install run test test-fast lint bench clean

install: $(STAMP)

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[test]'
	touch $(STAMP)

run: $(STAMP)
	$(BIN)/snakemake --cores 2

# ruff (style, imports, docstring layout), numpydoc (every public function documents
# its parameters and what it returns), mypy (types).
lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/numpydoc lint $$(find src/slipwave -name '*.py')
	$(BIN)/mypy

test: lint
	$(BIN)/python -m pytest

# The unit tests and doctests alone (no whole virtual-bench test, no workflow run).
test-fast: $(STAMP)
	$(BIN)/python -m pytest -m "not slow"

# Every benchmark runs; the target fails if any missed its target.
bench: $(STAMP)
	@status=0; for bench in benchmarks/bench_*.py; do echo "== $$bench"; \
		$(BIN)/python $$bench || status=1; done; exit $$status

clean:
	rm -rf .snakemake
	find results -mindepth 1 ! -name README.md -delete
	find reports -mindepth 1 ! -name README.md -delete
