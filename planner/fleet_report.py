"""A fleet plan for people and tools: the JSON report (`fleet plan --json`, fleet.json), the
text `fleet plan` prints, and the plan directory: each glider's mission and plan file, the
report, the map. `load_plan_dir` reads a directory back for `fleet sim` and `fleet
montecarlo` (the missions and plans as written, the tracks from the report).
"""

from __future__ import annotations

import json
from collections.abc import Iterable
from contextlib import AbstractContextManager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gliderplan.contract.errors import GliderplanError, UsageError
from gliderplan.contract.files import OutputFolder, output_folder
from gliderplan.contract.units import J_PER_WH, finite_or_none
from gliderplan.language.fleet import Fleet
from gliderplan.planner.fleet import TARGET_IMPROVEMENT, FleetPlan, GliderPlan
from gliderplan.planner.fleet_capacity import hours
from gliderplan.planner.fleet_missions import Track

REPORT_FILE = "fleet.json"


def _utc(epoch_s: float) -> str:
    from datetime import UTC, datetime

    return datetime.fromtimestamp(epoch_s, UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def track_json(track: Track) -> dict:
    return {"points_m": np.round(track.points, 2).tolist(),
            "distance_m": np.round(track.distance_m, 2).tolist(),
            "segment_ends": list(track.segment_ends), "speed_mps": track.speed_mps,
            "surface_every_s": track.surface_every_s, "surface_stay_s": track.surface_stay_s,
            "start_offset_s": track.start_offset_s, "first_pass_m": track.first_pass_m,
            "line_visits_m": {str(k): list(v) for k, v in track.line_visits.items()}}


def track_from_json(data: dict) -> Track:
    return Track(np.asarray(data["points_m"], float), np.asarray(data["distance_m"], float),
                 tuple(int(e) for e in data["segment_ends"]), float(data["speed_mps"]),
                 float(data["surface_every_s"]), float(data["surface_stay_s"]),
                 float(data["start_offset_s"]), float(data["first_pass_m"]),
                 {int(k): tuple(v) for k, v in data["line_visits_m"].items()})


def _glider_json(fleet: Fleet, glider: GliderPlan) -> dict:
    cap, track = glider.capacity, glider.track
    spec = glider.spec
    return {
        "name": glider.name,
        "energy_j": glider.energy_j,
        "budget_j": glider.budget_j,
        "margin_j": glider.budget_j - glider.energy_j,
        "design_energy_j": cap.design_energy_j,
        "vehicle": spec.vehicle,
        "computer": spec.computer.board if spec.computer.clock_mhz is None
        else f"{spec.computer.board}@{spec.computer.clock_mhz:g}",
        "battery_j": spec.battery.energy_j,
        "charge": spec.charge,
        "start_utc": _utc(fleet.start_epoch_s + spec.start_offset_s),
        "speed_mps": cap.speed_mps,
        "water_speed_mps": cap.water_speed_mps,
        "band_m": list(cap.band),
        "end_s": cap.end_s,
        "energy_limited": cap.energy_limited,
        "distance_m": track.length_m,
        "passes": _passes(track),
        "parts": list(glider.parts),
        "lines_m": float(sum(fleet.parts[p].length_m for p in glider.parts)),
        "entry": "last" if glider.block.entry_last else "first",
        "first_coverage_s": track.first_coverage_s(),
        "segments": len(track.segment_ends),
        "surface_every_s": track.surface_every_s,
        "shadow_price_per_kwh": glider.shadow_price,
        "mission": f"{glider.name}.mission",
        "plan": f"{glider.name}.plan",
        "track": track_json(track),
    }


def _passes(track: Track) -> float:
    """Sweeps of its block the track holds (1 = the first sweep only)."""
    if track.first_pass_m <= 0.0:
        return 0.0
    transit = min(v[0] for v in track.line_visits.values() if v) if any(
        track.line_visits.values()) else 0.0
    sweep = max(track.first_pass_m - transit, 1.0)
    return float(max(track.length_m - transit, 0.0) / sweep)


def why_not(plan: FleetPlan) -> str | None:
    """When the coordinated plan gains less than TARGET_IMPROVEMENT over the equal split:
    what about this fleet leaves little to coordinate, measured on the plans."""
    if plan.improvement >= TARGET_IMPROVEMENT:
        return None
    fleet = plan.fleet
    caps = plan.baseline_capacities
    reach = [c.distance_m for c in caps]
    spread = max(reach) / max(min(reach), 1.0) - 1.0
    late = max(g.start_offset_s for g in fleet.gliders)
    short = [c.name for c in caps if c.energy_limited]
    reasons = []
    # the error that falls while most gliders are not yet (or no longer) on their lines
    # is the same whichever way the lines are shared
    times = plan.grid.times
    on = np.zeros(len(times))
    for glider in plan.gliders:
        track = glider.track
        arrive = track.start_offset_s + float(track.time_at(min(
            (v[0] for v in track.line_visits.values() if v), default=track.length_m)))
        stop = track.start_offset_s + glider.capacity.end_s
        on += (times >= arrive) & (times <= stop)
    few = on < 0.5 * len(plan.gliders)
    per_time = plan.evaluation.errors.mean(axis=1)
    idle = float(per_time[few].sum() / max(per_time.sum(), 1e-12))
    if idle > 0.3:
        reasons.append(f"{100 * idle:.0f} % of the mapping error falls while fewer than half "
                       "of the gliders are on their lines (late starts, transits, batteries "
                       "run out), whichever way the lines are shared")
    if spread < 0.3 and not short and late < 0.1 * fleet.period_s:
        reasons.append(f"the gliders are alike: each flies within {100 * spread:.0f} % of the "
                       "others' distance, none runs out of battery early and they start "
                       "together, so equal blocks are already near the best split")
    if fleet.goal.spacing_m and fleet.goal.spacing_m < 0.5 * fleet.field.length_m:
        reasons.append(f"the lines lie {fleet.goal.spacing_m / 1000:g} km apart, less than "
                       f"half the field's {fleet.field.length_m / 1000:g} km length scale: "
                       "each line is mapped by its neighbours' samples too, whoever flies "
                       "them")
    worst = plan.baseline_evaluation.mapping_error
    if worst < 0.1:
        reasons.append(f"even the equal split maps the field well (mapping error "
                       f"{worst:.3f}): little error is left to remove")
    if not reasons:
        reasons.append("few lines per glider leave few ways to cut the survey that differ")
    return (f"the coordinated plan lowers the mapping error by {100 * plan.improvement:.1f} %, "
            f"less than {100 * TARGET_IMPROVEMENT:.0f} %: " + "; ".join(reasons))


def report_json(plan: FleetPlan) -> dict:
    """The report (docs/fleet.md documents every field)."""
    fleet = plan.fleet
    a, base = plan.assignment, plan.baseline
    priced = [g for g in plan.gliders if g.shadow_price > 0.0]
    limiting = max(priced, key=lambda g: g.shadow_price).name if priced else None
    return {
        "report_version": 1,
        "fleet": fleet.name,
        "fleet_file": fleet.filename,
        "fleet_hash": fleet.hash,
        "status": "optimal" if a.status == "optimal" else a.status,
        "mapping_error": plan.evaluation.mapping_error,
        "baseline_mapping_error": plan.baseline_evaluation.mapping_error,
        "improvement": plan.improvement,
        "why_not": why_not(plan),
        "confidence": fleet.confidence,
        "confidence_lower_bound": plan.validation.lower_bound,
        "validation": {"method": "scenario design at a quantile, validated on fresh "
                                 "scenarios (Clopper-Pearson, one-sided 95 %)",
                       "scenarios": plan.validation.scenarios,
                       "finished": plan.validation.finished,
                       "design_quantile": plan.validation.design_quantile,
                       "design_scenarios": plan.validation.design_scenarios,
                       "failures": plan.validation.failures},
        "coverage": plan.evaluation.coverage,
        "finish_time_s": plan.evaluation.finish_s,
        "finish_time_utc": _utc(fleet.start_epoch_s + plan.evaluation.finish_s),
        "mapped_share": plan.evaluation.mapped_share,
        "start_utc": _utc(fleet.start_epoch_s),
        "finish_by_utc": _utc(fleet.start_epoch_s + fleet.period_s),
        "period_s": fleet.period_s,
        "field": {"length_m": fleet.field.length_m, "time_s": fleet.field.time_s,
                  "noise": fleet.field.noise, "source": fleet.field.source,
                  "grid_points": len(plan.grid.x), "grid_times": len(plan.grid.times)},
        "assignment": {"method": a.method, "status": a.status, "objective": a.objective,
                       "bound": a.bound, "gap": a.gap, "solve_s": a.solve_s, "arcs": a.arcs,
                       "polish": None if plan.polish is None else {
                           "tried": plan.polish.tried, "accepted": plan.polish.accepted,
                           "mapping_error_before": plan.polish.before,
                           "mapping_error_after": plan.polish.after,
                           "seconds": plan.polish.seconds}},
        "baseline": {
            "method": "equal split", "objective": base.objective,
            "finish_time_s": plan.baseline_evaluation.finish_s,
            "coverage": plan.baseline_evaluation.coverage,
            "model_finish_share": plan.baseline_validation.share,
            "confidence_lower_bound": plan.baseline_validation.lower_bound,
            "gliders": [{"name": plan.fleet.gliders[b.glider].name,
                         "parts": list(range(b.first, b.stop)),
                         "feasible": b.feasible} for b in base.blocks]},
        "separation": {**plan.separation,
                       "closest_m": finite_or_none(plan.separation["closest_m"])},
        "limiting_glider": limiting,
        "lines": [{"index": p.index, "kind": p.kind, "length_m": p.length_m,
                   "a_m": list(p.a), "b_m": list(p.b)} for p in fleet.parts],
        "gliders": [_glider_json(fleet, g) for g in plan.gliders],
        "notes": list(plan.notes),
        "seed": plan.seed,
        "plan_s": plan.plan_s,
    }


def report_text(report: dict) -> str:
    """What `fleet plan` prints."""
    lines = [f"{report['fleet']}: mapping error {report['mapping_error']:.3f} "
             f"(the equal split: {report['baseline_mapping_error']:.3f}, "
             f"{100 * report['improvement']:.1f} % lower)",
             f"  finishes (every line swept once) by {report['finish_time_utc']} in "
             f"{report['validation']['finished']} of {report['validation']['scenarios']} "
             f"scenarios: at least {100 * report['confidence_lower_bound']:.1f} % against "
             f"the {100 * report['confidence']:.0f} % asked "
             f"(the equal split: {100 * report['baseline']['model_finish_share']:.1f} %)",
             f"  lines assigned by {report['assignment']['method']} "
             f"({report['assignment']['status']}"
             + (f", gap {100 * report['assignment']['gap']:.2g} %" if report['assignment']['gap']
                is not None else "") + ")" + _polish_text(report['assignment']['polish'])]
    if report["why_not"]:
        lines.append(f"  {report['why_not']}")
    lines.append(f"  {'glider':<10} {'lines':>9} {'km':>6} {'speed':>6} {'until':>7} "
                 f"{'energy':>9} {'budget':>9} {'margin':>8} {'1st sweep':>9} {'per kWh':>8}")
    for g in report["gliders"]:
        parts = g["parts"]
        span = f"{parts[0]}-{parts[-1]}" if len(parts) > 1 else f"{parts[0]}"
        lines.append(
            f"  {g['name']:<10} {span:>9} {g['distance_m'] / 1000:>6.0f} "
            f"{g['speed_mps']:>6.3f} {hours(g['end_s']):>7} "
            f"{g['energy_j'] / J_PER_WH:>7.0f}Wh {g['budget_j'] / J_PER_WH:>7.0f}Wh "
            f"{100 * g['margin_j'] / max(g['budget_j'], 1.0):>7.0f}% "
            f"{hours(g['first_coverage_s']):>9} {g['shadow_price_per_kwh']:>8.3g}")
    if report["limiting_glider"]:
        lines.append(f"  the battery that limits the survey most: {report['limiting_glider']} "
                     "(mapping error lowered per extra kWh, 'per kWh')")
    else:
        lines.append("  no glider's battery limits the survey: each flies as fast as it may")
    sep = report["separation"]
    if sep["between"]:
        lines.append(f"  closest approach {sep['closest_m'] / 1000:.2f} km ({sep['between'][0]}"
                     f", {sep['between'][1]}, {hours(sep['at_s'])} in)")
    lines += [f"  note: {n}" for n in report["notes"]]
    return "\n".join(lines)


# ---- the plan directory ------------------------------------------------------------------

def write_plan_dir(plan: FleetPlan, output: str | Path | OutputFolder, *, force: bool = False,
                   inputs: Iterable[str | Path | None] = ()) -> tuple[Path, ...]:
    """Write the plan: per glider its mission and plan (and the plan's JSON report), the
    fleet report, the map (PNG, GeoJSON, KML) and the fleet page; into `output`, a folder
    written whole (contract.files.output_folder, with `force` and `inputs`), or a folder
    being written (a fleet run's plan/). Where the files will be."""
    from gliderplan.planner.planfile import write_plan_bytes
    from gliderplan.planner.report import report_json as plan_report
    from gliderplan.reports import fleet as drawing

    report = report_json(plan)
    files: dict[str, str | bytes] = {}
    for glider in plan.gliders:
        files[f"{glider.name}.mission"] = glider.mission_text
        files[f"{glider.name}.plan"] = write_plan_bytes(glider.result.plan)
        files[f"{glider.name}.plan.json"] = json.dumps(plan_report(glider.result),
                                                       indent=2) + "\n"
    files[REPORT_FILE] = json.dumps(report, indent=1) + "\n"
    files.update(drawing.map_files(plan.fleet, report, plan))
    files["fleet.html"] = drawing.page(plan.fleet, report, plan=plan, png=files["fleet.png"])
    if isinstance(output, OutputFolder):
        return tuple(output.write(name, data) for name, data in files.items())
    with plan_folder(output, plan.fleet, force=force, inputs=inputs) as folder:
        return write_plan_dir(plan, folder)


def plan_folder(output: str | Path, fleet: Fleet, *, force: bool = False,
                inputs: Iterable[str | Path | None] = ()) -> AbstractContextManager:
    """The folder `output` for a plan of `fleet` (contract.files.output_folder): opened
    before the fleet is planned, so that a folder that cannot take it is refused first."""
    names = [REPORT_FILE, "fleet.png", "fleet.geojson", "fleet.kml", "fleet.html"]
    for glider in fleet.gliders:
        names += [f"{glider.name}.mission", f"{glider.name}.plan", f"{glider.name}.plan.json"]
    return output_folder(output, command="fleet plan", force=force, recognised=names,
                         inputs=inputs)


@dataclass(frozen=True)
class StoredGlider:
    name: str
    mission_path: Path
    plan_path: Path
    track: Track
    report: dict


@dataclass(frozen=True)
class StoredPlan:
    directory: Path
    report: dict
    gliders: tuple[StoredGlider, ...]


def load_plan_dir(directory, fleet: Fleet) -> StoredPlan:
    """A plan directory written by `fleet plan -o`, for `fleet`: UsageError when it is no
    such directory, GliderplanError when it holds the plan of another fleet file."""
    from gliderplan.contract.files import read_input_text

    out = Path(directory)
    if not out.is_dir():
        raise UsageError(f"--plan {out}: no such directory (a plan of gliderplan fleet plan "
                         "-o DIR)")
    try:
        report = json.loads(read_input_text(out / REPORT_FILE, "fleet report"))
    except ValueError as err:
        raise GliderplanError(f"{out / REPORT_FILE}: cannot read: {err}") from None
    if report.get("fleet_hash") != fleet.hash:
        raise GliderplanError(f"--plan {out}: it is the plan of another fleet file (or of "
                              f"this one before it changed): plan {fleet.filename} again")
    gliders = []
    for entry in report["gliders"]:
        mission, plan_file = out / entry["mission"], out / entry["plan"]
        for path in (mission, plan_file):
            if not path.is_file():
                raise UsageError(f"--plan {out}: {path.name} is missing")
        gliders.append(StoredGlider(entry["name"], mission, plan_file,
                                    track_from_json(entry["track"]), entry))
    return StoredPlan(out, report, tuple(gliders))


def _polish_text(polish: dict | None) -> str:
    if not polish or not polish["accepted"]:
        return ""
    return (f"; {polish['accepted']} cut{'s' if polish['accepted'] != 1 else ''} moved by one "
            f"line on the mapping error itself ({polish['mapping_error_before']:.3f} -> "
            f"{polish['mapping_error_after']:.3f})")
