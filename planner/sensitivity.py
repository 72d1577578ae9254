"""Which assumption matters most: the plan's energy and quality when each model figure moves.

Each figure the plan rests on (the vehicle's energy and drag figures, the board's active
and idle power, each sensor device's on-power, the runtime's workload per tick) is moved
down and up by one standard deviation where its data file gives one (`sd`, from
calibration), else by 20 %, and the mission is planned again at the same budget with
`choose_plan` (the plan `gliderplan plan` would make with that figure). The model is
built once; a figure only changes parameter values (`model_for` re-uses it while the
structure holds), so a tornado of ~30 plans costs about as much as a short sweep.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

from gliderplan.language import ir
from gliderplan.planner.hardware import Hardware
from gliderplan.planner.inputs import PlanInputError, build_inputs
from gliderplan.planner.model import PlanModel, model_for
from gliderplan.planner.occupancy import Occupancy
from gliderplan.planner.plan import InfeasibleBudget, choose_plan, realised_energy_j
from gliderplan.power_models.vehicle import figure_value, with_figures

DEFAULT_SPREAD = 0.20  # relative move of a figure without a stated uncertainty
SOLVER_TOLERANCE = 1e-6  # relative change below which a figure moved nothing
# Vehicle figures that move energy (the depths and pitch a mission sets are not figures
# of the model): data-file key -> unit shown.
VEHICLE_FIGURES = {
    "hotel_power": "W", "pump_out_energy_per_volume": "J/cc",
    "pump_in_energy_per_volume": "J/cc", "pitch_energy": "J", "surface_power": "W",
    "iridium_power": "W", "iridium_time": "s", "surfacing_energy": "J",
    "flight.drag_cd0": "1", "pump_rate": "cc/s",
}


@dataclass(frozen=True)
class Swing:
    """The plan with one figure moved down and up."""

    figure: str  # "vehicle hotel_power", "board idle_power", "sensor ctd on_power", ...
    value: float  # the figure as the model has it
    unit: str
    step: float  # how far it moves either way [its unit]
    basis: str  # "1 sd (calibration)" or "20 % (no stated uncertainty)"
    energy_j: tuple[float, float]  # mission energy [J] with the figure down, up
    quality: tuple[float, float]  # plan quality with the figure down, up (NaN: over budget)


@dataclass(frozen=True)
class Sensitivity:
    energy_j: float  # the plan's energy [J] with every figure as it is
    quality: float
    budget_j: float
    swings: tuple[Swing, ...]  # the one that moves energy or quality most first


Change = Callable[[Hardware, float], Hardware]  # hardware with the figure at a value


def _vehicle(key: str) -> Change:
    return lambda hw, v: replace(hw, vehicle=with_figures(hw.vehicle, {key: v}))


def _board(attr: str) -> Change:
    def change(hw: Hardware, v: float) -> Hardware:
        scale = v / getattr(hw.board, attr) if getattr(hw.board, attr) else 1.0
        def scaled(boards: tuple) -> tuple:
            return tuple(replace(m, **{attr: getattr(m, attr) * scale}) for m in boards)
        return replace(hw, board=replace(hw.board, **{attr: v}), modes=scaled(hw.modes),
                       board_modes=scaled(hw.board_modes))
    return change


def _device(name: str) -> Change:
    return lambda hw, v: replace(hw, devices={**hw.devices, name: replace(
        hw.devices[name], on_power_w=v)})


def _workload(hw: Hardware, v: float) -> Hardware:
    return replace(hw, cycles_per_tick=v)


def figures(hardware: Hardware) -> list[tuple[str, float, str, float, str, Change]]:
    """(figure, value, unit, step, basis, change) of every figure the tornado moves."""
    vehicle = hardware.vehicle
    spread = {} if vehicle.uncertainty is None else dict(
        zip(vehicle.uncertainty.keys, vehicle.uncertainty.sd, strict=True))
    rows = []

    def add(name: str, value: float, unit: str, change: Change, sd: float | None = None):
        if sd:
            rows.append((name, value, unit, float(sd), "1 sd (calibration)", change))
        elif value:
            rows.append((name, value, unit, DEFAULT_SPREAD * abs(value),
                         f"{100 * DEFAULT_SPREAD:g} % (no stated uncertainty)", change))

    for key, unit in VEHICLE_FIGURES.items():
        add(f"vehicle {key}", figure_value(vehicle, key), unit, _vehicle(key), spread.get(key))
    for key in spread.keys() - VEHICLE_FIGURES.keys():
        add(f"vehicle {key}", figure_value(vehicle, key), "", _vehicle(key), spread[key])
    add(f"board {hardware.board.name} active_power", hardware.board.active_w, "W",
        _board("active_w"))
    add(f"board {hardware.board.name} idle_power", hardware.board.idle_w, "W",
        _board("idle_w"))
    for name, sensor in hardware.devices.items():
        add(f"sensor {name} on_power", sensor.on_power_w, "W", _device(name))
    add("runtime workload per tick", hardware.cycles_per_tick, "cycles", _workload)
    return rows


def _outcome(mission: ir.CheckedMission, hardware: Hardware, occupancy: Occupancy,
             model: PlanModel, budget_j: float) -> tuple[float, float, PlanModel]:
    """(energy [J], quality) of the plan at `budget_j`; over budget: (least energy, NaN)."""
    model = model_for(build_inputs(mission, hardware, occupancy), model)
    try:
        choice = choose_plan(model, budget_j)
    except InfeasibleBudget as short:
        return short.minimum_j, math.nan, model
    return realised_energy_j(model.inputs, choice.solution), choice.solution.quality, model


def _settled(value: float, base: float) -> float:
    """`value`, or `base` when they differ by no more than the solver's tolerance."""
    return base if abs(value - base) <= SOLVER_TOLERANCE * max(abs(base), 1e-12) else value


def sensitivity(model: PlanModel) -> Sensitivity:
    """The tornado of a built model's mission at its hardware's budget."""
    inputs = model.inputs
    mission, hardware, occupancy = inputs.mission, inputs.hardware, inputs.occupancy
    budget = hardware.budget_j
    energy, quality, model = _outcome(mission, hardware, occupancy, model, budget)
    swings = []
    for name, value, unit, step, basis, change in figures(hardware):
        results = []
        for moved in (value - step, value + step):
            try:
                results.append(_outcome(mission, change(hardware, max(moved, 0.0)),
                                        occupancy, model, budget))
            except PlanInputError:  # e.g. a workload no clock keeps up with
                results.append((math.nan, math.nan, model))
            model = results[-1][2]
        swings.append(Swing(name, value, unit, step, basis,
                            tuple(_settled(r[0], energy) for r in results),
                            tuple(_settled(r[1], quality) for r in results)))
    model_for(inputs, model)  # the caller's model as it was

    def weight(s: Swing) -> float:
        """The larger relative move of energy and quality (a figure that breaks the
        budget counts most)."""
        moves = [abs(e - energy) / energy for e in s.energy_j] + \
            [abs(q - quality) / quality if quality else 0.0 for q in s.quality]
        return max((m if math.isfinite(m) else math.inf) for m in moves)

    swings.sort(key=weight, reverse=True)
    return Sensitivity(energy, quality, budget, tuple(swings))
