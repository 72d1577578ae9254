"""`gliderplan route`: the least-time route through a current field to a mission's
waypoints, against the straight line, and both flown in the simulator.

  route MISSION --currents FIELD.nc|N,E [--start LAT,LON[,UTC]] [--speed M/S]
        [--cells N] [--fly] [--map FILE.png] [--json]

Prints each leg's time on the straight line and on the planned route, the time saved,
and the planned route as a goto list to paste into a mission (planner/routing.py). With
--fly, both routes are flown by the simulated glider (its yos, surfacings, position
estimate and current correction) and their times compared.
"""

from __future__ import annotations

import argparse
import math
import sys

from gliderplan.cli.common import (
    add_at_sea_arguments,
    add_mission_argument,
    add_start_argument,
    load_mission,
    parse_start,
)
from gliderplan.cli.common import start_epoch_s as parse_epoch
from gliderplan.cli.main import print_json

ORDER = 57


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    add_start_argument(parser, "as sim puts it in the water")
    add_at_sea_arguments(parser, "none: give one", "both routes (and, with --fly, both "
                                                   "flown tracks) over the current field")
    parser.add_argument("--speed", type=float, metavar="M/S",
                        help="the glider's speed over the ground in still water, yos and "
                             "surfacings included (default: the simulated glider's)")
    parser.add_argument("--cells", type=int, default=100, metavar="N",
                        help="grid points a side each leg is searched on (default 100)")
    parser.add_argument("--fly", action="store_true",
                        help="fly both routes in the simulator and compare their times")
    parser.add_argument("--json", action="store_true", help="print the routes as JSON")


def run(args: argparse.Namespace) -> int:
    from gliderplan.contract.errors import UsageError
    from gliderplan.planner.routing import (
        CAPTURE_M,
        NoRoute,
        arrival_s,
        flown_track,
        plan_route,
        transit_speed_mps,
    )
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim.current_files import checked_field
    from gliderplan.sim.loop import RunConfig, route_points_deg, start_position

    mission = load_mission(args)
    if args.currents is None:
        raise UsageError("--currents: route plans through a current field: give one")
    waypoints = route_points_deg(mission)
    if not waypoints:
        raise UsageError(f"{args.mission}: the mission has no waypoint to route to")
    if not 10 <= args.cells <= 400:
        raise UsageError(f"--cells {args.cells}: between 10 and 400")
    if args.speed is not None and not 0.05 <= args.speed <= 2.0:
        raise UsageError(f"--speed {args.speed:g}: a glider flies 0.05 to 2 m/s")
    lat, lon, when = parse_start(args.start) if args.start else (None, None, None)
    epoch = parse_epoch(when)
    start = (lat, lon) if lat is not None else start_position(mission, RunConfig())
    speed = args.speed or transit_speed_mps()
    field, notes = checked_field(args.currents, mission, load_vehicle(mission.vehicle),
                                 start, epoch, 0.0)
    try:
        plan = plan_route(field, start, waypoints, epoch, speed, args.cells)
    except NoRoute as err:
        raise UsageError(f"{args.mission}: {err}") from None
    result = plan.to_json() | {"speed_mps": speed}
    tracks, flown = {}, {}
    if args.fly:
        limit = 3.0 * (plan.straight_s if math.isfinite(plan.straight_s) else plan.planned_s)
        tracks = {name: flown_track(points, field, start, epoch, limit)
                  for name, points in (("straight", waypoints), ("planned", plan.waypoints()))}
        flown = {name: arrival_s(track, waypoints[-1]) for name, track in tracks.items()}
        result["flown_s"] = {k: (v if math.isfinite(v) else None) for k, v in flown.items()}
        result["flown_gain"] = 1.0 - flown["planned"] / flown["straight"] \
            if math.isfinite(flown["straight"]) else 1.0
    for note in notes:
        print(note, file=sys.stderr)
    if args.map is not None:
        import numpy as np

        from gliderplan.sim.seamap import SeaMap, write_map

        lines = {f"{name} route": (np.array([start[0]] + [p[0] for p in points]),
                                   np.array([start[1]] + [p[1] for p in points]))
                 for name, points in (("straight", waypoints), ("planned", plan.waypoints()))}
        for name, (time_s, lat, lon) in tracks.items():  # up to its arrival
            shown = time_s <= min(flown[name], float(time_s[-1]))
            lines[f"{name}, flown"] = (lat[shown], lon[shown])
        write_map(args.map, SeaMap(f"{mission.name}: routes", lines, tuple(waypoints),
                                   currents=field, epoch_s=epoch))
    if args.json:
        print_json(result)
        return 0
    print(_text(result, CAPTURE_M))
    return 0


def _hours(seconds: float | None) -> str:
    return "never" if seconds is None else f"{seconds / 3600:.1f} h"


def _text(r: dict, capture_m: float) -> str:
    from gliderplan.sim.geo import degrees_to_ddmm

    lines = [f"planned at {r['speed_mps']:.3f} m/s over the ground in still water",
             "leg  waypoint              straight    planned    saved"]
    for i, leg in enumerate(r["legs"], start=1):
        lat, lon = leg["waypoint"]
        saved = 1.0 - leg["planned_s"] / leg["straight_s"] if leg["straight_s"] else 1.0
        lines.append(f"{i:3d}  {lat:9.5f} {lon:10.5f}  {_hours(leg['straight_s']):>9s}  "
                     f"{_hours(leg['planned_s']):>9s}  {saved:6.0%}")
    lines.append(f"all  {'':20s}  {_hours(r['straight_s']):>9s}  {_hours(r['planned_s']):>9s}"
                 f"  {r['gain']:6.0%}")
    if "flown_s" in r:
        f = r["flown_s"]
        lines.append(f"flown in the simulator: straight {_hours(f['straight'])}, planned "
                     f"{_hours(f['planned'])}, saved {r['flown_gain']:.0%}")
    points = [p for leg in r["legs"] for p in leg["route"]]
    pairs = ", ".join(f"({degrees_to_ddmm(a):.4f}, {degrees_to_ddmm(b):.4f})" for a, b in points)
    lines.append(f"the planned route: flightroute goto_list({capture_m:g}, {pairs})")
    return "\n".join(lines)
