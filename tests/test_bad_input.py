"""Bad input everywhere gets one clear line: board, battery, vehicle and scenario files with
negative, NaN, missing or wrong-unit figures; `--battery` strings; garbage Slocum logs;
a plan for another mission; a path that does not exist or is a directory.

Each row is a command as a user types it, with the files it reads made from the shipped
ones with one thing broken. The command must exit with the code README.md documents for
the problem and say so on one line that names the file (and the key or line) and the
problem; never a traceback, never a result written.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode
from gliderplan.power_models.catalog import preset_path

ROOT = Path(__file__).resolve().parents[1]
FIG2 = str(ROOT / "examples" / "fig2.mission")
SCENARIOS = ROOT / "sim" / "data" / "scenarios_default.toml"
USAGE, BAD = ExitCode.USAGE, ExitCode.BAD_INPUT


def _edit(source: Path, old: str, new: str) -> str:
    """`source`'s text with `old` (a regular expression, which must match) replaced."""
    text = source.read_text()
    edited, count = re.subn(old, new, text, count=1, flags=re.MULTILINE)
    assert count == 1, (source, old)
    return edited


BOARD, BATTERY = preset_path("board", "ts7800"), preset_path("battery", "alkaline")
VEHICLE = preset_path("vehicle", "slocum_g2_shallow")
# file name -> its text, for every broken file a row may name
FILES = {
    "negative.board.toml": _edit(BOARD, r"value = 3\.42", "value = -3.42"),
    "nan.board.toml": _edit(BOARD, r"value = 3\.42", "value = nan"),
    "missing.board.toml": _edit(BOARD, r"^boot_time = .*\n", ""),
    "unit.board.toml": _edit(BOARD, r'value = 3\.42, unit = "W"', 'value = 3.42, unit = "V"'),
    "kind.board.toml": _edit(BOARD, r'^kind = "board"', 'kind = "vehicle"'),
    "garbage.board.toml": "\x89PNG this is no TOML [[[\n",
    "negative.battery.toml": _edit(BATTERY, r"value = 7\.8", "value = -7.8"),
    "nan.battery.toml": _edit(BATTERY, r"value = 7\.8", "value = nan"),
    "missing.battery.toml": _edit(BATTERY, r"^energy = .*\n", ""),
    "unit.battery.toml": _edit(BATTERY, r'value = 7\.8, unit = "MJ"', 'value = 7.8, unit = "MW"'),
    "fraction.battery.toml": _edit(BATTERY, r"value = 85,", "value = 185,"),
    "negative.vehicle.toml": _edit(VEHICLE, r"^hotel_power = \{ value = ", "\\g<0>-"),
    "nan.vehicle.toml": _edit(VEHICLE, r"^hotel_power = \{ value = [0-9.]+", "hotel_power = "
                              "{ value = nan"),
    "missing.vehicle.toml": _edit(VEHICLE, r"^hotel_power = .*\n", ""),
    "unit.vehicle.toml": _edit(VEHICLE, r'^(hotel_power = \{ value = [0-9.]+, unit = )"W"',
                               '\\1"J"'),
    "negative.scenarios.toml": _edit(SCENARIOS, r"^temperature_sigma_c = .*",
                                     "temperature_sigma_c = -0.005"),
    "nan.scenarios.toml": _edit(SCENARIOS, r"mean = 14,", "mean = nan,"),
    "missing.scenarios.toml": _edit(SCENARIOS, r"^wave_period_s = .*\n", ""),
    "unit.scenarios.toml": _edit(SCENARIOS, r"^thermocline_depth_m", "thermocline_depth_ft"),
    "range.scenarios.toml": _edit(SCENARIOS, r"high = 0\.25", "high = 25"),
    "probability.scenarios.toml": _edit(SCENARIOS, r"high = 0\.002", "high = 2"),
    "garbage.dbd": "\x00\x01 not a Slocum log at all\n" * 40,
    "header-only.dbd": "dbd_label: DBD(dinkum_binary_data)file\nencoding_ver: 5\n",
    "notes.txt": "a file of the wrong kind\n",
}
VEHICLE_MISSION = _edit(ROOT / "examples" / "fig2_annotated.mission",
                        r"^vehicle slocum_g2_shallow", 'vehicle "{vehicle}"')

def _shown(argv: list[str]) -> str:
    return " ".join("fig2" if a == FIG2 else a for a in argv[:3])


