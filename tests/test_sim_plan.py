"""The plan check: a sound plan passes; a deliberately under-budgeted plan (one that
believes a three-hour survey lasts one hour) is flagged, with the cause.

The predictions are computed here from the power models, independently of the
simulator: the hotel load less the instruments it holds (the CTD and optics of sebastian's
log), yo pump and pitch power, computer and CTD for the planned time.
"""

from __future__ import annotations

import json
import re
import zlib
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, TICK_S
from gliderplan.language import check_file
from gliderplan.power_models import load_board, load_sensor, load_vehicle
from gliderplan.power_models.catalog import preset_names

MISSION = Path(__file__).resolve().parent / "missions" / "sim_budget.mission"
PITCH_RAD, BALLAST_CC = 0.454, 233.0


def predicted_components_j(time_s: float) -> dict[str, float]:
    """Energy of flying the survey's yo (3-30 m) for `time_s` with the CTD always on."""
    vehicle = load_vehicle("slocum_g2_shallow")
    board = load_board("ts7800", 300.0)
    busy = board.busy_fraction(RUNTIME_CYCLES_PER_TICK, 1.0 / TICK_S)
    held_w = sum(load_sensor(d).on_power_w for d in vehicle.hotel_includes
                 if d in preset_names("sensor"))  # the instruments, not the fin
    return {
        "hotel": (vehicle.hotel_w - held_w) * time_s,
        "pump_and_pitch": float(vehicle.profile_power_w(3, 30, PITCH_RAD, BALLAST_CC)) * time_s,
        "computer": float(board.power_w(busy)) * time_s,
        "ctd": load_sensor("ctd").on_power_w * time_s,
    }


ASSUMED = "planned at its expect upper bound (3600 s per visit)"


def write_plan(tmp_path: Path, budget_j: float, planned_s: float,
               board: tuple[str, float] = ("ts7800", 300.0), survey: Path = MISSION) -> Path:
    """A plan for the survey (`survey`: the mission) predicting `planned_s` in it, written
    by hand from docs/plan-format.md: the prediction travels in the plan file, nothing
    beside it."""
    mission = check_file(str(survey)).mission
    components = predicted_components_j(planned_s)
    vehicle = load_vehicle("slocum_g2_shallow")
    inflections = float(vehicle.inflections_per_hour(3, 30, PITCH_RAD, BALLAST_CC)) \
        * planned_s / 3600
    predicted = sum(components.values())
    u = float(vehicle.glide(PITCH_RAD, BALLAST_CC)[0])
    name, clock = board
    body = (f"GPPLAN 3\nmission {mission.name}\nhash {mission.hash}\ncomputer {name} {clock:g}\n"
            f"budget_j {budget_j:.9g}\npredicted_j {predicted:.9g}\n"
            f"components {' '.join(components)}\nassumptions 1\nassume survey {ASSUMED}\n"
            f"states 1\nstate survey {clock:g} 600 1 1\n"
            f"predict {planned_s:.9g} 1 {inflections:.9g}\n"
            f"energy {' '.join(format(j, '.9g') for j in components.values())}\n"
            f"sensor temp 600 600\nprofile 0 1 {PITCH_RAD} {BALLAST_CC:.9g} {u:.9g}\nend\n"
            ).encode()
    plan = tmp_path / "survey.plan"
    plan.write_bytes(body + f"crc32 {zlib.crc32(body):08x}\n".encode())
    return plan


def simulate(tmp_path: Path, plan: Path, capsys, survey: Path = MISSION
             ) -> tuple[int, dict, str]:
    code = main(["sim", str(survey), "--plan", str(plan), "-o", str(tmp_path / "run")])
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    return code, summary, capsys.readouterr().err


def test_a_sound_plan_passes_and_the_simulation_agrees_with_its_prediction(tmp_path, capsys):
    code, summary, err = simulate(tmp_path, write_plan(tmp_path, 120e3, 10800.0), capsys)
    assert code == 0, err
    check = summary["plan_check"]
    assert check["verdict"] == "pass" and check["causes"] == []
    survey = summary["states"]["survey"]
    assert survey["simulated_j"] == pytest.approx(survey["predicted_j"], rel=0.05)
    assert survey["inflections"] == pytest.approx(survey["predicted_inflections"], rel=0.05)
    assert "plan check: pass" in err


