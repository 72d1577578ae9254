"""Benchmark: `gliderplan check` of large generated missions, whole process, against
lark's bare parse of the same text.

    .venv/bin/python bench/bench_check_scale.py [--states 5000 50000] [--runs 5]
                                                [--shape survey|fig2]

The mission is a chain of states, far more than the runtime holds: `check` runs every
pass in full and refuses it with that one error (exit 1). `survey` states (the
default) have a route, two alternative profiles, four sensors (two duty auto), a
variable assignment and two events (a call to a shared surfacing state, a goto to the
next state); `fig2` states are shaped like the paper's s1 (route, one profile, three
sensors, two events). The last state exits.

For each size: the median wall and CPU time of `gliderplan check FILE` as a user runs
it (a fresh process each run), and beside it where the CPU time goes, measured in this
process with Python's cycle collector paused as `check` pauses it: the parse into the
syntax tree and the checker (with the flow analysis); the rest of the whole-process
time is start-up, reading the file and exit. Baseline in the same run: lark's bare
parse of the smallest mission (its own parser on the same grammar, building lark's
tree and nothing else), in this process.

Targets: 5,000 states in at most 2 s wall time, whole process; CPU time per state at
the largest size at most 1.2x that at the smallest (linear growth; CPU rather than wall
time because other work on the machine's two cores lengthens the wall time of a long
run more than that of a short one).
"""

from __future__ import annotations

import argparse
import gc
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from whole_process import gliderplan, load_average, median_of

from gliderplan.contract import MAX_STATES, ExitCode
from gliderplan.language.checker import check
from gliderplan.language.parser import _lark, parse

TARGET_5000_S = 2.0
TARGET_LINEARITY = 1.2


def generate_fig2(states: int) -> str:
    parts = ["mission scale", ""]
    for i in range(states):
        nxt = f"goto s{i + 1}" if i + 1 < states else "exit"
        parts.append(
            f"state s{i}\n"
            "begin\n"
            f"  flightroute nav(3910.5, -7349.{i % 10}058)\n"
            f"  flightprofile yo(5.0, {10 + i % 30}, .454, .454)\n"
            "  sensors missiontime, depth, pitch\n"
            "  events\n"
            f"    case missiontime >= {(i + 1) * 500} {nxt}\n"
            f"    case depth > 200 && missiontime < 100 {nxt}\n"
            "end\n")
    return "\n".join(parts)


def generate(states: int) -> str:
    lines = ["mission scale", "battery 60 Ah at 14.4 V reserve 15 %", "horizon 30 d",
             "sensor temp weight 3 duty >= 0.25", "var band = 20", ""]
    for i in range(states):
        nxt = f"s{i + 1}" if i + 1 < states else "s0"
        final = "    case missiontime >= 2500000 exit\n" if i == states - 1 else ""
        lines.append(
            f"state s{i}\n"
            "begin\n"
            f"  flightroute nav({3900 + i % 50}.5, -7349.{i % 10}058)\n"
            f"  flightprofile yo(5, {20 + i % 30}, .454, .454) | yo(5, band, .454, .454)\n"
            "  sensors missiontime, depth, temp duty auto, oxygen duty auto\n"
            "  events\n"
            f"{final}"
            f"    case depth > 15 && temp < 10 set band = max(depth - 5, 10) call surfacing\n"
            f"    case missiontime >= {(i + 1) * 500} goto {nxt}\n"
            "end\n")
    lines.append("state surfacing\nbegin\n  flightprofile surface\n"
                 "  sensors missiontime, depth\n  events\n"
                 "    case depth < 1 return\nend\n")
    return "\n".join(lines)


def median_cpu_s(function: Callable[[], object], runs: int) -> float:
    """Median CPU time of `function()` in this process, with the cycle collector paused
    as check runs."""
    times = []
    for _ in range(runs):
        gc.disable()
        try:
            start = time.process_time()
            function()
            times.append(time.process_time() - start)
        finally:
            gc.enable()
        gc.collect()
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, nargs="+", default=[5000, 50000])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--shape", choices=("survey", "fig2"), default="survey")
    args = parser.parse_args()
    make = generate if args.shape == "survey" else generate_fig2
    sizes = sorted(args.states)
    print(f"gliderplan check, {args.shape} states, whole process: median of {args.runs} "
          f"runs ({load_average()} at the start)")
    print(f"{'states':>7} {'lines':>8} {'MB':>6} {'wall':>8} {'cpu':>8} | "
          f"in process, cpu: {'parse':>6} {'checker':>8}")
    cpu_per_state = {}
    with tempfile.TemporaryDirectory() as tmp:
        for states in sizes:
            text = make(states)
            path = Path(tmp) / f"scale{states}.mission"
            path.write_text(text)
            whole = median_of({"check": gliderplan("check", str(path))}, args.runs,
                              exit_code=ExitCode.BAD_INPUT)["check"]
            syntax = parse(text)
            mission, diagnostics = check(syntax, None)
            errors = [d.message for d in diagnostics if d.is_error]
            assert errors == [f"the mission has {states + (args.shape == 'survey')} states, "
                              f"more than the {MAX_STATES} the runtime holds"], errors[:3]
            parse_s = median_cpu_s(lambda t=text: parse(t), args.runs)
            check_s = median_cpu_s(lambda s=syntax: check(s, None), args.runs)
            del syntax, mission
            cpu_per_state[states] = whole.cpu_s / states
            print(f"{states:>7,} {text.count(chr(10)) + 1:>8,} {len(text) / 1e6:>6.2f} "
                  f"{whole.wall_s:>7.2f}s {whole.cpu_s:>7.2f}s | "
                  f"{'':>17}{parse_s:>5.2f}s {check_s:>7.2f}s")
            if states == 5000:
                verdict = "met" if whole.wall_s <= TARGET_5000_S else "MISSED"
                print(f"        5,000 states: {whole.wall_s:.2f} s whole process "
                      f"(target <= {TARGET_5000_S:g} s: {verdict})")
        smallest = make(sizes[0])
        lark = _lark()
        bare_s = median_cpu_s(lambda: lark.parse(smallest, start="start"), min(args.runs, 3))
    print(f"baseline: lark's bare parse of the {sizes[0]:,}-state text, in process: "
          f"{bare_s:.2f} s cpu; gliderplan check, whole process, takes "
          f"{cpu_per_state[sizes[0]] * sizes[0] / bare_s:.2f}x that")
    if len(sizes) > 1:
        growth = cpu_per_state[sizes[-1]] / cpu_per_state[sizes[0]]
        verdict = "met" if growth <= TARGET_LINEARITY else "MISSED"
        print(f"linear growth: cpu time per state at {sizes[-1]:,} states is {growth:.2f}x "
              f"that at {sizes[0]:,} (target <= {TARGET_LINEARITY:g}x: {verdict})")


if __name__ == "__main__":
    main()
