"""Monte Carlo: a mission (and its plan) flown in many drawn scenarios, and how likely it
is that the energy budget holds.

Scenario i is drawn from its own seed, the child i of the run's `SeedSequence`
(sim/scenarios.py), so a result depends on the run's seed and the scenario's index
only: not on the number of workers, nor on which worker flew it. Scenarios go to the
workers in batches (each long enough, ~100 ms, that sending it costs little) through
any `concurrent.futures`-style executor: a local process pool, or Dask distributed's
`Client.get_executor()`. An interrupted run keeps every scenario that finished.
"""

from __future__ import annotations

import concurrent.futures as cf
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import DEFAULT_HORIZON_S, TICK_S
from gliderplan.language import ir
from gliderplan.language.registry import SENSOR_BY_NAME
from gliderplan.planner.planfile import Plan
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.sim.energy import RunEnergy, account, check_flight
from gliderplan.sim.loop import RunConfig, RunRecord
from gliderplan.sim.scenarios import ScenarioSpec, draw_scenario

BATCH_S = 0.1  # a batch of scenarios takes at least this long [s], so sending it is cheap
BATCHES_PER_WORKER = 4  # at least this many batches per worker, so the ends even out
CONFIDENCE_Z = 1.959963984540054  # 95 % two-sided
QUANTILES = (0.05, 0.5, 0.95)


@dataclass(frozen=True)
class Job:
    """Everything a worker needs to fly scenarios of one run (pickled once per batch)."""

    mission: ir.CheckedMission
    plan: Plan | None  # the schedules flown and their prediction (None: sensors always on)
    vehicle: Vehicle  # the nominal vehicle the scenarios draw around
    spec: ScenarioSpec
    budget_j: float  # the plan's budget (else the mission's usable battery energy) [J]
    seed: int
    duration_s: float  # a run ends here if the mission has not exited [s]
    tick_s: float = TICK_S
    robust_tracker: bool = True


def scenario_seed(job: Job, index: int) -> np.random.SeedSequence:
    """Child `index` of the run's seed: what `SeedSequence(seed).spawn(n)[index]` is."""
    return np.random.SeedSequence(job.seed, spawn_key=(index,))


def fly_scenario(job: Job, index: int, runtime: str | None = None) -> dict:
    """Fly scenario `index`: one row of the results table (`runtime` as sim.flight.fly's:
    by default the compiled runtime's step)."""
    from gliderplan.sim.flight import fly

    scenario = draw_scenario(job.spec, job.vehicle, index, scenario_seed(job, index))
    config = RunConfig(tick_s=job.tick_s, duration_s=job.duration_s, seed=scenario.seed,
                       noise=scenario.noise, current=scenario.current)
    record = fly(job.mission, scenario.ocean, config, scenario.vehicle, job.plan,
                 robust_tracker=job.robust_tracker, runtime=runtime)
    energy = account(record, job.mission, scenario.vehicle, job.plan)
    check = check_flight(energy, job.plan)
    budget = job.budget_j * scenario.usable_fraction
    spent = np.cumsum(sum(energy.per_tick_j.values()))
    over = np.flatnonzero(spent > budget)
    component, excess = _most_overrun(energy, job.plan)
    names = record.state_names
    return {
        "scenario": index,
        "seed": scenario.seed,
        "energy_j": energy.total_j,
        "budget_j": budget,
        "held": bool(energy.total_j <= budget),
        "exhausted_s": float(record.columns["time_s"][over[0]]) if len(over) else math.nan,
        "duration_s": float(record.columns["time_s"][-1]) if len(spent) else 0.0,
        "ended": record.ended,
        "end_state": _end_state(record),
        "quality": flown_quality(job.mission, record),
        "plan_check": check.verdict,
        "overran_component": component,
        "overran_j": excess,
        **{f"time_{name}_s": energy.time_by_state_s.get(name, 0.0) for name in names},
        **{f"visits_{name}": n for name, n in record.visits().items()},
        **entry_arguments(job.mission, record),
        **{f"energy_{k}_j": v for k, v in energy.by_component_j().items()},
        **{f"drawn_{k}": v for k, v in scenario.drawn.items()},
    }


def entry_arguments(mission: ir.CheckedMission, record: RunRecord) -> dict[str, float]:
    """`entered_STATE_VARIABLE`: each variable a state's profiles read, as the state was
    first entered (NaN if it never was): what the planner evaluates the profiles with."""
    entered = record.entry_variables or {}
    return {f"entered_{state.name}_{name}": entered.get(state.name, {}).get(name, math.nan)
            for state in mission.states for name in state.profile_variables}


def _end_state(record: RunRecord) -> str:
    """The state the run ended in (for an exit: the state that exited)."""
    if record.ended == "exit" and record.trace:
        return record.trace[-1].from_state
    state = record.columns["state"]
    names = record.state_names
    return names[int(state[-1])] if len(state) and 0 <= state[-1] < len(names) else ""


