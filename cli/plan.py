"""`gliderplan plan`: plan duty cycles, flight profiles and computer clock under a battery budget.

  plan MISSION [--battery 1.2kWh] [--computer ts7800@300] [-o PLANFILE] [--json]
  plan MISSION --sweep N -o DIR     pareto.csv, computers.csv, batteries.csv, pareto.png

With -o the plan file (docs/plan-format.md) is written to PLANFILE and its report to
PLANFILE.json. A budget below what the mission needs exits 1 with the minimum energy
and the largest consumers.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from gliderplan.cli.common import add_mission_argument, load_mission, write_atomically
from gliderplan.cli.errors import CliError, UsageError

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


def run(args: argparse.Namespace) -> int:
    if args.sweep is not None and not 2 <= args.sweep <= 10_000:
        raise UsageError("--sweep N: N must be between 2 and 10000")
    if args.sweep is not None and not args.output:
        raise UsageError("--sweep needs -o DIR for its CSV files and plot")
    mission = load_mission(args)
    from gliderplan.language.semantics import MissionFault
    from gliderplan.planner.hardware import HardwareError, load_hardware
    from gliderplan.planner.inputs import PlanInputError
    from gliderplan.planner.plan import InfeasibleBudget, PlanningError
    from gliderplan.planner.planfile import PlanFileError
    from gliderplan.power_models.errors import ModelFileError

    try:
        hardware = load_hardware(mission, battery=args.battery, computer=args.computer)
        if args.sweep is not None:
            return _sweep(mission, hardware, args)
        return _plan(mission, hardware, args)
    except HardwareError as err:
        raise UsageError(str(err)) from None
    except ModelFileError as err:
        raise UsageError(f"{err}") from None
    except InfeasibleBudget as err:
        if args.json:
            from gliderplan.planner.report import infeasible_json

            print(json.dumps(infeasible_json(str(err), err.budget_j, err.minimum_j,
                                             err.consumers), indent=2))
        raise CliError(f"{args.mission}: {err}") from None
    except (PlanningError, PlanInputError) as err:
        raise CliError(f"{args.mission}: {err}") from None
    except MissionFault as err:
        raise CliError(f"{args.mission}: the mission's timeline fails at {err}") from None
    except PlanFileError as err:
        raise CliError(f"{args.mission}: no plan file can carry this plan: {err.message} "
                       "(docs/plan-format.md)") from None


def _plan(mission, hardware, args: argparse.Namespace) -> int:
    from gliderplan.planner.plan import plan_mission
    from gliderplan.planner.planfile import write_plan_bytes
    from gliderplan.planner.report import report_json, report_text

    plan = plan_mission(mission, hardware)
    report = report_json(plan)
    if args.output:
        report_path = Path(args.output + ".json")
        write_atomically(args.output, write_plan_bytes(plan))
        write_atomically(report_path, json.dumps(report, indent=2) + "\n")
    print(json.dumps(report, indent=2) if args.json else report_text(plan), end="")
    if args.json:
        print()
    if args.output and not args.json:
        print(f"wrote {args.output} and {args.output}.json")
    return 0


def _sweep(mission, hardware, args: argparse.Namespace) -> int:
    from gliderplan.planner.plan import prepare
    from gliderplan.planner.sweep import batteries, computers, pareto, plot_pareto

    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory (--sweep writes several files there)")

    live = sys.stderr.isatty()  # a counter rewritten in place only reads on a terminal

    def progress(label: str):
        def report(done: int, total: int) -> None:
            if live:
                print(f"\r{label}: {done}/{total}", end="\n" if done == total else "",
                      file=sys.stderr, flush=True)
            elif done == total:
                print(f"{label}: {done}/{total}", file=sys.stderr, flush=True)
        return report

    _, model = prepare(mission, hardware)
    frame = pareto(model, args.sweep, progress("pareto"))
    boards = computers(mission, budget_j=hardware.budget_j, progress=progress("computers"))
    packs = batteries(mission, computer=args.computer, progress=progress("batteries"))
    write_atomically(out / "pareto.csv", frame.to_csv(index=False))
    write_atomically(out / "computers.csv", boards.to_csv(index=False))
    write_atomically(out / "batteries.csv", packs.to_csv(index=False))
    write_atomically(out / "pareto.png",
                     plot_pareto(frame, f"{mission.name}: quality against budget"))
    if args.json:
        print(json.dumps({"pareto": frame.to_dict("records"),
                          "computers": boards.to_dict("records"),
                          "batteries": packs.to_dict("records")}, indent=2))
    else:
        table = frame[["budget_wh", "quality", "shadow_price"]]
        print(table.round({"budget_wh": 1, "quality": 4, "shadow_price": 5}).to_string(index=False))
        print(f"wrote pareto.csv, computers.csv, batteries.csv and pareto.png to {out}")
    return 0
