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
time beyond it, with the hotel load running throughout; the pump's energy is its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import VEHICLE_COMPONENTS, Component
from gliderplan.power_models import flight
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


def _turn(vehicle: Vehicle, name: str, depth_m: float, volume_cc: float, top: bool) -> Phase:
    """An inflection at `depth_m` pumping `volume_cc` [cc] (in at the top, out below)."""
    time = float(vehicle.pump_time_s(volume_cc)) + (
        vehicle.top_turn_s if top else vehicle.bottom_turn_s
    )
    pump = vehicle.pump_in_energy_j(depth_m, volume_cc) if top else vehicle.pump_energy_j(
        depth_m, volume_cc
    )
    return Phase(name, time, {Component.HOTEL: vehicle.hotel_w * time,
                              Component.PUMP: float(pump),
                              Component.PITCH: vehicle.pitch_energy_j})


def _glide(vehicle: Vehicle, name: str, leg: flight.Leg, dives: float = 0.0,
           surfacings: float = 0.0) -> Phase:
    time = float(leg.time_s)
    return Phase(name, time, {Component.HOTEL: vehicle.hotel_w * time}, dives, surfacings)


def surfacing_cycle(
    vehicle: Vehicle, command: YoCommand, ocean: DensityProfile | None = None,
    first_from_surface: bool = True,
) -> tuple[list[Phase], flight.Leg, flight.Leg]:
    """The phases of one surfacing cycle, from the top turn of its first dive (at the
    surface, or at the yo's top when `first_from_surface` is False) to leaving the
    surface; and the yo's dive and climb legs."""
    c, v = command, vehicle
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
    middle = [_turn(v, "top turn", c.top_m, yo, True), _glide(v, "dive", dive, 1.0),
              _turn(v, "bottom turn", c.bottom_m, yo, False), _glide(v, "climb", climb)]
    phases = []
    for k in range(c.dives_per_surfacing):
        cycle = list(middle)
        if k == 0 and first_from_surface:
            cycle[:2] = [_turn(v, "top turn", 0.0, up + c.ballast_cc, True),
                         _glide(v, "dive", first, 1.0)]
        if k == c.dives_per_surfacing - 1:
            cycle[2:] = [_turn(v, "bottom turn", c.bottom_m, c.ballast_cc + up, False),
                         _glide(v, "climb to the surface", to_surface, surfacings=1.0)]
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
    energy = dict.fromkeys(VEHICLE_COMPONENTS, 0.0)
    yos, surfacings = 0.0, 0.0
    left = horizon - full * cycle_s
    for p in phases:  # whole cycles, then the one the horizon cuts, pro rata
        share = full + (min(max(left / p.time_s, 0.0), 1.0) if p.time_s > 0 else left > 0)
        for k, e in p.energy_j.items():
            energy[k] += share * e
        yos += share * p.dives
        surfacings += share * p.surfacings
        left -= p.time_s
    return Forecast(
        command, dive, climb,
        yo_period_s=float(dive.time_s + climb.time_s + vehicle.turn_s(command.ballast_cc)),
        time_to_surface_s=to_surface, duration_s=horizon, yos=yos, surfacings=surfacings,
        energy_by_component_j=energy,
    )


def energy_interval_j(
    vehicles: list[Vehicle],
    command: YoCommand,
    ocean: DensityProfile | None = None,
    horizon_s: float | None = None,
    level: float = INTERVAL_LEVEL,
    noise_j: np.ndarray | None = None,
) -> tuple[float, float]:
    """The central `level` interval [J] of the forecast energy over `vehicles` drawn from
    a calibration's uncertainty (`draws.draw_vehicles`), plus `noise_j` [J] per draw (what
    the meter that will check it adds)."""
    energies = np.array([forecast(v, command, ocean, horizon_s).energy_j for v in vehicles])
    if noise_j is not None:
        energies = energies + noise_j
    tail = 50.0 * (1.0 - level)
    low, high = np.percentile(energies, [tail, 100.0 - tail])
    return float(low), float(high)
