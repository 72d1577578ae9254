"""The limits a plan must keep on the mission, vehicle and board it flies on
(`contract.FlightLimits`), loaded from their power-model files."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract import MAX_PLAN_SPEED_MPS, FlightLimits
from gliderplan.language import ir
from gliderplan.language.ir import CheckedMission
from gliderplan.language.registry import SENSOR_BY_NAME, cannot_fly
from gliderplan.power_models.battery import usable_budget_j

if TYPE_CHECKING:
    from gliderplan.power_models.vehicle import Vehicle

PITCH_STEPS = 2000  # pitches at which the fastest glide is sought: its peak is flat


def pitch_range_rad(dive_error_rad: float, climb_error_rad: float) -> tuple[float, float]:
    """The commanded pitches [rad] (open range) that the vehicle flies strictly between 0
    and pi/2 on its dives and its climbs, its pitch errors included (the flight model's
    domain: `power_models.flight`)."""
    errors = (dive_error_rad, climb_error_rad)
    return max(0.0, *(-e for e in errors)), math.pi / 2 - max(0.0, *errors)


def flight_limits(mission: CheckedMission, board: str | None = None) -> FlightLimits:
    """The limits of the mission's battery, sensors and vehicle on `board` (a preset or a
    board file; default the mission's computer). Raises ModelFileError for a file that
    cannot be loaded."""
    from gliderplan.power_models import load_board, load_vehicle

    computer = load_board(board if board is not None else mission.computer.board)
    return vehicle_limits(mission, load_vehicle(mission.vehicle),
                          tuple(sorted(m.clock_mhz for m in computer.clock_modes)),
                          computer.name)


def unplanned(mission: CheckedMission, vehicle: Vehicle) -> tuple[float, tuple[int, ...]]:
    """What `vehicle` flies of `mission` without a plan (`FlightLimits.unplanned_*`): for a
    propelled profile's `auto` speed, the least energy per metre [m/s] for its hotel load
    alone (the computer's is the plan's to add; 0 without propulsion), and per state the
    first alternative it can fly."""
    from gliderplan.planner.speed import best_speed
    from gliderplan.power_models.devices import base_power_w

    speed = 0.0 if vehicle.propulsion is None else \
        best_speed(vehicle.propulsion, base_power_w(vehicle)).speed_mps
    flown = tuple(next((k for k, p in enumerate(state.profiles)
                        if cannot_fly(p.kind, p.thrust, vehicle) is None), 0)
                  for state in mission.states)
    return speed, flown


def propulsion_rating(vehicle: Vehicle) -> dict[str, tuple[float, float]]:
    """FlightLimits' bounds from `vehicle`'s propulsion (none without one): the speeds
    [m s-1] it flies and its thruster's power command [W]."""
    propulsion = vehicle.propulsion
    return {} if propulsion is None else {
        "propelled_speed_mps": (propulsion.min_speed_mps, propulsion.max_speed_mps),
        **({"thrust_range_w": (propulsion.min_command_w, propulsion.max_command_w)}
           if propulsion.is_thruster else {})}


def vehicle_limits(mission: CheckedMission, vehicle: Vehicle, clocks_mhz: tuple[float, ...],
                   board: str | None = None) -> FlightLimits:
    """The limits of `mission` flown by `vehicle` on a board of `clocks_mhz` [MHz] named
    `board` (None: any): the battery less its reserve, the sensors' duty bounds, the pump,
    the pitches and fastest glide of a vehicle with a buoyancy engine (an AUV has none:
    no glide bounds beyond the contract's), the volume each yo needs, the speeds its
    propulsion flies and its thruster's power command, and what it flies without a plan
    (`unplanned`)."""
    from gliderplan.planner.inputs import duty_bounds
    from gliderplan.planner.rates import yo_band
    from gliderplan.power_models.devices import sensor_on

    low, high = pitch_range_rad(vehicle.dive_pitch_error_rad, vehicle.climb_pitch_error_rad)
    if vehicle.has_buoyancy_engine:
        pitches = np.linspace(low, high, PITCH_STEPS + 2)[1:-1]
        fastest = float(np.max(vehicle.max_speed_mps(pitches)))
    else:  # no wings and no pump: it glides at no pitch
        fastest = MAX_PLAN_SPEED_MPS

    def least_ballast_cc(profile: ir.Profile) -> float:
        """Volume [cc] below which the glider stays at a yo's turning depth: its trim over
        the band the planner plans it at (0 where the band is known only in flight, or
        for a yo the vehicle cannot fly: it is given no time)."""
        args = profile.constant_args()
        if profile.kind not in ("yo", "thermotrackyo") or args is None or \
                cannot_fly(profile.kind, profile.thrust, vehicle) is not None:
            return 0.0
        return float(vehicle.trim_offset_cc(*yo_band(profile, args)))

    speed, flown = unplanned(mission, vehicle)
    return FlightLimits(
        vehicle.unplanned_ballast_cc, vehicle.max_ballast_cc, clocks_mhz, board=board,
        max_budget_j=usable_budget_j(mission.battery.energy_j, mission.battery.reserve_fraction),
        pitch_range_rad=(low, high),
        max_speed_mps=fastest,
        duty_bounds=tuple(
            tuple((use.name, *duty_bounds(mission, state, use,
                                          sensor_on(vehicle, device).quality_alpha))
                  for use in state.sensors  # one logged without a duty is the plan's to cycle
                  if (device := SENSOR_BY_NAME[use.name].device) is not None
                  and use.duty is not None)
            for state in mission.states),
        min_ballast_cc=tuple(tuple(least_ballast_cc(p) for p in state.profiles)
                             for state in mission.states),
        unplanned_speed_mps=speed, unplanned_profiles=flown, envelope=vehicle.envelope,
        **propulsion_rating(vehicle))
