"""Plans at a confidence: the scenario approach (Campi & Garatti 2008).

Each of N sampled scenarios k (its simulated time in each state, its drawn vehicle
figures, its battery's usable share f_k) makes the plan's energy an affine function
E_k(x) of the decisions x (duties, device on-fractions, profile shares, clocks). The
plan keeps E_k(x) / f_k <= B for every k: N affine constraints whose coefficients are
cvxpy Parameters of fixed shape (N, n), so the problem stays convex, DCP and DPP.

Guarantee: with d the dimension of the decision space, the plan found from N independent
scenarios violates the budget in a fresh scenario with probability at most eps, except
with probability at most beta over the draw of the N scenarios, where

    beta = sum_{i < d} C(N, i) eps^i (1 - eps)^(N - i)

(Campi & Garatti 2008, Theorem 1; DESIGN.md's N >= (2 / eps)(ln(1 / beta) + d) is a
looser sufficient N). d counts the free decision variables: duties, devices, and per
state the profile and clock shares less the one equality each (they sum to one).
The mission's objective is kept: the best quality within every scenario's budget, or
the least mean energy that reaches the quality floor within every scenario's budget.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, replace

import cvxpy as cp
import numpy as np

from gliderplan.contract import MAX_SCENARIOS
from gliderplan.contract.errors import UsageError
from gliderplan.language import ir
from gliderplan.planner.hardware import Hardware
from gliderplan.planner.inputs import ENERGY_UNIT_J, Coefficients, PlanInputs, build_inputs
from gliderplan.planner.model import SOLVER, PlanModel, Solution, model_for
from gliderplan.planner.occupancy import measured_occupancy
from gliderplan.planner.plan import (
    J_PER_WH,
    Choice,
    PlanningError,
    PlanResult,
    _snapped,
    assemble,
)
from gliderplan.planner.planfile import MISSION_SUBJECT, Assumption
from gliderplan.power_models.vehicle import Vehicle

DEFAULT_RISK = 1e-3  # beta: the chance that the N scenarios drawn were unrepresentative
METHOD = "scenario approach (Campi & Garatti 2008)"


@dataclass(frozen=True)
class Confidence:
    """What a plan at a confidence guarantees, and how it was found."""

    requested: float  # 1 - eps asked for
    risk: float  # beta
    scenarios: int  # N
    dimension: int  # d
    achieved: float  # 1 - eps(N, d, beta): the confidence these N scenarios give
    support: int  # scenario constraints active at the plan
    seed: int
    method: str = METHOD

    def to_json(self) -> dict:
        return {"method": self.method, "requested": self.requested, "achieved": self.achieved,
                "risk": self.risk, "scenarios": self.scenarios, "dimension": self.dimension,
                "active_scenarios": self.support, "seed": self.seed}


def _tail(n: int, d: int, eps: float) -> float:
    """sum_{i < d} C(n, i) eps^i (1 - eps)^(n - i): the binomial tail of the guarantee."""
    from scipy.stats import binom

    return float(binom.cdf(d - 1, n, eps))


def scenarios_needed(confidence: float, dimension: int, risk: float = DEFAULT_RISK) -> int:
    """Smallest N whose plan holds with `confidence` except with probability `risk`."""
    eps = 1.0 - confidence
    n = max(dimension, 1)
    while _tail(n, dimension, eps) > risk:  # doubles, then bisects: tens of evaluations
        n *= 2
    low = n // 2
    while n - low > 1:
        mid = (low + n) // 2
        low, n = (low, mid) if _tail(mid, dimension, eps) <= risk else (mid, n)
    return n


def achieved_confidence(scenarios: int, dimension: int, risk: float = DEFAULT_RISK) -> float:
    """1 - eps for the smallest eps that N scenarios guarantee at `risk` (0 if N <= d)."""
    if scenarios < dimension:
        return 0.0
    low, high = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (low + high)
        low, high = (low, mid) if _tail(scenarios, dimension, mid) <= risk else (mid, high)
    return 1.0 - high


def decision_dimension(inputs: PlanInputs) -> int:
    """d: free decision variables (shares and clocks less their sum-to-one per state)."""
    n_p, n_q, n_r, n_m = inputs.sizes
    n_s = len(inputs.states)
    return n_p + n_q + (n_r - n_s) + (n_m - n_s)


class ScenarioModel:
    """A built planning model plus one energy constraint per scenario."""

    def __init__(self, model: PlanModel, count: int) -> None:
        if model.pace is not None:
            raise PlanningError("a plan at a confidence takes each state's time from "
                                "simulation; a transit leg's time would depend on its speed")
        self.model = model
        n_p, n_q, n_r, n_m = model.inputs.sizes
        self.p_fixed = cp.Parameter(count, name="scenario_fixed_j")
        self.p_prof = cp.Parameter((count, n_r), nonneg=True, name="scenario_prof_j")
        self.p_mode = cp.Parameter((count, n_m), nonneg=True, name="scenario_mode_j")
        self.p_dev = cp.Parameter((count, n_q), nonneg=True, name="scenario_dev_j") \
            if n_q else None
        energy = self.p_fixed + self.p_prof @ model.share + self.p_mode @ model.mode
        if self.p_dev is not None:
            energy = energy + self.p_dev @ model.device
        self.energy = energy
        self.constraint = energy <= model.p_budget
        self.quality_problem = cp.Problem(cp.Maximize(model.quality),
                                          [*model.common, self.constraint])
        self.energy_problem = cp.Problem(cp.Minimize(model.energy),
                                         [*model.common, model.quality >= model.p_floor,
                                          self.constraint])
        for problem in (self.quality_problem, self.energy_problem):
            assert problem.is_dcp(dpp=True), "the scenario model must stay DCP and DPP"

    def set_scenarios(self, coefficients: list[Coefficients], usable: list[float]) -> None:
        """Scenario k's coefficients, scaled by 1 / its battery's usable share."""
        scale = 1.0 / np.asarray(usable, float)
        self.p_fixed.value = np.array([c.fixed_j for c in coefficients]) * scale
        self.p_prof.value = np.array([c.prof_j for c in coefficients]) * scale[:, None]
        self.p_mode.value = np.array([c.mode_j for c in coefficients]) * scale[:, None]
        if self.p_dev is not None:
            self.p_dev.value = np.array([c.dev_j for c in coefficients]) * scale[:, None]

    def solve(self, problem: cp.Problem) -> tuple[Solution, float, int]:
        """(solution, budget's shadow price [quality per J], active scenario count)."""
        m = self.model
        start = time.perf_counter()
        try:
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", message="Solution may be inaccurate")
                problem.solve(solver=SOLVER)
        except cp.SolverError:
            pass
        status = problem.status or "solver_error"
        ok = status in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE)

        def value(x: cp.Variable | None) -> np.ndarray:
            if x is None:
                return np.zeros(0)
            return np.asarray(x.value, float) if ok else np.full(x.shape, np.nan)

        stats = problem.solver_stats
        solution = Solution(
            status=status, duty=value(m.duty), device=value(m.device), share=value(m.share),
            mode=value(m.mode), quality=float(m.quality.value) if ok else math.nan,
            model_energy_j=float(np.max(self.energy.value)) * ENERGY_UNIT_J if ok else math.nan,
            pace=np.zeros(0), budget_dual=None, solve_s=time.perf_counter() - start,
            solver_s=getattr(stats, "solve_time", None) if stats else None,
            iterations=getattr(stats, "num_iters", None) if stats else None)
        if not ok:
            return solution, 0.0, 0
        duals = np.asarray(self.constraint.dual_value, float).ravel()
        active = int(np.sum(self.energy.value >= m.p_budget.value * (1 - 1e-6)))
        price = float(duals.sum()) / ENERGY_UNIT_J if problem is self.quality_problem else 0.0
        return solution, price, active


