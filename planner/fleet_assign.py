"""Which glider flies which lines: the survey's lines, in the file's order, cut into one
contiguous block per glider, as a mixed-integer program (cvxpy, HiGHS).

Each glider flies one contiguous run of the survey's lines (as pilots split a survey: it
keeps gliders apart and their turns short). A block is an arc i -> j of a graph whose
nodes 0..P are the cuts between lines: the assignment is a path from node 0 to node P
that uses exactly one arc of every glider,

    minimise    sum_a cost_a y_a
    subject to  sum_{a out of 0} y_a = 1,  sum_{a into P} y_a = 1,
                sum_{a into k} y_a = sum_{a out of k} y_a     (0 < k < P),
                sum_{a of glider g} y_a = 1                   (every glider),
                y_a in {0, 1}.

Every arc's cost is exact, not linearised: the block's share of the survey times the
mapping error its lines keep (`fleet_mapping.RevisitTable`: a line swept every pass time,
from when the glider reaches the block until its flight ends; unsampled before and
after). Arcs a glider cannot fly are left out: its first sweep of the block (from where it
starts, in the design scenarios' current) must end before its flight does, and with a
revisit goal, no line may wait longer than the goal. The model has P + 1 + G rows and
three non-zeros per arc, whatever the number of gliders.

Past `MAX_MILP_ARCS` arcs, or when HiGHS finds no solution in its time limit, a
heuristic takes over: the gliders in the order their starts lie along the survey, the
best cut of the lines for that order by dynamic programming (exact for a fixed order),
improved by swapping neighbours in the order; its gap is measured against the LP
relaxation's bound.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

MAX_MILP_ARCS = 20_000  # past this, the heuristic (HiGHS takes many seconds past it)
DEFAULT_TIME_LIMIT_S = 20.0


@dataclass(frozen=True)
class BlockInputs:
    """Everything an arc's feasibility and cost depend on (arrays over gliders G, parts
    P, scenarios N)."""

    length_m: np.ndarray  # (P,) line lengths
    link_m: np.ndarray  # (P,) from the end of line p to line p + 1 (0 for the last)
    weight: np.ndarray  # (P,) share of the survey's area around each line (sums to 1)
    speed_mps: np.ndarray  # (G,) effective speed
    flight_share: float  # share of the time flying (the rest at the surface)
    launch_s: float
    start_s: np.ndarray  # (G,) start after the fleet's [s]
    end_s: np.ndarray  # (G,) end of its flight after its start [s]
    period_s: float
    transit_m: np.ndarray  # (G, P, 2) from its start to each end of each line
    line_factor: np.ndarray  # (G, P, N) time factor of a line in each scenario's current
    transit_factor: np.ndarray  # (G, P, 2, N) of the transit to each end
    quantile: float  # the share of scenarios a block may fail in (design)
    revisit_s: float | None  # longest a line may wait between sweeps
    error_of_pass: object  # RevisitTable
    time_scale_s: float  # the field's
    require_sweep: bool = True  # False: a block need only be reached in time (a re-plan
    # after a loss, when every line has been swept once already)

    @property
    def gliders(self) -> int:
        return len(self.speed_mps)

    @property
    def parts(self) -> int:
        return len(self.length_m)


@dataclass(frozen=True)
class Arcs:
    glider: np.ndarray  # (A,)
    first: np.ndarray  # (A,) first line of the block
    stop: np.ndarray  # (A,) one past its last line
    entry_last: np.ndarray  # (A,) entered at its last line
    cost: np.ndarray  # (A,)

    def __len__(self) -> int:
        return len(self.cost)


@dataclass(frozen=True)
class Block:
    glider: int
    first: int
    stop: int
    entry_last: bool
    cost: float
    feasible: bool = True


@dataclass(frozen=True)
class Assignment:
    blocks: tuple[Block, ...]  # one per glider, by glider index
    objective: float  # sum of the blocks' costs (the surrogate mapping error)
    method: str  # "milp" | "heuristic" | "brute force" | "equal split"
    status: str  # the solver's, or "feasible" / "infeasible"
    bound: float | None = None  # the best bound known (MILP dual bound or LP relaxation)
    solve_s: float = 0.0
    arcs: int = 0

    @property
    def gap(self) -> float | None:
        """Relative gap to the bound: how far from optimal at most."""
        if self.bound is None or not math.isfinite(self.objective):
            return None
        return max(self.objective - self.bound, 0.0) / max(abs(self.objective), 1e-12)


def _block_cost(inputs: BlockInputs, g: int, weight, first_pass_m, transit_m):
    """(cost, pass time [s], arrival [s after the fleet's start]) of glider g sweeping
    blocks (arrays or scalars): `weight` their share of the survey, `first_pass_m` one
    sweep's length, `transit_m` the way to them.

    While the glider sweeps the block, a line's error is that of a line swept every pass
    (`error_of_pass`); before the glider reaches it and after it stops, the error relaxes
    towards 1 as the samples age (Gaussian in time, as the covariance: the period's mean
    integrates it in closed form). The block's neighbours are left out: a per-block cost
    keeps the assignment a MILP; the local search after it (`planner.fleet.polish`) sees
    them."""
    rate = inputs.speed_mps[g] * inputs.flight_share
    pass_s = np.asarray(first_pass_m, float) / rate
    arrive = inputs.start_s[g] + inputs.launch_s + np.asarray(transit_m, float) / rate
    stop = min(inputs.start_s[g] + inputs.end_s[g], inputs.period_s)
    # a line is first reached half a pass after the block is, on average
    first = np.minimum(arrive + 0.5 * pass_s, stop)
    swept = inputs.error_of_pass(pass_s)
    memory = inputs.time_scale_s * math.sqrt(math.pi) / 2.0
    before = first - (1.0 - swept) * memory * _erf(first / inputs.time_scale_s)
    after_s = inputs.period_s - stop
    after = after_s - (1.0 - swept) * memory * math.erf(after_s / inputs.time_scale_s)
    mean = ((stop - first) * swept + before + after) / inputs.period_s
    return weight * mean, pass_s, arrive


def _erf(x):
    from scipy.special import erf

    return erf(x)


def build_arcs(inputs: BlockInputs) -> Arcs:
    """Every block every glider can fly, with its cost and the end it is entered by."""
    cum_len = np.concatenate([[0.0], np.cumsum(inputs.length_m)])
    cum_link = np.concatenate([[0.0], np.cumsum(inputs.link_m)])
    cum_w = np.concatenate([[0.0], np.cumsum(inputs.weight)])
    n_parts = inputs.parts
    q = 1.0 - inputs.quantile
    gliders, firsts, stops, entries, costs = [], [], [], [], []
    for g in range(inputs.gliders):
        rate = inputs.speed_mps[g] * inputs.flight_share
        deadline = inputs.end_s[g]
        # scenario time of lines p..: prefix sums over lines, per scenario
        swept = (inputs.length_m + inputs.link_m)[:, None] * inputs.line_factor[g]
        cum_swept = np.vstack([np.zeros(swept.shape[1]), np.cumsum(swept, axis=0)])
        nearest = inputs.transit_m[g].min(axis=1)
        for i in range(n_parts):
            # a block's first sweep in still water is at least this long: stop growing it
            # once even that misses the deadline
            j = np.arange(i + 1, n_parts + 1)
            sweep = cum_len[j] - cum_len[i] + cum_link[j - 1] - cum_link[i]
            reach = np.minimum(nearest[i], nearest[j - 1])
            still = inputs.launch_s + (reach + (sweep if inputs.require_sweep else 0.0)) / rate
            j = j[still <= deadline]
            if not len(j):
                continue
            sweep = cum_len[j] - cum_len[i] + cum_link[j - 1] - cum_link[i]
            scenario = cum_swept[j] - cum_swept[i]  # (J, N)
            best = None
            for last in (False, True):
                line = (j - 1) if last else np.full(len(j), i)
                end = np.argmin(inputs.transit_m[g, line], axis=1)
                transit = inputs.transit_m[g, line, end]
                factor = inputs.transit_factor[g, line, end]  # (J, N)
                times = inputs.launch_s + (transit[:, None] * factor
                                           + (scenario if inputs.require_sweep else 0.0)) / rate
                ok = np.quantile(times, q, axis=1) <= deadline
                if inputs.revisit_s is not None:
                    pass_q = np.quantile(scenario, q, axis=1) / rate
                    ok &= 2.0 * pass_q <= inputs.revisit_s
                cost = _block_cost(inputs, g, cum_w[j] - cum_w[i], sweep, transit)[0]
                cost = np.where(ok, cost, np.inf)
                if best is None:
                    best = (cost, np.zeros(len(j), bool))
                else:
                    better = cost < best[0]
                    best = (np.where(better, cost, best[0]), better)
            keep = np.isfinite(best[0])
            count = int(keep.sum())
            gliders.append(np.full(count, g))
            firsts.append(np.full(count, i))
            stops.append(j[keep])
            entries.append(best[1][keep])
            costs.append(best[0][keep])
    def cat(parts, dtype):
        return (np.concatenate(parts).astype(dtype) if parts
               else np.zeros(0, dtype))
    return Arcs(cat(gliders, int), cat(firsts, int), cat(stops, int), cat(entries, bool),
                cat(costs, float))


def block_of(inputs: BlockInputs, g: int, first: int, stop: int) -> Block:
    """Glider g on lines first..stop-1 whether it can fly them or not (the equal split's
    blocks): the better entry, its cost, and whether it is feasible at the design
    quantile."""
    length = float(inputs.length_m[first:stop].sum() + inputs.link_m[first:stop - 1].sum())
    weight = float(inputs.weight[first:stop].sum())
    rate = inputs.speed_mps[g] * inputs.flight_share
    swept = ((inputs.length_m + inputs.link_m)[first:stop, None]
             * inputs.line_factor[g, first:stop]).sum(axis=0)
    best = None
    for last in (False, True):
        line = stop - 1 if last else first
        end = int(np.argmin(inputs.transit_m[g, line]))
        transit = float(inputs.transit_m[g, line, end])
        times = inputs.launch_s + (transit * inputs.transit_factor[g, line, end]
                                   + (swept if inputs.require_sweep else 0.0)) / rate
        ok = np.quantile(times, 1.0 - inputs.quantile) <= inputs.end_s[g]
        if inputs.revisit_s is not None:
            ok &= 2.0 * np.quantile(swept, 1.0 - inputs.quantile) / rate <= inputs.revisit_s
        cost = float(_block_cost(inputs, g, weight, length, transit)[0])
        if best is None or cost < best.cost:
            best = Block(g, first, stop, last, cost, bool(ok))
    return best


# ---- solvers -----------------------------------------------------------------------------

@contextmanager
def quiet_stdout() -> Iterator[None]:
    """HiGHS prints its banner on the process's standard output (file descriptor 1)
    whatever its options say: point the descriptor at /dev/null while it solves, so that
    a command's output (`--json`) stays its own."""
    import os
    import sys

    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "wb") as null:
            os.dup2(null.fileno(), 1)
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def _matrices(arcs: Arcs, n_parts: int, n_gliders: int):
    import scipy.sparse as sp

    n = len(arcs)
    columns = np.arange(n)
    flow = sp.csr_matrix((np.concatenate([-np.ones(n), np.ones(n)]),
                          (np.concatenate([arcs.first, arcs.stop]),
                           np.concatenate([columns, columns]))), shape=(n_parts + 1, n))
    each = sp.csr_matrix((np.ones(n), (arcs.glider, columns)), shape=(n_gliders, n))
    target = np.zeros(n_parts + 1)
    target[0], target[n_parts] = -1.0, 1.0
    return flow, each, target


def _chosen(arcs: Arcs, picked: np.ndarray, n_gliders: int) -> tuple[Block, ...]:
    blocks = {int(arcs.glider[a]): Block(int(arcs.glider[a]), int(arcs.first[a]),
                                         int(arcs.stop[a]), bool(arcs.entry_last[a]),
                                         float(arcs.cost[a])) for a in picked}
    return tuple(blocks[g] for g in range(n_gliders))


def solve_milp(arcs: Arcs, n_parts: int, n_gliders: int,
               time_limit_s: float = DEFAULT_TIME_LIMIT_S) -> Assignment | None:
    """The exact assignment by HiGHS; None when it is infeasible (no path of one block
    per glider covers the lines). A solve stopped by the time limit returns its best
    solution and bound (its gap), or the heuristic's solution if it found none."""
    import warnings

    import cvxpy as cp

    flow, each, target = _matrices(arcs, n_parts, n_gliders)
    y = cp.Variable(len(arcs), boolean=True)
    problem = cp.Problem(cp.Minimize(arcs.cost @ y), [flow @ y == target, each @ y == 1])
    start = time.perf_counter()
    with warnings.catch_warnings(), quiet_stdout():
        warnings.filterwarnings("ignore", message="Solution may be inaccurate")
        # probing (presolve rule 15) spends tens of seconds on thousands of arcs and
        # finds nothing the LP does not: off
        problem.solve(solver=cp.HIGHS, time_limit=time_limit_s, presolve_rule_off=32768,
                      output_flag=False,
                      mip_rel_gap=1e-6)
    spent = time.perf_counter() - start
    stats = problem.solver_stats
    info = getattr(stats, "extra_stats", None) if stats else None
    bound = getattr(info, "mip_dual_bound", None) if info is not None else None
    if problem.status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
        return None
    if y.value is None:  # the time limit with no solution at all
        fallback = solve_heuristic(arcs, n_parts, n_gliders, positions=None)
        if fallback is None:
            return None
        return Assignment(fallback.blocks, fallback.objective, "heuristic",
                          f"MILP stopped at {time_limit_s:g} s without a solution",
                          fallback.bound, spent + fallback.solve_s, len(arcs))
    picked = np.flatnonzero(np.asarray(y.value) > 0.5)
    blocks = _chosen(arcs, picked, n_gliders)
    objective = float(sum(b.cost for b in blocks))
    status = "optimal" if problem.status == cp.OPTIMAL else str(problem.status)
    if bound is None or not math.isfinite(bound):
        bound = objective if status == "optimal" else None
    return Assignment(blocks, objective, "milp", status, min(bound, objective)
                      if bound is not None else None, spent, len(arcs))


def lp_bound(arcs: Arcs, n_parts: int, n_gliders: int, upper: float | None = None,
             iterations: int = 400) -> float:
    """A lower bound on every assignment's objective: the Lagrangian dual of "every glider
    once", by subgradient ascent (Polyak's step towards `upper`, a known objective, with
    its factor halved when the bound stalls). With those constraints priced (lambda_g),
    what is left is a shortest path over the cuts, whose LP is integral, so the dual's
    optimum is the LP relaxation's bound; any lambda gives a valid bound, and the best
    one met is kept."""
    order = np.argsort(arcs.stop, kind="stable")
    first, stop, glider = arcs.first[order], arcs.stop[order], arcs.glider[order]
    cost = arcs.cost[order]
    into = np.searchsorted(stop, np.arange(n_parts + 2))
    lam = np.zeros(n_gliders)
    best = -math.inf
    scale = float(np.median(cost)) if len(cost) else 1.0
    factor, stalled = 1.0, 0
    for _ in range(iterations):
        priced = cost - lam[glider]
        dist = np.full(n_parts + 1, math.inf)
        dist[0] = 0.0
        via = np.full(n_parts + 1, -1)
        for j in range(1, n_parts + 1):
            lo, hi = into[j], into[j + 1]
            if lo == hi:
                continue
            total = dist[first[lo:hi]] + priced[lo:hi]
            pick = int(np.argmin(total))
            dist[j], via[j] = total[pick], lo + pick
        if not math.isfinite(dist[n_parts]):
            return math.inf  # no path at all
        value = dist[n_parts] + lam.sum()
        if value > best + 1e-12:
            best, stalled = value, 0
        else:
            stalled += 1
            if stalled >= 15:
                factor, stalled = factor / 2.0, 0
        used = np.zeros(n_gliders)
        j = n_parts
        while j > 0:
            used[glider[via[j]]] += 1.0
            j = first[via[j]]
        slope = 1.0 - used
        norm = float(slope @ slope)
        if norm == 0.0:  # the path uses every glider once: the bound is exact
            return float(value)
        target = upper if upper is not None and upper > value else value + 0.1 * scale
        lam += factor * (target - value) / norm * slope
    return float(best)


def _dp(table: dict, order: list[int], n_parts: int) -> tuple[float, list[tuple[int, int]]]:
    """Best cut of lines 0..P-1 into len(order) blocks flown by `order` in turn: (cost,
    [(first, stop)])."""
    best = {0: (0.0, [])}
    for g in order:
        nxt: dict[int, tuple[float, list]] = {}
        for i, (cost, cuts) in best.items():
            for j, c in table[g].get(i, {}).items():
                total = cost + c
                if j not in nxt or total < nxt[j][0]:
                    nxt[j] = (total, [*cuts, (i, j)])
        best = nxt
    return best.get(n_parts, (math.inf, []))


def solve_heuristic(arcs: Arcs, n_parts: int, n_gliders: int,
                    positions: np.ndarray | None, with_bound: bool = True
                    ) -> Assignment | None:
    """Gliders in the order of `positions` (where each starts along the survey; default:
    the middle of its cheapest arc), the best cut for that order (DP), neighbours swapped
    while that helps; gap against the LP relaxation."""
    start = time.perf_counter()
    table: dict[int, dict[int, dict[int, float]]] = {g: {} for g in range(n_gliders)}
    entry: dict[tuple[int, int, int], bool] = {}
    for a in range(len(arcs)):
        g, i, j = int(arcs.glider[a]), int(arcs.first[a]), int(arcs.stop[a])
        table[g].setdefault(i, {})[j] = float(arcs.cost[a])
        entry[g, i, j] = bool(arcs.entry_last[a])
    if positions is None:
        positions = np.array([
            np.mean(0.5 * (arcs.first + arcs.stop)[arcs.glider == g])
            if np.any(arcs.glider == g) else 0.0 for g in range(n_gliders)])
    order = [int(g) for g in np.argsort(positions, kind="stable")]
    cost, cuts = _dp(table, order, n_parts)
    improved = True
    while improved:
        improved = False
        for k in range(n_gliders - 1):
            trial = order[:k] + [order[k + 1], order[k]] + order[k + 2:]
            c, cu = _dp(table, trial, n_parts)
            if c < cost - 1e-12:
                order, cost, cuts, improved = trial, c, cu, True
    if not math.isfinite(cost):
        return None
    blocks = sorted((Block(g, i, j, entry[g, i, j], table[g][i][j])
                     for g, (i, j) in zip(order, cuts, strict=True)), key=lambda b: b.glider)
    bound = lp_bound(arcs, n_parts, n_gliders, cost) if with_bound else None
    if bound is not None and not math.isfinite(bound):
        bound = None
    return Assignment(tuple(blocks), cost, "heuristic", "feasible", bound,
                      time.perf_counter() - start, len(arcs))


def brute_force(arcs: Arcs, n_parts: int, n_gliders: int) -> Assignment | None:
    """Every cut of the lines into contiguous blocks and every order of the gliders over
    them: the optimum by exhaustion (small cases only)."""
    table = {(int(g), int(i), int(j)): (float(c), bool(e)) for g, i, j, c, e in
             zip(arcs.glider, arcs.first, arcs.stop, arcs.cost, arcs.entry_last, strict=True)}
    best: tuple[float, tuple] | None = None
    for cuts in itertools.combinations(range(1, n_parts), n_gliders - 1):
        bounds = list(zip((0, *cuts), (*cuts, n_parts), strict=True))
        for order in itertools.permutations(range(n_gliders)):
            found = [table.get((g, i, j)) for g, (i, j) in zip(order, bounds, strict=True)]
            if None in found:
                continue
            total = sum(c for c, _ in found)
            if best is None or total < best[0]:
                best = (total, tuple(Block(g, i, j, e, c) for g, (i, j), (c, e)
                                     in zip(order, bounds, found, strict=True)))
    if best is None:
        return None
    return Assignment(tuple(sorted(best[1], key=lambda b: b.glider)), best[0], "brute force",
                      "optimal", best[0])


def equal_split(inputs: BlockInputs) -> Assignment:
    """The naive plan: the lines cut into blocks of equal length in their order, each
    given to the glider that starts nearest to it (assignment by least total transit),
    each glider flying it alone at its own capacity."""
    from scipy.optimize import linear_sum_assignment

    cum = np.concatenate([[0.0], np.cumsum(inputs.length_m)])
    n, gliders = inputs.parts, inputs.gliders
    cuts = [0]
    for k in range(1, gliders):
        cut = int(np.argmin(np.abs(cum - k * cum[-1] / gliders)))
        cuts.append(min(max(cut, cuts[-1] + 1), n - (gliders - k)))
    cuts.append(n)
    spans = list(zip(cuts, cuts[1:], strict=False))
    distance = np.array([[min(inputs.transit_m[g, i].min(), inputs.transit_m[g, j - 1].min())
                          for i, j in spans] for g in range(gliders)])
    rows, cols = linear_sum_assignment(distance)
    blocks = sorted((block_of(inputs, int(g), *spans[int(b)]) for g, b in zip(rows, cols,
                                                                                strict=True)),
                    key=lambda b: b.glider)
    feasible = all(b.feasible for b in blocks)
    return Assignment(tuple(blocks), float(sum(b.cost for b in blocks)), "equal split",
                      "feasible" if feasible else "infeasible")
