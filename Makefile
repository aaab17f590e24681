# sim_tactile: `make demo` and `make test` work on a fresh machine with Python 3.11.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
# torch is an optional extra; this pin takes the CPU wheel that this machine keeps on disk
# (an unpinned torch pulls a CUDA build of several GB).
TORCH_PIN := torch==2.13.0
STAMP_RUN := $(VENV)/.installed-run
STAMP_TEST := $(VENV)/.installed-test
STAMP_DOCS := $(VENV)/.installed-docs

.PHONY: demo test check docs lint format bench clean

$(BIN)/python:
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "make: $(PYTHON) not found; set PYTHON=..." >&2; exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

$(STAMP_RUN): pyproject.toml | $(BIN)/python
	$(BIN)/pip install -q -e .
	touch $@

$(STAMP_TEST): pyproject.toml | $(BIN)/python
	$(BIN)/pip install -q $(TORCH_PIN)
	$(BIN)/pip install -q -e '.[test,learn,ray,docs,tonic,hub,nir,neurobench]'
	# neurobench and norse (the tests' NIR consumer) declare torchaudio / torchvision, which
	# have no wheel for the pinned torch: installed without their declared dependencies; the
	# [neurobench] and [nir] extras above name what they import
	$(BIN)/pip install -q --no-deps neurobench==2.3.0 norse==1.1.0
	touch $@ $(STAMP_RUN) $(STAMP_DOCS)

# the main job: the soft-finger paper's task in simulation, quick (about a minute here)
demo: $(STAMP_RUN)
	$(BIN)/sim-tactile run finger7-v1 --quick --out demo-out

# the whole suite, on both cores (the tests are deterministic under pytest-xdist; the tests
# that read one data set share a worker, --dist loadgroup, so that one simulates it); it builds
# the manual too (tests/test_docs.py), so a broken cross-reference fails it
test: lint $(STAMP_TEST)
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup

# the fast lane (under two minutes): everything but the tests marked slow
check: lint $(STAMP_TEST)
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup -m "not slow"

$(STAMP_DOCS): pyproject.toml | $(BIN)/python
	$(BIN)/pip install -q -e '.[docs]'
	touch $@ $(STAMP_RUN)

# the manual (docs/, Sphinx) into build/docs, warnings as errors; it needs the [docs] extra
# only (the extras' libraries that the API pages import are mocked where missing)
docs: $(STAMP_DOCS)
	$(BIN)/sphinx-build -W --keep-going -b html docs build/docs

# style, and the one-way flow of the imports (import-linter's contracts in pyproject.toml)
lint: $(STAMP_TEST)
	$(BIN)/ruff check sim_tactile tests perf tools docs examples
	$(BIN)/ruff format --check sim_tactile tests perf tools docs examples
	$(BIN)/lint-imports

format: $(STAMP_TEST)
	$(BIN)/ruff format sim_tactile tests perf tools docs examples
	$(BIN)/ruff check --fix sim_tactile tests perf tools docs examples

bench: $(STAMP_TEST)
	$(BIN)/python perf/bench_plates.py
	$(BIN)/python perf/plate_views.py
	$(BIN)/python perf/bench_spikes.py
	$(BIN)/python perf/bench_finger.py
	$(BIN)/python perf/bench_sensors.py
	$(BIN)/python perf/bench_learn.py
	$(BIN)/python perf/bench_generate.py
	$(BIN)/sim-tactile bench speed-error --out build/bench/speed-error
	$(BIN)/sim-tactile bench stability

clean:
	rm -rf $(VENV) build demo-out .pytest_cache .ruff_cache
