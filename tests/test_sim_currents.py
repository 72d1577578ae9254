"""Currents in the sim as a user gives them (`--currents N,E|FIELD.nc|LOGDIR`) and where
the glider starts (`--start LAT,LON[,UTC]`): fields read as their makers write them, and
fields that cannot be flown refused with what is missing."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gliderplan.cli.main import main
from gliderplan.sim.current_files import read_logged_currents, read_netcdf_currents
from gliderplan.sim.geo import offset_m

REPO = Path(__file__).resolve().parents[1]
FIG2 = REPO / "examples" / "fig2.mission"  # waypoints near 39.175 N, 73.83 W
COMET = REPO.parent / "shared" / "data" / "slocum-logs-comet-2016"
NSB3 = REPO.parent / "shared" / "data" / "slocum-missions" / "nsb3" / "nsb3.mi"
START = "39.17,-73.83,2016-06-23T12:00:00Z"


def write_field(path: Path, names: tuple[str, str] = ("uo", "vo"), east: float = 0.2,
                north: float = 0.0, lons: np.ndarray | None = None, land: bool = False,
                standard: bool = False) -> Path:
    """A Copernicus-style field (time, depth, latitude, longitude) over fig2's waters."""
    import xarray as xr

    times = pd.date_range("2016-06-23", periods=3, freq="1D")
    depth = np.array([0.5, 50.0])
    lat = np.linspace(39.0, 39.4, 5)
    lon = np.linspace(-74.0, -73.6, 5) if lons is None else lons
    shape = (len(times), len(depth), len(lat), len(lon))
    u, v = np.full(shape, east), np.full(shape, north)
    if land:
        u[..., 2, 2] = v[..., 2, 2] = np.nan
    dims = ("time", "depth", "latitude", "longitude")
    attrs_u = {"standard_name": "eastward_sea_water_velocity"} if standard else {}
    attrs_v = {"standard_name": "northward_sea_water_velocity"} if standard else {}
    xr.Dataset({names[0]: (dims, u, attrs_u), names[1]: (dims, v, attrs_v)},
               coords={"time": times, "depth": depth, "latitude": lat,
                       "longitude": lon}).to_netcdf(path)
    return path


def final_position(run: Path) -> tuple[float, float]:
    table = pd.read_parquet(run / "timeseries.parquet")
    return float(table["lat_deg"].iloc[-1]), float(table["lon_deg"].iloc[-1])


def test_a_netcdf_field_drifts_the_glider_as_a_uniform_current_does(tmp_path, capsys):
    field = write_field(tmp_path / "field.nc")
    ends = {}
    for name, currents in (("field", str(field)), ("uniform", "0,0.2"), ("still", "0,0")):
        out = tmp_path / name
        assert main(["sim", str(FIG2), "--start", START, "--currents", currents,
                     "-o", str(out)]) == 0
        ends[name] = final_position(out)
    err = capsys.readouterr().err
    assert f"currents: {field}" in err and "the current field ends at 2016-06-25" in err
    assert ends["field"] == pytest.approx(ends["uniform"], abs=1e-6)
    east_m = (ends["field"][1] - ends["still"][1]) * 111_320 * math.cos(math.radians(39.17))
    assert east_m == pytest.approx(0.2 * 2500, rel=0.02)


def test_the_start_puts_the_glider_where_the_user_says(tmp_path):
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "--start", "39.2,-73.9", "-o", str(out)]) == 0
    first = pd.read_parquet(out / "timeseries.parquet").iloc[0]
    assert (first["lat_deg"], first["lon_deg"]) == pytest.approx((39.2, -73.9), abs=1e-4)


def test_hycom_names_and_longitudes_0_to_360_are_read(tmp_path):
    field = read_netcdf_currents(write_field(
        tmp_path / "hycom.nc", ("water_u", "water_v"), east=0.1, north=-0.3,
        lons=np.linspace(286.0, 286.4, 5)))
    assert field.at(39.2, -73.8, field.time_s[0] + 3600.0, 10.0) == pytest.approx((-0.3, 0.1))
    cf = read_netcdf_currents(write_field(tmp_path / "cf.nc", ("a", "b"), standard=True))
    assert cf.at(39.2, -73.8, cf.time_s[1]) == pytest.approx((0.0, 0.2))


