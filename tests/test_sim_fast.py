"""The pieces of the fast executor that compute a run of ticks at once give, element by
element, the very numbers the tick-by-tick reference computes one tick at a time."""

from __future__ import annotations

import math
import struct
from dataclasses import replace
from pathlib import Path

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st

from gliderplan.language import check_file, ir
from gliderplan.power_models import load_vehicle
from gliderplan.sim import compiled, geo, native, ocean, pilot
from gliderplan.sim.flight import fly
from gliderplan.sim.loop import RunConfig
from gliderplan.sim.science import Draws
from gliderplan.sim.vehicle import Current, GliderSim

REPO = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((REPO / "examples").glob("*.mission")) + sorted(
    (REPO / "tests" / "missions").glob("sim_*.mission"))
finite = st.floats(-1e4, 1e4, allow_nan=False)


def same_bits(a: np.ndarray, b) -> bool:
    b = np.asarray(b, dtype=np.float64)
    return a.shape == b.shape and np.array_equal(a.view(np.int64), b.view(np.int64))


@settings(max_examples=50, deadline=None)
@given(st.lists(finite, min_size=1, max_size=50), st.lists(finite, min_size=1, max_size=50))
def test_the_c_library_s_functions_over_arrays_are_math_s(xs, ys):
    x = np.array(xs)
    y = np.resize(np.array(ys), len(x))
    for name in ("sin", "cos", "tanh"):
        assert same_bits(getattr(native, name)(x), [getattr(math, name)(v) for v in xs]), name
    assert same_bits(native.atan2(y, x), [math.atan2(a, b) for a, b in zip(y, x, strict=True)])


@settings(max_examples=60, deadline=None)
@given(st.floats(-60, 60), st.floats(-170, 170), st.floats(-0.05, 0.05), st.floats(-0.05, 0.05),
       st.lists(st.floats(0.0, 400.0), min_size=1, max_size=120), st.integers(-1, 130),
       st.sampled_from([(0.0, 0.0), (0.3, -0.2), (0.0, 1.5)]), st.booleans(),
       st.sampled_from([10.0, 50.0, 2000.0]))
@example(39.17, -73.82, 0.0004, 0.0, [1.2] * 80, -1, (0.0, 0.0), True, 50.0).via(
    "a waypoint 44 m north: reached on the first tick")
def test_the_route_over_a_run_is_the_route_steered_tick_by_tick(
        lat, lon, dlat, dlon, distance, fix_at, current, advance, radius):
    """native.route against the runtime's route and the glider's drift, a tick at a time:
    the same headings and positions bit for bit, and the same tick reaching the waypoint."""
    pack = struct.Struct("<f")

    def f32(x: float) -> float:
        return pack.unpack(pack.pack(x))[0]

    target = (lat + dlat, lon + dlon)
    route = pilot.Waypoints((), ((geo.degrees_to_ddmm(target[0]),
                                  geo.degrees_to_ddmm(target[1])),) * (2 if advance else 1))
    route.radius_m = radius
    glider = GliderSim(load_vehicle("slocum_g2_shallow"), 4.0, lat, lon, Current(*current))
    glider.lat_deg, glider.lon_deg = lat + 0.001, lon - 0.002  # drifted from dead reckoning
    start = glider.positions
    headings, positions, reached = [], [start], len(distance)
    for j, metres in enumerate(distance):
        heading = f32(route.heading(f32(geo.degrees_to_ddmm(glider.dr_lat_deg)),
                                    f32(geo.degrees_to_ddmm(glider.dr_lon_deg)))[0])
        if route.k != 0:
            reached = j
            break
        headings.append(heading)
        glider.heading_rad = heading
        if j == fix_at:
            glider.dr_lat_deg, glider.dr_lon_deg = glider.lat_deg, glider.lon_deg
        glider._drift(metres, 4.0)
        positions.append(glider.positions)
    flown, heading, track = native.route(route.points[0], radius, advance, np.array(distance),
                                         fix_at, 4.0, current, start)
    # a tick within a billionth of the radius of it is left to the route itself
    assert flown == reached or (flown < reached and abs(math.hypot(*geo.offset_m(
        geo.ddmm_to_degrees(f32(geo.degrees_to_ddmm(positions[flown][0]))),
        geo.ddmm_to_degrees(f32(geo.degrees_to_ddmm(positions[flown][1]))),
        *target)) - radius) <= 1e-9 * radius)
    assert same_bits(heading[:flown], headings[:flown])
    assert same_bits(track[:, :flown + 1].T, positions[:flown + 1])


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-180, 180), min_size=1, max_size=30))
def test_position_readings_over_arrays_are_geo_s(degrees):
    assert same_bits(geo.degrees_to_ddmm_array(np.array(degrees)),
                     [geo.degrees_to_ddmm(v) for v in degrees])


