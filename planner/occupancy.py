"""Time the mission spends in each state, found before it flies.

The mission is run with the reference semantics on the runtime's tick grid, with
`missiontime` as the only sensor that has a value (every other reading is NaN, as on
the runtime before a sensor has reported). Missiontime guards then decide every exit
they can: Fig. 2 gives s1 0-500 s, s2 500-1500 s, s1 1500-2000 s, s3 2000-2500 s.
Which event fires and what its action does are the reference's (`semantics.fired_event`,
`semantics.act`); only an assignment that needs an unknown reading differs: it keeps the
variable's value.

A state whose exit depends on other sensors is planned at the upper bound of its
`expect` annotation (robust: the budget must hold when the water is unkind), leaving by
its first sensor-driven event that goes on with the mission (an abort above it, a
`goto` to a state that only exits, is the exception a plan does not budget for). A
state that neither guard nor `expect` ends runs to the mission's horizon. Between guard
crossings nothing changes, so the walk jumps from one crossing to the next instead of
stepping every tick: a 35 h mission takes a few hundred evaluations, not 30,000 ticks.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace

from gliderplan.contract import DEFAULT_HORIZON_S, TICK_S
from gliderplan.language import ir
from gliderplan.language.semantics import Machine, act, assigned, fired_event, start
from gliderplan.planner.legs import Position, leg_length_m, route_targets

NOMINAL_SPEED_MPS = 0.35  # Slocum horizontal speed (paper; BCO-DMO): transit times in the walk
_MAX_VISITS = 100_000  # bounds the walk of a mission that bounces between states forever


@dataclass(frozen=True)
class Visit:
    """One stay in a state: entry time, duration [s] and the variables on entry."""

    state: str
    entry_s: float
    duration_s: float
    variables: dict[str, float]
    ended_by: str  # "guard" | "expect" | "transit" | "horizon"


@dataclass(frozen=True)
class Occupancy:
    """Time [s] and visits per state, and how the walk decided them."""

    time_s: dict[str, float]
    visits: dict[str, int]
    variables: dict[str, dict[str, float]]  # state -> variables on its first visit
    trace: tuple[Visit, ...] = ()
    source: str = "timeline"  # "timeline" | "simulation"
    notes: tuple[str, ...] = field(default=())  # defaults and bounds used, for the report
    legs_m: dict[str, float] = field(default_factory=dict)  # transit state -> route length
    # propelled transit state -> the speed its legs are timed at [m/s]
    transit_speeds: dict[str, float] = field(default_factory=dict)

    @property
    def total_s(self) -> float:
        return float(sum(self.time_s.values()))


class _NaNSensors(dict):
    """Sensor readings where only missiontime is known."""

    def __init__(self, time_s: float) -> None:
        super().__init__(missiontime=time_s)

    def __missing__(self, key: str) -> float:
        return math.nan


def _comparisons(expr: ir.Expr) -> list[ir.BinaryOp]:
    match expr:
        case ir.BinaryOp(op, left, right):
            here = [expr] if op in ("<", "<=", ">", ">=", "==", "!=") else []
            return here + _comparisons(left) + _comparisons(right)
        case ir.UnaryOp(_, operand):
            return _comparisons(operand)
        case ir.FuncCall(_, args):
            return [c for a in args for c in _comparisons(a)]
    return []


def _crossings(state: ir.State, variables: dict[str, float], now_s: float) -> list[float]:
    """Grid times after `now_s` at which a missiontime comparison may change its value.

    Each side of a comparison is taken as affine in missiontime (what guards written
    with constants and variables are): the crossing is where their difference is zero.
    """
    times: set[float] = set()
    for event in state.events:
        for comparison in _comparisons(event.condition):
            def gap(t: float, c: ir.BinaryOp = comparison) -> float:
                sensors = _NaNSensors(t)
                return (ir.evaluate(c.left, sensors, variables)
                        - ir.evaluate(c.right, sensors, variables))
            g0, g1 = gap(now_s), gap(now_s + 1.0)
            slope = g1 - g0
            if not (math.isfinite(g0) and math.isfinite(slope)) or slope == 0.0:
                continue
            root = now_s - g0 / slope
            tick = math.ceil(root / TICK_S - 1e-9) * TICK_S
            times.update(t for t in (tick, tick + TICK_S) if t > now_s)
    return sorted(times)


def _next_guard(state: ir.State, variables: dict[str, float], from_s: float,
                until_s: float) -> tuple[float, ir.Event] | None:
    """First tick in [from_s, until_s] at which an event fires that changes something."""
    for t in [from_s, *_crossings(state, variables, from_s)]:
        if t > until_s:
            return None
        event = fired_event(state, _NaNSensors(t), variables)
        if event is None:
            continue
        if event.action is not None or _assign(event, t, variables) != variables:
            return t, event
    return None


def _reads_other_sensors(event: ir.Event) -> bool:
    return bool(ir.sensors_read(event.condition) - {"missiontime"})


def _ends_mission(mission: ir.CheckedMission, event: ir.Event) -> bool:
    """An `exit`, or a `goto` to a state whose every event exits: an abort."""
    if event.action == "exit":
        return True
    if event.action != "goto":
        return False
    events = mission.state(event.target).events
    return bool(events) and all(e.action == "exit" for e in events)


def _sensor_exit(mission: ir.CheckedMission, state: ir.State) -> ir.Event | None:
    """The event a state is planned to leave by when sensors decide: its first
    sensor-driven one that goes on with the mission (aborts above it are the exception
    the plan does not budget for), else its first sensor-driven one."""
    driven = [e for e in state.events if e.action is not None and _reads_other_sensors(e)]
    going_on = [e for e in driven if not _ends_mission(mission, e)]
    return (going_on or driven or [None])[0]


def _assign(event: ir.Event, time_s: float, variables: dict[str, float]) -> dict[str, float]:
    """Variables after the event's assignments (the reference's); a value that needs an
    unknown reading (not finite) leaves the variable as it was."""
    after = assigned(event, _NaNSensors(time_s), variables)
    return {k: v if math.isfinite(v) else variables[k] for k, v in after.items()}


# what the walk notes when a mission without `horizon` runs to the default one
DEFAULT_HORIZON_NOTE = (f"horizon {DEFAULT_HORIZON_S / 86400:g} d (default): the mission names "
                        "none and does not exit before it")


def mission_occupancy(mission: ir.CheckedMission, horizon_s: float | None = None,
                      transit_speeds: Mapping[str, float] | None = None) -> Occupancy:
    """Walk the mission's timeline; `horizon_s` defaults to the mission's `horizon`. A
    transit leg through a state of `transit_speeds` [m/s] (a propelled one,
    `rates.transit_speeds`) is timed at its speed, any other at NOMINAL_SPEED_MPS."""
    speeds = transit_speeds or {}
    notes: list[str] = []
    horizon = mission.run_limit_s(horizon_s)
    horizon_defaulted = horizon_s is None and mission.horizon_s is None
    machine, _ = start(mission)
    now = 0.0
    trace: list[Visit] = []
    position: Position | None = None  # where the last route left the glider
    legs: dict[str, float] = {}
    while machine.state is not None and now < horizon and len(trace) < _MAX_VISITS:
        state, variables = machine.state, dict(machine.variables)
        here = mission.state(state)
        entry, entry_vars = now, dict(variables)
        check_from = now if not trace else now + TICK_S  # the entering tick already fired
        limit = horizon
        sensor_exit = _sensor_exit(mission, here)
        if here.expect_s is not None and sensor_exit is not None:
            limit = min(horizon, entry + here.expect_s[1])
        found = None
        while True:
            found = _next_guard(here, variables, check_from, limit)
            if found is None or found[1].action is not None:
                break
            variables = _assign(found[1], found[0], variables)
            check_from = found[0] + TICK_S
        targets = route_targets(here.route)
        leg = leg_length_m(position, targets) if sensor_exit is not None else None
        if found is not None:
            fire_s, event, ended_by = found[0], found[1], "guard"
            if sensor_exit is not None:
                notes.append(f"{state}: its exits on readings ({_reads(here)}) are assumed "
                             "not to fire before its missiontime guard")
        elif limit == horizon and leg is not None:
            # A transit leg: a glide at the nominal speed, the planner chooses its own; a
            # propelled leg at its speed.
            speed = speeds.get(state, NOMINAL_SPEED_MPS)
            fire_s = entry + math.ceil(leg / speed / TICK_S) * TICK_S
            event, ended_by = sensor_exit, "transit"
            legs[state] = legs.get(state, 0.0) + leg
        elif limit < horizon:
            fire_s, event, ended_by = limit, sensor_exit, "expect"
            notes.append(f"{state}: planned at its expect upper bound "
                         f"({here.expect_s[1]:g} s per visit)")
        else:
            trace.append(Visit(state, entry, horizon - entry, entry_vars, "horizon"))
            why = "default horizon" if horizon_defaulted else "horizon"
            if sensor_exit is not None:
                notes.append(f"{state}: its exits on readings ({_reads(here)}) are assumed "
                             "not to fire")
            notes.append(f"{state}: no exit decided before the {why} ({horizon:g} s); "
                         "runs to it")
            break
        trace.append(Visit(state, entry, fire_s - entry, entry_vars, ended_by))
        position = targets[-1] if targets else position
        now = fire_s
        machine, _ = act(mission, Machine(state, machine.stack, _assign(event, fire_s, variables)),
                         event, fire_s)
    if horizon_defaulted and trace and trace[-1].ended_by == "horizon":
        notes.append(DEFAULT_HORIZON_NOTE)
    return replace(_summarise(mission, trace, notes, legs),
                   transit_speeds={s: v for s, v in speeds.items() if s in legs})


def _reads(state: ir.State) -> str:
    """The readings other than missiontime that a state's exits depend on."""
    names = set()
    for event in state.events:
        if event.action is not None:
            names |= ir.sensors_read(event.condition) - {"missiontime"}
    return ", ".join(sorted(names))


