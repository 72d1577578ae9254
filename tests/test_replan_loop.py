"""The shore in the simulator's loop (sim/replanning.py): at each surfacing the glider's
report goes up, the rest of the mission is replanned, the plan update goes down and the
runtime applies it; `sim --replan-every surfacing` and `montecarlo --replan` side by side
with the plan alone; scenario files that say where the truth drifts from the model."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.language import check_file
from gliderplan.planner import make_plan
from gliderplan.power_models import load_vehicle
from gliderplan.power_models.devices import base_power_w, sensor_on
from gliderplan.sim import FlightOptions, flight_setup, run_mission
from gliderplan.sim.montecarlo import montecarlo_mission
from gliderplan.sim.scenarios import (
    ScenarioFileError,
    draw_scenario,
    read_spec,
    scenario_seeds,
)

ROOT = Path(__file__).resolve().parents[1]
SHORT = str(ROOT / "tests" / "missions" / "replan_short.mission")
KEY = bytes(range(32))


@pytest.fixture(scope="module")
def short():
    return check_file(SHORT).checked()


@pytest.fixture(scope="module")
def signed(tmp_path_factory, short):
    """The short line survey's plan at confidence 0.95 (60 scenarios), signed as plan 5,
    and the vehicle's key."""
    where = tmp_path_factory.mktemp("vehicle")
    key = where / "vehicle.key"
    key.write_text(KEY.hex() + "\n")
    key.chmod(0o600)
    plan = where / "held.plan"
    make_plan(short, output=plan, sign=key, seq=5, confidence=0.95, scenarios=60, workers=2)
    return plan, key


def test_sim_replans_at_each_surfacing_and_counts_the_link(tmp_path, signed, short):
    plan, key = signed
    setup = flight_setup(short, FlightOptions(plan_path=plan, key_path=key, duration_s=86400.0))
    result = run_mission(setup, tmp_path / "run", replan_every="surfacing", plots=False)
    link = result.replanning
    assert link["surfacings"] == result.record.surfacings >= 8
    assert link["updates_applied"] >= 1 and link["updates_refused"] == 0
    assert 0 < link["update_bytes_max"] <= link["sbd_limits_bytes"]["down"] == 270
    assert link["up_bytes"] <= link["surfacings"] * link["sbd_limits_bytes"]["up"]
    assert link["up_bytes_per_day"] == pytest.approx(link["up_bytes"], rel=0.01)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["replanning"]["confidence"] == pytest.approx(0.95, abs=0.01)
    lines = (tmp_path / "run" / "replans.csv").read_text().splitlines()
    assert lines[0].startswith("time_s,used_j,voltage_v,plan_seq,status")
    assert len(lines) == 1 + link["surfacings"]
    seqs = [int(line.split(",")[3]) for line in lines[1:]]
    assert seqs[0] == 5 and seqs == sorted(seqs) and seqs[-1] > 5  # the glider's plan moved on


def test_the_c_runtimes_apply_the_updates_the_python_executor_does(tmp_path, signed, short):
    """The board binary over its link, the step in this process and the reference
    executor get the updates on the same ticks: the same updates, the same flight."""
    from gliderplan.planner.planfile import read_plan_bytes
    from gliderplan.planner.signing import read_key
    from gliderplan.sim.flight import fly
    from gliderplan.sim.loop import RunConfig
    from gliderplan.sim.ocean import load_ocean
    from gliderplan.sim.replanning import ShoreLoop

    plan_file, key_file = signed
    held = plan_file.read_bytes()
    plan = read_plan_bytes(held, short)
    vehicle = load_vehicle(short.vehicle)
    config = RunConfig(duration_s=8 * 3600.0)
    records, shores = {}, {}
    for runtime in ("python", "c", "step"):
        shore = ShoreLoop(short, held, read_key(key_file), tick_s=config.tick_s,
                          spec=read_spec())
        records[runtime] = fly(short, load_ocean("bench"), config, vehicle, plan,
                               str(plan_file), runtime, key_path=str(key_file), shore=shore)
        shores[runtime] = shore
    for runtime in ("c", "step"):
        assert shores[runtime].log.applied == shores["python"].log.applied >= 2, runtime
        assert [e.get("update_bytes") for e in shores[runtime].log.events] == \
            [e.get("update_bytes") for e in shores["python"].log.events], runtime
        for column in ("state", "sensor_power", "depth_m"):
            assert np.array_equal(records[runtime].columns[column],
                                  records["python"].columns[column]), (runtime, column)


