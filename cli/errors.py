"""Exceptions that the CLI turns into a message and an exit code (never a traceback)."""


class CliError(Exception):
    """A failure the user can act on; the message is printed as is."""

    exit_code = 1


class UsageError(CliError):
    """Bad command-line usage: a missing file, a malformed option value."""

    exit_code = 2
