"""What each fleet glider can fly: its energy against speed, from the planner itself, and
how far and how long its battery carries it at the fleet's confidence.

The planner prices a transit leg at the pace it chooses (planner/README.md, "Transit
legs"). A probe mission (the glider's own hardware, yo band and sensors; one 20 km leg;
one surfacing) is planned at horizons that force faster and faster paces: each plan gives
the effective speed (distance over time, turns included) and the power while gliding, so
the fleet's energy per second of flight is the planner's, not a second model of it.
Between probed speeds the power is interpolated linearly: power grows convexly with
speed, so the chord errs high (on the safe side).

Scenarios (sim/scenarios.py, the Monte Carlo's own draws) vary the vehicle's figures, the
battery's usable share and the current. A drawn figure changes the energy by its
elasticity, measured on the probe by the planner (the figure moved 5 %); the current
changes how long the glider takes over the ground, not what a second of flight costs.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract import MAX_PLAN_ENERGY_J
from gliderplan.language.fleet import Fleet, GliderSpec
from gliderplan.language.fleet_geometry import Router
from gliderplan.planner.fleet_missions import LAUNCH_S, Track, mission_text

PROBE_LEG_M = 20_000.0  # the probe's transit leg [m]
SPEED_CAP_MPS = 0.34  # the planner's walk takes transit legs at 0.35 m/s: no faster [m/s]
SPEED_STEP = 1.08  # probed speeds: the cheapest, then 8 % faster each
PROBE_HORIZON_S = 30 * 86400.0
FIGURE_STEP = 0.05  # a figure moved by 5 % to measure its elasticity
FACTOR_CAP = 1e6  # a current the glider cannot stem: "never" as a finite number
PLANNING_ENTROPY = 0x666C656574  # "fleet": planning scenarios never repeat the Monte Carlo's


class CapacityError(ValueError):
    """A glider whose hardware cannot fly the goal's yo; the message says why."""


@dataclass(frozen=True)
class SpeedCurve:
    """A glider kind flying its yo band: power against effective speed (the planner's)."""

    band: tuple[float, float]  # yo min, max depth [m]
    speed_mps: np.ndarray  # effective speeds probed, ascending [m/s]
    water_speed_mps: np.ndarray  # horizontal speed through the water at each [m/s]
    glide_w: np.ndarray  # mean power while flying at each [W]
    surfacing_j: float  # one stay at the surface: fix, call [J]
    launch_j: float  # the launch stay [J]
    elasticity: dict[str, tuple[float, float]]  # figure -> (d ln glide / d ln it, surfacing)
    figures: dict[str, float]  # the figures' nominal values

    def power_w(self, speed_mps) -> np.ndarray:
        return np.interp(speed_mps, self.speed_mps, self.glide_w)

    def water_speed(self, speed_mps) -> np.ndarray:
        return np.interp(speed_mps, self.speed_mps, self.water_speed_mps)


def kind_key(glider: GliderSpec, band: tuple[float, float]) -> tuple:
    """Gliders alike in everything the probe sees share one curve."""
    return (glider.vehicle, glider.computer.board, glider.computer.clock_mhz, band)


