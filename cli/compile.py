"""`gliderplan compile`: build a mission's runtime binary for the host or a glider's board."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gliderplan.cli.common import add_mission_argument, load_mission, write_atomically
from gliderplan.cli.errors import CliError, UsageError

ORDER = 40


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from gliderplan.runtime.build import TARGETS

    add_mission_argument(parser)
    parser.add_argument("--plan", metavar="PLANFILE",
                        help="plan file to check against the mission and copy beside the binary")
    parser.add_argument("--target", choices=tuple(TARGETS), default="host",
                        help="; ".join(f"{t.name}: {t.description}" for t in TARGETS.values())
                        + " (default host)")
    parser.add_argument("-o", "--output", metavar="DIR", required=True,
                        help="directory for MISSION.c, the binary and the plan")


def run(args: argparse.Namespace) -> int:
    from gliderplan.language.codegen_c import CodegenError
    from gliderplan.runtime.build import BuildError, PlanRejected, check_plan, compile_mission

    mission = load_mission(args)
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory")
    plan = _read_plan(args.plan) if args.plan else None
    try:
        if plan is not None:
            check_plan(mission, args.plan)
        binary = compile_mission(mission, out, args.target)
    except CodegenError as err:
        raise CliError(f"{args.mission}: {err}") from None
    except PlanRejected as err:
        raise CliError(f"plan rejected: {err}") from None
    except BuildError as err:
        raise CliError(str(err)) from None
    if plan is not None:
        write_atomically(out / Path(args.plan).name, plan)
    print(f"{binary} ({args.target})", file=sys.stderr)
    return 0


def _read_plan(path: str) -> bytes:
    try:
        return Path(path).read_bytes()
    except FileNotFoundError:
        raise UsageError(f"--plan {path}: no such file") from None
    except OSError as err:
        raise CliError(f"--plan {path}: {err.strerror}") from None
