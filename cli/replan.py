"""`gliderplan replan`: replan the rest of a mission from a surfacing's telemetry, as a plan update.

  replan MISSION --plan CURRENT.plan --telemetry T [--confidence P] [--key KEYFILE -o OUT]

Reads the glider's surfacing reports (T: a JSON telemetry file, or Slocum .sbd/.tbd logs or
a directory of them), updates the energy model's figures from what each interval measured
(power_models/posterior.py), and plans the rest of the mission from the glider's state at
the same confidence, warm from the plan it holds (CURRENT.plan, signed). Prints what
changed and why: the figures that moved, the battery's usable share, the duties, the new
shadow price. With -o OUT (and the vehicle's key) writes the plan update OUT (a signed
binary delta against CURRENT.plan of at most 270 bytes, one short Iridium message; a
chain OUT.1, OUT.2, ... with --max-updates), OUT.plan (the plan the glider holds once it is
applied: the next replan's --plan) and OUT.json. Telemetry no replan can rest on, or a
budget that cannot hold the rest at the confidence, is an error (exit 1): no update is
written and the glider keeps flying its plan.
"""

from __future__ import annotations

import argparse

from gliderplan.cli.common import (
    add_currents_argument,
    add_mission_argument,
    add_replan_confidence_argument,
    load_mission,
    parse_start,
    refuse_unpaired,
    start_epoch_s,
)
from gliderplan.contract import ExitCode

ORDER = 32


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    parser.add_argument("--plan", required=True, metavar="PLANFILE",
                        help="the signed plan the glider holds")
    parser.add_argument("--telemetry", required=True, nargs="+", metavar="T",
                        help="the glider's surfacing reports: a JSON file, or Slocum logs "
                             "(.sbd/.tbd, .dbd/.ebd) or directories of them")
    add_replan_confidence_argument(parser)
    parser.add_argument("--key", metavar="KEYFILE",
                        help="the vehicle's key (gliderplan keygen): signs the update")
    parser.add_argument("--seq", type=int, metavar="N",
                        help="the update's sequence number (default: one more than the plan's)")
    parser.add_argument("--max-updates", type=int, default=1, metavar="N",
                        help="send the changes in up to N updates of 270 bytes (default 1)")
    parser.add_argument("--scenario-file", metavar="FILE",
                        help="the figures' spreads and the battery's usable share the prior "
                             "takes (default: the shipped scenario file)")
    parser.add_argument("--if-infeasible", choices=("refuse", "least-energy"),
                        default="refuse",
                        help="when the budget left cannot hold the rest at the confidence: "
                             "refuse (default) or send the plan that needs the least")
    add_currents_argument(parser, "none: the plan's speeds and thruster commands stay; with "
                                  "one, the `auto` speeds and `thrust auto` are chosen anew "
                                  "for it from the glider's last position")
    parser.add_argument("--start", metavar="UTC",
                        help="with --currents: when the mission started (ISO 8601; default "
                             "2000-01-01T00:00:00Z), to read the field at the report's time")
    parser.add_argument("--json", action="store_true", help="print the report as JSON")
    parser.add_argument("-o", "--output", metavar="OUT",
                        help="write the update OUT, the plan OUT.plan and the report OUT.json")


def run(args: argparse.Namespace) -> int:
    from gliderplan.cli.main import print_json
    from gliderplan.planner.replan import replan_mission

    refuse_unpaired(args, {"--seq": ("--key",), "--start": ("--currents",)})
    mission = load_mission(args)
    when = parse_start(args.start)[2] if args.start else None
    run_ = replan_mission(mission, args.plan, args.telemetry, confidence=args.confidence,
                          key_path=args.key, output=args.output, seq=args.seq,
                          max_updates=args.max_updates, scenario_file=args.scenario_file,
                          if_infeasible=args.if_infeasible, currents=args.currents,
                          start_epoch_s=start_epoch_s(when))
    if args.json:
        print_json(run_.to_json())
        return ExitCode.OK
    print(f"{mission.name}: {run_.result.text()}")
    for note in run_.notes:
        print(f"telemetry: {note}")
    if run_.updates:
        sizes = ", ".join(f"{len(u)}" for u in run_.updates)
        print(f"update: {len(run_.updates)} message(s) of {sizes} bytes (at most 270 each)")
    elif args.key:
        print("update: none (nothing the glider flies changes)")
    for path in run_.files:
        print(f"wrote {path}")
    return ExitCode.OK
