"""`gliderplan compare-sbc`: which single-board computer, and at what workload the answer flips.

  compare-sbc MISSION [--computer NAME|FILE ...] [--battery 1.2kWh] [--cycles-per-tick N]
                      [--json] [-o DIR]

Compares the TS-5500, the TS-7800 at 300 and at 500 MHz (or the boards given with
--computer, repeatable: a preset, NAME@MHZ or a board file) on the mission at the same
battery: each board's energy with its active/idle/sleep split, its share of the mission,
the mission's energy and quality, the endurance at the same sampling plan, and the
workloads at which the ranking of the boards changes. With -o: boards.csv, workload.csv,
crossovers.csv and sbc.png in DIR.
"""

from __future__ import annotations

import argparse
from contextlib import nullcontext
from pathlib import Path

from gliderplan.cli.common import (
    add_cycles_argument,
    add_force_argument,
    add_mission_argument,
    load_mission,
)
from gliderplan.contract import interrupts
from gliderplan.contract.errors import UsageError
from gliderplan.contract.files import output_folder

ORDER = 35


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    parser.add_argument("--computer", metavar="NAME|FILE", action="append",
                        help="a board to compare (repeatable): ts5500, ts7800@300, "
                             "ts7800@500, ts7800 (the planner picks the clock) or a board "
                             "file; default: ts5500, ts7800@300 and ts7800@500")
    parser.add_argument("--battery", metavar="ENERGY|PRESET",
                        help="battery energy (1.2kWh, 60Ah@14.4V) or preset; default: the "
                             "mission's")
    add_cycles_argument(parser)
    parser.add_argument("--json", action="store_true", help="print the comparison as JSON")
    parser.add_argument("-o", "--output", metavar="DIR",
                        help="write boards.csv, workload.csv, crossovers.csv and sbc.png here "
                             "(a folder written whole)")
    add_force_argument(parser)


def run(args: argparse.Namespace) -> int:
    out = Path(args.output) if args.output else None
    if out is not None and out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory (compare-sbc writes several files there)")
    mission = load_mission(args)
    from gliderplan.planner.compare import COMPUTERS, compare_boards
    from gliderplan.reports import sbc

    with output_folder(out, command="compare-sbc", force=args.force, recognised=sbc.FILES,
                       inputs=(args.mission,)) if out is not None else nullcontext() as folder:
        comparison = compare_boards(mission, args.computer or COMPUTERS, battery=args.battery,
                                    cycles_per_tick=args.cycles_per_tick)
        interrupts.raise_if_stopped()
        files = sbc.write_files(comparison, folder) if folder is not None else ()
    print(sbc.as_json(comparison) if args.json else sbc.comparison_text(comparison), end="")
    if files and not args.json:
        print(f"wrote {', '.join(f.name for f in files)} to {out}")
    return 0
