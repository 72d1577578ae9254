"""Benchmark: Monte Carlo of the imported Slocum mission nsb3 (30 days a scenario): the
whole `gliderplan montecarlo` command's throughput in scenario-days per core-second
beside the C step's own ticks per second (the limit), and scenarios per second with 1
and 2 local workers and a Dask LocalCluster of 2 workers in this process.

    .venv/bin/python bench/bench_montecarlo.py [--whole 1000] [--scenarios 20] [--no-dask]
                                               [--reference 2] [--days 30]

The mission: nsb3 of the shared Slocum logs, imported with `gliderplan import-slocum`
(its missing .ma files allowed), flown without a plan (every sensor it logs on, the
budget its usable battery), the shipped scenario file, seed 0, runs of --days.

1. The limit: the nominal flight of nsb3 on the C step in this process (`fly`, the bench
   ocean), ticks per CPU second, and what that is in simulated days per core-second.
2. The command a user runs, `gliderplan montecarlo nsb3.mission --scenarios N --workers 2
   --duration 30d -o DIR`, once, as a whole process (bench/whole_process.py: wall, and
   CPU of the command and its workers): scenario-days flown (each scenario ends at 30
   days or earlier, at its battery's reserve) per core-second, as a share of the limit;
   the time 1,000 scenarios take on 2 cores at that throughput (target: under 3 minutes),
   measured if N is 1,000, else extrapolated (stated so) from the same command of 2
   scenarios (the start-up: imports, the workers, the files; the baseline) and the CPU
   each further scenario adds.
3. With --scenarios: the same scenarios flown by 1 worker (this process: the baseline),
   2 local workers (a process pool) and a Dask LocalCluster of 2 workers; the tables must
   be identical; parallel efficiency at K workers = rate(K) / (K x rate(1)). The first
   --reference scenarios are also flown by the Python reference executor: the C step's
   speed-up, rows identical.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import pandas as pd
from whole_process import Timing, gliderplan, import_slocum, load_average, run_once

from gliderplan.language import check_file
from gliderplan.sim import FlightOptions, FlightSetup, flight_setup, montecarlo
from gliderplan.sim.backends import scenario_executor
from gliderplan.sim.flight import fly
from gliderplan.sim.scenarios import read_spec

TARGET_MIN = 3.0  # 1,000 scenarios of 30 days on 2 cores
TARGET_SCENARIOS = 1000
CORES = 2
BASELINE_SCENARIOS = 2  # the start-up's run: the parent flies one, a worker the other


def step_limit(setup: FlightSetup) -> float:
    """Section 1: simulated days per CPU second of the C step in this process."""
    mission, ocean, vehicle = setup.mission, setup.water.ocean, setup.vehicle
    fly(mission, ocean, replace(setup.config, duration_s=3600.0), vehicle,
        runtime="step")  # warm-up: imports, the build's cache
    start_cpu, start = time.process_time(), time.perf_counter()
    record = fly(mission, ocean, setup.config, vehicle, runtime="step")
    cpu, wall = time.process_time() - start_cpu, time.perf_counter() - start
    ticks = len(record.columns["time_s"])
    flown_days = record.columns["time_s"][-1] / 86400.0
    print(f"the C step in this process, nsb3 nominal: {flown_days:.1f} days flown "
          f"({record.ended}), {ticks:,} ticks in {cpu:.2f} s CPU ({wall:.2f} s wall): "
          f"{ticks / cpu:,.0f} ticks per CPU s = {flown_days / cpu:,.0f} simulated days per "
          f"core-second (the limit; {load_average()})")
    return flown_days / cpu


def whole_command(path: Path, work: Path, scenarios: int, days: float, limit: float) -> bool:
    """Section 2; False if the target is missed (measured or extrapolated)."""
    def run(count: int) -> tuple[Timing, float]:
        """The command's wall and CPU time, and the scenario-days it flew."""
        out = work / f"mc-{count}"
        timing = run_once(gliderplan("montecarlo", str(path), "--scenarios", str(count),
                                     "--workers", str(CORES), "--duration", f"{days:g}d",
                                     "-o", str(out)))
        return timing, pd.read_parquet(out / "scenarios.parquet")["duration_s"].sum() / 86400

    print(f"gliderplan montecarlo nsb3.mission --workers {CORES} --duration {days:g}d "
          f"({load_average()}):")
    base, base_days = run(BASELINE_SCENARIOS)
    timing, flown = run(scenarios)
    throughput = flown / timing.cpu_s
    per_scenario = (timing.cpu_s - base.cpu_s) / (scenarios - BASELINE_SCENARIOS)
    marginal = (flown - base_days) / (timing.cpu_s - base.cpu_s)
    print(f"  --scenarios {BASELINE_SCENARIOS} (the start-up, the baseline): "
          f"{base.wall_s:.1f} s wall, {base.cpu_s:.1f} s CPU")
    print(f"  --scenarios {scenarios}: {timing.wall_s:.1f} s wall, {timing.cpu_s:.1f} s CPU "
          f"(the command and its workers), {flown:,.0f} scenario-days flown: "
          f"{throughput:.1f} scenario-days per core-second, start-up included; "
          f"{marginal:.1f} beyond the baseline's ({per_scenario:.2f} s CPU a scenario), "
          f"{100 * marginal / limit:.0f} % of the C step's own {limit:,.0f}; "
          f"{load_average()}")
    if scenarios == TARGET_SCENARIOS:
        minutes, how = timing.cpu_s / CORES / 60.0, "measured: its CPU over 2 cores"
    else:
        minutes = (base.cpu_s + (TARGET_SCENARIOS - BASELINE_SCENARIOS) * per_scenario) \
            / CORES / 60.0
        how = (f"extrapolated: the baseline's CPU and {TARGET_SCENARIOS - BASELINE_SCENARIOS}"
               f" scenarios at {per_scenario:.2f} s CPU, over {CORES} cores")
    print(f"  {TARGET_SCENARIOS:,} scenarios on {CORES} free cores: {minutes:.1f} min ({how}; "
          f"the wall time here {timing.wall_s / 60:.1f} min for {scenarios}); target "
          f"{TARGET_MIN:g} min: {'met' if minutes < TARGET_MIN else 'not met'}")
    return minutes < TARGET_MIN


