# Two commands on a fresh machine: `make demo` and `make test`.
# The virtual environment is (re)built only when requirements.lock or pyproject.toml change.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# uv installs the lock in seconds (pip: about a minute); pip is the fallback where uv cannot reach the index.
UV     := $(BIN)/uv pip install --quiet --python $(BIN)/python
PIP    := $(BIN)/python -m pip install --quiet --disable-pip-version-check

.PHONY: demo test docs bench bench-scale bench-smoke notebooks clean

$(STAMP): requirements.lock pyproject.toml
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --disable-pip-version-check "$$(grep '^uv==' requirements.lock)"
	$(UV) -r requirements.lock || $(PIP) -r requirements.lock
	$(UV) --no-deps --no-build-isolation -e . || $(PIP) --no-deps --no-build-isolation -e .
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/hertz-chain demo

test: $(STAMP)
	$(BIN)/python -m pytest -n 2 --dist worksteal -q --durations=20

# The documentation site (mkdocs-material + mkdocstrings) into site/, every warning an error.
docs: $(STAMP)
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict

# Full benchmark suite (~30 min on 2 cores; 29 min on 2026-11-28): writes benchmarks/results.md and the raw JSON.
bench: $(STAMP)
	$(BIN)/python benchmarks/run.py --output benchmarks/results.md --json benchmarks/results.json
	$(BIN)/python benchmarks/optimize.py --output benchmarks/optimize.md
	$(BIN)/python benchmarks/sweep.py --output benchmarks/sweep.md
	$(BIN)/python benchmarks/long_chains.py --output benchmarks/long_chains.md
	$(BIN)/python benchmarks/baselines.py --output benchmarks/baselines.md --json benchmarks/baselines.json
	$(BIN)/python benchmarks/solver_choice.py --output benchmarks/solver_choice.md

# One sweep of 10^6 designs end to end through the CLI (~10 min on 2 cores): benchmarks/sweep_scale.md.
bench-scale: $(STAMP)
	$(BIN)/python benchmarks/sweep_scale.py --output benchmarks/sweep_scale.md

# A one-minute smoke run (n = 2, one regime) into out/; CI runs the same through tests/test_benchmarks_smoke.py.
bench-smoke: $(STAMP)
	$(BIN)/python benchmarks/run.py --quick --output out/bench-smoke.md --json out/bench-smoke.json

# Execute every notebook (full grids) into out/notebooks/*.ipynb, with outputs and figures.
notebooks: $(STAMP)
	$(BIN)/python notebooks/execute.py --force

clean:
	rm -rf $(VENV) build site *.egg-info
