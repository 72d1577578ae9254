"""The fast executor: the reference executor's flight computed a run of ticks at a time.

`FastForward` is offered each tick by the loop (sim/loop.py) and flies as many ticks as
it can in one go, exactly as `PythonRuntime` (sim/executor.py) flying the simulated
glider and science computer tick by tick would: the same transition trace and every
per-tick record bit for bit. It leaves to the loop the ticks on which something happens
that a run does not compute: an event fires, the plan switches to another profile
alternative, a waypoint is reached, a state's or profile's first tick; and every tick
of a profile the runs do not cover (thermotrackyo, hover, arguments that read sensors).

A run of ticks, in order:
1. the schedule: the profile alternative from the time in the state, the events on the
   clock, then the sensors' power;
2. the flight: a yo leg after leg, each leg's depths the running sum (cumsum, the same
   additions in the same order) of the depth changes of `GliderSim.glide_from` (the
   actuators settling, then steady), the depth readings with their noise giving the tick
   the leg turns; a compressible hull's depths (or any hull's in a stratified ocean),
   each the last plus the glide's change at it, tick after tick in C (sim/native.c); a
   surfacing: the climb, then the ticks at
   the surface. Over a sea floor the run ends before the tick that would take the
   glider below it, or on which a dive turns at the yo's altimeter stop (the loop flies
   those ticks);
3. the CTD along those depths (its lag is a recursion, one number at a time, in C);
4. the events: every condition over the run's readings at once; the run ends before
   the first tick on which one holds;
5. the route: a heading comes from this tick's position and sets the next one, through
   the readings' binary32 rounding: steered tick after tick in C, up to the tick that
   may reach a waypoint (so the count of waypoints reached is the same on every tick of
   a run).
The run's length adapts, per state: twice what the last run flew when a tick it had
computed was thrown away (an event on a reading, a waypoint), so that work computed past
an event is bounded by the work kept; twice the last length when nothing computed was
lost (the run was flown whole, or cut at once by an event on the time, whose tick is
known before anything is computed).
"""

from __future__ import annotations

import bisect
import itertools
import math
import operator
import struct
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract import SURFACE_PITCH_RAD
from gliderplan.language import ir
from gliderplan.language.registry import SENSOR_BY_NAME, altitude_stop_m
from gliderplan.sim import compiled, native, pilot
from gliderplan.sim.executor import PythonRuntime
from gliderplan.sim.geo import degrees_to_ddmm, degrees_to_ddmm_array
from gliderplan.sim.loop import Columns
from gliderplan.sim.science import (
    BATTERY_V,
    CONSTANT_READINGS,
    DEVICE_MASKS,
    SECONDS_PER_DAY,
    SENT_ALWAYS_MASK,
    ScienceComputer,
    powered_mask,
)
from gliderplan.sim.vehicle import SURFACE_DEPTH_M, Glide

MIN_RUN_TICKS = 64
MAX_RUN_TICKS = 16384
MAX_BACKOFF_TICKS = 1024
SHORT_RUN_TICKS = 32  # a run costs about what the loop pays for this many ticks

_COMMAND_F32 = struct.Struct("<4f")
_ONE_F32 = struct.Struct("<f")


class _S:
    """Sensor indices by name, for `match` (its value patterns are dotted names)."""

    MISSIONTIME, DEPTH, PITCH, HEADING, ALTITUDE, LAT, LON, BATTERY = (
        SENSOR_BY_NAME[n].index for n in ("missiontime", "depth", "pitch", "heading",
                                          "altitude", "lat", "lon", "battery"))
    TEMP, CONDUCTIVITY, SALINITY, CURRENT, HALFCYCLE, WPTDIST, WPTREACHED, TIMEOFDAY = (
        SENSOR_BY_NAME[n].index for n in ("temp", "conductivity", "salinity", "current",
                                          "halfcycle", "wptdist", "wptreached", "timeofday"))
    ENERGY_LEFT = SENSOR_BY_NAME["energy_left"].index


# the executor's own, set before every tick's events
_RUNTIME_READINGS = (_S.HALFCYCLE, _S.WPTDIST, _S.WPTREACHED)
_TEMP_BIT = 1 << _S.TEMP
_DIVE, _CLIMB = pilot.DIVE, pilot.CLIMB


def _f32(x: np.ndarray) -> np.ndarray:
    """Through the link: binary32 and back, as struct's 'f' rounds."""
    return np.asarray(x, np.float64).astype(np.float32).astype(np.float64)


def _f32_scalar(x: float) -> float:
    return _ONE_F32.unpack(_ONE_F32.pack(x))[0]


def _command_f32(pitch_rad: float, ballast_cc: float) -> tuple[float, float]:
    """A COMMAND's pitch and ballast as the glider receives them (binary32)."""
    _, pitch, ballast, _ = _COMMAND_F32.unpack(_COMMAND_F32.pack(0.0, pitch_rad, ballast_cc,
                                                                 0.0))
    return pitch, ballast


@dataclass
class _Flight:
    """The glider over a run of `count` ticks (arrays of the tick's start, step outputs)."""

    count: int
    depth_m: np.ndarray  # count + 1: before each tick and after the last
    pitch_rad: np.ndarray
    phase: np.ndarray
    pumped_out_cc: np.ndarray
    pumped_in_cc: np.ndarray
    inflection: np.ndarray
    distance_m: np.ndarray
    legs: list[tuple[int, int, Glide, int]]  # (first tick, ticks, glide, leg) under water
    surface_from: int  # first tick at the surface (count: none)
    surface_time_s: np.ndarray  # after each tick at the surface
    fix_at: int  # the GPS fix's tick, or -1
    surface_starts: bool  # the surfacing begins in this run

    def actuators_at(self, tick: int, before: tuple) -> tuple:
        """The glider's actuators at the start of `tick` of the run (`before`: at its
        first tick)."""
        for first, ticks, glide, _ in reversed(self.legs):
            if first < tick:
                return _after(glide, min(tick - first, ticks))
        return before


def _after(glide: Glide, ticks: int) -> tuple:
    """Actuators after `ticks` ticks of a glide."""
    return glide.actuators[min(ticks, glide.settled)]


