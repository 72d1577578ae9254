"""The closed loop: the science computer sends a SENSORS frame, a runtime (the Python
executor, or the compiled C runtime behind the pty) answers a COMMAND, the glider flies
it for one tick. The simulator owns the clock, so a run is lock-step and deterministic
for its seed. Records the transition trace and one row per tick."""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

import numpy as np

from gliderplan.contract import (
    DEFAULT_HORIZON_S,
    MAX_SIMULATED_TICKS,
    NO_STATE,
    TICK_S,
    TRANSITION_NAMES,
    TransitionKind,
)
from gliderplan.language import ir
from gliderplan.language.semantics import MissionFault, Transition, start
from gliderplan.power_models.flight import DensityProfile
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.runtime.protocol import Command
from gliderplan.sim.currents import CurrentField
from gliderplan.sim.geo import ddmm_to_degrees, move_degrees
from gliderplan.sim.ocean import Ocean, SeaFloor
from gliderplan.sim.science import ScienceComputer, SensorNoise
from gliderplan.sim.vehicle import Current, GliderSim

if TYPE_CHECKING:
    from gliderplan.sim.bathymetry import Bathymetry

_COMMAND_F32 = struct.Struct("<6f")
PROGRESS_TICKS = 50_000  # report progress this often on long runs


class Runtime(Protocol):
    # the transitions (kind, from, to, stack depth codes) the last step made before its
    # COMMAND's (an event's, on the tick the envelope ended the mission)
    superseded: list[tuple[int, int, int, int]]

    def step(self, tick: int, mask: int, values: list[float]) -> Command: ...


DEFAULT_START_EPOCH_S = 946684800.0  # a run that names no start: 2000-01-01T00:00:00Z


@dataclass(frozen=True)
class RunConfig:
    tick_s: float = TICK_S
    duration_s: float = DEFAULT_HORIZON_S  # the run ends here if the mission has not exited
    seed: int = 0
    noise: SensorNoise = SensorNoise()
    current: Current = Current()  # a constant current, or where `currents` gives none
    # a current varying in space and time (sim.currents); None: `current` everywhere
    currents: CurrentField | None = None
    # the glider's current correction (`u_use_current_correction`): dead reckoning with
    # the current measured at each fix, and heading upstream of its waypoint
    current_correction: bool = True
    start_lat_deg: float | None = None  # None: 500 m south of the mission's first point
    start_lon_deg: float | None = None
    start_epoch_s: float = DEFAULT_START_EPOCH_S  # UTC of missiontime 0 [s since 1970]
    floor: SeaFloor | Bathymetry | None = None  # the sea floor (None: none)
    # the in-situ density flown through (None: uniform water of the vehicle's reference)
    water: DensityProfile | None = None

    def __post_init__(self) -> None:
        """A run too long to hold is refused before it starts (MAX_SIMULATED_TICKS)."""
        ticks = self.duration_s / self.tick_s
        if ticks > MAX_SIMULATED_TICKS:
            from gliderplan.contract.errors import UsageError

            raise UsageError(
                f"a run of {self.duration_s / 86400:.4g} d at a {self.tick_s:g} s tick is "
                f"{ticks:,.0f} ticks, more than the {MAX_SIMULATED_TICKS:,} one run holds in "
                "memory (one row a tick): fly a shorter time (--duration, the mission's horizon) "
                "or a longer tick (--tick)")


