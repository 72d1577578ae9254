"""The planner's timeline and convex model: Fig. 2's exact timeline, DPP re-solves, an
independent water-filling solver, monotone Pareto frontier and the shadow price."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from gliderplan.language import check_source
from gliderplan.language.source import read_mission
from gliderplan.planner.hardware import load_hardware
from gliderplan.planner.inputs import ENERGY_UNIT_J, PlanInputError, build_inputs, coefficients
from gliderplan.planner.model import model_for
from gliderplan.planner.occupancy import mission_occupancy
from gliderplan.planner.plan import InfeasibleBudget, PlanningError, plan_mission, prepare
from gliderplan.planner.sweep import computers, energy_range_j, pareto
from gliderplan.planner.waterfill import separable_form, water_fill
from gliderplan.power_models import flight
from gliderplan.power_models.devices import base_power_w

ROOT = Path(__file__).resolve().parents[1]
TIGHT = {"tol_gap_abs": 1e-12, "tol_gap_rel": 1e-12, "tol_feas": 1e-12}
# Tolerances this tight make Clarabel flag some solves "inaccurate"; the tests check the
# accuracy themselves, against an independent solver or finite differences.
INACCURATE_OK = pytest.mark.filterwarnings("ignore:Solution may be inaccurate")


def mission(path: str):
    result = check_source(read_mission(str(ROOT / path)), path, None)
    assert result.mission is not None, result.render()
    return result.mission


def source_mission(text: str):
    result = check_source(text, "<test>", None)
    assert result.mission is not None, result.render()
    return result.mission


def test_fig2_timeline_is_the_papers_run():
    occupancy = mission_occupancy(mission("examples/fig2.mission"))
    runs = [(v.state, v.entry_s, v.entry_s + v.duration_s) for v in occupancy.trace]
    assert runs == [("s1", 0, 500), ("s2", 500, 1500), ("s1", 1500, 2000), ("s3", 2000, 2500)]
    assert occupancy.time_s == {"s1": 1000, "s2": 1000, "s3": 500}


def test_sensor_driven_exit_is_planned_at_its_expect_upper_bound():
    m = source_mission("""mission m
state a
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, depth, temp duty auto
  expect 10 min .. 1 h
  events
    case temp < 10 goto b
end
state b
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 5000 exit
end
""")
    occupancy = mission_occupancy(m)
    assert occupancy.time_s == {"a": 3600, "b": 1400}
    assert any("expect upper bound" in note for note in occupancy.notes)


def test_an_abort_above_the_planned_exit_is_not_taken_for_it():
    m = source_mission("""mission m
horizon 5000 s
state survey
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, depth, halfcycle
  expect 10 min .. 20 min
  events
    case depth > 60 goto abort
    case halfcycle >= 4 call surfacing
end
state surfacing
begin
  flightroute noheading
  flightprofile surface
  sensors missiontime, depth
  events
    case missiontime >= 0 return
end
state abort
begin
  flightroute noheading
  flightprofile surface
  sensors missiontime, depth
  events
    case depth <= 0.3 exit
end
""")
    occupancy = mission_occupancy(m)
    assert [v.state for v in occupancy.trace[:3]] == ["survey", "surfacing", "survey"]
    assert occupancy.time_s["abort"] == 0 and occupancy.visits["surfacing"] >= 4


def test_open_ended_state_runs_to_the_horizon():
    m = source_mission("""mission m
horizon 2 h
state a
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, depth, temp duty auto
  events
    case temp < 10 exit
