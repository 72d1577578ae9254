"""The planner on propelled vehicles: the chosen cruise speed, the propulsion's energy,
alternatives a vehicle cannot fly, and `compare-vehicles` on the example mission flown
by a glider, a hybrid and an AUV by changing only its vehicle line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from gliderplan.language import check_source
from gliderplan.planner.make import make_plan
from gliderplan.planner.report import report_json
from gliderplan.planner.speed import best_speed, choice_at
from gliderplan.power_models.devices import base_power_w
from gliderplan.power_models.vehicle import load_vehicle

EXAMPLE = Path(__file__).parent.parent / "examples" / "propelled_transect.mission"
VEHICLES = ("slocum_g2_shallow", "slocum_g3_hybrid", "lauv")


def _example_on(vehicle: str):
    source = EXAMPLE.read_text().replace("vehicle slocum_g3_hybrid", f"vehicle {vehicle}")
    result = check_source(source, "propelled_transect.mission")
    assert result.ok, [d.message for d in result.diagnostics]
    return result


@pytest.mark.parametrize("vehicle", VEHICLES)
def test_the_example_flies_on_each_vehicle_by_its_vehicle_line(vehicle: str) -> None:
    result = _example_on(vehicle)
    report = report_json(make_plan(result.mission))
    kinds = {p["kind"] for s in report["states"] for p in s["profiles"] if p["share"] > 0}
    assert kinds == ({"cruise"} if vehicle == "lauv" else {"yo"})
    warned = [d.message for d in result.diagnostics]
    assert all("the planner gives it no time" in m for m in warned)
    assert bool(warned) == (vehicle != "slocum_g3_hybrid")


def test_auto_speed_is_the_least_energy_per_metre_and_beats_one_metre_per_second() -> None:
    report = report_json(make_plan(_example_on("lauv").mission))
    lauv = load_vehicle("lauv")
    state = report["states"][0]
    load = base_power_w(lauv) + state["energy_by_component_j"]["computer"] / state["time_s"]
    chosen = best_speed(lauv.propulsion, load)
    assert state["speed_m_s"] == pytest.approx(chosen.speed_mps, rel=1e-6)
    assert state["energy_by_component_j"]["propulsion"] == pytest.approx(
        chosen.propulsion_w * state["time_s"], rel=1e-6)
    fixed = choice_at(lauv.propulsion, load, 1.0)
    # the model's own prediction of the saving per km, and a real saving
    assert fixed.energy_per_m_j - chosen.energy_per_m_j == pytest.approx(
        (load + float(lauv.propulsion.power_w(1.0))) / 1.0
        - (load + chosen.propulsion_w) / chosen.speed_mps)
    assert chosen.energy_per_m_j < fixed.energy_per_m_j


def test_compare_vehicles_json_and_crossover() -> None:
    run = subprocess.run([sys.executable, "-m", "gliderplan.cli", "compare-vehicles",
                          str(EXAMPLE), *[a for v in VEHICLES for a in ("--vehicle", v)],
                          "--json"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    data = json.loads(run.stdout)
    rows = {v["vehicle"]: v for v in data["vehicles"]}
    assert [rows[v]["kind"] for v in VEHICLES] == ["glider", "hybrid", "auv"]
    assert all(r["energy_j"] > 0 and r["duration_s"] == 8 * 3600 for r in rows.values())
    # still water: the glider is cheapest per km; a strong head current: the AUV
    assert min(rows.values(), key=lambda r: r["energy_per_km_j"])["vehicle"] == VEHICLES[0]
    assert data["crossovers"] and data["crossovers"][-1]["to"] == "lauv"


def test_compare_vehicles_plans_the_mission_on_each_vehicle_in_python() -> None:
    from gliderplan.planner.vehicles import compare_vehicles, crossovers

    results = compare_vehicles(_example_on("lauv").mission, list(VEHICLES))
    assert [(r.vehicle, r.kind) for r in results] == [
        ("slocum_g2_shallow", "glider"), ("slocum_g3_hybrid", "hybrid"), ("lauv", "auv")]
    # still water: the glider goes furthest per joule, the AUV least far
    assert results[0].energy_per_km_j < results[1].energy_per_km_j < results[2].energy_per_km_j
    assert [(f["from"], f["to"]) for f in crossovers(results)] == [
        ("slocum_g2_shallow", "slocum_g3_hybrid"), ("slocum_g3_hybrid", "lauv")]


def test_compare_vehicles_refuses_an_unknown_vehicle() -> None:
    run = subprocess.run([sys.executable, "-m", "gliderplan.cli", "compare-vehicles",
                          str(EXAMPLE), "--vehicle", "submarine"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode in (1, 2) and "submarine" in run.stderr
    assert "Traceback" not in run.stderr


TRANSIT = """mission transit
vehicle VEHICLE
computer ts7800 @ 300 MHz
battery 5 kWh reserve 10 %
state start
begin
  flightroute nav(3910.5, -7349.8058)
  flightprofile PROFILE
  sensors missiontime, depth
  events
    case missiontime >= 600 goto out
