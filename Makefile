# Two entry points: `make run` (default scenario) and `make test`.
# Both create .venv and install the project into it on first use.
PYTHON ?= python3
VENV := .venv
STAMP := $(VENV)/.installed

.PHONY: run test lint clean clean-cache

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/python -m pip install --quiet --upgrade pip
	$(VENV)/bin/python -m pip install --quiet -e '.[test,dev]'
	touch $(STAMP)

run: $(STAMP)
	$(VENV)/bin/sins run

test: $(STAMP)
	$(VENV)/bin/python -m pytest -q

lint: $(STAMP)
	$(VENV)/bin/ruff check sins tests tools
	$(VENV)/bin/ruff format --check sins tests tools
	$(VENV)/bin/mypy

clean:
	rm -rf $(VENV) build *.egg-info

# numba caches a kernel against its own file only; run this after editing a module a kernel inlines.
clean-cache:
	find sins -name '*.nbi' -delete -o -name '*.nbc' -delete
