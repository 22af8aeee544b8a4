# Set-up and everyday commands. `make run` and `make test` work on a fresh machine with Python 3.11.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test test-fast browser lint docs bench bench-optim clean

# pip's output goes to $(VENV)/install.log (its tail is shown if it fails). torch comes first and
# pinned: this version resolves to a CPU build.
$(STAMP): pyproject.toml
	@echo "installing stlopt and its dependencies (torch, BoTorch, PyBullet) into $(VENV); a few minutes, once ..."
	@$(PYTHON) -m venv $(VENV) && { \
	  $(BIN)/pip install --upgrade pip && \
	  $(BIN)/pip install torch==2.13.0 && \
	  $(BIN)/pip install -e '.[test]'; } > $(VENV)/install.log 2>&1 || { \
	  tail -n 15 $(VENV)/install.log; echo "installation failed; pip's whole log is in $(VENV)/install.log"; exit 1; }
	@touch $(STAMP)
	@echo "installed; pip's log is in $(VENV)/install.log"

# The main job: learn the skill from the bundled demonstrations and optimise it for phi1 with the
# PyBullet backend (the task's method, 32 trials), printing the robustness before and after, then
# draw the report. `optimize` learns the skill itself (the model is kept in the run directory).
# Running it again continues (or just reports) the same run; `make clean` starts afresh.
RUN_DIR := runs/main

run: $(STAMP)
	@if [ -d $(RUN_DIR)/phi1 ]; then resume=--resume; else resume=; fi; \
	  $(BIN)/stlopt optimize configs/phi1.yaml --out $(RUN_DIR)/phi1 --quiet $$resume > /dev/null
	@$(BIN)/stlopt report $(RUN_DIR)/phi1 > /dev/null
	@echo "watch the best trial: $(BIN)/stlopt replay $(RUN_DIR)/phi1 --video $(RUN_DIR)/phi1-best.mp4"

# Two test processes (one per core), each single-threaded: BLAS and torch threads of two
# processes would otherwise compete for the same two cores. The console examples of each page
# (README, docs/) run in one worker (each follows the examples before it); the other tests are
# handed out one at a time, the longest first (tests/conftest.py), so that both workers stay
# busy to the end. The 20 longest tests are listed at the end.
PYTEST := OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 $(BIN)/python -m pytest -q -n 2 --dist loadgroup --durations=20

test: $(STAMP) lint docs browser
	$(PYTEST)

test-fast: $(STAMP) lint docs
	$(PYTEST) -m "not slow"

# The dashboard's browser test drives Debian's Chromium: installed with apt-get when missing
# (as root, as on CI; otherwise install the package chromium yourself).
browser:
	@command -v chromium > /dev/null || { echo "installing Debian's chromium for the dashboard's browser test ..."; \
	  { apt-get install -y -qq chromium || { apt-get update -qq && apt-get install -y -qq chromium; }; } > /tmp/stlopt-apt.log 2>&1 || { \
	  tail -n 5 /tmp/stlopt-apt.log; echo "could not install chromium: install Debian's package chromium, then run make test again"; exit 1; }; }

lint: $(STAMP)
	$(BIN)/ruff check stl_lfd tests benchmarks examples
	$(BIN)/ruff format --check stl_lfd tests benchmarks examples

# The documentation site (mkdocs.yml, docs/): strict, so a broken link or a docstring the API
# pages cannot render fails the build; offline (no theme fonts or plugins that fetch).
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --quiet --site-dir site

bench: $(STAMP)
	$(BIN)/python -m benchmarks

# The optimiser suite (benchmarks/problems, every method over 10 seeds; hours on 2 cores).
# Optuna is a benchmark extra: it drives the same objective with its default TPE sampler.
# Runs already in benchmarks/results/suite.jsonl are kept; `--table` only prints them.
bench-optim: $(STAMP)
	$(BIN)/pip install --quiet -e '.[bench]'
	$(BIN)/python -m benchmarks.bench_suite --jobs 2

clean:
	rm -rf $(VENV) runs site .pytest_cache .hypothesis