end
""")
    assert mission_occupancy(m).time_s == {"a": 7200}


def test_thermocline_survey_timeline_follows_its_variables():
    occupancy = mission_occupancy(mission("examples/thermocline_survey.mission"))
    assert occupancy.total_s == 126000  # exit at 35 h
    assert occupancy.visits["surface_fix"] == 4
    assert occupancy.time_s["surface_fix"] == 4 * 900
    assert occupancy.time_s["launch"] == 600


def test_plan_stays_within_budget_and_bounds():
    m = mission("examples/fig2_annotated.mission")
    plan = plan_mission(m).plan
    assert plan.predicted_j <= plan.budget_j
    s2 = next(s for s in plan.states if s.name == "s2")
    duties = {x.name: x.duty for x in s2.sensors}
    assert duties["temp"] >= 0.5 - 1e-9  # the state's `require temp duty >= 0.5`
    assert duties["oxygen"] <= 0.8 + 1e-9  # the mission's `sensor oxygen duty <= 0.8`
    for state in plan.states:
        assert abs(sum(p.share for p in state.profiles) - 1) < 1e-9


def test_model_is_dpp_and_a_new_budget_changes_the_answer():
    m = mission("tests/missions/planner_separable.mission")
    _, model = prepare(m)
    assert model.quality_problem.is_dcp(dpp=True)
    low, high = energy_range_j(model)
    first = model.solve_quality(low + 0.2 * (high - low))
    second = model.solve_quality(low + 0.8 * (high - low))
    assert second.quality > first.quality + 1e-3


@INACCURATE_OK
def test_water_filling_agrees_with_cvxpy():
    m = mission("tests/missions/planner_separable.mission")
    inputs, model = prepare(m)
    separable = separable_form(inputs, coefficients(inputs))
    assert separable is not None
    low, high = energy_range_j(model)
    for fraction in (0.1, 0.5, 0.9):
        budget = low + fraction * (high - low)
        sol = model.solve_quality(budget, **TIGHT)
        duties, quality, lam = water_fill(separable, budget / ENERGY_UNIT_J)
        np.testing.assert_allclose(quality, sol.quality, rtol=1e-6)
        np.testing.assert_allclose(duties, sol.duty, rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(lam / ENERGY_UNIT_J, sol.budget_dual, rtol=1e-5)


@INACCURATE_OK
def test_water_filling_on_the_annotated_paper_mission():
    inputs, model = prepare(mission("examples/fig2_annotated.mission"))
    separable = separable_form(inputs, coefficients(inputs))
    assert separable is not None
    low, high = energy_range_j(model)
    budget = low + 0.4 * (high - low)
    sol = model.solve_quality(budget, **TIGHT)
    _, quality, _ = water_fill(separable, budget / ENERGY_UNIT_J)
    np.testing.assert_allclose(quality, sol.quality, rtol=1e-6)


def test_shared_device_is_not_separable():
    inputs, _ = prepare(mission("examples/thermocline_survey.mission"))
    assert separable_form(inputs, coefficients(inputs)) is None  # temp + conductivity: one CTD


@INACCURATE_OK
def test_quality_never_falls_as_the_budget_grows_and_price_is_the_slope():
    _, model = prepare(mission("tests/missions/planner_separable.mission"))
    frame = pareto(model, 25)
    assert (frame["status"] == "optimal").all()
    assert np.all(np.diff(frame["quality"]) >= -1e-7)
    assert frame["quality"].iloc[-1] > frame["quality"].iloc[0]
    # shadow price [quality/Wh] against a central finite difference of the frontier
    for budget in (frame["budget_j"].iloc[8], frame["budget_j"].iloc[16]):
        step = 1.0  # J
        up = model.solve_quality(budget + step, **TIGHT).quality
        down = model.solve_quality(budget - step, **TIGHT).quality
        price = model.solve_quality(budget, **TIGHT).budget_dual * 3600
        np.testing.assert_allclose((up - down) / (2 * step) * 3600, price, rtol=1e-3)
    # the price falls along the frontier (diminishing returns)
    assert np.all(np.diff(frame["shadow_price"]) <= 1e-6)


def test_infeasible_budget_names_minimum_and_consumers():
    m = mission("examples/fig2_annotated.mission")
    with pytest.raises(InfeasibleBudget) as info:
        plan_mission(m, budget_j=10_000)
    err = info.value
    assert err.minimum_j > 10_000 and len(err.consumers) == 3
    text = str(err)
    assert "needs at least" in text and "computer" in text and "Wh" in text
    assert "infeasible" not in text.lower() and "solver" not in text.lower()


def test_minimize_energy_meets_the_quality_floor_at_least_cost():
    m = mission("examples/thermocline_survey.mission")
    result = plan_mission(m)
    plan = result.plan
    assert result.quality >= 0.5 - 1e-6 and plan.predicted_j <= plan.budget_j
    assert result.budgeted_energy_j >= result.minimum_energy_j * (1 - 1e-8)
    assert plan.predicted_j <= result.budgeted_energy_j * (1 + 1e-8)  # warm-ups it skips
    richer = plan_mission(m, budget_j=2 * plan.budget_j).plan
    assert richer.predicted_j == pytest.approx(plan.predicted_j, rel=1e-6)  # not the goal


def test_each_objective_s_least_budget_is_what_it_needs():
    """The survey as written (minimize energy, quality >= 0.5) needs the energy its floor
    costs: its sensors draw from the battery; asking for the best quality needs less (any
    quality will do at the least). Each least budget is the one its infeasible-budget
    message names, and the plan draws less than it is budgeted (warm-ups the budget counts
    are not drawn when a sensor stays on)."""
    survey = mission("examples/thermocline_survey.mission")
    text = read_mission(str(ROOT / "examples/thermocline_survey.mission"))
    best = source_mission(text.replace("objective minimize energy quality >= 0.5",
                                       "objective maximize quality"))
    floor, anything = plan_mission(survey), plan_mission(best)
    assert floor.quality >= 0.5 - 1e-6
    assert anything.minimum_energy_j < floor.minimum_energy_j
    assert floor.plan.predicted_j <= floor.minimum_energy_j * (1 + 1e-9)
    for m, least in ((survey, floor.minimum_energy_j), (best, anything.minimum_energy_j)):
        with pytest.raises(InfeasibleBudget) as info:
            plan_mission(m, budget_j=least * (1 - 1e-3))
        assert info.value.minimum_j == pytest.approx(least, rel=1e-9)
        assert plan_mission(m, budget_j=least * (1 + 1e-7)).minimum_energy_j == \
            pytest.approx(least, rel=1e-9)


@pytest.mark.parametrize("path", ["examples/thermocline_survey.mission",
                                  "examples/fig2_annotated.mission",
                                  "tests/missions/planner_transit.mission"])
def test_the_plan_sits_on_or_under_its_pareto_curve(path):
    """The plan's operating point, at the budget it takes (counted as the curve's budgets
    are), against the curve made on the same model: no curve budget below the least the
    plan's minimum says, the plan taking at least that, and no more quality than the
    curve's at its budget (solver tolerance)."""
    from gliderplan.planner.plan import solve_plan

    m = mission(path)
    _, model = prepare(m)
    result = solve_plan(model)
    frontier = pareto(model, 12)
    start = float(frontier["budget_j"].iloc[0])
    assert start <= result.minimum_energy_j * (1 + 1e-9)
    assert (frontier["budget_j"] >= start * (1 - 1e-9)).all()
    assert result.budgeted_energy_j >= result.minimum_energy_j * (1 - 1e-7)
    assert result.plan.predicted_j <= result.budgeted_energy_j * (1 + 1e-8)
    curve = model.solve_quality(result.budgeted_energy_j).quality
    assert result.quality <= curve + 1e-6
    if m.objective.sense == "minimize_energy":
        # the survey's floor (0.5) costs energy (its sensors are billed): the plan is the
        # least energy that reaches it, on the curve at its budget
        assert result.budgeted_energy_j == pytest.approx(result.minimum_energy_j, rel=1e-6)
        assert result.quality == pytest.approx(curve, abs=1e-4)
    else:  # the best quality its budget buys: on the curve
        assert result.quality == pytest.approx(curve, abs=1e-5)


