"""The planner's two commands as Python calls: `make_plan` (`gliderplan plan`) plans a
mission and writes its plan file and report; `sweep_mission` (`gliderplan plan --sweep`)
writes the Pareto, computer and battery sweeps. Both raise GliderplanErrors that say
what to change; the heavy libraries load on the first call."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, interrupts
from gliderplan.contract.errors import UsageError
from gliderplan.contract.files import output_folder, write_files_atomically
from gliderplan.language.ir import CheckedMission

if TYPE_CHECKING:
    import pandas as pd

    from gliderplan.planner.plan import PlanResult

SWEEP_FILES = ("pareto.csv", "computers.csv", "batteries.csv", "pareto.png")
SweepProgress = Callable[[str, int, int], None]  # (sweep, points done, points in all)


def make_plan(mission: CheckedMission, *, battery: str | None = None,
              computer: str | None = None, cycles_per_tick: float = RUNTIME_CYCLES_PER_TICK,
              output: str | Path | None = None,
              confidence: float | None = None, scenarios: int | None = None, seed: int = 0,
              risk: float = 1e-3, scenario_file: str | Path | None = None, workers: int = 1,
              occupancy_from_sim: bool = False,
              progress: Callable[[float, float], None] | None = None,
              sign: str | Path | None = None, seq: int | None = None,
              currents: str | None = None, start: tuple[float, float] | None = None,
              start_epoch_s: float | None = None) -> PlanResult:
    """Plan `mission` on its own hardware, or with `battery` ("1.2kWh", "60Ah@14.4V", a
    preset) and `computer` ("ts7800@500"; "ts7800" lets the planner pick the clock) in
    its place; `cycles_per_tick` [cycles] is the board's work every tick. With
    `confidence`, the budget holds with that probability: the scenario approach over
    `scenarios` simulated scenarios (default: as many as the confidence needs at `risk`)
    drawn from `scenario_file` (default: the shipped one) from `seed`, flown by `workers`
    processes (planner/confidence.py). With `occupancy_from_sim`, the time in each state
    (its visits, the variables its profiles read) comes from flying the plan, planned
    again until it settles (planner/simulated.py): one flight in the simulator's default
    water from `seed`, or the mean of `scenarios` scenarios drawn as for `confidence`.
    With `output`, write the plan file there and its
    JSON report beside it (`output`.json), atomically and together (never one without the
    other), and where it flies propelled its energy per km against speed
    (`output`.speed.png, reports/speed.py), unless a stop signal arrived
    (KeyboardInterrupt: an interrupted plan is no plan, even where a library swallowed
    the signal); with `sign` (a key file) the plan
    file is signed as plan number `seq` (default: `signing.default_sequence()`). The
    result holds the plan
    (`.plan`, what the file holds) and what its solve tells (quality, minimum energy,
    shadow price, the confidence). With `currents` (N,E [m/s], a NetCDF field or a
    directory of glider logs, as `sim --currents`), each propelled `auto` speed is the
    least energy per km over ground on its state's route legs from `start` (lat, lon
    [deg]; default: where the simulator puts the vehicle in) at `start_epoch_s` [s since
    1970] (planner/water.py). Raises InfeasibleBudget (with the minimum energy and
    the largest consumers), PlanningError, NoHeadway (naming the leg no speed can fly),
    CurrentError, HardwareError or ModelFileError."""
    from gliderplan.planner.hardware import load_hardware
    from gliderplan.planner.plan import plan_mission
    from gliderplan.planner.planfile import write_plan_bytes
    from gliderplan.planner.report import report_json

    if confidence is not None and occupancy_from_sim:
        raise UsageError("--confidence and --occupancy-from-sim: choose one (a plan at a "
                         "confidence plans each scenario on the times it flew)")
    if seq is not None and sign is None:
        raise UsageError("--seq goes with --sign KEYFILE")
    from gliderplan.sim.backends import check_run_size

    check_run_size(scenarios, workers)
    hardware = load_hardware(mission, battery=battery, computer=computer,
                             cycles_per_tick=cycles_per_tick)
    if currents is not None:
        from gliderplan.planner.water import in_water

        hardware = in_water(hardware, mission, currents, start, start_epoch_s)
    if occupancy_from_sim:
        result = _plan_on_simulation(mission, hardware, scenarios, seed, scenario_file,
                                     workers, progress)
    elif confidence is None:
        result = plan_mission(mission, hardware)
    else:
        from gliderplan.planner.confidence import plan_mission_at_confidence
        from gliderplan.sim.backends import scenario_executor
        from gliderplan.sim.scenarios import read_spec

        for name, value in (("--confidence", confidence), ("--risk", risk)):
            if not 0.0 < value < 1.0:
                raise UsageError(f"{name} {value:g}: must lie strictly between 0 and 1")
        spec = read_spec(scenario_file)
        with scenario_executor(workers) as executor:
            result = plan_mission_at_confidence(
                mission, hardware, confidence, scenarios=scenarios, seed=seed, risk=risk,
                spec=spec, executor=executor, workers=workers, progress=progress)
    data = write_plan_bytes(result.plan)
    if sign is not None:
        from gliderplan.planner.signing import default_sequence, read_key, sign_plan

        seq = default_sequence() if seq is None else seq
        data = sign_plan(data, read_key(sign), seq)
        result = replace(result, plan=replace(result.plan, seq=seq))
    result = replace(result, upload_bytes=len(data))
    interrupts.raise_if_stopped()
    if output is not None:
        files = {output: data,
                 f"{output}.json": json.dumps(report_json(result), indent=2) + "\n"}
        if hardware.vehicle.propulsion is not None:
            from gliderplan.reports.speed import speed_frame, speed_png

            frame = speed_frame(mission, hardware, result.plan)
            if len(frame):
                files[f"{output}.speed.png"] = speed_png(frame)
        write_files_atomically(files)
    return result


def _plan_on_simulation(mission: CheckedMission, hardware, scenarios: int | None,  # noqa: ANN001
                        seed: int, scenario_file: str | Path | None, workers: int,
                        progress: Callable[[float, float], None] | None) -> PlanResult:
    from gliderplan.planner.simulated import flown_in_scenarios, flown_once, plan_on_simulation

    if scenarios is None:
        return plan_on_simulation(mission, hardware, flown_once(mission, hardware, seed),
                                  f"one flight in the bench ocean with the CTD's noise, "
                                  f"seed {seed}")
    from gliderplan.sim.backends import scenario_executor
    from gliderplan.sim.scenarios import read_spec

    spec = read_spec(scenario_file)
    with scenario_executor(workers) as executor:
        fly_plan = flown_in_scenarios(mission, hardware, scenarios, seed, spec, executor,
                                      workers, progress)
        return plan_on_simulation(mission, hardware, fly_plan,
                                  f"the mean of {scenarios} scenarios drawn from "
                                  f"{spec.source}, seed {seed}")


@dataclass(frozen=True)
class Sweep:
    """The tradeoff tables of one mission (planner/README.md, "Sweeps")."""

    pareto: pd.DataFrame  # best quality against budget
    computers: pd.DataFrame  # the plan on each computer
    batteries: pd.DataFrame  # the plan with each battery
    files: tuple[Path, ...]


def sweep_mission(mission: CheckedMission, points: int, output_dir: str | Path, *,
                  battery: str | None = None, computer: str | None = None,
                  cycles_per_tick: float = RUNTIME_CYCLES_PER_TICK,
                  progress: SweepProgress | None = None, force: bool = False) -> Sweep:
    """The Pareto frontier at `points` budgets (2 to 10000), the plan on each computer at
    the mission's budget and with each battery; writes SWEEP_FILES into `output_dir`, a
    folder written whole (contract.files.output_folder; `force`: replace a folder holding
    other files than a gliderplan run's). Interrupted, it writes nothing."""
    from gliderplan.planner.hardware import load_hardware
    from gliderplan.planner.plan import prepare
    from gliderplan.planner.sweep import batteries, computers, pareto, plot_pareto

    if not 2 <= points <= 10_000:
        raise UsageError("--sweep N: N must be between 2 and 10000")
    out = Path(output_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory (--sweep writes several files there)")
    hardware = load_hardware(mission, battery=battery, computer=computer,
                             cycles_per_tick=cycles_per_tick)

    def labelled(label: str) -> Callable[[int, int], None] | None:
        return None if progress is None else lambda done, total: progress(label, done, total)

    with output_folder(out, command="plan --sweep", force=force,
                       recognised=SWEEP_FILES) as folder:
        _, model = prepare(mission, hardware)
        frame = pareto(model, points, labelled("pareto"))
        boards = computers(mission, budget_j=hardware.budget_j, progress=labelled("computers"),
                           cycles_per_tick=cycles_per_tick)
        packs = batteries(mission, computer=computer, progress=labelled("batteries"),
                          cycles_per_tick=cycles_per_tick)
        contents = {"pareto.csv": frame.to_csv(index=False),
                    "computers.csv": boards.to_csv(index=False),
                    "batteries.csv": packs.to_csv(index=False),
                    "pareto.png": plot_pareto(frame, f"{mission.name}: quality against budget")}
        interrupts.raise_if_stopped()
        files = tuple(folder.write(name, contents[name]) for name in SWEEP_FILES)
    return Sweep(frame, boards, packs, files)
