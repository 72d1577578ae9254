# Two entry points for a fresh machine: `make demo` and `make test`.
# Both create .venv and install gliderplan into it; `test` also installs the system
# packages the C runtime tests need (cross compilers, qemu-user, valgrind, libFuzzer);
# under CI=true it fails when one cannot be installed.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint sysdeps mutants clean lock

# Installs are reproducible: every package at the version constraints.txt pins (`make
# lock` updates it on purpose).
$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -c constraints.txt -e '.[test]'
	touch $@

# A fresh resolve of pyproject.toml's ranges into constraints.txt, in a scratch venv;
# then `make clean test` and commit both.
LOCK_VENV := .venv-lock
lock:
	rm -rf $(LOCK_VENV)
	$(PYTHON) -m venv $(LOCK_VENV)
	$(LOCK_VENV)/bin/pip install --quiet --upgrade pip
	$(LOCK_VENV)/bin/pip install --quiet -e '.[test]'
	{ sed -n '/^#/p' constraints.txt; $(LOCK_VENV)/bin/pip freeze --exclude-editable; } \
		> constraints.txt.new
	mv constraints.txt.new constraints.txt
	rm -rf $(LOCK_VENV)

# The whole pipeline on the built-in examples: check, plan under the battery budget,
# compile mission and plan to C, fly them on the simulated glider over a
# pseudo-terminal, sweep the survey's quality against its budget, forecast a month's
# survey by device, and write the tradeoff report of the annotated Fig. 2 mission; then
# plan, fly and report the example fleet of five gliders.
DEMO := out/demo
GP := $(BIN)/gliderplan
demo: $(STAMP)
	$(GP) check examples/*.mission
	$(GP) plan examples/fig2_annotated.mission -o $(DEMO)/fig2.plan
	$(GP) compile examples/fig2_annotated.mission --plan $(DEMO)/fig2.plan -o $(DEMO)/build
	$(GP) sim examples/fig2_annotated.mission --plan $(DEMO)/fig2.plan --runtime c -o $(DEMO)/run
	$(GP) plan examples/thermocline_survey.mission --sweep 20 -o $(DEMO)/sweep
	$(GP) forecast examples/survey_month.mission --duration 30d
	@echo "demo: plan and report in $(DEMO)/fig2.plan{,.json}; binary in $(DEMO)/build;"
	@echo "      flight (trace.csv, summary.json, depth.png, energy.png) in $(DEMO)/run;"
	@echo "      Pareto sweep (pareto.csv, pareto.png, computers.csv, batteries.csv) in $(DEMO)/sweep"
	$(GP) report examples/fig2_annotated.mission --plan $(DEMO)/fig2.plan --run $(DEMO)/run \
		-o $(DEMO)/report
	@echo "report of the annotated Fig. 2 mission (open it in a browser): $(DEMO)/report/report.html"
	$(GP) fleet plan examples/shelf.fleet -o $(DEMO)/fleet/plan
	$(GP) fleet sim examples/shelf.fleet --plan $(DEMO)/fleet/plan -o $(DEMO)/fleet/sim \
		--lose ru28@4d
	$(GP) fleet montecarlo examples/shelf.fleet --plan $(DEMO)/fleet/plan --scenarios 10 \
		-o $(DEMO)/fleet/montecarlo
	@echo "fleet of five gliders on the shelf: plan, missions and map in $(DEMO)/fleet/plan;"
	@echo "      one flight per glider (and ru28 lost after 4 d) in $(DEMO)/fleet/sim;"
	@echo "      10 scenarios in $(DEMO)/fleet/montecarlo; each has its fleet.html page"

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
