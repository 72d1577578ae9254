"""Propelled flight in the simulator: a propeller AUV level at its commanded speed, a
hybrid glider's thruster-assisted yo, their motors billed from the [propulsion] model,
the yo's thrust in the plan file, and the example flown without a plan on an AUV."""

from __future__ import annotations

import json
import math
import zlib
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.language import check_source
from gliderplan.planner.plan import plan_mission
from gliderplan.planner.planfile import PlanFileError, read_plan_bytes, write_plan_bytes
from gliderplan.power_models import load_vehicle
from gliderplan.power_models.propulsion import thrust_assisted_speed
from gliderplan.sim.vehicle import PROPELLED_PATH_RAD, Current, GliderSim

REPO = Path(__file__).resolve().parents[1]
LAUV = load_vehicle("lauv")
HYBRID = load_vehicle("slocum_g3_hybrid")


def vehicle_sim(vehicle, depth_m: float) -> GliderSim:
    return GliderSim(vehicle, 4.0, 39.0, -73.0, Current(), depth_m)


def test_an_auv_flies_level_at_the_commanded_speed_drawing_its_model_s_power():
    auv = vehicle_sim(LAUV, 20.0)
    start = auv.lon_deg
    auv.step(20.0, 0.0, 0.0, math.pi / 2, True, False, 1.2)  # east at 1.2 m/s
    assert auv.depth_m == 20.0 and auv.pitch_rad == 0.0
    assert auv.propulsion_w == pytest.approx(float(LAUV.propulsion.power_w(1.2)))
    east = (auv.lon_deg - start) * math.pi / 180 * 6371000.0 * math.cos(39.0 * math.pi / 180)
    assert east == pytest.approx(1.2 * 4.0, rel=1e-6)
    # toward a deeper target along a path no steeper than its limit, nose down
    auv.step(60.0, 0.0, 0.0, math.pi / 2, True, False, 1.2)
    assert auv.depth_m == pytest.approx(20.0 + 1.2 * 4.0 * math.sin(PROPELLED_PATH_RAD))
    assert auv.pitch_rad == pytest.approx(-PROPELLED_PATH_RAD)
    # a speed beyond the model's range is flown at its end
    auv.step(60.0, 0.0, 0.0, 0.0, True, False, 5.0)
    assert auv.propulsion_w == pytest.approx(float(LAUV.propulsion.power_w(
        LAUV.propulsion.max_speed_mps)))


def test_a_thruster_speeds_a_hybrid_s_yo_along_its_path_and_draws_its_power():
    plain, assisted = vehicle_sim(HYBRID, 10.0), vehicle_sim(HYBRID, 10.0)
    for _ in range(40):  # past the pump run: a steady dive
        plain.step(90.0, -0.454, -200.0, 0.0, True, False)
        assisted.step(90.0, -0.454, -200.0, 0.0, True, False, 0.0, 4.0)
    dz, start = plain.depth_m, assisted.depth_m
    plain.step(90.0, -0.454, -200.0, 0.0, True, False)
    assisted.step(90.0, -0.454, -200.0, 0.0, True, False, 0.0, 4.0)
    dz = plain.depth_m - dz
    u = float(HYBRID.glide(0.454 + HYBRID.dive_pitch_error_rad, 200.0)[0])
    fl, propulsion = HYBRID.flight, HYBRID.propulsion
    faster = float(thrust_assisted_speed(u, propulsion.thrust_power_w(4.0), fl.rho_kg_m3,
                                         fl.wing_area_m2, fl.drag_cd0)) / u
    assert (assisted.depth_m - start) == pytest.approx(dz * faster, rel=1e-3)
    assert faster > 1.1
    assert assisted.propulsion_w == pytest.approx(propulsion.assist_draw_w(4.0))
    assert plain.propulsion_w == 0.0


HYBRID_THRUST = """mission assisted
vehicle slocum_g3_hybrid
computer ts7800 @ 300 MHz
battery 1 kWh reserve 10 %
state s
begin
  flightroute nav(3910.5, -7349.8058)
  flightprofile yo(5, 30, .454, .454) thrust 3 W
  sensors missiontime, depth
  events
    case missiontime >= 7200 exit
end
"""


def test_a_plan_file_carries_a_yo_s_thrust_and_refuses_a_bad_one():
    mission = check_source(HYBRID_THRUST, "assisted.mission").mission
    plan = plan_mission(mission).plan
    assert plan.states[0].profiles[0].thrust_w == 3.0
    data = write_plan_bytes(plan)
    line = next(x for x in data.decode().splitlines() if x.startswith("profile "))
    assert len(line.split()) == 7 and line.endswith(" 3")
    assert read_plan_bytes(data, mission) == plan
    body = data[:data.rindex(b"crc32 ")].replace(line.encode(), line[:-1].encode() + b"-3")
    bad = body + f"crc32 {zlib.crc32(body):08x}\n".encode()
    with pytest.raises(PlanFileError, match="thrust must lie in") as info:
        read_plan_bytes(bad, mission)
    assert info.value.line == data.decode().splitlines().index(line) + 1


def test_the_example_flies_without_a_plan_on_an_auv_on_its_propeller(tmp_path, capsys):
    source = (REPO / "examples" / "propelled_transect.mission").read_text()
    mission = tmp_path / "auv.mission"
    mission.write_text(source.replace("vehicle slocum_g3_hybrid", "vehicle lauv"))
    assert main(["sim", str(mission), "-o", str(tmp_path / "run")]) == 0
    assert "pitch" not in capsys.readouterr().err  # the yo it cannot fly is not flown
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    energy = summary["energy_by_component_j"]
    assert energy["propulsion"] > energy["hotel"] > 0  # on the propeller all the way
    assert energy["pump"] == 0.0
