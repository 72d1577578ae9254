"""`gliderplan compare-vehicles`: the same mission on a glider, a hybrid and an AUV.

  compare-vehicles MISSION --vehicle NAME|FILE [--vehicle ...] [--battery 1kWh] [--json]

Plans the mission on each vehicle in place of its own (a state's alternatives a vehicle
cannot fly get no time) and prints its energy, time, distance, the least energy per km
in still water at its best speed, its range on the battery, and the head currents where
the cheapest vehicle per km changes (where the propeller pays).
"""

from __future__ import annotations

import argparse
import json

from gliderplan.cli.common import add_mission_argument, load_mission

ORDER = 36


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    parser.add_argument("--vehicle", metavar="NAME|FILE", action="append", required=True,
                        help="a vehicle to fly the mission on (repeatable): a preset "
                             "(slocum_g2_shallow, slocum_g3_hybrid, lauv) or a vehicle file")
    parser.add_argument("--battery", metavar="ENERGY|PRESET",
                        help="battery energy (1kWh, 60Ah@14.4V) or preset; default: the "
                             "mission's")
    parser.add_argument("--json", action="store_true", help="print the comparison as JSON")


def run(args: argparse.Namespace) -> int:
    mission = load_mission(args)
    from gliderplan.planner.vehicles import HEAD_CURRENTS_MPS, compare_vehicles, crossovers

    results = compare_vehicles(mission, args.vehicle, battery=args.battery)
    flips = crossovers(results)
    if args.json:
        print(json.dumps({
            "mission": mission.name,
            "vehicles": [{"vehicle": r.vehicle, "kind": r.kind, "energy_j": r.energy_j,
                          "duration_s": r.duration_s, "distance_km": r.distance_km,
                          "energy_per_km_j": r.energy_per_km_j,
                          "best_speed_mps": r.best_speed_mps, "range_km": r.range_km,
                          "energy_per_km_against_current_j": [
                              None if x != x else x for x in r.per_km_against_current_j]}
                         for r in results],
            "head_currents_mps": [float(c) for c in HEAD_CURRENTS_MPS],
            "crossovers": flips}, indent=2))
        return 0
    print(f"mission {mission.name} on {len(results)} vehicles")
    print(f"{'vehicle':20s} {'kind':7s} {'energy kJ':>10s} {'time h':>7s} {'km':>7s} "
          f"{'kJ/km':>7s} {'at m/s':>7s} {'range km':>9s}")
    for r in results:
        print(f"{r.vehicle:20s} {r.kind:7s} {r.energy_j / 1e3:10.1f} {r.duration_s / 3600:7.2f} "
              f"{r.distance_km:7.2f} {r.energy_per_km_j / 1e3:7.2f} {r.best_speed_mps:7.3g} "
              f"{r.range_km:9.1f}")
    for f in flips:
        print(f"against a head current of {f['head_current_mps']:.3g} m/s and more, "
              f"{f['to']} needs the least energy per km" + (
                  f" (before: {f['from']})" if f["from"] else ""))
    return 0
