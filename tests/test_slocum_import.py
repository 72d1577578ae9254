"""Slocum missions imported as a pilot would: the real helgo and nsb3 missions import,
check, plan and fly, and the simulated glider keeps the yo band, the waypoints in
their order and the surfacing schedule their .ma files give (read here on their own,
not through the importer); bad files stop with one line naming file and line."""

from __future__ import annotations

import itertools
import math
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import check_file
from gliderplan.language.registry import SENSOR_BY_NAME
from gliderplan.language.slocum import import_mission
from gliderplan.language.slocum_files import SlocumFileError
from gliderplan.language.slocum_sampling import yo_phases
from gliderplan.power_models import load_sensor, load_vehicle
from gliderplan.sim.geo import ddmm_to_degrees
from gliderplan.sim.science import NOISE_PRESETS

REPO = Path(__file__).resolve().parents[1]
MISSIONS = REPO.parent / "shared" / "data" / "slocum-missions"
TICK_S = 4.0
METRES_PER_DEGREE = 6371000.0 * np.pi / 180.0
# the yo turns on the depth reading: the true depth may lie this far short of the target
READING_ERROR_M = 5 * NOISE_PRESETS["ctd"].depth_sigma_m


def _needs_missions() -> None:
    if not MISSIONS.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"the Slocum missions are missing: {MISSIONS}")
        pytest.skip("the Slocum missions are not present")


def ma_args(path: Path) -> dict[str, float]:
    """The b_args of a .ma file, read with nothing but a regular expression."""
    found = re.findall(r"^\s*b_arg:\s*(\w+)\([^)]*\)\s+(\S+)", path.read_text(), re.M)
    return {name: float(value) for name, value in found}


def ma_waypoints(path: Path) -> list[tuple[float, float]]:
    """(lat, lon) DDMM.MMMM of a goto list, from its (lon, lat) lines."""
    block = path.read_text().split("<start:waypoints>")[1].split("<end:waypoints>")[0]
    points = []
    for line in block.splitlines():
        fields = line.split("#")[0].split()
        if len(fields) == 2:
            points.append((float(fields[1]), float(fields[0])))
    return points


@pytest.fixture(scope="module")
def flown(tmp_path_factory) -> dict[str, Path]:
    """Each real mission imported, checked, planned and flown for its 7-day horizon."""
    _needs_missions()
    runs = {}
    # helgo's c_science_all_on powers every science device gliderplan models (a warning),
    # more than the default pack holds for 7 days: it flies a larger battery (a plan made
    # with `plan --battery` would be refused on the mission's own)
    for name, extra in (("helgo", ["--allow-missing-mafiles", "--battery",
                                   "3 kWh reserve 15 %"]), ("nsb3", [])):
        out = tmp_path_factory.mktemp(name)
        mission = out / f"{name}.mission"
        assert main(["import-slocum", str(MISSIONS / name / f"{name}.mi"), *extra,
                     "-o", str(mission)]) == 0
        assert main(["check", "--strict", str(mission)]) == 0
        assert main(["plan", str(mission), "-o", str(out / f"{name}.plan")]) == 0
        assert main(["sim", str(mission), "--plan", str(out / f"{name}.plan"),
                     "-o", str(out / "run")]) == 0
        runs[name] = out
    return runs


def _series(run: Path) -> pd.DataFrame:
    return pd.read_parquet(run / "run" / "timeseries.parquet")


def _turns(depth: np.ndarray) -> tuple[list[float], list[float]]:
    """Depths of the yo's bottoms and tops (local extremes) in a depth series."""
    bottoms, tops = [], []
    for i in range(1, len(depth) - 1):
        if depth[i] >= depth[i - 1] and depth[i] > depth[i + 1]:
            bottoms.append(float(depth[i]))
        elif depth[i] <= depth[i - 1] and depth[i] < depth[i + 1] and depth[i] > 0.3:
            tops.append(float(depth[i]))
    return bottoms, tops


@pytest.mark.parametrize("name, yo", [("helgo", "yo50.ma"), ("nsb3", "yo10.ma")])
def test_the_glider_flies_the_yo_band_of_the_ma_file(flown, name, yo):
    args = ma_args(MISSIONS / name / "mafiles" / yo)
    table = _series(flown[name])
    survey = table[table["state"] == "survey"]
    bottoms, tops = _turns(survey["depth_m"].to_numpy())
    assert len(bottoms) > 50
    # turns on the tick the depth reading passes the target: within one tick's glide (< 1 m)
    assert min(bottoms) >= args["d_target_depth"] - READING_ERROR_M
    assert max(bottoms) < args["d_target_depth"] + 1.0
    assert all(args["c_target_depth"] - 1.0 < t <= args["c_target_depth"] + READING_ERROR_M
               for t in tops)


@pytest.mark.parametrize("name, goto", [("helgo", "goto_l50.ma"), ("nsb3", "goto_l10.ma")])
def test_the_glider_reaches_the_waypoints_in_the_ma_files_order(flown, name, goto):
    path = MISSIONS / name / "mafiles" / goto
    radius = ma_args(path)["list_when_wpt_dist"]
    points = ma_waypoints(path)
    table = _series(flown[name])
    lat, lon = table["lat_deg"].to_numpy(), table["lon_deg"].to_numpy()
    arrivals = []
    for k, (plat, plon) in enumerate(points):
        north = (ddmm_to_degrees(plat) - lat) * METRES_PER_DEGREE
        east = (ddmm_to_degrees(plon) - lon) * METRES_PER_DEGREE * np.cos(np.radians(lat))
        inside = np.hypot(north, east) <= radius + 2.0  # a tick's glide past the radius
        before = np.concatenate([[False], inside[:-1]])  # inside at the start: reached
        arrivals += [(int(i), k) for i in np.flatnonzero(inside & ~before)]
    order = [k for _, k in sorted(arrivals)]
    assert len(order) >= len(points)  # the whole list (nsb3: four times round in 7 days)
    assert order == [i % len(points) for i in range(len(order))]


def _surfacing_calls(run: Path) -> pd.DataFrame:
    trace = pd.read_csv(run / "run" / "trace.csv")
    return trace[(trace["kind"] == "call") & trace["to_state"].str.startswith("surface")]


def test_helgo_surfaces_after_the_yos_half_cycles(flown):
    half_cycles = ma_args(MISSIONS / "helgo" / "mafiles" / "yo50.ma")["num_half_cycles_to_do"]
    no_comm_s = ma_args(MISSIONS / "helgo" / "mafiles" / "surfac51.ma")["when_secs"]
    table = _series(flown["helgo"])
    calls = _surfacing_calls(flown["helgo"])
    assert len(calls) > 100
    assert set(calls["to_state"]) == {"surface_1"}  # never the no-comm one: calls every hour
    depth, state = table["depth_m"].to_numpy(), table["state"].to_numpy()
    ticks = (calls["time_s"] / TICK_S).astype(int).to_numpy()
    for a, b in zip(ticks, ticks[1:], strict=False):
        dives = depth[a:b][state[a:b] == "survey"]
        bottoms, tops = _turns(dives)
        assert len(bottoms) + len(tops) + 1 == half_cycles  # the last climb ends the yo
        assert depth[b] <= 3.1  # the surfacing starts where the last climb ended
    gaps = np.diff(calls["time_s"])
    assert gaps.max() < no_comm_s


