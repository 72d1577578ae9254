"""A progress bar on stderr: redrawn in place on a terminal, one line per update in a log."""

from __future__ import annotations

import sys
from collections.abc import Callable


class ProgressBar:
    """`bar(done, total)` draws; `text(done, total)` says what the numbers are."""

    WIDTH = 30

    def __init__(self, text: Callable[[float, float], str]) -> None:
        self.text = text
        self.shown = False
        self.live = sys.stderr.isatty()

    def __call__(self, done: float, total: float) -> None:
        filled = int(self.WIDTH * done / total) if total else self.WIDTH
        bar = f"[{'#' * filled}{'.' * (self.WIDTH - filled)}] {self.text(done, total)}"
        if self.live:
            print("\r" + bar, end="", file=sys.stderr, flush=True)
        else:
            print(bar, file=sys.stderr, flush=True)
        self.shown = True

    def finish(self) -> None:
        if self.shown and self.live:
            print(file=sys.stderr)
