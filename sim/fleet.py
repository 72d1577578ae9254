"""Fly a fleet plan: every glider's mission in the closed loop, in one shared ocean
(`gliderplan fleet sim` and `fleet montecarlo`).

`fly_fleet` flies each glider once with `sim.run_mission` (its run files and NetCDF in a
directory of its own) and judges the flight as a survey: was every line swept by the
finish, what map do the profiles flown make. `montecarlo_fleet` flies every glider in N
scenarios with `sim.montecarlo`'s own scenario flights: all gliders of scenario i share
its seed, so they fly the same ocean and current and draw the same battery share (and
gliders of one preset the same model error). Work goes out through
`sim.backends.scenario_executor`, as `gliderplan montecarlo`'s does: by default on Dask,
a LocalCluster of `workers` processes, or a running scheduler given by its address
(`scheduler=None`: this process, or a process pool); results depend on the seed only,
never on the workers nor where they run.

A glider can be lost (`lose=(name, time)`): it flies until then. What the rest of the
fleet can still cover is the fleet planned again from that moment, the survivors where
their plans had them and with what their batteries still hold (`replan_after_loss`).
"""

from __future__ import annotations

import json
import math
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gliderplan.contract import interrupts
from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import OutputFolder, output_folder
from gliderplan.language.fleet import Fleet
from gliderplan.planner.fleet import FleetPlan
from gliderplan.planner.fleet_mapping import sample_spacing
from gliderplan.planner.fleet_missions import LAUNCH_S, Track
from gliderplan.planner.fleet_report import (
    StoredGlider,
    StoredPlan,
    load_plan_dir,
    write_plan_dir,
)

TRACK_STEP_S = 60.0  # flown positions kept every minute
PLAN_DIR = "plan"  # in a run's folder: the plan made for it (no --plan)
MAP_FILES = ("fleet.png", "fleet.geojson", "fleet.kml", "fleet.html")
SIM_FILES = ("fleet_sim.json", *MAP_FILES, PLAN_DIR)  # and a folder per glider
MONTECARLO_FILES = ("scenarios.parquet", "summary.json", "mapping_error.png", *MAP_FILES,
                    PLAN_DIR)
Progress = Callable[[float, float], None]
# the plan a fleet run flies: stored (`fleet plan -o`), or the planner that makes it
PlanToFly = StoredPlan | Callable[[], FleetPlan]


# ---- judging a flight as a survey --------------------------------------------------------

@dataclass(frozen=True)
class GliderOutcome:
    name: str
    energy_j: float
    budget_j: float
    held: bool  # its budget held
    ended: str
    swept: bool  # its block swept once by the finish
    segments_done: int
    lines_swept: int
    samples: tuple  # (t [s after the fleet's start], x, y [m]) thinned along what it flew


def first_pass_segment(track: Track) -> int:
    """The segment (1-based) whose end completes the first sweep of the block."""
    ends = track.distance_m[list(track.segment_ends)]
    return int(np.searchsorted(ends, track.first_pass_m - 1e-6) + 1)


def _lines_swept(track: Track, done_m: float) -> int:
    return sum(1 for visits in track.line_visits.values() if visits and visits[0] <= done_m)


