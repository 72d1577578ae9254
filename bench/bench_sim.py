"""Benchmark: the simulator's speed with the Python executor and with the C runtime in
closed loop over a pseudo-terminal.

    .venv/bin/python bench/bench_sim.py [--days 30] [--c-days 1] [--tick 4] [--no-c]

Mission: tests/missions/sim_month.mission (yo 3-38 m along three waypoints, a surfacing
with an Iridium call every 6 h, CTD on; exits after 30 days), bench ocean, seed 0.

1. Python executor, --days of mission at --tick: wall time and simulated seconds per
   wall second (target: 30 days at 4 s in <= 10 s). Baseline in the same run: the
   reference semantics (`language.semantics.step`, tree-walking `ir.evaluate`) checking
   the events of every one of those ticks, against the executor's compiled checks.
2. C runtime closed loop: the mission compiled for the host (cached), SENSORS and
   COMMAND frames over a pty for --c-days: ticks per wall second (target >= 10,000) and
   the ratio to real time; the Python executor on the same ticks is the baseline.
   For comparison, MOOS-IvP's uSimMarine is reported to run 50-300x real time.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path

from gliderplan.language import check_file, semantics
from gliderplan.language.registry import SENSORS
from gliderplan.power_models import load_vehicle
from gliderplan.sim import compiled, ocean
from gliderplan.sim.flight import fly
from gliderplan.sim.loop import RunConfig, RunRecord

MISSION = Path(__file__).resolve().parents[1] / "tests" / "missions" / "sim_month.mission"
USIMMARINE_REAL_TIME = (50, 300)  # MOOS-IvP uSimMarine, reported time warp


def timed_run(mission, days: float, tick_s: float, runtime: str) -> tuple[RunRecord, float]:
    config = RunConfig(tick_s=tick_s, duration_s=days * 86400.0, seed=0)
    vehicle = load_vehicle(mission.vehicle)
    start = time.perf_counter()
    record = fly(mission, ocean.bench(), config, vehicle, runtime=runtime)
    return record, time.perf_counter() - start


def event_checks(mission, record: RunRecord) -> tuple[float, float]:
    """Wall time [s] of checking every tick's events: reference semantics vs compiled."""
    c = record.columns
    names = record.state_names
    # (state, stack as deep as it was: its contents do not matter to the check, time, depth)
    ticks = [(names[s], (names[0],) * k, t, d)
             for s, k, t, d in zip(c["state"], c["stack_depth"], c["time_s"], c["depth_m"],
                                   strict=True) if s < len(names)]
    variables = {v.name: v.initial for v in mission.variables}
    array = [0.0] * len(SENSORS)
    start = time.perf_counter()
    for state, stack, t, d in ticks:
        named = {"missiontime": t, "depth": d, **{s.name: 0.0 for s in SENSORS[2:]}}
        semantics.step(mission, semantics.Machine(state, stack, variables), named, t)
    reference_s = time.perf_counter() - start
    checkers = {s.name: compiled.event_checker(s) for s in mission.states}
    start = time.perf_counter()
    for state, _, t, d in ticks:
        array[0], array[1] = t, d
        checkers[state](array, variables)
    return reference_s, time.perf_counter() - start


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--days", type=float, default=30.0)
    parser.add_argument("--c-days", type=float, default=1.0)
    parser.add_argument("--tick", type=float, default=4.0)
    parser.add_argument("--no-c", action="store_true", help="skip the C closed loop")
    args = parser.parse_args(argv)
    mission = check_file(str(MISSION)).mission

    record, wall_s = timed_run(mission, args.days, args.tick, "python")
    simulated_s = float(record.columns["time_s"][-1])
    ticks = len(record.columns["time_s"])
    print(f"Python executor: {args.days:g} d at {args.tick:g} s = {ticks} ticks in "
          f"{wall_s:.2f} s wall: {simulated_s / wall_s:,.0f} simulated s per wall s, "
          f"{ticks / wall_s:,.0f} ticks/s ({record.ended}, {len(record.trace)} transitions)")
    reference_s, compiled_s = event_checks(mission, record)
    print(f"  event checks on those ticks: reference semantics {reference_s:.2f} s, "
          f"compiled {compiled_s:.2f} s ({reference_s / compiled_s:.0f}x)")

    if args.no_c:
        return 0
    if shutil.which("cc") is None:
        print("C closed loop: skipped (no C compiler)", file=sys.stderr)
        return 0
    timed_run(mission, 0.01, args.tick, "c")  # compile once (cached) outside the timing
    c_record, c_wall_s = timed_run(mission, args.c_days, args.tick, "c")
    py_record, py_wall_s = timed_run(mission, args.c_days, args.tick, "python")
    if c_record.trace != py_record.trace:
        print("C and Python traces differ!", file=sys.stderr)
        return 1
    c_ticks = len(c_record.columns["time_s"])
    rate = c_ticks / c_wall_s
    warp = rate * args.tick
    print(f"C runtime over the pty: {c_ticks} ticks in {c_wall_s:.2f} s wall: {rate:,.0f} "
          f"ticks/s, {warp:,.0f}x real time (uSimMarine: {USIMMARINE_REAL_TIME[0]}-"
          f"{USIMMARINE_REAL_TIME[1]}x, so {warp / USIMMARINE_REAL_TIME[1]:.0f}-"
          f"{warp / USIMMARINE_REAL_TIME[0]:.0f}x faster)")
    print(f"  baseline, Python executor in-process on the same ticks: "
          f"{c_ticks / py_wall_s:,.0f} ticks/s (C over the pty: "
          f"{py_wall_s / c_wall_s:.2f}x of it); identical traces")
    return 0


if __name__ == "__main__":
    sys.exit(main())
