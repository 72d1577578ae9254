"""One error, one exit code, in every command that can meet it (README.md, "Exit codes"):
the library raises it with its code (`contract.errors`), `cli/main.py` alone prints it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import MAX_INPUT_BYTES, MAX_STATES, ExitCode

FIG2 = str(Path(__file__).resolve().parents[1] / "examples" / "fig2.mission")
ANNOTATED = str(Path(__file__).resolve().parents[1] / "examples" / "fig2_annotated.mission")
LONG = "a" * 300  # longer than any file name may be (255 bytes)
SLOCUM_MISSIONS = {
    "good.mi": "behavior: surface\n  b_arg: start_when(enum) 9\n  b_arg: when_secs(sec) 600\n",
    "bad.mi": "behavior: yo\n  b_arg: start_when(enum)\n",
    "noma.mi": "behavior: yo\n  b_arg: args_from_file(enum) 10\n",
    "unknown.mi": "behavior: loiter_about\n",
}

# (what is wrong, the commands that meet it, the exit code, what the message says)
# Paths are relative to the test's temporary directory; "{bad}" is a mission that does
# not parse, "{broken}" a plan file that breaks the format, "{file}" a regular file,
# "{slocum}" a directory of Slocum missions (SLOCUM_MISSIONS: good.mi and broken ones).
CASES = [
    ("missing mission file", [
        ["check", "none.mission"], ["fmt", "none.mission"], ["plan", "none.mission"],
        ["compile", "none.mission", "-o", "out"], ["sim", "none.mission", "-o", "out"],
        ["montecarlo", "none.mission", "--scenarios", "2", "-o", "out"],
        ["compare-sbc", "none.mission"], ["import-slocum", "none.mission", "-o", "out"],
        ["fleet", "check", "none.mission"], ["fleet", "plan", "none.mission"],
        ["fleet", "sim", "none.mission", "-o", "out"],
        ["fleet", "montecarlo", "none.mission", "--scenarios", "2", "-o", "out"],
    ], ExitCode.USAGE, "none.mission: no such file"),
    ("a directory for a mission", [
        ["check", "."], ["fmt", "."], ["plan", "."], ["compile", ".", "-o", "out"],
        ["sim", ".", "-o", "out"], ["import-slocum", ".", "-o", "out"],
    ], ExitCode.USAGE, "is a directory"),
    ("a malformed line of a Slocum mission", [
        ["import-slocum", "{slocum}/bad.mi", "-o", "out"],
    ], ExitCode.BAD_INPUT, "bad.mi:2: malformed line 'b_arg: start_when(enum)'"),
    ("a .ma file that is not there", [
        ["import-slocum", "{slocum}/noma.mi", "-o", "out"],
    ], ExitCode.BAD_INPUT, "noma.mi:2: args_from_file 10: no file"),
    ("an unknown Slocum behavior", [
        ["import-slocum", "{slocum}/unknown.mi", "-o", "out"],
    ], ExitCode.BAD_INPUT, "unknown.mi:1: unknown behavior 'loiter_about'"),
    ("missing run directory", [
        ["export", "none", "--kml"], ["report", ANNOTATED, "--run", "none", "-o", "out"],
    ], ExitCode.USAGE, "none: no such directory"),
    ("a mission that does not parse", [
        ["check", "{bad}"], ["fmt", "{bad}"], ["plan", "{bad}"],
        ["compile", "{bad}", "-o", "out"], ["sim", "{bad}", "-o", "out"],
    ], ExitCode.BAD_INPUT, "bad.mission:2:"),
    ("a mission larger than the runtime holds", [  # refused before a model is built
        ["check", "{big}"], ["plan", "{big}"], ["compile", "{big}", "-o", "out"],
        ["sim", "{big}", "-o", "out"], ["montecarlo", "{big}", "--scenarios", "2", "-o", "out"],
        ["compare-sbc", "{big}"], ["report", "{big}", "-o", "out"],
    ], ExitCode.BAD_INPUT, f"more than the {MAX_STATES} the runtime holds"),
    ("a stack deeper than the runtime's", [
        ["check", FIG2, "--max-stack", "40"], ["plan", FIG2, "--max-stack", "40"],
        ["compile", FIG2, "--max-stack", "40", "-o", "out"],
        ["sim", FIG2, "--max-stack", "40", "-o", "out"],
    ], ExitCode.USAGE, "--max-stack must be between 1 and 32"),
    ("missing plan file", [
        ["compile", FIG2, "--plan", "none.plan", "-o", "out"],
        ["sim", FIG2, "--plan", "none.plan", "-o", "out"],
        ["montecarlo", FIG2, "--plan", "none.plan", "--scenarios", "2", "-o", "out"],
    ], ExitCode.USAGE, "none.plan: no such file"),
    ("a plan that breaks the format", [
        ["compile", FIG2, "--plan", "{broken}", "-o", "out"],
        ["sim", FIG2, "--plan", "{broken}", "-o", "out"],
        ["montecarlo", FIG2, "--plan", "{broken}", "--scenarios", "2", "-o", "out"],
    ], ExitCode.BAD_INPUT, "plan rejected: "),
    ("unknown board preset", [
        ["plan", FIG2, "--computer", "ts9000"], ["power", "show", "board", "ts9000"],
        ["compare-sbc", FIG2, "--computer", "ts9000"],
    ], ExitCode.USAGE, "unknown board preset"),
    ("a clock the board does not have", [
        ["plan", FIG2, "--computer", "ts7800@400"], ["power", "show", "board", "ts7800@400"],
    ], ExitCode.USAGE, "no 400 MHz clock"),
    ("missing model file", [
        ["plan", FIG2, "--computer", "none.toml"], ["power", "show", "vehicle", "none.toml"],
        ["calibrate", ".", "--base", "none.toml"],
    ], ExitCode.USAGE, "none.toml: no such file"),
    ("missing data file", [
        ["calibrate", "none.dbd"], ["sim", FIG2, "--ocean", "none.dbd", "-o", "out"],
    ], ExitCode.USAGE, "none.dbd: no such"),
    ("missing scenario file", [
        ["montecarlo", FIG2, "--scenario-file", "none.toml", "--scenarios", "2", "-o", "out"],
        ["plan", ANNOTATED, "--confidence", "0.9", "--scenario-file", "none.toml"],
    ], ExitCode.USAGE, "none.toml: no such file"),
    ("a device for a file", [  # read, it would never end
        ["check", "/dev/zero"], ["fmt", "/dev/zero"], ["plan", "/dev/zero"],
        ["compile", FIG2, "--plan", "/dev/zero", "-o", "out"],
        ["sim", FIG2, "--plan", "/dev/urandom", "-o", "out"],
        ["sim", FIG2, "--ocean", "/dev/zero", "-o", "out"],
        ["montecarlo", FIG2, "--scenario-file", "/dev/zero", "--scenarios", "2", "-o", "out"],
        ["plan", FIG2, "--computer", "/dev/zero"], ["plan", FIG2, "--battery", "/dev/zero"],
        ["power", "show", "vehicle", "/dev/urandom"],
        ["compare-sbc", FIG2, "--computer", "/dev/zero"],
        ["import-slocum", "/dev/zero", "-o", "out"],
        ["calibrate", ".", "--base", "/dev/zero"], ["plan", FIG2, "--sign", "/dev/zero"],
    ], ExitCode.USAGE, "/dev/"),
    ("a device named in a mission", [  # `vehicle "/dev/zero"` once grew a process to 10 GB
        ["plan", "{device_vehicle}"], ["sim", "{device_vehicle}", "-o", "out"],
        ["compile", "{device_vehicle}", "-o", "out"], ["compare-sbc", "{device_vehicle}"],
        ["montecarlo", "{device_vehicle}", "--scenarios", "2", "-o", "out"],
        ["report", "{device_vehicle}", "-o", "out"],
        ["plan", "{device_computer}"], ["compare-sbc", "{device_computer}"],
    ], ExitCode.USAGE, "/dev/zero: is not a regular file (a device, pipe or socket)"),
    ("a file larger than any input", [
        ["check", "{huge}"], ["plan", FIG2, "--computer", "{huge}"],
        ["sim", FIG2, "--plan", "{huge}", "-o", "out"],
    ], ExitCode.BAD_INPUT, f"huge.toml: more than {MAX_INPUT_BYTES} bytes is too large"),
    ("a file name longer than the system allows", [
        ["check", LONG], ["fmt", LONG], ["plan", LONG], ["sim", LONG, "-o", "out"],
        ["sim", FIG2, "--plan", LONG, "-o", "out"],
        ["plan", FIG2, "--computer", f"{LONG}.toml"],
        ["power", "show", "board", f"{LONG}.toml"],
    ], ExitCode.USAGE, "file name too long"),
    ("a result that cannot be written there", [
        ["plan", FIG2, "-o", "{file}/fig2.plan"], ["plan", FIG2, "-o", f"{LONG}.plan"],
        ["plan", ANNOTATED, "--sweep", "3", "-o", "{file}/sweep"],
        ["compile", FIG2, "-o", "{file}/build"],
        ["sim", FIG2, "--duration", "60s", "-o", "{file}/run"],
        ["montecarlo", FIG2, "--scenarios", "2", "--duration", "60s", "-o", "{file}/mc"],
        ["compare-sbc", FIG2, "-o", "{file}/sbc"],
        ["report", ANNOTATED, "-o", "{file}/report"],
        ["import-slocum", "{slocum}/good.mi", "-o", "{file}/good.mission"],
    ], ExitCode.USAGE, "cannot write"),
    ("a battery no number can hold", [
        ["plan", FIG2, "--battery", "1e400Wh"], ["plan", FIG2, "--battery", "1e305kWh"],
        ["compare-sbc", FIG2, "--battery", "1e400Wh"],
    ], ExitCode.USAGE, "must be positive and finite"),
    ("no scenario to fly", [
        ["montecarlo", FIG2, "--scenarios", "0", "-o", "out"],
        ["plan", ANNOTATED, "--confidence", "0.9", "--scenarios", "0"],
        ["plan", ANNOTATED, "--occupancy-from-sim", "--scenarios", "0"],
    ], ExitCode.USAGE, "--scenarios 0: must be between 1 and 1,000,000"),
    ("fewer than one worker", [  # plan once flew its scenarios in this process instead
        ["montecarlo", FIG2, "--scenarios", "2", "--workers", "0", "-o", "out"],
        ["plan", ANNOTATED, "--confidence", "0.9", "--workers", "0"],
        ["plan", ANNOTATED, "--occupancy-from-sim", "--scenarios", "2", "--workers", "0"],
    ], ExitCode.USAGE, "--workers 0: must be at least 1"),
    ("a scheduler address Dask cannot read", [  # once an internal error, exit 70
        ["montecarlo", FIG2, "--scenarios", "2", "--scheduler", "nowhere", "-o", "out"],
    ], ExitCode.USAGE, "--scheduler nowhere: expected local or tcp://HOST:PORT"),
    ("a yo deeper than the vehicle's rating", [  # once an internal error
        ["plan", "{deep}"], ["compare-sbc", "{deep}"], ["report", "{deep}", "-o", "out"],
        ["sim", "{deep}", "-o", "out"],  # the simulated glider once sank to 501 m, exit 0
        ["montecarlo", "{deep}", "--scenarios", "2", "-o", "out"],
    ], ExitCode.BAD_INPUT, "max depth 500 m is beyond the vehicle's rated 100 m"),
    ("a yo deeper than the vehicle can climb back from", [  # once an internal error
        ["power", "energy", "--max-depth", "500"],
        ["power", "speed", "--hotel-w", "1", "--max-depth", "500"],
    ], ExitCode.BAD_INPUT, "the glider cannot climb below "),
    ("a pitch the calibrated glider would fly below 0", [  # its dive error is -2.2 deg
        ["plan", "{flat}"], ["compare-sbc", "{flat}"], ["sim", "{flat}", "-o", "out"],
        ["montecarlo", "{flat}", "--scenarios", "2", "-o", "out"],
        ["power", "energy", "--pitch-deg", "1"],
    ], ExitCode.BAD_INPUT, "a glide's pitch must lie strictly between 0 and pi/2 rad"),
    ("a negative seed", [
        ["sim", FIG2, "--seed", "-1", "-o", "out"],
        ["montecarlo", FIG2, "--scenarios", "2", "--seed", "-1", "-o", "out"],
        ["plan", ANNOTATED, "--confidence", "0.9", "--seed", "-1"],
    ], ExitCode.USAGE, "--seed: expected an integer >= 0, got '-1'"),
]


def exit_code(argv: list[str]) -> int:
    """What `gliderplan ARGV` exits with (argparse's own errors exit through SystemExit)."""
    try:
        return main(argv)
    except SystemExit as stop:
        return int(stop.code)


@pytest.mark.parametrize("argvs, code, message", [case[1:] for case in CASES],
                         ids=[case[0] for case in CASES])
def test_one_error_exits_alike_in_every_command(tmp_path, monkeypatch, capsys, argvs, code,
                                                message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.mission").write_text("mission m\nstate s begin\n")
    (tmp_path / "broken.plan").write_text("GPPLAN 1\nmission sampleMission\n")
    (tmp_path / "file").write_text("a file, not a directory\n")
    (tmp_path / "big.mission").write_text("mission big\n" + "".join(
        f"state s{i}\nbegin\n  flightprofile yo(5, 20, .454, .454)\n  sensors missiontime\n"
        f"  events\n    case missiontime >= {10 * i + 10} {'exit' if i == 1999 else 'goto '}"
        f"{'' if i == 1999 else f's{i + 1}'}\nend\n" for i in range(2000)))
    annotated = Path(ANNOTATED).read_text()
    (tmp_path / "device_vehicle.mission").write_text(
        annotated.replace("vehicle slocum_g2_shallow", 'vehicle "/dev/zero"'))
    (tmp_path / "deep.mission").write_text(  # the 100 m shallow glider, yo to 500 m
        annotated.replace("yo(5, 20,", "yo(5, 500,").replace("yo(5.0, 10,", "yo(5, 500,"))
    (tmp_path / "flat.mission").write_text(annotated.replace(".454", ".02"))
    (tmp_path / "device_computer.mission").write_text(
        annotated.replace("computer ts7800 @ 300 MHz", 'computer "/dev/zero"'))
    with open(tmp_path / "huge.toml", "wb") as huge:  # sparse: no disk space taken
        huge.truncate(MAX_INPUT_BYTES + 1)
    (tmp_path / "slocum" / "mafiles").mkdir(parents=True)
    for name, text in SLOCUM_MISSIONS.items():
        (tmp_path / "slocum" / name).write_text(text)
    for argv in argvs:
        argv = [a.format(bad="bad.mission", broken="broken.plan", file="file",
                         huge="huge.toml", slocum="slocum", big="big.mission",
                         device_vehicle="device_vehicle.mission",
                         device_computer="device_computer.mission", deep="deep.mission",
                         flat="flat.mission")
                for a in argv]
        assert exit_code(argv) == code, argv
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, (argv, err)
        assert err.count(f"gliderplan {argv[0]}: error: ") <= 1, err  # said once
        assert not (tmp_path / "out").exists()  # nothing written


def gliderplan(*args: str, **popen) -> subprocess.Popen:
    """`gliderplan ARGS` as a user runs it: its own process, this interpreter's package."""
    return subprocess.Popen([sys.executable, "-m", "gliderplan.cli", *args],
                            stderr=subprocess.PIPE, text=True, **popen)


@pytest.mark.parametrize("argv", [["check", "--json", ANNOTATED], ["fmt", ANNOTATED],
                                  ["power", "list"]], ids=lambda argv: argv[0])
def test_a_reader_that_went_away_stops_the_command_quietly(argv):
    """`gliderplan check --json M | head -0`: no message, the exit status of a process that
    SIGPIPE ended, as `cat` gives."""
    process = gliderplan(*argv, stdout=subprocess.PIPE)
    process.stdout.close()  # before the command writes a byte
    _, err = process.communicate(timeout=120)
    assert process.returncode == ExitCode.BROKEN_PIPE == 128 + signal.SIGPIPE
    assert err == ""


def test_a_named_pipe_in_a_mission_is_refused_at_once(tmp_path):
    """A pipe with no writer would block a reader for good: refused before it is read."""
    os.mkfifo(tmp_path / "pipe.toml")
    mission = tmp_path / "m.mission"
    mission.write_text(Path(ANNOTATED).read_text().replace(
        "vehicle slocum_g2_shallow", 'vehicle "pipe.toml"'))
    for argv in (["plan", str(mission)], ["power", "show", "board", "pipe.toml"],
                 ["check", "pipe.toml"], ["sim", FIG2, "--ocean", "pipe.toml", "-o", "out"],
                 ["plan", FIG2, "--sign", "pipe.toml"], ["import-slocum", "pipe.toml", "-o", "o"]):
        process = gliderplan(*argv, cwd=tmp_path, stdout=subprocess.DEVNULL)
        _, err = process.communicate(timeout=120)
        err = err.replace(f"{tmp_path}/", "")  # the mission's files are found beside it
        assert process.returncode == ExitCode.USAGE, (argv, err)
        assert err.startswith(f"gliderplan {argv[0]}: error: pipe.toml: "), err
        assert "not a regular file" in err, err
        assert len(err.strip().splitlines()) == 1, err


def test_a_named_pipe_in_a_run_directory_is_refused_at_once(tmp_path):
    """The run's tables are read whole by pyarrow, past the input limit, but never from a
    pipe."""
    run = tmp_path / "run"
    assert main(["sim", ANNOTATED, "--duration", "60s", "-o", str(run)]) == 0
    (run / "timeseries.parquet").unlink()
    os.mkfifo(run / "timeseries.parquet")
    process = gliderplan("report", ANNOTATED, "--run", str(run), "-o", str(tmp_path / "out"),
                         stdout=subprocess.DEVNULL)
    _, err = process.communicate(timeout=120)
    assert process.returncode == ExitCode.USAGE, err
    assert err == (f"gliderplan report: error: {run}/timeseries.parquet: is not a regular file "
                   "(a device, pipe or socket), not a run's time series\n")


def test_every_command_is_a_documented_call_that_a_test_calls():
    """README.md's Python block names, for every command, the call it is a shell over
    (`from MODULE import NAME  # COMMAND`); each such call exists and a test other than
    the command-line ones calls it directly."""
    import importlib
    import re

    from gliderplan.cli.main import subcommands

    root = Path(__file__).resolve().parents[1]
    readme = (root / "README.md").read_text()
    block = readme[readme.index("```python\n"):]
    block = block[:block.index("\n```\n")]
    documented = {}
    for module, names, commands in re.findall(r"^from (\S+) import ([\w, ]+?)\s*# (.+)$",
                                              block, re.M):
        for command in re.findall(r"[a-z][a-z-]*", commands):
            documented.setdefault(command, []).extend(
                (module, n.strip()) for n in names.split(","))
    tests = [p.read_text() for p in (root / "tests").glob("test_*.py")
             if p.name not in ("test_cli_exit_codes.py", "test_check_cli.py")]
    for command in subcommands():
        assert command in documented, f"README.md documents no call for `{command}`"
        for module, name in documented[command]:
            assert hasattr(importlib.import_module(module), name), (command, module, name)
            assert any(re.search(rf"\b{name}\b", t) for t in tests), (
                f"no test calls {module}.{name} (`gliderplan {command}`) directly")