def _most_overrun(energy: RunEnergy, plan: Plan | None) -> tuple[str, float]:
    """The component whose energy exceeded the plan's prediction by the most [J] (its
    excess; negative when every component stayed under), or, without a plan, the
    largest consumer and its energy."""
    flown = energy.by_component_j()
    if plan is None:
        name = max(flown, key=flown.get, default="")
        return name, flown.get(name, 0.0)
    predicted = plan.components_j
    excess = {k: flown.get(k, 0.0) - predicted.get(k, 0.0) for k in {*flown, *predicted}}
    name = max(sorted(excess), key=excess.get)
    return name, excess[name]


def flown_quality(mission: ir.CheckedMission, record: RunRecord) -> float:
    """Data quality as flown: over the sensors the mission weighs, the weighted share of
    the time a state logged the sensor that its device was on (0..1; NaN without any)."""
    state = np.minimum(record.columns["state"], len(mission.states))  # the exit's row: none
    power = record.columns["sensor_power"]
    total = weight = 0.0
    for pref in mission.sensor_preferences:
        info = SENSOR_BY_NAME[pref.sensor]
        logs = [any(u.name == pref.sensor for u in s.sensors) for s in mission.states]
        logging = np.array([*logs, False])[state]
        if not logging.any() or pref.weight <= 0.0:
            continue
        on = (power[logging] >> info.index & 1).mean()
        total += pref.weight * float(on)
        weight += pref.weight
    return total / weight if weight else math.nan


def run_batch(job: Job, indices: Iterable[int]) -> list[dict]:
    """Fly a batch of scenarios (what a worker does with one task)."""
    return [fly_scenario(job, i) for i in indices]


# ---- the run ----------------------------------------------------------------------------

@dataclass(frozen=True)
class MonteCarloResult:
    rows: list[dict]  # one per finished scenario, by index
    requested: int
    interrupted: bool
    wall_s: float

    def table(self):
        """The rows as a pandas DataFrame."""
        import pandas as pd

        return pd.DataFrame(self.rows)


def batches(count: int, first_s: float, workers: int) -> list[list[int]]:
    """Scenarios 1..count-1 (0 was flown to time one) in batches of at least BATCH_S
    each at `first_s` [s] per scenario, but at least BATCHES_PER_WORKER per worker."""
    rest = list(range(1, count))
    if not rest:
        return []
    size = max(1, math.ceil(BATCH_S / max(first_s, 1e-6)))
    size = min(size, max(1, math.ceil(len(rest) / (BATCHES_PER_WORKER * max(workers, 1)))))
    return [rest[i:i + size] for i in range(0, len(rest), size)]


def run_montecarlo(job: Job, count: int, executor: cf.Executor | None = None, workers: int = 1,
                   progress: Callable[[int, int], None] | None = None) -> MonteCarloResult:
    """Fly `count` scenarios: in this process without an executor, else batches through
    `executor` (with `workers` workers). Ctrl-C stops it and keeps what finished."""
    start = time.perf_counter()
    rows: dict[int, dict] = {}
    interrupted = False
    futures: set[cf.Future] = set()
    try:
        t0 = time.perf_counter()
        rows[0] = fly_scenario(job, 0)
        if progress:
            progress(1, count)
        plan = batches(count, time.perf_counter() - t0, workers)
        if executor is None:
            for batch in plan:
                rows.update((r["scenario"], r) for r in run_batch(job, batch))
                if progress:
                    progress(len(rows), count)
        else:
            futures = {executor.submit(run_batch, job, batch) for batch in plan}
            for future in cf.as_completed(futures):
                rows.update((r["scenario"], r) for r in future.result())
                if progress:
                    progress(len(rows), count)
    except KeyboardInterrupt:
        interrupted = True
        for future in futures:
            future.cancel()
    ordered = [rows[i] for i in sorted(rows)]
    return MonteCarloResult(ordered, count, interrupted, time.perf_counter() - start)


# ---- what the runs say ------------------------------------------------------------------

def wilson_interval(held: int, n: int, z: float = CONFIDENCE_Z) -> tuple[float, float]:
    """Wilson score interval of a proportion held / n (95 % by default)."""
    if n == 0:
        return 0.0, 1.0
    p = held / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(0.0, centre - half), min(1.0, centre + half)


