"""Reference computations in CPU cycles (data/computations.toml), to read a workload in
cycles per tick as "two thermocline fits per tick"."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from pathlib import Path

from gliderplan.power_models.catalog import DATA_DIR
from gliderplan.power_models.datafile import read_model_file

COMPUTATIONS_FILE = DATA_DIR / "computations.toml"


@dataclass(frozen=True)
class Computation:
    name: str
    description: str
    cycles: float  # [cycles] of one run
    source: str


@cache
def load_computations(path: Path = COMPUTATIONS_FILE) -> tuple[Computation, ...]:
    """The computations of a computations file, in file order."""
    top = read_model_file(path, "computations")
    found = []
    for table in top.tables("computation"):
        cycles = table.quantity("cycles", "cycles", positive=True)
        found.append(Computation(table.text("name"), table.text("description"), cycles,
                                 table.data["cycles"]["source"]))
        table.finish()
    top.finish()
    return tuple(found)


def equivalents(cycles_per_tick: float) -> dict[str, float]:
    """How many runs of each reference computation per tick `cycles_per_tick` is."""
    return {c.name: cycles_per_tick / c.cycles for c in load_computations()}
