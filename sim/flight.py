"""One simulated flight of a checked mission: the glider and its science computer in an
ocean, flown by the compiled runtime's step in this process (the default), by the
Python reference executor or by the compiled C runtime over a pty."""

from __future__ import annotations

import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from gliderplan.contract import TRANSITION_NAMES
from gliderplan.language import ir
from gliderplan.language.registry import cannot_fly
from gliderplan.language.semantics import Transition
from gliderplan.power_models.vehicle import Vehicle, yo_flight_problem
from gliderplan.sim.loop import RunConfig, RunRecord, make_science, simulate
from gliderplan.sim.ocean import Ocean

if TYPE_CHECKING:
    from gliderplan.contract import FlightLimits
    from gliderplan.planner.planfile import Plan
    from gliderplan.sim.faults import FaultSpec
    from gliderplan.sim.replanning import ShoreLoop

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
        faults: FaultSpec | None = None, shore: ShoreLoop | None = None,
        keep_interrupted: bool = False) -> RunRecord:
    """Fly the mission until it exits or `config.duration_s` ends; KeyboardInterrupt
    goes through, but with `keep_interrupted` it ends the flight (sim.loop.simulate).

    `runtime`: "step" (the compiled runtime's step with the glider, science and energy
    models in C, sim/flight.c; a flight the C loop does not model, `cflight.flies_in_c`,
    flies the same step in the Python loop), "python" (the reference executor, tick by
    tick: the same flight bit for bit), "c" (the board binary over a pty); default
    `default_runtime()`. The C runtime reads its plan from `plan_path` (the file `plan`
    was read from), or with `key_path` (the key provisioned on the vehicle) gets it
    uploaded over the link, and keeps its checkpoints and event log in `state_dir` if
    given; raises emulator.EmulatorError when it cannot be built or started, PlanRejected
    when it refuses the plan. `faults` (C runtime only) are injected on the line and into
    the runtime's board; the record says what they did. `shore` (sim/replanning.py) is
    the shore in the loop: at each surfacing the glider's report goes up, and the plan
    updates it sends back are applied by the runtime (the C runtime's over its link; it
    must hold the key: `key_path`).
    """
    from gliderplan.planner.limits import flight_limits
    from gliderplan.sim.energy import BatteryGauge

    runtime = runtime or default_runtime()
    science = make_science(mission, ocean, config, vehicle)
    gauge = BatteryGauge(mission, vehicle, plan, config.tick_s)
    if runtime == "python":
        from gliderplan.sim.executor import PythonRuntime

        # without a plan: the same buoyancy volume, alternatives and speed the compiler
        # gives the C runtime (the board's clocks are not the executor's to set)
        executor = PythonRuntime(mission, plan, vehicle.unplanned_ballast_cc, robust_tracker,
                                 vehicle.max_ballast_cc, vehicle.envelope,
                                 flown_limits(mission, vehicle, (0.0,)))
        hook = None
        if shore is not None:
            from gliderplan.sim.replanning import PythonVehicle

            hook = _surfacing(shore, PythonVehicle(executor, shore.held, shore.key, mission,
                                                   _reader(mission, vehicle, plan)).deliver,
                              mission)
        record = simulate(mission, executor, science, config, progress, gauge=gauge,
                          on_surfacing=hook, keep_interrupted=keep_interrupted)
        record.entry_variables = executor.entry_variables
        record.envelope = located(executor.envelope_notes, mission)
        record.events_fired = executor.event_count
        return record
    if runtime not in ("c", "step"):
        raise ValueError(f"runtime must be one of {RUNTIMES}, not {runtime!r}")
    from gliderplan.planner.planfile import plan_board_limits

    board = plan_board_limits(mission, plan) if plan is not None else flight_limits(mission)
    # the vehicle flown: a scenario's may differ
    limits = flown_limits(mission, vehicle, board.clocks_mhz)
    if runtime == "step":
        return _fly_step(mission, science, config, plan, limits, robust_tracker, progress,
                         gauge, shore, keep_interrupted)
    from gliderplan.sim.emulator import start_c_runtime

    schedule = None
    if faults is not None:
        from gliderplan.planner.occupancy import mission_occupancy
        from gliderplan.sim.faults import FaultSchedule

        # kills fall within the run: up to the mission's end on its timeline, if sooner
        span_s = min(config.duration_s, mission_occupancy(mission, config.duration_s).total_s)
        schedule = FaultSchedule(faults, config.seed, int(span_s / config.tick_s),
                                 config.tick_s)
    c_runtime = start_c_runtime(mission, plan_path, limits, naive_tracker=not robust_tracker,
                                key_path=key_path, state_dir=state_dir, faults=schedule)
    hook = None if shore is None else _surfacing(shore, c_runtime.deliver_update, mission)
    try:
        record = simulate(mission, c_runtime, science, config, progress, gauge=gauge,
                          on_surfacing=hook, keep_interrupted=keep_interrupted)
    finally:
        c_runtime.close()
    record.suspends = c_runtime.suspends  # counted once the runtime has ended
    record.envelope = located(c_runtime.envelope_notes(), mission)
    if schedule is not None:
        record.faults, record.events_log = c_runtime.report(), c_runtime.events_log
        if record.events_log is not None:  # the transitions made, lost COMMANDs or not
            record.trace = logged_trace(record.events_log, record.flown_s)
    return record


