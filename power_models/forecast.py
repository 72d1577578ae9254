"""Forward forecast of a yo mission from the vehicle model alone.

What a pilot knows before the glider flies: the commanded yo band, pitch and buoyancy
volume, how often it surfaces, and the water it flies through. From these and the
vehicle's (calibrated) figures the forecast gives the time of each dive and climb, the
yo period, the time to the surface, how many yos a span holds and the energy of every
component; with the calibration's uncertainty, the 90 % interval of that energy.

A surfacing cycle is, from a top turn: `dives_per_surfacing` x (top turn, dive, bottom
turn, climb) where the last climb goes to the surface on the largest buoyancy volume,
then the time at the surface (GPS fix, then the Iridium call). A turn is the pump run
(pumped volume / pump rate, 2 x the volume either side of neutral) and the vehicle's turn
time beyond it, with the glider's gliding load running throughout; the pump's energy is
its own. The gliding load is billed by device (`devices.gliding_power_w`): the base, the
fin, and each instrument the mission runs at its duty, so that the energy splits by device.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract import VEHICLE_COMPONENTS, Component
from gliderplan.power_models import flight
from gliderplan.power_models.devices import gliding_power_w
from gliderplan.power_models.flight import DensityProfile
from gliderplan.power_models.vehicle import Vehicle

INTERVAL_LEVEL = 0.90


@dataclass(frozen=True)
class YoCommand:
    """The commands of a yo mission (a Slocum yo behaviour and its surfacing).
    Depths [m], pitches [rad] (magnitudes), volumes [cc] either side of neutral."""

    top_m: float  # climb target: the top turn
    bottom_m: float  # dive target, or the sea floor less the altimeter's clearance
    dive_pitch_rad: float
    climb_pitch_rad: float
    ballast_cc: float
    dives_per_surfacing: int
    # (device, duty [1]) of the instruments run while gliding; None: those the vehicle's
    # hotel load holds, always on (the glider as it was calibrated)
    instruments: tuple[tuple[str, float], ...] | None = None

    def __post_init__(self) -> None:
        if not (0.0 <= self.top_m < self.bottom_m):
            raise ValueError(f"a yo needs 0 <= top < bottom, got {self.top_m}-{self.bottom_m} m")
        if self.dives_per_surfacing < 1:
            raise ValueError("the glider must dive at least once between surfacings")


@dataclass(frozen=True)
class Phase:
    """One piece of a surfacing cycle: duration [s], energy per component [J], and how
    many dives it completes (1 for a dive's glide)."""

    name: str
    time_s: float
    energy_j: dict[str, float]
    dives: float = 0.0
    surfacings: float = 0.0


@dataclass(frozen=True)
class Forecast:
    command: YoCommand
    dive: flight.Leg  # a dive across the band
    climb: flight.Leg  # a climb across the band
    yo_period_s: float  # top turn to top turn
    time_to_surface_s: float  # from a top turn, the schedule's dives, to the surface
    duration_s: float  # the span forecast
    yos: float  # dives flown in it
    surfacings: float  # surfacing climbs flown in it
    energy_by_component_j: dict[str, float]

    @property
    def energy_j(self) -> float:
        return float(sum(self.energy_by_component_j.values()))


def _turn(vehicle: Vehicle, load_w: dict[str, float], name: str, depth_m: float,
          volume_cc: float, top: bool) -> Phase:
    """An inflection at `depth_m` pumping `volume_cc` [cc] (in at the top, out below), the
    gliding load `load_w` [W by device] running."""
    time = float(vehicle.pump_time_s(volume_cc)) + (
        vehicle.top_turn_s if top else vehicle.bottom_turn_s
    )
    pump = vehicle.pump_in_energy_j(depth_m, volume_cc) if top else vehicle.pump_energy_j(
        depth_m, volume_cc
    )
    return Phase(name, time, {**{d: w * time for d, w in load_w.items()},
                              Component.PUMP: float(pump),
                              Component.PITCH: vehicle.pitch_energy_j})


def _glide(load_w: dict[str, float], name: str, leg: flight.Leg, dives: float = 0.0,
           surfacings: float = 0.0) -> Phase:
    time = float(leg.time_s)
    return Phase(name, time, {d: w * time for d, w in load_w.items()}, dives, surfacings)


def surfacing_cycle(
    vehicle: Vehicle, command: YoCommand, ocean: DensityProfile | None = None,
    first_from_surface: bool = True,
) -> tuple[list[Phase], flight.Leg, flight.Leg]:
    """The phases of one surfacing cycle, from the top turn of its first dive (at the
    surface, or at the yo's top when `first_from_surface` is False) to leaving the
    surface; and the yo's dive and climb legs."""
    c, v = command, vehicle
    load = gliding_power_w(v, None if c.instruments is None else dict(c.instruments))
    pitch_down, pitch_up = v.flown_pitch_rad(c.dive_pitch_rad, c.climb_pitch_rad)
    up = max(v.max_ballast_cc, c.ballast_cc)
    # one glide solution per pitch, for [the yo's band, the band from the surface]
    downs = flight.glide_leg(v.flight, [c.top_m, 0.0], c.bottom_m, pitch_down, c.ballast_cc,
                             False, ocean)
    ups = flight.glide_leg(v.flight, [c.top_m, 0.0], c.bottom_m, pitch_up, [c.ballast_cc, up],
                           True, ocean)
    dive, first, climb, to_surface = downs[0], downs[1], ups[0], ups[1]
    yo = 2.0 * c.ballast_cc
    # the dives between the first and the last are alike: their phases are computed once
    middle = [_turn(v, load, "top turn", c.top_m, yo, True), _glide(load, "dive", dive, 1.0),
              _turn(v, load, "bottom turn", c.bottom_m, yo, False),
              _glide(load, "climb", climb)]
    phases = []
    for k in range(c.dives_per_surfacing):
        cycle = list(middle)
        if k == 0 and first_from_surface:
            cycle[:2] = [_turn(v, load, "top turn", 0.0, up + c.ballast_cc, True),
                         _glide(load, "dive", first, 1.0)]
        if k == c.dives_per_surfacing - 1:
            cycle[2:] = [_turn(v, load, "bottom turn", c.bottom_m, c.ballast_cc + up, False),
                         _glide(load, "climb to the surface", to_surface, surfacings=1.0)]
        phases += cycle
    phases.append(Phase("GPS fix", v.surface_s,
                        {Component.SURFACE: v.surface_w * v.surface_s + v.surfacing_fixed_j}))
    phases.append(Phase("Iridium call", v.iridium_s,
                        {Component.IRIDIUM: v.iridium_w * v.iridium_s}))
    return phases, dive, climb


def forecast(
    vehicle: Vehicle,
    command: YoCommand,
    ocean: DensityProfile | None = None,
    horizon_s: float | None = None,
) -> Forecast:
    """Forecast `command` flown by `vehicle` through `ocean` (default: uniform water of the
    vehicle's reference density).

    Without a horizon: from a top turn at the yo's top, the schedule's dives and the
    climb to the surface, ending on arrival there (what validation compares with a
    log's later dives). With `horizon_s` [s]: surfacing cycles from the surface on,
    until the horizon (the last one cut where the horizon falls).
    """
    phases, dive, climb = surfacing_cycle(vehicle, command, ocean, horizon_s is not None)
    to_surface = sum(p.time_s for p in phases[:-2])
    if horizon_s is None:
        phases, horizon = phases[:-2], to_surface
    else:
        horizon = float(horizon_s)
    cycle_s = sum(p.time_s for p in phases)
    full = math.floor(horizon / cycle_s)
    left = horizon - full * cycle_s
    shares = []
    for p in phases:  # whole cycles, then the one the horizon cuts, pro rata
        shares.append(full + (min(max(left / p.time_s, 0.0), 1.0) if p.time_s > 0 else left > 0))
        left -= p.time_s
    return _summed(vehicle, command, phases, shares, dive, climb, to_surface, horizon)


def forecast_cycles(vehicle: Vehicle, command: YoCommand, cycles: tuple[int, ...],
                    ocean: DensityProfile | None = None, from_surface: bool = True
                    ) -> Forecast:
    """Surfacing cycles of `cycles` dives each, flown one after another: from the top turn
    of the first (at the surface when `from_surface`, else at the yo's top), the stays at
    the surface between them (GPS fix, Iridium call), to the arrival at the surface after
    the last. What a record's later part holds when its glider surfaced every few dives."""
    if not cycles or min(cycles) < 1:
        raise ValueError("each surfacing cycle needs at least one dive")
    phases: list[Phase] = []
    dive = climb = None
    for k, dives in enumerate(cycles):
        part, dive, climb = surfacing_cycle(vehicle, replace(command, dives_per_surfacing=dives),
                                            ocean, from_surface or k > 0)
        phases += part if k + 1 < len(cycles) else part[:-2]
    time = sum(p.time_s for p in phases)
    return _summed(vehicle, command, phases, [1.0] * len(phases), dive, climb, time, time)


def _summed(vehicle: Vehicle, command: YoCommand, phases: list[Phase], shares: list[float],
            dive: flight.Leg, climb: flight.Leg, to_surface_s: float, duration_s: float
            ) -> Forecast:
    """The forecast of `phases` flown `shares` times each."""
    energy = dict.fromkeys(VEHICLE_COMPONENTS, 0.0)
    yos, surfacings = 0.0, 0.0
    for p, share in zip(phases, shares, strict=True):
        for k, e in p.energy_j.items():
            energy[k] = energy.get(k, 0.0) + share * e
        yos += share * p.dives
        surfacings += share * p.surfacings
    return Forecast(
        command, dive, climb,
        yo_period_s=float(dive.time_s + climb.time_s + vehicle.turn_s(command.ballast_cc)),
        time_to_surface_s=to_surface_s, duration_s=duration_s, yos=yos, surfacings=surfacings,
        energy_by_component_j=energy,
    )


def energy_interval_j(
    vehicles: list[Vehicle],
    command: YoCommand,
    ocean: DensityProfile | None = None,
    horizon_s: float | None = None,
    level: float = INTERVAL_LEVEL,
    noise_j: np.ndarray | None = None,
    cycles: tuple[int, ...] | None = None,
    from_surface: bool = True,
) -> tuple[float, float]:
    """The central `level` interval [J] of the forecast energy over `vehicles` drawn from
    a calibration's uncertainty (`draws.draw_vehicles`), plus `noise_j` [J] per draw (what
    the meter that will check it adds); with `cycles`, of `forecast_cycles`."""
    energies = np.array([
        (forecast(v, command, ocean, horizon_s) if cycles is None
         else forecast_cycles(v, command, cycles, ocean, from_surface)).energy_j
        for v in vehicles])
    if noise_j is not None:
        energies = energies + noise_j
    tail = 50.0 * (1.0 - level)
    low, high = np.percentile(energies, [tail, 100.0 - tail])
    return float(low), float(high)
