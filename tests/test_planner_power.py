"""Power management planned, written, compared and flown: the board's energy in a state
that sleeps between ticks, the clock the planner picks for `computer clock auto`, the
plan file's `power` line, the crossover of a sleeping board, and both runtimes putting
the board to sleep after every tick of such a state."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from gliderplan.contract import TICK_S
from gliderplan.language import check_source
from gliderplan.planner.compare import compare_boards
from gliderplan.planner.hardware import HardwareError, load_hardware
from gliderplan.planner.plan import plan_mission
from gliderplan.planner.planfile import PlanFileError, read_plan_bytes, write_plan_bytes
from gliderplan.power_models import load_board

MISSION = """mission power
computer ts7800{clock}
battery 1 kWh reserve 10 %
state work
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
{work}
  sensors missiontime, depth, temp
  events
    case missiontime >= 3600 goto rest
end
state rest
begin
  flightroute noheading
  flightprofile yo(3, 30, .454, .454)
{rest}
  sensors missiontime, depth
  events
    case missiontime >= 7200 exit
end
"""


def mission(work: str = "", rest: str = "", clock: str = ""):
    def indent(text: str) -> str:
        return "\n".join(f"  {line}" for line in text.splitlines())

    text = MISSION.format(work=indent(work), rest=indent(rest), clock=clock)
    result = check_source(text, "power.mission")
    assert result.mission is not None, result.render()
    return result.mission, text


def computer_j(plan, state: int) -> float:
    return plan.plan.states[state].energy_by_component_j["computer"]


def test_a_state_that_sleeps_is_charged_its_sleep_and_wake_ups():
    awake, _ = mission(clock=" @ 300 MHz")
    asleep, _ = mission(rest="computer sleep between ticks", clock=" @ 300 MHz")
    board = load_board("ts7800@300")
    ticks = 3600 / TICK_S
    sleeping = plan_mission(asleep)
    per_tick = board.tick_energy(2e5, TICK_S, sleep=True)
    assert computer_j(sleeping, 1) == pytest.approx(ticks * float(per_tick.total_j), rel=1e-6)
    assert computer_j(plan_mission(awake), 1) == pytest.approx(
        ticks * float(board.tick_energy(2e5, TICK_S).total_j), rel=1e-6)
    assert computer_j(sleeping, 1) < 0.5 * computer_j(plan_mission(awake), 1)
    assert sleeping.plan.states[1].sleep and not sleeping.plan.states[0].sleep


def test_auto_picks_the_clock_that_costs_least_at_the_states_work():
    # awake, the slow clock idles cheaper; asleep at a heavy workload the fast clock
    # finishes sooner and sleeps longer (race to sleep)
    light, _ = mission(work="computer clock auto", rest="computer clock auto")
    heavy, _ = mission(work="computer clock auto\ncomputer sleep between ticks\n"
                            "computer workload 2e8 cycles per tick",
                       rest="computer clock auto")
    assert [s.clock_mhz for s in plan_mission(light).plan.states] == [300, 300]
    planned = plan_mission(heavy).plan
    assert [s.clock_mhz for s in planned.states] == [500, 300]
    assert planned.states[0].cycles_per_tick == 2e8
    slow, fast = (load_board(f"ts7800@{c}").tick_energy(2e8, TICK_S, sleep=True).total_j
                  for c in (300, 500))
    assert float(fast) < float(slow)


def test_a_states_own_clock_overrides_the_missions():
    fixed, _ = mission(work="computer clock 500 MHz", clock=" @ 300 MHz")
    assert [s.clock_mhz for s in plan_mission(fixed).plan.states] == [500, 300]


def test_a_board_that_cannot_sleep_plans_the_state_awake_and_says_so():
    asleep, _ = mission(rest="computer sleep between ticks")
    plan = plan_mission(asleep, load_hardware(asleep, computer="ts5500"))
    assert not plan.plan.states[1].sleep
    assert any("cannot sleep between ticks" in a.text for a in plan.plan.assumptions)


def test_a_board_without_the_states_clock_is_refused(tmp_path):
    fixed, _ = mission(work="computer clock 500 MHz")
    from gliderplan.power_models.catalog import preset_path

    board = tmp_path / "other.toml"  # clocks of 300 and 400 MHz, none of 500
    board.write_text(preset_path("board", "ts7800").read_text().replace(
        "value = 500, unit", "value = 400, unit"))
    with pytest.raises(HardwareError, match="state work: computer clock 500 MHz: board "
                                            "ts7800 has no such clock"):
        load_hardware(fixed, computer=str(board))
    # a board of one clock, or one held at a clock, runs every state at it, and says so
    held = plan_mission(fixed, load_hardware(fixed, computer="ts7800@300"))
    assert [s.clock_mhz for s in held.plan.states] == [300, 300]
    assert any("computer clock 500 MHz" in a.text for a in held.plan.assumptions)


def test_the_plan_file_carries_sleep_and_work_and_reads_back():
    asleep, _ = mission(work="computer workload 7.1e6 cycles per tick",
                        rest="computer sleep between ticks")
    plan = plan_mission(asleep).plan
    data = write_plan_bytes(plan)
    assert b"\npower 0 7100000\n" in data and b"\npower 1 200000\n" in data
    assert read_plan_bytes(data, asleep) == plan
    awake, _ = mission()
    assert b"\npower " not in write_plan_bytes(plan_mission(awake).plan)
    # a plan that would put the board to sleep where the mission does not (the hash
    # guards this too; the reader checks it as the C runtime does)
    awake_rest, _ = mission(work="computer workload 7.1e6 cycles per tick")
    awake_rest.__dict__["hash"] = asleep.hash
    with pytest.raises(PlanFileError, match="SLEEP 1 where the mission does not sleep"):
        read_plan_bytes(data, awake_rest)


def test_a_sleeping_board_crosses_over_where_the_planner_says():
    asleep, _ = mission(work="computer sleep between ticks", rest="computer sleep between ticks")
    comparison = compare_boards(asleep, ["ts7800@300", "ts7800@500"])
    (crossing, *_) = comparison.crossovers
    assert crossing.before == ("ts7800@300", "ts7800@500")
    assert crossing.after == ("ts7800@500", "ts7800@300")
    w = crossing.cycles_per_tick

    def computer(spec: str, cycles: float) -> float:
        planned = plan_mission(asleep, load_hardware(asleep, computer=spec,
                                                     cycles_per_tick=cycles))
        return planned.plan.components_j["computer"]

    assert computer("ts7800@300", 0.9 * w) < computer("ts7800@500", 0.9 * w)
    assert computer("ts7800@300", 1.1 * w) > computer("ts7800@500", 1.1 * w)
    sleep_j = {r.name: r.energy.sleep_j + r.energy.wake_j for r in comparison.boards}
    assert all(j > 0 for j in sleep_j.values())


@pytest.mark.parametrize("runtime", ["python", "c"])
@pytest.mark.parametrize("planned", [True, False])
def test_the_runtime_puts_the_board_to_sleep_after_every_tick_of_a_sleeping_state(
        tmp_path, runtime, planned):
    if runtime == "c" and shutil.which("cc") is None:
        pytest.skip("no C compiler (make sysdeps)")
    _, text = mission(rest="computer sleep between ticks")
    source = tmp_path / "power.mission"
    source.write_text(text)
    plan = tmp_path / "power.plan"

    def gliderplan(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "gliderplan.cli", *args],
                              capture_output=True, text=True, timeout=600)

    assert gliderplan("plan", str(source), "-o", str(plan)).returncode == 0
    with_plan = ["--plan", str(plan)] if planned else []  # without: the mission's settings
    run = gliderplan("sim", str(source), *with_plan, "--runtime", runtime,
                     "-o", str(tmp_path / "run"))
    assert run.returncode == 0, run.stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    # rest lasts 3600 s: 900 ticks, each answered and followed by a sleep; the exit's
    # tick is not
    assert summary["computer_suspends"] == 900
    if not planned:
        return
    predicted = json.loads(Path(f"{plan}.json").read_text())["states"]
    for state in predicted:
        flown = summary["states"][state["name"]]["simulated_by_component_j"]["computer"]
        assert flown == pytest.approx(state["energy_by_component_j"]["computer"], rel=1e-3)
