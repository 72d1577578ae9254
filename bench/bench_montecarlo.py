"""Benchmark: Monte Carlo scenarios per second of the thermocline survey (35 h each) with
1 and 2 local workers and a Dask LocalCluster of 2 workers, and the parallel efficiency.

    .venv/bin/python bench/bench_montecarlo.py [--scenarios 40] [--no-dask]

Each backend flies the same scenarios (seed 0) of examples/thermocline_survey.mission
with its plan; the tables must be identical. The baseline is 1 worker (this process) in
the same run: efficiency at K workers = rate(K) / (K x rate(1)). The whole command,
`gliderplan montecarlo ... --scenarios N --workers 2`, is timed as a process too.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from gliderplan.language import check_file
from gliderplan.planner.plan import plan_mission
from gliderplan.planner.planfile import write_plan_bytes
from gliderplan.power_models import load_vehicle
from gliderplan.sim import montecarlo
from gliderplan.sim.backends import scenario_executor
from gliderplan.sim.scenarios import read_spec

REPO = Path(__file__).resolve().parents[1]
SURVEY = REPO / "examples" / "thermocline_survey.mission"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenarios", type=int, default=40)
    parser.add_argument("--no-dask", action="store_true")
    args = parser.parse_args(argv)
    mission = check_file(str(SURVEY)).mission
    nominal = plan = plan_mission(mission).plan
    job = montecarlo.Job(mission, plan, load_vehicle(mission.vehicle), read_spec(),
                         nominal.budget_j, 0, mission.horizon_s)
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
        rates[label] = (rate, workers)
        base = rates[runs[0][0]][0]
        print(f"{label}: {args.scenarios} scenarios in {wall:.1f} s = {rate:.2f} scenarios/s; "
              f"parallel efficiency {100 * rate / (workers * base):.0f} %")
    same = all(t.equals(tables[0]) for t in tables[1:])
    print(f"identical tables across backends: {same}")
    with tempfile.TemporaryDirectory() as tmp:
        plan_path = Path(tmp) / "survey.plan"
        plan_path.write_bytes(write_plan_bytes(nominal))
        command = [str(Path(sys.executable).with_name("gliderplan")), "montecarlo", str(SURVEY),
                   "--plan", str(plan_path), "--scenarios", str(args.scenarios), "--workers",
                   "2", "-o", str(Path(tmp) / "mc")]
        start = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        wall = time.perf_counter() - start
    print(f"whole command, 2 workers: {wall:.1f} s for {args.scenarios} scenarios; "
          f"1,000 would take ~{1000 * wall / args.scenarios / 60:.1f} min")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
