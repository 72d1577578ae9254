"""A progress bar on stderr: redrawn in place on a terminal; elsewhere (a log, a pipe, CI)
one plain line now and then, never a line per update."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable

# [s] of wall time between two progress lines off a terminal; GLIDERPLAN_PROGRESS_S sets
# another (0: a line per update)
LOG_INTERVAL_S = 15.0


def log_interval_s() -> float:
    """[s] between two progress lines off a terminal: $GLIDERPLAN_PROGRESS_S, else
    LOG_INTERVAL_S."""
    try:
        return max(float(os.environ.get("GLIDERPLAN_PROGRESS_S", LOG_INTERVAL_S)), 0.0)
    except ValueError:
        return LOG_INTERVAL_S


class ProgressBar:
    """`bar(done, total)` draws; `text(done, total)` says what the numbers are.

    Off a terminal the first line comes after `interval_s` and then at most one every
    `interval_s`, so a short run prints none and a long one a line now and then."""

    WIDTH = 30

    def __init__(self, text: Callable[[float, float], str],
                 interval_s: float | None = None) -> None:
        self.text = text
        self.shown = False
        self.live = sys.stderr.isatty()
        self.interval_s = log_interval_s() if interval_s is None else interval_s
        self._next_line = time.monotonic() + self.interval_s

    def __call__(self, done: float, total: float) -> None:
        if self.live:
            filled = int(self.WIDTH * min(done / total, 1.0)) if total else self.WIDTH
            bar = f"[{'#' * filled}{'.' * (self.WIDTH - filled)}] {self.text(done, total)}"
            print("\r" + bar, end="", file=sys.stderr, flush=True)
            self.shown = True
        elif time.monotonic() >= self._next_line:
            share = f" ({100 * done / total:.0f} %)" if total else ""
            print(f"progress: {self.text(done, total)}{share}", file=sys.stderr, flush=True)
            self._next_line = time.monotonic() + self.interval_s

    def finish(self) -> None:
        if self.shown and self.live:
            print(file=sys.stderr)
            self.shown = False


class Steps:
    """`steps(text)` says that a step of a long command starts: the line is rewritten in
    place on a terminal; elsewhere each step is a line of its own once the command has run
    `quiet_s` (a quick run, or one refused at once, prints none)."""

    def __init__(self, command: str, quiet_s: float = 5.0) -> None:
        self.command = command
        self.live = sys.stderr.isatty()
        self.shown = 0  # characters of the line on the terminal
        self._loud_from = time.monotonic() + quiet_s

    def __call__(self, text: str) -> None:
        line = f"{self.command}: {text}..."
        if self.live:
            print("\r" + line.ljust(self.shown), end="", file=sys.stderr, flush=True)
            self.shown = len(line)
        elif time.monotonic() >= self._loud_from:
            print(line, file=sys.stderr, flush=True)

    def finish(self) -> None:
        if self.shown:
            print("\r" + " " * self.shown + "\r", end="", file=sys.stderr, flush=True)
            self.shown = 0
