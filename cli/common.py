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


def replan_confidence(text: str) -> float:
    """A replan's confidence: a probability in [0.5, 1)."""
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not 0.5 <= value < 1.0:
        raise argparse.ArgumentTypeError(f"expected a probability in [0.5, 1), got {text!r}")
    return value


def add_replan_confidence_argument(parser: argparse.ArgumentParser,
                                   needs: str | None = None) -> None:
    """`--confidence P`: the probability the rest of the mission, replanned, holds its
    budget; `needs`: the option that turns replanning on, if there is one."""
    parser.add_argument("--confidence", type=replan_confidence, metavar="P",
                        help=f"{f'with {needs}: ' if needs else ''}the confidence the rest is "
                             "replanned at: the probability its budget holds (default: the "
                             "plan's own, else 0.95)")


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


def add_start_argument(parser: argparse.ArgumentParser, default: str) -> None:
    """`--start LAT,LON[,UTC]` (parse_start); `default`: what it is without one."""
    parser.add_argument("--start", metavar="LAT,LON[,UTC]",
                        help="where and when the glider is put in the water: LAT,LON "
                             "[decimal degrees], LAT,LON,UTC or UTC (ISO 8601); default: "
                             + default)


def add_currents_argument(parser: argparse.ArgumentParser, default: str) -> None:
    """`--currents` (sim.current_files.load_currents)."""
    parser.add_argument("--currents", metavar="N,E|FIELD.nc|LOGDIR",
                        help="the current the glider flies through: N,E toward north and "
                             "east [m/s]; a CF NetCDF current field (eastward/northward_"
                             "sea_water_velocity, Copernicus uo/vo, HYCOM water_u/water_v); "
                             "or Slocum flight logs (*.dbd) whose measured currents persist "
                             f"(default: {default})")


def add_at_sea_arguments(parser: argparse.ArgumentParser, currents_default: str,
                         map_shows: str) -> None:
    """`--currents` (sim.current_files.load_currents) and `--map FILE` (sim.seamap)."""
    add_currents_argument(parser, currents_default)
    parser.add_argument("--map", metavar="FILE.png",
                        help=f"also draw {map_shows} (PNG or SVG)")


def parse_start(text: str) -> tuple[float | None, float | None, str | None]:
    """`--start LAT,LON[,UTC]` or `--start UTC` -> (lat, lon [deg] or None, UTC text or
    None); UsageError naming what is wrong."""
    from gliderplan.contract.errors import UsageError

    parts = [p.strip() for p in text.split(",")]
    if len(parts) == 1:
        return None, None, parts[0]
    if len(parts) > 3:
        raise UsageError(f"--start {text!r}: expected LAT,LON[,UTC] or UTC")
    try:
        lat, lon = float(parts[0]), float(parts[1])
    except ValueError:
        raise UsageError(f"--start {text!r}: LAT,LON must be decimal degrees "
                         "(e.g. 54.75,15.10)") from None
    if not (-90.0 <= lat <= 90.0 and -180.0 <= lon <= 180.0):
        raise UsageError(f"--start {text!r}: latitude must lie in [-90, 90] and longitude "
                         "in [-180, 180] degrees")
    return lat, lon, parts[2] if len(parts) == 3 else None


def start_epoch_s(when: str | None) -> float:
    """The UTC of `--start` [s since 1970] (None: the simulator's default start)."""
    from gliderplan.contract.errors import UsageError
    from gliderplan.sim.export import parse_utc
    from gliderplan.sim.loop import DEFAULT_START_EPOCH_S

    try:
        return parse_utc(when) if when else DEFAULT_START_EPOCH_S
    except ValueError as err:
        raise UsageError(f"--start: {err}") from None
