"""Runtime bench: what one tick costs the glider's computer, and the link, whole process.

    .venv/bin/python bench/bench_runtime.py [--runs 3] [--tick 4]

Instructions are callgrind's count of every instruction the mission binary's process
executes (the dynamic loader, the C library, start-up and exit included) while it flies
a mission over a pseudo-terminal against `protocol.Link`, with `--state-dir` on as on the
glider: event log, checkpoints, the link's framing, the mission's step. A second run of
each binary is stopped (SIGTERM) after its first tick: start-up and exit. Per tick is
the difference over the ticks between. Instruction counts do not depend on the machine's
load; the median of --runs runs is printed (they differ by the few instructions of a
read that found half a frame). callgrind's inclusive counts split the tick into the
mission's step (`gp_runtime_tick`), the link in (`gp_serial_read`,
`gp_frame_reader_feed`, `gp_sensors_unpack`), the link out (`gp_command_pack`,
`gp_frame_seal`, `gp_serial_write`), the checkpoint (`gp_journal_append`,
`gp_checkpoint_store`) and the event log (`gp_events_append`); the rest is the loop and
the clock.

Missions: the paper's Fig. 2 (without and with a plan) and a generated mission whose
state checks 200 events every tick. Readings: a 5-25 m yo (400 s period), a noisy
thermocline at 12 m, the glider drifting north at 0.3 m/s. Builds: the host's and the
TS-5500's (i486, musl, under callgrind's x86 tool); the TS-7800's ARM cannot run under
callgrind here. Also: link bytes per tick each way, peak RSS, text and static RAM
(.data + .bss) per board.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import tty
import zlib
from dataclasses import dataclass
from pathlib import Path

from gliderplan.contract import PLAN_FORMAT_VERSION, TICK_S
from gliderplan.language import check_source
from gliderplan.language.ir import CheckedMission
from gliderplan.planner.limits import flight_limits
from gliderplan.runtime.build import C_FLAGS, TARGETS, compile_mission, runtime_sources
from gliderplan.runtime.protocol import FdPort, Link

ROOT = Path(__file__).resolve().parents[1]
GOALS = {"instructions_per_tick": 2000, "text_bytes": 64 * 1024, "link_bytes_per_tick": 64}
# The parts of a tick, by the exported functions callgrind counts inclusively.
PARTS = {"step": ("gp_runtime_tick",),
         "link in": ("gp_serial_read", "gp_frame_reader_feed", "gp_sensors_unpack"),
         "link out": ("gp_command_pack", "gp_frame_seal", "gp_serial_write"),
         "checkpoint": ("gp_checkpoint_store", "gp_journal_append"),
         "event log": ("gp_events_append",)}
TS5500_HZ = 133e6  # AMD Elan SC520 clock
# Cycles per instruction assumed for the SC520 (a 486 core: ~1-2 for integer work, the
# x87 adds 8-70 cycles per operation); 4 is a pessimistic average for this mix.
TS5500_CPI = 4.0


def bench200_source(n_events: int = 200) -> str:
    """A two-state mission whose first state checks `n_events` events every tick.

    All but the last never fire (depth beyond reach), so every tick pays for all of them.
    """
    never = [f"    case depth > {1000 + k} && temp < {k} - 40 goto done"
             for k in range(n_events - 1)]
    return "\n".join([
        "mission bench200", "", "state patrol", "begin",
        "  flightroute nav(3910.5, -7349.8058)",
        "  flightprofile thermotrackyo(5, 25, .454, .454, 3, 4)",
        "  sensors missiontime, depth, pitch, temp", "  events", *never,
        "    case missiontime >= 2500 goto done", "end", "",
        "state done", "begin", "  flightroute noheading", "  flightprofile surface",
        "  sensors missiontime, depth", "  events", "    case missiontime >= 2510 exit",
        "end", ""])


def checked(source: str, name: str) -> CheckedMission:
    result = check_source(source, name)
    if result.mission is None:
        sys.exit(result.render())
    return result.mission


def fig2_plan(mission: CheckedMission, target: str) -> bytes:
    """A plan by hand (docs/plan-format.md) for the board of build `target` at its fastest
    clock: a CTD duty of 1/4 in s2; one profile per state."""
    board = mission.computer.board if target == "host" else target
    mhz = f"{flight_limits(mission, board).clocks_mhz[-1]:g}"
    body = (f"GPPLAN {PLAN_FORMAT_VERSION}\nmission {mission.name}\nhash {mission.hash}\n"
            f"computer {board} {mhz}\n"
            "budget_j 6630000\npredicted_j 9876.5\ncomponents hotel\nassumptions 0\nstates 3\n"
            f"state s1 {mhz} 600 0 1\npredict 1000 2 20\nenergy 3950\n"
            "profile 0 1 0.3 150 0.31\nend\n"
            f"state s2 {mhz} 600 1 1\npredict 1000 1 12\nenergy 3950\n"
            "sensor temp 60 15\nprofile 0 1 0.4 200 0.3\nend\n"
            f"state s3 {mhz} 600 0 1\npredict 500 1 5\nenergy 1976.5\n"
            "profile 0 1 0.454 230 0.31\nend\n").encode()
    return body + f"crc32 {zlib.crc32(body):08x}\n".encode()


def readings(tick: int, tick_s: float) -> dict[int, float]:
    """Sensors of one tick: missiontime, a 5-25 m yo, pitch, a position drifting north at
    0.3 m/s (lat, lon in DDMM.MMMM), a thermocline at 12 m with +-0.3 C of flicker."""
    t = tick * tick_s
    phase = t % 400.0 / 200.0
    depth = 5.0 + 20.0 * (phase if phase < 1.0 else 2.0 - phase)
    temp = (22.0 if depth < 12.0 else 9.0) + (0.3 if tick % 2 else -0.3)
    return {0: t, 1: depth, 2: -0.45 if phase < 1.0 else 0.45, 6: 3910.4 + 0.3 * t / 1852.0,
            7: -7349.7, 9: temp}


class CountingPort(FdPort):
    """FdPort that counts the bytes each way."""

    def __init__(self, fd: int) -> None:
        super().__init__(fd)
        self.read_bytes = self.written_bytes = 0

    def read(self, size: int = 1) -> bytes:
        data = super().read(size)
        self.read_bytes += len(data)
        return data

    def write(self, data: bytes) -> int:
        self.written_bytes += len(data)
        return super().write(data)


@dataclass
class Flight:
    ticks: int
    sensors_bytes: list[int]  # written per tick (SENSORS, with any retransmission)
    command_bytes: list[int]  # read per tick (COMMAND)
    peak_rss_kib: int


def fly(command: list[str], work: Path, tick_s: float, stop_after: int | None = None,
        pid_to_watch: bool = False) -> Flight:
    """Fly the binary over a pty with a fresh state directory until the mission exits (or
    `stop_after` ticks, then SIGTERM); bytes per tick each way."""
    state = work / "state"
    shutil.rmtree(state, ignore_errors=True)
    master, slave = os.openpty()
    tty.setraw(slave)
    process = subprocess.Popen([*command, "--device", os.ttyname(slave), "--state-dir",
                                str(state)], stderr=subprocess.PIPE)
    port = CountingPort(master)
    link = Link(port, retransmit_s=5.0)  # callgrind is slow to answer: no retransmissions
    try:
        hello = link.wait_hello(60)
        tick, peak_kib = 0, 0
        sent, received = [], []
        while True:
            before_out, before_in = port.written_bytes, port.read_bytes
            values = {i: v for i, v in readings(tick, tick_s).items()
                      if hello.read_mask >> i & 1}  # what the runtime reads, as HELLO says
            done = link.step(tick, values).done
            sent.append(port.written_bytes - before_out)
            received.append(port.read_bytes - before_in)
            if pid_to_watch:
                peak_kib = max(peak_kib, high_water_kib(process.pid))
            tick += 1
            if done or tick == stop_after:
                break
        if not done:
            process.send_signal(signal.SIGTERM)
        link.wait_release(60)
        status = process.wait(60)
    finally:
        os.close(master)
        os.close(slave)
    if status != (0 if done else 4):
        sys.exit(f"{command[-1]}: exit status {status}: {process.stderr.read().decode()}")
    process.stderr.close()
    return Flight(tick, sent, received, peak_kib)


def high_water_kib(pid: int) -> int:
    """VmHWM of a running process [KiB]; 0 once it has gone."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return 0
    found = re.search(r"^VmHWM:\s+(\d+) kB", status, re.MULTILINE)
    return int(found.group(1)) if found else 0


