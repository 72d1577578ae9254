"""`plan_fleet`: several gliders sharing one survey (`gliderplan fleet plan`).

1. Each glider kind (vehicle, board, yo band) is probed through the planner
   (`fleet_capacity.speed_curve`): power against speed.
2. Scenarios are drawn as the Monte Carlo draws them (ocean, current, battery, the
   vehicle's figures), from a stream of their own. Each glider flies the fastest speed
   whose energy for its whole share of the survey holds in all but a design share of
   them, or, if none lasts, its cheapest speed until its battery runs out: how far it
   flies and until when.
3. The lines are cut into one contiguous block per glider (`fleet_assign`, a MILP by
   HiGHS) to minimise the mapping error the blocks keep (`fleet_mapping`), every block's
   first sweep finished in time in all but the design share of the scenarios.
4. Each glider's track and mission are generated (`fleet_missions`), checked, and planned
   by the planner (`planner.plan`): the energy and budget reported are that plan's.
5. The plan is validated on fresh scenarios: the share in which every glider keeps its
   budget and sweeps its block by the finish, with a Clopper-Pearson bound at risk
   1e-3. Below the fleet's confidence, the design share is cut and the plan made again.
6. The plan's mapping error is objective analysis on its tracks' samples; the naive plan
   a pilot would make (equal blocks in order, each to the glider nearest it, each flown
   alone at its own capacity) is evaluated the same way.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract.units import J_PER_WH
from gliderplan.language.fleet import Fleet, FleetError, GliderSpec
from gliderplan.planner import fleet_assign as assign
from gliderplan.planner.fleet_capacity import (
    Capacity,
    CapacityError,
    Scenarios,
    SpeedCurve,
    bands,
    capacity,
    draw_scenarios,
    flight_energy,
    ground_factor,
    hours,
    kind_key,
    leg_factors,
    pick,
    router_for,
    speed_curve,
)
from gliderplan.planner.fleet_mapping import (
    Grid,
    combined,
    evaluation_grid,
    mapping_error,
    one_blas_thread,
    revisit_table,
    sample_spacing,
)
from gliderplan.planner.fleet_missions import LAUNCH_S, Track, build_track, mission_text

DESIGN_SCENARIOS = 300
VALIDATION_SCENARIOS = 1000
RISK = 0.05  # a one-sided 95 % bound, as the Monte Carlo's 95 % intervals
ROUNDS = 5  # design shares tried before the fleet is declared infeasible
# The local search on the true mapping error tries at most this many cuts: bounded work
# that does not depend on the machine's load, so one fleet always gets one plan (10
# gliders over 200 lines settle in some 45 tries, about 1 s of CPU)
POLISH_TRIALS = 120
ENERGY_TOLERANCE = 1.01  # the planner's energy may exceed the fleet model's by this
REPORT_VERSION = 1
TARGET_IMPROVEMENT = 0.2  # what the coordinated plan should gain over the equal split
METHOD = ("scenario design at a quantile, validated a posteriori on fresh scenarios "
          "(Clopper-Pearson bound)")

Progress = Callable[[float, float], None]


@dataclass(frozen=True)
class GliderPlan:
    """One glider's part of the fleet plan."""

    spec: GliderSpec
    capacity: Capacity
    block: assign.Block
    track: Track
    mission_text: str
    result: object  # planner.plan.PlanResult of its mission
    shadow_price: float  # mapping error lowered per extra kWh of its battery

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def energy_j(self) -> float:
        return float(self.result.plan.predicted_j)

    @property
    def budget_j(self) -> float:
        return float(self.result.plan.budget_j)

    @property
    def parts(self) -> tuple[int, ...]:
        return tuple(range(self.block.first, self.block.stop))


@dataclass(frozen=True)
class Validation:
    scenarios: int
    finished: int
    lower_bound: float  # of the probability that the whole survey finishes, at RISK
    design_quantile: float
    design_scenarios: int
    failures: dict[str, int]  # glider -> scenarios it failed in
    causes: dict[str, dict[str, int]]  # glider -> {"budget": n, "sweep": n} failures

    @property
    def share(self) -> float:
        return self.finished / self.scenarios if self.scenarios else 0.0


@dataclass(frozen=True)
class Evaluation:
    """A plan's tracks judged as a map: the figures `fleet plan` prints."""

    mapping_error: float
    errors: np.ndarray  # (times, points)
    coverage: float  # share of the survey's line length swept by the finish
    finish_s: float  # when the last glider has swept its block once [s after the start]
    mapped_share: float  # share of (point, time) pairs with err < 0.5


