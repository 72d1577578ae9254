"""Differential tests.

1. Every example mission and every simulator mission, flown by the Python executor, by
   the compiled C runtime over a pty and by its step in this process against the same
   simulated glider, gives the same trace.csv (and, through the same glider, the same dive
   profile).
2. The C flight (the runtime's step with the glider, science and energy models in C,
   sim/flight.c: the simulator's default) and the Python reference (the reference
   executor and the Python models, tick by tick) fly every example, every simulator
   mission and random missions alike: the same transition trace, events, variables and
   every per-tick record (the energy's too), bit for bit.
"""

from __future__ import annotations

import json
import shutil
import zlib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from gliderplan.cli.main import main
from gliderplan.language import check_file, check_source
from gliderplan.power_models import load_vehicle
from gliderplan.sim.flight import fly
from gliderplan.sim.loop import RunConfig
from gliderplan.sim.ocean import SeaFloor, flat_floor, load_ocean
from gliderplan.sim.science import NOISE_PRESETS
from gliderplan.sim.vehicle import Current

REPO = Path(__file__).resolve().parents[1]
MISSIONS = sorted((REPO / "examples").glob("*.mission")) + sorted(
    (REPO / "tests" / "missions").glob("sim_*.mission"))
# the oceans and sensors each mission was written for; long missions are cut short
RUN_OPTIONS = {
    "sim_first_sea_run.mission": ["--ocean", "sea-trial"],
    "sim_sea_trial.mission": ["--ocean", "sea-trial", "--noise", "nonmonotonic"],
    "sim_month.mission": ["--duration", "1d"],
    "sim_altimeter.mission": ["--floor", "38"],  # dives turn 4 m above it, the last yo grounds
    "survey_month.mission": ["--duration", "1d"],
    "sim_propelled_auv.mission": ["--floor", "40"],  # follows it 8 m above
}

needs_cc = pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc)")


@needs_cc
@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.name)
def test_python_and_c_runtimes_give_identical_traces(path, tmp_path, capsys):
    options = RUN_OPTIONS.get(path.name, [])
    runs = {}
    for runtime in ("python", "c", "step"):
        out = tmp_path / runtime
        code = main(["sim", str(path), "--runtime", runtime, "--seed", "7", *options,
                     "-o", str(out)])
        assert code == 0, capsys.readouterr().err
        runs[runtime] = out
    python_trace = (runs["python"] / "trace.csv").read_text()
    assert python_trace.count("\n") >= 2  # a start and at least one more transition
    python_series = pd.read_parquet(runs["python"] / "timeseries.parquet")
    for runtime in ("c", "step"):
        assert (runs[runtime] / "trace.csv").read_text() == python_trace, runtime
        series = pd.read_parquet(runs[runtime] / "timeseries.parquet")
        for column in ("depth_m", "pitch_rad", "state", "stack_depth", "profile", "temp_on"):
            assert python_series[column].equals(series[column]), (runtime, column)


@needs_cc
def test_the_naive_tracker_is_the_same_in_both_runtimes(tmp_path):
    path = REPO / "tests" / "missions" / "sim_sea_trial.mission"
    depths = []
    for runtime in ("python", "c", "step"):
        out = tmp_path / runtime
        assert main(["sim", str(path), "--runtime", runtime, "--ocean", "sea-trial",
                     "--noise", "nonmonotonic", "--tracker", "naive", "-o", str(out)]) == 0
        depths.append(pd.read_parquet(out / "timeseries.parquet")["depth_m"])
    assert depths[0].equals(depths[1]) and depths[0].equals(depths[2])


