"""`gliderplan compare-sbc` as a user runs it: the boards with their data files' figures,
the energy split, the crossovers (checked against the planner itself at workloads either
side), the files it writes, and bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

from gliderplan.cli.common import check_file
from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, TICK_S
from gliderplan.planner.compare import compare_boards
from gliderplan.planner.hardware import load_hardware
from gliderplan.planner.inputs import PlanInputError
from gliderplan.planner.plan import plan_mission
from gliderplan.power_models import load_board
from gliderplan.power_models.catalog import preset_path

ROOT = Path(__file__).resolve().parents[1]
ANNOTATED = str(ROOT / "examples" / "fig2_annotated.mission")
SURVEY = str(ROOT / "examples" / "thermocline_survey.mission")


def gliderplan(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gliderplan.cli", *args],
                          capture_output=True, text=True, timeout=300)


def compare_json(*args: str) -> dict:
    run = gliderplan("compare-sbc", *args, "--json")
    assert run.returncode == 0, run.stderr
    return json.loads(run.stdout)


def computer_j(mission, spec: str, cycles: float) -> float:
    """The computer's energy in the plan `gliderplan plan --computer spec` makes."""
    plan = plan_mission(mission, load_hardware(mission, computer=spec, cycles_per_tick=cycles))
    return plan.plan.components_j["computer"]


def test_the_three_boards_with_table_i_figures_and_the_data_files_idle_powers():
    data = compare_json(ANNOTATED)
    boards = data["boards"]
    assert list(boards) == ["ts5500", "ts7800@300", "ts7800@500"]
    # Table I of Woithe & Kremer
    assert [b["active_power_w"] for b in boards.values()] == [2.7, 3.42, 4.14]
    assert [b["idle_power_w"] for b in boards.values()] == [
        load_board(spec).idle_w for spec in boards]
    for name, board in boards.items():
        assert any(k.endswith("idle_power") and "assumption" in v
                   for k, v in board["assumptions"].items()), name
        parts = sum(board[k] for k in ("active_j", "idle_j", "sleep_j", "wake_j", "boot_j"))
        assert parts == pytest.approx(board["board_energy_j"], rel=1e-12)
        assert board["share_of_mission"] == pytest.approx(
            board["board_energy_j"] / board["mission_energy_j"])
        assert board["status"] == "optimal" and 0 < board["quality"] <= 1
        assert board["endurance_days"] > 0
    assert boards["ts5500"]["boot_energy_j"] == pytest.approx(20 * 2.7)  # boot time x active
    assert boards["ts5500"]["sleep_power_w"] is None  # it cannot sleep between ticks
    assert any("assumption" in note for note in data["assumptions"])
    # the workload it rests on, and the measurement beside that assumption
    assert data["assumptions"][0].startswith(
        f"workload per tick: {RUNTIME_CYCLES_PER_TICK:,.0f} cycles")
    assert data["assumptions"][1].startswith(
        f"ts5500: the runtime's own code is {load_board('ts5500').runtime_code_cycles:,.0f} cycles")


def _bench_instructions(build: str, mission: str) -> int:
    """Instructions a tick of `mission` on `build`, as bench/README.md's runtime table
    reports them (the "now" column)."""
    for line in (ROOT / "bench" / "README.md").read_text().splitlines():
        cells = [c.strip().strip("*") for c in line.strip("|").split("|")]
        if cells[:2] == [build, mission]:
            return int(cells[3].replace(",", ""))
    raise AssertionError(f"bench/README.md has no row for {build} {mission}")


def test_the_workload_says_where_it_comes_from_beside_the_runtimes_measured_code():
    """The default workload is the contract's assumed whole tick, and compare-sbc says so;
    beside it, on the TS-5500, the runtime's own code as its board file gives it (the
    bench's measured i486 count, at the cycles per instruction the file assumes), its
    share, and what the rest of the assumed tick costs the board, from the figures alone.
    The TS-7800's ARM build is not measured, and the comparison says that too."""
    data = compare_json(SURVEY)
    workload = data["workload"]
    assert workload["cycles_per_tick"] == RUNTIME_CYCLES_PER_TICK and workload["assumed"]
    assert "an assumption (contract.RUNTIME_CYCLES_PER_TICK)" in workload["source"]
    assert "are not" in workload["source"]  # what the measurement leaves out is said
    ts5500 = load_board("ts5500")
    code = data["boards"]["ts5500"]["runtime_code"]
    assert code["instructions_per_tick"] == ts5500.runtime_instructions == \
        _bench_instructions("ts5500 i486", "fig2")
    assert code["instructions_source"].startswith("bench/bench_runtime.py")
    assert code["cycles_per_instruction_source"].startswith("assumption:")
    assert "cycles_per_instruction" in data["boards"]["ts5500"]["assumptions"]
    own = ts5500.runtime_instructions * ts5500.cycles_per_instruction
    assert code["cycles_per_tick"] == ts5500.runtime_code_cycles == own
    assert code["share_of_workload"] == pytest.approx(own / RUNTIME_CYCLES_PER_TICK)
    # the rest of the tick, idle power to active power for its cycles on every tick
    mission = check_file(SURVEY).mission
    plan = plan_mission(mission, load_hardware(mission, computer="ts5500")).plan
    ticks = sum(s.time_s for s in plan.states) / TICK_S
    rest_s = (RUNTIME_CYCLES_PER_TICK - own) / ts5500.cycles_per_s
    assert code["rest_energy_j"] == pytest.approx(
        ticks * (ts5500.active_w - ts5500.idle_w) * rest_s, rel=1e-9)
    for name in ("ts7800@300", "ts7800@500"):
        assert data["boards"][name]["runtime_code"] is None
    text = gliderplan("compare-sbc", SURVEY).stdout
    assert "(workload: below)" in text.splitlines()[0]
    assert f"workload per tick: {RUNTIME_CYCLES_PER_TICK:,.0f} cycles, the runtime's whole " \
        f"{TICK_S:g} s tick" in text
    assert "ts7800@300, ts7800@500: the runtime's own code is not measured" in text
    given = compare_json(SURVEY, "--cycles-per-tick", "5e7", "--computer", "ts5500")
    assert not given["workload"]["assumed"]
    assert given["boards"]["ts5500"]["runtime_code"]["share_of_workload"] == \
        pytest.approx(own / 5e7)


