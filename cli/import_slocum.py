"""`gliderplan import-slocum`: translate a Slocum layered-control mission (.mi and its .ma files).

  import-slocum MISSION.mi [--mafiles DIR] -o OUT.mission [--horizon 7d]
                [--vehicle SPEC] [--computer SPEC] [--battery SPEC]

Writes OUT.mission in the gliderplan language and checks it. What has no counterpart
stays in OUT.mission as a comment and is reported as a warning (FILE:LINE: warning:
...). An unknown behavior, a .ma file that is not there and a malformed line are
errors (exit 1) naming the file and line.
"""

from __future__ import annotations

import argparse
import sys

from gliderplan.language.slocum import Hardware

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
    defaults = Hardware()
    parser.add_argument("--vehicle", metavar="PRESET|FILE",
                        help=f"the glider it flies on (default {defaults.vehicle}; give your "
                             "calibrated glider: gliderplan calibrate -o)")
    parser.add_argument("--computer", metavar="SPEC",
                        help=f"an extra board that runs the mission (default {defaults.computer}"
                             ": the glider's own computers)")
    parser.add_argument("--battery", metavar="SPEC",
                        help="its battery as a mission writes it (default "
                             f"'{defaults.battery.replace('%', '%%')}', the Slocum alkaline "
                             "pack)")  # argparse formats help with %
    parser.add_argument("--allow-missing-mafiles", action="store_true",
                        help="leave out a behavior whose .ma file is missing (a warning) "
                             "instead of stopping")
    parser.add_argument("--json", action="store_true",
                        help="print what was written and the warnings as JSON (docs/json.md)")


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from gliderplan.cli.sim import parse_duration_s
    from gliderplan.language.slocum import import_mission

    given = {k: getattr(args, k) for k in ("vehicle", "computer", "battery")
             if getattr(args, k) is not None}
    hardware = replace(Hardware(), **given, given=frozenset(given))
    imported = import_mission(args.mission, args.output, args.mafiles,
                              parse_duration_s(args.horizon, "--horizon"),
                              args.allow_missing_mafiles, hardware)
    for warning in imported.warnings:
        print(warning, file=sys.stderr)
    said = ", ".join(f"{k} {getattr(hardware, k)}" + ("" if k in given else " (default)")
                     for k in ("vehicle", "computer", "battery"))
    print(f"wrote {imported.path}: {imported.states} states, {len(imported.warnings)} "
          f"warning(s); {said}", file=sys.stderr)
    if args.json:
        from gliderplan.cli.main import print_json

        print_json({"ok": True, "output": str(imported.path), "states": imported.states,
                    "hardware": {k: {"spec": getattr(hardware, k), "default": k not in given}
                                 for k in ("vehicle", "computer", "battery")},
                    "warnings": [_warning_json(w) for w in imported.warnings]})
    return 0


def _warning_json(warning) -> dict:  # noqa: ANN001 (language.slocum.Warning_)
    """An import warning as a diagnostic object (docs/json.md)."""
    from gliderplan.contract.errors import diagnostic_json

    return diagnostic_json(warning.message, severity="warning", file=str(warning.where.path),
                           line=warning.where.line)