def test_occupancy_from_simulation_replaces_the_timeline():
    m = mission("examples/fig2_annotated.mission")
    static = plan_mission(m).plan
    measured = plan_mission(m, occupancy_s={"s1": 2000, "s2": 1000, "s3": 500}).plan
    assert measured.states[0].time_s == 2000
    assert measured.states[0].energy_j > 1.9 * static.states[0].energy_j
    with pytest.raises(ValueError, match="nosuch"):
        plan_mission(m, occupancy_s={"nosuch": 10})


def test_faster_computer_costs_more_and_a_free_clock_picks_the_cheaper():
    m = mission("examples/fig2_annotated.mission")
    slow = plan_mission(m, load_hardware(m, computer="ts7800@300")).plan
    fast = plan_mission(m, load_hardware(m, computer="ts7800@500")).plan
    free = plan_mission(m, load_hardware(m, computer="ts7800")).plan
    assert fast.components_j["computer"] > slow.components_j["computer"]
    assert {s.clock_mhz for s in free.states} == {300}


def test_contradictory_annotations_are_reported():
    m = source_mission("""mission m
sensor temp duty >= 0.6
state a
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, temp duty auto
  require temp duty <= 0.5
  events
    case missiontime >= 100 exit
end
""")
    with pytest.raises(PlanInputError, match="state a: sensor temp"):
        plan_mission(m)