@settings(max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1), st.sampled_from([(5.0, 20.0), (3.0, 60.0), (8.0, 30.5)]),
       st.floats(0.0, 0.3))
def test_a_compressible_hull_s_yo_is_the_glider_stepped_under_the_yo_routine(seed, band, sigma):
    """native.squeezed_yo against the glider stepped a tick at a time under the runtime's
    yo, deciding each turn on the depth reading as the link carries it (binary32): the
    same depths bit for bit and the same turns, among them turns only that rounding
    decides (a reading 1e-7 m short of the edge, which binary32 rounds onto it)."""
    from gliderplan.sim.fast import _command_f32, squeezed_rows

    vehicle = load_vehicle("slocum_g2_shallow")
    flight = vehicle.flight
    assert flight.compressibility_per_pa > 0.0  # the calibrated hull is squeezed
    low, high = band
    args, ticks = (low, high, 0.454, 0.454), 600
    pack = struct.Struct("<f")
    rng = np.random.default_rng(seed)
    noise = sigma * rng.standard_normal(ticks + 1)
    glider = GliderSim(vehicle, 4.0, 39.0, -73.0, depth_m=low + 1.0)
    start, actuators = glider.depth_m, glider.actuators
    yo = pilot.Yo(glider.depth_m, args)
    depths, legs, near_edge = [start], [], 0
    for t in range(ticks):
        if abs(glider.depth_m - high) < 1.0 and rng.random() < 0.3:  # 1e-7 m short of it
            noise[t] = (high - 1e-7) - glider.depth_m
            near_edge += 1
        reading = pack.unpack(pack.pack(max(0.0, glider.depth_m + noise[t])))[0]
        target, pitch, ballast, _ = yo.command(reading, math.nan, args, None, 200.0)
        glider.step(target, *_command_f32(pitch, ballast), 0.0, False, False)
        depths.append(glider.depth_m)
        legs.append(yo.leg)
    commands = {leg: _command_f32(*pilot._yo_command(leg, low, high, args, None, 200.0)[1:3])
                for leg in (pilot.DIVE, pilot.CLIMB)}
    first = glider.glide_from(actuators, *commands[legs[0]])
    second = glider.glide_from(first.actuators[first.settled], *commands[1 - legs[0]])
    third = glider.glide_from(second.actuators[second.settled], *commands[legs[0]])
    assert third.actuators[third.settled] == first.actuators[first.settled]
    reach = float(np.abs(noise).max()) + 1.0  # no reading reaches an edge from beyond this
    flown, native_depths, stop = native.squeezed_yo(
        [(squeezed_rows(g, flight.trim_cc), g.settled) for g in (first, second, third)],
        flight.rho_kg_m3 * flight.g_m_s2, flight.hull_volume_cc * flight.compressibility_per_pa,
        noise, (low + reach, high - reach), (low, high), legs[0] == pilot.DIVE, ticks, start)
    turns = [t for t in range(1, ticks) if legs[t] != legs[t - 1]]
    assert not stop and flown[:, 0].tolist() == [0, *turns]
    assert same_bits(native_depths, depths)
    assert near_edge == 0 or len(turns) > 0


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(0, 120), min_size=1, max_size=40), st.floats(0, 1e6),
       st.sampled_from(["bench", "sea-trial", "uniform"]))
