# Two-command quick start: `make demo` and `make test` each set up .venv on a fresh machine.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test verify bench clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test]"
	touch $(STAMP)

demo: $(STAMP)
	$(PY) -m mlsgalerkin.cli run gravity_current --dx 0.004 --out results/demo --overwrite

test: $(STAMP)
	$(PY) -m pytest -q -m "not slow"

verify: $(STAMP)
	$(PY) -m pytest -q -m slow || test $$? -eq 5  # 5: no test is marked slow yet
	$(PY) verification/kernel_study.py --out verification/results/kernel_study
	OPENBLAS_NUM_THREADS=1 $(PY) verification/galerkin_convergence.py --out verification/results/galerkin_convergence
	$(PY) verification/fluid_validation.py --out verification/results/fluid_validation
	$(PY) verification/fluid_core.py --section all --out verification/results/fluid_core
	$(PY) verification/structure_validation.py --section all --out verification/results/structure
	$(PY) verification/volume_attribution.py --out verification/results/volume_consistency
	$(PY) verification/wave_absorption.py --out verification/results/wave_absorption
	$(PY) verification/sloshing_energy.py --out verification/results/volume_consistency

bench: $(STAMP)
	$(PY) benchmarks/run_all.py

clean:
	rm -rf $(VENV) results .pytest_cache
