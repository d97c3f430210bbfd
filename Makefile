# Two commands on a fresh machine: `make run` and `make test` (README, quick start).
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DEFAULT_SCENE := cases/swash_plate_4cyl.toml
DEFAULT_RESULT := results/$(basename $(notdir $(DEFAULT_SCENE))).h5

.PHONY: run test bench install clean

# Bytecode is written here: where PYTHONDONTWRITEBYTECODE is set (as on the machine of
# results/benchmarks/targets.md), each run would otherwise compile transient's sources again,
# 0.1–0.2 s of a ~1 s warm start (README, Start-up).
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
	$(VENV)/bin/transient plot $(DEFAULT_RESULT) -o results

# One pytest worker per core, at most 4 (a process compiling the stepper held 1.0 GB); worksteal
# moves queued tests from a busy worker to an idle one (the first runs compile for minutes).
test: $(STAMP)
	$(PY) -m pytest -q -n auto --maxprocesses 4 --dist worksteal

# The work-precision record and issue 5's targets in results/benchmarks/ (19 min 55 s measured on
# 2026-11-27; 27 min 43 s on the slower machine of 2026-11-26). CyRK, the compiled peer, comes with
# the optional `bench` extra.
bench: $(STAMP)
	$(PY) -m pip install -q -e '.[test,bench]'
	$(BYTECODE)
	$(VENV)/bin/transient bench -o results/benchmarks

clean:
	rm -rf $(VENV) results/*.h5 results/*.png