# (what is wrong, argv, exit code, what the one line says after "gliderplan CMD: error: ")
ROWS = [
    # board files
    ("board negative", ["plan", FIG2, "--computer", "negative.board.toml"], BAD,
     "negative.board.toml: mode[0].active_power: must be > 0 W, got -3.42 W"),
    ("board NaN", ["power", "show", "board", "nan.board.toml"], BAD,
     "nan.board.toml: mode[0].active_power: value must be a finite number, got nan"),
    ("board missing figure", ["compare-sbc", FIG2, "--computer", "missing.board.toml"], BAD,
     "missing.board.toml: boot_time: missing"),
    ("board wrong unit", ["plan", FIG2, "--computer", "unit.board.toml"], BAD,
     "unit.board.toml: mode[0].active_power: unit 'V' is not a unit of power"),
    ("board of another kind", ["plan", FIG2, "--computer", "kind.board.toml"], BAD,
     "kind.board.toml: kind: this file describes a 'vehicle', expected a 'board'"),
    ("board not TOML", ["power", "show", "board", "garbage.board.toml"], BAD,
     "garbage.board.toml: not valid TOML"),
    # battery files
    ("battery negative", ["power", "show", "battery", "negative.battery.toml"], BAD,
     "negative.battery.toml: energy: must be > 0 MJ, got -7.8 MJ"),
    ("battery NaN", ["power", "show", "battery", "nan.battery.toml"], BAD,
     "nan.battery.toml: energy: value must be a finite number, got nan"),
    ("battery missing figure", ["power", "show", "battery", "missing.battery.toml"], BAD,
     "missing.battery.toml: energy: give exactly one of 'energy' and 'capacity'"),
    ("battery wrong unit", ["power", "show", "battery", "unit.battery.toml"], BAD,
     "unit.battery.toml: energy: unit 'MW' is not a unit of energy"),
    ("battery over 100 %", ["power", "show", "battery", "fraction.battery.toml"], BAD,
     "fraction.battery.toml: usable_fraction: must be <= 100 %, got 185 %"),
    # vehicle files, named in a mission or on the command line
    ("vehicle negative", ["plan", "{mission:negative.vehicle.toml}"], BAD,
     "negative.vehicle.toml: hotel_power: must be >= 0 W, got -2.41364 W"),
    ("vehicle NaN", ["sim", "{mission:nan.vehicle.toml}", "-o", "out"], BAD,
     "nan.vehicle.toml: hotel_power: value must be a finite number, got nan"),
    ("vehicle missing figure", ["power", "show", "vehicle", "missing.vehicle.toml"], BAD,
     "missing.vehicle.toml: hotel_power: missing"),
    ("vehicle wrong unit", ["compile", "{mission:unit.vehicle.toml}", "-o", "out"], BAD,
     "unit.vehicle.toml: hotel_power: unit 'J' is not a unit of power"),
    ("vehicle as the calibration base", ["calibrate", "header-only.dbd", "--base",
                                         "nan.vehicle.toml", "-o", "out/v.toml"], BAD,
     "nan.vehicle.toml: hotel_power: value must be a finite number, got nan"),
    # scenario files
    ("scenarios negative", ["montecarlo", FIG2, "--scenarios", "2", "--scenario-file",
                            "negative.scenarios.toml", "-o", "out"], BAD,
     "negative.scenarios.toml: sensors.temperature_sigma_c: value -0.005 is outside "
     "[0, inf]"),
    ("scenarios NaN", ["montecarlo", FIG2, "--scenarios", "2", "--scenario-file",
                       "nan.scenarios.toml", "-o", "out"], BAD,
     "nan.scenarios.toml: ocean.thermocline_depth_m: mean must be a finite number, got nan"),
    ("scenarios missing figure", ["montecarlo", FIG2, "--scenarios", "2", "--scenario-file",
                                  "missing.scenarios.toml", "-o", "out"], BAD,
     "missing.scenarios.toml: ocean.wave_period_s: missing"),
    ("scenarios wrong unit", ["montecarlo", FIG2, "--scenarios", "2", "--scenario-file",
                              "unit.scenarios.toml", "-o", "out"], BAD,
     "unit.scenarios.toml: ocean.thermocline_depth_ft: unknown key"),
    ("scenarios current past any ocean's", ["montecarlo", FIG2, "--scenarios", "2",
                                            "--scenario-file", "range.scenarios.toml", "-o",
                                            "out"], BAD,
     "range.scenarios.toml: ocean.current_speed_mps: high 25 is outside [0, 10]"),
    ("scenarios probability past 1", ["plan", FIG2, "--confidence", "0.9", "--scenario-file",
                                      "probability.scenarios.toml"], BAD,
     "probability.scenarios.toml: sensors.spike_probability_1: high 2 is outside [0, 1]"),
    # --battery strings
    *((f"--battery {text.lstrip('=')!r}", ["plan", FIG2, f"--battery{text}"], USAGE,
       f"--battery {text.lstrip('=')!r}: {said}") for text, said in [
        ("=", "expected an energy such as 1.2kWh"),
        ("=lots", "expected an energy such as 1.2kWh"),
        ("=-5Wh", "expected an energy such as 1.2kWh"),
        ("=1.2", "expected an energy such as 1.2kWh"),
        ("=1.2 parsec", "unit 'parsec' is not an energy or a charge"),
        ("=0Wh", "the energy must be positive and finite"),
        ("=nanWh", "expected an energy such as 1.2kWh"),
        ("=1e400Wh", "the energy must be positive and finite"),
        ("=60Ah", "a charge in Ah needs a positive voltage"),
        ("=60Ah@0V", "a charge in Ah needs a positive voltage"),
    ]),
    # Slocum logs (only the message: what a log holds is calibrate's to judge)
    ("garbage log", ["calibrate", "garbage.dbd", "-o", "out/v.toml"], BAD,
     "garbage.dbd: not a Slocum log (no dbd_label line first)"),
    ("log cut in its header", ["calibrate", "header-only.dbd", "-o", "out/v.toml"], BAD,
     "header-only.dbd: not a Slocum log (its header ends after 2 lines, with no "
     "num_ascii_tags line)"),
    ("a file of another kind as a log", ["calibrate", "notes.txt", "-o", "out/v.toml"], BAD,
     "notes.txt: not a Slocum log (no dbd_label line first)"),
    ("ocean logs that are garbage", ["sim", FIG2, "--ocean", "logs", "-o", "out"], BAD,
     "logs/garbage.ebd: not a Slocum log (no dbd_label line first)"),
    # a plan for another mission
    # (compile asks the runtime's own reader, the others the planner's)
    ("plan for another mission: compile", ["compile", FIG2, "--plan", "other.plan", "-o",
                                           "out"], BAD,
     "plan rejected: sampleMission: other.plan line 2: plan is for mission 'other', this "
     "runtime runs 'sampleMission'"),
    *((f"plan for another mission: {argv[0]}", argv, BAD,
       "plan rejected: other.plan:2: plan for mission 'other', not 'sampleMission'")
      for argv in (["sim", FIG2, "--plan", "other.plan", "-o", "out"],
                   ["montecarlo", FIG2, "--plan", "other.plan", "--scenarios", "2", "-o",
                    "out"])),
    # paths that do not exist, or are directories
    *((f"no such file: {_shown(argv)}", argv, USAGE, "none.toml: no such file")
      for argv in (["plan", FIG2, "--computer", "none.toml"],
                   ["power", "show", "battery", "none.toml"],
                   ["plan", "{mission:none.toml}"],
                   ["montecarlo", FIG2, "--scenarios", "2", "--scenario-file", "none.toml",
                    "-o", "out"],
                   ["calibrate", "header-only.dbd", "--base", "none.toml", "-o", "out/v.toml"])),
    *((f"a directory: {_shown(argv)}", argv, USAGE, "dir.toml: is a directory")
      for argv in (["plan", FIG2, "--computer", "dir.toml"],
                   ["power", "show", "vehicle", "dir.toml"],
                   ["sim", "{mission:dir.toml}", "-o", "out"],
                   ["sim", FIG2, "--plan", "dir.toml", "-o", "out"],
                   ["plan", FIG2, "--confidence", "0.9", "--scenario-file", "dir.toml"])),
]


