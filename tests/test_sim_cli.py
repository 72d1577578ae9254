"""`gliderplan sim` as a user runs it: the files of a run, their columns, and bad input."""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import modules_loaded_by

from gliderplan.cli.main import main
from gliderplan.cli.sim import parse_duration_s
from gliderplan.contract import MAX_EXPRESSION_DEPTH
from gliderplan.contract.errors import UsageError
from gliderplan.contract.files import RUN_MARKER

REPO = Path(__file__).resolve().parents[1]
FIG2 = REPO / "examples" / "fig2.mission"
FILES = {"trace.csv", "timeseries.parquet", "summary.json", "depth.png", "energy.png"}
WRITTEN = FILES | {RUN_MARKER}  # a run's folder: its files and the marker saying what wrote it


def test_a_run_writes_every_file(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "--seed", "3", "-o", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == WRITTEN
    assert (out / "trace.csv").read_text() == (
        "time_s,kind,from_state,to_state,stack_depth\n"
        "0,start,,s1,0\n500,call,s1,s2,1\n1500,return,s2,s1,0\n"
        "2000,goto,s1,s3,0\n2500,exit,s3,,0\n")
    for png in ("depth.png", "energy.png"):
        assert (out / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "sampleMission: exit after 2500 s" in capsys.readouterr().err


def test_a_run_loads_no_library_it_does_not_use(tmp_path):
    """`sim` writes its files without pandas, scipy or the planner's solvers (pandas alone
    costs a run half a second of start-up)."""
    code, loaded = modules_loaded_by(["sim", str(FIG2), "-o", str(tmp_path / "run")])
    assert (code, loaded & {"pandas", "scipy", "cvxpy", "clarabel", "xarray"}) == (0, set())
    assert {p.name for p in (tmp_path / "run").iterdir()} == WRITTEN


def test_timeseries_columns_and_summary(tmp_path):
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "-o", str(out)]) == 0
    table = pd.read_parquet(out / "timeseries.parquet")
    for column in ("time_s", "depth_m", "pitch_rad", "temperature_c", "temp_reading_c",
                   "state", "stack_depth",
                   "temp_on", "oxygen_on", "power_hotel_w", "power_pump_w",
                   "power_computer_w", "power_total_w", "battery_remaining_j"):
        assert column in table.columns, column
    # sebastian's hotel load holds its CTD: it is billed apart, only while it runs (s2)
    assert (table["power_ctd_w"] > 0).groupby(table["state"]).any().to_dict()["s2"]
    assert not (table["power_ctd_w"] > 0)[table["state"] == "s1"].any()
    assert len(table) == 626 and table["time_s"].iloc[-1] == 2500.0
    flying = table[table["state"] != ""]  # the last row: the tick of the exit
    assert flying["temp_on"].groupby(flying["state"]).any().to_dict() == {
        "s1": False, "s2": True, "s3": False}  # only s2 logs temp
    assert flying["temp_on"][flying["state"] == "s2"].all()
    # the CTD's reading is sent in the ticks after a COMMAND that powers it
    sent = table["temp_reading_c"].notna()
    powered_before = table["temp_on"].shift(1, fill_value=False)
    assert sent.equals(powered_before) and sent.sum() == 250  # 500-1500 s at 4 s
    read = table[sent]
    assert (read["temp_reading_c"] - read["temperature_c"]).abs().max() < 0.1
    assert set(table["stack_depth"][table["state"] == "s2"]) == {1}
    summary = json.loads((out / "summary.json").read_text())
    total = summary["energy_j"]
    assert total == pytest.approx(sum(summary["energy_by_component_j"].values()))
    assert total == pytest.approx(sum(s["simulated_j"] for s in summary["states"].values()))
    assert total == pytest.approx((table["power_total_w"] * 4.0).sum())
    assert table["battery_remaining_j"].iloc[-1] == pytest.approx(7.8e6 - total)
    assert summary["plan_check"]["verdict"] == "no plan"


def test_duration_ends_a_run_that_has_not_exited(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "--duration", "30min", "-o", str(out)]) == 0
    trace = (out / "trace.csv").read_text().splitlines()
    assert trace[-1] == "1500,return,s2,s1,0"  # no goto (2000 s) or exit (2500 s)
    assert pd.read_parquet(out / "timeseries.parquet")["time_s"].iloc[-1] == 1800.0
    assert json.loads((out / "summary.json").read_text())["ended"] == "duration"


