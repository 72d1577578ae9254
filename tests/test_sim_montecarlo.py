"""Monte Carlo as a user runs it: seeded scenarios, results that do not depend on the
workers, the files of a run, bad scenario files, Ctrl-C, progress."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gliderplan.cli.main import main
from gliderplan.language import check_file
from gliderplan.power_models import load_vehicle
from gliderplan.sim import FlightOptions, flight_setup, montecarlo
from gliderplan.sim.backends import scenario_executor
from gliderplan.sim.scenarios import (
    ScenarioFileError,
    draw_scenario,
    read_spec,
    scenario_seeds,
)

REPO = Path(__file__).resolve().parents[1]
FIG2 = REPO / "examples" / "fig2_annotated.mission"
SURVEY = REPO / "examples" / "thermocline_survey.mission"
FILES = {"scenarios.parquet", "summary.json", "energy.png", "exhaustion.png"}


def _job(seed: int = 7, budget_j: float = 60e3) -> montecarlo.Job:
    mission = check_file(str(FIG2)).mission
    setup = flight_setup(mission, FlightOptions(seed=seed, duration_s=2600.0))
    return montecarlo.Job(replace(setup, budget_j=budget_j), read_spec())


def test_a_scenario_is_its_seed_and_index_whatever_else_was_drawn():
    spec, vehicle = read_spec(), load_vehicle("slocum_g2_shallow")
    seeds = scenario_seeds(3, 5)
    first = [draw_scenario(spec, vehicle, i, s) for i, s in enumerate(seeds)]
    again = draw_scenario(spec, vehicle, 4, scenario_seeds(3, 5)[4])
    assert again == first[4]
    assert len({s.ocean.depth_m for s in first}) == 5  # the draws differ between scenarios
    assert all(6.0 <= s.ocean.depth_m <= 30.0 for s in first)  # clipped to its bounds
    assert first[0].vehicle.hotel_w != vehicle.hotel_w  # model figures are drawn too
    job = _job(seed=3)
    assert montecarlo.scenario_seed(job, 4).generate_state(2).tolist() == \
        seeds[4].generate_state(2).tolist()


def test_calibrated_spreads_and_correlations_come_first(tmp_path):
    text = (REPO / "power_models" / "data" / "vehicle_slocum_g3.toml").read_text()
    text = text.replace('value = 1.158, unit = "W"', 'value = 1.158, unit = "W", sd = 0.2', 1)
    path = tmp_path / "g3.toml"
    path.write_text(text)
    vehicle = load_vehicle(str(path))
    spec = read_spec()
    hotel = [draw_scenario(spec, vehicle, i, s).vehicle.hotel_w
             for i, s in enumerate(scenario_seeds(1, 400))]
    # the file's 0.2 W, not the scenario file's default 5 % (0.06 W)
    assert 0.15 < np.std(hotel) < 0.25


def test_results_do_not_depend_on_the_number_of_workers():
    job = _job()
    alone = montecarlo.run_montecarlo(job, 5)
    with scenario_executor(2) as pool:
        pooled = montecarlo.run_montecarlo(job, 5, pool, 2)
    assert [r["scenario"] for r in pooled.rows] == list(range(5))
    pd.testing.assert_frame_equal(alone.table(), pooled.table())
    assert alone.table()["energy_j"].nunique() == 5


def test_dask_local_cluster_gives_the_local_pools_results():
    pytest.importorskip("distributed")
    job = _job(seed=11)
    with scenario_executor(2) as pool:
        local = montecarlo.run_montecarlo(job, 4, pool, 2)
    with scenario_executor(2, "local") as dask:
        distributed = montecarlo.run_montecarlo(job, 4, dask, 2)
    pd.testing.assert_frame_equal(local.table(), distributed.table())
    assert distributed.table()["scenario"].tolist() == [0, 1, 2, 3]
    assert distributed.table()["energy_j"].gt(0).all()


def test_the_budget_verdict_follows_each_scenarios_battery():
    spent = montecarlo.run_montecarlo(_job(budget_j=1e9), 3).table()
    tight = float(spent["energy_j"].median())
    table = montecarlo.run_montecarlo(_job(budget_j=tight / 0.97), 3).table()
    assert (table["held"] == (table["energy_j"] <= table["budget_j"])).all()
    assert table["budget_j"].nunique() == 3  # each scenario's battery holds its own share
    exhausted = table.loc[~table["held"], "exhausted_s"]
    assert exhausted.notna().all() and (exhausted < table.loc[~table["held"],
                                                              "duration_s"]).all()


def test_wilson_interval_brackets_the_share():
    low, high = montecarlo.wilson_interval(95, 100)
    assert low < 0.95 < high
    assert montecarlo.wilson_interval(10, 10)[1] == pytest.approx(1.0)
    assert montecarlo.wilson_interval(10, 10)[0] == pytest.approx(0.7225, abs=1e-3)


def test_command_writes_its_files_and_says_how_likely(tmp_path, capsys):
    out = tmp_path / "mc"
    args = ["montecarlo", str(FIG2), "--scenarios", "4", "--workers", "1", "--seed", "5",
            "-o", str(out)]
    assert main(args) == 0
    assert {p.name for p in out.iterdir()} == FILES | {".gliderplan-run"}
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scenarios"] == 4 and summary["budget_held"] == 4
    low, high = summary["probability_interval_95"]
    assert low < 1.0 and high == pytest.approx(1.0)
    assert set(summary["energy_j"]) == {"p05", "p50", "p95"}
    table = pd.read_parquet(out / "scenarios.parquet")
    for column in ("scenario", "energy_j", "duration_s", "quality", "end_state", "held",
                   "overran_component", "drawn_thermocline_depth_m", "time_s1_s"):
        assert column in table
    assert (table["end_state"] == "s3").all()
    assert "the budget held in 4 of 4 scenarios: 100.0 %" in capsys.readouterr().out
    for png in ("energy.png", "exhaustion.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_ctrl_c_keeps_the_scenarios_that_finished(tmp_path, monkeypatch, capsys):
    real = montecarlo.fly_scenario

    def interrupted_at_two(job, index):
        if index == 2:
            raise KeyboardInterrupt
        return real(job, index)

    monkeypatch.setattr(montecarlo, "fly_scenario", interrupted_at_two)
    out = tmp_path / "mc"
    code = main(["montecarlo", str(FIG2), "--scenarios", "5", "--workers", "1", "-o",
                 str(out)])
    assert code == 130
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] and summary["scenarios"] == 2
    assert "2 of 5 scenarios finished" in capsys.readouterr().err


def test_ctrl_c_on_a_pool_keeps_what_finished_and_the_log_has_a_line_per_update(tmp_path):
    out = tmp_path / "mc"
    run = subprocess.Popen(
        [sys.executable, "-m", "gliderplan.cli", "montecarlo", str(SURVEY), "--scenarios",
         "200", "--workers", "2", "-o", str(out)],
        stderr=subprocess.PIPE, text=True, start_new_session=True,
        env={**os.environ, "GLIDERPLAN_PROGRESS_S": "0"})  # a line per update in the log
    logged, counts = [], []
    for line in run.stderr:  # a log, not a terminal: plain lines
        logged.append(line)
        counts.append(int(line.split("progress: ")[1].split(" of ")[0]))
        if counts[-1] >= 3:
            break
    os.killpg(run.pid, signal.SIGINT)  # Ctrl-C at a terminal reaches the workers too
    said = run.stderr.read()
    assert run.wait(timeout=120) == 130
    summary = json.loads((out / "summary.json").read_text())
    finished = summary["scenarios"]
    assert summary["interrupted"] and 3 <= finished < 200
    table = pd.read_parquet(out / "scenarios.parquet")
    assert len(table) == finished and table["scenario"].is_unique
    assert f"{finished} of 200 scenarios finished" in said and "Traceback" not in said
    # scenario 0 first, then a line as each batch finishes (a batch may hold several)
    assert counts[0] == 1 and counts == sorted(set(counts)) and "\r" not in "".join(logged)


def test_progress_is_one_bar_redrawn_in_place_on_a_terminal(monkeypatch):
    from gliderplan.cli.progress import ProgressBar

    class Terminal(io.StringIO):
        def isatty(self) -> bool:
            return True

    terminal = Terminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    bar = ProgressBar(lambda done, total: f"{done:.0f} of {total:.0f} scenarios")
    for done in (1, 2, 3):
        bar(done, 3)
    bar.finish()
    shown = terminal.getvalue()
    assert shown.count("\r") == 3 and shown.count("\n") == 1
    assert shown.startswith("\r[##########....................] 1 of 3 scenarios")
    assert shown.endswith("\r[##############################] 3 of 3 scenarios\n")


@pytest.mark.parametrize(("text", "message"), [
    ('kind = "board"\n', 'kind: expected "scenarios"'),
    ('kind = "scenarios"\n[ocean]\n', "ocean.thermocline_depth_m: missing"),
    ('kind = "scenarios"\n[ocean]\nthermocline_depth_m = { dist = "gamma" }\n',
     "dist: expected fixed, uniform or normal"),
    ('kind = "scenarios"\n[ocean]\nthermocline_depth_m = { dist = "uniform", low = 3 }\n',
     "thermocline_depth_m: high: missing"),
    ('kind = "scenarios"\n[ocean]\nthermocline_depht_m = 3\n',
     "ocean.thermocline_depht_m: unknown key"),
    ('kind = "scenarios"\n[vehicle]\nhotel_powr = { relative_sd = 0.1 }\n',
     "vehicle.hotel_powr: not a vehicle figure"),
    ("kind = \n", "not valid TOML"),
])
def test_bad_scenario_files_name_file_and_key(tmp_path, capsys, text, message):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(ScenarioFileError, match=message):
        read_spec(path)
    code = main(["montecarlo", str(FIG2), "--scenarios", "2", "--scenario-file", str(path),
                 "-o", str(tmp_path / "mc")])
    err = capsys.readouterr().err
    assert code == 1 and f"{path}: " in err and "Traceback" not in err
    assert not (tmp_path / "mc").exists()


def test_bad_usage_exits_2(tmp_path, capsys):
    for extra in (["--scenarios", "0"], ["--scenarios", "2", "--workers", "0"],
                  ["--scenarios", "2", "--scenario-file", str(tmp_path / "none.toml")],
                  ["--scenarios", "2", "--plan", str(tmp_path / "none.plan")]):
        assert main(["montecarlo", str(FIG2), *extra, "-o", str(tmp_path / "mc")]) == 2
    assert "Traceback" not in capsys.readouterr().err


def test_montecarlo_mission_is_the_command_as_one_call(tmp_path):
    from gliderplan.sim.montecarlo import montecarlo_mission

    mission = check_file(str(FIG2)).checked()
    setup = flight_setup(mission, FlightOptions(seed=7, duration_s=2600.0))
    run = montecarlo_mission(setup, tmp_path / "mc", scenarios=3)
    assert {p.name for p in run.files} == FILES and all(p.is_file() for p in run.files)
    assert [r["scenario"] for r in run.result.rows] == [0, 1, 2]
    assert json.loads((tmp_path / "mc" / "summary.json").read_text()) == run.summary
    assert run.summary["scenarios"] == 3 and run.summary["seed"] == 7
    # what was flown: every scenario flies Fig. 2 to its exit at 2500 s, within budget, on
    # energy of its own draws; the file and the summary say what the runs did
    table = pd.read_parquet(tmp_path / "mc" / "scenarios.parquet")
    pd.testing.assert_frame_equal(table, run.result.table())
    assert (table["end_state"] == "s3").all() and (table["ended"] == "exit").all()
    assert (table["duration_s"] == 2500.0).all() and table["held"].all()
    assert table["energy_j"].gt(0).all() and table["energy_j"].nunique() == 3
    assert run.summary["ended"] == {"exit": 3} and run.summary["budget_held"] == 3
    assert run.summary["energy_j"]["p50"] == pytest.approx(table["energy_j"].median())


def test_montecarlo_puts_every_glider_in_the_water_at_the_start(tmp_path, capsys,
                                                               monkeypatch):
    from gliderplan.cli.main import main
    from gliderplan.sim import flight

    fig2 = str(Path(__file__).resolve().parents[1] / "examples" / "fig2.mission")
    starts = []
    real_fly = flight.fly

    def fly(mission, ocean, config, *args, **kwargs):
        starts.append((config.start_lat_deg, config.start_lon_deg, config.start_epoch_s))
        return real_fly(mission, ocean, config, *args, **kwargs)

    monkeypatch.setattr(flight, "fly", fly)
    assert main(["montecarlo", fig2, "--scenarios", "2", "--workers", "1", "--duration",
                 "600s", "--start", "39.3,-73.9,2016-06-23T12:00Z",
                 "-o", str(tmp_path / "mc")]) == 0
    assert starts == [(39.3, -73.9, 1466683200.0)] * 2
    assert main(["montecarlo", fig2, "--scenarios", "2", "--start", "39.3",
                 "-o", str(tmp_path / "bad")]) == 2
    assert "not an ISO 8601 time" in capsys.readouterr().err


def test_the_budget_is_the_battery_less_its_reserve_times_the_share_drawn(tmp_path):
    """Fig. 2 carries 1.2 kWh and keeps 15 % in reserve: a plan may spend 1.02 kWh
    (3.672 MJ), the planner, `check` and a run without a plan alike; a scenario whose pack
    holds 90 % of its rating may spend 0.9 of that."""
    from gliderplan.planner.hardware import load_hardware
    from gliderplan.planner.limits import flight_limits
    from gliderplan.power_models.battery import drawn_budget_j, usable_budget_j

    assert usable_budget_j(1.2 * 3.6e6, 0.15) == pytest.approx(3.672e6)
    assert drawn_budget_j(3.672e6, 0.9) == pytest.approx(3.3048e6)
    mission = check_file(str(FIG2)).mission
    assert load_hardware(mission).budget_j == pytest.approx(3.672e6)
    assert flight_limits(mission).max_budget_j == pytest.approx(3.672e6)
    setup = flight_setup(mission, FlightOptions(seed=2, duration_s=600.0))
    assert setup.budget_j == pytest.approx(3.672e6)
    run = montecarlo.montecarlo_mission(setup, tmp_path, scenarios=3)
    assert run.summary["budget_j"] == pytest.approx(3.672e6)
    table = run.result.table()
    assert table["budget_j"].to_numpy() == pytest.approx(
        3.672e6 * table["drawn_usable_fraction_1"].to_numpy())


STARTING_DASK = """
import os, signal, sys
import distributed
from gliderplan.contract import interrupts
from gliderplan.sim.backends import scenario_executor

class Interrupted(distributed.LocalCluster):  # the user's Ctrl-C while the workers start
    def __init__(self, *args, **kwargs):
        os.kill(os.getpid(), signal.SIGINT)
        super().__init__(*args, **kwargs)

distributed.LocalCluster = Interrupted
with interrupts.handling():
    try:
        with scenario_executor(2, "local") as executor:
            print("started:", executor.submit(sum, (1, 2)).result())
    except KeyboardInterrupt:
        print("stopped:", interrupts.stopped())
        sys.exit(130)
print("the Ctrl-C was lost")
"""


def test_a_ctrl_c_while_dask_s_workers_start_stops_the_run_and_no_worker_takes_it():
    """A Ctrl-C while the local cluster starts is kept until it has started, then stops
    the run (it used to be ignored there, and the run went on to its end); the workers,
    which must not take it, print no traceback."""
    run = subprocess.run([sys.executable, "-c", STARTING_DASK], capture_output=True,
                         text=True, timeout=300)
    assert (run.returncode, run.stdout) == (130, "stopped: True\n"), run.stderr
    assert "Traceback" not in run.stderr
