"""The compiled runtime's step in this process (sim/cstep.py): built once and cached, it
reads its plan with the runtime's own reader, and reports what the Python executor does.
That it flies every mission as the reference and the board binary do:
tests/test_sim_differential.py."""

from __future__ import annotations

import shutil
import zlib
from dataclasses import replace
from pathlib import Path

import pytest

from gliderplan.language import check_file
from gliderplan.planner.limits import flight_limits
from gliderplan.planner.planfile import PlanRejected

REPO = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")


def test_the_step_refuses_a_plan_the_runtime_refuses():
    from gliderplan.sim.cstep import CStep

    mission = check_file(str(REPO / "examples" / "fig2.mission")).mission
    body = (f"GPPLAN 3\nmission {mission.name}\nhash {'0' * 64}\n").encode()
    with pytest.raises(PlanRejected, match="the runtime refused the plan: line 3"):
        CStep(mission, body + f"crc32 {zlib.crc32(body):08x}\n".encode(),
              flight_limits(mission))


def test_the_shared_objects_are_built_once(tmp_path, monkeypatch):
    from gliderplan.sim import cstep

    monkeypatch.setenv("GLIDERPLAN_CACHE_DIR", str(tmp_path))
    mission = check_file(str(REPO / "examples" / "fig2.mission")).mission
    cstep._tables_address.cache_clear()
    cstep.mission_tables(mission, flight_limits(mission))
    built = sorted(p.name for p in tmp_path.glob("*/*/*.so"))
    assert built == ["libmission.so"]
    cstep._tables_address.cache_clear()
    cstep.mission_tables(mission, flight_limits(mission))  # from the cache
    assert sorted(p.name for p in tmp_path.glob("*/*/*.so")) == built


def test_vehicles_of_other_ratings_fly_one_build_of_the_tables(tmp_path, monkeypatch):
    """A Monte Carlo's scenarios draw a vehicle each: its rating goes to the step at
    init, the mission's tables are built once."""
    from gliderplan.sim import cstep

    monkeypatch.setenv("GLIDERPLAN_CACHE_DIR", str(tmp_path))
    mission = check_file(str(REPO / "examples" / "fig2.mission")).mission
    nominal = flight_limits(mission)
    drawn = replace(nominal, envelope=replace(nominal.envelope, max_pitch_rad=0.3,
                                              max_pump_power_w=5.0))
    cstep._tables_address.cache_clear()
    assert cstep.mission_tables(mission, nominal) == cstep.mission_tables(mission, drawn)
    assert len(list(tmp_path.glob("*/*/libmission.so"))) == 1


def _first_command(limits):
    from gliderplan.contract import SENSORS
    from gliderplan.sim.cstep import CStep

    mission = check_file(str(REPO / "examples" / "fig2.mission")).mission
    step = CStep(mission, None, limits)
    return step.step(0, 1, [0.0] * len(SENSORS)), step


def test_the_step_holds_commands_to_the_flights_envelope():
    from gliderplan.contract import EnvelopeAction

    mission = check_file(str(REPO / "examples" / "fig2.mission")).mission
    nominal = flight_limits(mission)
    free, free_step = _first_command(nominal)
    held, held_step = _first_command(replace(nominal, envelope=replace(
        nominal.envelope, max_pitch_rad=0.3, action=EnvelopeAction.CLAMP)))
    assert free.pitch_rad == pytest.approx(0.454) and not free_step.envelope_notes
    assert held.pitch_rad == pytest.approx(0.3) and held_step.envelope_notes


def test_the_step_reports_what_the_runtime_holds():
    from gliderplan.contract import NO_STATE, SENSORS
    from gliderplan.sim.cstep import CStep

    mission = check_file(str(REPO / "examples" / "fig2.mission")).mission
    step = CStep(mission, None, flight_limits(mission))
    values = [0.0] * len(SENSORS)
    for tick, time_s in enumerate((0.0, 500.0, 1500.0, 2000.0, 2500.0)):
        values[0] = time_s
        command = step.step(tick, 1, values)
    assert command.state == NO_STATE and step.events_fired == 4
    assert set(step.entry_variables) == {"s1", "s2", "s3"}
