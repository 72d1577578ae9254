"""Runtime bench: instructions per tick, text size, peak RSS and link bytes per tick.

    .venv/bin/python bench/bench_runtime.py [--ticks-per-s 1]

Instructions are counted by callgrind over a bench driver that links the runtime's
library (every runtime/src/*.c but main) with a generated mission and feeds it SENSORS
frames from memory: `--toggle-collect` counts only the function named, so start-up
and I/O are excluded. Two counts per mission: the step alone (`gp_runtime_tick`) and
the whole per-tick CPU work (SENSORS decoded, step, COMMAND encoded). Missions: the
paper's Fig. 2 (without and with a plan) and a generated mission whose state checks
200 events every tick. The i486 build (the TS-5500's instruction set) is counted too,
when its cross compiler is installed. Text size is size(1) of the binaries; peak RSS
and link bytes come from a Fig. 2 run over a pty against protocol.Link.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import tty
import zlib
from pathlib import Path

from gliderplan.language import check_source
from gliderplan.language.ir import CheckedMission
from gliderplan.runtime.build import (
    C_FLAGS,
    LINK_FLAGS,
    TARGETS,
    compile_mission,
    runtime_sources,
)
from gliderplan.runtime.protocol import FdPort, Link

ROOT = Path(__file__).resolve().parents[1]
TS5500_HZ = 133e6  # AMD Elan SC520 clock
# Cycles per instruction assumed for the SC520 (a 486 core: ~1-2 for integer work, the
# x87 adds 8-70 cycles per operation); 4 is a pessimistic average for this mix.
TS5500_CPI = 4.0
GOALS = {"instructions_fig2": 2000, "text_bytes": 64 * 1024, "link_bytes_per_tick": 64}

DRIVER = r"""
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gp_frame.h"
#include "gp_plan.h"
#include "gp_runtime.h"

/* argv: ticks, seconds per tick, [plan file]. Runs the mission to its end (or `ticks`)
 * on synthetic readings: a 5-25 m yo and a noisy thermocline at 12 m. */
static gp_runtime runtime;
static gp_plan plan;
static char plan_text[65536];
static gp_frame_reader reader;

/* One tick's CPU work without its system calls. */
__attribute__((noinline)) int bench_tick(const gp_run_options *options, const uint8_t *wire,
                                         size_t len, uint8_t *answer, size_t *answer_len)
{
    gp_frame frame;
    size_t used;
    uint32_t tick;
    if (gp_frame_reader_feed(&reader, wire, len, &used, &frame) != GP_FRAME_OK
        || gp_sensors_unpack(&frame, &tick, runtime.sensors) != GP_FRAME_OK) {
        return -1;
    }
    gp_command command;
    gp_tick_report report;
    gp_runtime_tick(&runtime, &gp_mission_table, options, tick, &command, &report);
    uint8_t payload[GP_MAX_PAYLOAD];
    size_t n = gp_command_pack(&command, payload);
    *answer_len = gp_frame_build(GP_MSG_COMMAND, frame.seq, frame.seq, payload, n, answer);
    return (command.flags & GP_FLAG_DONE) != 0;
}

