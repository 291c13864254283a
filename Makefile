# Everything a fresh machine needs: `make run` (main job) and `make test` (test suite).
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: run test test-quick lint bench compile notebooks docs docs-snapshots clean-venv

## The package is installed editable, so Python compiles its modules from source on every
## start unless their bytecode is cached; with PYTHONDONTWRITEBYTECODE set (as on this
## machine) it never is, which cost a short command ~0.1 s of CPU. pip compiles the
## dependencies at install; `compile` does the same for pipeline/ (only changed modules;
## __pycache__ is git-ignored, and a stale .pyc is ignored by Python, never used).
## The install says what it does (it takes minutes on a fresh machine): a line per step, and
## pip's own line per package it collects and installs.
$(STAMP): requirements.txt pyproject.toml
	@echo "[1/4] creating the virtual environment $(VENV) with $(PYTHON)"
	$(PYTHON) -m venv $(VENV)
	@echo "[2/4] installing the pinned requirements (requirements.txt; several minutes on a fresh machine)"
	$(PY) -m pip install --progress-bar on -r requirements.txt
	@echo "[3/4] installing spindlebench itself (editable)"
	$(PY) -m pip install --quiet --no-deps -e .
	@echo "[4/4] compiling the package's modules"
	$(PY) -m compileall -q pipeline
	touch $(STAMP)
	@echo "installed into $(VENV)"

compile: $(STAMP)
	$(PY) -m compileall -q pipeline

## Main job on the embedded default: build the FMU from models/, simulate the paper's five
## experiments, run the selection comparison on them and on the real recording.
run: $(STAMP)
	$(VENV)/bin/spindlebench demo --out results

## The suite on every core (pytest-xdist), in a temporary folder of its own (--basetemp): the
## shared /tmp/pytest-of-USER numbering is cleaned by every pytest run on the machine, and a
## worker's folder vanished under a notebook test once (pytest-dev/pytest#5456, #5524). `--dist loadfile` keeps each test module on one
## worker, so a module-scoped fixture (an FMU build, a simulated study) is made once; the
## slowest modules are collected first (tests/conftest.py: SLOW_FIRST) and start at once.
test: $(STAMP)
	$(VENV)/bin/ruff check pipeline tests bench
	$(PY) -m pytest -n auto --dist loadfile --no-loadscope-reorder --basetemp="$$(mktemp -d -t spindlebench-tests-XXXXXX)"

## The short loop: every test but the `slow` ones (marked in the test files and, for modules
## others edit, in tests/conftest.py), on every core. `make test` still runs everything.
test-quick: $(STAMP)
	$(PY) -m pytest -m "not slow" -n auto

## The course: execute every notebook in notebooks/ and write it as HTML with its outputs.
notebooks: $(STAMP)
	$(PY) -m spindlebench.commands.course results/notebooks

## The documentation site (mkdocs, Material): the course executed first so its pages show the
## outputs; generated pages come from the code (docs/hooks/generate.py). Open
## results/site/index.html (no server needed).
docs: notebooks
	test -f results/README.md || $(MAKE) run
	SPINDLEBENCH_DOCS_RUN=1 NO_MKDOCS_2_WARNING=1 $(PY) -m mkdocs build --strict --quiet