@dataclass(frozen=True)
class FleetPlan:
    fleet: Fleet
    gliders: tuple[GliderPlan, ...]
    assignment: assign.Assignment
    evaluation: Evaluation
    baseline: assign.Assignment
    baseline_tracks: tuple[Track, ...]
    baseline_capacities: tuple[Capacity, ...]
    baseline_evaluation: Evaluation
    validation: Validation
    baseline_validation: Validation
    grid: Grid
    separation: dict
    notes: tuple[str, ...]
    seed: int
    plan_s: float
    polish: Polish | None = None

    @property
    def improvement(self) -> float:
        base = self.baseline_evaluation.mapping_error
        return 1.0 - self.evaluation.mapping_error / base if base > 0 else 0.0


# ---- the plan ----------------------------------------------------------------------------

class UnreachableGliders(FleetError):
    """Gliders with no block of lines they can fly in time (`names`)."""

    def __init__(self, error: FleetError, names: tuple[str, ...]) -> None:
        super().__init__(str(error), details=error.details, diagnostics=error.diagnostics,
                         file=error.file)
        self.names = names


@dataclass(frozen=True)
class Prepared:
    """What every design round of a fleet's plan shares: the gliders' speed curves, the
    scenarios (design and validation), the revisit table, the evaluation grid."""

    fleet: Fleet
    router: object
    curves: dict[tuple, SpeedCurve]
    design: Scenarios
    fresh: Scenarios
    table: object  # fleet_mapping.RevisitTable
    grid: Grid


def prepare(fleet: Fleet, *, seed: int = 0, scenario_file=None,
            step: Callable[[str], None] | None = None) -> Prepared:
    """Probe every glider kind, draw the scenarios, tabulate the revisit error."""
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim.scenarios import read_spec

    spec = read_spec(scenario_file)
    curves: dict[tuple, SpeedCurve] = {}
    vehicles: dict[tuple, object] = {}
    loaded: dict[str, object] = {}
    for glider in fleet.gliders:
        for band in bands(fleet):
            key = kind_key(glider, band)
            if key in curves:
                continue
            if glider.vehicle not in loaded:
                loaded[glider.vehicle] = load_vehicle(glider.vehicle)
            vehicle = vehicles[key] = loaded[glider.vehicle]
            figures, moved = _drawn_figures(spec, vehicle, seed)
            like = next((curves[k] for k in curves if k[0] == key[0] and k[3] == key[3]), None)
            try:
                curves[key] = speed_curve(glider, fleet, band, figures, moved, like)
            except CapacityError as err:
                raise fleet.error(f"glider '{glider.name}': {err}", "sample",
                                  "a shallower band, or another vehicle") from None
            if step is not None:
                step("probed a kind of glider")
    design = draw_scenarios(fleet, curves, vehicles, spec, seed, 0, DESIGN_SCENARIOS)
    fresh = draw_scenarios(fleet, curves, vehicles, spec, seed, DESIGN_SCENARIOS,
                           VALIDATION_SCENARIOS)
    return Prepared(fleet, router_for(fleet), curves, design, fresh, revisit_table(fleet),
                    evaluation_grid(fleet))


def design_round(prepared: Prepared, quantile: float, require_sweep: bool = True
                 ) -> tuple[list[Capacity], assign.BlockInputs, assign.Arcs]:
    """Each glider's capacity at the design `quantile`, the assignment's inputs and the
    blocks each glider can fly (a glider with none cannot reach the survey:
    UnreachableGliders);
    `require_sweep` as for `plan_fleet`."""
    fleet, curves = prepared.fleet, prepared.curves
    caps = [pick([capacity(g, fleet, curves[kind_key(g, b)], kind_key(g, b), prepared.design,
                           quantile) for b in bands(fleet)]) for g in fleet.gliders]
    _check_usable(fleet, caps, curves)
    inputs = replace(block_inputs(fleet, caps, prepared.design, prepared.router, quantile,
                                  prepared.table), require_sweep=require_sweep)
    arcs = assign.build_arcs(inputs)
    _check_reachable(fleet, inputs, arcs, caps)
    return caps, inputs, arcs


def plan_fleet(fleet: Fleet, *, seed: int = 0, scenario_file=None,
               time_limit_s: float = assign.DEFAULT_TIME_LIMIT_S, solver: str = "auto",
               require_sweep: bool = True, progress: Progress | None = None) -> FleetPlan:
    """Plan `fleet` (module docstring). `solver`: "auto" (the MILP up to
    `assign.MAX_MILP_ARCS` arcs, else the heuristic), "milp" or "heuristic".
    `require_sweep`: every line swept once by the finish at the confidence (False: only
    the mapping error counts, each glider reaching its block in time; the validation's
    share is reported, not enforced: a re-plan after a loss, the survey swept). Raises
    FleetError, located in the fleet file, for a glider that cannot reach the survey, a
    fleet that cannot sweep it at its confidence, a vehicle that cannot fly the yo, or
    gliders planned closer than the separation."""
    # the planner's matrices are a few dozen variables, the mapping error's small too
    with one_blas_thread():
        return _plan_fleet(fleet, seed, scenario_file, time_limit_s, solver, require_sweep,
                           progress)


