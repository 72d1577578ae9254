"""The sensitivity tornado: each figure moved by its stated uncertainty (or 20 %), the plan
made again at the same budget, the figure that matters most first."""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import pytest

from gliderplan.language import check_source
from gliderplan.planner.hardware import load_hardware
from gliderplan.planner.plan import plan_mission, prepare
from gliderplan.planner.sensitivity import sensitivity
from gliderplan.power_models.catalog import preset_path
from gliderplan.power_models.vehicle import with_figures

MISSION = """mission tornado
vehicle "{vehicle}"
computer ts7800 @ 300 MHz
battery {battery} Wh reserve 0 %
sensor temp weight 1
state survey
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, depth, temp duty auto
  events
    case missiontime >= 36000 exit
end
"""


def mission_with(tmp_path: Path, battery: float, hotel_sd: float | None = None):
    """The preset glider (its hotel load's sd `hotel_sd` [W] instead of the calibrated one)
    flying a 10 h survey on a `battery` [Wh]."""
    text = preset_path("vehicle", "slocum_g2_shallow").read_text()
    if hotel_sd is not None:
        text, found = re.subn(r"^(hotel_power = \{.*sd = )[-+.e0-9]+", rf"\g<1>{hotel_sd}", text,
                              count=1, flags=re.MULTILINE)
        assert found, "the preset's hotel_power carries no sd"
    vehicle = tmp_path / "glider.toml"
    vehicle.write_text(text)
    source = MISSION.format(vehicle=vehicle, battery=battery)
    return check_source(source, "tornado.mission").checked()


def test_a_stated_uncertainty_is_used_and_the_biggest_effect_comes_first(tmp_path):
    mission = mission_with(tmp_path, 1000.0, hotel_sd=0.8)
    _, model = prepare(mission, load_hardware(mission))
    tornado = sensitivity(model)
    swings = {s.figure: s for s in tornado.swings}
    hotel = swings["vehicle hotel_power"]
    assert hotel.step == pytest.approx(0.8) and hotel.basis.startswith("1 sd")
    # the pump's rate is fitted to its readings, with a bootstrap sd; the board's idle
    # power has none stated
    assert swings["vehicle pump_rate"].basis.startswith("1 sd")
    assert swings["board ts7800 idle_power"].basis.startswith("20 %")
    # +-0.8 W of hotel load moves more than the computer idle power +-20 % (0.51 W)
    assert tornado.swings[0].figure == "vehicle hotel_power"
    # the swing is the plan made again with the figure moved, nothing else
    hardware = load_hardware(mission)
    low = plan_mission(mission, replace(hardware, vehicle=with_figures(
        hardware.vehicle, {"hotel_power": hardware.vehicle.hotel_w - 0.8})))
    assert hotel.energy_j[0] == pytest.approx(low.plan.predicted_j, rel=1e-6)
    assert hotel.energy_j[0] < tornado.energy_j < hotel.energy_j[1]


def test_a_figure_the_budget_cannot_buy_shows_as_no_quality(tmp_path):
    mission = mission_with(tmp_path, 1000.0, hotel_sd=0.8)
    least = plan_mission(mission).minimum_energy_j
    tight = mission_with(tmp_path, 1.02 * least / 3600, hotel_sd=0.8)  # 2 % above the least
    _, model = prepare(tight, load_hardware(tight))
    hotel = {s.figure: s for s in sensitivity(model).swings}["vehicle hotel_power"]
    assert math.isnan(hotel.quality[1])  # 0.8 W more hotel load: over the budget
    assert hotel.energy_j[1] > tight.battery.energy_j
    assert not math.isnan(hotel.quality[0])


def test_each_figure_says_what_it_rests_on_and_sleep_figures_move_where_a_state_sleeps(
        tmp_path):
    awake = mission_with(tmp_path, 1000.0)
    asleep = check_source(MISSION.format(vehicle=tmp_path / "glider.toml", battery=1000.0)
                          .replace("  sensors", "  computer sleep between ticks\n  sensors"),
                          "tornado.mission").checked()
    tornadoes = {}
    for name, mission in (("awake", awake), ("asleep", asleep)):
        _, model = prepare(mission, load_hardware(mission))
        tornadoes[name] = {s.figure: s for s in sensitivity(model).swings}
    awake, asleep = tornadoes["awake"], tornadoes["asleep"]
    # the sources are the data files' own words
    hotel = awake["vehicle hotel_power"]
    assert hotel.source.startswith("gliderplan calibrate on the sebastian 2014 log")
    assert not hotel.assumed
    idle = awake["board ts7800 idle_power"]
    assert idle.assumed and "75 % of active" in idle.source
    assert not awake["board ts7800 active_power"].assumed  # Table I of the paper
    assert awake["board ts7800 active_power"].source == "Woithe & Kremer, Table I"
    assert awake["runtime workload per tick"].assumed
    # a board that idles between ticks has no sleep figure to move; one that sleeps has
    assert not [f for f in awake if "sleep_power" in f]
    assert not [f for f in awake if "wake_energy" in f]
    sleep = asleep["board ts7800 sleep_power"]
    assert sleep.assumed and sleep.value == pytest.approx(0.8)
    assert sleep.energy_j[0] < sleep.energy_j[1]  # a hungrier sleep costs more
    # the swing is the plan of a board whose data file says 0.96 W asleep
    board = tmp_path / "hungry.toml"
    board.write_text(preset_path("board", "ts7800").read_text().replace(
        "power = { value = 0.8,", "power = { value = 0.96,"))
    hungry = check_source(MISSION.format(vehicle=tmp_path / "glider.toml", battery=1000.0)
                          .replace("computer ts7800", f'computer "{board}"')
                          .replace("  sensors", "  computer sleep between ticks\n  sensors"),
                          "tornado.mission").checked()
    assert sleep.energy_j[1] == pytest.approx(plan_mission(hungry).plan.predicted_j, rel=1e-6)
    wake = asleep["board ts7800 wake_energy"]
    assert wake.assumed and wake.energy_j[0] < wake.energy_j[1]
    # asleep, the idle power moves nothing the board draws between ticks
    assert asleep["board ts7800 idle_power"].energy_j[1] - \
        asleep["board ts7800 idle_power"].energy_j[0] < \
        awake["board ts7800 idle_power"].energy_j[1] - awake["board ts7800 idle_power"].energy_j[0]


def test_every_figure_carries_its_unit(tmp_path):
    # the calibrated figures too (turn times, pitch errors, trim, compressibility, density),
    # in the unit the model holds them in, as the vehicle file writes it
    mission = mission_with(tmp_path, 1000.0)
    _, model = prepare(mission, load_hardware(mission))
    units = {s.figure: s.unit for s in sensitivity(model).swings}
    assert all(units.values()), [f for f, u in units.items() if not u]
    assert units["vehicle bottom_turn_time"] == "s"
    assert units["vehicle dive_pitch_error"] == "rad"
    assert units["vehicle flight.trim_volume"] == "cc"
    assert units["vehicle flight.compressibility"] == "1/Pa"
    assert units["vehicle flight.water_density"] == "kg/m3"
    assert units["vehicle hotel_power"] == "W" and units["vehicle pump_rate"] == "cc/s"
