"""Reading mission files: every way a file can be unreadable becomes one clear line
(`contract.files.read_input_text`, the reader of every file gliderplan reads)."""

from __future__ import annotations

from pathlib import Path

from gliderplan.contract.files import read_input_text


def read_mission(path: str | Path) -> str:
    """The text of a mission file (UTF-8), or InputFileError naming the file."""
    return read_input_text(path, "mission file")
