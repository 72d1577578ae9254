"""Benchmark: a simulated month. The fast executor against the tick-by-tick reference, and
the whole `gliderplan sim` command of the month-long survey.

    .venv/bin/python bench/bench_sim_month.py [--days 30] [--runs 5] [--tick 4]

1. The Python executor flies --days (30) of examples/survey_month.mission (the month-long
   thermocline survey) and of tests/missions/sim_month.mission (yo 3-38 m along three
   waypoints, a surfacing with an Iridium call every 6 h, CTD on), bench ocean, seed 0,
   in runs of ticks (sim/fast.py; target: 30 days in <= 1 s) and, as the baseline in the
   same run, tick by tick (`fly(..., tick_by_tick=True)`, the reference). The two flights
   must be identical, trace and every per-tick column bit for bit.
2. The whole command as the user runs it, `gliderplan sim examples/survey_month.mission
   -o DIR` (check, fly, account, trace.csv, timeseries.parquet, summary.json and the two
   plots, which a second process draws while the first writes the rest; target <= 2 s):
   a fresh process each run, median of --runs after a warm-up; beside it the CPU time
   of each stage in this process.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from whole_process import gliderplan, load_average, median_of

from gliderplan.language import check_file
from gliderplan.power_models import load_vehicle
from gliderplan.sim import ocean
from gliderplan.sim.flight import fly
from gliderplan.sim.loop import RunConfig, RunRecord

REPO = Path(__file__).resolve().parents[1]
SURVEY = REPO / "examples" / "survey_month.mission"
MISSIONS = (SURVEY, REPO / "tests" / "missions" / "sim_month.mission")


def timed_run(mission, days: float, tick_s: float,
              tick_by_tick: bool = False) -> tuple[RunRecord, float]:
    """A flight and its wall time [s]."""
    config = RunConfig(tick_s=tick_s, duration_s=days * 86400.0, seed=0)
    vehicle = load_vehicle(mission.vehicle)
    start = time.perf_counter()
    record = fly(mission, ocean.bench(), config, vehicle, tick_by_tick=tick_by_tick)
    return record, time.perf_counter() - start


def identical(a: RunRecord, b: RunRecord) -> bool:
    return a.trace == b.trace and a.columns.keys() == b.columns.keys() and all(
        np.array_equal(a.columns[k].view(np.uint8), b.columns[k].view(np.uint8))
        for k in a.columns)


def fast_against_reference(path: Path, days: float, tick_s: float) -> bool:
    """Section 1 for one mission; False if the two flights differ."""
    mission = check_file(str(path)).mission
    timed_run(mission, 0.1, tick_s)  # warm-up: imports, caches
    fast, fast_s = timed_run(mission, days, tick_s)
    reference, reference_s = timed_run(mission, days, tick_s, tick_by_tick=True)
    ticks = len(fast.columns["time_s"])
    same = identical(fast, reference)
    print(f"{path.name}, {days:g} d at {tick_s:g} s ({ticks:,} ticks, {len(fast.trace)} "
          f"transitions): runs of ticks {fast_s:.2f} s ({ticks / fast_s:,.0f} ticks/s), "
          f"tick by tick {reference_s:.2f} s ({ticks / reference_s:,.0f} ticks/s): "
          f"{reference_s / fast_s:.1f}x; identical flights: {same}")
    return same


def whole_command(runs: int) -> None:
    """Section 2: `gliderplan sim` of the month-long survey, whole process and by stage."""
    with tempfile.TemporaryDirectory() as tmp:
        command = gliderplan("sim", str(SURVEY), "-o", str(Path(tmp) / "run"))
        timing = median_of({"sim": command}, runs)["sim"]
    print(f"gliderplan sim {SURVEY.name} (30 d, every file and plot): "
          f"{timing.wall_s:.2f} s wall, {timing.cpu_s:.2f} s CPU (median of {runs}; "
          f"{load_average()})")
    stages = stage_times()
    print("  stages (CPU, this process): " + ", ".join(
        f"{name} {seconds:.2f} s" for name, seconds in stages.items())
        + f"; {sum(stages.values()):.2f} s")


def stage_times() -> dict[str, float]:
    """CPU time [s] of each stage of `run_mission`'s pipeline after the check, in this
    process (the imports of pyarrow and matplotlib counted in the stage that needs them)."""
    from gliderplan.sim import energy, outputs, plots

    clock = time.process_time
    times: dict[str, float] = {}
    mission = check_file(str(SURVEY)).mission
    vehicle = load_vehicle(mission.vehicle)
    start = clock()
    record = fly(mission, ocean.bench(), RunConfig(), vehicle)
    times["fly"] = clock() - start
    start = clock()
    used = energy.account(record, mission, vehicle, None)
    times["account"] = clock() - start
    start = clock()
    table = outputs.timeseries_table(record, used, mission.battery.energy_j)
    outputs.parquet_bytes(table, outputs.TIMESERIES_DICTIONARY)
    outputs.trace_csv(record.trace)
    times["files"] = clock() - start
    start = clock()
    plots.depth_png(plots.depth_series(record))
    plots.energy_png(plots.energy_series(record, used, None))
    times["plots (a second process in the command)"] = clock() - start
    return times


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--days", type=float, default=30.0)
    parser.add_argument("--runs", type=int, default=5, help="runs of the whole command")
    parser.add_argument("--tick", type=float, default=4.0)
    args = parser.parse_args(argv)
    print(load_average())
    same = [fast_against_reference(path, args.days, args.tick) for path in MISSIONS]
    if not all(same):
        print("the fast executor's flight differs from the reference!", file=sys.stderr)
        return 1
    whole_command(args.runs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
