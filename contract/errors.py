"""The one base class of the errors a user can act on, and the exit code each carries.

Every domain error (a bad mission, a plan file that breaks the format, an infeasible
budget, a file that does not exist...) derives from `GliderplanError`. Its message is
complete, naming the file and place, and its `exit_code` is what every `gliderplan`
command exits with for it, so one error exits alike in every command. The library
raises them; `cli/main.py` alone turns them into messages.
"""

from __future__ import annotations

from collections.abc import Sequence

from gliderplan.contract import ExitCode


class GliderplanError(Exception):
    """A failure the user can act on, said in one line. `usage`: the input names nothing
    that exists (a missing file, an unknown preset or clock), so the command was used
    wrongly. `details`: what to show before that line (a mission's diagnostics), and
    `diagnostics` the same as JSON objects (`diagnostic_json`); `file`: the file at fault,
    where one is. `report`: what a command's --json prints beside the error (the minimum
    energy of an infeasible budget, say)."""

    exit_code: ExitCode = ExitCode.BAD_INPUT

    def __init__(self, message: str, *, usage: bool = False, details: str = "",
                 diagnostics: Sequence[dict] = (), file: str | None = None) -> None:
        super().__init__(message)
        self.details = details
        self.diagnostics = list(diagnostics)
        self.file = file
        self.report: dict = {}
        if usage:
            self.exit_code = ExitCode.USAGE

    def to_json(self, command: str) -> dict:
        """What `gliderplan COMMAND --json` prints on stdout when it fails with this error
        (docs/json.md, "Errors")."""
        said = self.diagnostics or [diagnostic_json(str(self), file=self.file)]
        return {"ok": False, "command": command, "exit_code": int(self.exit_code),
                "error": str(self), "diagnostics": said, **self.report}


def diagnostic_json(message: str, *, severity: str = "error", file: str | None = None,
                    line: int | None = None, column: int | None = None,
                    end_line: int | None = None, end_column: int | None = None,
                    hint: str | None = None) -> dict:
    """A diagnostic as JSON (docs/json.md): the file, 1-based line and column of its first
    character and of the one after its last (None where it has none), severity ("error"
    or "warning"), message, hint (None if none)."""
    return {"file": file, "line": line, "column": column, "end_line": end_line,
            "end_column": end_column, "severity": severity, "message": message, "hint": hint}


class UsageError(GliderplanError):
    """Bad usage: a malformed or contradictory option, a path that does not exist."""

    exit_code = ExitCode.USAGE
