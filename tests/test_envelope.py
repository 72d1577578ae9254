"""The safety envelope: a command outside the vehicle's rating, whatever computed it, is
held or ends the flight alike in the C runtime and the Python executor; `sim` says so and
exits 5; `check` refuses what it can prove out of range, with its place."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gliderplan.cli.main import main
from gliderplan.contract import Envelope, EnvelopeAction, ExitCode, PumpEnergy
from gliderplan.power_models.vehicle_figures import load_envelope

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


def _flown_alike(mission: Path, tmp_path: Path, capsys, code: int, ended: str,
                 runtimes: tuple[str, ...] = ("c",)) -> tuple[tuple, dict[str, tuple]]:
    """`mission` flown by the Python reference and each of `runtimes` (the board binary
    over the pty: "c"; the step in the C flight: "step"): the same exit `code`, the same
    transitions at the same times, an end starting with `ended` and the envelope's same
    words in each; the reference's flight and the others' (by runtime) are returned."""
    python = _sim(mission, tmp_path / "py", "python", capsys)
    others = {}
    for runtime in runtimes:
        others[runtime] = other = _sim(mission, tmp_path / runtime, runtime, capsys)
        assert python[0] == other[0] == code, (runtime, python[3], other[3])
        assert python[1] == other[1], runtime
        assert python[2]["ended"].startswith(ended), runtime
        assert other[2]["ended"].startswith(ended), runtime
        assert python[2]["envelope"] == other[2]["envelope"], runtime
    return python, others


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
    python, _ = _flown_alike(mission, tmp_path, capsys, ExitCode.ENVELOPE, ended, ("c", "step"))
    assert python[2]["ended"] == ended
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
    python, _ = _flown_alike(mission, tmp_path, capsys, code, ended)
    assert python[2]["ended"] == ended and python[2]["envelope"] == envelope


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


@pytest.mark.parametrize(("vehicle", "rate", "code", "rated"), [
    # the shallow Slocum's max_turn_rate: 0.154 rad/s, 8.82 deg/s, either way
    ("slocum_g2_shallow", "-9", ExitCode.BAD_INPUT, "8.82"),
    ("slocum_g2_shallow", "8.8", ExitCode.OK, "8.82"),
    # the propeller AUV's: its autopilot's 30 deg/s (issue 28)
    ("lauv", "40", ExitCode.BAD_INPUT, "30"), ("lauv", "-29", ExitCode.OK, "30")])
def test_check_refuses_a_turn_faster_than_the_vehicle_s_rated_turn_rate(tmp_path, capsys,
                                                                          vehicle, rate, code,
                                                                          rated):
    profile = "cruise(10, 1)" if vehicle == "lauv" else "yo(5, 20, .454, .454)"
    mission = tmp_path / "m.mission"
    mission.write_text(f"""mission m
vehicle {vehicle}

state s1
begin
  flightroute turn({rate})
  flightprofile {profile}
  sensors missiontime, depth
  events
    case missiontime >= 100 exit
end
""")
    assert main(["check", str(mission)]) == code
    err = capsys.readouterr().err
    assert (f"m.mission:6:20: error: turn rate {rate} deg/s is beyond the vehicle's rated "
            f"{rated} deg/s" in err) == (code == ExitCode.BAD_INPUT), err


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


def _vehicle_with(tmp_path: Path, name: str, base: Path, lines: str, action: str) -> Path:
    """A copy of a shipped vehicle file with `lines` added to its [envelope] and `action`."""
    text = base.read_text().replace('action = "surface"', f'{lines}\naction = "{action}"')
    vehicle = tmp_path / f"{name}_{action}.toml"
    vehicle.write_text(text)
    return vehicle


LAUV = ROOT / "power_models" / "data" / "vehicle_lauv.toml"


def _fast_cruise(tmp_path: Path, action: str) -> Path:
    """A cruise on the propeller AUV whose speed a variable sets past its table at 300 s."""
    vehicle = _vehicle_with(tmp_path, "lauv", LAUV, "", action)
    mission = tmp_path / f"speed_{action}.mission"
    mission.write_text(f"""mission fast
vehicle "{vehicle}"
horizon 20 min
var speed = 1