def _variable_arguments(mission: ir.CheckedMission, trace: list[Visit]) -> list[str]:
    """Notes for profile arguments that read variables: planned at their value on the
    state's first visit, though the flight may change them."""
    notes = []
    assigned = {a.variable for s in mission.states for e in s.events for a in e.assignments}
    first = {}
    for visit in trace:
        first.setdefault(visit.state, visit.variables)
    initial = {v.name: v.initial for v in mission.variables}
    for state in mission.states:
        read = sorted(set(state.profile_variables) & assigned)
        if read:
            values = first.get(state.name, initial)
            notes.append(f"{state.name}: profile arguments {', '.join(read)} planned at "
                         + ", ".join(f"{v} = {values[v]:g}" for v in read)
                         + " (their value on entry); events may change them in flight")
    return notes


def _summarise(mission: ir.CheckedMission, trace: list[Visit], notes: list[str],
               legs: dict[str, float]) -> Occupancy:
    time_s = {s.name: 0.0 for s in mission.states}
    visits = {s.name: 0 for s in mission.states}
    first_vars: dict[str, dict[str, float]] = {}
    for visit in trace:
        time_s[visit.state] += visit.duration_s
        visits[visit.state] += 1
        first_vars.setdefault(visit.state, visit.variables)
    initial = {v.name: v.initial for v in mission.variables}
    for s in mission.states:
        first_vars.setdefault(s.name, initial)
    notes = [*notes, *_variable_arguments(mission, trace)]
    return Occupancy(time_s, visits, first_vars, tuple(trace), "timeline",
                     tuple(dict.fromkeys(notes)), legs)