def speed_curve(glider: GliderSpec, fleet: Fleet, band: tuple[float, float],
                figure_keys: tuple[str, ...], moved_keys: frozenset[str] = frozenset(),
                like: SpeedCurve | None = None) -> SpeedCurve:
    """Probe the planner for `glider`'s kind flying `band`; the elasticities of those
    `figure_keys` that the scenarios move (`moved_keys`; the others stay 0). `like`: a
    curve of the same vehicle and band on another board, whose figures' effect in watts
    this one shares (a board adds power no vehicle figure moves): its elasticities are
    rescaled to this kind's power instead of probed again."""
    from gliderplan.language import check_source
    from gliderplan.language.ir import Battery
    from gliderplan.planner.hardware import load_hardware
    from gliderplan.planner.inputs import build_inputs
    from gliderplan.planner.model import model_for
    from gliderplan.planner.occupancy import mission_occupancy
    from gliderplan.planner.plan import PlanningError, solve_plan
    from gliderplan.power_models.flight import FlightModelError
    from gliderplan.power_models.vehicle import figure_value, with_figures

    # An ample battery (well within what the checker accepts): the probe asks what flying
    # costs, not whether it fits.
    probe = replace(glider, battery=Battery(MAX_PLAN_ENERGY_J / 10.0, 0.0), charge=1.0,
                    start=(0.0, 0.0), start_offset_s=0.0)
    line = np.array([[0.0, 0.0], [PROBE_LEG_M, 0.0]])
    track = Track(line, np.array([0.0, PROBE_LEG_M]), (1,), 0.3, fleet.surface_every_s,
                  fleet.surface_stay_s, 0.0, PROBE_LEG_M, {})
    model = None
    checked: dict[float, tuple] = {}  # horizon -> its probe mission, hardware, occupancy

    def plan(horizon_s: float, vehicle=None):
        nonlocal model
        if horizon_s not in checked:  # the figures' probes fly one horizon: check it once
            text = mission_text("probe", probe, fleet, band, track, horizon_s, "probe")
            mission = check_source(text, "probe.mission").checked()
            checked[horizon_s] = (mission, load_hardware(mission), mission_occupancy(mission))
        mission, hardware, occupancy = checked[horizon_s]
        if vehicle is not None:
            hardware = replace(hardware, vehicle=vehicle)
        inputs = build_inputs(mission, hardware, occupancy)
        model = model_for(inputs, model)
        result = solve_plan(model)
        states = {s.name: s for s in result.plan.states}
        return states["seg1"], states["fix"], states["launch"]

    try:
        seg, fix, launch = plan(PROBE_HORIZON_S)
    except (PlanningError, FlightModelError) as err:
        raise CapacityError(f"{glider.vehicle} cannot fly yo {band[0]:g}-{band[1]:g} m: "
                            f"{err}") from None
    speeds = [PROBE_LEG_M / seg.time_s]
    water = [seg.profiles[0].speed_mps]
    power = [seg.energy_j / seg.time_s]
    surfacing_j, launch_j = fix.energy_j / max(fix.visits, 1), launch.energy_j
    while speeds[-1] * SPEED_STEP <= SPEED_CAP_MPS:
        target = speeds[-1] * SPEED_STEP
        try:
            faster, _, _ = plan(LAUNCH_S + PROBE_LEG_M / target + fleet.surface_stay_s)
        except PlanningError:  # faster than the vehicle flies
            break
        speeds.append(PROBE_LEG_M / faster.time_s)
        water.append(faster.profiles[0].speed_mps)
        power.append(faster.energy_j / faster.time_s)
    order = np.argsort(speeds)
    if like is not None:
        curve = SpeedCurve(band, np.asarray(speeds)[order], np.asarray(water)[order],
                           np.asarray(power)[order], surfacing_j, launch_j, {}, like.figures)
        ratio = float(like.power_w(like.speed_mps[len(like.speed_mps) // 2])
                      / curve.power_w(like.speed_mps[len(like.speed_mps) // 2]))
        surface = like.surfacing_j / surfacing_j
        return replace(curve, elasticity={k: (g * ratio, s * surface)
                                          for k, (g, s) in like.elasticity.items()})
    # elasticities at the middle speed probed
    middle = speeds[len(speeds) // 2]
    horizon = LAUNCH_S + PROBE_LEG_M / middle + fleet.surface_stay_s
    base_seg, base_fix, _ = plan(horizon)
    vehicle = checked[horizon][1].vehicle
    elasticity, figures = {}, {}
    for key in figure_keys:
        value = figure_value(vehicle, key)
        figures[key] = value
        if value == 0.0 or key not in moved_keys:
            elasticity[key] = (0.0, 0.0)
            continue
        for step in (FIGURE_STEP, -FIGURE_STEP):  # down when up leaves no plan (a pump
            try:  # that cannot keep the pace any more)
                moved_seg, moved_fix, _ = plan(horizon, with_figures(
                    vehicle, {key: value * (1.0 + step)}))
                break
            except (PlanningError, FlightModelError):
                moved_seg = None
        if moved_seg is None:
            raise CapacityError(f"{glider.vehicle}: its plan fails with {key} moved by "
                                f"{100 * FIGURE_STEP:g} % either way")
        glide = (moved_seg.energy_j / moved_seg.time_s) / (base_seg.energy_j / base_seg.time_s)
        surfacing = moved_fix.energy_j / base_fix.energy_j if base_fix.energy_j else 1.0
        elasticity[key] = ((glide - 1.0) / step, (surfacing - 1.0) / step)
    return SpeedCurve(band, np.asarray(speeds)[order], np.asarray(water)[order],
                      np.asarray(power)[order], surfacing_j, launch_j, elasticity, figures)


# ---- scenarios ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Scenarios:
    """Drawn worlds the fleet plan must hold in: per scenario the battery's usable share,
    the current, and per glider kind the energy ratios of its drawn figures."""

    usable: np.ndarray  # (N,) share of the rated energy the battery holds [1]
    current_north: np.ndarray  # (N,) [m/s]
    current_east: np.ndarray  # (N,) [m/s]
    glide_ratio: dict[tuple, np.ndarray]  # kind -> (N,) power while gliding / nominal
    surfacing_ratio: dict[tuple, np.ndarray]  # kind -> (N,) surfacing energy / nominal

    def __len__(self) -> int:
        return len(self.usable)


def draw_scenarios(fleet: Fleet, curves: dict[tuple, SpeedCurve], vehicles: dict[tuple, object],
                   spec, seed: int, first: int, count: int) -> Scenarios:
    """Scenarios `first`..`first + count - 1` of the planning stream from `seed` (never
    the Monte Carlo's: another root), as `sim.scenarios.draw_scenario` draws them: one
    ocean and one battery share for the whole fleet, each vehicle's figures after them
    from the same stream (`draw_figures`; gliders of one preset draw the same relative
    errors: the model's error is theirs alike)."""
    from gliderplan.sim.scenarios import draw_figures, draw_scenario

    root = np.random.SeedSequence([seed, PLANNING_ENTROPY])
    shared = len(spec.ocean) + len(spec.sensors) + len(spec.battery)  # one number each
    usable = np.empty(count)
    north = np.empty(count)
    east = np.empty(count)
    glide = {k: np.empty(count) for k in curves}
    surface = {k: np.empty(count) for k in curves}
    by_vehicle: dict[int, list[tuple]] = {}
    for kind in curves:
        by_vehicle.setdefault(id(vehicles[kind]), []).append(kind)
    for n in range(count):
        child = np.random.SeedSequence(root.entropy, spawn_key=(first + n,))
        drawn = draw_scenario(spec, next(iter(vehicles.values())), first + n, child)
        usable[n] = drawn.usable_fraction
        north[n], east[n] = drawn.current.north_mps, drawn.current.east_mps
        for kinds in by_vehicle.values():
            rng = np.random.default_rng(child)
            rng.random(shared)  # the ocean's, the sensors' and the battery's numbers
            figures = draw_figures(vehicles[kinds[0]], spec.vehicle_relative_sd, rng)
            for kind in kinds:
                curve = curves[kind]
                g = s = 0.0
                for key, (eg, es) in curve.elasticity.items():
                    nominal = curve.figures[key]
                    moved = figures.get(key, nominal) / nominal - 1.0 if nominal else 0.0
                    g += eg * moved
                    s += es * moved
                glide[kind][n], surface[kind][n] = max(1.0 + g, 0.1), max(1.0 + s, 0.1)
    return Scenarios(usable, north, east, glide, surface)


# ---- one glider's capacity ---------------------------------------------------------------

@dataclass(frozen=True)
class Capacity:
    """How glider `name` flies the survey: its speed, how long it flies, how far."""

    name: str
    kind: tuple
    band: tuple[float, float]
    speed_mps: float  # effective speed over the ground in still water [m/s]
    water_speed_mps: float  # through the water [m/s]
    end_s: float  # it stops flying this long after its start: the window's end or its battery [s]
    window_s: float  # from its start to the survey's finish [s]
    energy_limited: bool  # its battery, not the finish, ends its flight
    distance_m: float  # it flies this far in all [m]
    budget_j: float  # usable energy [J]
    nominal_energy_j: float  # energy of that flight in the nominal world [J]
    design_energy_j: float  # at the design quantile (as a share of each scenario's budget) [J]

    def flight_share(self, fleet: Fleet) -> float:
        return fleet.surface_every_s / (fleet.surface_every_s + fleet.surface_stay_s)


def flight_energy(curve: SpeedCurve, fleet: Fleet, speed_mps: float, duration_s: float,
                  glide_ratio=1.0, surfacing_ratio=1.0):
    """Energy [J] of `duration_s` [s] from the glider's start at `speed_mps`: the launch,
    then gliding with a stay at the surface every surfacing interval."""
    flying = np.maximum(duration_s - LAUNCH_S, 0.0)
    period = fleet.surface_every_s + fleet.surface_stay_s
    power = (fleet.surface_every_s * curve.power_w(speed_mps) * glide_ratio
             + curve.surfacing_j * surfacing_ratio) / period
    return curve.launch_j + flying * power


def capacity(glider: GliderSpec, fleet: Fleet, curve: SpeedCurve, kind: tuple,
             scenarios: Scenarios, quantile: float) -> Capacity:
    """The speed at which the glider sweeps farthest over the ground in its share of the
    survey, in all but `quantile` of the scenarios: at each probed speed it flies its
    whole window if its energy holds there (else until its battery runs out, at the same
    quantile), and the scenarios' currents slow a back-and-forth sweep by their factor
    (`sweep_factor`, at the same quantile). Faster costs energy; slower loses ground to
    the current."""
    window = fleet.period_s - glider.start_offset_s
    budget = glider.usable_j
    grid = np.linspace(curve.speed_mps[0], curve.speed_mps[-1], 40)
    g, s = scenarios.glide_ratio[kind], scenarios.surfacing_ratio[kind]
    period = fleet.surface_every_s + fleet.surface_stay_s
    power = (fleet.surface_every_s * curve.power_w(grid)[:, None] * g[None, :]
             + curve.surfacing_j * s[None, :]) / period  # (speeds, N)
    lasts = LAUNCH_S + (scenarios.usable[None, :] * budget - curve.launch_j) / power
    end = np.minimum(np.quantile(lasts, quantile, axis=1), window)
    share = fleet.surface_every_s / period
    through = grid * share * np.maximum(end - LAUNCH_S, 0.0)
    factor = np.quantile(sweep_factor(curve.water_speed(grid), scenarios), 1.0 - quantile,
                         axis=1)
    best = int(np.argmax(through / factor))
    speed, stop = float(grid[best]), float(end[best])
    limited = stop < window
    nominal = float(flight_energy(curve, fleet, speed, stop))
    shares = flight_energy(curve, fleet, speed, stop, g, s) / scenarios.usable
    return Capacity(glider.name, kind, curve.band, speed, float(curve.water_speed(speed)),
                    stop, window, limited, float(through[best]), budget, nominal,
                    float(np.quantile(shares, 1.0 - quantile)))


def sweep_factor(water_mps: np.ndarray, scenarios: Scenarios, directions: int = 12):
    """(speeds, N): how much longer a back-and-forth sweep takes in each scenario's
    current than in still water, averaged over line directions (a block's lines may lie
    any way to the current)."""
    angles = np.linspace(0.0, np.pi, directions, endpoint=False)
    east, north = np.sin(angles), np.cos(angles)
    out = np.zeros((len(water_mps), len(scenarios)))
    for n, u in enumerate(water_mps):
        there = ground_factor(u, east[:, None], north[:, None], scenarios.current_east[None, :],
                              scenarios.current_north[None, :])
        back = ground_factor(u, -east[:, None], -north[:, None],
                             scenarios.current_east[None, :], scenarios.current_north[None, :])
        out[n] = np.mean(0.5 * (np.minimum(there, FACTOR_CAP) + np.minimum(back, FACTOR_CAP)),
                         axis=0)
    return out


def ground_factor(water_mps: float, heading_east: np.ndarray, heading_north: np.ndarray,
                  current_east: np.ndarray, current_north: np.ndarray) -> np.ndarray:
    """Time over the ground in a current / time in still water, for legs of unit
    direction (east, north) [arrays broadcast together], a glider crabbing to hold its
    track at `water_mps` through the water: u / (c.d + sqrt(u^2 - (c x d)^2)); infinite
    where the current holds it back."""
    along = current_east * heading_east + current_north * heading_north
    across = current_east * heading_north - current_north * heading_east
    square = water_mps ** 2 - across ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        ground = along + np.sqrt(np.where(square > 0.0, square, np.nan))
        factor = np.where(ground > 1e-3, water_mps / ground, np.inf)
    return np.minimum(np.where(np.isnan(factor), np.inf, factor), FACTOR_CAP)


def leg_factors(points: np.ndarray, water_mps: float, scenarios: Scenarios) -> np.ndarray:
    """(legs, N): each leg's time factor in each scenario's current."""
    legs = np.diff(points, axis=0)
    length = np.hypot(legs[:, 0], legs[:, 1])
    safe = np.where(length > 0.0, length, 1.0)
    return ground_factor(water_mps, (legs[:, 0] / safe)[:, None], (legs[:, 1] / safe)[:, None],
                         scenarios.current_east[None, :], scenarios.current_north[None, :])


def router_for(fleet: Fleet) -> Router:
    from gliderplan.language.fleet_geometry import polygon

    return Router([polygon(list(k)) for k in fleet.keepouts])


def bands(fleet: Fleet) -> list[tuple[float, float]]:
    """The yo bands a glider may fly: the goal's, and down to the bottom when given (a
    deeper yo turns less often: cheaper per metre)."""
    goal = fleet.goal
    found = [(goal.min_depth_m, goal.max_depth_m)]
    if goal.bottom_m is not None and goal.bottom_m > goal.max_depth_m + 1.0:
        found.append((goal.min_depth_m, goal.bottom_m))
    return found


def pick(capacities: list[Capacity]) -> Capacity:
    """Of a glider's options (one per band), the one that flies farthest."""
    return max(capacities, key=lambda c: (c.distance_m, -c.nominal_energy_j))


def hours(seconds: float) -> str:
    return f"{seconds / 3600.0:.3g} h" if seconds < 2 * 86400 else f"{seconds / 86400.0:.3g} d"

