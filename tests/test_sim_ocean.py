"""The simulated ocean: presets, profile files (and their errors), the North Sea log."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gliderplan.contract.errors import UsageError
from gliderplan.power_models.slocum_log import LogError
from gliderplan.sim import ocean
from gliderplan.sim.ocean import OceanFileError
from gliderplan.sim.slocum_ocean import leg_starts, read_logged_ocean

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
LOGS = DATA / "slocum-logs"


def test_bench_is_24_c_at_the_surface_and_7_c_deep_with_a_moving_thermocline():
    water = ocean.bench()
    assert water.temperature_c(0.0, 0.0) == pytest.approx(24.0, abs=0.01)
    assert water.temperature_c(40.0, 0.0) == pytest.approx(7.0, abs=0.01)
    centres = water.thermocline_depth_m(np.linspace(0, 1200, 50))
    assert centres.max() - centres.min() > 5.0  # one internal wave, +-3 m
    assert water.temperature_c(water.thermocline_depth_m(300.0), 300.0) == pytest.approx(15.5)


def test_sea_trial_thermocline_lies_between_10_and_18_m():
    water = ocean.sea_trial()
    surface, deep = water.temperature_c(0.0), water.temperature_c(40.0)
    change = surface - deep
    assert water.temperature_c(10.0) > deep + 0.85 * change
    assert water.temperature_c(18.0) < deep + 0.15 * change


def test_scalar_and_array_evaluations_agree():
    water = ocean.bench()
    depths, times = np.linspace(0, 30, 31), np.linspace(0, 3000, 31)
    vector = water.temperature_c(depths, times)
    scalar = [water.water_at(float(d), float(t))[0] for d, t in zip(depths, times, strict=True)]
    assert np.allclose(vector, scalar, rtol=0, atol=1e-12)


def test_uniform_water_is_the_same_everywhere():
    water = ocean.uniform(12.0)
    assert water.temperature_c(0.0) == water.temperature_c(80.0, 1e5) == 12.0


def test_profile_file_interpolates_in_depth_and_time(tmp_path):
    path = tmp_path / "casts.csv"
    path.write_text("depth_m,temperature_c,salinity_psu,time_s\n"
                    "0,20,34,0\n10,10,35,0\n0,22,34,100\n10,12,35,100\n")
    water = ocean.read_profile_csv(path)
    assert water.temperature_c(5.0, 0.0) == pytest.approx(15.0)
    assert water.temperature_c(5.0, 50.0) == pytest.approx(16.0)
    assert water.temperature_c(50.0, 1e4) == pytest.approx(12.0)  # held beyond the data
    assert water.salinity_psu(5.0, 0.0) == pytest.approx(34.5)
    assert water.water_at(5.0, 50.0) == pytest.approx((16.0, 34.5))
    assert np.allclose(water.temperature_c(np.array([5.0, 5.0]), np.array([0.0, 50.0])),
                       [15.0, 16.0])


@pytest.mark.parametrize("text, where, what", [
    ("", ":1:", "empty"),
    ("depth,temp\n0,20\n", ":1:", "header"),
    ("depth_m,temperature_c\n0,20\n5\n", ":3:", "expected 2 fields"),
    ("depth_m,temperature_c\n0,20\n5,warm\n", ":3:", "not a number"),
    ("depth_m,temperature_c\n-1,20\n", ":2:", "depth_m must be >= 0"),
    ("depth_m,temperature_c\n0,20\n10,99\n", ":3:", "not sea water"),
    ("depth_m,temperature_c\n10,20\n5,18\n", ":3:", "must increase"),
    ("depth_m,temperature_c\n", ":2:", "no samples"),
])
def test_a_bad_profile_file_is_reported_with_its_line(tmp_path, text, where, what):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(OceanFileError) as err:
        ocean.read_profile_csv(path)
    assert f"{path}{where}" in str(err.value) and what in str(err.value)


def test_unknown_preset_or_missing_file_names_the_presets():
    with pytest.raises(OceanFileError, match="bench, sea-trial, uniform"):
        ocean.load_ocean("atlantis")


def _needs_logs() -> None:
    if not LOGS.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"the Slocum sample logs are missing: {LOGS}")
        pytest.skip("the Slocum sample logs are not present")


def test_replayed_logs_are_20_c_over_15_c_at_5_to_20_m_with_north_sea_salinity():
    _needs_logs()
    water = ocean.load_ocean(str(LOGS))
    assert len(water.casts_s) >= 10  # one cast per logged dive or climb
    for t in (0.0, 2000.0, 4000.0):
        assert water.temperature_c(2.0, t) == pytest.approx(20.3, abs=0.5)
        assert water.temperature_c(30.0, t) == pytest.approx(14.9, abs=0.3)
        assert water.temperature_c(5.0, t) > 19.5 and water.temperature_c(20.0, t) < 15.2
        assert water.temperature_c(12.0, t) < 18.9  # the thermocline lies between
        # TEOS-10 practical salinity of the German Bight, fresher at the surface
        assert 32.0 < water.salinity_psu(1.0, t) < water.salinity_psu(30.0, t) < 34.0
    # the water changes from cast to cast: the replay is not one mean profile
    assert water.temperature_c(12.0, 0.0) != pytest.approx(water.temperature_c(12.0, 4000.0),
                                                           abs=0.5)


def test_one_science_log_replays_alone():
    _needs_logs()
    first = sorted(LOGS.glob("*.ebd"))[0]
    logged = read_logged_ocean(first)
    assert logged.files == (first,)
    assert logged.latitude_deg == pytest.approx(54.28, abs=0.01)  # from the .dbd beside it
    assert logged.profile.start_epoch_s == pytest.approx(1406206796.2, abs=1.0)  # 2014-07-24


def test_logs_that_are_not_there_say_what_is_needed(tmp_path):
    with pytest.raises(OceanFileError, match="no Slocum science logs"):
        ocean.load_ocean(str(tmp_path))
    with pytest.raises(OceanFileError, match="no such file"):
        ocean.load_ocean(str(tmp_path / "x.ebd"))
    (tmp_path / "bad.ebd").write_bytes(b"not a log")
    with pytest.raises(LogError, match=r"bad.ebd: not a Slocum log \(no dbd_label line"):
        ocean.load_ocean(str(tmp_path / "bad.ebd"))


def test_replayed_logs_give_the_floor_their_flight_logs_saw():
    _needs_logs()
    water = ocean.load_water(str(LOGS))
    floor = water.floor
    assert floor is not None and len(floor.times_s) >= 40  # m_water_depth along the flight
    assert floor.median_m == pytest.approx(39.2, abs=0.1)
    assert 38.0 < min(floor.depths_m) and max(floor.depths_m) < 41.0
    assert np.all(np.diff(floor.times_s) > 0.0)
    assert water.floor_note.startswith("sea floor at 38.7-40.6 m along time")
    assert "m_water_depth" in water.floor_note
    # on the casts' clock: both start at the first CTD sample
    assert 0.0 < floor.times_s[0] < water.ocean.casts_s[-1]
    times = np.linspace(-100.0, 9000.0, 37)
    assert floor.depth_along(times).tolist() == [floor.depth_at(t) for t in times]
    # --floor overrides what the logs saw
    assert ocean.load_water(str(LOGS), ocean.flat_floor(25.0)).floor.depths_m == (25.0,)


def test_science_logs_without_their_flight_logs_have_no_floor_and_say_so(tmp_path):
    _needs_logs()
    first = sorted(LOGS.glob("*.ebd"))[0]
    alone = tmp_path / first.name
    alone.write_bytes(first.read_bytes())  # a scratch copy, without the .dbd beside it
    shutil.copytree(LOGS / "cac", tmp_path / "cac")
    water = ocean.load_water(str(alone))
    assert water.floor is None
    assert "no flight logs (*.dbd) beside the science logs" in water.floor_note
    assert "no sea floor" in water.floor_note


class _Logs:
    """Flight logs as dbdreader gives them, from arrays."""

    def __init__(self, **series: tuple[list[float], list[float]]) -> None:
        self.series = {k: (np.array(t, float), np.array(v, float)) for k, (t, v) in
                       series.items()}

    def get(self, name):
        return self.series[name]

    def get_sync(self, first, *others):
        t, v = self.series[first]
        return (t, v, *(np.interp(t, *self.series[o]) for o in others))


def test_the_floor_is_the_glider_s_water_depth_else_its_depth_plus_altitude():
    from gliderplan.sim.slocum_ocean import floor_readings

    water_depth = _Logs(m_water_depth=([10.0, 20.0, 30.0], [-1.0, 41.0, 42.0]))
    time, depth, what = floor_readings(water_depth)
    assert (time.tolist(), depth.tolist(), what) == ([20.0, 30.0], [41.0, 42.0], "m_water_depth")
    altimeter = _Logs(m_water_depth=([10.0], [-1.0]),
                      m_altitude=([10.0, 20.0, 30.0], [-1.0, 5.0, 4.0]),
                      m_depth=([0.0, 40.0], [0.0, 40.0]))
    time, depth, what = floor_readings(altimeter)
    assert (time.tolist(), depth.tolist(), what) == ([20.0, 30.0], [25.0, 34.0],
                                                     "m_depth + m_altitude")
    nothing = _Logs(m_water_depth=([10.0], [-1.0]), m_altitude=([10.0], [-1.0]),
                    m_depth=([10.0], [20.0]))
    time, _, what = floor_readings(nothing)
    assert not len(time) and what.startswith("the flight logs hold no floor reading")


@pytest.mark.parametrize("depth", [-3.0, 0.0, float("nan"), float("inf")])
def test_a_floor_must_be_a_finite_depth_below_the_surface(depth):
    with pytest.raises(UsageError, match="--floor .*: the sea floor's depth must be a finite"):
        ocean.flat_floor(depth)


def test_a_floor_that_is_no_number_names_the_option():
    with pytest.raises(UsageError, match="--floor 'deep': expected the sea floor's depth"):
        ocean.parse_floor("deep")
    assert ocean.parse_floor("40").depth_at(123.0) == 40.0


def test_legs_split_at_the_turns_not_at_noise():
    yo = np.concatenate([np.linspace(0, 20, 50), np.linspace(20, 3, 40), np.linspace(3, 20, 40)])
    yo = yo + 0.3 * np.sin(np.arange(yo.size))  # noise below the turn threshold
    starts = leg_starts(yo)
    assert len(starts) == 3
    assert abs(starts[1] - 49) <= 2 and abs(starts[2] - 89) <= 2




def test_the_replay_example_flies_the_survey_through_the_logged_water(tmp_path):
    _needs_logs()
    example = Path(__file__).resolve().parents[1] / "examples" / "replay_ocean.sh"
    gliderplan = Path(sys.executable).with_name("gliderplan")
    run = subprocess.run([str(example), str(LOGS), str(tmp_path / "run")],
                         env={**os.environ, "GLIDERPLAN": str(gliderplan)},
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    table = pd.read_parquet(tmp_path / "run" / "timeseries.parquet")
    assert table["temperature_c"][table["depth_m"] < 3].min() > 19.5
    assert table["temperature_c"][table["depth_m"] > 19].max() < 15.3
    assert subprocess.run([str(example)], capture_output=True).returncode == 2  # usage
