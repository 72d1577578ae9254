"""`gliderplan export`: a simulated run as NetCDF (CF trajectory, IOOS Glider DAC), GeoJSON or KML.

  export RUNDIR --netcdf --geojson --kml [-o DIR]

Reads RUNDIR/timeseries.parquet and summary.json (written by `gliderplan sim`) and
writes trajectory.nc, track.geojson and track.kml into RUNDIR (or DIR).
"""

from __future__ import annotations

import argparse
import sys

ORDER = 65


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("run", metavar="RUNDIR", help="directory of a run of gliderplan sim")
    parser.add_argument("--netcdf", action="store_true",
                        help="trajectory.nc: CF trajectory with IOOS Glider DAC variable "
                             "names and ACDD global attributes")
    parser.add_argument("--geojson", action="store_true", help="track.geojson: the track")
    parser.add_argument("--kml", action="store_true", help="track.kml: the track")
    parser.add_argument("-o", "--output", metavar="DIR",
                        help="where to write (default: RUNDIR)")
    parser.add_argument("--json", action="store_true",
                        help="print the files written as JSON (docs/json.md)")


def run(args: argparse.Namespace) -> int:
    from gliderplan.sim.export import FORMATS, export_run

    written = export_run(args.run, [name for name in FORMATS if getattr(args, name)],
                         args.output)
    for path in written:
        print(f"wrote {path}", file=sys.stderr)
    if args.json:
        from gliderplan.cli.main import print_json

        print_json({"ok": True, "run": args.run, "files": [str(p) for p in written]})
    return 0
