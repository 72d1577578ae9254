"""Benchmark: `gliderplan plan` and `gliderplan plan --sweep 50` as a user runs them,
against starting Python with cvxpy, and where their time goes.

    .venv/bin/python bench/bench_plan_startup.py [--runs 7] [MISSION]

Whole process (medians of N runs, taken in turn): `gliderplan plan MISSION -o FILE`,
`gliderplan plan MISSION --sweep 50 -o DIR` and, as the baseline in the same run,
`python -c "import cvxpy"`: the planner solves with cvxpy, so a plan cannot start
faster than that.

Beside it, the CPU time of each stage in a fresh process (medians of the same number of
runs): importing the planner (cvxpy, numpy, scipy), checking the mission, building the
model, solving the plan; for the sweep, importing pandas, the 50-point Pareto sweep,
the computer and battery sweeps, importing matplotlib (Agg) and drawing pareto.png.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from whole_process import ENV, gliderplan, load_average, median_of

REPO = Path(__file__).resolve().parent.parent
SWEEP_POINTS = 50

# The stages of a plan and of a sweep in a fresh process, CPU time from the interpreter's
# start-up on; the model built for the plan is the one the sweep uses, as in `plan --sweep`.
_STAGES = """
import json, sys, time
clock = time.process_time
marks = [("start", clock())]
def mark(name):
    marks.append((name, clock()))
import gliderplan.planner.plan
mark("import planner")
from gliderplan.language import check_file
mission = check_file(sys.argv[1]).mission
mark("check")
from gliderplan.planner.plan import prepare, solve_plan
_, model = prepare(mission)
mark("build")
solve_plan(model)
mark("solve")
import gliderplan.planner.sweep
mark("import pandas")
from gliderplan.planner.sweep import batteries, computers, pareto, plot_pareto
frame = pareto(model, int(sys.argv[2]))
mark("pareto")
computers(mission)
batteries(mission)
mark("computers, batteries")
import matplotlib
matplotlib.use("Agg")
import matplotlib.figure
mark("import matplotlib")
plot_pareto(frame, "bench")
mark("plot")
print(json.dumps({name: t - marks[i][1] for i, (name, t) in enumerate(marks[1:])}))
"""


def stages_s(mission: str, runs: int) -> dict[str, float]:
    found: dict[str, list[float]] = {}
    for _ in range(runs):
        out = subprocess.run([sys.executable, "-c", _STAGES, mission, str(SWEEP_POINTS)],
                             check=True, env=ENV, capture_output=True, text=True).stdout
        for stage, seconds in json.loads(out).items():
            found.setdefault(stage, []).append(seconds)
    return {stage: statistics.median(times) for stage, times in found.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("mission", nargs="?",
                        default=str(REPO / "examples" / "thermocline_survey.mission"))
    parser.add_argument("--runs", type=int, default=7)
    args = parser.parse_args()
    print(f"{Path(args.mission).name}, medians of {args.runs} runs ({load_average()})")
    with tempfile.TemporaryDirectory() as tmp:
        medians = median_of({
            "plan": gliderplan("plan", args.mission, "-o", f"{tmp}/mission.plan"),
            "sweep": gliderplan("plan", args.mission, "--sweep", str(SWEEP_POINTS),
                                "-o", f"{tmp}/sweep"),
            "cvxpy": [sys.executable, "-c", "import cvxpy"]}, args.runs)
    base = medians["cvxpy"]
    for name, label in (("plan", "gliderplan plan"),
                        ("sweep", f"gliderplan plan --sweep {SWEEP_POINTS}"),
                        ("cvxpy", "python -c 'import cvxpy'")):
        timing = medians[name]
        print(f"{label:<33} {timing.wall_s:6.2f} s wall {timing.cpu_s:6.2f} s cpu "
              f"({timing.wall_s / base.wall_s:.2f}x, {timing.cpu_s / base.cpu_s:.2f}x "
              "import cvxpy)")
    stages = stages_s(args.mission, args.runs)
    total = sum(stages.values())
    print("cpu time by stage in a fresh process (plan: up to solve; sweep: all):")
    for stage, seconds in stages.items():
        print(f"  {stage:<22} {seconds:6.3f} s {100 * seconds / total:5.1f} %")


if __name__ == "__main__":
    main()
