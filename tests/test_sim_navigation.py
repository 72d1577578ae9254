"""The glider's position estimate and current correction under water (sim.navigation):
the current it measures at each GPS fix, the estimate that flies with it, and the heading
upstream of its course."""

from __future__ import annotations

import math

import pytest

from gliderplan.power_models import load_vehicle
from gliderplan.power_models.segments import IRIDIUM
from gliderplan.sim.geo import offset_m
from gliderplan.sim.navigation import corrected_heading, updated_current
from gliderplan.sim.vehicle import Current, GliderSim

VEHICLE = load_vehicle("slocum_g2_shallow").neutral()
PITCH, BALLAST = 0.454, 233.0


def dive_and_surface(g: GliderSim, heading_rad: float, dive_ticks: int) -> None:
    """Yo between 5 and 30 m on `heading_rad` for `dive_ticks`, then surface to the call."""
    descending = True
    for _ in range(dive_ticks):
        descending = g.depth_m < 29.0 if descending else g.depth_m <= 6.0
        g.step(30.0 if descending else 3.0, -PITCH if descending else PITCH,
               -BALLAST if descending else BALLAST, heading_rad, True, False)
    while g.phase != IRIDIUM:
        g.step(0.0, PITCH, BALLAST, heading_rad, True, True)
    while g.phase == IRIDIUM:  # the call ends: it dives again
        g.step(0.0, PITCH, BALLAST, heading_rad, True, True)


def test_the_fix_measures_the_current_and_the_next_dive_s_estimate_is_right():
    current = Current(north_mps=-0.05, east_mps=0.2)
    g = GliderSim(VEHICLE, 4.0, 39.0, -73.0, current, 5.0)
    dive_and_surface(g, 0.0, 900)
    # the first dive's estimate knew no current: the fix measures it, m_water_vx/vy
    assert g.measured.north_mps == pytest.approx(-0.05, abs=0.002)
    assert g.measured.east_mps == pytest.approx(0.2, abs=0.002)
    dive_and_surface(g, 0.0, 900)
    before_fix = offset_m(g.dr_lat_deg, g.dr_lon_deg, g.lat_deg, g.lon_deg)
    # an hour later the estimate that flew with it is metres off, not the 720 m of the first
    assert math.hypot(*before_fix) < 10.0


def test_current_correction_heads_upstream_so_the_track_over_the_ground_holds_its_course():
    speed, current = 0.3, (0.0, 0.1)  # north-bound in a current toward the east
    heading = corrected_heading(0.0, speed, *current)
    assert heading == pytest.approx(2 * math.pi - math.asin(0.1 / 0.3))
    over_ground_east = speed * math.sin(heading) + current[1]
    assert over_ground_east == pytest.approx(0.0, abs=1e-12)
    assert speed * math.cos(heading) > 0.0  # still making way north
    # a current across faster than the glider: met head on across, not a NaN
    assert corrected_heading(0.0, 0.1, 0.0, 0.5) == pytest.approx(1.5 * math.pi)
    assert corrected_heading(1.0, 0.0, 0.0, 0.5) == 1.0  # no speed: the course as it is


def test_a_glider_with_current_correction_keeps_its_course_once_it_knows_the_current():
    current = Current(0.0, 0.15)
    g = GliderSim(VEHICLE, 4.0, 39.0, -73.0, current, 5.0, correction_speed_mps=0.3)
    dive_and_surface(g, 0.0, 900)  # the first dive measures the current
    start = g.lat_deg, g.lon_deg
    dive_and_surface(g, 0.0, 900)
    north, east = offset_m(*start, g.lat_deg, g.lon_deg)
    uncorrected = 0.15 * 900 * 4.0
    assert north > 0.0 and abs(east) < 0.3 * uncorrected  # mostly the surface's drift


def test_updated_current_adds_the_fix_s_error_over_the_time_since_the_last():
    assert updated_current(0.1, 0.0, 360.0, -720.0, 3600.0) == pytest.approx((0.2, -0.2))
    assert updated_current(0.1, 0.2, 50.0, 50.0, 0.0) == (0.1, 0.2)  # no fix before


def test_current_correction_off_in_a_mission_lets_the_current_carry_the_glider(tmp_path):
    """A transit north in a current toward the east, surfacing every hour: with the
    correction the glider heads upstream after its first fix; `current_correction off`
    (u_use_current_correction 0) flies the bearing to the waypoint and is carried east."""
    import pandas as pd

    from gliderplan.cli.main import main
    from gliderplan.planner.routing import transit_mission

    text = transit_mission([(39.5, -73.9)], 6 * 3600.0, surface_every_s=3600.0)
    east_m = {}
    for setting in ("on", "off"):
        mission = tmp_path / f"{setting}.mission"
        mission.write_text(text.replace("mission transit\n",
                                        f"mission transit\ncurrent_correction {setting}\n"))
        out = tmp_path / setting
        assert main(["sim", str(mission), "--start", "39.1,-73.9", "--currents", "0,0.1",
                     "-o", str(out)]) == 0
        end = pd.read_parquet(out / "timeseries.parquet").iloc[-1]
        east_m[setting] = offset_m(39.1, -73.9, end["lat_deg"], end["lon_deg"])[1]
    assert east_m["on"] < 0.5 * east_m["off"]
    assert east_m["off"] > 0.5 * 0.1 * 6 * 3600.0  # bearing to the waypoint: carried off


