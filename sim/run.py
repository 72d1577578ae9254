"""`run_mission`: one simulated flight from a checked mission to its files, the pipeline of
`gliderplan sim`: load the vehicle, the ocean and the plan, fly, bill every component,
check the flight against the plan, write the run's files."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from gliderplan.contract import DEFAULT_HORIZON_S, TICK_S, interrupts
from gliderplan.contract.errors import UsageError
from gliderplan.contract.files import output_folder
from gliderplan.language.ir import CheckedMission
from gliderplan.planner.planfile import Plan, load_plan

if TYPE_CHECKING:  # numpy and pandas: loaded when a run starts
    from gliderplan.planner.speed import Leg
    from gliderplan.power_models.flight import DensityProfile
    from gliderplan.power_models.vehicle import Vehicle
    from gliderplan.sim.currents import CurrentField
    from gliderplan.sim.energy import FlightCheck, RunEnergy
    from gliderplan.sim.loop import RunConfig, RunRecord
    from gliderplan.sim.ocean import Water

RUN_FILES = ("trace.csv", "timeseries.parquet", "summary.json", "depth.png", "energy.png",
             "events.log")  # events.log: the C runtime's own, with --faults
NETCDF_FILE = "trajectory.nc"  # with netcdf=True
REPLANS_FILE = "replans.csv"  # with replan_every: what each surfacing did
REPLAN_EVERY = ("surfacing",)
# what a run's folder may hold (its files, `gliderplan export`'s): a folder holding only
# these is taken for an earlier run (one written before folders carried their marker)
RECOGNISED_FILES = (*RUN_FILES, NETCDF_FILE, "trajectory_og1.nc", "trajectory_cf.nc",
                    "track.geojson", "track.kml", REPLANS_FILE)
TRACKERS = ("robust", "naive")


@dataclass(frozen=True)
class RunResult:
    """A simulated flight: what happened, what it cost, the verdict against its plan."""

    record: RunRecord  # the transition trace and one row per tick
    energy: RunEnergy  # every component's energy, per tick and per state [J]
    check: FlightCheck  # the flight against the plan ("no plan" without one)
    plan: Plan | None
    files: tuple[Path, ...]  # the run's files, written into their folder whole
    water_notes: tuple[str, ...] = ()  # the sea floor, where the glider reached it
    # a stop signal arrived once the flight was over, while its files were written: they
    # hold the whole flight, and the command stops (exit 130 or 143) all the same
    stopped: bool = False
    replanning: dict | None = None  # with replan_every: what crossed the link (summary.json's)
    current_notes: tuple[str, ...] = ()  # the currents flown, and warnings about them
    currents: CurrentField | None = None  # the field flown (None: none, or a constant)

    @property
    def interrupted(self) -> bool:
        """The flight was cut short by a stop signal: the files hold the part flown."""
        return self.record.ended == "interrupted"


# What the C runtime keeps in its state directory (runtime/README.md)
RUNTIME_STATE_FILES = ("checkpoint", "events.log", "plan", "plans.log")


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
    that is): the ocean's density profile (TEOS-10, `sim.ocean.density_profile_of`, as
    `gliderplan forecast` takes it) and its mean over the depths the mission flies (over
    the floor's median, where the water has one)."""
    from gliderplan.planner.forecast import WATER_DEPTHS_M
    from gliderplan.planner.rates import band_density
    from gliderplan.sim.ocean import density_profile_of

    density = density_profile_of(given.ocean, WATER_DEPTHS_M)
    floor_m = None if given.floor is None else given.floor.median_m
    rho = band_density(mission, density, vehicle, floor_m)
    note = (f"water: {spec}: in-situ density (TEOS-10) {density.rho_kg_m3.min():.1f}-"
            f"{density.rho_kg_m3.max():.1f} kg/m3 over 0-{WATER_DEPTHS_M[-1]:.0f} m, flown "
            f"at each depth; the glider ballasted for {rho:.1f} kg/m3, its mean over the "
            f"depths the mission flies (trimmed in {vehicle.flight.rho_kg_m3:.1f} kg/m3 as "
            "calibrated)")
    return vehicle.ballasted_for(rho), density, note


