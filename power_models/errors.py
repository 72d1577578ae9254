"""The one error a model file can raise: it names the file and the key at fault."""

from __future__ import annotations


class ModelFileError(ValueError):
    """A model data file (preset or the user's own) that cannot be used as it is."""

    def __init__(self, path: str, key: str | None, message: str) -> None:
        self.path = path
        self.key = key
        self.message = message
        where = f"{path}: {key}" if key else path
        super().__init__(f"{where}: {message}")