def _fly_step(mission: ir.CheckedMission, science, config: RunConfig,  # noqa: ANN001
              plan: Plan | None, limits: FlightLimits, robust_tracker: bool,
              progress: Callable[[float, float], None] | None, gauge,  # noqa: ANN001
              shore: ShoreLoop | None, keep_interrupted: bool) -> RunRecord:
    """The compiled runtime's step in this process: in the C loop where it models the
    flight (stopping at each surfacing for the shore, if in the loop), else in the Python
    loop."""
    from gliderplan.planner.planfile import write_plan_bytes
    from gliderplan.sim.cflight import CFlight, flies_in_c, flight_context_bytes
    from gliderplan.sim.cstep import CStep

    held = shore.held if shore is not None else \
        None if plan is None else write_plan_bytes(plan)
    step = CStep(mission, held, limits, naive_tracker=not robust_tracker,
                 context_bytes=flight_context_bytes())
    hook = None if shore is None else _surfacing(shore, step.update_plan(shore.key), mission)
    if flies_in_c(science):
        record = CFlight(mission, step, science, gauge.billing, mission.battery.energy_j,
                         config).fly(progress, keep_interrupted, hook)
    else:
        record = simulate(mission, step, science, config, progress, gauge=gauge,
                          on_surfacing=hook, keep_interrupted=keep_interrupted)
        record.entry_variables, record.events_fired = step.entry_variables, step.events_fired
        record.suspends = step.suspends
    record.envelope = located(step.envelope_notes, mission)
    return record


def flown_limits(mission: ir.CheckedMission, vehicle: Vehicle,
                 clocks_mhz: tuple[float, ...]) -> FlightLimits:
    """The limits of `vehicle` (a scenario's may differ from the mission's) on a board of
    `clocks_mhz` [MHz]: its pump, its propulsion's speeds and thruster power (a plan or
    an update beyond them is refused), and what it flies without a plan (the alternatives
    and the `auto` speed the compiler gives the C runtime); no other bound beyond the
    contract's."""
    from gliderplan.contract import FlightLimits
    from gliderplan.planner.limits import propulsion_rating, unplanned

    speed, flown = unplanned(mission, vehicle)
    return FlightLimits(vehicle.unplanned_ballast_cc, vehicle.max_ballast_cc, clocks_mhz,
                        unplanned_speed_mps=speed, unplanned_profiles=flown,
                        envelope=vehicle.envelope, **propulsion_rating(vehicle))


def _surfacing(shore: ShoreLoop, deliver, mission: ir.CheckedMission):  # noqa: ANN001, ANN202
    from gliderplan.sim.replanning import surfacing_hook

    return surfacing_hook(shore, deliver, mission.battery.energy_j)


def _reader(mission: ir.CheckedMission, vehicle: Vehicle, plan: Plan | None):  # noqa: ANN202
    """How the Python executor's vehicle reads a plan an update makes: strictly, within
    the vehicle's pump and the board's clocks, as the C runtime does."""
    from gliderplan.planner.planfile import plan_board_limits, read_plan_bytes

    board = plan_board_limits(mission, plan).clocks_mhz if plan is not None else (0.0,)
    limits = flown_limits(mission, vehicle, board)
    return lambda data: read_plan_bytes(data, mission, "", limits)


def located(notes: list[str], mission: ir.CheckedMission) -> list[str]:
    """The envelope guard's notes with each state's place (`state s1 (line 6):`)."""
    places = {f"state {s.name}:": f"state {s.place}:" for s in mission.states}
    return [re.sub(r"state \S+:", lambda m: places.get(m[0], m[0]), note, count=1)
            for note in notes]


def logged_trace(events_log: str, flown_s: float) -> list[Transition]:
    """The transitions of a runtime's event log (docs/reliability.md) made before
    `flown_s` [s], as trace rows; its fault and clamp records are no transitions."""
    trace = []
    for line in events_log.splitlines():
        time_s, kind, from_state, to_state, depth = line.split()
        if kind in TRANSITION_NAMES.values() and float(time_s) < flown_s:
            trace.append(Transition(float(time_s), kind, from_state.strip("-"),
                                    to_state.strip("-"), int(depth)))
    return trace


def refuse_unflyable_yos(mission: ir.CheckedMission, vehicle: Vehicle,
                         plan: Plan | None) -> None:
    """FlightModelError (bad input, exit 1, as `plan` says it) for a yo of constant depths
    the vehicle cannot fly with the pitch and volume it would be flown at: one deeper than
    its trim and pumped volume climb back from would leave the simulated glider sinking
    (`gliderplan sim` and `montecarlo` ask before they fly).
    A yo whose band reads variables is left to the flight."""
    for i, state in enumerate(mission.states):
        for k, profile in enumerate(state.profiles):
            if cannot_fly(profile.kind, profile.thrust, vehicle) is not None:
                continue  # one the vehicle cannot fly is never flown (no plan time, check warns)
            flown = (None, None) if plan is None else (plan.states[i].profiles[k].pitch_rad,
                                                       plan.states[i].profiles[k].ballast_cc)
            problem = yo_flight_problem(f"{state.place}: flightprofile {k}", vehicle,
                                        profile.kind, profile.constant_args(), *flown)
            if problem is not None:
                raise problem
