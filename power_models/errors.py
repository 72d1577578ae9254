"""The one error a model file can raise: it names the file and the key at fault."""

from __future__ import annotations

from gliderplan.contract.errors import GliderplanError


class ModelFileError(GliderplanError, ValueError):
    """A model data file (preset or the user's own) that cannot be used as it is; `usage`
    when the spec names nothing (no such file, preset or clock)."""

    def __init__(self, path: str, key: str | None, message: str, *, usage: bool = False) -> None:
        self.path = path
        self.key = key
        self.message = message
        where = f"{path}: {key}" if key else path
        super().__init__(f"{where}: {message}", usage=usage, file=path)
