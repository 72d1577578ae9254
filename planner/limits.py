"""The limits a plan must keep on the vehicle and board it flies on (`contract.FlightLimits`),
loaded from their power-model files."""

from __future__ import annotations

from gliderplan.contract import FlightLimits
from gliderplan.language.ir import CheckedMission


def flight_limits(mission: CheckedMission, board: str | None = None) -> FlightLimits:
    """The limits of the mission's vehicle on `board` (a preset or a board file; default the
    mission's computer). Raises ModelFileError for a file that cannot be loaded."""
    from gliderplan.power_models import load_board, load_vehicle

    vehicle = load_vehicle(mission.vehicle)
    computer = load_board(board if board is not None else mission.computer.board)
    return FlightLimits(vehicle.unplanned_ballast_cc, vehicle.max_ballast_cc,
                        tuple(sorted(m.clock_mhz for m in computer.clock_modes)))
