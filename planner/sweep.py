"""Tradeoff sweeps: quality against budget (the Pareto frontier), against the computer
and against the battery. The frontier is the best quality at each budget; the computer
and battery sweeps show the plan `plan.choose_plan` would fly, as `plan_mission` does.
A sweep builds the model once and only changes parameter values between solves (cvxpy's
DPP path: no re-compilation), unless the model's structure changes (`model.structure`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pandas as pd

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, Component
from gliderplan.language import ir
from gliderplan.planner.compare import COMPUTERS, compared_specs
from gliderplan.planner.hardware import load_hardware
from gliderplan.planner.inputs import build_inputs
from gliderplan.planner.model import SATURATION_TOLERANCE, PlanModel, model_for
from gliderplan.planner.plan import J_PER_WH, InfeasibleBudget, choose_plan, state_energy_j
from gliderplan.planner.rates import hardware_occupancy

BATTERIES = ("alkaline", "lithium_primary", "rechargeable")
Progress = Callable[[int, int], None]


def energy_range_j(model: PlanModel) -> tuple[float, float]:
    """(least energy the mission needs, energy at which more budget buys no quality) [J],
    as the model counts energy (the budget constraint's own measure)."""
    least = model.solve_energy(-1.0)
    if not least.optimal:
        raise ValueError(f"the mission's constraints cannot all hold ({least.status})")
    best = model.solve_quality(model.ample_budget_j())
    saturated = model.solve_energy(best.quality - SATURATION_TOLERANCE * abs(best.quality))
    return least.model_energy_j, max(saturated.model_energy_j, least.model_energy_j)


def pareto(model: PlanModel, points: int, progress: Progress | None = None) -> pd.DataFrame:
    """Best quality at `points` budgets from the minimum energy to saturation (one point
    when the minimum already saturates: a mission with nothing to trade)."""
    low, high = energy_range_j(model)
    # Nothing to trade (no duty to choose): a single point, and energy buys no quality.
    flat = high <= low * (1.0 + 1e-9)
    rows = []
    for i, budget in enumerate([low] if flat else np.linspace(low, high, points)):
        sol = model.solve_quality(float(budget))
        rows.append({"budget_j": float(budget), "budget_wh": float(budget) / J_PER_WH,
                     "quality": sol.quality, "energy_j": sol.model_energy_j,
                     "shadow_price": 0.0 if flat else (sol.budget_dual or 0.0) * J_PER_WH,
                     "status": sol.status, "solve_ms": 1000 * sol.solve_s})
        if progress:
            progress(i + 1, 1 if flat else points)
    return pd.DataFrame(rows)


def _row(model: PlanModel, budget_j: float) -> dict:
    """Minimum energy and the plan `choose_plan` flies at one budget."""
    row = {"budget_j": budget_j, "minimum_energy_j": np.nan, "status": "infeasible",
           "quality": np.nan, "energy_j": np.nan, "shadow_price": np.nan,
           "computer_j": np.nan}
    try:
        choice = choose_plan(model, budget_j)
    except InfeasibleBudget as short:
        return {**row, "minimum_energy_j": short.minimum_j}
    energies = state_energy_j(model.inputs, choice.solution)
    row.update(minimum_energy_j=choice.minimum_j, status="optimal",
               quality=choice.solution.quality,
               energy_j=float(sum(sum(e.values()) for e in energies)),
               shadow_price=choice.shadow_price,
               computer_j=float(sum(e[Component.COMPUTER] for e in energies)))
    return row


def computers(mission: ir.CheckedMission, specs: Sequence[str] = COMPUTERS,
              budget_j: float | None = None, progress: Progress | None = None,
              cycles_per_tick: float = RUNTIME_CYCLES_PER_TICK) -> pd.DataFrame:
    """The plan on each computer (and on none beside them for a `computer none` mission),
    at the mission's budget or `budget_j`. The model is re-used while its structure stays
    (a fixed clock), rebuilt when it changes (a board whose clocks the planner chooses
    among)."""
    model = None
    rows = []
    specs = compared_specs(mission, specs)
    for i, spec in enumerate(specs):
        hardware = load_hardware(mission, computer=spec, cycles_per_tick=cycles_per_tick)
        # a propelled leg's speed, and so its time, follows the board's load
        model = model_for(build_inputs(mission, hardware, hardware_occupancy(mission, hardware)),
                          model)
        budget = hardware.budget_j if budget_j is None else budget_j
        board = hardware.board
        rows.append({"computer": board.name if board.is_none
                     else f"{board.name}@{board.clock_mhz:g}", **_row(model, budget)})
        if progress:
            progress(i + 1, len(specs))
    return pd.DataFrame(rows)


def batteries(mission: ir.CheckedMission, specs: Sequence[str] = BATTERIES,
              computer: str | None = None, progress: Progress | None = None,
              cycles_per_tick: float = RUNTIME_CYCLES_PER_TICK) -> pd.DataFrame:
    """The plan with each battery (only the budget changes)."""
    model = None
    rows = []
    for i, spec in enumerate(specs):
        hardware = load_hardware(mission, battery=spec, computer=computer,
                                 cycles_per_tick=cycles_per_tick)
        if model is None:
            model = model_for(build_inputs(mission, hardware,
                                           hardware_occupancy(mission, hardware)))
        rows.append({"battery": spec, "battery_j": hardware.battery_j,
                     "reserve_fraction": hardware.reserve_fraction,
                     **_row(model, hardware.budget_j)})
        if progress:
            progress(i + 1, len(specs))
    return pd.DataFrame(rows)


def plot_pareto(frame: pd.DataFrame, title: str) -> bytes:
    """PNG of quality against budget, with the shadow price on a second axis."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
    ax.plot(frame["budget_wh"], frame["quality"], "o-", color="tab:blue", ms=3)
    ax.set_xlabel("energy budget [Wh]")
    ax.set_ylabel("quality [1]", color="tab:blue")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    price = ax.twinx()
    price.plot(frame["budget_wh"], frame["shadow_price"], "--", color="tab:red")
    price.set_ylabel("shadow price [quality per Wh]", color="tab:red")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    plt.close(fig)
    return buffer.getvalue()
