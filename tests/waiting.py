"""Waiting on a condition, not for a time: a test goes on as soon as what it waits for
has happened, and fails, saying what, if it does not within a bound."""

from __future__ import annotations

import time
from collections.abc import Callable

POLL_S = 0.005  # [s] between looks


def wait_until(condition: Callable[[], bool], timeout_s: float, what: str) -> None:
    """Return once `condition()` holds; fail the test if it has not within `timeout_s`."""
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, f"{what}: not within {timeout_s:g} s"
        time.sleep(POLL_S)
