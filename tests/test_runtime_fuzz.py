"""The C runtime's input readers under libFuzzer with ASan and UBSan (runtime/fuzz).

The frame decoder, the plan reader, the command line and the plan-update applier each
run for FUZZ_SECONDS from their committed corpus (40 s under CI=true: under three minutes
in all; 15 s elsewhere, or
GLIDERPLAN_FUZZ_SECONDS), and every committed input, the crashes found so far among
them, is replayed as a regression test.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest
from conftest import running_in_ci

RUNTIME = Path(__file__).resolve().parents[1] / "runtime"
FUZZERS = ("frame", "plan", "args", "update")
FUZZ_SECONDS = int(os.environ.get("GLIDERPLAN_FUZZ_SECONDS", 40 if running_in_ci() else 15))


@pytest.fixture(scope="module")
def libfuzzer(tmp_path_factory) -> None:
    """Skips unless clang links a libFuzzer program with the sanitizers."""
    if shutil.which("clang") is None or shutil.which("make") is None:
        pytest.skip("clang and make are needed for the fuzz tests (make sysdeps)")
    probe = tmp_path_factory.mktemp("probe") / "probe.c"
    probe.write_text("#include <stddef.h>\n#include <stdint.h>\n"
                     "int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n)"
                     " { (void)d; (void)n; return 0; }\n")
    done = subprocess.run(["clang", "-fsanitize=fuzzer,address,undefined", str(probe), "-o",
                           str(probe.with_suffix(""))], capture_output=True, text=True)
    if done.returncode != 0:
        pytest.skip(f"clang cannot link a libFuzzer program (make sysdeps installs "
                    f"libclang-rt-dev): {done.stderr.strip()[-200:]}")


def _make(target: str, build: Path, **variables: str) -> str:
    done = subprocess.run(["make", "-C", str(RUNTIME), target, f"FUZZ_BUILD={build}",
                           *(f"{k}={v}" for k, v in variables.items())],
                          capture_output=True, text=True, timeout=1200)
    output = done.stdout + done.stderr
    crashes = sorted(p.name for p in build.glob("crash-*"))
    assert done.returncode == 0, f"{crashes} in {build}:\n{output[-6000:]}"
    return output


def test_every_committed_fuzz_input_is_read_without_a_crash(libfuzzer, tmp_path):
    output = _make("fuzz-replay", tmp_path)
    committed = [p for name in FUZZERS for p in (RUNTIME / "fuzz" / "corpus" / name).iterdir()]
    assert any(p.name.startswith("crash-") for p in committed)
    assert output.count("Running: ") == len(committed)
    assert "ERROR" not in output and "runtime error" not in output


def test_the_fuzzers_find_no_crash(libfuzzer, tmp_path):
    output = _make("fuzz", tmp_path, FUZZ_SECONDS=str(FUZZ_SECONDS))
    runs = [int(n) for n in re.findall(r"stat::number_of_executed_units: (\d+)", output)]
    assert len(runs) == len(FUZZERS), output[-3000:]
    assert min(runs) > 10_000  # each harness really ran, past its seeds
    assert "runtime error" not in output
