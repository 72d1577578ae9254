"""Replanning at sea: the rest of a mission planned again at each surfacing from what the
glider measured, at the confidence the plan was made at, and sent as a plan update.

At a surfacing the shore knows what the glider reported (power_models/telemetry.py): the
energy its coulomb counter counted, its battery's voltage, its devices' on-time, the time
it spent in each state. Each interval between reports updates the belief in the energy
model's figures (power_models/posterior.py: a Kalman update of each figure group's
multiplier). The rest of the mission is then planned again:

    maximise  Q(d)  over what remains (duties, profile shares; the clocks stay the plan's)
    s.t.      mu(x) + || z L' P(x) ; sigma || <= budget left

where P(x) is the energy of each figure group over the time left in each state (affine in
the decisions), mu(x) = mean' P(x) its expectation under the belief, L L' = Sigma the
belief's covariance, sigma the spread of what no figure explains (the budget's, from the
battery's usable share, and the intervals to come), and z = Phi^-1(confidence): the
budget holds with the plan's confidence if the belief is right (a second-order-cone
chance constraint, exact for a Gaussian belief; DESIGN.md section 10 plans at a
confidence by the scenario approach, which needs simulated scenarios the shore does not
have at sea). Every number is a cvxpy Parameter of the model built once (`Replanner`),
so a replan is warm: it sets values and solves again (DPP). Compiling the parameters costs
more than a solve (0.5 s against 0.05 s on a 64-state mission), so a process that replans
once (`gliderplan replan`) solves with the values in place of the parameters instead.

The time left in each state is the plan's less what the glider has flown there, scaled
to the time left in the plan's mission; the plan's own rates (its prediction per state
and component) are the model each figure multiplies. What changes is what the glider
flies: the duties of the sensors marked `duty auto` (on-time rounded to 0.1 s) and the
profile shares (to 1e-4); the clocks, the sleep, the pitch and buoyancy stay. Given the
water the vehicle flies (`legs`: the current on each state's route, planner/water.py,
as `plan --currents` takes it), the speeds and thruster commands the planner chooses
(`auto` speeds, `thrust auto`) are chosen in it anew, and the rest of the mission's
energy is modelled at them.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import dataclass, field, replace
from decimal import Decimal
from pathlib import Path
from statistics import NormalDist

import cvxpy as cp
import numpy as np

from gliderplan.contract import NO_BOARD, VEHICLE_COMPONENTS, Component, same_clock
from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.units import J_PER_WH
from gliderplan.language import ir
from gliderplan.language.registry import PROFILES
from gliderplan.planner.inputs import ENERGY_UNIT_J, PlanInputs, build_inputs, coefficients
from gliderplan.planner.model import SOLVER, model_for
from gliderplan.planner.occupancy import measured_occupancy
from gliderplan.planner.plan import PlanningError, duty_fractions
from gliderplan.planner.planfile import (
    Plan,
    PlanFileError,
    PlanRejected,
    ProfilePlan,
    SensorPlan,
    read_plan_bytes,
)
from gliderplan.planner.rates import ProfileRates
from gliderplan.planner.speed import Leg
from gliderplan.power_models.battery import drawn_budget_j
from gliderplan.power_models.posterior import (
    COMPONENT_GROUPS,
    MODEL_NOISE,
    Belief,
    DischargeCurve,
    FigureMove,
    prior_belief,
)
from gliderplan.power_models.telemetry import NOMINAL_BUS_V, SurfacingReport

DEFAULT_CONFIDENCE = 0.95  # a plan that states none (made without --confidence)
ON_STEP_S = Decimal("0.1")  # [s] the on-time an update sets, rounded to this
SHARE_STEP = Decimal("0.0001")  # a profile share, rounded to this
IF_INFEASIBLE = ("refuse", "least-energy")
RETRIES = ((SOLVER, {}), (SOLVER, {"equilibrate_enable": False}),
           (SOLVER, {"static_regularization_constant": 1e-7}), (cp.SCS, {}))


class ReplanInfeasible(PlanningError):
    """The budget left cannot hold the rest of the mission at the confidence asked: no
    update is made, the glider keeps flying its plan; the message says what to cut."""


def stated_confidence(plan: Plan) -> float | None:
    """The confidence a plan was asked at, as its assumptions say it ("plan at confidence X
    (asked Y): ..."; a plan that says only what it achieved: X), else None."""
    import re

    for assumption in plan.assumptions:
        found = re.match(r"plan at confidence ([0-9.]+)(?: \(asked ([0-9.]+)\))?",
                         assumption.text)
        if found:
            return float(found[2] or found[1])
    return None


# ---- the model -----------------------------------------------------------------------------

class ChanceModel:
    """The planning model (its variables, quality and constraints) with the budget held
    at a confidence against the belief; every coefficient a Parameter."""

    def __init__(self, inputs: PlanInputs, groups: int) -> None:
        self.model = model = model_for(inputs)
        n_p, n_q, n_r, n_m = inputs.sizes
        self.m_fixed = cp.Parameter(name="mean_fixed")
        self.m_prof = cp.Parameter(n_r, name="mean_prof")
        self.m_mode = cp.Parameter(n_m, name="mean_mode")
        self.s_fixed = cp.Parameter(groups, name="spread_fixed")
        self.s_prof = cp.Parameter((groups, n_r), name="spread_prof")
        self.s_mode = cp.Parameter((groups, n_m), name="spread_mode")
        self.sigma = cp.Parameter(nonneg=True, name="unexplained")
        self.budget = cp.Parameter(name="budget_left")
        self.clocks = cp.Parameter(n_m, nonneg=True, name="clocks")
        mean = self.m_fixed + self.m_prof @ model.share + self.m_mode @ model.mode
        spread = self.s_fixed + self.s_prof @ model.share + self.s_mode @ model.mode
        self.m_dev = self.s_dev = None
        if n_q:
            self.m_dev = cp.Parameter(n_q, name="mean_dev")
            self.s_dev = cp.Parameter((groups, n_q), name="spread_dev")
            mean = mean + self.m_dev @ model.device
            spread = spread + self.s_dev @ model.device
        self.mean = mean
        self.held = mean + cp.norm(cp.hstack([spread, cp.reshape(self.sigma, (1,), order="F")]), 2)
        self.constraint = self.held <= self.budget
        common = [*model.common, model.mode == self.clocks]
        self.quality_problem = cp.Problem(cp.Maximize(model.quality), [*common, self.constraint])
        self.energy_problem = cp.Problem(cp.Minimize(mean), [*common, self.constraint,
                                                             model.quality >= model.p_floor])
        # the least the rest needs: with the mission's quality floor, or (a mission that
        # maximises quality) none, a second-order-cone problem without the quality's cones
        self.least_problem = cp.Problem(cp.Minimize(self.held),
                                        [*common, model.quality >= model.p_floor])
        self.least_free_problem = cp.Problem(cp.Minimize(self.held), common)
        for problem in (self.quality_problem, self.energy_problem, self.least_problem,
                        self.least_free_problem):
            assert problem.is_dcp(dpp=True), "the chance model must stay DCP and DPP"

    def solve(self, problem: cp.Problem, *, once: bool = False) -> tuple[str, float]:
        """Solve; (status, wall time [s]). `once`: the parameters' values taken as
        constants, not compiled for the next solves. Clarabel now and then stalls on the
        exponential cones of a problem whose numbers are fine (a few in a month of
        replans): it is asked again without equilibration, then with more regularisation,
        then SCS is."""
        start = time.perf_counter()
        for solver, options in RETRIES:
            try:
                with warnings.catch_warnings():  # the status says "optimal_inaccurate"
                    warnings.filterwarnings("ignore", message="Solution may be inaccurate")
                    problem.solve(solver=solver, ignore_dpp=once, **options)
            except cp.SolverError:  # its status would still be the last solve's
                continue
            return problem.status or "solver_error", time.perf_counter() - start
        return "solver_error", time.perf_counter() - start


def _root(cov: np.ndarray) -> np.ndarray:
    """R with R R' = cov (negative eigenvalues of rounding taken as 0)."""
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    return vectors * np.sqrt(np.clip(values, 0.0, None))


# ---- what the glider reports ----------------------------------------------------------------

@dataclass(frozen=True)
class DutyChange:
    """A sensor's planned duty before and after a replan."""

    state: str
    sensor: str
    before: float
    after: float


@dataclass(frozen=True)
class ReplanResult:
    """A replan: the plan to fly from now on (the held plan with its duties and shares
    changed), what it buys, and why it changed."""

    target: Plan
    status: str  # "updated", "unchanged", "least-energy" (infeasible at the confidence)
    confidence: float
    time_s: float  # [s] mission time of the report it rests on
    remaining_s: dict[str, float]  # [s] time left in each state
    used_j: float  # [J] drawn so far: the counter, past its last reading the figures
    predicted_used_j: float  # [J] the plan's prediction of it
    budget_left_j: float  # [J] expected: usable share x budget - used
    budget_left_sd_j: float
    energy_left_j: float  # [J] the rest of the mission at the target plan, expected
    energy_left_sd_j: float
    least_j: float | None  # [J] what the rest needs at the least, at the confidence (if asked)
    quality: float  # the rest of the mission's quality at the target plan [0, 1]
    shadow_price: float  # quality per extra Wh of budget left
    changes: tuple[DutyChange, ...]
    moves: tuple[FigureMove, ...]
    usable: tuple[float, float]  # the battery's usable share (mean, sd)
    usable_prior: tuple[float, float]
    notes: tuple[str, ...]
    solve_s: float

    def to_json(self) -> dict:
        return {
            "status": self.status, "confidence": self.confidence, "time_s": self.time_s,
            "used_j": self.used_j, "predicted_used_j": self.predicted_used_j,
            "budget_left_j": self.budget_left_j, "budget_left_sd_j": self.budget_left_sd_j,
            "energy_left_j": self.energy_left_j, "energy_left_sd_j": self.energy_left_sd_j,
            "least_energy_left_j": self.least_j, "quality": self.quality,
            "shadow_price": self.shadow_price, "remaining_s": self.remaining_s,
            "changes": [{"state": c.state, "sensor": c.sensor, "duty_before": c.before,
                         "duty_after": c.after} for c in self.changes],
            "figures": [{"group": m.name, "multiplier": m.posterior, "sd": m.sd,
                         "change": m.change, "figure_w": None if m.nominal_w is None
                         else m.nominal_w * m.posterior} for m in self.moves],
            "battery_usable": {"mean": self.usable[0], "sd": self.usable[1],
                               "prior_mean": self.usable_prior[0],
                               "prior_sd": self.usable_prior[1]},
            "notes": list(self.notes), "solve_s": self.solve_s,
        }

    def text(self, moved: float = 0.02) -> str:
        """What changed and why, for people."""
        wh = J_PER_WH
        lines = [f"at {self.time_s / 3600:.1f} h: drawn {self.used_j / wh:,.1f} Wh, the plan "
                 f"predicted {self.predicted_used_j / wh:,.1f} Wh; budget left "
                 f"{self.budget_left_j / wh:,.1f} Wh (sd {self.budget_left_sd_j / wh:,.1f}); "
                 f"the rest of the mission {self.energy_left_j / wh:,.1f} Wh "
                 f"(sd {self.energy_left_sd_j / wh:,.1f}) at confidence {self.confidence:g}"]
        moves = [m for m in self.moves if abs(m.change) >= moved]
        lines.append("figures moved: " + ("; ".join(map(str, moves)) if moves else
                                          f"none by {100 * moved:g} % or more"))
        prior, now = self.usable_prior, self.usable
        if abs(now[0] - prior[0]) >= 0.005 or now[1] < 0.9 * prior[1]:
            lines.append(f"battery: usable share {prior[0]:.3f} (sd {prior[1]:.3f}) -> "
                         f"{now[0]:.3f} (sd {now[1]:.3f}), from its voltage")
        if self.changes:
            lines.append("duties: " + "; ".join(
                f"{c.state} {c.sensor} {100 * c.before:.1f} -> {100 * c.after:.1f} %"
                for c in self.changes))
        else:
            lines.append("duties: no change")
        lines.append(f"quality of the rest {self.quality:.4f}; shadow price "
                     f"{self.shadow_price:.4g} quality per extra Wh")
        if self.status == "least-energy":
            lines.append(f"the budget left cannot hold the rest at confidence "
                         f"{self.confidence:g}: the plan that needs the least")
        return "\n".join(lines + [f"note: {n}" for n in self.notes])


# ---- the replanner ------------------------------------------------------------------------

def plan_hardware(mission: ir.CheckedMission, plan: Plan):  # noqa: ANN201
    """The hardware a plan was made on, as far as a plan file tells: its board and clock
    (a preset or none), the mission's vehicle and battery."""
    from gliderplan.planner.hardware import load_hardware
    from gliderplan.power_models.catalog import preset_names

    if plan.computer == NO_BOARD:
        return load_hardware(mission, computer=NO_BOARD)
    if plan.computer in preset_names("board"):
        return load_hardware(mission, computer=f"{plan.computer}@{plan.clock_mhz:g}")
    return load_hardware(mission)


def usable_prior(spec) -> tuple[float, float]:  # noqa: ANN001
    """(mean, sd) of the battery's usable share as a scenario file draws it."""
    if spec is None:
        return 1.0, 0.0
    dist = spec.battery["usable_fraction_1"]
    if dist.kind == "fixed":
        return dist.a, 0.0
    if dist.kind == "uniform":
        return 0.5 * (dist.a + dist.b), (dist.b - dist.a) / math.sqrt(12.0)
    return dist.a, dist.b


class Replanner:
    """Replans one mission at each surfacing: the model is built once (the first replan
    compiles it; the next ones only set values), the belief is updated report by report.

    `held`: the signed plan file the glider holds at the start (its prediction is the
    model the figures multiply); `spec`: the scenario file whose spreads and battery share
    are the prior (None: the vehicle file's alone, a battery that holds its rating);
    `once`: this process replans once, so the model's parameters are not compiled."""

    def __init__(self, mission: ir.CheckedMission, held: bytes, *,
                 confidence: float | None = None, spec=None,  # noqa: ANN001
                 if_infeasible: str = "refuse",
                 legs: dict[str, tuple[Leg, ...]] | None = None, once: bool = False) -> None:
        if if_infeasible not in IF_INFEASIBLE:
            raise ValueError(f"if_infeasible must be one of {IF_INFEASIBLE}")
        try:
            plan = read_plan_bytes(held, mission)
        except PlanFileError as err:
            raise PlanRejected(str(err)) from None
        self.mission, self.plan, self.if_infeasible = mission, plan, if_infeasible
        self.once = once
        self.confidence = confidence or stated_confidence(plan) or DEFAULT_CONFIDENCE
        if not 0.5 <= self.confidence < 1.0:
            raise PlanningError(f"confidence {self.confidence:g}: must lie in [0.5, 1)")
        self.z = NormalDist().inv_cdf(self.confidence)
        hardware = plan_hardware(mission, plan)
        if legs is not None:  # the water now known: propelled speeds and thrusts anew
            hardware = replace(hardware, legs=legs)
        self.rechoose = legs is not None
        times = {s.name: s.time_s for s in plan.states}
        occupancy = measured_occupancy(mission, times, {s.name: s.visits for s in plan.states},
                                       note="time in each state: the plan's")
        # every state's time is the plan's, transit legs' too: their speed is not replanned
        self.inputs = build_inputs(mission, hardware, occupancy)
        self.devices = dict.fromkeys(self.inputs.dev_name)
        powers = {d: hardware.devices[d].on_power_w for d in self.devices}
        spreads = {} if spec is None else spec.vehicle_relative_sd
        self.belief: Belief = prior_belief(hardware.vehicle, powers, usable_prior(spec),
                                           spreads)
        self.device_w = powers
        self.warmup_j = {d: hardware.devices[d].warmup_j for d in self.devices}
        self.flying = plan  # the plan the glider flies: the duties its devices cycle at
        self.curve = DischargeCurve.nominal(NOMINAL_BUS_V)
        self.chance = ChanceModel(self.inputs, len(self.belief.names))
        self.clock_onehot = self._clocks()
        # the plan's rates [W] of each state and component: the model the figures multiply
        self.rates = {s.name: {c: (j / s.time_s if s.time_s > 0 else 0.0)
                               for c, j in s.energy_by_component_j.items()}
                      for s in plan.states}
        self.last: SurfacingReport | None = None  # the last report with a counter reading
        self.notes: list[str] = []

    def _clocks(self) -> np.ndarray:
        """The plan's clock of each state, one-hot over the model's clock columns."""
        inputs = self.inputs
        onehot = np.zeros(len(inputs.mode_state))
        per_state = len(inputs.clocks)
        for s, state in enumerate(self.plan.states):
            column = next((k for k, board in enumerate(inputs.clocks)
                           if same_clock(state.clock_mhz, board.clock_mhz)), 0)
            onehot[s * per_state + column] = 1.0
        return onehot

    # -- learning

    def expected_j(self, before: SurfacingReport | None, report: SurfacingReport
                   ) -> dict[str, float]:
        """The model's energy of each figure group [J] over the interval between two
        reports (`before` None: from the start)."""
        start = 0.0 if before is None else before.time_s
        flown = self._flown_between(before, report, report.time_s - start)
        expected = {g: sum(self.rates[s].get(g, 0.0) * t for s, t in flown.items())
                    for g in COMPONENT_GROUPS}
        on_before = {} if before is None else before.device_on_s
        cycling = self._cycling()
        for device in self.devices:
            if report.device_on_s and (before is None or before.device_on_s):
                on = report.device_on_s.get(device, 0.0) - on_before.get(device, 0.0)
                switch_ons = sum(t / cycling[s][device] for s, t in flown.items()
                                 if device in cycling[s])
                expected[device] = self.device_w[device] * on \
                    + self.warmup_j[device] * switch_ons
            else:
                expected[device] = sum(self.rates[s].get(device, 0.0) * t
                                       for s, t in flown.items())
        return expected

    def _cycling(self) -> dict[str, dict[str, float]]:
        """State -> device -> its period [s], for the devices the plan flown switches on
        and off there (each switch-on costs a warm-up)."""
        from gliderplan.language.registry import SENSOR_BY_NAME

        cycling: dict[str, dict[str, float]] = {}
        for state in self.flying.states:
            duties: dict[str, tuple[float, float]] = {}
            for x in state.sensors:
                device = SENSOR_BY_NAME[x.name].device
                if device:
                    duty, period = duties.get(device, (0.0, x.period_s))
                    duties[device] = (max(duty, x.duty), period)
            cycling[state.name] = {d: p for d, (duty, p) in duties.items() if 0.0 < duty < 1.0}
        return cycling

    def _flown_between(self, before: SurfacingReport | None, report: SurfacingReport,
                       span_s: float) -> dict[str, float]:
        """[s] in each state between two reports: their states' times, else the interval
        shared as the plan shares the mission's time."""
        if report.state_time_s and (before is None or before.state_time_s):
            earlier = {} if before is None else before.state_time_s
            return {s: max(report.state_time_s.get(s, 0.0) - earlier.get(s, 0.0), 0.0)
                    for s in self.rates}
        total = sum(s.time_s for s in self.plan.states) or 1.0
        self._note("the reports say no time in each state: each interval is shared as the "
                   "plan shares the mission's time")
        return {s.name: span_s * s.time_s / total for s in self.plan.states}

    def _note(self, note: str) -> None:
        if note not in self.notes:
            self.notes.append(note)

    def observe(self, report: SurfacingReport) -> None:
        """Learn from one more report (in time order): the interval since the last one
        with a counter reading, and the battery's voltage."""
        if report.coulomb_amphr_total is None:
            return
        used = report.energy_used_j
        drawn = used - (0.0 if self.last is None else self.last.energy_used_j)
        self.belief = self.belief.observe(self.expected_j(self.last, report), drawn)
        self.belief = self.belief.observe_battery(used, report.battery_v, self.plan.budget_j,
                                                  self.curve)
        self.last = report

    # -- planning

    def remaining_s(self, report: SurfacingReport) -> dict[str, float]:
        """[s] left in each state after `report`: the plan's time less what was flown,
        scaled to the time left in the plan's mission."""
        planned = {s.name: s.time_s for s in self.plan.states}
        total = sum(planned.values())
        left = max(total - report.time_s, 0.0)
        if report.state_time_s:
            leftover = {s: max(t - report.state_time_s.get(s, 0.0), 0.0)
                        for s, t in planned.items()}
        else:
            leftover = dict(planned)
        share = sum(leftover.values())
        if share <= 0.0:
            leftover, share = dict(planned), total or 1.0
        return {s: t * left / share for s, t in leftover.items()}

    def _parameters(self, remaining: dict[str, float], used_j: float) -> tuple[float, float]:
        """Set the model's values for `remaining` [s] and the belief; (budget left mean,
        its sd) [J]."""
        inputs0, belief, chance = self.inputs, self.belief, self.chance
        t = np.array([remaining[s] for s in inputs0.states])
        visits = {s.name: (math.ceil(s.visits * remaining[s.name] / s.time_s)
                           if s.time_s > 0 else 0) for s in self.plan.states}
        occupancy = replace(inputs0.occupancy, time_s=dict(remaining), visits=visits)
        inputs = replace(inputs0, time_s=t, occupancy=occupancy)
        coeff = coefficients(inputs)
        chance.model.set_coefficients(coeff)
        names = belief.names
        n_q, n_r, n_m = len(inputs.dev_state), len(inputs.prof_state), len(inputs.mode_state)
        unit = 1.0 / ENERGY_UNIT_J
        prof = np.zeros((len(names), n_r))
        for r, rates in enumerate(inputs.profiles):
            for c in VEHICLE_COMPONENTS:
                prof[names.index(c), r] = rates.power_w.get(c, 0.0) * t[inputs.prof_state[r]]
        mode = np.zeros((len(names), n_m))
        powers = np.where(np.isfinite(inputs.mode_power_w), inputs.mode_power_w, 0.0)
        mode[names.index(Component.COMPUTER)] = powers * t[inputs.mode_state]
        dev = np.zeros((len(names), n_q))
        fixed = np.zeros(len(names))
        switch_ons = inputs.switch_ons()
        for q, device in enumerate(inputs.dev_name):
            dev[names.index(device), q] = inputs.dev_power_w[q] * t[inputs.dev_state[q]]
            fixed[names.index(device)] += inputs.dev_warmup_j[q] * switch_ons[q]
        mean, root = np.clip(belief.mean, 0.0, None), _root(belief.cov).T * self.z
        chance.m_fixed.value = float(mean @ fixed) * unit
        chance.m_prof.value = mean @ prof * unit
        chance.m_mode.value = mean @ mode * unit
        chance.s_fixed.value = root @ fixed * unit
        chance.s_prof.value = root @ prof * unit
        chance.s_mode.value = root @ mode * unit
        if n_q:
            chance.m_dev.value = mean @ dev * unit
            chance.s_dev.value = root @ dev * unit
        budget = self.plan.budget_j
        left_mean = drawn_budget_j(budget, belief.usable_mean) - used_j
        left_sd = belief.usable_sd * budget
        # what no figure explains in the intervals to come (each MODEL_NOISE of its energy,
        # independent), at the plan's own energy for the time left
        total_s = sum(s.time_s for s in self.plan.states) or 1.0
        left_s = sum(remaining.values())
        future = sum(s.energy_j for s in self.plan.states) * left_s / total_s
        intervals = max(left_s / max(self._interval_s(), 1.0), 1.0)
        noise = MODEL_NOISE * future / math.sqrt(intervals)
        chance.sigma.value = self.z * math.hypot(left_sd, noise) * unit
        chance.budget.value = left_mean * unit
        chance.clocks.value = self.clock_onehot
        floor = self.mission.objective.quality_floor \
            if self.mission.objective.sense == "minimize_energy" else -1.0
        chance.model.set_floor(floor)
        self._inputs_now = inputs
        return left_mean, math.hypot(left_sd, noise)

    def _interval_s(self) -> float:
        """[s] between surfacings, as the reports so far show (the plan's mission, without)."""
        if self.last is None or self.belief.intervals == 0:
            return sum(s.time_s for s in self.plan.states)
        return self.last.time_s / self.belief.intervals

    def _used_j(self, report: SurfacingReport) -> float:
        """[J] drawn by the time of `report`: its counter's, else (a gap) the last reading
        and what the figures learned so far say was drawn since, lest the budget left
        count the uncounted span as unspent."""
        if report.energy_used_j is not None:
            return report.energy_used_j
        counted = 0.0 if self.last is None else self.last.energy_used_j
        since = self.expected_j(self.last, report)
        estimate = sum(float(m) * since.get(n, 0.0)
                       for n, m in zip(self.belief.names, self.belief.mean, strict=True))
        since_s = report.time_s - (0.0 if self.last is None else self.last.time_s)
        self._note(f"no counter reading at {report.time_s / 3600:.1f} h: the "
                   f"{since_s / 3600:.1f} h since the last are taken to have drawn "
                   f"{estimate / J_PER_WH:,.1f} Wh, as the figures learned so far say")
        return counted + estimate

    def replan(self, held: bytes, report: SurfacingReport) -> ReplanResult:
        """The plan for the rest of the mission after `report` (observed already), from the
        plan the glider holds (`held`, a plan file of this mission)."""
        held_plan = read_plan_bytes(held, self.mission)
        self.flying = held_plan
        used = self._used_j(report)
        remaining = self.remaining_s(report)
        left_mean, left_sd = self._parameters(remaining, used)
        chance, model = self.chance, self.chance.model
        objective = self.mission.objective.sense
        problem = chance.energy_problem if objective == "minimize_energy" \
            else chance.quality_problem
        status, solve_s = chance.solve(problem, once=self.once)
        least = None
        result_status = "updated"
        if status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE, cp.INFEASIBLE,
                          cp.INFEASIBLE_INACCURATE):
            raise PlanningError(f"the solver could not replan the rest of the mission "
                                f"({status}): the glider keeps flying its current plan")
        if status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
            least_problem = chance.least_problem if objective == "minimize_energy" \
                else chance.least_free_problem
            least_status, spent = chance.solve(least_problem, once=self.once)
            solve_s += spent
            if least_status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE):
                raise PlanningError(f"the rest of the mission cannot be planned "
                                    f"({least_status}): its annotations cannot all hold")
            least = float(chance.held.value) * ENERGY_UNIT_J
            if self.if_infeasible == "refuse":
                raise ReplanInfeasible(self._infeasible_message(least, left_mean, report))
            result_status = "least-energy"
        price = 0.0
        if problem is chance.quality_problem and result_status == "updated":
            dual = chance.constraint.dual_value
            price = max(float(dual if dual is not None else 0.0), 0.0) / ENERGY_UNIT_J \
                * J_PER_WH
        target, changes = self._target(held_plan, remaining)
        energy_mean = float(chance.mean.value) * ENERGY_UNIT_J
        energy_sd = max(float(chance.held.value) * ENERGY_UNIT_J - energy_mean, 0.0) / self.z
        if result_status == "updated" and not changes and target == held_plan:
            result_status = "unchanged"
        predicted = sum(self.rates[s].get(c, 0.0) * t
                        for s, t in self._flown_between(None, report, report.time_s).items()
                        for c in self.rates[s])
        return ReplanResult(
            target, result_status, self.confidence, report.time_s, remaining, used, predicted,
            left_mean, left_sd, energy_mean, math.sqrt(max(energy_sd**2 - left_sd**2, 0.0)),
            least, float(model.quality.value), price, changes, tuple(self.belief.moves()),
            (self.belief.usable_mean, self.belief.usable_sd), self.belief.usable_prior,
            tuple(self.notes), solve_s)

    def at_launch(self, held: bytes) -> ReplanResult:
        """The plan before launch (nothing flown, nothing drawn), at the confidence against
        the prior belief: a plan made on the model, planned at the shore's confidence."""
        return self.replan(held, SurfacingReport(0.0, 0.0))

    def _infeasible_message(self, least_j: float, left_j: float,
                            report: SurfacingReport) -> str:
        wh = J_PER_WH
        worst = sorted(((m, abs(m.change)) for m in self.belief.moves()), key=lambda x: -x[1])
        moved = ", ".join(str(m) for m, _ in worst[:2])
        where = f"{report.source}: " if report.source else ""
        return (f"{where}at {report.time_s / 3600:.1f} h the budget left, {left_j / wh:,.1f} Wh "
                f"expected, cannot hold the rest of the mission at confidence "
                f"{self.confidence:g}: with every duty at its floor it needs "
                f"{least_j / wh:,.1f} Wh at that confidence ({moved}). No update is made: "
                "the glider keeps flying its current plan. Lower the duties' floors or the "
                "confidence, or send the plan that needs the least (--if-infeasible "
                "least-energy)")

    def _target(self, held: Plan, remaining: dict[str, float]
                ) -> tuple[Plan, tuple[DutyChange, ...]]:
        """The held plan with the solution's duties and shares, rounded as an update sends
        them; states with no time left keep theirs."""
        inputs, model = self._inputs_now, self.chance.model
        duty = duty_fractions(inputs, _values(model)) if len(inputs.duty_state) else []
        auto = {(inputs.duty_state[p], inputs.duty_sensor[p]): (float(duty[p]),
                                                                inputs.duty_lo[p],
                                                                inputs.duty_hi[p])
                for p in range(len(inputs.duty_state))}
        share = np.clip(np.asarray(model.share.value, float), 0.0, 1.0)
        states, changes = [], []
        for s, state in enumerate(held.states):
            if remaining[state.name] <= 0.0:
                states.append(state)
                continue
            sensors = []
            for x in state.sensors:
                if (s, x.name) not in auto:
                    sensors.append(x)
                    continue
                value, lo, hi = auto[(s, x.name)]
                on = _rounded_on(value * x.period_s, lo * x.period_s, hi * x.period_s)
                sensors.append(SensorPlan(x.name, x.period_s, on))
                if abs(on - x.on_s) >= float(ON_STEP_S) / 2:
                    changes.append(DutyChange(state.name, x.name, x.duty, on / x.period_s))
            rows = np.flatnonzero(inputs.prof_state == s)
            profiles = state.profiles
            if len(rows) > 1:
                shares = _rounded_shares(share[rows])
                profiles = tuple(replace(p, share=f)  # pitch, ballast, speed, thrust kept
                                 for p, f in zip(state.profiles, shares, strict=True))
            if self.rechoose:
                profiles = self._in_water(s, profiles, [inputs.profiles[r] for r in rows])
            states.append(replace(state, sensors=tuple(sensors), profiles=profiles))
        return replace(held, states=tuple(states)), tuple(changes)


    def _in_water(self, s: int, profiles: tuple[ProfilePlan, ...], rates: list[ProfileRates]
                  ) -> tuple[ProfilePlan, ...]:
        """State `s`'s planned profiles with the speed and thrust the planner chooses in
        the water given (`rates`, planner.rates): a propelled profile's speed, a
        thruster-assisted yo's speed and command; the others as they are."""
        written = self.mission.states[s].profiles
        return tuple(replace(p, speed_mps=r.speed_mps, thrust_w=r.thrust_w)
                     if r.flyable and (PROFILES[written[p.index].kind].propelled
                                       or written[p.index].thrust is not None) else p
                     for p, r in zip(profiles, rates, strict=True))


