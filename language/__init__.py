"""gliderplan.language: the mission language's grammar, checker, formatter and code generator.

`check_source` is the front end in one call: text in, checked mission and
diagnostics out. It never raises on bad input. `check_file` does the same for a file
(`gliderplan check`); `CheckResult.checked` turns a result with errors into a
MissionError for the commands that go on with the mission.
"""

from __future__ import annotations

import gc
import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

from gliderplan.contract import MAX_STACK_DEPTH
from gliderplan.contract.errors import UsageError
from gliderplan.language.diagnostics import (
    Diagnostic,
    MissionError,
    MissionSyntaxError,
    render_all,
)
from gliderplan.language.ir import CheckedMission
from gliderplan.language.source import read_mission


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

    def diagnostics_json(self) -> list[dict]:
        """Every diagnostic as a JSON object (`Diagnostic.to_json`)."""
        return [d.to_json(self.filename) for d in self.diagnostics]

    def checked(self) -> CheckedMission:
        """The checked mission; MissionError (with the diagnostics) if it has errors."""
        if self.mission is None:
            raise MissionError(f"{self.filename}: mission has errors", details=self.render(),
                               diagnostics=self.diagnostics_json(), file=self.filename)
        return self.mission


def check_file(path: str, stack_depth: int | None = None, *, model_files: bool = False
               ) -> CheckResult:
    """Read and check a mission file (`gliderplan check`). Raises InputFileError for a file
    that cannot be read as mission text, UsageError for a stack depth the runtime cannot
    hold; a bad mission is not an error here but a result with diagnostics. `model_files`:
    open the vehicle and board files it names too, and check the yos their vehicle flies
    (`gliderplan check`; the other commands load them when they need them)."""
    if stack_depth is not None and not 1 <= stack_depth <= MAX_STACK_DEPTH:
        raise UsageError(f"--max-stack must be between 1 and {MAX_STACK_DEPTH}, the "
                         "runtime's limit")
    return check_source(read_mission(path), path, stack_depth, model_files=model_files)


def check_source(source: str, filename: str = "<mission>",
                 stack_depth: int | None = None, *, model_files: bool = False) -> CheckResult:
    """Parse and check mission text (`model_files` as for `check_file`)."""
    with _cycle_collector_paused():
        return _check_source(source, filename, stack_depth, model_files)


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
        # What was built would all be scanned by the next young collection (it was
        # allocated while the collector was paused): hand it to the oldest generation,
        # which freeze and unfreeze do without visiting an object.
        gc.freeze()
        gc.unfreeze()
        if was_enabled:
            gc.enable()


def _check_source(source: str, filename: str, stack_depth: int | None,
                  model_files: bool) -> CheckResult:
    from gliderplan.language.checker import check
    from gliderplan.language.parser import parse

    try:
        syntax = parse(source)
    except MissionSyntaxError as err:
        return CheckResult(filename, source, None, err.diagnostics)
    try:
        # the files a mission names are beside it (a text of no file: the working folder)
        base_dir = "" if filename.startswith("<") else os.path.dirname(filename)
        mission, diagnostics = check(syntax, stack_depth, base_dir, model_files)
    except RecursionError:
        from gliderplan.language.parser import TOO_DEEP

        return CheckResult(filename, source, None, [TOO_DEEP])
    return CheckResult(filename, source, mission, diagnostics)
