"""What a plan predicts, state by state: energy by component, inflections, time.

The planner writes its report beside the plan (`gliderplan plan -o X.plan` writes
`X.plan.json`, planner/report.py). Without it the mission is planned again: when the
planner makes the very same plan file, its report is the prediction."""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from gliderplan.contract.errors import GliderplanError
from gliderplan.language.ir import CheckedMission


class PlanReportError(GliderplanError, ValueError):
    """An unreadable planner report; the message names the file and key."""


@dataclass(frozen=True)
class StatePrediction:
    energy_by_component_j: dict[str, float]
    inflections: float | None
    time_s: float | None

    @property
    def energy_j(self) -> float:
        return float(sum(self.energy_by_component_j.values()))


def predictions_from_report(report: object, where: str) -> dict[str, StatePrediction]:
    """Per-state predictions of a planner report: `states`, a list of objects with
    `name`, `energy_by_component_j`, `inflections` and `time_s`."""
    states = report.get("states") if isinstance(report, dict) else None
    if not isinstance(states, list):
        raise PlanReportError(f"{where}: states: missing (expected the per-state list of "
                              "the planner's report)")
    predictions = {}
    for i, entry in enumerate(states):
        name = entry.get("name") if isinstance(entry, dict) else None
        components = entry.get("energy_by_component_j") if isinstance(entry, dict) else None
        if not isinstance(name, str) or not isinstance(components, dict):
            raise PlanReportError(f"{where}: states[{i}]: needs a name and "
                                  "energy_by_component_j")
        try:
            energy = {str(k): float(v) for k, v in components.items()}
        except (TypeError, ValueError):
            raise PlanReportError(f"{where}: states[{i}].energy_by_component_j: values must "
                                  "be numbers") from None
        predictions[name] = StatePrediction(energy, _number(entry.get("inflections")),
                                            _number(entry.get("time_s")))
    return predictions


def _number(value: object) -> float | None:
    return float(value) if isinstance(value, int | float) else None


def read_plan_report(path: str | Path) -> dict[str, StatePrediction]:
    """Per-state predictions from a planner report file."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as err:
        raise PlanReportError(f"{path}: cannot read the plan's report: {err}") from None
    except json.JSONDecodeError as err:
        raise PlanReportError(f"{path}:{err.lineno}: not JSON: {err.msg}") from None
    return predictions_from_report(data, str(path))


def plan_predictions(plan_path: str | Path, mission: CheckedMission
                     ) -> tuple[dict[str, StatePrediction] | None, str]:
    """(predictions, where they came from: "report", "replanned" or "none")."""
    report = Path(f"{plan_path}.json")
    if report.is_file():
        return read_plan_report(report), "report"
    from gliderplan.planner.plan import PlanningError, plan_mission
    from gliderplan.planner.planfile import write_plan_bytes
    from gliderplan.planner.report import report_json

    try:
        replanned = plan_mission(mission)
    except (PlanningError, ValueError):  # an infeasible budget, unreadable hardware files:
        return None, "none"  # then the planner could not have made this plan either
    if write_plan_bytes(replanned) != Path(plan_path).read_bytes():
        return None, "none"
    return predictions_from_report(report_json(replanned), "the planner's report"), "replanned"