def test_import_slocum_translates_current_correction(tmp_path):
    from pathlib import Path

    from gliderplan.cli.main import main

    nsb3 = Path(__file__).resolve().parents[2] / "shared" / "data" / "slocum-missions" / \
        "nsb3" / "nsb3.mi"
    if not nsb3.is_file():
        pytest.skip("the shared Slocum missions")
    out = tmp_path / "nsb3.mission"
    assert main(["import-slocum", str(nsb3), "-o", str(out)]) == 0
    assert "\ncurrent_correction on\n" in out.read_text()  # nsb3.mi:10 sets it to 1


def test_a_held_heading_is_not_corrected_and_both_runtimes_fly_it_alike(tmp_path):
    """`heading(deg)` (Slocum's set_heading): in a current across it the glider keeps its
    compass heading and is carried off with the current, where a nav toward a point east
    of the start heads upstream; the C runtime commands the same heading over the pty and
    the same glider flies the same track."""
    import pandas as pd

    from gliderplan.cli.main import main
    from gliderplan.planner.routing import transit_mission

    # a transit surfacing every hour: the fixes measure the current
    text = transit_mission([(39.1, -73.4)], 4 * 3600.0, surface_every_s=3600.0)
    goto = "goto_list(1000, (3906.0000, -7324.0000))"  # 30' of longitude east
    tracks = {}
    for name, route, runtime in (("held", "heading(90)", "python"),
                                 ("held_c", "heading(90)", "c"), ("nav", goto, "python")):
        mission = tmp_path / f"{name}.mission"
        mission.write_text(text.replace(goto, route))
        out = tmp_path / name
        assert main(["sim", str(mission), "--runtime", runtime, "--currents", "0.1,0",
                     "--start", "39.1,-73.9", "--seed", "3", "-o", str(out)]) == 0
        tracks[name] = pd.read_parquet(out / "timeseries.parquet")
    held, nav = tracks["held"], tracks["nav"]
    for column in ("lat_deg", "lon_deg", "depth_m"):
        assert held[column].equals(tracks["held_c"][column]), column
    north_m = {k: offset_m(39.1, -73.9, t["lat_deg"].iloc[-1], t["lon_deg"].iloc[-1])[0]
               for k, t in (("held", held), ("nav", nav))}
    drift_m = 0.1 * 14400.0
    assert north_m["held"] == pytest.approx(drift_m, rel=0.05)  # carried the whole way
    # the correction heads upstream under water once a fix has measured the current (the
    # drift at the surface and on the first dive stay): about 0.55 of the held's
    assert north_m["nav"] < 0.7 * north_m["held"]


def _forecast_against_flight(tmp_path, capsys, route: str) -> list[tuple[dict, float, float]]:
    """A 4-hour transit flown on `route` in a 0.1 m/s northward current from 39.1 N, 73.9 W:
    the first three forecast surfacings, each with where the simulated glider was then."""
    import json

    import numpy as np
    import pandas as pd

    from gliderplan.cli.main import main
    from gliderplan.planner.routing import transit_mission

    text = transit_mission([(39.1, -73.4)], 4 * 3600.0, surface_every_s=3600.0)
    mission = tmp_path / "route.mission"
    mission.write_text(text.replace("goto_list(1000, (3906.0000, -7324.0000))", route))
    common = ["--currents", "0.1,0", "--start", "39.1,-73.9"]
    assert main(["forecast", str(mission), "--duration", "4h", "--json", *common]) == 0
    surfacings = json.loads(capsys.readouterr().out)["surfacings"]
    assert main(["sim", str(mission), *common, "-o", str(tmp_path / "run")]) == 0
    track = pd.read_parquet(tmp_path / "run" / "timeseries.parquet")
    assert len(surfacings) >= 3
    return [(s, float(np.interp(s["time_s"], track["time_s"], track["lat_deg"])),
             float(np.interp(s["time_s"], track["time_s"], track["lon_deg"])))
            for s in surfacings[:3]]


def test_the_surfacing_forecast_holds_the_heading_as_the_sim_flies_it(tmp_path, capsys):
    """A held heading in a current across it: the forecast surfacings lie where the
    simulated glider surfaces, within their 90 % ellipses."""
    for s, lat, lon in _forecast_against_flight(tmp_path, capsys, "heading(270)"):
        west_m = -offset_m(39.1, -73.9, lat, lon)[1]
        assert west_m > 0.5 * 0.2 * s["time_s"]  # flew west, its heading, not drifted
        assert math.hypot(*offset_m(s["lat"], s["lon"], lat, lon)) < s["ellipse_m"][0]


def test_the_surfacing_forecast_of_a_spiral_drifts_with_the_current_as_the_sim_flies_it(
        tmp_path, capsys):
    """A `turn` route (a fin held): the glider circles within some tens of metres, so the
    forecast surfacings drift with the current, where the simulated glider surfaces."""
    for s, lat, lon in _forecast_against_flight(tmp_path, capsys, "turn(1)"):
        north_m, east_m = offset_m(39.1, -73.9, lat, lon)
        assert north_m > 0.9 * 0.1 * s["time_s"]  # carried by the current
        assert abs(east_m) < 200.0  # circled, went nowhere through the water
        assert math.hypot(*offset_m(s["lat"], s["lon"], lat, lon)) < s["ellipse_m"][0]
