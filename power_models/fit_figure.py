"""One figure of a calibrated vehicle, with the evidence behind it (`vehicle_fit.py`, and
the modules that fit a part of it)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Figure:
    """One figure of the calibrated vehicle [model unit], keyed as in the data file."""

    key: str
    value: float
    fitted: bool  # False: the log cannot support it, kept from the base vehicle
    basis: str  # what it was fitted from, or why it was kept
    sd: float | None = None  # standard deviation [model unit]
    at_least: bool = False  # the log saw it cut short: the value is a lower bound
