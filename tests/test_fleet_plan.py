"""Fleet planning: the mapping error against a hand computation, the assignment against
brute force, the example and generated fleets against the equal split, and the fleets
that cannot be planned (docs/fleet.md)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from fleet_cases import block_problem, generated_fleet

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.language import check_source
from gliderplan.language.fleet import FieldScales, FleetError, check_fleet_file, check_fleet_source
from gliderplan.planner import fleet_assign as assign
from gliderplan.planner.fleet import TARGET_IMPROVEMENT, plan_fleet
from gliderplan.planner.fleet_mapping import Grid, mapping_error, point_errors
from gliderplan.planner.fleet_report import report_json, why_not

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "shelf.fleet"
SMALL = ROOT / "tests" / "fleets" / "small.fleet"
CALM = str(ROOT / "tests" / "fleets" / "calm.toml")
SCALES = FieldScales(10e3, 86400.0, 0.1)


# ---- the mapping error -------------------------------------------------------------------

def test_one_sample_leaves_the_error_a_hand_computation_gives():
    """err = 1 - c^2 / (1 + n), c = exp(-r^2/L^2 - dt^2/T^2)."""
    sample = (np.array([0.0]), np.array([0.0]), np.array([0.0]))
    at_t, at_x, at_y = np.array([43200.0]), np.array([5000.0]), np.array([0.0])
    c = math.exp(-(5000.0 / 10e3) ** 2 - (43200.0 / 86400.0) ** 2)  # exp(-0.5)
    expected = 1.0 - c * c / 1.1
    assert point_errors(sample, at_t, at_x, at_y, SCALES)[0] == pytest.approx(expected, 1e-12)
    assert expected == pytest.approx(0.66556, abs=1e-5)


def test_two_samples_give_the_two_by_two_inverse():
    """err = 1 - (c1^2 (1+n) - 2 r c1 c2 + c2^2 (1+n)) / ((1+n)^2 - r^2), r their
    covariance with each other."""
    samples = (np.array([0.0, 0.0]), np.array([0.0, 8000.0]), np.array([0.0, 0.0]))
    at = (np.array([0.0]), np.array([3000.0]), np.array([4000.0]))
    c1 = math.exp(-(3000.0 ** 2 + 4000.0 ** 2) / 1e8)
    c2 = math.exp(-(5000.0 ** 2 + 4000.0 ** 2) / 1e8)
    r = math.exp(-(8000.0 ** 2) / 1e8)
    d = 1.1
    expected = 1.0 - (c1 * c1 * d - 2.0 * r * c1 * c2 + c2 * c2 * d) / (d * d - r * r)
    assert point_errors(samples, *at, SCALES)[0] == pytest.approx(expected, 1e-12)


def test_without_samples_the_map_knows_nothing_and_a_sample_helps_most_where_it_was_taken():
    grid = Grid(np.array([0.0, 20e3]), np.array([0.0, 0.0]), np.array([0.0, 86400.0]))
    empty = (np.zeros(0), np.zeros(0), np.zeros(0))
    assert mapping_error(empty, grid, SCALES)[0] == 1.0
    _, errors = mapping_error((np.array([0.0]), np.array([0.0]), np.array([0.0])), grid,
                              SCALES)
    assert errors[0, 0] == pytest.approx(1 - 1 / 1.1)  # the sample's own place and time
    assert errors[0, 0] < errors[1, 0] < 1.0 and errors[0, 0] < errors[0, 1] < 1.0


# ---- the assignment ----------------------------------------------------------------------

@pytest.mark.parametrize("seed", range(6))
def test_the_milp_finds_the_brute_force_optimum(seed):
    inputs = block_problem(seed, gliders=3, parts=8)
    arcs = assign.build_arcs(inputs)
    exact = assign.brute_force(arcs, inputs.parts, inputs.gliders)
    found = assign.solve_milp(arcs, inputs.parts, inputs.gliders)
    assert exact is not None and found is not None
    assert found.method == "milp" and found.status == "optimal"
    assert found.objective == pytest.approx(exact.objective, rel=1e-7)
    # one contiguous block per glider, every line once
    cover = sorted((b.first, b.stop) for b in found.blocks)
    assert cover[0][0] == 0 and cover[-1][1] == inputs.parts
    assert all(a[1] == b[0] for a, b in zip(cover, cover[1:], strict=False))
    # the heuristic is no better than the optimum, and its bound no higher
    heuristic = assign.solve_heuristic(arcs, inputs.parts, inputs.gliders, None)
    assert heuristic.objective >= exact.objective - 1e-9
    assert heuristic.bound <= exact.objective + 1e-9
    assert 0.0 <= heuristic.gap < 0.05


def test_an_infeasible_assignment_is_none_not_a_solver_status():
    inputs = block_problem(0, gliders=3, parts=8)
    # by 100,000 s a glider can sweep a block or two, and the fleet not every line
    short = assign.BlockInputs(**{**inputs.__dict__, "end_s": np.full(3, 100_000.0)})
    arcs = assign.build_arcs(short)
    assert len(arcs) > 0  # the solver is asked, and finds no assignment
    assert assign.solve_milp(arcs, short.parts, short.gliders) is None


def test_the_equal_split_cuts_the_lines_into_equal_lengths():
    inputs = block_problem(3, gliders=3, parts=9)
    split = assign.equal_split(inputs)
    lengths = [inputs.length_m[b.first:b.stop].sum() for b in split.blocks]
    assert sorted(b.glider for b in split.blocks) == [0, 1, 2]
    assert max(lengths) - min(lengths) < 2 * inputs.length_m.max()


# ---- whole fleets ------------------------------------------------------------------------

@pytest.fixture(scope="module")
def example():
    return plan_fleet(check_fleet_file(EXAMPLE).checked())


def test_the_example_beats_the_equal_split_by_a_fifth_at_its_confidence(example):
    report = report_json(example)
    assert report["improvement"] >= TARGET_IMPROVEMENT, report["why_not"]
    assert report["mapping_error"] < report["baseline_mapping_error"]
    assert report["confidence_lower_bound"] >= report["confidence"] == 0.9
    # the equal split does not even hold the confidence on this fleet
    assert report["baseline"]["model_finish_share"] < report["confidence"]
    assert report["coverage"] == pytest.approx(1.0)
    assert report["finish_time_s"] < example.fleet.period_s


def test_each_glider_flies_a_checked_mission_within_its_budget(example):
    assert sorted(p for g in example.gliders for p in g.parts) == list(
        range(len(example.fleet.parts)))
    for glider in example.gliders:
        assert check_source(glider.mission_text, f"{glider.name}.mission").ok
        assert 0.0 < glider.energy_j <= glider.budget_j
        assert glider.budget_j == pytest.approx(glider.spec.usable_j, rel=1e-6)
    # ru29's pack is 60 % spent: its battery limits the survey; ru30's does not
    prices = {g.name: g.shadow_price for g in example.gliders}
    assert prices["ru29"] > 0.0 and prices["ru30"] == 0.0
    assert report_json(example)["limiting_glider"] in ("ru28", "ru29")


def test_the_report_has_the_keys_tools_read(example):
    report = json.loads(json.dumps(report_json(example)))
    for key in ("mapping_error", "baseline_mapping_error", "confidence", "gliders"):
        assert key in report
    for glider in report["gliders"]:
        assert {"name", "energy_j", "budget_j"} <= set(glider)


def test_a_slow_machine_gets_the_same_plan(example, monkeypatch):
    """The polish is bounded by its tries, not by the clock: a machine so loaded that
    every reading of the clock is five seconds on plans the example as an idle one."""
    from types import SimpleNamespace

    from gliderplan.planner import fleet as fleet_planner

    clock = iter(range(0, 10 ** 6, 5))
    monkeypatch.setattr(fleet_planner, "time", SimpleNamespace(perf_counter=lambda: next(clock)))
    slow = plan_fleet(check_fleet_file(EXAMPLE).checked())
    assert example.polish.tried > 0
    assert (slow.polish.tried, slow.polish.after) == (example.polish.tried, example.polish.after)
    assert [(g.name, g.parts) for g in slow.gliders] == [(g.name, g.parts) for g in example.gliders]


@pytest.mark.parametrize("seed", [2, 4])
def test_generated_fleets_beat_the_equal_split_or_say_why_not(seed):
    plan = plan_fleet(check_fleet_source(generated_fleet(seed), "g.fleet").checked())
    reason = why_not(plan)
    assert plan.validation.lower_bound >= plan.fleet.confidence
    if plan.improvement >= TARGET_IMPROVEMENT:
        assert reason is None
    else:
        assert reason is not None and "less than 20 %" in reason


def test_fleet_plan_json_prints_only_the_report(capsys):
    assert main(["fleet", "plan", str(SMALL), "--scenario-file", CALM, "--json"]) == ExitCode.OK
    report = json.loads(capsys.readouterr().out)  # nothing else on stdout (HiGHS's banner)
    assert report["fleet"] == "smallBox" and len(report["gliders"]) == 3


# ---- fleets that cannot be planned -------------------------------------------------------

def small(**changes: str) -> str:
    text = SMALL.read_text()
    for old, new in changes.items():
        assert old in text
        text = text.replace(old, new)
    return text


def plan_error(text: str) -> FleetError:
    fleet = check_fleet_source(text, "t.fleet").checked()
    with pytest.raises(FleetError) as raised:
        plan_fleet(fleet, scenario_file=CALM)
    assert raised.value.exit_code == ExitCode.BAD_INPUT
    return raised.value


def test_a_glider_that_cannot_reach_the_survey_is_named_at_its_start():
    text = small(**{"start (3919.0, -7401.0)": "start (3700.0, -7401.0)"})  # 150 km away
    err = plan_error(text)
    assert "glider 'alpha' cannot reach the survey" in str(err)
    line = text.splitlines().index("  start (3700.0, -7401.0)") + 1
    assert f"t.fleet:{line}:9: error:" in err.details


def test_a_survey_the_fleet_cannot_sweep_in_time_is_refused_at_the_finish():
    text = small(**{"finish by 2 d": "finish by 20 h",
                    "spacing 2 km": "spacing 1 km"})
    err = plan_error(text)
    assert "glider 'bravo' cannot sweep even its nearest line in time" in str(err)
    assert "t.fleet:" in err.details and "^" in err.details


def test_gliders_planned_closer_than_the_separation_are_refused():
    text = small(**{"confidence 90 %": "confidence 90 %\nseparation 3 km",
                    "start (3927.0, -7401.0)": "start (3919.1, -7401.0)"})
    err = plan_error(text)
    assert "come within" in str(err) and "closer than the separation of 3000 m" in str(err)
    assert f"t.fleet:{text.splitlines().index('separation 3 km') + 1}:1:" in err.details


def test_fleet_plan_exits_1_for_an_unplannable_fleet(tmp_path, capsys):
    path = tmp_path / "far.fleet"
    path.write_text(small(**{"start (3919.0, -7401.0)": "start (3700.0, -7401.0)"}))
    assert main(["fleet", "plan", str(path), "--scenario-file", CALM]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert "cannot reach the survey" in err and err.rstrip().splitlines()[-1].startswith(
        "gliderplan fleet: error: ")
    assert main(["fleet", "plan", str(path), "--scenario-file", CALM, "--json"]) == 1
    (found,) = json.loads(capsys.readouterr().out)["diagnostics"]
    line = path.read_text().splitlines().index("  start (3700.0, -7401.0)") + 1
    assert (found["file"], found["line"], found["column"]) == (str(path), line, 9)
    assert "glider 'alpha' cannot reach the survey" in found["message"]
