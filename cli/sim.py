"""`gliderplan sim`: fly a mission (and its plan) on the simulated glider and check its energy.

Writes RUNDIR/trace.csv, timeseries.parquet, summary.json, depth.png and energy.png
(and trajectory.nc with --netcdf); with --runtime c and --state-dir DIR the runtime's
own checkpoint and events.log in DIR (and with --faults its events.log in RUNDIR too).
Without --plan every sensor a state logs is always on. --faults SPEC injects faults
into the C runtime's line and board (docs/reliability.md). The plan check is one verdict
from the run's total: exit status 3, the run spent more than the plan's budget (a plan
violation); "over prediction", it spent more than the plan predicted by more than the 5 %
tolerance but kept its budget (exit 0, or 4 with --strict-prediction); the states that
overran their own prediction are listed below it, with the component responsible.
RUNDIR is written whole, replacing a previous run there (a folder holding other files is
refused without --force). Ctrl-C (or SIGTERM) in flight writes the part flown, marked
partial (summary.json: complete false), and exits 130 (143).
"""

from __future__ import annotations

import argparse
import math
import re
import sys

from gliderplan.cli.common import (
    add_at_sea_arguments,
    add_force_argument,
    add_mission_argument,
    add_replan_confidence_argument,
    add_start_argument,
    load_mission,
    parse_start,
    refuse_unpaired,
    seed,
)
from gliderplan.contract import DEFAULT_HORIZON_S, MAX_PLAN_TIME_S, TICK_S, ExitCode
from gliderplan.contract.errors import UsageError
from gliderplan.contract.units import UNITS

ORDER = 60
_DURATION = re.compile(r"^\s*([0-9]+(?:\.[0-9]*)?(?:[eE][-+]?[0-9]+)?)\s*([A-Za-z]+)\s*$")
LONG_RUN_TICKS = 100_000  # progress on stderr for runs longer than this
SHOWN_SURFACINGS = 50  # surfacings printed; summary.json holds them all


def parse_duration_s(text: str, option: str = "--duration") -> float:
    """'3600s', '90min', '6h', '30d' -> seconds; UsageError (naming `option`) otherwise."""
    match = _DURATION.match(text)
    if match is None or match[2] not in UNITS["time"]:
        raise UsageError(f"{option} {text!r}: expected a number with a unit: "
                         f"{', '.join(UNITS['time'])} (e.g. 3600s, 90min, 6h, 30d)")
    seconds = float(match[1]) * UNITS["time"][match[2]]
    if not math.isfinite(seconds) or seconds <= 0.0:
        raise UsageError(f"{option} {text!r}: must be a positive time")
    if seconds > MAX_PLAN_TIME_S:  # what a plan, a horizon and an expect bound may span
        raise UsageError(f"{option} {text!r}: must be at most "
                         f"{MAX_PLAN_TIME_S / 86400 / 365:g} years")
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
    parser.add_argument("--floor", metavar="DEPTH_M|FILE.nc",
                        help="a flat sea floor at DEPTH_M metres, or a bathymetry grid "
                             "(NetCDF: GEBCO elevation, or a depth): the altimeter reads the "
                             "height above it and the glider stops there (default: none, "
                             "the altimeter out of range; with --ocean LOGS the floor the "
                             "glider's flight logs saw)")
    parser.add_argument("--noise", choices=("none", "ctd", "nonmonotonic"), default="ctd",
                        help="sensor noise: ctd (default), none, or nonmonotonic (the "
                             "fluctuations of the paper's first sea trial)")
    parser.add_argument("--tracker", choices=("robust", "naive"), default="robust",
                        help="thermocline detection (default robust; naive: the paper's first)")
    add_at_sea_arguments(parser, "none", "the flown track, the surfacings, the waypoints "
                                         "and the current field")
    parser.add_argument("--current", dest="currents", help=argparse.SUPPRESS)  # its old name
    parser.add_argument("--seed", type=seed, default=0, help="random seed (default 0)")
    parser.add_argument("--tick", type=float, default=TICK_S, metavar="S",
                        help=f"sensor-array period [s] (default {TICK_S:g})")
    parser.add_argument("--duration", metavar="T",
                        help="end the run here if the mission has not exited (3600s, 90min, "
                             "6h, 30d; default: the mission's horizon, else 30d)")
    add_start_argument(parser, "500 m south of the mission's first waypoint, at the first "
                               "sample of replayed logs, else 2000-01-01T00:00:00Z")
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
    parser.add_argument("--strict-prediction", action="store_true",
                        help="exit 4 when the run spent more than the plan predicted by more "
                             "than its tolerance (5 %%), although within its budget")
    parser.add_argument("--json", action="store_true",
                        help="print the run's summary (summary.json) and its files as JSON")
    parser.add_argument("--replan-every", choices=("surfacing",), metavar="surfacing",
                        help="put the shore in the loop: at each surfacing the glider reports, "
                             "the rest of the mission is replanned and the plan update sent "
                             "to the runtime (needs --plan; RUNDIR/replans.csv)")
    add_replan_confidence_argument(parser, "--replan-every")
    parser.add_argument("--scenario-file", metavar="FILE",
                        help="with --replan-every: the spreads and battery share the replan's "
                             "prior takes (default: the shipped scenario file)")
    parser.add_argument("-o", "--output", metavar="RUNDIR", required=True,
                        help="directory for the run's files (written whole: it replaces "
                             "a previous run there)")
    add_force_argument(parser)


