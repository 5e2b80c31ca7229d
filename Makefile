# Two entry points: `make run` (default scenario) and `make test` (lint and the tests; CI runs it).
# Both create .venv and install the project into it on first use.
PYTHON ?= python3
VENV := .venv
STAMP := $(VENV)/.installed

.PHONY: run test lint docs clean clean-cache

# Quiet: one line says what happens; pip's -qq keeps its errors and drops its notices and warnings (a
# machine's pip configuration may name index folders it lacks, one warning per package looked up).
$(STAMP): pyproject.toml
	@echo "installing sins and its dependencies into $(VENV) (first use: a minute or two)"
	@$(PYTHON) -m venv $(VENV)
	@$(VENV)/bin/python -m pip install -qq --upgrade pip
	@$(VENV)/bin/python -m pip install -qq -e '.[test,dev]'
	@touch $(STAMP)

run: $(STAMP)
	@$(VENV)/bin/sins run

# Both cores: test files are dealt to two workers whole (a file's module fixtures are built once). One
# BLAS/OpenMP thread per worker: a pool per worker beside torch's oversubscribed the two cores and made
# the gap diagnosis four times slower (2.0 s -> 8.1 s a case). No CPU kernels pinned: the quality gate
# judges its figures over seeds, so a network that another machine's kernels train differently is a
# draw within the seeds' spread, not a regression (docs/development.md, "CPU kernels").
# The suite runs as four pytest sessions, each on fresh workers: a worker keeps what it has imported and
# allocated (torch, numba's compiled code, the allocators' high-water marks), so one that ran a share of
# every file climbed to 1.2-1.7 GB (docs/speed.md, "The test suite"). First the three files that train
# networks on rigs, one worker each (the same wall time as two workers, and no worker runs two of them),
# then the other files in three parts by name (test_gap.py, the longest file, takes one worker of the
# g-r part while the other runs the rest of it). The a-f part runs three workers on the two cores: its
# campaigns and examples wait on processes they start (dask's workers, a subprocess's interpreter), and
# a third worker fills the core a waiting one leaves (the two cores 194 % busy against 187 % with two
# workers, run after run on one tree; the g-r part was busier with two, 193 % against 182 %).
# Every session runs even when one fails; make fails after.
# Within a session the longest files go first (LONG_TESTS, longest first, from --durations), dealt
# in that order (--no-loadscope-reorder: xdist's own order is by the number of tests in a file, which
# dealt test_quality.py (93 s, ten tests) and test_tour.py (34 s, two) late, where each ran alone while
# the other worker idled).
HEAVY_TESTS = tests/test_crossrig.py tests/test_learned.py tests/test_compensation.py
LONG_TESTS = tests/test_gap.py tests/test_quality.py tests/test_campaign.py tests/test_campaign_gate.py \
	tests/test_examples.py tests/test_unit_gap_real.py tests/test_unit_gap.py tests/test_characterise.py tests/test_fuzz.py \
	tests/test_tour.py tests/test_campaign_folder.py tests/test_plots.py tests/test_bias.py \
	tests/test_gap_independent.py tests/test_vocabulary.py
longest_first = $(filter $(1),$(LONG_TESTS)) $(filter-out $(LONG_TESTS),$(1))
PART_1 = $(call longest_first,$(filter-out $(HEAVY_TESTS),$(wildcard tests/test_[a-f]*.py)))
PART_2 = $(call longest_first,$(filter-out $(HEAVY_TESTS),$(wildcard tests/test_[g-r]*.py)))
PART_3 = $(call longest_first,$(filter-out $(HEAVY_TESTS) $(PART_1) $(PART_2),$(wildcard tests/test_*.py)))
PYTEST = OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 \
	$(VENV)/bin/python -m pytest -q --dist loadfile --no-loadscope-reorder --durations=8
# Lint runs beside the first session (mypy, cold, is ~20 s on one core: the core the session leaves
# idle at its end); its output is printed when both are done, and its failure fails make as a session's.
test: $(STAMP)
	@status=0; lint_log=$$(mktemp); \
	echo "lint, beside tests 1/4 (its output follows that session)"; \
	$(MAKE) --no-print-directory lint > $$lint_log 2>&1 & lint_pid=$$!; \
	echo "tests 1/4: the files that train networks on rigs"; $(PYTEST) -n 3 $(HEAVY_TESTS) || status=1; \
	wait $$lint_pid || status=1; cat $$lint_log; rm -f $$lint_log; \
	echo "tests 2/4: test_a* to test_f*"; $(PYTEST) -n 3 $(PART_1) || status=1; \
	echo "tests 3/4: test_g* to test_r*"; $(PYTEST) -n 2 $(PART_2) || status=1; \
	echo "tests 4/4: test_s* to test_z*"; $(PYTEST) -n 2 $(PART_3) || status=1; \
	exit $$status

lint: $(STAMP)
	$(VENV)/bin/ruff check sins tests tools examples
	$(VENV)/bin/ruff format --check sins tests tools examples
	$(VENV)/bin/mypy

docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict --site-dir site

clean:
	rm -rf $(VENV) build site *.egg-info

# numba caches a kernel against its own file only; run this after editing a module a kernel inlines.
clean-cache:
	find sins -name '*.nbi' -delete -o -name '*.nbc' -delete
