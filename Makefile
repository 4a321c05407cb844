# Two commands a newcomer needs: `make run` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# `make run` benchmarks three presets into OUT/<preset>/ and writes one report comparing them:
# paper (the study's what-if: glucose's optical effect x11 and five device capabilities),
# wearable (a basic wearable, x12.5) and physical (published magnitudes, x1)
PRESET ?= paper,wearable,physical
SEED   ?= 0
OUT    ?= results
# make run's protocol: subject-grouped 5-fold CV with ONE repeat, the same folds for every
# model and preset (`nirglucose benchmark`'s default is 3 repeats: REPEATS=3 runs it, about
# 3 x the fitting time, past the 3-minute budget on 2 cores); the report's run line says so
REPEATS ?= 1
# every registered model but the two GP hybrids (ebl+gp, physics-inversion+gp: each fit is
# several backbone fits and a GP, 2.5 min more on 2 cores; studies/physics_inversion.py
# runs them) and the forward-model PINNs (original-pinn-fm, optimized-pinn-fm, rte-pinn-fm,
# selective-rte-pinn-fm: a physics-inversion fit per task; studies/pinn_forward.py
# runs them);
# tests/test_makefile.py keeps this list equal to the registry minus those
MODELS ?= ebl,pls,oracle,physics-inversion,device-inversion,original-pinn,optimized-pinn,rte-pinn,selective-rte-pinn,sdnn,mean,gp,gbr
# on physical a smaller set (to stay within the budget): the references (no skill, the
# GP, gradient boosting), the linear models, the deployable forward-model inversion, the
# privileged references (oracle, physics-inversion) and the study's best PINN; the
# metrics of OUT/physical/ list what ran (tests/test_makefile.py keeps it inside MODELS)
PHYSICAL_MODELS ?= mean,ebl,pls,gp,gbr,device-inversion,oracle,physics-inversion,original-pinn
comma := ,
# passed only when PRESET has physical (PRESET=paper runs MODELS alone)
PRESET_MODELS = $(if $(filter physical,$(subst $(comma), ,$(PRESET))),--preset-models physical=$(PHYSICAL_MODELS))

.PHONY: run test test-slow install lint bench docs clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

$(STAMP): $(BIN)/python pyproject.toml requirements.lock
	$(BIN)/python -m pip install -q -c requirements.lock -e ".[dev]"
	$(BIN)/python -m nirglucose.simulation.kernels  # numba's cache, as pip's .pyc files
	touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(BIN)/nirglucose benchmark --preset $(PRESET) --seed $(SEED) --out $(OUT) --jobs 2 \
		--repeats $(REPEATS) --models $(MODELS) $(PRESET_MODELS)
	$(BIN)/nirglucose report $(OUT) --out $(OUT)/report.html --jobs 2
	@echo "report: $(abspath $(OUT))/report.html"

# worksteal: an idle worker takes tests from the other's queue, so the last slow file does
# not run alone. `make test` is the fast suite (budget: 4 minutes on 2 cores); the tests
# marked `slow` (whole studies, end-to-end runs, Monte Carlo checks) run in `make test-slow`,
# which CI runs too (.ci/run): nothing is skipped, only scheduled apart.
test: $(STAMP)
	$(BIN)/python -m pytest -q -n 2 --dist worksteal -m "not slow"

test-slow: $(STAMP)
	$(BIN)/python -m pytest -q -n 2 --dist worksteal -m slow

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks studies tools validation

# the speed checks only (each prints one JSON object on its last line); the research
# scripts are in studies/ and the tools that write package data in tools/
bench: $(STAMP)
	for b in benchmarks/*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

# the documentation site: installs the docs extra into the same .venv, warnings are errors
DOCS_STAMP := $(VENV)/.installed-docs

$(DOCS_STAMP): $(STAMP) pyproject.toml requirements.lock
	$(BIN)/python -m pip install -q -c requirements.lock -e ".[dev,docs]"
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	MPLBACKEND=agg $(BIN)/python -m sphinx -W --keep-going -b html docs docs/_build/html
	@echo "docs: $(abspath docs/_build/html)/index.html"

clean:
	rm -rf $(VENV) results .pytest_cache build src/*.egg-info docs/_build docs/_generated docs/generated docs/auto_examples
