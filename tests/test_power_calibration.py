"""Calibration: recovering known figures from a synthetic log, and the real glider's log.

The real-log tests read ../shared/data/slocum-logs relative to the project root (the
sebastian 2014 dive series). Where it is missing they are skipped and say so (under
CI=true a skip fails); where it is present, a replay error above 5 % fails loudly.
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
import synthetic_glider as sg

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.power_models import calibration, load_vehicle
from gliderplan.power_models.catalog import preset_names, preset_path
from gliderplan.power_models.deployments import Deployment
from gliderplan.power_models.slocum_log import FlightLog
from gliderplan.power_models.vehicle import FIGURES, figure_value, read_vehicle_file

LOGS = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "slocum-logs"
COMET = LOGS.parent / "slocum-logs-comet-2016"
needs_logs = pytest.mark.skipif(
    not LOGS.is_dir(),
    reason="real Slocum logs not found at ../shared/data/slocum-logs (relative to the project "
    "root): the calibration check against real data did NOT run",
)
MAX_VALIDATION_ERROR = 0.05

# ---- a synthetic glider whose figures are known ------------------------------------
def _synthetic_log(bottoms=(20.0, 40.0, 60.0, 20.0, 40.0, 60.0)) -> FlightLog:
    return sg.synthetic_log(bottoms)


def test_fit_recovers_a_known_glider():
    fit = calibration.fit_energy(_synthetic_log(), load_vehicle("slocum_g3"))
    vehicle = fit.vehicle
    assert vehicle.hotel_w == pytest.approx(sg.HOTEL_W, rel=0.02)
    assert vehicle.surface_w == pytest.approx(sg.SURFACE_W, rel=0.05)
    assert vehicle.iridium_w == pytest.approx(sg.IRIDIUM_W, rel=0.02)
    assert vehicle.pump_energy_j(40.0, 460.0) == pytest.approx(
        (sg.PUMP_OUT_J_PER_CC + sg.PUMP_OUT_J_PER_CC_M * 40) * 460, rel=0.05
    )
    assert vehicle.pump_out_j_per_cc_m == pytest.approx(sg.PUMP_OUT_J_PER_CC_M, rel=0.1)
    assert vehicle.pump_in_j_per_cc == pytest.approx(sg.PUMP_IN_J_PER_CC, rel=0.1)
    fitted = {c.key for c in fit.coefficients if c.fitted}
    assert fitted >= {"hotel_power", "surface_power", "iridium_power", "pump_in_energy_per_volume",
                      "pump_out_energy_per_volume", "pump_out_energy_per_volume_depth"}


def test_the_pump_and_the_surfacing_are_the_log_s_not_the_base_s():
    from gliderplan.power_models.vehicle_fit import fit_once

    base = load_vehicle("slocum_g3")  # 20.5 cc/s, +-560 cc, 389 J per surfacing
    vehicle, figures, *_ = fit_once(_synthetic_log(), base)
    fitted = {f.key: f for f in figures if f.fitted}
    assert vehicle.pump_rate_cc_s == pytest.approx(sg.PUMP_RATE_CC_S, rel=0.01)
    assert vehicle.max_ballast_cc == sg.truth().max_ballast_cc != base.max_ballast_cc
    assert "x_ballast_pumped_max" in fitted["max_ballast"].basis
    # the surface power the log measured holds the air pump and the GPS: nothing on top
    assert base.surfacing_fixed_j > 0 and vehicle.surfacing_fixed_j == 0.0
    assert "count them twice" in fitted["surfacing_energy"].basis


def test_a_log_without_the_pump_s_readings_keeps_the_base_s_rate_and_says_why():
    from dataclasses import replace

    from gliderplan.power_models.vehicle_fit import fit_once

    log = _synthetic_log()
    log = replace(log, pump_velocity_cc_s=np.full(log.t_s.size, np.nan),
                  ballast_limit_cc=float("nan"))
    base = load_vehicle("slocum_g3")
    vehicle, figures, *_ = fit_once(log, base)
    by_key = {f.key: f for f in figures}
    assert not by_key["pump_rate"].fitted and vehicle.pump_rate_cc_s == base.pump_rate_cc_s
    assert "no m_ballast_pumped_vel" in by_key["pump_rate"].basis
    # without the pump's limit, the largest volume it pumped: a lower bound, and said so
    assert by_key["max_ballast"].at_least
    assert vehicle.max_ballast_cc == pytest.approx(np.max(np.abs(log.ballast_cc)))


def test_a_log_at_one_depth_keeps_the_depth_term_of_the_base():
    base = load_vehicle("slocum_g3")
    fit = calibration.fit_energy(_synthetic_log(bottoms=(40.0,)), base)
    kept = {c.key: c for c in fit.coefficients}["pump_out_energy_per_volume_depth"]
    assert not kept.fitted and fit.vehicle.pump_out_j_per_cc_m == base.pump_out_j_per_cc_m


SURFACING = ("surface_power", "iridium_power", "surface_time", "iridium_time")


def test_two_or_more_surfacings_are_resampled_for_their_spread():
    from gliderplan.power_models.vehicle_fit import fit_vehicle

    calls = (100.0, 400.0, 250.0)  # the synthetic glider's surface stays are alike but these
    fit = fit_vehicle(sg.synthetic_log(calls_s=calls), load_vehicle("slocum_g3"), resamples=8)
    by_key = {f.key: f for f in fit.figures}
    u = fit.vehicle.uncertainty
    assert set(SURFACING) <= set(u.keys)
    call = by_key["iridium_time"]
    # the record ends in the last call: the two whole stays give the figure, the bootstrap's
    # sd of a mean of two: the calls' spread / sqrt(2)
    assert call.value == pytest.approx(250.0, rel=0.02)
    assert "the last, which the record cuts short, left out" in call.basis
    assert call.sd == pytest.approx(np.std(calls[:2]) / math.sqrt(2), rel=0.15)
    assert "bootstrap over 2 surfacings" in call.basis and "independent" in call.basis
    assert not call.at_least and u.at_least == ()
    # stays alike but for their calls: no spread to resample, so a stated one, not none
    stay = by_key["surface_time"]
    assert "assumption, 30 % of the value" in stay.basis
    assert stay.sd == pytest.approx(0.3 * stay.value)
    order = list(u.keys)
    dive = next(k for k in order if k not in SURFACING)  # a figure of the dives' bootstrap
    assert u.correlation[order.index("iridium_time"), order.index(dive)] == 0.0


def test_a_few_alike_stays_are_spread_as_one_stay_scatters():
    """Two stays whose calls barely differ cannot show how stays differ: the sd is no less
    than the assumed scatter of a stay (30 %) over the stays seen."""
    from gliderplan.power_models.vehicle_fit import fit_vehicle

    fit = fit_vehicle(sg.synthetic_log(calls_s=(240.0, 245.0, 240.0)),
                      load_vehicle("slocum_g3"), resamples=4)
    call = next(f for f in fit.figures if f.key == "iridium_time")
    assert call.sd == pytest.approx(0.3 * call.value / math.sqrt(2), rel=1e-6)
    assert "raised to the assumed scatter of a stay (30 %) over 2 stays" in call.basis


def test_a_single_surfacing_gets_a_stated_spread_never_none():
    from gliderplan.power_models.surfacing_fit import ASSUMED_RELATIVE_SD
    from gliderplan.power_models.vehicle_fit import fit_vehicle

    fit = fit_vehicle(_synthetic_log(), load_vehicle("slocum_g3"), resamples=4)
    for f in fit.figures:
        if f.key in SURFACING:
            assert f.sd == pytest.approx(ASSUMED_RELATIVE_SD[f.key] * f.value), f.key
            assert "sd: assumption" in f.basis and "1 surfacing(s)" in f.basis, f.key
    assert set(SURFACING) <= set(fit.vehicle.uncertainty.keys)


def test_replay_of_the_synthetic_glider_is_nearly_exact():
    result = calibration.validate(_synthetic_log(), load_vehicle("slocum_g3"))
    assert abs(result.relative_error) < 0.01
    assert result.measured_j > 0


# ---- the real glider ----------------------------------------------------------------
def _calibrate(capsys, *extra):
    code = main(["calibrate", str(LOGS), "--cache", str(LOGS / "cac"), "--json", *extra])
    out = capsys.readouterr().out
    return code, (json.loads(out) if out.strip() else None)


@needs_logs
def test_real_log_replay_error_is_within_five_percent(capsys):
    code, report = _calibrate(capsys, "--validate")
    assert code == 0
    error = report["relative_error"]
    val = report["validation"]
    assert val["kind"].startswith("replay")
    assert abs(error) <= MAX_VALIDATION_ERROR, (
        f"replay error {error:+.2%} exceeds {MAX_VALIDATION_ERROR:.0%}: predicted "
        f"{val['predicted_j']:.0f} J vs coulomb counter {val['measured_j']:.0f} J ({val['split']})"
    )
    # fitted and held-out parts are different stretches of the record
    assert 0.2 * report["duration_s"] < val["duration_s"] < 0.8 * report["duration_s"]
    assert val["predicted_by_component_j"]["pump"] > 0 and val["measured_j"] > 1000


@needs_logs
def test_real_log_writes_every_fitted_figure_with_its_sd_and_source(capsys, tmp_path):
    out = tmp_path / "sebastian.toml"
    code, report = _calibrate(capsys, "-o", str(out))
    assert code == 0 and report["output"] == str(out)
    vehicle = read_vehicle_file(out)
    assert vehicle.name == "sebastian"
    text = out.read_text()
    fitted = {f["key"] for f in report["figures"] if f["fitted"]}
    assert fitted >= {
        "hotel_power", "pump_out_energy_per_volume", "pump_in_energy_per_volume",
        "flight.drag_cd0", "flight.trim_volume", "flight.compressibility",
        "flight.water_density", "top_turn_time", "bottom_turn_time", "dive_pitch_error",
        "climb_pitch_error", "surface_time", "iridium_time", "surface_power", "iridium_power",
    }
    for key in fitted:  # each with its own source line, not the base's
        line = next(x for x in text.splitlines() if x.startswith(key.split(".")[-1] + " = "))
        assert "gliderplan calibrate on sebastian-2014-204-05-000" in line, key
    # the bootstrap over dives gives the flight and energy figures a spread ...
    assert set(vehicle.uncertainty.keys) >= {"hotel_power", "flight.drag_cd0",
                                             "flight.trim_volume", "top_turn_time"}
    assert np.all(vehicle.uncertainty.sd > 0)
    # ... the one surfacing shows none, so its figures get a spread the file calls an
    # assumption, independent of the rest; the call the record cut short is a lower bound
    data = tomllib.loads(text)
    for key in SURFACING:
        assert key in vehicle.uncertainty.keys, key
        assert "sd: assumption" in data[key]["source"] and data[key]["sd"] > 0, key
    assert data["iridium_time"]["at_least"] is True
    # its one stay is cut short in its call: both its times are lower bounds
    assert vehicle.uncertainty.at_least == ("surface_time", "iridium_time")
    assert "surfacing figures: assumed" in data["uncertainty"]["source"]
    order = list(vehicle.uncertainty.keys)
    corr = vehicle.uncertainty.correlation
    assert corr[order.index("surface_time"), order.index("hotel_power")] == 0.0
    # light in the North Sea water its CTD measured (1023-1025 kg/m3), not 1025
    assert 1023.0 < vehicle.flight.rho_kg_m3 < 1025.0 and vehicle.flight.trim_cc > 0
    # they logged throughout; the fin moved through every glide
    assert vehicle.hotel_includes == ("ctd", "optics", "fin")


@needs_logs
def test_the_preset_is_this_log_calibrated(capsys, tmp_path):
    out = tmp_path / "sebastian.toml"
    _, report = _calibrate(capsys, "-o", str(out))
    mine, preset = read_vehicle_file(out), load_vehicle("slocum_g2_shallow")
    # every figure the preset's source says calibrate fitted, as the preset writes it (6
    # digits), with its sd and the bootstrap's correlation (3 decimals)
    fitted = [f for f in report["figures"] if f["fitted"]]
    assert {f["key"] for f in fitted} >= {"pump_out_energy_per_volume", "pitch_energy",
                                          "surface_power", "iridium_power"}
    for f in fitted:
        assert figure_value(preset, f["key"]) == pytest.approx(f["value"], rel=1e-5,
                                                               abs=1e-5), f["key"]
    spread = dict(zip(preset.uncertainty.keys, preset.uncertainty.sd, strict=True))
    # the instruments the log cannot separate keep their published figures and spread
    published = {f["key"] for f in report["figures"] if f["key"].startswith("devices.")
                 and not f["fitted"]}
    assert published == {"devices.ctd.on_power", "devices.optics.on_power"}
    assert spread.keys() == {f["key"] for f in fitted if f["sd"] is not None} | published
    for f in fitted:
        if f["sd"] is not None:
            assert spread[f["key"]] == pytest.approx(f["sd"], rel=5e-3), f["key"]
    assert preset.uncertainty.keys == mine.uncertainty.keys
    assert np.allclose(preset.uncertainty.correlation, mine.uncertainty.correlation,
                       atol=2e-3)
    for attribute in ("hotel_w", "pump_in_j_per_cc", "top_turn_s", "bottom_turn_s",
                      "iridium_s", "surface_s"):
        assert getattr(mine, attribute) == pytest.approx(getattr(preset, attribute), rel=0.01,
                                                         abs=0.01), attribute
    for attribute in ("drag_cd0", "trim_cc", "compressibility_per_pa", "rho_kg_m3"):
        assert getattr(mine.flight, attribute) == pytest.approx(
            getattr(preset.flight, attribute), rel=0.01), attribute


# every figure the shared log measures: the current sensor phase by phase, the pump's
# readings and limit, the steady glides with the CTD, the pitch, the turns, the surfacing
MEASURED = (
    "hotel_power", "surface_power", "iridium_power", "surfacing_energy",
    "pump_out_energy_per_volume", "pump_in_energy_per_volume", "pitch_energy", "pump_rate",
    "max_ballast", "surface_time", "iridium_time", "top_turn_time", "bottom_turn_time",
    "dive_pitch_error", "climb_pitch_error", "flight.drag_cd0", "flight.trim_volume",
    "flight.compressibility", "flight.water_density", "devices.fin.on_power",
    "devices.fin.duty",
)
# fitted given a figure the log cannot show, the base's depth term of the pump-in energy
# (every pump-in run is at the top of a yo)
DEPENDS_ON_THE_BASE = ("pump_in_energy_per_volume",)


@pytest.fixture(scope="module", params=[n for n in preset_names("vehicle")
                                         if load_vehicle(n).kind == "glider"])
def calibrated_on(request, tmp_path_factory):
    """(base, its calibration of the shared log with --validate, the written file)."""
    if not LOGS.is_dir():
        pytest.skip(needs_logs.kwargs["reason"])
    from gliderplan.power_models import calibrate

    out = tmp_path_factory.mktemp(request.param) / "mine.toml"
    result = calibrate([str(LOGS)], base=request.param, validate=True, output=out)
    return request.param, result, out


def _entry(data: dict, key: str) -> dict:
    if key.startswith("devices."):
        _, device, figure = key.split(".")
        return data["devices"][device][figure]
    return data["flight"][key[7:]] if key.startswith("flight.") else data[key]


@needs_logs
def test_every_base_preset_calibrates_to_a_forecast_within_the_bounds(calibrated_on):
    base, result, _ = calibrated_on
    f = result.report["forecast"]
    assert abs(f["energy_relative_error"]) < 0.03, (base, f["energy_relative_error"])
    low, high = f["energy_interval_j"]
    assert low < f["measured_j"] < high, (base, f["energy_interval_j"], f["measured_j"])
    assert abs(f["yo_period_relative_error"]) < 0.10, base
    for kind, error in f["vertical_speed_relative_error"].items():
        assert abs(error) < 0.10, (base, kind, error)
    # the forecast names what it took from the base: nothing the log measured
    assert not set(f["figures_from_base"]) & set(MEASURED), f["figures_from_base"]


@needs_logs
def test_no_base_figure_the_log_measures_survives_calibration(calibrated_on):
    base, result, out = calibrated_on
    written = tomllib.loads(out.read_text())
    preset = tomllib.loads(preset_path("vehicle", base).read_text())
    logs = "gliderplan calibrate on sebastian-2014-204-05-000, sebastian-2014-204-05-001: "
    for key in MEASURED:
        entry = _entry(written, key)
        assert entry["source"].startswith(logs), (base, key, entry["source"])
        try:
            theirs = _entry(preset, key)["source"]
        except KeyError:
            continue  # a figure the preset leaves at its default
        if not theirs.startswith("gliderplan calibrate on"):
            assert theirs not in entry["source"], (base, key)
    # the log decides them, not the base: the same from every base
    mine = read_vehicle_file(out)
    reference = load_vehicle("slocum_g2_shallow")  # calibrated on this log
    for key in set(MEASURED) - set(DEPENDS_ON_THE_BASE):
        assert figure_value(mine, key) == pytest.approx(figure_value(reference, key),
                                                        rel=1e-4, abs=1e-6), (base, key)
    # what the hotel load and the surface power hold, said by the log
    assert written["hotel_includes"]["source"].startswith(logs)
    assert mine.hotel_includes == ("ctd", "optics", "fin")
    assert "air pump" in written["surface_power"]["source"]
    assert mine.surfacing_fixed_j == 0.0
    # every other figure says it is the base's
    for key in set(FIGURES) - set(MEASURED):
        try:
            entry = _entry(written, key)
        except KeyError:
            continue
        assert entry["source"].startswith(f"base {base} ("), (key, entry["source"])


@needs_logs
def test_max_error_turns_a_poor_fit_into_a_failure(capsys):
    assert main(["calibrate", str(LOGS), "--validate", "--max-error", "0.00001"]) == 1
    assert "exceeds --max-error" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        (["calibrate", "nowhere.dbd"], 2, "nowhere.dbd: no such file"),
        (["calibrate", ".", "--max-error", "0.05"], 2, "--max-error needs --validate"),
        # NaN would pass every forecast (|error| > nan is never true)
        (["calibrate", ".", "--validate", "--max-error", "nan"], 2, "got 'nan'"),
        (["calibrate", ".", "--validate", "--max-error", "inf"], 2, "got 'inf'"),
        (["calibrate", ".", "--validate", "--max-error", "-0.01"], 2, "got '-0.01'"),
        (["calibrate", ".", "-o", "out.txt"], 2, "must end in .toml"),
        (["calibrate", ".", "--base", "slocum_g9"], 2, "unknown vehicle preset"),
    ],
)
def test_calibrate_bad_input(capsys, argv, code, message):
    try:
        result = main(argv)
    except SystemExit as exit_:  # argparse rejects a malformed value before run()
        result = exit_.code
    assert result == code
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_calibrate_rejects_a_file_that_is_not_a_log(capsys, tmp_path):
    bogus = tmp_path / "x.dbd"
    bogus.write_bytes(b"not a log")
    assert main(["calibrate", str(bogus)]) == 1
    assert f"{bogus}: not a Slocum log (no dbd_label line first)" in capsys.readouterr().err


def _copy_logs(tmp_path: Path) -> Path:
    copy = tmp_path / "logs"
    copy.mkdir()
    for log in LOGS.glob("*.?bd"):
        (copy / log.name).write_bytes(log.read_bytes())
    return copy


def _cut(path: Path, fraction: float) -> None:
    """Cut a log file short, as an interrupted transfer leaves it."""
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * fraction)])


@needs_logs
@pytest.mark.parametrize("victim", ["sebastian-2014-204-05-000.dbd",
                                    "sebastian-2014-204-05-001.ebd"])
def test_a_truncated_log_is_refused_and_nothing_is_written(capsys, tmp_path, victim):
    logs = _copy_logs(tmp_path)
    _cut(logs / victim, 0.6)
    out = tmp_path / "mine.toml"
    code = main(["calibrate", str(logs), "--cache", str(LOGS / "cac"), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 1
    assert err.count("\n") == 1 and f"{logs / victim}: truncated" in err, err
    assert not out.exists()


@needs_logs
def test_a_log_whose_time_runs_backwards_is_refused(capsys, tmp_path):
    # cut inside the last data cycle, then given the end-of-file tag back: the cut cycle
    # decodes into a time near 0, and every duration across it would be negative
    logs = _copy_logs(tmp_path)
    victim = logs / "sebastian-2014-204-05-001.dbd"
    _cut(victim, 2 / 3)
    victim.write_bytes(victim.read_bytes() + b"X")
    out = tmp_path / "mine.toml"
    code = main(["calibrate", str(logs), "--cache", str(LOGS / "cac"), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 1 and f"{victim}: its time runs backwards" in err, err
    assert not out.exists()


def test_a_calibration_that_would_not_load_leaves_the_output_alone(capsys, tmp_path,
                                                                    monkeypatch):
    from gliderplan.power_models import log_calibration

    # a pump that gives energy back: the fitted pump-out energy per cc comes out negative
    monkeypatch.setattr(sg, "PUMP_OUT_J_PER_CC", -2.0)
    monkeypatch.setattr(log_calibration, "read_flight_log", lambda *_: _synthetic_log())
    monkeypatch.setattr(log_calibration, "expand_log_paths", list)
    monkeypatch.setattr(log_calibration, "split_deployments",
                        lambda files: [Deployment(tuple(files), None)])
    out = tmp_path / "mine.toml"
    out.write_text("the pilot's earlier file\n")
    code = main(["calibrate", str(tmp_path), "-o", str(out)])
    err = capsys.readouterr().err
    assert code == 1
    assert f"{out}: not written: the calibrated pump_out_energy_per_volume must be >= 0" in err
    assert out.read_text() == "the pilot's earlier file\n"


@needs_logs
def test_calibrate_is_the_command_as_one_call(tmp_path):
    from gliderplan.power_models import calibrate

    result = calibrate([str(LOGS)], validate=True, output=tmp_path / "sebastian.toml")
    assert abs(result.relative_error) <= MAX_VALIDATION_ERROR
    # the error --max-error checks is the forward forecast's
    assert result.report["forecast"]["energy_relative_error"] == result.relative_error
    written = read_vehicle_file(tmp_path / "sebastian.toml")
    assert written.name == "sebastian"
    assert written.hotel_w == pytest.approx(result.vehicle.hotel_w, rel=1e-5)


def test_logs_without_the_coulomb_counter_are_refused_naming_what_is_missing(capsys):
    """Science logs alone hold no counter, current or depth: the calibration says which
    variables it needs and exits 1, with nothing written."""
    science = sorted(COMET.glob("*.ebd"))[:1] if COMET.is_dir() else []
    if not science:
        pytest.skip("the comet 2016 logs are not present")
    assert main(["calibrate", str(science[0])]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert "m_coulomb_amphr_total (the coulomb counter, the energy drawn)" in err
    assert "Traceback" not in err