def callgrind(binary: Path, args: list[str], work: Path, tick_s: float,
              stop_after: int | None = None) -> tuple[Flight, dict[str, int]]:
    """A flight under callgrind: (the flight, inclusive instructions per function with
    "total" for the whole process)."""
    out = work / "callgrind.out"
    flight = fly(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
                  str(binary), *args], work, tick_s, stop_after)
    report = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100",
                             str(out)], capture_output=True, text=True, check=True).stdout
    counts = {"total": int(re.search(r"^([\d,]+) +\(100.0%\) +PROGRAM TOTALS", report,
                                     re.MULTILINE)[1].replace(",", ""))}
    for found in re.finditer(r"^\s*([\d,]+) \([\d. %]+\)\s+\S*?:(\w+)[ .]", report,
                             re.MULTILINE):
        counts.setdefault(found[2], int(found[1].replace(",", "")))
    return flight, counts


def per_tick(binary: Path, args: list[str], work: Path, tick_s: float,
             runs: int) -> tuple[int, dict[str, float], Flight]:
    """(start-up and exit, per-tick instructions by part with "tick" the whole, a
    flight): medians over `runs` pairs of whole and one-tick runs."""
    samples: dict[str, list[float]] = {}
    startups = []
    for _ in range(runs):
        flight, whole = callgrind(binary, args, work, tick_s)
        _, first = callgrind(binary, args, work, tick_s, stop_after=1)
        ticks = flight.ticks - 1
        samples.setdefault("tick", []).append((whole["total"] - first["total"]) / ticks)
        for part, functions in PARTS.items():
            spent = sum(whole.get(f, 0) - first.get(f, 0) for f in functions)
            samples.setdefault(part, []).append(spent / ticks)
        startups.append(first["total"])
    medians = {part: statistics.median(values) for part, values in samples.items()}
    medians["rest"] = medians["tick"] - sum(medians[p] for p in PARTS)
    return int(statistics.median(startups)), medians, flight


