"""`computer none`: a mission on the glider's own computers, whose power the vehicle's base
load already holds, so that no board is charged. Checked (the states may set no board),
planned (0 J computer, no clock, no boot, and the plan says so), written and read by
both plan readers, flown by both runtimes and in Monte Carlo, compiled only for a target
named, and compared against the boards it does without."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd
import pytest

from gliderplan.cli.main import main
from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, TICK_S, ExitCode
from gliderplan.language import check_source, ir
from gliderplan.language.formatter import format_source
from gliderplan.planner.hardware import load_hardware
from gliderplan.planner.limits import flight_limits
from gliderplan.planner.plan import plan_mission
from gliderplan.planner.planfile import PlanFileError, read_plan_bytes, write_plan_bytes
from gliderplan.power_models import load_board
from gliderplan.power_models.catalog import preset_path
from gliderplan.power_models.errors import ModelFileError

ROOT = Path(__file__).resolve().parents[1]
FIG2 = ROOT / "examples" / "fig2.mission"
ASSUMPTION = ("computer none: the glider's own computers run the mission (their power is "
              "in the vehicle's base load); no extra board is charged")
SETTINGS = """mission pm
computer none

state a
begin
  flightprofile yo(3, 30, .454, .454)
  computer clock 300 MHz
  computer sleep between ticks
  computer workload 7e6 cycles per tick
  sensors missiontime, depth
  events
    case missiontime >= 600 exit
end
"""


def fig2_text(computer: str = "computer none") -> str:
    """The paper's Fig. 2 with a `computer` line (the file has none: ts7800 by default)."""
    return FIG2.read_text().replace("mission sampleMission\n",
                                    f"mission sampleMission\n{computer}\n", 1)


def checked(text: str) -> ir.CheckedMission:
    result = check_source(text, "pm.mission")
    assert result.mission is not None, result.render()
    return result.mission


@pytest.fixture
def fig2_none(tmp_path) -> Path:
    path = tmp_path / "fig2_none.mission"
    path.write_text(fig2_text())
    return path


def run_json(capsys, *argv: str) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


# ---- the language ---------------------------------------------------------------------

def test_check_accepts_computer_none_and_carries_it_into_the_json(fig2_none, capsys):
    mission = checked(fig2_text())
    assert mission.computer == ir.Computer("none") and mission.computer.is_none
    assert "computer" not in mission.defaults_used
    assert run_json(capsys, "check", str(fig2_none))["mission"]["computer"] == {"board": "none",
                                                                    "clock_mhz": None}
    assert mission.hash != checked(fig2_text("computer ts7800")).hash
    assert "\ncomputer none\n" in format_source(fig2_text())
    assert not ir.DEFAULT_COMPUTER.is_none  # a mission that says nothing keeps its board


def test_check_refuses_each_board_setting_of_a_state_at_its_line(tmp_path, capsys):
    result = check_source(SETTINGS, "pm.mission")
    assert result.mission is None
    shown = result.render()
    for line, setting in ((7, "clock"), (8, "sleep"), (9, "workload")):
        assert (f"pm.mission:{line}:3: error: state 'a' sets 'computer {setting}', but the "
                "mission has no board to set ('computer none')") in shown
    assert shown.count("hint: the glider's own computers run the mission: remove the "
                       "line, or name a board, e.g. 'computer ts7800'") == 3
    path = tmp_path / "pm.mission"
    path.write_text(SETTINGS)
    assert main(["check", str(path)]) == ExitCode.BAD_INPUT
    assert f"{path}:7:3: error: state 'a' sets 'computer clock'" in capsys.readouterr().err


def test_check_refuses_a_clock_on_none_and_suggests_none_for_a_typo():
    result = check_source(fig2_text("computer none @ 300 MHz"), "pm.mission")
    assert result.mission is None
    assert "pm.mission:2:17: error: 'computer none' has no clock" in result.render()
    typo = check_source(fig2_text("computer nnoe"), "pm.mission").render()
    assert "unknown board preset 'nnoe'" in typo and "did you mean 'none'?" in typo


def test_a_board_file_may_not_take_the_name_none(tmp_path):
    board = tmp_path / "mine.toml"
    board.write_text(preset_path("board", "ts7800").read_text().replace(
        'name = "ts7800"', 'name = "none"', 1))
    with pytest.raises(ModelFileError, match="'none' is taken"):
        load_board(str(board))


# ---- the plan -------------------------------------------------------------------------

