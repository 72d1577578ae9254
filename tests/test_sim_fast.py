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
from gliderplan.sim import compiled, geo, libm, ocean, pilot
from gliderplan.sim.flight import fly
from gliderplan.sim.loop import RunConfig
from gliderplan.sim.science import Draws, first_order_lag

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
        assert same_bits(getattr(libm, name)(x), [getattr(math, name)(v) for v in xs]), name
    assert same_bits(libm.atan2(y, x), [math.atan2(a, b) for a, b in zip(y, x, strict=True)])


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(finite, finite), min_size=1, max_size=60))
def test_headings_in_binary32_are_the_route_s(offsets):
    north, east = (np.array(v) for v in zip(*offsets, strict=True))
    pack = struct.Struct("<f")
    want = [pack.unpack(pack.pack(geo.bearing_rad(n, e)))[0] for n, e in offsets]
    assert same_bits(geo.bearing_binary32_array(north, east), want)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(-90, 90), min_size=1, max_size=30),
       st.lists(st.floats(-180, 180), min_size=1, max_size=30))
def test_positions_and_readings_over_arrays_are_geo_s(lats, lons):
    lat, lon = np.array(lats), np.resize(np.array(lons), len(lats))
    assert same_bits(geo.degrees_to_ddmm_array(lat), [geo.degrees_to_ddmm(v) for v in lat])
    ddmm = geo.degrees_to_ddmm_array(lon)
    assert same_bits(geo.ddmm_to_degrees_array(ddmm), [geo.ddmm_to_degrees(v) for v in ddmm])
    north, east = geo.offset_m_array(lat, lon, 39.17, -73.82)
    pairs = [geo.offset_m(a, b, 39.17, -73.82) for a, b in zip(lat, lon, strict=True)]
    assert same_bits(north, [p[0] for p in pairs]) and same_bits(east, [p[1] for p in pairs])


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
    assert same_bits(first_order_lag(np.array(water), before, keep), want)


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