def _plan_fleet(fleet: Fleet, seed: int, scenario_file, time_limit_s: float, solver: str,
                require_sweep: bool, progress: Progress | None) -> FleetPlan:
    began = time.perf_counter()
    kinds = {kind_key(g, b) for g in fleet.gliders for b in bands(fleet)}
    step = _Steps(progress, len(kinds) + 2 + len(fleet.gliders))
    prepared = prepare(fleet, seed=seed, scenario_file=scenario_file, step=step)
    router, curves, design, fresh = (prepared.router, prepared.curves, prepared.design,
                                     prepared.fresh)
    grid = prepared.grid
    # Split between the budget and the sweep; the scenarios are the fleet's (one ocean), so
    # the gliders mostly fail together and the validation below checks the joint share.
    quantile = (1.0 - fleet.confidence) / 2.0
    notes: list[str] = []
    best = None
    passed = None  # the last design share whose plan validated (or whose MILP was feasible)
    for round_ in range(ROUNDS):
        caps, inputs, arcs = design_round(prepared, quantile, require_sweep)
        assignment = _solve(arcs, inputs, solver, time_limit_s)
        if round_ == 0:
            step("assigned the lines")
        if assignment is None:
            if best is None:
                raise _infeasible(fleet, inputs, caps, quantile)
            # too strict to have a plan at all: back off half way (in log) toward the last
            quantile = math.sqrt(quantile * passed)
            continue
        passed = quantile
        assignment, polished = polish(fleet, arcs, assignment, caps, router, grid)
        tracks = [build_track(g, list(fleet.parts[b.first:b.stop]), b.entry_last,
                              c.distance_m, c.speed_mps, fleet, router)
                  for g, c, b in zip(fleet.gliders, caps, assignment.blocks, strict=True)]
        results, tracks, caps = _plan_missions(fleet, caps, tracks, assignment, curves, router,
                                               step if round_ == 0 else None)
        validation = validate(fleet, caps, tracks, curves, fresh, quantile, DESIGN_SCENARIOS,
                              [r.plan.predicted_j for r in results])
        if best is None or validation.lower_bound > best[-1].lower_bound:
            best = (caps, inputs, assignment, polished, tracks, results, validation)
        if validation.lower_bound >= fleet.confidence or not require_sweep:
            break
        notes.append(f"designed at the {100 * (1 - quantile):.4g} % quantile, the plan finished "
                     f"in {validation.finished} of {validation.scenarios} fresh scenarios "
                     f"(at least {100 * validation.lower_bound:.3g} %): designed again at a "
                     "stricter quantile")
        # the gliders fail in partly different scenarios: shrink each one's share by what
        # the fleet as a whole missed
        missed = 1.0 - validation.share
        quantile *= min(0.9, max(0.1, 0.8 * (1.0 - fleet.confidence) / max(missed, 1e-6)))
    caps, inputs, assignment, polished, tracks, results, validation = best
    if validation.lower_bound < fleet.confidence and require_sweep:
        worst = max(validation.failures, key=validation.failures.get, default=None)
        raise fleet.error(
            f"no plan found finishes the survey at {100 * fleet.confidence:.3g} % confidence: "
            f"the best finished in {validation.finished} of {validation.scenarios} scenarios "
            f"(at least {100 * validation.lower_bound:.3g} %)"
            + (f"; glider '{worst}' failed most ({validation.failures[worst]})" if worst else ""),
            "confidence", "lower the confidence, give the gliders more time ('finish by') or "
            "charge, or leave lines out")
    # the naive plan, evaluated the same way
    baseline = assign.equal_split(inputs)
    base_tracks = [build_track(g, list(fleet.parts[b.first:b.stop]), b.entry_last,
                               c.distance_m, c.speed_mps, fleet, router)
                   for g, c, b in zip(fleet.gliders, caps, baseline.blocks, strict=True)]
    base_validation = validate(fleet, caps, base_tracks, curves, fresh, quantile,
                               DESIGN_SCENARIOS, [c.nominal_energy_j for c in caps])
    evaluation = evaluate(fleet, tracks, grid)
    base_evaluation = evaluate(fleet, base_tracks, grid)
    step("mapped the field")
    separation = closest_approach(fleet, tracks)
    if fleet.separation_m > 0.0 and separation["closest_m"] < fleet.separation_m:
        a, b = separation["between"]
        raise fleet.error(
            f"gliders '{a}' and '{b}' come within {separation['closest_m']:.0f} m of each "
            f"other {hours(separation['at_s'])} after the start, closer than the separation "
            f"of {fleet.separation_m:.0f} m", "separation",
            "start them further apart or at different times, widen the line spacing, or "
            "lower the separation")
    prices = shadow_prices(fleet, caps, assignment, curves, design, quantile, router,
                           prepared.table)
    gliders = tuple(GliderPlan(g, c, b, t, m, r, p) for g, c, b, t, m, r, p in zip(
        fleet.gliders, caps, assignment.blocks, tracks,
        [mission_for(fleet, g, c, t) for g, c, t in zip(fleet.gliders, caps, tracks,
                                                          strict=True)],
        results, prices, strict=True))
    return FleetPlan(fleet, gliders, assignment, evaluation, baseline, tuple(base_tracks),
                     tuple(caps), base_evaluation, validation, base_validation, grid,
                     separation, tuple(notes), seed, time.perf_counter() - began, polished)