def squeezed_rows(glide: Glide, trim_cc: float) -> np.ndarray:
    """A compressible hull's glide as native.c's `gpn_squeezed_yo` reads it: per row, the
    sign of the buoyancy, the volume plus trim [cc], the signed vertical speed per square
    root of a cc [m s-1], the time gliding [s]."""
    w_per_root = glide.speeds_per_root[1]
    return np.array([(math.copysign(1.0, b), b + trim_cc, -w_per_root if b > 0.0 else w_per_root,
                      s) for b, s in zip(glide.ballast_cc.tolist(), glide.glide_s.tolist(),
                                         strict=True)])


def halfcycles(routine, flight: _Flight) -> np.ndarray:
    """The routine's `halfcycle` before each tick of the run and after its last (count + 1
    values): a yo's count goes up on the tick whose command turns it, the first leg's
    when the run begins with a turn (`routine.leg` is the leg before the run)."""
    counts = np.full(flight.count + 1, float(routine.halfcycle))
    if isinstance(routine, pilot.Yo) and flight.legs:
        turns = [first for first, _, _, _ in flight.legs[1:]]
        if flight.legs[0][3] != routine.leg:
            turns.insert(0, 0)
        begun = np.zeros(flight.count + 1)
        np.add.at(begun, [t + 1 for t in turns if t < flight.count], 1.0)
        counts += np.cumsum(begun)
    return counts