def test_unreachable_quality_floor_is_explained():
    m = source_mission("""mission m
objective minimize energy quality >= 0.99
sensor oxygen duty <= 0.1
state a
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, oxygen duty auto
  events
    case missiontime >= 100 exit
end
""")
    with pytest.raises(PlanningError, match="quality floor 0.99 cannot be reached"):
        plan_mission(m)


def test_timeline_follows_calls_returns_and_assignments():
    m = source_mission("""mission m
var next_fix = 1000
var until = 0
state dive
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 4000 exit
    case missiontime >= next_fix
      set until = missiontime + 200, next_fix = missiontime + 1000 call fix
end
state fix
begin
  flightroute noheading
  flightprofile surface
  sensors missiontime, lat, lon
  events
    case missiontime >= until return
end
""")
    occupancy = mission_occupancy(m)
    runs = [(v.state, v.entry_s, v.duration_s) for v in occupancy.trace]
    assert runs[:4] == [("dive", 0, 1000), ("fix", 1000, 200), ("dive", 1200, 800),
                        ("fix", 2000, 200)]
    assert occupancy.time_s == {"dive": 3400, "fix": 600}
    assert occupancy.visits == {"dive": 4, "fix": 3}


TRANSIT = """mission leg
computer {computer}
battery 200 Wh reserve 10 %
{horizon}
state start
begin
  flightroute nav(3910.5, -7349.8)
  flightprofile yo(3, 10, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 600 goto transit
end
state transit
begin
  flightroute nav(3916.5, -7349.8)
  flightprofile yo(3, 10, .454, .454)
  sensors missiontime, depth, altitude, temp duty auto
  events
    case altitude < 5 exit
end
"""


def _transit_plan(computer: str = "ts7800 @ 300 MHz", horizon: str = ""):
    m = source_mission(TRANSIT.format(computer=computer, horizon=horizon))
    inputs, model = prepare(m)
    return m, inputs, plan_mission(m).plan