## After a model change and a rerun (make run, the studies of docs/validation.md, `python -m
## spindlebench.model.discretisation --out results/discretisation/discretisation.json`,
## `python -m spindlebench.model.cold_start --json results/cold_start/cold_start.json`, the
## benchmark run docs/benchmark.md names, the evaluate runs of docs/hooks/tables.py's
## EVALUATE_RUNS): copy the files the docs' tables read from results/ to their committed
## copies in docs/snapshots/ (what a checkout without results/ shows), only those that
## results/ has.
SNAPSHOT_FILES := README.md table6_rmse.csv provenance.json
docs-snapshots:
	for study in paper_study caiviac_study caiviac_cycle_study ambient_following_study \
	    caiviac_methods; do \
	  for f in $(SNAPSHOT_FILES); do test ! -f results/$$study/$$f || \
	    { mkdir -p docs/snapshots/$$study && cp results/$$study/$$f docs/snapshots/$$study/; }; \
	  done; done
	for run in results/caiviac_sensitivity/*/train_*; do test -d $$run || continue; \
	  dest=docs/snapshots/$${run#results/}; mkdir -p $$dest; \
	  cp $$run/table6_rmse.csv $$run/provenance.json $$dest/; done
	if ls results/fingerprint/*.json >/dev/null 2>&1; then mkdir -p docs/snapshots/fingerprint && \
	  cp results/fingerprint/*.json docs/snapshots/fingerprint/; fi
	if ls results/twin/*.json >/dev/null 2>&1; then mkdir -p docs/snapshots/twin && \
	  cp results/twin/*.json docs/snapshots/twin/; fi
	for run in results/caiviac_identification/*/caiviac.json; do test -f $$run || continue; \
	  dest=docs/snapshots/$$(dirname $${run#results/}); mkdir -p $$dest; cp $$run $$dest/; done
	for sweep in season-sweep season-sweep-methods af-sweep; do \
	  test -f results/$$sweep/summary/by_method.csv || continue; \
	  mkdir -p docs/snapshots/$$sweep/summary; \
	  cp results/$$sweep/summary/by_method.csv docs/snapshots/$$sweep/summary/; \
	  cp results/$$sweep/README.md results/$$sweep/provenance.json docs/snapshots/$$sweep/; done
	for place in placement af-placement placement-methods; do test -f results/$$place/placements.csv || continue; \
	  mkdir -p docs/snapshots/$$place; \
	  cp results/$$place/placements.csv results/$$place/README.md \
	    results/$$place/provenance.json docs/snapshots/$$place/; done
	for month in compensate-month compensate-month-cold; do \
	  test -f results/$$month/summary.csv || continue; mkdir -p docs/snapshots/$$month; \
	  cp results/$$month/summary.csv results/$$month/README.md \
	    results/$$month/provenance.json docs/snapshots/$$month/; done
	if test -f results/tiny-compensate-five-probe/README.md; then \
	  mkdir -p docs/snapshots/tiny-compensate-five-probe/drift_um; \
	  cp results/tiny-compensate-five-probe/README.md docs/snapshots/tiny-compensate-five-probe/; \
	  cp results/tiny-compensate-five-probe/drift_um/provenance.json \
	    docs/snapshots/tiny-compensate-five-probe/drift_um/; fi
	for report in spindle caiviac_spindle; do test -f results/iso230-3/$$report/spindle.json || \
	  continue; mkdir -p docs/snapshots/iso230-3/$$report; \
	  cp results/iso230-3/$$report/spindle.json docs/snapshots/iso230-3/$$report/; done
	for test in etve spectrum axis; do test -f results/iso230-3/$$test/$$test.json || continue; \
	  mkdir -p docs/snapshots/iso230-3/$$test; \
	  cp results/iso230-3/$$test/$$test.json docs/snapshots/iso230-3/$$test/; done
	if test -f results/caiviac_calibration/caiviac_calibration.json; then \
	  mkdir -p docs/snapshots/caiviac_calibration; cp \
	  results/caiviac_calibration/caiviac_calibration.json docs/snapshots/caiviac_calibration/; fi
	for evaluation in caiviac_targets_raw caiviac_targets_diff probes_targets_raw \
	    probes_targets_diff; do \
	  test -f results/iso230-3/$$evaluation.json || continue; mkdir -p docs/snapshots/iso230-3; \
	  cp results/iso230-3/$$evaluation.json docs/snapshots/iso230-3/; done
	for file in discretisation/discretisation.json cold_start/cold_start.json \
	    benchmark/mine/leaderboard.json caiviac-six-correlated/k2.json \
	    caiviac-six-correlated/k3.json; do \
	  test -f results/$$file || continue; mkdir -p docs/snapshots/$$(dirname $$file); \
	  cp results/$$file docs/snapshots/$$file; done

bench: compile
	for script in bench/*.py; do $(PY) $$script || exit 1; done

clean-venv:
	rm -rf $(VENV)
