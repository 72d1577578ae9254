"""`gliderplan montecarlo`: how likely is it that the plan finishes on its battery?

  montecarlo MISSION [--plan P] --scenarios N [--workers K] [--seed S] -o DIR
             [--scenario-file F] [--scheduler local|tcp://HOST:PORT] [--duration T]

Flies the mission (with its plan; without one every sensor a state logs is always on and
the budget is the mission's usable battery) in N scenarios drawn from the scenario file
(default: the one that ships, sim/data/scenarios_default.toml) and writes
DIR/scenarios.parquet (one row per scenario), DIR/summary.json (the probability that the
budget holds, with its 95 % interval; energy and duration quantiles), DIR/energy.png and
DIR/exhaustion.png. Deterministic for a seed, whatever the number or kind of workers.
Ctrl-C (or SIGTERM) stops it at once, workers and all, and writes the scenarios that
finished, marked partial and with no probability (exit 130, 143).
"""

from __future__ import annotations

import argparse
import os
import sys

from gliderplan.cli.common import (
    add_force_argument,
    add_mission_argument,
    add_replan_confidence_argument,
    add_start_argument,
    load_mission,
    parse_start,
    refuse_unpaired,
    seed,
)
from gliderplan.cli.main import print_json
from gliderplan.contract import ExitCode

ORDER = 65


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    parser.add_argument("--plan", metavar="PLANFILE",
                        help="plan to fly; its budget and prediction are what the "
                             "scenarios are checked against")
    parser.add_argument("--scenarios", type=int, required=True, metavar="N",
                        help="number of scenarios to fly")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1, metavar="K",
                        help="worker processes (default: one per core; 1 flies in this "
                             "process)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of the run (default 0)")
    parser.add_argument("--scenario-file", metavar="FILE",
                        help="the distributions to draw from (TOML; default: the shipped "
                             "summer shelf sea)")
    parser.add_argument("--scheduler", metavar="local|tcp://HOST:PORT",
                        help="run on Dask distributed: a LocalCluster of --workers "
                             "processes, or a running scheduler")
    parser.add_argument("--duration", metavar="T",
                        help="end each run here if the mission has not exited (default: "
                             "the mission's horizon, else 30d)")
    parser.add_argument("--tracker", choices=("robust", "naive"), default="robust",
                        help="thermocline detection (default robust)")
    parser.add_argument("--replan", action="store_true",
                        help="fly each scenario twice: the plan alone, and with the shore "
                             "replanning the rest at each surfacing (plan updates); report "
                             "both side by side, both planned at one confidence (a plan "
                             "made at another, or on the model, is replanned at it before "
                             "launch)")
    add_replan_confidence_argument(parser, "--replan")
    parser.add_argument("--key", metavar="KEYFILE",
                        help="with --replan: the vehicle's key (the plan signed with it; "
                             "default: a key made for the run)")
    add_start_argument(parser, "500 m south of the mission's first waypoint, at "
                               "2000-01-01T00:00:00Z")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("-o", "--output", metavar="DIR", required=True,
                        help="directory for scenarios.parquet, summary.json and the plots "
                             "(written whole: it replaces a previous run there)")
    add_force_argument(parser)


