"""One error, one exit code, in every command that can meet it (README.md, "Exit codes"):
the library raises it with its code (`contract.errors`), `cli/main.py` alone prints it."""

from __future__ import annotations

from pathlib import Path

import pytest

from gliderplan.cli.main import main
from gliderplan.contract import ExitCode

FIG2 = str(Path(__file__).resolve().parents[1] / "examples" / "fig2.mission")

# (what is wrong, the commands that meet it, the exit code, what the message says)
# Paths are relative to the test's temporary directory; "{bad}" is a mission that does
# not parse, "{broken}" a plan file that breaks the format.
CASES = [
    ("missing mission file", [
        ["check", "none.mission"], ["fmt", "none.mission"], ["plan", "none.mission"],
        ["compile", "none.mission", "-o", "out"], ["sim", "none.mission", "-o", "out"],
        ["montecarlo", "none.mission", "--scenarios", "2", "-o", "out"],
        ["compare-sbc", "none.mission"],
    ], ExitCode.USAGE, "none.mission: no such file"),
    ("a directory for a mission", [
        ["check", "."], ["fmt", "."], ["plan", "."], ["compile", ".", "-o", "out"],
        ["sim", ".", "-o", "out"],
    ], ExitCode.USAGE, "is a directory"),
    ("a mission that does not parse", [
        ["check", "{bad}"], ["fmt", "{bad}"], ["plan", "{bad}"],
        ["compile", "{bad}", "-o", "out"], ["sim", "{bad}", "-o", "out"],
    ], ExitCode.BAD_INPUT, "bad.mission:2:"),
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
]


@pytest.mark.parametrize("argvs, code, message", [case[1:] for case in CASES],
                         ids=[case[0] for case in CASES])
def test_one_error_exits_alike_in_every_command(tmp_path, monkeypatch, capsys, argvs, code,
                                                message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.mission").write_text("mission m\nstate s begin\n")
    (tmp_path / "broken.plan").write_text("GPPLAN 1\nmission sampleMission\n")
    for argv in argvs:
        argv = [a.format(bad="bad.mission", broken="broken.plan") for a in argv]
        assert main(argv) == code, argv
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err, (argv, err)
        assert err.count(f"gliderplan {argv[0]}: error: ") <= 1, err  # said once
        assert not (tmp_path / "out").exists()  # nothing written
