"""`gliderplan fleet`: plan, fly and report several gliders sharing one survey.

  fleet check FLEET                      diagnostics of a fleet file (exit 1: bad file)
  fleet plan FLEET [-o DIR] [--json]     lines to gliders, speeds, each glider's mission
  fleet sim FLEET [--plan DIR] -o DIR [--lose GLIDER@TIME] [--current N,E] [--workers K]
            [--scheduler local|tcp://HOST:PORT]
  fleet montecarlo FLEET [--plan DIR] --scenarios N -o DIR [--lose GLIDER@TIME]
                   [--workers K] [--scheduler local|tcp://HOST:PORT]

A fleet file names the gliders (vehicle, board, battery and charge, where and when each
is put in the water), the survey (areas cut into lines, transects, waypoints, keep-out
areas), what to sample and by when (docs/fleet.md). `plan` gives each glider one block of
the survey's lines and the speed its battery allows, so that the field's mapping error
is least with every glider's budget and the first sweep of every line held at the
fleet's confidence; it prints the plan against the equal split a pilot would make and,
with -o, writes each glider's mission and plan, fleet.json, the map (fleet.png,
fleet.geojson, fleet.kml) and the fleet page (fleet.html). `sim` flies every glider once
in one ocean (a run directory per glider, with trajectory.nc); `montecarlo` flies the
fleet in N drawn scenarios and gives the probability that the whole survey is finished.
Without --plan, both plan the fleet (with --seed) once -o is found fit to take the run
(a folder that is not is refused before the planning) and write that plan into -o.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import sys

from gliderplan.cli.common import add_force_argument, seed
from gliderplan.contract import ExitCode
from gliderplan.contract.errors import UsageError

ORDER = 67


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from gliderplan.cli.main import _Parser

    actions = parser.add_subparsers(dest="action", metavar="ACTION", parser_class=_Parser)
    actions.required = True
    check = actions.add_parser("check", help="check a fleet file")
    check.add_argument("fleet", help="fleet file (.fleet by convention)")
    check.add_argument("--json", action="store_true",
                       help="print {file, ok, exit_code, diagnostics, fleet} as JSON")
    plan = actions.add_parser("plan", help="assign the survey's lines, choose speeds, "
                                           "plan each glider's mission")
    _common(plan)
    plan.add_argument("-o", "--output", metavar="DIR",
                      help="write the missions, plans, fleet.json, the map and fleet.html "
                           "(written whole: it replaces a previous plan there)")
    add_force_argument(plan)
    plan.add_argument("--json", action="store_true", help="print the report as JSON")
    plan.add_argument("--solver", choices=("auto", "milp", "heuristic"), default="auto",
                      help="the assignment: the MILP (HiGHS) up to its size limit (auto), "
                           "always, or the heuristic (with its gap to the LP bound)")
    plan.add_argument("--time-limit", type=float, default=20.0, metavar="S",
                      help="stop the MILP after S seconds with its best plan and gap "
                           "(default 20)")
    for name, help_text in (("sim", "fly every glider once in one shared ocean"),
                            ("montecarlo", "fly the fleet in N scenarios: the probability "
                                           "that the whole survey is finished")):
        fly = actions.add_parser(name, help=help_text)
        _common(fly)
        fly.add_argument("--plan", metavar="DIR", help="the plan to fly (fleet plan -o DIR); "
                                                       "default: plan now, into -o")
        fly.add_argument("-o", "--output", metavar="DIR", required=True,
                         help="directory for the runs, the summary, the map and fleet.html "
                              "(written whole: it replaces a previous run there)")
        add_force_argument(fly)
        fly.add_argument("--lose", metavar="GLIDER@TIME",
                         help="the glider is lost at TIME after the survey's start (e.g. "
                              "ru29@3d); the report says what the rest can still cover")
        fly.add_argument("--workers", type=int, default=os.cpu_count() or 1, metavar="K",
                         help="worker processes (default: one per core; 1 flies in this "
                              "process)")
        fly.add_argument("--scheduler", metavar="local|tcp://HOST:PORT",
                         help="where the flights run, on Dask distributed: a LocalCluster "
                              "of --workers processes (the default for more than one), or "
                              "a running scheduler")
        fly.add_argument("--json", action="store_true", help="print the summary as JSON")
        if name == "sim":
            fly.add_argument("--ocean", default=None,
                             help="ocean preset, CSV or Slocum logs, flown in its density (as "
                                  "gliderplan sim; default: the bench temperatures in uniform "
                                  "water, the water the plans assume)")
            fly.add_argument("--current", metavar="NORTH,EAST", default="0,0",
                             help="depth-averaged current of the whole ocean [m/s]")
            fly.add_argument("--runtime", choices=("python", "c"), default="python",
                             help="the runtime every glider flies (as gliderplan sim)")
        else:
            fly.add_argument("--scenarios", type=int, required=True, metavar="N",
                             help="number of scenarios to fly")


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("fleet", help="fleet file (.fleet by convention)")
    parser.add_argument("--seed", type=seed, default=0,
                        help="seed of the scenarios (default 0)")
    parser.add_argument("--scenario-file", metavar="FILE",
                        help="the distributions to draw scenarios from (TOML; default: the "
                             "shipped summer shelf sea)")


def load_fleet(path: str):
    """The checked fleet named on the command line; its warnings to stderr."""
    from gliderplan.language.fleet import check_fleet_file

    result = check_fleet_file(path)
    fleet = result.checked()
    if result.diagnostics:
        print(result.render(), file=sys.stderr)
    return fleet


def parse_loss(text: str | None, fleet) -> tuple[str, float] | None:
    """`GLIDER@TIME` (ru29@3d: lost 3 days after the survey's start) -> (name, [s])."""
    from gliderplan.cli.sim import parse_duration_s

    if text is None:
        return None
    name, _, when = text.partition("@")
    names = [g.name for g in fleet.gliders]
    if name not in names or not when:
        raise UsageError(f"--lose {text}: expected GLIDER@TIME with a glider of the fleet "
                         f"({', '.join(names)}), e.g. {names[0]}@3d")
    at = parse_duration_s(when, "--lose")
    glider = fleet.glider(name)
    if not glider.start_offset_s < at < fleet.period_s:
        raise UsageError(f"--lose {text}: {name} flies from {glider.start_offset_s / 86400:g} d "
                         f"to {fleet.period_s / 86400:g} d after the survey's start")
    return name, at


def run(args: argparse.Namespace) -> int:
    return {"check": _check, "plan": _plan, "sim": _fly,
            "montecarlo": _fly}[args.action](args)


def _check(args: argparse.Namespace) -> int:
    from gliderplan.language.fleet import check_fleet_file

    result = check_fleet_file(args.fleet)
    fleet = result.fleet
    code = ExitCode.OK if fleet is not None else ExitCode.BAD_INPUT
    if args.json:
        summary = None if fleet is None else {
            "name": fleet.name, "gliders": [g.name for g in fleet.gliders],
            "lines": len(fleet.parts), "length_m": sum(p.length_m for p in fleet.parts)}
        print(json.dumps({"file": args.fleet, "ok": fleet is not None, "exit_code": int(code),
                          "diagnostics": result.diagnostics_json(), "fleet": summary},
                         indent=1))
    if result.diagnostics:
        print(result.render(), file=sys.stderr)
    if fleet is None:
        errors = sum(d.is_error for d in result.diagnostics)
        print(f"gliderplan fleet: {args.fleet}: {errors} error{'s' if errors != 1 else ''}",
              file=sys.stderr)
    elif not args.json:
        print(f"{args.fleet}: ok: fleet {fleet.name}, {len(fleet.gliders)} gliders, "
              f"{len(fleet.parts)} lines ({sum(p.length_m for p in fleet.parts) / 1000:.1f} "
              "km)")
    return code


def _planned(args: argparse.Namespace, fleet):
    """The fleet planned (a stop while it is planned is no plan)."""
    from gliderplan.cli.progress import ProgressBar
    from gliderplan.contract import interrupts
    from gliderplan.planner.fleet import plan_fleet

    progress = ProgressBar(lambda done, total: f"step {done:.0f} of {total:.0f}")
    try:
        plan = plan_fleet(fleet, seed=args.seed, scenario_file=args.scenario_file,
                          time_limit_s=getattr(args, "time_limit", 20.0),
                          solver=getattr(args, "solver", "auto"), progress=progress)
    finally:
        progress.finish()
    interrupts.raise_if_stopped()  # the MILP's solver may have swallowed it
    return plan


def _plan(args: argparse.Namespace) -> int:
    from gliderplan.planner.fleet_report import (
        plan_folder,
        report_json,
        report_text,
        write_plan_dir,
    )

    if not 0.0 < args.time_limit:
        raise UsageError(f"--time-limit {args.time_limit:g}: must be positive")
    fleet = load_fleet(args.fleet)
    with plan_folder(args.output, fleet, force=args.force,
                     inputs=(args.fleet, args.scenario_file)) if args.output \
            else contextlib.nullcontext() as folder:
        plan = _planned(args, fleet)
        if folder is not None:
            write_plan_dir(plan, folder)
    report = report_json(plan)
    print(json.dumps(report, indent=1) if args.json else report_text(report))
    if args.output and not args.json:
        print(f"wrote the plan to {args.output}/ (fleet.json, GLIDER.mission, GLIDER.plan, "
              "fleet.png, fleet.geojson, fleet.kml, fleet.html)")
    return ExitCode.OK


def _fly(args: argparse.Namespace) -> int:
    from gliderplan.cli.progress import ProgressBar
    from gliderplan.planner.fleet_report import load_plan_dir
    from gliderplan.sim.fleet import fly_fleet, montecarlo_fleet

    fleet = load_fleet(args.fleet)
    lose = parse_loss(args.lose, fleet)
    if args.workers < 1:
        raise UsageError(f"--workers {args.workers}: must be at least 1")
    # on Dask by default: a LocalCluster of the workers (one worker: this process)
    scheduler = args.scheduler or ("local" if args.workers > 1 else None)
    # without --plan, the fleet is planned once -o DIR is claimed, into DIR/plan
    plan = (lambda: _planned(args, fleet)) if args.plan is None \
        else load_plan_dir(args.plan, fleet)
    inputs = (args.fleet, args.scenario_file)
    if args.action == "sim":
        current = _current(args.current)
        progress = ProgressBar(lambda done, total: f"{done:.0f} of {total:.0f} gliders flown")
        try:
            summary = fly_fleet(fleet, plan, args.output, workers=args.workers,
                                scheduler=scheduler, seed=args.seed, ocean=args.ocean,
                                current=current, runtime=args.runtime, lose=lose,
                                progress=progress, force=args.force, inputs=inputs)
        finally:
            progress.finish()
        print(json.dumps(summary, indent=1) if args.json else _sim_text(summary))
        if summary["interrupted"]:
            print(f"  interrupted: {summary['flown']} of {summary['requested']} gliders "
                  f"flown; the files in {args.output} hold them (fleet_sim.json: complete "
                  "false)", file=sys.stderr)
            return ExitCode.INTERRUPTED
        return ExitCode.OK
    progress = ProgressBar(lambda done, total: f"{done:.0f} of {total:.0f} flights")
    try:
        summary = montecarlo_fleet(fleet, plan, args.output, scenarios=args.scenarios,
                                   workers=args.workers, scheduler=scheduler,
                                   seed=args.seed, scenario_file=args.scenario_file,
                                   lose=lose, progress=progress, force=args.force,
                                   inputs=inputs)
    finally:
        progress.finish()
    print(json.dumps(summary, indent=1) if args.json else _montecarlo_text(summary))
    if summary["interrupted"]:
        print(f"  interrupted: {summary['scenarios']} of {summary['requested']} scenarios "
              f"finished; the files in {args.output} hold them (summary.json: complete "
              "false, no finish probability)", file=sys.stderr)
        return ExitCode.INTERRUPTED
    return ExitCode.OK


def _current(text: str) -> tuple[float, float]:
    import math

    try:
        north, east = (float(v) for v in text.split(","))
    except ValueError:
        north = east = math.nan
    if not (math.isfinite(north) and math.isfinite(east)) or math.hypot(north, east) > 2.0:
        raise UsageError(f"--current {text!r}: expected NORTH,EAST in m/s (e.g. 0.1,-0.05), "
                         "at most 2 m/s")
    return north, east


def _sim_text(s: dict) -> str:
    if not s["complete"]:
        lines = [f"{s['fleet']}: interrupted: {s['flown']} of {s['requested']} gliders flown; "
                 "no verdict on the survey"]
        lines += [f"  {g['name']:<10} {g['energy_j'] / 3600:>7.0f} Wh of "
                  f"{g['budget_j'] / 3600:>6.0f} Wh, ended by {g['ended']}"
                  for g in s["gliders"]]
        return "\n".join(lines)
    lines = [f"{s['fleet']}: the survey {'was' if s['finished'] else 'was not'} finished; "
             f"realised mapping error {s['mapping_error']:.3f} (planned "
             f"{s['planned_mapping_error']:.3f})"]
    for g in s["gliders"]:
        lines.append(f"  {g['name']:<10} {g['energy_j'] / 3600:>7.0f} Wh of "
                     f"{g['budget_j'] / 3600:>6.0f} Wh, ended by {g['ended']}, "
                     f"{g['lines_swept']} line{'' if g['lines_swept'] == 1 else 's'} swept"
                     + ("" if g["swept"] else " (its block not swept once)")
                     + (" LOST" if g["lost"] else ""))
    if s.get("lost"):
        lines.append(f"  {s['lost']['glider']} lost: {s['lost']['summary']}")
    return "\n".join(lines)


def _montecarlo_text(s: dict) -> str:
    if s["complete"]:
        low, high = s["finish_interval"]
        finish = (f"{s['fleet']}: the whole survey finished in {s['finished']} of "
                  f"{s['scenarios']} scenarios: {100 * s['finish_probability']:.1f} % (95 % "
                  f"interval {100 * low:.1f}-{100 * high:.1f} %), planned at "
                  f"{100 * s['planned_confidence']:.0f} %")
    else:
        finish = (f"{s['fleet']}: interrupted after {s['scenarios']} of {s['requested']} "
                  "scenarios: no finish probability (a partial run is not the sample asked "
                  "for)")
    lines = [finish,
             f"  realised mapping error {s['mapping_error']['p05']:.3f} / "
             f"{s['mapping_error']['p50']:.3f} / {s['mapping_error']['p95']:.3f} (5 / 50 / 95 %)"
             f", planned {s['planned_mapping_error']:.3f}"]
    for g in s["gliders"]:
        q = s["energy_j"][g["name"]]
        lines.append(f"  {g['name']:<10} energy {q['p05'] / 3600:,.0f} / {q['p50'] / 3600:,.0f}"
                     f" / {q['p95'] / 3600:,.0f} Wh of {g['budget_j'] / 3600:,.0f} Wh; budget "
                     f"held in {g['budget_held']}, block swept in {g['swept']}")
    if s.get("lost"):
        lines.append(f"  {s['lost']['glider']} lost: {s['lost']['summary']}")
    return "\n".join(lines)
