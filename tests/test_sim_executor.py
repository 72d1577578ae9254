"""The Python executor: compiled conditions agree with the reference semantics, sensor
values pass through binary32, the plan's schedule and routes follow docs/pilot.md, and
plan files are read strictly."""

from __future__ import annotations

import math
import zlib
from pathlib import Path

import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from gliderplan.cli.main import main
from gliderplan.contract import FLIGHT_SENSORS_MASK, NO_STATE
from gliderplan.language import check_file, check_source, ir
from gliderplan.language.registry import SENSORS
from gliderplan.planner.planfile import PlanFileError, read_plan_bytes
from gliderplan.power_models import load_vehicle
from gliderplan.sim import compiled, pilot
from gliderplan.sim.executor import PythonRuntime
from gliderplan.sim.geo import ddmm_to_degrees, offset_m
from gliderplan.sim.science import powered_mask

REPO = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((REPO / "examples").glob("*.mission")) + sorted(
    (REPO / "tests" / "missions").glob("sim_*.mission"))
ALL_ON = (1 << len(SENSORS)) - 1


def mission_from(text: str) -> ir.CheckedMission:
    result = check_source(text, "test.mission")
    assert result.mission is not None, result.render()
    return result.mission


def readings(**values: float) -> list[float]:
    array = [math.nan] * len(SENSORS)
    for name, value in values.items():
        array[[s.name for s in SENSORS].index(name)] = value
    return array


sensor_values = st.one_of(st.floats(-50, 3000, allow_nan=False), st.just(math.nan),
                          st.sampled_from([0.0, 500.0, 1500.0, 2000.0, 2500.0]))


@pytest.mark.parametrize("path", EXAMPLES, ids=lambda p: p.name)
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_compiled_event_checks_agree_with_the_reference_semantics(path, data):
    mission = check_file(str(path)).mission
    s = data.draw(st.lists(sensor_values, min_size=len(SENSORS), max_size=len(SENSORS)))
    v = {var.name: data.draw(sensor_values) for var in mission.variables}
    named = {info.name: s[info.index] for info in SENSORS}
    for state in mission.states:
        expected = next((i for i, e in enumerate(state.events)
                         if ir.evaluate(e.condition, named, v) != 0.0), -1)
        assert compiled.event_checker(state)(s, v) == expected
        for profile in state.profiles:
            got = compiled.arguments(profile)(s, v)
            want = tuple(ir.evaluate(a, named, v) for a in profile.args)
            assert [repr(x) for x in got] == [repr(float(x)) for x in want]


def test_sensor_values_reach_conditions_as_binary32():
    mission = mission_from("""mission f32
state a
begin
  flightroute noheading
  flightprofile hover(5)
  sensors missiontime, depth
  events
    case depth >= 10.1 exit
end
""")
    # 10.09999995 < 10.1 in double, but the link rounds it to binary32 10.1000004
    executor = PythonRuntime(mission, None, 200.0)
    command = executor.step(0, FLIGHT_SENSORS_MASK, readings(missiontime=0.0, depth=10.09999995))
    assert command.transition == 5 and command.state == NO_STATE


def test_a_sensor_not_sent_keeps_its_last_value():
    mission = mission_from("""mission stale
state a
begin
  flightroute noheading
  flightprofile hover(5)
  sensors missiontime, depth, temp
  events
    case temp < 10 exit
end
""")
    executor = PythonRuntime(mission, None, 200.0)
    mask = powered_mask(ALL_ON)
    assert executor.step(0, mask, readings(missiontime=0, depth=1, temp=15.0)).transition == 1
    # the CTD is off this tick: its old 15 C stands, the new 5 C is not seen
    assert executor.step(1, FLIGHT_SENSORS_MASK, readings(missiontime=4, temp=5.0)).transition == 0
    assert executor.step(2, mask, readings(missiontime=8, temp=5.0)).transition == 5