end
state out
begin
  flightroute nav(3920.5, -7349.8058)
  flightprofile PROFILE
  sensors missiontime, depth, wptdist
  events
    case wptdist < 60 exit
end
"""


@pytest.mark.parametrize(("vehicle", "profile"), [("lauv", "cruise(10, auto)"),
                                                  ("lauv", "cruise(10, 1.2)"),
                                                  ("slocum_g3_hybrid", "cruise(10, auto)")])
def test_a_propelled_transit_leg_is_timed_at_its_speed(vehicle: str, profile: str) -> None:
    source = TRANSIT.replace("VEHICLE", vehicle).replace("PROFILE", profile)
    result = check_source(source, "transit.mission")
    assert result.ok, [d.message for d in result.diagnostics]
    plan = make_plan(result.mission)
    state = plan.plan.states[1]
    speed = state.profiles[0].speed_mps
    if "1.2" in profile:
        assert speed == 1.2
    # the leg between the two points, 10' of latitude apart: 18.5 km
    leg_m = speed * state.time_s
    assert leg_m == pytest.approx(18532, abs=speed * 4.0 + 1.0)
    assert state.time_s < leg_m / 0.35 / 1.4  # not the glider's nominal 0.35 m/s
    assert any("propelled transit leg of 18.5 km" in a.text
               for a in plan.plan.assumptions)


def test_a_propelled_plan_draws_energy_per_km_against_speed_beside_it(tmp_path) -> None:
    from gliderplan.cli.main import main

    for vehicle in ("lauv", "slocum_g2_shallow"):
        mission = tmp_path / f"{vehicle}.mission"
        mission.write_text(EXAMPLE.read_text().replace("vehicle slocum_g3_hybrid",
                                                       f"vehicle {vehicle}"))
        assert main(["plan", str(mission), "-o", str(tmp_path / f"{vehicle}.plan")]) == 0
    assert (tmp_path / "lauv.plan.speed.png").read_bytes().startswith(b"\x89PNG")
    assert not (tmp_path / "slocum_g2_shallow.plan.speed.png").exists()  # nothing propelled


def test_the_report_shows_energy_per_km_against_speed_with_the_chosen_point(tmp_path) -> None:
    import pandas as pd

    from gliderplan.reports.report import make_report

    result = _example_on("lauv")
    report = make_report(result.mission, tmp_path, sweep_points=3)
    assert report.sections[3:5] == ("speed", "vehicles")
    vehicles = pd.read_csv(tmp_path / "vehicles.csv")
    assert list(vehicles.columns) == ["head_current_mps", "lauv", *VEHICLES[:2]]  # its own first
    page = (tmp_path / "report.html").read_text()
    assert "against a head current of 0.65 m/s and more, lauv needs the least energy" in page
    assert 'id="speed"' in (tmp_path / "report.html").read_text()
    frame = pd.read_csv(tmp_path / "speed.csv")
    plan = json.loads((tmp_path / "propelledTransect.plan.json").read_text())
    for state in plan["states"]:
        rows = frame[frame["state"] == state["name"]]
        chosen = rows[rows["chosen"]]
        assert chosen["speed_mps"].tolist() == [state["speed_m_s"]]
        # auto: no speed of the curve takes less per km than the chosen one
        curve = rows[~rows["chosen"]]["energy_per_km_kj"]
        assert curve.min() >= chosen["energy_per_km_kj"].iloc[0] * (1 - 1e-9)