def test_a_board_file_gives_its_measured_code_with_what_an_instruction_costs(tmp_path):
    from gliderplan.power_models.errors import ModelFileError

    board = tmp_path / "quick.toml"
    text = BOARD.format(active=10.0, idle=2.0)
    count = 'runtime_instructions = { value = 3000, unit = "instructions", source = "test" }\n'
    board.write_text(text.replace("[[mode]]", count + "[[mode]]"))
    with pytest.raises(ModelFileError, match="cycles_per_instruction: missing"):
        load_board(str(board))
    cpi = ('cycles_per_instruction = { value = 1.5, unit = "cycles/instruction", '
           'source = "assumption: test" }\n')
    board.write_text(text.replace("[[mode]]", count + cpi + "[[mode]]"))
    assert load_board(str(board)).runtime_code_cycles == 4500
    data = compare_json(ANNOTATED, "--computer", str(board))
    assert data["boards"]["quickboard"]["runtime_code"]["cycles_per_tick"] == 4500


def test_board_energy_is_what_the_planner_charges_for_the_computer():
    mission = check_file(ANNOTATED).mission
    data = compare_json(ANNOTATED, "--cycles-per-tick", "5e7")
    for spec, board in data["boards"].items():
        assert board["board_energy_j"] == pytest.approx(computer_j(mission, spec, 5e7),
                                                        rel=1e-9)
    # the active share follows the workload: 5e7 cycles every 4 s at 133 MHz
    assert data["assumptions"][0].startswith(
        "workload per tick: 50,000,000 cycles, given with --cycles-per-tick")
    ts5500 = data["boards"]["ts5500"]
    busy_s = 5e7 / 133e6
    assert ts5500["active_j"] / (ts5500["active_j"] + ts5500["idle_j"]) == pytest.approx(
        2.7 * busy_s / (2.7 * busy_s + 2.2 * (TICK_S - busy_s)))


def test_endurance_ranks_with_board_power_at_the_same_sampling_plan():
    data = compare_json(SURVEY)
    boards = data["boards"]
    power = {n: b["board_energy_j"] for n, b in boards.items()}
    by_power = sorted(power, key=power.get)
    by_endurance = sorted(boards, key=lambda n: -boards[n]["endurance_days"])
    assert by_power == by_endurance


def test_the_crossover_where_the_ts5500_cannot_keep_up_is_its_clock_times_the_tick():
    data = compare_json(SURVEY)
    first = data["crossovers"][0]
    capacity = 133e6 * TICK_S  # cycles a 133 MHz board runs in one tick
    assert first["cycles_per_tick"] == pytest.approx(capacity, rel=1e-9)
    assert first["ranking_before"][0] == "ts5500" and "ts5500" not in first["ranking_after"]
    assert first["extra_computations_per_tick"]["thermocline_fit"] == pytest.approx(
        (capacity - 2e5) / 7096504)
    mission = check_file(SURVEY).mission
    below = {spec: computer_j(mission, spec, 0.999 * capacity)
             for spec in ("ts5500", "ts7800@300")}
    assert below["ts5500"] < below["ts7800@300"]
    with pytest.raises(PlanInputError, match="no clock keeps up"):
        computer_j(mission, "ts5500", 1.001 * capacity)


BOARD = """kind = "board"
name = "quickboard"
description = "a fast board with a low idle power, for the test"
default_clock = {{ value = 1000, unit = "MHz", source = "test" }}
boot_time = {{ value = 1, unit = "s", source = "test" }}
[[mode]]
clock = {{ value = 1000, unit = "MHz", source = "test" }}
active_power = {{ value = {active}, unit = "W", source = "test" }}
idle_power = {{ value = {idle}, unit = "W", source = "assumption: test" }}
"""


