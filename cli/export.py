"""`gliderplan export`: a simulated run as NetCDF (IOOS DAC, OceanGliders OG1.0, CF), GeoJSON, KML.

  export RUNDIR --format og1|ioos|cf [--format ...] --geojson --kml [-o DIR]
         [--metadata FILE.toml] [--json]

Reads RUNDIR/timeseries.parquet and summary.json (written by `gliderplan sim`) and
writes trajectory.nc (ioos; --netcdf says the same), trajectory_og1.nc,
trajectory_cf.nc, track.geojson and track.kml into RUNDIR (or DIR). --metadata names the
deployment's people and names (creator, institution, project, sea name, WMO id...);
without it the files say they hold a simulation.
"""

from __future__ import annotations

import argparse
import sys

ORDER = 65


def _formats(text: str) -> list[str]:
    """`og1,ioos` -> ["og1", "ioos"] (argparse type)."""
    return [f.strip() for f in text.split(",") if f.strip()]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("run", metavar="RUNDIR", help="directory of a run of gliderplan sim")
    parser.add_argument("--format", type=_formats, action="extend", metavar="og1|ioos|cf",
                        default=[],
                        help="NetCDF: og1 (OceanGliders 1.0, trajectory_og1.nc), ioos (IOOS "
                             "Glider DAC, trajectory.nc), cf (plain CF-1.6, "
                             "trajectory_cf.nc); repeat or separate with commas")
    parser.add_argument("--netcdf", action="store_true", help="the same as --format ioos")
    parser.add_argument("--geojson", action="store_true", help="track.geojson: the track")
    parser.add_argument("--kml", action="store_true", help="track.kml: the track")
    parser.add_argument("--metadata", metavar="FILE",
                        help="TOML file of the deployment's people and names for the NetCDF "
                             "files (docs/json.md lists its keys)")
    parser.add_argument("-o", "--output", metavar="DIR",
                        help="where to write (default: RUNDIR); another folder is written "
                             "whole, as a run of its own")
    parser.add_argument("--force", action="store_true",
                        help="with -o: replace a folder that holds files other than a "
                             "gliderplan run's (they are deleted)")
    parser.add_argument("--json", action="store_true",
                        help="print the files written as JSON (docs/json.md)")


def run(args: argparse.Namespace) -> int:
    from gliderplan.sim.export import export_run

    formats = [*args.format, *(["ioos"] if args.netcdf else []),
               *(name for name in ("geojson", "kml") if getattr(args, name))]
    written = export_run(args.run, formats, args.output, args.metadata, force=args.force)
    for path in written:
        print(f"wrote {path}", file=sys.stderr)
    if args.json:
        from gliderplan.cli.main import print_json

        print_json({"ok": True, "run": args.run, "files": [str(p) for p in written]})
    return 0