def _drawn_figures(spec, vehicle, seed: int) -> tuple[tuple[str, ...], frozenset[str]]:
    """The vehicle figures scenarios draw, and those a few draws actually move (a figure
    drawn with no spread needs no elasticity)."""
    from gliderplan.sim.scenarios import draw_scenario

    draws = [draw_scenario(spec, vehicle, i, np.random.SeedSequence([seed, i]))
             for i in range(3)]
    keys = tuple(k[len("vehicle."):] for k in draws[0].drawn if k.startswith("vehicle."))
    moved = frozenset(k for k in keys if len({d.drawn[f"vehicle.{k}"] for d in draws}) > 1)
    return keys, moved


class _Steps:
    def __init__(self, progress: Progress | None, total: int) -> None:
        self.progress, self.total, self.done = progress, total, 0

    def __call__(self, what: str) -> None:
        self.done += 1
        if self.progress is not None:
            self.progress(min(self.done, self.total), self.total)


def _solve(arcs: assign.Arcs, inputs: assign.BlockInputs, solver: str,
           time_limit_s: float) -> assign.Assignment | None:
    if not len(arcs):
        return None
    use_milp = solver == "milp" or (solver == "auto" and len(arcs) <= assign.MAX_MILP_ARCS)
    if use_milp:
        return assign.solve_milp(arcs, inputs.parts, inputs.gliders, time_limit_s)
    positions = _start_positions(inputs)
    return assign.solve_heuristic(arcs, inputs.parts, inputs.gliders, positions)


@dataclass(frozen=True)
class Polish:
    """The local search on the true mapping error after the assignment."""

    tried: int
    accepted: int
    before: float  # mapping error of the assignment as solved
    after: float
    seconds: float


def polish(fleet: Fleet, arcs: assign.Arcs, assignment: assign.Assignment,
           caps: list[Capacity], router, grid: Grid,
           max_trials: int = POLISH_TRIALS) -> tuple[assign.Assignment, Polish]:
    """Move the cut between two neighbouring blocks by one line while that lowers the
    mapping error of objective analysis on the tracks (the assignment's cost is a
    per-block surrogate, blind to a line being mapped by its neighbours' samples); only
    to blocks the assignment had as arcs (feasible at the design quantile). Stops when
    no move helps or after `max_trials` tries."""
    started = time.perf_counter()
    table = {(int(g), int(i), int(j)): (float(c), bool(e)) for g, i, j, c, e in zip(
        arcs.glider, arcs.first, arcs.stop, arcs.cost, arcs.entry_last, strict=True)}
    spacing = sample_spacing(fleet)
    samples: dict[int, tuple] = {}

    def sampled(block: assign.Block):
        key = (block.glider, block.first, block.stop)
        if key not in samples:
            track = build_track(fleet.gliders[block.glider],
                                list(fleet.parts[block.first:block.stop]), block.entry_last,
                                caps[block.glider].distance_m, caps[block.glider].speed_mps,
                                fleet, router)
            samples[key] = track.samples(spacing)
        return samples[key]

    errors: dict[tuple, float] = {}  # a trial rejected once comes round again next pass

    def error_of(blocks) -> float:
        key = tuple((b.glider, b.first, b.stop, b.entry_last) for b in blocks)
        if key not in errors:
            errors[key] = mapping_error(combined([sampled(b) for b in blocks]), grid,
                                        fleet.field)[0]
        return errors[key]

    blocks = sorted(assignment.blocks, key=lambda b: b.first)
    best = before = error_of(blocks)
    tried = accepted = 0
    improved = True
    while improved and tried < max_trials:
        improved = False
        for k in range(len(blocks) - 1):
            for delta in (1, -1):
                left, right = blocks[k], blocks[k + 1]
                cut = left.stop + delta
                a = table.get((left.glider, left.first, cut))
                b = table.get((right.glider, cut, right.stop))
                if a is None or b is None or tried >= max_trials:
                    continue
                trial = list(blocks)
                trial[k] = assign.Block(left.glider, left.first, cut, a[1], a[0])
                trial[k + 1] = assign.Block(right.glider, cut, right.stop, b[1], b[0])
                tried += 1
                error = error_of(trial)
                if error < best - 1e-5:
                    blocks, best, improved = trial, error, True
                    accepted += 1
    if accepted:  # the solver's objective and bound stay what it proved
        assignment = replace(assignment, blocks=tuple(sorted(blocks, key=lambda b: b.glider)))
    return assignment, Polish(tried, accepted, before, best, time.perf_counter() - started)


