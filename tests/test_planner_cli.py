"""`gliderplan plan` as a user runs it: tables, files, JSON, sweeps and bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
from conftest import modules_loaded_by

from gliderplan.planner.planfile import read_plan_bytes

ROOT = Path(__file__).resolve().parents[1]
ANNOTATED = str(ROOT / "examples" / "fig2_annotated.mission")
FIG2 = str(ROOT / "examples" / "fig2.mission")
SURVEY = str(ROOT / "examples" / "thermocline_survey.mission")


def gliderplan(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gliderplan.cli", *args],
                          capture_output=True, text=True, timeout=300)


def test_table_says_what_each_state_does():
    run = gliderplan("plan", ANNOTATED)
    assert run.returncode == 0, run.stderr
    out = run.stdout
    for text in ("quality", "shadow price", "energy by component", "s1", "s2", "s3",
                 "hotel", "computer", "ctd", "optode", "temp"):
        assert text in out
    assert "1,020 Wh budget" in out  # a kilowatt-hour pack reads without an exponent
    assert "e+" not in out


def test_fig2_without_annotations_says_which_defaults_it_used():
    run = gliderplan("plan", FIG2)
    assert run.returncode == 0, run.stderr
    assert "vehicle slocum_g2_shallow (default)" in run.stdout
    assert "computer ts7800 @ 300 MHz (default)" in run.stdout
    assert "battery" in run.stdout and "(default)" in run.stdout


def test_a_plan_imports_neither_the_tables_nor_the_plotting_of_sweeps(tmp_path):
    """pandas and matplotlib take a third of a second each to import: only --sweep,
    which writes CSV tables and pareto.png, pays for them."""
    code, loaded = modules_loaded_by(["plan", SURVEY, "-o", str(tmp_path / "p.plan")])
    assert (code, loaded & {"pandas", "matplotlib"}, "cvxpy" in loaded) == (0, set(), True)


def test_a_yo_s_altimeter_stop_is_planned_to_max_depth_and_said_so():
    from gliderplan.language import check_source
    from gliderplan.planner import make_plan

    source = ("mission m\nstate s\nbegin\n  flightroute noheading\n"
              "  flightprofile yo(3, 50, .454, .454, 4)\n  sensors missiontime, depth\n"
              "  events\n    case missiontime >= 7200 exit\nend\n")
    stopped = make_plan(check_source(source).checked()).plan
    plain = make_plan(check_source(source.replace(", 4)", ")")).checked()).plan
    assert ("s", "flightprofile 0: turns at 4 m above the sea floor: planned to max_depth "
            "(50 m), the floor unknown") in [(a.subject, a.text) for a in stopped.assumptions]
    assert stopped.states[0].energy_j == plain.states[0].energy_j


def test_output_writes_plan_and_report(tmp_path):
    out = tmp_path / "survey.plan"
    run = gliderplan("plan", SURVEY, "-o", str(out), "--json")
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report == json.loads((tmp_path / "survey.plan.json").read_text())
    contents = read_plan_bytes(out.read_bytes())
    assert contents.mission == "thermoclineSurvey"
    assert report["status"] == "optimal" and report["energy_j"] <= report["budget_j"]
    for key in ("quality", "shadow_price", "assumptions", "solver", "components_j"):
        assert key in report
    assert report["solver"]["iterations"] > 0
    state = report["states"][2]
    assert state["name"] == "track"
    assert set(state["energy_by_component_j"]) >= {"hotel", "computer", "pump", "pitch",
                                                   "surface", "ctd", "optode", "optics"}
    assert sum(state["energy_by_component_j"].values()) == pytest.approx(state["energy_j"])
    assert sum(s["energy_j"] for s in report["states"]) == pytest.approx(report["energy_j"])
    assert {"index", "kind", "share", "speed_mps", "pitch_rad", "ballast_cc"} <= \
        set(state["profiles"][0])
    assert {"name", "duty", "period_s", "on_s"} <= set(state["sensors"][0])
    assert contents.predicted_j == pytest.approx(report["energy_j"], rel=1e-8)


def test_battery_and_computer_options_change_the_plan():
    small = json.loads(gliderplan("plan", SURVEY, "--battery", "300Wh", "--json").stdout)
    assert small["budget_j"] == pytest.approx(0.8 * 300 * 3600)  # the mission's 20 % reserve
    fast = json.loads(gliderplan("plan", SURVEY, "--computer", "ts7800@500", "--json").stdout)
    assert fast["computer"]["clock_mhz"] == 500
    assert fast["components_j"]["computer"] > small["components_j"]["computer"]
    preset = json.loads(gliderplan("plan", ANNOTATED, "--battery", "alkaline", "--json").stdout)
    assert preset["budget_j"] == pytest.approx(0.85 * 7.8e6)


def test_cycles_per_tick_prices_the_computer_and_goes_into_the_plan(tmp_path):
    # the runtime's own 200,000 cycles a tick, then a billion (half a 4 s tick at 500 MHz)
    own = json.loads(gliderplan("plan", SURVEY, "--json").stdout)
    out = tmp_path / "busy.plan"
    run = gliderplan("plan", SURVEY, "--cycles-per-tick", "1e9", "-o", str(out), "--json")
    assert run.returncode == 0, run.stderr
    busy = json.loads(run.stdout)
    assert busy["components_j"]["computer"] > 1.2 * own["components_j"]["computer"]
    assert {s.cycles_per_tick for s in read_plan_bytes(out.read_bytes()).states} == {1e9}
    run = gliderplan("plan", SURVEY, "--computer", "ts5500", "--cycles-per-tick", "1e9")
    assert run.returncode == 1 and "no clock keeps up" in run.stderr


def test_infeasible_budget_exits_1_with_the_minimum():
    run = gliderplan("plan", ANNOTATED, "--battery", "4Wh")
    assert run.returncode == 1
    assert "needs at least" in run.stderr and "Largest consumers" in run.stderr
    assert "3.4 Wh (4 Wh less the 15 % reserve)" in run.stderr  # the mission keeps 15 %
    assert "Traceback" not in run.stderr
    run = gliderplan("plan", ANNOTATED, "--battery", "4Wh", "--json")
    assert run.returncode == 1
    report = json.loads(run.stdout)
    assert report["status"] == "infeasible" and report["shortfall_j"] > 0
    assert len(report["largest_consumers_j"]) == 3


@pytest.mark.parametrize("args,code,message", [
    (["--battery", "4parsec"], 2, "parsec"),
    (["--battery", "lots"], 2, "expected an energy"),
    (["--computer", "ts9000"], 2, "unknown board preset"),
    (["--computer", "ts7800@400"], 2, "no 400 MHz clock"),
    (["--sweep", "1", "-o", "x"], 2, "between 2 and"),
    (["--sweep", "5"], 2, "needs -o"),
])
def test_bad_options_give_a_clear_error(args, code, message):
    run = gliderplan("plan", ANNOTATED, *args)
    assert run.returncode == code
    assert message in run.stderr and "Traceback" not in run.stderr


def test_bad_mission_file_exits_1(tmp_path):
    bad = tmp_path / "bad.mission"
    bad.write_text("mission m\nstate a\nbegin\n  sensors nosuch\nend\n")
    run = gliderplan("plan", str(bad))
    assert run.returncode == 1 and "bad.mission:" in run.stderr
    run = gliderplan("plan", str(tmp_path / "missing.mission"))
    assert run.returncode == 2 and "Traceback" not in run.stderr


def test_sweep_writes_csvs_and_plot(tmp_path):
    run = gliderplan("plan", str(ROOT / "tests/missions/planner_separable.mission"),
                     "--sweep", "12", "-o", str(tmp_path / "sweep"))
    assert run.returncode == 0, run.stderr
    pareto = pd.read_csv(tmp_path / "sweep" / "pareto.csv")
    assert len(pareto) == 12 and (pareto["quality"].diff().dropna() >= -1e-7).all()
    boards = pd.read_csv(tmp_path / "sweep" / "computers.csv")
    assert list(boards["computer"]) == ["ts5500@133", "ts7800@300", "ts7800@500"]
    assert boards["minimum_energy_j"].is_monotonic_increasing  # faster boards draw more
    # the mission's 13.5 Wh pack is too small for the TS-7800 at 500 MHz
    assert list(boards["status"]) == ["optimal", "optimal", "infeasible"]
    assert boards["computer_j"].iloc[0] < boards["computer_j"].iloc[1]
    packs = pd.read_csv(tmp_path / "sweep" / "batteries.csv")
    assert list(packs["battery"]) == ["alkaline", "lithium_primary", "rechargeable"]
    png = (tmp_path / "sweep" / "pareto.png").read_bytes()
    assert png.startswith(b"\x89PNG")
    # off a terminal, progress is an occasional line, never one per budget solved
    assert "\r" not in run.stderr and run.stderr.count("pareto") <= 1, run.stderr


def test_mission_too_big_for_a_plan_file_is_refused_by_its_check(tmp_path, capsys):
    from gliderplan.cli.main import main

    actions = [f"goto s{i + 1}" for i in range(69)] + ["exit"]
    states = [f"state s{i}\nbegin\n  flightroute noheading\n  flightprofile yo(3, 30, .454, "
              f".454)\n  sensors missiontime\n  events\n    case missiontime >= {(i + 1) * 60} "
              f"{action}\nend\n" for i, action in enumerate(actions)]
    path = tmp_path / "big.mission"
    path.write_text("mission big\n" + "".join(states))
    assert main(["plan", str(path), "-o", str(tmp_path / "big.plan")]) == 1
    err = capsys.readouterr().err
    assert f"{path}:514:7: error: the mission has 70 states, more than the 64" in err
    assert not (tmp_path / "big.plan").exists()


def test_sweep_of_a_mission_with_nothing_to_trade_is_one_point(tmp_path):
    run = gliderplan("plan", FIG2, "--sweep", "5", "-o", str(tmp_path))
    assert run.returncode == 0, run.stderr
    pareto = pd.read_csv(tmp_path / "pareto.csv")
    assert len(pareto) == 1 and pareto["shadow_price"].iloc[0] == 0.0


def test_make_plan_and_sweep_mission_are_the_plan_command_as_calls(tmp_path):
    from gliderplan.language import check_file
    from gliderplan.planner import make_plan, sweep_mission

    mission = check_file(ANNOTATED).checked()
    plan = make_plan(mission, battery="500Wh", output=tmp_path / "a.plan").plan
    report = json.loads((tmp_path / "a.plan.json").read_text())
    assert report["budget_j"] == pytest.approx(plan.budget_j) == pytest.approx(0.85 * 500 * 3600)
    assert read_plan_bytes((tmp_path / "a.plan").read_bytes(), mission) == plan
    seen = []
    sweep = sweep_mission(check_file(SURVEY).checked(), 4, tmp_path / "sweep",
                          progress=lambda label, done, total: seen.append((label, done, total)))
    assert [p.name for p in sweep.files] == ["pareto.csv", "computers.csv", "batteries.csv",
                                             "pareto.png"]
    assert len(sweep.pareto) == 4 and list(sweep.computers["computer"]) == \
        ["ts5500@133", "ts7800@300", "ts7800@500"]
    assert ("pareto", 4, 4) in seen and ("batteries", 3, 3) in seen
    # the call refuses what the command refuses, with the same error (exit 2)
    from gliderplan.contract import ExitCode
    from gliderplan.contract.errors import GliderplanError

    for options, message in (({"seq": 5}, "--seq goes with --sign KEYFILE"),
                             ({"confidence": 0.9, "workers": 0}, "--workers 0: must be at "),
                             ({"confidence": 0.9, "scenarios": 0}, "--scenarios 0: must be ")):
        with pytest.raises(GliderplanError, match=message) as refused:
            make_plan(mission, **options)
        assert refused.value.exit_code == ExitCode.USAGE
