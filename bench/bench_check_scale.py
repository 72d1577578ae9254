"""Benchmark: parse + check of a generated 5,000-state mission against lark's bare parse.

    .venv/bin/python bench/bench_check_scale.py [--states 5000] [--runs 3] [--shape survey|fig2]

The mission is a chain of states. `survey` states (the default) have a route, two
alternative profiles, four sensors (two duty auto), a variable assignment and two
events (a call to a shared surfacing state, a goto to the next state); `fig2` states
are shaped like the paper's s1 (route, one profile, three sensors, two events). The
last state exits.
Prints the size, the median time of `check_source` (parse, syntax tree, checker and
flow analysis) and of lark's parse of the same text without building our tree, lines
per second, and the ratio. Targets: parse + check <= 2 s; ratio <= 1.5 (the front end
adds less than 50 % to the bare parse).
"""

from __future__ import annotations

import argparse
import gc
import statistics
import time

from gliderplan.language import check_source
from gliderplan.language.parser import _lark


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


def median_s(function, runs: int) -> float:  # noqa: ANN001
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def paused(function):  # noqa: ANN001, ANN201
    """`function()` with Python's cycle collector paused, as check_source runs."""
    gc.disable()
    try:
        return function()
    finally:
        gc.enable()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=5000)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--shape", choices=("survey", "fig2"), default="survey")
    args = parser.parse_args()
    text = (generate if args.shape == "survey" else generate_fig2)(args.states)
    lines = text.count("\n") + 1
    result = check_source(text, "scale.mission")
    assert result.ok, result.render()[:2000]
    lark = _lark()
    full_s = median_s(lambda: check_source(text, "scale.mission"), args.runs)
    # the baseline under the same conditions as check_source: cycle collector paused
    bare_s = median_s(lambda: paused(lambda: lark.parse(text, start="start")), args.runs)
    gc_on_s = median_s(lambda: lark.parse(text, start="start"), args.runs)
    print(f"{args.states} {args.shape} states, {lines} lines, {len(text) / 1e6:.2f} MB")
    print(f"parse + check: {full_s:.2f} s ({lines / full_s:,.0f} lines/s; target <= 2 s)")
    print(f"lark bare parse: {bare_s:.2f} s ({lines / bare_s:,.0f} lines/s); "
          f"{gc_on_s:.2f} s with the cycle collector running")
    print(f"ratio: {full_s / bare_s:.2f}x (target <= 1.5x)")


if __name__ == "__main__":
    main()
