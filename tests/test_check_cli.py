"""`gliderplan check` as a user runs it: exit codes and messages, never a traceback."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import modules_loaded_by

from gliderplan.cli.main import main

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def test_fig2_checks_clean(capsys):
    assert main(["check", str(EXAMPLES / "fig2.mission")]) == 0
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    ("content", "expected_code", "message"),
    [
        (None, 2, "no such file"),
        (b"", 1, "the file is empty"),
        (b"mission \xff\n", 1, "not UTF-8"),
        (b"\x7fELF\x00\x01", 1, "binary file"),
    ],
)
def test_unreadable_input_is_a_clear_error(tmp_path, capsys, content, expected_code, message):
    path = tmp_path / "m.mission"
    if content is not None:
        path.write_bytes(content)
    assert main(["check", str(path)]) == expected_code
    err = capsys.readouterr().err
    assert message in err
    assert "Traceback" not in err


def test_directory_is_bad_usage(tmp_path, capsys):
    assert main(["check", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err


def test_console_script_runs_without_traceback(tmp_path):
    bad = tmp_path / "bad.mission"
    bad.write_text("mission m\nstate s begin flightprofile yo(5, 20, .454, .454)\n"
                   " events case depht > 3 exit\nend\n")
    proc = subprocess.run([sys.executable, "-m", "gliderplan.cli", "check", str(bad)],
                          capture_output=True, text=True)
    assert proc.returncode == 1
    assert f"{bad}:3:14: error: unknown sensor or variable 'depht'" in proc.stderr
    assert "did you mean 'depth'?" in proc.stderr
    assert "Traceback" not in proc.stderr


def _write(tmp_path: Path, text: str) -> str:
    path = tmp_path / "m.mission"
    path.write_text(text)
    return str(path)


_WARNS_ONLY = ("mission m\nstate s1 begin flightprofile surface sensors missiontime\n"
               " events case missiontime < 0 exit case missiontime > 9 exit end\n")
_HAS_ERROR = "mission m\nstate s1 begin flightprofile yo(5, 20, .454, 2) end\n"


@pytest.mark.parametrize(
    ("text", "flags", "expected_code"),
    [
        (_WARNS_ONLY, [], 0),
        (_WARNS_ONLY, ["--strict"], 1),
        (_HAS_ERROR, [], 1),
        (_HAS_ERROR, ["--strict"], 1),
        (_WARNS_ONLY, ["--max-stack", "0"], 2),
        (_WARNS_ONLY, ["--max-stack", "32"], 0),
        (_WARNS_ONLY, ["--max-stack", "33"], 2),
    ],
)
def test_exit_codes(tmp_path, capsys, text, flags, expected_code):
    assert main(["check", *flags, _write(tmp_path, text)]) == expected_code
    assert "Traceback" not in capsys.readouterr().err


def test_a_stack_the_runtime_cannot_hold_fails_the_check_at_its_line(tmp_path, capsys):
    path = _write(tmp_path, "mission m\nstack 40\n" + _WARNS_ONLY.split("\n", 1)[1])
    assert main(["check", path]) == 1
    assert f"{path}:2:7: error: stack depth must be a whole number from 1 to 32" \
        in capsys.readouterr().err


def test_strict_examples_are_clean(capsys):
    for path in sorted(EXAMPLES.glob("*.mission")):
        assert main(["check", "--strict", str(path)]) == 0, capsys.readouterr().err


def test_no_mission_argument_is_bad_usage():
    with pytest.raises(SystemExit) as exit_:
        main(["check"])
    assert exit_.value.code == 2


def test_one_bad_path_among_several_is_reported_and_fails(tmp_path, capsys):
    """A missing file exits 2 beside other files as it does alone (one exit code per kind
    of error, whatever the number of files)."""
    code = main(["check", str(EXAMPLES / "fig2.mission"), str(tmp_path / "none.mission")])
    assert code == 2
    assert "none.mission: no such file" in capsys.readouterr().err


def test_too_large_file_is_refused_before_reading(tmp_path, capsys):
    path = tmp_path / "huge.mission"
    with path.open("wb") as handle:
        handle.truncate(17 * 1024 * 1024)  # sparse: nothing is actually written
    assert main(["check", str(path)]) == 1
    assert "too large for a mission" in capsys.readouterr().err


@pytest.mark.parametrize("text", ["x" * 1_000_000, "mission m\n" + "state (\n" * 50_000,
                                  "mission m\n" + "(" * 100_000])
def test_large_garbage_gives_diagnostics_not_a_crash(tmp_path, capsys, text):
    assert main(["check", _write(tmp_path, text)]) == 1
    err = capsys.readouterr().err
    assert "error:" in err
    assert "internal error" not in err


def test_json_dump_of_the_checked_mission(capsys):
    assert main(["check", "--json", str(EXAMPLES / "fig2.mission")]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["ok"] and data["diagnostics"] == [] and data["exit_code"] == 0
    assert [s["name"] for s in data["mission"]["states"]] == ["s1", "s2", "s3"]
    assert len(data["mission"]["hash"]) == 64


def test_check_without_json_does_not_serialise_the_mission(monkeypatch, capsys):
    """The JSON form and its hash cost seconds on a large mission: only on request."""
    from gliderplan.language.ir import CheckedMission

    def refuse(self):
        raise AssertionError("to_json called without --json")

    monkeypatch.setattr(CheckedMission, "to_json", refuse)
    assert main(["check", str(EXAMPLES / "fig2.mission")]) == 0
    assert capsys.readouterr().out == ""


def test_check_imports_nothing_of_the_later_stages():
    """`check` runs the front end only: no runtime, planner or simulator, and none of the
    libraries they need; of the power models, only the vehicle file's reader (numpy-free),
    for the rating its profiles are held to."""
    code, loaded = modules_loaded_by(["check", str(EXAMPLES / "fig2.mission")])
    heavy = {"numpy", "pandas", "cvxpy", "scipy", "matplotlib", "clarabel"}
    stages = {"gliderplan.runtime", "gliderplan.planner", "gliderplan.sim"}
    assert (code, loaded & (heavy | stages)) == (0, set())


def test_help_lists_every_subcommand(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    for name in ("check", "fmt", "plan", "compile", "sim", "power", "calibrate"):
        assert f"    {name}" in out, out


def test_unknown_subcommand_is_bad_usage_naming_the_choices(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["chek", str(EXAMPLES / "fig2.mission")])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'chek'" in err and "'check'" in err
