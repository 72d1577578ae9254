"""Power per device: the glide's power split into a base load and each logged device's, on a
synthetic glider whose devices' figures are known, and billed by the planner, the simulator
and the forecast alike (`power_models.devices`)."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest
import synthetic_glider as sg

from gliderplan.power_models import load_sensor, load_vehicle
from gliderplan.power_models import segments as seg
from gliderplan.power_models.deployments import Deployment
from gliderplan.power_models.device_fit import fit_devices
from gliderplan.power_models.devices import base_power_w, gliding_power_w
from gliderplan.power_models.draws import draw_vehicles
from gliderplan.power_models.slocum_instruments import INSTRUMENTS, devices, sampling_duty
from gliderplan.power_models.vehicle_fit import fit_vehicle

BOTTOMS = (40.0,) * 8
DVL_W, LOGGER_W, OPTICS_W, OPTODE_W = 1.1, 1.7, 0.6, 0.3
SWITCHING = {
    "dvl": (DVL_W, frozenset({0, 1, 4, 5})),  # on in half the dives: separable
    "logger": (LOGGER_W, frozenset(range(8))),  # on in every dive: not separable
    "optics": (OPTICS_W, frozenset({2, 3, 6})),  # optics and optode switch together
    "optode": (OPTODE_W, frozenset({2, 3, 6})),
}


@pytest.fixture(scope="module")
def log():
    return sg.synthetic_log(BOTTOMS, devices=SWITCHING)


@pytest.fixture(scope="module")
def fit(log):
    return fit_devices(log, seg.segment(log), seg.interval_energy_j(log))


def _figure(fit, device):
    return next(f for f in fit.figures if f.device == device)


def test_a_device_that_switches_on_its_own_is_fitted(fit):
    dvl = _figure(fit, "dvl")
    assert dvl.fitted and not dvl.held
    assert dvl.on_power_w == pytest.approx(DVL_W, rel=1e-6)
    assert dvl.duty == pytest.approx(0.5, abs=0.05)


def test_a_device_on_throughout_keeps_its_published_figure_in_the_hotel_load(fit):
    logger = _figure(fit, "logger")
    assert not logger.fitted and logger.held
    assert logger.on_power_w == load_sensor("logger").on_power_w
    assert "the log cannot tell it from the base load" in logger.basis
    low, high = load_sensor("logger").power_range_w
    assert logger.sd_w == pytest.approx((high - low) / 4.0)
    # the base takes what the published figure misses: the whole glide is still measured
    assert fit.base_w + logger.on_power_w == pytest.approx(sg.HOTEL_W + LOGGER_W, rel=1e-6)


def test_devices_that_switch_together_are_fitted_as_one_and_split_by_their_published_figures(
        fit):
    optics, optode = _figure(fit, "optics"), _figure(fit, "optode")
    assert optics.fitted and optode.fitted
    assert optics.on_power_w + optode.on_power_w == pytest.approx(OPTICS_W + OPTODE_W)
    published = load_sensor("optics").on_power_w / load_sensor("optode").on_power_w
    assert optics.on_power_w / optode.on_power_w == pytest.approx(published)
    assert "switching with optode" in optics.basis and "switching with optics" in optode.basis
    assert optics.sd_w > 0 and optode.sd_w > 0  # the split is uncertain, and says so


def test_the_fin_s_power_and_its_moving_share_are_fitted():
    log = sg.synthetic_log(BOTTOMS, devices={"fin": (0.4, frozenset({1, 3, 5, 7}))})
    fit = fit_devices(log, seg.segment(log), seg.interval_energy_j(log))
    fin = _figure(fit, "fin")
    assert fin.kind == "actuator" and fin.held and fin.fitted
    assert fin.on_power_w == pytest.approx(0.4, rel=1e-6)
    assert fit.hotel_w == pytest.approx(sg.HOTEL_W + 0.4 * fin.duty, rel=1e-6)


def test_a_fitted_figure_outside_its_published_span_is_flagged():
    log = sg.synthetic_log(BOTTOMS, devices={"dvl": (9.0, frozenset({0, 1, 4, 5}))})
    dvl = _figure(fit_devices(log, seg.segment(log), seg.interval_energy_j(log)), "dvl")
    assert dvl.flag == "9 W lies outside the published 0.75-3.5 W"


def test_a_device_on_too_briefly_keeps_its_published_figure():
    log = sg.synthetic_log(BOTTOMS[:2], devices={"dvl": (DVL_W, frozenset())})
    never = _figure(fit_devices(log, seg.segment(log), seg.interval_energy_j(log)), "dvl")
    assert not never.fitted and not never.held and "on for 0 s" in never.basis
    brief = sg.synthetic_log(BOTTOMS[:4], devices={"dvl": (DVL_W, frozenset({1, 2}))})
    dvl = _figure(fit_devices(brief, seg.segment(brief), seg.interval_energy_j(brief)), "dvl")
    assert dvl.fitted  # on for two dives of ~560 s, off for two: enough
    short = sg.synthetic_log((8.0, 8.0), devices={"dvl": (DVL_W, frozenset({1}))})
    dvl = _figure(fit_devices(short, seg.segment(short), seg.interval_energy_j(short)), "dvl")
    assert not dvl.fitted and "too little to fit it" in dvl.basis


def test_the_calibrated_vehicle_carries_every_device_figure_with_an_sd(log):
    calibration = fit_vehicle(log, load_vehicle("slocum_g3"), resamples=6)
    vehicle = calibration.vehicle
    spread = dict(zip(vehicle.uncertainty.keys, vehicle.uncertainty.sd, strict=True))
    for device in ("dvl", "logger", "optics", "optode"):
        assert spread[f"devices.{device}.on_power"] > 0.0, device
    assert vehicle.hotel_includes == ("logger",)
    assert base_power_w(vehicle) == pytest.approx(vehicle.hotel_w - LOAD_OF(vehicle, "logger"))


def LOAD_OF(vehicle, device):  # noqa: N802
    return vehicle.device(device).on_power_w


def test_a_mission_is_billed_for_the_instruments_it_runs_at_their_duty():
    vehicle = load_vehicle("slocum_g2_shallow")  # its hotel load holds the CTD and optics
    ctd, optics = (load_sensor(d).on_power_w for d in ("ctd", "optics"))
    as_calibrated = gliding_power_w(vehicle)
    assert sum(as_calibrated.values()) == pytest.approx(vehicle.hotel_w)
    half_ctd = gliding_power_w(vehicle, {"ctd": 0.5})
    assert sum(half_ctd.values()) == pytest.approx(vehicle.hotel_w - optics - 0.5 * ctd)
    assert half_ctd["ctd"] == pytest.approx(0.5 * ctd)
    fin = vehicle.device("fin")
    assert half_ctd["fin"] == pytest.approx(fin.on_power_w * fin.duty)


def test_draws_never_make_a_negative_base_load(monkeypatch):
    """The instruments the hotel load holds have wide published figures; the load itself is
    measured: a draw whose instruments would draw more than the load is drawn again."""
    from gliderplan.power_models import draws

    vehicle = load_vehicle("slocum_g2_shallow")
    wide = dataclasses.replace(vehicle, uncertainty=dataclasses.replace(
        vehicle.uncertainty, sd=vehicle.uncertainty.sd * 4.0))

    def lowest_base(n: int = 1000) -> float:
        drawn = draw_vehicles(wide, n, np.random.default_rng(4))
        return min(v.hotel_w - sum(v.device(d).on_power_w for d in ("ctd", "optics"))
                   for v in drawn)

    assert lowest_base() >= 0.0
    monkeypatch.setattr(draws, "MAX_REDRAWS", 0)
    assert lowest_base() < 0.0  # without the redraws some would: the bound binds


def test_every_device_an_instrument_is_has_a_preset():
    from gliderplan.power_models.catalog import preset_names

    assert set(devices()) <= set(preset_names("sensor"))
    assert INSTRUMENTS[19].switch == "c_flntu_on" and INSTRUMENTS[43].device == "dvl"
    assert INSTRUMENTS[1].device == "ctd" and INSTRUMENTS[39].device == "logger"


@pytest.mark.parametrize("interval, expected", [(-1.0, 0.0), (np.nan, 0.0), (0.0, 1.0),
                                                (20.0, 0.25), (2.0, 1.0)])
def test_a_sampling_interval_powers_the_instrument_for_its_warm_up_and_one_sample(
        interval, expected):
    assert float(sampling_duty(interval, 3.0, 0.5)) == pytest.approx(expected)


def test_calibrate_writes_the_device_table(tmp_path, monkeypatch):
    from gliderplan.power_models import log_calibration

    log = sg.synthetic_log(BOTTOMS, devices=SWITCHING)
    monkeypatch.setattr(log_calibration, "read_flight_log", lambda logs, cache: log)
    monkeypatch.setattr(log_calibration, "expand_log_paths", list)
    monkeypatch.setattr(log_calibration, "split_deployments",
                        lambda files: [Deployment(tuple(files), None)])
    out = tmp_path / "mine.toml"
    log_calibration.calibrate(["synthetic"], base="slocum_g3", output=out)
    data = tomllib.loads(out.read_text())
    assert data["devices"]["dvl"]["kind"] == "sensor"
    assert data["devices"]["dvl"]["on_power"]["value"] == pytest.approx(DVL_W, rel=1e-4)
    assert data["devices"]["dvl"]["on_power"]["sd"] >= 0.0
    assert "published figure" in data["devices"]["logger"]["on_power"]["source"]
    assert data["hotel_includes"]["devices"] == ["logger"]
    mine = load_vehicle(str(out))
    assert mine.device("dvl").on_power_w == pytest.approx(DVL_W, rel=1e-4)


def test_a_configuration_is_forecast_from_the_fit_of_another():
    """Half the dives run a DVL beside the logger, half the logger alone: fitted on the
    first (the DVL on throughout them: its published figure), the second's energy is
    forecast from it, inside its interval."""
    from gliderplan.power_models.config_check import check_configurations

    log = sg.synthetic_log(BOTTOMS, devices={"dvl": (DVL_W, frozenset({0, 1, 2, 3})),
                                             "logger": (LOGGER_W, frozenset(range(8)))})
    check = check_configurations(log, load_vehicle("slocum_g3"))
    assert check.fitted_devices == ("dvl", "logger") and check.reason == ""
    (other,) = check.forecasts
    assert other.devices == ("logger",) and other.dives >= 3
    assert abs(other.relative_error) < 0.1
    assert other.interval_j[0] <= other.measured_j <= other.interval_j[1]


def test_a_log_with_one_configuration_says_it_cannot_be_cross_checked():
    from gliderplan.power_models.config_check import check_configurations

    log = sg.synthetic_log(BOTTOMS[:4], devices={"logger": (LOGGER_W, frozenset(range(4)))})
    check = check_configurations(log, load_vehicle("slocum_g3"))
    assert check.forecasts == ()
    assert check.reason.startswith("every dive ran the same instruments (logger)")