def test_the_ocean_along_a_run_is_the_ocean_at_each_tick(depths, start, preset):
    water = ocean.load_ocean(preset)
    depth = np.array(depths)
    time = start + 4.0 * np.arange(len(depth))
    temperature, salinity = water.water_along(depth, time)
    each = [water.water_at(d, t) for d, t in zip(depth.tolist(), time.tolist(), strict=True)]
    assert same_bits(temperature, [e[0] for e in each])
    assert same_bits(salinity, [e[1] for e in each])


def test_a_measured_profile_along_a_run_is_the_profile_at_each_tick(tmp_path):
    path = tmp_path / "casts.csv"
    path.write_text("depth_m,temperature_c,salinity_psu,time_s\n"
                    "0,20,34,0\n7.5,18.2,34.4,0\n30,10,35,0\n0,22,34,3600\n30,12,35,3600\n")
    water = ocean.read_profile_csv(path)
    rng = np.random.default_rng(1)
    depth, time = rng.uniform(-1, 40, 500), rng.uniform(-100, 4000, 500)
    temperature, salinity = water.water_along(depth, time)
    each = [water.water_at(d, t) for d, t in zip(depth.tolist(), time.tolist(), strict=True)]
    assert same_bits(temperature, [e[0] for e in each])
    assert same_bits(salinity, [e[1] for e in each])


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-5, 35), min_size=1, max_size=80),
       st.one_of(st.just(math.nan), st.floats(-5, 35)),
       st.sampled_from([0.0, math.exp(-8), 0.3, 0.97]))
def test_the_ctd_lag_over_a_run_is_the_recursion(water, before, keep):
    c, want = before, []
    for w in water:
        c = w if c != c else w + (c - w) * keep
        want.append(c)
    assert same_bits(native.first_order_lag(np.array(water), before, keep), want)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(0, 5000), min_size=1, max_size=8))
@example([4096]).via("a run ending on a block's end")
@example([0, 4096, 0, 8192]).via("nothing taken, and whole blocks")
def test_random_numbers_are_the_same_taken_one_by_one_or_in_runs(takes):
    def stream() -> Draws:
        rng = np.random.default_rng(5)
        return Draws(lambda: rng.standard_normal((4096, 2)))

    one, runs = stream(), stream()
    for take in takes:
        rows = runs.peek(take)
        runs.skip(take)
        assert rows.tolist() == [one.next() for _ in range(take)]
    assert runs.next() == one.next()


def test_the_plan_s_schedule_over_a_run_is_the_schedule_at_each_tick():
    from gliderplan.planner.planfile import ProfilePlan, StatePlan

    block = StatePlan("s", 300.0, 1800.0, 3600.0, 1, 0.0, {}, (),
                      (ProfilePlan(0, 0.7, 0.4, 200.0, 0.3), ProfilePlan(1, 0.0, 0.4, 200.0, 0.3),
                       ProfilePlan(2, 0.3, 0.4, 200.0, 0.3)))
    t_in = np.arange(0.0, 20000.0, 3.7)
    assert pilot.profile_indices(block, t_in).tolist() == \
        [pilot.profile_index(block, t) for t in t_in]
    logged = ((0, 0.0, 0.0), (9, 300.0, 177.0), (12, 60.0, 20.5), (13, 300.0, 0.0))
    assert pilot.sensor_power_masks(logged, t_in).tolist() == \
        [pilot.sensor_power_mask(logged, t) for t in t_in]


def test_a_long_survey_is_flown_in_runs_of_ticks(monkeypatch):
    """Where nothing happens between ticks the fast executor flies them in runs; the
    ticks the loop flies one by one are those on which an event fires and a few more."""
    from gliderplan.sim.executor import PythonRuntime

    one_by_one = []
    step = PythonRuntime.step

    def counted(self, tick, mask, values):
        one_by_one.append(tick)
        return step(self, tick, mask, values)

    monkeypatch.setattr(PythonRuntime, "step", counted)
    mission = check_file(str(REPO / "examples" / "survey_month.mission")).mission
    calibrated = load_vehicle(mission.vehicle)
    rigid = replace(calibrated, flight=replace(calibrated.flight, compressibility_per_pa=0.0))
    # a hull squeezed by sea pressure (the calibrated preset's) changes the speed with
    # depth, a rigid one does not: both are flown in runs
    assert calibrated.flight.compressibility_per_pa > 0.0
    for vehicle in (calibrated, rigid):
        one_by_one.clear()
        record = fly(mission, ocean.bench(), RunConfig(duration_s=2 * 86400.0, seed=1),
                     vehicle)
        assert len(record.columns["time_s"]) == 43201
        assert len(record.trace) < len(one_by_one) < 0.02 * 43201


