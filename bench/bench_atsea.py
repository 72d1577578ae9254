"""Benchmark: a 12-hour surfacing forecast with its 200 draws in a gridded current field,
and current-aware routing across a 100 x 100 field over 10 waypoints (headings only, and
with the pitch chosen for the least energy), each the whole `gliderplan` command a user
runs (targets: under 5 s and under 10 s).

    .venv/bin/python bench/bench_atsea.py [--runs 3]

The baselines, in the same run: the same forecast in still water (its surfacings drawn
without the field), and `gliderplan check` of the routed mission (the start-up every
command pays).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np
from whole_process import gliderplan, load_average, median_of

from gliderplan.planner.routing import transit_mission

FORECAST_TARGET_S, ROUTE_TARGET_S = 5.0, 10.0
START = "39.10,-73.90,2016-06-23T00:00Z"


def write_field(path: Path) -> None:
    """100 x 100 points over 0.5 x 0.6 degrees, 3 days: an eastward jet and an eddy."""
    import pandas as pd
    import xarray as xr

    lat, lon = np.linspace(38.9, 39.4, 100), np.linspace(-74.1, -73.5, 100)
    grid_lat, grid_lon = np.meshgrid(lat, lon, indexing="ij")
    east = 0.3 * np.exp(-((grid_lat - 39.2) / 0.03) ** 2)
    r2 = ((grid_lat - 39.05) / 0.05) ** 2 + ((grid_lon + 73.7) / 0.06) ** 2
    north = 0.15 * (grid_lon + 73.7) / 0.06 * np.exp(-r2)
    east = east - 0.15 * (grid_lat - 39.05) / 0.05 * np.exp(-r2)
    times = pd.date_range("2016-06-22", periods=4, freq="1D")
    dims = ("time", "latitude", "longitude")
    xr.Dataset({"uo": (dims, np.repeat(east[None], 4, 0)),
                "vo": (dims, np.repeat(north[None], 4, 0))},
               coords={"time": times, "latitude": lat, "longitude": lon}).to_netcdf(path)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        field, mission = Path(tmp) / "field.nc", Path(tmp) / "transit.mission"
        write_field(field)
        rng = np.random.default_rng(0)
        points = [(float(a), float(b)) for a, b in
                  zip(rng.uniform(38.95, 39.35, 10), rng.uniform(-74.05, -73.55, 10),
                      strict=True)]
        mission.write_text(transit_mission(points, 12 * 3600.0, surface_every_s=3600.0))
        times = median_of({
            "forecast": gliderplan("forecast", str(mission), "--duration", "12h", "--start",
                                   START, "--currents", str(field), "--json"),
            "forecast, still water": gliderplan("forecast", str(mission), "--duration",
                                                "12h", "--json"),
            "route": gliderplan("route", str(mission), "--start", START, "--currents",
                                str(field), "--speed", "0.25", "--json"),
            "route --minimise energy": gliderplan("route", str(mission), "--start", START,
                                                  "--currents", str(field), "--speed", "0.25",
                                                  "--minimise", "energy", "--json"),
            "check": gliderplan("check", str(mission)),
        }, args.runs)
    print(f"whole process, median of {args.runs} ({load_average()}):")
    for name, t in times.items():
        print(f"  {name:24s} {t.wall_s:6.2f} s wall, {t.cpu_s:6.2f} s CPU")
    forecast, route = times["forecast"].wall_s, times["route"].wall_s
    paced = times["route --minimise energy"].wall_s
    still, check = times["forecast, still water"].wall_s, times["check"].wall_s
    print(f"the field adds {forecast - still:.2f} s to the forecast ({forecast / still:.1f}x); "
          f"routing {route / check:.1f}x a check, with the pitch chosen {paced / check:.1f}x "
          f"({paced / route:.1f}x headings only)")
    ok = forecast < FORECAST_TARGET_S and max(route, paced) < ROUTE_TARGET_S
    print(f"targets: forecast < {FORECAST_TARGET_S:g} s, route < {ROUTE_TARGET_S:g} s: "
          f"{'met' if ok else 'NOT met'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
