# slipwave: `make run` runs the workflow on the default campaign, `make test` the tests.
PYTHON ?= python3
VENV := .venv
BIN := $(CURDIR)/$(VENV)/bin
STAMP := $(VENV)/.installed
# the package alone, what `make run` needs (the test and docs tools come with `install`)
RUN_STAMP := $(VENV)/.installed-run
# Rules call the `slipwave` command: the venv goes first on PATH.
export PATH := $(BIN):$(PATH)

.PHONY: install system-deps run test test-fast lint docs bench slurm-test clean

install: $(STAMP)

$(RUN_STAMP): pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e .
	touch $(RUN_STAMP)

$(STAMP): $(RUN_STAMP)
	$(BIN)/python -m pip install --quiet -e '.[test,docs]'
	touch $(STAMP)

# What pip cannot install: Debian's Chromium and poppler-utils, with which the tests look
# at the reports as a reader does (they skip, saying so, without them), and the Pango
# that WeasyPrint prints PDFs with. Needs root (CI runs as root); apt-get only where
# something is missing.
SYSTEM_PACKAGES := chromium poppler-utils libpango-1.0-0 libpangoft2-1.0-0 fonts-dejavu-core
system-deps:
	@missing=$$(for p in $(SYSTEM_PACKAGES); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -n "$$missing" ]; then \
		if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
			apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq $$missing; \
		else echo "missing Debian packages (install them as root): $$missing"; fi; \
	fi

run: $(RUN_STAMP)
	$(BIN)/snakemake --cores 2

# ruff (style, imports, docstring layout), numpydoc (every public function documents
# its parameters and what it returns), mypy (types), import-linter (the package's
# layers: no cycle, no upward import, no video library under the analysis).
lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/numpydoc lint $$(find src/slipwave -name '*.py')
	$(BIN)/mypy
	$(BIN)/lint-imports

# The documentation site in docs/_build/html (read on two processes), warnings as errors;
# the doctest builder runs the tutorial (the default campaign through the library).
docs: $(STAMP)
	$(BIN)/sphinx-build -q -W --keep-going -j 2 -b html docs docs/_build/html
	$(BIN)/sphinx-build -q -W -b doctest docs docs/_build/doctest

# Two pytest workers (pytest-xdist), a test file to each: a file's module fixtures (the
# default campaign simulated, the Colas records denoised) are built once. One BLAS
# thread per worker: two workers with two threads each on two cores run slower than one.
# Files go out in collection order (tests/conftest.py puts the longest first; xdist would
# otherwise send the files with the most tests first, and the workflow's run last).
test: lint docs
	OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \
		$(BIN)/python -m pytest -n 2 --dist loadfile --no-loadscope-reorder

# The unit tests and doctests alone (no whole virtual-bench test, no workflow run).
test-fast: $(STAMP)
	$(BIN)/python -m pytest -m "not slow"

# The workflow on a real one-node SLURM cluster through Snakemake's executor plugin
# (installs slurm-wlm and munge with apt-get; needs root); not part of `make test`.
slurm-test: $(STAMP)
	bash tests/slurm/run.sh

# Every benchmark runs, its figures go to benchmarks/RESULTS.md; the target fails if any
# missed its target.
bench: $(STAMP)
	$(BIN)/python benchmarks/run_all.py

clean:
	rm -rf .snakemake docs/_build docs/generated
	find results -mindepth 1 ! -name README.md -delete
	find reports -mindepth 1 ! -name README.md -delete
