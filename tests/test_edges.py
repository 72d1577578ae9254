"""Trust at the edges (issue 28): bad input of every kind, in every command, ends in one
line naming the file (and key or line) and the exit code README.md documents for it:
binary, truncated and deeply nested files, NaN and infinite numbers, absurd values, named
pipes, symbolic-link loops, read-only files, a full output; options that need another;
plans checked where they enter; SIGTERM handled as Ctrl-C; --json and --version.

Each row of CASES is a command as a user types it, in a folder holding the broken files
FILES names; "{x}" is the path of file x there. The command must exit with the code and
say the message on stderr, never a traceback, and write no result.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

from gliderplan.cli.main import main
from gliderplan.contract import (
    MAX_DATA_DEPTH,
    MAX_SENSOR_WEIGHT,
    MAX_SIMULATED_TICKS,
    ExitCode,
)
from gliderplan.power_models.catalog import preset_path

REPO = Path(__file__).resolve().parents[1]
FIG2 = REPO / "examples" / "fig2.mission"
ANNOTATED = (REPO / "examples" / "fig2_annotated.mission").read_text()
MONTH = REPO / "examples" / "survey_month.mission"
USAGE, BAD = ExitCode.USAGE, ExitCode.BAD_INPUT
VEHICLE = preset_path("vehicle", "slocum_g2_shallow").read_text()
BOARD = preset_path("board", "ts7800").read_text()
BATTERY = preset_path("battery", "alkaline").read_text()
SCENARIOS = (REPO / "sim" / "data" / "scenarios_default.toml").read_text()
DEEP = "[" * 5000 + "]" * 5000  # a TOML array nested 5,000 deep


def annotated(old: str, new: str) -> str:
    """The annotated Fig. 2 with `old` replaced by `new` (which must be there)."""
    assert old in ANNOTATED, old
    return ANNOTATED.replace(old, new, 1)


def toml_with(text: str, line: str) -> str:
    """A model file's text with a line appended before its first table."""
    head, brace, tail = text.partition("\n[")
    return f"{head}\n{line}\n{brace}{tail}" if brace else f"{text}\n{line}\n"


FILES: dict[str, str | bytes] = {
    # data files nested past MAX_DATA_DEPTH, or holding numbers that are not finite
    "deep.vehicle.toml": toml_with(VEHICLE, f"deep = {DEEP}"),
    "deep.board.toml": toml_with(BOARD, f"deep = {DEEP}"),
    "deep.battery.toml": toml_with(BATTERY, f"deep = {DEEP}"),
    "deep.scenarios.toml": toml_with(SCENARIOS, f"deep = {DEEP}"),
    "dotted.vehicle.toml": toml_with(VEHICLE, "[" + ".".join(["a"] * 40) + "]\nx = 1"),
    "inf.vehicle.toml": re.sub(r"(hotel_power = \{ value = )[0-9.]+", r"\g<1>inf", VEHICLE,
                               count=1),
    "inf.battery.toml": re.sub(r"value = 7\.8", "value = -inf", BATTERY, count=1),
    "truncated.vehicle.toml": VEHICLE[: len(VEHICLE) // 2].rsplit("{", 1)[0] + "{ value =",
    "binary.vehicle.toml": b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR" + bytes(range(256)),
    "binary.mission": b"mission m\x00\x01\x02\n",
    "latin1.mission": "mission m\n# caf\u00e9\n".encode("latin-1"),
    # missions with absurd values
    "weight.mission": annotated("sensor temp weight 3", "sensor temp weight 1e308"),
    "floor.mission": annotated("objective maximize quality",
                               "objective minimize energy quality >= 1e308"),
    "battery.mission": annotated("battery 1.2 kWh", "battery 1e300 kWh"),
    "horizon.mission": annotated("horizon 1 h", "horizon 1e300 h"),
    "tick_horizon.mission": annotated("horizon 1 h", "horizon 1 s"),
    "deepfile.mission": annotated("vehicle slocum_g2_shallow", 'vehicle "deep.vehicle.toml"'),
    "preset.mission": annotated("battery 1.2 kWh reserve 15 %", "battery alkalin"),
    "loopfile.mission": annotated("vehicle slocum_g2_shallow", 'vehicle "loop.toml"'),
    "sleepy.mission": annotated("computer ts7800 @ 300 MHz", "computer ts7800 @ 300 MHz")
    .replace("  sensors missiontime, depth, pitch, temp duty auto\n",
             "  sensors missiontime, depth, pitch, temp duty auto\n"
             "  computer sleep between ticks\n", 1),
    "broken.mission": "mission m\nstate s begin\n",
    # run files
    "nan-summary/summary.json": '{"mission": "m", "tick_s": NaN}',
    "cut-summary/summary.json": '{"mission": "m", "tick_s": 4',
    "deep-summary/summary.json": "[" * 10000 + "]" * 10000,
    "metadata.toml": 'sea_name = ["North Sea"]\n',
}


@pytest.fixture
def folder(tmp_path, monkeypatch) -> Path:
    monkeypatch.chdir(tmp_path)
    for name, content in FILES.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content)
    os.mkfifo(tmp_path / "pipe.toml")
    os.symlink("loop.toml", tmp_path / "loop.toml")  # a link to itself
    os.symlink("loop2.mission", tmp_path / "loop1.mission")
    os.symlink("loop1.mission", tmp_path / "loop2.mission")
    (tmp_path / "readonly.mission").write_text("mission   m\n" + FIG2.read_text()
                                               .split("\n", 1)[1])
    (tmp_path / "readonly.mission").chmod(0o444)
    (tmp_path / "readonly.plan").write_text("an earlier plan\n")
    (tmp_path / "readonly.plan").chmod(0o444)
    return tmp_path


