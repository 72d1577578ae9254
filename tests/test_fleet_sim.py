"""Flying a fleet plan: every glider in one ocean, the Monte Carlo on Dask giving what the
local run gives, the finish probability against the planned confidence, a lost glider,
the files (NetCDF per glider, the map as GeoJSON and KML), the fleet page in Chromium."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.language.fleet import check_fleet_file
from gliderplan.planner.fleet import plan_fleet
from gliderplan.planner.fleet_report import load_plan_dir, write_plan_dir
from gliderplan.sim.fleet import fly_fleet, montecarlo_fleet, replan_after_loss

ROOT = Path(__file__).resolve().parents[1]
SMALL = ROOT / "tests" / "fleets" / "small.fleet"
CALM = str(ROOT / "tests" / "fleets" / "calm.toml")
CHROMIUM = "/usr/bin/chromium"


@pytest.fixture(scope="module")
def fleet():
    return check_fleet_file(SMALL).checked()


@pytest.fixture(scope="module")
def planned(fleet, tmp_path_factory):
    directory = tmp_path_factory.mktemp("plan")
    plan = plan_fleet(fleet, scenario_file=CALM)
    write_plan_dir(plan, directory)
    return plan, load_plan_dir(directory, fleet)


@pytest.fixture(scope="module")
def flown(fleet, planned, tmp_path_factory):
    out = tmp_path_factory.mktemp("sim")
    return out, fly_fleet(fleet, planned[1], out, workers=1, current=(0.05, -0.03))


def test_the_plan_directory_holds_what_the_flights_read(planned, fleet):
    _, stored = planned
    names = {p.name for p in stored.directory.iterdir()}
    for glider in fleet.gliders:
        assert {f"{glider.name}.mission", f"{glider.name}.plan",
                f"{glider.name}.plan.json"} <= names
    assert {"fleet.json", "fleet.png", "fleet.geojson", "fleet.kml", "fleet.html"} <= names


def test_a_plan_of_another_fleet_file_is_refused(planned, tmp_path):
    _, stored = planned
    other = tmp_path / "other.fleet"
    other.write_text(SMALL.read_text().replace("finish by 2 d", "finish by 3 d"))
    assert main(["fleet", "sim", str(other), "--plan", str(stored.directory), "-o",
                 str(tmp_path / "out"), "--workers", "1"]) == ExitCode.BAD_INPUT


def test_every_glider_flies_its_plan_in_one_ocean(flown, planned, fleet):
    out, summary = flown
    assert summary["finished"] is True
    assert [g["name"] for g in summary["gliders"]] == [g.name for g in fleet.gliders]
    for glider, planned_glider in zip(summary["gliders"], planned[0].gliders, strict=True):
        assert glider["held"] and glider["swept"]
        assert glider["energy_j"] == pytest.approx(planned_glider.energy_j, rel=0.15)
    assert summary["current_mps"] == {"north": 0.05, "east": -0.03}
    assert summary["mapping_error"] == pytest.approx(summary["planned_mapping_error"], abs=0.1)
    assert json.loads((out / "fleet_sim.json").read_text()) == summary


def test_the_survivors_of_a_loss_fly_their_own_plans_and_the_report_says_what_they_cover(
        flown, fleet, planned, tmp_path):
    """alpha lost after 12 h: bravo and charlie fly exactly the tracks they fly without the
    loss (before and after it), their lines are their plan's, alpha's track stops at the
    loss; the report gives what the survivors still cover and the map they make."""
    import xarray as xr

    whole, kept = flown
    out = tmp_path / "lost"
    lost_at = 12 * 3600.0
    summary = fly_fleet(fleet, planned[1], out, workers=2,
                        current=(0.05, -0.03), lose=("alpha", lost_at))
    for name in ("bravo", "charlie"):
        with xr.open_dataset(whole / name / "trajectory.nc") as a, \
                xr.open_dataset(out / name / "trajectory.nc") as b:
            for variable in ("time", "lat", "lon", "depth"):
                assert a[variable].values.tolist() == b[variable].values.tolist(), variable
    with xr.open_dataset(out / "alpha" / "trajectory.nc") as data:
        flew_s = (data["time"].values[-1] - data["time"].values[0]) / np.timedelta64(1, "s")
    assert lost_at - 120.0 <= flew_s <= lost_at

    def features(directory, kind):
        collection = json.loads((directory / "fleet.geojson").read_text())
        return {f["properties"]["glider"]: f["geometry"] for f in collection["features"]
                if f["properties"].get("kind") == kind}

    assert features(out, "assignment") == features(whole, "assignment")
    flown_before, flown_after = features(whole, "flown track"), features(out, "flown track")
    assert flown_after["bravo"] == flown_before["bravo"]
    assert flown_after["charlie"] == flown_before["charlie"]
    assert flown_after["alpha"] != flown_before["alpha"]
    gliders = {g["name"]: g for g in summary["gliders"]}
    before = {g["name"]: g for g in kept["gliders"]}
    assert gliders["alpha"]["lost"] and not gliders["alpha"]["swept"]
    for name in ("bravo", "charlie"):
        assert gliders[name] == before[name]
    assert summary["finished"] is False
    lost = summary["lost"]
    assert lost["survivors"] == ["bravo", "charlie"]
    assert lost["mapping_error_flown"] == summary["mapping_error"] > kept["mapping_error"]
    assert 0.0 < lost["coverage_without_replan"] < 1.0
    assert f"cover {100 * lost['coverage_without_replan']:.0f} % of the lines' length" \
        in lost["summary"]


def test_each_glider_has_its_netcdf_and_the_map_its_tracks(flown, fleet):
    import xarray as xr

    out, _ = flown
    for glider in fleet.gliders:
        with xr.open_dataset(out / glider.name / "trajectory.nc") as data:
            assert data.sizes["time"] > 100
            assert float(data["lat"].min()) > 39.0
    collection = json.loads((out / "fleet.geojson").read_text())
    kinds = {f["properties"].get("kind") for f in collection["features"]}
    assert {"area", "assignment", "planned track", "flown track"} <= kinds
    import geojson

    assert geojson.loads((out / "fleet.geojson").read_text()).is_valid
    from fastkml import KML

    document = KML.parse(out / "fleet.kml").features[0]
    names = [m.name or "" for m in document.features]
    assert sum("flown track" in n for n in names) == len(fleet.gliders)
    assert sum(n.endswith(" lines") for n in names) == len(fleet.gliders)


def test_a_glider_lost_early_leaves_lines_the_rest_cannot_sweep_in_time(fleet, planned):
    _, stored = planned
    lost = replan_after_loss(fleet, stored, ("alpha", 12 * 3600.0), scenario_file=CALM)
    assert lost["glider"] == "alpha" and lost["survivors"] == ["bravo", "charlie"]
    assert lost["lines"] == [3, 4] and lost["lines_swept_before"] == [4]
    assert lost["mapping_error_without_replan"] > stored.report["mapping_error"]
    assert lost["replan"] is None
    assert "it had swept 1 of its 2 lines once" in lost["summary"]
    assert "and cannot take them over" in lost["summary"]
    # its line 3 is left unswept: what the survivors cover, told beside the map they make
    unswept = fleet.parts[3].length_m
    total = sum(p.length_m for p in fleet.parts)
    assert lost["coverage_without_replan"] == pytest.approx(1.0 - unswept / total)
    assert f"cover {100 * (1.0 - unswept / total):.0f} % of the lines' length" \
        in lost["summary"]


def test_a_glider_lost_after_sweeping_its_lines_leaves_them_to_the_rest(fleet, planned):
    _, stored = planned
    lost = replan_after_loss(fleet, stored, ("alpha", 36 * 3600.0), scenario_file=CALM)
    assert lost["lines_swept_before"] == lost["lines"]
    replan = lost["replan"]
    assert replan["sweep_required"] is False
    assert replan["mapping_error"] < lost["mapping_error_without_replan"]
    parts = sorted(p for g in replan["gliders"] for p in g["parts"])
    assert parts == list(range(len(fleet.parts)))
    assert "so the survey is finished" in lost["summary"]
    assert lost["coverage_without_replan"] == replan["coverage"] == 1.0


def test_the_monte_carlo_on_dask_gives_what_this_process_gives(fleet, planned, tmp_path):
    """Dask by default (a LocalCluster of 1 and of 2 workers) and a running cluster given
    by its address fly the very scenarios this process flies."""
    from distributed import LocalCluster

    _, stored = planned

    def flown(label, **where):
        summary = montecarlo_fleet(fleet, stored, tmp_path / label, scenarios=4, seed=3,
                                   scenario_file=CALM, **where)
        table = pd.read_parquet(tmp_path / label / "scenarios.parquet")
        return summary, table.sort_values(["scenario", "glider"]).reset_index(drop=True)

    here, reference = flown("here", workers=1, scheduler=None)
    runs = {"local1": flown("local1", workers=1), "local2": flown("local2", workers=2)}
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster:
        runs["address"] = flown("address", workers=2, scheduler=cluster.scheduler_address)
    assert here["scheduler"] == "none" and runs["local2"][0]["scheduler"] == "local"
    assert runs["address"][0]["scheduler"].startswith("tcp://")
    for label, (summary, table) in runs.items():
        pd.testing.assert_frame_equal(reference, table, obj=label)
        for key in ("finished", "finish_probability", "finish_interval", "mapping_error",
                    "energy_j", "gliders"):
            assert summary[key] == here[key], (label, key)


def test_ctrl_c_on_dask_keeps_the_whole_scenarios_and_says_so(planned, tmp_path):
    """Ctrl-C at a terminal (SIGINT to the whole process group, Dask's workers too) on
    the default LocalCluster: exit 130, the scenarios every glider finished written and
    marked incomplete, no finish probability, and no traceback from the cluster."""
    _, stored = planned
    out = tmp_path / "mc"
    run = subprocess.Popen(
        [sys.executable, "-m", "gliderplan.cli", "fleet", "montecarlo", str(SMALL), "--plan",
         str(stored.directory), "--scenarios", "60", "--workers", "2", "--scenario-file", CALM,
         "-o", str(out)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
        env={**os.environ, "GLIDERPLAN_PROGRESS_S": "0"})
    for line in run.stderr:
        if "progress: " in line and int(line.split("progress: ")[1].split(" of ")[0]) >= 40:
            break
    os.killpg(run.pid, signal.SIGINT)
    said, err = run.communicate(timeout=120)
    assert run.returncode == 130
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scheduler"] == "local"
    assert summary["interrupted"] and not summary["complete"] and summary["requested"] == 60
    assert 1 <= summary["scenarios"] < 60
    assert summary["finish_probability"] is None and summary["finish_interval"] is None
    table = pd.read_parquet(out / "scenarios.parquet")
    assert (table.groupby("scenario")["glider"].nunique() == 3).all()
    assert table["scenario"].nunique() == summary["scenarios"]
    assert f"interrupted after {summary['scenarios']} of 60 scenarios" in said
    assert f"interrupted: {summary['scenarios']} of 60 scenarios finished" in err
    assert "Traceback" not in err


def test_the_survey_finishes_at_least_as_often_as_planned(fleet, planned, tmp_path):
    """The Monte Carlo, on seeds the plan never saw, finishes the survey in at least the
    share of scenarios the plan was made for."""
    _, stored = planned
    summary = montecarlo_fleet(fleet, stored, tmp_path, scenarios=40, workers=2, seed=11,
                               scenario_file=CALM)
    assert summary["scenarios"] == 40
    assert summary["finish_probability"] >= fleet.confidence, summary
    low, high = summary["finish_interval"]
    assert low <= summary["finish_probability"] <= high
    table = pd.read_parquet(tmp_path / "scenarios.parquet")
    assert len(table) == 40 * len(fleet.gliders)


def test_fleet_montecarlo_json_gives_the_keys_tools_read(planned, tmp_path, capsys):
    _, stored = planned
    code = main(["fleet", "montecarlo", str(SMALL), "--plan", str(stored.directory),
                 "--scenarios", "2", "--workers", "1", "--scenario-file", CALM,
                 "--lose", "bravo@1d", "-o", str(tmp_path), "--json"])
    assert code == ExitCode.OK
    summary = json.loads(capsys.readouterr().out)
    assert {"finish_probability", "finish_interval", "scenarios"} <= set(summary)
    assert summary["lost"]["glider"] == "bravo"
    assert (tmp_path / "mapping_error.png").stat().st_size > 0


@pytest.mark.parametrize("argv, message", [
    (["--lose", "zulu@1d"], "--lose zulu@1d: expected GLIDER@TIME"),
    (["--lose", "alpha@9d"], "--lose alpha@9d: alpha flies from 0 d to 2 d"),
    (["--current", "north"], "--current 'north': expected NORTH,EAST"),
    (["--scheduler", "nowhere"], "--scheduler nowhere: expected local or tcp://HOST:PORT"),
    (["--scheduler", "tcp://127.0.0.1:9"], "--scheduler tcp://127.0.0.1:9: cannot reach it"),
])
def test_bad_options_are_bad_usage(planned, tmp_path, capsys, argv, message):
    _, stored = planned
    code = main(["fleet", "sim", str(SMALL), "--plan", str(stored.directory), "-o",
                 str(tmp_path), "--workers", "1", *argv])
    assert code == ExitCode.USAGE
    assert message in capsys.readouterr().err


@pytest.mark.skipif(shutil.which(CHROMIUM) is None, reason="needs Debian's chromium")
def test_the_fleet_page_shows_its_sections_and_the_map_in_chromium(flown, fleet):
    from playwright.sync_api import sync_playwright

    out, _ = flown
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=[
            "--no-sandbox", "--disable-gpu", "--no-first-run"])
        page = browser.new_page()
        errors = []
        page.on("pageerror", lambda err: errors.append(str(err)))
        page.goto((out / "fleet.html").as_uri())
        for section in ("fleet-summary", "fleet-gliders", "fleet-map", "fleet-sim"):
            assert page.locator(f"section#{section}").count() == 1, section
        width = page.evaluate("document.querySelector('#fleet-map img').naturalWidth")
        assert width > 300  # the map decoded
        rows = page.locator("#fleet-gliders tbody tr").count()
        assert rows == len(fleet.gliders)
        assert errors == []
        browser.close()
