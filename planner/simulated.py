"""Plans on simulated occupancy: the time in each state, its visits and the variables its
profiles read on entry, measured by flying the plan, then planned again until they settle.

The static timeline (planner/occupancy.py) cannot know when an exit on a sensor reading
fires, nor what an event assigns from a reading; the simulator can. Round k flies plan k
(once in the water `gliderplan sim` flies by default, or in N drawn scenarios, whose mean
it takes) and plans again on what it flew. The occupancy has settled when a round flies
the occupancy its plan was planned on: every state's time within SETTLED_SHARE of itself
(or a tick per visit), the same visits and variables. That plan is the one returned, so its
prediction is what flying it gives. A mission whose occupancy keeps moving (a plan that
changes what the flight does, which changes the plan back) stops after MAX_ROUNDS, and
the plan says so among its assumptions.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract import TICK_S
from gliderplan.language import ir
from gliderplan.planner.hardware import Hardware
from gliderplan.planner.inputs import build_inputs
from gliderplan.planner.model import model_for
from gliderplan.planner.occupancy import measured_occupancy
from gliderplan.planner.plan import PlanResult, plan_mission, solve_plan
from gliderplan.planner.planfile import MISSION_SUBJECT, Assumption, Plan

SETTLED_SHARE = 0.01  # a state's time may move by 1 % (or a tick per visit) between rounds
VARIABLE_TOLERANCE = 1e-3  # relative: a variable on entry that moves less has settled
MAX_ROUNDS = 6


@dataclass(frozen=True)
class Flown:
    """What flights of a plan measured: per state its time [s], visits and the variables
    its profiles read on first entry (of the states entered)."""

    time_s: dict[str, float]
    visits: dict[str, int]
    variables: dict[str, dict[str, float]]

    def settled_against(self, other: Flown) -> bool:
        """Whether `other` measured the same occupancy, within the tolerances."""
        return (self.visits == other.visits
                and all(abs(t - other.time_s[k]) <= max(SETTLED_SHARE * max(t, other.time_s[k]),
                                                        TICK_S * self.visits[k])
                        for k, t in self.time_s.items())
                and self.variables.keys() == other.variables.keys()
                and all(math.isclose(v, other.variables[k].get(n, math.nan),
                                     rel_tol=VARIABLE_TOLERANCE)
                        for k, mine in self.variables.items() for n, v in mine.items()))


FlyPlan = Callable[[Plan], Flown]  # flies a plan, measures what it flew


def plan_on_simulation(mission: ir.CheckedMission, hardware: Hardware, fly_plan: FlyPlan,
                       source: str) -> PlanResult:
    """Plan on the timeline, then on what `fly_plan` measures of each plan, until the
    occupancy settles (or MAX_ROUNDS). `source` says how the flights were flown, for the
    plan's assumptions."""
    result = plan_mission(mission, hardware)
    planned_on: Flown | None = None
    changed = ""
    for round_ in range(1, MAX_ROUNDS + 1):
        flown = fly_plan(result.plan)
        if planned_on is not None and flown.settled_against(planned_on):
            return _stated(result, f"occupancy settled after {_plans(round_ - 1)}: flying "
                                   "this plan gives the occupancy it was planned on (each "
                                   f"state's time within {100 * SETTLED_SHARE:g} % or a tick "
                                   "per visit)")
        changed = _largest_change(flown, planned_on)
        occupancy = measured_occupancy(mission, flown.time_s, flown.visits, flown.variables,
                                       "time in each state, its visits and the variables "
                                       f"its profiles read on entry: simulated, {source}")
        result = solve_plan(model_for(build_inputs(mission, hardware, occupancy)))
        planned_on = flown
    return _stated(result, f"occupancy NOT settled after {_plans(MAX_ROUNDS)} (the last "
                           f"moved {changed}): flying this plan may not give the occupancy "
                           "it was planned on")


def _plans(count: int) -> str:
    return f"{count} re-plan" + ("" if count == 1 else "s")


def _largest_change(flown: Flown, before: Flown | None) -> str:
    if before is None:
        return "everything"
    name = max(flown.time_s, key=lambda k: abs(flown.time_s[k] - before.time_s[k]))
    return f"{name} by {abs(flown.time_s[name] - before.time_s[name]) / 3600:.2f} h"


def _stated(result: PlanResult, text: str) -> PlanResult:
    plan = result.plan
    note = Assumption(MISSION_SUBJECT, text)
    return replace(result, plan=replace(plan, assumptions=(*plan.assumptions, note)))


# ---- flying a plan -------------------------------------------------------------------

def flown_once(mission: ir.CheckedMission, hardware: Hardware, seed: int) -> FlyPlan:
    """One flight of each plan in the water `gliderplan sim` flies by default (the bench
    ocean, the CTD's noise) from `seed`, to the mission's horizon (else 30 days)."""
    from gliderplan.sim.energy import account
    from gliderplan.sim.flight import fly
    from gliderplan.sim.setup import FlightOptions, flight_setup

    def fly_plan(plan: Plan) -> Flown:
        setup = flight_setup(mission, FlightOptions(seed=seed), plan=plan,
                             vehicle=hardware.vehicle)
        record = fly(mission, setup.water.ocean, setup.config, setup.vehicle, plan,
                     runtime=setup.runtime)
        if record.ended == "interrupted":
            raise KeyboardInterrupt
        used = account(record, mission, setup.vehicle, plan)
        return Flown(dict(used.time_by_state_s), record.visits(),
                     _read_by_profiles(mission, record.entry_variables or {}))

    return fly_plan


def flown_in_scenarios(mission: ir.CheckedMission, hardware: Hardware, scenarios: int,
                       seed: int, spec, executor, workers: int,  # noqa: ANN001
                       progress: Callable[[float, float], None] | None) -> FlyPlan:
    """Each plan flown in the same `scenarios` scenarios drawn from `spec` from `seed`
    (Monte Carlo, sim/montecarlo.py): the mean time and visits per state, the mean of the
    variables on entry over the scenarios that entered the state."""
    from gliderplan.sim import montecarlo
    from gliderplan.sim.setup import FlightOptions, flight_setup

    def fly_plan(plan: Plan) -> Flown:
        setup = flight_setup(mission, FlightOptions(seed=seed), plan=plan,
                             vehicle=hardware.vehicle)
        job = montecarlo.Job(setup, spec)
        result = montecarlo.run_montecarlo(job, scenarios, executor, workers, progress)
        if result.interrupted:
            raise KeyboardInterrupt
        rows = result.rows
        time_s = {s.name: float(np.mean([r[f"time_{s.name}_s"] for r in rows]))
                  for s in mission.states}
        visits = {s.name: round(float(np.mean([r[f"visits_{s.name}"] for r in rows])))
                  for s in mission.states}
        variables: dict[str, dict[str, float]] = {}
        for state in mission.states:
            for name in state.profile_variables:
                values = [v for r in rows
                          if math.isfinite(v := r[f"entered_{state.name}_{name}"])]
                if values:
                    variables.setdefault(state.name, {})[name] = float(np.mean(values))
        return Flown(time_s, visits, variables)

    return fly_plan


def _read_by_profiles(mission: ir.CheckedMission,
                      entered: dict[str, dict[str, float]]) -> dict[str, dict[str, float]]:
    """Of the variables on entry, those each state's profiles read."""
    return {s.name: {n: entered[s.name][n] for n in s.profile_variables}
            for s in mission.states if s.name in entered and s.profile_variables}

