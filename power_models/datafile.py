"""Reading model data files: TOML where every number is `{ value, unit, source }`.

A file looks like

    kind = "board"
    name = "ts5500"
    active_power = { value = 2.7, unit = "W", source = "Woithe & Kremer, Table I" }

The reader checks the kind, converts each number to the model's unit and rejects a
missing key, a unit of the wrong dimension, a missing source or a negative value with a
`ModelFileError` that names the file and the key (`ts5500.toml: active_power: ...`).
"""

from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gliderplan.contract.files import DataFileError, read_data
from gliderplan.contract.units import UNITS, accepted_units, to_model_unit
from gliderplan.power_models.errors import ModelFileError
from gliderplan.power_models.plausible import plausible


@dataclass(frozen=True)
class Table:
    """One TOML table of a model file, with where it came from for error messages."""

    path: str
    prefix: str  # dotted key of this table in the file ("" for the top level)
    data: dict[str, Any]
    used: set[str] = field(default_factory=set, compare=False)
    kind: str = ""  # the file's kind ("vehicle", "board", ...): its figures' plausible ranges

    def finish(self) -> None:
        """Refuse keys the model never read: most often a misspelt key."""
        for name in self.data:
            if name not in self.used:
                close = difflib.get_close_matches(name, sorted(self.used), n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise self.error(name, f"unknown key{hint}")

    def key(self, name: str) -> str:
        return f"{self.prefix}.{name}" if self.prefix else name

    def error(self, name: str | None, message: str) -> ModelFileError:
        return ModelFileError(self.path, self.key(name) if name else self.prefix or None, message)

    def missing(self, name: str, expected: str) -> ModelFileError:
        """The error for a required key that is absent, pointing at a likely misspelling."""
        close = difflib.get_close_matches(name, [k for k in self.data if k not in self.used], n=1)
        hint = f"; is {close[0]!r} a misspelling of it?" if close else ""
        return self.error(name, f"missing ({expected}){hint}")

    def has(self, name: str) -> bool:
        self.used.add(name)
        return name in self.data

    def text(self, name: str, default: str | None = None) -> str:
        """A string field; `default` None means required."""
        self.used.add(name)
        if name not in self.data:
            if default is None:
                raise self.missing(name, "a text value is required")
            return default
        value = self.data[name]
        if not isinstance(value, str) or not value.strip():
            raise self.error(name, f"expected a non-empty text value, got {value!r}")
        return value

    def quantity(
        self,
        name: str,
        dimension: str,
        default: float | None = None,
        *,
        minimum: float = 0.0,
        maximum: float = math.inf,
        positive: bool = False,
    ) -> float:
        """A number in the model's unit of `dimension`; `default` None means required.

        Values below `minimum` (0 unless told: powers, times and energies are never
        negative) or above `maximum` are refused; `positive` also refuses zero.
        """
        self.used.add(name)
        if name not in self.data:
            if default is None:
                raise self.missing(
                    name,
                    f"expected {{ value = ..., unit = ..., source = ... }} "
                    f"with a unit of {dimension}: {accepted_units(dimension)}",
                )
            return default
        entry = self.data[name]
        if not isinstance(entry, dict):
            raise self.error(
                name, f"expected {{ value = ..., unit = ..., source = ... }}, got {entry!r}"
            )
        unknown = set(entry) - {"value", "unit", "source", "note", "sd", "at_least"}
        if unknown:
            raise self.error(name, f"unknown field(s) {sorted(unknown)}")
        for part in ("value", "unit", "source"):
            if part not in entry:
                raise self.error(name, f"missing {part!r}")
        value, unit, source = entry["value"], entry["unit"], entry["source"]
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or not math.isfinite(value)
        ):
            raise self.error(name, f"value must be a finite number, got {value!r}")
        if not isinstance(source, str) or not source.strip():
            raise self.error(name, "source must say where the number comes from")
        if not isinstance(unit, str) or unit not in UNITS[dimension]:
            raise self.error(
                name,
                f"unit {unit!r} is not a unit of {dimension} "
                f"(use one of {accepted_units(dimension)})",
            )
        converted = to_model_unit(float(value), unit, dimension)
        if converted < minimum or (positive and converted <= 0.0):
            least = value_in(minimum, unit, dimension)
            bound = "> 0" if positive and minimum <= 0.0 else f">= {least:g}"
            raise self.error(name, f"must be {bound} {unit}, got {value} {unit}")
        if converted > maximum:
            most = value_in(maximum, unit, dimension)
            raise self.error(name, f"must be <= {most:g} {unit}, got {value} {unit}")
        if (bounds := plausible(self.kind, self.key(name))) is not None and \
                not bounds.low <= converted <= bounds.high:
            low, high = (value_in(x, unit, dimension) for x in (bounds.low, bounds.high))
            raise self.error(name, f"{value} {unit} lies outside the plausible {low:g} to "
                             f"{high:g} {unit} ({bounds.source})")
        return converted

    def quantities(self, name: str, dimension: str, *, positive: bool = False) -> list[float]:
        """A list of numbers in the model's unit of `dimension`, `{ values = [...], unit =
        ..., source = ... }` (a table's column, e.g. power against speed); each checked as
        `quantity` checks one (never negative; `positive` also refuses zero)."""
        self.used.add(name)
        entry = self.data.get(name)
        shape = "{ values = [...], unit = ..., source = ... }"
        if entry is None:
            raise self.missing(name, f"expected {shape} with a unit of {dimension}: "
                                     f"{accepted_units(dimension)}")
        if not isinstance(entry, dict) or not isinstance(entry.get("values"), list) \
                or not entry["values"]:
            raise self.error(name, f"expected {shape} with at least one value, got {entry!r}")
        unknown = set(entry) - {"values", "unit", "source", "note"}
        if unknown:
            raise self.error(name, f"unknown field(s) {sorted(unknown)}")
        return [Table(self.path, self.prefix, {name: {"value": v, **{
            k: entry.get(k) for k in ("unit", "source") if k in entry}}}).quantity(
                name, dimension, positive=positive) for v in entry["values"]]

    def sd(self, name: str, dimension: str) -> float | None:
        """The standard deviation [model unit] written next to a figure's value (`sd`, in the
        figure's own unit: calibration's bootstrap uncertainty), or None. Call after
        `quantity` has checked the entry."""
        entry = self.data.get(name)
        if not isinstance(entry, dict) or "sd" not in entry:
            return None
        spread = entry["sd"]
        if isinstance(spread, bool) or not isinstance(spread, int | float) or not (
            math.isfinite(spread) and spread >= 0.0
        ):
            raise self.error(name, f"sd must be a finite number >= 0, got {spread!r}")
        return abs(to_model_unit(float(spread), entry["unit"], dimension))

    def at_least(self, name: str) -> bool:
        """Whether a figure is marked `at_least = true`: its value is a lower bound (the log
        saw it cut short), so a draw from its sd never goes below it. Call after
        `quantity` has checked the entry."""
        entry = self.data.get(name)
        if not isinstance(entry, dict) or "at_least" not in entry:
            return False
        if not isinstance(entry["at_least"], bool):
            raise self.error(name, f"at_least must be true or false, got {entry['at_least']!r}")
        return entry["at_least"]

    def span(self, name: str, dimension: str) -> tuple[float, float] | None:
        """An optional range `{ low = ..., high = ..., unit = ..., source = ... }` in the
        model's unit of `dimension` (the published span of a figure, e.g. a device's
        power), or None when the file has none; low <= high, both finite and >= 0."""
        self.used.add(name)
        if name not in self.data:
            return None
        entry = self.data[name]
        shape = "{ low = ..., high = ..., unit = ..., source = ... }"
        if not isinstance(entry, dict):
            raise self.error(name, f"expected {shape}, got {entry!r}")
        unknown = set(entry) - {"low", "high", "unit", "source", "note"}
        missing = [p for p in ("low", "high", "unit", "source") if p not in entry]
        if unknown or missing:
            what = f"unknown field(s) {sorted(unknown)}" if unknown else f"missing {missing[0]!r}"
            raise self.error(name, f"{what}: expected {shape}")
        unit, source = entry["unit"], entry["source"]
        if not isinstance(source, str) or not source.strip():
            raise self.error(name, "source must say where the numbers come from")
        if not isinstance(unit, str) or unit not in UNITS[dimension]:
            raise self.error(name, f"unit {unit!r} is not a unit of {dimension} "
                                   f"(use one of {accepted_units(dimension)})")
        ends = []
        for part in ("low", "high"):
            value = entry[part]
            if isinstance(value, bool) or not isinstance(value, int | float) or not (
                    math.isfinite(value) and value >= 0):
                raise self.error(name, f"{part} must be a finite number >= 0, got {value!r}")
            ends.append(to_model_unit(float(value), unit, dimension))
        if ends[0] > ends[1]:
            raise self.error(name, f"low {entry['low']} {unit} is above high "
                                   f"{entry['high']} {unit}")
        return ends[0], ends[1]

    def text_list(self, name: str) -> list[str]:
        """A list of text values."""
        self.used.add(name)
        items = self.data.get(name)
        if not isinstance(items, list) or not all(isinstance(i, str) and i for i in items):
            raise self.error(name, f"expected a list of names, got {items!r}")
        return list(items)

    def tables(self, name: str) -> list[Table]:
        """An array of tables (`[[name]]`), at least one."""
        self.used.add(name)
        items = self.data.get(name)
        if not isinstance(items, list) or not items or not all(isinstance(i, dict) for i in items):
            raise self.error(name, f"expected at least one [[{self.key(name)}]] table")
        return [Table(self.path, f"{self.key(name)}[{i}]", item, kind=self.kind)
                for i, item in enumerate(items)]

    def table(self, name: str) -> Table:
        """A sub-table (`[name]`)."""
        self.used.add(name)
        item = self.data.get(name)
        if not isinstance(item, dict):
            raise self.error(name, f"expected a [{self.key(name)}] table")
        return Table(self.path, self.key(name), item, kind=self.kind)


