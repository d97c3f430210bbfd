# Two commands on a fresh machine: `make run` and `make test` (README, quick start).
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
DEFAULT_SCENE := cases/swash_plate_4cyl.toml
DEFAULT_RESULT := results/$(basename $(notdir $(DEFAULT_SCENE))).h5

.PHONY: run test bench install clean

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -e '.[test]'
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

# The work-precision record in results/benchmarks/ (issue 5; 14 min 8 s measured at b0ece4d). CyRK, the
# compiled peer, comes with the optional `bench` extra.
bench: $(STAMP)
	$(PY) -m pip install -q -e '.[test,bench]'
	$(VENV)/bin/transient bench -o results/benchmarks

clean:
	rm -rf $(VENV) results/*.h5 results/*.png
