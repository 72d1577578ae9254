"""The simulated ocean: presets, profile files (and their errors), the North Sea log."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gliderplan.sim import ocean
from gliderplan.sim.ocean import OceanFileError

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
    with pytest.raises(OceanFileError, match="bench, sea-trial, north-sea, uniform"):
        ocean.load_ocean("atlantis")


@pytest.mark.skipif(not LOGS.is_dir(), reason="the Slocum sample logs are not present")
def test_north_sea_profile_from_the_slocum_log_is_20_c_over_15_c_at_5_to_20_m():
    water = ocean.load_ocean("north-sea", LOGS)
    assert water.temperature_c(2.0) == pytest.approx(20.2, abs=0.5)
    assert water.temperature_c(30.0) == pytest.approx(14.9, abs=0.3)
    assert water.temperature_c(5.0) > 19.5 and water.temperature_c(20.0) < 15.2
    assert water.temperature_c(12.0) < 17.5  # the thermocline lies between


def test_north_sea_without_logs_says_what_is_needed(tmp_path):
    with pytest.raises(OceanFileError, match="Slocum logs"):
        ocean.load_ocean("north-sea")
    with pytest.raises(OceanFileError, match="no Slocum science logs"):
        ocean.load_ocean("north-sea", tmp_path)
