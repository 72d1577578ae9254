"""The limits a plan must keep on the vehicle and board it flies on (`contract.FlightLimits`),
loaded from their power-model files."""

from __future__ import annotations

from typing import TYPE_CHECKING

from gliderplan.contract import FlightLimits
from gliderplan.language.ir import CheckedMission

if TYPE_CHECKING:
    from gliderplan.power_models.vehicle import Vehicle


def flight_limits(mission: CheckedMission, board: str | None = None) -> FlightLimits:
    """The limits of the mission's vehicle on `board` (a preset or a board file; default the
    mission's computer). Raises ModelFileError for a file that cannot be loaded."""
    from gliderplan.power_models import load_board, load_vehicle

    computer = load_board(board if board is not None else mission.computer.board)
    return vehicle_limits(mission, load_vehicle(mission.vehicle),
                          tuple(sorted(m.clock_mhz for m in computer.clock_modes)))


def vehicle_limits(mission: CheckedMission, vehicle: Vehicle,
                   clocks_mhz: tuple[float, ...]) -> FlightLimits:
    """The limits of `mission` flown by `vehicle` on a board of `clocks_mhz` [MHz]: its pump,
    and without a plan the buoyancy volume, the first alternative of each state it can fly
    and, for a propelled profile's `auto` speed, the least energy per metre for its hotel
    load alone (the computer's is the plan's to add)."""
    from gliderplan.language.registry import cannot_fly
    from gliderplan.planner.speed import best_speed
    from gliderplan.power_models.devices import base_power_w

    speed = 0.0 if vehicle.propulsion is None else \
        best_speed(vehicle.propulsion, base_power_w(vehicle)).speed_mps
    flown = tuple(next((k for k, p in enumerate(state.profiles)
                        if cannot_fly(p.kind, p.thrust, vehicle) is None), 0)
                  for state in mission.states)
    return FlightLimits(vehicle.unplanned_ballast_cc, vehicle.max_ballast_cc, clocks_mhz,
                        speed, flown)
