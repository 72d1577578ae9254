"""What a glider reports at a surfacing (power_models/telemetry.py), and the figures learned
from it (power_models/posterior.py): JSON and Slocum logs read alike, gaps noted, a counter
that runs backwards refused; the Kalman update finds a device that draws more than its
figure, the voltage a battery that holds less than its rating."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from gliderplan.contract import SBD_MO_SHORT_BYTES, UpdateStatus
from gliderplan.power_models import load_vehicle
from gliderplan.power_models.posterior import DischargeCurve, prior_belief
from gliderplan.power_models.telemetry import (
    SurfacingReport,
    TelemetryError,
    UpdateAck,
    check_reports,
    pack_report,
    read_telemetry,
    unpack_report,
    write_json_telemetry,
)

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
COMET = SHARED / "slocum-logs-comet-2016"
STATES = ("launch", "survey", "surface_fix")


def report(time_s: float, ah: float | None, **fields) -> SurfacingReport:
    return SurfacingReport(time_s, ah, fields.pop("battery_v", 14.9), **fields)


def write(tmp_path: Path, data: object) -> Path:
    path = tmp_path / "telemetry.json"
    path.write_text(json.dumps(data))
    return path


def test_json_telemetry_reads_back_what_was_written(tmp_path):
    reports = [report(21600, 1.5, lat=3910.5, lon=-7349.8, state="surface_fix",
                      stack=("survey",), device_on_s={"ctd": 9000.0, "dvl": 4000.0},
                      state_time_s={"launch": 600.0, "survey": 21000.0}, plan_seq=12,
                      ack=UpdateAck(UpdateStatus.APPLIED, 12, "ok: plan 12 in force"))]
    path = tmp_path / "t.json"
    path.write_text(write_json_telemetry(reports))
    (read,) = read_telemetry(path)
    assert read.to_json() == reports[0].to_json()
    assert read.energy_used_j == pytest.approx(1.5 * 3600 * 15.0)


@pytest.mark.parametrize("data, said", [
    ({"time_s": 10, "coulomb": 1}, "coulomb: unknown key"),
    ({"coulomb_amphr_total": 1}, "time_s: every report says when it was taken"),
    ({"time_s": "noon"}, "time_s: expected a finite number"),
    ({"time_s": 10, "device_on_s": {"sonar": 5}}, "'sonar' is not one of ctd"),
    ({"time_s": 10, "ack": {"status": "maybe", "seq": 1}}, "ack: expected"),
    ({"time_s": 10, "battery_v": -1}, "battery_v: -1 is below 0"),
])
def test_a_bad_report_is_one_clear_error_naming_the_key(tmp_path, data, said):
    with pytest.raises(TelemetryError, match=said):
        read_telemetry(write(tmp_path, [data]))


def test_gaps_are_noted_and_the_interval_spans_them():
    reports = [report(21600, 1.0), report(43200, None), report(64800, 3.1)]
    notes = check_reports(reports, STATES)
    assert any("no coulomb counter reading (a gap)" in n for n in notes)
    assert any("43200 s since the last report with a counter reading" in n for n in notes)


@pytest.mark.parametrize("reports, said", [
    ([report(21600, 2.0), report(43200, 1.5)],
     "the coulomb counter runs backwards: 1.5 Ah at 43200 s after 2 Ah at 21600 s"),
    ([report(43200, 1.0), report(21600, 2.0)], "reports out of order"),
    ([report(21600, 1.0, state="spiral")], "state 'spiral': the mission has no such state"),
    ([report(21600, None)], "no report has a coulomb counter reading"),
    ([], "no surfacing report"),
    ([report(100, 1.0, device_on_s={"ctd": 50}), report(200, 1.1, device_on_s={"ctd": 40})],
     "device_on_s.ctd runs backwards"),
])
def test_telemetry_no_replan_can_rest_on_is_refused(reports, said):
    with pytest.raises(TelemetryError, match=said):
        check_reports(reports, STATES)


def test_the_binary_report_fits_one_short_message_and_reads_back():
    sent = report(2_592_000, 123.456, lat=3910.5, lon=-7349.8125, state="survey",
                  stack=("survey",), device_on_s={"ctd": 1e6, "optode": 2e6, "dvl": 5e5},
                  state_time_s={s: 86400.0 for s in STATES}, plan_seq=1_700_000_123,
                  ack=UpdateAck(UpdateStatus.STALE, 1_700_000_120))
    data = pack_report(sent, STATES)
    assert len(data) <= SBD_MO_SHORT_BYTES
    back = unpack_report(data, STATES)
    assert (back.time_s, back.coulomb_amphr_total, back.battery_v, back.state, back.stack,
            back.plan_seq) == (2_592_000, 123.456, 14.9, "survey", ("survey",), 1_700_000_123)
    assert back.lat == pytest.approx(3910.5) and back.lon == pytest.approx(-7349.8125)
    assert back.device_on_s == sent.device_on_s and back.state_time_s == sent.state_time_s
    assert back.ack == UpdateAck(UpdateStatus.STALE, 1_700_000_120)
    many = tuple(f"s{i}" for i in range(64))
    with pytest.raises(TelemetryError, match="more than the 340 of one short message up"):
        pack_report(report(10, 1.0, state_time_s={s: 1.0 for s in many}), many)
    with pytest.raises(TelemetryError, match="cut short"):
        unpack_report(data[:-3], STATES)


@pytest.mark.skipif(not COMET.is_dir() and os.environ.get("CI") != "true",
                    reason=f"the shared Slocum logs are missing: {COMET}")
def test_slocum_segments_are_reports_of_the_surfacings_that_end_them():
    reports = read_telemetry([str(COMET)])
    assert len(reports) == 10  # ten segments
    assert check_reports(reports) == []
    times = [r.time_s for r in reports]
    assert times == sorted(times) and times[-1] == pytest.approx(14866, abs=5)
    charge = [r.coulomb_amphr_total for r in reports]
    assert charge == sorted(charge) and 1.5 < charge[-1] < 4.0  # 4.1 h at ~5 W: ~1.4 Ah
    last = reports[-1].device_on_s
    assert set(last) >= {"ctd", "dvl", "logger", "optics"} and last["dvl"] < times[-1]
    assert 5440 < reports[0].lat < 5450  # DDMM.MMMM, off Bornholm
    assert all(13.5 < r.battery_v < 14.5 for r in reports)


def test_the_kalman_update_finds_a_device_hungrier_than_its_figure():
    """A month of intervals whose DVL on-time varies: the measured energy says the DVL
    draws 30 % more; the posterior says so (the prior's pull left in it), and is surer
    than the prior."""
    vehicle = load_vehicle("slocum_g2_shallow")
    belief = prior_belief(vehicle, {"ctd": 0.24, "dvl": 1.3}, (0.97, 0.03))
    rng = np.random.default_rng(1)
    for _ in range(120):
        expected = {"hotel": 1.3 * 21600, "pump": 0.9 * 21600, "surface": 3.9 * 900,
                    "iridium": 5.2 * 205, "ctd": 0.24 * 21600 * rng.uniform(0.25, 1),
                    "dvl": 1.3 * 21600 * rng.uniform(0.0, 1.0)}
        truth = sum(expected.values()) + 0.3 * expected["dvl"]
        belief = belief.observe(expected, truth * rng.normal(1.0, 0.005))
    moved = {m.name: m for m in belief.moves()}
    assert moved["dvl"].posterior == pytest.approx(1.3, abs=0.04)
    assert moved["dvl"].sd < 0.5 * 0.1  # the prior's 10 %, halved at least
    assert abs(moved["hotel"].change) < 0.05


def test_the_voltage_tells_a_weaker_battery_once_enough_is_drawn():
    """A pack that holds 85 % of its rating: a few readings near full tell nothing; readings
    over half the pack tell it, whatever the full pack's voltage."""
    vehicle = load_vehicle("slocum_g2_shallow")
    belief = prior_belief(vehicle, {}, (0.97, 0.03))
    curve = DischargeCurve.nominal(15.0)
    budget, rng = 1e7, np.random.default_rng(2)

    def read(belief, drawn):
        volts = curve.voltage(drawn / 0.85) - 0.3 + rng.normal(0.0, curve.noise_v)
        return belief.observe_battery(drawn * budget, volts, budget, curve)

    early = belief
    for drawn in (0.002, 0.004, 0.006, 0.008):
        early = read(early, drawn)
    assert (early.usable_mean, early.usable_sd) == (0.97, 0.03)  # too little drawn to tell
    late = early
    for drawn in np.linspace(0.05, 0.6, 12):
        late = read(late, drawn)
    assert late.usable_mean == pytest.approx(0.85, abs=0.02) and late.usable_sd < 0.015
