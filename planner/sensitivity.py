"""Which assumption matters most: the plan's energy and quality when each model figure moves.

Each figure the plan rests on (the vehicle's energy and drag figures, the board's active
and idle power, its sleep power and wake-up energy where a state sleeps between ticks,
each sensor device's on-power, the runtime's workload per tick) is moved
down and up by one standard deviation where its data file gives one (`sd`, from
calibration), else by 20 %, and the mission is planned again at the same budget with
`choose_plan` (the plan `gliderplan plan` would make with that figure). The model is
built once; a figure only changes parameter values (`model_for` re-uses it while the
structure holds): the thermocline survey's 44 plans take 0.46 s of CPU (bench/README.md). Each
swing carries its figure's source from the data file, so the report can say which
figures are assumptions.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK
from gliderplan.language import ir
from gliderplan.planner.hardware import Hardware
from gliderplan.planner.inputs import PlanInputError, build_inputs
from gliderplan.planner.model import PlanModel, model_for
from gliderplan.planner.occupancy import Occupancy
from gliderplan.planner.plan import InfeasibleBudget, choose_plan, realised_energy_j
from gliderplan.power_models.board import Board
from gliderplan.power_models.datafile import figure_sources, is_assumption
from gliderplan.power_models.vehicle import figure_unit, figure_value, with_figures

DEFAULT_SPREAD = 0.20  # relative move of a figure without a stated uncertainty
SOLVER_TOLERANCE = 1e-6  # relative change below which a figure moved nothing
SOURCES_JOINT = "; "  # between the sources of a figure given once per clock
# Vehicle figures that move energy (the depths and pitch a mission sets are not figures
# of the model), by data-file key; each is shown in the model's unit (`figure_unit`).
VEHICLE_FIGURES = (
    "hotel_power", "pump_out_energy_per_volume", "pump_in_energy_per_volume", "pitch_energy",
    "surface_power", "iridium_power", "iridium_time", "surfacing_energy", "flight.drag_cd0",
    "pump_rate",
)


@dataclass(frozen=True)
class Swing:
    """The plan with one figure moved down and up."""

    figure: str  # "vehicle hotel_power", "board idle_power", "sensor ctd on_power", ...
    value: float  # the figure as the model has it
    unit: str
    step: float  # how far it moves either way [its unit]
    basis: str  # "1 sd (calibration)" or "20 % (no stated uncertainty)"
    source: str  # what the figure rests on, as its data file says ("; " between several)
    energy_j: tuple[float, float]  # mission energy [J] with the figure down, up
    quality: tuple[float, float]  # plan quality with the figure down, up (NaN: over budget)

    @property
    def assumed(self) -> bool:
        """Whether the figure (or, for a board's figure, one clock's) rests on an
        assumption."""
        return is_assumption(self.source)


@dataclass(frozen=True)
class Sensitivity:
    energy_j: float  # the plan's energy [J] with every figure as it is
    quality: float
    budget_j: float
    swings: tuple[Swing, ...]  # the one that moves energy or quality most first


Change = Callable[[Hardware, float], Hardware]  # hardware with the figure at a value


@dataclass(frozen=True)
class Figure:
    """A model figure the tornado moves, and how."""

    name: str
    value: float
    unit: str
    step: float
    basis: str
    source: str
    change: Change


def _vehicle(key: str) -> Change:
    return lambda hw, v: replace(hw, vehicle=with_figures(hw.vehicle, {key: v}))


def _board_figure(read: Callable[[Board], float],
                  write: Callable[[Board, float], Board]) -> Change:
    """A figure of the board moved at every clock by the same factor."""
    def change(hw: Hardware, v: float) -> Hardware:
        base = read(hw.board)
        scale = v / base if base else 1.0

        def moved(board: Board) -> Board:
            return write(board, read(board) * scale)
        return replace(hw, board=moved(hw.board), modes=tuple(map(moved, hw.modes)),
                       board_modes=tuple(map(moved, hw.board_modes)))
    return change


def _board(attr: str) -> Change:
    return _board_figure(lambda b: getattr(b, attr), lambda b, v: replace(b, **{attr: v}))


def _sleep(attr: str) -> Change:
    return _board_figure(lambda b: getattr(b.sleep, attr),
                         lambda b, v: replace(b, sleep=replace(b.sleep, **{attr: v})))


def _device(name: str) -> Change:
    return lambda hw, v: replace(hw, devices={**hw.devices, name: replace(
        hw.devices[name], on_power_w=v)})


def _workload(hw: Hardware, v: float) -> Hardware:
    return replace(hw, cycles_per_tick=v)


def _sources(path: Path | None, key: str) -> str:
    """The data file's sources of a figure, or "" for a model built without a file."""
    return SOURCES_JOINT.join(figure_sources(path, key)) if path is not None else ""


