"""`plan_mission`: from a checked mission to a plan, and what the plan predicts.

The mission's objective picks the problem: maximise quality within the budget, or
minimise energy subject to a quality floor. A budget below what the mission needs at
the least is not a solver status but an `InfeasibleBudget` that says how much is
needed and what consumes it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract import VEHICLE_COMPONENTS, Component
from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.units import J_PER_WH
from gliderplan.language import ir
from gliderplan.language.semantics import MissionFault
from gliderplan.planner.hardware import Hardware, load_hardware
from gliderplan.planner.inputs import (
    PROFILE_CYCLE_S,
    SENSOR_PERIOD_S,
    PlanInputs,
    build_inputs,
    utility,
)
from gliderplan.planner.model import SATURATION_TOLERANCE, PlanModel, Solution, model_for
from gliderplan.planner.occupancy import NOMINAL_SPEED_MPS, measured_occupancy
from gliderplan.planner.planfile import (
    Assumption,
    Plan,
    ProfilePlan,
    SensorPlan,
    StatePlan,
    as_written,
)
from gliderplan.planner.rates import hardware_occupancy
from gliderplan.power_models.devices import base_power_w

_ON_EDGE = 1e-6  # a duty this close to 0 or 1 does not cycle (no warm-ups)
_SHARE_EDGE = 1e-5  # a profile share this small is solver noise (5 ms of a 500 s state)
_NO_PRICE = 1e-9  # quality per Wh below which the budget is not what limits the plan


class PlanningError(GliderplanError):
    """The mission cannot be planned as asked; the message says why in domain terms."""


class InfeasibleBudget(PlanningError):
    def __init__(self, budget_j: float, minimum_j: float,
                 consumers: list[tuple[str, float]], origin: str = "") -> None:
        """`origin`: where the budget came from, e.g. "4 Wh less the 15 % reserve"."""
        self.budget_j, self.minimum_j, self.consumers = budget_j, minimum_j, consumers
        short = minimum_j - budget_j
        top = ", ".join(f"{name} {j / J_PER_WH:.3g} Wh" for name, j in consumers)
        of = f" ({origin})" if origin else ""
        super().__init__(
            f"the budget of {budget_j / J_PER_WH:.4g} Wh{of} is too small: the mission needs at "
            f"least {minimum_j / J_PER_WH:.4g} Wh ({short / J_PER_WH:.4g} Wh or "
            f"{100 * short / minimum_j:.3g} % more). Largest consumers at that minimum: {top}.")


@dataclass(frozen=True)
class PlanResult:
    """A plan and what its solve tells about it (the report's figures): the quality it
    buys, the least energy the mission needs, what one more Wh would buy."""

    plan: Plan  # what the plan file holds
    mission: ir.CheckedMission
    objective: str  # "maximize_quality" or "minimize_energy"
    quality: float  # [0, 1]
    minimum_energy_j: float  # least budget the mission can be planned on [J] (`Choice`)
    budgeted_energy_j: float  # the plan's energy as the budget counts it [J], >= predicted
    shadow_price: float  # quality per extra Wh of budget at this plan
    time_source: str  # "timeline" (static walk) or "simulation" (measured occupancy)
    solver_status: str
    solve_s: float
    solver_iterations: int | None
    state_quality: tuple[float | None, ...]  # weighted quality of each state's device sensors
    confidence: object | None = None  # planner.confidence.Confidence of a plan at a confidence
    status: str = "optimal"  # "infeasible": `least_energy_plan`, beyond the budget
    upload_bytes: int = 0  # [bytes] of the plan file as sent to the glider (0: not written)
    battery_j: float = 0.0  # [J] the battery the plan was made for (0: not known)
    reserve_fraction: float = 0.0  # [1] and its reserve


def prepare(mission: ir.CheckedMission, hardware: Hardware | None = None,
            occupancy_s: dict[str, float] | None = None) -> tuple[PlanInputs, PlanModel]:
    """The inputs and the built model (parameters set) for a mission."""
    hardware = hardware or load_hardware(mission)
    try:
        occupancy = (hardware_occupancy(mission, hardware) if occupancy_s is None
                     else measured_occupancy(mission, occupancy_s))
    except MissionFault as fault:
        raise PlanningError(f"the mission's timeline fails at {fault}") from None
    inputs = build_inputs(mission, hardware, occupancy)
    return inputs, model_for(inputs)


def plan_mission(mission: ir.CheckedMission, hardware: Hardware | None = None, *,
                 budget_j: float | None = None,
                 occupancy_s: dict[str, float] | None = None) -> PlanResult:
    """Plan a checked mission. `hardware` defaults to the mission's annotations,
    `budget_j` [J] to (1 - reserve) x battery; `occupancy_s` (state -> seconds measured
    in simulation) replaces the static timeline. Raises InfeasibleBudget or PlanningError."""
    _, model = prepare(mission, hardware, occupancy_s)
    return solve_plan(model, budget_j)


def solve_plan(model: PlanModel, budget_j: float | None = None) -> PlanResult:
    """The plan of a prepared model at `budget_j` [J] (default: the hardware's budget)."""
    hardware = model.inputs.hardware
    origin = "" if budget_j is not None or not hardware.reserve_fraction else (
        f"{hardware.battery_j / J_PER_WH:.4g} Wh less the "
        f"{100 * hardware.reserve_fraction:.3g} % reserve")
    choice = choose_plan(model, hardware.budget_j if budget_j is None else budget_j, origin)
    return assemble(model.inputs, choice)


@dataclass(frozen=True)
class Choice:
    """The plan a budget buys (`choose_plan`): the solution to fly and what it tells."""

    solution: Solution  # snapped: values within solver tolerance of a bound are on it
    budget_j: float  # [J]
    minimum_j: float  # least budget the mission can be planned on [J], as budgets count
    shadow_price: float  # quality per extra Wh of budget; 0 when the budget does not limit


# Two energies belong to a plan. Its prediction (`Plan.predicted_j`) is what it draws:
# warm-ups only for the devices it does cycle. Budgets count energy as the convex model
# does, which charges warm-ups to every device that may cycle (a switch-on cost is not
# convex): an upper bound of the prediction. The least budget, the infeasible-budget
# message, the Pareto curve and a plan's place on it all use the budget's measure, so
# that "needs at least" means one number whatever the objective.


def choose_plan(model: PlanModel, budget_j: float, origin: str = "") -> Choice:
    """Which plan to fly at `budget_j` [J], for the mission's objective: the best quality
    within the budget (and of the plans with that quality, the cheapest when the budget
    is not what limits), or the least energy that reaches the quality floor (and of the
    plans with that energy, the best quality). Raises
    InfeasibleBudget when the budget is below what the mission needs (`origin` says where
    the budget came from), PlanningError when the annotations cannot all hold."""
    inputs = model.inputs
    least = model.solve_energy(-1.0)
    if not least.optimal:
        hint = " and whether the horizon leaves time for the transit legs" \
            if inputs.transit.size else ""
        raise PlanningError("the mission's annotations cannot all hold together: check the "
                            f"duty and quality annotations{hint}")
    if inputs.mission.objective.sense == "minimize_energy":
        floor = inputs.mission.objective.quality_floor
        chosen = model.solve_energy(floor)
        if not chosen.optimal:
            best = model.solve_quality(model.ample_budget_j())
            raise PlanningError(f"the quality floor {floor:g} cannot be reached: the best "
                                f"this mission can do is {best.quality:.4g}")
        _check_budget(inputs, chosen, budget_j, origin)
        least = chosen  # the floor's least energy: no budget below it can be planned on
        priced = model.solve_quality(chosen.model_energy_j)
        shadow = priced.budget_dual if priced.optimal else 0.0
        if priced.status == "optimal" and priced.quality > chosen.quality:
            chosen = priced  # quality that costs nothing more (a sensor the hotel powers)
    else:
        _check_budget(inputs, least, budget_j, origin)
        chosen = model.solve_quality(budget_j)
        if not chosen.optimal:
            raise PlanningError(f"the solver could not plan this mission ({chosen.status})")
        shadow = chosen.budget_dual
        if shadow is not None and shadow * J_PER_WH < _NO_PRICE:
            chosen = _cheapest_at(model, chosen)
    price = (shadow or 0.0) * J_PER_WH
    return Choice(_snapped(inputs, chosen), budget_j, least.model_energy_j,
                  price if price >= _NO_PRICE else 0.0)


def _cheapest_at(model: PlanModel, best: Solution) -> Solution:
    """Of the plans with `best`'s quality, the cheapest (budget to spare). Its floor lies
    at the optimum, where the solver may stop short of its tolerances (status
    optimal_inaccurate): a floor a little lower, at most SATURATION_TOLERANCE of the
    quality, is solved cleanly; else the first found only to reduced accuracy, else
    `best` itself."""
    found = best
    for slack in (1e-9, 1e-7, SATURATION_TOLERANCE):
        cheapest = model.solve_energy(best.quality * (1 - slack))
        if cheapest.status == "optimal":
            return cheapest
        if cheapest.optimal and found is best:
            found = cheapest
    return found


def least_energy_plan(model: PlanModel, budget_j: float) -> PlanResult:
    """The plan that needs the least energy: what the mission costs at the least when
    `budget_j` [J] cannot buy it (status "infeasible" then). PlanningError when the
    annotations cannot all hold."""
    least = model.solve_energy(-1.0)
    if not least.optimal:
        raise PlanningError("the mission's annotations cannot all hold together")
    result = assemble(model.inputs, Choice(_snapped(model.inputs, least), budget_j,
                                           least.model_energy_j, 0.0))
    short = least.model_energy_j > budget_j * (1 + 1e-9)
    return replace(result, status="infeasible") if short else result


def _check_budget(inputs: PlanInputs, needed: Solution, budget_j: float, origin: str) -> None:
    """InfeasibleBudget unless `budget_j` covers the solution as the model counts it
    (warm-ups included: what the budget constraint itself measures)."""
    if needed.model_energy_j > budget_j * (1 + 1e-9):
        raise InfeasibleBudget(budget_j, needed.model_energy_j,
                               largest_consumers(inputs, needed), origin)


def _snap(x: np.ndarray, lo: np.ndarray | float, hi: np.ndarray | float,
          edge: float = _ON_EDGE) -> np.ndarray:
    """Values within solver tolerance of a bound put on it (a duty of 0.9999999 is 1)."""
    x = np.clip(x, lo, hi)
    x = np.where(np.abs(x - lo) < edge, lo, x)
    return np.where(np.abs(x - hi) < edge, hi, x)


def _snapped(inputs: PlanInputs, sol: Solution) -> Solution:
    steady_duty, steady_dev = ~inputs.duty_in_transit, ~inputs.device_in_transit
    duty = np.where(steady_duty, _snap(sol.duty, inputs.duty_lo, inputs.duty_hi), sol.duty)
    device = np.where(steady_dev, _snap(sol.device, inputs.dev_lo, inputs.dev_hi), sol.device)
    return replace(sol, duty=duty, device=device,
                   share=_snap(sol.share, 0.0, 1.0, _SHARE_EDGE), quality=float(sol.quality))


# ---- what a solution means ----------------------------------------------------------------

def _profile_components(inputs: PlanInputs, sol: Solution) -> np.ndarray:
    """(n_r, len(VEHICLE_COMPONENTS)) energy [J] of each profile share."""
    t = inputs.time_s[inputs.prof_state]
    power = np.array([[p.power_w[c] for c in VEHICLE_COMPONENTS] for p in inputs.profiles])
    return power * (np.clip(sol.share, 0.0, 1.0) * t)[:, None]


def _pace_total(inputs: PlanInputs, sol: Solution) -> np.ndarray:
    """(n_t,) time per metre [s m-1] of each transit leg, pump runs and turns included."""
    tr = inputs.transit
    return sol.pace + tr.pump_s / sol.pace**2 + tr.turn_s_per_m if tr.size else np.zeros(0)


def state_times_s(inputs: PlanInputs, sol: Solution) -> np.ndarray:
    """(n_s,) time [s] in each state: fixed, or route length x time per metre."""
    times = inputs.time_s.copy()
    times[inputs.transit.state] = inputs.transit.length_m * _pace_total(inputs, sol)
    return times


def _fractions(inputs: PlanInputs, sol: Solution, rows_state: np.ndarray,
               values: np.ndarray) -> np.ndarray:
    """Duties as fractions of time; transit rows hold on-time per metre."""
    fraction = np.array(values, float)
    per_metre = dict(zip(inputs.transit.state, _pace_total(inputs, sol), strict=True))
    for i, s in enumerate(rows_state):
        if s in per_metre:
            fraction[i] = values[i] / per_metre[s]
    return np.clip(fraction, 0.0, 1.0)


def duty_fractions(inputs: PlanInputs, sol: Solution) -> np.ndarray:
    return _fractions(inputs, sol, inputs.duty_state, sol.duty)


def _device_energy_j(inputs: PlanInputs, sol: Solution) -> np.ndarray:
    on = _fractions(inputs, sol, inputs.dev_state, sol.device)
    cycling = (on > _ON_EDGE) & (on < 1.0 - _ON_EDGE)
    return (inputs.dev_power_w * on * state_times_s(inputs, sol)[inputs.dev_state]
            + np.where(cycling, inputs.dev_warmup_j * inputs.switch_ons(), 0.0))


def _chosen_modes(inputs: PlanInputs, sol: Solution) -> np.ndarray:
    """Index into inputs.clocks of the clock each state runs at (the largest share; a
    transit leg runs at its cheapest clock, which its energy per metre assumes)."""
    n_modes = len(inputs.clocks)
    chosen = np.argmax(sol.mode.reshape(len(inputs.states), n_modes), axis=1)
    powers = inputs.mode_power_w.reshape(len(inputs.states), n_modes)
    for s in inputs.transit.state:
        chosen[s] = int(np.nanargmin(powers[s]))
    return chosen


def state_energy_j(inputs: PlanInputs, sol: Solution) -> list[dict[str, float]]:
    """Energy [J] per state and component, as the plan will fly it."""
    result = [dict.fromkeys(VEHICLE_COMPONENTS, 0.0) for _ in inputs.states]
    for r, row in enumerate(_profile_components(inputs, sol)):
        for c, value in zip(VEHICLE_COMPONENTS, row, strict=True):
            result[inputs.prof_state[r]][c] += float(value)
    times = state_times_s(inputs, sol)
    tr, vehicle = inputs.transit, inputs.hardware.vehicle
    for i, s in enumerate(tr.state):
        result[s][Component.HOTEL] = base_power_w(vehicle) * float(times[s])
        result[s][Component.PUMP] = float(tr.length_m[i] * tr.pump_j[i] / sol.pace[i] ** 2)
        result[s][Component.PITCH] = float(tr.length_m[i] * tr.pitch_j_per_m[i])
    n_modes = len(inputs.clocks)
    for s, m in enumerate(_chosen_modes(inputs, sol)):
        result[s][Component.COMPUTER] = float(inputs.mode_power_w[s * n_modes + m] * times[s])
    result[0][Component.COMPUTER] += inputs.hardware.board.boot_j  # booted for the start state
    for q, value in enumerate(_device_energy_j(inputs, sol)):
        name = inputs.dev_name[q]
        result[inputs.dev_state[q]][name] = result[inputs.dev_state[q]].get(name, 0.0) \
            + float(value)
    return result


def realised_energy_j(inputs: PlanInputs, sol: Solution) -> float:
    return float(sum(sum(s.values()) for s in state_energy_j(inputs, sol)))


def largest_consumers(inputs: PlanInputs, sol: Solution, n: int = 3) -> list[tuple[str, float]]:
    """The `n` components that draw the most energy [J] in a solution."""
    totals: dict[str, float] = {}
    for state in state_energy_j(inputs, sol):
        for k, v in state.items():
            totals[k] = totals.get(k, 0.0) + v
    return sorted(totals.items(), key=lambda kv: -kv[1])[:n]


def _state_quality(inputs: PlanInputs, sol: Solution, s: int) -> float | None:
    """Weighted quality of a state's device sensors; on a transit leg the model's measure,
    on-time per metre against full sampling at the nominal speed."""
    terms = [(w, float(utility(a, d))) for st, _, d, a, w in inputs.fixed if st == s]
    mine = inputs.duty_state == s
    sampled = np.where(inputs.duty_in_transit, sol.duty * NOMINAL_SPEED_MPS, sol.duty)
    terms += [(w, float(utility(a, min(d, 1.0)))) for w, a, d in
              zip(inputs.weight[mine], inputs.alpha[mine], sampled[mine], strict=True)]
    weight = sum(w for w, _ in terms)
    return float(sum(w * u for w, u in terms) / weight) if weight > 0 else None


def assemble(inputs: PlanInputs, choice: Choice) -> PlanResult:
    """The plan of a chosen solution, state by state, every number as its file holds it."""
    hardware, sol = inputs.hardware, choice.solution
    energies = state_energy_j(inputs, sol)
    components = list(dict.fromkeys(k for e in energies for k in e))
    modes = _chosen_modes(inputs, sol)
    duty = duty_fractions(inputs, sol)
    times = state_times_s(inputs, sol)
    legs = {s: i for i, s in enumerate(inputs.transit.state)}
    states = []
    for s, state in enumerate(inputs.mission.states):
        t = float(times[s])
        visits = inputs.occupancy.visits[state.name]
        visit_s = t / visits if visits else 0.0
        period = min(SENSOR_PERIOD_S, visit_s) if visit_s > 0 else SENSOR_PERIOD_S
        cycle = min(PROFILE_CYCLE_S, visit_s) if visit_s > 0 else PROFILE_CYCLE_S
        by_sensor = {inputs.duty_sensor[p]: float(duty[p])
                     for p in np.flatnonzero(inputs.duty_state == s)}
        by_sensor.update({n: d for st, n, d, _, _ in inputs.fixed if st == s and d < 1.0})
        sensors = tuple(SensorPlan(use.name, as_written(period),
                                   as_written(by_sensor[use.name] * period))
                        for use in state.sensors if use.name in by_sensor)
        rows = np.flatnonzero(inputs.prof_state == s)
        shares = np.clip(sol.share[rows], 0.0, 1.0)
        shares = shares / shares.sum()
        profiles = tuple(
            ProfilePlan(p.index, float(f), p.pitch_rad, p.ballast_cc, p.speed_mps, p.thrust_w)
            for p, f in zip((inputs.profiles[r] for r in rows), shares, strict=True))
        inflections = float(sum(inputs.profiles[r].inflections_per_s * f * t
                                for r, f in zip(rows, shares, strict=True)))
        if s in legs:
            profiles, inflections = _transit_profile(inputs, sol, legs[s], profiles[0])
        energy = {c: as_written(energies[s].get(c, 0.0)) for c in components}
        states.append(StatePlan(
            state.name, as_written(inputs.clocks[modes[s]].clock_mhz),
            as_written(cycle), as_written(t), visits, as_written(inflections), energy, sensors,
            tuple(ProfilePlan(p.index, as_written(p.share), as_written(p.pitch_rad),
                              as_written(p.ballast_cc), as_written(p.speed_mps),
                              as_written(p.thrust_w))
                  for p in profiles),
            sleep=hardware.sleeps(state), cycles_per_tick=as_written(hardware.cycles(state))))
    notes = dict.fromkeys([*_describe_defaults(inputs), *inputs.notes])
    plan = Plan(inputs.mission.name, inputs.mission.hash, hardware.board.name,
                as_written(hardware.board.clock_mhz), as_written(choice.budget_j),
                as_written(sum(s.energy_j for s in states)), tuple(states),
                tuple(Assumption.from_note(note) for note in notes))
    return PlanResult(
        plan=plan, mission=inputs.mission, objective=inputs.mission.objective.sense,
        quality=float(sol.quality), minimum_energy_j=choice.minimum_j,
        shadow_price=choice.shadow_price, time_source=inputs.occupancy.source,
        budgeted_energy_j=sol.model_energy_j, solver_status=sol.status, solve_s=sol.solve_s,
        solver_iterations=sol.iterations,
        state_quality=tuple(_state_quality(inputs, sol, s)
                            for s in range(len(inputs.mission.states))),
        battery_j=hardware.battery_j, reserve_fraction=hardware.reserve_fraction)


def _transit_profile(inputs: PlanInputs, sol: Solution, i: int,
                     profile: ProfilePlan) -> tuple[tuple[ProfilePlan, ...], float]:
    """The planned speed of transit leg `i`, the buoyancy that flies it, its inflections."""
    tr, vehicle = inputs.transit, inputs.hardware.vehicle
    speed = 1.0 / float(sol.pace[i])
    ballast = min(float(vehicle.yo_ballast_cc(speed, tr.pitch_rad[i], tr.min_depth_m[i],
                                              tr.max_depth_m[i])), vehicle.max_ballast_cc)
    planned = replace(profile, share=1.0, speed_mps=speed, ballast_cc=ballast)
    return (planned,), float(tr.length_m[i] * tr.inflections_per_m[i])


def _describe_defaults(inputs: PlanInputs) -> list[str]:
    """The mission's defaulted annotations with the values the plan used."""
    hw, mission = inputs.hardware, inputs.mission
    values = {
        "vehicle": f"vehicle {mission.vehicle}",
        "computer": f"computer {hw.board.name} @ {hw.board.clock_mhz:g} MHz",
        "battery": f"battery {hw.battery_j / (1e3 * J_PER_WH):.4g} kWh reserve "
                   f"{100 * hw.reserve_fraction:g} %",
        "objective": "objective maximize quality",
    }
    return [f"{values.get(key, key)} (default)" for key in mission.defaults_used
            if key not in hw.overridden]
