"""Which presets exist and where a model spec points: cheap, no numpy.

Presets are the files `data/<kind>_<name>.toml` shipped with the package. A spec is a
preset name (`ts7800`) or a path to the user's own `.toml` file. The language checker
calls `preset_names` to validate `vehicle NAME` / `computer NAME` annotations, so this
module only lists files.
"""

from __future__ import annotations

import difflib
from pathlib import Path

from gliderplan.power_models.errors import ModelFileError

KINDS = ("board", "sensor", "vehicle", "battery")
DATA_DIR = Path(__file__).resolve().parent / "data"


def _check_kind(kind: str) -> None:
    if kind not in KINDS:
        raise ValueError(f"unknown model kind {kind!r}; expected one of {', '.join(KINDS)}")


def preset_names(kind: str) -> list[str]:
    """Names of the shipped presets of `kind` ("board", "sensor", "vehicle", "battery")."""
    _check_kind(kind)
    prefix = f"{kind}_"
    return sorted(p.stem[len(prefix) :] for p in DATA_DIR.glob(f"{prefix}*.toml"))


def preset_path(kind: str, name: str) -> Path:
    """The data file of a shipped preset (it may not exist; see `resolve`)."""
    _check_kind(kind)
    return DATA_DIR / f"{kind}_{name}.toml"


def is_path_spec(spec: str) -> bool:
    """True if `spec` names a file rather than a preset."""
    return spec.endswith(".toml") or "/" in spec or "\\" in spec


def resolve(kind: str, spec: str) -> Path:
    """The file a spec refers to: a preset name or a path to a user's `.toml` file."""
    if is_path_spec(spec):
        return Path(spec)
    names = preset_names(kind)
    if spec not in names:
        close = difflib.get_close_matches(spec, names, n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ModelFileError(
            spec,
            None,
            f"unknown {kind} preset (presets: {', '.join(names)}; "
            f"or give a path to a .toml file){hint}",
            usage=True,
        )
    return preset_path(kind, spec)
