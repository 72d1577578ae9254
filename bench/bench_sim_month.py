"""Benchmark: a simulated month on the runtime's C step, against the Python reference and
per simulated day across missions, printed as ratios from one run.

    .venv/bin/python bench/bench_sim_month.py [--days 30] [--reference-days 1] [--runs 3]

1. In this process: the C flight (the compiled runtime's step with the glider, science
   and energy models in C, sim/flight.c; `fly`'s default) and the Python reference
   (`fly(..., runtime="python")`) fly --reference-days of examples/survey_month.mission
   and of tests/missions/sim_month.mission, bench ocean, seed 0: the flights must be
   identical (trace and every per-tick column bit for bit); ticks per second of each.
2. The month-long survey and the event-heavy imported Slocum missions nsb3 and helgo
   (`import-slocum` of the shared logs' .mi files), --days each (a mission may end
   before): the flight in this process on the C step, CPU time per simulated day, as a
   ratio of the survey's (target: nsb3 and helgo <= 1.5x); and the whole command as the
   user runs it, `gliderplan sim MISSION --duration 30d -o DIR` (check, fly, account,
   every file and plot; a fresh process, median of --runs after a warm-up): wall and
   CPU time (target < 2 s wall).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from whole_process import IMPORTED, gliderplan, import_slocum, load_average, median_of

from gliderplan.language import check_file
from gliderplan.sim.flight import fly
from gliderplan.sim.loop import RunRecord
from gliderplan.sim.setup import FlightOptions, flight_setup

REPO = Path(__file__).resolve().parents[1]
SURVEY = REPO / "examples" / "survey_month.mission"
MISSIONS = (SURVEY, REPO / "tests" / "missions" / "sim_month.mission")
COMMAND_GOAL_S = 2.0
PER_DAY_GOAL = 1.5  # an imported mission's cost per simulated day, over the survey's


def timed_run(mission, days: float, tick_s: float, runtime: str) -> tuple[RunRecord, float]:
    """A flight and its wall time [s]."""
    setup = flight_setup(mission, FlightOptions(noise="none", tick_s=tick_s,
                                                duration_s=days * 86400.0, runtime=runtime))
    start = time.perf_counter()
    record = fly(mission, setup.water.ocean, setup.config, setup.vehicle, runtime=runtime)
    return record, time.perf_counter() - start


def identical(a: RunRecord, b: RunRecord) -> bool:
    return a.trace == b.trace and a.columns.keys() == b.columns.keys() and all(
        np.array_equal(a.columns[k].view(np.uint8), b.columns[k].view(np.uint8))
        for k in a.columns)


def step_against_reference(path: Path, days: float, tick_s: float) -> bool:
    """Section 1 for one mission; False if the two flights differ."""
    mission = check_file(str(path)).mission
    timed_run(mission, 0.1, tick_s, "step")  # warm-up: imports, the build's cache
    step, step_s = timed_run(mission, days, tick_s, "step")
    reference, reference_s = timed_run(mission, days, tick_s, "python")
    ticks = len(step.columns["time_s"])
    same = identical(step, reference)
    print(f"{path.name}, {days:g} d at {tick_s:g} s ({ticks:,} ticks, {len(step.trace)} "
          f"transitions): C step {step_s:.2f} s ({ticks / step_s:,.0f} ticks/s), Python "
          f"reference {reference_s:.2f} s ({ticks / reference_s:,.0f} ticks/s): "
          f"{reference_s / step_s:.0f}x; identical flights: {same}")
    return same


def whole_commands(work: Path, days: float, runs: int) -> bool:
    """Section 2; False if a target is missed."""
    missions = {"survey_month": SURVEY}
    for name in IMPORTED:
        if (path := import_slocum(name, work)) is not None:
            missions[name] = path
    per_day = {}
    for name, path in missions.items():
        mission = check_file(str(path)).mission
        start = time.process_time()
        record, _ = timed_run(mission, days, 4.0, "step")
        flown_days = record.columns["time_s"][-1] / 86400.0
        per_day[name] = (time.process_time() - start) / flown_days
        print(f"{name}: {flown_days:.1f} days flown ({record.ended}) on the C step, "
              f"{per_day[name] * 1000:.1f} ms CPU per simulated day")
    outputs = {name: work / name for name in missions}
    commands = {name: gliderplan("sim", str(path), "--duration", f"{days:g}d", "-o",
                                 str(outputs[name])) for name, path in missions.items()}
    timings = median_of(commands, runs)
    for name, timing in timings.items():
        summary = json.loads((outputs[name] / "summary.json").read_text())
        print(f"gliderplan sim {name} --duration {days:g}d: {timing.wall_s:.2f} s wall, "
              f"{timing.cpu_s:.2f} s CPU, {summary['simulated_s'] / 86400:.1f} days flown "
              f"(median of {runs}; target < {COMMAND_GOAL_S:g} s: wall "
              f"{'met' if timing.wall_s < COMMAND_GOAL_S else 'not met'}, CPU "
              f"{'met' if timing.cpu_s < COMMAND_GOAL_S else 'not met'})")
    met = all(t.wall_s < COMMAND_GOAL_S for t in timings.values())
    for name in per_day.keys() - {"survey_month"}:
        ratio = per_day[name] / per_day["survey_month"]
        met &= ratio <= PER_DAY_GOAL
        print(f"  {name} per simulated day: {ratio:.2f}x the survey's (target <= "
              f"{PER_DAY_GOAL:g}x)")
    print(f"  every command under {COMMAND_GOAL_S:g} s: "
          f"{all(t.wall_s < COMMAND_GOAL_S for t in timings.values())}")
    return met


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--days", type=float, default=30.0, help="of each whole command")
    parser.add_argument("--reference-days", type=float, default=1.0,
                        help="flown by both the C step and the Python reference")
    parser.add_argument("--runs", type=int, default=3, help="runs of each whole command")
    parser.add_argument("--tick", type=float, default=4.0)
    args = parser.parse_args(argv)
    print(load_average())
    same = [step_against_reference(path, args.reference_days, args.tick) for path in MISSIONS]
    if not all(same):
        print("the C step's flight differs from the reference!", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory() as tmp:
        met = whole_commands(Path(tmp), args.days, args.runs)
    print(load_average())
    return 0 if met else 2


if __name__ == "__main__":
    sys.exit(main())