def test_transit_leg_flies_the_speed_that_minimises_energy_per_metre():
    m, inputs, plan = _transit_plan()
    leg = inputs.occupancy.legs_m["transit"]
    assert leg == pytest.approx(6 * 1852, rel=1e-3)  # 6 minutes of latitude
    transit = plan.states[1]
    speed = transit.profiles[0].speed_mps
    vehicle = inputs.hardware.vehicle
    # the load billed per second of the leg: the base and the computer (the CTD, duty-
    # cycled below 1, is billed for its on-time per metre, whatever the speed)
    assert 0.0 < transit.sensors[0].duty < 1.0
    load = base_power_w(vehicle) + transit.energy_by_component_j["computer"] / transit.time_s
    expected = float(vehicle.optimal_speed_mps(load, 3, 10, 0.454))
    assert speed == pytest.approx(expected, rel=1e-3)  # the pace model's u* = (P/2c)^(1/3)
    pump_s = leg * inputs.transit.pump_s[0] * speed**2
    turn_s = leg * inputs.transit.turn_s_per_m[0]
    assert transit.time_s == pytest.approx(leg / speed + pump_s + turn_s, rel=1e-6)
    assert plan.predicted_j <= plan.budget_j
    assert separable_form(inputs, coefficients(inputs)) is None


def test_turns_lengthen_a_transit_leg_and_cost_hotel_energy():
    m = source_mission(TRANSIT.format(computer="ts7800 @ 300 MHz", horizon=""))
    hardware = load_hardware(m)
    turning = dataclasses.replace(hardware, vehicle=dataclasses.replace(
        hardware.vehicle, top_turn_s=50.0, bottom_turn_s=30.0))
    plain, slow = plan_mission(m, hardware).plan, plan_mission(m, turning).plan
    inputs, _ = prepare(m, turning)
    leg = inputs.occupancy.legs_m["transit"]
    cycles = leg / (2 * (10 - 3) / float(flight.glide_slope(turning.vehicle.flight, 0.454)))
    extra_s = slow.states[1].time_s - leg * (1 / slow.states[1].profiles[0].speed_mps
                                             + inputs.transit.pump_s[0]
                                             * slow.states[1].profiles[0].speed_mps**2)
    assert extra_s == pytest.approx(80.0 * cycles, rel=1e-6)  # two turns a yo cycle
    assert slow.predicted_j > plain.predicted_j


def test_hungrier_computer_flies_the_transit_faster():
    _, _, slow = _transit_plan("ts7800 @ 300 MHz")
    _, _, fast = _transit_plan("ts7800 @ 500 MHz")
    assert fast.states[1].profiles[0].speed_mps > slow.states[1].profiles[0].speed_mps


def test_horizon_makes_the_transit_faster():
    _, _, free = _transit_plan()
    free_speed = free.states[1].profiles[0].speed_mps
    hours = round(0.97 * (free.states[1].time_s + 600) / 3600, 2)  # 3 % sooner than it would
    _, inputs, tight = _transit_plan(horizon=f"horizon {hours} h")
    transit = tight.states[1]
    assert transit.time_s + 600 <= hours * 3600 * (1 + 1e-6)
    assert transit.profiles[0].speed_mps > free_speed


def test_report_says_where_the_times_came_from():
    from gliderplan.planner.report import report_json

    m = mission("examples/fig2_annotated.mission")
    assert report_json(plan_mission(m))["time_source"] == "timeline"
    measured = plan_mission(m, occupancy_s={"s1": 900, "s2": 1100, "s3": 500})
    assert report_json(measured)["time_source"] == "simulation"


def test_a_board_too_slow_for_the_runtime_is_refused():
    # 1e10 cycles every 4 s is 2.5 GHz of work: the TS-5500's 133 MHz cannot keep up
    m = mission("examples/fig2_annotated.mission")
    with pytest.raises(PlanInputError, match="no clock keeps up"):
        plan_mission(m, load_hardware(m, computer="ts5500", cycles_per_tick=1e10))