def outcome_from_segments(name: str, track: Track, segment_times: list[float],
                          partial: float, energy_j: float, budget_j: float, held: bool,
                          ended: str, window_s: float, spacing_m: float) -> GliderOutcome:
    """A flight judged from the time spent in each segment state (`segment_times`, the
    segments entered in order, the last one `partial` done) and the stays between them:
    the planned path flown at the times the flight took. What the Monte Carlo's rows
    hold: not positions, but the time in every state."""
    ends = track.distance_m[list(track.segment_ends)]
    starts = np.concatenate([[0.0], ends[:-1]])
    done = len(segment_times) - (1 if partial < 1.0 else 0)
    knots_d, knots_t = [0.0], [LAUNCH_S]
    clock = LAUNCH_S
    for k, spent in enumerate(segment_times):
        fraction = 1.0 if k < done else partial
        knots_d.append(starts[k] + fraction * (ends[k] - starts[k]))
        clock += spent
        knots_t.append(clock)
        clock += track.surface_stay_s
    reached = knots_d[-1] if knots_d else 0.0
    d = np.arange(spacing_m / 2.0, reached, spacing_m)
    t = track.start_offset_s + np.interp(d, knots_d, knots_t)
    x = np.interp(d, track.distance_m, track.points[:, 0])
    y = np.interp(d, track.distance_m, track.points[:, 1])
    inside = t <= track.start_offset_s + window_s
    swept = done >= first_pass_segment(track)
    return GliderOutcome(name, energy_j, budget_j, held, ended, swept, done,
                         _lines_swept(track, ends[done - 1] if done else 0.0),
                         (t[inside], x[inside], y[inside]))


# ---- one flight of each glider ----------------------------------------------------------

def _fly_one(task: dict) -> dict:
    """Fly one glider with `run_mission` into a scratch directory; return its files and
    what the survey needs of the flight (a worker's task: plain data in and out)."""
    from gliderplan.language import check_source
    from gliderplan.sim import FlightOptions, flight_setup, run_mission

    mission = check_source(task["mission_text"], task["mission_name"]).checked()
    with tempfile.TemporaryDirectory(prefix="gliderplan-fleet-") as scratch:
        plan_path = Path(scratch) / "glider.plan"
        plan_path.write_bytes(task["plan_bytes"])
        options = FlightOptions(plan_path=plan_path, runtime=task["runtime"],
                                ocean=task["ocean"],
                                currents="{!r},{!r}".format(*task["current"]),
                                seed=task["seed"], duration_s=task["duration_s"],
                                start_utc=task["start_utc"])
        result = run_mission(flight_setup(mission, options), Path(scratch) / "run",
                             netcdf=True)
        if result.interrupted:  # the part flown, which run_mission keeps: no flight here
            raise KeyboardInterrupt
        interrupts.raise_if_stopped()  # one while it was written stops the fleet too
        files = {p.name: p.read_bytes() for p in result.files}
    columns = result.record.columns
    t = columns["time_s"]
    keep = np.unique(np.searchsorted(t, np.arange(0.0, t[-1] + TRACK_STEP_S, TRACK_STEP_S)
                                     ).clip(0, len(t) - 1))
    entered = {}
    for transition in result.record.trace:
        if transition.to_state and transition.to_state not in entered:
            entered[transition.to_state] = transition.time_s
    return {"name": task["name"], "files": files, "time_s": t[keep],
            "lat": columns["lat_deg"][keep], "lon": columns["lon_deg"][keep],
            "energy_j": float(result.energy.total_j),
            "budget_j": float(result.plan.budget_j), "ended": result.record.ended,
            "entered": entered, "time_by_state_s": dict(result.energy.time_by_state_s)}


@contextmanager
def _run_folder(output_dir: str | Path, command: str, fleet: Fleet, plan: PlanToFly,
                force: bool, recognised: tuple[str, ...],
                inputs: Iterable) -> Iterator[tuple[OutputFolder, StoredPlan]]:
    """The run's folder (contract.files.output_folder) and the stored plan to fly: `plan`
    as stored (`fleet plan -o`), or made now by `plan()` and written into the folder's
    plan/. The folder is claimed first: one that cannot take the run is refused before
    minutes of planning."""
    names = (*recognised, *(g.name for g in fleet.gliders))
    stored_in = plan.directory if isinstance(plan, StoredPlan) else None
    with output_folder(output_dir, command=command, force=force, recognised=names,
                       inputs=(*inputs, stored_in)) as folder:
        if isinstance(plan, StoredPlan):
            yield folder, plan
        else:
            write_plan_dir(plan(), folder.sub(PLAN_DIR))
            stored = load_plan_dir(folder.path / PLAN_DIR, fleet)
            yield folder, replace(stored, directory=folder.final(PLAN_DIR))