state s1
begin
  flightroute noheading
  flightprofile cruise(10, speed)
  sensors missiontime, depth
  events
    case missiontime >= 300 && speed == 1 set speed = 3
    case missiontime >= 1000 exit
end
""")
    return mission


@needs_cc
@pytest.mark.parametrize(("action", "ended", "what"), [
    ("surface", "envelope", "the mission ends, surfacing"),
    ("clamp", "exit", "held at the limit"),
    ("fault", "fault", "releasing control"),
])
def test_both_runtimes_hold_a_speed_past_the_propulsion_s_table_alike(tmp_path, capsys, action,
                                                                     ended, what):
    mission = _fast_cruise(tmp_path, action)
    python, others = _flown_alike(mission, tmp_path, capsys, ExitCode.ENVELOPE, ended)
    c = others["c"]
    assert python[2]["envelope"] == [
        "envelope: missiontime 300 s, state s1 (line 9): speed 3 m/s beyond the vehicle's "
        f"1.55556 m/s; {what}"]  # the table's top: 1400 rpm at 1 m/s per 900 rpm
    assert python[2]["energy_j"] == pytest.approx(c[2]["energy_j"], rel=1e-9)


def _yo_with_pump(tmp_path: Path, action: str, power_w: float) -> Path:
    """The paper's 5-10 m yo on the shallow glider rated for `power_w` of pumping."""
    vehicle = _vehicle_with(tmp_path, "g2", G2, f'max_pump_power = {{ value = {power_w}, '
                            'unit = "W", source = "a test" }', action)
    mission = tmp_path / f"pump_{action}.mission"
    mission.write_text(f"""mission pumping
vehicle "{vehicle}"
horizon 2 h

state s1
begin
  flightroute noheading
  flightprofile yo(5, 10, .454, .454)
  sensors missiontime, depth
  events
    case missiontime >= 5400 exit
end
""")
    return mission


@needs_cc
@pytest.mark.parametrize(("action", "ended", "what"), [
    ("surface", "envelope", "the mission ends, surfacing"),
    ("clamp", "envelope", "the mission ends, surfacing"),  # energy spent cannot be held back
    ("fault", "fault", "releasing control"),
])
def test_both_runtimes_stop_a_pump_working_past_its_energy_per_hour_alike(
        tmp_path, capsys, action, ended, what):
    mission = _yo_with_pump(tmp_path, action, 1.0)  # the yo pumps ~2.4 W on average
    python, _ = _flown_alike(mission, tmp_path, capsys, ExitCode.ENVELOPE, ended)
    note = python[2]["envelope"][0]
    assert "state s1 (line 8): pump energy within an hour" in note
    assert "beyond the vehicle's 3600 J" in note and note.endswith(what)
    ended_s = float(note.split("missiontime ")[1].split(" s")[0])
    assert 1500 < ended_s < 3600  # a bucket of 3600 J, filled at ~2.4 W, paid back at 1 W


def test_a_pump_within_its_energy_per_hour_flies_on(tmp_path, capsys):
    mission = _yo_with_pump(tmp_path, "surface", 4.0)
    code, _, summary, said = _sim(mission, tmp_path / "py", "python", capsys)
    assert code == ExitCode.OK, said
    assert summary["envelope"] == [] and summary["ended"] == "exit"


def _zigzag(tmp_path: Path, action: str, name: str = "g2", base: Path = G2,
            profile: str = "yo(5, 20, .454, .454)") -> Path:
    """Two states whose waypoints lie either side of the vehicle (a copy of `base` with
    `action`, flying `profile`), swapped every 60 s."""
    vehicle = _vehicle_with(tmp_path, name, base, "", action)
    mission = tmp_path / f"zigzag_{action}.mission"
    mission.write_text(f"""mission zigzag
vehicle "{vehicle}"
horizon 30 min
var next = 60

state east
begin
  flightroute nav(3910.5, -7340.0)
  flightprofile {profile}
  sensors missiontime, depth
  events
    case missiontime >= 1200 exit
    case missiontime >= next set next = next + 60 goto west
end

state west
begin
  flightroute nav(3910.5, -7355.0)
  flightprofile {profile}
  sensors missiontime, depth
  events
    case missiontime >= 1200 exit
    case missiontime >= next set next = next + 60 goto east
end
""")
    return mission