class FastForward:
    """Runs of ticks for `sim.loop.simulate`, flown as `runtime` would fly them."""

    def __init__(self, mission: ir.CheckedMission, runtime: PythonRuntime,
                 science: ScienceComputer) -> None:
        self.ex, self.science, self.glider = runtime, science, science.glider
        self.tick_s = science.tick_s
        self.run_ticks = [MIN_RUN_TICKS] * len(mission.states)  # per state
        self._computed = 0  # ticks the last run computed past its schedule
        # per state: ticks left to the loop after a short run, and the tick to try again
        # (a state whose events fire every few ticks holds back no other state's runs)
        self._backoff = [0] * len(mission.states)
        self._resume = [0] * len(mission.states)
        self._glides: dict[tuple, Glide | None] = {}
        self._changes: dict[int, np.ndarray] = {}  # per glide: its depth changes, long
        self._change_lists: dict[int, list[float]] = {}
        self._sums: dict[int, list[float]] = {}
        self._rows: dict[int, np.ndarray] = {}  # per glide: `squeezed_rows`
        # each state's events by the stage of a run at which their readings are known
        self._events = [_staged(s) for s in mission.states]
        # the sensors whose last value the executor reads: the mission's conditions,
        # assignments and profile arguments, the time of entry, the routines and routes
        expressions = [x for s in mission.states for e in s.events
                       for x in (e.condition, *(a.value for a in e.assignments))]
        expressions += [a for s in mission.states for p in s.profiles for a in p.args]
        altimeter = {_S.ALTITUDE} if any(p.has_altimeter_stop for s in mission.states
                                         for p in s.profiles) else set()
        self._executor_reads = sorted(compiled.sensors_read(expressions) | altimeter
                                      | {_S.MISSIONTIME, _S.DEPTH, _S.LAT, _S.LON, _S.TEMP})
        self._covered = [[_covered(p) for p in s.profiles] for s in mission.states]
        # the battery reading changes within a run (the loop's gauge): a mission that reads
        # it is flown tick by tick
        self._reads_energy = _S.ENERGY_LEFT in self._executor_reads
        self._rigid = not self.glider.speed_depends_on_depth
        self._ocean = hasattr(science.ocean, "water_along")
        c = self.glider.current
        self._current_reading = math.hypot(c.north_mps, c.east_mps)

    def __call__(self, tick: int, last_tick: int, columns: Columns) -> int:
        ex = self.ex
        machine = ex.machine
        if machine is None or machine.state is None or tick < self._resume[ex.state_i] \
                or self._reads_energy \
                or ex.profile_k < 0 or not self._ocean or self._flows() \
                or (ex.guard is not None and ex.guard.held) \
                or not self._covered[ex.state_i][ex.profile_k] \
                or not isinstance(ex.route, _ROUTES):
            return 0
        i = ex.state_i
        self._computed = 0
        flown = self._run(tick, min(self.run_ticks[i], last_tick - tick + 1), columns)
        grown = 2 * (flown if flown < self._computed else self.run_ticks[i])
        self.run_ticks[i] = min(MAX_RUN_TICKS, max(MIN_RUN_TICKS, grown))
        # after runs that flew less than they cost, the next is tried later and later:
        # where events fire every few ticks (an assignment on every tick near the
        # surface, a bookkeeping event every metre of depth) the loop's own ticks are
        # cheaper
        self._backoff[i] = 0 if flown >= SHORT_RUN_TICKS else \
            min(MAX_BACKOFF_TICKS, 2 * self._backoff[i] + 1)
        self._resume[i] = tick + flown + self._backoff[i]
        return flown

    def _flows(self) -> bool:
        """A current moves the glider or its estimate (sim.navigation), or the floor
        depends on where it is (sim.bathymetry): flown by the loop's own ticks, which
        carry the model of record of both."""
        return self.science.currents is not None or self.glider.flows \
            or self.science.floor_by_position

    # ---- one run ----------------------------------------------------------------------

    def _run(self, tick: int, count: int, columns: Columns) -> int:
        ex, sci = self.ex, self.science
        i, k = ex.state_i, ex.profile_k
        state_plan = ex.plan.states[i] if ex.plan is not None else None
        time_s = np.arange(tick, tick + count) * self.tick_s
        missiontime = _f32(time_s)
        t_in = missiontime - ex.entry_time_s
        if state_plan is not None and sum(p.share > 0.0 for p in state_plan.profiles) > 1:
            count = _first(pilot.profile_indices(state_plan, t_in) != k, count)
        # the events on the clock cut the run before the sensors' schedule is worked out:
        # they read only sensors sent on every tick
        values = _Readings(self, time_s, missiontime)
        count = self._until_event(_SCHEDULE, values, count)
        if count == 0:
            return 0
        self._computed = count
        power = (np.full(count, ex.constant_power[i], np.int64)
                 if ex.constant_power[i] is not None
                 else pilot.sensor_power_masks(ex.power_tables[i], t_in[:count]))
        sent = values.sent = _powered(np.concatenate([[sci.sensor_power], power[:-1]]))
        flight = self._flight(i, k, state_plan, count)
        if flight is None or flight.count == 0:
            return 0
        count = self._above_floor(flight, time_s, count)
        if count == 0:
            return 0
        values.flight = flight
        noise = sci.normal.peek(count)
        depth = flight.depth_m[:count]
        values.depth_reading = _f32(_positive(depth + sci.noise.depth_sigma_m * noise[:, 1]))
        count = self._until_event(_FLIGHT, values, count)
        if count == 0:
            return 0
        ctd = values.ctd = sci.ctd_along(depth[:count], time_s[:count])
        count = self._until_event(_CTD, values, count)
        if count == 0:
            return 0
        nav = values.nav = self._route(flight, count)
        count = self._until_event(_NAV, values, nav.count)
        count = self._within_guard(flight, values, self._volume(state_plan, k), count)
        if count == 0:
            return 0

        # the run stands: its rows, then everything a reference tick reads, as after it
        temp_reading = np.where(sent[:count] & _TEMP_BIT != 0, ctd.measured_c[:count], np.nan)
        columns.extend(count, {
            "depth_m": depth[:count], "pitch_rad": flight.pitch_rad[:count],
            "temperature_c": ctd.water_c[:count], "temp_reading_c": temp_reading,
            "state": i, "stack_depth": len(ex.machine.stack), "profile": k,
            "sensor_power": power[:count], "phase": flight.phase[:count],
            "pumped_out_cc": flight.pumped_out_cc[:count],
            "pumped_in_cc": flight.pumped_in_cc[:count],
            "inflection": flight.inflection[:count],
            "lat_deg": nav.lat[:count], "lon_deg": nav.lon[:count],
        })
        sci.commit_ctd(ctd, count, float(temp_reading[-1]))
        sci.sensor_power = int(power[count - 1])
        ex.suspends += count * ex.sleeps[i]  # the board sleeps after each tick, as there
        every = int(np.bitwise_and.reduce(sent[:count]))
        some = int(np.bitwise_or.reduce(sent[:count]))
        for index in self._executor_reads:
            if some >> index & 1:
                last = count - 1 if every >> index & 1 else \
                    _last(sent[:count] >> index & 1 != 0)
                ex.s[index] = values.sensor_at(index, last)
        for index in _RUNTIME_READINGS:  # as the executor set them for the last tick
            ex.s[index] = values.sensor_at(index, count - 1)
        self._commit_glider(flight, nav, tick, count)
        values.commit_held(count)
        return count

    def _above_floor(self, flight: _Flight, time_s: np.ndarray, count: int) -> int:
        """The first `count` ticks of the flight (`count` at most its own) up to the first
        on which the glider would end below the sea floor (the loop stops it there), or
        on which a yo's dive reads the altimeter at its stop (the loop turns it)."""
        count = min(count, flight.count)
        floor = self.science.floor
        if floor is None:
            return count
        bottom = floor.depth_along(time_s[:count])
        stops = flight.depth_m[1:count + 1] > bottom
        ex = self.ex
        profile = ex.state.profiles[ex.profile_k]
        stop = altitude_stop_m(profile.kind, ex.constant_args[ex.state_i][ex.profile_k] or
                               ex.argument_fns[ex.state_i][ex.profile_k](ex.s,
                                                                         ex.machine.variables))
        if profile.kind == "yo" and stop > 0.0 and flight.legs:
            lengths = [ticks for _, ticks, _, _ in flight.legs]
            diving = np.repeat([leg == _DIVE for _, _, _, leg in flight.legs], lengths)
            altitude = _f32(bottom - flight.depth_m[:count])  # as the executor reads it
            stops[:len(diving)] |= diving[:count] & (altitude[:len(diving)] <= stop)
        return _first(stops, count)

    def _until_event(self, stage: int, values: _Readings, count: int) -> int:
        """The run's ticks before the first on which one of the events checked at `stage`
        (a checker and the sensors it reads) fires; the held event's variables over the
        run worked out first where its readings become known."""
        events = self._events[self.ex.state_i]
        if events.held is not None and events.held.stage == stage:
            values.hold(events.held, count)
        if events.stages[stage] is None:
            return count
        fires, wanted = events.stages[stage]
        s = {index: values.held(index, count) for index in wanted}
        return _first(fires(s, values.variables(count), count), count)

    def _commit_glider(self, flight: _Flight, nav: _Route, tick: int, count: int) -> None:
        g, ex = self.glider, self.ex
        g.actuators = flight.actuators_at(count, g.actuators)
        g.depth_m = float(flight.depth_m[count])
        g.positions = nav.positions_at(count)
        if nav.heading is not None:
            g.heading_rad = float(nav.heading[count - 1])
        last = count - 1
        g.phase = int(flight.phase[last])
        g.pumped_out_cc = float(flight.pumped_out_cc[last])
        g.pumped_in_cc = float(flight.pumped_in_cc[last])
        g.inflection = bool(flight.inflection[last])
        if count > flight.surface_from:
            g.surface_time_s = float(flight.surface_time_s[count - 1 - flight.surface_from])
            g.surfacings += flight.surface_starts
        else:
            g.surface_time_s = -1.0
        if isinstance(ex.routine, pilot.Yo):
            counts = halfcycles(ex.routine, flight)
            ex.routine.halfcycle = int(counts[count])
            ex.routine.leg = next(leg for first, _, _, leg in reversed(flight.legs)
                                  if first < count)
            if ex.guard is not None:  # the guard saw each tick's command, as the runtime's
                turns = np.flatnonzero(np.diff(counts[:count + 1]))
                if len(turns):
                    ex.guard.turned = True
                    ex.guard.last_turn_s = _f32_scalar((tick + int(turns[-1])) * self.tick_s)
                ex.guard.climbing = ex.routine.leg == _CLIMB

    # ---- the flight --------------------------------------------------------------------

    def _flight(self, i: int, k: int, state_plan, count: int) -> _Flight | None:
        ex = self.ex
        profile = ex.state.profiles[k]
        args = ex.constant_args[i][k] or ex.argument_fns[i][k](ex.s, ex.machine.variables)
        pitch = state_plan.profiles[k].pitch_rad if state_plan is not None else None
        ballast = self._volume(state_plan, k)
        if profile.kind == "yo":
            return self._yo(args, pitch, ballast, count)
        return self._surfacing(ballast, count)

    def _volume(self, state_plan, k: int) -> float:
        """[cc] the volume alternative `k` pumps either side of neutral: the plan's, else
        the mission's default."""
        return state_plan.profiles[k].ballast_cc if state_plan is not None \
            else self.ex.default_ballast_cc

    def _within_guard(self, flight: _Flight, values: _Readings, ballast_cc: float,
                      count: int) -> int:
        """The run's ticks before the first on which the envelope guard would act on the
        heading's turns or the pump's energy (`EnvelopeGuard.replay`), from the headings
        and volumes the routines command on each."""
        ex = self.ex
        guard = ex.guard
        if guard is None or count == 0 or not (
                math.isfinite(guard.envelope.max_turn_rate_rad_s)
                or math.isfinite(guard.envelope.max_pump_power_w)):
            return count
        headings = [ex.route.toward_rad(a, b) for a, b in zip(
            values.sensor(_S.LAT, 0, count).tolist(), values.sensor(_S.LON, 0, count).tolist(),
            strict=True)]
        volumes = np.full(count, ballast_cc)
        if isinstance(ex.routine, pilot.Yo):  # its leg turns on the ticks its halfcycle counts
            turned = np.diff(halfcycles(ex.routine, flight)[:count + 1]) != 0
            climbing = (np.cumsum(turned) % 2 == 1) != (ex.routine.leg == _CLIMB)
            volumes = np.where(climbing, ballast_cc, -ballast_cc)
        return guard.replay(values.missiontime[:count].tolist(),
                            values.depth_reading[:count].tolist(), headings, volumes.tolist())

    def _glide(self, actuators: tuple, command: tuple[float, float]) -> Glide | None:
        key = (actuators, command)
        if key not in self._glides:
            self._glides[key] = self.glider.glide_from(actuators, *command)
        return self._glides[key]

    def _yo(self, args: tuple[float, ...], pitch: float | None, ballast: float,
            count: int) -> _Flight | None:
        """A yo over the run: the legs' turning ticks predicted in double precision, then
        certified all at once on the exact depths (each the running sum, in order, of
        the depth changes, as the glider adds them) and readings (through binary32).
        From the first leg whose turn the certificate refutes, that leg is flown exactly
        and the rest predicted again: every round certifies at least one more leg, and a
        refuted prediction needs a reading within a millionth of the band's edge."""
        low, high = args[0], args[1]
        commands = {leg: _command_f32(*pilot._yo_command(leg, low, high, args, pitch,
                                                         ballast)[1:3])
                    for leg in (_DIVE, _CLIMB)}
        sci, g = self.science, self.glider
        # the depth sensor's error each tick, as `readings` adds it to the depth
        noise_array = sci.noise.depth_sigma_m * sci.normal.peek(count + 1)[:, 1]
        spread = float(np.abs(noise_array).max())
        edges = {_DIVE: high, _CLIMB: low}
        x = g.depth_m + float(noise_array[0])
        reading = _f32_scalar(x if x > 0.0 else 0.0)
        leg = self.ex.routine.leg
        if leg == _DIVE and reading >= high:
            leg = _CLIMB
        elif leg == _CLIMB and reading <= low:
            leg = _DIVE
        if not self._rigid:
            return self._yo_squeezed(commands, noise_array, spread, edges, leg, count)
        noise = noise_array.tolist()
        legs: list[tuple[int, int, Glide, int]] = []
        j, depth, actuators, exact = 0, g.depth_m, g.actuators, False
        while True:
            while j < count:
                glide = self._glide(actuators, commands[leg])
                if glide is None:
                    break
                if exact:  # the leg the certificate refuted: tick by tick in binary32
                    ticks, leg_depths, stop = self._leg(glide, depth, noise, j, spread,
                                                        edges[leg], leg == _DIVE, count - j)
                    exact = False
                    if stop:  # clamped at the surface: the run ends before that tick
                        if ticks:
                            legs.append((j, ticks, glide, leg))
                        j += ticks
                        break
                    end_depth = leg_depths[ticks]
                else:
                    ticks, change = self._predict(glide, depth, noise, j, spread, edges[leg],
                                                  leg == _DIVE, count - j)
                    end_depth = depth + change
                legs.append((j, ticks, glide, leg))
                depth = end_depth
                actuators = _after(glide, ticks)
                j += ticks
                leg = _CLIMB if leg == _DIVE else _DIVE
            if not legs:
                return None
            flight = self._assemble(j, legs, None, surface=None)
            refuted = self._refuted(flight, noise_array, edges)
            if refuted is None:
                return flight
            # legs before the refuted one stand; fly it exactly, predict the rest again
            first = legs[refuted][0]
            leg = legs[refuted][3]
            del legs[refuted:]
            j, depth, exact = first, float(flight.depth_m[first]), True
            actuators = flight.actuators_at(first, g.actuators)

    def _predict(self, glide: Glide, depth: float, noise: list[float], first: int,
                 spread: float, edge: float, diving: bool, limit: int) -> tuple[int, float]:
        """The ticks of a yo leg (at most `limit`) and its depth change, predicted in double
        precision: the first later tick whose depth plus its noise reaches `edge`."""
        sums = self._sums.get(id(glide))
        if sums is None:
            sums = self._sums[id(glide)] = list(itertools.accumulate(glide.dz_m.tolist(),
                                                                     initial=0.0))
        settled = min(glide.settled, limit)
        for t in range(1, settled + 1):
            x = depth + sums[t] + noise[first + t]
            if t < limit and ((x >= edge) if diving else (x <= edge)):
                return t, sums[t]
        if settled == limit:
            return limit, sums[limit]
        base = depth + sums[glide.settled]
        step = sums[glide.settled + 1] - sums[glide.settled]
        start = settled + 1
        if step != 0.0 and (step > 0.0) == diving:  # skip the ticks that cannot reach it
            near = edge - spread if diving else edge + spread
            start = max(start, settled + int((near - base) / step))
        for t in range(start, limit):
            x = base + (t - settled) * step + noise[first + t]
            if (x >= edge) if diving else (x <= edge):
                return t, base + (t - settled) * step - depth
        return limit, base + (limit - settled) * step - depth

    def _refuted(self, flight: _Flight, noise: np.ndarray, edges: dict[int, float]
                 ) -> int | None:
        """The first leg whose turn, or a tick within it, the exact depths and readings
        contradict (a depth below the surface counts), or None: every turn stands."""
        legs, n = flight.legs, flight.count
        depth = flight.depth_m
        ends = np.array([first + ticks for first, ticks, _, _ in legs])
        lengths = np.diff(np.concatenate([[0], ends]))
        diving = np.repeat([leg == _DIVE for _, _, _, leg in legs], lengths)[:n - 1]
        edge = np.repeat([edges[leg] for _, _, _, leg in legs], lengths)[:n - 1]
        x = depth[1:n] + noise[1:n]
        reading = _f32(np.where(x > 0.0, x, 0.0))
        turns = np.zeros(n, bool)
        turns[ends[ends < n] - 1] = True
        wrong = depth[1:n + 1] < 0.0  # wrong[w]: tick w (of the leg holding it) refuted
        wrong[:n - 1] |= np.where(diving, reading >= edge, reading <= edge) != turns[:n - 1]
        bad = int(wrong.argmax())
        if not wrong[bad]:
            return None
        return int(np.searchsorted(ends, bad, side="right"))

    def _surfacing(self, ballast: float, count: int) -> _Flight | None:
        g = self.glider
        command = _command_f32(SURFACE_PITCH_RAD, ballast)
        legs: list[tuple[int, int, Glide, int]] = []
        depths: list[np.ndarray] = []
        depth = g.depth_m
        climb = 0
        if depth > SURFACE_DEPTH_M:
            glide = self._glide(g.actuators, command)
            if glide is None:
                return None
            profile = self._depths(glide, depth, count)
            up = np.flatnonzero(profile[1:] <= SURFACE_DEPTH_M)
            climb = int(up[0]) + 1 if len(up) else count
            if len(up):  # the last climbing tick is clamped at the surface, the run's last too
                profile[climb] = max(0.0, float(profile[climb]))
            legs.append((0, climb, glide, 0))
            depths.append(profile[:climb])
            depth = float(profile[climb])
        at_surface = count - climb
        surface_time = g.surface_time_s if climb == 0 else -1.0
        phases, after, fix = g.surface_along(at_surface, surface_time)
        if at_surface:
            depths.append(np.concatenate([[depth], np.zeros(at_surface - 1)]))
            depth = 0.0
        flight = self._assemble(climb, legs, np.concatenate([*depths, [depth]]),
                                surface=(at_surface, phases, after))
        flight.fix_at = climb + fix if fix >= 0 else -1
        flight.surface_starts = surface_time < 0.0
        return flight

    def _assemble(self, ticks: int, legs: list, depth_m: np.ndarray | None,
                  surface: tuple | None) -> _Flight:
        """The per-tick arrays of the legs under water, then of the ticks at the surface
        (`depth_m`: before each tick and after the last; None: the legs' running sum
        from where the glider is)."""
        tables: dict[int, int] = {}
        glides: list[Glide] = []
        for _, _, glide, _ in legs:
            if id(glide) not in tables:
                tables[id(glide)] = sum(len(x.dz_m) for x in glides)
                glides.append(glide)
        if legs:
            starts = np.array([first for first, _, _, _ in legs])
            lengths = np.array([n for _, n, _, _ in legs])
            base = np.repeat([tables[id(gl)] for _, _, gl, _ in legs], lengths)
            settled = np.repeat([gl.settled for _, _, gl, _ in legs], lengths)
            offset = np.arange(ticks) - np.repeat(starts, lengths)
            rows = base + np.minimum(offset, settled)

            def column(name: str) -> np.ndarray:
                return np.concatenate([getattr(gl, name) for gl in glides])[rows]
        else:
            def column(name: str) -> np.ndarray:
                return np.empty(0)
        pitch = column("pitch_rad")
        phase = column("phase")
        out, inn = column("pumped_out_cc"), column("pumped_in_cc")
        inflection = column("inflection").astype(bool)
        if depth_m is None:
            depth_m = np.empty(ticks + 1)
            depth_m[0] = self.glider.depth_m
            depth_m[1:] = column("dz_m")
            np.add.accumulate(depth_m, out=depth_m)
        if self._rigid or not legs:
            distance = column("distance_m")
        else:  # at the depth each tick starts at
            u_per_root = np.repeat([gl.speeds_per_root[0] for _, _, gl, _ in legs], lengths)
            distance = self.glider.glide_distances(u_per_root, column("ballast_cc"),
                                                   column("glide_s"), depth_m[:ticks])
        surface_time = np.empty(0)
        count = ticks
        if surface is not None and surface[0]:
            n, phases, surface_time = surface
            g = self.glider
            held_pitch = g.actuators[0] if not legs else _after(legs[-1][2], legs[-1][1])[0]
            pitch = np.concatenate([pitch, np.full(n, held_pitch)])
            phase = np.concatenate([phase, phases])
            out = np.concatenate([out, np.zeros(n)])
            inn = np.concatenate([inn, np.zeros(n)])
            inflection = np.concatenate([inflection, np.zeros(n, bool)])
            distance = np.concatenate([distance, np.zeros(n)])
            count += n
        return _Flight(count, depth_m, pitch, phase, out, inn, inflection, distance, legs,
                       ticks, surface_time, -1, False)

    def _leg(self, glide: Glide, depth: float, noise: list[float], first: int,
             spread: float, edge: float, diving: bool, limit: int
             ) -> tuple[int, list[float], bool]:
        """Ticks of one yo leg from `depth` on tick `first` (at most `limit`), its depths
        before each tick and after, and whether the run must stop after it.

        The leg ends on the first later tick whose depth reading (depth plus that tick's
        `noise`, at most `spread` in size, through binary32) reaches the band's `edge`.
        Depths are running sums, added in order as the glider adds them; where they run
        steadily one way, bisection finds the ticks near the edge and only those are
        decided in binary32, as the routine decides. A depth the glider would clamp at
        the surface stops the run before the tick that clamps (the loop flies it)."""
        changes = self._change_lists.get(id(glide))
        if changes is None:
            changes = self._change_lists[id(glide)] = glide.dz_m.tolist()
        settled = min(glide.settled, limit)
        depths = list(itertools.accumulate(changes[:settled], initial=depth))
        margin = spread + 1e-6 * max(1.0, abs(edge))  # beyond which no reading can reach it
        near = edge - margin if diving else edge + margin

        def ends(t: int) -> tuple[int, list[float], bool] | None:
            """The leg's end if tick t ends it (a clamp or a turn)."""
            d = depths[t]
            if d < 0.0:
                return t - 1, depths, True
            if ((d >= near) if diving else (d <= near)) and t < limit \
                    and _reaches(d + noise[first + t], edge, diving):
                return t, depths, False
            return None

        for t in range(1, settled + 1):  # settling: tick by tick
            if (end := ends(t)) is not None:
                return end
        if settled == limit:
            return limit, depths, False
        step = changes[glide.settled]
        if step == 0.0 or (step > 0.0) != diving:  # not moving toward the edge: scan it all
            guess = limit - settled
        else:
            guess = int((edge - depths[-1]) / step) + 8
        while True:
            n = min(max(guess, 8), limit - settled)
            depths = depths[:settled + 1]
            depths += itertools.accumulate(itertools.repeat(step, n), initial=depths[-1])
            del depths[settled + 1]  # accumulate's `initial` repeats the last depth
            start = settled + 1
            if guess < limit - settled and near >= 0.0:  # steadily toward the edge: bisect
                start = max(start, bisect.bisect_left(depths, near, lo=settled) if diving else
                            bisect.bisect_left(depths, -near, lo=settled, key=operator.neg))
            for t in range(start, settled + n + 1):
                if (end := ends(t)) is not None:
                    return end
            if settled + n == limit:
                return limit, depths, False
            guess = 2 * n

    def _yo_squeezed(self, commands: dict[int, tuple[float, float]], noise: np.ndarray,
                     spread: float, edges: dict[int, float], leg: int, count: int
                     ) -> _Flight | None:
        """`_yo` for a compressible hull, whose glide speed changes with the depth each
        tick starts at: every leg flown exactly, each depth the last plus
        `GliderSim.glide_rates`' change at it (native.c's `gpn_squeezed_yo`, the same
        operations in the same order), each turn decided on the tick's reading as `_leg`
        decides it. The legs after the first alternate between two glides while each
        settles before its turn; from a leg that does not, the next is found here."""
        flight = self.glider.vehicle.flight
        weight = flight.rho_kg_m3 * flight.g_m_s2  # net_buoyancy_cc's (rho g) depth
        squeeze = flight.hull_volume_cc * flight.compressibility_per_pa
        water = self.glider.stratification
        lift = None if water is None else (water.lift_cc, water.step_m)
        # beyond `near` of an edge no reading can reach it
        near = tuple(edges[d] + (1.0 if d == _CLIMB else -1.0) * (
            spread + 1e-6 * max(1.0, abs(edges[d]))) for d in (_CLIMB, _DIVE))
        edge = (edges[_CLIMB], edges[_DIVE])
        legs: list[tuple[int, int, Glide, int]] = []
        depths = [np.array([self.glider.depth_m])]
        j, actuators = 0, self.glider.actuators
        while j < count:
            first = self._glide(actuators, commands[leg])
            if first is None:
                break
            glides = [first]
            settled = first.actuators[first.settled]
            second = self._glide(settled, commands[1 - leg])
            third = None if second is None else \
                self._glide(second.actuators[second.settled], commands[leg])
            if third is not None and third.actuators[third.settled] == settled:
                glides += [second, third]  # the next legs' glides, again and again
            flown, leg_depths, stop = native.squeezed_yo(
                [(self._rows_of(glide), glide.settled) for glide in glides], weight, squeeze,
                noise[j:], near, edge, leg == _DIVE, count - j, float(depths[-1][-1]), lift)
            for n, (start, ticks) in enumerate(flown.tolist()):
                legs.append((j + start, ticks, glides[0 if n == 0 else 2 - n % 2],
                             leg if n % 2 == 0 else 1 - leg))
            depths.append(leg_depths[1:])
            if stop or not len(flown):
                break
            j = legs[-1][0] + legs[-1][1]
            actuators = _after(legs[-1][2], legs[-1][1])
            leg = 1 - legs[-1][3]
        if not legs:
            return None
        return self._assemble(legs[-1][0] + legs[-1][1], legs, np.concatenate(depths),
                              surface=None)

    def _rows_of(self, glide: Glide) -> np.ndarray:
        rows = self._rows.get(id(glide))
        if rows is None:
            rows = self._rows[id(glide)] = squeezed_rows(glide,
                                                         self.glider.vehicle.flight.trim_cc)
        return rows

    def _depths(self, glide: Glide, depth: float, ticks: int) -> np.ndarray:
        """Depths before each of `ticks` ticks of a glide from `depth`, and after the last:
        the running sum of the depth changes, added in order as the glider adds them. A
        compressible hull's climb stops after the first depth at the surface."""
        if not glide.rigid:
            return self._climb_squeezed(glide, depth, ticks)
        changes = self._changes.get(id(glide))
        if changes is None or len(changes) <= ticks:
            n = max(2 * ticks + 2, 512)
            changes = np.concatenate([[0.0], glide.dz_m[np.minimum(np.arange(n),
                                                                    glide.settled)]])
            self._changes[id(glide)] = changes
        depths = changes[:ticks + 1].copy()
        depths[0] = depth
        return np.add.accumulate(depths, out=depths)

    def _climb_squeezed(self, glide: Glide, depth: float, ticks: int) -> np.ndarray:
        """A compressible hull's climb to the surface, tick by tick (`GliderSim.glide_rates`):
        the depths before each tick and after the last, which is the first at the surface
        (at most `ticks` ticks). Unclamped, as `_depths`: the caller clamps the last."""
        depths = [depth]
        rate, per_root, settled = self.glider.glide_rates, glide.speeds_per_root, glide.settled
        ballast, glide_s = glide.ballast_cc.tolist(), glide.glide_s.tolist()
        for t in range(ticks):
            row = min(t, settled)
            depth = depth + rate(per_root, ballast[row], glide_s[row], depth)[0]
            depths.append(depth)
            if depth <= SURFACE_DEPTH_M:
                break
        return np.array(depths)

    # ---- the route ---------------------------------------------------------------------

    def _route(self, flight: _Flight, count: int) -> _Route:
        g, route = self.glider, self.ex.route
        distance = flight.distance_m[:count]
        fix = flight.fix_at if flight.fix_at < count else -1
        if isinstance(route, pilot.NoHeading):
            positions = g.drift_along(distance, np.full(count, g.heading_rad))
            return _Route(count, None, *positions)
        c = g.current
        flown, heading, positions = native.route(
            route.points[route.k], route.radius_m, route.may_reach(), distance, fix,
            self.tick_s, (c.north_mps, c.east_mps), g.positions)
        return _Route(flown, heading, *positions)


