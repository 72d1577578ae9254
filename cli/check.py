"""`gliderplan check`: report every problem in one or more missions."""

from __future__ import annotations

import argparse
import json
import sys

from gliderplan.cli.common import add_max_stack_argument, check_file
from gliderplan.cli.errors import CliError
from gliderplan.contract import ExitCode

ORDER = 10


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("missions", nargs="+", metavar="MISSION", help="mission file(s)")
    parser.add_argument("--json", action="store_true",
                        help="print the checked mission(s) as JSON on stdout")
    parser.add_argument("--strict", action="store_true", help="warnings fail the check too")
    add_max_stack_argument(parser)


def run(args: argparse.Namespace) -> int:
    failed = False
    checked = []
    for path in args.missions:
        try:
            result = check_file(path, args.max_stack)
        except CliError as err:
            print(f"gliderplan check: error: {err}", file=sys.stderr)
            failed = True
            if err.exit_code == ExitCode.USAGE and len(args.missions) == 1:
                return ExitCode.USAGE
            continue
        if result.diagnostics:
            print(result.render(), file=sys.stderr)
        has_warnings = any(not d.is_error for d in result.diagnostics)
        failed |= not result.ok or (args.strict and has_warnings)
        if args.json and result.mission is not None:  # the JSON and its hash cost seconds
            checked.append(result.mission.to_json())    # on a large mission: only on request
    if checked:
        print(json.dumps(checked[0] if len(checked) == 1 else checked, indent=2))
    return ExitCode.BAD_INPUT if failed else ExitCode.OK
