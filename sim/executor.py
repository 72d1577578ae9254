"""The Python reference executor: what the C runtime does with one SENSORS frame.

The events of the current state are checked by a compiled checker (sim/compiled.py),
once per tick: the ticks on which nothing fires (almost all of them) cost one function
call. The event it finds is fired by `language.semantics.fire` (the reference
semantics: assignments, then the action).
Commands come from the library routines of docs/pilot.md (sim/pilot.py). Sensor
values arrive as the link carries them: IEEE binary32, widened to double.
"""

from __future__ import annotations

import functools
import math
import struct
from typing import TYPE_CHECKING

from gliderplan.contract import (
    FLAG_CLIMBING,
    FLAG_DONE,
    FLAG_ENVELOPE,
    FLAG_HEADING,
    FLAG_HEADING_HOLD,
    FLAG_SURFACE,
    N_SENSORS,
    NO_STATE,
    SURFACE_PITCH_RAD,
    TRANSITION_NAMES,
    Envelope,
    EnvelopeAction,
    FlightLimits,
    TransitionKind,
)
from gliderplan.language import ir, semantics
from gliderplan.language.registry import PROFILES, SENSOR_BY_NAME, SENSORS
from gliderplan.runtime.protocol import Command
from gliderplan.sim import compiled, pilot
from gliderplan.sim.envelope import EnvelopeGuard, Held

if TYPE_CHECKING:
    from gliderplan.planner.planfile import Plan

# COMMAND's `transition` of each kind the reference semantics reports.
_KIND_CODES = {name: kind for kind, name in TRANSITION_NAMES.items()}
_F32 = struct.Struct(f"<{N_SENSORS}f")
(_DEPTH, _LAT, _LON, _TEMP, _HALFCYCLE, _WPTDIST, _WPTREACHED, _ENERGY, _ALTITUDE,
 _HEADING) = (
    SENSOR_BY_NAME[n].index for n in ("depth", "lat", "lon", "temp", "halfcycle", "wptdist",
                                      "wptreached", "energy_left", "altitude", "heading"))
_SURFACE_PITCH_F32 = struct.unpack("<f", struct.pack("<f", SURFACE_PITCH_RAD))[0]


@functools.cache
def _runs(mask: int) -> tuple[tuple[int, int], ...]:
    """The set bits of a sensor mask as (first, stop) index ranges."""
    runs: list[tuple[int, int]] = []
    for i in range(N_SENSORS):
        if mask >> i & 1:
            if runs and runs[-1][1] == i:
                runs[-1] = (runs[-1][0], i + 1)
            else:
                runs.append((i, i + 1))
    return tuple(runs)


def _floats(values: tuple[float, ...] | None) -> tuple[float, ...] | None:
    return None if values is None else tuple(float(v) for v in values)