def _start_positions(inputs: assign.BlockInputs) -> np.ndarray:
    """Where each glider starts along the survey: the line nearest to it."""
    return np.argmin(inputs.transit_m.min(axis=2), axis=1).astype(float)


def block_inputs(fleet: Fleet, caps: list[Capacity], scenarios: Scenarios, router,
                 quantile: float, table) -> assign.BlockInputs:
    """The assignment's inputs: lines, links, weights, and each glider's reach."""
    parts = fleet.parts
    length = np.array([p.length_m for p in parts])
    link = np.zeros(len(parts))
    for k in range(len(parts) - 1):
        a, b = parts[k], parts[k + 1]
        link[k] = min(math.dist(x, y) for x in (a.a, a.b) for y in (b.a, b.b))
    width = np.array([fleet.goal.spacing_m if p.kind == "area" and fleet.goal.spacing_m
                      else fleet.field.length_m for p in parts])
    weight = length * width
    weight /= weight.sum()
    heading = np.array([(p.b[0] - p.a[0], p.b[1] - p.a[1]) for p in parts]) / length[:, None]
    east, north = heading[:, 0], heading[:, 1]
    transit = np.empty((len(caps), len(parts), 2))
    transit_factor = np.empty((len(caps), len(parts), 2, len(scenarios)))
    line_factor = np.empty((len(caps), len(parts), len(scenarios)))
    ends = np.array([[p.a, p.b] for p in parts])  # (P, 2 ends, xy)
    for g, (glider, cap) in enumerate(zip(fleet.gliders, caps, strict=True)):
        # straight to each end, all at once; the few legs a keep-out blocks, around it
        legs = ends - np.asarray(glider.start)[None, None, :]
        transit[g] = np.hypot(legs[..., 0], legs[..., 1])
        safe = np.where(transit[g] > 0.0, transit[g], 1.0)
        transit_factor[g] = ground_factor(
            cap.water_speed_mps, (legs[..., 0] / safe)[..., None],
            (legs[..., 1] / safe)[..., None], scenarios.current_east[None, None, :],
            scenarios.current_north[None, None, :])
        for p, part in enumerate(parts):
            for e, end in enumerate((part.a, part.b)):
                if router.clear(glider.start, end):
                    continue
                path = np.asarray(router.path(glider.start, end))
                lengths = np.hypot(*np.diff(path, axis=0).T)
                transit[g, p, e] = float(lengths.sum())
                factors = leg_factors(path, cap.water_speed_mps, scenarios)
                transit_factor[g, p, e] = (lengths[:, None] * factors).sum(axis=0) \
                    / max(lengths.sum(), 1e-9)
        there = ground_factor(cap.water_speed_mps, east[:, None], north[:, None],
                              scenarios.current_east[None, :], scenarios.current_north[None, :])
        back = ground_factor(cap.water_speed_mps, -east[:, None], -north[:, None],
                             scenarios.current_east[None, :], scenarios.current_north[None, :])
        line_factor[g] = 0.5 * (there + back)  # a sweep flies a line either way
    return assign.BlockInputs(
        length, link, weight, np.array([c.speed_mps for c in caps]),
        fleet.surface_every_s / (fleet.surface_every_s + fleet.surface_stay_s), LAUNCH_S,
        np.array([g.start_offset_s for g in fleet.gliders]), np.array([c.end_s for c in caps]),
        fleet.period_s, transit, line_factor, transit_factor, quantile, fleet.goal.revisit_s,
        table, fleet.field.time_s)


def _check_usable(fleet: Fleet, caps: list[Capacity], curves) -> None:
    for glider, cap in zip(fleet.gliders, caps, strict=True):
        if cap.end_s <= LAUNCH_S + 600.0:
            curve = curves[cap.kind]
            day = float(flight_energy(curve, fleet, cap.speed_mps, 86400.0))
            raise fleet.error(
                f"glider '{glider.name}' has too little energy to fly at all: "
                f"{glider.usable_j / J_PER_WH:.3g} Wh above its reserve, a day of flight "
                f"takes {day / J_PER_WH:.3g} Wh", glider.battery_span,
                "charge it, or leave it out of the fleet")