@pytest.mark.parametrize("field_args, start, message", [
    ({"names": ("temp", "salt")}, START,
     "no current variables: expected the standard names eastward_sea_water_velocity"),
    ({"lons": np.linspace(-74.0, -73.85, 5)}, "39.17,-73.9,2016-06-23T12:00:00Z",
     "the route reaches 39.1750, -73.8301 (2 of its 3 points outside)"),
    ({}, "39.17,-73.83,2016-07-30T00:00:00Z",
     "the field covers 2016-06-23T00:00:00Z to 2016-06-25T00:00:00Z; the run starts at"),
    ({"land": True}, "39.2,-73.8,2016-06-23T12:00:00Z", "is on land"),
    ({"east": 4.0}, START, "a current of 4 m/s"),
])
def test_a_field_that_cannot_be_flown_is_refused_naming_what_is_missing(
        tmp_path, capsys, field_args, start, message):
    field = write_field(tmp_path / "field.nc", **field_args)
    out = tmp_path / "run"
    assert main(["sim", str(FIG2), "--start", start, "--currents", str(field),
                 "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize("start, message", [
    ("39.2", "not an ISO 8601 time"),
    ("north,west", "LAT,LON must be decimal degrees"),
    ("39,-73,2016-06-23,1", "expected LAT,LON[,UTC] or UTC"),
])
def test_a_bad_start_is_a_usage_error(tmp_path, capsys, start, message):
    assert main(["sim", str(FIG2), "--start", start, "-o", str(tmp_path / "r")]) == 2
    assert message in capsys.readouterr().err


def test_not_a_netcdf_file_is_a_message(tmp_path, capsys):
    bad = tmp_path / "field.nc"
    bad.write_text("not netcdf\n")
    assert main(["sim", str(FIG2), "--currents", str(bad), "-o", str(tmp_path / "r")]) == 1
    err = capsys.readouterr().err
    assert f"{bad}: not a NetCDF file" in err and "Traceback" not in err


@pytest.mark.skipif(not COMET.is_dir() and os.environ.get("CI") != "true",
                    reason="the shared comet logs")
def test_the_currents_a_glider_measured_persist_from_its_flight_logs():
    import dbdreader

    logged = read_logged_currents(COMET)
    t, vx = dbdreader.MultiDBD(pattern=str(COMET / "*.dbd"), cacheDir=str(COMET / "cac")
                               ).get("m_water_vx")
    assert logged.at(0.0, 0.0, float(t[3]) + 1.0)[1] == pytest.approx(vx[3])
    assert logged.at(10.0, 20.0, float(t[-1]) + 86400.0)[1] == pytest.approx(vx[-1])


