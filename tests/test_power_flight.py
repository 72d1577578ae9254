"""The vehicle model: steady-glide speeds of DESIGN.md section 8, yo energy, optimal speed."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from gliderplan.power_models import flight, load_vehicle

PITCH_26 = math.radians(26.0)


@pytest.fixture(params=["slocum_g2_shallow", "slocum_g3"])
def vehicle(request):
    return load_vehicle(request.param).neutral()


@pytest.mark.parametrize(
    ("ballast_cc", "u_mps", "w_mps"), [(100, 0.21, 0.11), (230, 0.31, 0.17), (460, 0.45, 0.24)]
)
def test_glide_speeds_at_26_degrees_match_the_derived_figures(ballast_cc, u_mps, w_mps):
    u, w = load_vehicle("slocum_g2_shallow").glide(PITCH_26, ballast_cc)
    assert u == pytest.approx(u_mps, rel=0.10)
    assert w == pytest.approx(w_mps, rel=0.10)


@pytest.mark.parametrize("cd0", [0.02, 0.15, 1.0])
def test_the_angle_of_attack_balances_lift_and_drag(vehicle, cd0):
    # the steady glide's balance, Cd = CL tan(pitch + alpha), to double precision
    params = dataclasses.replace(vehicle.flight, drag_cd0=cd0)
    pitch = np.linspace(0.02, 1.5, 300)
    alpha = flight.angle_of_attack_rad(params, pitch)
    assert np.all((alpha > 0) & (pitch + alpha < math.pi / 2))
    drag = params.drag_cd0 + params.drag_cd1_per_rad2 * alpha**2
    lift = (params.lift_wing_per_rad + params.lift_hull_per_rad) * alpha
    np.testing.assert_allclose(drag / (lift * np.tan(pitch + alpha)), 1.0, rtol=1e-12)
    assert flight.angle_of_attack_rad(params, 0.45) == pytest.approx(
        alpha[np.searchsorted(pitch, 0.45)], abs=0.01)  # a scalar solves alike


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
    g2 = load_vehicle("slocum_g2_shallow").neutral()
    design = dataclasses.replace(
        g2,
        flight=dataclasses.replace(g2.flight, drag_cd0=0.15),  # as DESIGN.md derived them
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
            + vehicle.pump_in_energy_j(5.0, 400.0)
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


@pytest.mark.parametrize("turn_s", [0.0, 30.0])
def test_transit_coefficient_gives_energy_per_metre(vehicle, turn_s):
    hotel = 3.5
    vehicle = dataclasses.replace(vehicle, top_turn_s=turn_s, bottom_turn_s=turn_s / 2)
    for u in (0.15, 0.25, 0.3):
        ballast = vehicle.ballast_for_speed(u, PITCH_26)
        direct = vehicle.energy_per_km_j(5.0, 60.0, PITCH_26, ballast, hotel) / 1e3
        c = vehicle.transit_coefficient(5.0, 60.0, PITCH_26, hotel)
        formula = (hotel / u + vehicle.pitch_j_per_m(5.0, 60.0, PITCH_26)
                   + hotel * vehicle.turn_s_per_m(5.0, 60.0, PITCH_26) + c * u**2)
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
    assert g3.surfacing_with_iridium_j == pytest.approx(389.37 + 5.5498 * 637)


# ---- trim, compressibility and the water column ----------------------------------------
BAND = (3.0, 36.0)


def _trimmed(trim_cc=0.0, eps=0.0, hull_cc=60_000.0):
    vehicle = load_vehicle("slocum_g2_shallow")
    return dataclasses.replace(vehicle.flight, hull_volume_cc=hull_cc, trim_cc=trim_cc,
                               compressibility_per_pa=eps)


def test_a_neutral_glider_in_uniform_water_dives_and_climbs_alike():
    params = _trimmed()
    dive, climb = (flight.glide_leg(params, *BAND, PITCH_26, 230.0, up) for up in (False, True))
    _, w = flight.glide(params, PITCH_26, 230.0)
    assert dive.w_mps == pytest.approx(w) and climb.w_mps == pytest.approx(w)
    assert dive.time_s == pytest.approx((BAND[1] - BAND[0]) / w)


def test_a_glider_trimmed_light_climbs_faster_than_it_dives():
    params = _trimmed(trim_cc=80.0)
    dive, climb = (flight.glide_leg(params, *BAND, PITCH_26, 230.0, up) for up in (False, True))
    _, w_dive = flight.glide(params, PITCH_26, 230.0 - 80.0)
    _, w_climb = flight.glide(params, PITCH_26, 230.0 + 80.0)
    assert dive.w_mps == pytest.approx(w_dive) and climb.w_mps == pytest.approx(w_climb)
    with pytest.raises(ValueError, match="cannot dive"):
        flight.glide_leg(_trimmed(trim_cc=250.0), *BAND, PITCH_26, 230.0, False)


def test_the_hull_squeezed_at_depth_makes_deep_dives_faster():
    params = _trimmed(eps=5e-10)
    shallow, deep = (flight.glide_leg(params, top, top + 10.0, PITCH_26, 230.0, False)
                     for top in (0.0, 90.0))
    assert deep.w_mps > shallow.w_mps
    # 60 l squeezed by 5e-10 per Pa at 95 m: ~29 cc heavier
    squeeze = 60_000.0 * 5e-10 * params.rho_kg_m3 * params.g_m_s2 * 95.0
    assert deep.w_mps == pytest.approx(float(flight.glide(params, PITCH_26, 230.0 + squeeze)[1]),
                                       rel=1e-3)


def test_net_buoyancy_follows_the_water_density():
    params = _trimmed(trim_cc=40.0, eps=4e-10)
    mass_kg = params.rho_kg_m3 * (params.hull_volume_cc - params.trim_cc) * 1e-6
    rho, depth, pumped = 1027.0, 30.0, -230.0
    pressure = params.rho_kg_m3 * params.g_m_s2 * depth
    volume_cc = params.hull_volume_cc * (1 - params.compressibility_per_pa * pressure)
    expected = volume_cc + pumped - mass_kg / rho * 1e6  # B / (rho g) of Merckelbach et al.
    assert flight.net_buoyancy_cc(params, pumped, depth, rho) == pytest.approx(expected)
    # denser water deep down: the glider dives slower there than in uniform water
    ocean = flight.DensityProfile(np.array([0.0, 40.0]), np.array([params.rho_kg_m3, 1027.0]))
    uniform = flight.glide_leg(params, *BAND, PITCH_26, 230.0, False)
    layered = flight.glide_leg(params, *BAND, PITCH_26, 230.0, False, ocean)
    assert layered.time_s > uniform.time_s


def test_turn_times_lengthen_the_yo(vehicle):
    turning = dataclasses.replace(vehicle, top_turn_s=40.0, bottom_turn_s=20.0)
    per_hour = vehicle.inflections_per_hour(5.0, 50.0, PITCH_26, 200.0)
    slower = turning.inflections_per_hour(5.0, 50.0, PITCH_26, 200.0)
    assert 7200.0 / slower - 7200.0 / per_hour == pytest.approx(60.0)
