"""One simulated flight of a checked mission: the glider and its science computer in an
ocean, flown by the compiled runtime's step in this process (the default), by the
Python reference executor or by the compiled C runtime over a pty."""

from __future__ import annotations

import shutil
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from gliderplan.contract import FlightLimits
from gliderplan.language import ir
from gliderplan.power_models.vehicle import Vehicle, flying_yo
from gliderplan.sim.loop import RunConfig, RunRecord, make_science, simulate
from gliderplan.sim.ocean import Ocean

if TYPE_CHECKING:
    from gliderplan.planner.planfile import Plan
    from gliderplan.sim.faults import FaultSpec

RUNTIMES = ("python", "c", "step")


def default_runtime() -> str:
    """"step" (the compiled runtime's step in this process), or "python" (the reference
    executor) where no C compiler is installed to build it."""
    from gliderplan.runtime.build import TARGETS

    return "step" if shutil.which(TARGETS["host"].compiler) else "python"


def fly(mission: ir.CheckedMission, ocean: Ocean, config: RunConfig, vehicle: Vehicle,
        plan: Plan | None = None, plan_path: str | None = None, runtime: str | None = None,
        robust_tracker: bool = True,
        progress: Callable[[float, float], None] | None = None,
        key_path: str | None = None,
        state_dir: str | Path | None = None,
        faults: FaultSpec | None = None) -> RunRecord:
    """Fly the mission until it exits or `config.duration_s` ends.

    `runtime`: "step" (the compiled runtime's step with the glider, science and energy
    models in C, sim/flight.c, or in Python for water the C loop does not model), "python"
    (the reference executor, tick by tick: the same flight bit for bit), "c" (the board
    binary over a pty); default `default_runtime()`. The C runtime reads its plan from
    `plan_path` (the file `plan` was read from), or with `key_path` (the key provisioned
    on the vehicle) gets it uploaded over the link, and keeps its checkpoints and event
    log in `state_dir` if given; raises emulator.EmulatorError when it cannot be built or
    started, PlanRejected when it refuses the plan. `faults` (C runtime only) are injected
    on the line and into the runtime's board; the record says what they did.
    """
    from gliderplan.sim.energy import BatteryGauge

    runtime = runtime or default_runtime()
    science = make_science(mission, ocean, config, vehicle)
    gauge = BatteryGauge(mission, vehicle, plan, config.tick_s)
    if runtime == "python":
        from gliderplan.sim.executor import PythonRuntime

        # without a plan: the same buoyancy volume the compiler gives the C runtime
        executor = PythonRuntime(mission, plan, vehicle.unplanned_ballast_cc, robust_tracker,
                                 vehicle.max_ballast_cc)
        record = simulate(mission, executor, science, config, progress, gauge=gauge)
        record.entry_variables = executor.entry_variables
        record.events_fired = executor.event_count
        return record
    if runtime not in ("c", "step"):
        raise ValueError(f"runtime must be one of {RUNTIMES}, not {runtime!r}")
    limits = flown_limits(mission, vehicle, plan)
    if runtime == "step":
        from gliderplan.planner.planfile import write_plan_bytes
        from gliderplan.sim.cflight import CFlight, flies_in_c, flight_context_bytes
        from gliderplan.sim.cstep import CStep

        step = CStep(mission, None if plan is None else write_plan_bytes(plan), limits,
                     naive_tracker=not robust_tracker, context_bytes=flight_context_bytes())
        if flies_in_c(ocean):
            return CFlight(mission, step, science, gauge.billing, mission.battery.energy_j,
                           config).fly(progress)
        record = simulate(mission, step, science, config, progress, gauge=gauge)
        record.entry_variables, record.events_fired = step.entry_variables, step.events_fired
        record.suspends = step.suspends
        return record
    from gliderplan.sim.emulator import start_c_runtime

    schedule = None
    if faults is not None:
        from gliderplan.sim.faults import FaultSchedule

        schedule = FaultSchedule(faults, config.seed, int(config.duration_s / config.tick_s),
                                 config.tick_s)
    c_runtime = start_c_runtime(mission, plan_path, limits, naive_tracker=not robust_tracker,
                                key_path=key_path, state_dir=state_dir, faults=schedule)
    try:
        record = simulate(mission, c_runtime, science, config, progress, gauge=gauge)
    finally:
        c_runtime.close()
    record.suspends = c_runtime.suspends  # counted once the runtime has ended
    if schedule is not None:
        record.faults, record.events_log = c_runtime.report(), c_runtime.events_log
    return record


def refuse_unflyable_yos(mission: ir.CheckedMission, vehicle: Vehicle,
                         plan: Plan | None) -> None:
    """FlightModelError (bad input, exit 1, as `plan` says it) for a yo of constant depths
    the vehicle cannot fly with the pitch and volume it would be flown at: one deeper than
    its trim and pumped volume climb back from would leave the simulated glider sinking
    (`gliderplan sim` and `montecarlo` ask before they fly).
    A yo whose band reads variables is left to the flight."""
    for i, state in enumerate(mission.states):
        for k, profile in enumerate(state.profiles):
            args = profile.constant_args()
            if profile.kind not in ("yo", "thermotrackyo") or args is None:
                continue
            planned = plan.states[i].profiles[k] if plan is not None else None
            pitch = planned.pitch_rad if planned else 0.5 * (args[2] + args[3])
            ballast = planned.ballast_cc if planned else vehicle.unplanned_ballast_cc
            with flying_yo(f"{state.name}: flightprofile {k}", vehicle, args[0], args[1]):
                vehicle.inflections_per_hour(args[0], args[1], pitch, ballast)


def flown_limits(mission: ir.CheckedMission, vehicle: Vehicle, plan: Plan | None
                 ) -> FlightLimits:
    """The limits the compiled runtime flies with: the vehicle flown (a scenario's may
    differ from the mission's) on the board the plan flies on (else the mission's)."""
    from gliderplan.planner.limits import flight_limits
    from gliderplan.planner.planfile import plan_board_limits

    board = plan_board_limits(mission, plan) if plan is not None else flight_limits(mission)
    return FlightLimits(vehicle.unplanned_ballast_cc, vehicle.max_ballast_cc, board.clocks_mhz)