def write_plan(path: Path, mission_path: Path) -> Path:
    """A plan for sim_alternating.mission: profile shares, sensor duty cycles, clocks."""
    from gliderplan.language import check_file

    mission = check_file(str(mission_path)).mission
    body = (f"GPPLAN 3\nmission {mission.name}\nhash {mission.hash}\ncomputer ts7800 300\n"
            "budget_j 1000000\npredicted_j 100000\ncomponents hotel\nassumptions 0\nstates 2\n"
            "state survey 300 1200 2 2\npredict 30000 1 200\nenergy 90000\n"
            "sensor temp 60 20\nsensor oxygen 300 100\n"
            "profile 0 0.6 0.4 150 0.25\nprofile 1 0.4 0.454 233 0.32\nend\n"
            "state fix 300 600 0 1\npredict 3000 1 0\nenergy 10000\n"
            "profile 0 1 0.454 200 0.3\nend\n").encode()
    path.write_bytes(body + f"crc32 {zlib.crc32(body):08x}\n".encode())
    return path


@needs_cc
def test_a_plan_s_schedule_is_flown_the_same_by_both_runtimes(tmp_path):
    mission = REPO / "tests" / "missions" / "sim_alternating.mission"
    plan = write_plan(tmp_path / "alternating.plan", mission)
    series = {}
    for runtime in ("python", "c", "step"):
        out = tmp_path / runtime
        assert main(["sim", str(mission), "--plan", str(plan), "--runtime", runtime,
                     "-o", str(out)]) == 0
        series[runtime] = (pd.read_parquet(out / "timeseries.parquet"),
                           (out / "trace.csv").read_text())
    python, python_trace = series["python"]
    assert python_trace.count("call") == 2
    for runtime in ("c", "step"):
        c, c_trace = series[runtime]
        assert c_trace == python_trace, runtime
        for column in ("depth_m", "pitch_rad", "profile", "temp_on", "oxygen_on", "lat_deg",
                       "lon_deg"):
            assert python[column].equals(c[column]), (runtime, column)
    survey = python[python["state"] == "survey"]
    assert set(survey["profile"]) == {0, 1}  # both bands flown
    assert 0.25 < survey["temp_on"].mean() < 0.45  # 20 s of every 60 s
    assert 0.25 < survey["oxygen_on"].mean() < 0.45  # 100 s of every 300 s


@needs_cc
@pytest.mark.parametrize("name", ["fig2_annotated.mission", "thermocline_survey.mission"])
def test_the_planner_s_plans_are_flown_the_same_by_both_runtimes(name, tmp_path):
    mission = REPO / "examples" / name
    plan = tmp_path / "mission.plan"
    assert main(["plan", str(mission), "-o", str(plan)]) == 0
    outputs = {}
    for runtime in ("python", "c", "step"):
        out = tmp_path / runtime
        assert main(["sim", str(mission), "--plan", str(plan), "--runtime", runtime,
                     "-o", str(out)]) == 0
        outputs[runtime] = ((out / "trace.csv").read_text(),
                            pd.read_parquet(out / "timeseries.parquet"))
    python_trace, python = outputs["python"]
    for runtime in ("c", "step"):
        c_trace, c = outputs[runtime]
        assert c_trace == python_trace, runtime
        for column in ("depth_m", "profile", "temp_on", "oxygen_on"):
            assert python[column].equals(c[column]), (runtime, column)


@needs_cc
@pytest.mark.parametrize("vehicle", ["slocum_g2_shallow", "slocum_g3_hybrid", "lauv"])
def test_a_propelled_plan_is_flown_the_same_by_both_runtimes_and_holds(vehicle, tmp_path):
    """The propelled transect planned on a glider, a hybrid and an AUV (its vehicle line
    alone changed): every runtime flies the plan alike, and its energy as planned."""
    source = (REPO / "examples" / "propelled_transect.mission").read_text()
    mission = tmp_path / "transect.mission"
    mission.write_text(source.replace("vehicle slocum_g3_hybrid", f"vehicle {vehicle}"))
    plan = tmp_path / "transect.plan"
    assert main(["plan", str(mission), "-o", str(plan)]) == 0
    outputs = {}
    for runtime in ("python", "c", "step"):
        out = tmp_path / runtime
        assert main(["sim", str(mission), "--plan", str(plan), "--runtime", runtime,
                     "-o", str(out)]) == 0
        outputs[runtime] = ((out / "trace.csv").read_text(),
                            pd.read_parquet(out / "timeseries.parquet"),
                            json.loads((out / "summary.json").read_text()))
    python_trace, python, summary = outputs["python"]
    assert python_trace.count("goto") == 1
    for runtime in ("c", "step"):
        c_trace, c, _ = outputs[runtime]
        assert c_trace == python_trace, runtime
        for column in ("depth_m", "pitch_rad", "profile", "lat_deg", "lon_deg",
                       "power_propulsion_w" if vehicle != "slocum_g2_shallow"
                       else "power_pump_w"):
            assert python[column].equals(c[column]), (runtime, column)
    assert summary["plan_check"]["verdict"] == "pass", summary["plan_check"]["headline"]
    if vehicle == "lauv":  # level at 20 m, then 10 m, on the propeller all the way
        assert python["power_propulsion_w"].iloc[1:-1].min() > 0.0
        assert python["depth_m"].max() == pytest.approx(20.0, abs=0.01)