def test_runs_of_ticks_leave_each_waypoint_reached_to_the_loop(monkeypatch):
    """`wptreached` is one number over a run: a run ends before a tick that may reach a
    waypoint (the last of a list too, which counts once), and the loop steps that tick
    through the reference, which counts it on the tick a tick-by-tick flight does. The
    rest is flown in runs."""
    from gliderplan.sim.executor import PythonRuntime

    stepped = []  # (tick, state, waypoints reached after the tick) of each tick stepped
    step = PythonRuntime.step

    def counted(self, tick, mask, values):
        command = step(self, tick, mask, values)
        stepped.append((tick, self.machine.state, self.route.reached))
        return command

    monkeypatch.setattr(PythonRuntime, "step", counted)
    path = REPO / "tests" / "missions" / "sim_waypoints_reached.mission"
    mission = check_file(str(path)).mission

    def counts(tick_by_tick: bool) -> tuple[list[tuple], int]:
        """The ticks on which the state or its count changed, and the ticks stepped."""
        stepped.clear()
        fly(mission, ocean.bench(), RunConfig(duration_s=86400.0, seed=1),
            load_vehicle(mission.vehicle), tick_by_tick=tick_by_tick)
        changes = [row for i, row in enumerate(stepped)
                   if i == 0 or row[1:] != stepped[i - 1][1:]]
        return changes, len(stepped)

    reference, ticks = counts(tick_by_tick=True)
    fast, few = counts(tick_by_tick=False)
    assert fast == reference and few < 0.05 * ticks
    # the transect's three waypoints (its last ends it; a return resumes the count), two
    # laps of the goto list, and none on the nav route home
    seen = {}
    for _, state, reached in reference:
        seen.setdefault(state, []).append(reached)
    assert seen == {"transect": [0, 1, 1, 2, 2, 3], "fix": [0, 0], "laps": [0, 1, 2, 3, 4],
                    "home": [0], None: [0]}


def test_every_kind_of_condition_is_checked_over_a_run_as_the_reference_checks_it():
    depth, temp = ir.SensorRef("depth"), ir.SensorRef("temp")
    conditions = [
        ir.BinaryOp("||", ir.UnaryOp("!", depth),
                    ir.BinaryOp(">", ir.FuncCall("max", (temp, ir.Const(0.0))),
                                ir.BinaryOp("/", ir.VarRef("top"), ir.Const(0.0)))),
        ir.BinaryOp("&&", ir.BinaryOp("<=", ir.FuncCall("min", (depth, temp)),
                                      ir.FuncCall("abs", (ir.UnaryOp("-", temp),))),
                    ir.BinaryOp("!=", ir.BinaryOp("+", ir.BinaryOp("<", depth, temp),
                                                  ir.BinaryOp(">", depth, temp)),
                                ir.Const(1.0))),
        ir.UnaryOp("!", ir.BinaryOp("==", ir.VarRef("top"), ir.Const(5.0))),
        ir.BinaryOp(">=", ir.FuncCall("mod", (depth, temp)), ir.FuncCall("mod", (temp, depth))),
    ]
    values = [0.0, -0.0, 1.0, 5.0, -3.0, math.nan, math.inf]
    rows = [(d, t) for d in values for t in values]
    arrays = {1: np.array([r[0] for r in rows]), 9: np.array([r[1] for r in rows])}
    for condition in conditions:
        for top in (5.0, 0.0, math.nan):
            fires = compiled.firing_ticks([ir.Event(condition)])(arrays, {"top": top},
                                                                 len(rows))
            want = [ir.evaluate(condition, {"depth": d, "temp": t}, {"top": top}) != 0.0
                    for d, t in rows]
            assert fires.tolist() == want
