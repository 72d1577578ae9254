"""`gliderplan hindcast`: how well the surfacing forecast does on a real flight.

  hindcast LOGDIR [--ahead N] [--json]

LOGDIR holds a Slocum glider's flight logs (*.dbd, cache files in cac/). From each
surfacing's fixes and the current the glider measured up to it, forecasts the next N
surfacings (default 2) as `gliderplan forecast` does and compares them with the fixes the
glider took: the error [m] against the forecast horizon, and how often the fix fell
inside the 90 % ellipse (planner/hindcast.py).
"""

from __future__ import annotations

import argparse

from gliderplan.cli.main import print_json

ORDER = 56


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("logs", metavar="LOGDIR",
                        help="a Slocum glider's flight logs: a *.dbd file or a directory")
    parser.add_argument("--ahead", type=int, default=2, metavar="N",
                        help="surfacings ahead to forecast from each (default 2)")
    parser.add_argument("--json", action="store_true",
                        help="print every check and the summary as JSON")


def run(args: argparse.Namespace) -> int:
    from dataclasses import asdict

    from gliderplan.contract.errors import UsageError
    from gliderplan.planner.hindcast import hindcast, summary

    if not 1 <= args.ahead <= 20:
        raise UsageError(f"--ahead {args.ahead}: between 1 and 20 surfacings")
    checks = hindcast(args.logs, args.ahead)
    if not checks:
        raise UsageError(f"{args.logs}: no dive between two surfacings to check a forecast on")
    rows = summary(checks)
    if args.json:
        print_json({"summary": rows, "checks": [asdict(c) for c in checks]})
        return 0
    print("ahead  forecasts  horizon (median)  error median  error 90th pct  fix in 90 % ellipse")
    for r in rows:
        print(f"{r['ahead']:5d}  {r['count']:9d}  {r['median_horizon_s'] / 60:12.0f} min"
              f"  {r['median_error_m'] / 1e3:9.2f} km  {r['p90_error_m'] / 1e3:11.2f} km"
              f"  {r['inside_ellipse']:18.0%}")
    return 0
