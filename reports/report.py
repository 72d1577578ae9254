"""`make_report`: the offline tradeoff report of one mission, the pipeline of `gliderplan report`.

It plans the mission (or reads the plan given), sweeps quality against budget, flies the
plan on the simulated glider (or reads a run given), compares the boards, moves every
model figure by its uncertainty, and writes `report.html` (one self-contained page) and
the CSV file behind every figure into one directory.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from gliderplan.contract import TICK_S, ExitCode, interrupts
from gliderplan.contract.errors import UsageError
from gliderplan.contract.files import (
    InputFileError,
    OutputFolder,
    output_folder,
    read_data,
    read_input,
)
from gliderplan.contract.units import J_PER_WH
from gliderplan.language.ir import CheckedMission
from gliderplan.reports import charts
from gliderplan.reports.html import Section, Table, esc, facts_html, page

if TYPE_CHECKING:
    from gliderplan.planner.planfile import Plan

SWEEP_POINTS = 20  # budgets on the Pareto curve
QUALITY_TOLERANCE = 1e-4  # [1] a plan this close to the curve's quality is on it
PROFILE_ROWS = 4000  # the depth profile is drawn (and its CSV written) at most this dense
HTML = "report.html"
# what a report's folder holds (a folder holding only these is an earlier report's)
REPORT_FILES = (HTML, "pareto.csv", "energy_by_state.csv", "speed.csv", "vehicles.csv",
                "plan_vs_simulation.csv", "profile.csv", "track.csv", "sbc_boards.csv",
                "sbc_workload.csv", "sbc_crossovers.csv", "sensitivity.csv",
                "montecarlo.csv", "run")


@dataclass(frozen=True)
class Report:
    html: Path
    files: tuple[Path, ...]  # every file written, the page first
    sections: tuple[str, ...]  # ids of the page's sections, in order


def _wh(joules: float) -> float:
    return joules / J_PER_WH


def _json(path: Path, what: str) -> dict:
    try:
        return read_data(path, "JSON file", finite=False)  # a summary may hold NaN
    except InputFileError as err:  # say what the file should have been
        raise InputFileError(f"{err} ({what})", usage=err.exit_code == ExitCode.USAGE) \
            from None


def _regular(path: Path, what: str) -> None:
    """Refuse what is no regular file before pyarrow reads it whole (a named pipe would
    block it); the input limit does not apply to a month's run (contract.files)."""
    try:
        read_input(path, what, head=0)
    except InputFileError as err:
        raise UsageError(str(err)) from None


# ---- the plan ------------------------------------------------------------------------

def _plan_report(mission: CheckedMission, model, plan_path: Path | None, out: OutputFolder
                 ) -> tuple[Plan, dict, Path, list[Path]]:
    """(the plan as its file holds it, the planner's JSON report of it, the plan file,
    files written): the plan given with its report beside it (PLAN.json), or the plan
    made now, written to the folder `out` (the file where it is written now; the files
    where they will be). The report flies and draws this plan: its file is read once."""
    from gliderplan.planner.plan import solve_plan
    from gliderplan.planner.planfile import load_plan, read_plan_bytes, write_plan_bytes
    from gliderplan.planner.report import report_json

    if plan_path is not None:
        plan = load_plan(plan_path, mission)  # a sane plan for this mission, or a clear error
        report = _json(Path(f"{plan_path}.json"), "the plan's report, written beside it by "
                       "`gliderplan plan -o PLAN`")
        if report.get("hash") != mission.hash or not isinstance(report.get("states"), list):
            raise UsageError(f"{plan_path}.json: not the report of a plan for this mission")
        differs = _differs(report, plan)
        if differs:
            raise UsageError(f"{plan_path}.json: not the report of {plan_path} ({differs} "
                             "differ): plan again with `gliderplan plan -o PLAN`, which "
                             "writes both")
        if "budgeted_energy_j" not in report:
            raise UsageError(f"{plan_path}.json: made by an older gliderplan (no "
                             "budgeted_energy_j, the plan's place on the Pareto curve): plan "
                             "again with `gliderplan plan -o PLAN`")
        return plan, report, plan_path, []
    result = solve_plan(model)
    name = f"{mission.name}.plan"
    report = report_json(result)
    data = write_plan_bytes(result.plan)
    files = [out.write(name, data),
             out.write(f"{name}.json", json.dumps(report, indent=2) + "\n")]
    return read_plan_bytes(data, mission), report, out.path / name, files


