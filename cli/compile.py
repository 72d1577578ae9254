"""`gliderplan compile`: build a mission's runtime binary for the host or a glider's board."""

from __future__ import annotations

import argparse
import sys

from gliderplan.cli.common import add_mission_argument, load_mission

ORDER = 40


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from gliderplan.runtime.build import TARGETS

    add_mission_argument(parser)
    parser.add_argument("--plan", metavar="PLANFILE",
                        help="plan file to check against the mission and copy beside the binary")
    parser.add_argument("--target", choices=tuple(TARGETS),
                        help="; ".join(f"{t.name}: {t.description}" for t in TARGETS.values())
                        + " (default host; a mission with 'computer none' must say)")
    parser.add_argument("-o", "--output", metavar="DIR", required=True,
                        help="directory for MISSION.c, the binary and the plan")


def run(args: argparse.Namespace) -> int:
    from gliderplan.runtime.build import build_target, compile_mission

    mission = load_mission(args)
    target = build_target(mission, args.target)
    binary = compile_mission(mission, args.output, target, args.plan)
    print(f"{binary} ({target})", file=sys.stderr)
    return 0