# ---- the C flight against the Python reference ---------------------------------------

def flown_alike(mission, config: RunConfig, ocean="bench", plan=None, vehicle=None,
                rigid: bool = False, shore=None):
    """Fly `mission` on the Python reference and in the C flight (in `ocean`, a preset name
    or an Ocean; `vehicle`: default the mission's, whose calibrated hull is compressible:
    its speed changes with depth; `rigid`: with the hull made incompressible; `shore`:
    makes the shore each flight has in the loop, whose logs must be the same too); the two
    flights must be the same (the flight is returned)."""
    vehicle = vehicle or load_vehicle(mission.vehicle)
    if rigid:
        vehicle = replace(vehicle, flight=replace(vehicle.flight, compressibility_per_pa=0.0))
    water = load_ocean(ocean) if isinstance(ocean, str) else ocean
    shores = (shore(), shore()) if shore else (None, None)
    reference = fly(mission, water, config, vehicle, plan, runtime="python", shore=shores[0])
    flown = fly(mission, water, config, vehicle, plan, runtime="step", shore=shores[1])
    if shore:
        assert shores[1].log == shores[0].log
    assert flown.trace == reference.trace
    assert (flown.ended, flown.surfacings, flown.events_fired, flown.grounded_ticks) == \
        (reference.ended, reference.surfacings, reference.events_fired,
         reference.grounded_ticks)
    assert flown.entry_variables == reference.entry_variables
    assert flown.envelope == reference.envelope
    assert flown.columns.keys() == reference.columns.keys()
    for name, column in reference.columns.items():
        ours = flown.columns[name]
        assert ours.dtype == column.dtype and ours.shape == column.shape, name
        assert np.array_equal(ours.view(np.uint8), column.view(np.uint8)), name
    return flown


# (ocean, noise, current north/east [m/s], duration [s], rigid hull) each mission is
# flown in: the calibrated (compressible) hull and a rigid one
FAST_CASES = [("bench", "ctd", (0.0, 0.0), 2 * 86400.0, False),
              ("sea-trial", "nonmonotonic", (0.08, -0.05), 6 * 3600.0, True)]


@pytest.mark.parametrize("case", FAST_CASES, ids=["bench", "sea-trial-current-rigid"])
@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.name)
def test_the_c_flight_flies_every_mission_as_the_reference(path, case):
    ocean, noise, (north, east), duration_s, rigid = case
    mission = check_file(str(path)).mission
    config = RunConfig(duration_s=min(duration_s, mission.horizon_s or duration_s), seed=11,
                       noise=NOISE_PRESETS[noise], current=Current(north, east))
    flown_alike(mission, config, ocean, rigid=rigid)


@pytest.mark.parametrize("rigid", [False, True], ids=["calibrated", "rigid"])
@pytest.mark.parametrize("name", ["fig2_annotated.mission", "thermocline_survey.mission",
                                  "survey_month.mission"])
