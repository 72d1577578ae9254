"""A simulated run exported for glider data pipelines: NetCDF read back (CF trajectory,
IOOS Glider DAC names, ACDD attributes, checked by the IOOS compliance checker), and
the track opened by standard GeoJSON and KML readers."""

from __future__ import annotations

import json
from pathlib import Path

import geojson
import numpy as np
import pandas as pd
import pytest
import xarray as xr
from fastkml import KML

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.contract.errors import UsageError
from gliderplan.sim.export import ExportError, export_run, profile_ids

REPO = Path(__file__).resolve().parents[1]
FIG2 = REPO / "examples" / "fig2.mission"
START = "2024-06-01T06:00:00Z"
DAC_VARIABLES = {  # name -> (standard_name, units) of the IOOS Glider DAC template
    "time": ("time", "seconds since 1970-01-01T00:00:00Z"),
    "lat": ("latitude", "degrees_north"),
    "lon": ("longitude", "degrees_east"),
    "depth": ("depth", "m"),
    "pressure": ("sea_water_pressure", "dbar"),
    "temperature": ("sea_water_temperature", "degree_Celsius"),
    "profile_time": ("time", "seconds since 1970-01-01T00:00:00Z"),
    "profile_lat": ("latitude", "degrees_north"),
    "profile_lon": ("longitude", "degrees_east"),
}
ACDD_GLOBALS = ("title", "summary", "keywords", "Conventions", "id", "naming_authority",
                "history", "source", "processing_level", "license", "date_created",
                "creator_name", "institution", "standard_name_vocabulary",
                "geospatial_lat_min", "geospatial_lat_max", "geospatial_lon_min",
                "geospatial_lon_max", "geospatial_vertical_min", "geospatial_vertical_max",
                "time_coverage_start", "time_coverage_end", "featureType", "cdm_data_type")


