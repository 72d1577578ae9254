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

demo: $(STAMP)
	$(BIN)/gliderplan check examples/*.mission

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
