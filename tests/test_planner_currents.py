"""`plan --currents`: a propelled `auto` speed chosen for the least energy per km over
ground on the state's route in the mission's water (planner/water.py, planner/speed.py),
against a brute-force search, and the report's curve in that water."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from gliderplan.cli.main import main
from gliderplan.language import check_source
from gliderplan.planner.hardware import load_hardware
from gliderplan.planner.make import make_plan
from gliderplan.planner.speed import Leg, cheapest_way, head_current
from gliderplan.planner.water import route_legs
from gliderplan.power_models.devices import base_power_w
from gliderplan.power_models.vehicle import load_vehicle
from gliderplan.sim.currents import UniformCurrent

# one state cruising north on the hybrid's thruster (a cubic model: its optimum lies
# inside its speed range); the vehicle is put in 500 m south of the waypoint
MISSION = """mission cruiseNorth

vehicle slocum_g3_hybrid
computer ts7800 @ 300 MHz
battery 1 kWh reserve 10 %

state transect
begin
  flightroute nav(3910.5, -7349.8058)
  flightprofile cruise(20, auto)
  sensors missiontime, depth
  events
    case missiontime >= 3600 exit
end
"""


@pytest.fixture
def mission_file(tmp_path):
    path = tmp_path / "cruise_north.mission"
    path.write_text(MISSION)
    return path


def _plan_json(capsys, path, *options: str) -> dict:
    assert main(["plan", str(path), "--json", *options]) == 0
    return json.loads(capsys.readouterr().out)


def _load_w(state: dict) -> float:
    """[W] the load besides the thruster the state's speed was chosen for."""
    hybrid = load_vehicle("slocum_g3_hybrid")
    return base_power_w(hybrid) + state["energy_by_component_j"]["computer"] / state["time_s"]


def _brute_force_mps(load_w: float, along_mps: float, across_mps: float = 0.0) -> float:
    """The speed of least energy per metre over ground on a fine grid of the range."""
    p = load_vehicle("slocum_g3_hybrid").propulsion
    u = np.linspace(p.min_speed_mps, p.max_speed_mps, 200_001)
    ground = np.sqrt(u * u - across_mps**2) + along_mps
    cost = np.where(ground > 0, (load_w + p.power_w(u)) / ground, np.inf)
    return float(u[np.argmin(cost)])


def test_in_still_water_the_plan_speed_is_the_closed_form(capsys, mission_file):
    still = _plan_json(capsys, mission_file)["states"][0]
    zero = _plan_json(capsys, mission_file, "--currents=0,0")["states"][0]
    propulsion = load_vehicle("slocum_g3_hybrid").propulsion
    closed = propulsion.optimal_speed_mps(_load_w(still))
    assert propulsion.min_speed_mps < closed < propulsion.max_speed_mps
    assert still["speed_m_s"] == pytest.approx(closed, rel=0.01)
    assert zero["speed_m_s"] == pytest.approx(still["speed_m_s"], rel=1e-9)


def test_against_a_head_current_the_plan_speed_rises_to_the_brute_force_least(
        capsys, mission_file):
    still = _plan_json(capsys, mission_file)["states"][0]
    # toward the south: straight against a vehicle heading north
    head = _plan_json(capsys, mission_file, "--currents=-0.2,0")["states"][0]
    assert head["speed_m_s"] > still["speed_m_s"] * 1.1
    assert head["speed_m_s"] == pytest.approx(_brute_force_mps(_load_w(head), -0.2), rel=0.01)
    # the thruster draws what that speed costs for the state's time
    thruster = load_vehicle("slocum_g3_hybrid").propulsion
    assert head["energy_by_component_j"]["propulsion"] == pytest.approx(
        float(thruster.power_w(head["speed_m_s"])) * head["time_s"], rel=1e-6)


def test_following_and_beam_currents_differ_from_a_head_current(capsys, mission_file):
    speeds = {name: _plan_json(capsys, mission_file, f"--currents={spec}")["states"][0]
              for name, spec in (("still", "0,0"), ("head", "-0.2,0"),
                                 ("following", "0.2,0"), ("beam", "0,0.2"))}
    mps = {k: v["speed_m_s"] for k, v in speeds.items()}
    assert mps["following"] < mps["still"] < mps["beam"] < mps["head"]
    assert mps["following"] == pytest.approx(
        _brute_force_mps(_load_w(speeds["following"]), 0.2), rel=0.01)
    assert mps["beam"] == pytest.approx(
        _brute_force_mps(_load_w(speeds["beam"]), 0.0, 0.2), rel=0.01)