def fly_fleet(fleet: Fleet, plan: PlanToFly, output_dir, *, workers: int = 1,
              scheduler: str | None = "local", seed: int = 0, ocean: str | None = None,
              current: tuple[float, float] = (0.0, 0.0), runtime: str = "python",
              lose: tuple[str, float] | None = None, progress: Progress | None = None,
              force: bool = False, inputs: Iterable = ()) -> dict:
    """Fly every glider of `plan` once (`gliderplan fleet sim`); write OUTPUT/GLIDER/ (its
    run files, trajectory.nc) and OUTPUT/fleet_sim.json, the map and the fleet page, a
    folder written whole (contract.files.output_folder: `force`, and `inputs`, the files
    read, refused inside it); a plan made now (`plan()`, called once the folder is
    claimed) is written into OUTPUT/plan.
    `ocean` as `run_mission`'s (default: uniform water, as the plans assume); `current`
    (north, east) [m/s] is the whole ocean's; each glider's sensor noise is
    seeded from `seed` and its place in the fleet. Returns fleet_sim.json's content.

    Ctrl-C or SIGTERM stops it at once: the gliders whose flights finished are written,
    fleet_sim.json `complete` false with no verdict on the survey (`finished` and the
    mapping error null: the survey was not flown); KeyboardInterrupt if none finished."""
    from gliderplan.sim.backends import gather, scenario_executor

    # what finished is written whole: a stop once it has is remembered (exit 130 or 143),
    # a second one abandons the writing and leaves the folder's previous run
    with interrupts.deferred(armed=False) as writing, \
            _run_folder(output_dir, "fleet sim", fleet, plan, force, SIM_FILES,
                        (*inputs, ocean)) as (folder, stored):
        tasks = []
        for n, glider in enumerate(stored.gliders):
            spec = fleet.glider(glider.name)
            duration = fleet.period_s - spec.start_offset_s
            if lose is not None and lose[0] == glider.name:
                duration = lose[1] - spec.start_offset_s
            tasks.append(({
                "name": glider.name, "mission_text": glider.mission_path.read_text(),
                "mission_name": str(stored.directory / glider.mission_path.name),
                "plan_bytes": glider.plan_path.read_bytes(),
                "runtime": runtime, "ocean": ocean, "current": current,
                "seed": int(np.random.SeedSequence([seed, n]).generate_state(1)[0]),
                "duration_s": duration,
                "start_utc": _utc(fleet.start_epoch_s + spec.start_offset_s)},))
        flights: dict[str, dict] = {}

        def collect(task: tuple, flight: dict) -> None:
            flights[flight["name"]] = flight
            if progress:
                progress(len(flights), len(tasks))

        with scenario_executor(min(workers, len(tasks)), scheduler) as executor:
            interrupted = gather(executor, _fly_one, tasks, collect)
        if not flights:
            raise KeyboardInterrupt  # nothing flown, nothing to write
        writing.arm()
        flown_gliders = [g for g in stored.gliders if g.name in flights]
        for glider in flown_gliders:
            for name, data in flights[glider.name]["files"].items():
                folder.sub(glider.name).write(name, data)
        meta = {"ocean": ocean, "current_mps": {"north": current[0], "east": current[1]},
                "runtime": runtime, "seed": seed, "workers": workers,
                "scheduler": scheduler or ("local pool" if workers > 1 else "none")}
        if interrupted:
            summary = _partial_sim(fleet, stored, [flights[g.name] for g in flown_gliders])
            summary.update(meta)
        else:
            outcomes = [_outcome_of_flight(fleet, g, flights[g.name])
                        for g in stored.gliders]
            summary = _survey(fleet, stored, outcomes, lose)
            summary.update(meta)
            if lose is not None:
                summary["lost"] = replan_after_loss(fleet, stored, lose,
                                                    summary["mapping_error"])
            flown = {g.name: np.column_stack([flights[g.name]["lon"],
                                              flights[g.name]["lat"],
                                              flights[g.name]["time_s"]])
                     for g in stored.gliders}
            _write_fleet_files(folder, fleet, stored, flown, sim=summary)
        folder.write("fleet_sim.json", json.dumps(summary, indent=1) + "\n")
        folder.complete = not interrupted
    return summary


