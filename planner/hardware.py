"""The hardware a plan is made for: vehicle, computer (and the clocks it may run at),
battery, and the sensor devices the mission logs, from the mission's annotations or
from overrides given on the command line."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from gliderplan.contract import MAX_PLAN_ENERGY_J, RUNTIME_CYCLES_PER_TICK, ExitCode, same_clock
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import ir
from gliderplan.language.registry import SENSOR_BY_NAME
from gliderplan.planner.speed import STILL_WATER, Leg
from gliderplan.power_models import load_battery, load_board, load_vehicle
from gliderplan.power_models.battery import energy_to_j, usable_budget_j
from gliderplan.power_models.board import Board, board_spec
from gliderplan.power_models.catalog import preset_names
from gliderplan.power_models.devices import sensor_on
from gliderplan.power_models.sensor import Sensor
from gliderplan.power_models.vehicle import Vehicle

_ENERGY = re.compile(
    r"^\s*(?P<value>[0-9]+(?:\.[0-9]+)?(?:[eE][-+]?[0-9]+)?)\s*(?P<unit>[A-Za-z]+)"
    r"(?:\s*(?:@|at)\s*(?P<volts>[0-9]+(?:\.[0-9]+)?)\s*V)?\s*$")


class HardwareError(GliderplanError, ValueError):
    """A hardware option the planner cannot use (a malformed --battery); the message says
    which and why."""

    exit_code = ExitCode.USAGE


@dataclass(frozen=True)
class Hardware:
    vehicle: Vehicle
    board: Board  # at the mission's (or default) clock
    modes: tuple[Board, ...]  # clocks the planner may choose between, slowest first
    battery_j: float  # [J] stored energy
    reserve_fraction: float  # [1] kept unused
    devices: dict[str, Sensor]  # device name -> power model, for every device the mission logs
    overridden: frozenset[str] = frozenset()  # annotations replaced by the caller
    cycles_per_tick: float = RUNTIME_CYCLES_PER_TICK  # work per tick of states that say none
    board_modes: tuple[Board, ...] = ()  # every clock of the board, slowest first
    held: bool = False  # every state at `modes`, whatever its `computer clock` says
    # the water it flies: state -> its route's legs with their currents
    # (`planner.water.route_legs`); a state without is planned in still water
    legs: dict[str, tuple[Leg, ...]] = field(default_factory=dict)
    water_notes: tuple[str, ...] = ()  # where the current came from, for the assumptions

    @property
    def budget_j(self) -> float:
        """Usable energy [J] = (1 - reserve) x battery (power_models.battery.usable_budget_j)."""
        return usable_budget_j(self.battery_j, self.reserve_fraction)

    def clocks(self, state: ir.State) -> tuple[Board, ...]:
        """The board at each clock a state may run at: its `computer clock` (one, or all
        of the board's for `auto`), else the mission's."""
        use = state.computer
        if self.held or (use.clock_mhz is None and not use.clock_auto):
            return self.modes
        if use.clock_auto:
            return self.board_modes
        return tuple(m for m in self.board_modes if same_clock(use.clock_mhz, m.clock_mhz))

    def sleeps(self, state: ir.State) -> bool:
        """Whether the board sleeps between ticks in `state`: the state asks, the board can."""
        return state.computer.sleep and self.board.sleep is not None

    def cycles(self, state: ir.State) -> float:
        """The board's work every tick in `state` [cycles]: its own, else the mission's."""
        return state.computer.cycles_per_tick or self.cycles_per_tick

    def water(self, state: ir.State) -> tuple[Leg, ...]:
        """The legs `state`'s speed is chosen for: its route's in the plan's current, else
        still water."""
        return self.legs.get(state.name, STILL_WATER)


def parse_battery(spec: str) -> tuple[float, float | None]:
    """(energy [J], reserve fraction or None) of "1.2kWh", "500 Wh",
    "60Ah@14.4V" or a battery preset ("alkaline"; its usable fraction sets the reserve)."""
    if spec in preset_names("battery"):
        pack = load_battery(spec)
        return pack.energy_j, 1.0 - pack.usable_fraction
    match = _ENERGY.match(spec)
    if match is None:
        raise HardwareError(
            f"--battery {spec!r}: expected an energy such as 1.2kWh, 500Wh, 60Ah@14.4V, "
            f"or a preset ({', '.join(preset_names('battery'))})")
    volts = float(match["volts"]) if match["volts"] else None
    try:
        energy = energy_to_j(float(match["value"]), match["unit"], volts)
    except ValueError as err:
        raise HardwareError(f"--battery {spec!r}: {err}") from None
    if not 0.0 < energy < math.inf:
        raise HardwareError(f"--battery {spec!r}: the energy must be positive and finite")
    if energy > MAX_PLAN_ENERGY_J:
        raise HardwareError(f"--battery {spec!r}: larger than any plan can carry "
                            f"({MAX_PLAN_ENERGY_J:g} J; the largest Slocum pack holds 12 MJ)")
    return energy, None


def mission_devices(mission: ir.CheckedMission) -> list[str]:
    """Power-model devices behind the sensors the mission logs, in first-use order."""
    names = (SENSOR_BY_NAME[u.name].device for s in mission.states for u in s.sensors)
    return list(dict.fromkeys(d for d in names if d))


def load_hardware(mission: ir.CheckedMission, *, battery: str | None = None,
                  computer: str | None = None,
                  cycles_per_tick: float = RUNTIME_CYCLES_PER_TICK) -> Hardware:
    """The mission's hardware with optional overrides (`battery` as for `parse_battery`,
    `computer` as "ts7800", "ts7800@500" or a board file). A computer given without a
    clock lets the planner choose among the board's clocks (and the states' own `computer
    clock` settings apply); with one, every state runs at it. `cycles_per_tick` is the
    board's work every tick in states that do not say (`computer workload`)."""
    vehicle = load_vehicle(mission.vehicle)
    if computer is None:
        spec, clock = mission.computer.board, mission.computer.clock_mhz
    else:
        spec, clock = computer, board_spec(computer)[1]
    board = load_board(spec, clock)
    board_modes = tuple(board.modes())
    modes = (board,) if clock is not None else board_modes
    # A clock given on the command line holds every state at it (a board compared at
    # one clock); so does a board that has one.
    held = (computer is not None and clock is not None) or len(board_modes) == 1
    for state in mission.states:
        wanted = state.computer.clock_mhz
        if not held and wanted is not None and not board.has_clock(wanted):
            raise HardwareError(f"state {state.name}: computer clock {wanted:g} MHz: board "
                                f"{board.name} has no such clock; --computer NAME@MHZ holds "
                                "every state at one clock")
    if battery is None:
        energy, reserve = mission.battery.energy_j, mission.battery.reserve_fraction
    else:
        energy, preset_reserve = parse_battery(battery)
        reserve = mission.battery.reserve_fraction if preset_reserve is None else preset_reserve
    devices = {d: sensor_on(vehicle, d) for d in mission_devices(mission)}
    overridden = frozenset(k for k, v in (("battery", battery), ("computer", computer)) if v)
    return Hardware(vehicle, board, modes, energy, reserve, devices, overridden,
                    cycles_per_tick, board_modes, held)
