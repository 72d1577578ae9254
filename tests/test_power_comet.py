"""A second real glider: comet, 2016, ten segments of one deployment with a DVL, a
microstructure logger, an FLNTU and a CTD (../shared/data/slocum-logs-comet-2016).

Calibrated on its logs, it forecasts its own later dives forward within 5 % with the
counter inside the 90 % interval, and its yo period within 10 %; every device figure has
an sd and a source; and a mission that runs fewer devices is forecast without the others.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import tomllib
from pathlib import Path

import pytest

from gliderplan.cli.main import main

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
COMET = DATA / "slocum-logs-comet-2016"
NSB3 = DATA / "slocum-missions" / "nsb3" / "nsb3.mi"


def _needs_comet() -> None:
    if not COMET.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"the comet 2016 logs are missing: {COMET}")
        pytest.skip("the comet 2016 logs are not present")


@pytest.fixture(scope="module")
def comet(tmp_path_factory):
    """(calibrate --validate --json's report, the calibrated vehicle file)."""
    _needs_comet()
    out = tmp_path_factory.mktemp("comet") / "comet.toml"
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        assert main(["calibrate", str(COMET), "--validate", "--json", "-o", str(out)]) == 0
    return json.loads(text.getvalue()), out


def test_the_forward_forecast_holds_its_truth(comet):
    report, _ = comet
    f = report["forecast"]
    assert abs(f["energy_relative_error"]) < 0.05
    low, high = f["energy_interval_j"]
    assert low <= f["measured_j"] <= high
    assert abs(f["yo_period_relative_error"]) < 0.10
    # the record surfaced every four dives: the forecast flies it so
    assert f["command"]["surfacing_cycles"] == [4, 4, 1]


def test_every_device_figure_has_an_sd_and_a_source(comet):
    report, out = comet
    table = {row["device"]: row for row in report["devices"]["table"]}
    assert set(table) == {"ctd", "optics", "logger", "dvl", "fin"}
    # the DVL, logger and FLNTU run in every dive and switch off together at the surface:
    # the log cannot separate them from the base load; their published figures stand
    for device in ("dvl", "logger", "optics", "ctd"):
        assert not table[device]["fitted"] and table[device]["in_hotel"], device
        assert "the log cannot tell it from the base load" in table[device]["basis"]
    assert table["fin"]["fitted"]
    written = tomllib.loads(out.read_text())
    for device, entry in written["devices"].items():
        for figure in (v for k, v in entry.items() if k != "kind"):
            assert figure["sd"] > 0 and figure["source"].startswith("gliderplan calibrate"), (
                device, figure)
    assert written["hotel_includes"]["devices"] == ["ctd", "optics", "logger", "dvl", "fin"]


def test_the_cross_configuration_check_says_why_it_cannot_run_on_comet(comet):
    report, _ = comet
    said = report["configurations"]["not_possible"]
    assert said.startswith("every dive ran the same instruments (ctd, dvl, logger, optics)")


def test_a_mission_without_the_dvl_and_logger_is_forecast_without_them(comet, capsys):
    _, vehicle = comet
    if not NSB3.is_file():
        pytest.skip("the Slocum missions are not present")
    assert main(["forecast", str(NSB3), "--vehicle", str(vehicle), "--duration", "10d",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert "dvl" not in data["devices"] and "logger" not in data["devices"]
    taken_out = [a for a in data["assumptions"] if "not run by this mission" in a]
    assert {a.split(":")[0] for a in taken_out} == {"dvl", "logger"}
    assert data["computer"] == "none"
    # the glide costs the calibrated hotel load less the DVL's and logger's figures
    hotel = tomllib.loads(vehicle.read_text())["hotel_power"]["value"]
    gliding = data["states"]["survey"]["time_s"]
    glide_j = sum(data["devices"][k] for k in ("hotel", "fin", "ctd", "optics"))
    assert glide_j / gliding == pytest.approx(hotel - 1.5 - 1.3, rel=0.01)


def test_two_deployments_pool_their_device_figures_and_measure_the_drift(capsys, tmp_path):
    """Two deployments in one calibration (sebastian 2014 and comet 2016 stand in for two
    years of one glider: the mechanics are the same): each is fitted alone, a device figure
    both fitted is their inverse-variance mean, the hotel load is the latest's, and the
    spread of their hotel loads is the drift a forecast adds."""
    _needs_comet()
    sebastian = DATA / "slocum-logs"
    out = tmp_path / "both.toml"
    assert main(["calibrate", str(sebastian), str(COMET), "--json", "-o", str(out)]) == 0
    report = json.loads(capsys.readouterr().out)
    first, latest = report["deployments"]
    assert first["name"].startswith("sebastian") and latest["name"].startswith("comet")
    assert report["base_drift"]["value_w"] == pytest.approx(
        abs(latest["hotel_power_w"] - first["hotel_power_w"]) / 2 ** 0.5)
    fin = next(f for f in report["figures"] if f["key"] == "devices.fin.on_power")
    assert fin["basis"].startswith("fitted on 2 deployments")
    written = tomllib.loads(out.read_text())
    assert written["hotel_power"]["value"] == pytest.approx(latest["hotel_power_w"], rel=1e-5)
    assert written["base_drift"]["value"] == pytest.approx(report["base_drift"]["value_w"],
                                                           rel=1e-2)
    mission = tmp_path / "m.mission"
    mission.write_text((Path(__file__).parents[1] / "examples" / "fig2.mission").read_text())
    assert main(["forecast", str(mission), "--vehicle", str(out), "--json"]) == 0
    said = json.loads(capsys.readouterr().out)["assumptions"]
    assert any("its file's base_drift" in a for a in said)


def test_the_drift_between_deployments_says_what_it_rests_on():
    from gliderplan.power_models.deployments import DEFAULT_DRIFT_W, drift_w

    sd, said = drift_w([2.0, 2.5, 3.0])
    assert sd == pytest.approx(0.5) and said.startswith("the sd of the hotel loads of its 3")
    close, why = drift_w([2.0, 2.1])
    assert close == DEFAULT_DRIFT_W and "two say little" in why