def test_montecarlo_replan_reports_both_side_by_side(tmp_path, signed, short, capsys):
    plan, key = signed
    setup = flight_setup(short, FlightOptions(plan_path=plan, key_path=key, duration_s=86400.0))
    run = montecarlo_mission(setup, tmp_path / "mc", scenarios=4, replan=True,
                             scenario_file="hungry_dvl")
    s = run.summary
    assert {"hold_rate", "hold_rate_static", "quality", "quality_static",
            "update_bytes_max"} <= set(s)
    assert 0 < s["update_bytes_max"] <= 270
    assert s["link"]["sbd_limits_bytes"] == {"up": 340, "down": 270}
    table = run.result.table()
    assert {"held_static", "quality_static", "energy_j_static", "down_bytes"} <= set(table)
    assert s["quality"] == pytest.approx(table["quality"].mean())
    code = main(["montecarlo", SHORT, "--plan", str(plan), "--key", str(key), "--replan",
                 "--scenarios", "2", "--workers", "1", "--duration", "6h", "--json", "-o",
                 str(tmp_path / "cli")])
    assert code == ExitCode.OK
    said = json.loads(capsys.readouterr().out)
    assert said["replan"] is True and said["scenarios"] == 2
    # the plan was made at 0.95: both flights fly it, the shore replans at 0.95
    assert said["confidence"] == s["confidence"] == 0.95
    assert said["plan_flown"] == "the plan as given, planned at confidence 0.95"


def test_a_plan_made_on_the_model_is_planned_at_the_confidence_before_launch(tmp_path, short):
    """A plan made without --confidence states none: flown alone it would be judged
    against the replanned flight at another confidence. Both start from it replanned
    before launch at the confidence: signed as a later plan, its duties changed, and the
    shore, asked again at launch, changes nothing."""
    from gliderplan.planner.planfile import read_plan_bytes
    from gliderplan.planner.replan import Replanner
    from gliderplan.planner.signing import check_signature
    from gliderplan.sim.replanning import plan_at_confidence

    key = tmp_path / "vehicle.key"
    key.write_text(KEY.hex() + "\n")
    key.chmod(0o600)
    model_plan = tmp_path / "model.plan"
    make_plan(short, output=model_plan, sign=key, seq=3)
    held = model_plan.read_bytes()
    prior = read_spec().model()
    launched, confidence, how = plan_at_confidence(short, held, KEY, confidence=None,
                                                   spec=prior)
    assert confidence == 0.95 and "replanned before launch at confidence 0.95" in how
    assert check_signature(launched, KEY) > 3
    before, after = read_plan_bytes(held, short), read_plan_bytes(launched, short)
    assert after.budget_j == before.budget_j and after.states != before.states
    again = Replanner(short, launched, confidence=0.95, spec=prior).at_launch(launched)
    assert again.status == "unchanged"  # what the shore would plan at 0.95 at launch
    setup = flight_setup(short, FlightOptions(plan_path=model_plan, key_path=key,
                                              duration_s=3 * 3600.0))
    run = montecarlo_mission(setup, tmp_path / "mc", scenarios=1, replan=True)
    assert run.summary["confidence"] == 0.95 and run.summary["plan_flown"] == how


def test_replanning_holds_the_budget_where_a_hungrier_device_breaks_the_plan_alone(
        tmp_path, signed, short):
    """The DVL draws 60 % more than the model says: the plan made at 95 % on the model
    holds its budget in fewer scenarios than it promised; replanned at each surfacing, the
    same scenarios hold it at least as often as promised."""
    plan, key = signed
    drift = tmp_path / "hungrier.toml"
    drift.write_text('kind = "scenarios"\nbase = "default"\n[drift]\n'
                     '"devices.dvl.on_power" = 1.6\n')
    run = montecarlo_mission(flight_setup(short, FlightOptions(plan_path=plan, key_path=key)),
                             tmp_path / "mc", scenarios=40, replan=True, scenario_file=drift,
                             workers=2)
    s = run.summary
    assert s["hold_rate_static"] < 0.95 <= s["hold_rate"]


