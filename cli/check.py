"""`gliderplan check`: report every problem in one or more missions."""

from __future__ import annotations

import argparse
import json
import sys

from gliderplan.cli.common import add_max_stack_argument
from gliderplan.cli.main import report
from gliderplan.contract import ExitCode
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import check_file

ORDER = 10


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("missions", nargs="+", metavar="MISSION", help="mission file(s)")
    parser.add_argument("--json", action="store_true",
                        help="print the checked mission(s) as JSON on stdout")
    parser.add_argument("--strict", action="store_true", help="warnings fail the check too")
    add_max_stack_argument(parser)


def run(args: argparse.Namespace) -> int:
    """Every file is checked; exit 1 if any fails (alone, a file exits with its error's
    code: 2 for one that does not exist)."""
    code = ExitCode.OK
    checked = []
    for path in args.missions:
        try:
            result = check_file(path, args.max_stack)
        except GliderplanError as err:  # an unreadable file: say so, check the others
            alone = report("check", err)
            code = max(code, alone if len(args.missions) == 1 else ExitCode.BAD_INPUT)
            continue
        if result.diagnostics:
            print(result.render(), file=sys.stderr)
        has_warnings = any(not d.is_error for d in result.diagnostics)
        if not result.ok or (args.strict and has_warnings):
            code = max(code, ExitCode.BAD_INPUT)
        if args.json and result.mission is not None:  # the JSON and its hash cost seconds
            checked.append(result.mission.to_json())    # on a large mission: only on request
    if checked:
        print(json.dumps(checked[0] if len(checked) == 1 else checked, indent=2))
    return code
