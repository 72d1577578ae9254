"""The convex planning model, built once from cvxpy Parameters (DCP and DPP).

Two problems share the variables and the constraints of `inputs.PlanInputs`:

    quality problem:  maximise  Q(d)  s.t.  E(D, f, g) <= budget, common constraints
    energy problem:   minimise  E(D, f, g)  s.t.  Q(d) >= floor, common constraints

with Q = sum_p omega_p log(1 + a_p d_p) / log(1 + a_p) + Q0 (concave: a weighted sum of
logs of affine functions) and E = E0 + e_dev . D + e_prof . f + e_mode . g (affine). The
common constraints are linear in the variables (duty bounds, D >= d of every sensor a
device serves, shares summing to one, clocks that keep up) or concave >= constant
(per-sensor quality floors). Every number that depends on the time in each state, the
budget or the hardware is a Parameter, so a sweep only sets values and re-solves: cvxpy
compiles the problem once and reuses the compiled form.
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass

import cvxpy as cp
import numpy as np
import scipy.sparse as sp

from gliderplan.planner.inputs import ENERGY_UNIT_J, Coefficients, PlanInputs, coefficients
from gliderplan.planner.occupancy import NOMINAL_SPEED_MPS

SOLVER = cp.CLARABEL
SATURATION_TOLERANCE = 1e-6  # relative quality below the maximum that counts as saturated
MAX_PACE_S_PER_M = 10.0  # slowest transit: 0.1 m/s (assumption: below it a glider steers badly)
NOMINAL_PACE_S_PER_M = 1.0 / NOMINAL_SPEED_MPS


@dataclass(frozen=True)
class Solution:
    status: str  # cvxpy status: optimal, infeasible, ...
    duty: np.ndarray
    device: np.ndarray
    share: np.ndarray
    mode: np.ndarray
    quality: float
    model_energy_j: float
    pace: np.ndarray  # (n_t,) [s m-1] of the transit legs
    budget_dual: float | None  # d quality / d energy [1 J-1], quality problem only
    solve_s: float  # wall-clock time of the solve call [s], compilation included
    solver_s: float | None  # time inside Clarabel [s]
    iterations: int | None

    @property
    def optimal(self) -> bool:
        return self.status in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE)


def _selector(rows: np.ndarray, n_cols: int) -> sp.csr_matrix:
    """Sparse 0/1 matrix with a one in (i, rows[i])."""
    n = len(rows)
    return sp.csr_matrix((np.ones(n), (np.arange(n), rows)), shape=(n, n_cols))


def structure(inputs: PlanInputs) -> tuple:
    """What the built problems hold as constants rather than Parameters: the index sets
    and sizes, the duty and device bounds, the utility curvatures, the clocks that cannot
    keep up, the transit legs' pump and speed limits, whether there is a horizon. Two
    inputs with the same structure can share one model (a sweep only sets values)."""
    tr = inputs.transit
    arrays = (inputs.duty_state, inputs.duty_device, inputs.alpha, inputs.duty_lo,
              inputs.duty_hi, inputs.dev_state, inputs.dev_lo, inputs.dev_hi, inputs.prof_state,
              inputs.mode_state, np.isfinite(inputs.mode_power_w), tr.state, tr.pump_s,
              tr.min_pace)
    return (len(inputs.states), inputs.mission.horizon_s is not None,
            tuple(sorted(inputs.sensor_quality_min.items())),
            *((a.shape, a.dtype.str, a.tobytes()) for a in arrays))


def model_for(inputs: PlanInputs, reuse: PlanModel | None = None) -> PlanModel:
    """A model of `inputs` with its coefficients set: `reuse` itself when its structure is
    that of `inputs` (no re-compilation), else a model built anew."""
    model = reuse if reuse is not None and reuse.structure == structure(inputs) \
        else PlanModel(inputs)
    model.inputs = inputs
    model.set_coefficients(coefficients(inputs))
    return model


class PlanModel:
    """The two problems and their parameters for one mission's index sets."""

    def __init__(self, inputs: PlanInputs) -> None:
        self.inputs = inputs
        self.structure = structure(inputs)
        n_p, n_q, n_r, n_m = inputs.sizes
        n_s = len(inputs.states)
        self.duty = cp.Variable(n_p, name="duty") if n_p else None
        self.device = cp.Variable(n_q, name="device") if n_q else None
        self.share = cp.Variable(n_r, nonneg=True, name="share")
        self.mode = cp.Variable(n_m, nonneg=True, name="clock")
        self.p_dev = cp.Parameter(n_q, nonneg=True, name="dev_j") if n_q else None
        self.p_prof = cp.Parameter(n_r, nonneg=True, name="prof_j")
        self.p_mode = cp.Parameter(n_m, nonneg=True, name="mode_j")
        self.p_fixed = cp.Parameter(nonneg=True, name="fixed_j")
        self.p_omega = cp.Parameter(n_p, nonneg=True, name="omega") if n_p else None
        self.p_quality0 = cp.Parameter(nonneg=True, name="quality0")
        self.p_budget = cp.Parameter(nonneg=True, name="budget")
        self.p_floor = cp.Parameter(name="floor")
        self.p_sensor = {k: (cp.Parameter(n_p, nonneg=True), cp.Parameter(nonneg=True))
                         for k in inputs.sensor_quality_min}

        energy = self.p_fixed + self.p_prof @ self.share + self.p_mode @ self.mode
        quality = self.p_quality0
        tr = inputs.transit
        transit_duty = inputs.duty_in_transit
        transit_dev = inputs.device_in_transit
        steady_duty = np.flatnonzero(~transit_duty)
        steady_dev = np.flatnonzero(~transit_dev)
        common = [_selector(inputs.prof_state, n_s).T @ self.share == 1,
                  _selector(inputs.mode_state, n_s).T @ self.mode == 1]
        unusable = ~np.isfinite(inputs.mode_power_w)
        if unusable.any():
            common.append(self.mode[np.flatnonzero(unusable)] == 0)
        unflyable = [j for j, p in enumerate(inputs.profiles) if not p.flyable]
        if unflyable:  # alternatives the vehicle cannot fly
            common.append(self.share[unflyable] == 0)
        if n_q:
            energy = energy + self.p_dev @ self.device
            common += [self.device[steady_dev] >= inputs.dev_lo[steady_dev],
                       self.device[steady_dev] <= inputs.dev_hi[steady_dev]]
        if n_p:
            utility = cp.multiply(1.0 / np.log1p(inputs.alpha),
                                  cp.log1p(cp.multiply(inputs.alpha, self.duty)))
            quality = quality + self.p_omega @ utility
            common += [self.duty[steady_duty] >= inputs.duty_lo[steady_duty],
                       self.duty[steady_duty] <= inputs.duty_hi[steady_duty],
                       _selector(inputs.duty_device, n_q) @ self.device >= self.duty]
        self.pace = cp.Variable(tr.size, name="pace") if tr.size else None
        self.p_transit: dict[str, cp.Parameter] = {}
        if tr.size:
            energy, quality = self._transit(energy, quality, common)
            for sensor, (weights, offset) in self.p_sensor.items():
                common.append(weights @ utility + offset >= inputs.sensor_quality_min[sensor])
        self.energy = energy
        self.quality = quality
        self.common = common  # what every problem over these variables keeps
        self.budget_constraint = energy <= self.p_budget
        self.quality_problem = cp.Problem(cp.Maximize(quality), [*common, self.budget_constraint])
        self.energy_problem = cp.Problem(cp.Minimize(energy), [*common, quality >= self.p_floor])
        for problem in (self.quality_problem, self.energy_problem):
            assert problem.is_dcp(dpp=True), "the planning model must stay DCP and DPP"
        self.set_floor(0.0)
        self.set_budget_j(0.0)

    def _transit(self, energy, quality, common: list) -> tuple:
        """Transit legs in the pace formulation: per metre, glide time p, pump time k p^-2,
        on-time x <= p; energy and time are convex in p, quality a perspective."""
        inputs, tr = self.inputs, self.inputs.transit
        n_t = tr.size
        where = {s: i for i, s in enumerate(tr.state)}
        rows = np.flatnonzero(inputs.duty_in_transit)
        devs = np.flatnonzero(inputs.device_in_transit)
        p = self.pace
        pump = cp.multiply(tr.pump_s, cp.power(p, -2))  # pump time per metre
        par = self.p_transit
        par["pace_j"] = cp.Parameter(n_t, nonneg=True)
        par["inv_pace_j"] = cp.Parameter(n_t, nonneg=True)
        energy = energy + par["pace_j"] @ p + par["inv_pace_j"] @ cp.power(p, -2)
        common += [p >= tr.min_pace, p <= MAX_PACE_S_PER_M]
        if len(devs):
            sel = _selector(np.array([where[s] for s in inputs.dev_state[devs]]), n_t)
            floor = inputs.dev_lo[devs]
            common.append(self.device[devs] >= cp.multiply(floor, sel @ (p + pump)))
            free = np.flatnonzero(floor == 0.0)
            if len(free):
                common.append(self.device[devs[free]] <= (sel @ p)[free])
        if len(rows):
            sel = _selector(np.array([where[s] for s in inputs.duty_state[rows]]), n_t)
            glide, x, a = sel @ p, self.duty[rows], inputs.alpha[rows]
            common += [x >= cp.multiply(inputs.duty_lo[rows], sel @ (p + pump)),
                       x <= cp.multiply(inputs.duty_hi[rows], glide),
                       x <= inputs.duty_hi[rows] * NOMINAL_PACE_S_PER_M]
            # Along a route, data quality is sampling per metre: on-time per metre against
            # full-duty sampling at the nominal speed (flying slower buys no more than that).
            per_metre = cp.multiply(1.0 / np.log1p(a),
                                    cp.log1p(cp.multiply(a / NOMINAL_PACE_S_PER_M, x)))
            par["omega"] = cp.Parameter(len(rows), nonneg=True)
            quality = quality + par["omega"] @ per_metre
        if inputs.mission.horizon_s is not None:
            par["leg_m"] = cp.Parameter(n_t, nonneg=True)
            par["leg_pump_m"] = cp.Parameter(n_t, nonneg=True)
            par["horizon_left_s"] = cp.Parameter()
            common.append(par["leg_m"] @ p + par["leg_pump_m"] @ cp.power(p, -2)
                          <= par["horizon_left_s"])
        return energy, quality

    # ---- parameter values ----------------------------------------------------------
    def set_coefficients(self, c: Coefficients) -> None:
        self.coefficients = c
        if self.p_dev is not None:
            self.p_dev.value = c.dev_j
        self.p_prof.value = c.prof_j
        self.p_mode.value = c.mode_j
        self.p_fixed.value = c.fixed_j
        if self.p_omega is not None:
            self.p_omega.value = c.omega
        self.p_quality0.value = c.quality0
        for sensor, (weights, offset) in self.p_sensor.items():
            weights.value = c.sensor_omega[sensor]
            offset.value = c.sensor_quality0[sensor]
        values = {"pace_j": c.pace_j, "inv_pace_j": c.inv_pace_j,
                  "omega": c.omega_transit[self.inputs.duty_in_transit],
                  "leg_m": c.leg_m, "leg_pump_m": c.leg_pump_m,
                  "horizon_left_s": c.horizon_left_s}
        for name, parameter in self.p_transit.items():
            parameter.value = values[name]

    def set_budget_j(self, budget_j: float) -> None:
        self.p_budget.value = max(budget_j, 0.0) / ENERGY_UNIT_J

    def set_floor(self, quality: float) -> None:
        self.p_floor.value = quality

    def ample_budget_j(self) -> float:
        """A budget [J] above anything the mission can spend: the quality problem without
        a budget (an infinite one would upset the solver's scaling)."""
        c = self.coefficients
        most = c.fixed_j + float(c.dev_j.sum() + c.prof_j.sum() + c.mode_j.sum())
        if self.pace is not None:  # the slowest and the fastest legs bound the transit cost
            fastest = 1.0 / self.inputs.transit.min_pace
            most += float(c.pace_j.sum() * MAX_PACE_S_PER_M + c.inv_pace_j @ fastest**2)
        return 2.0 * most * ENERGY_UNIT_J + 1.0

    # ---- solving -------------------------------------------------------------------
    def solve_quality(self, budget_j: float, **options: float) -> Solution:
        """Best quality within `budget_j` [J]."""
        self.set_budget_j(budget_j)
        return self._solve(self.quality_problem, **options)

    def solve_energy(self, quality_floor: float, **options: float) -> Solution:
        """Least energy that reaches `quality_floor`."""
        self.set_floor(quality_floor)
        return self._solve(self.energy_problem, **options)

    def _solve(self, problem: cp.Problem, **options: float) -> Solution:
        start = time.perf_counter()
        try:
            with warnings.catch_warnings():  # the status below says "optimal_inaccurate"
                warnings.filterwarnings("ignore", message="Solution may be inaccurate")
                problem.solve(solver=SOLVER, **options)
        except cp.SolverError:
            pass  # reported through the status below
        elapsed = time.perf_counter() - start
        status = problem.status or "solver_error"
        stats = problem.solver_stats
        ok = status in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE)

        def value(x: cp.Variable | None) -> np.ndarray:
            if x is None:
                return np.zeros(0)
            return np.asarray(x.value, float) if ok else np.full(x.shape, np.nan)

        dual = None
        if ok and problem is self.quality_problem:
            dual = float(self.budget_constraint.dual_value) / ENERGY_UNIT_J
        return Solution(
            status=status, duty=value(self.duty), device=value(self.device),
            share=value(self.share), mode=value(self.mode),
            quality=float(self.quality.value) if ok else float("nan"),
            model_energy_j=float(self.energy.value) * ENERGY_UNIT_J if ok else float("nan"),
            pace=value(self.pace),
            budget_dual=dual, solve_s=elapsed,
            solver_s=getattr(stats, "solve_time", None) if stats else None,
            iterations=getattr(stats, "num_iters", None) if stats else None,
        )
