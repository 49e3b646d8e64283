# ftkin: `make demo` and `make test` work on a fresh machine.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo test install lint docs bench fuzz soak clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(STAMP): $(PY) pyproject.toml
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/ftkin demo

test: $(STAMP)
	bash scripts/install-system-deps.sh
	$(VENV)/bin/lint-imports
	$(MAKE) docs
	$(PY) -m pytest -q
	$(PY) benchmarks/fuzz_readers.py --seconds 20

lint: $(STAMP)
	$(VENV)/bin/ruff format --check ftkin tests benchmarks docs scripts
	$(VENV)/bin/ruff check ftkin tests benchmarks docs scripts
	$(VENV)/bin/lint-imports

docs: $(STAMP)
	$(VENV)/bin/sphinx-build -W --keep-going -q -b html docs docs/_build/html

bench: $(STAMP)
	for script in benchmarks/bench_*.py; do echo "== $$script"; $(PY) $$script || exit 1; done

fuzz: $(STAMP)
	$(PY) benchmarks/fuzz_readers.py --seconds $${FUZZ_SECONDS:-60}

soak: $(STAMP)
	$(PY) benchmarks/soak_control.py
	$(PY) benchmarks/soak_mujoco_stability.py

clean:
	rm -rf $(VENV) build dist *.egg-info .pytest_cache docs/_build