def _differs(report: dict, plan: Plan) -> str:
    """What of a plan's JSON report is not the plan's own figure as its file writes it
    (9 significant digits): its budget, prediction, states, their times and sensor
    schedules ("" when nothing)."""
    from gliderplan.planner.planfile import number

    def figures(entry: object, keys: tuple[str, ...]) -> tuple:
        if not isinstance(entry, dict):
            return ()
        return tuple(number(float(v)) if isinstance(v := entry.get(k), (int, float))
                     and not isinstance(v, bool) else v for k in keys)

    states = report["states"]
    if [s.get("name") if isinstance(s, dict) else None for s in states] != \
            [s.name for s in plan.states]:
        return "the states"
    wrong = [what for what, given, own in (
        ("budget_j", figures(report, ("budget_j",)), (number(plan.budget_j),)),
        ("energy_j", figures(report, ("energy_j",)), (number(plan.predicted_j),)),
        *((f"{s.name}'s time_s", figures(r, ("time_s",)), (number(s.time_s),))
          for r, s in zip(states, plan.states, strict=True)),
        *((f"{s.name}'s sensors",
           tuple(figures(x, ("name", "period_s", "on_s")) for x in r.get("sensors")
                 if isinstance(r.get("sensors"), list)),
           tuple((x.name, number(x.period_s), number(x.on_s)) for x in s.sensors))
          for r, s in zip(states, plan.states, strict=True)))
        if given != own]
    return ", ".join(wrong[:3])


def _energy_frame(report: dict) -> pd.DataFrame:
    """Energy [Wh] of each state by component (energy_by_state.csv)."""
    components = list(report["components_j"])
    rows = [{"state": s["name"],
             **{f"{c}_wh": _wh(s["energy_by_component_j"].get(c, 0.0)) for c in components},
             "total_wh": _wh(s["energy_j"])} for s in report["states"]]
    return pd.DataFrame(rows)


# ---- the run ---------------------------------------------------------------------------

def _read_run(mission: CheckedMission, run_dir: Path) -> tuple[dict, pd.DataFrame]:
    """(summary.json, time series) of a `gliderplan sim` run of `mission`."""
    import pyarrow.parquet as pq

    summary = _json(run_dir / "summary.json", "the run's summary, written by `gliderplan sim`")
    if summary.get("mission_hash") != mission.hash:
        raise UsageError(f"{run_dir}: a run of another mission (or of another version of it)")
    if summary.get("complete") is False or summary.get("ended") == "interrupted":
        raise UsageError(f"{run_dir}: a partial run, interrupted after "
                         f"{summary.get('simulated_s', 0):g} s (summary.json: complete "
                         "false): fly it again to the end")
    try:
        _regular(run_dir / "timeseries.parquet", "run's time series")
        series = pq.read_table(run_dir / "timeseries.parquet",
                               columns=["time_s", "depth_m", "temperature_c", "state",
                                        "lat_deg", "lon_deg"]
                               ).to_pandas()
    except (OSError, KeyError, ValueError) as err:
        raise UsageError(f"{run_dir}/timeseries.parquet: cannot read the run's time "
                         f"series: {err}") from None
    return summary, series


def _plan_vs_sim_frame(summary: dict, report: dict) -> pd.DataFrame:
    """Per state: predicted and simulated energy [Wh] and time [h] (plan_vs_simulation.csv)."""
    flown = summary.get("states", {})
    rows = []
    for state in report["states"]:
        sim = flown.get(state["name"], {})
        rows.append({"state": state["name"], "predicted_wh": _wh(state["energy_j"]),
                     "simulated_wh": _wh(sim.get("simulated_j", 0.0)),
                     "predicted_h": state["time_s"] / 3600.0,
                     "simulated_h": sim.get("time_s", 0.0) / 3600.0})
    frame = pd.DataFrame(rows)
    with np.errstate(divide="ignore", invalid="ignore"):
        frame["difference_pct"] = 100 * (frame["simulated_wh"] / frame["predicted_wh"] - 1)
    return frame


def _profile_frame(series: pd.DataFrame) -> pd.DataFrame:
    """Depth and water temperature against time (profile.csv), every k-th tick."""
    step = max(1, math.ceil(len(series) / PROFILE_ROWS))
    thin = series.iloc[::step]
    return pd.DataFrame({"time_h": thin["time_s"].to_numpy() / 3600.0,
                         "depth_m": thin["depth_m"].to_numpy(),
                         "temperature_c": thin["temperature_c"].to_numpy(),
                         "state": thin["state"].astype(str).to_numpy()})


def _track_frame(series: pd.DataFrame) -> pd.DataFrame:
    """The flown track (track.csv): time and true position, every k-th tick."""
    thin = series.iloc[::max(1, math.ceil(len(series) / PROFILE_ROWS))]
    return pd.DataFrame({"time_h": thin["time_s"].to_numpy() / 3600.0,
                         "lat_deg": thin["lat_deg"].to_numpy(),
                         "lon_deg": thin["lon_deg"].to_numpy()})


