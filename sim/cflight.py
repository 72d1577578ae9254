"""The simulated flight in C: the glider, its science computer, its battery and the
runtime's own step, tick after tick in one loop (sim/flight.c, in the step library).

Each tick is the tick of `sim.loop.simulate` flying the runtime's step, bit for bit: the
same operations in the same order on the same doubles, through the same C library, with
the Python models (sim/vehicle.py, sim/science.py, sim/ocean.py, sim/energy.py) as the
reference (tests/test_sim_differential.py holds them together). Python sets the flight up
from those models, gives the loop what only Python computes (blocks of random numbers from the
run's numpy generators; the glide speeds at a pitch, solved by `power_models.flight`),
and takes the record back.
"""

from __future__ import annotations

import ctypes
import math
from collections.abc import Callable

import numpy as np

from gliderplan.contract import (
    EARTH_RADIUS_M,
    MAX_STATES,
    N_SENSORS,
    NO_STATE,
    TRANSITION_NAMES,
    Component,
    TransitionKind,
)
from gliderplan.language import ir
from gliderplan.language.semantics import Transition
from gliderplan.power_models.segments import MIN_PUMPED_CC
from gliderplan.sim import vehicle as glider_model
from gliderplan.sim.cstep import CStep, Report, fault_message, step_library
from gliderplan.sim.energy import DEVICE_BITS, Billing
from gliderplan.sim.loop import (
    COLUMN_TYPES,
    PROGRESS_TICKS,
    RunConfig,
    RunRecord,
    Surfaced,
    SurfacingHook,
)
from gliderplan.sim.ocean import MeasuredProfile, Thermocline
from gliderplan.sim.science import (
    BATTERY_V,
    CONSTANT_READINGS,
    SENT_ALWAYS_MASK,
    ScienceComputer,
)

WAVES = 8  # GPS_WAVES
DEVICES = 8  # GPS_DEVICES
TRACE = 1024  # GPS_TRACE
RAN, ENDED, FAULT, NEED_NOISE, NEED_PITCH, TRACE_FULL, DONE, ENVELOPE, SURFACED = range(9)

_double, _int, _uint, _pointer = ctypes.c_double, ctypes.c_int32, ctypes.c_uint32, \
    ctypes.c_void_p


class _Physics(ctypes.Structure):
    """sim/flight.c's gps_physics, field for field."""

    _fields_ = [
        ("tick_s", _double),
        *((name, _double) for name in (
            "pump_rate_cc_s", "climb_pitch_error_rad", "dive_pitch_error_rad",
            "bottom_turn_s", "top_turn_s", "surface_s", "iridium_s", "rho_kg_m3", "g_m_s2",
            "hull_volume_cc", "compressibility_per_pa", "trim_cc", "surface_depth_m",
            "hover_rate_m_s", "pitch_rate_rad_s", "min_pumped_cc", "earth_radius_m",
            "current_north_mps", "current_east_mps", "correction_speed_mps")),
        ("lift_cc", _pointer), ("n_lift", _int), ("lift_step_m", _double),
        ("floor_times_s", _pointer), ("floor_depths_m", _pointer), ("n_floor", _int),
        *((name, _double) for name in ("surface_c", "deep_c", "thermocline_m", "thickness_m",
                                       "surface_psu", "deep_psu")),
        ("n_waves", _int),
        ("wave_amplitude_m", _double * WAVES), ("wave_period_s", _double * WAVES),
        ("wave_phase_rad", _double * WAVES),
        ("depths_m", _pointer), ("casts_s", _pointer), ("temperatures_c", _pointer),
        ("salinities_psu", _pointer), ("n_depths", _int), ("n_casts", _int),
        *((name, _double) for name in ("temperature_sigma_c", "depth_sigma_m", "spike_c",
                                       "lag_keep", "start_epoch_s")),
        ("spikes", _int), ("constant", _double * N_SENSORS), ("sent_always", _uint),
        ("device_bits", _uint * DEVICES), ("n_devices", _int),
        *((name, _double) for name in ("gliding_w", "surface_w", "iridium_w", "pitch_energy_j",
                                       "pump_out_j_per_cc", "pump_out_j_per_cc_m",
                                       "pump_in_j_per_cc", "pump_in_j_per_cc_m")),
        ("computer_w", _double * MAX_STATES), ("boot_j", _double), ("computer_billed", _int),
        ("device_on_w", _double * DEVICES), ("device_warmup_j", _double * DEVICES),
        ("battery_j", _double), ("last_tick", _int),
    ]


class _Transition(ctypes.Structure):
    _fields_ = [("tick", ctypes.c_uint32), ("kind", ctypes.c_uint8),
                ("from_state", ctypes.c_uint8), ("to_state", ctypes.c_uint8),
                ("depth", ctypes.c_uint8)]