def _partial_sim(fleet: Fleet, stored: StoredPlan, flights: list[dict]) -> dict:
    """fleet_sim.json of a run stopped before every glider flew: the flights that
    finished, and no verdict on the survey."""
    return {"fleet": fleet.name, "fleet_hash": fleet.hash, "plan": str(stored.directory),
            "complete": False, "interrupted": True, "flown": len(flights),
            "requested": len(stored.gliders), "finished": None, "mapping_error": None,
            "planned_mapping_error": stored.report["mapping_error"],
            "gliders": [{"name": f["name"], "energy_j": f["energy_j"],
                         "budget_j": f["budget_j"], "ended": f["ended"]} for f in flights]}


def _outcome_of_flight(fleet: Fleet, glider: StoredGlider, flight: dict) -> GliderOutcome:
    """A flight judged from where it went: its segments' states entered and left, the
    positions flown, thinned every quarter of the field's length scale."""
    track = glider.track
    segments = len(track.segment_ends)
    entered = flight["entered"]
    done = 0
    for k in range(1, segments + 1):
        after = f"seg{k + 1}" if k < segments else None
        finished_k = (after in entered) if after else flight["ended"] == "exit"
        if not finished_k:
            break
        done = k
    x, y = fleet.projection.to_xy(flight["lat"], flight["lon"])
    t = np.asarray(flight["time_s"], float)
    step = np.hypot(np.diff(x), np.diff(y))
    along = np.concatenate([[0.0], np.cumsum(step)])
    spacing = sample_spacing(fleet)
    marks = np.arange(spacing / 2.0, along[-1], spacing) if along[-1] > 0 else np.zeros(0)
    samples = (track.start_offset_s + np.interp(marks, along, t), np.interp(marks, along, x),
               np.interp(marks, along, y))
    ends = track.distance_m[list(track.segment_ends)]
    return GliderOutcome(glider.name, flight["energy_j"], flight["budget_j"],
                         flight["energy_j"] <= flight["budget_j"] and flight["ended"] != "reserve",
                         flight["ended"], done >= first_pass_segment(track), done,
                         _lines_swept(track, ends[done - 1] if done else 0.0), samples)


def _survey(fleet: Fleet, stored: StoredPlan, outcomes: list[GliderOutcome],
            lose: tuple[str, float] | None) -> dict:
    from gliderplan.planner.fleet_mapping import combined, evaluation_grid, mapping_error

    grid = evaluation_grid(fleet)
    error, _ = mapping_error(combined([o.samples for o in outcomes]), grid, fleet.field)
    finished = all(o.swept and o.held for o in outcomes)
    return {"fleet": fleet.name, "fleet_hash": fleet.hash, "plan": str(stored.directory),
            "complete": True, "interrupted": False, "flown": len(outcomes),
            "requested": len(stored.gliders), "finished": finished, "mapping_error": error,
            "planned_mapping_error": stored.report["mapping_error"],
            "gliders": [{"name": o.name, "energy_j": o.energy_j, "budget_j": o.budget_j,
                         "held": o.held, "ended": o.ended, "swept": o.swept,
                         "segments_done": o.segments_done, "lines_swept": o.lines_swept,
                         "lost": lose is not None and lose[0] == o.name}
                        for o in outcomes]}


def _utc(epoch_s: float) -> str:
    from gliderplan.sim.export import utc_text

    return utc_text(epoch_s)