def plan_at_confidence(mission: ir.CheckedMission, hardware: Hardware,
                       scenario_times_s: list[dict[str, float]], vehicles: list[Vehicle],
                       usable: list[float], confidence: float, risk: float = DEFAULT_RISK,
                       seed: int = 0, budget_j: float | None = None) -> PlanResult:
    """The plan whose budget holds in every sampled scenario: scenario k spends
    `scenario_times_s[k]` in each state, with `vehicles[k]`'s figures and a battery that
    holds `usable[k]` of its rating. Its prediction is at the scenarios' mean times with
    the nominal vehicle; `PlanResult.confidence` says what the N scenarios guarantee, and
    the plan's assumptions say it too."""
    count = len(scenario_times_s)
    if count == 0 or not (len(vehicles) == len(usable) == count):
        raise ValueError("one vehicle and one usable share per scenario")
    mean = {s.name: float(np.mean([t.get(s.name, 0.0) for t in scenario_times_s]))
            for s in mission.states}
    inputs = build_inputs(mission, hardware, measured_occupancy(mission, mean))
    model = model_for(inputs)
    per_scenario = [model_for(build_inputs(mission, replace(hardware, vehicle=v),
                                           measured_occupancy(mission, t))).coefficients
                    for t, v in zip(scenario_times_s, vehicles, strict=True)]
    scenarios = ScenarioModel(model, count)
    scenarios.set_scenarios(per_scenario, usable)
    budget = hardware.budget_j if budget_j is None else budget_j
    model.set_budget_j(budget)
    if mission.objective.sense == "minimize_energy":
        model.set_floor(mission.objective.quality_floor)
        chosen, _, active = scenarios.solve(scenarios.energy_problem)
        price = 0.0
        if chosen.optimal:
            _, price, _ = scenarios.solve(scenarios.quality_problem)
    else:
        chosen, price, active = scenarios.solve(scenarios.quality_problem)
    if not chosen.optimal:
        raise PlanningError(f"no plan keeps the budget of {budget / J_PER_WH:.4g} Wh in all "
                            f"{count} scenarios ({chosen.status}): raise the budget or ask "
                            "for less confidence")
    least = model.solve_energy(-1.0)
    choice = Choice(_snapped(inputs, chosen), budget, least.model_energy_j,
                    max(price * J_PER_WH, 0.0))
    dimension = decision_dimension(inputs)
    stated = Confidence(confidence, risk, count, dimension,
                        achieved_confidence(count, dimension, risk), active, seed)
    result = assemble(inputs, choice)
    stated_note = Assumption(
        MISSION_SUBJECT, f"plan at confidence {stated.achieved:.3g} (asked {confidence:g}): the "
        f"budget holds in every one of {count} simulated scenarios ({stated.method}; risk "
        f"{risk:g}, dimension {dimension}); the prediction is at the scenarios' mean times")
    plan = replace(result.plan, assumptions=(*result.plan.assumptions, stated_note))
    return replace(result, plan=plan, confidence=stated)