def test_nsb3_surfaces_every_when_secs_after_reaching_the_surface(flown):
    every_s = ma_args(MISSIONS / "nsb3" / "mafiles" / "surfac10.ma")["when_secs"]
    table = _series(flown["nsb3"])
    calls = _surfacing_calls(flown["nsb3"])
    assert set(calls["to_state"]) == {"surface_3"}  # every 3 h, before the 12 h no-comm one
    assert len(calls) >= 7 * 86400 / (every_s + 1200) - 1
    surfaced = (table["state"].str.startswith("surface") & (table["depth_m"] <= 0.3)).to_numpy()
    arrivals = table["time_s"].to_numpy()[np.flatnonzero(surfaced[1:] & ~surfaced[:-1]) + 1]
    for call in calls["time_s"].iloc[1:]:
        last = arrivals[arrivals < call].max()
        assert call - last == pytest.approx(every_s, abs=2 * TICK_S)


def test_the_translation_says_what_it_left_out(flown, capsys):
    text = (flown["helgo"] / "helgo.mission").read_text()
    assert "left out: sample (helgo.mi:58), its .ma file sample50.ma is missing" in text
    # the altimeter stop is kept: yo's fifth argument, with a comment, and no warning
    assert "flightprofile yo(3, 50, 0.43, 0.43, 5)" in text
    assert "# d_target_altitude 5 m: a dive also turns 5 m above the sea floor" in text
    assert "not translated: d_target_altitude" not in text
    assert "flightroute goto_list(50, (5441, 647), (5413.5, 621.6), (5416, 723))" in text


def test_import_reports_warnings_with_file_and_line(tmp_path, capsys):
    _needs_missions()
    assert main(["import-slocum", str(MISSIONS / "nsb3" / "nsb3.mi"),
                 "-o", str(tmp_path / "n.mission")]) == 0
    err = capsys.readouterr().err
    assert re.search(r"nsb3/mafiles/yo10\.ma:8: warning: yo: not translated: d_use_pitch 1", err)
    assert "u_use_current_correction" not in err  # translated: current_correction on
    # what the science behaviors leave out is in the mission too, not only on the terminal
    assert re.search(r"nsb3\.mi:91: warning: sensors_in: not translated: c_att_time 0", err)
    text = (tmp_path / "n.mission").read_text()
    assert "# sensors_in (nsb3.mi:89): not translated: c_att_time 0, c_alt_time -1" in text
    assert "sensor_type 39" not in err  # the logger is a device of the power model


def test_nsb3_keeps_its_altimeter_stop_and_turns_above_the_north_sea_floor(tmp_path, capsys):
    _needs_missions()
    out = tmp_path / "n.mission"
    assert main(["import-slocum", str(MISSIONS / "nsb3" / "nsb3.mi"), "-o", str(out)]) == 0
    assert "d_target_altitude" not in capsys.readouterr().err  # no warning: it is translated
    text = out.read_text()
    assert "flightprofile yo(3, 50, 0.454, 0.454, 4)" in text  # yo10.ma: 50 m, 4 m above
    # flown over a floor of 40 m (the German Bight's 33-45 m) the dives turn near 36 m
    assert main(["sim", str(out), "--floor", "40", "--duration", "6h",
                 "-o", str(tmp_path / "run")]) == 0
    table = pd.read_parquet(tmp_path / "run" / "timeseries.parquet")
    bottoms, _ = _turns(table["depth_m"][table["state"] == "survey"].to_numpy())
    assert len(bottoms) > 5
    assert max(bottoms) < 37.0  # the stop, and the tick the pump takes to turn
    assert 36.0 - READING_ERROR_M <= float(np.median(bottoms))  # a surfacing cuts a few short


