"""Flying a fleet plan: every glider in one ocean, the Monte Carlo on Dask giving what the
local run gives, the finish probability against the planned confidence, a lost glider,
the files (NetCDF per glider, the map as GeoJSON and KML), the fleet page in Chromium."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

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
    assert "the rest cannot take them over" in lost["summary"]


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


def test_the_monte_carlo_on_dask_gives_what_the_local_run_gives(fleet, planned, tmp_path):
    _, stored = planned
    local = montecarlo_fleet(fleet, stored, tmp_path / "local", scenarios=4, workers=1,
                             seed=3, scenario_file=CALM)
    dask = montecarlo_fleet(fleet, stored, tmp_path / "dask", scenarios=4, workers=2,
                            scheduler="local", seed=3, scenario_file=CALM)
    a = pd.read_parquet(tmp_path / "local" / "scenarios.parquet")
    b = pd.read_parquet(tmp_path / "dask" / "scenarios.parquet")
    pd.testing.assert_frame_equal(a.sort_values(["scenario", "glider"]).reset_index(drop=True),
                                  b.sort_values(["scenario", "glider"]).reset_index(drop=True))
    for key in ("finished", "finish_probability", "finish_interval", "mapping_error",
                "energy_j"):
        assert local[key] == dask[key]
    assert dask["scheduler"] == "local"


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
