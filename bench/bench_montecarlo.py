"""Benchmark: Monte Carlo of the month-long thermocline survey (30 days a scenario):
scenarios per second with 1 and 2 local workers and a Dask LocalCluster of 2 workers, the
parallel efficiency, and the whole `gliderplan montecarlo` command of 1,000 scenarios.

    .venv/bin/python bench/bench_montecarlo.py [--scenarios 40] [--whole 1000] [--no-dask]
                                               [--reference 2]

Each backend flies the same --scenarios scenarios (seed 0) of
examples/survey_month.mission with its plan; the tables must be identical. The baseline
is 1 worker (this process) in the same run: efficiency at K workers = rate(K) / (K x
rate(1)). The first --reference scenarios are also flown by the Python reference
executor: the C step's speed-up, rows identical. Then the command a user runs,
`gliderplan montecarlo ... --scenarios 1000 --workers 2` (target: at most 10 minutes on
a 2-core machine), timed as a whole process.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from whole_process import gliderplan, load_average

from gliderplan.language import check_file
from gliderplan.planner.plan import plan_mission
from gliderplan.planner.planfile import write_plan_bytes
from gliderplan.sim import FlightOptions, flight_setup, montecarlo
from gliderplan.sim.backends import scenario_executor
from gliderplan.sim.scenarios import read_spec

REPO = Path(__file__).resolve().parents[1]
SURVEY = REPO / "examples" / "survey_month.mission"
TARGET_MIN = 10.0  # 1,000 scenarios on 2 cores


def reference_speedup(job: montecarlo.Job, scenarios: int) -> bool:
    """The first `scenarios` scenarios flown by the C step and by the Python reference, in
    this process: the C step's speed-up; False if a row differs."""
    import pandas as pd

    times = {"step": 0.0, "python": 0.0}
    rows: dict[str, list] = {"step": [], "python": []}
    for index in range(scenarios):
        for runtime in times:
            start = time.perf_counter()
            rows[runtime].append(montecarlo.fly_scenario(job, index, runtime))
            times[runtime] += time.perf_counter() - start
    same = pd.DataFrame(rows["step"]).equals(pd.DataFrame(rows["python"]))
    print(f"{scenarios} scenarios on the C step {times['step']:.1f} s, on the Python "
          f"reference {times['python']:.1f} s: {times['python'] / times['step']:.1f}x; "
          f"identical rows: {same} ({load_average()})")
    return same


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenarios", type=int, default=40,
                        help="scenarios per backend for the rates")
    parser.add_argument("--whole", type=int, default=1000,
                        help="scenarios of the whole command (0: skip it)")
    parser.add_argument("--no-dask", action="store_true")
    parser.add_argument("--reference", type=int, default=2,
                        help="scenarios also flown by the Python reference, for the C "
                             "step's speed-up (0: skip)")
    args = parser.parse_args(argv)
    print(load_average())
    mission = check_file(str(SURVEY)).mission
    plan = plan_mission(mission).plan
    job = montecarlo.Job(flight_setup(mission, FlightOptions(duration_s=mission.horizon_s),
                                      plan=plan), read_spec())
    runs = [("1 worker (this process)", 1, None), ("2 local workers", 2, None)]
    if not args.no_dask:
        runs.append(("Dask LocalCluster, 2 workers", 2, "local"))
    tables, rates = [], {}
    for label, workers, scheduler in runs:
        with scenario_executor(workers, scheduler) as executor:
            start = time.perf_counter()
            result = montecarlo.run_montecarlo(job, args.scenarios, executor, workers)
            wall = time.perf_counter() - start
        tables.append(result.table())
        rate = args.scenarios / wall
        rates[label] = rate
        base = rates[runs[0][0]]
        print(f"{label}: {args.scenarios} scenarios of 30 d in {wall:.1f} s = {rate:.3f} "
              f"scenarios/s; parallel efficiency {100 * rate / (workers * base):.0f} % "
              f"({load_average()})")
    same = all(t.equals(tables[0]) for t in tables[1:])
    print(f"identical tables across backends: {same}")
    if args.reference:
        same = reference_speedup(job, args.reference) and same
    if args.whole:
        with tempfile.TemporaryDirectory() as tmp:
            plan_path = Path(tmp) / "survey.plan"
            plan_path.write_bytes(write_plan_bytes(plan))
            command = gliderplan("montecarlo", str(SURVEY), "--plan", str(plan_path),
                                 "--scenarios", str(args.whole), "--workers", "2",
                                 "-o", str(Path(tmp) / "mc"))
            start = time.perf_counter()
            subprocess.run(command, check=True, capture_output=True)
            wall = time.perf_counter() - start
        print(f"whole command, 2 workers: {args.whole} scenarios of 30 d in {wall / 60:.1f} min "
              f"({args.whole / wall:.3f} scenarios/s; target {TARGET_MIN:g} min for 1,000; "
              f"{load_average()})")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