def test_the_plan_charges_no_computer_and_says_why(fig2_none, capsys):
    report = run_json(capsys, "plan", str(fig2_none))
    assert report["computer"] == {"board": "none", "clock_mhz": 0.0}
    assert report["components_j"]["computer"] == 0.0
    assert [s["energy_by_component_j"]["computer"] for s in report["states"]] == [0.0] * 3
    assert [s["clock_mhz"] for s in report["states"]] == [0.0] * 3
    assert {"subject": "mission", "text": ASSUMPTION} in report["assumptions"]
    # the board's share of the same mission on the default TS-7800, and only that, is gone
    board = run_json(capsys, "plan", str(FIG2))
    assert board["components_j"]["computer"] > 0.25 * board["energy_j"]
    assert report["energy_j"] < board["energy_j"] - board["components_j"]["computer"] + 1e-6
    assert main(["plan", str(fig2_none)]) == 0
    text = capsys.readouterr().out
    assert "maximize quality on none (the glider's own computers)" in text
    assert f"  - {ASSUMPTION}" in text


def test_the_plan_file_round_trips_and_the_readers_hold_none_to_clock_0(fig2_none, tmp_path):
    mission = checked(fig2_text())
    plan = plan_mission(mission).plan
    data = write_plan_bytes(plan)
    assert b"\ncomputer none 0\n" in data
    assert all(line.split()[2] == "0" for line in data.decode().splitlines()
               if line.startswith("state "))
    assert read_plan_bytes(data, mission, limits=flight_limits(mission)) == plan
    # a clock on none is refused on any build; a board's plan on a mission without one
    with pytest.raises(PlanFileError, match="4: clock 300 MHz: computer none has no "
                                            "clock to set"):
        read_plan_bytes(data.replace(b"computer none 0", b"computer none 300"))
    board_plan = plan_mission(mission, load_hardware(mission, computer="ts7800@300")).plan
    with pytest.raises(PlanFileError, match=r"4: computer ts7800: the mission flies on board "
                                            r"none \(plan again with --computer none\)"):
        read_plan_bytes(write_plan_bytes(board_plan), mission, limits=flight_limits(mission))
    fig2 = checked(fig2_text("computer ts7800"))
    on_fig2 = plan_mission(fig2, load_hardware(fig2, computer="none")).plan
    assert read_plan_bytes(write_plan_bytes(on_fig2), fig2, limits=flight_limits(fig2))


def test_plan_computer_overrides_the_missions_board_both_ways(fig2_none, capsys):
    none = run_json(capsys, "plan", str(fig2_none))
    dropped = run_json(capsys, "plan", str(FIG2), "--computer", "none")
    added = run_json(capsys, "plan", str(fig2_none), "--computer", "ts7800@300")
    board = run_json(capsys, "plan", str(FIG2), "--computer", "ts7800@300")
    assert dropped["components_j"] == none["components_j"]
    assert dropped["computer"]["board"] == "none"
    assert added["components_j"] == board["components_j"]
    assert added["components_j"]["computer"] > 0
    assert ASSUMPTION not in {a["text"] for a in added["assumptions"]}
    assert main(["plan", str(FIG2), "--computer", "none@300"]) == ExitCode.USAGE
    assert "computer none has no clock to set" in capsys.readouterr().err


def test_a_states_settings_planned_on_none_are_said_not_to_apply(tmp_path):
    mission = checked(SETTINGS.replace("computer none", "computer ts7800"))
    plan = plan_mission(mission, load_hardware(mission, computer="none")).plan
    assert plan.components_j["computer"] == 0.0 and not plan.states[0].sleep
    assert "a: its computer settings do not apply: there is no board to set (computer " \
           "none)" in {str(a) for a in plan.assumptions}


# ---- the flight -----------------------------------------------------------------------

@pytest.mark.parametrize("runtime", ["python", "c"])
def test_sim_bills_no_computer_and_saves_the_boards_power_times_the_time(fig2_none, tmp_path,
                                                                         runtime):
    assert main(["sim", str(fig2_none), "--runtime", runtime, "-o",
                 str(tmp_path / "none")]) == 0
    assert main(["sim", str(FIG2), "--runtime", runtime, "-o", str(tmp_path / "ts7800")]) == 0
    none, board = (json.loads((tmp_path / run / "summary.json").read_text())
                   for run in ("none", "ts7800"))
    assert none["energy_by_component_j"]["computer"] == 0.0
    ts7800 = load_board("ts7800@300")
    flown_s = 2500.0  # Fig. 2 exits at 2500 s either way
    saved = float(ts7800.mean_power_w(RUNTIME_CYCLES_PER_TICK, TICK_S)) * flown_s \
        + ts7800.boot_j
    total = [sum(run["energy_by_component_j"].values()) for run in (none, board)]
    assert total[1] - total[0] == pytest.approx(saved, rel=1e-9)
    assert saved > 6000.0  # about 2.57 W for 2500 s: a third of the mission


@pytest.mark.parametrize("runtime", ["python", "c"])
def test_a_plan_for_none_flies_within_its_prediction(fig2_none, tmp_path, runtime):
    plan = tmp_path / "none.plan"
    assert main(["plan", str(fig2_none), "-o", str(plan)]) == 0
    assert main(["sim", str(fig2_none), "--plan", str(plan), "--runtime", runtime,
                 "-o", str(tmp_path / "run")]) == 0
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["energy_by_component_j"]["computer"] == 0.0
    assert summary["plan_check"]["verdict"] == "pass"