def _check_reachable(fleet: Fleet, inputs: assign.BlockInputs, arcs: assign.Arcs,
                     caps: list[Capacity]) -> None:
    """Every glider needs one block it can fly: else it cannot reach the survey."""
    found = []
    for g, (glider, cap) in enumerate(zip(fleet.gliders, caps, strict=True)):
        if np.any(arcs.glider == g):
            continue
        nearest = float(inputs.transit_m[g].min())
        rate = cap.speed_mps * inputs.flight_share
        arrive = LAUNCH_S + nearest / rate
        limit = "its battery runs out" if cap.energy_limited else "the survey finishes"
        if arrive >= cap.end_s:
            what = (f"cannot reach the survey: its nearest line is {nearest / 1000:.3g} km "
                    f"away, {hours(arrive)} at {cap.speed_mps:.2f} m/s")
        else:
            line = int(np.argmin(inputs.transit_m[g].min(axis=1)))
            one = assign.block_of(inputs, g, line, line + 1)
            sweep = inputs.length_m[line] / rate
            along = (f" and {hours(sweep)} along its {inputs.length_m[line] / 1000:.3g} km"
                     if inputs.require_sweep else "")
            what = (f"cannot {'sweep' if inputs.require_sweep else 'reach'} even its nearest "
                    f"line in time: {hours(arrive)} to reach it{along} in still water at "
                    f"{cap.speed_mps:.2f} m/s, longer in the strongest "
                    f"{100 * inputs.quantile:.3g} % of the design scenarios' currents"
                    if not one.feasible else "has no block it can fly in time")
        found.append((glider, f"glider '{glider.name}' {what}, and {limit} "
                              f"{hours(cap.end_s)} after it starts"))
    if found:
        from gliderplan.language.diagnostics import error

        first, message = found[0]
        more = tuple(error(m, g.start_span, "start it nearer the survey, or earlier")
                     for g, m in found[1:])
        raise UnreachableGliders(
            fleet.error(message, first.start_span, "start it nearer the survey, or earlier",
                        more), tuple(g.name for g, _ in found))


def _infeasible(fleet: Fleet, inputs: assign.BlockInputs, caps: list[Capacity],
                quantile: float) -> FleetError:
    needed = float(inputs.length_m.sum() + inputs.link_m.sum())
    reach = sum(c.speed_mps * inputs.flight_share * max(c.end_s - LAUNCH_S, 0.0) for c in caps)
    why = ("no way to give every glider one block of lines and sweep them all by the finish "
           f"in {100 * (1 - quantile):.4g} % of the design scenarios: the survey's lines are "
           f"{needed / 1000:.4g} km, the fleet flies {reach / 1000:.4g} km in all in still "
           "water, and currents slow it")
    if fleet.goal.revisit_s is not None:
        why += f", with every line flown again within {hours(fleet.goal.revisit_s)}"
    return fleet.error(why, "finish", "finish later, add gliders or charge, "
                       "or survey fewer lines (a wider spacing)")


def mission_for(fleet: Fleet, glider: GliderSpec, cap: Capacity, track: Track) -> str:
    header = (f"generated by gliderplan fleet plan from {fleet.filename} (fleet {fleet.name}): "
              f"glider {glider.name}\nyo {cap.band[0]:g}-{cap.band[1]:g} m at "
              f"{cap.speed_mps:.3f} m/s over the ground, {track.length_m / 1000:.1f} km, "
              f"surfacing every {hours(track.surface_every_s)}")
    return mission_text(glider.name, glider, fleet, cap.band, track,
                        fleet.period_s - glider.start_offset_s, header)


