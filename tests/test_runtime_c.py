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


def _listed() -> list[str]:
    """The tests the runner runs: its TESTS list."""
    return re.findall(r"^\s+X\((test_\w+)\)", (RUNTIME / "tests" / "run_tests.c").read_text(),
                      re.MULTILINE)


def _assert_all_passed(output: str) -> None:
    """The runner's summary says every listed test ran and passed."""
    match = re.search(r"^(\d+) passed, (\d+) failed$", output, re.MULTILINE)
    assert match, output[-2000:]
    assert (int(match[1]), int(match[2])) == (len(_listed()), 0), output[-4000:]


def test_the_runner_lists_every_c_unit_test_once():
    """A test written but left out of the runner's list would never run."""
    defined = {name for source in (RUNTIME / "tests").glob("test_*.c")
               for name in re.findall(r"^void (test_\w+)\(void\)", source.read_text(),
                                      re.MULTILINE)}
    listed = _listed()
    assert len(listed) == len(set(listed))
    assert set(listed) == defined


def test_c_unit_tests_pass(tmp_path):
    _assert_all_passed(_make("test", BUILD=str(tmp_path / "build"), CC="gcc"))


def test_c_unit_tests_pass_under_sanitizers(tmp_path):
    output = _make("sanitize", SANITIZE_BUILD=str(tmp_path / "build-sanitize"), CC="gcc")
    _assert_all_passed(output)
    assert "runtime error" not in output and "AddressSanitizer" not in output


@pytest.mark.parametrize("target", ["ts7800", "ts5500"])
def test_c_unit_tests_pass_on_the_boards_cpu_models(tmp_path, target, board_runner):
    emulator = board_runner(target)
    board = TARGETS[target]
    output = _make("test", BUILD=str(tmp_path / "build"), CC=board.compiler,
                   CFLAGS=" ".join(board.flags), RUN=" ".join(emulator))
    _assert_all_passed(output)
