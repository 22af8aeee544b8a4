# Set-up and everyday commands. `make run` and `make test` work on a fresh machine with Python 3.11.
PYTHON ?= python3.11
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: run test test-fast bench clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	# torch first and pinned: this version resolves to a CPU build
	$(BIN)/pip install --quiet torch==2.13.0
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

# The main job. Until the optimiser lands it evaluates the bundled specifications on the
# bundled signals, then learns the skill from the bundled demonstrations and evaluates phi1
# and phi2 on its retrieved trajectory (both violated: that is what the optimiser will fix).
RUN_DIR := runs/main

run: $(STAMP)
	@echo "stlopt main job: the optimiser is not built yet; this evaluates the bundled" >&2
	@echo "specifications and learns the skill that the optimiser will adapt." >&2
	@for case in "example s1" "example s2" "phi1 three_regions" "phi2 three_regions"; do \
	  set -- $$case; \
	  for semantics in classic new; do \
	    printf '%-8s %-14s %-8s ' "$$1" "$$2" "$$semantics"; \
	    $(BIN)/stlopt robustness specs/$$1.stl examples/$$2.csv --semantics $$semantics 2>&1 | paste -sd' ' || exit 1; \
	  done; \
	done
	@mkdir -p $(RUN_DIR)
	$(BIN)/stlopt learn demos/three_regions -K 6 -o $(RUN_DIR)/three_regions.npz --plot $(RUN_DIR)/skill.png
	$(BIN)/stlopt retrieve $(RUN_DIR)/three_regions.npz --rate 240 --duration 22 -o $(RUN_DIR)/reference.csv
	@for spec in phi1 phi2; do \
	  printf '%-8s learned skill  new      ' "$$spec"; \
	  $(BIN)/stlopt robustness specs/$$spec.stl $(RUN_DIR)/reference.csv --semantics new 2>&1 | paste -sd' ' || exit 1; \
	done
	@echo "Results are in $(RUN_DIR)/: the model (three_regions.npz), its figure (skill.png) and" >&2
	@echo "its reference trajectory (reference.csv). Specs: specs/; language: README.md." >&2

test: $(STAMP)
	$(BIN)/python -m pytest -q

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow"

bench: $(STAMP)
	$(BIN)/python -m benchmarks

clean:
	rm -rf $(VENV) runs .pytest_cache .hypothesis
