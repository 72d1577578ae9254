"""`gliderplan forecast`: what a mission will cost on a glider, by device, with its interval.

  forecast MISSION [--vehicle FILE|PRESET] [--ocean LOGDIR|PRESET|CSV] [--floor DEPTH_M]
           [--duration T] [--json]

MISSION is a gliderplan mission or a Slocum `.mi` (its .ma files in mafiles/ beside it, as
`import-slocum` reads them). Prints the energy, the duration, the yos and the surfacings,
the energy of each device and every assumption the forecast rests on. The vehicle
defaults to the mission's; calibrate yours from its logs (`gliderplan calibrate`).
"""

from __future__ import annotations

import argparse
import sys

from gliderplan.cli.main import print_json
from gliderplan.contract.errors import UsageError

ORDER = 55


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("mission", metavar="MISSION",
                        help="a mission (.mission), or a Slocum mission (.mi) with its .ma files")
    parser.add_argument("--vehicle", metavar="FILE|PRESET",
                        help="the glider: a calibrated vehicle file (gliderplan calibrate -o) "
                             "or a preset (default: the mission's)")
    parser.add_argument("--ocean", metavar="LOGDIR|PRESET|CSV",
                        help="the water it flies in: a glider's science logs (*.ebd or a "
                             "directory), a profile CSV or a preset (bench, sea-trial, "
                             "uniform); default: the vehicle's reference water")
    parser.add_argument("--floor", metavar="DEPTH_M",
                        help="the sea floor's depth [m]: a yo with an altimeter stop is "
                             "planned to turn above it (default: the floor the logs of "
                             "--ocean LOGDIR saw, else unknown: planned to max_depth)")
    parser.add_argument("--duration", metavar="T",
                        help="how long (3600s, 6h, 30d; default: the mission's horizon, else "
                             "30d)")
    parser.add_argument("--mafiles", metavar="DIR",
                        help="with a .mi: the directory of its .ma files")
    parser.add_argument("--json", action="store_true", help="print the forecast as JSON")


def run(args: argparse.Namespace) -> int:
    from gliderplan.cli.sim import parse_duration_s
    from gliderplan.planner.forecast import forecast_mission, load_forecast_mission, water

    if args.mafiles is not None and not args.mission.lower().endswith(".mi"):
        raise UsageError(f"--mafiles: {args.mission} is no Slocum .mi mission; the .ma files "
                         "are read for one alone")
    duration = None if args.duration is None else parse_duration_s(args.duration)
    mission, warnings = load_forecast_mission(args.mission, args.mafiles)
    imported = tuple(w for w in warnings if w.startswith("import-slocum: "))
    for warning in warnings:
        if warning not in imported:  # a mission's own warnings
            print(warning, file=sys.stderr)
    if imported:
        print(f"{args.mission}: {len(imported)} setting(s) the import could not carry over: "
              "listed with the assumptions", file=sys.stderr)
    from gliderplan.sim.ocean import parse_floor

    floor = None if args.floor is None else parse_floor(args.floor)
    ocean, source, floor, floor_note = water(args.ocean, floor)
    result = forecast_mission(mission, vehicle=args.vehicle, duration_s=duration, ocean=ocean,
                              ocean_source=source, floor=floor, floor_note=floor_note,
                              said=imported)
    if args.json:
        print_json(result.to_json())
    else:
        print(_text(result.to_json()))
    return 0


def _energy(joules: float, large: bool) -> str:
    return f"{joules / 3.6e6:.4g} kWh" if large else f"{joules / 1e3:.4g} kJ"


def _text(f: dict) -> str:
    low, high = f["energy_interval_j"]
    days = f["duration_s"] / 86400.0
    large = f["energy_j"] >= 3.6e6
    lines = [
        f"mission {f['mission']} on vehicle {f['vehicle']}, computer {f['computer']}",
        f"energy     {_energy(f['energy_j'], large)}, {f['interval_level']:.0%} interval "
        f"{_energy(low, large)} to {_energy(high, large)}",
        f"duration   {days:.3g} d ({f['duration_s']:,.0f} s)",
        f"yos        {f['yos']:,.0f} ({f['interval_level']:.0%} interval "
        f"{f['yos_interval'][0]:,.0f} to {f['yos_interval'][1]:,.0f})",
        f"surfacings {f['surfacings']:,.0f}",
    ]
    if f["defaults"]:
        lines.append(f"defaults   {', '.join(f['defaults'])} (not named by the mission)")
    lines += ["", "energy by device:"]
    total = f["energy_j"] or 1.0
    for name, joules in sorted(f["devices"].items(), key=lambda kv: -kv[1]):
        if joules > 0.0:
            lines.append(f"  {name:10s} {joules / 1e3:12,.1f} kJ  {joules / total:6.1%}")
    lines += ["", "assumptions:"] + [f"  - {a}" for a in f["assumptions"]]
    return "\n".join(lines)
