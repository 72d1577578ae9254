"""`gliderplan plan`: plan duty cycles, flight profiles and computer clock under a battery budget.

  plan MISSION [--battery 1.2kWh] [--computer ts7800@300] [-o PLANFILE] [--json]
       [--sign KEYFILE [--seq N]]
  plan MISSION --confidence 0.95 [--scenarios N]   the budget holds in that share of scenarios
  plan MISSION --occupancy-from-sim [--scenarios N]   each state's time as simulated
  plan MISSION --sweep N -o DIR     pareto.csv, computers.csv, batteries.csv, pareto.png
  plan MISSION --currents N,E|FIELD.nc|LOGDIR [--start LAT,LON[,UTC]]
                                    propelled speeds chosen for the water on the route

With -o the plan file (docs/plan-format.md) is written to PLANFILE and its report to
PLANFILE.json (and where it flies propelled, its energy per km against speed with the
chosen speed to PLANFILE.speed.png); with --sign KEYFILE the plan file is signed for the
vehicle holding that key
(docs/plan-format.md, "Signed plans"). The report gives the plan's upload size in bytes. A
budget below what the mission needs exits 1 with the minimum energy and the largest
consumers.
"""

from __future__ import annotations

import argparse
import os

from gliderplan.cli.common import (
    add_currents_argument,
    add_cycles_argument,
    add_force_argument,
    add_mission_argument,
    add_start_argument,
    load_mission,
    parse_start,
    refuse_unpaired,
    seed,
    start_epoch_s,
)
from gliderplan.cli.main import print_json
from gliderplan.contract.errors import UsageError

ORDER = 30


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    parser.add_argument("--battery", metavar="ENERGY|PRESET",
                        help="battery energy (1.2kWh, 500Wh, 60Ah@14.4V) or preset "
                             "(alkaline, lithium_primary, rechargeable); default: the mission's")
    parser.add_argument("--computer", metavar="BOARD[@MHZ]",
                        help="ts5500, ts7800@300, ts7800@500, ts7800 (planner picks the "
                             "clock) or a board file; default: the mission's")
    parser.add_argument("-o", "--output", metavar="PATH",
                        help="plan file (report beside it as PATH.json); with --sweep a "
                             "directory")
    parser.add_argument("--json", action="store_true", help="print the JSON report")
    parser.add_argument("--sweep", type=int, metavar="N",
                        help="Pareto sweep with N budgets, plus computer and battery sweeps")
    parser.add_argument("--confidence", type=float, metavar="C",
                        help="plan so that the budget holds with this probability (e.g. "
                             "0.95): the scenario approach over simulated scenarios")
    parser.add_argument("--occupancy-from-sim", action="store_true",
                        help="plan each state's time (visits, the variables its profiles "
                             "read) as the simulator flies the plan, re-planned until it "
                             "settles: one flight, or the mean of --scenarios scenarios")
    parser.add_argument("--scenarios", type=int, metavar="N",
                        help="with --confidence: scenarios to fly (default: as many as the "
                             "confidence needs at --risk); with --occupancy-from-sim: fly "
                             "N drawn scenarios each round instead of one flight")
    parser.add_argument("--risk", type=float, metavar="B",
                        help="with --confidence: the chance that the scenarios drawn were "
                             "unrepresentative (default 0.001)")
    parser.add_argument("--seed", type=seed,
                        help="with --confidence or --occupancy-from-sim: seed (default 0)")
    parser.add_argument("--scenario-file", metavar="FILE",
                        help="with --confidence or --scenarios: the distributions to draw "
                             "from")
    parser.add_argument("--workers", type=int, metavar="K",
                        help="with --confidence or --scenarios: worker processes (default: "
                             "one per core)")
    parser.add_argument("--sign", metavar="KEYFILE",
                        help="sign the plan with the vehicle's key (gliderplan keygen)")
    parser.add_argument("--seq", type=int, metavar="N",
                        help="with --sign: the plan's sequence number, above every plan "
                             "signed before (default: the time in seconds since 1970)")
    add_cycles_argument(parser)
    add_force_argument(parser)
    add_currents_argument(parser, "still water; with one, each propelled `auto` speed is "
                                  "chosen for the least energy per km over ground on its "
                                  "route")
    add_start_argument(parser, "the mission's start, else 500 m south of its first waypoint, "
                               "at 2000-01-01T00:00:00Z")