@pytest.mark.skipif(not NSB3.is_file(), reason="the shared Slocum missions")
def test_the_imported_nsb3_flies_toward_its_waypoints_from_the_start_and_prints_surfacings(
        tmp_path, capsys):
    mission = tmp_path / "nsb3.mission"
    assert main(["import-slocum", str(NSB3), "-o", str(mission)]) == 0
    out = tmp_path / "run"
    assert main(["sim", str(mission), "--start", "54.2,7.0,2016-06-23T12:00Z", "--currents",
                 "0.05,0", "--duration", "7h", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    fixes = json.loads((out / "summary.json").read_text())["surfacing_fixes"]
    assert len(fixes) == 3 and "surfacings (GPS fix" in err
    # its goto list's first waypoint is 54 33.5 N, 7 13.0 E: north-east
    assert fixes[-1]["lat"] > fixes[0]["lat"] + 0.04 and fixes[-1]["lon"] > fixes[0]["lon"]
    assert f"{fixes[1]['lat']:9.5f} {fixes[1]['lon']:10.5f}" in err
    # the forecast's surfacings land where the simulated glider surfaced, in its ellipse
    assert main(["forecast", str(mission), "--start", "54.2,7.0,2016-06-23T12:00Z",
                 "--currents", "0.05,0", "--duration", "7h", "--json"]) == 0
    forecast = json.loads(capsys.readouterr().out)["surfacings"]
    for fix, surfacing in zip(fixes[1:], forecast[1:], strict=False):
        north, east = offset_m(surfacing["lat"], surfacing["lon"], fix["lat"], fix["lon"])
        assert math.hypot(north, east) < min(400.0, surfacing["ellipse_m"][1])
        assert abs(surfacing["time_s"] - fix["time_s"]) < 900.0


START_LINE = """mission m
start 54.2, -7.5

state s
begin
  flightroute nav(5433.5, -713)
  flightprofile yo(3, 20, 0.454, 0.454)
  sensors missiontime, depth
  events
    case missiontime >= 600 exit
end
"""


def test_a_start_line_puts_the_glider_there_and_start_overrides_it(tmp_path, capsys):
    from gliderplan.language import check_source
    from gliderplan.language.formatter import format_source

    assert check_source(START_LINE).checked().start_deg == (54.2, -7.5)
    assert "start 54.2, -7.5\n" in format_source(START_LINE)
    mission = tmp_path / "m.mission"
    mission.write_text(START_LINE)
    for args, where in (([], (54.2, -7.5)), (["--start", "54.0,-7.0"], (54.0, -7.0))):
        out = tmp_path / f"run{len(args)}"
        assert main(["sim", str(mission), *args, "-o", str(out)]) == 0
        first = pd.read_parquet(out / "timeseries.parquet").iloc[0]
        assert (first["lat_deg"], first["lon_deg"]) == pytest.approx(where)
    mission.write_text(START_LINE.replace("start 54.2, -7.5", "start 95, 7"))
    assert main(["check", str(mission)]) == 1
    err = capsys.readouterr().err
    assert f"{mission}:2:1: error: start: latitude must lie in [-90, 90]" in err


def write_bathymetry(path: Path) -> Path:
    """GEBCO-style elevation over fig2's waters: 60 m deep in the west shoaling to 15 m in
    the east, land north of 39.3 N."""
    import xarray as xr

    lat, lon = np.linspace(39.0, 39.4, 41), np.linspace(-74.0, -73.6, 41)
    elevation = -np.interp(lon, [-74.0, -73.6], [60.0, 15.0])[None, :].repeat(41, 0)
    elevation[lat > 39.3, :] = 12.0
    xr.Dataset({"elevation": (("lat", "lon"), elevation)},
               coords={"lat": lat, "lon": lon}).to_netcdf(path)
    return path


def test_a_bathymetry_grid_is_the_floor_under_the_glider(tmp_path, capsys):
    floor = str(write_bathymetry(tmp_path / "gebco.nc"))
    deep, shallow = tmp_path / "deep", tmp_path / "shallow"
    # fig2 dives to 20 m: over 59 m of water it never reaches the floor, over 15.2 m it does
    assert main(["sim", str(FIG2), "--start", "39.17,-73.99", "--floor", floor,
                 "--duration", "1200s", "-o", str(deep)]) == 0
    assert main(["sim", str(FIG2), "--start", "39.17,-73.605", "--floor", floor,
                 "--duration", "1200s", "-o", str(shallow)]) == 0
    summaries = {run.name: json.loads((run / "summary.json").read_text())
                 for run in (deep, shallow)}
    assert summaries["deep"]["grounded"] is None and summaries["shallow"]["grounded"]
    assert "bathymetry" in summaries["deep"]["sea_floor"]
    capsys.readouterr()
    assert main(["sim", str(FIG2), "--start", "39.35,-73.8", "--floor", floor,
                 "-o", str(tmp_path / "land")]) == 2
    err = capsys.readouterr().err
    assert "is on land in the bathymetry" in err and not (tmp_path / "land").exists()
    bad = write_field(tmp_path / "currents.nc")
    assert main(["sim", str(FIG2), "--floor", str(bad), "-o", str(tmp_path / "b")]) == 1
    assert "no bathymetry: expected a variable named" in capsys.readouterr().err


def test_the_step_flies_a_field_over_a_grid_as_the_reference(tmp_path):
    """A current field and a bathymetry grid are looked up where the glider is, in Python:
    the runtime's C step flies them in the Python loop, the same flight as the reference
    executor's, grounding included."""
    field = str(write_field(tmp_path / "field.nc", north=0.05))
    floor = str(write_bathymetry(tmp_path / "gebco.nc"))
    runs = {}
    for runtime in ("python", "step"):
        out = tmp_path / runtime
        assert main(["sim", str(FIG2), "--start", "39.17,-73.605,2016-06-23T12:00:00Z",
                     "--currents", field,
                     "--floor", floor, "--duration", "1200s", "--runtime", runtime,
                     "-o", str(out)]) == 0
        runs[runtime] = ((out / "trace.csv").read_text(),
                         pd.read_parquet(out / "timeseries.parquet"),
                         json.loads((out / "summary.json").read_text()))
    (trace, table, summary), (step_trace, step_table, step_summary) = runs.values()
    assert step_trace == trace
    assert summary["grounded"] and step_summary["grounded"] == summary["grounded"]
    for column in ("depth_m", "lat_deg", "lon_deg", "state", "power_pump_w"):
        assert table[column].equals(step_table[column]), column
