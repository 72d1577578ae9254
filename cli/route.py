"""`gliderplan route`: the least-time route through a current field to a mission's
waypoints, against the straight line, and both flown in the simulator.

  route MISSION --currents FIELD.nc|N,E [--start LAT,LON[,UTC]] [--speed M/S]
        [--minimise time|energy] [--cells N] [--fly] [--map FILE.png] [--json]

Prints each leg's time on the straight line and on the planned route, the time saved,
and the planned route as a goto list to paste into a mission (planner/routing.py). With
--minimise, the yo's pitch (the glider's speed through the water and its draw) is
chosen too, for the least time or energy, against the straight line at the transit's
pitch (planner/route_pace.py). With --fly, both routes are flown by the simulated
glider (its yos, surfacings, position estimate and current correction) and their times
(and energies) compared.
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
                             "surfacings included, at the transit's pitch (default: the "
                             "simulated glider's; --minimise scales it to the other pitches)")
    parser.add_argument("--minimise", choices=("time", "energy"),
                        help="choose the yo's pitch too (the speed through the water), for "
                             "the least time or energy (default: headings only, at --speed)")
    parser.add_argument("--cells", type=int, default=100, metavar="N",
                        help="grid points a side each leg is searched on (default 100)")
    parser.add_argument("--fly", action="store_true",
                        help="fly both routes in the simulator and compare their times")
    parser.add_argument("--json", action="store_true", help="print the routes as JSON")


def run(args: argparse.Namespace) -> int:
    from gliderplan.contract.errors import UsageError
    from gliderplan.planner.routing import (
        CAPTURE_M,
        TRANSIT_PITCH_RAD,
        NoRoute,
        arrival,
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
    pitch, paced = TRANSIT_PITCH_RAD, None
    try:
        if args.minimise is None:
            plan = plan_route(field, start, waypoints, epoch, speed, args.cells)
        else:
            paced = _paced(field, start, waypoints, epoch, speed, args.minimise, args.cells)
            plan, speed, pitch = paced.plan, paced.pace.speed_mps, paced.pace.pitch_rad
    except NoRoute as err:
        raise UsageError(f"{args.mission}: {err}") from None
    result = plan.to_json() | {"speed_mps": speed}
    if paced is not None:
        result |= {"minimise": args.minimise} | paced.to_json()
    tracks, flown = {}, {}
    if args.fly:
        straight = paced.straight_s if paced is not None else plan.straight_s
        limit = 3.0 * (straight if math.isfinite(straight) else plan.planned_s)
        tracks = {"straight": flown_track(waypoints, field, start, epoch, limit),
                  "planned": flown_track(plan.waypoints(), field, start, epoch, limit, pitch)}
        flown = {name: arrival(track, waypoints[-1]) for name, track in tracks.items()}
        result["flown_s"] = {k: _finite(t) for k, (t, _) in flown.items()}
        result["flown_j"] = {k: _finite(j) for k, (_, j) in flown.items()}
        result["flown_gain"] = _saved(flown["planned"][0], flown["straight"][0])
        result["flown_energy_gain"] = _saved(flown["planned"][1], flown["straight"][1])
    for note in notes:
        print(note, file=sys.stderr)
    if args.map is not None:
        import numpy as np

        from gliderplan.sim.seamap import SeaMap, write_map

        lines = {f"{name} route": (np.array([start[0]] + [p[0] for p in points]),
                                   np.array([start[1]] + [p[1] for p in points]))
                 for name, points in (("straight", waypoints), ("planned", plan.waypoints()))}
        for name, (time_s, lat, lon, _) in tracks.items():  # up to its arrival
            shown = time_s <= min(flown[name][0], float(time_s[-1]))
            lines[f"{name}, flown"] = (lat[shown], lon[shown])
        write_map(args.map, SeaMap(f"{mission.name}: routes", lines, tuple(waypoints),
                                   currents=field, epoch_s=epoch))
    if args.json:
        print_json(result)
        return 0
    print(_text(result, CAPTURE_M))
    return 0


def _paced(field, start: tuple[float, float], waypoints: list[tuple[float, float]],
           epoch: float, transit_mps: float, minimise: str, cells: int):
    """The route and pitch of least time or energy (planner.route_pace)."""
    from gliderplan.planner.route_pace import paces, plan_paced_route

    nominal, choices = paces(transit_mps, waypoints)
    return plan_paced_route(field, start, waypoints, epoch, nominal, choices, minimise, cells)


def _finite(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _saved(planned: float, straight: float) -> float:
    """[1] what the planned route saves of the straight one's (1: the straight never
    arrives)."""
    return 1.0 - planned / straight if math.isfinite(straight) else 1.0


def _hours(seconds: float | None) -> str:
    return "never" if seconds is None else f"{seconds / 3600:.1f} h"


def _kj(joules: float | None) -> str:
    return "never" if joules is None else f"{joules / 1e3:.0f} kJ"


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
    if "minimise" in r:
        straight_j = r["straight_nominal_j"]
        lines.append(f"least {r['minimise']}: pitch {math.degrees(r['pitch_rad']):.0f} deg "
                     f"({r['pace_speed_mps']:.3f} m/s, {r['power_w']:.2f} W) against the "
                     f"straight line at {math.degrees(r['nominal_pitch_rad']):.0f} deg: "
                     f"{_hours(r['planned_s'])} and {r['planned_j'] / 1e3:.0f} kJ against "
                     f"{_hours(r['straight_nominal_s'])} and "
                     f"{'never' if straight_j is None else f'{straight_j / 1e3:.0f} kJ'}, "
                     f"saved {r['time_gain']:.0%} of the time, {r['energy_gain']:.0%} of the "
                     "energy")
    if "flown_s" in r:
        f, j = r["flown_s"], r["flown_j"]
        lines.append(f"flown in the simulator: straight {_hours(f['straight'])}, planned "
                     f"{_hours(f['planned'])}, saved {r['flown_gain']:.0%}; energy "
                     f"{_kj(j['straight'])} against {_kj(j['planned'])}, saved "
                     f"{r['flown_energy_gain']:.0%}")
    points = [p for leg in r["legs"] for p in leg["route"]]
    pairs = ", ".join(f"({degrees_to_ddmm(a):.4f}, {degrees_to_ddmm(b):.4f})" for a, b in points)
    lines.append(f"the planned route: flightroute goto_list({capture_m:g}, {pairs})")
    return "\n".join(lines)
