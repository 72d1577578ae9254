"""What several subcommands share: loading and checking a mission file, writing results."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from gliderplan.cli.errors import CliError, UsageError
from gliderplan.contract import DEFAULT_STACK_DEPTH, MAX_STACK_DEPTH
from gliderplan.language import CheckResult, check_source
from gliderplan.language.ir import CheckedMission
from gliderplan.language.source import SourceError, read_mission


def add_mission_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("mission", help="mission file (any name; .mission by convention)")
    add_max_stack_argument(parser)


def add_max_stack_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--max-stack", type=int, metavar="N", default=None,
                        help=f"runtime state-stack depth, 1 to {MAX_STACK_DEPTH} "
                             f"(default: the mission's, else {DEFAULT_STACK_DEPTH})")


def check_file(path: str, stack_depth: int | None = None) -> CheckResult:
    """Read and check one file; unreadable files raise CliError/UsageError."""
    if stack_depth is not None and not 1 <= stack_depth <= MAX_STACK_DEPTH:
        raise UsageError(f"--max-stack must be between 1 and {MAX_STACK_DEPTH}, the "
                         "runtime's limit")
    try:
        source = read_mission(path)
    except SourceError as err:
        raise (UsageError if err.usage else CliError)(str(err)) from None
    return check_source(source, path, stack_depth)


def load_mission(args: argparse.Namespace) -> CheckedMission:
    """The checked mission named on the command line; diagnostics go to stderr."""
    result = check_file(args.mission, args.max_stack)
    if result.diagnostics:
        print(result.render(), file=sys.stderr)
    if result.mission is None:
        raise CliError(f"{args.mission}: mission has errors")
    return result.mission


def write_atomically(path: str | Path, data: str | bytes) -> None:
    """Write a result file so that a crash leaves either the old file or the new one."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    mode = "wb" if isinstance(data, bytes) else "w"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, mode) as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; results are for sharing
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