def test_clock_follows_the_computation_the_mission_needs():
    m = mission("examples/fig2_annotated.mission")
    light = plan_mission(m, load_hardware(m, computer="ts7800")).plan
    assert {s.clock_mhz for s in light.states} == {300}  # idles cheaper at the slow clock
    # 1.6e9 cycles every 4 s is 400 MHz of work: only the 500 MHz clock keeps up
    heavy = plan_mission(m, load_hardware(m, computer="ts7800", cycles_per_tick=1.6e9)).plan
    assert {s.clock_mhz for s in heavy.states} == {500}
    assert heavy.components_j["computer"] > light.components_j["computer"]


def test_each_computer_in_a_sweep_gets_the_plan_made_for_it_alone():
    """The sweep re-uses one model while its structure stays (a fixed clock) and builds
    another when it changes (a board whose clock the planner chooses)."""
    m = mission("examples/fig2_annotated.mission")
    specs = ("ts7800@500", "ts7800", "ts5500")
    rows = computers(m, specs).to_dict("records")
    for spec, row in zip(specs, rows, strict=True):
        alone = plan_mission(m, load_hardware(m, computer=spec))
        assert row["status"] == "optimal"
        assert row["quality"] == pytest.approx(alone.quality, rel=1e-6), spec
        assert row["energy_j"] == pytest.approx(alone.plan.predicted_j, rel=1e-6), spec
        assert row["computer_j"] == pytest.approx(alone.plan.components_j["computer"],
                                                  rel=1e-6)
    assert rows[0]["computer_j"] > rows[1]["computer_j"]  # free clock: the cheaper 300 MHz


def test_a_model_is_reused_only_for_inputs_of_the_same_structure():
    m = mission("examples/fig2_annotated.mission")
    occupancy = mission_occupancy(m)

    def inputs(spec: str):
        return build_inputs(m, load_hardware(m, computer=spec), occupancy)

    fixed = model_for(inputs("ts7800@300"))
    assert model_for(inputs("ts7800@500"), fixed) is fixed
    assert model_for(inputs("ts7800"), fixed) is not fixed


@pytest.mark.parametrize("path", sorted((ROOT / "examples").glob("*.mission"))
                         + sorted((ROOT / "tests" / "missions").glob("planner_*.mission")),
                         ids=lambda p: p.name)
def test_every_example_is_planned_to_the_solver_s_full_accuracy(path):
    """A plan with budget to spare flies the cheapest of the best plans; its quality floor
    sits at the optimum, where the solver once stopped at reduced accuracy (the annotated
    Fig. 2 reported optimal_inaccurate)."""
    result = plan_mission(mission(str(path.relative_to(ROOT))))
    assert result.solver_status == "optimal"


@pytest.mark.parametrize(("low", "high", "threshold"), [(5, 20, 10), (2, 30, 6), (10, 14, 10),
                                                        (0, 60, 80), (5, 20, 20)])
def test_thermocline_tracking_is_planned_at_the_band_it_flies_on_average(low, high, threshold):
    """thermotrackyo flies [max(min, z - h), min(max, z + h)] once it has found the
    thermocline at z; planned at that band's mean width over z anywhere in [min, max],
    centred: against the band averaged over z directly."""
    from gliderplan.language import ir
    from gliderplan.planner.rates import yo_band

    profile = ir.Profile("thermotrackyo", ())
    planned = yo_band(profile, (low, high, 0.454, 0.454, 6.0, threshold))
    z = np.linspace(low, high, 200_001)
    flown_low = np.maximum(low, z - threshold / 2)
    flown_high = np.minimum(high, z + threshold / 2)
    def mean(x: np.ndarray) -> float:  # over z uniform in [min, max]
        return float(np.trapezoid(x, z)) / (high - low)

    assert planned[1] - planned[0] == pytest.approx(mean(flown_high - flown_low), rel=1e-6)
    assert 0.5 * sum(planned) == pytest.approx(mean(0.5 * (flown_low + flown_high)), abs=1e-6)
    assert yo_band(ir.Profile("yo", ()), (low, high, 0.454, 0.454)) == (low, high)
