"""tests/sysdeps.sh, which `make test` runs first, against a scripted package manager.

CI once went green with its cross-compiler and qemu tests skipped: another package
manager held apt's lock, the install gave up ("sysdeps: could not install ...") and the
run went on. Now a held lock is waited for, and under CI=true a tool that cannot be
installed fails the run. Here dpkg, apt-get, id and sleep are stand-ins on PATH, so
no package is installed and no time is spent waiting.
"""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

SYSDEPS = Path(__file__).resolve().parent / "sysdeps.sh"
LOCKED = ("E: Could not get lock /var/lib/apt/lists/lock. It is held by process 4242 "
          "(apt-get)\nE: Unable to lock directory /var/lib/apt/lists/")

STAND_INS = {
    # every package is installed but those named in $MISSING
    "dpkg": 'for p in $MISSING; do [ "$2" = "$p" ] && exit 1; done; exit 0',
    # the lock is held for the first $LOCKED_CALLS calls (-1: for ever)
    "apt-get": f"""echo "$*" >> "$CALLS"
n=$(wc -l < "$CALLS")
if [ "$LOCKED_CALLS" -lt 0 ] || [ "$n" -le "$LOCKED_CALLS" ]; then
    printf '%s\\n' "{LOCKED}" >&2; exit 100
fi""",
    "id": "echo 0",  # root: no sudo needed
    "sleep": 'echo "$1" >> "$SLEPT"',
    "i486-linux-musl-gcc": "exit 0",
}


def sysdeps(tmp_path: Path, *, missing: str, locked_calls: int, ci: bool,
            lock_wait_s: int = 900) -> tuple[subprocess.CompletedProcess, list[str], int]:
    """Run sysdeps.sh with the stand-ins: its result, apt-get's calls, the seconds slept."""
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name, body in STAND_INS.items():
        (bin_dir / name).write_text(f"#!/bin/sh\n{body}\n")
        (bin_dir / name).chmod(0o755)
    musl = tmp_path / "musl"  # an install that needs no rebuild
    (musl / "lib").mkdir(parents=True)
    (musl / "lib" / "musl-gcc.specs").write_text("crtprec64.o\n")
    (musl / "lib" / "libc.a").write_text("__floatscan_x87\n")
    calls, slept = tmp_path / "calls", tmp_path / "slept"
    calls.touch()
    slept.touch()
    env = {**os.environ, "PATH": f"{bin_dir}:{os.environ['PATH']}", "MISSING": missing,
           "LOCKED_CALLS": str(locked_calls), "CALLS": str(calls), "SLEPT": str(slept),
           "MUSL_PREFIX": str(musl), "LOCK_WAIT_S": str(lock_wait_s),
           "CI": "true" if ci else ""}
    done = subprocess.run(["sh", str(SYSDEPS)], env=env, capture_output=True, text=True,
                          timeout=60)
    return done, calls.read_text().splitlines(), sum(map(int, slept.read_text().split()))


@pytest.mark.parametrize("ci", [True, False], ids=["ci", "developer"])
def test_a_held_lock_is_waited_for_and_the_install_goes_on(tmp_path, ci):
    done, calls, slept_s = sysdeps(tmp_path, missing="qemu-user clang", locked_calls=3, ci=ci)
    assert done.returncode == 0, done.stderr
    assert "sysdeps: waiting for another package manager" in done.stderr
    assert slept_s == 15  # three refusals, five seconds each
    assert len(calls) == 5 and all(call.endswith(" update") for call in calls[:4])
    assert calls[4].endswith(" install -y --no-install-recommends qemu-user clang")
    assert all("DPkg::Lock::Timeout=900" in call for call in calls)  # dpkg's lock: apt waits


def test_under_ci_a_lock_never_released_fails_the_run(tmp_path):
    done, calls, slept_s = sysdeps(tmp_path, missing="qemu-user", locked_calls=-1, ci=True,
                                   lock_wait_s=60)
    assert done.returncode == 1
    assert slept_s == 60 and len(calls) == 13  # it waited as long as it was told to
    assert done.stderr.rstrip().endswith(
        "sysdeps: could not install qemu-user (CI=true: every tool the tests need must be "
        "installed)")


def test_off_ci_a_lock_never_released_says_what_will_be_skipped(tmp_path):
    done, _, slept_s = sysdeps(tmp_path, missing="qemu-user", locked_calls=-1, ci=False,
                               lock_wait_s=10)
    assert done.returncode == 0 and slept_s == 10
    assert done.stderr.rstrip().endswith(
        "sysdeps: could not install qemu-user; the tests that need it will be skipped")


def test_nothing_missing_touches_no_package_manager(tmp_path):
    done, calls, _ = sysdeps(tmp_path, missing="", locked_calls=-1, ci=True)
    assert done.returncode == 0 and calls == [] and done.stderr == ""