@pytest.fixture
def workdir(tmp_path, monkeypatch) -> Path:
    monkeypatch.chdir(tmp_path)
    for name, text in FILES.items():
        (tmp_path / name).write_text(text)
    (tmp_path / "dir.toml").mkdir()
    logs = tmp_path / "logs"
    logs.mkdir()
    (logs / "garbage.ebd").write_text(FILES["garbage.dbd"])
    other = tmp_path / "other.mission"
    other.write_text(Path(FIG2).read_text().replace("sampleMission", "other"))
    assert main(["plan", str(other), "-o", "other.plan"]) == 0
    return tmp_path


@pytest.mark.parametrize(("argv", "code", "says"), [row[1:] for row in ROWS],
                         ids=[row[0] for row in ROWS])
def test_bad_input_gets_one_line_and_its_exit_code(workdir, capsys, argv, code, says):
    capsys.readouterr()
    argv = [_argument(workdir, a) for a in argv]
    try:
        exit_code = main(argv)
    except SystemExit as stop:  # argparse's own refusals
        exit_code = int(stop.code)
    # a file a mission names is found beside it: here, the test's folder
    err = capsys.readouterr().err.replace(f"{workdir}/", "")
    assert exit_code == code, (argv, err)
    assert err.startswith(f"gliderplan {argv[0]}: error: {says}"), err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert not (workdir / "out").exists()


def _argument(workdir: Path, text: str) -> str:
    """`{mission:FILE}`: a copy of the annotated Fig. 2 flying the vehicle in FILE."""
    if match := re.fullmatch(r"\{mission:(.+)\}", text):
        path = workdir / f"with-{match[1]}.mission"
        path.write_text(VEHICLE_MISSION.replace("{vehicle}", match[1]))
        return str(path)
    return text
