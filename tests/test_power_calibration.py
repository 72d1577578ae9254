"""Calibration: recovering known figures from a synthetic log, and the real glider's log.

The real-log tests read ../shared/data/slocum-logs relative to the project root (the
sebastian 2014 dive series). Where it is missing they are skipped and say so (under
CI=true a skip fails); where it is present, a replay error above 5 % fails loudly.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import synthetic_glider as sg

from gliderplan.cli.main import main
from gliderplan.power_models import calibration, load_vehicle
from gliderplan.power_models.slocum_log import FlightLog
from gliderplan.power_models.vehicle import figure_value, read_vehicle_file

LOGS = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "slocum-logs"
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


def test_a_log_at_one_depth_keeps_the_depth_term_of_the_base():
    base = load_vehicle("slocum_g3")
    fit = calibration.fit_energy(_synthetic_log(bottoms=(40.0,)), base)
    kept = {c.key: c for c in fit.coefficients}["pump_out_energy_per_volume_depth"]
    assert not kept.fitted and fit.vehicle.pump_out_j_per_cc_m == base.pump_out_j_per_cc_m


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
    # ... the one surfacing gives none
    assert "surface_time" not in vehicle.uncertainty.keys
    # light in the North Sea water its CTD measured (1023-1025 kg/m3), not 1025
    assert 1023.0 < vehicle.flight.rho_kg_m3 < 1025.0 and vehicle.flight.trim_cc > 0
    assert vehicle.hotel_includes == ("ctd", "optics")  # they logged throughout


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
    assert spread.keys() == {f["key"] for f in fitted if f["sd"] is not None}
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
