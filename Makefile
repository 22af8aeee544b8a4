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
# bundled signals (the paper's example S1/S2 and a path through the demonstrated regions).
run: $(STAMP)
	@echo "stlopt main job: the optimiser is not built yet, so this evaluates the bundled" >&2
	@echo "specifications (specs/) on the bundled signals (examples/)." >&2
	@for case in "example s1" "example s2" "phi1 three_regions" "phi2 three_regions"; do \
	  set -- $$case; \
	  for semantics in classic new; do \
	    printf '%-8s %-14s %-8s ' "$$1" "$$2" "$$semantics"; \
	    $(BIN)/stlopt robustness specs/$$1.stl examples/$$2.csv --semantics $$semantics 2>&1 | paste -sd' ' || exit 1; \
	  done; \
	done
	@echo "Specs are in specs/, signals in examples/; see README.md for the language." >&2

test: $(STAMP)
	$(BIN)/python -m pytest -q

test-fast: $(STAMP)
	$(BIN)/python -m pytest -q -m "not slow"

bench: $(STAMP)
	$(BIN)/python -m benchmarks

clean:
	rm -rf $(VENV) runs .pytest_cache .hypothesis
