"""The units gliderplan reads, grouped by dimension, with their factor to the code's unit.

One table for every reader: a model data file, a command-line option and a mission's
annotations (through `language.units`) mean the same by each unit. The code works in SI,
except cc for pumped volume and MHz for clocks, the units pilots use. Every number in a
data file carries its unit; the loader converts it and refuses a unit of the wrong
dimension, so "240 mW" and "0.24 W" both load and "240 mAh" for a power is an error that
names the key.
"""

from __future__ import annotations

import math

# dimension -> {unit spelling: factor that turns a value in that unit into the code's unit}
UNITS: dict[str, dict[str, float]] = {
    "power": {"W": 1.0, "mW": 1e-3, "kW": 1e3},
    "energy": {"J": 1.0, "kJ": 1e3, "MJ": 1e6, "Wh": 3600.0, "kWh": 3.6e6},
    "time": {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0, "d": 86400.0},
    "frequency": {"Hz": 1.0, "1/s": 1.0, "1/min": 1.0 / 60.0},
    "clock": {"MHz": 1.0, "GHz": 1e3},
    "volume": {"cc": 1.0, "ml": 1.0, "l": 1e3, "m3": 1e6},
    "flow": {"cc/s": 1.0, "ml/s": 1.0},
    "length": {"m": 1.0, "km": 1e3},
    "speed": {"m/s": 1.0, "km/h": 1.0 / 3.6, "kn": 1852.0 / 3600.0},
    "rotation": {"rpm": 1.0},  # propeller revolutions per minute
    "angle": {"rad": 1.0, "deg": math.pi / 180.0},
    "angular_rate": {"rad/s": 1.0, "deg/s": math.pi / 180.0},
    "area": {"m2": 1.0},
    "mass": {"kg": 1.0, "g": 1e-3},
    "density": {"kg/m3": 1.0},
    "acceleration": {"m/s2": 1.0},
    "per_angle": {"1/rad": 1.0, "1/deg": 180.0 / math.pi},
    "compressibility": {"1/Pa": 1.0, "1/dbar": 1e-4},
    "pump_per_volume": {"J/cc": 1.0},
    "pump_per_volume_depth": {"J/(cc m)": 1.0},
    "voltage": {"V": 1.0},
    "charge": {"Ah": 3600.0, "mAh": 3.6},  # [C]
    "dimensionless": {"1": 1.0},
    "fraction": {"1": 1.0, "%": 0.01},
    "cycles_per_clock": {"cycles/clock": 1.0},
    "cycles": {"cycles": 1.0, "Mcycles": 1e6},
    "instructions": {"instructions": 1.0},
    "cycles_per_instruction": {"cycles/instruction": 1.0},
}


J_PER_WH = UNITS["energy"]["Wh"]
C_PER_AH = UNITS["charge"]["Ah"]


def to_model_unit(value: float, unit: str, dimension: str) -> float:
    """Convert `value` given in `unit` to the model's unit of `dimension`.

    Raises KeyError if `unit` does not belong to `dimension` (the caller names the key).
    """
    return value * UNITS[dimension][unit]


def accepted_units(dimension: str) -> str:
    """The units of a dimension, as a human-readable list for error messages."""
    return ", ".join(repr(u) for u in UNITS[dimension])


def finite_or_none(value: float) -> float | None:
    """`value`, or None (JSON's null) where it is NaN or infinite: JSON has no such number."""
    return value if math.isfinite(value) else None