@dataclass
class RunRecord:
    """What happened: the trace, per-tick columns, how the run ended."""

    trace: list[Transition]
    columns: dict[str, np.ndarray]
    state_names: tuple[str, ...]
    tick_s: float
    ended: str  # "exit", "reserve", "envelope", "duration", "interrupted" or "fault: ..."
    surfacings: int
    faults: dict | None = None  # with injected faults: what they did (CRuntime.report)
    events_log: str | None = None  # with faults: the C runtime's own event log
    suspends: int = 0  # ticks after which the runtime put the board to sleep
    # state -> the variables as it was first entered (the Python executor's; None for
    # the C runtime, whose variables the link does not carry)
    entry_variables: dict[str, dict[str, float]] | None = None
    # events the Python executor fired, as its COMMANDs count them (None for the C runtime)
    events_fired: int | None = None
    grounded_ticks: int = 0  # ticks the glider ended at the sea floor
    first_grounded_s: float = math.nan  # missiontime [s] of the first of them
    # what the envelope guard did, as the runtime said it ("envelope: missiontime ...")
    envelope: list[str] = field(default_factory=list)

    @property
    def flown_s(self) -> float:
        """[s] mission time up to which the run flew: its ticks' end, less half a tick."""
        return len(self.columns["time_s"]) * self.tick_s - self.tick_s / 2

    @property
    def envelope_acted(self) -> bool:
        """Whether the envelope guard held a command or ended the run on one."""
        return bool(self.envelope) or self.ended == "envelope"

    def visits(self) -> dict[str, int]:
        """Stays in each state flown: every transition into it (the start, a goto, a call,
        a return to the caller)."""
        stays = dict.fromkeys(self.state_names, 0)
        for transition in self.trace:
            if transition.to_state:
                stays[transition.to_state] += 1
        return stays


def start_position(mission: ir.CheckedMission, config: RunConfig) -> tuple[float, float]:
    """Where the glider is put in the water [deg]."""
    if config.start_lat_deg is not None and config.start_lon_deg is not None:
        return config.start_lat_deg, config.start_lon_deg
    if mission.start_deg is not None:
        return mission.start_deg
    points = route_points_deg(mission)
    if points:
        return move_degrees(*points[0], -500.0, 0.0)
    return 0.0, 0.0


def route_points_deg(mission: ir.CheckedMission) -> list[tuple[float, float]]:
    """The mission's waypoints (lat, lon) [deg], state by state."""
    points = []
    for state in mission.states:
        route = state.route
        ddmm = [(route.params[0], route.params[1])] if route.kind == "nav" else \
            list(route.points or ())
        points += [(ddmm_to_degrees(lat), ddmm_to_degrees(lon)) for lat, lon in ddmm]
    return points


# One row per tick: the glider before the tick's step, the COMMAND that answered it, the
# step's outputs. Python numbers in the tick-by-tick loop, these types in the record.
# The narrowest type that holds each: a month of ticks is 650,000 rows.
COLUMN_TYPES: dict[str, type] = {
    "depth_m": np.float64, "pitch_rad": np.float64, "temperature_c": np.float64,
    "temp_reading_c": np.float64, "state": np.int16, "stack_depth": np.int8,
    "profile": np.int8, "sensor_power": np.int32, "phase": np.int8,
    "pumped_out_cc": np.float64, "pumped_in_cc": np.float64, "inflection": np.bool_,
    "lat_deg": np.float64, "lon_deg": np.float64,
    "propulsion_w": np.float64,  # the propeller's or thruster's draw [W] (0: none)
}


class Columns:
    """The record's columns as they grow: rows appended one tick at a time (`rows`, lists
    of Python numbers), written into arrays sized for the whole run."""

    def __init__(self, ticks: int) -> None:
        self.rows: dict[str, list] = {k: [] for k in COLUMN_TYPES}
        self._arrays = {k: np.empty(ticks, t) for k, t in COLUMN_TYPES.items()}
        self._filled = 0

    def _flush_rows(self) -> None:
        n = min(len(v) for v in self.rows.values())  # an interrupted tick's row is not whole
        at = self._filled
        for key, values in self.rows.items():
            if n:
                self._arrays[key][at:at + n] = values[:n]
            values.clear()  # the same list: appends bound to it stay valid
        self._filled += n

    def arrays(self) -> dict[str, np.ndarray]:
        """Every column over the ticks whose rows are complete (an interruption may have
        left the last tick's row half written)."""
        self._flush_rows()
        return {k: v[:self._filled] for k, v in self._arrays.items()}


