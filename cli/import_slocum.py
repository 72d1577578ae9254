"""`gliderplan import-slocum`: translate a Slocum layered-control mission (.mi and its .ma files).

  import-slocum MISSION.mi [--mafiles DIR] -o OUT.mission [--horizon 7d]

Writes OUT.mission in the gliderplan language and checks it. What has no counterpart
stays in OUT.mission as a comment and is reported as a warning (FILE:LINE: warning:
...). An unknown behavior, a .ma file that is not there and a malformed line are
errors (exit 1) naming the file and line.
"""

from __future__ import annotations

import argparse
import sys

ORDER = 5
DEFAULT_HORIZON = "7d"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("mission", metavar="MISSION.mi", help="Slocum mission file")
    parser.add_argument("--mafiles", metavar="DIR",
                        help="directory of the .ma files (default: mafiles/ beside the .mi, "
                             "or beside its missions/ directory)")
    parser.add_argument("-o", "--output", metavar="OUT.mission", required=True,
                        help="the translated mission")
    parser.add_argument("--horizon", metavar="T", default=DEFAULT_HORIZON,
                        help="how long the mission is planned and simulated for (a Slocum "
                             "mission runs until its pilot ends it; default 7d, or abend's "
                             "overtime when shorter)")
    parser.add_argument("--allow-missing-mafiles", action="store_true",
                        help="leave out a behavior whose .ma file is missing (a warning) "
                             "instead of stopping")


def run(args: argparse.Namespace) -> int:
    from gliderplan.cli.sim import parse_duration_s
    from gliderplan.language.slocum import import_mission

    imported = import_mission(args.mission, args.output, args.mafiles,
                              parse_duration_s(args.horizon, "--horizon"),
                              args.allow_missing_mafiles)
    for warning in imported.warnings:
        print(warning, file=sys.stderr)
    print(f"wrote {imported.path}: {imported.states} states, {len(imported.warnings)} "
          "warning(s)", file=sys.stderr)
    return 0