def test_a_climb_s_altitude_is_still_left_out_and_an_odd_yo_ends_at_the_stop(tmp_path, capsys):
    yo = YO_MA.replace("num_half_cycles_to_do(nodim) -1",
                       "num_half_cycles_to_do(nodim) 3\n b_arg: d_target_altitude(m) 4\n"
                       " b_arg: c_target_altitude(m) 6")
    path = _mission(tmp_path, "behavior: yo\n b_arg: args_from_file(enum) 10\n", yo10_ma=yo)
    out = tmp_path / "m.mission"
    assert main(["import-slocum", str(path), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "not translated: c_target_altitude 6" in err and "d_target_altitude" not in err
    text = out.read_text()
    assert "flightprofile yo(3, 20, 0.45, 0.45, 4)" in text
    # the third leg, a dive, ends where it turns: at 20 m or 4 m above the floor
    assert "halfcycle > 3 || halfcycle == 3 && (depth >= 20 || altitude <= 4)" in text


def test_a_missing_ma_file_stops_the_import_with_its_line(tmp_path, capsys):
    _needs_missions()
    out = tmp_path / "h.mission"
    assert main(["import-slocum", str(MISSIONS / "helgo" / "helgo.mi"), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert "helgo.mi:59: args_from_file 50: no file" in err and "sample50.ma" in err
    assert "Traceback" not in err and not out.exists()


def _mission(tmp_path: Path, mi: str, **mafiles: str) -> Path:
    (tmp_path / "mafiles").mkdir(exist_ok=True)
    for name, text in mafiles.items():
        (tmp_path / "mafiles" / name.replace("_ma", ".ma")).write_text(text)
    path = tmp_path / "m.mi"
    path.write_text(mi)
    return path


YO_MA = ("behavior_name=yo\n<start:b_arg>\n b_arg: d_target_depth(m) 20\n"
         " b_arg: c_target_depth(m) 3\n b_arg: d_use_pitch(enum) 3\n"
         " b_arg: d_pitch_value(X) -0.45\n b_arg: c_use_pitch(enum) 3\n"
         " b_arg: c_pitch_value(X) 0.45\n b_arg: num_half_cycles_to_do(nodim) -1\n<end:b_arg>\n")


SET_HEADING_MI = ("behavior: surface\n b_arg: start_when(enum) 9\n b_arg: when_secs(sec) 3600\n"
                  " b_arg: end_action(enum) 2\n b_arg: gps_wait_time(s) 120\n"
                  "behavior: set_heading\n b_arg: args_from_file(enum) 10\n"
                  "behavior: goto_list\n b_arg: args_from_file(enum) 10\n"
                  "behavior: yo\n b_arg: args_from_file(enum) 10\n")


def _set_heading_ma(mode: str, value: str) -> str:
    return (f"behavior_name=set_heading\n<start:b_arg>\n b_arg: use_heading(bool) {mode}\n"
            f" b_arg: heading_value(X) {value}\n<end:b_arg>\n")


def test_set_heading_is_a_heading_held_uncorrected_by_both_runtimes(tmp_path, capsys):
    # set_heading above the goto list: it commands the heading, the list is left out
    path = _mission(tmp_path, SET_HEADING_MI, yo10_ma=YO_MA,
                    goto_l10_ma=GOTO_MA.format(legs=-1),
                    set_he10_ma=_set_heading_ma("1", "4.712389"))
    out = tmp_path / "h.mission"
    assert main(["import-slocum", str(path), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert re.search(r"m\.mi:8: warning: goto_list: only the first route behavior \(\S*m\.mi:6\)",
                     err), err
    text = out.read_text()
    assert "flightroute heading(270.0000011)" in text
    assert "# use_heading 1, heading_value 4.712389 rad: 270.0000011 deg held" in text
    assert main(["check", str(out)]) == 0
    tracks = {}
    for runtime in ("python", "c"):
        assert main(["sim", str(out), "--runtime", runtime, "--start", "54.5,7.5",
                     "--duration", "6h", "--currents", "0.1,0", "-o",
                     str(tmp_path / runtime)]) == 0
        tracks[runtime] = pd.read_parquet(tmp_path / runtime / "timeseries.parquet")
    for column in ("lat_deg", "lon_deg"):
        assert tracks["python"][column].equals(tracks["c"][column]), column
    end = tracks["python"].iloc[-1]
    north_m = (end["lat_deg"] - 54.5) * METRES_PER_DEGREE
    west_m = (7.5 - end["lon_deg"]) * METRES_PER_DEGREE * np.cos(np.radians(54.5))
    assert north_m == pytest.approx(0.1 * 6 * 3600.0, rel=0.05)  # carried, not corrected
    assert west_m > 2000.0  # flew west, its heading


def test_a_fin_held_is_a_spiral_at_the_fin_s_turn_rate_in_both_runtimes(tmp_path, capsys):
    """use_heading 4 (HM_FIN): 0.3 rad of fin held is a `turn` at the vehicle's
    fin_turn_rate times the fin; the Python reference and the C runtime (over the pty and
    as the in-process step) fly the same spiral, whose course turns
    clockwise at that rate under water (no current: the course is the heading)."""
    mi = SET_HEADING_MI.replace("behavior: goto_list\n b_arg: args_from_file(enum) 10\n", "")
    path = _mission(tmp_path, mi, yo10_ma=YO_MA, set_he10_ma=_set_heading_ma("4", "0.3"))
    out = tmp_path / "f.mission"
    assert main(["import-slocum", str(path), "-o", str(out)]) == 0
    rate_rad_s = load_vehicle("slocum_g2_shallow").fin_turn_rate_per_s * 0.3
    text = out.read_text()
    route = re.search(r"flightroute turn\((\S+)\)", text)
    assert route and float(route[1]) == pytest.approx(math.degrees(rate_rad_s), rel=1e-6)
    assert "# use_heading 4, heading_value 0.3 rad of fin: a steady turn" in text
    assert main(["check", str(out)]) == 0
    tracks = {}
    for runtime in ("python", "c", "step"):
        assert main(["sim", str(out), "--runtime", runtime, "--start", "54.5,7.5",
                     "--duration", "1h", "-o", str(tmp_path / runtime)]) == 0
        tracks[runtime] = pd.read_parquet(tmp_path / runtime / "timeseries.parquet")
    for runtime, column in itertools.product(("c", "step"), ("lat_deg", "lon_deg", "depth_m")):
        assert tracks["python"][column].equals(tracks[runtime][column]), (runtime, column)
    track = tracks["python"]
    north = np.diff(track["lat_deg"].to_numpy()) * METRES_PER_DEGREE
    east = np.diff(track["lon_deg"].to_numpy()) * METRES_PER_DEGREE * np.cos(np.radians(54.5))
    under = (track["depth_m"].to_numpy()[1:] > 2.0) & (np.hypot(north, east) > 0.0)
    course = np.unwrap(np.arctan2(east[under], north[under]))
    seconds = np.diff(track["time_s"].to_numpy())[under]
    turned = np.diff(course) / seconds[1:]
    assert np.median(turned) == pytest.approx(rate_rad_s, rel=0.02)
    assert course[-1] - course[0] > 2.0 * math.pi  # more than a full circle: a spiral


def test_a_roll_held_is_left_out_and_says_why(tmp_path, capsys):
    mi = SET_HEADING_MI.replace("behavior: goto_list\n b_arg: args_from_file(enum) 10\n", "")
    path = _mission(tmp_path, mi, yo10_ma=YO_MA, set_he10_ma=_set_heading_ma("2", "0.2"))
    out = tmp_path / "r.mission"
    assert main(["import-slocum", str(path), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "set_he10.ma:3: warning: set_heading: not translated: use_heading 2 " \
           "(set_he10.ma:3), heading_value 0.2 (set_he10.ma:4): a roll held (HM_ROLL): the " \
           "shared Slocum logs command no roll" in err
    text = out.read_text()
    assert "flightroute noheading" in text and "# not translated: use_heading 2" in text


@pytest.mark.parametrize("mi, mafiles, message", [
    ("behavior: set_heading\n b_arg: use_heading(bool) 7\n b_arg: heading_value(X) 1\n", {},
     "m.mi:2: use_heading 7 is no mode of set_heading"),
    ("behavior: set_heading\n b_arg: use_heading(bool) 1\n", {},
     "m.mi:1: set_heading needs use_heading and heading_value"),
    ("behavior: set_heading\n b_arg: use_heading(bool) 4\n b_arg: heading_value(X) 0.5\n",
     {}, "m.mi:3: heading_value 0.5 rad is no fin angle of use_heading 4"),
    ("behavior: set_heading\n b_arg: use_heading(bool) 4\n b_arg: heading_value(X) -0.44\n",
     {}, "m.mi:3: heading_value -0.44 rad is no fin angle of use_heading 4"),
    ("behavior: yo\n  b_arg: args_from_file(enum) 10\nbehavior: loiter_about\n",
     {"yo10_ma": YO_MA}, "m.mi:3: unknown behavior 'loiter_about'"),
    ("behavior: yo\n  b_arg: args_from_file(enum) 10\n  b_arg: start_when(enum)\n",
     {"yo10_ma": YO_MA}, "m.mi:3: malformed line 'b_arg: start_when(enum)'"),
    ("  b_arg: start_when(enum) 0\n", {}, "m.mi:1: b_arg before any 'behavior:' line"),
    ("behavior: yo\n  b_arg: d_target_depth(m) deep\n", {}, "m.mi:2: d_target_depth: 'deep' "
     "is not a number"),
    ("behavior: yo\n  b_arg: num_half_cycles_to_do(nodim) 1e400\n", {},
     "m.mi:2: num_half_cycles_to_do: '1e400' is not a number"),
    ("behavior: abend\n  b_arg: remaining_charge_min(%) 100\n", {},
     "m.mi:2: remaining_charge_min 100 %: the mission would abort at once"),
    ("behavior: yo\n  b_arg: args_from_file(enum) 11\n", {"yo10_ma": YO_MA},
     "m.mi:2: args_from_file 11: no file"),
    ("behavior: goto_list\n  b_arg: args_from_file(enum) 10\n",
     {"goto_l10_ma": "behavior_name=goto_list\n<start:b_arg>\n<end:b_arg>\n"
                     "<start:waypoints>\n713.0 5475.0\n<end:waypoints>\n"},
     "goto_l10.ma:5: latitude 5475.0 is not DDMM.MMMM"),
    ("behavior: yo\n  b_arg: args_from_file(enum) 10\n",
     {"yo10_ma": "behavior_name=yo\n b_arg: d_target_depth(m) 20\n"},
     "yo10.ma:2: unexpected line 'b_arg: d_target_depth(m) 20' before <start:b_arg>"),
    ("behavior: yo\n  b_arg: args_from_file(enum) 10\n",
     {"yo10_ma": "behavior_name=surface\n<start:b_arg>\n<end:b_arg>\n"},
     "yo10.ma:1: this file is for behavior 'surface'"),
    ("behavior: surface\n b_arg: start_when(enum) 9\n b_arg: when_secs(sec) -60\n", {},
     "m.mi:3: when_secs -60 s is no time to wait: start_when 9 surfaces when_secs after it "
     "last reached the surface"),
    ("behavior: surface\n b_arg: args_from_file(enum) 10\n b_arg: start_when(enum) 12\n",
     {"surfac10_ma": "behavior_name=surface\n<start:b_arg>\n b_arg: when_secs(sec) 0\n"
                     "<end:b_arg>\n"},
     "surfac10.ma:3: when_secs 0 s is no time to wait: start_when 12 surfaces when_secs "
     "after it last left the surface"),
    ("behavior: sample\n b_arg: sensor_type(enum) 1\n b_arg: nth_yo_to_sample(nodim) 0\n", {},
     "m.mi:3: nth_yo_to_sample 0: no yo to sample"),
    ("behavior: sample\n b_arg: sensor_type(enum) 1\n b_arg: state_to_sample(enum) 16\n", {},
     "m.mi:3: state_to_sample 16 is no sum of 1 diving, 2 hovering, 4 climbing and 8 on the "
     "surface (0-15)"),
    ("behavior: sample\n b_arg: sensor_type(enum) 1.5\n", {},
     "m.mi:2: sensor_type 1.5 is not a whole number"),
    ("behavior: sample\n b_arg: sensor_type(enum) 1\n b_arg: min_depth(m) 30\n"
     " b_arg: max_depth(m) 10\n", {},
     "m.mi:4: sample between min_depth 30 m and max_depth 10 m: no depth lies between"),
    ("behavior: sample\n b_arg: args_from_file(enum) 12\n", {},
     "m.mi:2: args_from_file 12: no file"),
])
def test_bad_slocum_files_stop_with_one_line_naming_file_and_line(tmp_path, capsys, mi,
                                                                  mafiles, message):
    path = _mission(tmp_path, mi, **mafiles)
    out = tmp_path / "out.mission"
    assert main(["import-slocum", str(path), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert message in err, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not out.exists()


def test_import_mission_is_the_call_behind_import_slocum(tmp_path):
    path = _mission(tmp_path, "behavior: yo\n  b_arg: args_from_file(enum) 10\n"
                    "behavior: surface\n  b_arg: start_when(enum) 9\n"
                    "  b_arg: when_secs(sec) 3600\n", yo10_ma=YO_MA)
    imported = import_mission(path, tmp_path / "m.mission", horizon_s=86400.0)
    assert imported.path == tmp_path / "m.mission" and imported.states == 2
    assert check_file(str(imported.path)).ok and imported.warnings == ()
    text = imported.path.read_text()
    assert "horizon 86400 s" in text  # the horizon given, not the default 7 days
    assert "case missiontime - surfaced_s >= 3600 set surfaced_s = missiontime call" in text
    unknown = _mission(tmp_path, "behavior: yo\n  b_arg: args_from_file(enum) 10\n"
                       "behavior: loiter_about\n", yo10_ma=YO_MA)
    with pytest.raises(SlocumFileError) as refused:
        import_mission(unknown, tmp_path / "u.mission")
    assert refused.value.exit_code == ExitCode.BAD_INPUT
    assert str(refused.value).startswith(f"{unknown}:3: unknown behavior 'loiter_about'")
    for missing in (tmp_path / "none.mi", tmp_path):  # no such file; a directory
        with pytest.raises(GliderplanError) as refused:
            import_mission(missing, tmp_path / "n.mission")
        assert refused.value.exit_code == ExitCode.USAGE
    assert not (tmp_path / "u.mission").exists() and not (tmp_path / "n.mission").exists()


def test_bad_usage_exits_2(tmp_path, capsys):
    assert main(["import-slocum", str(tmp_path / "nope.mi"), "-o", str(tmp_path / "x")]) == 2
    path = _mission(tmp_path, "behavior: yo\n", )
    assert main(["import-slocum", str(path), "--mafiles", str(tmp_path / "none"),
                 "-o", str(tmp_path / "x")]) == 2
    assert main(["import-slocum", str(path), "--horizon", "soon", "-o",
                 str(tmp_path / "x")]) == 2
    assert "--horizon 'soon'" in capsys.readouterr().err


def test_a_synthetic_mission_translates_every_surfacing_mode(tmp_path):
    surfac = ("behavior_name=surface\n<start:b_arg>\n b_arg: end_action(enum) 2\n"
              " b_arg: gps_wait_time(s) 120\n<end:b_arg>\n")
    mi = ("behavior: abend\n b_arg: overtime(s) 36000\n b_arg: overdepth(m) 60\n"
          "behavior: surface\n b_arg: start_when(enum) 0\n b_arg: args_from_file(enum) 10\n"
          "behavior: surface\n b_arg: start_when(enum) 7\n b_arg: when_wpt_dist(m) 300\n"
          "behavior: surface\n b_arg: start_when(enum) 1\n b_arg: end_action(enum) 0\n"
          "behavior: surface\n b_arg: start_when(enum) 13\n b_arg: when_utc_hour(hr) 6\n"
          " b_arg: when_utc_min(min) 30\n"
          "behavior: surface\n b_arg: start_when(enum) 13\n b_arg: when_utc_min(min) 15\n"
          "behavior: surface\n b_arg: start_when(enum) 13\n b_arg: when_utc_day(day) 3\n"
          "behavior: goto_wpt\n b_arg: wpt_units(enum) 2\n b_arg: wpt_x(lon) -7349.0\n"
          " b_arg: wpt_y(lat) 3910.5\n"
          "behavior: yo\n b_arg: args_from_file(enum) 10\n"
          " b_arg: num_half_cycles_to_do(nodim) 3\n"
          "behavior: sample\n b_arg: sensor_type(enum) 1\n b_arg: state_to_sample(enum) 1\n")
    path = _mission(tmp_path, mi, yo10_ma=YO_MA, surfac10_ma=surfac)
    out = tmp_path / "s.mission"
    assert main(["import-slocum", str(path), "-o", str(out)]) == 0
    text = out.read_text()
    assert "horizon 36000 s" in text  # abend overtime bounds the mission
    assert "case missiontime >= 36000 goto abort" in text
    assert "case depth > 60 goto abort" in text
    assert "case surface_1_done == 0 set surface_1_done = 1" in text
    assert "case wptdist <= 300 && near_wpt_2 == 0" in text
    assert "case halfcycle > 3 || halfcycle == 3 && depth >= 20" in text  # odd: at the bottom
    assert "case timeofday >= 23400 && timeofday < 23460" in text  # 06:30 UTC
    assert "case mod(timeofday, 3600) >= 900 && mod(timeofday, 3600) < 960" in text
    assert "start_when 13: at a date, not translated" in text
    assert "flightroute nav(3910.5, -7349)" in text
    dives = yo_phases(3, 20, 0.45, 0.45, "slocum_g2_shallow").dive_share
    assert f"temp duty {dives:.2g}," in text and 0.5 < dives < 0.7  # sampled on dives only
    assert main(["sim", str(out), "--duration", "4h", "--start", "2024-06-01T06:10Z",
                 "-o", str(tmp_path / "run")]) == 0
    trace = (tmp_path / "run" / "trace.csv").read_text()
    assert "300,call,survey,surface_5" in trace  # 06:15 by the glider's clock
    assert "call,survey,surface_1" in trace  # at once
    assert ",exit,surface_3,," in trace  # the yo's end: surfacing, then end_action 0 quits


@pytest.mark.skipif(shutil.which("cc") is None and os.environ.get("CI") != "true",
                    reason="no C compiler (cc)")
def test_the_c_runtime_flies_an_imported_mission_as_the_reference_does(flown, tmp_path):
    mission = flown["helgo"] / "helgo.mission"
    traces = []
    for runtime in ("python", "c"):
        out = tmp_path / runtime
        assert main(["sim", str(mission), "--runtime", runtime, "--duration", "8h",
                     "-o", str(out)]) == 0
        traces.append((out / "trace.csv").read_text())
    assert traces[0] == traces[1] and traces[0].count("call,survey,surface_1") >= 15


def test_abend_on_minimum_charge_reads_the_batterys_coulomb_counter(tmp_path):
    # remaining_charge_min of the default 7.8 MJ pack: 99.9 % is spent within the hour
    path = _mission(tmp_path, "behavior: abend\n b_arg: remaining_charge_min(%) 99.9\n"
                    "behavior: yo\n b_arg: args_from_file(enum) 10\n", yo10_ma=YO_MA)
    out = tmp_path / "c.mission"
    imported = import_mission(path, out)
    assert imported.warnings == ()
    text = out.read_text()
    assert _has(text, "case energy_left < 7792200 goto abort  # remaining_charge_min 99.9 %")
    assert main(["sim", str(out), "--duration", "3h", "-o", str(tmp_path / "run")]) == 0
    trace = pd.read_csv(tmp_path / "run" / "trace.csv")
    aborted = trace[(trace["kind"] == "goto") & (trace["to_state"] == "abort")]
    assert len(aborted) == 1 and aborted["time_s"].iloc[0] < 3600
    assert trace["kind"].iloc[-1] == "exit"


def test_science_behaviors_say_what_they_leave_out_in_the_mission(tmp_path, capsys):
    # a sensor sampled only while hovering (never, in the simulator), sensors_in's flight
    # sensors, a sample at intervals: each a warning with its line and a comment
    mi = ("behavior: yo\n b_arg: args_from_file(enum) 10\n"
          "behavior: sample\n b_arg: sensor_type(enum) 19\n b_arg: state_to_sample(enum) 2\n"
          "behavior: sample\n b_arg: sensor_type(enum) 1\n b_arg: state_to_sample(enum) 5\n"
          " b_arg: intersample_time(s) 10\n"
          "behavior: sensors_in\n b_arg: c_att_time(sec) 0\n b_arg: u_battery_time(sec) 10\n")
    path = _mission(tmp_path, mi, yo10_ma=YO_MA)
    out = tmp_path / "s.mission"
    assert main(["import-slocum", str(path), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    text = out.read_text()
    assert "m.mi:5: warning: sample: not translated: state_to_sample 2" in err
    assert "# sample (m.mi:3): not translated: state_to_sample 2 (the yo never hovers: the " \
           "sensor samples never)" in text
    assert "chlorophyll" not in text.split("state survey")[1].split("end")[0]
    # a sample every 10 s: the CTD's 2 s warm-up and one 2 s sample (0.5 Hz) in every 10
    assert "# sample (m.mi:6): ctd (sensor_type 1 PROFILE) diving and climbing: duty 0.4 " \
           "in the yo, intersample_time 10 s: (its warm-up 2 s + 2 s a sample) / 10 s" in text
    assert _has(text, "temp duty 0.4, conductivity duty 0.4, salinity duty 0.4")
    assert "m.mi:11: warning: sensors_in: not translated: c_att_time 0" in err
    assert "# sensors_in (m.mi:10): not translated: c_att_time 0, u_battery_time 10" in text


def test_a_yo_of_a_billion_half_cycles_imports_at_once(tmp_path):
    path = _mission(tmp_path, "behavior: yo\n b_arg: args_from_file(enum) 10\n",
                    yo10_ma=YO_MA.replace("num_half_cycles_to_do(nodim) -1",
                                          "num_half_cycles_to_do(nodim) 1e9"))
    imported = import_mission(path, tmp_path / "y.mission")
    assert "1000000000 half cycles at the" in imported.path.read_text()


GOTO_MA = ("behavior_name=goto_list\n<start:b_arg>\n b_arg: list_stop_when(enum) 7\n"
           " b_arg: list_when_wpt_dist(m) 50\n b_arg: initial_wpt(enum) 0\n"
           " b_arg: num_legs_to_run(nodim) {legs}\n<end:b_arg>\n<start:waypoints>\n"
           "-7349.8 3910.5\n-7349.4 3910.8\n-7349.5 3910.2\n<end:waypoints>\n")


def _calls_at(run: Path, state: str) -> list[float]:
    trace = pd.read_csv(run / "trace.csv")
    return trace[(trace["kind"] == "call") & (trace["to_state"] == state)]["time_s"].tolist()


def _distance_m(table: pd.DataFrame, time_s: float, point: tuple[float, float]) -> float:
    """From the glider, on the tick before `time_s` (the one that reached the waypoint, its
    surfacing called on the next), to a (lat, lon) DDMM.MMMM point [m]."""
    row = table[table["time_s"] == time_s - TICK_S].iloc[0]
    north = (ddmm_to_degrees(point[0]) - row["lat_deg"]) * METRES_PER_DEGREE
    east = (ddmm_to_degrees(point[1]) - row["lon_deg"]) * METRES_PER_DEGREE * np.cos(
        np.radians(row["lat_deg"]))
    return float(np.hypot(north, east))


def test_a_finite_goto_list_surfaces_at_each_waypoint_and_at_its_end(tmp_path, capsys):
    # start_when 8 at every waypoint reached (resuming), start_when 3 at the end of the
    # list (quitting), on the runtime's count of waypoints reached
    mi = ("behavior: surface\n b_arg: start_when(enum) 8\n b_arg: end_action(enum) 2\n"
          " b_arg: gps_wait_time(s) 120\n b_arg: when_secs(sec) -60\n"
          "behavior: surface\n b_arg: start_when(enum) 3\n b_arg: end_action(enum) 0\n"
          " b_arg: gps_wait_time(s) 120\n"
          "behavior: goto_list\n b_arg: args_from_file(enum) 10\n"
          "behavior: yo\n b_arg: args_from_file(enum) 10\n")
    path = _mission(tmp_path, mi, yo10_ma=YO_MA, goto_l10_ma=GOTO_MA.format(legs=4))
    out = tmp_path / "g.mission"
    assert main(["import-slocum", str(path), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    # a when_secs that start_when 8 does not read: a warning at its line, and a comment
    assert "m.mi:5: warning: surface: not translated: when_secs -60" in err
    text = out.read_text()
    assert "# not translated: when_secs -60 (start_when 8 does not read it" in text
    assert _has(text, "case wptreached > wpt_surfaced_1 set wpt_surfaced_1 = wptreached, "
                "surfaced_s = missiontime call surface_1")
    assert "case wptreached >= 4 set surfaced_s = missiontime call surface_2" in text
    assert main(["check", "--strict", str(out)]) == 0
    assert main(["sim", str(out), "--duration", "1d", "-o", str(tmp_path / "run")]) == 0
    ma = tmp_path / "mafiles" / "goto_l10.ma"
    legs, points = int(ma_args(ma)["num_legs_to_run"]), ma_waypoints(ma)
    radius = 50.0  # a list run N legs is flown as waypoints, each reached within 50 m
    table = _series(tmp_path)
    at_waypoints = _calls_at(tmp_path / "run", "surface_1")
    # once at every waypoint the .ma file's list gives, in its order, legs waypoints in all
    assert len(at_waypoints) == legs
    for leg, time_s in enumerate(at_waypoints):
        assert _distance_m(table, time_s, points[leg % len(points)]) <= radius + 2.0
    # the end of the list: right after the last waypoint's surfacing resumes; then it quits
    at_end = _calls_at(tmp_path / "run", "surface_2")
    assert len(at_end) == 1 and at_end[0] > at_waypoints[-1]
    trace = pd.read_csv(tmp_path / "run" / "trace.csv")
    assert trace["kind"].iloc[-1] == "exit" and trace["from_state"].iloc[-1] == "surface_2"


def test_stack_idle_with_a_list_run_once_surfaces_when_it_is_flown(tmp_path, capsys):
    # the yo never ends: the stack goes idle when the list has been flown once (-2), and
    # stays so: each time the glider resumes it surfaces again, as a Slocum glider does
    mi = ("behavior: surface\n b_arg: start_when(enum) 1\n b_arg: end_action(enum) 1\n"
          " b_arg: keystroke_wait_time(s) 300\n"
          "behavior: goto_list\n b_arg: args_from_file(enum) 10\n"
          "behavior: yo\n b_arg: args_from_file(enum) 10\n")
    path = _mission(tmp_path, mi, yo10_ma=YO_MA, goto_l10_ma=GOTO_MA.format(legs=-2))
    out = tmp_path / "o.mission"
    imported = import_mission(path, out)
    assert [w.message.split(":")[0] for w in imported.warnings] == ["goto_list"]
    assert "not translated: num_legs_to_run -2" in imported.warnings[0].message
    text = out.read_text()
    assert "stack idle: the goto list's end (its 3 waypoints reached, num_legs_to_run -2; " \
           "num_half_cycles_to_do -1: the yo never ends); then again each time it resumes" \
           in text
    assert "case wptreached >= 3 set surfaced_s = missiontime call surface_1" in text
    assert main(["sim", str(out), "--duration", "8h", "-o", str(tmp_path / "run")]) == 0
    points = ma_waypoints(tmp_path / "mafiles" / "goto_l10.ma")
    calls = _calls_at(tmp_path / "run", "surface_1")
    assert _distance_m(_series(tmp_path), calls[0], points[-1]) <= 52.0
    gaps = np.diff(calls)
    assert len(calls) > 5 and gaps.max() < 300 + 120  # the wait, a climb and a tick


def test_surfacings_that_can_never_start_are_a_comment_and_a_warning(tmp_path, capsys):
    # a list that loops for ever and a yo that never ends: stack idle and the list's end
    # never come; a goto_wpt, flown as nav, never reaches its waypoint
    looping = ("behavior: surface\n b_arg: start_when(enum) 3\n"
               "behavior: surface\n b_arg: start_when(enum) 1\n"
               "behavior: surface\n b_arg: start_when(enum) 9\n b_arg: when_secs(s) 3600\n"
               "behavior: goto_list\n b_arg: args_from_file(enum) 10\n"
               "behavior: yo\n b_arg: args_from_file(enum) 10\n")
    path = _mission(tmp_path, looping, yo10_ma=YO_MA, goto_l10_ma=GOTO_MA.format(legs=-1))
    assert main(["import-slocum", str(path), "-o", str(tmp_path / "l.mission")]) == 0
    err = capsys.readouterr().err
    assert "m.mi:2: warning: surface: start_when 3 (at the end of the goto list) never " \
           "happens: num_legs_to_run -1: the goto list loops for ever" in err
    assert "m.mi:4: warning: surface: start_when 1 (stack idle) never happens: " \
           "num_half_cycles_to_do -1: the yo never ends, and num_legs_to_run -1" in err
    text = (tmp_path / "l.mission").read_text()
    assert "start_when 3, at the end of the goto list: never (num_legs_to_run -1" in text
    assert "wptreached" not in text
    nav = ("behavior: surface\n b_arg: start_when(enum) 8\n"
           "behavior: goto_wpt\n b_arg: wpt_units(enum) 2\n b_arg: wpt_x(lon) -7349.0\n"
           " b_arg: wpt_y(lat) 3910.5\n")
    path = _mission(tmp_path, nav)
    assert main(["import-slocum", str(path), "-o", str(tmp_path / "n.mission")]) == 0
    assert "m.mi:2: warning: surface: start_when 8 (when a waypoint is reached) never " \
           "happens: goto_wpt is flown as nav" in capsys.readouterr().err



# ---- the science bay: sample and sensors_in -----------------------------------------------
def _import(tmp_path: Path, capsys, mi: str, *options: str) -> tuple[str, str]:
    """(the translated mission, the warnings) of a mission with YO_MA's 3-20 m yo; it
    checks (a mission that never exits is a warning)."""
    path = _mission(tmp_path, mi, yo10_ma=YO_MA)
    out = tmp_path / "s.mission"
    assert main(["import-slocum", str(path), *options, "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert main(["check", str(out)]) == 0
    capsys.readouterr()
    return out.read_text(), err


def _logged(text: str, state: str = "survey") -> dict[str, str]:
    """A state's science sensors -> duty ("" always on), as the checked mission has them."""
    from gliderplan.language import check_source

    uses = check_source(text).checked().state(state).sensors
    return {u.name: "" if u.duty is None else format(u.duty, ".10g") for u in uses
            if SENSOR_BY_NAME[u.name].device is not None}


def _has(text: str, line: str) -> bool:
    """Whether the mission holds `line`, however the canonical layout spaces or wraps it."""
    return " ".join(line.split()) in " ".join(text.split())


def test_nsb3_samples_its_ctd_and_flntu_in_the_yo_and_leaves_the_logger_and_dvl_off(
        tmp_path, capsys):
    _needs_missions()
    out = tmp_path / "n.mission"
    assert main(["import-slocum", str(MISSIONS / "nsb3" / "nsb3.mi"), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    text = out.read_text()
    # sample10.ma and sample11.ma: state_to_sample 5, intersample_time 0
    assert _logged(text) == {s: "" for s in ("temp", "conductivity", "salinity",
                                             "chlorophyll", "backscatter")}
    assert "# sample (nsb3.mi:78, sample11.ma): optics (sensor_type 19 FLNTU) diving and " \
           "climbing: always on in the yo" in text
    # sample13.ma (the MicroRider) and sample14.ma (the DVL): intersample_time -1
    assert "# sample (nsb3.mi:83, sample13.ma): logger (sensor_type 39 LOGGER): " \
           "intersample_time -1: off" in text
    assert "# sample (nsb3.mi:86, sample14.ma): dvl (sensor_type 43 DVL): intersample_time " \
           "-1: off" in text
    assert "shear" not in text and "groundspeed" not in text
    assert not [line for line in err.splitlines() if "warning: sample" in line]
    # the CTD at the surface too: sensors_in's c_profile_on 0, below the samples
    assert _logged(text, "surface_3") == {"temp": "", "conductivity": "", "salinity": ""}
    assert "# ctd: sampled by sample (nsb3.mi:75, sample10.ma) and sensors_in (nsb3.mi:89): " \
           "the union of their phases" in text


def test_a_device_sampled_on_dives_only_is_on_for_the_share_of_the_yo_the_glider_dives(
        tmp_path, capsys):
    text, err = _import(tmp_path, capsys, "behavior: yo\n b_arg: args_from_file(enum) 10\n"
                        "behavior: sample\n b_arg: sensor_type(enum) 43\n"
                        " b_arg: state_to_sample(enum) 1\n")
    duty = float(_logged(text)["groundspeed"])
    assert f"# sample (m.mi:3): dvl (sensor_type 43 DVL) diving only: duty {duty:.2g} in the " \
           "yo, the share of a 3-20 m yo spent diving on slocum_g2_shallow" in text
    out = tmp_path / "s.mission"
    assert main(["plan", str(out), "-o", str(tmp_path / "s.plan")]) == 0
    assert main(["sim", str(out), "--plan", str(tmp_path / "s.plan"), "--duration", "6h",
                 "-o", str(tmp_path / "run")]) == 0
    table = _series(tmp_path)
    survey = table[table["state"] == "survey"]
    # the simulated glider dives (nose down: the dive and the turn at the top that starts
    # it) for that share of the yo, and the planned DVL draws its power for as long
    diving = float((survey["pitch_rad"] < 0).mean())
    assert diving == pytest.approx(duty, abs=0.02)
    period_s, on_s = next(map(float, line.split()[2:4]) for line in (
        tmp_path / "s.plan").read_text().splitlines() if line.startswith("sensor groundspeed"))
    assert on_s / period_s == pytest.approx(duty, abs=0.01)
    dvl_j = float(survey["power_dvl_w"].sum()) * TICK_S
    expected_w = float(load_sensor("dvl").mean_power_w(diving, period_s))  # + its warm-ups
    assert dvl_j == pytest.approx(expected_w * len(survey) * TICK_S, rel=0.02)


def test_intervals_depths_and_every_nth_yo_scale_the_duty_and_say_why(tmp_path, capsys):
    mi = ("behavior: surface\n b_arg: start_when(enum) 9\n b_arg: when_secs(s) 3600\n"
          "behavior: yo\n b_arg: args_from_file(enum) 10\n"
          "behavior: sample\n b_arg: sensor_type(enum) 59\n b_arg: state_to_sample(enum) 13\n"
          " b_arg: intersample_time(s) 10\n b_arg: nth_yo_to_sample(nodim) 3\n"
          " b_arg: max_depth(m) 10\n")
    text, err = _import(tmp_path, capsys, mi)
    # the CTD41CP2 is the ctd: 7 m of the 3-20 m band, one yo in 3, 4 s of every 10 s
    duty = 7 / 17 / 3 * 0.4
    assert _logged(text)["temp"] == f"{duty:.2g}"
    assert f"duty {duty:.2g} in the yo = 0.41 (min_depth -5 m to max_depth 10 m keep 3-10 m " \
           "of the 3-20 m yo (at an even vertical speed)) x 0.33 (nth_yo_to_sample 3: one yo " \
           "in 3) x 0.4 (intersample_time 10 s: (its warm-up 2 s + 2 s a sample) / 10 s)" \
           in text
    assert _logged(text, "surface_1")["temp"] == "0.4"  # at the surface: the interval only
    assert "warning: sample" not in err


@pytest.mark.parametrize("mi, line, warning, comment", [
    ("behavior: sample\n b_arg: state_to_sample(enum) 5\n", 1,
     "sample: no sensor_type: read as 0 (C_SCIENCE_ALL_ON), the default this translation "
     "assumes", "every science device (sensor_type 0 C_SCIENCE_ALL_ON) diving and climbing"),
    ("behavior: sample\n b_arg: sensor_type(enum) 999\n", 2,
     "sample: sensor_type 999 is no instrument the Slocum firmware knows: the forecast does "
     "not power it", "sensor_type 999 (no instrument the Slocum firmware knows): the forecast "
     "does not power it"),
    ("behavior: sample\n b_arg: sensor_type(enum) 51\n", 2,
     "sample: sensor_type 51 is SUNA, an instrument gliderplan has no power model of: the "
     "forecast does not power it", "sensor_type 51 (SUNA, an instrument gliderplan has no "
     "power model of)"),
    ("behavior: sample\n b_arg: sensor_type(enum) 2\n", 2,
     "sample: sensor_type 2 is HS2, deleted from the Slocum firmware", "(HS2, deleted"),
    ("behavior: sample\n b_arg: sensor_type(enum) 1\n b_arg: state_to_sample(enum) 0\n", 3,
     "sample: state_to_sample 0: no state to sample in: sensor_type 1 is never switched on",
     "ctd (sensor_type 1 PROFILE): state_to_sample 0, in no state: off"),
    ("behavior: sample\n b_arg: sensor_type(enum) 1\n b_arg: state_to_sample(enum) 5\n"
     " b_arg: nth_yo_to_sample(nodim) -2\n", 4,
     "sample: not translated: nth_yo_to_sample -2 (m.mi:6): the first yo, which it leaves "
     "out, is sampled as the others; then one yo in 2", "duty 0.5 in the yo, "
     "nth_yo_to_sample -2: one yo in 2"),
    ("behavior: sample\n b_arg: sensor_type(enum) 1\n b_arg: state_to_sample(enum) 5\n"
     " b_arg: tod_start(hhmm) 600\n", 4,
     "sample: not translated: tod_start 600 (m.mi:6): gliderplan's models have no "
     "counterpart", "not translated: tod_start 600"),
    ("behavior: sensors_in\n b_arg: c_suna_on(sec) 0\n", 2,
     "sensors_in: c_suna_on is SUNA, an instrument gliderplan has no power model of: the "
     "forecast does not power it", "c_suna_on (SUNA, an instrument gliderplan has no power "
     "model of): the forecast does not power it"),
])
def test_what_the_science_bay_cannot_power_is_a_warning_at_its_line_and_a_comment(
        tmp_path, capsys, mi, line, warning, comment):
    text, err = _import(tmp_path, capsys, "behavior: yo\n b_arg: args_from_file(enum) 10\n"
                        + mi)
    assert f"m.mi:{line + 2}: warning: {warning}" in err, err
    survey_comments = text.split("state survey")[0]
    assert comment in survey_comments


def test_a_sample_whose_ma_file_is_missing_is_left_out_when_allowed(tmp_path, capsys):
    mi = ("behavior: yo\n b_arg: args_from_file(enum) 10\n"
          "behavior: sample\n b_arg: args_from_file(enum) 12\n")
    text, err = _import(tmp_path, capsys, mi, "--allow-missing-mafiles")
    assert "m.mi:3: warning: sample: its .ma file" in err and "sample12.ma is missing" in err
    assert "# left out: sample (m.mi:3), its .ma file sample12.ma is missing" in text
    assert _logged(text) == {}


def test_several_behaviors_of_one_device_sample_the_union_of_their_phases(tmp_path, capsys):
    # the DVL: sampled on dives by one sample and on climbs by another: always on; the
    # optode: off on dives (the first behavior), on everywhere else by sensors_in
    mi = ("behavior: yo\n b_arg: args_from_file(enum) 10\n"
          "behavior: sample\n b_arg: sensor_type(enum) 43\n b_arg: state_to_sample(enum) 1\n"
          "behavior: sample\n b_arg: sensor_type(enum) 43\n b_arg: state_to_sample(enum) 4\n"
          "behavior: sample\n b_arg: sensor_type(enum) 54\n b_arg: state_to_sample(enum) 1\n"
          " b_arg: intersample_time(s) -1\n"
          "behavior: sensors_in\n b_arg: c_oxy4_on(sec) 0\n")
    text, err = _import(tmp_path, capsys, mi)
    climbs = yo_phases(3, 20, 0.45, 0.45, "slocum_g2_shallow").climb_share
    assert _logged(text) == {"groundspeed": "", "oxygen": f"{climbs:.2g}"}
    assert "# dvl: sampled by sample (m.mi:3) and sample (m.mi:6): the union of their " \
           "phases" in text
    assert "# optode: sampled by sample (m.mi:9) and sensors_in (m.mi:13)" in text


def test_sensors_in_reads_every_switch_of_the_science_bay(tmp_path, capsys):
    mi = ("behavior: yo\n b_arg: args_from_file(enum) 10\n"
          "behavior: sensors_in\n b_arg: c_ad2cp_on(sec) 60\n b_arg: c_uModem_on(sec) 0\n"
          " b_arg: c_microrider_on(sec) -1\n b_arg: c_bb3slo_on(sec) 0\n")
    text, err = _import(tmp_path, capsys, mi)
    # the AD2CP every 60 s: its 5 s start-up and a 1 s ping ensemble
    assert _logged(text) == {"current": "0.1", "modem": "", "chlorophyll": "",
                             "backscatter": ""}
    assert "# sensors_in (m.mi:3): adcp (c_ad2cp_on 60): duty 0.1 in every state, " \
           "intersample_time 60 s: (its warm-up 5 s + 1 s a sample) / 60 s" in text
    assert "# sensors_in (m.mi:3): logger (c_microrider_on -1): off" in text
    assert "warning:" not in err


def test_an_imported_mission_names_its_hardware_and_is_in_canonical_layout(tmp_path, capsys):
    """A Slocum mission runs on the glider's own computers: `computer none` by default, as
    the output says; the options name others; the mission is as `fmt` writes it."""
    _needs_missions()
    for name in ("nsb3", "helgo"):
        out = tmp_path / f"{name}.mission"
        assert main(["import-slocum", str(MISSIONS / name / f"{name}.mi"), "-o", str(out),
                     "--allow-missing-mafiles"]) == 0
        err = capsys.readouterr().err
        assert "vehicle slocum_g2_shallow (default), computer none (default)" in err
        mission = check_file(str(out)).checked()
        assert mission.computer.board == "none" and mission.vehicle == "slocum_g2_shallow"
        assert _has(out.read_text(), "computer none  # the default of import-slocum --computer")
        assert main(["fmt", "--check", str(out)]) == 0, name
    out = tmp_path / "given.mission"
    assert main(["import-slocum", str(MISSIONS / "nsb3" / "nsb3.mi"), "-o", str(out),
                 "--vehicle", "slocum_g3", "--computer", "ts7800 @ 500 MHz",
                 "--battery", "1 kWh reserve 10 %"]) == 0
    assert "vehicle slocum_g3, computer ts7800 @ 500 MHz, battery 1 kWh reserve 10 %" in \
        capsys.readouterr().err
    mission = check_file(str(out)).checked()
    assert (mission.vehicle, mission.computer.board, mission.computer.clock_mhz) == (
        "slocum_g3", "ts7800", 500.0)
    assert mission.battery.energy_j == pytest.approx(3.6e6)


@pytest.mark.parametrize("option, value, message", [
    ("--vehicle", "nosuch", "unknown vehicle preset 'nosuch'"),
    ("--computer", "ts9999", "ts9999"),
    ("--battery", "10 parsecs", "'parsecs' is not a unit of energy"),
])
def test_hardware_a_mission_cannot_name_is_bad_usage(tmp_path, capsys, option, value, message):
    _needs_missions()
    out = tmp_path / "x.mission"
    code = main(["import-slocum", str(MISSIONS / "nsb3" / "nsb3.mi"), "-o", str(out),
                 option, value])
    err = capsys.readouterr().err
    assert code == ExitCode.USAGE and message in err and "Traceback" not in err
    assert not out.exists()


def test_a_mission_with_no_behavior_says_it_only_waits_at_the_surface(tmp_path, capsys):
    text, err = _import(tmp_path, capsys, "# an empty file\n")
    assert "m.mi:1: warning: no behavior" in err
    assert "only waits at the surface" in text


def test_import_slocum_help_prints(capsys):
    """Its --battery default holds a '%' that argparse read as a format (a traceback)."""
    with pytest.raises(SystemExit) as done:
        main(["import-slocum", "--help"])
    assert done.value.code == 0 and "reserve 15 %" in capsys.readouterr().out