DEEP_SAID = f"nested more than {MAX_DATA_DEPTH} deep"
# (what is wrong, argv, exit code, what stderr says)
CASES = [
    # bounded parsing: depth, numbers that are not finite, binary and truncated files
    ("deep vehicle named in a mission: plan", ["plan", "{deepfile.mission}"], BAD, DEEP_SAID),
    ("deep vehicle named in a mission: sim", ["sim", "{deepfile.mission}", "-o", "out"], BAD,
     DEEP_SAID),
    ("deep vehicle named in a mission: compile", ["compile", "{deepfile.mission}", "-o", "out"],
     BAD, DEEP_SAID),
    ("deep vehicle named in a mission: compare-sbc", ["compare-sbc", "{deepfile.mission}"], BAD,
     DEEP_SAID),
    ("deep vehicle named in a mission: report", ["report", "{deepfile.mission}", "-o", "out"],
     BAD, DEEP_SAID),
    ("deep vehicle named in a mission: forecast", ["forecast", "{deepfile.mission}"], BAD,
     DEEP_SAID),
    ("deep vehicle: power show", ["power", "show", "vehicle", "{deep.vehicle.toml}"], BAD,
     DEEP_SAID),
    ("deep board: plan --computer", ["plan", str(FIG2), "--computer", "{deep.board.toml}"],
     BAD, DEEP_SAID),
    ("deep battery: power show", ["power", "show", "battery", "{deep.battery.toml}"], BAD,
     DEEP_SAID),
    ("deep scenario file: montecarlo", ["montecarlo", str(FIG2), "--scenarios", "2",
                                        "--scenario-file", "{deep.scenarios.toml}", "-o",
                                        "out"], BAD, DEEP_SAID),
    ("deep vehicle as a calibration base", ["calibrate", ".", "--base",
                                            "{deep.vehicle.toml}"], BAD, DEEP_SAID),
    ("tables nested by dotted keys", ["power", "show", "vehicle", "{dotted.vehicle.toml}"],
     BAD, DEEP_SAID),
    ("infinite figure", ["power", "show", "vehicle", "{inf.vehicle.toml}"], BAD,
     "inf.vehicle.toml: hotel_power: value must be a finite number, got inf"),
    ("minus infinite battery", ["power", "show", "battery", "{inf.battery.toml}"], BAD,
     "inf.battery.toml: energy: value must be a finite number, got -inf"),
    ("truncated TOML", ["power", "show", "vehicle", "{truncated.vehicle.toml}"], BAD,
     "truncated.vehicle.toml: not valid TOML"),
    ("binary model file", ["plan", str(FIG2), "--computer", "{binary.vehicle.toml}"], BAD,
     "binary.vehicle.toml: binary file (contains NUL bytes)"),
    ("binary mission", ["check", "{binary.mission}"], BAD,
     "binary.mission: binary file (contains NUL bytes), not a mission"),
    ("Latin-1 mission", ["fmt", "{latin1.mission}"], BAD, "latin1.mission:2: not UTF-8 text"),
    ("NaN in a run summary", ["export", "{nan-summary}", "--kml"], BAD,
     "summary.json: tick_s must be a finite number, got nan"),
    ("truncated run summary", ["export", "{cut-summary}", "--format", "og1"], BAD,
     "summary.json: not valid JSON"),
    ("deeply nested run summary", ["export", "{deep-summary}", "--format", "ioos"], BAD,
     "summary.json: tables or arrays nested more than"),
    ("a metadata file of the wrong shape", ["export", "{nan-summary}", "--format", "og1",
                                            "--metadata", "{metadata.toml}"], USAGE,
     "metadata.toml: sea_name: expected a non-empty text"),
    # numbers checked where they enter (the mission's diagnostics name the line)
    ("weight 1e308: plan", ["plan", "{weight.mission}"], BAD,
     f"weight.mission:13:20: error: a weight must lie between 0 and {MAX_SENSOR_WEIGHT:g}"),
    ("weight 1e308: compare-sbc", ["compare-sbc", "{weight.mission}"], BAD,
     "weight.mission:13:20: error: a weight must lie between 0"),
    ("quality floor 1e308", ["plan", "{floor.mission}"], BAD,
     "floor.mission:10:38: error: a quality floor must lie between 0 and 1"),
    ("battery 1e300 kWh: sim", ["sim", "{battery.mission}", "-o", "out"], BAD,
     "larger than any plan can carry"),
    ("battery 1e300 Wh on the command line", ["plan", str(FIG2), "--battery", "1e300Wh"],
     USAGE, "--battery '1e300Wh': larger than any plan can carry"),
    ("horizon 1e300 h", ["check", "{horizon.mission}"], BAD,
     "horizon must lie between one tick (4 s) and 10 years"),
    ("horizon shorter than a tick", ["plan", "{tick_horizon.mission}"], BAD,
     "horizon must lie between one tick"),
    ("a battery preset no file names", ["check", "{preset.mission}"], BAD,
     "unknown battery preset 'alkalin'"),
    # a run longer than memory holds: refused at once, saying how long it would be
    ("sim --tick 0.1 of a 30-day mission", ["sim", str(MONTH), "--tick", "0.1", "-o", "out"],
     USAGE, f"is 25,920,000 ticks, more than the {MAX_SIMULATED_TICKS:,} one run holds"),
    ("montecarlo of 3,000 days", ["montecarlo", str(FIG2), "--scenarios", "2",
                                   "--duration", "3000d", "-o", "out"], USAGE,
     "ticks, more than the"),
    ("montecarlo --workers 100000", ["montecarlo", str(FIG2), "--scenarios", "2",
                                     "--workers", "100000", "-o", "out"], USAGE,
     "--workers 100000: at most 256 worker processes"),  # once forked until none were left
    ("plan --confidence --workers 100000", ["plan", str(FIG2), "--confidence", "0.9",
                                            "--workers", "100000"], USAGE,
     "--workers 100000: at most 256"),
    ("forecast of 1e300 days", ["forecast", str(FIG2), "--duration", "1e300d"], USAGE,
     "--duration '1e300d': must be at most 10 years"),  # once forecast, exit 0
    ("import-slocum over 1e300 days", ["import-slocum", "x.mi", "--horizon", "1e300d", "-o",
                                       "out"], USAGE, "--horizon '1e300d': must be at most"),
    ("power energy below the deepest ocean", ["power", "energy", "--max-depth", "1e308"],
     USAGE, "--max-depth must be at most 11,000 m, the deepest ocean"),
    ("power speed for a 1e308 W hotel load", ["power", "speed", "--hotel-w", "1e308"], USAGE,
     "--hotel-w values must be at most 1000 W"),  # once overflowed, exit 0
    ("power energy from a NaN top", ["power", "energy", "--min-depth", "nan"], USAGE,
     "--min-depth must be >= 0"),  # once printed a table of NaN, exit 0
    # named pipes and symbolic-link loops
    ("a named pipe for a metadata file", ["export", "{nan-summary}", "--format", "og1",
                                          "--metadata", "{pipe.toml}"], USAGE,
     "pipe.toml: is not a regular file"),
    ("a named pipe for a key", ["compile", str(FIG2), "--plan", "{pipe.toml}", "--key",
                                "{pipe.toml}", "-o", "out"], USAGE,
     "pipe.toml: is not a regular file"),
    ("a symbolic-link loop for a mission", ["check", "{loop1.mission}"], USAGE,
     "loop1.mission: cannot open: Too many levels of symbolic links"),
    ("a symbolic-link loop named in a mission", ["plan", "{loopfile.mission}"], USAGE,
     "loop.toml: cannot open: Too many levels of symbolic links"),
    ("a symbolic-link loop for a board", ["compare-sbc", str(FIG2), "--computer",
                                          "{loop.toml}"], USAGE,
     "loop.toml: cannot open: Too many levels of symbolic links"),
    # read-only results are refused, not replaced
    ("fmt --write of a read-only mission", ["fmt", "--write", "{readonly.mission}"], USAGE,
     "readonly.mission: read-only (mode 444): not replaced"),
    ("plan -o over a read-only plan", ["plan", str(FIG2), "-o", "{readonly.plan}"], USAGE,
     "readonly.plan: read-only (mode 444): not replaced"),
    # options that need another: refused, not ignored
    ("plan --scenarios alone", ["plan", str(FIG2), "--scenarios", "5"], USAGE,
     "--scenarios works only with --confidence or --occupancy-from-sim"),
    ("plan --risk alone", ["plan", str(FIG2), "--risk", "0.01"], USAGE,
     "--risk works only with --confidence"),
    ("plan --seq alone", ["plan", str(FIG2), "--seq", "7"], USAGE,
     "--seq works only with --sign"),
    ("plan --sweep with --confidence", ["plan", str(FIG2), "--sweep", "5", "--confidence",
                                        "0.9", "-o", "sweep"], USAGE,
     "--sweep plans at N budgets without --confidence"),
    ("compile --key alone", ["compile", str(FIG2), "--key", "vehicle.key", "-o", "out"], USAGE,
     "--key works only with --plan"),
    ("calibrate --name alone", ["calibrate", ".", "--name", "g1"], USAGE,
     "--name works only with --output"),
    ("fmt --json alone", ["fmt", "--json", str(FIG2)], USAGE,
     "--json says what --check or --write did"),
    ("forecast --mafiles of a mission", ["forecast", str(FIG2), "--mafiles", "."], USAGE,
     "--mafiles: "),
    ("export to an unknown format", ["export", "{nan-summary}", "--format", "netcdf3"], USAGE,
     "--format netcdf3: expected one of og1, ioos, cf"),
    # a board feature the target lacks
    ("a TS-7800 sleep built for the TS-5500", ["compile", "{sleepy.mission}", "--target",
                                               "ts5500", "-o", "out"], BAD,
     "cannot run on board ts5500 (target ts5500; clocks 133 MHz): state s1 asks to 'sleep "
     "between ticks'"),
    # one exit code per kind of error, whatever the number of files
    ("a missing mission beside a good one: check", ["check", str(FIG2), "none.mission"], USAGE,
     "none.mission: no such file"),
    ("a missing mission beside a broken one: fmt", ["fmt", "{broken.mission}", "none.mission"],
     USAGE, "none.mission: no such file"),
]