@pytest.mark.parametrize("text, seconds", [
    ("3600s", 3600.0), ("90min", 5400.0), ("6h", 21600.0), ("30d", 2592000.0), ("1.5h", 5400.0)])
def test_durations_take_units(text, seconds):
    assert parse_duration_s(text) == seconds


@pytest.mark.parametrize("text", ["3600", "6 hours", "-1h", "0s", "h", "1e400s"])
def test_bad_durations_are_usage_errors(text):
    with pytest.raises(UsageError, match="--duration"):
        parse_duration_s(text)


@pytest.mark.parametrize("args, code, message", [
    (["--duration", "soon"], 2, "--duration 'soon': expected a number with a unit"),
    (["--ocean", "atlantis"], 2, "no such ocean file or preset"),
    (["--plan", "missing.plan"], 2, "missing.plan: no such file"),
    (["--current", "north"], 2, "--currents 'north': no such file or directory"),
    (["--tick", "0"], 2, "--tick 0"),
    (["--floor", "-3"], 2, "--floor -3.0: the sea floor's depth must be a finite number"),
    (["--floor", "0"], 2, "--floor 0.0: the sea floor's depth must be a finite number"),
    (["--floor", "nan"], 2, "--floor nan: the sea floor's depth must be a finite number"),
    (["--floor", "deep"], 2, "--floor 'deep': expected the sea floor's depth in metres"),
])
def test_bad_input_is_a_message_not_a_traceback(tmp_path, capsys, args, code, message):
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), *args, "-o", str(out)]) == code
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not out.exists()  # nothing half-written


def test_a_bad_ocean_file_names_file_and_line(tmp_path, capsys):
    water = tmp_path / "water.csv"
    water.write_text("depth_m,temperature_c\n0,20\n10,cold\n")
    assert main(["sim", str(FIG2), "--ocean", str(water), "-o", str(tmp_path / "r")]) == 1
    assert f"{water}:3: not a number" in capsys.readouterr().err


def test_a_bad_plan_file_names_the_line(tmp_path, capsys):
    plan = tmp_path / "fig2.plan"
    plan.write_text("GPPLAN 3\nmission sampleMission\n")
    assert main(["sim", str(FIG2), "--plan", str(plan), "-o", str(tmp_path / "r")]) == 1
    assert f"plan rejected: {plan}:3: expected a 'hash' line" in capsys.readouterr().err


def test_a_measured_profile_file_colours_the_run(tmp_path):
    water = tmp_path / "water.csv"
    water.write_text("depth_m,temperature_c\n0,18\n8,18\n12,9\n40,9\n")
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "--ocean", str(water), "-o", str(out)]) == 0
    table = pd.read_parquet(out / "timeseries.parquet")
    assert table["temperature_c"].max() == pytest.approx(18.0)
    assert table["temperature_c"][table["depth_m"] > 15].max() == pytest.approx(9.0)


def test_rerunning_into_the_same_directory_replaces_the_files(tmp_path):
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "--duration", "10min", "-o", str(out)]) == 0
    assert main(["sim", str(FIG2), "-o", str(out)]) == 0
    assert (out / "trace.csv").read_text().endswith("2500,exit,s3,,0\n")
    assert {p.name for p in out.iterdir()} == WRITTEN  # no temporary files left behind


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) for the runtime")
def test_the_c_runtime_keeps_its_state_directory_when_asked(tmp_path, capsys):
    out, state = tmp_path / "run", tmp_path / "state"
    assert main(["sim", str(FIG2), "--runtime", "c", "--state-dir", str(state),
                 "-o", str(out)]) == 0, capsys.readouterr().err
    # the runtime's own event log says what the simulator's trace says
    rows = (out / "trace.csv").read_text().splitlines()[1:]
    assert (state / "events.log").read_text().splitlines() == [
        " ".join(field or "-" for field in row.split(",")) for row in rows]
    assert (state / "checkpoint").stat().st_size > 0
    assert {p.name for p in out.iterdir()} == WRITTEN

    # a second flight into it would resume the first one's checkpoint: refused
    again = tmp_path / "again"
    assert main(["sim", str(FIG2), "--runtime", "c", "--state-dir", str(state),
                 "-o", str(again)]) == 2
    err = capsys.readouterr().err
    assert f"--state-dir {state}: holds an earlier flight's checkpoint, events.log," in err
    assert "Traceback" not in err and not again.exists()


