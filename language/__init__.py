"""gliderplan.language: the mission language's grammar, checker, formatter and code generator.

`check_source` is the front end in one call: text in, checked mission and
diagnostics out. It never raises on bad input.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from gliderplan.language.diagnostics import Diagnostic, MissionSyntaxError, render_all
from gliderplan.language.ir import CheckedMission


@dataclass(frozen=True)
class CheckResult:
    filename: str
    source: str
    mission: CheckedMission | None  # None when there are errors
    diagnostics: list[Diagnostic] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.mission is not None

    def render(self) -> str:
        return render_all(self.diagnostics, self.filename, self.source)


def check_source(source: str, filename: str = "<mission>",
                 stack_depth: int | None = None) -> CheckResult:
    """Parse and check mission text."""
    with _cycle_collector_paused():
        return _check_source(source, filename, stack_depth)


@contextmanager
def _cycle_collector_paused() -> Iterator[None]:
    """The parse tree, syntax tree and IR are built in one go and hold no cycles to
    collect, yet the collector rescans them as they grow: 55 % of the time of a
    5,000-state check (bench/bench_check_scale.py)."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def _check_source(source: str, filename: str, stack_depth: int | None) -> CheckResult:
    from gliderplan.language.checker import check
    from gliderplan.language.parser import parse

    try:
        syntax = parse(source)
    except MissionSyntaxError as err:
        return CheckResult(filename, source, None, err.diagnostics)
    try:
        mission, diagnostics = check(syntax, stack_depth)
    except RecursionError:
        from gliderplan.language.parser import TOO_DEEP

        return CheckResult(filename, source, None, [TOO_DEEP])
    return CheckResult(filename, source, mission, diagnostics)