def _argv(folder: Path, argv: list[str]) -> list[str]:
    return [re.sub(r"\{([^}]+)\}", lambda m: str(folder / m[1]), a) for a in argv]


@pytest.mark.parametrize(("argv", "code", "says"), [c[1:] for c in CASES],
                         ids=[c[0] for c in CASES])
def test_bad_input_exits_with_its_code_and_says_what_is_wrong(folder, capsys, argv, code,
                                                              says):
    argv = _argv(folder, argv)
    try:
        exit_code = main(argv)
    except SystemExit as stop:
        exit_code = int(stop.code)
    err = capsys.readouterr().err
    assert exit_code == code, (argv, err)
    assert says in err.replace(f"{folder}/", ""), err
    assert "Traceback" not in err and "internal error" not in err, err
    files = sum(a.endswith(".mission") for a in argv[1:])  # check and fmt: one per file
    assert err.count(f"gliderplan {argv[0]}: error: ") <= max(files, 1), err
    assert not (folder / "out").exists()


def test_at_least_forty_bad_inputs_are_tried():
    assert len(CASES) >= 40


# ---- a full output ----------------------------------------------------------------------

@pytest.mark.parametrize("argv", [["check", "--json", str(FIG2)], ["fmt", str(FIG2)],
                                  ["power", "list", "--json"]], ids=lambda a: a[0])