def _declare(library: ctypes.CDLL) -> ctypes.CDLL:
    if getattr(library, "_flight_declared", False):
        return library
    for name, result, arguments in (
            ("gps_flight_size", ctypes.c_size_t, []),
            ("gps_physics_size", ctypes.c_size_t, []),
            ("gps_flight_start", None, [_pointer, _pointer, _pointer]),
            ("gps_flight_speeds", None, [_pointer, _double, _double, _double]),
            ("gps_flight_noise", None, [_pointer, _pointer, _pointer]),
            ("gps_flight_status", None, [_pointer, _pointer]),
            ("gps_flight_set", None, [_pointer, _pointer]),
            ("gps_flight_noise_at", None, [_pointer, _pointer]),
            ("gps_flight_report", None, [_pointer, _pointer]),
            ("gps_flight_stop_at_surfacings", None, [_pointer]),
            ("gps_flight_surfaced", None, [_pointer, _pointer]),
            ("gps_flight_take_trace", _int, [_pointer, _pointer]),
            ("gps_fly", _int, [_pointer, _int])):
        function = getattr(library, name)
        function.restype, function.argtypes = result, arguments
    library._flight_declared = True
    return library


def flight_context_bytes() -> int:
    """The size of a flight's context, which begins with the step's (CStep)."""
    return _declare(step_library()).gps_flight_size()


def flies_in_c(science: ScienceComputer) -> bool:
    """Whether the loop in C models this flight (else the Python loop flies the same step):
    a glider without a propeller or thruster (their models are Python's), in a constant
    current (a current field is looked up where the glider is), over a floor that varies in
    time only (a bathymetry grid is looked up where it is), in water it models."""
    if science.glider.vehicle.propulsion is not None or science.currents is not None \
            or science.floor_by_position:
        return False
    ocean = science.ocean
    if isinstance(ocean, Thermocline):
        return len(ocean.waves) <= WAVES
    return isinstance(ocean, MeasuredProfile)


def _doubles(values) -> np.ndarray:
    return np.ascontiguousarray(values, dtype=np.float64)


def _address(array: np.ndarray) -> int:
    return array.__array_interface__["data"][0]