def test_only_the_c_runtime_keeps_a_state_directory(tmp_path, capsys):
    out, state = tmp_path / "run", tmp_path / "state"
    assert main(["sim", str(FIG2), "--state-dir", str(state), "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"--state-dir {state}: only the C runtime keeps one (--runtime c)" in err
    assert not out.exists() and not state.exists()
    state.write_text("not a directory")
    assert main(["sim", str(FIG2), "--runtime", "c", "--state-dir", str(state),
                 "-o", str(out)]) == 2
    assert f"--state-dir {state}: not a directory" in capsys.readouterr().err
    assert not out.exists()


LOGS = REPO.parent / "shared" / "data" / "slocum-logs"


@pytest.mark.skipif(not LOGS.is_dir() and os.environ.get("CI") != "true",
                    reason="the Slocum sample logs are not present")
def test_the_ocean_replays_the_slocum_logs(tmp_path):
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "--ocean", str(LOGS), "-o", str(out)]) == 0
    table = pd.read_parquet(out / "timeseries.parquet")
    assert table["temperature_c"][table["depth_m"] < 3].min() > 19.5
    assert table["temperature_c"][table["depth_m"] > 19].max() < 15.3


ALTIMETER = REPO / "tests" / "missions" / "sim_altimeter.mission"


def test_a_sea_floor_turns_the_dives_at_the_altimeter_stop_and_stops_the_glider(tmp_path,
                                                                                capsys):
    out = tmp_path / "run"
    assert main(["sim", str(ALTIMETER), "--floor", "38", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "sea floor at 38.0 m: --floor 38" in err
    assert "the glider reached the sea floor at" in err  # the last yo, without a stop
    table = pd.read_parquet(out / "timeseries.parquet")
    survey = table[table["state"] == "survey"]
    # each dive turned 4 m above the floor: the band's 50 m is never reached
    assert 33.0 < survey["depth_m"].max() < 36.0
    assert table["depth_m"].max() == 38.0  # the floor stops the yo without a stop
    summary = json.loads((out / "summary.json").read_text())
    assert summary["sea_floor"] == "sea floor at 38.0 m: --floor 38"
    grounded = summary["grounded"]
    assert grounded["first_s"] > 9000.0 and grounded["ticks"] > 0  # in the last state
    assert table["depth_m"][table["time_s"] >= grounded["first_s"] + 4.0].iloc[0] == 38.0


def test_without_a_floor_the_altimeter_reads_nothing_and_the_yo_turns_at_its_band(tmp_path,
                                                                                  capsys):
    out = tmp_path / "run"
    assert main(["sim", str(ALTIMETER), "-o", str(out)]) == 0
    # the mission has an altimeter stop: the run says it never fires
    assert "  no sea floor: the altimeter reads NaN (out of range)" in capsys.readouterr().err
    table = pd.read_parquet(out / "timeseries.parquet")
    assert table["depth_m"][table["state"] == "survey"].max() >= 50.0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["sea_floor"].startswith("no sea floor") and summary["grounded"] is None


@pytest.mark.skipif(not LOGS.is_dir() and os.environ.get("CI") != "true",
                    reason="the Slocum sample logs are not present")
def test_replayed_logs_give_the_floor_the_glider_saw(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["sim", str(ALTIMETER), "--ocean", str(LOGS), "--duration", "1h",
                 "-o", str(out)]) == 0
    assert "sea floor at 38.7-40.6 m along time (median 39.2 m)" in capsys.readouterr().err
    table = pd.read_parquet(out / "timeseries.parquet")
    # the German Bight's 39 m: dives turn some 4 m above it, above 37 m
    assert 33.0 < table["depth_m"].max() < 37.0


def test_the_water_given_is_flown_at_its_density_with_the_glider_ballasted_for_it(tmp_path,
                                                                                   capsys):
    mission = REPO / "examples" / "thermocline_survey.mission"
    runs = {}
    for name, args in (("default", []), ("bench", ["--ocean", "bench"])):
        out = tmp_path / name
        assert main(["sim", str(mission), "--duration", "3h", *args, "-o", str(out)]) == 0
        runs[name] = (capsys.readouterr().err, json.loads((out / "summary.json").read_text()),
                      pd.read_parquet(out / "timeseries.parquet"))
    err, summary, table = runs["bench"]
    said = summary["water_density"]
    assert said.startswith("water: bench: in-situ density (TEOS-10) 1021.0-1030.1 kg/m3")
    # ballasted as `gliderplan forecast` ballasts it: one definition of the band's density
    from gliderplan.language import check_file
    from gliderplan.planner.rates import band_density
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim.ocean import density_profile_of, load_ocean

    checked = check_file(str(mission)).checked()
    rho = band_density(checked, density_profile_of(load_ocean("bench")),
                       load_vehicle(checked.vehicle))
    assert 1024.5 < rho < 1025.5  # the survey's 5-40 m of the bench water, not the 1024.3
    assert f"flown at each depth; the glider ballasted for {rho:.1f} kg/m3" in said
    assert f"  {said}" in err
    default_err, default, default_table = runs["default"]
    assert default["water_density"] == ("water: uniform, the vehicle's reference density "
                                        "(1024.3 kg/m3)")
    assert "water:" not in default_err  # the default says nothing on the terminal
    # the same temperatures, another water: the glides differ
    assert table["temperature_c"].iloc[0] == default_table["temperature_c"].iloc[0]
    assert not table["depth_m"].equals(default_table["depth_m"])


def test_a_long_run_shows_progress(tmp_path, capsys, monkeypatch):
    mission = REPO / "tests" / "missions" / "sim_month.mission"
    monkeypatch.setenv("GLIDERPLAN_PROGRESS_S", "0")  # a line per update
    assert main(["sim", str(mission), "--duration", "5d", "-o", str(tmp_path / "r")]) == 0
    lines = capsys.readouterr().err.splitlines()  # not a terminal: plain lines
    bars = [line for line in lines if line.startswith("progress: ")]
    assert len(bars) >= 2 and all("of 5.00 d simulated (" in bar for bar in bars)
    assert "\r" not in "".join(lines)
    monkeypatch.delenv("GLIDERPLAN_PROGRESS_S")  # by default, a line every 15 s at most
    assert main(["sim", str(mission), "--duration", "5d", "-o", str(tmp_path / "r")]) == 0
    assert "progress: " not in capsys.readouterr().err  # this run takes a few seconds


def test_a_current_carries_the_glider_east(tmp_path):
    tracks = {}
    for current in ("0,0", "0,0.2"):
        out = tmp_path / current
        assert main(["sim", str(FIG2), "--current", current, "-o", str(out)]) == 0
        tracks[current] = pd.read_parquet(out / "timeseries.parquet")
    drift = tracks["0,0.2"]["lon_deg"].iloc[-1] - tracks["0,0"]["lon_deg"].iloc[-1]
    metres = drift * 111_320 * math.cos(math.radians(tracks["0,0"]["lat_deg"].iloc[-1]))
    assert metres == pytest.approx(0.2 * 2500, rel=0.01)  # 0.2 m/s for 2500 s


def interrupt_at(monkeypatch, at_tick: int) -> None:
    """Ctrl-C while the science computer reads the sensors of tick `at_tick` (in the
    Python loop, `--runtime python`; the C flight is interrupted at a progress report,
    below)."""
    from gliderplan.sim.science import ScienceComputer

    original = ScienceComputer.readings

    def readings(self, tick):
        if tick == at_tick:
            raise KeyboardInterrupt
        return original(self, tick)
    monkeypatch.setattr(ScienceComputer, "readings", readings)


def test_ctrl_c_keeps_the_part_flown(tmp_path, capsys, monkeypatch):
    interrupt_at(monkeypatch, 300)
    assert main(["sim", str(FIG2), "--runtime", "python", "--tick", "4", "-o",
                 str(tmp_path)]) == 130
    assert {p.name for p in tmp_path.iterdir()} == WRITTEN
    table = pd.read_parquet(tmp_path / "timeseries.parquet")
    assert len(table) == 300 and table["time_s"].iloc[-1] == 299 * 4
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["ended"] == "interrupted" and summary["complete"] is False
    assert json.loads((tmp_path / RUN_MARKER).read_text())["complete"] is False
    trace = pd.read_csv(tmp_path / "trace.csv")
    assert list(trace["kind"]) == ["start", "call"]  # s1 -call-> s2 at 500 s, then Ctrl-C
    assert "interrupted" in capsys.readouterr().err


def test_ctrl_c_in_a_long_run_keeps_the_part_flown_and_its_plots(tmp_path, capsys,
                                                                 monkeypatch):
    # a run this long draws its plots in a second process while it writes the rest
    from gliderplan.cli.progress import ProgressBar
    from gliderplan.sim import plotter

    started = []
    real_start = plotter.PlotProcess.__init__
    monkeypatch.setattr(plotter.PlotProcess, "__init__",
                        lambda self: started.append(1) or real_start(self))
    monkeypatch.setattr(ProgressBar, "__call__",  # Ctrl-C at the first progress report
                        lambda self, done, total: os.kill(os.getpid(), signal.SIGINT))
    mission = REPO / "tests" / "missions" / "sim_month.mission"
    assert main(["sim", str(mission), "--duration", "10d", "-o", str(tmp_path)]) == 130
    assert started and {p.name for p in tmp_path.iterdir()} == WRITTEN
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["ended"] == "interrupted" and 0 < summary["simulated_s"] < 10 * 86400
    for png in ("depth.png", "energy.png"):
        assert (tmp_path / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "interrupted" in capsys.readouterr().err


def test_ctrl_c_before_the_first_tick_writes_nothing(tmp_path, capsys, monkeypatch):
    interrupt_at(monkeypatch, 0)
    assert main(["sim", str(FIG2), "--runtime", "python", "-o", str(tmp_path / "run")]) == 130
    assert not (tmp_path / "run").exists()
    assert "interrupted" in capsys.readouterr().err


def test_run_mission_is_the_sim_command_as_one_call(tmp_path):
    from gliderplan.language import check_file
    from gliderplan.planner import make_plan
    from gliderplan.sim import FlightOptions, flight_setup, run_mission

    annotated = check_file(str(REPO / "examples" / "fig2_annotated.mission")).checked()
    plan_path = tmp_path / "fig2.plan"
    make_plan(annotated, output=plan_path)
    result = run_mission(flight_setup(annotated, FlightOptions(plan_path=plan_path, seed=3)),
                         tmp_path / "run")
    assert {p.name for p in result.files} == FILES and all(p.is_file() for p in result.files)
    assert [t.kind for t in result.record.trace] == ["start", "call", "return", "goto", "exit"]
    assert result.check.verdict in ("pass", "over prediction") and not result.interrupted
    assert result.plan is not None and result.check.budget_j == result.plan.budget_j
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["energy_j"] == pytest.approx(result.energy.total_j)


# A mission that `check` takes must fly: one whose conditions nest as deep as the
# contract allows, in four ways (a long sum, a chain of minus signs, calls in calls and a
# long `||`), and one that exits on its first tick.
_DEEP = MAX_EXPRESSION_DEPTH - 1  # and the comparison makes the limit
_LIMIT_DEEP = f"""mission deep
state s1
begin
  flightprofile yo(5, 20, .454, .454)
  sensors missiontime, depth
  events
    case {" + ".join(["depth"] * (_DEEP + 1))} >= {5 * (_DEEP + 1)} goto s2
end
state s2
begin
  flightprofile yo(5, 20, .454, .454)
  sensors missiontime, depth
  events
    case {"-" * (_DEEP - _DEEP % 2)}missiontime >= 600 goto s3
end
state s3
begin
  flightprofile yo(5, 20, .454, .454)
  sensors missiontime, depth
  events
    case {"abs(" * (_DEEP - 1)}missiontime - 1200{")" * (_DEEP - 1)} < 2 goto s4
end
state s4
begin
  flightprofile yo(5, 20, .454, .454)
  sensors missiontime, depth
  events
    case {" || ".join(["missiontime < 0"] * _DEEP)} || missiontime >= 1500 exit
end
"""
_FIRST_TICK_EXIT = """mission brief
state s
begin
  flightprofile yo(5, 20, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 0 exit
end
"""
RUNTIMES = ["python", pytest.param("c", marks=pytest.mark.skipif(
    shutil.which("cc") is None, reason="no C compiler (cc) for the runtime"))]


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_conditions_as_deep_as_the_contract_allows_fly(tmp_path, runtime):
    mission = tmp_path / "deep.mission"
    mission.write_text(_LIMIT_DEEP)
    assert main(["check", str(mission)]) == 0
    assert main(["sim", str(mission), "--runtime", runtime, "-o", str(tmp_path / "run")]) == 0
    trace = (tmp_path / "run" / "trace.csv").read_text().splitlines()
    assert [row.split(",")[1:4] for row in trace[1:]] == [
        ["start", "", "s1"], ["goto", "s1", "s2"], ["goto", "s2", "s3"], ["goto", "s3", "s4"],
        ["exit", "s4", ""]]
    times = [float(row.split(",")[0]) for row in trace[1:]]
    assert 0 < times[1] < 600 and times[2:] == [600, 1200, 1500]


@pytest.mark.parametrize("runtime", RUNTIMES)
def test_a_mission_that_exits_on_its_first_tick_flies(tmp_path, capsys, runtime):
    mission = tmp_path / "brief.mission"
    mission.write_text(_FIRST_TICK_EXIT)
    out = tmp_path / "run"
    assert main(["sim", str(mission), "--runtime", runtime, "-o", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == WRITTEN
    assert (out / "trace.csv").read_text().splitlines()[1:] == ["0,start,,s,0", "0,exit,s,,0"]
    assert "brief: exit after 0 s" in capsys.readouterr().err


def test_boards_are_not_compared_on_a_mission_that_flies_no_time(tmp_path, capsys):
    mission = tmp_path / "brief.mission"
    mission.write_text(_FIRST_TICK_EXIT)
    for argv in (["compare-sbc", str(mission)],
                 ["report", str(mission), "-o", str(tmp_path / "report")]):
        assert main(argv) == 1
        err = capsys.readouterr().err
        assert err == (f"gliderplan {argv[0]}: error: mission brief flies for 0 s (it exits "
                       "on its first tick): boards are compared by the power they draw over "
                       "a mission's time\n")
    assert not (tmp_path / "report").exists()


def test_a_long_run_is_plotted_from_a_decimated_series_that_keeps_its_extremes():
    from gliderplan.sim.plots import PLOTTED_TICKS, decimated

    t = np.arange(648_001) * 4.0
    depth = 20.0 + 15.0 * np.sin(2 * np.pi * t / 410.0)  # a yo about every 100 ticks
    depth[123_457] = 61.0  # one deep excursion between the stretches' first ticks
    shown = decimated(depth)
    assert len(shown) <= PLOTTED_TICKS + 1
    assert (np.diff(shown) > 0).all() and shown[0] == 0 and shown[-1] == len(t) - 1
    assert 123_457 in shown and depth[shown].min() == depth.min()
    # every stretch of ticks keeps its band: the deepest and shallowest of each
    width = -(-3 * len(t) // PLOTTED_TICKS)
    for start in range(0, len(t) - width, 50 * width):
        mine = shown[(shown >= start) & (shown < start + width)]
        stretch = depth[start:start + width]
        assert depth[mine].max() == stretch.max() and depth[mine].min() == stretch.min()
    assert decimated(depth[:500]).tolist() == list(range(500))  # short runs: every tick


@pytest.mark.parametrize("start", ["9999-12-31T23:59Z", "0001-01-01T00:00Z", "2101-01-01",
                                   "1969-12-31T23:00Z"])
def test_a_start_outside_the_years_a_run_may_start_in_is_bad_usage(tmp_path, capsys, start):
    """Dates at the calendar's edges crashed the run or the export that read it."""
    from gliderplan.contract import START_YEARS, ExitCode

    code = main(["sim", str(FIG2), "--start", start, "--duration", "600s", "-o",
                 str(tmp_path / "run")])
    err = capsys.readouterr().err
    assert code == ExitCode.USAGE
    assert f"a run starts between {START_YEARS[0]} and {START_YEARS[1]}" in err
    assert not (tmp_path / "run").exists()