def _track_section(mission: CheckedMission, frame: pd.DataFrame, summary: dict) -> Section:
    from gliderplan.sim.loop import route_points_deg
    from gliderplan.sim.seamap import SeaMap, image

    fixes = summary.get("surfacing_fixes", [])
    figure = image(SeaMap("", {"flown": (frame["lat_deg"].to_numpy(),
                                         frame["lon_deg"].to_numpy())},
                          tuple(route_points_deg(mission)), tuple(fixes)), "svg")
    return Section("track", "Track at sea", (
        f"<p>The simulated glider's true track, its {len(fixes)} surfacings' GPS fixes and "
        "the mission's waypoints (<code>gliderplan forecast --map</code> draws the forecast "
        "surfacings with their 90 % ellipses and the current field).</p>",),
        figure.decode("utf-8"), "Latitude against longitude [deg].", ("track.csv",))


# ---- Monte Carlo ----------------------------------------------------------------------

def _montecarlo(directory: Path, mission: CheckedMission) -> tuple[pd.DataFrame, dict]:
    """(one row per scenario in Wh and h: montecarlo.csv, the summary) of a
    `gliderplan montecarlo` result directory."""
    summary = _json(directory / "summary.json", "the Monte Carlo summary, written by "
                    "`gliderplan montecarlo`")
    if summary.get("mission_hash") != mission.hash:
        raise UsageError(f"{directory}: Monte Carlo of another mission (or of another "
                         "version of it)")
    if summary.get("complete") is False or summary.get("interrupted"):
        raise UsageError(f"{directory}: a partial Monte Carlo, interrupted after "
                         f"{summary.get('scenarios', '?')} of {summary.get('requested', '?')} "
                         "scenarios (summary.json: complete false): run it again to the end")
    try:
        _regular(directory / "scenarios.parquet", "Monte Carlo table")
        table = pd.read_parquet(directory / "scenarios.parquet",
                                columns=["scenario", "energy_j", "budget_j", "held",
                                         "duration_s", "exhausted_s", "quality", "ended"])
    except (OSError, KeyError, ValueError) as err:
        raise UsageError(f"{directory}/scenarios.parquet: cannot read the scenarios: "
                         f"{err}") from None
    frame = pd.DataFrame({
        "scenario": table["scenario"], "energy_wh": table["energy_j"] / J_PER_WH,
        "budget_wh": table["budget_j"] / J_PER_WH, "held": table["held"],
        "duration_h": table["duration_s"] / 3600.0,
        "exhausted_h": table["exhausted_s"] / 3600.0, "quality": table["quality"],
        "ended": table["ended"]})
    return frame, summary


# ---- the page ---------------------------------------------------------------------------

