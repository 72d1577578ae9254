"""Benchmark: whole-process time of `gliderplan check` against starting Python with lark.

    .venv/bin/python bench/bench_check_startup.py [--runs 21] [MISSION]

Runs `gliderplan check MISSION` (default examples/fig2.mission) and
`python -c "import lark"` in turn, N times each, and prints the medians and their ratio.
Target: ratio <= 2, i.e. checking a mission costs at most as much again as the
interpreter and the parser library take to start.

Beside it, where a check's time goes, in fresh processes of the same interpreter
(medians of the same number of runs): importing the command line and the front end
(lark included), loading the grammar from lark's cache, setting up the parse driver,
and checking the mission.

Both commands run with bytecode caching on, as on a user's machine: without it every
gliderplan module is compiled from source on every run, while lark, installed by pip,
is precompiled, which would compare unlike with unlike.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
from pathlib import Path

from whole_process import ENV, gliderplan, load_average, median_of

REPO = Path(__file__).resolve().parent.parent

# Each stage of a check in a fresh process, timed from the interpreter's start-up on.
_STAGES = """
import json, sys, time
start = time.perf_counter()
import gliderplan.cli.check, gliderplan.cli.main, gliderplan.language.parser
imported = time.perf_counter()
from gliderplan.language import check_source
from gliderplan.language.parser import _lark, _parser
_lark()
grammar = time.perf_counter()
_parser()
driver = time.perf_counter()
text = open(sys.argv[1]).read()
assert check_source(text, sys.argv[1]).ok
checked = time.perf_counter()
print(json.dumps({"import": imported - start, "grammar": grammar - imported,
                  "driver": driver - grammar, "check": checked - driver}))
"""


def stages_s(mission: str, runs: int) -> dict[str, float]:
    found: dict[str, list[float]] = {}
    for _ in range(runs):
        out = subprocess.run([sys.executable, "-c", _STAGES, mission], check=True, env=ENV,
                             capture_output=True, text=True).stdout
        for stage, seconds in json.loads(out).items():
            found.setdefault(stage, []).append(seconds)
    return {stage: statistics.median(times) for stage, times in found.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mission", nargs="?", default=str(REPO / "examples" / "fig2.mission"))
    parser.add_argument("--runs", type=int, default=21)
    args = parser.parse_args()
    print(load_average())
    medians = median_of({"check": gliderplan("check", args.mission),
                         "lark": [sys.executable, "-c", "import lark"]}, args.runs)
    check, lark = medians["check"], medians["lark"]
    print(f"gliderplan check {Path(args.mission).name}: {check.wall_s * 1e3:.1f} ms wall, "
          f"{check.cpu_s * 1e3:.1f} ms cpu (median of {args.runs})")
    print(f"python -c 'import lark':       {lark.wall_s * 1e3:.1f} ms wall, "
          f"{lark.cpu_s * 1e3:.1f} ms cpu")
    print(f"ratio: {check.wall_s / lark.wall_s:.2f}x wall, {check.cpu_s / lark.cpu_s:.2f}x cpu "
          "(target <= 2x)")
    stages = stages_s(args.mission, args.runs)
    print("in a fresh process: " + ", ".join(f"{name} {seconds * 1e3:.1f} ms"
                                             for name, seconds in stages.items()))


if __name__ == "__main__":
    main()