def _track_turns_rad(out: Path) -> np.ndarray:
    """|change of the track's direction| [rad] from one tick to the next, where the glider
    moved on both (no current: the track is the heading commanded)."""
    frame = pd.read_parquet(out / "timeseries.parquet")
    north = np.diff(frame["lat_deg"].to_numpy())
    east = np.diff(frame["lon_deg"].to_numpy()) * np.cos(np.radians(39.17))
    bearing = np.where(np.hypot(north, east) > 1e-9, np.arctan2(east, north), np.nan)
    turns = np.abs(np.angle(np.exp(1j * np.diff(bearing))))
    return turns[~np.isnan(turns)]


@needs_cc
@pytest.mark.parametrize("action", ["surface", "clamp", "fault"])
def test_both_runtimes_turn_the_heading_at_the_rated_rate_under_every_action(
        tmp_path, capsys, action):
    mission = _zigzag(tmp_path, action)
    python, _ = _flown_alike(mission, tmp_path, capsys, ExitCode.OK, "")  # flown, not refused
    assert python[2]["envelope"] == []
    turns = _track_turns_rad(tmp_path / "py")
    assert np.array_equal(turns, _track_turns_rad(tmp_path / "c"))
    # each swap asks a half turn at once; the glider turns 0.154 rad/s x 4 s a tick
    assert 0.5 < turns.max() <= 0.154 * 4.0 * 1.001  # the track's bearing: to 1e-3


def test_without_a_turn_rate_the_same_swaps_turn_at_once(tmp_path, capsys):
    mission = _zigzag(tmp_path, "surface")
    vehicle = tmp_path / "g2_surface.toml"
    vehicle.write_text("\n".join(line for line in vehicle.read_text().splitlines()
                                 if not line.startswith("max_turn_rate")))
    code, _, _, said = _sim(mission, tmp_path / "py", "python", capsys)
    assert code == ExitCode.OK, said
    assert _track_turns_rad(tmp_path / "py").max() > 2 * 0.154 * 4.0  # the test above bites


def test_the_propeller_auv_turns_no_faster_than_its_autopilot_s_heading_rate(tmp_path,
                                                                             capsys):
    """Issue 28: the LAUV had no turn rate, and turned any half turn within a tick. Its
    autopilot's heading-rate limit, 30 deg/s, holds its turns to 2.09 rad a tick of 4 s:
    each swap's half turn takes two."""
    mission = _zigzag(tmp_path, "surface", "lauv", LAUV, "cruise(10, 1)")
    code, _, summary, said = _sim(mission, tmp_path / "py", "python", capsys)
    assert code == ExitCode.OK and summary["envelope"] == [], said
    turns = _track_turns_rad(tmp_path / "py")
    rated = math.radians(30.0) * 4.0
    assert 0.9 * rated < turns.max() <= rated * 1.001  # the track's bearing: to 1e-3


def _fastest_mps(out: Path) -> float:
    """The glider's fastest horizontal speed [m/s] over one tick of 4 s in a run."""
    frame = pd.read_parquet(out / "timeseries.parquet")
    step_m = np.hypot(np.diff(frame["lat_deg"].to_numpy()) * 111_195.0,
                      np.diff(frame["lon_deg"].to_numpy()) * 111_195.0
                      * np.cos(np.radians(39.17)))
    return float(step_m.max()) / 4.0


