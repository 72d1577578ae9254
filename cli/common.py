"""What several subcommands share: the mission argument and loading a checked mission."""

from __future__ import annotations

import argparse
import math
import sys

from gliderplan.contract import DEFAULT_STACK_DEPTH, MAX_STACK_DEPTH, RUNTIME_CYCLES_PER_TICK
from gliderplan.language import check_file
from gliderplan.language.ir import CheckedMission


def add_mission_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("mission", help="mission file (any name; .mission by convention)")
    add_max_stack_argument(parser)


def add_max_stack_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--max-stack", type=int, metavar="N", default=None,
                        help=f"runtime state-stack depth, 1 to {MAX_STACK_DEPTH} "
                             f"(default: the mission's, else {DEFAULT_STACK_DEPTH})")


def cycles_per_tick(text: str) -> float:
    """A workload in cycles per tick (argparse type): a positive finite number."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a positive number of cycles, got {text!r}")
    return value


def seed(text: str) -> int:
    """A random seed (argparse type): an integer >= 0, as numpy's SeedSequence takes."""
    try:
        value = int(text)
    except ValueError:
        value = -1
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected an integer >= 0, got {text!r}")
    return value


def refuse_unpaired(args: argparse.Namespace, needs: dict[str, tuple[str, ...]]) -> None:
    """UsageError for an option given without one of the options it works with: `needs`
    maps an option ("--scenarios") to those ("--confidence", "--occupancy-from-sim"); an
    option is given when its value is neither None nor False."""
    from gliderplan.contract.errors import UsageError

    def given(option: str) -> bool:
        return getattr(args, option.lstrip("-").replace("-", "_")) not in (None, False)

    for option, partners in needs.items():
        if given(option) and not any(given(p) for p in partners):
            raise UsageError(f"{option} works only with {' or '.join(partners)}: give "
                             f"{'one of them' if len(partners) > 1 else 'it'} too, or leave "
                             f"{option} out")


def add_force_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--force", action="store_true",
                        help="write into an -o folder that holds files other than a "
                             "gliderplan run's: they are deleted (without it such a folder "
                             "is refused; a previous run's folder is always replaced whole)")


def add_cycles_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--cycles-per-tick", type=cycles_per_tick, metavar="N",
                        default=RUNTIME_CYCLES_PER_TICK,
                        help="the board's work every tick [cycles] in states that do not say "
                             f"(default: {RUNTIME_CYCLES_PER_TICK:,.0f}, the runtime's whole "
                             "tick, an assumption: compare-sbc sets it beside each board's "
                             "measured code)")


def load_mission(args: argparse.Namespace) -> CheckedMission:
    """The checked mission named on the command line; its warnings go to stderr (its
    errors travel in the MissionError that `checked` raises)."""
    result = check_file(args.mission, args.max_stack)
    mission = result.checked()
    if result.diagnostics:
        print(result.render(), file=sys.stderr)
    return mission
