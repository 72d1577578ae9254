"""Single-board computers (SBCs) that run the mission: power per clock, boot cost, throughput.

A board draws `idle_w` when it has nothing to do and `active_w` while busy; a workload
of `cycles_per_tick` x `ticks_per_s` keeps it busy a fraction of the time, so its mean
power is idle + (active - idle) x busy. Table I of Woithe & Kremer gives the active
powers; the other figures and their basis are in the data files.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gliderplan.power_models.catalog import is_path_spec, resolve
from gliderplan.power_models.datafile import read_model_file
from gliderplan.power_models.errors import ModelFileError


@dataclass(frozen=True)
class ClockMode:
    """The figures of a board at one clock."""

    clock_mhz: float
    active_w: float
    idle_w: float


@dataclass(frozen=True)
class Board:
    """A board at one clock. Powers [W], times [s], energies [J], throughput [cycles s-1]."""

    name: str
    description: str
    clock_mhz: float
    active_w: float
    idle_w: float
    sleep_w: float
    boot_s: float
    boot_j: float
    cycles_per_s: float
    cycles_per_clock: float
    clock_modes: tuple[ClockMode, ...]
    boot_j_given: bool  # True: boot energy from the file; False: boot_s x active_w

    def modes(self) -> list[Board]:
        """This board at each of its available clocks, slowest first."""
        return [self.at_clock(m.clock_mhz) for m in self.clock_modes]

    def at_clock(self, clock_mhz: float) -> Board:
        """This board at another of its clocks [MHz]; ValueError if it has no such clock."""
        for mode in self.clock_modes:
            if abs(mode.clock_mhz - clock_mhz) < 1e-6:
                return replace(
                    self,
                    clock_mhz=mode.clock_mhz,
                    active_w=mode.active_w,
                    idle_w=mode.idle_w,
                    boot_j=self.boot_j if self.boot_j_given else self.boot_s * mode.active_w,
                    cycles_per_s=mode.clock_mhz * 1e6 * self.cycles_per_clock,
                )
        clocks = ", ".join(f"{m.clock_mhz:g}" for m in self.clock_modes)
        raise ValueError(
            f"board {self.name!r} has no {clock_mhz:g} MHz clock (available: {clocks})"
        )

    def busy_fraction(
        self, cycles_per_tick: np.ndarray | float, ticks_per_s: np.ndarray | float
    ) -> np.ndarray:
        """Fraction of time [1] the workload keeps the CPU busy; above 1 it cannot keep up."""
        return (
            np.asarray(cycles_per_tick, float) * np.asarray(ticks_per_s, float) / self.cycles_per_s
        )

    def power_w(self, busy_fraction: np.ndarray | float) -> np.ndarray:
        """Mean electrical power [W] at a busy fraction in [0, 1] (clipped)."""
        busy = np.clip(np.asarray(busy_fraction, float), 0.0, 1.0)
        return self.idle_w + (self.active_w - self.idle_w) * busy


_SPEC = re.compile(
    r"^\s*(?P<name>[^@]+?)\s*(?:@\s*(?P<clock>[0-9]+(?:\.[0-9]+)?)\s*(?:MHz)?)?\s*$", re.I
)


def board_spec(spec: str) -> tuple[Path, float | None]:
    """The file and the clock [MHz] (None: not given) of a spec such as "ts7800@500",
    "ts7800 @ 500 MHz", "ts5500" or "boards/mine.toml"."""
    if is_path_spec(spec):
        return resolve("board", spec), None
    match = _SPEC.match(spec)
    if match is None:
        raise ModelFileError(spec, None, "expected NAME, NAME@CLOCK_MHZ or a path to a .toml file",
                             usage=True)
    clock = float(match["clock"]) if match["clock"] else None
    return resolve("board", match["name"]), clock


def load_board(spec: str, clock_mhz: float | None = None) -> Board:
    """Load a board: a preset name, "ts7800@500" (clock in MHz) or a path to a .toml file.

    `clock_mhz` overrides a clock in the spec; without either the board runs at its file's
    `default_clock`. Raises ModelFileError (naming the file and key) for a bad file, an
    unknown preset or an unavailable clock.
    """
    path, spec_clock = board_spec(spec)
    board = read_board_file(path)
    wanted = clock_mhz if clock_mhz is not None else spec_clock
    if wanted is None:
        return board
    try:
        return board.at_clock(wanted)
    except ValueError as err:
        raise ModelFileError(str(path), "mode", str(err), usage=True) from None


def read_board_file(path: Path) -> Board:
    """Parse and validate a board data file."""
    top = read_model_file(path, "board")
    modes = []
    for table in top.tables("mode"):
        clock = table.quantity("clock", "clock", positive=True)
        active = table.quantity("active_power", "power", positive=True)
        idle = table.quantity("idle_power", "power")
        if idle > active:
            raise table.error("idle_power", "must not exceed active_power")
        table.finish()
        modes.append(ClockMode(clock, active, idle))
    modes.sort(key=lambda m: m.clock_mhz)
    default_clock = top.quantity("default_clock", "clock", modes[0].clock_mhz, positive=True)
    boot_s = top.quantity("boot_time", "time")
    boot_given = top.has("boot_energy")
    template = Board(
        name=top.text("name"),
        description=top.text("description", ""),
        clock_mhz=modes[0].clock_mhz,
        active_w=modes[0].active_w,
        idle_w=modes[0].idle_w,
        sleep_w=top.quantity("sleep_power", "power"),
        boot_s=boot_s,
        boot_j=top.quantity("boot_energy", "energy", 0.0),
        cycles_per_s=0.0,
        cycles_per_clock=top.quantity("cycles_per_clock", "cycles_per_clock", 1.0, positive=True),
        clock_modes=tuple(modes),
        boot_j_given=boot_given,
    )
    top.finish()
    try:
        return template.at_clock(default_clock)
    except ValueError as err:
        raise top.error("default_clock", str(err)) from None
