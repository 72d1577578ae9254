"""Units the annotations accept, normalised to SI, with hints for a wrong or missing unit."""

from __future__ import annotations

# dimension -> unit -> factor to SI (J, s, Hz, fraction, V, C)
UNITS: dict[str, dict[str, float]] = {
    "energy": {"J": 1.0, "kJ": 1e3, "MJ": 1e6, "Wh": 3600.0, "kWh": 3.6e6},
    "charge": {"Ah": 3600.0, "mAh": 3.6},
    "time": {"s": 1.0, "min": 60.0, "h": 3600.0, "d": 86400.0},
    "frequency": {"MHz": 1e6, "GHz": 1e9},
    "fraction": {"%": 0.01},
    "voltage": {"V": 1.0},
}


class UnitProblem(Exception):
    """A missing or wrong unit, with a hint that says what would be right."""

    def __init__(self, message: str, hint: str):
        super().__init__(message)
        self.message = message
        self.hint = hint


def to_si(value: float, unit: str | None, dimensions: tuple[str, ...]) -> tuple[float, str]:
    """(value in SI, dimension it matched), or raise UnitProblem naming what was expected."""
    accepted = {u: (factor, dim) for dim in dimensions for u, factor in UNITS[dim].items()}
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
    return " or ".join(dimensions)


def _number(value: float) -> str:
    return f"{value:g}"
