"""Plans on simulated occupancy (`plan --occupancy-from-sim`): the plan predicts what
flying it gives, where the static timeline cannot know when an exit on a reading fires."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.language import check_file
from gliderplan.planner.hardware import load_hardware
from gliderplan.planner.simulated import MAX_ROUNDS, Flown, plan_on_simulation

REPO = Path(__file__).resolve().parents[1]
SURVEY = REPO / "examples" / "thermocline_survey.mission"


def _flown_states(tmp_path: Path, plan: Path, name: str) -> dict:
    out = tmp_path / name
    assert main(["sim", str(SURVEY), "--plan", str(plan), "-o", str(out)]) == 0
    return json.loads((out / "summary.json").read_text())


def test_a_plan_on_simulated_occupancy_predicts_the_flight(tmp_path, capsys):
    timeline, simulated = tmp_path / "timeline.plan", tmp_path / "simulated.plan"
    assert main(["plan", str(SURVEY), "-o", str(timeline)]) == 0
    assert main(["plan", str(SURVEY), "--occupancy-from-sim", "-o", str(simulated)]) == 0
    out = capsys.readouterr().out
    assert "simulated, one flight in the bench ocean with the CTD's noise, seed 0" in out
    assert "occupancy settled after" in out
    report = json.loads(Path(f"{simulated}.json").read_text())
    assert report["time_source"] == "simulation"

    # the timeline plans find_thermocline to its missiontime guards (17.8 h); the glider
    # finds the thermocline in minutes and tracks it for the rest of the mission
    wrong = _flown_states(tmp_path, timeline, "timeline")["states"]
    assert wrong["track"]["time_s"] > 2 * wrong["track"]["predicted_time_s"]
    flown = _flown_states(tmp_path, simulated, "simulated")
    for name, state in flown["states"].items():
        assert state["time_s"] == pytest.approx(state["predicted_time_s"], rel=0.01), name
    # the band the glider tracks is the one found in flight, not the variables' initial
    # 5-40 m: its inflections, hence its pump energy, are planned as flown
    track = flown["states"]["track"]
    assert track["inflections"] == pytest.approx(track["predicted_inflections"], rel=0.2)
    assert wrong["track"]["inflections"] > 3 * wrong["track"]["predicted_inflections"]
    assert flown["energy_j"] == pytest.approx(flown["plan_check"]["predicted_j"], rel=0.05)


def test_occupancy_from_scenarios_is_their_mean(tmp_path, capsys):
    plan = tmp_path / "p.plan"
    assert main(["plan", str(SURVEY), "--occupancy-from-sim", "--scenarios", "3",
                 "--workers", "1", "--seed", "4", "-o", str(plan)]) == 0
    assert "simulated, the mean of 3 scenarios drawn from scenarios_default.toml, seed 4" \
        in capsys.readouterr().out
    states = {s["name"]: s for s in json.loads(Path(f"{plan}.json").read_text())["states"]}
    # hours at most as flown (its temp is duty-cycled by the plan), not the timeline's 17.8 h
    assert 0 < states["find_thermocline"]["time_s"] < 3 * 3600


def _alternating(plans: list) -> object:
    """A flight whose occupancy flips with every plan flown (never settles)."""
    def fly_plan(plan) -> Flown:  # noqa: ANN001
        plans.append(plan)
        long = len(plans) % 2 == 0
        return Flown({"launch": 600.0, "find_thermocline": 7200.0 if long else 600.0,
                      "track": 100000.0, "surface_fix": 4500.0, "recover": 3600.0},
                     {"launch": 1, "find_thermocline": 9, "track": 14, "surface_fix": 5,
                      "recover": 1}, {})
    return fly_plan


def test_an_occupancy_that_never_settles_is_said_so():
    mission = check_file(str(SURVEY)).mission
    plans: list = []
    result = plan_on_simulation(mission, load_hardware(mission), _alternating(plans),
                                "a test flight")
    assert len(plans) == MAX_ROUNDS
    said = result.plan.assumptions[-1].text
    assert said.startswith(f"occupancy NOT settled after {MAX_ROUNDS} re-plans")
    assert "find_thermocline by 1.83 h" in said


@pytest.mark.parametrize(("extra", "message"), [
    (["--confidence", "0.9"], "--confidence and --occupancy-from-sim: choose one"),
    (["--scenarios", "0"], "--scenarios 0: must be between 1 and 1,000,000"),
])
def test_bad_occupancy_options_exit_2(capsys, extra, message):
    assert main(["plan", str(SURVEY), "--occupancy-from-sim", *extra]) == 2
    assert message in capsys.readouterr().err