def figures(hardware: Hardware, mission: ir.CheckedMission) -> list[Figure]:
    """Every figure the tornado moves for `mission`: the vehicle's, the board's active and
    idle power (and its sleep power and wake-up energy where a state sleeps), each
    device's on-power and the runtime's workload, each with its data file's source."""
    vehicle, board = hardware.vehicle, hardware.board
    spread = {} if vehicle.uncertainty is None else dict(
        zip(vehicle.uncertainty.keys, vehicle.uncertainty.sd, strict=True))
    rows = []

    def add(name: str, value: float, unit: str, change: Change, source: str,
            sd: float | None = None) -> None:
        if sd:
            rows.append(Figure(name, value, unit, float(sd), "1 sd (calibration)", source,
                               change))
        elif value:
            rows.append(Figure(name, value, unit, DEFAULT_SPREAD * abs(value),
                               f"{100 * DEFAULT_SPREAD:g} % (no stated uncertainty)", source,
                               change))

    for key in [*VEHICLE_FIGURES, *sorted(spread.keys() - set(VEHICLE_FIGURES))]:
        add(f"vehicle {key}", figure_value(vehicle, key), figure_unit(key),
            _vehicle(key), _sources(vehicle.path, key), spread.get(key))
    for key, attr in (("active_power", "active_w"), ("idle_power", "idle_w")):
        add(f"board {board.name} {key}", getattr(board, attr), "W", _board(attr),
            _sources(board.path, key))
    if any(hardware.sleeps(state) for state in mission.states):
        add(f"board {board.name} sleep_power", board.sleep.power_w, "W", _sleep("power_w"),
            _sources(board.path, "sleep.power"))
        add(f"board {board.name} wake_energy", board.sleep.wake_j, "J", _sleep("wake_j"),
            _sources(board.path, "wake_energy"))
    for name, sensor in hardware.devices.items():
        add(f"sensor {name} on_power", sensor.on_power_w, "W", _device(name),
            _sources(sensor.path, "on_power"))
    workload = "assumption: the runtime's whole tick (contract.RUNTIME_CYCLES_PER_TICK)" \
        if hardware.cycles_per_tick == RUNTIME_CYCLES_PER_TICK else "given (--cycles-per-tick)"
    if board.runtime_code_cycles is not None:
        workload += (f"; the runtime's own code measured on this board's build is "
                     f"{board.runtime_code_cycles:,.0f} cycles of it (board file)")
    add("runtime workload per tick", hardware.cycles_per_tick, "cycles", _workload, workload)
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
    for f in figures(hardware, mission):
        results = []
        for moved in (f.value - f.step, f.value + f.step):
            try:
                results.append(_outcome(mission, f.change(hardware, max(moved, 0.0)),
                                        occupancy, model, budget))
            except PlanInputError:  # e.g. a workload no clock keeps up with
                results.append((math.nan, math.nan, model))
            model = results[-1][2]
        swings.append(Swing(f.name, f.value, f.unit, f.step, f.basis, f.source,
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