class Gauge(Protocol):
    """The battery's coulomb counter (sim.energy.BatteryGauge)."""

    reserve_j: float
    counted: int  # the ticks billed: the reading is of the ticks before this one

    def reading(self, tick: int, columns: Columns) -> float: ...


@dataclass(frozen=True)
class Surfaced:
    """The glider at a surfacing, before the next tick is flown: the coulomb counter's
    reading `left_j` [J] and the tick `read_tick` before which it was last brought up to
    date, the true position [deg] and the columns of every tick flown (arrays, one row a
    tick)."""

    read_tick: int
    left_j: float
    lat_deg: float
    lon_deg: float
    columns: Mapping[str, np.ndarray]


class SurfacingHook(Protocol):
    def __call__(self, surfaced: Surfaced) -> None:
        """The glider has surfaced (the shore's turn: telemetry up, a plan update down)."""
        ...


def simulate(mission: ir.CheckedMission, runtime: Runtime, science: ScienceComputer,
             config: RunConfig, progress: Callable[[float, float], None] | None = None,
             gauge: Gauge | None = None, on_surfacing: SurfacingHook | None = None,
             keep_interrupted: bool = False) -> RunRecord:
    """Run the loop until the mission exits (or its energy guard ends it), the runtime
    faults or the duration ends. KeyboardInterrupt (Ctrl-C, SIGTERM) goes through, but
    with `keep_interrupted` it ends the run, which the record says ("interrupted"): the
    caller writes the part flown and marks it partial (never a result of its own).
    `gauge` gives the science computer its `energy_left` reading (NaN without one).
    `on_surfacing` (with a `gauge`) is called once per surfacing, before the first tick
    flown after the loop sees the glider at the surface."""
    names = tuple(s.name for s in mission.states)
    glider = science.glider
    tick_s = config.tick_s
    last_tick = int(math.floor(config.duration_s / tick_s + 1e-9))
    trace: list[Transition] = []
    columns = Columns(last_tick + 1)
    cols = columns.rows
    depth_c, pitch_c, temp_c = cols["depth_m"], cols["pitch_rad"], cols["temperature_c"]
    reading_c = cols["temp_reading_c"]
    state_c, stack_c, profile_c = cols["state"], cols["stack_depth"], cols["profile"]
    power_c, phase_c = cols["sensor_power"], cols["phase"]
    out_c, in_c, infl_c = cols["pumped_out_cc"], cols["pumped_in_cc"], cols["inflection"]
    motor_c = cols["propulsion_w"]
    lat_c, lon_c = cols["lat_deg"], cols["lon_deg"]
    ended = "duration"
    pack, unpack = _COMMAND_F32.pack, _COMMAND_F32.unpack
    readings, runtime_step, apply = science.readings, runtime.step, science.apply
    tick = 0
    last_state = NO_STATE
    surfaced = glider.surfacings
    try:
        while tick <= last_tick:
            energy_left = math.nan if gauge is None else gauge.reading(tick, columns)
            if on_surfacing is not None and glider.surfacings != surfaced:
                surfaced = glider.surfacings
                on_surfacing(Surfaced(gauge.counted, energy_left, glider.lat_deg,
                                      glider.lon_deg, columns.arrays()))
            science.energy_left_j = energy_left
            mask, values = readings(tick)
            depth_c.append(glider.depth_m)
            pitch_c.append(glider.pitch_rad)
            temp_c.append(science.water_temperature_c)
            reading_c.append(science.ctd_temperature_c)
            lat_c.append(glider.lat_deg)
            lon_c.append(glider.lon_deg)
            try:
                cmd = runtime_step(tick, mask, values)
            except MissionFault as fault:
                ended = f"fault: {fault}"
                _close_row(cols, last_state)
                break
            time_s = tick * tick_s
            if tick == 0:
                trace.append(start(mission, time_s)[1])
            # an event's transition on the tick the envelope ended the mission, then the end
            for kind, src, dst, depth in (*runtime.superseded, (
                    cmd.transition, cmd.from_state, cmd.to_state, cmd.stack_depth)):
                if kind > TransitionKind.START:
                    trace.append(Transition(time_s, TRANSITION_NAMES[kind], names[src],
                                            "" if dst == NO_STATE else names[dst], depth))
            last_state = cmd.state
            state_c.append(cmd.state)
            stack_c.append(cmd.stack_depth)
            profile_c.append(cmd.profile)
            power_c.append(cmd.sensor_power)
            if cmd.state == NO_STATE:
                ended = {TransitionKind.RESERVE: "reserve",
                         TransitionKind.ENVELOPE: "envelope"}.get(cmd.transition, "exit")
                phase_c.append(glider.phase)
                out_c.append(0.0)
                in_c.append(0.0)
                infl_c.append(False)
                motor_c.append(0.0)
                break
            target, pitch, ballast, heading, speed, thrust = unpack(pack(
                cmd.depth_target_m, cmd.pitch_rad, cmd.ballast_cc, cmd.heading_rad,
                cmd.speed_mps, cmd.thrust_w))
            apply(target, pitch, ballast, heading, cmd.flags, cmd.sensor_power, speed, thrust)
            phase_c.append(glider.phase)
            out_c.append(glider.pumped_out_cc)
            in_c.append(glider.pumped_in_cc)
            infl_c.append(glider.inflection)
            motor_c.append(glider.propulsion_w)
            if progress is not None and tick % PROGRESS_TICKS == 0 and tick:
                progress(time_s, last_tick * tick_s)
            tick += 1
    except KeyboardInterrupt:  # keep what was flown: the caller writes it out
        if not keep_interrupted:
            raise
        ended = "interrupted"
    arrays = columns.arrays()
    n = len(arrays["state"])
    record = RunRecord(trace, {"time_s": np.arange(n, dtype=float) * tick_s, **arrays}, names,
                       tick_s, ended, glider.surfacings, suspends=getattr(runtime, "suspends", 0),
                       grounded_ticks=science.grounded_ticks,
                       first_grounded_s=science.first_grounded_s)
    record.trace = [t for t in trace if t.time_s < record.flown_s]
    return record


