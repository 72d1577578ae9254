"""The C runtime's unit tests (runtime/tests): plain, under ASan + UBSan, and on the
boards' own CPU models under qemu-user."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from gliderplan.runtime.build import TARGETS

RUNTIME = Path(__file__).resolve().parents[1] / "runtime"

pytestmark = pytest.mark.skipif(
    shutil.which("gcc") is None or shutil.which("make") is None,
    reason="gcc and make are needed to build the C runtime (apt-get install gcc make)",
)


def _make(target: str, **variables: str) -> str:
    result = subprocess.run(
        ["make", "-C", str(RUNTIME), target, *(f"{k}={v}" for k, v in variables.items())],
        capture_output=True, text=True, timeout=600,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, output[-4000:]
    return output


def _summary(output: str) -> tuple[int, int]:
    match = re.search(r"^(\d+) passed, (\d+) failed$", output, re.MULTILINE)
    assert match, output[-2000:]
    return int(match[1]), int(match[2])


def test_c_unit_tests_pass(tmp_path):
    passed, failed = _summary(_make("test", BUILD=str(tmp_path / "build"), CC="gcc"))
    assert failed == 0 and passed >= 40


def test_c_unit_tests_pass_under_sanitizers(tmp_path):
    output = _make("sanitize", SANITIZE_BUILD=str(tmp_path / "build-sanitize"), CC="gcc")
    passed, failed = _summary(output)
    assert failed == 0 and passed >= 40
    assert "runtime error" not in output and "AddressSanitizer" not in output


@pytest.mark.parametrize("target", ["ts7800", "ts5500"])
def test_c_unit_tests_pass_on_the_boards_cpu_models(tmp_path, target, board_runner):
    emulator = board_runner(target)
    board = TARGETS[target]
    output = _make("test", BUILD=str(tmp_path / "build"), CC=board.compiler,
                   CFLAGS=" ".join(board.flags), RUN=" ".join(emulator))
    passed, failed = _summary(output)
    assert failed == 0 and passed >= 40
