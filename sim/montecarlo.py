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
from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract import SBD_MO_SHORT_BYTES, SBD_MT_SHORT_BYTES
from gliderplan.contract.units import finite_or_none
from gliderplan.language import ir
from gliderplan.language.registry import SENSOR_BY_NAME
from gliderplan.planner.planfile import Plan
from gliderplan.power_models.battery import drawn_budget_j
from gliderplan.sim.energy import RunEnergy, account, check_flight
from gliderplan.sim.loop import RunRecord
from gliderplan.sim.scenarios import ScenarioSpec, draw_scenario
from gliderplan.sim.setup import FlightSetup

BATCH_S = 0.1  # a batch of scenarios takes at least this long [s], so sending it is cheap
BATCHES_PER_WORKER = 4  # at least this many batches per worker, so the ends even out
CONFIDENCE_Z = 1.959963984540054  # 95 % two-sided
QUANTILES = (0.05, 0.5, 0.95)


@dataclass(frozen=True)
class Job:
    """Everything a worker needs to fly scenarios of one run (pickled once per batch)."""

    # the nominal flight the scenarios draw around: mission, plan, vehicle, budget, tick,
    # duration, tracker, start; its seed is the run's
    setup: FlightSetup
    spec: ScenarioSpec
    # replanning (`montecarlo --replan`): the signed plan the vehicle holds, its key, the
    # confidence the shore replans at (None: the plan's own)
    held: bytes | None = None
    key: bytes | None = None
    confidence: float | None = None

    @property
    def replan(self) -> bool:
        return self.held is not None


def scenario_seed(job: Job, index: int) -> np.random.SeedSequence:
    """Child `index` of the run's seed: what `SeedSequence(seed).spawn(n)[index]` is."""
    return np.random.SeedSequence(job.setup.config.seed, spawn_key=(index,))


def fly_scenario(job: Job, index: int, runtime: str | None = None) -> dict:
    """Fly scenario `index`: one row of the results table (`runtime` as sim.flight.fly's:
    by default the compiled runtime's step). With replanning the row is the flight with
    the shore in the loop, and the static plan's flight of the same scenario beside it
    (`held_static`, `quality_static`, ...)."""
    from gliderplan.sim.flight import fly

    setup = job.setup
    scenario = draw_scenario(job.spec, setup.vehicle, index, scenario_seed(job, index))
    config = replace(setup.config, seed=scenario.seed, noise=scenario.noise,
                     current=scenario.current)
    record = fly(setup.mission, scenario.ocean, config, scenario.vehicle, setup.plan,
                 robust_tracker=setup.robust_tracker, runtime=runtime)
    row = _row(job, scenario, record)
    if not job.replan:
        return row
    from gliderplan.sim.replanning import ShoreLoop

    shore = ShoreLoop(setup.mission, job.held, job.key, tick_s=config.tick_s,
                      usable_truth=scenario.usable_fraction, seed=scenario.seed,
                      confidence=job.confidence, spec=job.spec.model())
    replanned = fly(setup.mission, scenario.ocean, config, scenario.vehicle, setup.plan,
                    robust_tracker=setup.robust_tracker, runtime=runtime, shore=shore)
    link = shore.log.summary(max(float(replanned.columns["time_s"][-1]), config.tick_s))
    return {**_row(job, scenario, replanned),
            **{f"{k}_static": row[k] for k in STATIC_COLUMNS},
            **{k: link[k] for k in LINK_COLUMNS}}


# with replanning, the static plan's flight beside the replanned one: these columns
STATIC_COLUMNS = ("energy_j", "held", "exhausted_s", "duration_s", "ended", "quality",
                  "plan_check")
LINK_COLUMNS = ("surfacings", "updates_applied", "updates_refused", "replans_least_energy",
                "replans_not_sent", "replans_failed", "up_bytes", "down_bytes", "up_messages",
                "down_messages", "update_bytes_max")


