"""Power management in the language: `computer clock N MHz | auto`, `computer sleep between
ticks`, `computer workload N cycles per tick` in a state, parsed, formatted, checked
against the board's data file and carried into the checked mission and the C tables."""

from __future__ import annotations

import pytest

from gliderplan.contract import FlightLimits
from gliderplan.language import check_source, ir
from gliderplan.language.codegen_c import generate_c
from gliderplan.language.formatter import format_source
from gliderplan.power_models import load_vehicle

MISSION = """mission pm
{computer}

state a
begin
  flightprofile yo(3, 30, .454, .454)
{settings}
  sensors missiontime, depth
  events
    case missiontime >= 600 exit
end
"""


def source(settings: str, computer: str = "computer ts7800") -> str:
    lines = "\n".join(f"  {line}" for line in settings.splitlines())
    return MISSION.format(computer=computer, settings=lines)


def checked(settings: str, computer: str = "computer ts7800") -> ir.CheckedMission:
    result = check_source(source(settings, computer), "pm.mission")
    assert result.mission is not None, result.render()
    return result.mission


def diagnostics(settings: str, computer: str = "computer ts7800") -> list[str]:
    result = check_source(source(settings, computer), "pm.mission")
    return [f"{d.severity}: {d.message} | {d.hint}" for d in result.diagnostics]


def test_settings_reach_the_checked_mission():
    state = checked("computer clock 500 MHz\ncomputer sleep between ticks\n"
                    "computer workload 7.1e6 cycles per tick").states[0]
    assert state.computer == ir.ComputerUse(clock_mhz=500.0, sleep=True,
                                            cycles_per_tick=7.1e6)
    assert checked("computer clock auto").states[0].computer.clock_auto
    assert checked("computer clock 0.5 GHz").states[0].computer.clock_mhz == 500.0


def test_a_mission_without_settings_keeps_its_hash():
    # the canonical JSON leaves out a state that says nothing: plans and builds made
    # before power management still match
    plain = checked("")
    assert "computer" not in plain.to_json()["states"][0]
    assert plain.hash != checked("computer sleep between ticks").hash


def test_format_gives_the_canonical_spelling_and_keeps_the_meaning():
    text = source("computer   clock 500  MHz\ncomputer sleep   between ticks\n"
                  "computer workload 7.1e6 cycles  per tick\ncomputer clock auto")
    out = format_source(text.replace("computer clock auto", "")) + ""
    assert "  computer clock 500 MHz\n  computer sleep between ticks\n" \
           "  computer workload 7.1e6 cycles per tick\n" in out
    assert format_source(out) == out


@pytest.mark.parametrize(("settings", "computer", "expected"), [
    ("computer clock 400 MHz", "computer ts7800",
     "error: board ts7800 has no 400 MHz clock | its clocks: 300, 500 MHz; or 'computer "
     "clock auto'"),
    ("computer clock 300 V", "computer ts7800", "error: "),
    ("", "computer ts7800 @ 400 MHz",
     "error: board ts7800 has no 400 MHz clock | its clocks: 300, 500 MHz; or leave the "
     "clock out"),
    ("", "computer ts5500 @ 300 MHz", "error: board ts5500 has no 300 MHz clock | its "
     "clocks: 133 MHz"),
    ("computer sleep between ticks", "computer ts5500",
     "error: board ts5500 cannot sleep between ticks | its data file has no [sleep] table"),
    ("computer workload 3e9 cycles per tick", "computer ts7800",
     "error: board ts7800 runs at most 2,000,000,000 cycles in a 4 s tick (at 500 MHz)"),
    ("computer workload 1.3e9 cycles per tick", "computer ts7800 @ 300 MHz",
     "error: board ts7800 runs at most 1,200,000,000 cycles in a 4 s tick (at 300 MHz)"),
    ("computer workload 0 cycles per tick", "computer ts7800",
     "error: a workload is a positive number of cycles"),
    ("computer sleep between ticks\ncomputer workload 1.15e9 cycles per tick",
     "computer ts7800 @ 300 MHz",
     "warning: no time to sleep: the work (3.83 s) and the wake-up (0.3 s) fill the 4 s tick"),
    ("computer clock auto\ncomputer clock 300 MHz", "computer ts7800",
     "error: state 'a' sets 'computer clock' twice | the first is on line 7"),
])
def test_the_checker_holds_settings_to_the_board(settings, computer, expected):
    assert any(d.startswith(expected) for d in diagnostics(settings, computer)), \
        diagnostics(settings, computer)