def _path_of(spec: str | None) -> str | None:
    """The file or folder `--ocean` or `--currents` names (None: a preset, numbers)."""
    return spec if spec is not None and Path(spec).exists() else None


def with_currents(mission: CheckedMission, config: RunConfig, spec: str, vehicle: Vehicle
                  ) -> tuple[RunConfig, list[str]]:
    """`config` flying the currents of `--currents SPEC` (sim.current_files.checked_field),
    and notes for the user."""
    import dataclasses

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


def grounding(record: RunRecord) -> dict | None:
    """Whether the glider reached the sea floor: the first time [s] and the ticks it ended
    there (None: it never did)."""
    if not record.grounded_ticks:
        return None
    return {"first_s": record.first_grounded_s, "ticks": record.grounded_ticks,
            "time_s": record.grounded_ticks * record.tick_s}


def run_mission(mission: CheckedMission, output_dir: str | Path, *,
                plan_path: str | Path | None = None, runtime: str | None = None,
                ocean: str | None = None, noise: str = "ctd", tracker: str = "robust",
                currents: str | None = None, seed: int = 0, tick_s: float = TICK_S,
                duration_s: float | None = None, start_utc: str | None = None,
                start_position: tuple[float, float] | None = None,
                netcdf: bool = False,
                progress: Callable[[float, float], None] | None = None,
                plots: bool = True, key_path: str | Path | None = None,
                state_dir: str | Path | None = None, faults: str | None = None,
                floor: float | str | None = None,
                replan_every: str | None = None, confidence: float | None = None,
                scenario_file: str | Path | None = None, force: bool = False,
                mission_path: str | Path | None = None) -> RunResult:
    """Fly `mission` on the simulated glider and write RUN_FILES into `output_dir`, a
    folder written whole (contract.files.output_folder; `force`: replace a folder that
    holds other files than a gliderplan run's; `mission_path`, the mission's file, is
    refused inside it, as every file the run reads).

    `plan_path`: the plan to fly and to check the flight against (without one every
    sensor a state logs is always on). `runtime`: "step" (the compiled runtime's step in
    this process; the default where a C compiler is installed), "python" (the reference
    executor) or "c" (the compiled runtime over a pseudo-terminal).
    `ocean`: a preset (bench, sea-trial, uniform), a CSV file, or Slocum science logs to
    replay (FILE.ebd or a directory): the glider flies its temperature, salinity and
    in-situ density (TEOS-10), ballasted for the mean density over the depths the mission
    flies, as `gliderplan forecast` flies it (`planner.rates.band_density`,
    `Vehicle.ballasted_for`); default: the bench preset's temperatures in uniform water of
    the vehicle's reference density. `noise`: a key of `science.NOISE_PRESETS`.
    `tracker`: "robust" or "naive" (the paper's first).
    `currents`: the text of `sim --currents` (N,E [m/s], a NetCDF field, flight logs:
    sim.current_files), refused where it does not cover the run or the start is on its
    land. `seed`, `tick_s` [s], `duration_s` [s] (default: the mission's horizon, else
    30 days). `start_utc`: ISO 8601 time of missiontime 0 (default: the replayed logs'
    first sample, else 2000-01-01T00:00:00Z). `start_position`: (lat, lon) [deg] where the
    glider is put in the water (default: 500 m south of the mission's first waypoint).
    `netcdf`: also write trajectory.nc (sim.export). `progress(done_s, total_s)` is
    called on long runs, whose plots a second process draws (sim/plotter.py).
    `plots`: False leaves out depth.png and energy.png (a caller that draws its own).
    `key_path`: the key provisioned on the simulated vehicle; the plan must be signed with
    it (the C runtime gets it uploaded over the link and checks it itself).
    `state_dir`: the C runtime keeps its checkpoints and event log there, as on the glider
    (its fdatasyncs included); a directory that holds an earlier flight's files is refused,
    since the runtime would resume that flight against a glider that starts afresh.
    `faults`: a fault SPEC (sim/faults.py) injected into the C runtime's line and board;
    the run then also writes the runtime's own events.log, and summary.json says what the
    faults did.
    `floor`: the sea floor's depth [m] (a number, or the text of `sim --floor`), a flat
    floor under the whole run; default: none, or under replayed Slocum logs the floor they
    saw (sim.ocean.load_water). The glider stops at the floor; summary.json says where the
    floor came from and whether the glider reached it (`sea_floor`, `grounded`).
    `replan_every`: "surfacing" puts the shore in the loop (sim/replanning.py): at each
    surfacing the glider's report goes up, the rest of the mission is replanned at
    `confidence` (default: the plan's own) with the prior of `scenario_file` (default: the
    shipped one), and the plan update goes down to the runtime, which applies it (the C
    runtime over its link). The vehicle holds `key_path`'s key, or without one a key made
    for the run, with which the plan is signed; summary.json's `replanning` says what
    crossed the link, and replans.csv what each surfacing did. With `currents`, the shore
    replans in them (`shore_water`).

    Raises a GliderplanError (a missing or bad file, a plan for another mission, a
    runtime that cannot be built, a folder that cannot be written); KeyboardInterrupt if
    nothing was flown, or on a second stop signal while the files are written (the folder
    then keeps its previous run): a run interrupted in flight keeps and writes the part
    flown, marked partial (`RunResult.interrupted`, summary.json's `complete`).
    """
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim import energy as accounting
    from gliderplan.sim import export, outputs
    from gliderplan.sim import plots as drawing
    from gliderplan.sim.export import parse_utc, utc_text
    from gliderplan.sim.flight import default_runtime, fly, refuse_unflyable_yos
    from gliderplan.sim.loop import DEFAULT_START_EPOCH_S, RunConfig
    from gliderplan.sim.ocean import flat_floor, load_water, parse_floor
    from gliderplan.sim.plotter import PlotProcess
    from gliderplan.sim.science import NOISE_PRESETS

    if not (math.isfinite(tick_s) and 0.1 <= tick_s <= 60.0):
        raise UsageError(f"--tick {tick_s:g}: must lie between 0.1 and 60 s")
    if noise not in NOISE_PRESETS or tracker not in TRACKERS:
        raise UsageError(f"noise {noise!r} or tracker {tracker!r}: expected one of "
                         f"{', '.join(NOISE_PRESETS)} and one of {', '.join(TRACKERS)}")
    runtime = runtime or default_runtime()
    out = Path(output_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory")
    if state_dir is not None:
        check_state_dir(Path(state_dir), runtime)
    try:
        start = parse_utc(start_utc) if start_utc else None
    except ValueError as err:
        raise UsageError(f"--start: {err}") from None
    duration = duration_s if duration_s is not None else mission.horizon_s or DEFAULT_HORIZON_S
    fault_spec = None
    if faults is not None:
        from gliderplan.sim.faults import parse_faults

        if runtime != "c":
            raise UsageError("--faults: faults are injected into the C runtime's line and "
                             "board: add --runtime c")
        fault_spec = parse_faults(faults)
    sea_floor = None if floor is None else \
        parse_floor(floor) if isinstance(floor, str) else flat_floor(floor)
    vehicle = load_vehicle(mission.vehicle)
    given = load_water(ocean or "bench", sea_floor)
    water = given.ocean
    density, density_note = None, (f"water: uniform, the vehicle's reference density "
                                   f"({vehicle.flight.rho_kg_m3:.1f} kg/m3)")
    if ocean is not None:
        vehicle, density, density_note = flown_water(mission, vehicle, given, ocean)
    if start is None:
        start = getattr(water, "start_epoch_s", None) or DEFAULT_START_EPOCH_S
    lat, lon = start_position or (None, None)
    config = RunConfig(tick_s=tick_s, duration_s=duration, seed=seed,
                       noise=NOISE_PRESETS[noise], start_epoch_s=start, floor=given.floor,
                       water=density, start_lat_deg=lat, start_lon_deg=lon)
    if getattr(given.floor, "by_position", False):
        from gliderplan.sim.loop import start_position

        problem = given.floor.start_problem(*start_position(mission, config))
        if problem is not None:
            raise UsageError(f"--floor {floor}: {problem}")
    field_notes: list[str] = []
    if currents is not None:
        config, field_notes = with_currents(mission, config, currents, vehicle)
    plan = None if plan_path is None else load_plan(plan_path, mission)
    refuse_unflyable_yos(mission, vehicle, plan)
    if key_path is not None:
        if plan_path is None:
            raise UsageError("--key: the key checks a plan's signature; give --plan too")
        from gliderplan.planner.planfile import read_plan_data
        from gliderplan.planner.signing import check_signature, read_key

        key = read_key(key_path)
        if runtime != "c":  # the C runtime over the link checks for itself
            check_signature(read_plan_data(plan_path), key, str(plan_path))
    # every file the run reads (refused inside the folder it replaces)
    read = (mission_path, plan_path, key_path, state_dir, _path_of(ocean), _path_of(currents),
            scenario_file)
    shore = None
    if replan_every is not None:
        shore, plan_path, key_path = _shore(mission, replan_every, plan_path, key_path, runtime,
                                            tick_s, confidence, scenario_file,
                                            None if currents is None else
                                            shore_water(mission, config))
    plotter: PlotProcess | None = None

    def progressed(done_s: float, total_s: float) -> None:
        """A run long enough to report its progress draws its plots in a second process,
        which imports matplotlib while the rest is flown."""
        nonlocal plotter
        if plots and plotter is None:
            plotter = PlotProcess()
        if progress is not None:
            progress(done_s, total_s)

    # The first stop signal during the flight ends it (the record says "interrupted");
    # once the flight is over, one waits while what was flown is written (a second one
    # abandons it, leaving the folder's previous run): the run is written whole or not.
    with interrupts.deferred(armed=False) as writing, \
            output_folder(out, command="sim", force=force, recognised=RECOGNISED_FILES,
                          inputs=read) as folder:
        try:
            record = fly(mission, water, config, vehicle, plan, None if plan_path is None
                         else str(plan_path), runtime, robust_tracker=tracker == "robust",
                         progress=progressed,
                         key_path=None if key_path is None else str(key_path),
                         state_dir=state_dir, faults=fault_spec, shore=shore,
                         keep_interrupted=True)
            writing.arm()
            if not len(record.columns["time_s"]):
                raise KeyboardInterrupt  # nothing flown, nothing to write
            used = accounting.account(record, mission, vehicle, plan)
            check = accounting.check_flight(used, plan)
            contents = {}
            if plots:
                series = drawing.depth_series(record), drawing.energy_series(record, used, plan)
                if plotter is not None:
                    plotter.draw(*series)  # drawn there while the other files are written here
                else:
                    contents["depth.png"] = drawing.depth_png(series[0])
                    contents["energy.png"] = drawing.energy_png(series[1])
            meta = {"mission": mission.name, "mission_hash": mission.hash, "runtime": runtime,
                    "ocean": ocean or "bench", "water_density": density_note, "noise": noise,
                    "tracker": tracker, "seed": seed,
                    "tick_s": tick_s, "plan": None if plan_path is None else str(plan_path),
                    "vehicle": mission.vehicle, "start_utc": utc_text(start),
                    "currents": currents or "none",
                    "sea_floor": given.floor_note, "grounded": grounding(record),
                    "current_mps": {"north": config.current.north_mps,
                                    "east": config.current.east_mps},
                    "run_limit_s": duration}
            if shore is not None:
                flown_s = float(record.columns["time_s"][-1]) + tick_s
                meta["replanning"] = {"every": replan_every,
                                      "confidence": shore.replanner.confidence,
                                      **shore.log.summary(flown_s)}
                contents[REPLANS_FILE] = _replans_csv(shore.log.events)
            columns = record.columns  # the water's salinity where the glider was: the CTD's
            salinity = water.salinity_psu(columns["depth_m"], columns["time_s"])
            table = outputs.timeseries_table(record, used, mission.battery.energy_j, salinity)
            contents["trace.csv"] = outputs.trace_csv(record.trace)
            contents["timeseries.parquet"] = outputs.parquet_bytes(
                table, dictionary=outputs.TIMESERIES_DICTIONARY)
            contents["summary.json"] = outputs.summary(record, used, check, plan, meta)
            if record.events_log is not None:
                contents["events.log"] = record.events_log
            if netcdf:
                contents[NETCDF_FILE] = export.netcdf_bytes(
                    table.to_pandas(), {**meta, "ended": record.ended,
                                        "simulated_s": outputs.simulated_s(record)})
            if plotter is not None:
                contents["depth.png"], contents["energy.png"] = plotter.pngs()
        finally:
            if plotter is not None:
                plotter.close()
            if getattr(shore, "workdir", None) is not None:
                shore.workdir.cleanup()
        written = [name for name in (*RUN_FILES, REPLANS_FILE, NETCDF_FILE) if name in contents]
        for name in written:
            folder.write(name, contents[name])
        folder.complete = record.ended != "interrupted"
    notes = [density_note, given.floor_note]
    if record.grounded_ticks:
        notes.append(f"the glider reached the sea floor at {record.first_grounded_s:g} s and "
                     f"stopped there, {record.grounded_ticks} ticks in all (a yo deeper than "
                     "the water: give it an altimeter stop, yo's fifth argument)")
    return RunResult(record, used, check, plan, tuple(folder.final(n) for n in written),
                     tuple(notes), stopped=writing.requested,
                     replanning=meta.get("replanning"), current_notes=tuple(field_notes),
                     currents=config.currents)


def shore_water(mission: CheckedMission, config: RunConfig) -> dict[str, tuple[Leg, ...]]:
    """The water the shore replans in: the run's current on each state's route from where
    and when the glider is put in (planner.water.route_legs), the water `plan --currents
    --start` plans in, so that a replan chooses the speeds and thrusts for the current
    flown, not for still water."""
    from gliderplan.planner.water import route_legs
    from gliderplan.sim.currents import UniformCurrent
    from gliderplan.sim.loop import start_position

    field = config.currents or UniformCurrent(config.current.north_mps,
                                              config.current.east_mps)
    return route_legs(mission, field, start_position(mission, config), config.start_epoch_s)


def _shore(mission: CheckedMission, every: str, plan_path: str | Path | None,
           key_path: str | Path | None, runtime: str, tick_s: float,
           confidence: float | None, scenario_file: str | Path | None,
           legs: dict[str, tuple[Leg, ...]] | None):  # noqa: ANN202
    """The shore of a run with replanning, and the plan and key the vehicle holds (the plan
    signed with a key made for the run when none is given; for the C runtime, which reads
    both from files, they are kept in a temporary directory for the run). `legs`: the
    water it replans in (`shore_water`; None: still water, the plan's speeds kept)."""
    import secrets

    from gliderplan.planner.planfile import read_plan_data
    from gliderplan.planner.signing import check_signature, read_key, sign_plan
    from gliderplan.sim.replanning import ShoreLoop
    from gliderplan.sim.scenarios import read_spec

    if every not in REPLAN_EVERY:
        raise UsageError(f"--replan-every {every}: expected one of {', '.join(REPLAN_EVERY)}")
    if plan_path is None:
        raise UsageError("--replan-every: replanning changes a plan: give --plan")
    held = read_plan_data(plan_path)
    if key_path is not None:
        key = read_key(key_path)
        check_signature(held, key, str(plan_path))
    else:
        key = secrets.token_bytes(32)
        held = sign_plan(held, key, 1)
    shore = ShoreLoop(mission, held, key, tick_s=tick_s, confidence=confidence,
                      spec=read_spec(scenario_file), legs=legs)
    if key_path is None and runtime == "c":  # files for the runtime, removed after the run
        import tempfile

        from gliderplan.contract.files import write_atomically

        shore.workdir = tempfile.TemporaryDirectory(prefix="gliderplan-vehicle-")
        vehicle = Path(shore.workdir.name)
        key_path, plan_path = vehicle / "vehicle.key", vehicle / "signed.plan"
        write_atomically(key_path, key.hex() + "\n", private=True)
        write_atomically(plan_path, held)
    return shore, plan_path, key_path


def _replans_csv(events: list[dict]) -> str:
    """One line per surfacing: what the shore heard and did."""
    columns = ("time_s", "used_j", "voltage_v", "plan_seq", "status", "quality",
               "budget_left_j", "energy_left_j", "update_bytes")
    lines = [",".join(columns)]
    for event in events:
        cells = []
        for column in columns:
            value = event.get(column, "")
            if isinstance(value, list):
                value = "+".join(map(str, value))
            elif isinstance(value, float):
                value = f"{value:.6g}"
            cells.append(str(value))
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"
