"""Benchmark: fleet planning and flying (docs/fleet.md).

    .venv/bin/python bench/bench_fleet.py [--runs 3] [--scenarios 200] [--skip-montecarlo]
                                          [--skip-plan]

1. Whole process (bench/whole_process.py: medians after a warm-up, wall and CPU):
   `gliderplan fleet plan BIG --json` of a generated fleet of 10 gliders over 200 lines
   (a 100 km strip of 2 km lines 0.5 km apart, 14 days). Target: under 10 s. Beside it,
   the same command on the example (examples/shelf.fleet, 5 gliders, 12 lines), and the
   baseline every fleet command pays: `gliderplan fleet check BIG` (start-up, reading
   the file, cutting the survey into lines); ratios against it.
2. The assignment against its baselines, measured in the same run:
   - on the example: the coordinated plan's mapping error against the equal split's;
   - on small cases (3 gliders, 8 lines): the MILP against brute force (every cut and
     every order of the gliders), their objectives and times;
   - on BIG: the MILP (HiGHS) against the heuristic and its Lagrangian bound.
3. `fleet montecarlo`: a generated fleet of 10 gliders, 7 days, --scenarios scenarios
   flown in this process (the baseline), and on Dask (the commands' default) by a
   LocalCluster of 1 and of 2 workers; the parallel efficiency rate(K) / (K rate(1)) of
   Dask's workers; the tables must be identical. By default the issue's 200 scenarios;
   fewer are extrapolated to 200 from the rates measured (the scenarios are independent
   flights).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from whole_process import gliderplan, load_average, median_of

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "tests"))
from fleet_cases import block_problem, generated_fleet  # noqa: E402

from gliderplan.language.fleet import check_fleet_file, check_fleet_source  # noqa: E402
from gliderplan.planner import fleet_assign as assign  # noqa: E402
from gliderplan.planner.fleet import design_round, plan_fleet, prepare  # noqa: E402

EXAMPLE = REPO / "examples" / "shelf.fleet"
TARGET_S = 10.0
BIG = dict(gliders=10, lines=200, line_km=2.0, spacing_km=0.5, days=14)
FLOWN = dict(gliders=10, lines=40, line_km=6.0, spacing_km=2.0, days=7)
ISSUE_SCENARIOS = 200  # the issue's Monte Carlo: 10 gliders x 200 scenarios x 7 days


def whole_process(work: Path, runs: int) -> None:
    big = work / "big.fleet"
    big.write_text(generated_fleet(11, **BIG))
    times = median_of({"big": gliderplan("fleet", "plan", str(big), "--json"),
                       "example": gliderplan("fleet", "plan", str(EXAMPLE), "--json"),
                       "check": gliderplan("fleet", "check", str(big))}, runs)
    print(f"1. whole process, median of {runs} ({load_average()}):")
    base = times["check"]
    for name, label in (("big", "plan 10 gliders x 200 lines"), ("example", "plan the example"),
                        ("check", "check 10 x 200 (baseline)")):
        t = times[name]
        verdict = "" if name != "big" else (
            f"  target {TARGET_S:g} s: {'met' if t.wall_s <= TARGET_S else 'MISSED'} "
            f"(wall), {'met' if t.cpu_s <= TARGET_S else 'MISSED'} (CPU)")
        print(f"   fleet {label:<28} wall {t.wall_s:6.2f} s  CPU {t.cpu_s:6.2f} s  "
              f"x{t.wall_s / base.wall_s:5.1f} wall, x{t.cpu_s / base.cpu_s:5.1f} CPU of "
              f"the check{verdict}")


def assignment(work: Path) -> None:
    print("2. the assignment against its baselines")
    plan = plan_fleet(check_fleet_file(EXAMPLE).checked())
    print(f"   example: mapping error {plan.evaluation.mapping_error:.4f} against the equal "
          f"split's {plan.baseline_evaluation.mapping_error:.4f}: ratio "
          f"{plan.evaluation.mapping_error / plan.baseline_evaluation.mapping_error:.3f} "
          f"({100 * plan.improvement:.1f} % lower); finishes in "
          f"{100 * plan.validation.share:.1f} % of the model's scenarios, the equal split "
          f"in {100 * plan.baseline_validation.share:.1f} %")
    same, milp_s, brute_s = 0, 0.0, 0.0
    cases = range(10)
    for seed in cases:
        inputs = block_problem(seed, gliders=3, parts=8)
        arcs = assign.build_arcs(inputs)
        start = time.perf_counter()
        exact = assign.brute_force(arcs, inputs.parts, inputs.gliders)
        brute_s += time.perf_counter() - start
        start = time.perf_counter()
        found = assign.solve_milp(arcs, inputs.parts, inputs.gliders)
        milp_s += time.perf_counter() - start
        same += abs(found.objective - exact.objective) <= 1e-7 * abs(exact.objective)
    print(f"   {len(cases)} small cases (3 gliders, 8 lines): the MILP found the brute-force "
          f"optimum in {same} of {len(cases)}; {1000 * milp_s / len(cases):.0f} ms against "
          f"{1000 * brute_s / len(cases):.0f} ms each")
    big = check_fleet_source(generated_fleet(11, **BIG), "big.fleet").checked()
    _, inputs, arcs = design_round(prepare(big), (1.0 - big.confidence) / 2.0)
    start = time.perf_counter()
    heuristic = assign.solve_heuristic(arcs, inputs.parts, inputs.gliders, None)
    heuristic_s = time.perf_counter() - start
    start = time.perf_counter()
    exact = assign.solve_milp(arcs, inputs.parts, inputs.gliders, time_limit_s=120.0)
    milp_s = time.perf_counter() - start
    print(f"   BIG ({len(arcs):,} arcs): heuristic {heuristic_s:.2f} s, objective "
          f"{heuristic.objective:.5f}, Lagrangian bound {heuristic.bound:.5f} (gap "
          f"{100 * heuristic.gap:.2f} %); MILP {milp_s:.2f} s, {exact.status}, objective "
          f"{exact.objective:.5f}: the heuristic is "
          f"{100 * (heuristic.objective / exact.objective - 1):.3f} % above the optimum")


def montecarlo(work: Path, scenarios: int) -> None:
    import resource

    import pandas as pd

    from gliderplan.planner.fleet_report import load_plan_dir, write_plan_dir
    from gliderplan.sim.fleet import montecarlo_fleet

    fleet = check_fleet_source(generated_fleet(21, **FLOWN), "flown.fleet").checked()
    write_plan_dir(plan_fleet(fleet), work / "plan")
    stored = load_plan_dir(work / "plan", fleet)
    flights = scenarios * len(fleet.gliders)
    print(f"3. fleet montecarlo: {len(fleet.gliders)} gliders x {scenarios} scenarios x "
          f"{fleet.period_s / 86400:g} days ({load_average()})")
    rates, tables = {}, {}
    for label, workers, scheduler in (("this process", 1, None), ("Dask, 1 worker", 1, "local"),
                                      ("Dask, 2 workers", 2, "local")):
        out = work / label.replace(" ", "_").replace(",", "")
        before = [resource.getrusage(who) for who in (resource.RUSAGE_SELF,
                                                      resource.RUSAGE_CHILDREN)]
        start = time.perf_counter()
        summary = montecarlo_fleet(fleet, stored, out, scenarios=scenarios, workers=workers,
                                   scheduler=scheduler)
        spent = time.perf_counter() - start
        cpu = sum(after.ru_utime + after.ru_stime - (was.ru_utime + was.ru_stime)
                  for after, was in zip([resource.getrusage(who) for who in (
                      resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN)], before, strict=True))
        rates[label] = flights / spent
        tables[label] = pd.read_parquet(out / "scenarios.parquet")
        against = rates["Dask, 1 worker"] if workers > 1 else rates["this process"]
        efficiency = rates[label] / (workers * against)
        extrapolated = "" if scenarios >= ISSUE_SCENARIOS else (
            f"  {ISSUE_SCENARIOS} scenarios: "
            f"{ISSUE_SCENARIOS * len(fleet.gliders) / rates[label] / 60:5.1f} min (extrapolated)")
        print(f"   {label:<16} {spent:7.1f} s wall  {cpu:7.1f} s CPU  {rates[label]:5.2f} "
              f"flights/s  efficiency {efficiency:.2f}{extrapolated}  "
              f"finished {summary['finished']} of {summary['scenarios']}  ({load_average()})")
    base = tables["this process"].sort_values(["scenario", "glider"]).reset_index(drop=True)
    for label, table in tables.items():
        other = table.sort_values(["scenario", "glider"]).reset_index(drop=True)
        pd.testing.assert_frame_equal(base, other, obj=label)
    print("   the three tables are identical; efficiency of Dask at 1 worker is against this "
          "process, at 2 against Dask at 1")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--scenarios", type=int, default=ISSUE_SCENARIOS)
    parser.add_argument("--skip-montecarlo", action="store_true")
    parser.add_argument("--skip-plan", action="store_true", help="only the Monte Carlo (3.)")
    args = parser.parse_args()
    np.seterr(all="ignore")
    with tempfile.TemporaryDirectory() as scratch:
        work = Path(scratch)
        if not args.skip_plan:
            whole_process(work, args.runs)
            assignment(work)
        if not args.skip_montecarlo:
            montecarlo(work, args.scenarios)


if __name__ == "__main__":
    main()
