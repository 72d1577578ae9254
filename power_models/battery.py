"""Battery packs: stored energy, the fraction a mission may use, and unit conversions.

A pack file gives either its energy (`energy`, in J, kJ, MJ, Wh or kWh) or its charge
capacity at a nominal voltage (`capacity` in Ah or mAh, and `voltage` in V).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gliderplan.contract.units import C_PER_AH, J_PER_WH, UNITS
from gliderplan.power_models.catalog import resolve
from gliderplan.power_models.datafile import read_model_file


def j_to_wh(joules: float) -> float:
    """Joules to watt-hours."""
    return joules / J_PER_WH


def j_to_ah(joules: float, volts: float) -> float:
    """Energy [J] to the charge [Ah] it takes at `volts` [V]."""
    return joules / volts / C_PER_AH


def energy_to_j(value: float, unit: str, volts: float | None = None) -> float:
    """An energy or a charge in any accepted unit (J, kJ, MJ, Wh, kWh; Ah, mAh at `volts`)."""
    if unit in UNITS["energy"]:
        return value * UNITS["energy"][unit]
    if unit in UNITS["charge"]:
        if volts is None or volts <= 0.0:
            raise ValueError(f"a charge in {unit} needs a positive voltage to become energy")
        return value * UNITS["charge"][unit] * volts  # C x V = J
    accepted = ", ".join([*UNITS["energy"], *UNITS["charge"]])
    raise ValueError(f"unit {unit!r} is not an energy or a charge (use one of {accepted})")


def usable_budget_j(energy_j: float, reserve_fraction: float) -> float:
    """The energy [J] a plan may spend of a pack of `energy_j` [J] that keeps
    `reserve_fraction` [1] unused: (1 - reserve) x energy. The one definition: the planner's
    budget, the limit `check` proves a plan against, a run without a plan."""
    return (1.0 - reserve_fraction) * energy_j


def drawn_budget_j(budget_j: float, usable_share: float) -> float:
    """A plan's budget [J] when the pack holds `usable_share` [1] of its rating (a drawn
    Monte Carlo scenario, the truth a replanning shore does not know): budget x share."""
    return budget_j * usable_share


@dataclass(frozen=True)
class Battery:
    """A battery pack. Energy [J], voltage [V], usable fraction [1]."""

    name: str
    description: str
    energy_j: float
    usable_fraction: float
    voltage_v: float

    @property
    def usable_j(self) -> float:
        """Energy [J] a mission may draw before the pack is considered empty."""
        return self.energy_j * self.usable_fraction

    @property
    def energy_wh(self) -> float:
        return j_to_wh(self.energy_j)

    @property
    def capacity_ah(self) -> float:
        """Charge [Ah] at the nominal voltage."""
        return j_to_ah(self.energy_j, self.voltage_v)


def load_battery(spec: str) -> Battery:
    """Load a pack: a preset name (`alkaline`, ...) or a path to a .toml file."""
    return read_battery_file(resolve("battery", spec))


def read_battery_file(path: Path) -> Battery:
    """Parse and validate a battery data file."""
    top = read_model_file(path, "battery")
    volts = top.quantity("voltage", "voltage", positive=True)
    if top.has("energy") == top.has("capacity"):
        raise top.error("energy", "give exactly one of 'energy' and 'capacity'")
    if top.has("energy"):
        energy = top.quantity("energy", "energy", positive=True)
    else:
        energy = top.quantity("capacity", "charge", positive=True) * volts  # C x V = J
    battery = Battery(
        name=top.text("name"),
        description=top.text("description", ""),
        energy_j=energy,
        usable_fraction=top.quantity("usable_fraction", "fraction", maximum=1.0, positive=True),
        voltage_v=volts,
    )
    top.finish()
    return battery