def test_each_condition_is_evaluated_once_per_tick(monkeypatch):
    """The compiled checker finds the event; firing it evaluates no condition again
    (only the assignment's value, through the reference semantics)."""
    mission = mission_from("""mission once
var bottom = 20
state a begin flightroute noheading flightprofile hover(5) sensors missiontime, depth
  events
    case depth > bottom set bottom = depth + 2
    case missiontime >= 8 exit
end
""")
    conditions = {id(e.condition) for s in mission.states for e in s.events}
    evaluated = []
    reference = ir.evaluate

    def spy(expr, sensors, variables):
        evaluated.append(id(expr))
        return reference(expr, sensors, variables)

    monkeypatch.setattr(ir, "evaluate", spy)
    executor = PythonRuntime(mission, None, 200.0)
    kinds = [executor.step(t, FLIGHT_SENSORS_MASK, readings(missiontime=4.0 * t, depth=21.0 + t))
             .transition for t in range(3)]
    assert kinds == [1, 0, 5]  # start; the assignment fired at 4 s; exit at 8 s
    assert executor.machine.variables == {"bottom": 23.0}  # 21 + 2 at tick 0, then 22 < 23
    assert evaluated and not conditions & set(evaluated)


PLAN_MISSION = """mission planned
state a
begin
  flightroute noheading
  flightprofile yo(2, 10, .454, .454) | hover(5)
  sensors missiontime, depth, temp duty auto, oxygen duty auto
  events
    case missiontime >= 100000 exit
end
"""


def plan_text(mission: ir.CheckedMission, body: str, *, crc: str | None = None) -> bytes:
    head = (f"GPPLAN 3\nmission {mission.name}\nhash {mission.hash}\ncomputer ts7800 300\n"
            "budget_j 180000\npredicted_j 9876.5\ncomponents hotel\nassumptions 0\n"
            f"states 1\n{body}")
    data = head.encode()
    return data + f"crc32 {crc or format(zlib.crc32(data), '08x')}\n".encode()


GOOD_BLOCK = ("state a 300 600 2 2\npredict 100000 1 800\nenergy 9876.5\n"
              "sensor temp 60 15\nsensor oxygen 100 100\n"
              "profile 0 0.75 0.4 150 0.3\nprofile 1 0.25 0.454 230 0.31\nend\n")


def test_the_plan_schedule_powers_sensors_and_alternates_profiles():
    mission = mission_from(PLAN_MISSION)
    plan = read_plan_bytes(plan_text(mission, GOOD_BLOCK), mission, "p.plan")
    executor = PythonRuntime(mission, plan, 200.0)
    temp_bit, oxygen_bit = 1 << 9, 1 << 12
    seen = {}
    for tick, t in enumerate([0.0, 14.0, 16.0, 61.0, 449.0, 450.0, 599.0, 600.0]):
        command = executor.step(tick, powered_mask(ALL_ON),
                                readings(missiontime=t, depth=3.0, temp=15.0, lat=0, lon=0))
        seen[t] = command
    assert [bool(seen[t].sensor_power & temp_bit) for t in (0.0, 14.0, 16.0, 61.0)] == \
        [True, True, False, True]
    assert all(c.sensor_power & oxygen_bit for c in seen.values())  # ON_S = PERIOD_S
    assert [seen[t].profile for t in (0.0, 449.0, 450.0, 599.0, 600.0)] == [0, 0, 1, 1, 0]
    assert seen[0.0].pitch_rad == pytest.approx(-0.4)  # the plan's pitch, diving
    assert seen[0.0].ballast_cc == -150.0
    assert seen[450.0].pitch_rad == 0.0 and seen[450.0].depth_target_m == 5.0  # hover


def test_without_a_plan_every_logged_sensor_is_on_and_the_default_ballast_flies():
    mission = mission_from(PLAN_MISSION)
    ballast_cc = load_vehicle(mission.vehicle).unplanned_ballast_cc
    executor = PythonRuntime(mission, None, ballast_cc)
    command = executor.step(0, powered_mask(0), readings(missiontime=0.0, depth=0.0))
    logged = sum(1 << i for i in (0, 1, 9, 12))
    assert command.sensor_power == logged
    assert command.ballast_cc == -ballast_cc == -233.0
    assert command.profile == 0


