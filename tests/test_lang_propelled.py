"""Propelled flight in the language: `cruise(depth, speed)`, `altitude(height, speed)`,
a thruster assist on a yo (`thrust 3 W`) and `auto` settings, checked against the
mission's vehicle with a location for every error."""

from __future__ import annotations

import subprocess
import sys

import pytest

from gliderplan.language import check_source
from gliderplan.language.formatter import format_source

_TEMPLATE = """mission m
vehicle {vehicle}
state s1
begin
  flightprofile {profile}
  sensors missiontime, depth
  events
    case missiontime > 100 exit
end
"""


def _check(vehicle: str, profile: str):
    return check_source(_TEMPLATE.format(vehicle=vehicle, profile=profile), "m.mission")


@pytest.mark.parametrize(("vehicle", "profile"), [
    ("lauv", "cruise(10, auto)"),
    ("lauv", "cruise(10, 1.2) | altitude(5, auto)"),
    ("lauv", "surface"),
    ("slocum_g3_hybrid", "yo(5, 20, .454, .454) thrust 3 W"),
    ("slocum_g3_hybrid", "yo(5, 20, .454, .454) thrust auto | cruise(10, auto)"),
    ("slocum_g2_shallow", "yo(5, 20, .454, .454)"),
])
def test_a_vehicle_flies_what_it_can(vehicle: str, profile: str) -> None:
    result = _check(vehicle, profile)
    assert result.ok, [d.message for d in result.diagnostics]


def test_auto_speed_and_thrust_reach_the_checked_mission() -> None:
    state = _check("slocum_g3_hybrid", "cruise(10, auto) | yo(5, 20, .454, .454) thrust 2.5 W"
                   ).mission.states[0]
    cruise, yo = state.profiles
    assert (cruise.kind, cruise.auto, len(cruise.args), cruise.propelled) == \
        ("cruise", ("speed",), 1, True)
    assert (yo.thrust, yo.propelled) == (2.5, True)


@pytest.mark.parametrize(("vehicle", "profile", "where", "message"), [
    ("slocum_g2_shallow", "cruise(10, 1)", (5, 17),
     "'cruise' flies on a propeller, and vehicle slocum_g2_shallow is a glider without one"),
    ("lauv", "yo(5, 20, .454, .454)", (5, 17),
     "'yo' flies on a buoyancy engine, and vehicle lauv is an auv without one"),
    ("lauv", "cruise(10, 3)", (5, 28),
     "vehicle lauv: 3 m/s is beyond the propulsion's 0.556-1.56 m/s"),
    ("slocum_g3_hybrid", "yo(5, 20, .454, .454) thrust -2 W", (5, 46),
     "thrust must be positive, got -2 W"),
    ("slocum_g3_hybrid", "yo(5, 20, .454, .454) thrust 12 W", (5, 46),
     "vehicle slocum_g3_hybrid: 12 W is beyond the thruster's power-command range (1-9 W)"),
    ("slocum_g2_shallow", "yo(5, 20, .454, .454) thrust 3 W", (5, 46),
     "vehicle slocum_g2_shallow has no thruster to assist a yo"),
    ("lauv", "cruise(10, 1) thrust 3 W", (5, 38), "a thruster assists a yo, not 'cruise'"),
    ("lauv", "cruise(auto, 1)", (5, 24), "'depth' of 'cruise' cannot be 'auto'"),
    ("lauv", "cruise(10, -1)", (5, 28), "speed of 'cruise' is -1 m/s, outside"),
    ("slocum_g3_hybrid", "yo(5, 20, .454, .454) thrust 3 kJ", (5, 48), "unit"),
])
def test_what_a_vehicle_cannot_fly_is_refused_where_it_is_written(
        vehicle: str, profile: str, where: tuple[int, int], message: str) -> None:
    result = _check(vehicle, profile)
    errors = [d for d in result.diagnostics if d.is_error]
    assert errors and message in errors[0].message, [d.message for d in errors]
    assert (errors[0].span.line, errors[0].span.column) == where


def test_the_formatter_keeps_auto_and_thrust() -> None:
    source = _TEMPLATE.format(vehicle="slocum_g3_hybrid",
                              profile="cruise(10,auto) | yo(5,20,.454,.454) thrust  3 W")
    formatted = format_source(source)
    assert "flightprofile cruise(10, auto) | yo(5, 20, .454, .454) thrust 3 W" in formatted
    assert format_source(formatted) == formatted


def test_check_on_the_command_line_says_file_line_and_exits_1(tmp_path) -> None:
    path = tmp_path / "glider.mission"
    path.write_text(_TEMPLATE.format(vehicle="slocum_g2_shallow", profile="cruise(10, 1)"))
    run = subprocess.run([sys.executable, "-m", "gliderplan.cli", "check", str(path)],
                         capture_output=True, text=True)
    assert run.returncode == 1
    assert f"{path}:5:17: error: 'cruise' flies on a propeller" in run.stderr
    assert "Traceback" not in run.stderr