class CFlight:
    """One flight of the runtime's `step` in the C loop, set up from the Python models:
    the science computer `science` (its glider, ocean, floor and random generators as
    `sim.loop.make_science` put them in the water) and the battery's bill `billing`."""

    def __init__(self, mission: ir.CheckedMission, step: CStep, science: ScienceComputer,
                 billing: Billing, battery_j: float, config: RunConfig) -> None:
        self.library = library = _declare(step_library())
        if library.gps_physics_size() != ctypes.sizeof(_Physics):
            raise RuntimeError("sim/flight.c's gps_physics and sim/cflight.py's disagree")
        self.mission, self.step, self.science = mission, step, science
        self.tick_s = config.tick_s
        self.last_tick = int(math.floor(config.duration_s / config.tick_s + 1e-9))
        self._keep: list[np.ndarray] = []  # arrays the loop reads: alive as long as it runs
        self._normal = self._spikes = None  # the blocks of random numbers in use
        self.physics = self._physics(science, billing, battery_j, config)
        self.columns = {k: np.empty(self.last_tick + 1, t) for k, t in COLUMN_TYPES.items()}
        pointers = (_pointer * len(COLUMN_TYPES))(*(_address(a) for a in self.columns.values()))
        self._pointers = pointers
        library.gps_flight_start(step.context, ctypes.byref(self.physics), pointers)
        glider = science.glider
        self._set_glider(glider)

    def _set_glider(self, glider: glider_model.GliderSim) -> None:
        """The glider and the science computer as the Python models start them."""
        science = self.science
        values = (_double * 11)(glider.depth_m, glider.pitch_rad, glider.ballast_cc,
                                glider.heading_rad, glider.lat_deg, glider.lon_deg,
                                glider.dr_lat_deg, glider.dr_lon_deg, science.flicker_c,
                                glider.measured.north_mps, glider.measured.east_mps)
        self.library.gps_flight_set(self.step.context, values)

    def _keep_array(self, values) -> int:
        array = _doubles(values)
        self._keep.append(array)
        return _address(array)

    def _physics(self, science: ScienceComputer, billing: Billing, battery_j: float,
                 config: RunConfig) -> _Physics:
        glider, vehicle = science.glider, science.glider.vehicle
        flight, noise, ocean = vehicle.flight, science.noise, science.ocean
        p = _Physics(tick_s=config.tick_s, pump_rate_cc_s=vehicle.pump_rate_cc_s,
                     climb_pitch_error_rad=vehicle.climb_pitch_error_rad,
                     dive_pitch_error_rad=vehicle.dive_pitch_error_rad,
                     bottom_turn_s=vehicle.bottom_turn_s, top_turn_s=vehicle.top_turn_s,
                     surface_s=vehicle.surface_s, iridium_s=vehicle.iridium_s,
                     rho_kg_m3=flight.rho_kg_m3, g_m_s2=flight.g_m_s2,
                     hull_volume_cc=flight.hull_volume_cc,
                     compressibility_per_pa=flight.compressibility_per_pa,
                     trim_cc=flight.trim_cc, surface_depth_m=glider_model.SURFACE_DEPTH_M,
                     hover_rate_m_s=glider_model.HOVER_RATE_M_S,
                     pitch_rate_rad_s=glider_model.PITCH_RATE_RAD_S,
                     min_pumped_cc=MIN_PUMPED_CC, earth_radius_m=EARTH_RADIUS_M,
                     current_north_mps=glider.current.north_mps,
                     current_east_mps=glider.current.east_mps,
                     correction_speed_mps=glider.correction_speed_mps,
                     temperature_sigma_c=noise.temperature_sigma_c,
                     depth_sigma_m=noise.depth_sigma_m, spike_c=noise.spike_c,
                     lag_keep=science.lag_keep, start_epoch_s=science.start_epoch_s,
                     spikes=int(science.spikes is not None),
                     sent_always=SENT_ALWAYS_MASK, last_tick=self.last_tick,
                     battery_j=battery_j)
        if glider.stratification is not None:
            lift = glider.stratification
            p.lift_cc, p.n_lift = self._keep_array(lift.lift_cc), len(lift.lift_cc)
            p.lift_step_m = lift.step_m
        if science.floor is not None:
            p.floor_times_s = self._keep_array(science.floor.times_s)
            p.floor_depths_m = self._keep_array(science.floor.depths_m)
            p.n_floor = len(science.floor.times_s)
        if isinstance(ocean, Thermocline):
            p.surface_c, p.deep_c = ocean.surface_c, ocean.deep_c
            p.thermocline_m, p.thickness_m = ocean.depth_m, ocean.thickness_m
            p.surface_psu, p.deep_psu = ocean.surface_psu, ocean.deep_psu
            p.n_waves = len(ocean.waves)
            for i, wave in enumerate(ocean.waves):
                p.wave_amplitude_m[i] = wave.amplitude_m
                p.wave_period_s[i] = wave.period_s
                p.wave_phase_rad[i] = wave.phase_rad
        else:
            p.depths_m = self._keep_array(ocean.depths_m)
            p.casts_s = self._keep_array(ocean.casts_s)
            p.temperatures_c = self._keep_array(ocean.temperatures_c)
            p.salinities_psu = self._keep_array(ocean.salinities_psu)
            p.n_depths, p.n_casts = len(ocean.depths_m), len(ocean.casts_s)
        constant = [math.nan] * N_SENSORS
        for index, value in CONSTANT_READINGS.items():
            constant[index] = value
        constant[_index("battery")] = BATTERY_V
        constant[_index("current")] = science.current_reading
        p.constant[:] = constant
        devices = list(billing.sensors.items())
        p.n_devices = len(devices)
        for d, (device, sensor) in enumerate(devices):
            p.device_bits[d] = DEVICE_BITS[device]
            p.device_on_w[d] = sensor.on_power_w
            p.device_warmup_j[d] = sensor.warmup_j
        p.gliding_w, p.surface_w, p.iridium_w = billing.gliding_w, vehicle.surface_w, \
            vehicle.iridium_w
        p.pitch_energy_j = vehicle.pitch_energy_j
        p.pump_out_j_per_cc, p.pump_out_j_per_cc_m = vehicle.pump_out_j_per_cc, \
            vehicle.pump_out_j_per_cc_m
        p.pump_in_j_per_cc, p.pump_in_j_per_cc_m = vehicle.pump_in_j_per_cc, \
            vehicle.pump_in_j_per_cc_m
        p.computer_w[:len(billing.computer_w)] = billing.computer_w.tolist()
        p.boot_j = billing.boot_j
        p.computer_billed = int(Component.COMPUTER not in billing.held)
        return p

    # ---- flying ------------------------------------------------------------------------

    def fly(self, progress: Callable[[float, float], None] | None = None,
            keep_interrupted: bool = False,
            on_surfacing: SurfacingHook | None = None) -> RunRecord:
        """Fly until the mission exits (or its energy guard ends it), the runtime refuses
        an event or the run's duration ends. KeyboardInterrupt goes through, but with
        `keep_interrupted` it ends the flight, and `on_surfacing` is called at each
        surfacing, as `sim.loop.simulate`'s: the loop stops there and goes on after it."""
        library, context = self.library, self.step.context
        names = tuple(s.name for s in self.mission.states)
        trace: list[Transition] = []
        ended = "duration"
        report_at = PROGRESS_TICKS  # the tick past which progress is reported next
        if on_surfacing is not None:
            library.gps_flight_stop_at_surfacings(context)
        try:
            while True:
                status = library.gps_fly(context, PROGRESS_TICKS)
                if progress is not None:  # the loop returns often (noise, pitches, trace)
                    tick = int(self._status()[0])
                    if tick > report_at:
                        progress((tick - 1) * self.tick_s, self.last_tick * self.tick_s)
                        report_at = tick - tick % PROGRESS_TICKS + PROGRESS_TICKS
                if status == NEED_NOISE:
                    self._give_noise()
                elif status == NEED_PITCH:
                    pitch = self._status()[4]
                    u, w = self.science.glider.glide_speeds(pitch)
                    library.gps_flight_speeds(context, pitch, u, w)
                elif status == TRACE_FULL:
                    trace += self._take_trace(names)
                elif status == ENVELOPE:
                    self.step.note_envelope(self._report())
                elif status == SURFACED:
                    on_surfacing(self._surfaced())
                elif status != RAN:
                    break
            report = self._report()
            if status in (ENDED, FAULT) and report.envelope.limit:
                self.step.note_envelope(report)
            if status == ENDED:
                last = report.transitions[report.n_transitions - 1]
                ended = {TransitionKind.RESERVE: "reserve",
                         TransitionKind.ENVELOPE: "envelope"}.get(last.kind, "exit")
            elif status == FAULT and not report.fault:  # the envelope's fault action
                ended = f"fault: tick {int(self._status()[0]) - 1}: " \
                        f"{self.step.envelope_notes[-1]}"
            elif status == FAULT:
                time_s = float(np.float32((self._status()[0] - 1) * self.tick_s))
                ended = f"fault: {fault_message(self.mission, report, time_s)}"
        except KeyboardInterrupt:  # keep what was flown: the caller writes it out
            if not keep_interrupted:
                raise
            ended = "interrupted"
        trace += self._take_trace(names)
        tick, surfacings, grounded, first_grounded, _ = self._status()
        n = int(tick)
        trace = [t for t in trace if t.time_s < n * self.tick_s - self.tick_s / 2]
        columns = {"time_s": np.arange(n, dtype=float) * self.tick_s,
                   **{k: v[:n] for k, v in self.columns.items()}}
        return RunRecord(trace, columns, names, self.tick_s, ended, int(surfacings),
                         suspends=self.step.suspends, grounded_ticks=int(grounded),
                         first_grounded_s=first_grounded,
                         entry_variables=self.step.entry_variables,
                         events_fired=self.step.events_fired)

    def _surfaced(self) -> Surfaced:
        """The glider at a surfacing, before the next tick (as `sim.loop.simulate` says it)."""
        values = (_double * 4)()
        self.library.gps_flight_surfaced(self.step.context, values)
        tick = int(self._status()[0])
        return Surfaced(int(values[1]), values[0], values[2], values[3],
                        {k: v[:tick] for k, v in self.columns.items()})

    def _report(self) -> Report:
        """The report of the last tick flown."""
        report = Report()
        self.library.gps_flight_report(self.step.context, ctypes.byref(report))
        return report

    def _give_noise(self) -> None:
        """The next blocks of the science computer's random numbers the loop has used up:
        drawn from its generators in the order the Python loop draws them."""
        science, context = self.science, self.step.context
        at = (_int * 2)()
        self.library.gps_flight_noise_at(context, at)
        if at[0]:
            self._normal = _doubles(science.normal.block())
        if at[1]:
            self._spikes = _doubles(science.spikes.block())
        self.library.gps_flight_noise(context,
                                      _address(self._normal) if at[0] else None,
                                      _address(self._spikes) if at[1] else None)

    def _status(self) -> tuple[float, float, float, float, float]:
        """(next tick, surfacings, ticks grounded, first grounded [s], pitch wanted [rad])."""
        values = (_double * 5)()
        self.library.gps_flight_status(self.step.context, values)
        return tuple(values)

    def _take_trace(self, names: tuple[str, ...]) -> list[Transition]:
        buffer = (_Transition * TRACE)()
        count = self.library.gps_flight_take_trace(self.step.context, buffer)
        trace = []
        for t in buffer[:count]:
            time_s = t.tick * self.tick_s
            if t.kind == TransitionKind.START:
                trace.append(Transition(time_s, "start", "", names[t.to_state], 0))
                continue
            trace.append(Transition(time_s, TRANSITION_NAMES[t.kind], names[t.from_state],
                                    "" if t.to_state == NO_STATE else names[t.to_state],
                                    t.depth))
        return trace


def _index(name: str) -> int:
    from gliderplan.language.registry import SENSOR_BY_NAME

    return SENSOR_BY_NAME[name].index
