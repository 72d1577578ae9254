"""The language's execution semantics as pure functions: the reference the C runtime must match.

One tick: the current state's events are checked in order; the first whose condition
is true fires: its assignments run in order (each sees the ones before), then its
action. `call` pushes the current state and enters the target, `return` pops,
`goto` clears the stack, `exit` ends the mission.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from gliderplan.contract.errors import GliderplanError
from gliderplan.language import ir


@dataclass(frozen=True)
class Transition:
    """One row of a transition trace (the format of trace.csv and the runtime's event log)."""

    time_s: float
    kind: str  # start | goto | call | return | exit | reserve (the energy guard)
    from_state: str  # "" on start
    to_state: str  # "" on exit
    stack_depth: int  # after the transition


@dataclass(frozen=True)
class Machine:
    """Where a running mission is: current state (None once exited), stack, variables."""

    state: str | None
    stack: tuple[str, ...] = ()
    variables: Mapping[str, float] = field(default_factory=dict)

    @property
    def exited(self) -> bool:
        return self.state is None


class MissionFault(GliderplanError):
    """The mission did something the runtime refuses (stack overflow or underflow)."""


def start(mission: ir.CheckedMission, time_s: float = 0.0) -> tuple[Machine, Transition]:
    variables = {v.name: v.initial for v in mission.variables}
    first = mission.states[0].name
    return Machine(first, (), variables), Transition(time_s, "start", "", first, 0)


def fired_event(state: ir.State, sensors: Mapping[str, float],
                variables: Mapping[str, float]) -> ir.Event | None:
    """The first event of the state whose condition holds, or None."""
    for event in state.events:
        if ir.evaluate(event.condition, sensors, variables) != 0.0:
            return event
    return None


def step(mission: ir.CheckedMission, machine: Machine, sensors: Mapping[str, float],
         time_s: float) -> tuple[Machine, Transition | None]:
    """Advance one tick with the given sensor readings; return the new machine and transition."""
    if machine.state is None:
        return machine, None
    event = fired_event(mission.state(machine.state), sensors, machine.variables)
    if event is None:
        return machine, None
    return fire(mission, machine, event, sensors, time_s)


def fire(mission: ir.CheckedMission, machine: Machine, event: ir.Event,
         sensors: Mapping[str, float], time_s: float) -> tuple[Machine, Transition | None]:
    """Fire `event`, whose condition holds: its assignments in order (each sees the ones
    before), then its action. For a caller that found the event itself (once per tick)."""
    variables = assigned(event, sensors, machine.variables)
    return act(mission, Machine(machine.state, machine.stack, variables), event, time_s)


def assigned(event: ir.Event, sensors: Mapping[str, float],
             variables: Mapping[str, float]) -> dict[str, float]:
    """The variables after the event's assignments, in order (each sees the ones before)."""
    result = dict(variables)
    for assign in event.assignments:
        result[assign.variable] = ir.evaluate(assign.value, sensors, result)
    return result


def act(mission: ir.CheckedMission, machine: Machine, event: ir.Event,
        time_s: float) -> tuple[Machine, Transition | None]:
    """The event's action on a machine in the event's state whose variables already hold
    the event's assignments: the machine after it and its transition (None: no action)."""
    here, stack, variables = machine.state, machine.stack, machine.variables
    match event.action:
        case None:
            return machine, None
        case "goto":
            after = Machine(event.target, (), variables)
        case "call":
            if len(stack) >= mission.stack_depth:
                raise MissionFault(f"{time_s:g} s: call {event.target} from {here} overflows "
                                   f"the state stack ({mission.stack_depth})")
            after = Machine(event.target, stack + (here,), variables)
        case "return":
            if not stack:
                raise MissionFault(f"{time_s:g} s: return from {here} with an empty stack")
            after = Machine(stack[-1], stack[:-1], variables)
        case "exit":
            after = Machine(None, (), variables)
        case other:
            raise ValueError(f"unknown action {other!r}")
    transition = Transition(time_s, event.action, here, after.state or "", len(after.stack))
    return after, transition
