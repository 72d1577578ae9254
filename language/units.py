"""Units the annotations accept, normalised to the code's units, with hints for a wrong or
missing unit. The units and their factors are the contract's one table
(`gliderplan.contract.units`): a unit means the same in a mission as in a data file."""

from __future__ import annotations

import re

from gliderplan.contract.units import UNITS as _TABLE

_SPELLABLE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*|%")  # what the grammar reads after a number
# dimension -> unit -> factor to the code's unit (J, C, s, MHz, fraction, V), for the
# dimensions annotations use and the units a mission can spell
ANNOTATION_UNITS: dict[str, dict[str, float]] = {
    dimension: {u: f for u, f in _TABLE[dimension].items() if _SPELLABLE.fullmatch(u)}
    for dimension in ("energy", "charge", "time", "clock", "fraction", "voltage", "power",
                      "length", "angle")  # length and angle: the fleet file's (language/fleet.py)
}


class UnitProblem(Exception):
    """A missing or wrong unit, with a hint that says what would be right."""

    def __init__(self, message: str, hint: str):
        super().__init__(message)
        self.message = message
        self.hint = hint


def normalise(value: float, unit: str | None, dimensions: tuple[str, ...]) -> tuple[float, str]:
    """(value in the code's unit, dimension it matched), or raise UnitProblem naming what
    was expected."""
    accepted = {u: (factor, dim) for dim in dimensions
                for u, factor in ANNOTATION_UNITS[dim].items()}
    examples = ", ".join(accepted)
    if unit is None:
        first = next(iter(accepted))
        raise UnitProblem(
            f"missing unit: expected {_dimension_words(dimensions)}",
            f"write e.g. '{_number(value)} {first}' (units: {examples})",
        )
    if unit in accepted:
        factor, dimension = accepted[unit]
        return value * factor, dimension
    by_case = [u for u in accepted if u.lower() == unit.lower()]
    if by_case:
        hint = f"did you mean '{by_case[0]}'? (units are case-sensitive)"
    else:
        hint = f"use one of: {examples}"
    raise UnitProblem(f"'{unit}' is not a unit of {_dimension_words(dimensions)}", hint)


def _dimension_words(dimensions: tuple[str, ...]) -> str:
    return " or ".join("clock frequency" if d == "clock" else d for d in dimensions)


def _number(value: float) -> str:
    return f"{value:g}"
