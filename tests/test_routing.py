"""Current-aware routes: through a jet the planned route beats the straight line by
about what it predicts, flown in the simulator; and bad input."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from gliderplan.cli.main import main
from gliderplan.planner.routing import ground_speed, path_time_s, plan_route
from gliderplan.sim.currents import GriddedCurrent, UniformCurrent

MISSION = """mission hop

state go
begin
  flightroute nav(3906.0, -7339.0)
  flightprofile yo(3, 30, 0.454, 0.454)
  sensors missiontime, depth
  events
    case missiontime >= 86400 exit
end
"""


def jet(lat: np.ndarray, lon: np.ndarray) -> GriddedCurrent:
    """An eastward jet along 39.16 N over a westward counter-current along 39.1 N."""
    grid_lat, _ = np.meshgrid(lat, lon, indexing="ij")
    east = 0.35 * np.exp(-((grid_lat - 39.16) / 0.02) ** 2) \
        - 0.15 * np.exp(-((grid_lat - 39.1) / 0.03) ** 2)
    shape = (1, 1, len(lat), len(lon))
    return GriddedCurrent(np.array([0.0]), np.array([0.0]), lat, lon, np.zeros(shape),
                          east.reshape(shape))


def write_jet(path: Path) -> Path:
    import xarray as xr

    field = jet(np.linspace(39.0, 39.3, 61), np.linspace(-74.0, -73.6, 81))
    xr.Dataset({"uo": (("latitude", "longitude"), field.east_mps[0, 0]),
                "vo": (("latitude", "longitude"), field.north_mps[0, 0])},
               coords={"latitude": field.lat_deg, "longitude": field.lon_deg}).to_netcdf(path)
    return path


def test_ground_speed_holds_the_course_or_says_it_cannot():
    assert ground_speed(np.array(0.0), np.array(0.1), np.array(0.0), 0.3) == \
        pytest.approx(np.sqrt(0.3 ** 2 - 0.1 ** 2))
    assert np.isnan(ground_speed(np.array(0.0), np.array(0.4), np.array(0.0), 0.3))
    assert np.isnan(ground_speed(np.array(-0.4), np.array(0.0), np.array(0.0), 0.3))


def test_in_a_uniform_current_the_straight_line_is_the_route():
    field = UniformCurrent(0.05, 0.1)
    plan = plan_route(field, (39.1, -73.9), [(39.1, -73.8), (39.15, -73.8)], 0.0, 0.25)
    assert plan.gain == pytest.approx(0.0, abs=0.01)
    assert plan.straight_s == pytest.approx(
        path_time_s(field, [(39.1, -73.9), (39.1, -73.8), (39.15, -73.8)], 0.0, 0.25))


def test_through_a_jet_the_planned_route_saves_time_and_flies_it(tmp_path, capsys):
    mission = tmp_path / "hop.mission"
    mission.write_text(MISSION)
    field = write_jet(tmp_path / "jet.nc")
    assert main(["route", str(mission), "--currents", str(field), "--start",
                 "39.1,-73.8,2016-06-23T00:00Z", "--speed", "0.23", "--fly", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["gain"] > 0.3  # up into the jet and back, not against the counter-current
    assert max(lat for lat, _ in r["legs"][0]["route"]) > 39.13
    flown = r["flown_s"]
    assert flown["planned"] < flown["straight"]
    assert r["flown_gain"] == pytest.approx(r["gain"], abs=0.2)


@pytest.mark.parametrize("args, message", [
    (["--currents", "0,0", "--cells", "5"], "--cells 5: between 10 and 400"),
    (["--currents", "0,0", "--speed", "9"], "--speed 9: a glider flies 0.05 to 2 m/s"),
    (["--currents", "0,0.3", "--speed", "0.2"], "the current holds the glider off it"),
    (["--currents", "0,0.5", "--speed", "0.2", "--minimise", "energy"],
     "no route reaches the waypoints at any pitch of 15, 20, 26, 32 degrees"),
])
def test_bad_route_input_is_a_message(tmp_path, capsys, args, message):
    mission = tmp_path / "hop.mission"
    mission.write_text(MISSION.replace("nav(3906.0, -7339.0)", "nav(3906.0, -7349.0)"))
    assert main(["route", str(mission), "--start", "39.1,-73.7", *args]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_maps_are_drawn_for_sim_forecast_and_route(tmp_path):
    mission = tmp_path / "hop.mission"
    mission.write_text(MISSION)
    field = str(write_jet(tmp_path / "jet.nc"))
    start = "39.1,-73.8,2016-06-23T00:00Z"
    for command in (["sim", str(mission), "--duration", "3h", "-o", str(tmp_path / "run")],
                    ["forecast", str(mission), "--duration", "12h"],
                    ["route", str(mission), "--speed", "0.23"]):
        out = tmp_path / f"{command[0]}.png"
        assert main([*command, "--start", start, "--currents", field, "--map", str(out)]) == 0
        assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["route", str(mission), "--start", start, "--currents", field,
                 "--map", str(tmp_path / "m.gif")]) == 2


def test_the_pitch_is_chosen_for_the_least_time_or_energy():
    """The fastest pace for time; for energy the pace whose route costs least, which in
    still water is not the fastest (the pump's and pitch motor's draw grows faster than
    the speed past the transit's pitch)."""
    from gliderplan.planner.route_pace import paces, plan_paced_route

    still = UniformCurrent(0.0, 0.0)
    start, points = (39.1, -73.9), [(39.1, -73.8)]
    nominal, choices = paces(0.23, points)
    assert len(choices) == 4 and nominal.speed_mps == pytest.approx(0.23)
    fastest = max(choices, key=lambda p: p.speed_mps)
    by_time = plan_paced_route(still, start, points, 0.0, nominal, choices, "time", 20)
    by_energy = plan_paced_route(still, start, points, 0.0, nominal, choices, "energy", 20)
    assert by_time.pace == fastest
    least = min(choices, key=lambda p: p.power_w / p.speed_mps)
    assert by_energy.pace == least and least != fastest
    assert by_energy.planned_j < by_time.planned_j and by_time.plan.planned_s < \
        by_energy.plan.planned_s
    assert by_energy.gains()["energy"] >= 0.0  # never worse than the straight line's


def test_through_a_jet_the_paced_route_saves_time_and_energy_as_flown(tmp_path, capsys):
    mission = tmp_path / "hop.mission"
    mission.write_text(MISSION)
    field = write_jet(tmp_path / "jet.nc")
    assert main(["route", str(mission), "--currents", str(field), "--start",
                 "39.1,-73.8,2016-06-23T00:00Z", "--speed", "0.23", "--minimise", "energy",
                 "--fly", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["minimise"] == "energy" and r["energy_gain"] > 0.3
    flown_s, flown_j = r["flown_s"], r["flown_j"]
    assert flown_s["planned"] < flown_s["straight"] and flown_j["planned"] < flown_j["straight"]
    # the sim's energy and time saved are what the plan predicts, within its model's error
    assert r["flown_energy_gain"] == pytest.approx(r["energy_gain"], abs=0.15)
    assert r["flown_gain"] == pytest.approx(r["time_gain"], abs=0.15)
    # the forecast's power is the sim's: the straight line's energy within 15 %
    assert flown_j["straight"] == pytest.approx(r["straight_nominal_j"], rel=0.15)
