"""`gliderplan compile`: build a mission's runtime binary for the host or a glider's board."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from gliderplan.cli.common import add_force_argument, add_mission_argument, load_mission
from gliderplan.contract import interrupts
from gliderplan.contract.files import output_folder

ORDER = 40


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from gliderplan.runtime.build import TARGETS

    add_mission_argument(parser)
    parser.add_argument("--plan", metavar="PLANFILE",
                        help="plan file to check against the mission and the target's board, "
                             "and copy beside the binary")
    parser.add_argument("--key", metavar="KEYFILE",
                        help="with --plan: the key provisioned on the vehicle (gliderplan "
                             "keygen); the plan must be signed with it, as the runtime will "
                             "check")
    parser.add_argument("--target", choices=tuple(TARGETS),
                        help="; ".join(f"{t.name}: {t.description}" for t in TARGETS.values())
                        + " (default host; a mission with 'computer none' must say)")
    parser.add_argument("--json", action="store_true",
                        help="print what was built as JSON (docs/json.md)")
    parser.add_argument("-o", "--output", metavar="DIR", required=True,
                        help="directory for MISSION.c, the binary and the plan (a folder "
                             "written whole: an earlier build there is replaced)")
    add_force_argument(parser)


def _keep_unchanged_source(previous: Path, new: Path) -> None:
    """The previous build's MISSION.c in the new folder, its timestamp and all (make's):
    compile_mission leaves it if the C it generates is the same."""
    try:
        if previous.is_file():
            os.link(previous, new)
    except OSError:
        pass


def run(args: argparse.Namespace) -> int:
    from gliderplan.cli.common import refuse_unpaired
    from gliderplan.runtime.build import build_target, compile_mission

    refuse_unpaired(args, {"--key": ("--plan",)})
    mission = load_mission(args)
    target = build_target(mission, args.target)
    source = f"{mission.name}.c"
    names = (source, mission.name, *(() if args.plan is None else (Path(args.plan).name,)))
    with output_folder(args.output, command="compile", force=args.force, recognised=names,
                       inputs=(args.mission, args.plan, args.key)) as folder:
        _keep_unchanged_source(Path(args.output) / source, folder.path / source)
        built = compile_mission(mission, folder.path, target, args.plan, key_path=args.key)
        interrupts.raise_if_stopped()
    binary = folder.final(built.name)
    print(f"{binary} ({target})", file=sys.stderr)
    if args.json:
        from gliderplan.cli.main import print_json

        plan = None if args.plan is None else str(Path(args.output) / Path(args.plan).name)
        print_json({"ok": True, "mission": mission.name, "mission_hash": mission.hash,
                    "target": target, "binary": str(binary),
                    "c_source": str(Path(args.output) / f"{mission.name}.c"), "plan": plan,
                    "signature": None if args.key is None else "verified"})
    return 0
