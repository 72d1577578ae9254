"""The fleet file: what checks, what is refused and where (docs/fleet.md), and the exit codes
of `gliderplan fleet check` (0 ok, 1 a bad fleet file, 2 bad usage)."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.language.fleet import FleetError, check_fleet_file, check_fleet_source

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "shelf.fleet"
SMALL = ROOT / "tests" / "fleets" / "small.fleet"
SMALL_TEXT = SMALL.read_text()


def errors(text: str) -> list[tuple[int, int, str, str | None]]:
    """(line, column, message, hint) of every error in `text`."""
    result = check_fleet_source(text, "t.fleet")
    return [(d.span.line, d.span.column, d.message, d.hint) for d in result.diagnostics
            if d.is_error]


def where(text: str, fragment: str, nth: int = 0) -> tuple[int, int]:
    """(line, column) of the nth `fragment` in `text`, as diagnostics count them."""
    offset = -1
    for _ in range(nth + 1):
        offset = text.index(fragment, offset + 1)
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def test_the_example_checks_into_lines_gliders_and_a_period():
    fleet = check_fleet_file(EXAMPLE).checked()
    assert fleet.name == "njShelf"
    assert [g.name for g in fleet.gliders] == ["ru28", "ru29", "ru30", "ru31", "ru32"]
    assert fleet.period_s == 7 * 86400 and fleet.confidence == 0.9
    assert fleet.glider("ru32").start_offset_s == 86400.0  # a day late
    assert fleet.glider("ru29").charge == pytest.approx(0.4)
    assert fleet.glider("ru31").computer.board == "ts7800"
    assert fleet.field.length_m == 12e3 and fleet.field.time_s == 2 * 86400
    assert [s.name for s in fleet.goal.sensors] == ["temp", "conductivity"]
    assert fleet.goal.sensors[1].duty == 0.5  # `duty >= 0.5`: flown at the least asked
    # lines 4 km apart across the area, those through the keep-out cut in two pieces
    assert len(fleet.parts) == 12
    pieces = [p for p in fleet.parts if p.length_m < 14e3]
    assert len(pieces) == 4 and len({p.line for p in pieces}) == 2


def test_a_usable_charge_is_what_is_left_above_the_reserve():
    fleet = check_fleet_file(EXAMPLE).checked()
    ru29 = fleet.glider("ru29")  # 1.2 kWh at 40 %, a reserve of 10 % of the rating
    assert ru29.usable_j == pytest.approx(1.2 * 3.6e6 * (0.4 - 0.1))


def test_a_syntax_error_is_located_with_a_caret_and_the_rest_is_still_read():
    text = SMALL_TEXT.replace("finish by 2 d", "finish 2 d").replace(
        "confidence 90 %", "confidence = 90 %")
    found = errors(text)
    assert len(found) == 2, found  # both, not just the first
    assert found[0][:2] == where(text, "2 d")
    rendered = check_fleet_source(text, "t.fleet").render()
    assert re.search(r"t\.fleet:\d+:\d+: error: ", rendered)
    assert "^" in rendered


@pytest.mark.parametrize("change, fragment, message", [
    (("sample temp,", "sample tmep,"), "tmep", "'tmep' is no sensor to sample"),
    (("confidence 90 %", "confidence 120 %"), "120 %", "confidence must lie strictly"),
    (("finish by 2 d", "finish by 2000-01-01T00:00Z"), "2000-01-01T00:00Z",
     "the survey finishes before it starts"),
    (("depth 5 .. 30 m", "depth 30 .. 5 m"), "depth 30 .. 5 m",
     "the depth band must run from a shallower"),
    (("charge 15 %", "charge 5 %"), "charge 5 %", "glider 'bravo' has no usable charge"),
    (("field 8 km 1 d", "field 8 km 1 kWh"), "kWh", "'kWh' is not a unit of time"),
])
def test_a_bad_setting_is_refused_where_it_is_written(change, fragment, message):
    text = SMALL_TEXT.replace(*change)
    found = errors(text)
    assert any(m.startswith(message) and (line, col) == where(text, fragment)
               for line, col, m, _ in found), found


def test_a_misspelt_sensor_gets_a_hint():
    found = errors(SMALL_TEXT.replace("sample temp,", "sample tmep,"))
    assert found[0][3] == "did you mean 'temp'?"


def test_a_glider_named_twice_and_one_without_a_start_are_both_refused():
    text = SMALL_TEXT.replace("glider charlie", "glider alpha").replace(
        "  start (3927.0, -7401.0)\n", "")
    messages = [m for _, _, m, _ in errors(text)]
    assert "glider 'alpha' is named twice" in messages
    assert "glider 'bravo' has no start position" in messages


def test_overlapping_areas_are_refused_at_the_second():
    second = "  area (3922.0, -7358.0), (3927.0, -7358.0), (3927.0, -7345.0), (3922.0, -7345.0)\n"
    text = SMALL_TEXT.replace("end\n\nsample", second + "end\n\nsample")
    found = errors(text)
    assert len(found) == 1
    line, _, message, hint = found[0]
    assert line == where(text, second.strip())[0]
    assert message.startswith("this area overlaps the area on line 12")
    assert "merge the two areas" in hint


def test_areas_that_only_touch_along_an_edge_do_not_overlap():
    beside = "  area (3925.0, -7400.0), (3928.0, -7400.0), (3928.0, -7352.0), (3925.0, -7352.0)\n"
    text = SMALL_TEXT.replace("end\n\nsample", beside + "end\n\nsample")
    assert errors(text) == []


@pytest.mark.parametrize("area, why", [
    ("area (3920.0, -7400.0), (3920.0, -7355.0), (3920.0, -7352.0)",
     "this area is empty: it encloses no area"),
    ("area (3920.0, -7400.0), (3920.5, -7400.0), (3920.5, -7352.0), (3920.0, -7352.0)",
     "this area is empty: no line fits at 2 km spacing"),
    ("area (3920.0, -7400.0), (3925.0, -7352.0), (3925.0, -7400.0), (3920.0, -7352.0)",
     "this area is not usable: its edges cross each other"),
])
def test_an_empty_or_crossed_area_is_refused(area, why):
    old = "area (3920.0, -7400.0), (3925.0, -7400.0), (3925.0, -7352.0), (3920.0, -7352.0)"
    text = SMALL_TEXT.replace(old, area)
    found = errors(text)
    assert found and found[0][2].startswith(why), found
    assert found[0][0] == where(text, area)[0]


def test_an_area_under_a_keep_out_is_empty_and_a_start_inside_one_is_refused():
    keepout = ("  keepout (3919.0, -7402.0), (3926.0, -7402.0), (3926.0, -7350.0), "
               "(3919.0, -7350.0)\n")
    text = SMALL_TEXT.replace("end\n\nsample", keepout + "end\n\nsample")
    messages = [m for _, _, m, _ in errors(text)]
    assert "this area is empty: keep-out areas cover it" in messages


def test_a_start_inside_a_keep_out_is_refused_at_the_start():
    keepout = ("  keepout (3918.0, -7402.0), (3919.5, -7402.0), (3919.5, -7359.0), "
               "(3918.0, -7359.0)\n")
    text = SMALL_TEXT.replace("end\n\nsample", keepout + "end\n\nsample")
    found = errors(text)
    assert [(line, m) for line, _, m, _ in found] == [
        (where(text, "start (3919.0, -7401.0)")[0], "glider 'alpha' starts inside a keep-out area")]


def test_more_gliders_than_lines_is_refused_at_the_first_glider_too_many():
    text = SMALL_TEXT.replace("spacing 2 km", "spacing 4 km")  # 2 lines for 3 gliders
    found = errors(text)
    assert len(found) == 1
    line, _, message, hint = found[0]
    assert line == where(text, "glider charlie")[0]
    assert message == "3 gliders share a survey of 2 parts: every glider needs one at least"
    assert "cut the survey finer" in hint


def test_a_transect_and_a_route_are_parts_and_a_transect_needs_two_points():
    text = SMALL_TEXT.replace(
        "    heading 90 deg\n",
        "    heading 90 deg\n  transect (3930.0, -7400.0), (3930.0, -7352.0)\n"
        "  waypoints (3932.0, -7400.0), (3934.0, -7355.0), (3932.0, -7352.0)\n")
    fleet = check_fleet_source(text, "t.fleet").fleet
    kinds = [p.kind for p in fleet.parts]
    assert kinds.count("transect") == 1 and kinds.count("waypoints") == 2
    bad = SMALL_TEXT.replace("    heading 90 deg\n", "    heading 90 deg\n  transect "
                             "(3930.0, -7400.0), (3930.0, -7355.0), (3930.0, -7352.0)\n")
    assert errors(bad)[0][2] == "a transect runs between 2 points, not 3"


def test_an_empty_file_says_what_a_fleet_file_holds():
    found = check_fleet_source("# nothing\n", "t.fleet").diagnostics
    assert found[0].message == "the file has only comments: there is no fleet in it"
    assert "fleet NAME" in found[0].hint


def test_checked_on_a_fleet_with_errors_raises_with_the_diagnostics():
    result = check_fleet_source(SMALL_TEXT.replace("sample temp,", "sample tmep,"), "t.fleet")
    with pytest.raises(FleetError) as raised:
        result.checked()
    assert raised.value.exit_code == ExitCode.BAD_INPUT
    assert "t.fleet:" in raised.value.details


def test_fleet_check_exits_0_for_a_good_file_1_for_a_bad_one_2_for_no_file(tmp_path, capsys):
    assert main(["fleet", "check", str(EXAMPLE)]) == ExitCode.OK
    assert "5 gliders, 12 lines" in capsys.readouterr().out
    bad = tmp_path / "bad.fleet"
    bad.write_text(SMALL_TEXT.replace("sample temp,", "sample tmep,"))
    assert main(["fleet", "check", str(bad)]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert f"{bad}:" in err and "error: 'tmep' is no sensor to sample" in err
    assert main(["fleet", "check", str(tmp_path / "none.fleet")]) == ExitCode.USAGE
    assert "none.fleet: no such file" in capsys.readouterr().err
    assert main(["fleet", "plan", str(bad)]) == ExitCode.BAD_INPUT


def test_fleet_without_an_action_is_bad_usage(capsys):
    with pytest.raises(SystemExit) as raised:
        main(["fleet"])
    assert raised.value.code == ExitCode.USAGE


def test_fleet_check_json_gives_each_diagnostic_at_its_line(tmp_path, capsys):
    assert main(["fleet", "check", str(EXAMPLE), "--json"]) == ExitCode.OK
    report = json.loads(capsys.readouterr().out)
    assert report["ok"] and report["fleet"]["lines"] == 12 and report["diagnostics"] == []
    bad = tmp_path / "bad.fleet"
    bad.write_text(SMALL_TEXT.replace("sample temp,", "sample tmep,"))
    assert main(["fleet", "check", str(bad), "--json"]) == ExitCode.BAD_INPUT
    report = json.loads(capsys.readouterr().out)
    assert report["ok"] is False and report["exit_code"] == 1 and report["fleet"] is None
    (found,) = report["diagnostics"]
    line = next(n for n, t in enumerate(SMALL_TEXT.splitlines(), 1)
                if t.startswith("sample temp,"))
    assert (found["file"], found["line"], found["severity"]) == (str(bad), line, "error")
    assert "'tmep' is no sensor to sample" in found["message"]