def resealed(data: bytes) -> bytes:
    """`data` with its checksum recomputed, so that a reader gets past the checksum."""
    body = data[: data.rindex(b"crc32 ")]
    return body + f"crc32 {zlib.crc32(body):08x}\n".encode()


@pytest.mark.parametrize("mutate, line, message", [
    (lambda d: d.replace(b"hash ", b"hash 0"), 3, "hash"),
    (lambda d: d.replace(b"state a 300 600 2 2", b"state a 300 600 2 1")
     .replace(b"profile 1 0.25 0.454 230 0.31\n", b"")
     .replace(b"profile 0 0.75", b"profile 0 1"), 10, "1 profiles, the mission's state has 2"),
    (lambda d: d.replace(b"sensor oxygen", b"sensor salinity"), 14,
     "sensor 'salinity' is not logged by the state"),
    (lambda d: d.replace(b"sensor temp 60 15\nsensor oxygen 100 100",
                         b"sensor oxygen 100 100\nsensor temp 60 15"), 14,
     "out of the state's order"),
])
def test_a_plan_that_does_not_fit_the_mission_is_rejected_naming_the_line(mutate, line, message):
    mission = mission_from(PLAN_MISSION)
    with pytest.raises(PlanFileError) as err:
        read_plan_bytes(resealed(mutate(plan_text(mission, GOOD_BLOCK))), mission, "p.plan")
    assert str(err.value).startswith(f"p.plan:{line}:") and message in str(err.value)


def test_a_plan_with_a_wrong_checksum_is_rejected():
    mission = mission_from(PLAN_MISSION)
    with pytest.raises(PlanFileError, match=r"p.plan:18: checksum mismatch"):
        read_plan_bytes(plan_text(mission, GOOD_BLOCK, crc="00000000"), mission, "p.plan")


