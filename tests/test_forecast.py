"""`gliderplan forecast`: what a mission will cost on a glider, by device, with its 90 %
interval and every assumption; a Slocum `.mi` forecast as imported (its own computers)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.language import check_source
from gliderplan.planner.forecast import forecast_mission
from gliderplan.power_models import load_sensor, load_vehicle
from gliderplan.power_models.devices import base_power_w

ROOT = Path(__file__).resolve().parents[1]
MISSIONS = ROOT.parent / "shared" / "data" / "slocum-missions"
DAY = 86400.0

SURVEY = """mission survey
vehicle {vehicle}
computer {computer}
battery 1 kWh reserve 10 %
horizon 2 d
var last = 0
state yo
begin
  flightroute noheading
  flightprofile yo(3, 36, .43, .43)
  sensors missiontime, depth, {sensors}
  events
    case missiontime - last >= 43200 set last = missiontime call fix
end
state fix
begin
  flightroute noheading
  flightprofile surface
  sensors missiontime, depth
  events
    case missiontime - last >= 800 return
end
"""


def _mission(vehicle="slocum_g2_shallow", computer="none", sensors="temp"):
    text = SURVEY.format(vehicle=vehicle, computer=computer, sensors=sensors)
    return check_source(text, "survey.mission").checked()


def _forecast(capsys, *args) -> dict:
    assert main(["forecast", *args, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_the_forecast_adds_up_by_device_and_states_its_interval():
    result = forecast_mission(_mission(), draws=100)
    data = result.to_json()
    assert data["energy_j"] == pytest.approx(sum(data["devices"].values()))
    low, high = data["energy_interval_j"]
    assert low < data["energy_j"] < high
    assert data["duration_s"] == pytest.approx(2 * DAY)
    assert data["yos"] > 100 and data["surfacing_count"] == 3  # at 12, 24 and 36 h
    assert data["yos_interval"][0] <= data["yos"] <= data["yos_interval"][1]
    assert data["yos_interval"][1] > data["yos_interval"][0]  # the flight figures' spread
    assert data["devices"]["computer"] == 0.0  # computer none
    assert any("computer none" in a and "no extra board" in a for a in data["assumptions"])


def test_an_extra_board_is_charged_only_where_the_mission_names_one():
    none = forecast_mission(_mission(), draws=20)
    board = forecast_mission(_mission(computer="ts7800 @ 300 MHz"), draws=20)
    extra = board.devices_j["computer"]
    assert extra > 0 and board.energy_j - none.energy_j == pytest.approx(extra, rel=1e-6)


def test_an_instrument_is_billed_for_its_duty_and_one_the_hotel_holds_but_the_mission_does_not_run_is_taken_out():  # noqa: E501
    vehicle = load_vehicle("slocum_g2_shallow")  # its hotel load holds the CTD and optics
    full = forecast_mission(_mission(sensors="temp"), draws=20)
    half = forecast_mission(_mission(sensors="temp duty 0.5"), draws=20)
    gliding = full.states["yo"].gliding_s
    ctd = load_sensor("ctd").on_power_w
    assert full.devices_j["ctd"] - half.devices_j["ctd"] == pytest.approx(0.5 * ctd * gliding)
    assert "optics" not in full.devices_j  # not run: out of the hotel load
    fin = vehicle.device("fin")
    assert full.devices_j["hotel"] == pytest.approx(
        (base_power_w(vehicle) - fin.on_power_w * fin.duty) * gliding)
    assert any(a.startswith("optics: in the vehicle's hotel load as calibrated, not run")
               for a in full.assumptions)


def test_the_interval_widens_with_the_drift_to_another_deployment():
    vehicle = load_vehicle("slocum_g2_shallow")
    result = forecast_mission(_mission(), draws=200)
    low, high = result.interval_j
    gliding = result.states["yo"].gliding_s
    # the drift alone (sd 0.5 W over the glide) spans 2 x 1.64 sd; the figures add to it
    assert high - low > 2 * 1.64 * 0.5 * gliding * 0.9
    assert vehicle.base_drift_w == 0.0  # the preset states none: the default, said so
    assert any("sd 0.5 W over the gliding time" in a for a in result.assumptions)


def test_forecast_of_a_slocum_mission_runs_on_its_own_computers(capsys):
    if not MISSIONS.is_dir():
        pytest.skip("the Slocum missions are not present")
    data = _forecast(capsys, str(MISSIONS / "nsb3" / "nsb3.mi"), "--duration", "10d")
    assert data["computer"] == "none" and data["devices"]["computer"] == 0.0
    assert set(data) >= {"energy_j", "energy_interval_j", "duration_s", "devices",
                         "assumptions"}
    assert len(data["energy_interval_j"]) == 2 and data["duration_s"] == pytest.approx(10 * DAY)
    # nsb3 samples its CTD and FLNTU while it yos; its logger and DVL stay off
    assert data["devices"]["ctd"] > 0 and data["devices"]["optics"] > 0
    assert "dvl" not in data["devices"] and "logger" not in data["devices"]
    assert data["surfacing_count"] == pytest.approx(10 * 8, abs=2)  # every 3 h
    # what the import could not carry over is an assumption of the forecast
    assert any(a.startswith("import-slocum: ") and "d_use_pitch 1" in a
               for a in data["assumptions"])
    text = capsys.readouterr()
    assert main(["forecast", str(MISSIONS / "nsb3" / "nsb3.mi"), "--duration", "1d"]) == 0
    out = capsys.readouterr().out
    assert "computer none" in out and "energy by device:" in out and "assumptions:" in out
    del text


def test_a_calibrated_glider_s_devices_follow_the_mission(tmp_path, capsys):
    """A glider calibrated with a DVL on throughout: a mission without it is billed without
    it, and the forecast says so."""
    text = (ROOT / "power_models" / "data" / "vehicle_slocum_g2_shallow.toml").read_text()
    mine = tmp_path / "dvl.toml"
    mine.write_text(text.replace('devices = ["ctd", "optics", "fin"]',
                                 'devices = ["ctd", "optics", "fin", "dvl"]')
                    .replace("hotel_power = { value = 2.41364",
                             "hotel_power = { value = 3.71364"))
    mission = tmp_path / "m.mission"
    mission.write_text(SURVEY.format(vehicle=f'"{mine}"', computer="none", sensors="temp"))
    without = _forecast(capsys, str(mission))
    mission.write_text(SURVEY.format(vehicle=f'"{mine}"', computer="none",
                                     sensors="temp, groundspeed"))
    with_dvl = _forecast(capsys, str(mission))
    dvl = load_sensor("dvl").on_power_w
    gliding = with_dvl["states"]["yo"]["time_s"]
    assert with_dvl["devices"]["dvl"] == pytest.approx(dvl * gliding, rel=1e-6)
    assert with_dvl["energy_j"] - without["energy_j"] == pytest.approx(dvl * gliding, rel=0.01)
    assert any(a.startswith("dvl: in the vehicle's hotel load as calibrated, not run")
               for a in without["assumptions"])


def test_the_water_given_is_the_water_flown(capsys):
    data = _forecast(capsys, str(ROOT / "examples" / "fig2.mission"), "--ocean", "bench")
    water = next(a for a in data["assumptions"] if a.startswith("water: "))
    assert "bench: in-situ density (TEOS-10)" in water and "ballasted for it" in water


LOGS = ROOT.parent / "shared" / "data" / "slocum-logs"


def _yo_forecast(profile: str, floor: float | None = None):
    text = SURVEY.format(vehicle="slocum_g2_shallow", computer="none", sensors="temp")
    mission = check_source(text.replace("yo(3, 36, .43, .43)", profile), "m.mission").checked()
    from gliderplan.sim.ocean import flat_floor

    return forecast_mission(mission, duration_s=2 * DAY, draws=8,
                            floor=None if floor is None else flat_floor(floor))


def test_a_yo_with_an_altimeter_stop_is_planned_to_max_depth_where_the_floor_is_unknown():
    stopped = _yo_forecast("yo(3, 50, .43, .43, 4)")
    assert stopped.energy_j == _yo_forecast("yo(3, 50, .43, .43)").energy_j
    assert "yo: turns at 4 m above the sea floor: planned to max_depth (50 m), the floor " \
           "unknown" in stopped.assumptions


def test_over_a_known_floor_the_band_ends_where_the_altimeter_turns_the_dive():
    over = _yo_forecast("yo(3, 50, .43, .43, 4)", floor=40.0)
    band = _yo_forecast("yo(3, 36, .43, .43)")  # the band it flies: 40 m less 4 m
    assert (over.energy_j, over.yos) == (band.energy_j, band.yos)
    assert over.yos > 1.3 * _yo_forecast("yo(3, 50, .43, .43, 4)").yos  # shorter yos
    assert "yo: turns at 4 m above the sea floor: planned to 36 m, min(max_depth 50 m, the " \
           "floor's 40 m less 4 m)" in over.assumptions
    assert "sea floor: sea floor at 40.0 m: --floor 40" not in over.assumptions  # no note given
    # a floor deeper than the band changes nothing; a yo without a stop ignores the floor
    assert _yo_forecast("yo(3, 50, .43, .43, 4)", floor=80.0).energy_j == \
        _yo_forecast("yo(3, 50, .43, .43)").energy_j
    assert _yo_forecast("yo(3, 50, .43, .43)", floor=40.0).energy_j == \
        _yo_forecast("yo(3, 50, .43, .43)").energy_j


def test_the_floor_of_replayed_logs_sets_the_band(capsys):
    if not (MISSIONS.is_dir() and LOGS.is_dir()):
        pytest.skip("the Slocum missions or logs are not present")
    nsb3 = str(MISSIONS / "nsb3" / "nsb3.mi")
    data = _forecast(capsys, nsb3, "--duration", "2d", "--ocean", str(LOGS))
    notes = data["assumptions"]
    assert any(a.startswith("sea floor: sea floor at 38.7-40.6 m along time (median 39.2 m)")
               for a in notes)
    assert "survey: turns at 4 m above the sea floor: planned to 35.2 m, min(max_depth 50 m, " \
           "the floor's 39.2 m less 4 m)" in notes
    flat = _forecast(capsys, nsb3, "--duration", "2d", "--ocean", str(LOGS), "--floor", "60")
    assert data["yos"] > 1.2 * flat["yos"]  # over 60 m of water it dives to 50 m


@pytest.mark.parametrize("args, code, message", [
    (["examples/fig2.mission", "--floor", "-40"], ExitCode.USAGE,
     "--floor -40.0: the sea floor's depth must be a finite number"),
    (["examples/fig2.mission", "--floor", "deep"], ExitCode.USAGE,
     "--floor 'deep': expected the sea floor's depth in metres"),
    (["nosuch.mission"], ExitCode.USAGE, "nosuch.mission"),
    (["examples/fig2.mission", "--duration", "soon"], ExitCode.USAGE, "--duration 'soon'"),
    (["examples/fig2.mission", "--vehicle", "nosuch"], ExitCode.USAGE,
     "unknown vehicle preset"),
    (["examples/fig2.mission", "--ocean", "nosuch"], ExitCode.USAGE, "nosuch"),
])
def test_bad_input_is_a_message_and_an_exit_code(capsys, monkeypatch, args, code, message):
    monkeypatch.chdir(ROOT)
    assert main(["forecast", *args]) == code
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_a_slocum_mission_without_its_mafiles_is_refused_naming_them(tmp_path, capsys):
    if not MISSIONS.is_dir():
        pytest.skip("the Slocum missions are not present")
    lonely = tmp_path / "nsb3.mi"
    lonely.write_text((MISSIONS / "nsb3" / "nsb3.mi").read_text())
    assert main(["forecast", str(lonely)]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert ".ma" in err and "Traceback" not in err


def test_a_mission_with_errors_is_refused_with_its_diagnostics(tmp_path, capsys):
    bad = tmp_path / "bad.mission"
    bad.write_text("mission m\nstate s\nbegin\n  flightprofile yoo(3, 20, .4, .4)\nend\n")
    assert main(["forecast", str(bad)]) == ExitCode.BAD_INPUT
    assert "bad.mission:4" in capsys.readouterr().err


def test_the_water_of_a_glider_s_logs_is_the_water_flown(capsys):
    logs = ROOT.parent / "shared" / "data" / "slocum-logs-comet-2016"
    if not logs.is_dir():
        pytest.skip("the comet 2016 logs are not present")
    data = _forecast(capsys, str(ROOT / "examples" / "fig2.mission"), "--ocean", str(logs))
    water = next(a for a in data["assumptions"] if a.startswith("water: "))
    low, high = (float(x) for x in water.split("(TEOS-10) ")[1].split(" kg/m3")[0].split("-"))
    assert 1000.0 < low <= high < 1012.0  # the Baltic's brackish water, not the ocean's
    assert data["energy_interval_j"][0] < data["energy_j"] < data["energy_interval_j"][1]


def test_forecast_gives_every_surfacing_s_time_position_and_ellipse(capsys, tmp_path):
    """nsb3's goto list heads north-east from its south-west start: so must its
    surfacings, later and less sure each time; written as GeoJSON and KML."""
    if not MISSIONS.is_dir():
        pytest.skip("the Slocum missions are not present")
    mi = str(MISSIONS / "nsb3" / "nsb3.mi")
    out = tmp_path / "s.geojson"
    data = _forecast(capsys, mi, "--duration", "12h", "--start", "54.20,7.00,2016-06-23T12:00Z",
                     "--currents", "0.05,0", "--surfacings-out", str(out))
    surfacings = data["surfacings"]
    assert len(surfacings) == round(data["surfacing_count"]) == 4
    assert all(set(s) >= {"time_s", "lat", "lon", "ellipse_m"} for s in surfacings)
    lats = [s["lat"] for s in surfacings]
    # it starts at the surface (prepare_to_dive), then heads for 54 33.5 N, 7 13.0 E
    assert surfacings[0]["lat"] == pytest.approx(54.2) and surfacings[0]["time_s"] == 0.0
    assert lats == sorted(lats) and lats[1] > 54.21
    assert [s["time_s"] for s in surfacings] == sorted(s["time_s"] for s in surfacings)
    majors = [s["ellipse_m"][0] for s in surfacings]
    assert majors == sorted(majors) and all(len(s["ellipse_m"]) == 2 for s in surfacings)
    features = json.loads(out.read_text())["features"]
    assert [f["geometry"]["type"] for f in features[:2]] == ["Point", "Polygon"]
    kml = tmp_path / "s.kml"
    assert main(["forecast", mi, "--duration", "12h", "--surfacings-out", str(kml)]) == 0
    assert kml.read_text().count("<Placemark>") == 4


@pytest.mark.parametrize("args, message", [
    (["--surfacings-out", "s.txt"], "expected a .geojson, .json or .kml file"),
    (["--currents", "0,7"], "faster than any ocean current"),
    (["--start", "54.2"], "not an ISO 8601 time"),
])
def test_bad_surfacing_input_is_a_message(capsys, args, message):
    code = main(["forecast", str(ROOT / "examples" / "fig2.mission"), *args])
    err = capsys.readouterr().err
    assert code != 0 and message in err and "Traceback" not in err