def test_a_plan_for_none_on_a_boards_mission_bills_no_board(tmp_path):
    plan = tmp_path / "none.plan"
    assert main(["plan", str(FIG2), "--computer", "none", "-o", str(plan)]) == 0
    assert main(["sim", str(FIG2), "--plan", str(plan), "-o", str(tmp_path / "run")]) == 0
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["energy_by_component_j"]["computer"] == 0.0


def test_montecarlo_flies_none_without_a_board(fig2_none, tmp_path):
    plan = tmp_path / "none.plan"
    assert main(["plan", str(fig2_none), "-o", str(plan)]) == 0
    assert main(["montecarlo", str(fig2_none), "--plan", str(plan), "--scenarios", "3",
                 "--workers", "1", "-o", str(tmp_path / "mc")]) == 0
    flown = pd.read_parquet(tmp_path / "mc" / "scenarios.parquet")
    assert len(flown) == 3 and flown["held"].all()
    assert (flown["energy_computer_j"] == 0.0).all()


# ---- compile --------------------------------------------------------------------------

def test_compile_needs_a_target_for_a_mission_without_a_board(fig2_none, tmp_path, capsys):
    assert main(["compile", str(fig2_none), "-o", str(tmp_path / "out")]) == ExitCode.USAGE
    err = capsys.readouterr().err
    assert "mission sampleMission names no board (computer none)" in err
    assert "give --target host|ts7800|ts5500" in err
    assert not (tmp_path / "out").exists()
    plan = tmp_path / "none.plan"
    assert main(["plan", str(fig2_none), "-o", str(plan)]) == 0
    assert main(["compile", str(fig2_none), "--target", "host", "--plan", str(plan),
                 "-o", str(tmp_path / "out")]) == 0
    assert (tmp_path / "out" / "sampleMission").is_file()
    assert (tmp_path / "out" / "none.plan").read_bytes() == plan.read_bytes()


def test_the_runtime_flies_a_none_plan_on_a_boards_build_and_refuses_the_reverse(
        fig2_none, tmp_path, capsys):
    none_plan, board_plan = tmp_path / "none.plan", tmp_path / "ts7800.plan"
    assert main(["plan", str(FIG2), "--computer", "none", "-o", str(none_plan)]) == 0
    assert main(["compile", str(FIG2), "--plan", str(none_plan),
                 "-o", str(tmp_path / "board")]) == 0  # built for the TS-7800's clocks
    assert main(["plan", str(fig2_none), "--computer", "ts7800", "-o", str(board_plan)]) == 0
    capsys.readouterr()
    assert main(["compile", str(fig2_none), "--target", "host", "--plan", str(board_plan),
                 "-o", str(tmp_path / "none")]) == ExitCode.BAD_INPUT
    assert "line 4: computer ts7800: the mission flies on board none (plan again with " \
        "--computer none)" in capsys.readouterr().err


# ---- what a board costs ---------------------------------------------------------------

def test_compare_sbc_adds_none_beside_the_boards(fig2_none, capsys):
    data = run_json(capsys, "compare-sbc", str(fig2_none))
    assert list(data["boards"]) == ["ts5500", "ts7800@300", "ts7800@500", "none"]
    none = data["boards"]["none"]
    assert (none["board_energy_j"], none["clock_mhz"], none["clocks_mhz"]) == (0.0, None, [])
    assert all(b["board_energy_j"] > 0 for name, b in data["boards"].items() if name != "none")
    assert none["mission_energy_j"] < min(b["mission_energy_j"] for b in data["boards"].values()
                                          if b is not none)
    assert all("none" not in c["ranking_before"] + c["ranking_after"]
               for c in data["crossovers"])
    assert main(["compare-sbc", str(fig2_none)]) == 0
    text = capsys.readouterr().out
    assert "3 boards and none (no extra board)" in text
    assert "cheapest board on this mission: ts5500" in text
    assert "the cheapest board, ts5500, adds" in text
    # a mission with a board lists the boards only
    assert list(run_json(capsys, "compare-sbc", str(FIG2))["boards"]) == [
        "ts5500", "ts7800@300", "ts7800@500"]


def test_the_report_shows_the_computer_as_none(fig2_none, tmp_path):
    from gliderplan.reports.report import make_report

    report = make_report(checked(fig2_text()), tmp_path / "report", sweep_points=3)
    html = report.html.read_text()
    assert "<dt>computer</dt><dd>none (the glider&#x27;s own computers)</dd>" in html
    boards = pd.read_csv(tmp_path / "report" / "sbc_boards.csv")
    assert boards.set_index("board").loc["none", "board_energy_j"] == 0.0


def test_power_show_describes_no_board(capsys):
    data = run_json(capsys, "power", "show", "board", "none")
    assert (data["name"], data["file"], data["figures"]) == ("none", None, [])