@pytest.fixture(scope="module")
def run(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("export") / "run"
    assert main(["sim", str(FIG2), "--netcdf", "--start", START, "-o", str(out)]) == 0
    return out


def test_the_netcdf_reads_back_with_the_dac_variables_and_acdd_attributes(run):
    raw = xr.open_dataset(run / "trajectory.nc", decode_times=False, mask_and_scale=False)
    for name, (standard_name, units) in DAC_VARIABLES.items():
        assert raw[name].attrs["standard_name"] == standard_name, name
        assert raw[name].attrs["units"] == units, name
    for name in ("trajectory", "platform", "instrument_ctd", "profile_id"):
        assert name in raw.variables, name
    assert raw["trajectory"].attrs["cf_role"] == "trajectory_id"
    assert raw["instrument_ctd"].attrs["platform"] == "platform"
    assert raw["temperature"].attrs["instrument"] == "instrument_ctd"
    assert raw["profile_id"].dtype == np.int32
    for attr in ACDD_GLOBALS:
        assert str(raw.attrs[attr]).strip(), attr
    assert raw.attrs["featureType"] == "trajectory"
    assert "CF-1.6" in raw.attrs["Conventions"] and "ACDD-1.3" in raw.attrs["Conventions"]
    assert raw.attrs["time_coverage_start"] == START

    table = pd.read_parquet(run / "timeseries.parquet")
    ds = xr.open_dataset(run / "trajectory.nc")
    assert len(ds.time) == len(table)
    seconds = (ds.time.values - np.datetime64("2024-06-01T06:00:00")) / np.timedelta64(1, "s")
    assert np.allclose(seconds, table["time_s"])
    assert np.allclose(ds.depth, table["depth_m"]) and np.allclose(ds.lat, table["lat_deg"])
    # the CTD's readings, and fill (read back as NaN) while it is off
    assert np.array_equal(np.isnan(ds.temperature), np.isnan(table["temp_reading_c"]))
    # pressure from depth: about 1.01 dbar per metre
    deep = ds.depth > 5
    assert np.allclose(ds.pressure[deep] / ds.depth[deep], 1.01, atol=0.01)
    # one profile per dive or climb of fig2's yo, each with its centre time and place
    ids = raw["profile_id"].values
    numbers = np.unique(ids[ids > 0])
    assert list(numbers) == list(range(1, len(numbers) + 1)) and len(numbers) >= 10
    assert len(ds.profile) == len(numbers)
    for k, t in zip(numbers, raw["profile_time"].values, strict=True):
        inside = raw["time"].values[ids == k]
        assert inside.min() <= t <= inside.max()


def _failures(results) -> list[tuple[int, str, list[str]]]:
    return [(r.weight, r.name, r.msgs) for r in results if r.value[0] != r.value[1]]


# ---- the compliance checker, offline ------------------------------------------------
# cc-plugin-glider (gliderdac:3.0) fetches NCEI's thesauri (projects, platforms,
# instruments, institutions) and its sea-names list when it is loaded; cc-plugin-og
# (og:1.0) fetches NERC's OG1 parameter collection for one check. The tests run offline:
# `_offline` serves them from stand-ins. The NCEI thesauri are served empty, so the one
# check that looks names up in them (low priority: a simulation is registered with no
# NCEI project) is the one that does not pass; the sea names are a few of NCEI's list;
# the OG1 collection is served with the terms the export uses
# (sim.netcdf_formats.OG1_TERMS, taken from the OG format manual's examples), so that
# check tests their form and that every measurement variable has one, not NERC's list.
NCEI_ISO = (b'<?xml version="1.0"?><gmd:MD_Metadata xmlns:gmd="http://www.isotc211.org/2005/'
            b'gmd" xmlns:gco="http://www.isotc211.org/2005/gco" '
            b'xmlns:gmx="http://www.isotc211.org/2005/gmx"/>')
NCEI_SEA_NAMES = ("North Atlantic Ocean", "South Atlantic Ocean", "North Pacific Ocean",
                  "South Pacific Ocean", "Indian Ocean", "Arctic Ocean", "Southern Ocean",
                  "North Sea", "Baltic Sea")


class _Served:
    """What `requests.get(url)` returns for the plugins' resources, offline."""

    status_code = 200

    def __init__(self, url: str) -> None:
        from gliderplan.sim.netcdf_formats import OG1, OG1_TERMS

        self.url = url
        seas = "".join(f"<seaname><seaname>{n}</seaname></seaname>" for n in NCEI_SEA_NAMES)
        self.text = f'<?xml version="1.0" encoding="utf-8"?><seanames>{seas}</seanames>' \
            if "seanames" in url else NCEI_ISO.decode()
        self.content = self.text.encode()
        self.graph = [{"@id": OG1 + term + "/"} for term in OG1_TERMS.values()] + [{}]

    def raise_for_status(self) -> None:
        pass

    def json(self) -> dict:
        return {"@graph": self.graph}


def _check(path: Path, tests: list[str], monkeypatch) -> dict:
    """test -> [(priority, name, messages)] of the checks `path` does not pass."""
    import requests
    from compliance_checker.runner import CheckSuite

    monkeypatch.setattr(requests, "get", lambda url, *args, **kwargs: _Served(url))
    suite = CheckSuite()
    suite.load_all_available_checkers()
    dataset = suite.load_dataset(str(path))
    found = {}
    for test in tests:
        results, errors = suite.run_all(dataset, [test], skip_checks=[])[test]
        assert not errors, (test, errors)
        found[test] = _failures(results)
    return found


NCEI_TABLES = "File has NCEI approved project, institution, platform_type, and instrument"


@pytest.fixture(scope="module")
def exported(run, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("formats")
    assert main(["export", str(run), "--format", "og1,ioos", "--format", "cf", "-o",
                 str(out)]) == 0
    return out


@pytest.mark.filterwarnings("ignore")  # the checker's own, on loading and parsing
def test_the_og1_export_passes_the_oceangliders_checker_and_acdd(exported, monkeypatch):
    failed = _check(exported / "trajectory_og1.nc", ["og:1.0", "acdd:1.3"], monkeypatch)
    assert failed == {"og:1.0": [], "acdd:1.3": []}  # every check, of every priority


@pytest.mark.filterwarnings("ignore")
def test_the_ioos_export_passes_the_glider_dac_checker_cf_and_acdd(exported, monkeypatch):
    failed = _check(exported / "trajectory.nc", ["gliderdac:3.0", "cf:1.6", "acdd:1.3"],
                    monkeypatch)
    assert [f[1] for f in failed["gliderdac:3.0"]] == [NCEI_TABLES]  # low: see above
    assert failed["acdd:1.3"] == []
    # CF prefers "standard" to "gregorian" (suggested), which the DAC asks for (required)
    assert [(f[0], f[1]) for f in failed["cf:1.6"]] == [(1, "§4.4.1 Calendar")]


@pytest.mark.filterwarnings("ignore")
def test_the_cf_export_passes_cf_and_acdd(exported, monkeypatch):
    failed = _check(exported / "trajectory_cf.nc", ["cf:1.6", "acdd:1.3"], monkeypatch)
    assert failed == {"cf:1.6": [], "acdd:1.3": []}


def test_salinity_conductivity_and_density_are_teos10_from_the_ctd(exported, run):
    import gsw

    table = pd.read_parquet(run / "timeseries.parquet")
    og1 = xr.open_dataset(exported / "trajectory_og1.nc", decode_times=False)
    on = ~np.isnan(table["temp_reading_c"].to_numpy())
    assert on.sum() > 100 and np.isnan(og1.PSAL.values[~on]).all()  # fill while it is off
    assert np.allclose(og1.PSAL.values[on], table["salinity_psu"].to_numpy()[on])
    p = og1.PRES.values[on]
    conductivity = gsw.C_from_SP(og1.PSAL.values[on], og1.TEMP.values[on], p)  # mS/cm
    assert np.allclose(og1.CNDC.values[on], conductivity)
    sa = gsw.SA_from_SP(og1.PSAL.values[on], p, og1.LONGITUDE.values[on],
                        og1.LATITUDE.values[on])
    rho = gsw.rho(sa, gsw.CT_from_t(sa, og1.TEMP.values[on], p), p)
    assert np.allclose(og1.DENSITY.values[on], rho) and 1020 < np.nanmean(rho) < 1030
    ioos = xr.open_dataset(exported / "trajectory.nc")
    assert np.allclose(ioos.conductivity.values[on], conductivity / 10.0)  # S m-1
    assert og1.attrs["start_date"] == "20240601T060000" and og1.sizes == {
        "N_MEASUREMENTS": len(table)}


def test_the_deployment_s_names_come_from_a_metadata_file(run, tmp_path, capsys):
    (tmp_path / "meta.toml").write_text('creator_name = "A. Pilot"\nsea_name = "North Sea"\n'
                                        'wmo_id = "6801665"\n')
    assert main(["export", str(run), "--format", "og1", "--metadata",
                 str(tmp_path / "meta.toml"), "-o", str(tmp_path / "out")]) == 0
    og1 = xr.open_dataset(tmp_path / "out" / "trajectory_og1.nc")
    assert og1.attrs["creator_name"] == "A. Pilot" and og1.attrs["sea_name"] == "North Sea"
    assert str(og1.WMO_IDENTIFIER.values) == "6801665"
    (tmp_path / "bad.toml").write_text('creator_nam = "A. Pilot"\n')
    capsys.readouterr()
    assert main(["export", str(run), "--format", "og1", "--metadata",
                 str(tmp_path / "bad.toml"), "-o", str(tmp_path / "x")]) == ExitCode.USAGE
    assert "bad.toml: creator_nam: not a metadata key" in capsys.readouterr().err


def test_export_writes_the_track_as_geojson_and_kml_for_standard_readers(run, tmp_path):
    assert main(["export", str(run), "--geojson", "--kml", "-o", str(tmp_path)]) == 0
    table = pd.read_parquet(run / "timeseries.parquet")
    first = [table["lon_deg"].iloc[0], table["lat_deg"].iloc[0]]
    last = [table["lon_deg"].iloc[-1], table["lat_deg"].iloc[-1]]
    steps = np.diff(np.round(table[["lon_deg", "lat_deg"]].to_numpy(), 7), axis=0)
    moves = 1 + int(np.any(steps != 0, axis=1).sum())  # a glider at the surface waits

    collection = geojson.loads((tmp_path / "track.geojson").read_text())
    assert collection.is_valid
    line = collection["features"][0]["geometry"]
    assert line["type"] == "LineString" and len(line["coordinates"]) == moves
    assert np.allclose(line["coordinates"][0], first) and np.allclose(line["coordinates"][-1],
                                                                      last)

    document = KML.parse(tmp_path / "track.kml").features[0]
    track, start, end = document.features
    coords = np.array(track.geometry.coords)
    assert len(coords) == moves and np.allclose(coords[-1][:2], last)
    assert np.allclose(start.geometry.coords[0][:2], first)
    assert track.times.begin.dt.isoformat() == "2024-06-01T06:00:00+00:00"
    assert end.name.endswith("end")


def test_a_long_track_is_thinned_but_keeps_its_ends(run, tmp_path):
    from gliderplan.sim.export import _track

    table = pd.read_parquet(run / "timeseries.parquet")
    thinned = _track(table, max_points=100)
    assert len(thinned) <= 101
    assert np.allclose(thinned[0], table[["lon_deg", "lat_deg"]].iloc[0])
    assert np.allclose(thinned[-1], table[["lon_deg", "lat_deg"]].iloc[-1])


def test_profiles_are_dives_and_climbs_not_the_surface():
    depth = np.concatenate([np.zeros(10), np.linspace(0, 20, 40), np.linspace(20, 2, 30),
                            np.linspace(2, 2.5, 10)])
    ids = profile_ids(depth)
    assert set(ids[11:48]) == {1} and set(ids[51:78]) == {2}
    assert (ids[:10] == -999).all()  # waiting at the surface


@pytest.mark.parametrize("argv, code, message", [
    (["export", "{run}"], 2, "--format og1|ioos|cf (NetCDF), --geojson and/or --kml"),
    (["export", "{run}", "--format", "netcdf4"], 2, "--format netcdf4: expected one of"),
    (["export", "{missing}", "--kml"], 2, "nope: no such directory"),
    (["export", "{empty}", "--kml"], 2, "summary.json: no such file; is"),
    (["export", "{broken}", "--kml"], 1, "summary.json: not valid JSON"),
])
def test_export_refuses_bad_input_in_one_line(run, tmp_path, capsys, argv, code, message):
    (tmp_path / "empty").mkdir()
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "summary.json").write_text("{not json")
    names = {"run": run, "missing": tmp_path / "nope", "empty": tmp_path / "empty",
             "broken": tmp_path / "broken"}
    assert main([a.format(**names) for a in argv]) == code
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err


def test_export_run_is_the_call_behind_export(run, tmp_path):
    written = export_run(run, ["kml", "netcdf", "geojson"], tmp_path / "out")
    assert [p.name for p in written] == ["track.kml", "trajectory.nc", "track.geojson"]
    assert all(p.stat().st_size > 0 for p in written)
    with pytest.raises(UsageError) as refused:
        export_run(tmp_path / "nope", ["kml"])
    assert refused.value.exit_code == ExitCode.USAGE
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "summary.json").write_text("[]")
    (tmp_path / "bad" / "timeseries.parquet").write_bytes((run / "timeseries.parquet")
                                                           .read_bytes())
    with pytest.raises(ExportError) as refused:
        export_run(tmp_path / "bad", ["kml"])
    assert refused.value.exit_code == ExitCode.BAD_INPUT
    assert str(refused.value).startswith(f"{tmp_path / 'bad' / 'summary.json'}: expected a "
                                         "JSON table (object), got list; is ")
    assert not (tmp_path / "bad" / "track.kml").exists()


def test_sim_refuses_a_start_that_is_not_a_time(tmp_path, capsys):
    assert main(["sim", str(FIG2), "--start", "yesterday", "-o", str(tmp_path)]) == 2
    assert "--start: 'yesterday' is not an ISO 8601 time" in capsys.readouterr().err


def test_the_summary_records_the_start(run):
    assert json.loads((run / "summary.json").read_text())["start_utc"] == START