int main(int argc, char **argv)
{
    if (argc < 3) {
        return 2;
    }
    long ticks = strtol(argv[1], NULL, 10);
    double step_s = strtod(argv[2], NULL);
    gp_run_options options = {NULL, 0};
    if (argc > 3) {
        FILE *f = fopen(argv[3], "rb");
        char error[GP_PLAN_ERROR_LEN];
        size_t n = f ? fread(plan_text, 1, sizeof plan_text, f) : 0;
        if (!f || gp_plan_read(plan_text, n, &gp_mission_table, &plan, error) != 0) {
            fprintf(stderr, "plan: %s\n", f ? error : "cannot open");
            return 1;
        }
        fclose(f);
        options.plan = &plan;
    }
    gp_runtime_init(&runtime);
    double readings[GP_N_SENSORS] = {0};
    uint32_t mask = gp_mission_table.read_mask;
    long done_at = -1;
    for (long tick = 0; tick < ticks && done_at < 0; tick++) {
        double t = (double)tick * step_s;
        double phase = fmod(t, 400.0) / 200.0;   /* 0..2 */
        readings[0] = t;
        readings[1] = 5.0 + 20.0 * (phase < 1.0 ? phase : 2.0 - phase);
        readings[2] = phase < 1.0 ? -0.45 : 0.45;
        readings[6] = 3910.4;
        readings[7] = -7349.7;
        readings[9] = (readings[1] < 12.0 ? 22.0 : 9.0) + 0.3 * sin(t * 1.7);
        uint8_t payload[GP_MAX_PAYLOAD], wire[GP_MAX_FRAME], answer[GP_MAX_FRAME];
        size_t n = gp_sensors_pack((uint32_t)tick, mask, readings, payload);
        size_t len = gp_frame_build(GP_MSG_SENSORS, (uint8_t)tick, 0, payload, n, wire);
        size_t answer_len = 0;
        int result = bench_tick(&options, wire, len, answer, &answer_len);
        if (result < 0) {
            fprintf(stderr, "tick %ld: frame refused\n", tick);
            return 1;
        }
        if (result == 1) {
            done_at = tick;
        }
    }
    printf("%ld\n", done_at < 0 ? ticks : done_at + 1);
    return 0;
}
"""


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


def fig2_plan(mission: CheckedMission) -> bytes:
    """A plan by hand (docs/plan-format.md): a CTD duty of 1/4 in s2, two alternating
    yos in s1 so that the schedule has work every tick."""
    body = (f"GPPLAN 2\nmission {mission.name}\nhash {mission.hash}\ncomputer ts7800 300\n"
            "budget_j 6630000\npredicted_j 9876.5\ncomponents hotel\nassumptions 0\nstates 3\n"
            "state s1 300 600 0 1\npredict 1000 2 20\nenergy 3950\n"
            "profile 0 1 0.3 150 0.31\nend\n"
            "state s2 300 600 1 1\npredict 1000 1 12\nenergy 3950\n"
            "sensor temp 60 15\nprofile 0 1 0.4 200 0.3\nend\n"
            "state s3 300 600 0 1\npredict 500 1 5\nenergy 1976.5\n"
            "profile 0 1 0.454 230 0.31\nend\n").encode()
    return body + f"crc32 {zlib.crc32(body):08x}\n".encode()


def build_driver(mission_c: Path, out: Path, compiler: list[str], flags: list[str]) -> Path:
    with runtime_sources() as (include, sources):
        library = [str(s) for s in sources if s.name != "gp_main.c"]
        driver = out.parent / "bench_driver.c"
        driver.write_text(DRIVER)
        subprocess.run([*compiler, *C_FLAGS, *flags, f"-I{include}", *library, str(mission_c),
                        str(driver), "-o", str(out), *LINK_FLAGS], check=True)
    return out


def instructions(driver: Path, function: str, ticks: int, step_s: float,
                 plan: Path | None) -> tuple[int, int]:
    """(instructions inside `function` and its callees, ticks run) under callgrind."""
    out = driver.parent / f"callgrind.{function}.out"
    command = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}",
               f"--toggle-collect={function}", str(driver), str(ticks), repr(step_s)]
    done = subprocess.run([*command, *([str(plan)] if plan else [])], capture_output=True,
                          text=True, check=True)
    ran = int(done.stdout.split()[-1])
    totals = re.search(r"^(?:summary|totals): (\d+)", out.read_text(), re.MULTILINE)
    return int(totals.group(1)), ran


def text_bytes(binary: Path, size_tool: str = "size") -> int:
    lines = subprocess.run([size_tool, str(binary)], capture_output=True, text=True,
                           check=True).stdout.splitlines()
    return int(lines[1].split()[0])


def runtime_object_text(compiler: list[str], flags: list[str], mission_c: Path,
                        work: Path) -> int:
    """Text of the runtime's own objects and the mission (no C library)."""
    total = 0
    with runtime_sources() as (include, sources):
        for source in [*sources, mission_c]:
            obj = work / f"{source.stem}.o"
            subprocess.run([*compiler, *C_FLAGS, *flags, f"-I{include}", "-c", str(source),
                            "-o", str(obj)], check=True)
            total += text_bytes(obj)
    return total


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


def link_run(binary: Path, step_s: float, work: Path) -> dict[str, float]:
    """Fly Fig. 2 over a pty; bytes per tick each way and the runtime's peak RSS [KiB]."""
    master, slave = os.openpty()
    tty.setraw(slave)
    process = subprocess.Popen([str(binary), "--device", os.ttyname(slave),
                                "--state-dir", str(work / "state")])
    port = CountingPort(master)
    link = Link(port)
    link.wait_hello(30)
    hello_in = port.read_bytes
    tick, peak_kib = 0, 0
    while True:
        readings = {0: tick * step_s, 1: 5.0 + tick % 20, 2: 0.4, 6: 3910.4, 7: -7349.7,
                    9: 15.0}
        done = link.step(tick, readings).done
        peak_kib = max(peak_kib, high_water_kib(process.pid))
        if done:
            break
        tick += 1
    ticks = tick + 1
    link.wait_release()
    _, status, _ = os.wait4(process.pid, 0)
    os.close(master)
    os.close(slave)
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"the runtime exited with {os.waitstatus_to_exitcode(status)}")
    return {"ticks": ticks, "sensors_bytes": port.written_bytes / ticks,
            "command_bytes": (port.read_bytes - hello_in) / ticks,
            "peak_rss_kib": peak_kib}