def run(args: argparse.Namespace) -> int:
    from gliderplan.sim.run import run_mission
    from gliderplan.sim.setup import FlightOptions, flight_setup

    refuse_unpaired(args, {"--confidence": ("--replan-every",),
                           "--scenario-file": ("--replan-every",)})
    mission = load_mission(args)
    lat, lon, start_utc = parse_start(args.start) if args.start else (None, None, None)
    duration_s = parse_duration_s(args.duration) if args.duration else None
    ticks = mission.run_limit_s(duration_s) / max(args.tick, 1e-9)
    from gliderplan.cli.progress import ProgressBar

    progress = ProgressBar(lambda done, total: f"{done / 86400:.2f} of {total / 86400:.2f} d "
                           "simulated") if ticks > LONG_RUN_TICKS else None
    try:
        options = FlightOptions(
            plan_path=args.plan, runtime=args.runtime, ocean=args.ocean, noise=args.noise,
            tracker=args.tracker, currents=args.currents, seed=args.seed, tick_s=args.tick,
            duration_s=duration_s, start_utc=start_utc,
            start_position=None if lat is None else (lat, lon), floor=args.floor,
            faults=args.faults, key_path=args.key, state_dir=args.state_dir)
        result = run_mission(flight_setup(mission, options), args.output, netcdf=args.netcdf,
                             progress=progress, replan_every=args.replan_every,
                             confidence=args.confidence, scenario_file=args.scenario_file,
                             force=args.force, mission_path=args.mission)
    finally:
        if progress is not None:
            progress.finish()
    record, check = result.record, result.check
    print(f"{mission.name}: {record.ended} after {_time_text(record.columns['time_s'][-1])}, "
          f"{len(record.trace)} transitions, {result.energy.total_j / 1e3:.1f} kJ; "
          f"plan check: {check.headline}", file=sys.stderr)
    stops = any(p.has_altimeter_stop for s in mission.states for p in s.profiles)
    density, floor = result.water_notes[0], result.water_notes[1:]
    if args.ocean is not None:
        print(f"  {density}", file=sys.stderr)
    if args.floor is not None or stops or result.record.grounded_ticks \
            or _replayed(args.ocean):
        for note in floor:
            print(f"  {note}", file=sys.stderr)
    if duration_s is None and mission.horizon_s is None and record.ended == "duration":
        print(f"  ran to the default horizon, {DEFAULT_HORIZON_S / 86400:g} d: the mission names "
              "none (--duration sets another)", file=sys.stderr)
    for note in result.current_notes:
        print(f"  {note}", file=sys.stderr)
    if args.replan_every:
        print(_replanning(result), file=sys.stderr)
    _print_surfacings(result.record)
    if args.map is not None:
        _draw_map(args.map, mission, result)
    if check.causes:
        print("  states over their own prediction:" if check.verdict != "violation" or
              "planned" in check.causes[0] else "  where it went:", file=sys.stderr)
    for cause in check.causes:
        print(f"    {cause}", file=sys.stderr)
    for note in record.envelope:
        print(f"  {note}", file=sys.stderr)
    if record.faults is not None and record.faults["kills"] < record.faults["kills_asked"]:
        print(f"  kill={record.faults['kills_asked']}: {record.faults['kills']} delivered; the "
              "run ended before the others fell due (drawn over the mission's timeline; "
              "kill=N@T draws them over T)", file=sys.stderr)
    if result.interrupted:
        print(f"  interrupted: the outputs in {args.output} cover the part flown, "
              f"{_time_text(record.columns['time_s'][-1])} (summary.json: complete false)",
              file=sys.stderr)
        code = ExitCode.INTERRUPTED
    elif result.stopped:
        print(f"  interrupted once the flight was over: the outputs in {args.output} hold "
              "all of it", file=sys.stderr)
        code = ExitCode.INTERRUPTED
    elif record.envelope_acted:
        print("  the vehicle was commanded outside its rating (its vehicle file's "
              "[envelope])", file=sys.stderr)
        code = ExitCode.ENVELOPE
    elif record.ended.startswith("fault"):
        print(f"  the outputs in {args.output} cover the part flown", file=sys.stderr)
        code = ExitCode.LINK_FAILED
    elif check.verdict == "violation":
        code = ExitCode.OVER_BUDGET
    elif check.verdict == "over prediction" and args.strict_prediction:
        code = ExitCode.OVER_PREDICTION
    else:
        code = ExitCode.OK
    if args.json:
        import json

        from gliderplan.cli.main import print_json

        written = next(f for f in result.files if f.name == "summary.json")
        summary = json.loads(written.read_text())  # as written: what a pipeline reads later
        print_json({"ok": code == ExitCode.OK, "exit_code": int(code), **summary,
                    "files": [str(f) for f in result.files]})
    return code


