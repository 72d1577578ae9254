"""Under CI=true a skipped test fails; the boards' CPU models for the tests that run them.

Tests skip only when something outside the project is missing: a cross compiler, qemu,
libFuzzer, the shared Slocum logs. A developer's machine may lack them, and pytest's
summary (-ra) says which tests were skipped and why; CI installs every one of them
(`make test` runs tests/sysdeps.sh), so there a skip means a check that never ran.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable

import pytest


def running_in_ci() -> bool:
    return os.environ.get("CI", "").lower() in ("true", "1")


def modules_loaded_by(argv: list[str]) -> tuple[int, set[str]]:
    """`gliderplan ARGV` in a fresh interpreter: its exit code and the modules it loaded
    (top-level packages, and for gliderplan's own, e.g. `gliderplan.sim`)."""
    probe = ("import sys\n"
             "from gliderplan.cli.main import main\n"
             f"code = main({argv!r})\n"
             "print(code, *sorted(m.split('.')[0] if not m.startswith('gliderplan.') else\n"
             "                    '.'.join(m.split('.')[:2]) for m in set(sys.modules)))\n")
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout, proc.stdout + proc.stderr
    code, *loaded = proc.stdout.splitlines()[-1].split()
    return int(code), set(loaded)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if running_in_ci() and report.skipped and not hasattr(report, "wasxfail"):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome = "failed"
        report.longrepr = f"skipped under CI=true, where every tool must be installed: {reason}"


@pytest.fixture
def board_runner() -> Callable[[str], list[str]]:
    """For a build target, the command prefix that runs its binaries on the board's own CPU
    model (`qemu-i386 -cpu 486`, `qemu-arm -cpu arm926`; nothing for the host). Skips when
    the target's compiler or emulator is not installed."""
    from gliderplan.runtime.build import TARGETS

    def runner(target: str) -> list[str]:
        board = TARGETS[target]
        tools = [board.compiler, *board.emulator[:1]]
        missing = [tool for tool in tools if shutil.which(tool) is None]
        if missing:
            pytest.skip(f"{' and '.join(missing)} not installed (make sysdeps)")
        return list(board.emulator)

    return runner
