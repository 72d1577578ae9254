"""`gliderplan report`: one offline HTML page of a mission's tradeoffs, and the CSV behind it.

  report MISSION [--plan PLAN] [--run RUNDIR] [--montecarlo DIR]
         [--currents N,E|FIELD.nc|LOGDIR [--start LAT,LON[,UTC]]] -o DIR

Writes DIR/report.html (self-contained: figures inline, no network) with the summary and
verdict, the Pareto curve, energy by state and component, plan against simulation, the
depth and temperature profile, the board comparison, the sensitivity to each model
figure and, when given, the Monte Carlo distribution; and one CSV file per figure.
Without --plan the mission is planned now (the plan is written into DIR); without --run
the plan is flown now on the simulated glider (into DIR/run). With --currents (the one
a plan given was made with) the mission is planned, drawn and flown in that water.
"""

from __future__ import annotations

import argparse

from gliderplan.cli.common import (
    add_currents_argument,
    add_force_argument,
    add_mission_argument,
    add_start_argument,
    load_mission,
    parse_start,
    refuse_unpaired,
)

ORDER = 70


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    parser.add_argument("--plan", metavar="PLAN",
                        help="a plan made by `gliderplan plan -o PLAN` (its PLAN.json beside "
                             "it); default: plan now")
    parser.add_argument("--run", metavar="RUNDIR",
                        help="a `gliderplan sim` run of that plan; default: fly it now")
    parser.add_argument("--montecarlo", metavar="DIR",
                        help="a `gliderplan montecarlo` result to show")
    parser.add_argument("--json", action="store_true",
                        help="print the files written as JSON (docs/json.md)")
    parser.add_argument("-o", "--output", metavar="DIR", required=True,
                        help="directory for report.html and its CSV files (a folder "
                             "written whole)")
    add_force_argument(parser)
    add_currents_argument(parser, "still water; with one, the mission is planned (each "
                                  "propelled `auto` speed on its route), drawn and flown in "
                                  "it")
    add_start_argument(parser, "the mission's start, else 500 m south of its first waypoint, "
                               "at 2000-01-01T00:00:00Z")


def run(args: argparse.Namespace) -> int:
    mission = load_mission(args)
    from gliderplan.reports.report import make_report

    refuse_unpaired(args, {"--start": ("--currents",)})
    lat, lon, when = parse_start(args.start) if args.start else (None, None, None)
    report = make_report(mission, args.output, plan_path=args.plan, run_dir=args.run,
                         montecarlo_dir=args.montecarlo, source=args.mission,
                         force=args.force, currents=args.currents, start_utc=when,
                         start=(lat, lon) if lat is not None else None)
    if args.json:
        from gliderplan.cli.main import print_json

        print_json({"ok": True, "mission": mission.name, "html": str(report.html),
                    "files": [str(f) for f in report.files], "sections": list(report.sections)})
    else:
        print(f"wrote {report.html} ({len(report.files) - 1} CSV and plan files beside it)")
    return 0
