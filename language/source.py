"""Reading mission files safely: every way a file can be unreadable becomes a clear error."""

from __future__ import annotations

from pathlib import Path

from gliderplan.contract.errors import GliderplanError

MAX_MISSION_BYTES = 16 * 1024 * 1024  # far beyond any real mission; guards the parser


class SourceError(GliderplanError):
    """The file cannot be read as mission text; `usage` when the path itself is wrong."""


def read_mission(path: str | Path) -> str:
    """The text of a mission file (UTF-8), or SourceError."""
    path = Path(path)
    if not path.exists():
        raise SourceError(f"{path}: no such file", usage=True)
    if path.is_dir():
        raise SourceError(f"{path}: is a directory, not a mission file", usage=True)
    try:
        size = path.stat().st_size
        if size > MAX_MISSION_BYTES:
            raise SourceError(f"{path}: {size} bytes is too large for a mission "
                              f"(limit {MAX_MISSION_BYTES} bytes)")
        data = path.read_bytes()
    except OSError as err:
        raise SourceError(f"{path}: cannot read: {err.strerror}", usage=True) from None
    if b"\0" in data:
        raise SourceError(f"{path}: binary file (contains NUL bytes), not mission text",
                          usage=False)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as err:
        line = data[: err.start].count(b"\n") + 1
        raise SourceError(f"{path}:{line}: not UTF-8 text (byte 0x{data[err.start]:02x})",
                          usage=False) from None