def _plan_missions(fleet: Fleet, caps: list[Capacity], tracks: list[Track],
                   assignment: assign.Assignment, curves, router, step):
    """Each glider's mission planned by the planner; a plan that costs more than the
    fleet model said flies a shorter track (less distance by the ratio), and so does one
    the horizon cannot hold (its segments, cut at waypoints, surface a little more often
    than the fleet model's mean: 3 % less each time)."""
    from gliderplan.language import check_source
    from gliderplan.planner.plan import InfeasibleBudget, PlanningError, plan_mission

    results = []
    for n, glider in enumerate(fleet.gliders):
        failure = None
        for _ in range(6):
            text = mission_for(fleet, glider, caps[n], tracks[n])
            checked = check_source(text, f"{glider.name}.mission")
            if not checked.ok:  # a generator bug, not the user's: say where
                raise RuntimeError(f"generated mission of {glider.name} does not check:\n"
                                   + checked.render())
            mission = checked.mission
            try:
                result = plan_mission(mission)
                over = result.plan.predicted_j / max(caps[n].nominal_energy_j, 1.0)
            except InfeasibleBudget as err:
                result, over = None, err.minimum_j / max(caps[n].nominal_energy_j, 1.0)
            except PlanningError as err:  # the horizon holds no pace for the legs
                result, over, failure = None, 1.03, err
            if result is not None and over <= ENERGY_TOLERANCE:
                break
            shrink = 1.0 / max(over, ENERGY_TOLERANCE)
            caps[n] = replace(caps[n], distance_m=caps[n].distance_m * shrink,
                              nominal_energy_j=caps[n].nominal_energy_j,
                              end_s=LAUNCH_S + (caps[n].end_s - LAUNCH_S) * shrink
                              if caps[n].energy_limited else caps[n].end_s)
            block = assignment.blocks[n]
            tracks[n] = build_track(glider, list(fleet.parts[block.first:block.stop]),
                                    block.entry_last, caps[n].distance_m, caps[n].speed_mps,
                                    fleet, router)
        if result is None and failure is not None:
            raise fleet.error(f"glider '{glider.name}': its mission cannot be planned: "
                              f"{failure}", glider.span)
        if result is None:
            raise fleet.error(f"glider '{glider.name}': its planned mission does not fit "
                              "its battery", glider.battery_span)
        results.append(result)
        if step is not None:
            step(f"planned {glider.name}")
    return results, tracks, caps


# ---- validation --------------------------------------------------------------------------

def finish_times(track: Track, water_mps: float, scenarios: Scenarios) -> np.ndarray:
    """(N,) when the glider has swept its block once in each scenario [s after its
    start]: every leg of its track to that point slowed or sped by the current."""
    upto = int(np.searchsorted(track.distance_m, track.first_pass_m - 1e-6) + 1)
    points = track.points[:upto + 1]
    lengths = np.hypot(*np.diff(points, axis=0).T)
    if not len(lengths):
        return np.full(len(scenarios), LAUNCH_S)
    factors = leg_factors(points, water_mps, scenarios)
    rate = track.speed_mps
    flying = (lengths[:, None] * factors).sum(axis=0) / rate
    stays = len([e for e in track.segment_ends if track.distance_m[e] < track.first_pass_m])
    return LAUNCH_S + flying + stays * track.surface_stay_s


def validate(fleet: Fleet, caps: list[Capacity], tracks: list[Track], curves,
             scenarios: Scenarios, quantile: float, design_count: int,
             energies_j: list[float]) -> Validation:
    """In how many scenarios every glider keeps its budget and sweeps its block by the
    finish (and, with a revisit goal, never leaves a line longer): with its lower
    Clopper-Pearson bound at RISK."""
    from scipy.special import betaincinv

    ok = np.ones(len(scenarios), bool)
    failures, causes = {}, {}
    for glider, cap, track, energy in zip(fleet.gliders, caps, tracks, energies_j, strict=True):
        curve = curves[cap.kind]
        duration = min(track.duration_s, cap.window_s)
        glide = flight_energy(curve, fleet, cap.speed_mps, duration) - curve.launch_j
        share = glide / max(float(flight_energy(curve, fleet, cap.speed_mps, duration)), 1.0)
        ratio = share * _period_ratio(curve, fleet, cap, scenarios) + (1.0 - share)
        held = energy * ratio <= scenarios.usable * glider.usable_j
        swept = finish_times(track, cap.water_speed_mps, scenarios) <= cap.window_s
        mine = held & swept
        if fleet.goal.revisit_s is not None:
            mine &= _revisits_kept(fleet, track, cap, scenarios)
        failures[glider.name] = int((~mine).sum())
        causes[glider.name] = {"budget": int((~held).sum()), "sweep": int((~swept).sum())}
        ok &= mine
    finished = int(ok.sum())
    n = len(scenarios)
    # Clopper-Pearson: the beta(k, n - k + 1) quantile at the risk
    lower = float(betaincinv(finished, n - finished + 1, RISK)) if finished else 0.0
    return Validation(n, finished, lower, quantile, design_count, failures, causes)


def _period_ratio(curve: SpeedCurve, fleet: Fleet, cap: Capacity, scenarios: Scenarios):
    """(N,) energy of a surfacing period (glide and stay) in each scenario / nominal."""
    kind = cap.kind
    glide = fleet.surface_every_s * float(curve.power_w(cap.speed_mps))
    return (glide * scenarios.glide_ratio[kind] + curve.surfacing_j
            * scenarios.surfacing_ratio[kind]) / (glide + curve.surfacing_j)


