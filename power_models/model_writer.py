"""Writing a model data file (the inverse of `datafile`).

Used by `gliderplan calibrate -o`: the base vehicle's file is re-written with the fitted
figures replaced, each with a source that says what it was fitted from.
"""

from __future__ import annotations

import json
from typing import Any


def _toml_value(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return format(float(value), ".6g") if isinstance(value, float) else str(value)
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a valid TOML basic string
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(v)}" for k, v in value.items()) + " }"
    if isinstance(value, list | tuple) and value and isinstance(value[0], list | tuple):
        return "[\n" + "".join(f"  {_toml_value(row)},\n" for row in value) + "]"
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    raise TypeError(f"cannot write {type(value).__name__} to a model file")


def _is_table(entry: dict[str, Any]) -> bool:
    """A [table] (holds figures or a matrix), not an inline one such as a figure."""
    return any(isinstance(v, dict) or (isinstance(v, list) and v and isinstance(v[0], list))
               for v in entry.values())


def to_toml(data: dict[str, Any], header: str = "") -> str:
    """TOML text of a model file: top-level keys, then [tables], a table of tables as
    [name.sub] (the device table: [devices.dvl])."""
    lines = [f"# {line}" for line in header.splitlines()]
    tables = {k: v for k, v in data.items() if isinstance(v, dict) and _is_table(v)}
    for key, value in data.items():
        if key not in tables:
            lines.append(f"{key} = {_toml_value(value)}")
    for name, table in tables.items():
        nested = all(isinstance(v, dict) and _is_table(v) for v in table.values())
        for sub_name, sub in (table.items() if nested else [(None, table)]):
            lines.append("")
            lines.append(f"[{name}.{sub_name}]" if nested else f"[{name}]")
            lines.extend(f"{k} = {_toml_value(v)}" for k, v in sub.items())
    return "\n".join(lines) + "\n"
