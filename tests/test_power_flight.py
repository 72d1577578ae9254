"""The vehicle model: steady-glide speeds of DESIGN.md section 8, yo energy, optimal speed."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gliderplan.power_models import load_vehicle

PITCH_26 = math.radians(26.0)


@pytest.fixture(params=["slocum_g2_shallow", "slocum_g3"])
def vehicle(request):
    return load_vehicle(request.param)


@pytest.mark.parametrize(
    ("ballast_cc", "u_mps", "w_mps"), [(100, 0.21, 0.11), (230, 0.31, 0.17), (460, 0.45, 0.24)]
)
def test_glide_speeds_at_26_degrees_match_the_derived_figures(ballast_cc, u_mps, w_mps):
    u, w = load_vehicle("slocum_g2_shallow").glide(PITCH_26, ballast_cc)
    assert u == pytest.approx(u_mps, rel=0.10)
    assert w == pytest.approx(w_mps, rel=0.10)


def test_glide_is_vectorised_and_ballast_for_speed_inverts_it(vehicle):
    pitch = np.radians([15.0, 20.0, 26.0, 35.0])[:, None]
    ballast = np.array([50.0, 150.0, 300.0])[None, :]
    u, w = vehicle.glide(pitch, ballast)
    assert u.shape == (4, 3) and np.all(u > 0) and np.all(w > 0)
    assert vehicle.ballast_for_speed(u, pitch) == pytest.approx(np.broadcast_to(ballast, (4, 3)))
    # steeper pitch: steeper glide path
    assert np.all(np.diff(w / u, axis=0) > 0)


def test_glide_refuses_impossible_input(vehicle):
    with pytest.raises(ValueError, match="pitch"):
        vehicle.glide(0.0, 200)
    with pytest.raises(ValueError, match="pitch"):
        vehicle.glide(math.pi / 2, 200)
    with pytest.raises(ValueError, match="ballast"):
        vehicle.glide(PITCH_26, -10)


def test_energy_per_km_reproduces_the_derived_figures():
    # DESIGN.md section 8: 2.63 W hotel, 165 J pump + 50 J pitch per inflection, 26 deg,
    # 230 cc either side, inflections taking no time.
    per_cc = 165.0 / 460.0
    design = dataclasses.replace(
        load_vehicle("slocum_g2_shallow"),
        hotel_w=2.63,
        pump_out_j_per_cc=per_cc,
        pump_out_j_per_cc_m=0.0,
        pump_in_j_per_cc=per_cc,
        pitch_energy_j=50.0,
        pump_rate_cc_s=math.inf,
    )
    energy = design.energy_per_km_j(5.0, np.array([10.0, 20.0, 40.0, 100.0]), PITCH_26, 230.0)
    assert energy / 1e3 == pytest.approx([31.6, 16.1, 11.7, 9.6], rel=0.02)


def test_deeper_yos_need_fewer_inflections_and_less_energy(vehicle):
    bottoms = np.array([20.0, 50.0, 100.0])
    per_hour = vehicle.inflections_per_hour(5.0, bottoms, PITCH_26, 200.0)
    assert np.all(np.diff(per_hour) < 0)
    u, w = vehicle.glide(PITCH_26, 200.0)
    cycle_s = 2 * (bottoms - 5.0) / w + 2 * 400.0 / vehicle.pump_rate_cc_s
    assert per_hour == pytest.approx(2 * 3600.0 / cycle_s)
    power = vehicle.profile_power_w(5.0, bottoms, PITCH_26, 200.0)
    expected = (
        (
            vehicle.pump_energy_j(bottoms, 400.0)
            + vehicle.pump_in_energy_j(400.0)
            + 2 * vehicle.pitch_energy_j
        )
        * per_hour
        / 7200.0
    )
    assert power == pytest.approx(expected)
    assert np.all(np.diff(vehicle.energy_per_km_j(5.0, bottoms, PITCH_26, 200.0)) < 0)


def test_g3_pump_model_is_the_fitted_formula():
    g3 = load_vehicle("slocum_g3")
    assert g3.pump_energy_j(100.0, 200.0) == pytest.approx(2.4888 * 200 + 0.012276 * 200 * 100)


def test_transit_coefficient_gives_energy_per_metre(vehicle):
    hotel = 3.5
    for u in (0.15, 0.25, 0.3):
        ballast = vehicle.ballast_for_speed(u, PITCH_26)
        direct = vehicle.energy_per_km_j(5.0, 60.0, PITCH_26, ballast, hotel) / 1e3
        c = vehicle.transit_coefficient(5.0, 60.0, PITCH_26, hotel)
        formula = hotel / u + vehicle.pitch_j_per_m(5.0, 60.0, PITCH_26) + c * u**2
        assert direct == pytest.approx(formula, rel=1e-9)


def test_optimal_speed_minimises_energy_per_km(vehicle):
    hotel = 1.5
    best = float(vehicle.optimal_speed_mps(hotel, 5.0, 100.0, PITCH_26))
    c = vehicle.transit_coefficient(5.0, 100.0, PITCH_26, hotel)
    assert best == pytest.approx(min((hotel / (2 * c)) ** (1 / 3), vehicle.max_speed_mps(PITCH_26)))
    grid = np.linspace(0.05, float(vehicle.max_speed_mps(PITCH_26)), 400)
    energy = vehicle.energy_per_km_j(
        5.0, 100.0, PITCH_26, vehicle.ballast_for_speed(grid, PITCH_26), hotel
    )
    assert best == pytest.approx(grid[np.argmin(energy)], abs=0.005)


def test_hungrier_hotel_load_flies_faster_until_the_pump_limit():
    g3 = load_vehicle("slocum_g3")
    speeds = g3.optimal_speed_mps(np.array([0.5, 1.0, 2.0, 4.0, 1000.0]), 5.0, 200.0, PITCH_26)
    assert np.all(np.diff(speeds) >= 0) and speeds[0] < speeds[3]
    assert speeds[-1] == pytest.approx(g3.max_speed_mps(PITCH_26))


def test_surfacing_costs(vehicle):
    assert vehicle.surfacing_with_iridium_j == pytest.approx(
        vehicle.surfacing_j + vehicle.iridium_w * vehicle.iridium_s
    )
    g3 = load_vehicle("slocum_g3")
    assert g3.surfacing_with_iridium_j == pytest.approx(389 + 5.55 * 637)