def measured_occupancy(mission: ir.CheckedMission, occupancy_s: dict[str, float],
                       visits: dict[str, int] | None = None,
                       variables: dict[str, dict[str, float]] | None = None,
                       note: str = "time in each state: measured in simulation") -> Occupancy:
    """Occupancy measured in simulation (state name -> seconds; unknown names are errors),
    with the visits and the variables on entry measured too where given (else one visit
    to each state flown, and the variables' initial values). `note` says where the
    figures come from, for the plan's assumptions."""
    unknown = sorted(set(occupancy_s) - set(mission.state_index))
    if unknown:
        raise ValueError(f"occupancy names states the mission does not have: {', '.join(unknown)}")
    bad = [k for k, v in occupancy_s.items() if not (math.isfinite(v) and v >= 0.0)]
    if bad:
        raise ValueError(f"occupancy of {', '.join(bad)} must be a finite number of seconds >= 0")
    time_s = {s.name: float(occupancy_s.get(s.name, 0.0)) for s in mission.states}
    stays = {k: int(v > 0.0) for k, v in time_s.items()}
    stays.update({k: max(int(n), stays[k]) for k, n in (visits or {}).items()})
    initial = {v.name: v.initial for v in mission.variables}
    on_entry = {s.name: {**initial, **(variables or {}).get(s.name, {})}
                for s in mission.states}
    return Occupancy(time_s, stays, on_entry, (), "simulation", (note,))
