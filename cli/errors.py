"""Exceptions that the CLI turns into a message and an exit code (never a traceback)."""

from gliderplan.contract import ExitCode


class CliError(Exception):
    """A failure the user can act on; the message is printed as is."""

    exit_code = ExitCode.BAD_INPUT


class UsageError(CliError):
    """Bad command-line usage: a missing file, a malformed option value."""

    exit_code = ExitCode.USAGE