def reference_speedup(job: montecarlo.Job, scenarios: int) -> bool:
    """The first `scenarios` scenarios flown by the C step and by the Python reference, in
    this process: the C step's speed-up; False if a row differs."""
    times = {"step": 0.0, "python": 0.0}
    rows: dict[str, list] = {"step": [], "python": []}
    for index in range(scenarios):
        for runtime in times:
            start = time.process_time()
            rows[runtime].append(montecarlo.fly_scenario(job, index, runtime))
            times[runtime] += time.process_time() - start
    same = pd.DataFrame(rows["step"]).equals(pd.DataFrame(rows["python"]))
    print(f"{scenarios} scenarios on the C step {times['step']:.1f} s CPU, on the Python "
          f"reference {times['python']:.1f} s CPU: {times['python'] / times['step']:.1f}x; "
          f"identical rows: {same} ({load_average()})")
    return same


def backends(job: montecarlo.Job, scenarios: int, dask: bool) -> bool:
    """Section 3's rates; False if the tables differ."""
    runs = [("1 worker (this process)", 1, None), ("2 local workers", 2, None)]
    if dask:
        runs.append(("Dask LocalCluster, 2 workers", 2, "local"))
    tables, rates = [], {}
    for label, workers, scheduler in runs:
        with scenario_executor(workers, scheduler) as executor:
            start = time.perf_counter()
            result = montecarlo.run_montecarlo(job, scenarios, executor, workers)
            wall = time.perf_counter() - start
        tables.append(result.table())
        rates[label] = scenarios / wall
        base = rates[runs[0][0]]
        print(f"{label}: {scenarios} scenarios in {wall:.1f} s wall = {rates[label]:.3f} "
              f"scenarios/s; parallel efficiency "
              f"{100 * rates[label] / (workers * base):.0f} % ({load_average()})")
    same = all(t.equals(tables[0]) for t in tables[1:])
    print(f"identical tables across backends: {same}")
    return same


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--whole", type=int, default=TARGET_SCENARIOS,
                        help="scenarios of the whole command (0: skip it)")
    parser.add_argument("--days", type=float, default=30.0, help="the run limit")
    parser.add_argument("--scenarios", type=int, default=0,
                        help="scenarios per backend for the rates (0: skip them)")
    parser.add_argument("--no-dask", action="store_true")
    parser.add_argument("--reference", type=int, default=0,
                        help="scenarios also flown by the Python reference, for the C "
                             "step's speed-up (0: skip)")
    args = parser.parse_args(argv)
    print(load_average())
    ok = True
    with tempfile.TemporaryDirectory() as tmp:
        path = import_slocum("nsb3", Path(tmp))
        if path is None:
            return 1
        mission = check_file(str(path)).mission
        setup = flight_setup(mission, FlightOptions(duration_s=args.days * 86400.0))
        limit = step_limit(setup)
        if args.whole:
            ok = whole_command(path, Path(tmp), args.whole, args.days, limit)
    job = montecarlo.Job(setup, read_spec())
    same = True
    if args.scenarios:
        same = backends(job, args.scenarios, not args.no_dask)
    if args.reference:
        same = reference_speedup(job, args.reference) and same
    print(load_average())
    return 1 if not same else 0 if ok else 2


if __name__ == "__main__":
    sys.exit(main())