_ROUTES = (pilot.NoHeading, pilot.Waypoints)


@dataclass
class _Route:
    """Headings flown (None: the route gives none) and positions over a run."""

    count: int
    heading: np.ndarray | None
    dr_lat: np.ndarray  # count + 1 values: before each tick and after the last
    dr_lon: np.ndarray
    lat: np.ndarray
    lon: np.ndarray

    def positions_at(self, tick: int) -> tuple[float, float, float, float]:
        return (float(self.dr_lat[tick]), float(self.dr_lon[tick]), float(self.lat[tick]),
                float(self.lon[tick]))


class _Readings:
    """The sensor array over a run: each sensor's value per tick as the science computer
    sends it (through binary32), and as the executor holds it (a sensor not sent keeps
    its last value). Filled in as the run is computed: the sensors sent, flight, CTD,
    route."""

    def __init__(self, fast: FastForward, time_s: np.ndarray, missiontime: np.ndarray) -> None:
        self.fast, self.time_s, self.missiontime = fast, time_s, missiontime
        self.sent: np.ndarray | None = None  # each tick's mask of the sensors sent
        # the held event over the run: whether it fires each tick, the values it assigns,
        # and the variables as each tick's events see them
        self.held_fires: np.ndarray | None = None
        self.assigned: dict[str, np.ndarray] = {}
        self.seen: dict[str, np.ndarray] = {}
        self.flight: _Flight | None = None
        self.depth_reading: np.ndarray | None = None
        self.ctd = None
        self.nav: _Route | None = None

    def sensor(self, index: int, first: int, stop: int) -> np.ndarray:
        """Sensor `index`'s value sent at ticks first..stop-1 (binary32)."""
        if index == _S.MISSIONTIME:
            return self.missiontime[first:stop]
        f, ctd, g = self.flight, self.ctd, self.fast.glider
        n = stop - first
        match index:
            case _S.DEPTH:
                return self.depth_reading[first:stop]
            case _S.PITCH:
                return _f32(f.pitch_rad[first:stop])
            case _S.HEADING:  # the glider's heading at the tick's start: the last one steered
                steered = None if self.nav is None else self.nav.heading
                if steered is None:
                    return np.full(n, _f32_scalar(g.heading_rad))
                return _f32(np.concatenate([[g.heading_rad], steered])[first:stop])
            case _S.ALTITUDE:
                floor = self.fast.science.floor
                if floor is None:
                    return np.full(n, math.nan)
                return _f32(floor.depth_along(self.time_s[first:stop]) - f.depth_m[first:stop])
            case _S.LAT | _S.LON:
                degrees = (self.nav.dr_lat if index == _S.LAT else self.nav.dr_lon)[first:stop]
                return _f32(degrees_to_ddmm_array(degrees))
            case _S.BATTERY:
                return np.full(n, _f32_scalar(BATTERY_V))
            case _S.TEMP:
                return _f32(ctd.measured_c[first:stop])
            case _S.CONDUCTIVITY:
                from gliderplan.sim.science import conductivity_s_m

                return _f32(conductivity_s_m(ctd.measured_c[first:stop],
                                             ctd.salinity_psu[first:stop]))
            case _S.SALINITY:
                return _f32(ctd.salinity_psu[first:stop])
            case _S.CURRENT:
                return np.full(n, _f32_scalar(self.fast._current_reading))
            case _S.HALFCYCLE:  # the runtime's own: the legs its yo has begun, as before a tick
                return halfcycles(self.fast.ex.routine, f)[first:stop]
            case _S.WPTREACHED:  # the runtime's own: a run ends before a waypoint is reached
                return np.full(n, float(self.fast.ex.route.reached))
            case _S.WPTDIST:  # the runtime's own, from this tick's position readings
                route = self.fast.ex.route
                return np.array([route.distance_m(a, b) for a, b in zip(
                    self.sensor(_S.LAT, first, stop).tolist(),
                    self.sensor(_S.LON, first, stop).tolist(), strict=True)])
            case _S.TIMEOFDAY:
                return _f32(np.fmod(self.fast.science.start_epoch_s + self.time_s[first:stop],
                                    SECONDS_PER_DAY))
        return np.full(n, _f32_scalar(CONSTANT_READINGS[index]))

    def sensor_at(self, index: int, tick: int) -> float:
        """Sensor `index`'s value sent at one tick of the run (binary32)."""
        if index in CONSTANT_READINGS:
            return _F32_CONSTANTS[index]
        f = self.flight
        match index:
            case _S.MISSIONTIME:
                return float(self.missiontime[tick])
            case _S.DEPTH:
                return float(self.depth_reading[tick])
            case _S.PITCH:
                return _f32_scalar(float(f.pitch_rad[tick]))
            case _S.ALTITUDE:
                floor = self.fast.science.floor
                if floor is None:
                    return math.nan
                return _f32_scalar(floor.depth_at(float(self.time_s[tick]))
                                   - float(f.depth_m[tick]))
            case _S.LAT | _S.LON:
                nav = self.nav
                return _f32_scalar(degrees_to_ddmm(float(
                    (nav.dr_lat if index == _S.LAT else nav.dr_lon)[tick])))
            case _S.BATTERY:
                return _F32_BATTERY
        return float(self.sensor(index, tick, tick + 1)[0])

    def hold(self, held: _Held, count: int) -> None:
        """The held event over the first `count` ticks: it fires on every tick its
        condition holds (the run ends before any other event fires), and each tick's
        events see the variables as the last firing before that tick left them."""
        s = {index: self.held(index, count) for index in held.reads}
        before = self.fast.ex.machine.variables
        self.held_fires = held.fires(s, before, count)
        fired = np.where(self.held_fires, np.arange(count), -1)
        last = np.concatenate([[-1], np.maximum.accumulate(fired)[:-1]])  # before each tick
        for name, value in held.values:
            self.assigned[name] = value(s, before, count)
            self.seen[name] = np.where(last >= 0, self.assigned[name][np.maximum(last, 0)],
                                       before[name])

    def variables(self, count: int) -> Mapping[str, float | np.ndarray]:
        """The variables as the events of the first `count` ticks see them."""
        before = self.fast.ex.machine.variables
        if not self.seen:
            return before
        return {**before, **{name: v[:count] for name, v in self.seen.items()}}

    def commit_held(self, count: int) -> None:
        """The executor after the held event's firings in the first `count` ticks."""
        if self.held_fires is None:
            return
        fired = np.flatnonzero(self.held_fires[:count])
        if len(fired):
            ex = self.fast.ex
            ex.event_count += len(fired)
            ex.machine = replace(ex.machine, variables={
                **ex.machine.variables,
                **{name: float(v[fired[-1]]) for name, v in self.assigned.items()}})

    def held(self, index: int, count: int) -> np.ndarray:
        """Sensor `index` as the executor holds it over the first `count` ticks."""
        values = self.sensor(index, 0, count)
        if index in _RUNTIME_READINGS or SENT_ALWAYS_MASK >> index & 1:
            return values
        sent = self.sent[:count] >> index & 1 != 0
        if sent.all():
            return values
        before = self.fast.ex.s[index]
        last = np.maximum.accumulate(np.where(sent, np.arange(count), -1))
        return np.where(last >= 0, values[np.maximum(last, 0)], before)