def test_the_truth_drifts_from_the_model_where_a_scenario_file_says():
    vehicle = load_vehicle("slocum_g2_shallow")
    seed = scenario_seeds(3, 1)[0]
    model = draw_scenario(read_spec(), vehicle, 0, seed)
    for name, check in (
        ("hungry_dvl", lambda s: sensor_on(s.vehicle, "dvl").on_power_w == pytest.approx(
            1.3 * sensor_on(model.vehicle, "dvl").on_power_w)),
        ("weak_battery", lambda s: s.usable_fraction == pytest.approx(
            0.9 * model.usable_fraction)),
        ("strong_current", lambda s: math.hypot(s.current.north_mps, s.current.east_mps)
         == pytest.approx(3 * math.hypot(model.current.north_mps, model.current.east_mps))),
    ):
        spec = read_spec(name)
        drifted = draw_scenario(spec, vehicle, 0, seed)
        assert check(drifted), name
        assert drifted.ocean == model.ocean  # the same draws, the drift on top
        assert spec.model().drift == {} and spec.model().ocean == read_spec().ocean


def test_a_device_the_hotel_load_holds_drifts_without_moving_the_rest(tmp_path):
    """The optics are in the calibrated hotel load: 30 % hungrier optics raise the hotel
    load by what they add, so the base load (the rest of the glider) stays."""
    drift = tmp_path / "optics.toml"
    drift.write_text('kind = "scenarios"\nbase = "default"\n[drift]\n'
                     '"devices.optics.on_power" = 1.3\n')
    vehicle = load_vehicle("slocum_g2_shallow")
    seed = scenario_seeds(0, 1)[0]
    model = draw_scenario(read_spec(), vehicle, 0, seed).vehicle
    truth = draw_scenario(read_spec(drift), vehicle, 0, seed).vehicle
    assert sensor_on(truth, "optics").on_power_w == pytest.approx(
        1.3 * sensor_on(model, "optics").on_power_w)
    assert base_power_w(truth) == pytest.approx(base_power_w(model))


@pytest.mark.parametrize("text, said", [
    ('kind = "scenarios"\nbase = "default"\n[drift]\nwind_factor = 2\n',
     "drift.wind_factor: neither current_speed_factor nor usable_fraction_factor"),
    ('kind = "scenarios"\nbase = "default"\n[drift]\ncurrent_speed_factor = -1\n',
     "drift.current_speed_factor: expected a factor > 0"),
    ('kind = "scenarios"\nbase = "stormy"\n', "base: expected the name of a shipped"),
])
def test_a_bad_drift_is_one_clear_error(tmp_path, text, said):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ScenarioFileError, match=said):
        read_spec(path)


def test_a_mission_that_weighs_no_sensor_has_no_quality_and_its_summary_is_json():
    """Without a weighted sensor the flown quality is no number: the summary says null
    (JSON has no NaN), not NaN, with and without replanning."""
    import pandas as pd

    from gliderplan.sim.montecarlo import LINK_COLUMNS, replanning

    table = pd.DataFrame({"held": [True, False], "held_static": [True, True],
                          "duration_s": [86400.0, 86400.0], "quality": [math.nan] * 2,
                          "quality_static": [math.nan] * 2,
                          **{name: [1, 2] for name in LINK_COLUMNS}})
    said = replanning(table)
    assert said["quality"] is None and said["quality_static"] is None
    assert said["hold_rate"] == 0.5
    assert json.loads(json.dumps(said, allow_nan=False))["quality"] is None
    from gliderplan.cli.montecarlo import _replanned

    said.update(scenarios=2, plan_flown="the plan given")
    assert "no quality as flown: the mission weighs no sensor" in _replanned("m", said)
