"""Calibrating a vehicle to a Slocum log: every figure the log supports, each with the
evidence behind it and, from a bootstrap over whole dives, how sure it is.

- energy: hotel, surface and Iridium power, pump and pitch energy (`calibration.py`, from
  the current sensor); no fixed energy per surfacing on top of a fitted surface power,
  which holds the air pump and the GPS already;
- devices: the glide's power split into a base load and each logged device's
  (`device_fit.py`): an instrument the log cannot separate keeps its published figure,
  with the sd its published span gives, and the hotel load holds it;
- pump: its rate from its own velocity readings, its largest volume from its software
  limit (the base's pump figures are another glider's);
- flight: drag Cd0, trim and hull compressibility (`flight_fit.py`, with gliderflight and
  the CTD's density), the pitch the glider flies when commanded a pitch (its pitch servo
  stops inside a deadband), and the turn times: how much longer each half-yo takes than
  the steady glide between its turns and its pump run;
- surfacing: time at the surface before the Iridium call, and the call's length
  (`surfacing_fit.py`).

The bootstrap resamples whole dives with replacement, refits, and gives each figure's
standard deviation and the figures' correlation. The surfacing figures are spread apart
(`surfacing_fit.py`): over the surfacings when there are two or more, else by a stated
assumption; never exact.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract.errors import GliderplanError
from gliderplan.power_models import segments as seg
from gliderplan.power_models.calibration import EnergyFit, fit_energy
from gliderplan.power_models.device_fit import DeviceFit, fit_devices
from gliderplan.power_models.dives import Dive, concatenate, split_dives
from gliderplan.power_models.fit_figure import Figure
from gliderplan.power_models.flight import DensityProfile, glide_leg
from gliderplan.power_models.flight_fit import FlightFit, FlightFitError, fit_flight, steady_glides
from gliderplan.power_models.seawater import density_profile
from gliderplan.power_models.slocum_log import FlightLog
from gliderplan.power_models.surfacing_fit import (
    SURFACING_KEYS,
    find_surfacings,
    surfacing_figures,
    surfacing_spread,
)
from gliderplan.power_models.vehicle import (
    Device,
    Uncertainty,
    Vehicle,
    device_key,
    with_figures,
)

BOOTSTRAP_RESAMPLES = 40
SEED = 2014
# not resampled over dives: a dive holds a whole surfacing or none; the pump's software
# limit is a setting, and no fixed surfacing energy beside a fitted surface power is a
# zero by construction
NOT_OVER_DIVES = (*SURFACING_KEYS, "surfacing_energy", "max_ballast")
MIN_PITCH_SAMPLES = 10  # steady samples a half-yo needs to tell its pitch


class CalibrationError(GliderplanError):
    """The log cannot support a calibration; the message says why."""


@dataclass(frozen=True)
class VehicleFit:
    vehicle: Vehicle  # the fitted figures, with their uncertainty
    figures: tuple[Figure, ...]
    energy: EnergyFit
    flight: FlightFit
    devices: DeviceFit
    ocean: DensityProfile  # the water the log flew through (its CTD)
    dives: int
    resamples: int  # bootstrap refits that succeeded

    def figure(self, key: str) -> Figure:
        return next(f for f in self.figures if f.key == key)


def commanded_volume_cc(log: FlightLog, start: int, stop: int) -> float:
    """Median commanded pumped volume [cc] (magnitude) over samples [start, stop), or the
    measured one where the log holds no command."""
    command = np.abs(log.commanded_ballast_cc[start:stop])
    command = command[np.isfinite(command)]
    if command.size:
        return float(np.median(command))
    return float(np.median(np.abs(log.ballast_cc[start:stop])))


def _pitch_errors(log: FlightLog) -> list[Figure]:
    """|Flown pitch| - |commanded pitch| [rad] of the last steady dive and climb: the pitch
    servo stops anywhere inside its deadband and carries its battery position from one
    half-yo to the next (servo memory), so the latest half-yo is the best guess of the next
    (the bootstrap's resamples then spread it as much as half-yos differ)."""
    steady = steady_glides(log) & np.isfinite(log.commanded_pitch_rad)
    figures = []
    for key, sign in (("dive_pitch_error", -1.0), ("climb_pitch_error", 1.0)):
        mine = steady & (np.sign(log.pitch_rad) == sign)
        runs = np.split(np.flatnonzero(mine), np.flatnonzero(np.diff(np.flatnonzero(mine)) > 1)
                        + 1) if mine.any() else []
        runs = [r for r in runs if r.size >= MIN_PITCH_SAMPLES]
        if not runs:
            figures.append(Figure(key, 0.0, False, "no steady half-yo with a commanded pitch"))
            continue
        last = runs[-1]
        error = np.abs(log.pitch_rad[last]) - np.abs(log.commanded_pitch_rad[last])
        figures.append(Figure(key, float(np.mean(error)), True,
                              f"flown minus commanded pitch of the last of {len(runs)} "
                              f"half-yos ({last.size} steady samples)"))
    return figures


def _turn_times(log: FlightLog, dives: list[Dive], vehicle: Vehicle,
                ocean: DensityProfile) -> list[Figure]:
    """Time each half-yo takes beyond its steady glide (at the flown pitch, through the
    log's water) and its pump run: the top turn from the dives, the bottom turn from the
    climbs. Turns at the surface (leaving it) are a different manoeuvre and left out."""
    samples: dict[str, list[float]] = {"top_turn_time": [], "bottom_turn_time": []}
    t, z = log.t_s, log.depth_m
    for k, dive in enumerate(dives):
        top, bottom = dive.top_turn, dive.bottom_turn
        if bottom is None:
            continue
        after = dives[k + 1].top_turn if k + 1 < len(dives) else None
        halves = []
        if top is not None and z[top.moving] >= seg.SURFACE_DEPTH_M:
            halves.append(("top_turn_time", top, bottom, False))
        if after is not None and z[after.moving] >= seg.SURFACE_DEPTH_M:
            halves.append(("bottom_turn_time", bottom, after, True))
        for key, first, second, up in halves:
            low, high = sorted((float(z[first.moving]), float(z[second.moving])))
            if high - low < 1.0 or z[first.stop:second.moving].min() < seg.SURFACE_DEPTH_M:
                continue  # no glide between, or a surfacing in between
            volume = commanded_volume_cc(log, first.stop, second.start)
            command = np.abs(log.commanded_pitch_rad[first.stop:second.moving])
            command = command[np.isfinite(command)]
            if not command.size:
                command = np.abs(log.pitch_rad[first.stop:second.moving])
            pitch = vehicle.flown_pitch_rad(float(np.median(command)), float(np.median(command)))
            leg = glide_leg(vehicle.flight, low, high, pitch[1 if up else 0], volume, up, ocean)
            pump = float(vehicle.pump_time_s(first.volume_cc))
            samples[key].append(t[second.moving] - t[first.moving] - float(leg.time_s) - pump)
    figures = []
    for key, values in samples.items():
        if values:
            # below 0 the glider glides on while it pumps; it never turns in less than that
            figures.append(Figure(key, max(float(np.mean(values)), 0.0), True,
                                  f"{len(values)} half-yos: time beyond the steady glide "
                                  "and the pump run (at least 0)"))
        else:
            figures.append(Figure(key, 0.0, False, "no whole half-yo between turns"))
    return figures


def _pump_figures(log: FlightLog, parts: seg.Segmentation, base: Vehicle) -> list[Figure]:
    """The pump's rate [cc/s] from its velocity readings inside its runs
    (m_ballast_pumped_vel; a yo pumps as much in as out, so the harmonic mean of the two
    directions' rates gives a yo's pump time), and its largest volume [cc] either side of
    neutral: its software limit (x_ballast_pumped_max), else the largest volume it pumped."""
    inside = np.zeros(log.t_s.size, bool)
    for event in parts.pump_events:
        inside[event.start:event.stop] = True
    reading = log.pump_velocity_cc_s[inside]
    reading = reading[np.isfinite(reading) & (reading != 0.0)]
    directions = {name: np.abs(reading[mask]) for name, mask in
                  (("out", reading > 0.0), ("in", reading < 0.0)) if mask.any()}
    if directions:
        rate = len(directions) / sum(float(np.mean(1.0 / v)) for v in directions.values())
        each = ", ".join(f"{k} {np.mean(v):.1f}" for k, v in directions.items())
        figures = [Figure("pump_rate", rate, True,
                          f"{reading.size} m_ballast_pumped_vel readings in "
                          f"{len(parts.pump_events)} pump runs ({each}): {rate:.4g} cc/s "
                          "for a yo's pump time")]
    else:
        figures = [Figure("pump_rate", base.pump_rate_cc_s, False,
                          "no m_ballast_pumped_vel reading in the log's pump runs")]
    pumped = np.abs(log.ballast_cc)
    span = f"m_ballast_pumped spans {np.min(log.ballast_cc):.0f} to {np.max(log.ballast_cc):.0f}"
    if np.isfinite(log.ballast_limit_cc) and log.ballast_limit_cc > 0.0:
        figures.append(Figure("max_ballast", log.ballast_limit_cc, True,
                              f"x_ballast_pumped_max, the pump's software limit either side "
                              f"of neutral ({span})"))
    elif pumped.size and np.max(pumped) >= seg.MIN_PUMPED_CC:
        figures.append(Figure("max_ballast", float(np.max(pumped)), True,
                              f"the largest volume pumped ({span}; no x_ballast_pumped_max): "
                              "the pump may reach further", at_least=True))
    else:
        figures.append(Figure("max_ballast", base.max_ballast_cc, False,
                              "the log pumps no volume"))
    return figures


def _surfacing_energy(energy: EnergyFit, base: Vehicle) -> Figure:
    """No fixed energy per surfacing beside a surface power fitted from the log: the
    current sensor measured the air pump and the GPS inside it."""
    surface = next(c for c in energy.coefficients if c.key == "surface_power")
    if surface.fitted:
        return Figure("surfacing_energy", 0.0, True,
                      f"0: the fitted surface power ({surface.basis}) holds the surfacing's "
                      "air pump and GPS; a fixed energy on top would count them twice")
    return Figure("surfacing_energy", base.surfacing_fixed_j, False,
                  "kept with the base's surface power: the log holds too little surface time")


def _device_figures(fit: DeviceFit) -> list[Figure]:
    """The device table's figures: each device's power (fitted, or its published figure
    with that figure's sd), and an actuator's share of the glide it moves."""
    figures = []
    for f in fit.figures:
        basis = f"{f.basis}; FLAGGED: {f.flag}" if f.flag else f.basis
        figures.append(Figure(device_key(f.device), f.on_power_w, f.fitted, basis, f.sd_w))
        if f.kind == "actuator":
            figures.append(Figure(device_key(f.device, "duty"), f.duty, f.fitted,
                                  f"the share of {fit.glide_s:.0f} s of glide it moved"))
    return figures


def with_devices(vehicle: Vehicle, fit: DeviceFit, logged: tuple[str, ...]) -> Vehicle:
    """`vehicle` with the device table and the hotel load's devices of a device fit; a
    device the log says nothing of (not in `logged`) stays as the vehicle has it."""
    fitted = {f.device for f in fit.figures}
    table = tuple(d for d in vehicle.devices if d.name not in fitted) + tuple(
        Device(f.device, f.kind, f.on_power_w, f.duty if f.kind == "actuator" else 1.0)
        for f in fit.figures)
    held = tuple(d for d in vehicle.hotel_includes if d not in logged) + tuple(
        f.device for f in fit.figures if f.held)
    return replace(vehicle, devices=table, hotel_includes=held)


def fit_once(log: FlightLog, base: Vehicle, ocean: DensityProfile | None = None
             ) -> tuple[Vehicle, list[Figure], EnergyFit, FlightFit, DeviceFit]:
    """One fit of every figure the log supports; the others stay as in `base`."""
    parts = seg.segment(log)
    if ocean is None:
        ocean = log_ocean(log)
    energy = fit_energy(log, base)
    flight = fit_flight(log, base.flight)
    devices = fit_devices(log, parts, seg.interval_energy_j(log))
    figures = [Figure(c.key, c.value, c.fitted, c.basis) for c in energy.coefficients]
    figures += _device_figures(devices)
    figures += [*_pump_figures(log, parts, base), _surfacing_energy(energy, base)]
    steady = f"{flight.samples} steady-glide samples (gliderflight, CTD density)"
    figures += [
        Figure("flight.drag_cd0", flight.params.drag_cd0, True, steady),
        Figure("flight.trim_volume", flight.params.trim_cc, True, steady),
        Figure("flight.compressibility", flight.params.compressibility_per_pa, True, steady),
        Figure("flight.water_density", flight.params.rho_kg_m3, True,
               f"mean in-situ density (TEOS-10) of the CTD over {flight.samples} steady-glide "
               "samples: the water the trim is given in"),
    ]
    figures += _pitch_errors(log)
    vehicle = with_devices(energy.vehicle, devices, log.device_names)
    vehicle = with_figures(vehicle, {f.key: f.value for f in figures if f.fitted})
    vehicle = replace(vehicle, flight=flight.params)
    figures += _turn_times(log, split_dives(log, parts), vehicle, ocean)
    figures += surfacing_figures(find_surfacings(log, parts))
    vehicle = with_figures(vehicle, {f.key: f.value for f in figures if f.fitted})
    return vehicle, figures, energy, flight, devices


def log_ocean(log: FlightLog) -> DensityProfile:
    """The water column the log flew through, from its CTD (1 m bins)."""
    if not np.isfinite(log.density_kg_m3).any():
        raise CalibrationError("the logs hold no CTD readings (sci_water_temp, sci_water_cond, "
                               "sci_water_pressure): the flight model needs the water's density")
    return density_profile(log.depth_m, log.density_kg_m3)


def fit_vehicle(log: FlightLog, base: Vehicle, resamples: int = BOOTSTRAP_RESAMPLES,
                seed: int = SEED) -> VehicleFit:
    """Fit `log`, bootstrap the fit over its whole dives (`resamples` refits) and spread the
    surfacing figures (`surfacing_fit`); a figure kept from `base` keeps its sd."""
    ocean = log_ocean(log)
    try:
        vehicle, figures, energy, flight, devices = fit_once(log, base, ocean)
    except FlightFitError as err:
        raise CalibrationError(str(err)) from None
    dives = split_dives(log)
    keys, sd, correlation, refits = _over_dives(log, dives, replace(base, flight=vehicle.flight),
                                                figures, ocean, resamples, seed)
    # a fitted figure with an sd of its own (devices that switch together, split by their
    # published figures): that split's uncertainty, beside the bootstrap's
    own = {f.key: f.sd for f in figures if f.fitted and f.sd is not None}
    sd = np.hypot(sd, [own.get(k, 0.0) for k in keys])
    surfacing = surfacing_spread(find_surfacings(log, seg.segment(log)), figures)
    fitted = {f.key for f in figures if f.fitted}
    kept = base.uncertainty
    kept_keys = () if kept is None else tuple(k for k in kept.keys if k not in fitted)
    kept_sd = {} if kept is None else dict(zip(kept.keys, kept.sd, strict=True))
    # published figures of devices the log cannot separate: their own sd, independent
    published = [f for f in figures if not f.fitted and f.sd is not None]
    blocks = [(keys, sd, correlation), (surfacing.keys, surfacing.sd, surfacing.correlation),
              (kept_keys, np.array([kept_sd[k] for k in kept_keys]), np.eye(len(kept_keys))),
              (tuple(f.key for f in published), np.array([f.sd for f in published]),
               np.eye(len(published)))]
    all_keys = tuple(k for block in blocks for k in block[0])
    spread = dict(zip(all_keys, np.concatenate([b[1] for b in blocks]), strict=True))
    figures = [replace(f, sd=spread.get(f.key), basis=f"{f.basis}; {surfacing.basis[f.key]}"
                       if f.key in surfacing.basis else f.basis) for f in figures]
    uncertainty = None
    if all_keys:
        source = f"gliderplan calibrate: bootstrap over {len(dives)} dives, {refits} refits"
        if surfacing.keys:
            source += f"; {surfacing.source}"
        if kept_keys:
            source += f"; {', '.join(kept_keys)}: the base's sd, independent"
        if published:
            source += "; " + ", ".join(f.key for f in published) + ": published figures " \
                "(sd from their published span), independent"
        at_least = (*surfacing.at_least,
                    *(k for k in kept_keys if kept is not None and k in kept.at_least))
        uncertainty = Uncertainty(all_keys, np.array([spread[k] for k in all_keys]),
                                  _block_diagonal([b[2] for b in blocks]), source, at_least)
    return VehicleFit(replace(vehicle, uncertainty=uncertainty), tuple(figures), energy,
                      flight, devices, ocean, len(dives), refits)


def _over_dives(log: FlightLog, dives: list[Dive], start: Vehicle, figures: list[Figure],
                ocean: DensityProfile, resamples: int, seed: int
                ) -> tuple[tuple[str, ...], np.ndarray, np.ndarray, int]:
    """(keys, sd [model units], correlation, refits) of the fitted figures that vary when
    whole dives are resampled with replacement and the log refitted from `start`."""
    spread_keys = [f.key for f in figures if f.fitted and f.key not in NOT_OVER_DIVES]
    rng = np.random.default_rng(seed)
    draws = []
    for _ in range(resamples if len(dives) >= 2 else 0):
        picked = [dives[i] for i in rng.integers(0, len(dives), len(dives))]
        try:
            _, refit, _, _, _ = fit_once(concatenate(log, picked), start, ocean)
        except (FlightFitError, ValueError):
            continue  # a resample without enough steady glides: it says nothing
        values = {f.key: f.value for f in refit if f.fitted}
        if all(k in values for k in spread_keys):
            draws.append([values[k] for k in spread_keys])
    samples = np.array(draws).reshape(len(draws), len(spread_keys))
    sd = samples.std(axis=0, ddof=1) if len(draws) >= 3 else np.zeros(len(spread_keys))
    varying = sd > 1e-9 * np.abs(samples.mean(axis=0)) if len(draws) else sd > 0.0
    keys = tuple(k for k, v in zip(spread_keys, varying, strict=True) if v)
    correlation = np.atleast_2d(np.corrcoef(samples[:, varying], rowvar=False)) if keys \
        else np.eye(0)
    return keys, sd[varying], correlation, len(draws)


def _block_diagonal(blocks: list[np.ndarray]) -> np.ndarray:
    """One correlation matrix of independent groups of figures."""
    size = sum(b.shape[0] for b in blocks)
    out, at = np.eye(size), 0
    for block in blocks:
        out[at:at + block.shape[0], at:at + block.shape[0]] = block
        at += block.shape[0]
    return out

