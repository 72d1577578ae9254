"""Which board, and when does the answer flip: single-board computers compared on one mission.

Each board is planned on the mission at the same battery (`choose_plan`, as
`gliderplan plan --computer` would), and its energy over the plan is split by what the
board does each tick (`Board.tick_energy`): run the tick's work (active), idle or sleep
until the next tick, wake up, plus one boot. Endurance is the usable battery spent at
the mission's own plan's vehicle and sensor power (the same sampling plan) plus each
board's mean power.

The crossover: a board's energy on the mission against the workload per tick (the same
cycles in every state, the states' times from its plan) is piecewise linear, and a
board that cannot keep up drops out. Where the ranking of the boards changes, the
workload is found by bisection, and said in cycles per tick and in reference
computations per tick beyond the runtime's own work.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import NO_BOARD, RUNTIME_CYCLES_PER_TICK, TICK_S, Component
from gliderplan.contract.units import to_model_unit
from gliderplan.language import ir
from gliderplan.planner.hardware import Hardware, HardwareError, load_hardware
from gliderplan.planner.inputs import build_inputs
from gliderplan.planner.model import model_for
from gliderplan.planner.plan import (
    InfeasibleBudget,
    PlanningError,
    PlanResult,
    assemble,
    choose_plan,
    least_energy_plan,
)
from gliderplan.planner.planfile import Plan
from gliderplan.planner.rates import hardware_occupancy
from gliderplan.power_models.board import Board, board_spec
from gliderplan.power_models.computation import equivalents
from gliderplan.power_models.datafile import file_entries, is_assumption

COMPUTERS = ("ts5500", "ts7800@300", "ts7800@500")
SECONDS_PER_DAY = 86400.0
_BISECTIONS = 60  # halvings of a workload interval in log space: far below a cycle
_GRID_POINTS = 600


@dataclass(frozen=True)
class BoardEnergy:
    """A board's energy [J] on a mission, by what it does."""

    active_j: float  # running the ticks' work
    idle_j: float  # idling between ticks
    sleep_j: float  # asleep between ticks
    wake_j: float  # waking up for the next tick
    boot_j: float  # booting once for the mission

    @property
    def total_j(self) -> float:
        return self.active_j + self.idle_j + self.sleep_j + self.wake_j + self.boot_j


@dataclass(frozen=True)
class RuntimeCode:
    """The runtime's own code on a board beside the workload the boards are compared at:
    its instructions a tick measured on the board's build, in cycles, and what the rest
    of the workload (the kernel's system calls and interrupts, not measured) costs."""

    instructions: float  # [instructions per tick] (board file: runtime_instructions)
    cycles_per_instruction: float  # [cycles] (board file: cycles_per_instruction)
    sources: dict[str, str]  # data-file key -> its source
    cycles: float  # [cycles per tick] instructions x cycles per instruction
    share: float  # [1] of the workload compared at
    rest_j: float  # the board's energy on the mission at the workload less at the code alone


@dataclass(frozen=True)
class BoardResult:
    """One board on the mission."""

    name: str  # "ts7800@300", or a board file's name with its clock
    hardware: Hardware
    planned: PlanResult  # status "infeasible": the least-energy plan, beyond the battery
    energy: BoardEnergy
    endurance_days: float  # usable battery at the reference plan's vehicle and sensors
    assumptions: dict[str, str]  # data-file key -> figure and source, for assumed figures
    runtime_code: RuntimeCode | None = None  # None: not measured on this board's build

    @property
    def board(self) -> Board:
        return self.hardware.board

    @property
    def share(self) -> float:
        """Fraction [1] of the mission's energy the board draws."""
        mission_j = self.planned.plan.predicted_j
        return self.energy.total_j / mission_j if mission_j else 0.0


@dataclass(frozen=True)
class Crossover:
    """A workload at which the ranking of the boards changes."""

    cycles_per_tick: float  # [cycles]
    before: tuple[str, ...]  # ranking just below, cheapest first (boards that keep up)
    after: tuple[str, ...]  # ranking just above
    reason: str

    @property
    def equivalents(self) -> dict[str, float]:
        """Reference computations per tick beyond the runtime's own work."""
        return equivalents(max(self.cycles_per_tick - RUNTIME_CYCLES_PER_TICK, 0.0))


@dataclass(frozen=True)
class Comparison:
    mission: str
    cycles_per_tick: float  # the workload the boards were planned at [cycles]
    battery_j: float
    budget_j: float
    reference: str  # the board whose plan sets the sampling plan for endurance
    boards: tuple[BoardResult, ...]
    workload: np.ndarray  # (n,) [cycles per tick] of the energy curves
    curves_j: dict[str, np.ndarray]  # board -> (n,) energy on the mission [J]; NaN: cannot
    crossovers: tuple[Crossover, ...]


