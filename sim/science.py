"""The science computer's side of the link: the sensor array it fills from the simulated
glider and ocean each tick, and the COMMAND fields it applies to the glider.

It sends the sensors without a device every tick and a device's sensors only while
the last COMMAND's `sensor_power` keeps that device on; a runtime keeps the last value
of a sensor it did not receive (NaN before the first), so a powered-off CTD reads stale.

Sensor models: the CTD's temperature lags the water with a first-order time constant
and carries Gaussian noise; the non-monotonic mode adds a flicker that alternates in
sign from one reading to the next (a cell that is not flushed, microstructure): larger
than the change per reading inside the thermocline, it makes every other reading go
the "wrong" way, which is what reset the naive tracker's window in the paper's first
sea trial.
The altimeter reads the height of the sea floor above the glider (the floor's depth less
the glider's, without noise), NaN where the run has no floor (out of range).
Every random number comes from one numpy Generator seeded per run: a run is
deterministic for its seed.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract import (
    FLAG_HEADING,
    FLAG_HEADING_HOLD,
    FLAG_SURFACE,
    FLIGHT_SENSORS_MASK,
    N_SENSORS,
    RUNTIME_READINGS_MASK,
)
from gliderplan.language.registry import SENSOR_BY_NAME, SENSORS
from gliderplan.sim.currents import CurrentField
from gliderplan.sim.geo import degrees_to_ddmm
from gliderplan.sim.ocean import Ocean, SeaFloor
from gliderplan.sim.vehicle import Current, GliderSim

if TYPE_CHECKING:
    from gliderplan.sim.bathymetry import Bathymetry

# sent every tick: the glider's own flight sensors (not the runtime's readings)
SENT_ALWAYS_MASK = FLIGHT_SENSORS_MASK & ~RUNTIME_READINGS_MASK
DEVICE_MASKS: dict[str, int] = {}
for _s in SENSORS:
    if _s.device is not None:
        DEVICE_MASKS[_s.device] = DEVICE_MASKS.get(_s.device, 0) | (1 << _s.index)

_TEMP_BIT = 1 << next(s.index for s in SENSORS if s.name == "temp")
BATTERY_V = 15.0  # assumption: alkaline pack voltage, constant over the run
# Readings the simulated glider holds constant, by sensor index: no roll, and the optode,
# optics, modem, DVL and microstructure logger of a quiet shelf sea without currents
# (assumption: over the ground a Slocum's ~0.35 m/s through the water, DESIGN.md section 8;
# shear 0.01 1/s, a dissipation near 1e-9 W/kg). sim/flight.c sends the same.
CONSTANT_READINGS: dict[int, float] = {SENSOR_BY_NAME[name].index: value for name, value in (
    ("roll", 0.0), ("oxygen", 250.0), ("chlorophyll", 1.0), ("backscatter", 0.001),
    ("modem", 0.0), ("groundspeed", 0.35), ("shear", 0.01))}
_ROLL, _OXYGEN, _CHLOROPHYLL, _BACKSCATTER, _MODEM, _GROUNDSPEED, _SHEAR = (
    CONSTANT_READINGS[SENSOR_BY_NAME[name].index]
    for name in ("roll", "oxygen", "chlorophyll", "backscatter", "modem", "groundspeed",
                 "shear"))
# `ScienceComputer.readings` lists every sensor's reading in the registry's order (a list
# built whole each tick, the loop's hot path): the order it writes, by name, checked here
_READINGS_ORDER = ("missiontime", "depth", "pitch", "roll", "heading", "altitude", "lat",
                   "lon", "battery", "temp", "conductivity", "salinity", "oxygen",
                   "chlorophyll", "backscatter", "current", "modem", "halfcycle", "wptdist",
                   "timeofday", "energy_left", "wptreached", "groundspeed", "shear")
if _READINGS_ORDER != tuple(s.name for s in SENSORS) or len(SENSORS) != N_SENSORS:
    raise ImportError("sim/science.py: ScienceComputer.readings lists the sensors in another "
                      "order than the registry: update _READINGS_ORDER and the list")
_NOISE_BLOCK = 4096  # random numbers drawn per numpy call
SECONDS_PER_DAY = 86400.0
# [s] between look-ups of a current field: a glider covers ~20 m in a minute, and a
# field's grid is kilometres and hours apart
CURRENT_LOOKUP_S = 60.0


@dataclass(frozen=True)
class SensorNoise:
    """How the CTD and the depth sensor err. [degC], [s], [m], probability [1]."""

    temperature_sigma_c: float = 0.0
    temperature_lag_s: float = 0.0  # first-order CTD response time
    flicker_c: float = 0.0  # non-monotonic mode: +-flicker_c alternating every reading
    depth_sigma_m: float = 0.0
    spike_probability: float = 0.0  # a reading off by +-spike_c (a fouled cell, a bubble)
    spike_c: float = 0.0


NOISE_PRESETS: dict[str, SensorNoise] = {
    "none": SensorNoise(),
    # Sea-Bird pumped CTD: ~0.5 s response, mK noise; depth sensor to a few cm
    "ctd": SensorNoise(temperature_sigma_c=0.005, temperature_lag_s=0.5, depth_sigma_m=0.02),
    # the paper's first sea trial: readings that are not monotonic within a leg
    "nonmonotonic": SensorNoise(temperature_sigma_c=0.1, temperature_lag_s=0.5, flicker_c=1.2,
                                depth_sigma_m=0.02),
}


class Draws:
    """Random numbers drawn from a generator a block at a time, one row per tick: row i is
    the same whether the rows are taken one by one (`next`) or a block at a time
    (`block`, by sim/flight.c), so a run flown either way sees the same noise."""

    def __init__(self, draw_block: Callable[[], np.ndarray]) -> None:
        self._draw_block = draw_block
        self._rows: list = []  # the current block as Python numbers
        self._at = _NOISE_BLOCK  # row of the current block taken next

    def next(self):
        """The next row, as Python numbers."""
        if self._at == _NOISE_BLOCK:
            self._rows, self._at = self._draw_block().tolist(), 0
        self._at += 1
        return self._rows[self._at - 1]

    def block(self) -> np.ndarray:
        """The next block of rows as the generator draws it (for a caller that takes the
        rows itself, sim/cflight.py, and no longer `next`)."""
        return self._draw_block()


def _spike_signs(rng: np.random.Generator, probability: float) -> np.ndarray:
    """A block of spike signs: 0, or -1 and +1 alike, with the spike probability."""
    u = rng.random((_NOISE_BLOCK, 2))
    return np.where(u[:, 0] < probability, np.where(u[:, 1] < 0.5, -1.0, 1.0), 0.0)


@functools.cache
def powered_mask(sensor_power: int) -> int:
    """Sensors sent in a tick: those without a device plus every sensor of a device that
    `sensor_power` (bit i: sensor i's device on) keeps powered."""
    mask = SENT_ALWAYS_MASK
    for bits in DEVICE_MASKS.values():
        if sensor_power & bits:
            mask |= bits
    return mask


class ScienceComputer:
    """The sensor array over a simulated glider in a simulated ocean."""

    def __init__(self, glider: GliderSim, ocean: Ocean, noise: SensorNoise, seed: int,
                 tick_s: float, start_epoch_s: float = 0.0,
                 floor: SeaFloor | Bathymetry | None = None,
                 currents: CurrentField | None = None) -> None:
        self.glider, self.ocean, self.noise, self.tick_s = glider, ocean, noise, tick_s
        self.floor = floor  # the sea floor (None: none, the altimeter out of range)
        # a bathymetry grid (sim.bathymetry): the floor under the glider where it is
        self.floor_by_position = getattr(floor, "by_position", False)
        self.currents = currents  # the current where the glider is (None: the glider's own)
        self._next_current_s = 0.0  # missiontime [s] of the next look-up in `currents`
        self.dry_lookups = 0  # look-ups that found no water (the field's land)
        self.grounded_ticks = 0  # ticks the glider ended at the floor
        self.first_grounded_s = math.nan  # missiontime [s] of the first
        self.start_epoch_s = start_epoch_s  # UTC of missiontime 0 [s since 1970]
        self.rng = np.random.default_rng(seed)
        self.sensor_power = 0  # from the last COMMAND; nothing is powered before the first
        self.lag_keep = math.exp(-tick_s / noise.temperature_lag_s) \
            if noise.temperature_lag_s > 0.0 else 0.0
        self._ctd_temp = math.nan
        self.flicker_c = noise.flicker_c if self.rng.random() < 0.5 else -noise.flicker_c
        c = glider.current
        self.current_reading = math.hypot(c.north_mps, c.east_mps)  # [m s-1]
        # (temperature, depth) standard normal draws, one row per tick
        self.normal = Draws(lambda: self.rng.standard_normal((_NOISE_BLOCK, 2)))
        # spikes come from a stream of their own: a run without them draws as before
        self.spikes: Draws | None = None
        if noise.spike_probability > 0.0:
            spike_rng = np.random.default_rng([seed, 1])
            self.spikes = Draws(lambda: _spike_signs(spike_rng, noise.spike_probability))
        self.water_temperature_c = math.nan  # at the glider, this tick (for the record)
        self.ctd_temperature_c = math.nan  # the CTD's reading sent this tick; NaN: CTD off
        self.energy_left_j = math.nan  # the coulomb counter's reading (sim.energy.BatteryGauge)
        self._time_s = 0.0  # missiontime [s] of the last readings

    def readings(self, tick: int) -> tuple[int, list[float]]:
        """(mask, values): the sensor array at `tick` (every sensor's value [registry units]) and
        which of them the SENSORS frame carries."""
        g, noise = self.glider, self.noise
        time_s = self._time_s = tick * self.tick_s
        if self.floor is not None:
            floor = self.floor.depth_under(g.lat_deg, g.lon_deg) if self.floor_by_position \
                else self.floor.depth_at(time_s)
            g.floor_m = floor if floor == floor else math.inf  # NaN: over the grid's land
            altitude = floor - g.depth_m
        else:
            altitude = math.nan
        if self.currents is not None and time_s >= self._next_current_s:
            g.current = Current(*self.currents.at(g.lat_deg, g.lon_deg,
                                                  self.start_epoch_s + time_s, g.depth_m))
            if not math.isfinite(g.current.north_mps + g.current.east_mps):
                g.current = Current()  # no water in the field here (its land mask): still
                self.dry_lookups += 1
            self._next_current_s = time_s + CURRENT_LOOKUP_S
        z_temp, z_depth = self.normal.next()
        temp, salinity = self.ocean.water_at(g.depth_m, time_s)
        self.water_temperature_c = temp
        ctd = self._ctd_temp
        ctd = temp if ctd != ctd else temp + (ctd - temp) * self.lag_keep
        self._ctd_temp = ctd
        self.flicker_c = -self.flicker_c
        measured = ctd + noise.temperature_sigma_c * z_temp + self.flicker_c
        if self.spikes is not None:
            measured += self.noise.spike_c * self.spikes.next()
        depth = max(0.0, g.depth_m + noise.depth_sigma_m * z_depth)
        values = [  # in _READINGS_ORDER; the runtime's own readings are never sent: NaN
            time_s, depth, g.pitch_rad, _ROLL, g.heading_rad, altitude,
            degrees_to_ddmm(g.dr_lat_deg), degrees_to_ddmm(g.dr_lon_deg), BATTERY_V,
            measured, conductivity_s_m(measured, salinity), salinity,
            _OXYGEN, _CHLOROPHYLL, _BACKSCATTER, self.current_reading, _MODEM,
            math.nan, math.nan,  # halfcycle, wptdist
            math.fmod(self.start_epoch_s + time_s, SECONDS_PER_DAY),  # the clock's time of day
            self.energy_left_j,
            math.nan,  # wptreached
            _GROUNDSPEED, _SHEAR,
        ]
        mask = powered_mask(self.sensor_power)
        self.ctd_temperature_c = measured if mask & _TEMP_BIT else math.nan
        return mask, values

    def apply(self, depth_target_m: float, pitch_rad: float, ballast_cc: float,
              heading_rad: float, flags: int, sensor_power: int, speed_mps: float = 0.0,
              thrust_w: float = 0.0) -> None:
        """Fly one tick under a COMMAND and switch the sensors it powers."""
        self.sensor_power = sensor_power
        g = self.glider
        g.step(depth_target_m, pitch_rad, ballast_cc, heading_rad,
               bool(flags & FLAG_HEADING), bool(flags & FLAG_SURFACE), speed_mps, thrust_w,
               corrects=not flags & FLAG_HEADING_HOLD)
        if g.grounded:
            if not self.grounded_ticks:
                self.first_grounded_s = self._time_s
            self.grounded_ticks += 1


def conductivity_s_m(temperature_c: float, salinity_psu: float) -> float:
    """Approximate sea-water conductivity [S m-1] (linearised about 15 C, 35 PSU)."""
    return 4.29 * (1.0 + 0.021 * (temperature_c - 15.0)) * (salinity_psu / 35.0)
