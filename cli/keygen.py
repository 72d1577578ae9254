"""`gliderplan keygen`: make a key for signing plans, to provision on a vehicle.

  keygen -o KEYFILE     32 random bytes as 64 hex digits, mode 0600, never over a file

Provision the file on the vehicle and start its runtime with `--key KEYFILE`; sign each
plan for it with `gliderplan plan --sign KEYFILE` (docs/plan-format.md, "Signed plans").
"""

from __future__ import annotations

import argparse
import sys

ORDER = 35


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("-o", "--output", metavar="KEYFILE", required=True,
                        help="where to write the key (refused if the file exists)")
    parser.add_argument("--json", action="store_true",
                        help="print where the key was written as JSON (never the key)")


def run(args: argparse.Namespace) -> int:
    from gliderplan.planner.signing import write_new_key

    write_new_key(args.output)
    print(f"wrote {args.output} (mode 0600): provision it on the vehicle (runtime --key) "
          "and sign plans with gliderplan plan --sign", file=sys.stderr)
    if args.json:
        from gliderplan.cli.main import print_json

        print_json({"ok": True, "key_file": args.output, "mode": "0600"})
    return 0
