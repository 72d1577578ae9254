"""`gliderplan forecast`: what a mission will cost on a glider, by device, with its interval.

  forecast MISSION [--vehicle FILE|PRESET] [--ocean LOGDIR|PRESET|CSV] [--floor DEPTH_M]
           [--duration T] [--start LAT,LON[,UTC]] [--currents N,E|FIELD.nc|LOGDIR]
           [--surfacings-out FILE.geojson|FILE.kml] [--json]

MISSION is a gliderplan mission or a Slocum `.mi` (its .ma files in mafiles/ beside it, as
`import-slocum` reads them). Prints the energy, the duration, the yos and the surfacings,
the energy of each device, every surfacing's time and position with its 90 % ellipse
(planner/surfacings.py, docs/at-sea.md) and every assumption the forecast rests on. The vehicle
defaults to the mission's; calibrate yours from its logs (`gliderplan calibrate`).
"""

from __future__ import annotations

import argparse
import sys

from gliderplan.cli.common import (
    add_at_sea_arguments,
    add_start_argument,
    parse_start,
    start_epoch_s,
)
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
    add_start_argument(parser, "500 m south of the mission's first waypoint, at "
                               "2000-01-01T00:00:00Z")
    add_at_sea_arguments(parser, "the currents measured in --ocean LOGDIR's flight logs, "
                                 "else none, with its uncertainty",
                         "the surfacings with their 90 %% ellipses, the waypoints and the "
                         "current field")
    parser.add_argument("--surfacings-out", metavar="FILE",
                        help="also write the surfacings and their ellipses as GeoJSON "
                             "(*.geojson, *.json) or KML (*.kml)")
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
    out = _surfacings_format(args.surfacings_out)
    ocean, source, floor, floor_note = water(args.ocean, floor)
    result = forecast_mission(mission, vehicle=args.vehicle, duration_s=duration, ocean=ocean,
                              ocean_source=source, floor=floor, floor_note=floor_note,
                              said=imported)
    result = with_surfacings(result, mission, args)
    if args.json:
        print_json(result.to_json())
    else:
        print(_text(result.to_json()))
    if out is not None:
        from gliderplan.contract.files import write_atomically
        from gliderplan.planner.surfacings import geojson, kml

        positions = list(result.positions)
        write_atomically(args.surfacings_out, geojson(positions, result.start_epoch_s)
                         if out == "geojson" else
                         kml(positions, result.start_epoch_s, mission.name))
    if args.map is not None:
        from gliderplan.sim.loop import route_points_deg
        from gliderplan.sim.seamap import SeaMap, write_map

        write_map(args.map, SeaMap(f"{mission.name}: forecast surfacings",
                                   waypoints=tuple(route_points_deg(mission)),
                                   surfacings=tuple(p.to_json() for p in result.positions),
                                   currents=result.currents, epoch_s=result.start_epoch_s))
    return 0


def _surfacings_format(path: str | None) -> str | None:
    """'geojson' or 'kml' by the file's name; UsageError for another."""
    if path is None:
        return None
    suffix = path.lower().rsplit(".", 1)[-1]
    if suffix in ("geojson", "json", "kml"):
        return "kml" if suffix == "kml" else "geojson"
    from gliderplan.contract.errors import UsageError

    raise UsageError(f"--surfacings-out {path}: expected a .geojson, .json or .kml file")


def with_surfacings(result, mission, args: argparse.Namespace):
    """`result` with where and when the glider surfaces, and what that rests on."""
    from dataclasses import replace
    from pathlib import Path

    from gliderplan.planner.surfacings import CURRENT_SIGMA_MPS, mission_surfacings
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim.current_files import checked_field, read_logged_currents
    from gliderplan.sim.currents import UniformCurrent
    from gliderplan.sim.loop import RunConfig, start_position

    lat, lon, when = parse_start(args.start) if args.start else (None, None, None)
    epoch = start_epoch_s(when)
    vehicle = load_vehicle(args.vehicle or mission.vehicle)
    start = (lat, lon) if lat is not None else start_position(mission, RunConfig())
    notes = []
    if args.currents is not None:
        field, notes = checked_field(args.currents, mission, vehicle, start, epoch,
                                     result.duration_s)
    elif args.ocean and Path(args.ocean).is_dir() and any(Path(args.ocean).glob("*.dbd")):
        field = read_logged_currents(args.ocean)
        notes = [f"currents: {field.description}, each held until the next"]
    else:
        field = UniformCurrent(0.0, 0.0)
        notes = ["currents: none given (--currents): still water"]
    notes.append(f"surfacings: when the mission's timeline surfaces, from "
                 f"{start[0]:.5f}, {start[1]:.5f} through the waypoints; ellipses of 90 % "
                 f"from 200 draws of a current straying {CURRENT_SIGMA_MPS:g} m/s, the "
                 "speed through the water and each dive's length")
    positions = mission_surfacings(mission, vehicle, result.duration_s, start, epoch, field)
    return replace(result, positions=tuple(positions), start_epoch_s=epoch, currents=field,
                   assumptions=result.assumptions + tuple(notes))


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
        f"surfacings {f['surfacing_count']:,.0f}",
    ]
    if f["defaults"]:
        lines.append(f"defaults   {', '.join(f['defaults'])} (not named by the mission)")
    lines += ["", "energy by device:"]
    total = f["energy_j"] or 1.0
    for name, joules in sorted(f["devices"].items(), key=lambda kv: -kv[1]):
        if joules > 0.0:
            lines.append(f"  {name:10s} {joules / 1e3:12,.1f} kJ  {joules / total:6.1%}")
    if f["surfacings"]:
        lines += ["", "surfacings (time after the start, position, 90 % ellipse semi-axes):"]
        lines += [f"  {i:4d}  {s['time_s'] / 3600:8.2f} h  {s['lat']:9.5f} {s['lon']:10.5f}"
                  f"  {s['ellipse_m'][0]:7.0f} x {s['ellipse_m'][1]:.0f} m"
                  for i, s in enumerate(f["surfacings"], start=1)]
    lines += ["", "assumptions:"] + [f"  - {a}" for a in f["assumptions"]]
    return "\n".join(lines)