def sizes(binary_or_object: Path) -> tuple[int, int, int]:
    """(text, data, bss) bytes as size(1) counts them."""
    lines = subprocess.run(["size", str(binary_or_object)], capture_output=True, text=True,
                           check=True).stdout.splitlines()
    text, data, bss = lines[1].split()[:3]
    return int(text), int(data), int(bss)


def runtime_objects(compiler: str, flags: list[str], mission_c: Path,
                    work: Path) -> tuple[int, int, int]:
    """(text, data, bss) of the runtime's own objects and the mission (no C library)."""
    total = [0, 0, 0]
    with runtime_sources() as (include, sources):
        for source in [*sources, mission_c]:
            obj = work / f"{source.stem}.o"
            subprocess.run([compiler, *C_FLAGS, *flags, f"-I{include}", "-c", str(source),
                            "-o", str(obj)], check=True)
            total = [a + b for a, b in zip(total, sizes(obj), strict=True)]
    return total[0], total[1], total[2]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3, help="callgrind runs (median)")
    parser.add_argument("--tick", type=float, default=TICK_S,
                        help=f"tick [s] (default {TICK_S:g}, the glider's)")
    args = parser.parse_args()
    for tool in ("cc", "valgrind", "callgrind_annotate", "size"):
        if shutil.which(tool) is None:
            sys.exit(f"bench_runtime: {tool} is not installed")
    fig2 = checked((ROOT / "examples" / "fig2.mission").read_text(), "fig2.mission")
    bench200 = checked(bench200_source(), "bench200.mission")

    with tempfile.TemporaryDirectory(prefix="bench-runtime-") as tmp:
        work = Path(tmp)
        os.environ.setdefault("GLIDERPLAN_CACHE_DIR", str(work / "cache"))
        targets = ["host"] + [t for t in ("ts5500",) if shutil.which(TARGETS[t].compiler)]
        print(f"instructions per tick, whole process under callgrind, --state-dir on, "
              f"{args.tick:g} s ticks, median of {args.runs} runs; "
              f"goal {GOALS['instructions_per_tick']} for Fig. 2")
        parts = " ".join(f"{p:>10}" for p in [*PARTS, "rest"])
        print(f"{'build':7} {'mission':10} {'ticks':>5} {'start-up':>9} {'tick':>6} {parts}")
        fig2_tick = {}
        for target in targets:
            plan = work / f"fig2-{target}.plan"
            plan.write_bytes(fig2_plan(fig2, target))
            for label, mission, options in (("fig2", fig2, []),
                                            ("fig2+plan", fig2, ["--plan", str(plan)]),
                                            ("bench200", bench200, [])):
                binary = compile_mission(mission, work / target / label, target)
                startup, tick, flight = per_tick(binary, options, work, args.tick, args.runs)
                if label == "fig2":
                    fig2_tick[target] = tick["tick"]
                cells = " ".join(f"{tick[p]:10.0f}" for p in [*PARTS, "rest"])
                print(f"{target:7} {label:10} {flight.ticks:5d} {startup:9,d} "
                      f"{tick['tick']:6.0f} {cells}")
        if "ts5500" in fig2_tick:
            share = fig2_tick["ts5500"] * TS5500_CPI / TS5500_HZ / args.tick
            print(f"TS-5500 CPU share, Fig. 2 at one tick per {args.tick:g} s: "
                  f"{fig2_tick['ts5500']:,.0f} instructions x {TS5500_CPI:g} cycles (assumed) "
                  f"/ {TS5500_HZ / 1e6:g} MHz = {100 * share:.4f} %")

        host = compile_mission(fig2, work / "host" / "fig2", "host")
        fig2_flight = fly([str(host)], work, args.tick, pid_to_watch=True)
        # the first tick's COMMAND is whole; the last one's bytes include the RELEASE
        steady_out = fig2_flight.sensors_bytes[1:-1]
        steady_in = fig2_flight.command_bytes[1:-1]
        both = [a + b for a, b in zip(steady_out, steady_in, strict=True)]
        print(f"\nlink, Fig. 2 over a pty (protocol.Link), {len(both)} ticks between the "
              f"first and the last: bytes per tick SENSORS {statistics.mean(steady_out):.1f}, "
              f"COMMAND {statistics.mean(steady_in):.1f}, both {statistics.mean(both):.1f} "
              f"(goal {GOALS['link_bytes_per_tick']}; most {max(both)}, over the goal on "
              f"{sum(b > GOALS['link_bytes_per_tick'] for b in both)} ticks); first tick "
              f"{fig2_flight.sensors_bytes[0]} + {fig2_flight.command_bytes[0]}, last "
              f"{fig2_flight.sensors_bytes[-1]} + {fig2_flight.command_bytes[-1]} (RELEASE "
              f"included)")
        print(f"peak RSS of the runtime (VmHWM, host, dynamic C library): "
              f"{fig2_flight.peak_rss_kib} KiB")

        print(f"\ntext and static RAM (size(1)), Fig. 2; text goal {GOALS['text_bytes']} B")
        print(f"{'board':7} {'runtime + mission objects: text':>32} {'data + bss':>11} "
              f"{'whole binary: text':>19} {'data + bss':>11}")
        mission_c = host.with_suffix(".c")
        for target in ("host", "ts7800", "ts5500"):
            board = TARGETS[target]
            if shutil.which(board.compiler) is None:
                print(f"{target:7} {board.compiler} not installed")
                continue
            flags = [f for f in board.flags if f != "-static"]
            text, data, bss = runtime_objects(board.compiler, flags, mission_c, work)
            binary = compile_mission(fig2, work / target / "fig2", target)
            whole_text, whole_data, whole_bss = sizes(binary)
            linked = "static" if "-static" in board.flags else "dynamic C library"
            print(f"{target:7} {text:32,d} {data + bss:11,d} {whole_text:19,d} "
                  f"{whole_data + whole_bss:11,d}  ({linked})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
