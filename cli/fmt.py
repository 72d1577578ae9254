"""`gliderplan fmt`: print missions in the canonical layout, or rewrite them in place.

Comments are kept. A file that does not parse is reported like `gliderplan check`
does and left alone. With --check nothing is printed or written: the files that
would change are listed and the exit code is 1 if there are any.
"""

from __future__ import annotations

import argparse
import sys

from gliderplan.cli.common import write_atomically
from gliderplan.cli.errors import UsageError
from gliderplan.contract import ExitCode
from gliderplan.language.diagnostics import MissionSyntaxError, render_all
from gliderplan.language.source import SourceError, read_mission

ORDER = 15


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("missions", nargs="+", metavar="MISSION", help="mission file(s)")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true",
                      help="change nothing; list files that are not formatted, exit 1 if any")
    mode.add_argument("--write", action="store_true",
                      help="rewrite the files in place (atomically) instead of printing")


def run(args: argparse.Namespace) -> int:
    # Imported here: every command's module is loaded at start-up, and `check` must start fast.
    from gliderplan.language.formatter import FormatError, format_source

    failed = False
    for path in args.missions:
        try:
            source = read_mission(path)
        except SourceError as err:
            if err.usage and len(args.missions) == 1:
                raise UsageError(str(err)) from None
            print(f"gliderplan fmt: error: {err}", file=sys.stderr)
            failed = True
            continue
        try:
            formatted = format_source(source)
        except MissionSyntaxError as err:
            print(render_all(err.diagnostics, path, source), file=sys.stderr)
            failed = True
            continue
        except FormatError as err:
            print(f"gliderplan fmt: error: {path}: {err}", file=sys.stderr)
            failed = True
            continue
        if args.check:
            if formatted != source:
                print(f"{path}: would be reformatted")
                failed = True
        elif args.write:
            if formatted != source:
                write_atomically(path, formatted)
        else:
            sys.stdout.write(formatted)
    return ExitCode.BAD_INPUT if failed else ExitCode.OK