def _write_fleet_files(folder: OutputFolder, fleet: Fleet, stored: StoredPlan,
                       flown: dict | None, sim: dict | None = None,
                       montecarlo: dict | None = None) -> None:
    from gliderplan.reports import fleet as drawing

    files = drawing.map_files(fleet, stored.report, flown=flown)
    for name, data in files.items():
        folder.write(name, data)
    folder.write("fleet.html", drawing.page(fleet, stored.report, flown=flown, sim=sim,
                                            montecarlo=montecarlo, png=files["fleet.png"]))


# ---- a lost glider -----------------------------------------------------------------------

def replan_after_loss(fleet: Fleet, stored: StoredPlan, lose: tuple[str, float],
                      flown_error: float | None = None, scenario_file=None) -> dict:
    """What the rest of the fleet can still cover when `lose` = (glider, time) is lost:
    the mapping error with its lines left unswept after the loss, and with the fleet
    planned again from then (each survivor where its plan has it, with its budget less
    what its plan spent so far), both over the whole period (the profiles taken before
    the loss count). The re-plan draws its scenarios from `scenario_file` (as
    `plan_fleet`)."""
    from gliderplan.language.ir import Battery
    from gliderplan.planner.fleet import UnreachableGliders, coverage, plan_fleet
    from gliderplan.planner.fleet_mapping import combined, evaluation_grid, mapping_error

    name, at = lose
    # until when each glider flies its own plan: the lost one until the loss
    until = {g.name: at if g.name == name else fleet.period_s for g in stored.gliders}
    spacing = sample_spacing(fleet)
    grid = evaluation_grid(fleet)
    before, after = [], {}  # each glider's samples up to the loss; the others' after it
    for glider in stored.gliders:
        t, x, y = glider.track.samples(spacing)
        early = t <= at
        before.append((t[early], x[early], y[early]))
        if glider.name != name:
            after[glider.name] = (t[~early], x[~early], y[~early])
    untouched, _ = mapping_error(combined(before + list(after.values())), grid, fleet.field)
    survivors = []
    for glider in stored.gliders:
        if glider.name == name:
            continue
        spec = fleet.glider(glider.name)
        entry = glider.report
        share = min(max((at - spec.start_offset_s) / max(entry["end_s"], 1.0), 0.0), 1.0)
        left = spec.usable_j - share * entry["energy_j"]
        x, y = glider.track.position_at(np.array([at]))
        charge = (left + spec.battery.reserve_fraction * spec.battery.energy_j) \
            / spec.battery.energy_j
        if left <= 0.0 or at >= spec.start_offset_s + entry["end_s"]:
            continue
        survivors.append(replace(spec, start=(float(x[0]), float(y[0])),
                                 start_offset_s=max(at, spec.start_offset_s),
                                 charge=min(charge, 1.0),
                                 battery=Battery(spec.battery.energy_j,
                                                 spec.battery.reserve_fraction)))
    lost_track = next(g.track for g in stored.gliders if g.name == name)
    visits = {part: [lost_track.start_offset_s + float(lost_track.time_at(d)) for d in seen]
              for part, seen in lost_track.line_visits.items()}
    result = {"glider": name, "at_s": at, "mapping_error_without_replan": untouched,
              "coverage_without_replan": coverage(fleet, [(g.track, until[g.name])
                                                          for g in stored.gliders]),
              "lines": sorted(visits),
              "lines_swept_before": sorted(p for p, t in visits.items() if t and t[0] <= at),
              "survivors": [s.name for s in survivors]}
    if flown_error is not None:
        result["mapping_error_flown"] = flown_error
    if not survivors:
        result["summary"] = "no glider is left to cover its lines"
        return result
    # every line swept before the loss: the survey is finished, and the others need only
    # keep mapping; else they must sweep what is left, at the fleet's confidence or at
    # even odds (what they can promise is part of the answer). A survivor with no line it
    # can reach in time keeps flying its own plan.
    finished = len(result["lines_swept_before"]) == len(visits)
    tries = [(None, False)] if finished else [(fleet.confidence, True), (0.5, True)]
    again, reason, asked, kept = None, None, None, []
    for confidence, sweep in tries:
        joining = list(survivors)
        while joining and again is None:
            try:
                again = plan_fleet(replace(fleet, gliders=tuple(joining),
                                           confidence=confidence or fleet.confidence),
                                   seed=0, scenario_file=scenario_file, require_sweep=sweep)
                asked = confidence
            except UnreachableGliders as err:
                reason = err
                joining = [g for g in joining if g.name not in err.names]
            except GliderplanError as err:
                reason = err
                break
        if again is not None:
            kept = [g.name for g in survivors if g not in joining]
            break
    swept = (f"it had swept {len(result['lines_swept_before'])} of its {len(visits)} "
             "lines once")
    if again is None:
        result["replan"] = None
        result["summary"] = (f"{swept}; they stay unswept after the loss (the rest flying "
                             f"their plans cover {100 * result['coverage_without_replan']:.0f} "
                             f"% of the lines' length, mapping error {untouched:.3f}), and "
                             f"cannot take them over: {reason}")
        return result
    later = [glider.track.samples(spacing) for glider in again.gliders]
    later += [after[k] for k in kept]
    replanned, _ = mapping_error(combined(before + later), grid, fleet.field)
    covered = coverage(fleet, [(g.track, at if g.name not in kept else until[g.name])
                               for g in stored.gliders]
                       + [(g.track, fleet.period_s) for g in again.gliders])
    result["replan"] = {
        "mapping_error": replanned,
        "coverage": covered,
        "sweep_required": not finished,
        "confidence": asked,
        "confidence_lower_bound": again.validation.lower_bound,
        "gliders": [{"name": g.name, "parts": list(g.parts)} for g in again.gliders],
        "keep_their_plan": kept}
    promise = ("keep mapping them" if finished else
               f"sweep every line again by the finish in at least "
               f"{100 * again.validation.lower_bound:.0f} % of scenarios")
    aside = f" ({', '.join(kept)} cannot reach another line in time and keep their plan)" \
        if kept else ""
    result["summary"] = (f"{swept}{', so the survey is finished' if finished else ''}; left as "
                         f"planned, its lines go unswept from then on (the rest flying "
                         f"their plans cover {100 * result['coverage_without_replan']:.0f} % "
                         f"of the lines' length, mapping error {untouched:.3f} over the "
                         f"period); planned again from then, {len(again.gliders)} others "
                         f"share all the lines and {promise} (coverage {100 * covered:.0f} %, "
                         f"mapping error {replanned:.3f}){aside}")
    return result