def test_the_c_flight_flies_the_planner_s_plans_as_the_reference(name, rigid, tmp_path):
    from gliderplan.planner.planfile import load_plan

    path = REPO / "examples" / name
    plan_path = tmp_path / "mission.plan"
    assert main(["plan", str(path), "-o", str(plan_path)]) == 0
    mission = check_file(str(path)).mission
    config = RunConfig(duration_s=min(86400.0, mission.horizon_s), seed=3,
                       noise=NOISE_PRESETS["ctd"], current=Current(0.03, 0.1))
    flown_alike(mission, config, "sea-trial", load_plan(plan_path, mission), rigid=rigid)


def test_the_c_flight_flies_a_hand_written_schedule_as_the_reference(tmp_path):
    from gliderplan.planner.planfile import load_plan

    path = REPO / "tests" / "missions" / "sim_alternating.mission"
    mission = check_file(str(path)).mission
    plan = load_plan(write_plan(tmp_path / "alternating.plan", path), mission)
    flown_alike(mission, RunConfig(duration_s=14400.0, seed=5), "bench", plan)


def test_the_c_flight_holds_a_heading_uncorrected_in_a_current_as_the_reference():
    """A held heading (Slocum's set_heading) after fixes have measured the current: the
    current correction, on for the mission, leaves it alone in the C flight as in the
    reference, and the glider is carried north with the current."""
    from gliderplan.planner.routing import transit_mission

    goto = "goto_list(1000, (3906.0000, -7324.0000))"
    text = transit_mission([(39.1, -73.4)], 4 * 3600.0, surface_every_s=3600.0)
    mission = check_source(text.replace(goto, "heading(90)")).mission
    assert mission.current_correction
    config = RunConfig(duration_s=4 * 3600.0, seed=3, current=Current(0.1, 0.0))
    flown = flown_alike(mission, config, "sea-trial")
    north_m = (flown.columns["lat_deg"][-1] - flown.columns["lat_deg"][0]) * 111_000.0
    assert north_m > 0.9 * 0.1 * 4 * 3600.0  # carried the whole way, not steered upstream


# floors under the altimeter mission: flat, shallower than a dive's turn, and one that
# rises and falls along the run as a glider's logged floor does
FLOORS = [flat_floor(38.0), flat_floor(20.0),
          SeaFloor((0.0, 1800.0, 4000.0, 9000.0), (45.0, 31.0, 52.5, 36.0), "along time")]


@pytest.mark.parametrize("rigid", [False, True], ids=["calibrated", "rigid"])
@pytest.mark.parametrize("floor", FLOORS, ids=["38m", "20m", "along-time"])
def test_the_c_flight_flies_over_a_sea_floor_as_the_reference(floor, rigid):
    mission = check_file(str(REPO / "tests" / "missions" / "sim_altimeter.mission")).mission
    config = RunConfig(duration_s=mission.horizon_s or 12600.0, seed=4,
                       noise=NOISE_PRESETS["ctd"], floor=floor)
    flown = flown_alike(mission, config, "sea-trial", rigid=rigid)
    assert flown.grounded_ticks > 0  # the last yo, without a stop, reaches the floor
    depth = flown.columns["depth_m"]
    bottom = floor.depth_along(flown.columns["time_s"])
    assert (depth <= bottom).all()
    survey = flown.columns["state"] == 0
    # every dive of the survey turned at its stop: 4 m above the floor, never at 50 m
    assert (depth[survey] < bottom[survey] - 2.0).all()


@pytest.mark.parametrize("rigid", [False, True], ids=["calibrated", "rigid"])
@pytest.mark.parametrize(("name", "ocean", "floor"), [
    ("examples/thermocline_survey.mission", "sea-trial", None),
    ("examples/fig2_annotated.mission", "bench", None),
    ("tests/missions/sim_altimeter.mission", "sea-trial", flat_floor(38.0))])