def summary(result: MonteCarloResult, meta: dict) -> dict:
    """Probability that the budget holds with its 95 % interval, energy and duration
    quantiles, how the runs ended."""
    table = result.table()
    n = len(table)
    held = int(table["held"].sum()) if n else 0
    low, high = wilson_interval(held, n)

    def quantiles(column: str) -> dict[str, float]:
        if not n:
            return {}
        values = np.quantile(table[column].to_numpy(float), QUANTILES)
        return {f"p{round(100 * q):02d}": float(v) for q, v in zip(QUANTILES, values,
                                                                   strict=True)}

    exhausted = table["exhausted_s"].dropna() if n else table
    return {
        **meta,
        "scenarios": n,
        "requested": result.requested,
        "interrupted": result.interrupted,
        "budget_held": held,
        "probability_budget_holds": held / n if n else None,
        "probability_interval_95": [low, high],
        "energy_j": quantiles("energy_j"),
        "duration_s": quantiles("duration_s"),
        "exhausted_before_end": int(len(exhausted)),
        "over_budget_by_tolerance": int((table["plan_check"] == "violation").sum()) if n
        else 0,
        "ended": {str(k): int(v) for k, v in table["ended"].value_counts().items()} if n
        else {},
        "wall_s": result.wall_s,
    }


# ---- the command ------------------------------------------------------------------------

MONTECARLO_FILES = ("scenarios.parquet", "summary.json", "energy.png", "exhaustion.png")


@dataclass(frozen=True)
class MonteCarloRun:
    """A Monte Carlo run of a mission: its scenarios, what they say, the files written."""

    result: MonteCarloResult
    summary: dict  # summary.json: the probability that the budget holds, quantiles, ...
    files: tuple  # of pathlib.Path: MONTECARLO_FILES in the output directory


def montecarlo_mission(mission: ir.CheckedMission, output_dir, *, scenarios: int,
                       plan_path=None, workers: int = 1, scheduler: str | None = None,
                       seed: int = 0, scenario_file=None, duration_s: float | None = None,
                       tracker: str = "robust",
                       progress: Callable[[int, int], None] | None = None) -> MonteCarloRun:
    """Fly `mission` (and the plan in `plan_path`: its budget and prediction; without one
    every sensor a state logs is on and the budget is the mission's usable battery) in
    `scenarios` scenarios drawn from `scenario_file` (default: the shipped one) from
    `seed`, on `workers` processes or the Dask `scheduler` ("local" or "tcp://HOST:PORT"),
    each run ending at `duration_s` [s] (default: the mission's horizon, else 30 days);
    write MONTECARLO_FILES into `output_dir` (the pipeline of `gliderplan montecarlo`).
    Raises KeyboardInterrupt only if no scenario finished: an interrupted run keeps and
    writes those that did (`MonteCarloRun.result.interrupted`)."""
    import json
    from pathlib import Path

    from gliderplan.contract.errors import UsageError
    from gliderplan.contract.files import write_atomically
    from gliderplan.planner.planfile import load_plan
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim import plots
    from gliderplan.sim.backends import check_run_size, scenario_executor
    from gliderplan.sim.flight import refuse_unflyable_yos
    from gliderplan.sim.outputs import parquet_bytes
    from gliderplan.sim.scenarios import read_spec

    check_run_size(scenarios, workers)
    out = Path(output_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory")
    duration = duration_s if duration_s is not None else mission.horizon_s or DEFAULT_HORIZON_S
    spec = read_spec(scenario_file)
    plan = None if plan_path is None else load_plan(plan_path, mission)
    vehicle = load_vehicle(mission.vehicle)
    refuse_unflyable_yos(mission, vehicle, plan)
    budget_j = plan.budget_j if plan is not None else \
        mission.battery.energy_j * (1.0 - mission.battery.reserve_fraction)
    job = Job(mission, plan, vehicle, spec, budget_j, seed, duration,
              robust_tracker=tracker == "robust")
    with scenario_executor(workers, scheduler) as executor:
        result = run_montecarlo(job, scenarios, executor, workers, progress)
    if not result.rows:
        raise KeyboardInterrupt  # nothing finished, nothing to write
    import pyarrow as pa

    table = result.table()
    meta = {"mission": mission.name, "mission_hash": mission.hash,
            "plan": None if plan_path is None else str(plan_path),
            "scenario_file": spec.source, "seed": seed, "run_limit_s": duration,
            "budget_j": budget_j, "workers": workers,
            "scheduler": scheduler or ("local pool" if workers > 1 else "none")}
    stated = summary(result, meta)
    contents = {
        "scenarios.parquet": parquet_bytes(pa.Table.from_pandas(table, preserve_index=False)),
        "summary.json": json.dumps(stated, indent=2) + "\n",
        "energy.png": plots.energy_histogram_png(
            table["energy_j"].to_numpy(float), table["budget_j"].to_numpy(float), budget_j,
            stated["probability_budget_holds"]),
        "exhaustion.png": plots.exhaustion_png(
            table["exhausted_s"].to_numpy(float), table["duration_s"].to_numpy(float)),
    }
    for name in MONTECARLO_FILES:
        write_atomically(out / name, contents[name])
    return MonteCarloRun(result, stated, tuple(out / name for name in MONTECARLO_FILES))
