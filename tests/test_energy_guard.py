"""The energy guard: when the battery's coulomb counter reads the reserve, the runtime ends
the mission (surface and hold, then RELEASE) whatever state and stack depth it is in;
both runtimes alike, in simulation, with an undersized battery and with a plan that
under-predicts the flight."""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from gliderplan.cli.main import main
from gliderplan.contract import (
    FLAG_CLIMBING,
    FLAG_DONE,
    FLAG_SURFACE,
    N_SENSORS,
    TransitionKind,
)
from gliderplan.language import check_file
from gliderplan.language.registry import SENSOR_BY_NAME
from gliderplan.planner.planfile import write_plan_bytes
from gliderplan.sim.energy import GAUGE_TICKS

ROOT = Path(__file__).resolve().parent
FIG2 = ROOT.parent / "examples" / "fig2_annotated.mission"
BUDGET = ROOT / "missions" / "sim_budget.mission"

# Called three deep, on a battery that reaches its reserve (6 kJ) in state d.
DEEP = """mission deep
battery 12 kJ reserve 50 %
state a
begin
  flightprofile yo(3, 20, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 100 call b
end
state b
begin
  flightprofile yo(3, 20, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 200 call c
end
state c
begin
  flightprofile yo(3, 20, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 300 call d
end
state d
begin
  flightprofile yo(3, 20, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 100000 exit
end
"""


def fly(mission: Path, run: Path, *options: str) -> tuple[list[str], dict, object]:
    assert main(["sim", str(mission), "-o", str(run), *options]) == 0
    trace = (run / "trace.csv").read_text().splitlines()[1:]
    summary = json.loads((run / "summary.json").read_text())
    return trace, summary, pq.read_table(run / "timeseries.parquet").to_pandas()


def check_guard_fired(summary: dict, series, reserve_j: float) -> None:
    """The run ended by the guard at the first read-out at or below the reserve: the
    battery is at most the reserve, and short of it by no more than the ticks since that
    read-out drew."""
    assert summary["ended"] == "reserve"
    left = series["battery_remaining_j"].to_numpy()
    drawn = -(left[1:] - left[:-1])
    assert left[-1] <= reserve_j
    assert left[-1] >= reserve_j - GAUGE_TICKS * drawn.max()


@pytest.mark.parametrize("runtime", ["python", "c"])
def test_an_undersized_battery_ends_the_mission_in_a_called_state(tmp_path, runtime):
    """Fig. 2 on 16 kJ with half in reserve: the guard ends the mission in s2, called
    from s1, at the same tick on both runtimes; the stack is emptied."""
    mission = tmp_path / "small.mission"
    mission.write_text(FIG2.read_text().replace("battery 1.2 kWh reserve 15 %",
                                                "battery 16 kJ reserve 50 %"))
    options = ["--runtime", runtime]
    if runtime == "c":
        options += ["--state-dir", str(tmp_path / "state")]
    trace, summary, series = fly(mission, tmp_path / "run", *options)
    assert trace == ["0,start,,s1,0", "500,call,s1,s2,1", "1280,reserve,s2,,0"]
    check_guard_fired(summary, series, 8e3)
    assert series["stack_depth"].iloc[-2] == 1  # in s2 at depth 1 until the guard
    if runtime == "c":  # the runtime's own log says so too
        log = (tmp_path / "state" / "events.log").read_text().splitlines()
        assert log[-1] == "1280 reserve s2 - 0"


@pytest.mark.parametrize("runtime", ["python", "c"])
def test_the_guard_fires_three_calls_deep(tmp_path, runtime):
    mission = tmp_path / "deep.mission"
    mission.write_text(DEEP)
    trace, summary, series = fly(mission, tmp_path / "run", "--runtime", runtime)
    assert trace[:4] == ["0,start,,a,0", "100,call,a,b,1", "200,call,b,c,2", "300,call,c,d,3"]
    assert len(trace) == 5 and trace[4].split(",")[1:] == ["reserve", "d", "", "0"]
    check_guard_fired(summary, series, 6e3)


def test_the_guard_commands_surface_and_hold():
    """The reference executor's COMMAND on the guard's tick, as the C runtime's (its unit
    test): mission done, surface, climbing at the surfacing pitch on the pump's full
    volume."""
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim.executor import PythonRuntime

    mission = check_file(str(FIG2)).mission
    vehicle = load_vehicle(mission.vehicle)
    executor = PythonRuntime(mission, None, vehicle.unplanned_ballast_cc, True,
                             vehicle.max_ballast_cc)
    energy = SENSOR_BY_NAME["energy_left"].index
    values = [0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 3910.0, -7349.0, 15.0, 15.0,
              *[0.0] * (N_SENSORS - 10)]
    values[energy] = 9e6
    mask = 0x2c3 | 1 << energy
    assert executor.step(0, mask, values).transition == TransitionKind.START
    values[0], values[energy] = 4.0, mission.battery.reserve_j
    command = executor.step(1, mask, values)
    assert command.transition == TransitionKind.RESERVE
    assert command.flags == FLAG_DONE | FLAG_SURFACE | FLAG_CLIMBING
    assert command.ballast_cc == vehicle.max_ballast_cc and command.pitch_rad > 0.45


def test_a_plan_that_under_predicts_is_cut_short_by_the_guard(tmp_path):
    """A plan made for one hour of the three-hour survey fits the battery on paper (60 kJ,
    15 % in reserve); the flight it makes does not, and the guard ends it at the reserve
    instead of flying the battery flat."""
    from gliderplan.planner.plan import plan_mission

    mission_file = tmp_path / "survey.mission"
    mission_file.write_text(BUDGET.read_text().replace("battery 120 kJ reserve 0 %",
                                                       "battery 60 kJ reserve 15 %"))
    mission = check_file(str(mission_file)).mission
    result = plan_mission(mission, occupancy_s={"survey": 3600.0})
    assert result.plan.predicted_j < 0.5 * 51e3  # on paper: well within the 51 kJ usable
    plan = tmp_path / "survey.plan"
    plan.write_bytes(write_plan_bytes(result.plan))
    assert main(["sim", str(mission_file), "--plan", str(plan), "-o", str(tmp_path / "run")]) \
        in (0, 3)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    series = pq.read_table(tmp_path / "run" / "timeseries.parquet").to_pandas()
    check_guard_fired(summary, series, 9e3)
    assert summary["simulated_s"] < 10800 and summary["energy_j"] > 2 * result.plan.predicted_j


def test_the_c_flight_stops_where_the_guard_fires(tmp_path):
    """The month-long survey on a tenth of its battery: the C flight's gauge reads the
    reserve where the Python reference's does, and the flight, the tick of the guard and
    every record are the reference's."""
    from test_sim_differential import flown_alike

    from gliderplan.sim.loop import RunConfig

    source = (ROOT.parent / "examples" / "survey_month.mission").read_text()
    mission_file = tmp_path / "short.mission"
    mission_file.write_text(source.replace("battery 350 Ah at 15 V reserve 10 %",
                                           "battery 35 Ah at 15 V reserve 10 %"))
    mission = check_file(str(mission_file)).mission
    record = flown_alike(mission, RunConfig(duration_s=10 * 86400.0, seed=2))
    assert record.ended == "reserve" and record.trace[-1].kind == "reserve"
    assert 86400 < record.trace[-1].time_s < 10 * 86400