def make_report(mission: CheckedMission, output_dir: str | Path, *,
                plan_path: str | Path | None = None, run_dir: str | Path | None = None,
                montecarlo_dir: str | Path | None = None, source: str = "",
                sweep_points: int = SWEEP_POINTS, force: bool = False,
                currents: str | None = None, start: tuple[float, float] | None = None,
                start_utc: str | None = None) -> Report:
    """Write the report of `mission` into `output_dir`: report.html and its CSV files,
    a folder written whole (contract.files.output_folder; `force`: replace a folder
    holding other files than a gliderplan run's). Interrupted, it writes nothing; a run
    or a Monte Carlo given that was interrupted (marked partial) is refused.

    `plan_path`: a plan made by `gliderplan plan -o PLAN` (its report PLAN.json beside
    it); without one the mission is planned now and the plan written beside the page.
    `run_dir`: a `gliderplan sim` run of that plan; without one the plan is flown now
    into `output_dir`/run. `montecarlo_dir`: a `gliderplan montecarlo` result, shown
    when given. `source`: the mission file's name, for the summary. With `currents` (as
    `plan --currents`, from `start` (lat, lon [deg]) at `start_utc`), the mission is
    planned, drawn and flown in that water. Raises a GliderplanError for any input that
    cannot be used."""
    out = Path(output_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory (report writes several files there)")
    for given, what in ((run_dir, "--run"), (montecarlo_dir, "--montecarlo")):
        if given is not None and not Path(given).is_dir():
            raise UsageError(f"{what} {given}: no such directory")
    plan_files = (f"{mission.name}.plan", f"{mission.name}.plan.json")
    with output_folder(out, command="report", force=force,
                       recognised=(*REPORT_FILES, *plan_files),
                       inputs=(source or None, plan_path, run_dir, montecarlo_dir)) as folder:
        return _write_report(mission, folder, plan_path, run_dir, montecarlo_dir, source,
                             sweep_points, currents, start, start_utc)


def _write_report(mission: CheckedMission, folder: OutputFolder, plan_path, run_dir,  # noqa: ANN001
                  montecarlo_dir, source: str, sweep_points: int, currents: str | None,
                  start: tuple[float, float] | None, start_utc: str | None) -> Report:
    from gliderplan.planner.compare import compare_boards
    from gliderplan.planner.hardware import load_hardware
    from gliderplan.planner.plan import prepare
    from gliderplan.planner.sensitivity import sensitivity
    from gliderplan.planner.sweep import pareto
    from gliderplan.reports import sbc
    from gliderplan.reports.speed import COMPARED_VEHICLES, speed_frame, vehicles_frame

    # what was given is read first: a wrong directory fails before anything is computed
    flown = _read_run(mission, Path(run_dir)) if run_dir else None
    carlo = _montecarlo(Path(montecarlo_dir), mission) if montecarlo_dir else None
    hardware = load_hardware(mission)
    if currents is not None:
        from gliderplan.planner.water import in_water
        from gliderplan.sim.export import parse_utc

        try:
            epoch = parse_utc(start_utc) if start_utc else None
        except ValueError as err:
            raise UsageError(f"--start: {err}") from None
        hardware = in_water(hardware, mission, currents, start, epoch)
    _, model = prepare(mission, hardware)
    comparison = compare_boards(mission)  # before anything is written: it may refuse
    plan, report, plan_file, written = _plan_report(
        mission, model, Path(plan_path) if plan_path else None, folder)
    shown_plan = Path(plan_path) if plan_path else folder.final(plan_file.name)
    frontier = pareto(model, sweep_points)
    tornado = sensitivity(model)
    run_path = Path(run_dir) if run_dir else folder.final("run")
    run_origin = "the run given"
    if flown is None:
        from gliderplan.sim import FlightOptions, flight_setup, run_mission

        options = FlightOptions(plan_path=plan_file, currents=currents, start_utc=start_utc,
                                start_position=start)
        run_mission(flight_setup(mission, options, plan=plan), folder.path / "run",
                    plots=False)
        interrupts.raise_if_stopped()  # a flight cut short is no flight to report
        flown = _read_run(mission, folder.path / "run")
        run_origin = ("flown now on the simulated glider (Python executor, bench ocean) "
                      f"into {run_path}")
    summary, series = flown

    tables = {
        "pareto.csv": frontier,
        "energy_by_state.csv": _energy_frame(report),
        "plan_vs_simulation.csv": _plan_vs_sim_frame(summary, report),
        "profile.csv": _profile_frame(series),
        "track.csv": _track_frame(series),
        "sbc_boards.csv": sbc.boards_frame(comparison),
        "sbc_workload.csv": sbc.workload_frame(comparison),
        "sbc_crossovers.csv": sbc.crossovers_frame(comparison),
        "sensitivity.csv": _sensitivity_frame(tornado),
    }
    if carlo is not None:
        tables["montecarlo.csv"] = carlo[0]
    speeds = speed_frame(mission, hardware, plan)
    vehicles = None
    if len(speeds):
        from gliderplan.planner.vehicles import compare_vehicles, crossovers, flies_on

        tables["speed.csv"] = speeds
        compared = compare_vehicles(mission, [  # those that can fly it: a glider no cruise
            spec for spec in dict.fromkeys([mission.vehicle, *COMPARED_VEHICLES])
            if flies_on(mission, spec)])
        tables["vehicles.csv"] = vehicles_frame(compared)
        vehicles = _vehicles_section(tables["vehicles.csv"], crossovers(compared))
    sections = [
        _summary_section(mission, source, hardware, report, shown_plan, summary, run_origin),
        _pareto_section(frontier, report, _star(model, frontier, report), shown_plan),
        _energy_section(tables["energy_by_state.csv"]),
        *([_speed_section(speeds), vehicles] if vehicles is not None else []),
        _plan_vs_sim_section(tables["plan_vs_simulation.csv"], summary, run_path, run_origin),
        _profile_section(tables["profile.csv"], len(series)),
        _track_section(mission, tables["track.csv"], summary),
        _sbc_section(comparison, tables),
        _sensitivity_section(tornado, tables["sensitivity.csv"]),
    ]
    if carlo is not None:
        sections.append(_montecarlo_section(*carlo, Path(montecarlo_dir)))
    interrupts.raise_if_stopped()
    for name, frame in tables.items():
        written.append(folder.write(name, frame.to_csv(index=False)))
    title = f"{mission.name}: tradeoff report"
    subtitle = (f"mission {source or mission.name} (hash {mission.hash[:12]}), planned on "
                f"{_computer(report)}; "
                "every figure's numbers are in the CSV file named under it")
    html_path = folder.write(HTML, page(title, subtitle, sections))
    return Report(html_path, (html_path, *written), tuple(s.id for s in sections))


def _computer(report: dict) -> str:
    """The plan report's computer as people read it."""
    from gliderplan.planner.planfile import computer_text

    return computer_text(report["computer"]["board"], report["computer"]["clock_mhz"])


# ---- sections ---------------------------------------------------------------------------

def _verdict(summary: dict) -> str:
    check = summary.get("plan_check", {})
    verdict = check.get("verdict", "no plan")
    simulated, predicted, budget = (check.get(k) for k in ("simulated_j", "predicted_j",
                                                           "budget_j"))
    text = f'<span class="verdict-{esc(verdict.replace(" ", "-"))}">{esc(verdict)}</span>'
    if simulated is not None and predicted:
        text += (f": simulated {_wh(simulated):,.4g} Wh against {_wh(predicted):,.4g} Wh "
                 f"predicted ({100 * (simulated / predicted - 1):+.1f} %)")
    if simulated is not None and budget:
        text += f" and a budget of {_wh(budget):,.4g} Wh ({100 * simulated / budget:.1f} % used)"
    causes = check.get("causes") or []
    if causes:  # below the run's one verdict: the states that overran their own prediction
        text += "<br>states over their own prediction: " + esc("; ".join(causes))
    return text


def _battery_text(report: dict, hardware) -> str:
    """The battery the plan was made for (`plan --battery` may have replaced the
    mission's; its report says which), else the mission's."""
    battery = report.get("battery") or {}
    if not battery.get("energy_j"):  # a report of an older gliderplan
        battery = {"energy_j": hardware.battery_j, "reserve_fraction": hardware.reserve_fraction}
    energy_j, reserve = battery["energy_j"], battery["reserve_fraction"]
    return f"{_wh(energy_j):,.4g} Wh, reserve {100 * reserve:.3g} %"


def _summary_section(mission: CheckedMission, source: str, hardware, report: dict,
                     plan_file: Path, summary: dict, run_origin: str) -> Section:
    budget = report["budget_j"]
    facts = [
        ("mission", esc(f"{mission.name} ({source})" if source else mission.name)),
        ("states", esc(", ".join(s.name for s in mission.states))),
        ("vehicle", esc(hardware.vehicle.name)),
        ("computer", esc(_computer(report))),
        ("battery", esc(_battery_text(report, hardware))),
        ("budget", esc(f"{_wh(budget):,.4g} Wh usable")),
        ("objective", esc(report["objective"].replace("_", " "))),
        ("predicted energy", esc(f"{_wh(report['energy_j']):,.4g} Wh "
                                 f"({100 * report['energy_j'] / budget:.1f} % of the budget): "
                                 "what the plan draws")),
        ("budget it takes", esc(f"{_wh(report['budgeted_energy_j']):,.4g} Wh as budgets count "
                                f"energy ({WARMUPS}); the least any plan of this mission takes "
                                f"is {_wh(report['minimum_energy_j']):,.4g} Wh")),
        ("predicted quality", esc(f"{report['quality']:.4f} (0 to 1)")),
        ("shadow price", esc(f"{report['shadow_price']:.4g} quality per extra Wh")),
        ("plan", esc(str(plan_file))),
        ("verdict of the simulated run", _verdict(summary)),
    ]
    notes = [f"planning assumption ({a['subject']}): {a['text']}"
             for a in report.get("assumptions", [])]
    notes.append(f"run: {run_origin}; ocean {summary.get('ocean', '?')}, noise "
                 f"{summary.get('noise', '?')}, seed {summary.get('seed', '?')}")
    return Section("summary", "Summary", (facts_html(facts),), notes=tuple(notes))


WARMUPS = "a sensor warm-up counted for every device that may duty-cycle"


@dataclass(frozen=True)
class Star:
    """The plan's point on the Pareto curve and what the curve says there."""

    budgeted_wh: float  # x: the budget the plan takes, as the curve's budgets count
    quality: float  # y
    drawn_wh: float  # the plan's predicted energy, <= budgeted_wh
    best_quality: float  # the curve at budgeted_wh: the best any plan reaches there
    same_model: bool  # the plan was made on the curve's inputs (hardware, times, workload)


def _star(model, frontier: pd.DataFrame, report: dict) -> Star:
    """Where the plan sits against the curve. A plan is on the curve's model when it
    needs the least budget the curve's model gives its objective: where the curve starts,
    or for a mission that minimises energy to a quality floor, that floor's least energy
    (a plan given by --plan may have been made for another computer or workload, or on
    simulated times; a battery moves only the budget, not the curve)."""
    objective = model.inputs.mission.objective
    least = float(frontier["budget_j"].iloc[0])
    if objective.sense == "minimize_energy" and objective.quality_floor:
        floor = model.solve_energy(objective.quality_floor)
        least = floor.model_energy_j if floor.optimal else math.nan
    budgeted = float(report["budgeted_energy_j"])
    same = math.isclose(report["minimum_energy_j"], least, rel_tol=1e-6)
    best = model.solve_quality(budgeted).quality if same else math.nan
    return Star(_wh(budgeted), float(report["quality"]), _wh(report["energy_j"]), best, same)


def _star_text(star: Star, report: dict, frontier: pd.DataFrame, plan_path: Path | None
               ) -> str:
    """What the star is, and why it sits where it does."""
    text = (f"The star is the plan: quality {star.quality:.4f} at the budget it takes, "
            f"{star.budgeted_wh:,.4g} Wh. Budgets count energy as the planner's convex model "
            f"does, {WARMUPS}, so that a plan within its budget holds it; the plan is "
            f"predicted to draw {star.drawn_wh:,.4g} Wh")
    warmups = star.budgeted_wh - star.drawn_wh
    text += (f" ({warmups:.2g} Wh of those warm-ups are for devices it keeps off or always "
             "on)." if warmups > 5e-4 else ".")
    text += " The curve, the least budget and the infeasible-budget message count the same way."
    start = float(frontier["budget_wh"].iloc[0])
    if not star.same_model:
        return (f"{text} The plan given ({plan_path}) was made on other inputs than this "
                "curve (the mission's own hardware and times): it needs at least "
                f"{_wh(report['minimum_energy_j']):,.4g} Wh where the curve starts at "
                f"{start:,.4g} Wh, so its star is placed by its own figures and is not a "
                "point of this curve.")
    if star.quality >= star.best_quality - QUALITY_TOLERANCE:
        return f"{text} It lies on the curve: no plan reaches more quality on that budget."
    where = ("the least budget, where the curve starts,"
             if math.isclose(star.budgeted_wh, start, rel_tol=1e-6) else "that budget")
    return (f"{text} It lies below the curve: at {where} the best plan reaches quality "
            f"{star.best_quality:.4f} (the solver did not reach that plan to full accuracy).")


def _pareto_section(frontier: pd.DataFrame, report: dict, star: Star,
                    plan_path: Path | None) -> Section:
    svg = charts.pareto(frontier, _wh(report["budget_j"]), star.budgeted_wh, star.quality)
    text = ("<p>The best quality each energy budget buys, from the least the mission needs "
            f"to where more energy buys nothing. At the plan one more Wh of budget buys "
            f"{report['shadow_price']:.4g} quality (the shadow price of the budget).</p>",
            f"<p>{esc(_star_text(star, report, frontier, plan_path))}</p>")
    table = Table(frontier[["budget_wh", "quality", "shadow_price", "status"]],
                  {"budget_wh": "budget [Wh]", "quality": "quality [1]",
                   "shadow_price": "shadow price [quality per Wh]"},
                  {"quality": ".4f", "shadow_price": ".4g", "budget_wh": ",.4g"})
    return Section("pareto", "Quality against budget (Pareto curve)", text, svg,
                   "Quality against the energy budget; dashed: the shadow price; star: the "
                   "plan, at the budget it takes.", ("pareto.csv",), (table,))


def _energy_section(frame: pd.DataFrame) -> Section:
    headers = {c: f"{c.removesuffix('_wh')} [Wh]" for c in frame.columns if c != "state"}
    return Section("energy", "Energy by state and component",
                   ("<p>What each state of the plan costs, by component: the vehicle's hotel "
                    "load, pump, pitch motor, surface and Iridium, the computer, and each "
                    "sensor device.</p>",),
                   charts.energy_by_state(frame), "Predicted energy of each state [Wh].",
                   ("energy_by_state.csv",),
                   (Table(frame, {"state": "state", **headers},
                          dict.fromkeys(headers, ",.3g")),))


def _speed_section(frame: pd.DataFrame) -> Section:
    from gliderplan.reports.speed import REFERENCE_SPEED_MPS, speed_svg

    chosen = frame[frame["chosen"]]
    headers = {"state": "state", "speed_mps": "chosen speed [m/s]",
               "energy_per_km_kj": "energy per km [kJ]"}
    return Section("speed", "Energy per km against speed", (
        "<p>Where the plan flies on the propeller: the energy each km over ground takes at "
        "each speed through the water (the vehicle's propulsion model with the state's hotel "
        "load and board, in the water it was planned for: still water, or along its route in "
        "the current given, still water dashed beside it), and the speed the planner chose, "
        "the least energy per km "
        "(or the one written). Too slow and the hotel load takes the battery, too fast "
        f"and drag does; the dotted line is a fixed {REFERENCE_SPEED_MPS:g} m/s cruise.</p>",),
        speed_svg(frame), "Energy per km [kJ] against speed [m/s]; stars: the chosen speeds.",
        ("speed.csv",), (Table(chosen[list(headers)], headers,
                               {"speed_mps": ".3g", "energy_per_km_kj": ",.4g"}),))


def _vehicles_section(frame: pd.DataFrame, flips: list[dict]) -> Section:
    from gliderplan.planner.vehicles import HEAD_CURRENTS_MPS
    from gliderplan.reports.speed import vehicles_svg

    said = "".join(f"<li>against a head current of {f['head_current_mps']:.3g} m/s and more, "
                   f"{esc(f['to'])} needs the least energy per km</li>" for f in flips)
    return Section("vehicles", "The mission on a glider, a hybrid and an AUV", (
        "<p>The same mission planned on each vehicle (<code>gliderplan compare-vehicles"
        "</code>): the least energy per km over ground against a head current, each at its "
        "best speed (a glider that cannot outrun the current makes no way). Where the "
        "cheapest vehicle "
        "changes, the thruster or the propeller pays:</p>",
        f"<ul>{said}</ul>" if flips else
        f"<p>No crossover up to {HEAD_CURRENTS_MPS[-1]:g} m/s.</p>"),
        vehicles_svg(frame, flips), "Energy per km [kJ] against the head current [m/s].",
        ("vehicles.csv",))


def _plan_vs_sim_section(frame: pd.DataFrame, summary: dict, run_path: Path,
                         origin: str) -> Section:
    text = (f"<p>The plan's prediction of each state against the simulated flight "
            f"({esc(origin)}). Verdict: {_verdict(summary)}.</p>")
    headers = {"predicted_wh": "predicted [Wh]", "simulated_wh": "simulated [Wh]",
               "predicted_h": "planned time [h]", "simulated_h": "flown time [h]",
               "difference_pct": "difference [%]"}
    return Section("plan-vs-simulation", "Plan against simulation", (text,),
                   charts.plan_vs_simulation(frame),
                   "Predicted and simulated energy of each state [Wh].",
                   ("plan_vs_simulation.csv",),
                   (Table(frame, headers, {**dict.fromkeys(headers, ",.3g"),
                                           "difference_pct": "+.1f"}),),
                   (f"run files: {run_path}",))


def _profile_section(frame: pd.DataFrame, ticks: int) -> Section:
    every = "" if len(frame) == ticks else f" (every {math.ceil(ticks / len(frame))}th tick)"
    return Section("profile", "Depth and temperature", (
        f"<p>The simulated dive profile coloured by the water temperature the glider met, "
        f"the mission's states as bands: {ticks:,} ticks of {TICK_S:g} s{every}.</p>",),
        charts.profile(frame), "Depth [m] against mission time [h].", ("profile.csv",))


def _sbc_section(comparison, tables: dict[str, pd.DataFrame]) -> Section:
    from gliderplan.reports import sbc

    boards = tables["sbc_boards.csv"]
    shown = boards[["board", "active_power_w", "idle_power_w", "board_energy_wh",
                    "share_of_mission", "mission_energy_wh", "quality", "endurance_days"]]
    headers = {"active_power_w": "active [W]", "idle_power_w": "idle [W]",
               "board_energy_wh": "board energy [Wh]", "share_of_mission": "share [1]",
               "mission_energy_wh": "mission energy [Wh]", "quality": "quality [1]",
               "endurance_days": "endurance [d]"}
    cheapest = sbc.cheapest_board(comparison)
    alone = sbc.no_board_text(comparison)
    flips = "; ".join(f"at {sbc.cycles_text(x.cycles_per_tick)} {x.reason} "
                      f"({sbc.equivalents_text(x)})" for x in comparison.crossovers)
    code = "".join(f"<li>{esc(line)}</li>" for line in sbc.runtime_code_lines(comparison))
    text = (f"<p>The TS-5500 and the TS-7800 at 300 and 500 MHz on this mission at the same "
            f"battery and workload ({comparison.cycles_per_tick:,.0f} cycles per tick): "
            f"cheapest is {esc(cheapest.name)}"
            + (f"; {esc(alone)}" if alone else "") + ". Where the ranking changes: "
            f"{esc(flips) or 'nowhere up to the fastest board'}.</p>",
            f"<p>The {esc(sbc.workload_basis(comparison))}.</p>",
            f'<ul class="notes">{code}</ul>',
            "<p>Below the tables: every other figure the comparison rests on that is an "
            "assumption rather than a measurement.</p>")
    crossings = tables["sbc_crossovers.csv"]
    return Section("sbc", "Single-board computers", text, sbc.energy_plot(comparison, "svg")
                   .decode("utf-8"), "Board energy on the mission against the workload per "
                   "tick; dashed: crossovers.", ("sbc_boards.csv", "sbc_workload.csv",
                                                  "sbc_crossovers.csv"),
                   (Table(shown, headers, {"share_of_mission": ".3f", "quality": ".4f",
                                           "endurance_days": ".1f"}),
                    Table(crossings[["cycles_per_tick", "ranking_before", "ranking_after",
                                     "reason"]], {"cycles_per_tick": "workload [cycles/tick]",
                                                  "ranking_before": "cheapest first, below",
                                                  "ranking_after": "above"},
                          {"cycles_per_tick": ",.0f"})),
                   tuple(sbc.assumption_lines(comparison, workload=False)))


ASSUMED_MARK = " *"  # after the name of a figure that is an assumption


def _sensitivity_frame(tornado) -> pd.DataFrame:
    return pd.DataFrame([{
        "figure": s.figure, "value": s.value, "unit": s.unit, "step": s.step, "basis": s.basis,
        "energy_down_wh": _wh(s.energy_j[0]), "energy_up_wh": _wh(s.energy_j[1]),
        "quality_down": s.quality[0], "quality_up": s.quality[1], "assumed": s.assumed,
        "source": s.source} for s in tornado.swings])


def _sensitivity_section(tornado, frame: pd.DataFrame) -> Section:
    top = frame.iloc[0]["figure"] if len(frame) else "-"
    assumed = frame[frame["assumed"]]["figure"].tolist() if len(frame) else []
    text = (f"<p>The plan made again with each model figure moved down and up by its "
            f"uncertainty (one standard deviation where calibration gives one, else 20 %), "
            f"at the same budget. Largest effect first: {esc(top)}. Quality shown as a gap "
            "(no bar) means the budget could not buy the mission with that figure.</p>",
            f"<p>Marked{esc(ASSUMED_MARK)}: figures that rest on an assumption, as their data "
            f"files say, rather than on measurements or published figures alone "
            f"({esc(', '.join(assumed)) or 'none'}); the table gives every figure's "
            "source.</p>")
    shown = frame.assign(figure=[f + (ASSUMED_MARK if a else "")
                                 for f, a in zip(frame["figure"], frame["assumed"],
                                                 strict=True)],
                         basis=[b.split(" (")[0] for b in frame["basis"]])
    # Units ride with their numbers and the basis is "1 sd" or "20 %" (the text above says
    # which is which): the table fits the page instead of scrolling sideways.
    headers = {"step": "moved by", "energy_down_wh": "energy down [Wh]",
               "energy_up_wh": "energy up [Wh]", "quality_down": "quality down [1]",
               "quality_up": "quality up [1]"}
    return Section("sensitivity", "Sensitivity: which assumption matters most", text,
                   charts.tornado(shown, _wh(tornado.energy_j), tornado.quality),
                   f"Mission energy and quality with each figure moved; the line is the plan "
                   f"({_wh(tornado.energy_j):,.4g} Wh, quality {tornado.quality:.4f}).",
                   ("sensitivity.csv",),
                   (Table(shown.drop(columns="assumed"), headers,
                          {**dict.fromkeys(headers, ",.4g"), "value": ",.4g"},
                          units={"value": "unit", "step": "unit"}),))


def _montecarlo_section(frame: pd.DataFrame, summary: dict, directory: Path) -> Section:
    n = summary.get("scenarios", len(frame))
    p = summary.get("probability_budget_holds")
    low, high = summary.get("probability_interval_95", [math.nan, math.nan])
    energy, duration = summary.get("energy_j", {}), summary.get("duration_s", {})

    def spread(values: dict, factor: float, unit: str) -> str:
        return ", ".join(f"{k} {v / factor:,.4g} {unit}" for k, v in values.items()) or "-"

    facts = [
        ("scenarios", esc(f"{n:,} flown (seed {summary.get('seed', '?')}, "
                          f"{summary.get('scenario_file', '?')})")),
        ("budget holds", esc("-" if p is None else f"in {100 * p:.1f} % of the scenarios "
                             f"(95 % interval {100 * low:.1f} to {100 * high:.1f} %)")),
        ("energy", esc(spread(energy, J_PER_WH, "Wh"))),
        ("duration", esc(spread(duration, 3600.0, "h"))),
        ("exceeded the usable charge drawn", esc(
            f"{summary.get('exceeded_drawn_usable_charge', 0)} scenarios (usable share drawn "
            f"from {summary.get('usable_share_drawn_from', 'the scenario file')})")),
        ("plan flown", esc(summary.get("plan") or "none: every sensor always on")),
    ]
    budget = summary.get("budget_j")
    figure = charts.histogram(frame["energy_wh"].to_numpy(float),
                              budget / J_PER_WH if budget else None, "mission energy [Wh]")
    return Section("montecarlo", "Monte Carlo: will the battery last?",
                   (facts_html(facts),), figure,
                   "Mission energy over the scenarios; dashed: the plan's budget.",
                   ("montecarlo.csv",), notes=(f"results: {directory}",))