# an option -> the options it works with (refused alone: it would be silently ignored)
NEEDS = {
    "--scenarios": ("--confidence", "--occupancy-from-sim"),
    "--risk": ("--confidence",),
    "--seed": ("--confidence", "--occupancy-from-sim"),
    "--scenario-file": ("--confidence", "--scenarios"),
    "--workers": ("--confidence", "--scenarios"),
    "--seq": ("--sign",),
    "--force": ("--sweep",),
    "--start": ("--currents",),
}
# what a sweep does not do: refused beside --sweep rather than ignored
NOT_WITH_SWEEP = ("--confidence", "--occupancy-from-sim", "--sign", "--scenarios",
                  "--currents")


def run(args: argparse.Namespace) -> int:
    refuse_unpaired(args, NEEDS)
    if args.sweep is not None:
        if not args.output:
            raise UsageError("--sweep needs -o DIR for its CSV files and plot")
        clash = [o for o in NOT_WITH_SWEEP if getattr(args, o[2:].replace("-", "_"))]
        if clash:
            raise UsageError(f"--sweep plans at N budgets without {', '.join(clash)}: "
                             "leave one or the other out")
    args.risk = 1e-3 if args.risk is None else args.risk
    args.seed = 0 if args.seed is None else args.seed
    args.workers = (os.cpu_count() or 1) if args.workers is None else args.workers
    mission = load_mission(args)
    lat, lon, when = parse_start(args.start) if args.start else (None, None, None)
    start = (lat, lon) if lat is not None else None
    if args.sweep is not None:
        return _sweep(mission, args)
    from gliderplan.cli.progress import ProgressBar
    from gliderplan.planner import make_plan
    from gliderplan.planner.plan import InfeasibleBudget
    from gliderplan.planner.report import infeasible_json, report_json, report_text

    progress = ProgressBar(lambda done, total: f"{done:.0f} of {total:.0f} scenarios flown")
    try:
        result = make_plan(mission, battery=args.battery, computer=args.computer,
                           cycles_per_tick=args.cycles_per_tick,
                           output=args.output, confidence=args.confidence,
                           scenarios=args.scenarios, seed=args.seed, risk=args.risk,
                           scenario_file=args.scenario_file, workers=args.workers,
                           occupancy_from_sim=args.occupancy_from_sim, progress=progress,
                           sign=args.sign, seq=args.seq, currents=args.currents,
                           start=start, start_epoch_s=start_epoch_s(when))
    except InfeasibleBudget as short:  # --json prints the report beside the error (main)
        short.report = infeasible_json(short)
        raise
    finally:
        progress.finish()
    if args.json:
        print_json(report_json(result))
    else:
        print(report_text(result), end="")
        if args.output:
            written = [f"{args.output}.json", f"{args.output}.speed.png"]
            print(f"wrote {args.output} and " + " and ".join(
                w for w in written if os.path.exists(w)))
    return 0


def _sweep(mission, args: argparse.Namespace) -> int:  # noqa: ANN001
    from gliderplan.cli.progress import ProgressBar
    from gliderplan.planner import sweep_mission

    bars: dict[str, ProgressBar] = {}

    def progress(label: str, done: int, total: int) -> None:
        if label not in bars:
            for bar in bars.values():
                bar.finish()
            bars[label] = ProgressBar(lambda d, t: f"{label}: {d:.0f} of {t:.0f}")
        bars[label](done, total)

    try:
        sweep = sweep_mission(mission, args.sweep, args.output, battery=args.battery,
                              computer=args.computer, progress=progress,
                              cycles_per_tick=args.cycles_per_tick, force=args.force)
    finally:
        for bar in bars.values():
            bar.finish()
    if args.json:
        print_json({"pareto": sweep.pareto.to_dict("records"),
                    "computers": sweep.computers.to_dict("records"),
                    "batteries": sweep.batteries.to_dict("records"),
                    "files": [str(p) for p in sweep.files]})
    else:
        table = sweep.pareto[["budget_wh", "quality", "shadow_price"]]
        print(table.round({"budget_wh": 1, "quality": 4, "shadow_price": 5}).to_string(index=False))
        print(f"wrote {', '.join(p.name for p in sweep.files)} to {args.output}")
    return 0