def test_a_full_output_is_an_output_that_cannot_be_written(argv):
    """stdout on a full disk (/dev/full): exit 2 as for an -o that cannot be written, one
    line, nothing left to fail at exit."""
    with open(os.devnull if not os.path.exists("/dev/full") else "/dev/full", "w") as full:
        run = subprocess.run([sys.executable, "-m", "gliderplan.cli", *argv], stdout=full,
                             stderr=subprocess.PIPE, text=True, timeout=120)
    assert run.returncode == ExitCode.USAGE, run.stderr
    assert run.stderr == (f"gliderplan {argv[0]}: error: cannot write the output (stdout): "
                          "No space left on device\n")


# ---- files a mission names are beside it ---------------------------------------------

def test_a_file_a_mission_names_is_found_beside_the_mission(tmp_path, monkeypatch):
    (tmp_path / "glider").mkdir()
    (tmp_path / "glider" / "my.toml").write_text(VEHICLE.replace(
        'name = "slocum_g2_shallow"', 'name = "mine"'))
    (tmp_path / "glider" / "pack.toml").write_text(BATTERY)
    mission = tmp_path / "glider" / "m.mission"
    mission.write_text(annotated("vehicle slocum_g2_shallow", 'vehicle "my.toml"').replace(
        "battery 1.2 kWh reserve 15 %", 'battery "pack.toml" reserve 10 %'))
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")  # no my.toml here
    from gliderplan.language import check_file

    checked = check_file(str(mission)).checked()
    assert checked.vehicle == str(tmp_path / "glider" / "my.toml")
    assert checked.battery.energy_j == pytest.approx(7.8e6)  # the pack's
    assert checked.battery.reserve_fraction == pytest.approx(0.10)  # the line's
    assert main(["plan", str(mission), "-o", "m.plan"]) == 0
    # checked from its own folder, the mission is the same: its hash holds the text
    monkeypatch.chdir(tmp_path / "glider")
    assert check_file("m.mission").checked().hash == checked.hash