def test_no_speed_that_makes_headway_is_a_clear_error_naming_the_leg(capsys, mission_file):
    code = main(["plan", str(mission_file), "--currents=-0.9,0"])
    err = capsys.readouterr().err
    assert code != 0
    assert "Traceback" not in err
    assert "state transect: leg 1 to 39.17500, -73.83010: no speed of 0.402-0.837 m/s " \
           "makes headway against its current of 0.9 m/s" in err


def test_a_head_current_below_the_range_never_picks_a_speed_without_headway():
    hybrid = load_vehicle("slocum_g3_hybrid")
    p = hybrid.propulsion
    # slower than the current: no way; the search must start above it
    head = 0.5 * (p.min_speed_mps + p.max_speed_mps)
    cost, speed = cheapest_way(hybrid, hybrid.hotel_w, None, head_current(head))
    assert speed > head and math.isfinite(cost)


def test_start_goes_with_currents_and_a_sweep_does_not(capsys, mission_file, tmp_path):
    assert main(["plan", str(mission_file), "--start", "39.17,-73.83"]) != 0
    assert "--currents" in capsys.readouterr().err
    assert main(["plan", str(mission_file), "--sweep", "3", "-o", str(tmp_path / "sweep"),
                 "--currents=0,0.1"]) != 0
    assert "--sweep plans at N budgets without --currents" in capsys.readouterr().err


def test_route_legs_resolve_the_current_on_each_track():
    mission = check_source(MISSION, "cruise_north.mission").mission
    legs = route_legs(mission, UniformCurrent(0.3, -0.1), (39.17, -73.83010), 0.0)
    (leg,) = legs["transect"]
    assert leg.length_m == pytest.approx(0.005 * 6371000.0 * math.pi / 180, rel=1e-3)
    assert leg.along_mps == pytest.approx(0.3, abs=1e-3)  # the track runs north
    assert abs(leg.across_mps) == pytest.approx(0.1, abs=1e-3)


def test_the_speed_curve_is_drawn_in_the_current_with_the_chosen_point(tmp_path):
    from gliderplan.reports.speed import CURRENT, STILL, speed_frame

    mission = check_source(MISSION, "cruise_north.mission").mission
    result = make_plan(mission, currents="-0.2,0", output=tmp_path / "p.plan")
    assert (tmp_path / "p.plan.speed.png").read_bytes().startswith(b"\x89PNG")
    hardware = load_hardware(mission)
    from dataclasses import replace

    hardware = replace(hardware, legs={"transect": (Leg("head", 1.0, -0.2),)})
    frame = speed_frame(mission, hardware, result.plan)
    assert set(frame["water"]) == {CURRENT, STILL}
    chosen = frame[frame["chosen"]]
    assert chosen["water"].tolist() == [CURRENT]
    assert chosen["speed_mps"].iloc[0] == pytest.approx(result.plan.states[0].profiles[0]
                                                        .speed_mps)
    curve = frame[(frame["water"] == CURRENT) & ~frame["chosen"]]["energy_per_km_kj"]
    assert curve.min() >= chosen["energy_per_km_kj"].iloc[0] * (1 - 1e-9)
    still = frame[(frame["water"] == STILL) & ~frame["chosen"]]["energy_per_km_kj"]
    assert still.min() < curve.min()  # the head current makes every km dearer


def test_the_html_report_plans_draws_and_flies_the_mission_in_the_current(tmp_path):
    import pandas as pd

    from gliderplan.reports.report import make_report
    from gliderplan.reports.speed import CURRENT, STILL

    mission = check_source(MISSION, "cruise_north.mission").mission
    make_report(mission, tmp_path, sweep_points=3, currents="-0.2,0")
    frame = pd.read_csv(tmp_path / "speed.csv")
    plan = json.loads((tmp_path / "cruiseNorth.plan.json").read_text())
    chosen = frame[frame["chosen"]]
    assert chosen["water"].tolist() == [CURRENT]
    assert chosen["speed_mps"].iloc[0] == pytest.approx(plan["states"][0]["speed_m_s"])
    assert plan["states"][0]["speed_m_s"] == pytest.approx(
        _brute_force_mps(_load_w(plan["states"][0]), -0.2), rel=0.01)
    assert set(frame["water"]) == {CURRENT, STILL}
    assert "in the current" in (tmp_path / "report.html").read_text()
    run = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert run["current_mps"] == {"north": -0.2, "east": 0.0}  # flown in it too