def run(args: argparse.Namespace) -> int:
    from gliderplan.cli.progress import ProgressBar
    from gliderplan.cli.sim import parse_duration_s
    from gliderplan.sim.montecarlo import montecarlo_mission
    from gliderplan.sim.setup import FlightOptions, flight_setup

    refuse_unpaired(args, {"--confidence": ("--replan",), "--key": ("--replan",)})
    mission = load_mission(args)
    lat, lon, when = parse_start(args.start) if args.start else (None, None, None)
    progress = ProgressBar(lambda done, total: f"{done:.0f} of {total:.0f} scenarios")
    options = FlightOptions(
        plan_path=args.plan, seed=args.seed, tracker=args.tracker,
        duration_s=parse_duration_s(args.duration) if args.duration else None,
        start_utc=when, start_position=None if lat is None else (lat, lon), key_path=args.key)
    try:
        run_ = montecarlo_mission(
            flight_setup(mission, options), args.output, scenarios=args.scenarios,
            workers=args.workers, scheduler=args.scheduler,
            scenario_file=args.scenario_file, progress=progress, replan=args.replan,
            confidence=args.confidence, force=args.force, mission_path=args.mission)
    finally:
        progress.finish()
    summary = run_.summary
    if args.json:
        print_json(summary)
    elif run_.result.interrupted:
        print(_partial(mission.name, summary))
    else:
        print(_verdict(mission.name, summary))
    if run_.result.interrupted:
        print(f"  interrupted: {len(run_.result.rows)} of {args.scenarios} scenarios "
              f"finished; the files in {args.output} hold them, marked partial "
              "(summary.json: complete false, no probability)", file=sys.stderr)
        return ExitCode.INTERRUPTED
    if run_.stopped:
        print(f"  interrupted once every scenario had flown: the files in {args.output} "
              "hold the whole run", file=sys.stderr)
        return ExitCode.INTERRUPTED
    return ExitCode.OK


def _partial(name: str, s: dict) -> str:
    """An interrupted run as a pilot reads it: how far it got, and no hold rate."""
    return (f"{name}: INTERRUPTED after {s['scenarios']} of {s['requested']} scenarios: no "
            "probability that the budget holds (the scenarios that finished before a stop "
            "are not the run asked for; run it again to the end)\n"
            f"  of those that finished, the budget held in {s['budget_held']}")


def _verdict(name: str, s: dict) -> str:
    """What the scenarios did, as a pilot reads it: how often the budget held, the energy
    drawn, how many passed the usable charge drawn for them, how the runs ended."""
    if s.get("replan"):
        return _replanned(name, s)
    low, high = s["probability_interval_95"]
    e = s["energy_j"]
    ended = ", ".join(f"{count} by {how}" for how, count in s["ended"].items())
    return (f"{name}: the budget held in {s['budget_held']} of {s['scenarios']} scenarios: "
            f"{100 * s['probability_budget_holds']:.1f} % (95 % interval "
            f"{100 * low:.1f}-{100 * high:.1f} %)\n"
            f"  energy {e['p05'] / 1e3:,.0f} / {e['p50'] / 1e3:,.0f} / {e['p95'] / 1e3:,.0f} kJ "
            f"(5 / 50 / 95 %) against a budget of {s['budget_j'] / 1e3:,.0f} kJ\n"
            f"  {s['exceeded_drawn_usable_charge']} exceeded the usable charge drawn for the "
            f"scenario (the budget times a usable share drawn from "
            f"{s['usable_share_drawn_from']}); the runs ended: {ended}")


def _replanned(name: str, s: dict) -> str:
    """The side-by-side verdict of a run with replanning."""
    def rate(key: str) -> str:
        low, high = s[f"{key}_interval_95"]
        return f"{100 * s[key]:.1f} % ({100 * low:.1f}-{100 * high:.1f} %)"

    link = s["link"]
    return (f"{name}: the budget held in {rate('hold_rate')} of {s['scenarios']} scenarios "
            f"with replanning at each surfacing, {rate('hold_rate_static')} with the plan "
            f"alone; both from {s['plan_flown']}\n"
            + (f"  quality as flown {s['quality']:.4f} with replanning, "
               f"{s['quality_static']:.4f} alone\n" if s["quality"] is not None else
               "  no quality as flown: the mission weighs no sensor\n") +
            f"  link: {link['surfacings_per_mission']:.0f} surfacings a mission; up "
            f"{link['up_bytes_per_day']:,.0f} B/day ({link['up_bytes_per_mission']:,.0f} a "
            f"mission), down {link['down_bytes_per_day']:,.0f} B/day "
            f"({link['down_bytes_per_mission']:,.0f} a mission); the largest update "
            f"{s['update_bytes_max']} bytes (SBD: {link['sbd_limits_bytes']['up']} up, "
            f"{link['sbd_limits_bytes']['down']} down)")