def test_battery_presets_are_in_the_mission_language():
    from gliderplan.language import check_source
    from gliderplan.power_models import load_battery

    pack = load_battery("alkaline")
    checked = check_source(annotated("battery 1.2 kWh reserve 15 %", "battery alkaline"),
                           "x.mission").checked()
    assert checked.battery.energy_j == pack.energy_j
    assert checked.battery.reserve_fraction == pytest.approx(1.0 - pack.usable_fraction)
    with_reserve = check_source(annotated("battery 1.2 kWh reserve 15 %",
                                          "battery alkaline reserve 30 %"), "x").checked()
    assert with_reserve.battery.reserve_fraction == pytest.approx(0.30)
    from gliderplan.language.formatter import format_source

    assert "battery alkaline reserve 30%" in format_source(
        annotated("battery 1.2 kWh reserve 15 %", "battery   alkaline reserve 30 %"))


# ---- plans checked where they enter --------------------------------------------------

def _recomputed(data: bytes, old: bytes, new: bytes) -> bytes:
    """A signed plan with a value changed and its CRC recomputed (the signature kept)."""
    lines = data.split(b"\n")
    at = next(i for i, line in enumerate(lines) if line.startswith(b"crc32 "))
    body = b"\n".join(lines[:at]).replace(old, new, 1) + b"\n"
    return body + f"crc32 {zlib.crc32(body):08x}\n".encode() + b"\n".join(lines[at + 1:])


def test_compile_checks_the_signature_with_the_vehicle_s_key(tmp_path, capsys):
    mission = tmp_path / "fig2.mission"
    mission.write_text(ANNOTATED)
    key, plan = tmp_path / "vehicle.key", tmp_path / "fig2.plan"
    assert main(["keygen", "-o", str(key)]) == 0
    assert main(["plan", str(mission), "-o", str(plan), "--sign", str(key)]) == 0
    assert main(["compile", str(mission), "--plan", str(plan), "--key", str(key), "-o",
                 str(tmp_path / "ok")]) == 0
    budget = re.search(rb"\nbudget_j (\S+)", plan.read_bytes())[1]
    tampered = tmp_path / "tampered.plan"
    tampered.write_bytes(_recomputed(plan.read_bytes(), b"budget_j " + budget,
                                     b"budget_j 99999"))
    capsys.readouterr()
    assert main(["compile", str(mission), "--plan", str(tampered), "--key", str(key), "-o",
                 str(tmp_path / "no")]) == BAD
    assert "the signature does not match" in capsys.readouterr().err
    unsigned = tmp_path / "unsigned.plan"
    assert main(["plan", str(mission), "-o", str(unsigned)]) == 0
    capsys.readouterr()
    assert main(["compile", str(mission), "--plan", str(unsigned), "--key", str(key), "-o",
                 str(tmp_path / "no")]) == BAD
    assert "the plan is not signed" in capsys.readouterr().err
    assert not (tmp_path / "no").exists()