def _print_surfacings(record) -> None:
    """Each surfacing's time and position (the first SHOWN_SURFACINGS; summary.json has
    them all)."""
    from gliderplan.sim.outputs import surfacing_fixes

    fixes = surfacing_fixes(record)
    if fixes:
        print("  surfacings (GPS fix: time, position; one run, no ellipse: gliderplan "
              "forecast gives them):", file=sys.stderr)
    for i, fix in enumerate(fixes[:SHOWN_SURFACINGS], start=1):
        print(f"    {i:4d}  {_time_text(fix['time_s']):>9s}  {fix['lat']:9.5f} {fix['lon']:10.5f}",
              file=sys.stderr)
    if len(fixes) > SHOWN_SURFACINGS:
        print(f"    ... {len(fixes) - SHOWN_SURFACINGS} more in summary.json", file=sys.stderr)


def _draw_map(path: str, mission, result) -> None:
    """`--map`: the run's track, surfacings, waypoints and current field."""
    import numpy as np

    from gliderplan.sim.loop import route_points_deg
    from gliderplan.sim.outputs import surfacing_fixes
    from gliderplan.sim.seamap import SeaMap, write_map

    c = result.record.columns
    write_map(path, SeaMap(f"{mission.name}: flown track",
                           {"flown": (np.asarray(c["lat_deg"]), np.asarray(c["lon_deg"]))},
                           tuple(route_points_deg(mission)),
                           tuple(surfacing_fixes(result.record)), result.currents))


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


def _replanning(result) -> str:  # noqa: ANN001
    """What the shore did at the surfacings of a run with replanning."""
    link = result.replanning
    return (f"  replanned at {link['surfacings']} surfacings: {link['updates_applied']} updates "
            f"applied, {link['updates_refused']} refused; link {link['up_bytes']:,} bytes up, "
            f"{link['down_bytes']:,} down, the largest update {link['update_bytes_max']} bytes")