def test_sweep_flies_east_west_lines_across_the_hull_alternating():
    corners = ((3910.0, -7350.0), (3910.0, -7349.0), (3911.0, -7349.0), (3911.0, -7350.0))
    points = pilot.sweep_waypoints(200.0, corners)
    lat0, lon0 = ddmm_to_degrees(3910.0), ddmm_to_degrees(-7350.0)
    local = [offset_m(lat0, lon0, lat, lon) for lat, lon in points]  # (north, east)
    height = offset_m(lat0, lon0, ddmm_to_degrees(3911.0), lon0)[0]  # one minute: ~1853 m
    width = offset_m(lat0, lon0, lat0, ddmm_to_degrees(-7349.0))[1]
    assert len(points) == 2 * int((height - 100.0) // 200.0 + 1)
    assert local[0][0] == pytest.approx(100.0)
    assert local[2][0] - local[0][0] == pytest.approx(200.0)
    for line in range(len(points) // 2):
        west_to_east = line % 2 == 0
        a, b = local[2 * line], local[2 * line + 1]
        assert a[0] == pytest.approx(b[0])  # east-west
        assert (a[1], b[1]) == (pytest.approx(0.0 if west_to_east else width, abs=1e-6),
                                pytest.approx(width if west_to_east else 0.0, abs=1e-6))


def test_waypoints_advance_within_50_m_and_heading_points_at_the_next():
    route = pilot.Waypoints((), ((3910.0, -7350.0), (3911.0, -7350.0)))
    heading, valid = route.heading(3909.0, -7350.0)  # south of both: head north
    assert valid and heading == pytest.approx(0.0) and route.k == 0
    route.heading(3910.0, -7350.0 + 0.0001)  # at the first point: on to the second
    assert route.k == 1
    heading, _ = route.heading(3912.0, -7350.0)  # past the last: turn back south
    assert heading == pytest.approx(math.pi)


def test_the_waypoints_reached_count_each_arrival_and_the_lists_last_once():
    route = pilot.Waypoints((), ((3910.0, -7350.0), (3911.0, -7350.0)))
    counts = []
    for lat in (3909.0, 3910.0, 3910.5, 3911.0, 3911.01, 3912.0, 3911.0):
        route.heading(lat, -7350.0)
        counts.append((route.k, route.reached))
    # the first reached and left behind; the last reached once, however often it is
    # passed again (the route holds the heading to it)
    assert counts == [(0, 0), (1, 1), (1, 1), (1, 2), (1, 2), (1, 2), (1, 2)]
    laps = pilot.GotoList((200.0,), ((3910.0, -7350.0), (3911.0, -7350.0)))
    for lat in (3910.0, 3911.0, 3910.0, 3911.0, 3910.0):
        laps.heading(lat, -7350.0)
    assert (laps.k, laps.reached) == (1, 5)  # a goto list counts on, lap after lap
    nav = pilot.Nav((3910.0, -7350.0), ())
    nav.heading(3910.0, -7350.0)  # on its point: a heading, never a waypoint reached
    assert nav.reached == 0 and pilot.NoHeading((), ()).reached == 0


def test_a_return_resumes_the_callers_waypoints_reached(tmp_path):
    """tests/missions/sim_waypoints_reached.mission: the transect surfaces once at each of
    its first two waypoints (a count that restarted after the surfacing's return would
    never reach the third), leaves at its third, and the goto list after two laps."""
    path = REPO / "tests" / "missions" / "sim_waypoints_reached.mission"
    assert main(["sim", str(path), "-o", str(tmp_path)]) == 0
    trace = pd.read_csv(tmp_path / "trace.csv")
    moves = list(zip(trace["kind"], trace["from_state"].fillna(""),
                     trace["to_state"].fillna(""), strict=True))
    assert moves == [("start", "", "transect"), ("call", "transect", "fix"),
                     ("return", "fix", "transect"), ("call", "transect", "fix"),
                     ("return", "fix", "transect"), ("goto", "transect", "laps"),
                     ("goto", "laps", "home"), ("exit", "home", "")]
    table = pd.read_parquet(tmp_path / "timeseries.parquet").set_index("time_s")
    mission = check_file(str(path)).mission
    transect, laps = mission.states[0].route.points, mission.states[2].route.points
    # each fired on the tick after the one its waypoint came within reach (50 m; 100 m for
    # the goto list), the glider having moved on by one tick's glide
    arrivals = [(t, p, 50.0) for t, p in zip(trace["time_s"][[1, 3, 5]], transect,
                                            strict=True)]
    arrivals.append((trace["time_s"][6], laps[1], 100.0))  # the fourth: two laps
    for time_s, (lat, lon), radius in arrivals:
        row = table.loc[time_s - 4.0]
        north, east = offset_m(row["lat_deg"], row["lon_deg"], ddmm_to_degrees(lat),
                               ddmm_to_degrees(lon))
        assert math.hypot(north, east) <= radius + 5.0



def test_a_goto_list_loops_and_counts_waypoints_reached_within_its_radius():
    route = pilot.GotoList((200.0,), ((3910.0, -7350.0), (3911.0, -7350.0)))
    assert route.distance_m(3909.0, -7350.0) == pytest.approx(1853.2, abs=1.0)
    route.heading(3910.1, -7350.0)  # 185 m from the first: within 200 m
    assert route.k == 1
    route.heading(3911.0, -7350.0)
    assert route.k == 0  # the list starts again
    assert math.isnan(route.distance_m(math.nan, -7350.0))
    assert math.isnan(pilot.NoHeading((), ()).distance_m(3910.0, -7350.0))


def test_a_yo_counts_its_half_cycles():
    yo = pilot.Yo(0.0, (3.0, 20.0, 0.4, 0.4))
    legs = []
    for depth in (0, 10, 20, 10, 3, 10, 20, 5, 3):
        yo.command(depth, math.nan, (3.0, 20.0, 0.4, 0.4), None, 200.0)
        legs.append(yo.halfcycle)
    assert legs == [1, 1, 2, 2, 3, 3, 4, 4, 5]


@pytest.mark.parametrize("routine", ["yo", "thermotrackyo"])
def test_a_dive_turns_at_the_altimeter_stop_as_the_c_runtime_s_test_has_it(routine):
    # the rows of runtime/tests/test_pilot.c, test_yo_should_turn_a_dive_at_its_altimeter_stop
    args = (3.0, 50.0, 0.4, 0.5, 4.0) if routine == "yo" else \
        (3.0, 50.0, 0.4, 0.5, 30.0, 6.0, 4.0)
    yo = pilot.PROFILE_ROUTINES[routine](3.0, args, altitude_m=40.0)
    flown = []
    for depth, altitude in ((3.0, 40.0), (30.0, math.nan), (35.0, 4.01), (35.5, 4.0),
                            (33.0, 2.0), (3.0, 40.0), (20.0, 3.0)):
        target = yo.command(depth, math.nan, args, None, 230.0, altitude)[0]
        flown.append((target, yo.halfcycle))
    assert flown == [(50, 1), (50, 1), (50, 1), (3, 2), (3, 2), (50, 3), (3, 4)]
    assert pilot.PROFILE_ROUTINES[routine](20.0, args, altitude_m=2.0).leg == pilot.CLIMB
    unstopped = args[:-1] + (0.0,)  # 0: no altimeter stop; left out, alike
    for stop in (unstopped, args[:-1]):
        yo = pilot.PROFILE_ROUTINES[routine](20.0, stop, altitude_m=0.5)
        yo.command(20.0, math.nan, stop, None, 230.0, 0.5)
        assert yo.leg == pilot.DIVE


GOTO_LIST = REPO / "tests" / "missions" / "sim_goto_list.mission"


def test_a_surfacing_call_resumes_the_waypoint_and_the_yo_count_restarts(tmp_path):
    assert main(["sim", str(GOTO_LIST), "-o", str(tmp_path)]) == 0
    table = pd.read_parquet(tmp_path / "timeseries.parquet")
    route = check_file(str(GOTO_LIST)).mission.states[0].route
    radius_m = route.params[0]
    reached = []  # (time, waypoint) of each arrival within the list's radius
    for k, (lat, lon) in enumerate(route.points):
        near = [math.hypot(*offset_m(a, b, ddmm_to_degrees(lat), ddmm_to_degrees(lon)))
                <= radius_m for a, b in zip(table["lat_deg"], table["lon_deg"], strict=True)]
        starts = [t for t, now, before in zip(table["time_s"][1:], near[1:], near[:-1],
                                                strict=True) if now and not before]
        reached += [(t, k) for t in starts]
    order = [k for _, k in sorted(reached)]
    assert order[:4] == [0, 1, 2, 0]  # in order, looping, across the surfacings
    # between two surfacings, four half cycles: two dives to 20 m
    surfacing = (table["state"] == "surface").to_numpy()
    starts = [i for i in range(1, len(table)) if surfacing[i] and not surfacing[i - 1]]
    assert len(starts) >= 20
    for a, b in zip(starts[1:], starts[2:], strict=False):
        depth = table["depth_m"].to_numpy()[a:b]
        bottoms = sum(1 for i in range(1, len(depth) - 1)
                      if depth[i] >= 19.5 and depth[i] >= depth[i - 1] and depth[i] > depth[i + 1])
        assert bottoms == 2


def test_the_clock_reads_utc_time_of_day_from_the_runs_start(tmp_path):
    mission = REPO / "tests" / "missions" / "sim_clock.mission"
    assert main(["sim", str(mission), "--start", "2024-06-01T06:10:00Z", "-o",
                 str(tmp_path)]) == 0
    calls = [line for line in (tmp_path / "trace.csv").read_text().splitlines()
             if ",call," in line or ",return," in line]
    # half past every hour (06:30 is 1200 s after 06:10), back under at 35 past
    assert calls[:4] == ["1200,call,dive,up,1", "1500,return,up,dive,0",
                         "4800,call,dive,up,1", "5100,return,up,dive,0"]
    assert ir._fmod(-7.0, 3.0) == -1.0 and math.isnan(ir._fmod(1.0, 0.0))
    assert math.isnan(ir._fmod(math.inf, 2.0)) and ir._fmod(5.0, math.inf) == 5.0
