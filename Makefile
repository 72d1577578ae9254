# Two entry points for a fresh machine: `make demo` and `make test`.
# Both create .venv and install gliderplan into it; `test` also installs the system
# packages the C runtime tests need (cross compilers, qemu-user, valgrind, libFuzzer);
# under CI=true it fails when one cannot be installed.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint sysdeps mutants clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $@

# The whole pipeline on the built-in examples: check, plan under the battery budget,
# compile mission and plan to C, fly them on the simulated glider over a
# pseudo-terminal, sweep the survey's quality against its budget, and write the
# tradeoff report of the annotated Fig. 2 mission.
DEMO := out/demo
GP := $(BIN)/gliderplan
demo: $(STAMP)
	$(GP) check examples/*.mission
	$(GP) plan examples/fig2_annotated.mission -o $(DEMO)/fig2.plan
	$(GP) compile examples/fig2_annotated.mission --plan $(DEMO)/fig2.plan -o $(DEMO)/build
	$(GP) sim examples/fig2_annotated.mission --plan $(DEMO)/fig2.plan --runtime c -o $(DEMO)/run
	$(GP) plan examples/thermocline_survey.mission --sweep 20 -o $(DEMO)/sweep
	@echo "demo: plan and report in $(DEMO)/fig2.plan{,.json}; binary in $(DEMO)/build;"
	@echo "      flight (trace.csv, summary.json, depth.png, energy.png) in $(DEMO)/run;"
	@echo "      Pareto sweep (pareto.csv, pareto.png, computers.csv, batteries.csv) in $(DEMO)/sweep"
	$(GP) report examples/fig2_annotated.mission --plan $(DEMO)/fig2.plan --run $(DEMO)/run \
		-o $(DEMO)/report
	@echo "report of the annotated Fig. 2 mission (open it in a browser): $(DEMO)/report/report.html"

lint: $(STAMP)
	$(BIN)/ruff check .

test: $(STAMP) lint sysdeps
	$(BIN)/python -m pytest -q

# Each listed fault planted in turn in the Python reference and in the C step: one line
# per mutant, `caught` or `survived`; fails if any survived (tests/mutants.py).
mutants: $(STAMP)
	$(BIN)/python tests/mutants.py

# Toolchains for the TS-7800 (ARMv5TE) and TS-5500 (i486) builds, qemu-user to run them
# on the boards' CPU models, valgrind, libFuzzer, musl built for the i486. Under CI=true
# a tool that cannot be installed fails the run, and so does any test that skips.
sysdeps:
	@sh tests/sysdeps.sh

clean:
	rm -rf $(VENV) out