def _revisits_kept(fleet: Fleet, track: Track, cap: Capacity, scenarios: Scenarios):
    """(N,) no line of the block waits longer than the goal between sweeps, in each
    scenario's current (the slowest leg's factor on the whole pass, conservatively)."""
    factors = leg_factors(track.points, cap.water_speed_mps, scenarios)
    worst = np.nanmax(np.where(np.isfinite(factors), factors, np.nan), axis=0)
    worst = np.where(np.isnan(worst), np.inf, worst)
    gaps = []
    for visits in track.line_visits.values():
        times = track.time_at(np.array(visits)) if visits else np.array([])
        end = min(track.duration_s, cap.window_s)
        marks = np.concatenate([times, [end]]) if len(times) else np.array([0.0, end])
        gaps.append(np.max(np.diff(marks)) if len(marks) > 1 else end)
    longest = max(gaps) if gaps else 0.0
    return longest * worst <= fleet.goal.revisit_s


# ---- judging a plan as a map ---------------------------------------------------------------

def evaluate(fleet: Fleet, tracks: list[Track], grid: Grid) -> Evaluation:
    spacing = sample_spacing(fleet)
    samples = combined([t.samples(spacing) for t in tracks])
    error, errors = mapping_error(samples, grid, fleet.field)
    finish = max((track.first_coverage_s() for track in tracks), default=0.0)
    return Evaluation(error, errors, coverage(fleet, [(t, fleet.period_s) for t in tracks]),
                      finish, float((errors < 0.5).mean()))


def coverage(fleet: Fleet, flown: list[tuple[Track, float]]) -> float:
    """Share of the survey's line length swept at least once by the gliders flying
    `flown`'s tracks, each until its time [s after the fleet's start] (the finish; for a
    lost glider, the loss)."""
    total = sum(p.length_m for p in fleet.parts)
    swept = set()
    for track, until_s in flown:
        for index, visits in track.line_visits.items():
            if visits and track.start_offset_s + float(track.time_at(visits[0])) \
                    <= min(until_s, fleet.period_s):
                swept.add(index)
    return sum(fleet.parts[i].length_m for i in swept) / total if total else 0.0


def closest_approach(fleet: Fleet, tracks: list[Track], step_s: float = 600.0) -> dict:
    """The nearest two gliders come to each other on their planned tracks: distance [m],
    which two, when [s after the start]."""
    times = np.arange(0.0, fleet.period_s + step_s, step_s)
    xy = [np.vstack(t.position_at(times)) for t in tracks]
    live = [(times >= t.start_offset_s) for t in tracks]
    best = {"required_m": fleet.separation_m, "closest_m": math.inf, "between": None,
            "at_s": None}
    for a in range(len(tracks)):
        for b in range(a + 1, len(tracks)):
            both = live[a] & live[b]
            if not both.any():
                continue
            gap = np.hypot(*(xy[a] - xy[b]))[both]
            k = int(np.argmin(gap))
            if gap[k] < best["closest_m"]:
                best.update(closest_m=float(gap[k]), at_s=float(times[both][k]),
                            between=[fleet.gliders[a].name, fleet.gliders[b].name])
    return best


def shadow_prices(fleet: Fleet, caps: list[Capacity], assignment: assign.Assignment, curves,
                  scenarios: Scenarios, quantile: float, router, table) -> list[float]:
    """Mapping error lowered per extra kWh of each glider's battery with the lines held
    where they are (the envelope theorem's value): 1 % more charge, its speed and end
    chosen again, its block's cost again. 0: its battery does not limit the survey."""
    from gliderplan.language.ir import Battery

    inputs = block_inputs(fleet, caps, scenarios, router, quantile, table)
    prices = []
    for n, glider in enumerate(fleet.gliders):
        block = assignment.blocks[n]
        more = replace(glider, battery=Battery(glider.battery.energy_j * 1.01,
                                               glider.battery.reserve_fraction / 1.01))
        extra_j = more.usable_j - glider.usable_j
        richer = pick([capacity(more, fleet, curves[kind_key(glider, b)],
                                kind_key(glider, b), scenarios, quantile)
                       for b in bands(fleet)])
        moved = replace(inputs, speed_mps=inputs.speed_mps.copy(), end_s=inputs.end_s.copy())
        moved.speed_mps[n], moved.end_s[n] = richer.speed_mps, richer.end_s
        before = assign.block_of(inputs, n, block.first, block.stop).cost
        after = assign.block_of(moved, n, block.first, block.stop).cost
        prices.append(max(before - after, 0.0) / (extra_j / (1000.0 * J_PER_WH)))
    return prices
