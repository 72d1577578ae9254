# Two entry points for a fresh machine: `make demo` and `make test`.
# Both create .venv and install gliderplan into it; `test` also installs the system
# packages the C runtime tests need (cross compilers, qemu-user, valgrind) when it can.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test lint sysdeps clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $@

# The whole pipeline on the built-in examples: check, plan under the battery budget,
# compile mission and plan to C, fly them on the simulated glider over a
# pseudo-terminal, and sweep the survey's quality against its budget.
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

lint: $(STAMP)
	$(BIN)/ruff check .

test: $(STAMP) lint sysdeps
	$(BIN)/python -m pytest -q

# Toolchains for the TS-7800 (ARMv5TE) and TS-5500 (i486) builds, qemu-user to run
# them, valgrind for the runtime bench. Installed when we may (root or sudo); tests
# that need a missing one say so and are reported as skipped.
SYSDEPS := gcc-arm-linux-gnueabi libc6-dev-armel-cross gcc-i686-linux-gnu \
	libc6-dev-i386-cross qemu-user valgrind
sysdeps:
	@missing=$$(for p in $(SYSDEPS); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -z "$$missing" ]; then exit 0; fi; \
	if [ "$$(id -u)" = 0 ]; then SUDO=; elif command -v sudo >/dev/null; then SUDO="sudo -n"; \
	else echo "sysdeps: cannot install $$missing (not root)"; exit 0; fi; \
	$$SUDO apt-get update -qq && $$SUDO env DEBIAN_FRONTEND=noninteractive \
		apt-get install -y -qq --no-install-recommends $$missing >/dev/null \
		|| echo "sysdeps: could not install $$missing"

clean:
	rm -rf $(VENV) out