def plan_mission_at_confidence(mission: ir.CheckedMission, hardware: Hardware,
                               confidence: float, *, scenarios: int | None = None,
                               seed: int = 0, risk: float = DEFAULT_RISK, spec=None,
                               executor=None, workers: int = 1, progress=None) -> PlanResult:
    """Plan so that the budget holds with `confidence`: fly the mission's nominal plan in
    N scenarios (N from the confidence and `risk` unless given), then plan on what each
    scenario spent its time on (`plan_at_confidence`). `spec`: a scenario file's
    distributions (default: the shipped one); `executor`/`workers` as in Monte Carlo."""
    from gliderplan.planner.plan import plan_mission, prepare
    from gliderplan.sim import montecarlo
    from gliderplan.sim.scenarios import draw_scenario, read_spec
    from gliderplan.sim.setup import FlightOptions, flight_setup

    if not 0.0 < confidence < 1.0 or not 0.0 < risk < 1.0:
        raise ValueError("confidence and risk must lie strictly between 0 and 1")
    nominal = plan_mission(mission, hardware).plan
    times = {s.name: s.time_s for s in nominal.states}
    dimension = decision_dimension(prepare(mission, hardware, times)[0])
    count = scenarios or scenarios_needed(confidence, dimension, risk)
    if count > MAX_SCENARIOS:
        raise UsageError(f"--confidence {confidence:g}: {count:,} scenarios are needed "
                         f"(Campi & Garatti, risk {risk:g}, {dimension} decisions), more than "
                         f"the {MAX_SCENARIOS:,} a run may fly: ask for less confidence, or "
                         "give --scenarios and read the confidence it reaches")
    spec = spec or read_spec()
    setup = flight_setup(mission, FlightOptions(seed=seed), plan=nominal,
                         vehicle=hardware.vehicle)
    job = montecarlo.Job(setup, spec)
    result = montecarlo.run_montecarlo(job, count, executor, workers, progress)
    if result.interrupted:
        raise KeyboardInterrupt
    rows = result.rows
    vehicles = [draw_scenario(spec, setup.vehicle, r["scenario"],
                              montecarlo.scenario_seed(job, r["scenario"])).vehicle for r in rows]
    scenario_times = [{s.name: r[f"time_{s.name}_s"] for s in mission.states} for r in rows]
    return plan_at_confidence(mission, hardware, scenario_times, vehicles,
                              [r["drawn_usable_fraction_1"] for r in rows], confidence, risk,
                              seed)