def compared_specs(mission: ir.CheckedMission, specs: Sequence[str]) -> tuple[str, ...]:
    """The boards to compare on `mission`: `specs`, and for a `computer none` mission
    `none` as well, so that what each board adds to the glider's own computers shows."""
    extra = (NO_BOARD,) if mission.computer.is_none and NO_BOARD not in specs else ()
    return (*specs, *extra)


def board_label(hardware: Hardware) -> str:
    """"ts7800@300" for a board held at one of its clocks; the bare name for a board of
    one clock ("ts5500") or whose clock the planner picks ("ts7800")."""
    board = hardware.board
    fixed = len(hardware.modes) == 1 and len(board.clock_modes) > 1
    return f"{board.name}@{board.clock_mhz:g}" if fixed else board.name


def plan_energy(hardware: Hardware, plan: Plan) -> BoardEnergy:
    """The board's energy over `plan`, split by what it does each tick (each state's work
    per tick at the clock the plan sets, asleep between ticks where the plan says) and one
    boot."""
    parts = np.zeros(4)
    for state in plan.states:
        board = hardware.board.at_clock(state.clock_mhz)
        tick = board.tick_energy(state.cycles_per_tick, TICK_S, state.sleep)
        parts += state.time_s / TICK_S * np.array(
            [float(tick.active_j), float(tick.idle_j), float(tick.sleep_j), float(tick.wake_j)])
    return BoardEnergy(*(float(p) for p in parts), hardware.board.boot_j)


def energy_curve_j(hardware: Hardware, mission: ir.CheckedMission, plan: Plan,
                   workload: np.ndarray) -> np.ndarray:
    """(n,) the board's energy [J] on the mission at each workload [cycles per tick] of
    the states without a `computer workload` of their own, the states' times those of
    `plan`, each state at its cheapest clock and asleep between ticks where it sleeps;
    NaN where no clock keeps up."""
    total = np.full(len(workload), hardware.board.boot_j)
    for state, planned in zip(mission.states, plan.states, strict=True):
        cycles = workload if state.computer.cycles_per_tick is None \
            else np.full(len(workload), state.computer.cycles_per_tick)
        per_tick = np.array([m.tick_energy(cycles, TICK_S, hardware.sleeps(state)).total_j
                             for m in hardware.clocks(state)])
        with np.errstate(all="ignore"):
            cheapest = np.where(np.isnan(per_tick).all(axis=0), np.nan,
                                np.nanmin(np.where(np.isnan(per_tick), np.inf, per_tick),
                                          axis=0))
        total = total + planned.time_s / TICK_S * cheapest
    return total


def _ranking(energies: dict[str, float]) -> tuple[str, ...]:
    """Boards that keep up, cheapest first."""
    return tuple(sorted((n for n, e in energies.items() if np.isfinite(e)),
                        key=lambda n: energies[n]))


Curve = Callable[[np.ndarray], dict[str, np.ndarray]]  # workloads -> board -> energy [J]


def crossovers(curve: Curve, names: Sequence[str], workload: np.ndarray
               ) -> tuple[Crossover, ...]:
    """Where the ranking of `curve(workload) -> {name: energy}` changes on the grid,
    each found by bisection between the grid points around it."""
    def rank_at(w: float) -> tuple[str, ...]:
        values = curve(np.array([w]))
        return _ranking({n: float(values[n][0]) for n in names})

    grid = curve(workload)
    ranks = [_ranking({n: float(grid[n][i]) for n in names}) for i in range(len(workload))]
    found = []
    for i in range(1, len(workload)):
        if ranks[i] == ranks[i - 1]:
            continue
        low, high = float(np.log(workload[i - 1])), float(np.log(workload[i]))
        before = ranks[i - 1]
        for _ in range(_BISECTIONS):
            middle = 0.5 * (low + high)
            if rank_at(float(np.exp(middle))) == before:
                low = middle
            else:
                high = middle
        after = rank_at(float(np.exp(high)))
        found.append(Crossover(float(np.exp(high)), before, after, _reason(before, after)))
    return tuple(found)


def _reason(before: tuple[str, ...], after: tuple[str, ...]) -> str:
    dropped = [n for n in before if n not in after]
    if not after:
        return "no board keeps up beyond this workload"
    if dropped:
        return f"{', '.join(dropped)} cannot keep up beyond this workload"
    swapped = [n for n in before if before.index(n) != after.index(n)]
    return f"{' and '.join(swapped)} cost the same here; beyond it their order reverses"


