"""Cross-configuration check: calibrate on the dives that ran one set of devices, forecast
the energy of the dives that ran another.

A dive's configuration is the set of instruments on for most of its glide. The dives of
the most common configuration are fitted (`vehicle_fit`, with the device split of
`device_fit`); each other configuration's dives are then billed with that fit, their own
durations, pump runs and surfacings as logged (what the device model must carry over is
which devices ran, not how the glider flew), every instrument at the share of the glide
it ran: the base load, and each instrument at the fitted vehicle's figure, its published
figure where the fitted dives never ran it. Truth is the coulomb counter over those dives.
The 90 % interval draws the fitted vehicle's figures (`draws`), published ones with the sd
of their published span.

A log whose dives all ran the same devices cannot be checked this way: the result says so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.power_models import segments as seg
from gliderplan.power_models.calibration import log_timeline
from gliderplan.power_models.devices import base_power_w, sensor_on
from gliderplan.power_models.dives import Dive, concatenate, split_dives
from gliderplan.power_models.draws import DEFAULT_DRAWS, DEFAULT_SEED, draw_vehicles
from gliderplan.power_models.forecast import INTERVAL_LEVEL
from gliderplan.power_models.slocum_log import FlightLog
from gliderplan.power_models.timeline import energy_by_component_j
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.power_models.vehicle_fit import fit_vehicle

MIN_DIVES = 2  # dives a configuration needs to be fitted on, or checked
ON_SHARE = 0.5  # an instrument on for more of a dive's glide than this ran in it
RESAMPLES = 12  # bootstrap refits of the fitted configuration (its sd; the check is a test)


@dataclass(frozen=True)
class ConfigurationForecast:
    """One configuration's dives billed by the fit of another's."""

    devices: tuple[str, ...]  # the instruments its dives ran
    dives: int
    predicted_j: float
    measured_j: float  # coulomb counter over its dives
    interval_j: tuple[float, float]

    @property
    def relative_error(self) -> float:
        return self.predicted_j / self.measured_j - 1.0


@dataclass(frozen=True)
class ConfigurationCheck:
    fitted_devices: tuple[str, ...]  # the configuration fitted on
    fitted_dives: int
    forecasts: tuple[ConfigurationForecast, ...]
    reason: str  # why no forecast could be made ("" when some were)


def _configuration(log: FlightLog, dive: Dive) -> frozenset[str]:
    """The instruments on for more than ON_SHARE of a dive's glide."""
    names = [n for n in log.device_names if n != "fin"]
    if not names:
        return frozenset()
    parts = seg.segment(log.slice(dive.start, dive.stop + 1))
    glide = parts.phase == seg.GLIDE
    dt = np.diff(log.t_s[dive.start:dive.stop + 1])
    if not (glide & (dt > 0)).any():
        return frozenset()
    on = log.devices_on()[dive.start:dive.stop][glide]
    shares = np.average(on, axis=0, weights=dt[glide])
    return frozenset(n for n, share in zip(log.device_names, shares, strict=True)
                     if n in names and share > ON_SHARE)


def replay_j(log: FlightLog, vehicle: Vehicle) -> float:
    """[J] `log`'s own timeline billed by `vehicle` device by device: the base load while
    it glides, each instrument while the log has it on (its share of each interval), the
    surface, Iridium, pump and pitch as the log flew them."""
    timeline = log_timeline(log)
    parts = energy_by_component_j(timeline, vehicle, gliding_w=base_power_w(vehicle))
    total = float(sum(p.sum() for p in parts.values()))
    phase = timeline.phase
    gliding = (phase == seg.GLIDE) | (phase == seg.PUMP) | (phase == seg.PITCH)
    on = log.devices_on()[:-1]
    for j, name in enumerate(log.device_names):
        if name != "fin":
            watts = sensor_on(vehicle, name).on_power_w
            total += float(np.sum(on[:, j] * gliding * watts * timeline.dt_s))
    return total


def check_configurations(log: FlightLog, base: Vehicle) -> ConfigurationCheck:
    """Fit the most common configuration's dives, forecast each other's."""
    dives = [d for d in split_dives(log) if d.bottom_turn is not None]
    groups: dict[frozenset[str], list[Dive]] = {}
    for dive in dives:
        groups.setdefault(_configuration(log, dive), []).append(dive)
    usable = {c: d for c, d in groups.items() if len(d) >= MIN_DIVES}
    ran = ", ".join(sorted(next(iter(groups)))) if len(groups) == 1 else ""
    if len(usable) < 2:
        why = (f"every dive ran the same instruments ({ran or 'none'}): there is no other "
               "configuration to forecast" if len(groups) == 1 else
               f"fewer than two configurations have {MIN_DIVES} dives or more")
        return ConfigurationCheck(tuple(sorted(ran.split(", "))) if ran else (),
                                  len(dives), (), why)
    fitted, fit_dives = max(usable.items(), key=lambda kv: len(kv[1]))
    vehicle = fit_vehicle(concatenate(log, fit_dives), base, RESAMPLES).vehicle
    drawn = draw_vehicles(vehicle, DEFAULT_DRAWS, np.random.default_rng(DEFAULT_SEED))
    tail = 50.0 * (1.0 - INTERVAL_LEVEL)
    forecasts = []
    for devices, checked in usable.items():
        if devices == fitted:
            continue
        joined = concatenate(log, checked)
        energies = [replay_j(joined, v) for v in drawn]
        low, high = np.percentile(energies, [tail, 100.0 - tail])
        forecasts.append(ConfigurationForecast(
            tuple(sorted(devices)), len(checked), replay_j(joined, vehicle),
            seg.counter_energy_j(joined), (float(low), float(high))))
    return ConfigurationCheck(tuple(sorted(fitted)), len(fit_dives), tuple(forecasts), "")
