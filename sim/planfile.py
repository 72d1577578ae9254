"""The plan the simulator flies: read strictly by the planner's reader (the format's one
Python reader, docs/plan-format.md), then checked against what the executor needs of each
state block, as the C runtime checks it: one profile line per alternative of the state,
sensor lines only for sensors the state logs, in the state's order."""

from __future__ import annotations

from pathlib import Path

from gliderplan.language.ir import CheckedMission
from gliderplan.planner.planfile import (
    PlanFile,
    PlanFileError,
    StateBlock,
    check_against_mission,
    read_plan_bytes,
    read_plan_file,
)

Plan = PlanFile
StatePlan = StateBlock

__all__ = ["Plan", "PlanFileError", "StatePlan", "parse_plan", "read_plan"]


def _check_blocks(plan: PlanFile, mission: CheckedMission, path: str) -> None:
    for block, state in zip(plan.states, mission.states, strict=True):
        if len(block.profiles) != len(state.profiles):
            raise PlanFileError(block.line, f"state {state.name}: {len(block.profiles)} "
                                f"profiles, the mission's state has {len(state.profiles)}",
                                path)
        logged = [use.name for use in state.sensors]
        positions = []
        for sensor in block.sensors:
            if sensor.name not in logged:
                raise PlanFileError(block.line, f"state {state.name}: sensor "
                                    f"{sensor.name!r} is not logged by the state", path)
            positions.append(logged.index(sensor.name))
        if positions != sorted(set(positions)):
            raise PlanFileError(block.line, f"state {state.name}: sensor lines out of the "
                                "state's order", path)


def parse_plan(data: bytes, path: str, mission: CheckedMission) -> PlanFile:
    """The plan in `data`, for `mission`; PlanFileError (`path:line: ...`) otherwise."""
    try:
        plan = read_plan_bytes(data)
        check_against_mission(plan, mission)
    except PlanFileError as err:
        raise PlanFileError(err.line, err.message, path) from None
    _check_blocks(plan, mission, path)
    return plan


def read_plan(path: str | Path, mission: CheckedMission) -> PlanFile:
    """Read a plan file for `mission`; PlanFileError names the file and line."""
    plan = read_plan_file(path, mission)
    _check_blocks(plan, mission, str(path))
    return plan