def _values(model):  # noqa: ANN001, ANN202
    """The model's variables' values as a Solution for `duty_fractions`."""
    from gliderplan.planner.model import Solution

    def value(x):  # noqa: ANN001, ANN202
        return np.zeros(0) if x is None else np.asarray(x.value, float)

    return Solution("optimal", value(model.duty), value(model.device), value(model.share),
                    value(model.mode), float(model.quality.value), math.nan, np.zeros(0),
                    None, 0.0, None, None)


def _rounded_on(on_s: float, low_s: float, high_s: float) -> float:
    """An on-time [s] rounded to ON_STEP_S within [low_s, high_s] (rounded inwards)."""
    step = ON_STEP_S
    value = (Decimal(on_s) / step).to_integral_value() * step
    low = -(-Decimal(low_s) // step) * step
    high = (Decimal(high_s) // step) * step
    if low <= high:
        value = min(max(value, low), high)
    return float(value)


def _rounded_shares(shares: np.ndarray) -> list[float]:
    """Profile shares rounded to SHARE_STEP that still sum to one exactly (the last
    share that is not 0 takes the rest)."""
    total = float(shares.sum()) or 1.0
    rounded = [(Decimal(float(f) / total) / SHARE_STEP).to_integral_value() * SHARE_STEP
               for f in shares]
    last = max(i for i, f in enumerate(rounded) if f > 0) if any(rounded) else len(rounded) - 1
    rounded[last] = Decimal(1) - sum(f for i, f in enumerate(rounded) if i != last)
    return [float(f) for f in rounded]


# ---- the command ----------------------------------------------------------------------------

@dataclass(frozen=True)
class ReplanRun:
    """`gliderplan replan`: the replan, the updates that carry it, the files written."""

    result: ReplanResult
    updates: tuple[bytes, ...]  # each at most MAX_UPDATE_BYTES, in the order to send
    plan_file: bytes  # the plan the glider holds once they are applied
    files: tuple[Path, ...] = ()
    notes: tuple[str, ...] = field(default=())

    def to_json(self) -> dict:
        return {**self.result.to_json(), "update_bytes": [len(u) for u in self.updates],
                "telemetry_notes": list(self.notes),
                "files": [str(f) for f in self.files]}


def _water_at(mission: ir.CheckedMission, currents: str, report: SurfacingReport,
              start_epoch_s: float | None) -> dict[str, tuple[Leg, ...]]:
    """The route's legs in `--currents` from where `report` places the glider (where the
    mission starts, if it gives no position), at its time."""
    from gliderplan.planner.legs import ddmm_to_degrees
    from gliderplan.planner.water import plan_water
    from gliderplan.sim.loop import DEFAULT_START_EPOCH_S

    here = None if report.lat is None or report.lon is None else \
        (ddmm_to_degrees(report.lat), ddmm_to_degrees(report.lon))
    epoch = DEFAULT_START_EPOCH_S if start_epoch_s is None else start_epoch_s
    return plan_water(mission, currents, here, epoch + report.time_s)[0]


class TelemetryMismatch(GliderplanError):
    """Telemetry that says the glider holds another plan than the one replanned."""


def replan_mission(mission: ir.CheckedMission, plan_path: str | Path,
                   telemetry: str | Path | list[str | Path], *,
                   confidence: float | None = None, key_path: str | Path | None = None,
                   output: str | Path | None = None, seq: int | None = None,
                   max_updates: int = 1, scenario_file: str | Path | None = None,
                   if_infeasible: str = "refuse", currents: str | None = None,
                   start_epoch_s: float | None = None) -> ReplanRun:
    """Replan the rest of `mission` after the telemetry (a JSON file or Slocum logs) from
    the signed plan in `plan_path`, which the glider holds, at `confidence` (default: the
    plan's own, else 0.95); the prior is the vehicle's figures with the scenario file's
    spreads and battery share. With `output` (and the vehicle's key in `key_path`), write
    the update (`output`; a chain of several: `output`.1, .2, ...), the plan the glider
    will hold (`output`.plan, signed: the next replan's --plan) and the report
    (`output`.json), atomically and together (never an update beside another's plan),
    unless a stop signal arrived (an interrupted replan is no update). Raises
    TelemetryError (bad telemetry), TelemetryMismatch (the glider reports another plan),
    ReplanInfeasible, UpdateError (the update cannot be sent as asked: what to cut),
    PlanRejected. With `currents` (as `plan --currents`) the speeds and thrusts the
    planner chooses are chosen anew in that water, on the route from the glider's last
    reported position, the field read at the report's time after the mission's start
    `start_epoch_s` [s since 1970] (default: the simulator's)."""
    import json

    from gliderplan.contract import interrupts
    from gliderplan.contract.errors import UsageError
    from gliderplan.contract.files import write_files_atomically
    from gliderplan.planner.planfile import plan_board_limits, read_plan_data
    from gliderplan.planner.signing import read_key
    from gliderplan.planner.update import make_updates
    from gliderplan.power_models.telemetry import check_reports, read_telemetry
    from gliderplan.sim.scenarios import read_spec

    if output is not None and key_path is None:
        raise UsageError("-o: an update is signed with the vehicle's key: give --key KEYFILE")
    if max_updates < 1:
        raise UsageError(f"--max-updates {max_updates}: must be at least 1")
    key = read_key(key_path) if key_path is not None else None
    held = read_plan_data(plan_path)
    reports = read_telemetry(telemetry)
    notes = check_reports(reports, tuple(s.name for s in mission.states))
    replanner = Replanner(mission, held, confidence=confidence,
                          spec=read_spec(scenario_file), if_infeasible=if_infeasible,
                          legs=None if currents is None else
                          _water_at(mission, currents, reports[-1], start_epoch_s), once=True)
    said = next((r for r in reversed(reports) if r.plan_seq is not None), None)
    if said is not None and said.plan_seq != replanner.plan.seq:
        ack = "" if said.ack is None else f" (its last update: {said.ack.status.name.lower()}"\
            f"{': ' + said.ack.message if said.ack.message else ''})"
        raise TelemetryMismatch(
            f"{said.source or 'the telemetry'}: the glider reports plan {said.plan_seq} in "
            f"force{ack}; {plan_path} is plan {replanner.plan.seq}: an update must be made "
            "against the plan the glider holds")
    for report in reports:
        replanner.observe(report)
    result = replanner.replan(held, reports[-1])
    updates: list[bytes] = []
    plan_file = held
    files: list[Path] = []
    if key is not None:
        plan = read_plan_bytes(held, mission)
        limits = plan_board_limits(mission, plan)
        chain = make_updates(held, result.target, key, first_seq=seq, max_updates=max_updates,
                             check=lambda data: read_plan_bytes(data, mission, "", limits))
        updates, plan_file = list(chain.updates), chain.plan_file
    run = ReplanRun(result, tuple(updates), plan_file, (), tuple(notes))
    if output is not None:
        out = Path(output)
        names = [out] if len(updates) <= 1 else [out.with_name(f"{out.name}.{i}")
                                                for i in range(1, len(updates) + 1)]
        contents = dict(zip(names, updates, strict=False))
        contents[out.with_name(out.name + ".plan")] = plan_file
        files = [*contents, out.with_name(out.name + ".json")]
        run = replace(run, files=tuple(files))
        contents[files[-1]] = json.dumps(run.to_json(), indent=2) + "\n"
        interrupts.raise_if_stopped()  # an interrupted replan sends nothing
        write_files_atomically(contents)  # together or not at all
        for stale in _other_chain_files(out, names):  # an earlier chain's: not to be sent
            stale.unlink(missing_ok=True)
    return run


def _other_chain_files(out: Path, names: list[Path]) -> list[Path]:
    """The updates an earlier replan wrote under `out` (`out`, or `out`.1, .2, ...) that
    are not this one's `names`: left beside the new chain they would read as part of it."""
    earlier = [out] if out.is_file() else []
    n = 1
    while (member := out.with_name(f"{out.name}.{n}")).is_file():
        earlier.append(member)
        n += 1
    return [path for path in earlier if path not in names]