def _close_row(cols: dict[str, list], state: int) -> None:
    """Complete the row of a tick whose runtime faulted (the glider's own control flies on)."""
    for key, value in (("state", state), ("stack_depth", 0), ("profile", 0),
                       ("sensor_power", 0), ("phase", 0), ("pumped_out_cc", 0.0),
                       ("pumped_in_cc", 0.0), ("inflection", False), ("propulsion_w", 0.0)):
        cols[key].append(value)


def make_science(mission: ir.CheckedMission, ocean: Ocean, config: RunConfig,
                 vehicle: Vehicle) -> ScienceComputer:
    """The science computer over a glider put in the water at the mission's start."""
    lat, lon = start_position(mission, config)
    glider = GliderSim(vehicle, config.tick_s, lat, lon, config.current, water=config.water,
                       correction_speed_mps=correction_speed_mps(vehicle)
                       if config.current_correction and mission.current_correction else 0.0)
    return ScienceComputer(glider, ocean, config.noise, config.seed, config.tick_s,
                           config.start_epoch_s, config.floor, config.currents)


def correction_speed_mps(vehicle: Vehicle) -> float:
    """[m s-1] the speed through the water a glider's current correction steers with: its
    horizontal speed at its nominal pitch on a full pump stroke (a Slocum steers with its
    own speed estimate, which a steady glide keeps near this). A vehicle without a buoyancy
    engine (an AUV) steers with the speed it cruises at without a plan (`GliderSim.step`
    steers a propelled tick with the speed commanded)."""
    if not vehicle.has_buoyancy_engine:
        from gliderplan.planner.speed import best_speed
        from gliderplan.power_models.devices import base_power_w

        return float(best_speed(vehicle.propulsion, base_power_w(vehicle)).speed_mps)
    return float(vehicle.max_speed_mps(vehicle.nominal_pitch_rad))
