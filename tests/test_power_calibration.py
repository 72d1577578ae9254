"""Calibration: recovering known figures from a synthetic log, and the real glider's log.

The real-log tests read ../shared/data/slocum-logs relative to the project root (the
sebastian 2014 dive series). Where it is missing they are skipped and say so; where it is
present, a validation error above 5 % fails loudly.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from gliderplan.cli.main import main
from gliderplan.power_models import calibration, load_vehicle
from gliderplan.power_models.slocum_log import FlightLog
from gliderplan.power_models.vehicle import read_vehicle_file

LOGS = Path(__file__).resolve().parent.parent.parent / "shared" / "data" / "slocum-logs"
needs_logs = pytest.mark.skipif(
    not LOGS.is_dir(),
    reason="real Slocum logs not found at ../shared/data/slocum-logs (relative to the project "
    "root): the calibration check against real data did NOT run",
)
MAX_VALIDATION_ERROR = 0.05

# ---- a synthetic glider whose figures are known ------------------------------------
HOTEL_W, SURFACE_W, IRIDIUM_W, VOLTS = 2.0, 4.0, 5.5, 14.0
PUMP_OUT_J_PER_CC, PUMP_OUT_J_PER_CC_M, PUMP_IN_J_PER_CC = 0.3, 0.012, 0.2
DT_S, PUMP_S = 2.0, 14.0


def _synthetic_log(cycles: int = 6, bottoms=(20.0, 40.0, 60.0)) -> FlightLog:
    """Surface, then yo cycles with pump runs at varying depths, then an Iridium call."""
    rows = []  # (duration s, depth start, depth end, ballast end, power W, flags)

    def add(duration, z0, z1, ballast, power, pump=False, iridium=False):
        rows.append((duration, z0, z1, ballast, power, pump, iridium))

    add(100, 0, 0, 230, SURFACE_W)
    for k in range(cycles):
        bottom = bottoms[k % len(bottoms)]
        add(PUMP_S, 1.5, 1.5, -230, HOTEL_W + PUMP_IN_J_PER_CC * 460 / PUMP_S, pump=True)
        add(bottom / 0.12, 1.5, bottom, -230, HOTEL_W)
        pump_out = (PUMP_OUT_J_PER_CC + PUMP_OUT_J_PER_CC_M * bottom) * 460
        add(PUMP_S, bottom, bottom, 230, HOTEL_W + pump_out / PUMP_S, pump=True)
        add(bottom / 0.18, bottom, 1.5, 230, HOTEL_W)
    add(120, 0, 0, 230, SURFACE_W)
    add(300, 0, 0, 230, IRIDIUM_W, iridium=True)

    t, depth, ballast, power, pump, iridium = [], [], [], [], [], []
    now, last_ballast = 0.0, 230.0
    for duration, z0, z1, ballast_end, watts, pumping, calling in rows:
        steps = int(round(duration / DT_S))
        for i in range(steps):
            frac = (i + 1) / steps
            t.append(now + (i + 1) * DT_S)
            depth.append(z0 + (z1 - z0) * frac)
            ballast.append(last_ballast + (ballast_end - last_ballast) * frac)
            power.append(watts)
            pump.append(pumping)
            iridium.append(calling)
        now += steps * DT_S
        last_ballast = ballast_end
    t = np.array([0.0, *t])
    power = np.array([SURFACE_W, *power])
    # power is constant over each interval ending at a sample: the counter sees exactly it
    charge = np.concatenate(([0.0], np.cumsum(power[1:] * np.diff(t)) / VOLTS / 3600.0))
    n = t.size
    return FlightLog(
        files=("synthetic",),
        start_epoch_s=0.0,
        t_s=t,
        depth_m=np.array([0.0, *depth]),
        pitch_rad=np.full(n, 0.4),
        ballast_cc=np.array([230.0, *ballast]),
        current_a=power / VOLTS,
        charge_ah=charge,
        battery_v=np.full(n, VOLTS),
        iridium_on=np.array([False, *iridium]),
        pump_moving=np.array([False, *pump]),
        battpos_moving=np.zeros(n, bool),
    )


def test_fit_recovers_a_known_glider():
    fit = calibration.fit_energy(_synthetic_log(), load_vehicle("slocum_g3"))
    vehicle = fit.vehicle
    assert vehicle.hotel_w == pytest.approx(HOTEL_W, rel=0.02)
    assert vehicle.surface_w == pytest.approx(SURFACE_W, rel=0.02)
    assert vehicle.iridium_w == pytest.approx(IRIDIUM_W, rel=0.02)
    assert vehicle.pump_energy_j(40.0, 460.0) == pytest.approx(
        (PUMP_OUT_J_PER_CC + PUMP_OUT_J_PER_CC_M * 40) * 460, rel=0.05
    )
    assert vehicle.pump_out_j_per_cc_m == pytest.approx(PUMP_OUT_J_PER_CC_M, rel=0.1)
    assert vehicle.pump_in_j_per_cc == pytest.approx(PUMP_IN_J_PER_CC, rel=0.1)
    assert all(c.fitted for c in fit.coefficients)


def test_a_log_at_one_depth_keeps_the_depth_term_of_the_base():
    base = load_vehicle("slocum_g3")
    fit = calibration.fit_energy(_synthetic_log(bottoms=(40.0,)), base)
    kept = {c.key: c for c in fit.coefficients}["pump_out_energy_per_volume_depth"]
    assert not kept.fitted and fit.vehicle.pump_out_j_per_cc_m == base.pump_out_j_per_cc_m


def test_validation_on_the_synthetic_glider_is_nearly_exact():
    result = calibration.validate(_synthetic_log(cycles=8), load_vehicle("slocum_g3"))
    assert abs(result.relative_error) < 0.01
    assert result.measured_j > 0


# ---- the real glider ----------------------------------------------------------------
def _calibrate(capsys, *extra):
    code = main(["calibrate", str(LOGS), "--cache", str(LOGS / "cac"), "--json", *extra])
    out = capsys.readouterr().out
    return code, (json.loads(out) if out.strip() else None)


@needs_logs
def test_real_log_validation_error_is_within_five_percent(capsys):
    code, report = _calibrate(capsys, "--validate")
    assert code == 0
    error = report["relative_error"]
    val = report["validation"]
    assert abs(error) <= MAX_VALIDATION_ERROR, (
        f"calibration validation error {error:+.2%} exceeds {MAX_VALIDATION_ERROR:.0%}: "
        f"predicted {val['predicted_j']:.0f} J vs coulomb counter {val['measured_j']:.0f} J "
        f"({val['split']})"
    )
    # fitted and held-out parts are different stretches of the record
    assert 0.2 * report["duration_s"] < val["duration_s"] < 0.8 * report["duration_s"]
    assert val["predicted_by_component_j"]["pump"] > 0 and val["measured_j"] > 1000


@needs_logs
def test_real_log_flight_model_vertical_speeds(capsys):
    _, report = _calibrate(capsys, "--validate")
    speeds = {s["direction"]: s for s in report["vertical_speed"]}
    assert set(speeds) == {"dive", "climb"}
    log_mean = (speeds["dive"]["log_w_mps"] + speeds["climb"]["log_w_mps"]) / 2
    model_mean = (speeds["dive"]["model_w_mps"] + speeds["climb"]["model_w_mps"]) / 2
    # The symmetric model cannot see the glider's trim (it dives slower than it climbs),
    # but its mean vertical speed must match the log's.
    assert model_mean == pytest.approx(log_mean, rel=0.10)
    # With the trim fitted on the other part of the record, each direction must match.
    assert report["trim_offset_cc"] > 0  # light: climbs faster than it dives
    for row in report["vertical_speed_trimmed"]:
        assert row["model_w_mps"] == pytest.approx(row["log_w_mps"], rel=0.10), row["direction"]


@needs_logs
def test_real_log_writes_a_loadable_vehicle_matching_the_preset(capsys, tmp_path):
    out = tmp_path / "sebastian.toml"
    code, report = _calibrate(capsys, "-o", str(out))
    assert code == 0 and report["output"] == str(out)
    vehicle = read_vehicle_file(out)
    assert vehicle.name == "sebastian"
    preset = load_vehicle("slocum_g2_shallow")  # its figures say they come from this log
    assert vehicle.hotel_w == pytest.approx(preset.hotel_w, rel=0.01)
    assert vehicle.pump_in_j_per_cc == pytest.approx(preset.pump_in_j_per_cc, rel=0.01)
    assert "gliderplan calibrate" in out.read_text()


@needs_logs
def test_max_error_turns_a_poor_fit_into_a_failure(capsys):
    assert main(["calibrate", str(LOGS), "--validate", "--max-error", "0.00001"]) == 1
    assert "exceeds --max-error" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "code", "message"),
    [
        (["calibrate", "nowhere.dbd"], 2, "nowhere.dbd: no such file"),
        (["calibrate", ".", "--max-error", "0.05"], 2, "--max-error needs --validate"),
        (["calibrate", ".", "-o", "out.txt"], 2, "must end in .toml"),
        (["calibrate", ".", "--base", "slocum_g9"], 2, "unknown vehicle preset"),
    ],
)
def test_calibrate_bad_input(capsys, argv, code, message):
    assert main(argv) == code
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_calibrate_rejects_a_file_that_is_not_a_log(capsys, tmp_path):
    bogus = tmp_path / "x.dbd"
    bogus.write_bytes(b"not a log")
    assert main(["calibrate", str(bogus)]) == 1
    assert "cannot read the logs" in capsys.readouterr().err


@needs_logs
def test_calibrate_is_the_command_as_one_call(tmp_path):
    from gliderplan.power_models import calibrate

    result = calibrate([str(LOGS)], validate=True, output=tmp_path / "sebastian.toml")
    assert abs(result.relative_error) <= MAX_VALIDATION_ERROR
    assert result.report["validation"]["relative_error"] == result.relative_error
    written = read_vehicle_file(tmp_path / "sebastian.toml")
    assert written.name == "sebastian"
    assert written.hotel_w == pytest.approx(result.vehicle.hotel_w, rel=1e-5)
