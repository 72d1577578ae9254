"""Benchmark: the simulator's speed with the runtime's C step in process and with the C
runtime in closed loop over a pseudo-terminal.

    .venv/bin/python bench/bench_sim.py [--days 30] [--c-days 1] [--tick 4] [--runs 3] [--no-c]
                                        [--mission FILE] [--reference]

Mission (default; --mission for another): tests/missions/sim_month.mission (yo 3-38 m
along three waypoints, a surfacing with an Iridium call every 6 h, CTD on; exits after 30
days), bench ocean, seed 0.

1. The C step (`fly`'s default), --days of mission at --tick: wall time and simulated
   seconds per wall second (target: 30 days at 4 s in <= 10 s). Beside it: the
   reference semantics (`language.semantics.step`, tree-walking `ir.evaluate`) checking
   the events of every one of those ticks, against the Python executor's compiled
   checks.
2. C runtime closed loop, --c-days at --tick, medians of --runs runs taken in turn:
   - the whole command the user runs, `gliderplan sim MISSION --runtime c --duration
     Nd`, against the same command for one tick (start-up, imports, build cache, output
     files and plots): ticks per wall second of the loop (target >= 10,000), and of the
     command as a whole; without a state directory (the command's default), with
     `--state-dir` on the disk as on the glider (checkpoints fdatasync'd), and with it in
     /dev/shm (memory, where fdatasync costs nothing); the records written;
   - the loop in this process (`sim.flight.fly`; the runtime is its own process): ticks
     per wall second, and CPU per tick on each side of the line;
   - the floor under any such loop: two C processes that only answer each other over a
     pty with frames of the same sizes (bench/pty_roundtrip.c), as many round trips;
   - the C step on the same ticks, in process (target: >= 20x the loop's ticks per
     second); the two traces must agree.
   For comparison, MOOS-IvP's uSimMarine is reported to run 50-300x real time.
3. With --reference: the Python reference executor on the same days
   (`fly(..., runtime="python")`); the two traces must agree.
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from whole_process import gliderplan, load_average, median_of

from gliderplan.language import check_file, semantics
from gliderplan.language.registry import SENSORS
from gliderplan.sim import compiled
from gliderplan.sim.flight import fly
from gliderplan.sim.loop import RunRecord
from gliderplan.sim.setup import FlightOptions, flight_setup

BENCH = Path(__file__).resolve().parent
MISSION = BENCH.parent / "tests" / "missions" / "sim_month.mission"
USIMMARINE_REAL_TIME = (50, 300)  # MOOS-IvP uSimMarine, reported time warp
# Frame sizes of the loop's usual tick (docs/protocol.md): SENSORS with the mission's
# five read sensors and no mask, a COMMAND whose heading changed.
SENSORS_WIRE_BYTES, COMMAND_WIRE_BYTES = 35, 21


def timed_run(mission, days: float, tick_s: float, runtime: str
              ) -> tuple[RunRecord, float, float, float]:
    """(record, wall [s], CPU of this process [s], CPU of processes it waited for [s])."""
    setup = flight_setup(mission, FlightOptions(noise="none", tick_s=tick_s,
                                                duration_s=days * 86400.0, runtime=runtime))
    children = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu, start = time.process_time(), time.perf_counter()
    record = fly(mission, setup.water.ocean, setup.config, setup.vehicle, runtime=runtime)
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    runtime_cpu = (after.ru_utime - children.ru_utime) + (after.ru_stime - children.ru_stime)
    return record, wall, cpu, runtime_cpu


def state_dirs(tmp: Path) -> dict[str, Path | None]:
    """Where the runtime keeps its state in the whole command: nowhere (`gliderplan sim`'s
    default), on the disk that holds the run (as on the glider: every checkpoint is
    fdatasync'd before its COMMAND goes), and in memory (/dev/shm, where fdatasync returns
    at once), which tells the disk's share from the rest of the checkpoints' cost."""
    where: dict[str, Path | None] = {"no state dir": None,
                                     "--state-dir on disk": tmp / "state"}
    if Path("/dev/shm").is_dir():
        where["--state-dir in /dev/shm"] = Path(f"/dev/shm/bench-sim-state-{os.getpid()}")
    return where


def records_written(state_dir: Path) -> int:
    """Checkpoint records a flight wrote after its first (runtime/README.md: a header,
    then two slots of the size at byte 72, each record opening with its sequence number;
    native byte order). Every other tick it stepped wrote a journal entry instead."""
    data = (state_dir / "checkpoint").read_bytes()
    slot = int.from_bytes(data[72:76], sys.byteorder)
    return max(int.from_bytes(data[at:at + 4], sys.byteorder)
               for at in (slot, 2 * slot) if len(data) >= at + 4) - 1


def pty_floor(binary: Path, round_trips: int) -> tuple[float, float]:
    """(wall [s], CPU of both processes [s]) of round trips over a pty and nothing else."""
    done = subprocess.run([str(binary), str(round_trips), str(SENSORS_WIRE_BYTES),
                           str(COMMAND_WIRE_BYTES)], capture_output=True, text=True, check=True)
    _, wall, cpu = done.stdout.split()
    return float(wall), float(cpu)


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
    parser.add_argument("--runs", type=int, default=3, help="runs of the C loop (median)")
    parser.add_argument("--no-c", action="store_true", help="skip the C closed loop")
    parser.add_argument("--mission", default=str(MISSION), help="the mission to fly")
    parser.add_argument("--reference", action="store_true",
                        help="also fly the days on the Python reference executor")
    args = parser.parse_args(argv)
    mission = check_file(args.mission).mission

    timed_run(mission, 0.01, args.tick, "step")  # warm-up: the build's cache
    record, wall_s, cpu_s, _ = timed_run(mission, args.days, args.tick, "step")
    simulated_s = float(record.columns["time_s"][-1])
    ticks = len(record.columns["time_s"])
    print(f"C step: {args.days:g} d at {args.tick:g} s = {ticks} ticks in "
          f"{wall_s:.2f} s wall ({cpu_s:.2f} s CPU, {load_average()}): "
          f"{simulated_s / wall_s:,.0f} simulated s per wall s, "
          f"{ticks / wall_s:,.0f} ticks/s ({record.ended}, {len(record.trace)} transitions)")
    reference_s, compiled_s = event_checks(mission, record)
    print(f"  event checks on those ticks: reference semantics {reference_s:.2f} s, "
          f"compiled {compiled_s:.2f} s ({reference_s / compiled_s:.0f}x)")
    if args.reference:
        reference, reference_s, _, _ = timed_run(mission, args.days, args.tick, "python")
        same = reference.trace == record.trace
        print(f"  the Python reference: {reference_s:.2f} s wall (the C step "
              f"{reference_s / wall_s:.1f}x faster; {'same' if same else 'DIFFERENT'} trace)")
        if not same:
            return 1

    if args.no_c:
        return 0
    if shutil.which("cc") is None:
        print("C closed loop: skipped (no C compiler)", file=sys.stderr)
        return 0
    return c_loop(mission, args)


def c_loop(mission, args: argparse.Namespace) -> int:
    """The C runtime's closed loop: whole command, in process, and the pty's floor."""
    timed_run(mission, 0.01, args.tick, "c")  # compile once (cached) outside the timing
    with tempfile.TemporaryDirectory(prefix="bench-sim-") as tmp:
        floor_binary = Path(tmp) / "pty_roundtrip"
        subprocess.run(["cc", "-O2", "-std=c11", str(BENCH / "pty_roundtrip.c"), "-o",
                        str(floor_binary)], check=True)
        command = gliderplan("sim", args.mission, "--runtime", "c", "--tick", f"{args.tick:g}")
        where = state_dirs(Path(tmp))
        commands, fresh = {}, {}  # fresh: each command's state directory, emptied each run
        for setting, state in where.items():
            for kind, duration in (("run", f"{args.c_days:g}d"), ("tick", f"{args.tick:g}s")):
                name, options = f"{kind}, {setting}", []
                if state is not None:
                    fresh[name] = Path(f"{state}-{kind}")
                    options = ["--state-dir", str(fresh[name])]
                commands[name] = [*command, "--duration", duration, *options, "-o",
                                  str(Path(tmp) / kind)]
        whole = median_of(commands, args.runs, fresh=fresh)
        records = records_written(fresh["run, --state-dir on disk"])
        for directory in fresh.values():
            shutil.rmtree(directory, ignore_errors=True)
        samples: dict[str, list[float]] = {}
        for _ in range(args.runs):  # in turn, so that a change of load falls on all alike
            record, wall, cpu, runtime_cpu = timed_run(mission, args.c_days, args.tick, "c")
            ticks = len(record.columns["time_s"])
            floor_wall, floor_cpu = pty_floor(floor_binary, ticks)
            step_record, step_wall, step_cpu, _ = timed_run(mission, args.c_days, args.tick,
                                                            "step")
            for name, value in (("wall", wall), ("cpu", cpu), ("runtime", runtime_cpu),
                                ("floor", floor_wall), ("floor cpu", floor_cpu),
                                ("step", step_wall), ("step cpu", step_cpu)):
                samples.setdefault(name, []).append(value)
    if record.trace != step_record.trace:
        print("the closed loop's and the C step's traces differ!", file=sys.stderr)
        return 1
    m = {name: statistics.median(values) for name, values in samples.items()}
    print(f"\nC runtime in closed loop over a pty, {args.c_days:g} d at {args.tick:g} s = "
          f"{ticks} ticks, medians of {args.runs} runs, {load_average()}:")
    loops = {}
    for setting in where:
        run, tick = whole[f"run, {setting}"], whole[f"tick, {setting}"]
        loops[setting] = run.wall_s - tick.wall_s
        print(f"  whole command, {setting}: {run.wall_s:.2f} s wall ({run.cpu_s:.2f} s CPU); "
              f"for one tick {tick.wall_s:.2f} s; the loop {ticks / loops[setting]:,.0f} "
              f"ticks/s (target 10,000), the command {ticks / run.wall_s:,.0f} ticks/s")
    extra_ms = 1e3 * (loops["--state-dir on disk"] - loops["no state dir"])
    print(f"  the state directory on disk: every tick fdatasync'd ({records} records, "
          f"{ticks - records} journal entries), {extra_ms:.0f} ms more loop: "
          f"{extra_ms / ticks:.2f} ms per tick")
    rate = ticks / m["wall"]
    print(f"  the loop in process: {rate:,.0f} ticks/s, {rate * args.tick:,.0f}x real time "
          f"(uSimMarine: {USIMMARINE_REAL_TIME[0]}-{USIMMARINE_REAL_TIME[1]}x); CPU per tick: "
          f"simulator {m['cpu'] / ticks * 1e6:.1f} us, runtime {m['runtime'] / ticks * 1e6:.1f} "
          f"us (its system calls and the pty's kernel work included)")
    print(f"  floor, the pty round trip alone ({SENSORS_WIRE_BYTES} + {COMMAND_WIRE_BYTES} "
          f"bytes, two C processes): {ticks / m['floor']:,.0f} round trips/s, "
          f"{m['floor cpu'] / ticks * 1e6:.1f} us CPU each; the loop runs at "
          f"{m['floor'] / m['wall']:.2f}x of it")
    loop_cpu = m["cpu"] + m["runtime"]
    print(f"  the C step in process on the same ticks: {ticks / m['step']:,.0f} ticks/s "
          f"wall, {ticks / m['step cpu']:,.0f} per CPU s; the loop in process "
          f"{ticks / m['wall']:,.0f} ticks/s wall, {ticks / loop_cpu:,.0f} per CPU s (both "
          f"processes): the step {m['wall'] / m['step']:.0f}x the loop's ticks/s in wall, "
          f"{loop_cpu / m['step cpu']:.0f}x in CPU (target 20x); identical traces")
    return 0


if __name__ == "__main__":
    sys.exit(main())