def test_the_c_flight_flies_the_water_s_density_as_the_reference(name, ocean, floor,
                                                                       rigid):
    # the water's in-situ density at each depth (sim --ocean): a rigid hull's speed then
    # changes with depth too
    from gliderplan.sim.ocean import density_profile_of, load_water
    from gliderplan.sim.setup import flown_water

    mission = check_file(str(REPO / name)).mission
    vehicle = load_vehicle(mission.vehicle)
    if rigid:
        vehicle = replace(vehicle, flight=replace(vehicle.flight, compressibility_per_pa=0.0))
    given = load_water(ocean, floor)
    ballasted, density, _ = flown_water(mission, vehicle, given, ocean)
    assert np.ptp(density_profile_of(given.ocean, np.arange(0.0, 60.0)).rho_kg_m3) > 1.0
    config = RunConfig(duration_s=min(86400.0, mission.horizon_s or 86400.0), seed=9,
                       noise=NOISE_PRESETS["ctd"], floor=floor, water=density)
    flown = flown_alike(mission, config, given.ocean, vehicle=ballasted)
    uniform = fly(mission, given.ocean, replace(config, water=None), ballasted)
    assert not np.array_equal(flown.columns["depth_m"], uniform.columns["depth_m"][
        :len(flown.columns["depth_m"])])  # the density changes the flight


# Random missions: three states (a start state that calls one and goes to the other),
# every profile and route the simulator flies, conditions on time, depth, temperature,
# position, the runtime's readings (the yo's leg, the distance to the waypoint, the
# waypoints reached), the clock and variables, assignments; flown in random water with
# random noise. Bands from the shallow glider's thinnest (its envelope's 3 m).
_PROFILES = st.one_of(
    st.builds(lambda lo, band, p, q: f"yo({lo}, {lo + band}, {p}, {q})",
              st.integers(0, 8), st.integers(3, 50), st.sampled_from([".3", ".454", ".6"]),
              st.sampled_from([".3", ".454", ".6"])),
    st.builds(lambda lo, band, stop: f"yo({lo}, {lo + band}, .454, .454, {stop})",
              st.integers(0, 8), st.integers(3, 50), st.sampled_from(["0", "2", "4.5", "top"])),
    st.just("yo(top, bottom, .454, .454)"),
    st.just("surface"),
    st.builds(lambda d: f"hover({d})", st.integers(0, 20)),
    st.builds(lambda lo, hi, t: f"thermotrackyo({lo}, {hi}, .454, .454, {t}, 6)",
              st.integers(1, 5), st.integers(20, 60), st.integers(1, 6)),
    st.builds(lambda lo, hi, stop: f"thermotrackyo({lo}, {hi}, .454, .454, 2, 6, {stop})",
              st.integers(1, 5), st.integers(20, 60), st.sampled_from(["3", "top"])),
)
_ROUTES = st.sampled_from([
    "noheading", "nav(3910.5, -7349.8058)", "nav(3910.2, -7349.9)",
    "waypoints((3910.5, -7349.8), (3910.1, -7349.2), (3909.8, -7350.0))",
    "sweep(150, (3910.0, -7350.0), (3910.0, -7349.6), (3910.3, -7349.6))",
    "goto_list(120, (3910.5, -7349.8), (3910.1, -7349.6))",
])
_CONDITIONS = st.sampled_from([
    "missiontime >= {t}", "depth > {d}", "depth < {d} && missiontime > 300",
    "temp < {c}", "temp > {c} || depth > 30", "missiontime >= a", "depth > b",
    "lat < 3910.3", "lon > -7349.7", "!(depth < {d}) && temp < {c}",
    "abs(depth - b) < 1", "max(temp, 0) > {c} && missiontime >= {t}",
    "halfcycle >= {h}", "halfcycle == {h} && depth >= {d}", "wptdist < {w}",
    "mod(timeofday, 3600) >= {t} && mod(timeofday, 3600) < {t} + 60",
    "wptreached >= {n}", "wptreached > b - 10 && depth > {d}", "altitude < {d}",
])
_ASSIGNMENTS = st.sampled_from([
    "", "set a = missiontime + {t} ", "set b = depth + 3 ", "set top = max(depth - 5, 1), "
    "bottom = depth + 5 ", "set a = missiontime + 600, b = b + 1 ", "set b = wptreached + 10 ",
])