# The stages of a run after which readings are known: the schedule (missiontime, the clock,
# the waypoints reached, which no tick of a run changes), the flight (depth, pitch,
# altitude, the fixed readings), the CTD, the route (position, heading).
_SCHEDULE, _FLIGHT, _CTD, _NAV = range(4)
_STAGE_OF = {_S.MISSIONTIME: _SCHEDULE, _S.TIMEOFDAY: _SCHEDULE, _S.WPTREACHED: _SCHEDULE,
             _S.TEMP: _CTD, _S.CONDUCTIVITY: _CTD, _S.SALINITY: _CTD, _S.LAT: _NAV, _S.LON: _NAV,
             _S.HEADING: _NAV, _S.WPTDIST: _NAV}


@dataclass(frozen=True)
class _Held:
    """An event that only assigns variables from readings and variables it does not
    assign (a sample held: `case depth < 8 set surface_temp = temp`): runs go on through
    the ticks on which it fires, each later tick seeing the variables as it left them."""

    stage: int  # at which its readings are known
    fires: Callable  # (s, v, n) -> whether its condition holds on each of n ticks
    values: tuple[tuple[str, Callable], ...]  # (variable, (s, v, n) -> its values)
    reads: frozenset[int]  # the sensors it reads


@dataclass(frozen=True)
class _Events:
    """A state's events for runs of ticks: in groups by the stage of a run at which all
    they read is known (per stage a checker of the group and the sensors it reads, or
    None), and the one event a run may fly through, if any."""

    stages: tuple[tuple | None, ...]
    held: _Held | None