# ---- Monte Carlo ---------------------------------------------------------------------------

def montecarlo_fleet(fleet: Fleet, plan: PlanToFly, output_dir, *,
                     scenarios: int, workers: int = 1, scheduler: str | None = "local",
                     seed: int = 0, scenario_file=None, lose: tuple[str, float] | None = None,
                     progress: Progress | None = None, force: bool = False,
                     inputs: Iterable = ()) -> dict:
    """Fly every glider in `scenarios` scenarios (`gliderplan fleet montecarlo`); write
    OUTPUT/scenarios.parquet (a row per glider and scenario), OUTPUT/summary.json, the
    histogram of the realised mapping error, the map and the fleet page, a folder written
    whole (as `fly_fleet`'s). Returns summary.json's content. Ctrl-C or SIGTERM stops it
    at once and keeps the scenarios every glider finished, never one cut short: the
    summary says `complete` false and gives no finish probability (those that finished
    are not the sample asked for); KeyboardInterrupt if none."""
    from gliderplan.language import check_file
    from gliderplan.sim import montecarlo
    from gliderplan.sim.backends import check_run_size, gather, scenario_executor
    from gliderplan.sim.scenarios import read_spec
    from gliderplan.sim.setup import FlightOptions, flight_setup

    check_run_size(scenarios, workers)
    spec = read_spec(scenario_file)
    with interrupts.deferred(armed=False) as writing, \
            _run_folder(output_dir, "fleet montecarlo", fleet, plan, force, MONTECARLO_FILES,
                        (*inputs, scenario_file)) as (folder, stored):
        jobs = {}
        for glider in stored.gliders:
            mission = check_file(str(glider.mission_path)).checked()
            g = fleet.glider(glider.name)
            duration = fleet.period_s - g.start_offset_s
            if lose is not None and lose[0] == glider.name:
                duration = lose[1] - g.start_offset_s
            options = FlightOptions(plan_path=glider.plan_path, seed=seed, duration_s=duration)
            jobs[glider.name] = montecarlo.Job(flight_setup(mission, options), spec)
        # one scenario of one glider per task: a flight of days takes far longer than
        # sending it (montecarlo.BATCH_S), progress is seen, and a stop keeps each one
        # that finished
        work = [(name, [i]) for i in range(scenarios) for name in jobs]
        rows: dict[str, dict[int, dict]] = {name: {} for name in jobs}
        started = time.perf_counter()
        total = len(jobs) * scenarios

        def collect(task: tuple, flown: list[dict]) -> None:
            name = next(n for n, job in jobs.items() if job is task[0])
            rows[name].update((row["scenario"], row) for row in flown)
            if progress:
                progress(sum(map(len, rows.values())), total)

        with scenario_executor(workers, scheduler) as executor:
            interrupted = gather(executor, montecarlo.run_batch,
                                 [(jobs[name], batch) for name, batch in work], collect)
        # a scenario counts once every glider flew it to its end
        common = sorted(set.intersection(*(
            {i for i, row in r.items() if row["ended"] != "interrupted"}
            for r in rows.values())))
        if not common:
            raise KeyboardInterrupt  # nothing finished, nothing to write
        writing.arm()
        summary, table = _montecarlo_summary(fleet, stored, rows, common, lose,
                                             complete=not interrupted)
        summary.update(requested=scenarios, interrupted=interrupted, seed=seed,
                       workers=workers,
                       scheduler=scheduler or ("local pool" if workers > 1 else "none"),
                       scenario_file=spec.source, wall_s=time.perf_counter() - started)
        if lose is not None:
            summary["lost"] = replan_after_loss(fleet, stored, lose,
                                                scenario_file=scenario_file)
        _write_montecarlo(folder, fleet, stored, summary, table)
        folder.complete = not interrupted
    return summary


