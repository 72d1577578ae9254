"""Boards, sensors, batteries and the preset catalog, as the planner and checker use them."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from gliderplan.power_models import load_battery, load_board, load_sensor
from gliderplan.power_models.battery import energy_to_j, j_to_ah, j_to_wh
from gliderplan.power_models.catalog import preset_names
from gliderplan.power_models.errors import ModelFileError


def test_catalog_lists_the_presets_the_language_names():
    assert preset_names("board") == ["ts5500", "ts7800"]
    assert {"slocum_g2_shallow", "slocum_g3"} <= set(preset_names("vehicle"))
    assert {"ctd", "optode", "optics", "adcp", "dvl", "logger", "modem"} <= set(
        preset_names("sensor"))
    assert {"alkaline", "lithium_primary", "rechargeable"} <= set(preset_names("battery"))
    with pytest.raises(ValueError, match="unknown model kind"):
        preset_names("boat")


def test_catalog_does_not_import_numpy():
    code = (
        "import sys; from gliderplan.power_models.catalog import preset_names; "
        "preset_names('vehicle'); print('numpy' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize(
    ("spec", "clock", "active_w"),
    [
        ("ts5500", None, 2.7),
        ("ts7800", 300, 3.42),
        ("ts7800@500", None, 4.14),
        ("ts7800 @ 500 MHz", None, 4.14),
        ("ts7800", 500, 4.14),
        ("ts7800@500", 300, 3.42),
    ],
)
def test_board_powers_are_table_one_exactly(spec, clock, active_w):
    assert load_board(spec, clock).active_w == active_w


def test_board_modes_cover_every_clock():
    assert [(b.clock_mhz, b.active_w) for b in load_board("ts7800").modes()] == [
        (300.0, 3.42),
        (500.0, 4.14),
    ]
    assert [b.clock_mhz for b in load_board("ts5500").modes()] == [133.0]


def test_board_without_that_clock_is_refused():
    with pytest.raises(ModelFileError, match="no 400 MHz clock"):
        load_board("ts7800@400")
    with pytest.raises(ModelFileError, match="did you mean 'ts7800'"):
        load_board("ts7880")
    with pytest.raises(ModelFileError, match="expected NAME"):
        load_board("ts7800@5.0.0")


def test_workload_becomes_busy_time_and_power():
    board = load_board("ts7800@300")
    busy = board.busy_fraction(np.array([0.0, 1.5e6, 3e6]), 100.0)  # cycles/tick x ticks/s
    assert busy == pytest.approx([0.0, 0.5, 1.0])
    power = board.power_w(busy)
    assert power[0] == board.idle_w and power[-1] == board.active_w
    assert power[1] == pytest.approx((board.idle_w + board.active_w) / 2)
    # the faster clock finishes the same work sooner
    assert load_board("ts7800@500").busy_fraction(1.5e6, 100.0) < busy[1]


def test_a_tick_is_active_for_its_work_then_idles_or_sleeps():
    board = load_board("ts7800@300")
    busy_s = 3e8 / 300e6  # 1 s of work in a 4 s tick
    idle = board.tick_energy(3e8, 4.0)
    assert float(idle.active_j) == pytest.approx(3.42 * busy_s)
    assert float(idle.idle_j) == pytest.approx(2.57 * 3.0)
    assert float(idle.sleep_j) == 0.0 and float(idle.wake_j) == 0.0
    asleep = board.tick_energy(3e8, 4.0, sleep=True)
    assert float(asleep.idle_j) == 0.0
    assert float(asleep.sleep_j) == pytest.approx(0.8 * (3.0 - 0.3))  # wake latency 0.3 s
    assert float(asleep.wake_j) == pytest.approx(1.03)
    assert float(asleep.total_j) < float(idle.total_j)
    assert board.mean_power_w(3e8, 4.0) == pytest.approx(float(idle.total_j) / 4.0)
    # the faster clock wakes at its own cost
    assert float(load_board("ts7800@500").tick_energy(3e8, 4.0, True).wake_j) == 1.24


def test_a_board_sleeps_only_where_it_can():
    assert load_board("ts5500").sleep is None
    ts5500 = load_board("ts5500")
    assert float(ts5500.tick_energy(1e6, 4.0, sleep=True).total_j) == pytest.approx(
        float(ts5500.tick_energy(1e6, 4.0).total_j))
    board = load_board("ts7800@300")
    no_room = 3.9 * 300e6  # 3.9 s of work: no time left for a 0.3 s wake-up
    assert not board.can_sleep(no_room, 4.0)
    assert float(board.tick_energy(no_room, 4.0, sleep=True).sleep_j) == 0.0
    too_much = board.tick_energy(5 * 300e6, 4.0)  # 5 s of work every 4 s
    assert np.isnan(float(too_much.total_j))


def test_boot_energy_follows_the_clock():
    slow, fast = load_board("ts7800").modes()
    assert fast.boot_j / slow.boot_j == pytest.approx(4.14 / 3.42)


@pytest.mark.parametrize("name", ["ctd", "optode", "optics", "adcp", "dvl", "logger", "modem"])
def test_sensor_quality_is_concave_from_zero_to_one(name):
    sensor = load_sensor(name)
    duty = np.linspace(0.0, 1.0, 101)
    quality = sensor.utility(duty)
    assert quality[0] == 0.0 and quality[-1] == pytest.approx(1.0)
    assert np.all(np.diff(quality) > 0)
    assert np.all(np.diff(quality, 2) <= 1e-12)  # diminishing returns


def test_ctd_is_the_sea_bird_figure():
    ctd = load_sensor("ctd")
    assert ctd.on_power_w == pytest.approx(0.24) and ctd.sample_hz == 0.5


def test_every_device_a_slocum_instrument_is_has_a_preset_and_a_sensor():
    from gliderplan.contract import SENSORS
    from gliderplan.power_models.slocum_instruments import devices

    logged = {s.device for s in SENSORS if s.device is not None}
    for device in devices():
        assert device in preset_names("sensor"), device
        assert device in logged, f"no sensor of the language is the {device}"
    assert load_sensor("dvl").on_power_w == pytest.approx(1.3)  # Nortek 1 MHz (DUNE)
    assert load_sensor("logger").on_power_w == pytest.approx(1.5)  # the stated assumption


@pytest.mark.parametrize("name", preset_names("sensor"))
def test_every_sensor_preset_gives_the_published_span_of_its_class(name):
    sensor = load_sensor(name)
    assert sensor.power_range_w is not None, f"{name}: no power_range"
    low, high = sensor.power_range_w
    assert 0.0 < low <= sensor.on_power_w <= high  # its own figure is one of the span


def test_cycling_a_sensor_costs_its_warm_up():
    optode = load_sensor("optode")
    always = optode.mean_power_w(np.array([0.0, 1.0]), 60.0)
    assert always.tolist() == pytest.approx([0.0, optode.on_power_w])
    half = optode.mean_power_w(0.5, 60.0)
    assert half == pytest.approx(0.5 * optode.on_power_w + optode.warmup_j / 60.0)


def test_battery_presets_and_conversions():
    alkaline = load_battery("alkaline")
    assert alkaline.energy_j == pytest.approx(7.8e6)
    assert 0 < alkaline.usable_fraction <= 1
    assert load_battery("lithium_primary").energy_wh == pytest.approx(3381)
    assert energy_to_j(1.0, "Wh") == 3600.0 and energy_to_j(7.8, "MJ") == 7.8e6
    assert j_to_wh(3600.0) == 1.0 and j_to_ah(energy_to_j(10.0, "Ah", 14.0), 14.0) == 10.0
    assert energy_to_j(1.2, "kWh") == pytest.approx(4.32e6)
    assert energy_to_j(100, "Ah", 15.0) == pytest.approx(5.4e6)
    with pytest.raises(ValueError, match="needs a positive voltage"):
        energy_to_j(100, "Ah")
    with pytest.raises(ValueError, match="not an energy or a charge"):
        energy_to_j(1.0, "W")


def test_timeline_energy_adds_up_every_component():
    from gliderplan.power_models import load_vehicle
    from gliderplan.power_models.segments import GLIDE, IRIDIUM, SURFACE
    from gliderplan.power_models.timeline import Timeline, energy_per_step_j

    vehicle, board = load_vehicle("slocum_g3"), load_board("ts7800@500")
    ctd = load_sensor("ctd")
    n = 6
    timeline = Timeline(
        dt_s=2.0,
        phase=np.array([SURFACE, IRIDIUM, GLIDE, GLIDE, GLIDE, GLIDE], np.int8),
        depth_m=np.array([0, 0, 10, 50, 50, 20.0]),
        pumped_out_cc=np.array([0, 0, 0, 400, 0, 0.0]),
        pumped_in_cc=np.array([0, 0, 400, 0, 0, 0.0]),
        inflection=np.array([0, 0, 1, 1, 0, 0], bool),
        board_busy=np.array([0, 0, 0, 1, 1, 0.5]),
        sensor_on=np.array([[0, 1, 1, 0, 1, 1]], bool),
    )
    energy = energy_per_step_j(timeline, vehicle, board, [ctd])
    assert energy.shape == (n,)
    expected_total = (
        2.0 * (vehicle.surface_w + vehicle.iridium_w + 4 * vehicle.hotel_w)
        + 2.0 * (3 * board.idle_w + 2 * board.active_w + 0.5 * (board.idle_w + board.active_w))
        + float(vehicle.pump_energy_j(50.0, 400.0))
        + float(vehicle.pump_in_energy_j(10.0, 400.0))
        + 2 * vehicle.pitch_energy_j
        + 4 * 2.0 * ctd.on_power_w
        + 2 * ctd.warmup_j  # on four steps, switched on twice
    )
    assert energy.sum() == pytest.approx(expected_total)
