"""The one base class of the errors a user can act on, and the exit code each carries.

Every domain error (a bad mission, a plan file that breaks the format, an infeasible
budget, a file that does not exist...) derives from `GliderplanError`. Its message is
complete, naming the file and place, and its `exit_code` is what every `gliderplan`
command exits with for it, so one error exits alike in every command. The library
raises them; `cli/main.py` alone turns them into messages.
"""

from __future__ import annotations

from gliderplan.contract import ExitCode


class GliderplanError(Exception):
    """A failure the user can act on, said in one line. `usage`: the input names nothing
    that exists (a missing file, an unknown preset or clock), so the command was used
    wrongly. `details`: what to show before that line (a mission's diagnostics)."""

    exit_code: ExitCode = ExitCode.BAD_INPUT

    def __init__(self, message: str, *, usage: bool = False, details: str = "") -> None:
        super().__init__(message)
        self.details = details
        if usage:
            self.exit_code = ExitCode.USAGE


class UsageError(GliderplanError):
    """Bad usage: a malformed or contradictory option, a path that does not exist."""

    exit_code = ExitCode.USAGE