@st.composite
def random_missions(draw) -> str:
    def condition() -> str:
        return draw(_CONDITIONS).format(t=draw(st.integers(60, 9000)),
                                        d=draw(st.integers(1, 40)),
                                        c=draw(st.integers(8, 23)),
                                        h=draw(st.integers(1, 12)),
                                        w=draw(st.integers(100, 900)),
                                        n=draw(st.integers(1, 4)))

    def assignment() -> str:
        return draw(_ASSIGNMENTS).format(t=draw(st.integers(60, 3600)))

    end = draw(st.integers(1800, 10800))
    states = []
    for name, events in (
            ("s0", [f"case {condition()} {assignment()}call s1",
                    f"case {condition()} {assignment()}goto s2",
                    f"case {condition()} {assignment() or 'set a = a + 1 '}"]),
            ("s1", [f"case {condition()} {assignment()}return"]),
            ("s2", [f"case {condition()} {assignment()}goto s0"])):
        profiles = " | ".join(draw(st.lists(_PROFILES, min_size=1, max_size=2)))
        duty = draw(st.sampled_from(["", " duty auto"]))
        states.append(
            f"state {name}\nbegin\n  flightroute {draw(_ROUTES)}\n"
            f"  flightprofile {profiles}\n"
            f"  sensors missiontime, depth, pitch, lat, lon, temp{duty}, oxygen{duty}\n"
            f"  events\n    case missiontime >= {end} exit\n    "
            + "\n    ".join(events) + "\nend\n")
    return ("mission random\nvar a = 900\nvar b = 10\nvar top = 4\nvar bottom = 25\n"
            + "\n".join(states))


# a return on the tick the pump's energy guard ends the mission: both are in the trace
_RETURN_AS_THE_PUMP_GUARD_ENDS = (
    'mission random\n'
    'var a = 900\n'
    'var b = 10\n'
    'var top = 4\n'
    'var bottom = 25\n'
    'state s0\n'
    'begin\n'
    '  flightroute noheading\n'
    '  flightprofile yo(0, 3, .3, .3)\n'
    '  sensors missiontime, depth, pitch, lat, lon, temp, oxygen\n'
    '  events\n'
    '    case missiontime >= 1800 exit\n'
    '    case missiontime >= 60 call s1\n'
    '    case missiontime >= 60 goto s2\n'
    '    case missiontime >= 60 set a = a + 1 \n'
    'end\n'
    '\n'
    'state s1\n'
    'begin\n'
    '  flightroute noheading\n'
    '  flightprofile yo(0, 4, .3, .3)\n'
    '  sensors missiontime, depth, pitch, lat, lon, temp, oxygen\n'
    '  events\n'
    '    case missiontime >= 1800 exit\n'
    '    case missiontime >= 60 return\n'
    'end\n'
    '\n'
    'state s2\n'
    'begin\n'
    '  flightroute noheading\n'
    '  flightprofile yo(top, bottom, .454, .454)\n'
    '  sensors missiontime, depth, pitch, lat, lon, temp, oxygen\n'
    '  events\n'
    '    case missiontime >= 1800 exit\n'
    '    case missiontime >= 60 goto s0\n'
    'end\n')
_SURFACED_ON_THE_RUN_S_LAST_TICK = (  # a return on the tick the climb surfaces
    "mission random\nstate s0\nbegin\n  flightroute noheading\n  flightprofile yo(0, 10, .3, .3)\n"
    "  sensors missiontime, depth\n  events\n    case missiontime >= 1800 exit\n"
    "    case depth > 10 call s1\nend\nstate s1\nbegin\n  flightroute noheading\n"
    "  flightprofile surface\n  sensors missiontime, depth\n  events\n"
    "    case missiontime >= 253 return\nend\n")


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(source=random_missions(), ocean=st.sampled_from(["bench", "sea-trial", "uniform"]),
       noise=st.sampled_from(["none", "ctd", "nonmonotonic"]),
       current=st.tuples(st.sampled_from([0.0, 0.05, -0.12]), st.sampled_from([0.0, 0.07])),
       seed=st.integers(0, 2**31), tick_s=st.sampled_from([4.0, 2.0, 3.7]),
       start_s=st.floats(9e8, 2e9), rigid=st.booleans(),
       floor=st.sampled_from([None, 12.0, 30.0, 55.0]))