def _row(job: Job, scenario, record: RunRecord) -> dict:  # noqa: ANN001
    """The results table's row of one flight of a scenario."""
    mission, plan = job.setup.mission, job.setup.plan
    energy = account(record, mission, scenario.vehicle, plan)
    check = check_flight(energy, plan)
    budget = drawn_budget_j(job.setup.budget_j, scenario.usable_fraction)
    spent = np.cumsum(sum(energy.per_tick_j.values()))
    over = np.flatnonzero(spent > budget)
    component, excess = _most_overrun(energy, plan)
    names = record.state_names
    return {
        "scenario": scenario.index,
        "seed": scenario.seed,
        "energy_j": energy.total_j,
        "budget_j": budget,
        "held": bool(energy.total_j <= budget),
        "exhausted_s": float(record.columns["time_s"][over[0]]) if len(over) else math.nan,
        "duration_s": float(record.columns["time_s"][-1]) if len(spent) else 0.0,
        "ended": record.ended,
        "end_state": _end_state(record),
        "quality": flown_quality(mission, record),
        "plan_check": check.verdict,
        "overran_component": component,
        "overran_j": excess,
        **{f"time_{name}_s": energy.time_by_state_s.get(name, 0.0) for name in names},
        **{f"visits_{name}": n for name, n in record.visits().items()},
        **entry_arguments(mission, record),
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
    `executor` (with `workers` workers). Ctrl-C or SIGTERM stops it at once (workers and
    all: sim.backends.halt) and keeps the scenarios that finished, never one cut short;
    the result says it was interrupted."""
    from gliderplan.contract import interrupts
    from gliderplan.sim.backends import gather, halt

    start = time.perf_counter()
    rows: dict[int, dict] = {}

    def collect(task: tuple, flown: list[dict]) -> None:
        rows.update((row["scenario"], row) for row in flown)
        if progress:
            progress(len(rows), count)

    try:
        t0 = time.perf_counter()
        rows[0] = fly_scenario(job, 0)
        if progress:
            progress(1, count)
        plan = batches(count, time.perf_counter() - t0, workers)
        if executor is None:  # scenario by scenario: a stop keeps each one that finished
            plan = [[index] for batch in plan for index in batch]
        interrupted = gather(executor, run_batch, [(job, batch) for batch in plan], collect)
    except KeyboardInterrupt:
        interrupted = True
        halt(executor)
    # a stop that something on the way swallowed still stops the run; a scenario whose
    # flight says it was interrupted is no scenario flown
    cut = [i for i, row in rows.items() if row["ended"] == "interrupted"]
    interrupted = interrupted or interrupts.stopped() or bool(cut)
    for i in cut:
        del rows[i]
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
    quantiles, how the runs ended. An interrupted run gives no probability (null): the
    scenarios that finished before the stop are not the sample asked for (the moment of
    a stop is chosen watching the run, and in a pool the short scenarios finish first);
    `complete` false, `scenarios` of `requested` say how far it got."""
    table = result.table()
    n = len(table)
    held = int(table["held"].sum()) if n else 0
    low, high = wilson_interval(held, n)
    complete = not result.interrupted

    def quantiles(column: str) -> dict[str, float]:
        if not n:
            return {}
        values = np.quantile(table[column].to_numpy(float), QUANTILES)
        return {f"p{round(100 * q):02d}": float(v) for q, v in zip(QUANTILES, values,
                                                                   strict=True)}

    exhausted = table["exhausted_s"].dropna() if n else table
    replanned = replanning(table, complete) if n and "held_static" in table else {}
    return {
        **meta,
        "complete": complete,
        "scenarios": n,
        "requested": result.requested,
        "interrupted": result.interrupted,
        "budget_held": held,
        "probability_budget_holds": held / n if n and complete else None,
        "probability_interval_95": [low, high] if complete else None,
        "energy_j": quantiles("energy_j"),
        "duration_s": quantiles("duration_s"),
        # scenarios whose energy passed the plan's budget times the usable share of the
        # battery drawn for them, at some time of the run (the run itself goes on: the
        # energy guard reads the mission's battery, not the drawn share)
        "exceeded_drawn_usable_charge": int(len(exhausted)),
        "over_budget_by_tolerance": int((table["plan_check"] == "violation").sum()) if n
        else 0,
        "ended": {str(k): int(v) for k, v in table["ended"].value_counts().items()} if n
        else {},
        **replanned,
        "wall_s": result.wall_s,
    }


def replanning(table, complete: bool = True) -> dict:  # noqa: ANN001
    """With replanning: the hold rate and the flown quality with and without it, side by
    side (95 % intervals), and what the link carried: bytes each way per day and per
    mission (means over the scenarios, and the most), the largest update. Not
    `complete` (interrupted), the hold rates and their intervals are None: the scenarios
    that finished are not the sample asked for (as `summary`'s probability)."""
    n = len(table)
    held, held_static = int(table["held"].sum()), int(table["held_static"].sum())
    days = np.maximum(table["duration_s"].to_numpy(float), 1.0) / 86400.0
    up, down = table["up_bytes"].to_numpy(float), table["down_bytes"].to_numpy(float)

    def rate(count: int) -> float | None:
        return count / n if complete else None

    def interval(count: int) -> list[float] | None:
        return list(wilson_interval(count, n)) if complete else None

    return {
        "hold_rate": rate(held), "hold_rate_interval_95": interval(held),
        "hold_rate_static": rate(held_static),
        "hold_rate_static_interval_95": interval(held_static),
        # None where the mission weighs no sensor (no quality to speak of)
        "quality": finite_or_none(float(table["quality"].mean())),
        "quality_static": finite_or_none(float(table["quality_static"].mean())),
        "update_bytes_max": int(table["update_bytes_max"].max()),
        "link": {
            "surfacings_per_mission": float(table["surfacings"].mean()),
            "up_bytes_per_day": float(np.mean(up / days)),
            "down_bytes_per_day": float(np.mean(down / days)),
            "up_bytes_per_mission": float(up.mean()), "down_bytes_per_mission": float(down.mean()),
            "down_bytes_per_mission_max": int(down.max()),
            "up_messages_per_mission": float(table["up_messages"].mean()),
            "down_messages_per_mission": float(table["down_messages"].mean()),
            "updates_refused": int(table["updates_refused"].sum()),
            "replans_least_energy": int(table["replans_least_energy"].sum()),
            "replans_not_sent": int(table["replans_not_sent"].sum()),
            "replans_failed": int(table["replans_failed"].sum()),
            "sbd_limits_bytes": {"up": SBD_MO_SHORT_BYTES, "down": SBD_MT_SHORT_BYTES},
        },
    }


# ---- the command ------------------------------------------------------------------------

MONTECARLO_FILES = ("scenarios.parquet", "summary.json", "energy.png", "exhaustion.png")


@dataclass(frozen=True)
class MonteCarloRun:
    """A Monte Carlo run of a mission: its scenarios, what they say, the files written."""

    result: MonteCarloResult
    summary: dict  # summary.json: the probability that the budget holds, quantiles, ...
    files: tuple  # of pathlib.Path: MONTECARLO_FILES in the output directory
    # a stop signal arrived once every scenario had flown, while they were written: the
    # files hold the whole run, and the command stops (exit 130 or 143) all the same
    stopped: bool = False


def montecarlo_mission(setup: FlightSetup, output_dir, *, scenarios: int,
                       workers: int = 1, scheduler: str | None = None, scenario_file=None,
                       progress: Callable[[int, int], None] | None = None,
                       replan: bool = False, confidence: float | None = None,
                       force: bool = False, mission_path=None) -> MonteCarloRun:
    """Fly the mission of `setup` (sim.setup.flight_setup: its plan's budget and
    prediction, or without one every sensor a state logs on and the budget the mission's
    usable battery; its seed, duration, tracker and start) in `scenarios` scenarios drawn
    from `scenario_file` (default: the shipped one) from the set-up's seed, on `workers`
    processes or the Dask `scheduler` ("local" or "tcp://HOST:PORT"); write
    MONTECARLO_FILES into `output_dir` (the pipeline of `gliderplan montecarlo`), a folder
    written whole (contract.files.output_folder: `force` replaces one holding other files
    than a gliderplan run's; `mission_path`, the mission's file, is refused inside, as
    every file the run reads).
    `replan`: each scenario is flown twice, with the plan alone and with the shore in the
    loop replanning the rest at each surfacing at `confidence` (default: the plan's own),
    its prior the scenario file without its drift (sim/replanning.py), both from the plan
    at that confidence (a plan that states another, or none, is replanned before launch:
    `plan_at_confidence`); the vehicle holds the set-up's key (the plan signed with it)
    or one made for the run. The summary then holds `hold_rate`, `hold_rate_static`,
    `quality`, `quality_static`, `update_bytes_max` and what the link carried
    (`replanning`).
    Raises KeyboardInterrupt if no scenario finished, or on a second stop while the files
    are written: an interrupted run keeps and writes those that did, marked partial and
    with no probability nor hold rate (`MonteCarloRun.result.interrupted`, summary.json's
    `complete`)."""
    import json
    from pathlib import Path

    from gliderplan.contract import interrupts
    from gliderplan.contract.errors import UsageError
    from gliderplan.contract.files import output_folder
    from gliderplan.sim import plots
    from gliderplan.sim.backends import check_run_size, scenario_executor
    from gliderplan.sim.outputs import parquet_bytes
    from gliderplan.sim.scenarios import read_spec

    check_run_size(scenarios, workers)
    out = Path(output_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory")
    spec = read_spec(scenario_file)
    mission, plan_path = setup.mission, setup.options.plan_path
    held = key = None
    launched = {}
    if replan:  # both flights planned at one confidence: the plan alone, and replanned
        from gliderplan.planner.planfile import read_plan_bytes
        from gliderplan.sim.replanning import plan_at_confidence

        held, key = _vehicle_plan(plan_path, setup.key)
        held, confidence, how = plan_at_confidence(mission, held, key, confidence=confidence,
                                                   spec=spec.model())
        setup = replace(setup, plan=read_plan_bytes(held, mission))
        launched = {"confidence": confidence, "plan_flown": how}
    job = Job(setup, spec, held=held, key=key, confidence=confidence)
    # Stopped while scenarios fly, the run keeps those that finished; once they are all
    # flown a stop waits while they are written (a second one abandons the writing and
    # leaves the folder's previous run).
    with interrupts.deferred(armed=False) as writing, \
            output_folder(out, command="montecarlo", force=force, recognised=MONTECARLO_FILES,
                          inputs=(mission_path, *setup.inputs, scenario_file)) as folder:
        with scenario_executor(workers, scheduler) as executor:
            result = run_montecarlo(job, scenarios, executor, workers, progress)
            writing.arm()
        if not result.rows:
            raise KeyboardInterrupt  # nothing finished, nothing to write
        import pyarrow as pa

        table = result.table()
        meta = {"mission": mission.name, "mission_hash": mission.hash,
                "plan": None if plan_path is None else str(plan_path),
                "scenario_file": spec.source, "seed": setup.config.seed,
                "run_limit_s": setup.config.duration_s, "budget_j": setup.budget_j,
                "workers": workers,
                "usable_share_drawn_from": spec.battery["usable_fraction_1"].text(),
                "scheduler": scheduler or ("local pool" if workers > 1 else "none"),
                "replan": replan, **launched}
        stated = summary(result, meta)
        contents = {
            "scenarios.parquet": parquet_bytes(pa.Table.from_pandas(table,
                                                                    preserve_index=False)),
            "summary.json": json.dumps(stated, indent=2) + "\n",
            "energy.png": plots.energy_histogram_png(
                table["energy_j"].to_numpy(float), table["budget_j"].to_numpy(float),
                setup.budget_j, stated["probability_budget_holds"], requested=scenarios),
            "exhaustion.png": plots.exhaustion_png(
                table["exhausted_s"].to_numpy(float), table["duration_s"].to_numpy(float)),
        }
        for name in MONTECARLO_FILES:
            folder.write(name, contents[name])
        folder.complete = not result.interrupted
    return MonteCarloRun(result, stated, tuple(folder.final(n) for n in MONTECARLO_FILES),
                         stopped=writing.requested)


def _vehicle_plan(plan_path, key: bytes | None) -> tuple[bytes, bytes]:  # noqa: ANN001
    """The signed plan file the vehicle holds and its key: `key` (the plan must be signed
    with it), or a key made for the run, which signs the plan."""
    import secrets

    from gliderplan.contract.errors import UsageError
    from gliderplan.planner.planfile import read_plan_data
    from gliderplan.planner.signing import check_signature, sign_plan

    if plan_path is None:
        raise UsageError("--replan: replanning changes a plan: give --plan")
    held = read_plan_data(plan_path)
    if key is not None:
        check_signature(held, key, str(plan_path))
        return held, key
    key = secrets.token_bytes(32)
    return sign_plan(held, key, 1), key