def _stage(sensors: frozenset[int]) -> int:
    return max((_STAGE_OF.get(s, _FLIGHT) for s in sensors), default=_SCHEDULE)


def _staged(state: ir.State) -> _Events:
    """The state's events for runs: every event but the held one (the first that assigns
    and does nothing else, whose assignments neither it nor the state's profiles read)
    ends a run before the first tick on which it holds; an event that reads what the held
    one assigns is checked from the held one's stage on."""
    held, assigned = None, frozenset()
    for event in state.events:
        names = frozenset(a.variable for a in event.assignments)
        read = frozenset().union(*(ir.variables_read(x) for x in (
            event.condition, *(a.value for a in event.assignments))))
        if event.action is None and names and not names & (read | set(state.profile_variables)):
            sensors = compiled.sensors_read([event.condition,
                                             *(a.value for a in event.assignments)])
            held = _Held(_stage(sensors), compiled.firing_ticks([event]),
                         tuple((a.variable, compiled.value_ticks(a.value))
                               for a in event.assignments), sensors)
            held_event, assigned = event, names
            break
    groups: list[list[ir.Event]] = [[] for _ in range(4)]
    for event in state.events:
        if held is not None and event is held_event:
            continue
        stage = _stage(compiled.sensors_read([event.condition]))
        if ir.variables_read(event.condition) & assigned:
            stage = max(stage, held.stage)
        groups[stage].append(event)
    return _Events(tuple((compiled.firing_ticks(g), compiled.sensors_read(
        [e.condition for e in g])) if g else None for g in groups), held)