def test_a_glider_flies_no_faster_than_its_held_pitch_and_pump_allow(tmp_path, capsys):
    """A glider has no speed command: its speed follows from pitch and pumped volume, which
    the guard holds. A mission asking a steep pitch on the clamp action flies no faster
    than one written at the rating's pitch, with the same full stroke."""
    vehicle = _vehicle_with(tmp_path, "g2", G2, "", "clamp")
    text = f"""mission steep
vehicle "{vehicle}"
horizon 30 min
var steep = PITCH

state s1
begin
  flightroute nav(3910.5, -7340.0)
  flightprofile yo(5, 90, steep, steep)
  sensors missiontime, depth
  events
    case missiontime >= 60 && steep < .5 set steep = 1.5
    case missiontime >= 1500 exit
end
"""
    asked, rated = tmp_path / "asked.mission", tmp_path / "rated.mission"
    asked.write_text(text.replace("PITCH", ".454"))
    rated_rad = load_envelope(str(vehicle)).max_pitch_rad
    rated.write_text(text.replace("PITCH", repr(rated_rad)))
    code, _, summary, said = _sim(asked, tmp_path / "asked", "python", capsys)
    assert code == ExitCode.ENVELOPE and "pitch -1.5 rad" in summary["envelope"][0], said
    assert "held at the limit" in summary["envelope"][0]
    code, _, summary, said = _sim(rated, tmp_path / "rated", "python", capsys)
    assert code == ExitCode.OK and summary["envelope"] == [], said
    assert _fastest_mps(tmp_path / "asked") <= _fastest_mps(tmp_path / "rated") * (1 + 1e-9)
    assert _fastest_mps(tmp_path / "asked") > 0.3  # it flew, at the rated pitch


def test_check_refuses_a_constant_speed_beyond_the_rating_with_its_place(tmp_path, capsys):
    mission = tmp_path / "m.mission"
    mission.write_text("""mission m
vehicle lauv

state s1
begin
  flightroute nav(3910.5, -7340.0)
  flightprofile cruise(20, 3)
  sensors missiontime, depth
  events
    case missiontime >= 100 exit
end
""")
    assert main(["check", str(mission)]) == ExitCode.BAD_INPUT
    assert "m.mission:7:28: error: vehicle lauv: 3 m/s is beyond the propulsion's" in \
        capsys.readouterr().err
    mission.write_text(mission.read_text().replace("cruise(20, 3)", "cruise(20, 1.2)"))
    assert main(["check", str(mission)]) == ExitCode.OK, capsys.readouterr().err


@pytest.mark.parametrize(("line", "problem"), [
    ('max_turn_rate = { value = -0.1, unit = "rad/s", source = "x" }', "max_turn_rate"),
    ('max_turn_rate = { value = nan, unit = "rad/s", source = "x" }', "max_turn_rate"),
    ('max_pump_power = { value = 0, unit = "W", source = "x" }', "max_pump_power"),
    ('max_pump_power = { value = inf, unit = "W", source = "x" }', "max_pump_power"),
    ('max_turn_rate = { value = 8, unit = "rad", source = "x" }', "max_turn_rate"),
])
def test_a_bad_turn_rate_or_pump_rating_is_refused_with_its_place(tmp_path, capsys, line,
                                                                   problem):
    vehicle = tmp_path / "bad.toml"
    vehicle.write_text("\n".join(x for x in G2.read_text().splitlines()
                                 if not x.startswith("max_turn_rate")).replace(
        "[envelope]", f"[envelope]\n{line}"))
    mission = tmp_path / "m.mission"
    mission.write_text((ROOT / "examples" / "fig2.mission").read_text().replace(
        "mission sampleMission", f'mission sampleMission\nvehicle "{vehicle}"'))
    assert main(["sim", str(mission), "-o", str(tmp_path / "out")]) == ExitCode.BAD_INPUT
    err = capsys.readouterr().err
    assert "bad.toml" in err and problem in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("bad", [
    {"speed_range_mps": (1.0, 0.5)}, {"speed_range_mps": (0.5, math.inf)},
    {"thrust_range_w": (-1.0, 9.0)}, {"max_turn_rate_rad_s": 0.0},
    {"max_turn_rate_rad_s": math.nan}, {"max_pump_power_w": -1.0},
    {"pump": PumpEnergy(out_j_per_cc=math.inf)},
])
def test_the_contract_refuses_an_envelope_with_a_bad_figure(bad):
    good = {"max_depth_m": 100.0, "max_pitch_rad": 0.9, "min_yo_band_m": 3.0,
            "min_inflection_s": 11.0, "action": EnvelopeAction.SURFACE}
    Envelope(**good)
    with pytest.raises(ValueError, match="not an envelope"):
        Envelope(**good, **bad)