class PythonRuntime:
    """A mission (and optional plan) executing tick by tick, like the compiled runtime."""

    def __init__(self, mission: ir.CheckedMission, plan: Plan | None, default_ballast_cc: float,
                 robust_tracker: bool = True, max_ballast_cc: float | None = None,
                 envelope: Envelope | None = None, limits: FlightLimits | None = None) -> None:
        """`default_ballast_cc` [cc] is flown where no plan sets one; `max_ballast_cc` [cc],
        the pump's volume, is the surfacing of the energy guard (default: the former);
        `envelope`, the vehicle's rating every command is held to (None: none, for tests
        of the semantics alone). `limits`: without a plan, the alternative of each state
        and the `auto` speed [m/s] flown (`FlightLimits.unplanned_*`; default: the first,
        none)."""
        self.mission = mission
        self.unplanned_speed_mps = 0.0 if limits is None else limits.unplanned_speed_mps
        self.unplanned = [0 if limits is None else limits.unplanned_profile(i)
                          for i in range(len(mission.states))]
        self.default_ballast_cc = default_ballast_cc
        self.max_ballast_cc = default_ballast_cc if max_ballast_cc is None else max_ballast_cc
        self.guard = None if envelope is None else EnvelopeGuard(envelope, self.max_ballast_cc)
        # what the guard did: "missiontime T s, state S: <limit>; <action>", as the C
        # runtime says it
        self.envelope_notes: list[str] = []
        # the transitions (kind, from, to, depth codes) a step made before its COMMAND's:
        # an event's, on the tick the envelope ended the mission after it
        self.superseded: list[tuple[int, int, int, int]] = []
        self.tick_transition: semantics.Transition | None = None
        self.reserve_j = mission.battery.reserve_j
        self.robust = robust_tracker
        self.index = mission.state_index
        self.checkers = [compiled.event_checker(s) for s in mission.states]
        self.argument_fns = [[compiled.arguments(p) for p in s.profiles] for s in mission.states]
        # constant arguments (most profiles) are evaluated once, not every tick
        self.constant_args = [[_floats(p.constant_args()) for p in s.profiles]
                              for s in mission.states]
        self.adopt_plan(plan)
        self.s = [math.nan] * N_SENSORS
        self.machine: semantics.Machine | None = None
        self.event_count = 0
        # per call on the stack: the caller's waypoint and the waypoints it had reached
        self.route_resume: list[tuple[int, int]] = []
        self.suspends = 0  # ticks after which the board was put to sleep
        self.entry_variables: dict[str, dict[str, float]] = {}  # state -> on first entry

    def adopt_plan(self, plan: Plan | None) -> None:
        """Fly `plan`'s schedules from the next tick on (at start-up, and when a plan update
        is accepted at a surfacing); the state, the stack and the routine flown go on."""
        self.plan = plan
        self.power_tables = [self._power_table(i, s) for i, s in enumerate(self.mission.states)]
        # states whose sensors are all always on have one power mask
        self.constant_power = [None if any(period for _, period, _ in table) else
                               pilot.sensor_power_mask(table, 0.0) for table in self.power_tables]
        # where the runtime suspends the board after answering a tick: the plan's SLEEP,
        # without a plan the mission's `computer sleep between ticks`
        self.sleeps = [plan.states[i].sleep if plan is not None else s.computer.sleep
                       for i, s in enumerate(self.mission.states)]

    def _power_table(self, i: int, state: ir.State) -> tuple[tuple[int, float, float], ...]:
        """(sensor index, period [s], on [s]) per logged sensor; period 0: always on."""
        scheduled = {}
        if self.plan is not None:
            scheduled = {s.name: (s.period_s, s.on_s) for s in self.plan.states[i].sensors}
        table = []
        for use in state.sensors:
            info = SENSOR_BY_NAME[use.name]
            period, on = scheduled.get(use.name, (0.0, 0.0)) if info.device else (0.0, 0.0)
            table.append((info.index, period, on))
        return tuple(table)

    def _enter(self, state: str) -> None:
        self.entry_variables.setdefault(state, dict(self.machine.variables))
        i = self.index[state]
        self.state_i = i
        self.state = self.mission.states[i]
        self.entry_time_s = self.s[0]
        self.profile_k = -1
        self.routine = None
        route = self.state.route
        self.route = pilot.ROUTE_ROUTINES[route.kind](route.params, route.points)
        if isinstance(self.route, pilot.Turn):
            self.route.enter(self.s[_HEADING])

    def _follow(self, kind: str, state: str | None) -> None:
        """Enter the state a transition leads to. A call keeps the caller's waypoint and
        count of waypoints reached, and its return resumes them (docs/pilot.md, Routes);
        goto forgets them all."""
        if kind == "call":
            self.route_resume.append((self.route.k, self.route.reached))
        elif kind == "goto":
            self.route_resume.clear()
        if state is None:
            return
        self._enter(state)
        if kind == "return":
            k, reached = self.route_resume.pop()
            if k < len(getattr(self.route, "points", ())):
                self.route.k, self.route.reached = k, reached

    def step(self, tick: int, mask: int, values: list[float]) -> Command:
        """Answer one SENSORS frame: `values` holds all sensors [registry units], of which
        those in `mask` arrive, through binary32 as on the link."""
        s = self.s
        self.superseded = []
        carried = _F32.unpack(_F32.pack(*values))
        for first, stop in _runs(mask):
            s[first:stop] = carried[first:stop]
        transition: semantics.Transition | None = None
        if self.machine is None:
            self.machine, transition = semantics.start(self.mission, s[0])
            self._enter(self.machine.state)
        # the runtime's own readings, as the events of this tick see them
        s[_HALFCYCLE] = float(self.routine.halfcycle) if self.routine is not None else 0.0
        s[_WPTDIST] = self.route.distance_m(s[_LAT], s[_LON])
        s[_WPTREACHED] = float(self.route.reached)
        machine = self.machine
        if machine.state is not None and s[_ENERGY] <= self.reserve_j:
            # the energy guard: whatever the state and the stack, the mission ends here
            self.machine = semantics.Machine(None, (), machine.variables)
            return self._command(tick, semantics.Transition(s[0], "reserve", machine.state,
                                                            "", 0))
        fired_i = -1 if machine.state is None else self.checkers[self.state_i](s, machine.variables)
        if fired_i >= 0:  # conditions checked once, above; the reference fires the event
            named = {info.name: s[info.index] for info in SENSORS}
            after, fired = semantics.fire(self.mission, machine, self.state.events[fired_i],
                                          named, s[0])
            self.machine = after
            self.event_count += 1
            if fired is not None:
                transition = fired
                self._follow(fired.kind, after.state)
        return self._command(tick, transition)

    def _command(self, tick: int, transition: semantics.Transition | None) -> Command:
        self.tick_transition = transition
        kind, src, dst = TransitionKind.NONE, NO_STATE, NO_STATE
        if transition is not None:
            kind = _KIND_CODES[transition.kind]
            src = self.index[transition.from_state] if transition.from_state else NO_STATE
            dst = self.index[transition.to_state] if transition.to_state else NO_STATE
        machine = self.machine
        if kind in (TransitionKind.RESERVE, TransitionKind.ENVELOPE):  # surface and hold
            return Command(tick, NO_STATE, 0, kind, src, dst, 0,
                           FLAG_DONE | FLAG_SURFACE | FLAG_CLIMBING, 0.0, _SURFACE_PITCH_F32,
                           float(self.max_ballast_cc), 0.0, 0, self.event_count)
        if machine.state is None:
            return Command(tick, NO_STATE, 0, kind, src, dst, 0, FLAG_DONE, 0.0, 0.0, 0.0, 0.0,
                           0, self.event_count)
        s, i = self.s, self.state_i
        t_in = s[0] - self.entry_time_s
        state_plan = self.plan.states[i] if self.plan is not None else None
        k = pilot.profile_index(state_plan, t_in, self.unplanned[i])
        args = self.constant_args[i][k] or self.argument_fns[i][k](s, machine.variables)
        profile = self.state.profiles[k]
        depth = s[_DEPTH]
        entered = k != self.profile_k
        if entered:
            self.profile_k = k
            routine = pilot.PROFILE_ROUTINES[profile.kind]
            self.routine = routine(depth, args, self.robust, s[_ALTITUDE]) \
                if profile.kind == "thermotrackyo" else routine(depth, args, s[_ALTITUDE])
        if state_plan is not None:
            planned = state_plan.profiles[k]
            pitch, ballast = planned.pitch_rad, planned.ballast_cc
            speed, thrust = planned.speed_mps, planned.thrust_w
        else:
            pitch, ballast = None, self.default_ballast_cc
            speed, thrust = None, profile.written_thrust_w
        target, pitch_cmd, ballast_cmd, surface = self.routine.command(
            depth, s[_TEMP], args, pitch, ballast, s[_ALTITUDE])
        speed = pilot.propelled_speed(args, speed, self.unplanned_speed_mps) \
            if PROFILES[profile.kind].propelled else 0.0
        thrust = thrust if profile.kind in pilot.ASSISTED else 0.0
        heading, valid = self.route.turned(t_in) if isinstance(self.route, pilot.Turn) \
            else self.route.heading(s[_LAT], s[_LON])
        flags = ((FLAG_SURFACE if surface else 0) | (FLAG_CLIMBING if ballast_cmd > 0.0 else 0)
                 | (FLAG_HEADING if valid else 0)
                 | (FLAG_HEADING_HOLD if valid and self.route.holds else 0))
        if self.guard is not None:
            band = (args[0], args[1]) if profile.kind in ("yo", "thermotrackyo") else None
            command = Held(target, pitch_cmd, ballast_cmd, heading, speed, thrust)
            held = self._hold(tick, entered, band, command, flags)
            if isinstance(held, Command):
                return held
            flags = held
            target, pitch_cmd, ballast_cmd = command.target_m, command.pitch_rad, \
                command.ballast_cc
            heading, speed, thrust = command.heading_rad, command.speed_mps, command.thrust_w
        power = self.constant_power[i]
        if power is None:
            power = pilot.sensor_power_mask(self.power_tables[i], t_in)
        self.suspends += self.sleeps[i]
        return Command(tick, i, len(machine.stack), kind, src, dst, k, flags, target, pitch_cmd,
                       ballast_cmd, heading, power, self.event_count, speed, thrust)

    def _hold(self, tick: int, entered: bool, band: tuple[float, float] | None,
              command: Held, flags: int) -> int | Command:
        """The envelope guard on this tick's command (runtime/src/gp_runtime.c): the flags
        to send, `command` held with the clamp action; or the mission's end (the surface
        action: a COMMAND) or a MissionFault (the fault action)."""
        guard = self.guard
        was_held = guard.held
        breach = guard.hold(entered, band, self.s[0], self.s[_DEPTH], command,
                            bool(flags & FLAG_CLIMBING), bool(flags & FLAG_HEADING))
        if breach is None:
            return flags
        ends = guard.ends(breach)
        fault = ends and guard.envelope.action == EnvelopeAction.FAULT
        if ends or not was_held:
            what = ("releasing control" if fault else "the mission ends, surfacing" if ends
                    else "held at the limit")
            self.envelope_notes.append(f"envelope: missiontime {self.s[0]:g} s, state "
                                       f"{self.state.name}: {breach.text()}; {what}")
        if fault:
            raise semantics.MissionFault(f"tick {tick}: {self.envelope_notes[-1]}")
        if ends:
            fired = self.tick_transition  # an event's, before the end: both are the tick's
            if fired is not None and fired.kind != "start":
                self.superseded = [(_KIND_CODES[fired.kind], self.index[fired.from_state],
                                    self.index[fired.to_state] if fired.to_state
                                    else NO_STATE, fired.stack_depth)]
            machine = self.machine
            self.machine = semantics.Machine(None, (), machine.variables)
            return self._command(tick, semantics.Transition(self.s[0], "envelope",
                                                            machine.state, "", 0))
        return flags | FLAG_ENVELOPE
