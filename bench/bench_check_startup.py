"""Benchmark: whole-process time of `gliderplan check` against starting Python with lark.

    .venv/bin/python bench/bench_check_startup.py [--runs 21] [MISSION]

Runs `gliderplan check MISSION` (default examples/fig2.mission) and
`python -c "import lark"` alternately, N times each, and prints the medians and their
ratio. Target: ratio <= 2, i.e. checking a mission costs at most as much again as the
interpreter and the parser library take to start.

Both commands run with bytecode caching on, as on a user's machine (the warm-up run
writes the .pyc files even if PYTHONDONTWRITEBYTECODE is set in this shell): without
it every gliderplan module is compiled from source on every run, while lark, installed
by pip, is precompiled, which would compare unlike with unlike.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


_ENV = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}


def wall_s(command: list[str]) -> float:
    start = time.perf_counter()
    subprocess.run(command, check=True, stdout=subprocess.DEVNULL, env=_ENV)
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mission", nargs="?", default=str(REPO / "examples" / "fig2.mission"))
    parser.add_argument("--runs", type=int, default=21)
    args = parser.parse_args()
    script = Path(sys.executable).with_name("gliderplan")
    check = ([str(script)] if script.exists() else [sys.executable, "-m", "gliderplan.cli"])
    check += ["check", args.mission]
    baseline = [sys.executable, "-c", "import lark"]
    wall_s(check), wall_s(baseline)  # warm the file cache and lark's grammar cache
    check_s, baseline_s = [], []
    for _ in range(args.runs):
        check_s.append(wall_s(check))
        baseline_s.append(wall_s(baseline))
    check_median, baseline_median = statistics.median(check_s), statistics.median(baseline_s)
    print(f"gliderplan check {Path(args.mission).name}: {check_median * 1e3:.1f} ms "
          f"(median of {args.runs})")
    print(f"python -c 'import lark':       {baseline_median * 1e3:.1f} ms")
    print(f"ratio: {check_median / baseline_median:.2f}x (target <= 2x)")


if __name__ == "__main__":
    main()