def _montecarlo_summary(fleet: Fleet, stored: StoredPlan, rows: dict, common: list[int],
                        lose, complete: bool = True) -> tuple[dict, object]:
    """summary.json and the table of the scenarios `common` (flown by every glider). Not
    `complete` (interrupted): no finish probability nor interval."""
    import pandas as pd

    from gliderplan.planner.fleet_mapping import (
        combined,
        evaluation_grid,
        mapping_error,
        one_blas_thread,
    )
    from gliderplan.sim.montecarlo import QUANTILES, wilson_interval

    grid = evaluation_grid(fleet)
    spacing = sample_spacing(fleet)
    records, finished, errors = [], 0, []
    with one_blas_thread():  # a mapping error per scenario: small matrices
        for index in common:
            outcomes = []
            for glider in stored.gliders:
                row = rows[glider.name][index]
                outcomes.append(_outcome_of_row(fleet, glider, row, spacing))
            done = all(o.swept and o.held for o in outcomes)
            finished += done
            error, _ = mapping_error(combined([o.samples for o in outcomes]), grid, fleet.field)
            errors.append(error)
            for o in outcomes:
                row = rows[o.name][index]
                records.append({"scenario": index, "glider": o.name, "energy_j": o.energy_j,
                                "budget_j": o.budget_j, "held": o.held, "ended": o.ended,
                                "swept": o.swept, "segments_done": o.segments_done,
                                "lines_swept": o.lines_swept, "fleet_finished": done,
                                "mapping_error": error,
                                "current_mps": row.get("drawn_current_speed_mps", math.nan),
                                "current_toward_deg": row.get("drawn_current_direction_deg",
                                                              math.nan),
                                "duration_s": row["duration_s"]})
    table = pd.DataFrame(records)
    n = len(common)
    low, high = wilson_interval(finished, n)

    def quantiles(values) -> dict[str, float]:
        found = np.quantile(np.asarray(values, float), QUANTILES)
        return {f"p{round(100 * q):02d}": float(v) for q, v in zip(QUANTILES, found,
                                                                   strict=True)}

    summary = {
        "fleet": fleet.name, "fleet_hash": fleet.hash, "plan": str(stored.directory),
        "complete": complete, "scenarios": n, "finished": finished,
        "finish_probability": finished / n if n and complete else None,
        "finish_interval": [low, high] if complete else None,
        "planned_confidence": fleet.confidence,
        "planned_mapping_error": stored.report["mapping_error"],
        "mapping_error": quantiles(errors),
        "energy_j": {g.name: quantiles(table.loc[table.glider == g.name, "energy_j"])
                     for g in stored.gliders},
        "gliders": [{"name": g.name,
                     "budget_held": int(table.loc[table.glider == g.name, "held"].sum()),
                     "swept": int(table.loc[table.glider == g.name, "swept"].sum()),
                     "budget_j": float(table.loc[table.glider == g.name, "budget_j"].median())}
                    for g in stored.gliders],
    }
    return summary, table