def value_in(model_value: float, unit: str, dimension: str) -> float:
    """`model_value` expressed in `unit` (for messages that quote the user's unit)."""
    return round(model_value / UNITS[dimension][unit], 9)


def read_model_file(path: Path, kind: str) -> Table:
    """Parse a model file and check that it describes a `kind` ("board", "vehicle", ...)."""
    shown = str(path)
    try:
        top = Table(shown, "", read_data(path, f"{kind} file"), kind=kind)
    except DataFileError as err:  # the model's own error, naming the file and key
        raise ModelFileError(shown, err.key, err.problem) from None
    top.text("description", "")
    found = top.text("kind")
    if found != kind:
        raise top.error("kind", f"this file describes a {found!r}, expected a {kind!r}")
    top.text("name")
    return top


def file_entries(path: Path) -> list[tuple[str, float | list[float], str, str]]:
    """Every number of a model file as (dotted key, value, unit, source), as written (a
    table's column as its list of values).

    For display (`gliderplan power show`); call after the file has loaded, so its shape is
    known to be valid.
    """
    data = read_data(path, "model file")
    rows: list[tuple[str, float | list[float], str, str]] = []

    def walk(prefix: str, table: dict[str, Any]) -> None:
        for key, item in table.items():
            dotted = f"{prefix}.{key}" if prefix else key
            if isinstance(item, dict) and ("value" in item or "values" in item):
                rows.append((dotted, item.get("value", item.get("values")), item["unit"],
                             item["source"]))
            elif isinstance(item, dict):
                walk(dotted, item)
            elif isinstance(item, list):  # an array of tables (a list of names is no figure)
                for index, sub in enumerate(item):
                    if isinstance(sub, dict):
                        walk(f"{dotted}[{index}]", sub)

    walk("", data)
    return rows


def file_spans(path: Path) -> list[tuple[str, float, float, str, str]]:
    """Every top-level range of a model file (`Table.span`) as (key, low, high, unit,
    source), as written; call after the file has loaded."""
    data = read_data(path, "model file")
    return [(key, item["low"], item["high"], item["unit"], item["source"])
            for key, item in data.items()
            if isinstance(item, dict) and "low" in item and "high" in item]


def figure_sources(path: Path, key: str) -> tuple[str, ...]:
    """The sources a model file gives for the figure `key`, each once: the entry of that
    dotted key ("hotel_power", "flight.drag_cd0", "sleep.power"), or of that key in every
    `[[mode]]` table ("idle_power": one per clock)."""
    mode = re.compile(rf"mode\[\d+\]\.{re.escape(key)}")
    return tuple(dict.fromkeys(source for dotted, _, _, source in file_entries(path)
                               if dotted == key or mode.fullmatch(dotted)))


def is_assumption(source: str) -> bool:
    """Whether a figure's source says it rests on an assumption (no measurement or
    publication behind it, or behind a part of it): data files write "assumption: why",
    or name the assumed part ("43 mA; x 10 V (assumption: the bus voltage)")."""
    return "assumption" in source.lower()