def test_compile_refuses_a_plan_made_for_another_board(tmp_path, capsys):
    mission = tmp_path / "fig2.mission"
    mission.write_text(ANNOTATED)
    plan = tmp_path / "ts5500.plan"
    assert main(["plan", str(mission), "--computer", "ts5500", "-o", str(plan)]) == 0
    capsys.readouterr()  # the runtime's own check names the board, not its clock
    assert main(["compile", str(mission), "--plan", str(plan), "-o", str(tmp_path / "o")]) \
        == BAD
    assert "ts5500.plan line 4: computer ts5500: the mission flies on board ts7800 (plan " \
        "again with --computer ts7800)" in capsys.readouterr().err


# ---- SIGTERM is Ctrl-C -------------------------------------------------------------------

def _stop_with_sigterm(argv: list[str], tmp_path: Path) -> tuple[int, str]:
    """Run `gliderplan ARGV`, send it SIGTERM once it reports progress; (exit code, its
    stderr). Its temporary files must be gone by then."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    process = subprocess.Popen([sys.executable, "-m", "gliderplan.cli", *argv],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "TMPDIR": str(scratch),
                                    "GLIDERPLAN_PROGRESS_S": "0"})
    said = []
    for line in process.stderr:  # a line per update: it is flying
        said.append(line)
        if line.startswith("progress: "):
            break
    process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=120)
    left = [p.name for p in scratch.iterdir() if not p.name.startswith(".lark_cache")]
    assert left == [], left  # temporary files removed
    return process.returncode, "".join(said) + err


def test_sigterm_stops_a_long_run_as_ctrl_c_does(tmp_path):
    out = tmp_path / "run"
    code, err = _stop_with_sigterm(["sim", str(MONTH), "--tick", "1", "-o", str(out)],
                                   tmp_path)
    assert code == ExitCode.TERMINATED == 128 + signal.SIGTERM, err
    assert "interrupted: the outputs in" in err and "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["ended"] == "interrupted" and 0 < summary["simulated_s"] < 30 * 86400


def test_sigterm_stops_the_c_runtime_and_removes_its_build(tmp_path):
    out = tmp_path / "run"
    code, err = _stop_with_sigterm(["sim", str(MONTH), "--runtime", "c", "-o", str(out)],
                                   tmp_path)
    assert code == ExitCode.TERMINATED, err
    assert (out / "timeseries.parquet").is_file()
    running = subprocess.run(["pgrep", "-f", str(tmp_path)], capture_output=True, text=True)
    assert running.stdout == "", running.stdout  # no runtime left behind


# ---- --json, --version -------------------------------------------------------------------

def test_check_json_prints_a_broken_mission_s_diagnostics(tmp_path, capsys):
    bad = tmp_path / "bad.mission"
    bad.write_text("mission m\nstate s begin\n")
    assert main(["check", "--json", str(bad)]) == BAD
    data = json.loads(capsys.readouterr().out)
    assert data["ok"] is False and data["mission"] is None
    (diagnostic,) = data["diagnostics"]
    assert diagnostic == {"file": str(bad), "line": 2, "column": 7, "end_line": 2,
                          "end_column": 8, "severity": "error",
                          "message": "state 's' has no 'end'",
                          "hint": "the file ends inside it; close it with 'end'"}


@pytest.mark.parametrize("argv", [
    ["check"], ["fmt", "--check"], ["plan"], ["compile", "-o", "out"], ["sim", "-o", "out"],
    ["montecarlo", "--scenarios", "2", "-o", "out"], ["compare-sbc"], ["forecast"],
    ["report", "-o", "out"], ["import-slocum", "-o", "out"]], ids=lambda a: a[0])
def test_every_command_s_error_is_json_under_json(tmp_path, capsys, argv, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main([argv[0], "none.mission", *argv[1:], "--json"]) == USAGE
    data = json.loads(capsys.readouterr().out)
    data = data[0] if isinstance(data, list) else data
    assert data["ok"] is False and data["exit_code"] == USAGE
    assert data["diagnostics"][0]["message"] == "none.mission: no such file"
    assert data["diagnostics"][0]["file"] == "none.mission"


def test_every_command_takes_json():
    from gliderplan.cli.main import build_parser, subcommands

    for name in subcommands():
        parser = build_parser(name)
        (commands,) = [a for a in parser._actions if isinstance(getattr(a, "choices", None),
                                                                dict)]
        forms = [commands.choices[name]]
        nested = [a for a in forms[0]._actions if isinstance(getattr(a, "choices", None),
                                                             dict)]
        if nested:  # power: each form
            forms = list(nested[0].choices.values())
        for form in forms:
            assert "--json" in {o for a in form._actions for o in a.option_strings}, name


def test_version(capsys):
    from importlib.metadata import version

    assert main(["--version"]) == 0
    assert capsys.readouterr().out == f"gliderplan {version('gliderplan')}\n"


# ---- words -------------------------------------------------------------------------------

def test_a_run_over_its_prediction_exits_4_under_strict_prediction(tmp_path, capsys):
    survey = REPO / "examples" / "thermocline_survey.mission"
    plan = tmp_path / "survey.plan"
    assert main(["plan", str(survey), "-o", str(plan)]) == 0
    capsys.readouterr()
    assert main(["sim", str(survey), "--plan", str(plan), "--strict-prediction", "-o",
                 str(tmp_path / "run")]) == ExitCode.OVER_PREDICTION == 4
    err = capsys.readouterr().err
    # one headline from the total, against the prediction and the budget
    assert re.search(r"plan check: over prediction: [\d.]+ kJ spent, [\d.]+ kJ predicted "
                     r"\(\+\d+\.\d %, tolerance 5 %\), budget [\d.]+ kJ", err), err
    assert err.count("plan check:") == 1


def test_a_state_over_its_prediction_does_not_make_the_run_s_verdict():
    from gliderplan.planner.planfile import Assumption, Plan, StatePlan
    from gliderplan.sim.energy import RunEnergy, check_flight

    def state(name: str, joules: float) -> StatePlan:
        return StatePlan(name, 300.0, 0.0, 100.0, 1, 0.0, {"hotel": joules}, (), ())

    plan = Plan("m", "0" * 64, "ts7800", 300.0, 1000.0, 200.0,
                (state("a", 100.0), state("b", 100.0)), (Assumption("mission", "x"),))
    flown = RunEnergy({"hotel": np.array([150.0, 40.0])},
                      {"a": {"hotel": 150.0}, "b": {"hotel": 40.0}}, {"a": 0, "b": 0},
                      {"a": 100.0, "b": 100.0})
    check = check_flight(flown, plan)
    assert check.verdict == "pass"  # 190 J against 200 J predicted
    assert check.headline.startswith("pass: 0.2 kJ spent, 0.2 kJ predicted (-5.0 %")
    assert len(check.causes) == 1 and check.causes[0].startswith("a: ")


def test_montecarlo_says_what_happened(tmp_path, capsys):
    assert main(["montecarlo", str(FIG2), "--scenarios", "3", "--workers", "1", "-o",
                 str(tmp_path / "mc")]) == 0
    out = capsys.readouterr().out
    assert "ran out" not in out
    assert re.search(r"\d+ exceeded the usable charge drawn for the scenario \(the budget "
                     r"times a usable share drawn from normal \(mean 0\.97, sd 0\.03, within "
                     r"0\.8-1\.02\)\); the runs ended: 3 by exit", out), out


def test_defaults_are_printed_where_the_prediction_is(capsys):
    assert main(["plan", str(FIG2)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[3].startswith("defaults: vehicle slocum_g2_shallow, computer ts7800 @ 300 "
                               "MHz, battery 2.167 kWh reserve 15 %")
    assert main(["forecast", str(MONTH.parent / "thermocline_survey.mission")]) == 0
    assert "defaults" not in capsys.readouterr().out  # the survey names them all