def _outcome_of_row(fleet: Fleet, glider: StoredGlider, row: dict,
                    spacing: float) -> GliderOutcome:
    """A Monte Carlo row (time in each state) as a survey flight."""
    track = glider.track
    times = []
    for k in range(1, len(track.segment_ends) + 1):
        spent = row.get(f"time_seg{k}_s", 0.0)
        if spent <= 0.0:
            break
        times.append(spent)
    ended_in = row.get("end_state", "")
    partial = 1.0
    if times and ended_in == f"seg{len(times)}" and row["ended"] != "exit":
        ends = track.distance_m[list(track.segment_ends)]
        k = len(times) - 1
        planned = (ends[k] - (ends[k - 1] if k else 0.0)) / track.speed_mps
        partial = min(times[-1] / max(planned, 1.0), 0.999)
    window = fleet.period_s - track.start_offset_s
    return outcome_from_segments(glider.name, track, times, partial, row["energy_j"],
                                 row["budget_j"], bool(row["held"]) and row["ended"] != "reserve",
                                 row["ended"], window, spacing)


def _write_montecarlo(folder: OutputFolder, fleet: Fleet, stored: StoredPlan, summary: dict,
                      table) -> None:
    import pyarrow as pa

    from gliderplan.reports.figures import pyplot, render
    from gliderplan.sim.outputs import parquet_bytes

    folder.write("scenarios.parquet",
                 parquet_bytes(pa.Table.from_pandas(table, preserve_index=False)))
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    errors = table.drop_duplicates("scenario")["mapping_error"].to_numpy(float)
    ax.hist(errors, bins=min(30, max(5, len(errors) // 4)), color="#1b6ca8", alpha=0.8)
    ax.axvline(summary["planned_mapping_error"], color="#d1495b", lw=1.5, label="planned")
    ax.set_xlabel("realised mapping error (share of the field's variance)")
    ax.set_ylabel("scenarios")
    ax.set_title(f"{fleet.name}: finished in {summary['finished']} of {summary['scenarios']} "
                 "scenarios" + ("" if summary["complete"] else
                                f" (interrupted: {summary['requested']} asked)"), fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    folder.write("mapping_error.png", render(fig, "png"))
    _write_fleet_files(folder, fleet, stored, None, montecarlo=summary)
    folder.write("summary.json", json.dumps(summary, indent=1) + "\n")
