"""`gliderplan fmt`: print missions in the canonical layout, or rewrite them in place.

Comments are kept. A file that does not parse is reported like `gliderplan check`
does and left alone. With --check nothing is printed or written: the files that
would change are listed and the exit code is 1 if there are any.
"""

from __future__ import annotations

import argparse
import sys

from gliderplan.cli.main import print_json, report
from gliderplan.contract import ExitCode
from gliderplan.contract.errors import GliderplanError, UsageError
from gliderplan.contract.files import write_atomically

ORDER = 15


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("missions", nargs="+", metavar="MISSION", help="mission file(s)")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true",
                      help="change nothing; list files that are not formatted, exit 1 if any")
    mode.add_argument("--write", action="store_true",
                      help="rewrite the files in place (atomically) instead of printing")
    parser.add_argument("--json", action="store_true",
                        help="print, for each file, whether it is in the canonical layout and "
                             "was rewritten, as JSON (with --check or --write)")


def run(args: argparse.Namespace) -> int:
    """Every file is formatted; the exit code is the worst of the files' (a file that does
    not exist exits 2 alone or beside others, a file that does not parse 1)."""
    # Imported here: every command's module is loaded for --help, and `check` must start fast.
    from gliderplan.language.formatter import format_file

    if args.json and not (args.check or args.write):
        raise UsageError("--json says what --check or --write did: give one of them (without "
                         "either, fmt prints the formatted missions themselves)")
    code = ExitCode.OK
    said = []
    for path in args.missions:
        try:
            source, formatted = format_file(path)
            if args.check:
                if formatted != source and not args.json:
                    print(f"{path}: would be reformatted")
                if formatted != source:
                    code = max(code, ExitCode.BAD_INPUT)
            elif args.write:
                if formatted != source:  # a read-only file is refused, not replaced
                    write_atomically(path, formatted)
            else:
                sys.stdout.write(formatted)
            said.append({"file": path, "ok": True, "canonical": formatted == source,
                         "written": bool(args.write and formatted != source),
                         "diagnostics": []})
        except GliderplanError as err:  # unreadable, does not parse, read-only: go on
            code = max(code, report("fmt", err))
            said.append({"file": path, "ok": False, "canonical": None, "written": False,
                         "exit_code": int(err.exit_code),
                         "diagnostics": err.to_json("fmt")["diagnostics"]})
    if args.json:
        print_json(said)
    return code
