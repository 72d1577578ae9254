"""A plan held to its mission: the one test of what a plan asks for against the battery,
the board, the sensors' duty bounds and the vehicle's flight model.

A plan file can be well formed, within the contract's bounds and signed, and still
contradict its mission: a budget larger than the battery, a prediction of 0 J, a sensor off
that a state requires, a board other than the mission's, a glide the vehicle cannot fly,
level flight (a propelled profile) or a thrust on a vehicle without propulsion, a propelled
speed outside its propulsion's range or a thrust outside its thruster's power command.
`plan_problem` finds the first such contradiction; the plan readers (Python's
`planner.planfile.read_plan_bytes` and the runtime's `gp_plan_read`, through
`gp_plan_check`, which mirrors this function rule for rule and message for message) refuse
the plan with it, wherever a plan enters: `sim`, `compile`, the runtime at start and over
the link. The figures are those of `FlightLimits` (`planner.limits.flight_limits`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from gliderplan.contract import NO_BOARD, PLAN_ROUNDING, FlightLimits

if TYPE_CHECKING:
    from gliderplan.planner.planfile import Plan

# Lines of the plan file's header (docs/plan-format.md): fixed by the format.
COMPUTER_LINE, BUDGET_LINE, PREDICTED_LINE = 4, 5, 6


@dataclass(frozen=True)
class PlanProblem:
    """Where a plan contradicts its mission: the plan file's line and what is wrong, the
    field first (the runtime says the same, "line N: message")."""

    line: int
    message: str


def _above(value: float, bound: float) -> bool:
    """`value` exceeds `bound` by more than the plan file's rounding."""
    return value > bound + PLAN_ROUNDING * abs(bound)


def plan_problem(plan: Plan, limits: FlightLimits) -> PlanProblem | None:
    """The first contradiction between `plan` and the mission, vehicle and board of
    `limits` (None: none), in the order `gp_plan_check` looks: the board, the budget, the
    prediction, then each state's sensors and profiles."""
    if limits.board is not None and plan.computer not in (limits.board, NO_BOARD):
        return PlanProblem(COMPUTER_LINE, f"computer {plan.computer}: the mission flies on "
                           f"board {limits.board} (plan again with --computer {limits.board})")
    if _above(plan.budget_j, limits.max_budget_j):
        return PlanProblem(BUDGET_LINE, f"budget_j {plan.budget_j:g} J exceeds the mission's "
                           f"battery less its reserve ({limits.max_budget_j:g} J)")
    states_j = sum(s.energy_j for s in plan.states)
    if abs(plan.predicted_j - states_j) > PLAN_ROUNDING * max(plan.predicted_j, states_j):
        return PlanProblem(PREDICTED_LINE, f"predicted_j {plan.predicted_j:g} J is not the sum "
                           f"of its states' energy ({states_j:g} J)")
    if not plan.predicted_j > 0:
        return PlanProblem(PREDICTED_LINE, "predicted_j 0 J: a flight draws energy")
    if _above(plan.predicted_j, plan.budget_j):
        return PlanProblem(PREDICTED_LINE, f"predicted_j {plan.predicted_j:g} J exceeds "
                           f"budget_j {plan.budget_j:g} J")
    for s, state in enumerate(plan.states):
        duty = {x.name: x.duty for x in state.sensors}
        for name, low, high in limits.duty_bounds[s] if limits.duty_bounds else ():
            flown = duty.get(name, 1.0)  # a sensor without a line is always on
            if flown < low - PLAN_ROUNDING or _above(flown, high):
                return PlanProblem(state.line, f"state {state.name}: sensor {name}: duty "
                                   f"{flown:g} outside the mission's [{low:g}, {high:g}]")
        for k, profile in enumerate(state.profiles):
            where = f"state {state.name}: profile {k}:"
            if profile.pitch_rad == 0.0 and profile.ballast_cc == 0.0:  # level: propelled
                if not limits.unplanned_speed_mps > 0:
                    return PlanProblem(state.line, f"{where} PITCH_RAD and BALLAST_CC 0 fly "
                                       "it level on a propeller, and the vehicle has none")
                low, high = limits.propelled_speed_mps
                if _above(low, profile.speed_mps) or _above(profile.speed_mps, high):
                    return PlanProblem(state.line, f"{where} SPEED_MPS {profile.speed_mps:g} "
                                       f"outside the vehicle's propulsion ({low:g}-{high:g} "
                                       "m/s)")
                continue  # no glide
            if profile.thrust_w > 0 and not limits.unplanned_speed_mps > 0:
                return PlanProblem(state.line, f"{where} THRUST_W {profile.thrust_w:g} on a "
                                   "vehicle without a thruster")
            low, high = limits.thrust_range_w
            if profile.thrust_w > 0 and (_above(low, profile.thrust_w)
                                         or _above(profile.thrust_w, high)):
                return PlanProblem(state.line, f"{where} THRUST_W {profile.thrust_w:g} outside "
                                   f"the vehicle's thruster ({low:g}-{high:g} W)")
            low, high = limits.pitch_range_rad
            least = limits.min_ballast_cc[s][k] if limits.min_ballast_cc else 0.0
            if not low < profile.pitch_rad < high:
                return PlanProblem(state.line, f"{where} PITCH_RAD {profile.pitch_rad:g} "
                                   f"outside the vehicle's ({low:g}, {high:g}) rad")
            if not profile.ballast_cc > least:
                return PlanProblem(state.line, f"{where} BALLAST_CC {profile.ballast_cc:g} "
                                   f"does not fly it: the vehicle needs more than {least:g} cc")
            if profile.ballast_cc > limits.max_ballast_cc:
                return PlanProblem(state.line, f"{where} BALLAST_CC {profile.ballast_cc:g} "
                                   f"exceeds the vehicle's pump ({limits.max_ballast_cc:g} cc)")
            if profile.thrust_w == 0 and _above(profile.speed_mps, limits.max_speed_mps):
                return PlanProblem(state.line, f"{where} SPEED_MPS {profile.speed_mps:g} "
                                   f"exceeds the vehicle's fastest glide "
                                   f"({limits.max_speed_mps:g} m/s)")
    return None