def assumed_figures(spec: str, hardware: Hardware, sleeping: bool) -> dict[str, str]:
    """The figures of a board's data file that this comparison uses and whose source says
    they are assumptions: data-file key -> "value unit: source". Clock modes the board is
    not held at are left out, and the sleep figures unless a state sleeps on it."""
    path, _ = board_spec(spec)
    if path is None:  # none: no board, no figures
        return {}
    entries = file_entries(path)
    clocks = {m.clock_mhz for m in (hardware.modes if hardware.held else hardware.board_modes)}
    unused = {key.split(".")[0] for key, value, unit, _ in entries
              if key.startswith("mode[") and key.endswith(".clock")
              and to_model_unit(value, unit, "clock") not in clocks}
    return {key: f"{value:g} {unit}: {source}" for key, value, unit, source in entries
            if is_assumption(source) and key.split(".")[0] not in unused
            and (sleeping or not (key.startswith("sleep.") or key.endswith(".wake_energy")))}


def runtime_code(hardware: Hardware, mission: ir.CheckedMission, plan: Plan,
                 cycles_per_tick: float) -> RuntimeCode | None:
    """The runtime's measured code on the board against `cycles_per_tick` [cycles] on
    `plan`'s times (`energy_curve_j`); None where the board file gives no measurement."""
    board = hardware.board
    cycles = board.runtime_code_cycles
    if cycles is None or board.path is None:
        return None
    sources = {key: source for key, _, _, source in file_entries(board.path)
               if key in ("runtime_instructions", "cycles_per_instruction")}
    at = energy_curve_j(hardware, mission, plan, np.array([cycles_per_tick, cycles]))
    return RuntimeCode(float(board.runtime_instructions), float(board.cycles_per_instruction),
                       sources, cycles, cycles / cycles_per_tick, float(at[0] - at[1]))


def compare_boards(mission: ir.CheckedMission, specs: Sequence[str] = COMPUTERS, *,
                   battery: str | None = None,
                   cycles_per_tick: float = RUNTIME_CYCLES_PER_TICK) -> Comparison:
    """The boards of `specs` ("ts5500", "ts7800@500", a board file) planned on `mission`
    with `battery` (default: the mission's) at `cycles_per_tick`, and the workloads at
    which their ranking flips; a `computer none` mission adds `none` (`compared_specs`),
    which draws nothing beside the boards and so takes no part in their ranking. Raises
    HardwareError/ModelFileError for a bad spec, PlanningError when the mission cannot be
    planned at all."""
    reference_hw = load_hardware(mission, battery=battery, cycles_per_tick=cycles_per_tick)
    occupancy = hardware_occupancy(mission, reference_hw)
    model = model_for(build_inputs(mission, reference_hw, occupancy))
    reference = _plan(model, reference_hw.budget_j).plan
    flown_s = sum(s.time_s for s in reference.states)
    if flown_s <= 0.0:
        raise PlanningError(f"mission {mission.name} flies for 0 s (it exits on its first "
                            "tick): boards are compared by the power they draw over a "
                            "mission's time")
    others_w = (reference.predicted_j - reference.components_j[Component.COMPUTER]) / flown_s
    results = []
    for spec in compared_specs(mission, specs):
        hardware = load_hardware(mission, battery=battery, computer=spec,
                                 cycles_per_tick=cycles_per_tick)
        model = model_for(build_inputs(mission, hardware, occupancy), model)
        planned = _plan(model, hardware.budget_j)
        energy = plan_energy(hardware, planned.plan)
        board_w = (energy.total_j - energy.boot_j) / sum(s.time_s for s in planned.plan.states)
        endurance = hardware.budget_j / (others_w + board_w) / SECONDS_PER_DAY
        name = board_label(hardware)
        if any(r.name == name for r in results):
            raise HardwareError(f"--computer {spec}: {name} is compared already")
        results.append(BoardResult(name, hardware, planned, energy, endurance,
                                   assumed_figures(spec, hardware, any(
                                       hardware.sleeps(st) for st in mission.states)),
                                   runtime_code(hardware, mission, planned.plan,
                                                cycles_per_tick)))
    boards = [r for r in results if not r.board.is_none]
    capacity = max((m.cycles_per_s * TICK_S for r in boards for m in r.hardware.board_modes),
                   default=10.0 * cycles_per_tick)  # none alone: it has no capacity to reach
    workload = np.geomspace(min(1e4, cycles_per_tick), 1.1 * capacity, _GRID_POINTS)

    def curve(w: np.ndarray) -> dict[str, np.ndarray]:
        return {r.name: energy_curve_j(r.hardware, mission, r.planned.plan, w)
                for r in results}

    names = [r.name for r in boards]
    return Comparison(mission.name, cycles_per_tick, reference_hw.battery_j,
                      reference_hw.budget_j, board_label(reference_hw), tuple(results),
                      workload, curve(workload), crossovers(curve, names, workload))


def _plan(model, budget_j: float) -> PlanResult:
    """The plan `choose_plan` flies at `budget_j`, or the least-energy plan (status
    "infeasible") when the budget cannot buy the mission on this board."""
    try:
        return assemble(model.inputs, choose_plan(model, budget_j))
    except InfeasibleBudget:
        return least_energy_plan(model, budget_j)

