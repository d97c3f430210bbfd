# Two commands on a fresh machine: `make run` and `make test` (README, quick start).
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DEFAULT_SCENE := cases/swash_plate_4cyl.toml
DEFAULT_RESULT := results/$(basename $(notdir $(DEFAULT_SCENE))).h5

.PHONY: run test test-fast lint test-stress test-cpu bench docs install clean

# Bytecode is written at install: where PYTHONDONTWRITEBYTECODE is set, each run would otherwise
# compile transient's sources again, a noticeable part of a warm start.
BYTECODE := $(PY) -m compileall -q transient

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
	$(BYTECODE)
	touch $(STAMP)

install: $(STAMP)

# Re-running `make run` replaces the default result on purpose (--force).
run: $(STAMP)
	$(VENV)/bin/transient run $(DEFAULT_SCENE) -o results --force
	$(VENV)/bin/transient plot $(DEFAULT_RESULT) -o results --force

# The suite's tiers (docs/developer/testing.md): `make test` the checks of `make lint`, then
# every test but the long stress; `make test-fast` the unit tests but the slow ones (the loop
# while changing the code); `make test-stress` that stress (marker `stress`); `make test-cpu` the
# runs again with the code built for another CPU.
# One pytest worker per core, at most 4 (a process compiling the stepper holds about a gigabyte);
# worksteal moves queued tests from a busy worker to an idle one (the first runs compile for
# minutes).
PYTEST := $(PY) -m pytest -q -n auto --maxprocesses 4 --dist worksteal

# The import contracts (pyproject.toml, [tool.importlinter]), ruff and mypy ([tool.ruff],
# [tool.mypy]): seconds, so they go first.
lint: $(STAMP)
	$(VENV)/bin/lint-imports
	$(VENV)/bin/ruff check .
	$(VENV)/bin/mypy

test: lint
	$(PYTEST) -m "not stress"

# Under two minutes once the kernels are cached: every test over about ten seconds is `slow`.
test-fast: $(STAMP)
	$(PYTEST) -m "not slow and not stress" tests/unit

# Kill-and-resume, random scenes of every mechanism, `transient stress --quick`.
test-stress: $(STAMP)
	$(PYTEST) -m stress

# The tests that run the stepper and compare its results, with numba compiling for the x86-64
# baseline (`generic`), numpy's SIMD loops and OpenBLAS's kernels at theirs: compiled code and
# linear algebra round differently on another CPU, the steps differ from there, and every
# comparison must still hold at the tolerance it states. Its own cache folder: its kernels and
# Wiebe tables are the baseline's, not the host's. The slow tests (reference paths) are left out:
# the stepper they check runs in the rest too.
CPU_CACHE := $(or $(TRANSIENT_CACHE_DIR),$(or $(XDG_CACHE_HOME),$(HOME)/.cache)/transient)-generic
test-cpu: $(STAMP)
	NUMBA_CPU_NAME=generic NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR" \
		OPENBLAS_CORETYPE=Prescott TRANSIENT_CACHE_DIR=$(CPU_CACHE) \
		$(PYTEST) -m "not slow and not stress" tests/validation tests/cli/test_golden.py

# The work-precision record and its targets in results/benchmarks/ (about twenty minutes; the
# record says how long). CyRK, the compiled peer, comes with the optional `bench` extra.
bench: $(STAMP)
	$(PY) -m pip install -q -e '.[test,bench]'
	$(BYTECODE)
	$(VENV)/bin/transient bench -o results/benchmarks --force

# The documentation site into docs/_build/html; warnings are errors. Every page is read afresh
# (-E): the scene keys, the CLI and the API pages are generated from the code, which Sphinx does
# not track. The gallery's examples run during the build (docs/examples; an unchanged example
# is not run again), so a cold numba cache makes the first build take minutes.
DOCS_STAMP := $(VENV)/.installed-docs

$(DOCS_STAMP): $(STAMP) pyproject.toml
	$(PY) -m pip install -q -e '.[test,docs]'
	$(BYTECODE)
	touch $(DOCS_STAMP)

# The API stubs are made afresh (autosummary leaves those of renamed modules behind).
docs: $(DOCS_STAMP)
	rm -rf docs/generated
	$(VENV)/bin/sphinx-build -E -n -W --keep-going -b html docs docs/_build/html

clean:
	rm -rf $(VENV) results/*.h5 results/*.png docs/_build docs/generated docs/auto_examples \
		docs/guide/_generated docs/_generated