@example(source=_RETURN_AS_THE_PUMP_GUARD_ENDS, ocean="bench", noise="none",
         current=(0.0, 0.0), seed=0, tick_s=4.0, start_s=9e8, rigid=False, floor=None)
@example(source=_SURFACED_ON_THE_RUN_S_LAST_TICK, ocean="bench", noise="none",
         current=(0.0, 0.0), seed=0, tick_s=4.0, start_s=9e8, rigid=True, floor=None)
def test_the_c_flight_flies_random_missions_as_the_reference(source, ocean, noise,
                                                                  current, seed, tick_s,
                                                                  start_s, rigid, floor):
    result = check_source(source, "random.mission")
    assert result.mission is not None, result.render()
    config = RunConfig(tick_s=tick_s, duration_s=12000.0, seed=seed,
                       noise=NOISE_PRESETS[noise], current=Current(*current),
                       start_epoch_s=start_s, floor=None if floor is None else flat_floor(floor))
    flown_alike(result.mission, config, ocean, rigid=rigid)


def test_the_c_flight_flies_the_shore_s_updates_as_the_reference(tmp_path):
    """With the shore in the loop the C flight stops at each surfacing for its report and
    replan, and flies the updates the runtime applies from the next tick: the same flight,
    reports and updates as the reference's."""
    from gliderplan.planner import make_plan
    from gliderplan.planner.planfile import read_plan_bytes
    from gliderplan.sim.replanning import ShoreLoop
    from gliderplan.sim.scenarios import read_spec

    mission = check_file(str(REPO / "tests" / "missions" / "replan_short.mission")).mission
    key = bytes(range(32))
    key_file = tmp_path / "vehicle.key"
    key_file.write_text(key.hex() + "\n")
    key_file.chmod(0o600)
    make_plan(mission, output=tmp_path / "held.plan", sign=key_file, seq=5)
    held = (tmp_path / "held.plan").read_bytes()
    config = RunConfig(duration_s=86400.0, seed=3, noise=NOISE_PRESETS["ctd"])
    shores = []

    def shore():  # a truth hungrier than the model: the replans change the plan
        shores.append(ShoreLoop(mission, held, key, tick_s=config.tick_s, usable_truth=0.9,
                                seed=5, spec=read_spec()))
        return shores[-1]

    flown = flown_alike(mission, config, plan=read_plan_bytes(held, mission), shore=shore)
    assert flown.surfacings == shores[1].log.surfacings >= 6
    assert shores[1].log.applied >= 2


# (mission, scenario, days): the survey's whole flight; 10 days of the month's scenario 1
# cross the end of a block of random numbers (the spikes' stream)
MONTE_CARLO_CASES = [("thermocline_survey.mission", 0, 1.5), ("thermocline_survey.mission", 1, 1.5),
                     ("survey_month.mission", 1, 10.0)]


@pytest.mark.parametrize(("name", "index", "days"), MONTE_CARLO_CASES)
def test_the_c_flight_flies_monte_carlo_scenarios_as_the_reference(name, index, days):
    # the scenarios' own water (an internal wave), noise (spikes), current and vehicle
    from gliderplan.sim.montecarlo import Job, scenario_seed
    from gliderplan.sim.scenarios import draw_scenario, read_spec

    mission = check_file(str(REPO / "examples" / name)).mission
    from gliderplan.sim.setup import FlightOptions, flight_setup

    job = Job(flight_setup(mission, FlightOptions(duration_s=days * 86400.0)), read_spec())
    scenario = draw_scenario(job.spec, job.setup.vehicle, index, scenario_seed(job, index))
    config = RunConfig(duration_s=days * 86400.0, seed=scenario.seed, noise=scenario.noise,
                       current=scenario.current)
    flown_alike(mission, config, scenario.ocean, vehicle=scenario.vehicle)
