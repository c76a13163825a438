# Two commands on a fresh machine: `make demo` (ddgjax verify --quick) and `make test` (see README).
PYTHON ?= python3.11
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo examples test test-all bench docs clean

$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null 2>&1 || { echo "need $(PYTHON) on PATH (or make PYTHON=python3)"; exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	@touch $(STAMP)

# the main job: every implemented statement of the reference, checked; report/report.md
demo: $(STAMP)
	$(VENV)/bin/ddgjax verify --quick --out report/

examples: $(STAMP)
	for script in examples/[!_]*.py; do echo "== $$script"; $(PY) $$script --out report/examples || exit 1; done

# one pytest worker per core (pytest-xdist); the longest modules first (tests/conftest.py), and a
# worker that runs out of tests takes half of the other's queue (worksteal)
test: $(STAMP)
	$(PY) -m pytest -q -n auto --dist worksteal

test-all: $(STAMP)
	$(PY) -m pytest -q -m ''

$(VENV)/.docs-installed: $(STAMP)
	$(PY) -m pip install --quiet -e '.[docs]'
	@touch $@

# the documentation site (mkdocs.yml, docs/) into site/, offline; warnings are errors
docs: $(VENV)/.docs-installed
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict

bench: $(STAMP)
	$(VENV)/bin/ddgjax bench

clean:
	rm -rf $(VENV) build site *.egg-info .pytest_cache
