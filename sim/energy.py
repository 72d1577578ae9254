"""Energy of a simulated run, component by component, and the check of the plan.

Every component is integrated over the run's ticks with `power_models.timeline` (one
vectorised pass): the vehicle's hotel load, the pump per inflection against depth, the
pitch motor, a propeller's or thruster's draw (its model's power at the speed or
thrust flown), the surface and Iridium phases, the computer at the clock of each state
from its workload per tick, and each sensor device from its on/off timeline (with a
warm-up at every switch-on) at the vehicle's own figure (`power_models.devices`): the
hotel load is billed less the instruments it holds, which are billed while they run.
`check_flight` compares the run with the plan's prediction per state, which the plan file
carries.

One verdict per run, from its total: a run that spends more than the plan's budget by
more than `PLAN_TOLERANCE` violates the plan; one within its budget that spends more than
the plan's prediction by more than the tolerance is "over prediction" (the budget held,
but the prediction was wrong); else it passes. The states that overran their own
prediction are listed below the verdict, each with the component responsible, whatever
the verdict (a state over its prediction in a run under it does not make the run's).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, SENSOR_DEVICES, Component
from gliderplan.language import ir
from gliderplan.language.registry import SENSORS
from gliderplan.planner.planfile import Plan, flown_board
from gliderplan.power_models import load_board
from gliderplan.power_models.devices import base_power_w, sensor_on
from gliderplan.power_models.timeline import Timeline, energy_by_component_j, sensor_energy_j
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.sim.loop import RunRecord

GAUGE_TICKS = 64  # the coulomb counter is read out every 64 ticks (256 s at the 4 s tick)
PLAN_TOLERANCE = 0.05  # simulated energy may exceed budget or prediction by 5 % before it counts
DEVICES = SENSOR_DEVICES
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
    parts = Billing(mission, vehicle, plan, record.tick_s).per_tick_j(c)
    dt = record.tick_s
    state = c["state"].astype(np.intp)
    states = len(mission.states)
    flown = np.bincount(np.minimum(state, states), minlength=states + 1)[:states]
    inflected = np.bincount(state[c["inflection"].astype(bool)], minlength=states + 1)
    by_component = {k: np.bincount(state, weights=v, minlength=states + 1)
                    for k, v in parts.items()}
    names = record.state_names
    by_state: dict[str, dict[str, float]] = {}
    inflections: dict[str, int] = {}
    times: dict[str, float] = {}
    for i in np.flatnonzero(flown).tolist():
        name = names[i]
        by_state[name] = {k: float(v[i]) for k, v in by_component.items()}
        inflections[name] = int(inflected[i])
        times[name] = float(flown[i] * dt)
    return RunEnergy(parts, by_state, inflections, times)


class Billing:
    """How a tick is billed: the vehicle's loads, the computer at the clock of each state
    (the plan's board when it names a preset or none, else the mission's; nothing for
    `computer none`), each sensor device. The model files are read once, here."""

    def __init__(self, mission: ir.CheckedMission, vehicle: Vehicle, plan: Plan | None,
                 dt: float) -> None:
        self.vehicle, self.dt, self.n_states = vehicle, dt, len(mission.states)
        self.held = vehicle.hotel_includes  # the computer in it: not billed again
        self.gliding_w = base_power_w(vehicle)  # the instruments it holds: billed as they run
        spec = flown_board(mission, plan)
        board = load_board(spec, mission.computer.clock_mhz if spec == mission.computer.board
                           else plan.clock_mhz)

        def tick_j(state: int) -> float:
            """The board's energy in a tick of `state`: at the clock, the work per tick and
            asleep or awake between ticks as the plan says (without a plan: as the
            mission's `computer` settings say, the runtime's own work elsewhere). A board
            that cannot keep up is billed busy."""
            if plan is not None:
                p = plan.states[state]
                at, cycles, sleep = board.at_clock(p.clock_mhz), p.cycles_per_tick, p.sleep
            else:
                use = mission.states[state].computer
                at = board.at_clock(use.clock_mhz) if use.clock_mhz else board
                cycles, sleep = use.cycles_per_tick or RUNTIME_CYCLES_PER_TICK, use.sleep
            energy = float(at.tick_energy(cycles, dt, sleep).total_j)
            return at.active_w * dt if np.isnan(energy) else energy

        self.computer_w = np.array([tick_j(i) / dt for i in range(self.n_states)])  # [W]
        self.boot_j = board.boot_j  # booted at its default clock in the first tick
        self.sensors = {d: sensor_on(vehicle, d) for d in DEVICES}

    def per_tick_j(self, c: Mapping[str, np.ndarray], boot: bool = True
                   ) -> dict[str, np.ndarray]:
        """Energy [J] of every component in each tick of the columns `c` (a run's, or some
        of its ticks in order); `boot`: the first is the run's first tick, in which the
        board boots. A sensor on in the first tick is counted as switched on there."""
        dt, vehicle = self.dt, self.vehicle
        state = c["state"].astype(int)
        timeline = Timeline(dt_s=dt, phase=c["phase"].astype(np.int8), depth_m=c["depth_m"],
                            pumped_out_cc=c["pumped_out_cc"], pumped_in_cc=c["pumped_in_cc"],
                            inflection=c["inflection"].astype(bool))
        parts = energy_by_component_j(timeline, vehicle, gliding_w=self.gliding_w)
        computer = self.computer_w[np.minimum(state, self.n_states - 1)] * dt
        if boot:
            computer[:1] += self.boot_j
        parts[Component.COMPUTER] = computer * (Component.COMPUTER not in self.held)
        if vehicle.propulsion is not None:  # its draw as the model gave it each tick
            parts[Component.PROPULSION] = c["propulsion_w"] * dt
        power = c["sensor_power"].astype(np.int64)
        for device, sensor in self.sensors.items():
            on = (power & DEVICE_BITS[device]) != 0
            if on.any():
                parts[device] = sensor_energy_j(on, sensor, dt)
        idle = np.flatnonzero(state >= self.n_states)  # the exit's row ends the run: no energy
        for joules in parts.values():
            joules[idle] = 0.0
        return parts


class BatteryGauge:
    """The simulated glider's coulomb counter as the science computer reads it out
    (sensor `energy_left` [J]): the battery's energy less what the ticks flown drew,
    billed as `Billing` bills them, brought up to date every GAUGE_TICKS ticks (in
    between it reads as at the last update, as a real counter read out now and then).
    The energy guard of the runtimes ends the mission when it reads the reserve."""

    def __init__(self, mission: ir.CheckedMission, vehicle: Vehicle, plan: Plan | None,
                 tick_s: float) -> None:
        self.billing = Billing(mission, vehicle, plan, tick_s)
        self.left_j = mission.battery.energy_j
        self.reserve_j = mission.battery.reserve_j
        self.counted = 0  # ticks billed

    def reading(self, tick: int, columns) -> float:
        """The reading at `tick` [J]; every tick before it is flown and in `columns`
        (sim.loop.Columns)."""
        update = tick - tick % GAUGE_TICKS
        if update > self.counted:
            arrays = columns.arrays()
            start = max(self.counted - 1, 0)  # a tick before: who switched on in the first
            part = {k: v[start:update] for k, v in arrays.items()}
            drawn = sum(self.billing.per_tick_j(part, boot=self.counted == 0).values()
                        )[self.counted - start:]
            self.left_j -= float(drawn.sum())
            self.counted = update
        return self.left_j


# ---- the flight against its plan -------------------------------------------------------

@dataclass(frozen=True)
class FlightCheck:
    """The verdict on a flight against its plan's budget and per-state prediction."""

    verdict: str  # "pass", "over prediction", "violation" or "no plan": from the total
    budget_j: float | None
    predicted_j: float | None
    simulated_j: float
    tolerance: float
    causes: tuple[str, ...]  # the states that overran their prediction (or the spenders)

    @property
    def over_prediction(self) -> float | None:
        """[1] the run's energy against the plan's prediction, less 1 (None: no plan)."""
        if not self.predicted_j:
            return None
        return self.simulated_j / self.predicted_j - 1.0

    @property
    def headline(self) -> str:
        """The run's one verdict line: the total against the prediction and the budget."""
        if self.budget_j is None or not self.predicted_j:
            return f"no plan: {self.simulated_j / 1e3:.1f} kJ spent, nothing to check against"
        return (f"{self.verdict}: {self.simulated_j / 1e3:.1f} kJ spent, "
                f"{self.predicted_j / 1e3:.1f} kJ predicted ({100 * self.over_prediction:+.1f} "
                f"%, tolerance {100 * self.tolerance:g} %), budget {self.budget_j / 1e3:.1f} kJ "
                f"({100 * self.simulated_j / self.budget_j:.1f} % used)")

    def to_json(self) -> dict:
        return {"verdict": self.verdict, "headline": self.headline, "budget_j": self.budget_j,
                "predicted_j": self.predicted_j, "simulated_j": self.simulated_j,
                "over_prediction": self.over_prediction, "tolerance": self.tolerance,
                "causes": list(self.causes)}


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
    over_prediction = simulated > plan.predicted_j * (1.0 + tolerance)
    verdict = "violation" if over_budget else "over prediction" if over_prediction else "pass"
    return FlightCheck(verdict, plan.budget_j, plan.predicted_j, simulated, tolerance,
                       tuple(text for _, text in causes))
