"""`gliderplan sim`: fly a mission (and its plan) on the simulated glider and check its energy.

Writes RUNDIR/trace.csv, timeseries.parquet, summary.json, depth.png and energy.png
(and trajectory.nc with --netcdf); with --runtime c and --state-dir DIR the runtime's
own checkpoint and events.log in DIR (and with --faults its events.log in RUNDIR too).
Without --plan every sensor a state logs is always on. --faults SPEC injects faults
into the C runtime's line and board (docs/reliability.md). Exit status 3: the run spent
more than the plan's budget (a plan violation; summary.json names the cause). A run
within its budget in which a state spent more than 5 % over its prediction says "plan
check: over prediction" and names the state and the component (exit 0).
"""

from __future__ import annotations

import argparse
import math
import re
import sys

from gliderplan.cli.common import add_mission_argument, load_mission, seed
from gliderplan.contract import DEFAULT_HORIZON_S, TICK_S, ExitCode
from gliderplan.contract.errors import UsageError
from gliderplan.contract.units import UNITS

ORDER = 60
_DURATION = re.compile(r"^\s*([0-9]+(?:\.[0-9]*)?(?:[eE][-+]?[0-9]+)?)\s*([A-Za-z]+)\s*$")
LONG_RUN_TICKS = 100_000  # progress on stderr for runs longer than this


def parse_duration_s(text: str, option: str = "--duration") -> float:
    """'3600s', '90min', '6h', '30d' -> seconds; UsageError (naming `option`) otherwise."""
    match = _DURATION.match(text)
    if match is None or match[2] not in UNITS["time"]:
        raise UsageError(f"{option} {text!r}: expected a number with a unit: "
                         f"{', '.join(UNITS['time'])} (e.g. 3600s, 90min, 6h, 30d)")
    seconds = float(match[1]) * UNITS["time"][match[2]]
    if not math.isfinite(seconds) or seconds <= 0.0:
        raise UsageError(f"{option} {text!r}: must be a positive time")
    return seconds


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    parser.add_argument("--plan", metavar="PLANFILE",
                        help="plan file to fly; the run is checked against the budget and "
                             "the per-state prediction it carries")
    parser.add_argument("--runtime", choices=("step", "python", "c"),
                        help="step: the compiled runtime's step in this process (default; "
                             "python where no C compiler is installed); python: the "
                             "reference executor; c: the compiled runtime over a "
                             "pseudo-terminal")
    parser.add_argument("--state-dir", metavar="DIR",
                        help="with --runtime c: the runtime keeps its checkpoints and event "
                             "log in DIR as on the glider (created if missing; must hold no "
                             "checkpoint)")
    parser.add_argument("--ocean", metavar="PRESET|FILE",
                        help="bench, sea-trial, uniform; a CSV file "
                             "depth_m,temperature_c[,salinity_psu][,time_s]; or Slocum "
                             "science logs to replay: FILE.ebd or a directory of them. The "
                             "glider flies its in-situ density, ballasted for it as "
                             "forecast does (default: bench's temperatures in uniform water "
                             "of the vehicle's reference density)")
    parser.add_argument("--floor", metavar="DEPTH_M",
                        help="a flat sea floor at DEPTH_M metres: the altimeter reads the "
                             "height above it and the glider stops there (default: none, "
                             "the altimeter out of range; with --ocean LOGS the floor the "
                             "glider's flight logs saw)")
    parser.add_argument("--noise", choices=("none", "ctd", "nonmonotonic"), default="ctd",
                        help="sensor noise: ctd (default), none, or nonmonotonic (the "
                             "fluctuations of the paper's first sea trial)")
    parser.add_argument("--tracker", choices=("robust", "naive"), default="robust",
                        help="thermocline detection (default robust; naive: the paper's first)")
    parser.add_argument("--current", metavar="N,E", default="0,0",
                        help="depth-averaged current toward north and east [m/s]")
    parser.add_argument("--seed", type=seed, default=0, help="random seed (default 0)")
    parser.add_argument("--tick", type=float, default=TICK_S, metavar="S",
                        help=f"sensor-array period [s] (default {TICK_S:g})")
    parser.add_argument("--duration", metavar="T",
                        help="end the run here if the mission has not exited (3600s, 90min, "
                             "6h, 30d; default: the mission's horizon, else 30d)")
    parser.add_argument("--start", metavar="UTC",
                        help="UTC time the mission starts, ISO 8601 (default: the first "
                             "sample of replayed logs, else 2000-01-01T00:00:00Z)")
    parser.add_argument("--netcdf", action="store_true",
                        help="also write RUNDIR/trajectory.nc (CF trajectory, IOOS Glider "
                             "DAC names, ACDD attributes); more formats: gliderplan export")
    parser.add_argument("--key", metavar="KEYFILE",
                        help="the key provisioned on the simulated vehicle (gliderplan "
                             "keygen): the plan must be signed with it (plan --sign); with "
                             "--runtime c it is uploaded over the link and the runtime checks it")
    parser.add_argument("--faults", metavar="SPEC",
                        help="with --runtime c: faults to inject on the line and into the "
                             "runtime's board, e.g. drop=0.01,flip=1e-4,dup=0.01,burst=5@0.001,"
                             "disconnect=600s@3600s,kill=10 (docs/reliability.md)")
    parser.add_argument("-o", "--output", metavar="RUNDIR", required=True,
                        help="directory for the run's files")