def high_water_kib(pid: int) -> int:
    """VmHWM of a running process [KiB]; 0 once it has gone. (wait4's ru_maxrss would
    count the forking Python interpreter's pages, not the runtime's.)"""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return 0
    found = re.search(r"^VmHWM:\s+(\d+) kB", status, re.MULTILINE)
    return int(found.group(1)) if found else 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ticks-per-s", type=float, default=1.0,
                        help="tick rate of the synthetic runs (default 1 Hz)")
    args = parser.parse_args()
    step_s = 1.0 / args.ticks_per_s
    for tool in ("cc", "valgrind", "size"):
        if shutil.which(tool) is None:
            sys.exit(f"bench_runtime: {tool} is not installed")
    fig2 = checked((ROOT / "examples" / "fig2.mission").read_text(), "fig2.mission")
    bench200 = checked(bench200_source(), "bench200.mission")

    with tempfile.TemporaryDirectory(prefix="bench-runtime-") as tmp:
        work = Path(tmp)
        os.environ.setdefault("GLIDERPLAN_CACHE_DIR", str(work / "cache"))
        plan = work / "fig2.plan"
        plan.write_bytes(fig2_plan(fig2))
        builds = [("host", ["cc"], [])]
        if shutil.which("i686-linux-gnu-gcc"):
            builds.append(("ts5500", ["i686-linux-gnu-gcc"], list(TARGETS["ts5500"].flags)))
        print(f"instructions per tick ({args.ticks_per_s:g} Hz ticks, callgrind, I/O "
              "excluded); step = gp_runtime_tick, tick = decode + step + encode")
        print(f"{'build':8} {'mission':16} {'ticks':>6} {'step':>8} {'tick':>8}")
        per_tick: dict[tuple[str, str], float] = {}
        for build, compiler, flags in builds:
            for label, mission, mission_plan in (("fig2", fig2, None),
                                                 ("fig2+plan", fig2, plan),
                                                 ("bench200", bench200, None)):
                out = work / build / mission.name
                out.mkdir(parents=True, exist_ok=True)
                binary = compile_mission(mission, out, "host")  # writes the mission's C
                driver = build_driver(binary.with_suffix(".c"), out / "driver", compiler, flags)
                step, ran = instructions(driver, "gp_runtime_tick", 100_000, step_s,
                                         mission_plan)
                whole, _ = instructions(driver, "bench_tick", 100_000, step_s, mission_plan)
                per_tick[build, label] = whole / ran
                print(f"{build:8} {label:16} {ran:6d} {step / ran:8.0f} {whole / ran:8.0f}")
        print(f"target for fig2: {GOALS['instructions_fig2']} instructions per tick")
        host_fig2 = per_tick["host", "fig2"]
        print(f"bench200 / fig2 (host, tick): {per_tick['host', 'bench200'] / host_fig2:.1f}x")
        i486 = per_tick.get(("ts5500", "fig2"), host_fig2)
        share = i486 * TS5500_CPI / TS5500_HZ * args.ticks_per_s
        print(f"TS-5500 CPU share at {args.ticks_per_s:g} Hz, fig2 "
              f"({'i486' if ('ts5500', 'fig2') in per_tick else 'host'} instructions, "
              f"CPI {TS5500_CPI:g}): {100 * share:.4f} %")

        print(f"\ntext size (size(1)), Fig. 2; target {GOALS['text_bytes']} B")
        host = compile_mission(fig2, work / "fig2-host", "host")
        print(f"  host binary (dynamic libc): {text_bytes(host)} B")
        print(f"  runtime + mission objects, host: "
              f"{runtime_object_text(['cc'], [], host.with_suffix('.c'), work)} B")
        for target in ("ts7800", "ts5500"):
            compiler = TARGETS[target].compiler
            if shutil.which(compiler) is None:
                print(f"  {target}: {compiler} not installed")
                continue
            static = compile_mission(fig2, work / f"fig2-{target}", target)
            flags = [f for f in TARGETS[target].flags if f != "-static"]
            objects = runtime_object_text([compiler], flags, host.with_suffix(".c"), work)
            print(f"  {target}: runtime + mission objects {objects} B; static binary with "
                  f"libc {text_bytes(static)} B")

        print("\nFig. 2 over a pty (protocol.Link), host binary")
        run = link_run(host, step_s * 10, work)  # 10 s ticks: the run takes ~1 s
        both = run["sensors_bytes"] + run["command_bytes"]
        print(f"  ticks {run['ticks']}, bytes per tick: SENSORS {run['sensors_bytes']:.1f}, "
              f"COMMAND {run['command_bytes']:.1f}, both {both:.1f} "
              f"(target {GOALS['link_bytes_per_tick']})")
        print(f"  peak RSS {run['peak_rss_kib']} KiB")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
