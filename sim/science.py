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
Every random number comes from one numpy Generator seeded per run: a run is
deterministic for its seed.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import FLIGHT_SENSORS_MASK
from gliderplan.language.registry import SENSORS
from gliderplan.sim.geo import degrees_to_ddmm
from gliderplan.sim.ocean import Ocean
from gliderplan.sim.vehicle import GliderSim

DEVICE_MASKS: dict[str, int] = {}
for _s in SENSORS:
    if _s.device is not None:
        DEVICE_MASKS[_s.device] = DEVICE_MASKS.get(_s.device, 0) | (1 << _s.index)

_TEMP_BIT = 1 << next(s.index for s in SENSORS if s.name == "temp")
BOTTOM_DEPTH_M = 200.0  # assumption: water depth for the altimeter reading
BATTERY_V = 15.0  # assumption: alkaline pack voltage, constant over the run
_NOISE_BLOCK = 4096  # random numbers drawn per numpy call


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


@functools.cache
def powered_mask(sensor_power: int) -> int:
    """Sensors sent in a tick: those without a device plus every sensor of a device that
    `sensor_power` (bit i: sensor i's device on) keeps powered."""
    mask = FLIGHT_SENSORS_MASK
    for bits in DEVICE_MASKS.values():
        if sensor_power & bits:
            mask |= bits
    return mask


class ScienceComputer:
    """The sensor array over a simulated glider in a simulated ocean."""

    def __init__(self, glider: GliderSim, ocean: Ocean, noise: SensorNoise, seed: int,
                 tick_s: float) -> None:
        self.glider, self.ocean, self.noise, self.tick_s = glider, ocean, noise, tick_s
        self.rng = np.random.default_rng(seed)
        self.sensor_power = 0  # from the last COMMAND; nothing is powered before the first
        self._lag_keep = math.exp(-tick_s / noise.temperature_lag_s) \
            if noise.temperature_lag_s > 0.0 else 0.0
        self._ctd_temp = math.nan
        self._noise: list[tuple[float, float]] = []
        # spikes come from a stream of their own: a run without them draws as before
        self._spike_rng = np.random.default_rng([seed, 1]) \
            if noise.spike_probability > 0.0 else None
        self._spikes: list[float] = []
        self._flicker_c = noise.flicker_c if self.rng.random() < 0.5 else -noise.flicker_c
        self.water_temperature_c = math.nan  # at the glider, this tick (for the record)
        self.ctd_temperature_c = math.nan  # the CTD's reading sent this tick; NaN: CTD off

    def _draws(self) -> tuple[float, float]:
        """(temperature, depth) standard normal draws for one tick."""
        if not self._noise:
            self._noise = self.rng.standard_normal((_NOISE_BLOCK, 2)).tolist()
            self._noise.reverse()
        return self._noise.pop()

    def _spike_c(self) -> float:
        """This reading's spike [degC]: 0, or +-spike_c with the spike probability."""
        if not self._spikes:
            u = self._spike_rng.random((_NOISE_BLOCK, 2))
            hit = u[:, 0] < self.noise.spike_probability
            self._spikes = np.where(hit, np.where(u[:, 1] < 0.5, -1.0, 1.0), 0.0).tolist()
            self._spikes.reverse()
        return self.noise.spike_c * self._spikes.pop()

    def readings(self, tick: int) -> tuple[int, list[float]]:
        """(mask, values): the sensor array at `tick` (all 17 values [registry units]) and
        which of them the SENSORS frame carries."""
        g, noise = self.glider, self.noise
        time_s = tick * self.tick_s
        z_temp, z_depth = self._draws()
        temp, salinity = self.ocean.water_at(g.depth_m, time_s)
        self.water_temperature_c = temp
        ctd = self._ctd_temp
        ctd = temp if ctd != ctd else temp + (ctd - temp) * self._lag_keep
        self._ctd_temp = ctd
        self._flicker_c = -self._flicker_c
        measured = ctd + noise.temperature_sigma_c * z_temp + self._flicker_c
        if self._spike_rng is not None:
            measured += self._spike_c()
        depth = max(0.0, g.depth_m + noise.depth_sigma_m * z_depth)
        c = self.glider.current
        values = [
            time_s, depth, g.pitch_rad, 0.0, g.heading_rad, BOTTOM_DEPTH_M - g.depth_m,
            degrees_to_ddmm(g.dr_lat_deg), degrees_to_ddmm(g.dr_lon_deg), BATTERY_V,
            measured, conductivity_s_m(measured, salinity), salinity,
            250.0, 1.0, 0.001, math.hypot(c.north_mps, c.east_mps), 0.0,
        ]
        mask = powered_mask(self.sensor_power)
        self.ctd_temperature_c = measured if mask & _TEMP_BIT else math.nan
        return mask, values

    def apply(self, depth_target_m: float, pitch_rad: float, ballast_cc: float,
              heading_rad: float, flags: int, sensor_power: int) -> None:
        """Fly one tick under a COMMAND and switch the sensors it powers."""
        self.sensor_power = sensor_power
        self.glider.step(depth_target_m, pitch_rad, ballast_cc, heading_rad,
                         bool(flags & 8), bool(flags & 1))


def conductivity_s_m(temperature_c: float, salinity_psu: float) -> float:
    """Approximate sea-water conductivity [S m-1] (linearised about 15 C, 35 PSU)."""
    return 4.29 * (1.0 + 0.021 * (temperature_c - 15.0)) * (salinity_psu / 35.0)
