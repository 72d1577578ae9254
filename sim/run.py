"""`run_mission`: one simulated flight from a checked mission to its files, the pipeline of
`gliderplan sim`: fly a flight's set-up (sim/setup.py: the vehicle, the ocean, the plan),
bill every component, check the flight against the plan, write the run's files."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from gliderplan.contract import interrupts
from gliderplan.contract.errors import UsageError
from gliderplan.contract.files import output_folder
from gliderplan.planner.planfile import Plan

if TYPE_CHECKING:  # numpy and pandas: loaded when a run starts
    from gliderplan.planner.speed import Leg
    from gliderplan.sim.currents import CurrentField
    from gliderplan.sim.energy import FlightCheck, RunEnergy
    from gliderplan.sim.loop import RunRecord
    from gliderplan.sim.setup import FlightSetup

RUN_FILES = ("trace.csv", "timeseries.parquet", "summary.json", "depth.png", "energy.png",
             "events.log")  # events.log: the C runtime's own, with --faults
NETCDF_FILE = "trajectory.nc"  # with netcdf=True
REPLANS_FILE = "replans.csv"  # with replan_every: what each surfacing did
REPLAN_EVERY = ("surfacing",)
# what a run's folder may hold (its files, `gliderplan export`'s): a folder holding only
# these is taken for an earlier run (one written before folders carried their marker)
RECOGNISED_FILES = (*RUN_FILES, NETCDF_FILE, "trajectory_og1.nc", "trajectory_cf.nc",
                    "track.geojson", "track.kml", REPLANS_FILE)


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


def grounding(record: RunRecord) -> dict | None:
    """Whether the glider reached the sea floor: the first time [s] and the ticks it ended
    there (None: it never did)."""
    if not record.grounded_ticks:
        return None
    return {"first_s": record.first_grounded_s, "ticks": record.grounded_ticks,
            "time_s": record.grounded_ticks * record.tick_s}


def run_mission(setup: FlightSetup, output_dir: str | Path, *, netcdf: bool = False,
                progress: Callable[[float, float], None] | None = None, plots: bool = True,
                replan_every: str | None = None, confidence: float | None = None,
                scenario_file: str | Path | None = None, force: bool = False,
                mission_path: str | Path | None = None) -> RunResult:
    """Fly the mission of `setup` (sim.setup.flight_setup: its plan, vehicle, water,
    runtime, faults) on the simulated glider and write RUN_FILES into `output_dir`, a
    folder written whole (contract.files.output_folder; `force`: replace a folder that
    holds other files than a gliderplan run's; `mission_path`, the mission's file, is
    refused inside it, as every file the run reads).

    `netcdf`: also write trajectory.nc (sim.export). `progress(done_s, total_s)` is
    called on long runs, whose plots a second process draws (sim/plotter.py).
    `plots`: False leaves out depth.png and energy.png (a caller that draws its own).
    `replan_every`: "surfacing" puts the shore in the loop (sim/replanning.py): at each
    surfacing the glider's report goes up, the rest of the mission is replanned at
    `confidence` (default: the plan's own) with the prior of `scenario_file` (default: the
    shipped one), and the plan update goes down to the runtime, which applies it (the C
    runtime over its link). The vehicle holds the options' key, or without one a key made
    for the run, with which the plan is signed; summary.json's `replanning` says what
    crossed the link, and replans.csv what each surfacing did. With the options'
    `currents`, the shore replans in them (`shore_water`).

    Raises a GliderplanError (a missing or bad file, a runtime that cannot be built, a
    folder that cannot be written); KeyboardInterrupt if nothing was flown, or on a second
    stop signal while the files are written (the folder then keeps its previous run): a
    run interrupted in flight keeps and writes the part flown, marked partial
    (`RunResult.interrupted`, summary.json's `complete`).
    """
    from gliderplan.sim import energy as accounting
    from gliderplan.sim import export, outputs
    from gliderplan.sim import plots as drawing
    from gliderplan.sim.export import utc_text
    from gliderplan.sim.flight import fly
    from gliderplan.sim.plotter import PlotProcess

    out = Path(output_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory")
    mission, options, plan, vehicle = setup.mission, setup.options, setup.plan, setup.vehicle
    config, runtime, water = setup.config, setup.runtime, setup.water.ocean
    plan_path, key_path = options.plan_path, options.key_path
    read = (mission_path, *setup.inputs, scenario_file)  # refused inside the folder replaced
    shore = None
    if replan_every is not None:
        shore, plan_path, key_path = _shore(setup, replan_every, confidence, scenario_file)
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
                         else str(plan_path), runtime, robust_tracker=setup.robust_tracker,
                         progress=progressed,
                         key_path=None if key_path is None else str(key_path),
                         state_dir=options.state_dir, faults=setup.faults, shore=shore,
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
                    "ocean": options.ocean or "bench", "water_density": setup.density_note,
                    "noise": options.noise, "tracker": options.tracker, "seed": config.seed,
                    "tick_s": config.tick_s,
                    "plan": None if plan_path is None else str(plan_path),
                    "vehicle": mission.vehicle, "start_utc": utc_text(config.start_epoch_s),
                    "currents": options.currents or "none",
                    "sea_floor": setup.water.floor_note, "grounded": grounding(record),
                    "current_mps": {"north": config.current.north_mps,
                                    "east": config.current.east_mps},
                    "run_limit_s": config.duration_s}
            if shore is not None:
                flown_s = float(record.columns["time_s"][-1]) + config.tick_s
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
    notes = [setup.density_note, setup.water.floor_note]
    if record.grounded_ticks:
        notes.append(f"the glider reached the sea floor at {record.first_grounded_s:g} s and "
                     f"stopped there, {record.grounded_ticks} ticks in all (a yo deeper than "
                     "the water: give it an altimeter stop, yo's fifth argument)")
    return RunResult(record, used, check, plan, tuple(folder.final(n) for n in written),
                     tuple(notes), stopped=writing.requested,
                     replanning=meta.get("replanning"), current_notes=setup.current_notes,
                     currents=config.currents)


def shore_water(setup: FlightSetup) -> dict[str, tuple[Leg, ...]]:
    """The water the shore replans in: the set-up's current on each state's route from
    where and when the glider is put in (planner.water.route_legs), the water
    `plan --currents --start` plans in, so that a replan chooses the speeds and thrusts
    for the current flown, not for still water."""
    from gliderplan.planner.water import route_legs
    from gliderplan.sim.currents import UniformCurrent
    from gliderplan.sim.loop import start_position

    mission, config = setup.mission, setup.config
    field = config.currents or UniformCurrent(config.current.north_mps,
                                              config.current.east_mps)
    return route_legs(mission, field, start_position(mission, config), config.start_epoch_s)


def _shore(setup: FlightSetup, every: str, confidence: float | None,
           scenario_file: str | Path | None):  # noqa: ANN202
    """The shore of a run with replanning, and the plan and key the vehicle holds (the plan
    signed with a key made for the run when none is given; for the C runtime, which reads
    both from files, they are kept in a temporary directory for the run). It replans in
    the currents the options give (`shore_water`), else in still water, the plan's speeds
    kept."""
    import secrets

    from gliderplan.planner.planfile import read_plan_data
    from gliderplan.planner.signing import check_signature, sign_plan
    from gliderplan.sim.replanning import ShoreLoop
    from gliderplan.sim.scenarios import read_spec

    plan_path, key_path = setup.options.plan_path, setup.options.key_path
    if every not in REPLAN_EVERY:
        raise UsageError(f"--replan-every {every}: expected one of {', '.join(REPLAN_EVERY)}")
    if plan_path is None:
        raise UsageError("--replan-every: replanning changes a plan: give --plan")
    held = read_plan_data(plan_path)
    if setup.key is not None:
        key = setup.key
        check_signature(held, key, str(plan_path))
    else:
        key = secrets.token_bytes(32)
        held = sign_plan(held, key, 1)
    legs = None if setup.options.currents is None else shore_water(setup)
    shore = ShoreLoop(setup.mission, held, key, tick_s=setup.config.tick_s,
                      confidence=confidence, spec=read_spec(scenario_file), legs=legs)
    if key_path is None and setup.runtime == "c":  # files for the runtime, removed after the run
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
