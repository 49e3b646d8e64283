# ftkin: `make demo` and `make test` work on a fresh machine.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo demo-robot test install lint docs docs-test docs-images bench fuzz soak clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(STAMP): $(PY) pyproject.toml
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

install: $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/ftkin demo

demo-robot: $(STAMP)
	$(VENV)/bin/ftkin robot demo

# pytest last, so that its summary closes the output.
test: $(STAMP)
	bash scripts/install-system-deps.sh
	$(MAKE) lint
	$(MAKE) docs
	$(PY) benchmarks/fuzz_readers.py --seconds 20
	$(PY) -m pytest -q --durations=25

lint: $(STAMP)
	$(VENV)/bin/ruff format --check ftkin tests benchmarks docs scripts conftest.py
	$(VENV)/bin/ruff check ftkin tests benchmarks docs scripts conftest.py
	$(VENV)/bin/lint-imports

docs: $(STAMP)
	$(VENV)/bin/sphinx-build -W --keep-going -q -b html docs docs/_build/html

# Each script exits 1 when a target row fails; make bench stops there. Outputs are recorded in
# benchmarks/results/<script>.txt (date, machine, load), which the docs quote.
bench: $(STAMP)
	for script in benchmarks/bench_*.py; do echo "== $$script"; FTKIN_BENCH_RECORD=1 $(PY) $$script || exit 1; done

# The docs' code blocks alone, the slow ones (browser, live server) included.
docs-test: $(STAMP)
	FTKIN_DOCS_SLOW=1 $(PY) -m pytest -q -p no:cacheprovider README.md docs tests/test_docs_reference.py

# Regenerate docs/images with the code their captions name.
docs-images: $(STAMP)
	PYTHONPATH=. $(PY) scripts/docs_images.py

fuzz: $(STAMP)
	$(PY) benchmarks/fuzz_readers.py --seconds $${FUZZ_SECONDS:-60}

soak: $(STAMP)
	$(PY) benchmarks/soak_control.py
	$(PY) benchmarks/soak_mujoco_stability.py

clean:
	rm -rf $(VENV) build dist *.egg-info .pytest_cache docs/_build
