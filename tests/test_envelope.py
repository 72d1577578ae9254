"""The safety envelope: a command outside the vehicle's rating, whatever computed it, is
held or ends the flight alike in the C runtime and the Python executor; `sim` says so and
exits 5; `check` refuses what it can prove out of range, with its place."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode

ROOT = Path(__file__).resolve().parents[1]
G2 = ROOT / "power_models" / "data" / "vehicle_slocum_g2_shallow.toml"
needs_cc = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")


def _mission(tmp_path: Path, action: str, assignment: str) -> Path:
    """A yo whose bottom a variable sets at 300 s, on the shallow glider with `action`."""
    vehicle = tmp_path / f"g2_{action}.toml"
    vehicle.write_text(G2.read_text().replace('action = "surface"', f'action = "{action}"'))
    mission = tmp_path / f"{action}.mission"
    mission.write_text(f"""mission deep
vehicle "{vehicle}"
horizon 20 min
var bottom = 10

state s1
begin
  flightroute noheading
  flightprofile yo(5, bottom, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 300 && bottom == 10 {assignment}
    case missiontime >= 1000 exit
end
""")
    return mission


def _sim(mission: Path, out: Path, runtime: str, capsys) -> tuple[int, str, dict, str]:
    code = main(["sim", str(mission), "--runtime", runtime, "--noise", "none", "-o", str(out)])
    said = capsys.readouterr().err
    return code, (out / "trace.csv").read_text(), json.loads(
        (out / "summary.json").read_text()), said


@needs_cc
@pytest.mark.parametrize(("action", "assignment", "ended", "says"), [
    ("surface", "set bottom = 3000", "envelope",
     "missiontime 300 s, state s1 (line 9): depth 3000 m beyond the vehicle's 100 m; "
     "the mission ends, surfacing"),
    ("clamp", "set bottom = 3000", "exit",
     "missiontime 300 s, state s1 (line 9): depth 3000 m beyond the vehicle's 100 m; "
     "held at the limit"),
    ("surface", "set bottom = 6", "envelope",
     "missiontime 300 s, state s1 (line 9): yo band 1 m beyond the vehicle's 3 m; "
     "the mission ends, surfacing"),
    ("clamp", "set bottom = -1000", "envelope", "state s1 (line 9): time between inflections"),
])
def test_both_runtimes_hold_a_variable_to_the_rating_alike(tmp_path, capsys, action,
                                                            assignment, ended, says):
    mission = _mission(tmp_path, action, assignment)
    python = _sim(mission, tmp_path / "py", "python", capsys)
    for runtime in ("c", "step"):  # the board binary, the step in the C flight
        c = _sim(mission, tmp_path / runtime, runtime, capsys)
        assert python[0] == c[0] == ExitCode.ENVELOPE, runtime
        assert python[1] == c[1], runtime  # the same transitions at the same times
        assert python[2]["ended"] == c[2]["ended"] == ended, runtime
        assert python[2]["envelope"] == c[2]["envelope"], runtime
    assert says in python[2]["envelope"][-1]
    assert says in python[3] and "outside its rating" in python[3]


@needs_cc
def test_the_fault_action_releases_control_and_the_sim_exits_5(tmp_path, capsys):
    mission = _mission(tmp_path, "fault", "set bottom = 3000")
    for runtime in ("python", "c", "step"):
        code, trace, summary, said = _sim(mission, tmp_path / runtime, runtime, capsys)
        assert code == ExitCode.ENVELOPE, said
        assert summary["ended"].startswith("fault")
        assert trace.splitlines()[1:] == ["0,start,,s1,0"]
        assert summary["envelope"] == ["envelope: missiontime 300 s, state s1 (line 9): depth "
                                       "3000 m beyond the vehicle's 100 m; releasing control"]


def test_a_flight_within_the_rating_is_untouched(tmp_path, capsys):
    mission = _mission(tmp_path, "surface", "set bottom = 20")
    code, trace, summary, _ = _sim(mission, tmp_path / "py", "python", capsys)
    assert code == ExitCode.OK
    assert summary["envelope"] == [] and summary["ended"] == "exit"


def _cruise(tmp_path: Path, assignment: str) -> Path:
    """A cruise on the propeller AUV whose depth a variable sets at 300 s."""
    mission = tmp_path / "cruise.mission"
    mission.write_text(f"""mission level
vehicle lauv
horizon 20 min
var level = 10

state s1
begin
  flightroute noheading
  flightprofile cruise(level, 1)
  sensors missiontime, depth
  events
    case missiontime >= 300 && level == 10 {assignment}
    case missiontime >= 1000 exit
end
""")
    return mission


@needs_cc
@pytest.mark.parametrize(("assignment", "code", "ended", "envelope"), [
    ("set level = 20", ExitCode.OK, "exit", []),  # pitch and volume 0: within the rating
    ("set level = 3000", ExitCode.ENVELOPE, "envelope",
     ["envelope: missiontime 300 s, state s1 (line 9): depth 3000 m beyond the vehicle's "
      "100 m; the mission ends, surfacing"]),
])
def test_both_runtimes_hold_a_cruise_to_the_rating_alike(tmp_path, capsys, assignment, code,
                                                         ended, envelope):
    mission = _cruise(tmp_path, assignment)
    python = _sim(mission, tmp_path / "py", "python", capsys)
    c = _sim(mission, tmp_path / "c", "c", capsys)
    assert python[0] == c[0] == code, (python[3], c[3])
    assert python[1] == c[1]
    assert python[2]["ended"] == c[2]["ended"] == ended
    assert python[2]["envelope"] == c[2]["envelope"] == envelope


@pytest.mark.parametrize(("text", "problem"), [
    ('action = "brake"', "expected fault, surface or clamp"),
    ("max_depth = { value = 20, unit = \"m\", source = \"x\" }",
     "must be deeper than the vehicle's nominal_max_depth"),
])
def test_a_bad_envelope_table_is_refused_with_its_key(tmp_path, capsys, text, problem):
    vehicle = tmp_path / "bad.toml"
    lines = G2.read_text().replace('action = "surface"', "").replace(
        'max_depth = { value = 100, unit = "m", source = ', "#")
    vehicle.write_text(lines.replace("[envelope]", f"[envelope]\n{text}"))
    mission = tmp_path / "m.mission"
    mission.write_text((ROOT / "examples" / "fig2.mission").read_text().replace(
        "mission sampleMission", f'mission sampleMission\nvehicle "{vehicle}"'))
    assert main(["sim", str(mission), "-o", str(tmp_path / "out")]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert "envelope" in err and problem in err


@pytest.mark.parametrize(("profile", "where", "message"), [
    ("yo(5, 1500, .454, .454)", "7:23", "max depth 1500 m is beyond the vehicle's rated 100 m"),
    ("yo(5, 20, .454, 1.2)", "7:33", "climb pitch 1.2 rad is beyond the vehicle's 0.908 rad"),
    ("yo(5, 6, .454, .454)", "7:17", "yo band 1 m is thinner than the vehicle's 3 m"),
    ("hover(250)", "7:23", "depth 250 m is beyond the vehicle's rated 100 m"),
])
def test_check_refuses_a_profile_it_can_prove_out_of_range_with_its_place(
        tmp_path, capsys, profile, where, message):
    mission = tmp_path / "m.mission"
    mission.write_text(f"""mission m
vehicle slocum_g2_shallow

state s1
begin
  flightroute noheading
  flightprofile {profile}
  sensors missiontime, depth
  events
    case missiontime >= 100 exit
end
""")
    assert main(["check", str(mission)]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert f"m.mission:{where}: error: {message}" in err
    assert "the rating of vehicle slocum_g2_shallow (its file's [envelope])" in err


def test_check_passes_the_shipped_examples_within_their_vehicles_ratings(capsys):
    missions = sorted(str(p) for p in (ROOT / "examples").glob("*.mission"))
    assert main(["check", *missions]) == ExitCode.OK


def test_check_refuses_a_cruise_beyond_the_auv_s_rating(tmp_path, capsys):
    mission = tmp_path / "m.mission"
    mission.write_text("""mission m
vehicle lauv

state s1
begin
  flightroute noheading
  flightprofile cruise(150, auto)
  sensors missiontime, depth
  events
    case missiontime >= 100 exit
end
""")
    assert main(["check", str(mission)]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert "m.mission:7:24: error: depth 150 m is beyond the vehicle's rated 100 m" in err
    assert "the rating of vehicle lauv (its file's [envelope])" in err
    mission.write_text(mission.read_text().replace("cruise(150,", "cruise(50,"))
    assert main(["check", str(mission)]) == ExitCode.OK, capsys.readouterr().err
