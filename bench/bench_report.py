"""Whole-process time and size of `gliderplan report` on the thermocline survey.

    .venv/bin/python bench/bench_report.py [--runs 3]

What a user pays: `gliderplan report examples/thermocline_survey.mission -o DIR` from
process start to exit (plan, 20-point Pareto sweep, a 35 h flight on the simulated
glider, three boards compared, ~45 re-plans for the sensitivity, six figures, the
page and its CSV files). Baseline, measured in turn in the same run: `gliderplan plan
--sweep 20` of the same mission (imports, plan, the same sweep, its PNG). Medians of
wall and CPU time (bench/whole_process.py), the ratio and the page's size. Targets:
report under 10 s, page under 2 MB.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from whole_process import gliderplan, load_average, median_of  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MISSION = str(ROOT / "examples" / "thermocline_survey.mission")
GOAL_S, GOAL_BYTES = 10.0, 2_000_000


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as work:
        out = Path(work) / "report"
        times = median_of({
            "report": gliderplan("report", MISSION, "-o", str(out)),
            "plan --sweep 20": gliderplan("plan", MISSION, "--sweep", "20",
                                          "-o", str(Path(work) / "sweep")),
        }, args.runs)
        size = (out / "report.html").stat().st_size
    report, sweep = times["report"], times["plan --sweep 20"]
    print(f"medians of {args.runs} runs after a warm-up, {load_average()} after them")
    for name, t in times.items():
        print(f"  {name:18s} wall {t.wall_s:6.2f} s   cpu {t.cpu_s:6.2f} s")
    print(f"  ratio report / sweep: wall {report.wall_s / sweep.wall_s:.2f}x, "
          f"cpu {report.cpu_s / sweep.cpu_s:.2f}x")
    print(f"  report.html: {size / 1e6:.3f} MB")
    print(f"targets: under {GOAL_S:g} s wall ({'met' if report.wall_s < GOAL_S else 'MISSED'}),"
          f" under {GOAL_BYTES / 1e6:g} MB ({'met' if size < GOAL_BYTES else 'MISSED'})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