def test_an_energy_crossover_agrees_with_the_planner_on_either_side(tmp_path):
    board = tmp_path / "quick.toml"
    board.write_text(BOARD.format(active=10.0, idle=2.0))
    data = compare_json(SURVEY, "--computer", "ts5500", "--computer", str(board))
    assert list(data["boards"]) == ["ts5500", "quickboard"]
    assert "mode[0].idle_power" in data["boards"]["quickboard"]["assumptions"]
    crossing = data["crossovers"][0]
    assert crossing["ranking_before"] == ["quickboard", "ts5500"]
    assert crossing["ranking_after"] == ["ts5500", "quickboard"]
    # where the two boards' energies meet, from their figures alone: per tick each costs
    # idle x tick + (active - idle) x cycles / clock, plus one boot per mission
    mission = check_file(SURVEY).mission
    ticks = sum(s.time_s for s in plan_mission(mission).plan.states) / TICK_S
    slow, fast = (2.2, 2.7, 133e6, 54.0), (2.0, 10.0, 1e9, 10.0)

    def energy(board, w):
        idle, active, hz, boot = board
        return boot + ticks * (idle * TICK_S + (active - idle) * w / hz)

    expected = (energy(slow, 0) - energy(fast, 0)) / (
        (fast[1] - fast[0]) / fast[2] - (slow[1] - slow[0]) / slow[2]) / ticks
    assert crossing["cycles_per_tick"] == pytest.approx(expected, rel=1e-3)
    w = crossing["cycles_per_tick"]
    assert computer_j(mission, str(board), 0.9 * w) < computer_j(mission, "ts5500", 0.9 * w)
    assert computer_j(mission, str(board), 1.1 * w) > computer_j(mission, "ts5500", 1.1 * w)


def test_output_files_hold_the_tables_and_the_plot(tmp_path):
    out = tmp_path / "sbc"
    run = gliderplan("compare-sbc", ANNOTATED, "-o", str(out))
    assert run.returncode == 0, run.stderr
    assert "ts5500" in run.stdout and "crossover" in run.stdout
    assert "* an assumption" in run.stdout and "2.2*" in run.stdout
    boards = pd.read_csv(out / "boards.csv")
    assert list(boards["board"]) == ["ts5500", "ts7800@300", "ts7800@500"]
    assert list(boards["active_power_w"]) == [2.7, 3.42, 4.14]
    curve = pd.read_csv(out / "workload.csv")
    assert list(curve.columns) == ["cycles_per_tick", "ts5500_wh", "ts7800@300_wh",
                                   "ts7800@500_wh"]
    assert curve["ts5500_wh"].isna().any() and curve["ts5500_wh"].notna().any()
    crossings = pd.read_csv(out / "crossovers.csv")
    assert len(crossings) >= 1 and "thermocline_fit_per_tick" in crossings.columns
    assert (out / "sbc.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_comparison_as_a_library_call():
    mission = check_file(ANNOTATED).mission
    comparison = compare_boards(mission, ["ts7800@500"], battery="2kWh")
    (board,) = comparison.boards
    assert board.name == "ts7800@500" and comparison.battery_j == pytest.approx(7.2e6)
    assert board.energy.total_j == pytest.approx(board.planned.plan.components_j["computer"])


@pytest.mark.parametrize(("args", "message"), [
    (["--computer", "ts9999"], "unknown board preset"),
    (["--computer", "ts7800@400"], "no 400 MHz clock"),
    (["--computer", "ts5500", "--computer", "ts5500"], "compared already"),
    (["--cycles-per-tick", "-5"], "positive number of cycles"),
    (["--cycles-per-tick", "lots"], "positive number of cycles"),
    (["--battery", "a lot"], "expected an energy"),
])
def test_bad_usage_is_one_line_and_exit_2(args, message):
    run = gliderplan("compare-sbc", ANNOTATED, *args)
    assert run.returncode == 2
    assert message in run.stderr and "Traceback" not in run.stderr


def test_a_file_where_the_output_directory_should_be_is_refused(tmp_path):
    taken = tmp_path / "taken"
    taken.write_text("x")
    run = gliderplan("compare-sbc", ANNOTATED, "-o", str(taken))
    assert run.returncode == 2 and "not a directory" in run.stderr


def test_a_bad_mission_exits_1(tmp_path):
    bad = tmp_path / "bad.mission"
    bad.write_text("mission m\nstate s\nbegin\n  flightprofile yo(5, 20, .454, .454)\nend\n"
                   "state s\nbegin\nend\n")
    run = gliderplan("compare-sbc", str(bad))
    assert run.returncode == 1 and "Traceback" not in run.stderr


def test_a_board_file_that_breaks_its_format_names_the_key(tmp_path):
    board = tmp_path / "broken.toml"
    board.write_text(preset_path("board", "ts7800").read_text().replace(
        'wake_on = ["serial", "timer"]', 'wake_on = ["sonar"]'))
    run = gliderplan("compare-sbc", ANNOTATED, "--computer", str(board))
    assert run.returncode == 1
    assert "sleep.wake_on" in run.stderr and "serial, timer" in run.stderr