def _current(text: str):
    from gliderplan.sim.vehicle import MAX_CURRENT_MPS, Current

    try:
        north, east = (float(x) for x in text.split(","))
    except ValueError:
        raise UsageError(f"--current {text!r}: expected two numbers N,E [m/s]") from None
    if not math.hypot(north, east) <= MAX_CURRENT_MPS:  # nan fails too
        raise UsageError(f"--current {text!r}: the speed must be finite and at most "
                         f"{MAX_CURRENT_MPS:g} m/s")
    return Current(north, east)


def run(args: argparse.Namespace) -> int:
    from gliderplan.sim.run import run_mission

    mission = load_mission(args)
    duration_s = parse_duration_s(args.duration) if args.duration else None
    ticks = (duration_s or mission.horizon_s or DEFAULT_HORIZON_S) / max(args.tick, 1e-9)
    from gliderplan.cli.progress import ProgressBar

    progress = ProgressBar(lambda done, total: f"{done / 86400:.2f} of {total / 86400:.2f} d "
                           "simulated") if ticks > LONG_RUN_TICKS else None
    try:
        result = run_mission(
            mission, args.output, plan_path=args.plan, runtime=args.runtime, ocean=args.ocean,
            noise=args.noise, tracker=args.tracker, current=_current(args.current),
            seed=args.seed, tick_s=args.tick, duration_s=duration_s, start_utc=args.start,
            netcdf=args.netcdf, progress=progress, key_path=args.key,
            state_dir=args.state_dir, faults=args.faults, floor=args.floor)
    finally:
        if progress is not None:
            progress.finish()
    record, check = result.record, result.check
    print(f"{mission.name}: {record.ended} after {_time_text(record.columns['time_s'][-1])}, "
          f"{len(record.trace)} transitions, {result.energy.total_j / 1e3:.1f} kJ; "
          f"plan check: {check.verdict}", file=sys.stderr)
    stops = any(p.has_altimeter_stop for s in mission.states for p in s.profiles)
    density, floor = result.water_notes[0], result.water_notes[1:]
    if args.ocean is not None:
        print(f"  {density}", file=sys.stderr)
    if args.floor is not None or stops or result.record.grounded_ticks \
            or _replayed(args.ocean):
        for note in floor:
            print(f"  {note}", file=sys.stderr)
    if check.causes:
        print("  over the plan's prediction:" if check.verdict == "over prediction"
              else "  cause:",
              file=sys.stderr)
    for cause in check.causes:
        print(f"    {cause}", file=sys.stderr)
    if result.interrupted:
        print(f"  interrupted: the outputs in {args.output} cover the part flown",
              file=sys.stderr)
        return ExitCode.INTERRUPTED
    return ExitCode.OVER_BUDGET if check.verdict == "violation" else ExitCode.OK


def _replayed(ocean: str | None) -> bool:
    """Whether `--ocean` names Slocum logs, which give a sea floor (or say why not)."""
    from pathlib import Path

    from gliderplan.sim.ocean import PRESETS

    return ocean is not None and ocean not in PRESETS and (
        Path(ocean).is_dir() or ocean.lower().endswith(".ebd"))


def _time_text(seconds: float) -> str:
    """Mission time as a pilot reads it: 2500 s, 5.2 h, 12.0 d."""
    if seconds >= 2 * 86400:
        return f"{seconds / 86400:.1f} d"
    if seconds >= 3 * 3600:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds:g} s"
