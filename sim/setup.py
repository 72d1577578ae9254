"""One flight's set-up, built once from a mission, its plan and the user's options: the
vehicle (ballasted for the water), the water and its floor, the run's configuration
(tick, duration, seed, noise, start, currents), the plan and its budget, the runtime and
the faults injected into it. `gliderplan sim` (its replanning shore too), `montecarlo`
(each scenario draws its world around it), `plan --confidence`,
`plan --occupancy-from-sim`, the report, `fleet sim`, `fleet montecarlo` and `route`'s
simulated transit fly what `flight_setup` builds; `forecast`, which flies no flight,
ballasts the glider for its water and takes its run limit as the set-up does
(`planner.rates.ballasted_in`, `CheckedMission.run_limit_s`)."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from gliderplan.contract import TICK_S
from gliderplan.contract.errors import UsageError
from gliderplan.language.ir import CheckedMission
from gliderplan.planner.planfile import Plan, load_plan
from gliderplan.power_models.battery import usable_budget_j

if TYPE_CHECKING:  # numpy and the models: loaded when a flight is set up
    from gliderplan.power_models.flight import DensityProfile
    from gliderplan.power_models.vehicle import Vehicle
    from gliderplan.sim.faults import FaultSpec
    from gliderplan.sim.loop import RunConfig
    from gliderplan.sim.ocean import Water

TRACKERS = ("robust", "naive")
# What the C runtime keeps in its state directory (runtime/README.md)
RUNTIME_STATE_FILES = ("checkpoint", "events.log", "plan", "plans.log")


@dataclass(frozen=True)
class FlightOptions:
    """What the user chose about a flight, as `gliderplan sim` takes it.

    `plan_path`: the plan to fly and to check the flight against (without one every sensor
    a state logs is always on). `runtime`: "step" (the compiled runtime's step in this
    process; the default where a C compiler is installed), "python" (the reference
    executor) or "c" (the compiled runtime over a pseudo-terminal). `ocean`: a preset
    (bench, sea-trial, uniform), a CSV file, or Slocum science logs to replay (FILE.ebd or
    a directory): the glider flies its temperature, salinity and in-situ density
    (TEOS-10), ballasted for the mean density over the depths the mission flies, as
    `gliderplan forecast` flies it
    (`planner.rates.ballasted_in`); default: the bench preset's
    temperatures in uniform water of the vehicle's reference density. `noise`: a key of
    `science.NOISE_PRESETS`. `tracker`: "robust" or "naive" (the paper's first).
    `currents`: the text of `sim --currents` (N,E [m/s], a NetCDF field, flight logs:
    sim.current_files), refused where it does not cover the run or the start is on its
    land. `seed`, `tick_s` [s], `duration_s` [s] (default: the mission's horizon, else
    30 days). `start_utc`: ISO 8601 time of missiontime 0 (default: the replayed logs'
    first sample, else 2000-01-01T00:00:00Z). `start_position`: (lat, lon) [deg] where the
    glider is put in the water (default: 500 m south of the mission's first waypoint).
    `key_path`: the key provisioned on the simulated vehicle; the plan must be signed with
    it (the C runtime gets it uploaded over the link and checks it itself).
    `state_dir`: the C runtime keeps its checkpoints and event log there, as on the glider
    (its fdatasyncs included); a directory that holds an earlier flight's files is refused,
    since the runtime would resume that flight against a glider that starts afresh.
    `faults`: a fault SPEC (sim/faults.py) injected into the C runtime's line and board;
    the run then also writes the runtime's own events.log, and summary.json says what the
    faults did. `floor`: the sea floor's depth [m] (a number, or the text of
    `sim --floor`), a flat floor under the whole run; default: none, or under replayed
    Slocum logs the floor they saw (sim.ocean.load_water). The glider stops at the floor;
    summary.json says where the floor came from and whether the glider reached it
    (`sea_floor`, `grounded`).
    """

    plan_path: str | Path | None = None
    runtime: str | None = None  # "step", "python" or "c" (None: sim.flight.default_runtime)
    ocean: str | None = None  # a preset, a CSV file or Slocum logs (None: bench, uniform)
    noise: str = "ctd"
    tracker: str = "robust"
    currents: str | None = None  # the text of `sim --currents`
    seed: int = 0
    tick_s: float = TICK_S  # [s]
    duration_s: float | None = None  # [s] (None: the mission's horizon, else 30 days)
    start_utc: str | None = None  # ISO 8601 UTC of missiontime 0
    start_position: tuple[float, float] | None = None  # (lat, lon) [deg]
    floor: float | str | None = None  # [m], or the text of `sim --floor`
    faults: str | None = None  # a fault SPEC (sim/faults.py), C runtime only
    key_path: str | Path | None = None  # the key provisioned on the vehicle
    state_dir: str | Path | None = None  # the C runtime's state directory


@dataclass(frozen=True)
class FlightSetup:
    """Everything a flight of `mission` is flown with, checked and loaded."""

    mission: CheckedMission
    options: FlightOptions
    plan: Plan | None  # the schedules flown and their prediction (None: sensors always on)
    vehicle: Vehicle  # as flown: ballasted for the water
    water: Water  # the ocean flown and its floor
    config: RunConfig  # tick, duration, seed, noise, start, floor, density, currents
    runtime: str
    budget_j: float  # the plan's budget, else the mission's battery less its reserve [J]
    faults: FaultSpec | None = None
    key: bytes | None = None  # the vehicle's key, read from options.key_path
    density_note: str = ""  # the water flown, for the user
    current_notes: tuple[str, ...] = ()  # the currents flown, and warnings about them

    @property
    def robust_tracker(self) -> bool:
        return self.options.tracker == "robust"

    @property
    def inputs(self) -> tuple[str | Path | None, ...]:
        """Every file or folder the flight reads (None where an option names none): a run
        refuses to replace a folder that holds one (contract.files.output_folder)."""
        o = self.options
        return (o.plan_path, o.key_path, o.state_dir, _path_of(o.ocean), _path_of(o.currents))


def flight_setup(mission: CheckedMission, options: FlightOptions = FlightOptions(), *,
                 plan: Plan | None = None, vehicle: Vehicle | None = None) -> FlightSetup:
    """The set-up of a flight of `mission` with `options`: the plan `plan` (one made in
    memory, or the one in `options.plan_path` already read), else read from
    `options.plan_path`; the vehicle (`vehicle`, default the mission's) ballasted for
    the water. Raises a GliderplanError naming the option or
    file that cannot be used, before anything is flown."""
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim.export import parse_utc
    from gliderplan.sim.flight import default_runtime, refuse_unflyable_yos
    from gliderplan.sim.loop import DEFAULT_START_EPOCH_S, RunConfig, start_position
    from gliderplan.sim.ocean import flat_floor, load_water, parse_floor
    from gliderplan.sim.science import NOISE_PRESETS

    o = options
    if not (math.isfinite(o.tick_s) and 0.1 <= o.tick_s <= 60.0):
        raise UsageError(f"--tick {o.tick_s:g}: must lie between 0.1 and 60 s")
    if o.noise not in NOISE_PRESETS or o.tracker not in TRACKERS:
        raise UsageError(f"noise {o.noise!r} or tracker {o.tracker!r}: expected one of "
                         f"{', '.join(NOISE_PRESETS)} and one of {', '.join(TRACKERS)}")
    runtime = o.runtime or default_runtime()
    if o.state_dir is not None:
        check_state_dir(Path(o.state_dir), runtime)
    try:
        start = parse_utc(o.start_utc) if o.start_utc else None
    except ValueError as err:
        raise UsageError(f"--start: {err}") from None
    duration = mission.run_limit_s(o.duration_s)
    fault_spec = None
    if o.faults is not None:
        from gliderplan.sim.faults import parse_faults

        if runtime != "c":
            raise UsageError("--faults: faults are injected into the C runtime's line and "
                             "board: add --runtime c")
        fault_spec = parse_faults(o.faults)
    sea_floor = None if o.floor is None else \
        parse_floor(o.floor) if isinstance(o.floor, str) else flat_floor(o.floor)
    vehicle = vehicle or load_vehicle(mission.vehicle)
    given = load_water(o.ocean or "bench", sea_floor)
    density, density_note = None, (f"water: uniform, the vehicle's reference density "
                                   f"({vehicle.flight.rho_kg_m3:.1f} kg/m3)")
    if o.ocean is not None:
        vehicle, density, density_note = flown_water(mission, vehicle, given, o.ocean)
    if start is None:
        start = getattr(given.ocean, "start_epoch_s", None) or DEFAULT_START_EPOCH_S
    lat, lon = o.start_position or (None, None)
    config = RunConfig(tick_s=o.tick_s, duration_s=duration, seed=o.seed,
                       noise=NOISE_PRESETS[o.noise], start_epoch_s=start, floor=given.floor,
                       water=density, start_lat_deg=lat, start_lon_deg=lon)
    if getattr(given.floor, "by_position", False):
        problem = given.floor.start_problem(*start_position(mission, config))
        if problem is not None:
            raise UsageError(f"--floor {o.floor}: {problem}")
    field_notes: list[str] = []
    if o.currents is not None:
        config, field_notes = with_currents(mission, config, o.currents, vehicle)
    if plan is None and o.plan_path is not None:
        plan = load_plan(o.plan_path, mission)
    refuse_unflyable_yos(mission, vehicle, plan)
    key = None
    if o.key_path is not None:
        if o.plan_path is None:
            raise UsageError("--key: the key checks a plan's signature; give --plan too")
        from gliderplan.planner.planfile import read_plan_data
        from gliderplan.planner.signing import check_signature, read_key

        key = read_key(o.key_path)
        if runtime != "c":  # the C runtime over the link checks for itself
            check_signature(read_plan_data(o.plan_path), key, str(o.plan_path))
    budget_j = plan.budget_j if plan is not None else \
        usable_budget_j(mission.battery.energy_j, mission.battery.reserve_fraction)
    return FlightSetup(mission, options, plan, vehicle, given, config, runtime, budget_j,
                       fault_spec, key, density_note, tuple(field_notes))


def _path_of(spec: str | None) -> str | None:
    """The file or folder `--ocean` or `--currents` names (None: a preset, numbers)."""
    return spec if spec is not None and Path(spec).exists() else None


def check_state_dir(state_dir: Path, runtime: str) -> None:
    """Refuse a state directory a simulated run cannot use: UsageError naming it."""
    if runtime != "c":
        raise UsageError(f"--state-dir {state_dir}: only the C runtime keeps one "
                         "(--runtime c)")
    if state_dir.exists() and not state_dir.is_dir():
        raise UsageError(f"--state-dir {state_dir}: not a directory")
    earlier = [name for name in RUNTIME_STATE_FILES if (state_dir / name).exists()]
    if earlier:
        raise UsageError(f"--state-dir {state_dir}: holds an earlier flight's "
                         f"{', '.join(earlier)}, which the runtime would resume or extend; "
                         "name an empty or new directory")


def flown_water(mission: CheckedMission, vehicle: Vehicle, given: Water, spec: str
                ) -> tuple[Vehicle, DensityProfile, str]:
    """(the vehicle ballasted for the water, the in-situ density it flies through, what
    that is): the ocean's density profile (TEOS-10, `sim.ocean.density_profile_of`) and
    its mean over the depths the mission flies (over the floor's median, where the water
    has one), as `gliderplan forecast` takes them (`planner.rates.ballasted_in`)."""
    from gliderplan.planner.rates import ballasted_in
    from gliderplan.sim.ocean import WATER_DEPTHS_M, density_profile_of

    density = density_profile_of(given.ocean)
    floor_m = None if given.floor is None else given.floor.median_m
    ballasted, rho = ballasted_in(mission, density, vehicle, floor_m)
    note = (f"water: {spec}: in-situ density (TEOS-10) {density.rho_kg_m3.min():.1f}-"
            f"{density.rho_kg_m3.max():.1f} kg/m3 over 0-{WATER_DEPTHS_M[-1]:.0f} m, flown "
            f"at each depth; the glider ballasted for {rho:.1f} kg/m3, its mean over the "
            f"depths the mission flies (trimmed in {vehicle.flight.rho_kg_m3:.1f} kg/m3 as "
            "calibrated)")
    return ballasted, density, note


def with_currents(mission: CheckedMission, config: RunConfig, spec: str, vehicle: Vehicle
                  ) -> tuple[RunConfig, list[str]]:
    """`config` flying the currents of `--currents SPEC` (sim.current_files.checked_field),
    and notes for the user."""
    from gliderplan.sim.current_files import checked_field
    from gliderplan.sim.currents import UniformCurrent
    from gliderplan.sim.loop import start_position
    from gliderplan.sim.vehicle import Current

    field, notes = checked_field(spec, mission, vehicle, start_position(mission, config),
                                 config.start_epoch_s, config.duration_s)
    if isinstance(field, UniformCurrent):
        return dataclasses.replace(config, current=Current(field.north_mps, field.east_mps)), \
            notes
    return dataclasses.replace(config, currents=field), notes
