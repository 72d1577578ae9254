"""The limits a plan must keep on the mission, vehicle and board it flies on
(`contract.FlightLimits`), loaded from their power-model files."""

from __future__ import annotations

import math

import numpy as np

from gliderplan.contract import FlightLimits
from gliderplan.language import ir
from gliderplan.language.ir import CheckedMission
from gliderplan.language.registry import SENSOR_BY_NAME

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
    from gliderplan.planner.inputs import duty_bounds
    from gliderplan.planner.rates import yo_band
    from gliderplan.power_models import load_board, load_vehicle
    from gliderplan.power_models.devices import sensor_on

    vehicle = load_vehicle(mission.vehicle)
    computer = load_board(board if board is not None else mission.computer.board)
    low, high = pitch_range_rad(vehicle.dive_pitch_error_rad, vehicle.climb_pitch_error_rad)
    pitches = np.linspace(low, high, PITCH_STEPS + 2)[1:-1]

    def least_ballast_cc(profile: ir.Profile) -> float:
        """Volume [cc] below which the glider stays at a yo's turning depth: its trim over
        the band the planner plans it at (0 where the band is known only in flight)."""
        args = profile.constant_args()
        if profile.kind not in ("yo", "thermotrackyo") or args is None:
            return 0.0
        return float(vehicle.trim_offset_cc(*yo_band(profile, args)))

    return FlightLimits(
        vehicle.unplanned_ballast_cc, vehicle.max_ballast_cc,
        tuple(sorted(m.clock_mhz for m in computer.clock_modes)), board=computer.name,
        max_budget_j=mission.battery.energy_j - mission.battery.reserve_j,
        pitch_range_rad=(low, high),
        max_speed_mps=float(np.max(vehicle.max_speed_mps(pitches))),
        duty_bounds=tuple(
            tuple((use.name, *duty_bounds(mission, state, use,
                                          sensor_on(vehicle, device).quality_alpha))
                  for use in state.sensors  # one logged without a duty is the plan's to cycle
                  if (device := SENSOR_BY_NAME[use.name].device) is not None
                  and use.duty is not None)
            for state in mission.states),
        min_ballast_cc=tuple(tuple(least_ballast_cc(p) for p in state.profiles)
                             for state in mission.states),
        envelope=vehicle.envelope)
