"""`gliderplan check`: report every problem in one or more missions."""

from __future__ import annotations

import argparse
import sys

from gliderplan.cli.common import add_max_stack_argument
from gliderplan.cli.main import print_json, report
from gliderplan.contract import ExitCode
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import check_file

ORDER = 10


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("missions", nargs="+", metavar="MISSION", help="mission file(s)")
    parser.add_argument("--json", action="store_true",
                        help="print each file's diagnostics and checked mission as JSON on "
                             "stdout (docs/json.md)")
    parser.add_argument("--strict", action="store_true", help="warnings fail the check too")
    add_max_stack_argument(parser)


def run(args: argparse.Namespace) -> int:
    """Every file is checked; the exit code is the worst of the files' (a file that does
    not exist exits 2 alone or beside others, a bad mission 1)."""
    code = ExitCode.OK
    checked = []
    for path in args.missions:
        try:
            result = check_file(path, args.max_stack, model_files=True)
        except GliderplanError as err:  # an unreadable file: say so, check the others
            code = max(code, report("check", err))
            checked.append({"file": path, "ok": False, "exit_code": int(err.exit_code),
                            "diagnostics": err.to_json("check")["diagnostics"],
                            "mission": None})
            continue
        if result.diagnostics:
            print(result.render(), file=sys.stderr)
        has_warnings = any(not d.is_error for d in result.diagnostics)
        failed = not result.ok or (args.strict and has_warnings)
        if failed:
            code = max(code, ExitCode.BAD_INPUT)
        if args.json:  # the JSON and its hash cost seconds on a large mission: on request
            checked.append({"file": path, "ok": not failed,
                            "exit_code": int(ExitCode.BAD_INPUT if failed else ExitCode.OK),
                            "diagnostics": result.diagnostics_json(),
                            "mission": result.mission.to_json() if result.mission else None})
    if args.json:
        print_json(checked[0] if len(checked) == 1 else checked)
    return code