# the science computer's fixed readings (sim/science.py, `readings`)
_F32_CONSTANTS = {k: _f32_scalar(v) for k, v in CONSTANT_READINGS.items()}
_F32_BATTERY = _f32_scalar(BATTERY_V)


def _covered(profile: ir.Profile) -> bool:
    """Whether runs of ticks compute this profile (else it is flown tick by tick)."""
    return profile.kind in ("yo", "surface") and not compiled.sensors_read(profile.args)


def _reaches(depth_m: float, edge: float, diving: bool) -> bool:
    """Whether the reading of this depth (clamped at 0, through binary32) reaches a yo
    band's edge: decided in double precision where binary32's rounding (6e-8 relative)
    cannot change the answer."""
    reading = depth_m if depth_m > 0.0 else 0.0
    if abs(reading - edge) <= 1e-6 * max(1.0, abs(edge)):
        reading = _f32_scalar(reading)
    return reading >= edge if diving else reading <= edge


def _positive(x: np.ndarray) -> np.ndarray:
    """max(0.0, x) as Python picks: x if x > 0 else 0.0."""
    return np.where(x > 0.0, x, 0.0)


def _powered(sensor_power: np.ndarray) -> np.ndarray:
    """`powered_mask` of each COMMAND's sensor power."""
    if (sensor_power == sensor_power[0]).all():
        return np.full(len(sensor_power), powered_mask(int(sensor_power[0])), np.int64)
    mask = np.full(len(sensor_power), SENT_ALWAYS_MASK, np.int64)
    for bits in DEVICE_MASKS.values():
        mask |= np.where(sensor_power & bits != 0, bits, 0)
    return mask


def _first(flags: np.ndarray, default: int) -> int:
    """Index of the first true flag, else `default`."""
    if not len(flags):
        return default
    at = int(np.argmax(flags))  # stops at the first true one
    return at if flags[at] else default


def _last(flags: np.ndarray) -> int:
    hit = np.flatnonzero(flags)
    return int(hit[-1]) if len(hit) else -1
