"""Each broken example gives exactly the diagnostics in its golden file.

The golden file examples/broken/NAME.expected holds the exact stderr of
`gliderplan check examples/broken/NAME.mission` run from the repository root.
After an intended change to a message, regenerate every golden file with

    GLIDERPLAN_UPDATE_GOLDEN=1 .venv/bin/python -m pytest tests/test_lang_golden.py

and review the diff before committing it.
"""

from __future__ import annotations

import difflib
import os
from pathlib import Path

import pytest

from gliderplan.cli.main import main

REPO = Path(__file__).resolve().parent.parent
BROKEN = REPO / "examples" / "broken"
MISSIONS = sorted(BROKEN.glob("*.mission"))
UPDATE = os.environ.get("GLIDERPLAN_UPDATE_GOLDEN") == "1"


def test_there_are_broken_examples_each_with_a_golden_file():
    assert len(MISSIONS) >= 5
    goldens = {p.stem for p in BROKEN.glob("*.expected")}
    assert goldens == {p.stem for p in MISSIONS}


@pytest.mark.parametrize("mission", MISSIONS, ids=lambda p: p.stem)
def test_golden_diagnostics(mission, monkeypatch, capsys):
    monkeypatch.chdir(REPO)
    code = main(["check", str(mission.relative_to(REPO))])
    stderr = capsys.readouterr().err
    golden = mission.with_suffix(".expected")
    if UPDATE:
        golden.write_text(stderr)
    expected = golden.read_text()
    diff = "".join(difflib.unified_diff(expected.splitlines(keepends=True),
                                        stderr.splitlines(keepends=True),
                                        f"{golden.name} (expected)", "gliderplan check (got)"))
    assert stderr == expected, f"diagnostics differ from the golden file:\n{diff}"
    assert code == (1 if "error:" in expected else 0)
    assert "Traceback" not in stderr


def test_warning_only_example_fails_under_strict(monkeypatch, capsys):
    monkeypatch.chdir(REPO)
    assert main(["check", "--strict", "examples/broken/dead_code.mission"]) == 1
    assert "warning:" in capsys.readouterr().err
