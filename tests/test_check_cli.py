"""`gliderplan check` as a user runs it: exit codes and messages, never a traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

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
