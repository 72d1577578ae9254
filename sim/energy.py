"""Energy of a simulated run, component by component, and the check of the plan.

Every component is integrated over the run's ticks with `power_models.timeline` (one
vectorised pass): the vehicle's hotel load, the pump per inflection against depth, the
pitch motor, the surface and Iridium phases, the computer at the clock of each state
from its workload per tick, and each sensor device from its on/off timeline (with a
warm-up at every switch-on), except what the vehicle's hotel load already holds
(`hotel_includes`: a fitted hotel load measured with the CTD logging has it inside).
`check_flight` compares the run with the plan's prediction per state, which the plan file
carries.

A run that spends more than the plan's budget by more than `PLAN_TOLERANCE` violates the
plan; the states that overran their prediction are named as the cause. A run within its
budget in which a state overran its own prediction by more than the tolerance is "over
prediction", with the state and the component responsible: the budget held, but the
plan's prediction was wrong.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, Component
from gliderplan.language import ir
from gliderplan.language.registry import SENSORS
from gliderplan.planner.planfile import Plan
from gliderplan.power_models import load_board, load_sensor
from gliderplan.power_models.catalog import preset_names
from gliderplan.power_models.timeline import Timeline, energy_by_component_j
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.sim.loop import RunRecord

PLAN_TOLERANCE = 0.05  # simulated energy may exceed budget or prediction by 5 % before it counts
DEVICES: tuple[str, ...] = tuple(dict.fromkeys(s.device for s in SENSORS if s.device))
DEVICE_BITS = {d: sum(1 << s.index for s in SENSORS if s.device == d) for d in DEVICES}


@dataclass(frozen=True)
class RunEnergy:
    """Per-tick energy [J] of each component and the run's totals."""

    per_tick_j: dict[str, np.ndarray]  # component -> (n,) energy in each tick
    by_state_j: dict[str, dict[str, float]]  # state -> component -> energy
    inflections_by_state: dict[str, int]
    time_by_state_s: dict[str, float]

    @property
    def total_j(self) -> float:
        return float(sum(v.sum() for v in self.per_tick_j.values()))

    def by_component_j(self) -> dict[str, float]:
        return {k: float(v.sum()) for k, v in self.per_tick_j.items()}


def account(record: RunRecord, mission: ir.CheckedMission, vehicle: Vehicle,
            plan: Plan | None) -> RunEnergy:
    """Energy of every component in every tick of the run."""
    c = record.columns
    dt = record.tick_s
    state = c["state"].astype(int)
    timeline = Timeline(dt_s=dt, phase=c["phase"].astype(np.int8), depth_m=c["depth_m"],
                        pumped_out_cc=c["pumped_out_cc"], pumped_in_cc=c["pumped_in_cc"],
                        inflection=c["inflection"].astype(bool))
    parts = energy_by_component_j(timeline, vehicle)
    held = vehicle.hotel_includes  # devices whose power the hotel load already holds
    parts[Component.COMPUTER] = _computer_j(state, dt, mission, plan) * (
        Component.COMPUTER not in held)
    power = c["sensor_power"].astype(np.int64)
    for device in DEVICES:
        on = (power & DEVICE_BITS[device]) != 0
        if on.any() and device not in held:
            device_timeline = Timeline(dt, timeline.phase, timeline.depth_m, np.zeros(len(on)),
                                       np.zeros(len(on)), np.zeros(len(on), bool),
                                       sensor_on=on[None, :])
            parts[device] = energy_by_component_j(device_timeline, vehicle,
                                                  sensors=[load_sensor(device)])[Component.SENSORS]
    flying = state < len(mission.states)  # the row of the exit is the run's end: no energy
    parts = {k: np.where(flying, v, 0.0) for k, v in parts.items()}
    names = record.state_names
    by_state: dict[str, dict[str, float]] = {}
    inflections: dict[str, int] = {}
    times: dict[str, float] = {}
    for i, name in enumerate(names):
        mine = state == i
        if not mine.any():
            continue
        by_state[name] = {k: float(v[mine].sum()) for k, v in parts.items()}
        inflections[name] = int(c["inflection"][mine].sum())
        times[name] = float(mine.sum() * dt)
    return RunEnergy(parts, by_state, inflections, times)


