"""Differential test: every example mission and every simulator mission, flown once by the
Python executor and once by the compiled C runtime over a pty against the same simulated
glider, gives the same trace.csv (and, through the same glider, the same dive profile)."""

from __future__ import annotations

import shutil
import zlib
from pathlib import Path

import pandas as pd
import pytest

from gliderplan.cli.main import main

REPO = Path(__file__).resolve().parents[1]
MISSIONS = sorted((REPO / "examples").glob("*.mission")) + sorted(
    (REPO / "tests" / "missions").glob("sim_*.mission"))
# the oceans and sensors each mission was written for; long missions are cut short
RUN_OPTIONS = {
    "sim_first_sea_run.mission": ["--ocean", "sea-trial"],
    "sim_sea_trial.mission": ["--ocean", "sea-trial", "--noise", "nonmonotonic"],
    "sim_month.mission": ["--duration", "1d"],
}

needs_cc = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")


@needs_cc
@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.name)
def test_python_and_c_runtimes_give_identical_traces(path, tmp_path, capsys):
    options = RUN_OPTIONS.get(path.name, [])
    runs = {}
    for runtime in ("python", "c"):
        out = tmp_path / runtime
        code = main(["sim", str(path), "--runtime", runtime, "--seed", "7", *options,
                     "-o", str(out)])
        assert code == 0, capsys.readouterr().err
        runs[runtime] = out
    python_trace = (runs["python"] / "trace.csv").read_text()
    assert python_trace.count("\n") >= 2  # a start and at least one more transition
    assert (runs["c"] / "trace.csv").read_text() == python_trace
    python_series = pd.read_parquet(runs["python"] / "timeseries.parquet")
    c_series = pd.read_parquet(runs["c"] / "timeseries.parquet")
    for column in ("depth_m", "pitch_rad", "state", "stack_depth", "profile", "temp_on"):
        assert python_series[column].equals(c_series[column]), column


@needs_cc
def test_the_naive_tracker_is_the_same_in_both_runtimes(tmp_path):
    path = REPO / "tests" / "missions" / "sim_sea_trial.mission"
    depths = []
    for runtime in ("python", "c"):
        out = tmp_path / runtime
        assert main(["sim", str(path), "--runtime", runtime, "--ocean", "sea-trial",
                     "--noise", "nonmonotonic", "--tracker", "naive", "-o", str(out)]) == 0
        depths.append(pd.read_parquet(out / "timeseries.parquet")["depth_m"])
    assert depths[0].equals(depths[1])


def write_plan(path: Path, mission_path: Path) -> Path:
    """A plan for sim_alternating.mission: profile shares, sensor duty cycles, clocks."""
    from gliderplan.language import check_file

    mission = check_file(str(mission_path)).mission
    body = (f"GPPLAN 2\nmission {mission.name}\nhash {mission.hash}\ncomputer ts7800 300\n"
            "budget_j 1000000\npredicted_j 100000\ncomponents hotel\nassumptions 0\nstates 2\n"
            "state survey 300 1200 2 2\npredict 30000 1 200\nenergy 90000\n"
            "sensor temp 60 20\nsensor oxygen 300 100\n"
            "profile 0 0.6 0.4 150 0.25\nprofile 1 0.4 0.454 233 0.32\nend\n"
            "state fix 300 600 0 1\npredict 3000 1 0\nenergy 10000\n"
            "profile 0 1 0.454 200 0.3\nend\n").encode()
    path.write_bytes(body + f"crc32 {zlib.crc32(body):08x}\n".encode())
    return path


@needs_cc
def test_a_plan_s_schedule_is_flown_the_same_by_both_runtimes(tmp_path):
    mission = REPO / "tests" / "missions" / "sim_alternating.mission"
    plan = write_plan(tmp_path / "alternating.plan", mission)
    series = {}
    for runtime in ("python", "c"):
        out = tmp_path / runtime
        assert main(["sim", str(mission), "--plan", str(plan), "--runtime", runtime,
                     "-o", str(out)]) == 0
        series[runtime] = (pd.read_parquet(out / "timeseries.parquet"),
                           (out / "trace.csv").read_text())
    (python, python_trace), (c, c_trace) = series["python"], series["c"]
    assert c_trace == python_trace and python_trace.count("call") == 2
    for column in ("depth_m", "pitch_rad", "profile", "temp_on", "oxygen_on", "lat_deg",
                   "lon_deg"):
        assert python[column].equals(c[column]), column
    survey = python[python["state"] == "survey"]
    assert set(survey["profile"]) == {0, 1}  # both bands flown
    assert 0.25 < survey["temp_on"].mean() < 0.45  # 20 s of every 60 s
    assert 0.25 < survey["oxygen_on"].mean() < 0.45  # 100 s of every 300 s


@needs_cc
@pytest.mark.parametrize("name", ["fig2_annotated.mission", "thermocline_survey.mission"])
def test_the_planner_s_plans_are_flown_the_same_by_both_runtimes(name, tmp_path):
    mission = REPO / "examples" / name
    plan = tmp_path / "mission.plan"
    assert main(["plan", str(mission), "-o", str(plan)]) == 0
    outputs = {}
    for runtime in ("python", "c"):
        out = tmp_path / runtime
        assert main(["sim", str(mission), "--plan", str(plan), "--runtime", runtime,
                     "-o", str(out)]) == 0
        outputs[runtime] = ((out / "trace.csv").read_text(),
                            pd.read_parquet(out / "timeseries.parquet"))
    (python_trace, python), (c_trace, c) = outputs["python"], outputs["c"]
    assert c_trace == python_trace
    for column in ("depth_m", "profile", "temp_on", "oxygen_on"):
        assert python[column].equals(c[column]), column
