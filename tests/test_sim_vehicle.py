"""The simulated glider: glide speeds of the flight model, inflections at the pump rate,
surfacing with GPS fix and Iridium call, hovering, dead reckoning against a current."""

from __future__ import annotations

import dataclasses
import math

import pytest

from gliderplan.power_models import load_vehicle
from gliderplan.power_models.flight import glide, net_buoyancy_cc
from gliderplan.power_models.segments import GLIDE, IRIDIUM, PUMP, SURFACE
from gliderplan.sim.geo import offset_m
from gliderplan.sim.vehicle import Current, GliderSim

VEHICLE = load_vehicle("slocum_g2_shallow").neutral()  # speeds: `glide` at the pumped volume
PITCH, BALLAST = 0.454, 233.0


def glider(tick_s: float = 1.0, current: Current | None = None, depth_m: float = 0.0):
    return GliderSim(VEHICLE, tick_s, 39.0, -73.0, current or Current(), depth_m)


def test_a_dive_sinks_at_the_flight_model_s_vertical_speed_after_pumping():
    g = glider(depth_m=5.0)
    pumping_s = 0
    while True:
        g.step(30.0, -PITCH, -BALLAST, 0.0, True, False)
        if g.phase != PUMP:
            break
        pumping_s += 1
    # 233 cc from neutral at 32 cc/s: 7.3 s of pumping (8 ticks), standing still meanwhile
    assert pumping_s == math.ceil(BALLAST / VEHICLE.pump_rate_cc_s)
    start = g.depth_m
    for _ in range(100):
        g.step(30.0, -PITCH, -BALLAST, 0.0, True, False)
    u, w = VEHICLE.glide(PITCH, BALLAST)
    assert (g.depth_m - start) / 100 == pytest.approx(float(w))
    assert g.pitch_rad == pytest.approx(-PITCH)


def test_an_inflection_pumps_twice_the_volume_and_counts_once():
    g = glider(depth_m=20.0)
    for _ in range(30):
        g.step(30.0, -PITCH, -BALLAST, 0.0, True, False)
    pumped_out, inflections = 0.0, 0
    for _ in range(30):  # turn: dive -> climb
        g.step(3.0, PITCH, BALLAST, 0.0, True, False)
        pumped_out += g.pumped_out_cc
        inflections += g.inflection
    assert pumped_out == pytest.approx(2 * BALLAST)
    assert inflections == 1


def test_surfacing_takes_a_fix_then_makes_the_iridium_call():
    g = glider(tick_s=10.0, depth_m=2.0)
    phases = []
    for _ in range(60):
        g.step(0.0, PITCH, BALLAST, 0.0, False, True)
        phases.append(g.phase)
    at_surface = [p for p in phases if p in (SURFACE, IRIDIUM)]
    assert g.surfacings == 1 and g.depth_m == 0.0
    fix, call = VEHICLE.surface_s, VEHICLE.iridium_s  # ticks that start in the call:
    assert at_surface.count(IRIDIUM) == sum(fix <= 10 * k < fix + call for k in range(60))
    first_call = at_surface.index(IRIDIUM)
    assert first_call == math.ceil(fix / 10.0)  # the GPS fix comes first
    assert all(p == SURFACE for p in at_surface[first_call + at_surface.count(IRIDIUM):])


def test_hover_moves_slowly_toward_its_depth():
    g = glider(depth_m=10.0)
    for _ in range(40):
        g.step(12.0, 0.0, 0.0, 0.0, False, False)
    assert g.depth_m == pytest.approx(12.0)
    assert g.phase == GLIDE


def test_a_current_carries_the_glider_away_from_its_dead_reckoning_until_a_fix():
    g = glider(tick_s=4.0, current=Current(north_mps=0.0, east_mps=0.1), depth_m=5.0)
    for _ in range(900):  # one hour heading north at depth
        g.step(30.0 if g.depth_m < 29 else 3.0, -PITCH, -BALLAST, 0.0, True, False)
    north, east = offset_m(g.dr_lat_deg, g.dr_lon_deg, g.lat_deg, g.lon_deg)
    assert east == pytest.approx(360.0, rel=0.01) and abs(north) < 1.0
    while g.phase != IRIDIUM:  # surface: the GPS fix puts the dead reckoning right
        g.step(0.0, PITCH, BALLAST, 0.0, False, True)
    north, east = offset_m(g.dr_lat_deg, g.dr_lon_deg, g.lat_deg, g.lon_deg)
    assert abs(east) <= 2 * 0.1 * 4.0 + 1e-6  # drift of the fix tick and the first call tick
    assert g.surfacings == 1


def test_the_ctd_lags_the_water_and_a_powered_off_ctd_is_not_sent():
    from gliderplan.contract import FLIGHT_SENSORS_MASK, RUNTIME_READINGS_MASK
    from gliderplan.sim import ocean
    from gliderplan.sim.science import ScienceComputer, SensorNoise

    g = glider(tick_s=4.0)
    science = ScienceComputer(g, ocean.bench(), SensorNoise(temperature_lag_s=8.0), 0, 4.0)
    mask, values = science.readings(0)
    # nothing powered before the first COMMAND; the runtime's own readings never sent
    assert mask == FLIGHT_SENSORS_MASK & ~RUNTIME_READINGS_MASK
    assert values[9] == pytest.approx(24.0, abs=0.01)
    g.depth_m = 40.0  # into 7 C water: the reading follows with an 8 s time constant
    science.apply(40.0, -PITCH, -BALLAST, 0.0, 0, 1 << 9)
    mask, values = science.readings(1)
    assert mask & (1 << 9) and mask & (1 << 11)  # the CTD's temperature and salinity
    assert values[9] == pytest.approx(7.0 + 17.0 * math.exp(-0.5), abs=0.02)


def test_a_trimmed_glider_dives_at_its_net_buoyancy_and_turns_for_its_turn_time():
    flight = dataclasses.replace(VEHICLE.flight, hull_volume_cc=60_000.0, trim_cc=60.0,
                                 compressibility_per_pa=5e-10)
    turning = dataclasses.replace(VEHICLE, flight=flight, top_turn_s=20.0, bottom_turn_s=0.0)
    g = GliderSim(turning, 1.0, 39.0, -73.0, Current(), 2.0)
    still = 0
    while g.depth_m == 2.0:  # pumping, then turning at the top: no vertical motion
        g.step(30.0, -PITCH, -BALLAST, 0.0, True, False)
        still += 1
    assert still == math.ceil(BALLAST / VEHICLE.pump_rate_cc_s) + 20
    for _ in range(60):
        g.step(30.0, -PITCH, -BALLAST, 0.0, True, False)
    before = g.depth_m
    g.step(30.0, -PITCH, -BALLAST, 0.0, True, False)
    net = -net_buoyancy_cc(flight, -BALLAST, before)  # 233 cc less the 60 cc light trim ...
    assert BALLAST - 60.0 < net < BALLAST  # ... plus the hull squeezed at depth
    assert g.depth_m - before == pytest.approx(float(glide(flight, PITCH, net)[1]), rel=1e-6)
