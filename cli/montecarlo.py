"""`gliderplan montecarlo`: how likely is it that the plan finishes on its battery?

  montecarlo MISSION [--plan P] --scenarios N [--workers K] [--seed S] -o DIR
             [--scenario-file F] [--scheduler local|tcp://HOST:PORT] [--duration T]

Flies the mission (with its plan; without one every sensor a state logs is always on and
the budget is the mission's usable battery) in N scenarios drawn from the scenario file
(default: the one that ships, sim/data/scenarios_default.toml) and writes
DIR/scenarios.parquet (one row per scenario), DIR/summary.json (the probability that the
budget holds, with its 95 % interval; energy and duration quantiles), DIR/energy.png and
DIR/exhaustion.png. Deterministic for a seed, whatever the number or kind of workers.
Ctrl-C keeps the scenarios that finished (exit 130).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from gliderplan.cli.common import add_mission_argument, load_mission
from gliderplan.contract import ExitCode
from gliderplan.contract.errors import UsageError
from gliderplan.contract.files import write_atomically

ORDER = 65
MAX_SCENARIOS = 1_000_000


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mission_argument(parser)
    parser.add_argument("--plan", metavar="PLANFILE",
                        help="plan to fly; its report PLANFILE.json gives the prediction")
    parser.add_argument("--scenarios", type=int, required=True, metavar="N",
                        help="number of scenarios to fly")
    parser.add_argument("--workers", type=int, default=os.cpu_count() or 1, metavar="K",
                        help="worker processes (default: one per core; 1 flies in this "
                             "process)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the run (default 0)")
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
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("-o", "--output", metavar="DIR", required=True,
                        help="directory for scenarios.parquet, summary.json and the plots")


def run(args: argparse.Namespace) -> int:
    from gliderplan.cli.progress import ProgressBar
    from gliderplan.cli.sim import parse_duration_s
    from gliderplan.planner.planfile import load_plan
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim import montecarlo, plots
    from gliderplan.sim.backends import scenario_executor
    from gliderplan.sim.scenarios import read_spec

    if not 1 <= args.scenarios <= MAX_SCENARIOS:
        raise UsageError(f"--scenarios {args.scenarios}: must be between 1 and "
                         f"{MAX_SCENARIOS:,}")
    if args.workers < 1:
        raise UsageError(f"--workers {args.workers}: must be at least 1")
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory")
    mission = load_mission(args)
    duration_s = parse_duration_s(args.duration) if args.duration else (
        mission.horizon_s or 30 * 86400.0)
    spec = read_spec(args.scenario_file)
    vehicle = load_vehicle(mission.vehicle)
    plan = None if args.plan is None else load_plan(args.plan, mission)
    budget_j = plan.budget_j if plan is not None else \
        mission.battery.energy_j * (1.0 - mission.battery.reserve_fraction)
    job = montecarlo.Job(mission, plan, vehicle, spec, budget_j, args.seed,
                         duration_s, robust_tracker=args.tracker == "robust")
    progress = ProgressBar(lambda done, total: f"{done:.0f} of {total:.0f} scenarios")
    try:
        with scenario_executor(args.workers, args.scheduler) as executor:
            result = montecarlo.run_montecarlo(job, args.scenarios, executor, args.workers,
                                               progress)
    finally:
        progress.finish()
    if not result.rows:
        raise KeyboardInterrupt  # nothing finished, nothing to write
    table = result.table()
    meta = {"mission": mission.name, "mission_hash": mission.hash, "plan": args.plan,
            "scenario_file": spec.source, "seed": args.seed, "run_limit_s": duration_s,
            "budget_j": budget_j, "workers": args.workers,
            "scheduler": args.scheduler or ("local pool" if args.workers > 1 else "none")}
    summary = montecarlo.summary(result, meta)
    write_atomically(out / "scenarios.parquet", _parquet(table))
    write_atomically(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    write_atomically(out / "energy.png", plots.energy_histogram_png(
        table["energy_j"].to_numpy(float), table["budget_j"].to_numpy(float), budget_j,
        summary["probability_budget_holds"]))
    write_atomically(out / "exhaustion.png", plots.exhaustion_png(
        table["exhausted_s"].to_numpy(float), table["duration_s"].to_numpy(float)))
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(_verdict(mission.name, summary))
    if result.interrupted:
        print(f"  interrupted: {len(result.rows)} of {args.scenarios} scenarios finished; "
              f"the files in {out} hold them", file=sys.stderr)
        return ExitCode.INTERRUPTED
    return ExitCode.OK


def _parquet(table) -> bytes:
    import pyarrow as pa

    from gliderplan.sim.outputs import parquet_bytes

    return parquet_bytes(pa.Table.from_pandas(table, preserve_index=False))


def _verdict(name: str, s: dict) -> str:
    low, high = s["probability_interval_95"]
    e = s["energy_j"]
    return (f"{name}: the budget held in {s['budget_held']} of {s['scenarios']} scenarios: "
            f"{100 * s['probability_budget_holds']:.1f} % (95 % interval "
            f"{100 * low:.1f}-{100 * high:.1f} %)\n"
            f"  energy {e['p05'] / 1e3:,.0f} / {e['p50'] / 1e3:,.0f} / {e['p95'] / 1e3:,.0f} kJ "
            f"(5 / 50 / 95 %) against a budget of {s['budget_j'] / 1e3:,.0f} kJ; "
            f"{s['exhausted_before_end']} ran out before the end")