def test_an_under_budgeted_plan_is_a_violation_with_its_cause(tmp_path, capsys):
    code, summary, err = simulate(tmp_path, write_plan(tmp_path, 40e3, 3600.0), capsys)
    assert code == 3
    check = summary["plan_check"]
    assert check["verdict"] == "violation"
    assert check["simulated_j"] > check["budget_j"] * (1 + check["tolerance"])
    (cause,) = check["causes"]
    assert cause.startswith("survey: ")
    planned, flown = map(int, re.search(r"(\d+) inflections planned, (\d+) flown", cause).groups())
    assert flown == pytest.approx(3 * planned, rel=0.1)  # three hours flown of one planned
    assert "1.00 h planned, 3.00 h flown" in cause
    assert f"the plan assumed: {ASSUMED}" in cause  # what the prediction rested on
    assert summary["plan_assumptions"] == [{"subject": "survey", "text": ASSUMED}]
    assert "plan check: violation" in err and "survey:" in err


def test_a_plan_for_another_mission_is_refused(tmp_path, capsys):
    plan = write_plan(tmp_path, 120e3, 10800.0)
    other = tmp_path / "other.mission"
    other.write_text(MISSION.read_text().replace("battery 120 kJ", "battery 121 kJ"))
    code = main(["sim", str(other), "--plan", str(plan), "-o", str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert code == 1 and "plan rejected" in err
    assert "survey.plan:3: plan made for another version" in err
    assert not (tmp_path / "run").exists()


def test_a_plan_whose_prediction_lacks_a_component_is_rejected_naming_the_line(
        tmp_path, capsys):
    plan = write_plan(tmp_path, 120e3, 10800.0)
    body = plan.read_bytes()
    body = body[: body.rindex(b"crc32 ")]
    energy = next(line for line in body.split(b"\n") if line.startswith(b"energy "))
    body = body.replace(energy, energy.rsplit(b" ", 1)[0])
    plan.write_bytes(body + f"crc32 {zlib.crc32(body):08x}\n".encode())
    code = main(["sim", str(MISSION), "--plan", str(plan), "-o", str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert code == 1
    assert "plan rejected: " in err and "survey.plan:13: 'energy' takes 4 fields, found 3" in err
    assert not (tmp_path / "run").exists()


def test_a_plan_predicting_more_than_its_budget_is_refused(tmp_path, capsys):
    # the prediction is right (three hours), the budget under it: the plan contradicts itself
    plan = write_plan(tmp_path, 40e3, 10800.0)
    code = main(["sim", str(MISSION), "--plan", str(plan), "-o", str(tmp_path / "run")])
    assert code == 1 and not (tmp_path / "run" / "summary.json").exists()
    assert re.search(r"survey.plan:6: predicted_j 5\d{4}(\.\d)? J exceeds budget_j 40000 J",
                     capsys.readouterr().err)


def test_the_computer_draws_the_power_of_the_plan_s_board_and_clock(tmp_path, capsys):
    survey = tmp_path / "ts5500.mission"
    survey.write_text(MISSION.read_text().replace("computer ts7800 @ 300 MHz", "computer ts5500"))
    plan = write_plan(tmp_path, 120e3, 10800.0, board=("ts5500", 133.0), survey=survey)
    code, summary, _ = simulate(tmp_path, plan, capsys, survey)
    assert code == 0
    board = load_board("ts5500", 133.0)
    busy = board.busy_fraction(RUNTIME_CYCLES_PER_TICK, 1.0 / TICK_S)
    # idle between ticks, and one boot (20 s at 2.7 W) before the first
    assert board.boot_j == pytest.approx(54.0)
    assert summary["energy_by_component_j"]["computer"] == pytest.approx(
        float(board.power_w(busy)) * 10800.0 + board.boot_j)


# ---- with the planner's own plans ------------------------------------------------------

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def planner_plan(tmp_path: Path, budget_j: float | None = None,
                 occupancy_s: dict[str, float] | None = None) -> Path:
    """The planner's plan file for the survey mission (no report beside it);
    `occupancy_s` tells it how long the survey will last."""
    from gliderplan.planner.plan import plan_mission
    from gliderplan.planner.planfile import write_plan_bytes

    plan = plan_mission(check_file(str(MISSION)).mission, budget_j=budget_j,
                        occupancy_s=occupancy_s).plan
    path = tmp_path / "survey.plan"
    path.write_bytes(write_plan_bytes(plan))
    return path


def test_the_planner_s_plan_for_the_survey_passes(tmp_path, capsys):
    code, summary, _ = simulate(tmp_path, planner_plan(tmp_path), capsys)
    assert code == 0
    check = summary["plan_check"]
    assert check["verdict"] == "pass"
    assert check["simulated_j"] == pytest.approx(check["predicted_j"], rel=0.05)


def test_a_plan_made_for_one_hour_of_a_three_hour_survey_is_a_violation(tmp_path, capsys):
    plan = planner_plan(tmp_path, budget_j=40e3, occupancy_s={"survey": 3600.0})
    code, summary, err = simulate(tmp_path, plan, capsys)
    assert code == 3
    (cause,) = summary["plan_check"]["causes"]
    planned, flown = map(int, re.search(r"(\d+) inflections planned, (\d+) flown", cause).groups())
    assert flown == pytest.approx(3 * planned, rel=0.1)
    assert "1.00 h planned, 3.00 h flown" in cause
    assert "plan check: violation" in err


def test_the_annotated_fig2_flies_its_plan_within_the_prediction(tmp_path, capsys):
    plan = tmp_path / "fig2.plan"
    mission = EXAMPLES / "fig2_annotated.mission"
    assert main(["plan", str(mission), "-o", str(plan)]) == 0
    assert main(["sim", str(mission), "--plan", str(plan), "-o", str(tmp_path / "run")]) == 0
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    check = summary["plan_check"]
    # every state within 5 % of its own prediction, the tracking state s2 too (planned at
    # the band tracking flies on average)
    assert check["verdict"] == "pass" and check["causes"] == []
    assert check["simulated_j"] == pytest.approx(check["predicted_j"], rel=0.05)
    assert [name for name, s in summary["states"].items() if "predicted_j" in s] == \
        ["s1", "s2", "s3"]


def test_the_simulator_checks_a_flight_against_the_plan_file_alone(tmp_path, capsys,
                                                                    monkeypatch):
    from gliderplan.planner import plan as planner
    from gliderplan.planner.planfile import read_plan_file

    plan = planner_plan(tmp_path)
    predicted = read_plan_file(plan).states[0]

    def no_planning(*args, **kwargs):
        raise AssertionError("the simulator planned again")

    monkeypatch.setattr(planner, "plan_mission", no_planning)
    monkeypatch.setattr(planner, "solve_plan", no_planning)
    code, summary, _ = simulate(tmp_path, plan, capsys)
    assert code == 0
    survey = summary["states"]["survey"]
    assert survey["predicted_by_component_j"] == predicted.energy_by_component_j
    assert survey["predicted_time_s"] == predicted.time_s
    assert survey["simulated_j"] == pytest.approx(survey["predicted_j"], rel=0.05)


def test_a_run_over_its_prediction_says_so_even_within_its_budget(tmp_path, capsys):
    mission = EXAMPLES / "thermocline_survey.mission"
    plan = tmp_path / "survey.plan"
    assert main(["plan", str(mission), "-o", str(plan)]) == 0
    code = main(["sim", str(mission), "--plan", str(plan), "-o", str(tmp_path / "run")])
    err = capsys.readouterr().err
    check = json.loads((tmp_path / "run" / "summary.json").read_text())["plan_check"]
    assert code == 0 and check["simulated_j"] < check["budget_j"]
    assert check["simulated_j"] > check["predicted_j"] * 1.05
    assert check["verdict"] == "over prediction"
    assert "plan check: over prediction: " in err and "states over their own prediction:" in err
    # the state that overran, the component that overran most, and why
    assert any(re.match(r"track: .* \((\w+) \+[\d.]+ kJ\); \d+ inflections planned", c)
               for c in check["causes"])


# ---- values no vehicle can fly ---------------------------------------------------------


@pytest.mark.parametrize(("edit", "said"), [
    ((b" 0.454 233 ", b" 0.454 5000 "),
     ":11: state survey: profile 0: BALLAST_CC 5000 exceeds the vehicle's pump (233 cc)"),
    ((b" 0.454 233 ", b" 0.454 1e300 "),
     ":11: state survey: profile 0: BALLAST_CC 1e+300 exceeds the vehicle's pump"),
    ((b"\ncomputer ts7800 300\n", b"\ncomputer ts7800 133\n"),
     ":4: clock 133 MHz: the board has 300, 500 MHz"),
    ((b"\nstate survey 300 600 ", b"\nstate survey 300 1e300 "), ":11: cycle 1e+300 exceeds"),
], ids=["5000cc", "1e300cc", "133MHz", "cycle"])
@pytest.mark.parametrize("command", ["sim", "compile"])
def test_a_plan_no_vehicle_can_fly_is_refused_naming_the_line(tmp_path, capsys, edit, said,
                                                              command):
    """Values a plan's CRC vouches for but the vehicle cannot fly (a ballast past the pump,
    a clock the board lacks, a cycle of 1e300 s): `sim` refuses them as the runtime does,
    and `compile --plan` because the runtime's own reader refuses them."""
    plan = write_plan(tmp_path, 120e3, 10800.0)
    body = plan.read_bytes()
    body = body[: body.rindex(b"crc32 ")]
    assert edit[0] in body
    body = body.replace(*edit)
    plan.write_bytes(body + f"crc32 {zlib.crc32(body):08x}\n".encode())
    out = tmp_path / "out"
    code = main([command, str(MISSION), "--plan", str(plan), "-o", str(out)])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(err) == 1, err
    where = said.split(":")[1]
    if command == "sim":
        assert f"survey.plan{said}" in err[0]
    else:  # the runtime's reader words it in the plan format's field names
        assert "survey.plan" in err[0] and f"line {where}: " in err[0]
    assert not (out / "summary.json").exists() and not (out / "sim_budget").exists()


DEVICES_MISSION = """mission devices
horizon 2 h

state s1
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, depth, groundspeed, shear duty 0.5
  events
    case groundspeed > 0.3 && shear > 0 && missiontime >= 1800 exit
end
"""


@pytest.mark.parametrize("runtime", ["python", "c"])
def test_the_dvl_and_the_microstructure_logger_are_read_and_billed(tmp_path, runtime):
    # the DVL always on, the logger on half the time: both runtimes read their constant
    # readings (0.35 m/s, 0.01 1/s) and the simulator bills each device's preset
    mission = tmp_path / "devices.mission"
    mission.write_text(DEVICES_MISSION)
    assert main(["plan", str(mission), "-o", str(tmp_path / "d.plan")]) == 0
    assert main(["sim", str(mission), "--plan", str(tmp_path / "d.plan"), "--runtime",
                 runtime, "-o", str(tmp_path / "run")]) == 0
    trace = (tmp_path / "run" / "trace.csv").read_text().splitlines()[1:]
    assert trace == ["0,start,,s1,0", "1800,exit,s1,,0"]  # the event read both readings
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    billed, seconds = summary["energy_by_component_j"], summary["simulated_s"]
    dvl, logger = load_sensor("dvl"), load_sensor("logger")
    assert billed["dvl"] == pytest.approx(dvl.on_power_w * seconds, rel=0.01)
    # half the time, plus a warm-up at each switch-on (one per period of the plan)
    assert 0.5 * logger.on_power_w * seconds <= billed["logger"] \
        <= 0.6 * logger.on_power_w * seconds
    assert summary["plan_check"]["verdict"] == "pass"