@pytest.mark.parametrize("spec", ["ts5500", "ts7800"])
@pytest.mark.parametrize("clock", [133, 300, 400, 500, 0.5])
def test_check_accepts_a_mission_clock_exactly_when_a_plan_reader_would(spec, clock):
    # the plan readers' test (the board's clocks the compiled mission carries) and the
    # planner's (a board loaded at that clock) agree with check's
    from gliderplan.planner.limits import flight_limits
    from gliderplan.power_models import load_board
    from gliderplan.power_models.errors import ModelFileError

    result = check_source(source("", f"computer {spec} @ {clock} MHz"), "pm.mission")
    reader = flight_limits(checked("", f"computer {spec}")).has_clock(clock)
    try:
        load_board(spec, clock)
        loads = True
    except ModelFileError:
        loads = False
    assert (result.mission is not None) == reader == loads, result.render()
    assert reader == ((spec, clock) in {("ts5500", 133), ("ts7800", 300), ("ts7800", 500)})


def test_a_mission_clock_on_a_board_file_is_held_to_that_file(tmp_path):
    from gliderplan.power_models.catalog import preset_path

    board = tmp_path / "fast.toml"
    board.write_text(preset_path("board", "ts7800").read_text().replace(
        "value = 500, unit", "value = 400, unit"))
    assert checked("", f'computer "{board}" @ 400 MHz').computer.clock_mhz == 400.0
    found = diagnostics("", f'computer "{board}" @ 500 MHz')
    assert any(d.startswith("error: board ts7800 has no 500 MHz clock | its clocks: 300, 400")
               for d in found), found
    found = diagnostics("", f'computer "{tmp_path}/none.toml" @ 300 MHz')
    assert any("no such file" in d for d in found), found


def test_a_board_that_wakes_only_on_its_timer_cannot_sleep_between_ticks(tmp_path):
    from gliderplan.power_models.catalog import preset_path

    board = tmp_path / "timer_only.toml"
    board.write_text(preset_path("board", "ts7800").read_text().replace(
        'wake_on = ["serial", "timer"]', 'wake_on = ["timer"]'))
    found = diagnostics("computer sleep between ticks", f'computer "{board}"')
    assert any("wakes only on timer, not on the serial line" in d for d in found), found


def test_a_board_file_that_cannot_be_read_is_said_at_the_setting(tmp_path):
    found = diagnostics("computer sleep between ticks", f'computer "{tmp_path}/none.toml"')
    assert any("computer settings need the board's figures" in d and "no such file" in d
               for d in found), found


def test_syntax_errors_name_what_was_expected():
    result = check_source(source("computer sleep on ticks"), "pm.mission")
    assert result.mission is None
    assert "between" in result.render()


def test_the_c_tables_carry_the_fixed_clock_and_the_sleep():
    limits = FlightLimits(230.0, 233.0, (300.0, 500.0),
                          envelope=load_vehicle("slocum_g2_shallow").envelope)
    code = generate_c(checked("computer clock 500 MHz\ncomputer sleep between ticks"), limits)
    assert ".clock_mhz = 500.0," in code and ".sleep = 1," in code
    plain = generate_c(checked(""), limits)
    assert ".clock_mhz" not in plain and ".sleep" not in plain


def test_checking_settings_reads_the_board_without_numpy(tmp_path):
    import subprocess
    import sys

    path = tmp_path / "pm.mission"
    path.write_text(source("computer clock auto\ncomputer sleep between ticks"))
    probe = ("import sys; from gliderplan.language import check_file; "
             f"assert check_file({str(path)!r}).mission is not None; "
             "print(sorted(m for m in ('numpy', 'cvxpy', 'pandas') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"