def _computer_j(state: np.ndarray, dt: float, mission: ir.CheckedMission,
                plan: Plan | None) -> np.ndarray:
    """The board's energy per tick in each state: the plan's board (when it names a
    preset), else the mission's, at the clock, the work per tick and asleep or awake
    between ticks as the plan says (without a plan: as the mission's `computer` settings
    say, the runtime's own work elsewhere). A board that cannot keep up is billed busy."""
    board = load_board(mission.computer.board, mission.computer.clock_mhz)
    if plan is not None and plan.computer in preset_names("board") \
            and plan.computer != board.name:
        board = load_board(plan.computer, plan.clock_mhz)

    def tick_j(state: int) -> float:
        if plan is not None:
            p = plan.states[state]
            at, cycles, sleep = board.at_clock(p.clock_mhz), p.cycles_per_tick, p.sleep
        else:
            use = mission.states[state].computer
            at = board.at_clock(use.clock_mhz) if use.clock_mhz else board
            cycles, sleep = use.cycles_per_tick or RUNTIME_CYCLES_PER_TICK, use.sleep
        energy = float(at.tick_energy(cycles, dt, sleep).total_j)
        return at.active_w * dt if np.isnan(energy) else energy

    per_state = np.array([tick_j(i) / dt for i in range(len(mission.states))])
    per_tick = per_state[np.minimum(state, len(per_state) - 1)] * dt
    per_tick[:1] += board.boot_j  # booted at its default clock for the first tick
    return per_tick


# ---- the flight against its plan -------------------------------------------------------

@dataclass(frozen=True)
class FlightCheck:
    """The verdict on a flight against its plan's budget and per-state prediction."""

    verdict: str  # "pass", "over prediction", "violation" or "no plan"
    budget_j: float | None
    predicted_j: float | None
    simulated_j: float
    tolerance: float
    causes: tuple[str, ...]  # why it overran (or what overran the prediction)

    def to_json(self) -> dict:
        return {"verdict": self.verdict, "budget_j": self.budget_j,
                "predicted_j": self.predicted_j, "simulated_j": self.simulated_j,
                "tolerance": self.tolerance, "causes": list(self.causes)}


def check_flight(energy: RunEnergy, plan: Plan | None,
                 tolerance: float = PLAN_TOLERANCE) -> FlightCheck:
    """Did the run stay within the plan's budget? Causes: states that overran their
    predicted energy, with inflections and time planned against flown and what the plan
    assumed of the state; without such a state, the states that spent most."""
    simulated = energy.total_j
    if plan is None:
        return FlightCheck("no plan", None, None, simulated, tolerance, ())
    causes = []
    for predicted in plan.states:
        name = predicted.name
        used = energy.by_state_j.get(name)
        flown = sum(used.values()) if used else 0.0
        if used is None or flown <= predicted.energy_j * (1.0 + tolerance):
            continue
        excess = {k: used[k] - v for k, v in predicted.energy_by_component_j.items() if k in used}
        most = max(excess, key=excess.get, default=None)
        detail = [f"{name}: {flown / 1e3:.1f} kJ spent, {predicted.energy_j / 1e3:.1f} kJ planned"
                  + (f" ({most} +{excess[most] / 1e3:.1f} kJ)" if most and excess[most] > 0
                     else "")]
        if energy.inflections_by_state[name] > predicted.inflections * (1.0 + tolerance):
            detail.append(f"{predicted.inflections:.0f} inflections planned, "
                          f"{energy.inflections_by_state[name]} flown")
        if energy.time_by_state_s[name] > predicted.time_s * (1.0 + tolerance):
            detail.append(f"{predicted.time_s / 3600:.2f} h planned, "
                          f"{energy.time_by_state_s[name] / 3600:.2f} h flown")
        detail += [f"the plan assumed: {a.text}" for a in plan.assumptions if a.subject == name]
        causes.append((flown - predicted.energy_j, "; ".join(detail)))
    causes.sort(reverse=True)
    over_budget = simulated > plan.budget_j * (1.0 + tolerance)
    if over_budget and not causes:  # no state overran its prediction: name the spenders
        spent = sorted(((sum(v.values()), k) for k, v in energy.by_state_j.items()),
                       reverse=True)
        causes = [(0.0, f"{simulated / 1e3:.1f} kJ spent against a budget of "
                        f"{plan.budget_j / 1e3:.1f} kJ; most in " + ", ".join(
                            f"{name} ({joules / 1e3:.1f} kJ)" for joules, name in spent[:3]))]
    verdict = "violation" if over_budget else "over prediction" if causes else "pass"
    return FlightCheck(verdict, plan.budget_j, plan.predicted_j, simulated, tolerance,
                       tuple(text for _, text in causes))
