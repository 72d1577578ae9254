"""Single-board computers (SBCs) that run the mission: power per clock, sleep, boot, throughput.

Every tick the runtime has `cycles_per_tick` of work: the board is active for
cycles / (clock x cycles per clock) seconds and then, until the next tick, either idles
(`idle_w`) or, if it can and the mission asks it to, sleeps (`sleep.power_w`) and pays
`sleep.wake_j` to wake for the next tick, which takes `sleep.wake_latency_s`. Powering
the board up for the mission costs `boot_j` once. Table I of Woithe & Kremer gives the
active powers; the other figures and their basis (most are assumptions) are in the data
files.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from gliderplan.contract import NO_BOARD, same_clock
from gliderplan.power_models.catalog import is_path_spec, resolve
from gliderplan.power_models.datafile import Table, read_model_file
from gliderplan.power_models.errors import ModelFileError

if TYPE_CHECKING:  # the methods that compute import numpy: `check` reads boards without it
    import numpy as np


@dataclass(frozen=True)
class ClockMode:
    """The figures of a board at one clock."""

    clock_mhz: float
    active_w: float
    idle_w: float
    wake_j: float = 0.0  # energy of a wake-up from sleep at this clock [J]


@dataclass(frozen=True)
class SleepMode:
    """Suspend between ticks: the board's draw while asleep, what waking costs, what wakes
    it ("serial": a byte on the science computer's line; "timer": its real-time clock)."""

    power_w: float
    wake_latency_s: float
    wake_j: float
    wakes_on: tuple[str, ...]


WAKE_SOURCES = ("serial", "timer")


@dataclass(frozen=True)
class TickEnergy:
    """Energy [J] of the board over one tick, by what it does: run the tick's work, idle or
    sleep until the next tick, wake up. NaN throughout where it cannot keep up."""

    active_j: np.ndarray
    idle_j: np.ndarray
    sleep_j: np.ndarray
    wake_j: np.ndarray

    @property
    def total_j(self) -> np.ndarray:
        return self.active_j + self.idle_j + self.sleep_j + self.wake_j


@dataclass(frozen=True)
class Board:
    """A board at one clock. Powers [W], times [s], energies [J], throughput [cycles s-1]."""

    name: str
    description: str
    clock_mhz: float
    active_w: float
    idle_w: float
    sleep: SleepMode | None  # None: the board cannot sleep between ticks
    boot_s: float
    boot_j: float
    cycles_per_s: float
    cycles_per_clock: float
    clock_modes: tuple[ClockMode, ...]
    boot_j_given: bool  # True: boot energy from the file; False: boot_s x active_w
    path: Path | None = field(default=None, compare=False)  # its data file: the sources
    # The runtime's own code every tick, measured on this board's build [instructions],
    # and the cycles an instruction takes on its CPU; None: not measured on this board.
    runtime_instructions: float | None = None
    cycles_per_instruction: float | None = None

    @property
    def is_none(self) -> bool:
        """Whether this is `computer none` (`NoBoard`): no board at all."""
        return False

    @property
    def runtime_code_cycles(self) -> float | None:
        """Cycles [cycles] of the runtime's own code every tick, from its measured
        instructions; None where they are not measured. The kernel's system calls and
        interrupts around it are not in it."""
        if self.runtime_instructions is None or self.cycles_per_instruction is None:
            return None
        return self.runtime_instructions * self.cycles_per_instruction

    def modes(self) -> list[Board]:
        """This board at each of its available clocks, slowest first."""
        return [self.at_clock(m.clock_mhz) for m in self.clock_modes]

    def clocks_text(self) -> str:
        """The board's clocks as people read them: "300, 500"."""
        return ", ".join(f"{m.clock_mhz:g}" for m in self.clock_modes)

    def has_clock(self, clock_mhz: float) -> bool:
        """Whether the board's data file has a mode at `clock_mhz` [MHz] (`same_clock`, as
        the plan readers test a plan's clocks against the same file's)."""
        return self._mode(clock_mhz) is not None

    def _mode(self, clock_mhz: float) -> ClockMode | None:
        return next((m for m in self.clock_modes if same_clock(clock_mhz, m.clock_mhz)), None)

    def at_clock(self, clock_mhz: float) -> Board:
        """This board at another of its clocks [MHz]; ValueError if it has no such clock."""
        mode = self._mode(clock_mhz)
        if mode is None:
            raise ValueError(f"board {self.name!r} has no {clock_mhz:g} MHz clock "
                             f"(available: {self.clocks_text()})")
        sleep = replace(self.sleep, wake_j=mode.wake_j) if self.sleep else None
        return replace(
            self,
            clock_mhz=mode.clock_mhz,
            active_w=mode.active_w,
            idle_w=mode.idle_w,
            sleep=sleep,
            boot_j=self.boot_j if self.boot_j_given else self.boot_s * mode.active_w,
            cycles_per_s=mode.clock_mhz * 1e6 * self.cycles_per_clock,
        )

    def busy_fraction(
        self, cycles_per_tick: np.ndarray | float, ticks_per_s: np.ndarray | float
    ) -> np.ndarray:
        """Fraction of time [1] the workload keeps the CPU busy; above 1 it cannot keep up."""
        import numpy as np

        return (
            np.asarray(cycles_per_tick, float) * np.asarray(ticks_per_s, float) / self.cycles_per_s
        )

    def power_w(self, busy_fraction: np.ndarray | float) -> np.ndarray:
        """Mean electrical power [W] at a busy fraction in [0, 1] (clipped), idling when
        not busy."""
        import numpy as np

        busy = np.clip(np.asarray(busy_fraction, float), 0.0, 1.0)
        return self.idle_w + (self.active_w - self.idle_w) * busy

    def can_sleep(self, cycles_per_tick: np.ndarray | float, tick_s: float) -> np.ndarray:
        """Whether the board can sleep between ticks of this work: it has a sleep mode and
        the work and the wake-up fit in the tick."""
        import numpy as np

        if self.sleep is None:
            return np.zeros(np.shape(cycles_per_tick), bool)
        busy_s = np.asarray(cycles_per_tick, float) / self.cycles_per_s
        return busy_s + self.sleep.wake_latency_s <= tick_s

    def tick_energy(self, cycles_per_tick: np.ndarray | float, tick_s: float,
                    sleep: bool = False) -> TickEnergy:
        """Energy [J] of one tick of `tick_s` [s] with `cycles_per_tick` [cycles] of work,
        idling between ticks, or sleeping where `sleep` is asked and `can_sleep`."""
        import numpy as np

        busy_s = np.asarray(cycles_per_tick, float) / self.cycles_per_s
        fits = busy_s <= tick_s
        asleep = self.can_sleep(cycles_per_tick, tick_s) & sleep
        rest_s = np.where(fits, tick_s - busy_s, np.nan)
        mode = self.sleep or SleepMode(0.0, 0.0, 0.0, ())
        nan = np.where(fits, 0.0, np.nan)
        return TickEnergy(
            active_j=np.where(fits, self.active_w * busy_s, np.nan),
            idle_j=np.where(asleep, 0.0, self.idle_w * rest_s) + nan,
            sleep_j=np.where(asleep, mode.power_w * (rest_s - mode.wake_latency_s), 0.0) + nan,
            wake_j=np.where(asleep, mode.wake_j, 0.0) + nan,
        )

    def mean_power_w(self, cycles_per_tick: np.ndarray | float, tick_s: float,
                     sleep: bool = False) -> np.ndarray:
        """Mean power [W] over ticks of this work (`tick_energy` per second); NaN where
        the board cannot keep up."""
        return self.tick_energy(cycles_per_tick, tick_s, sleep).total_j / tick_s


class NoBoard(Board):
    """`computer none`: no board beside the glider's own computers, whose power the
    vehicle's base (hotel) load already holds. It adds nothing to that load: 0 W busy or
    idle, no sleep, no boot. Its one clock, 0 MHz, is the plan file's "no clock to set";
    its throughput is unbounded, since no board of ours has to keep up with the work."""

    @property
    def is_none(self) -> bool:
        return True

    def at_clock(self, clock_mhz: float) -> Board:
        """Itself at its clock 0; ValueError for any other: it has no clock to set."""
        if not self.has_clock(clock_mhz):
            raise ValueError(f"computer {NO_BOARD} has no clock to set ({clock_mhz:g} MHz "
                             "asked): the glider's own computers run the mission")
        return self


NO_BOARD_MODEL = NoBoard(
    name=NO_BOARD, description="no extra board: the glider's own computers run the "
    "mission; their power is in the vehicle's base load",
    clock_mhz=0.0, active_w=0.0, idle_w=0.0, sleep=None, boot_s=0.0, boot_j=0.0,
    cycles_per_s=float("inf"), cycles_per_clock=float("inf"),
    clock_modes=(ClockMode(0.0, 0.0, 0.0),), boot_j_given=True)


_SPEC = re.compile(
    r"^\s*(?P<name>[^@]+?)\s*(?:@\s*(?P<clock>[0-9]+(?:\.[0-9]+)?)\s*(?:MHz)?)?\s*$", re.I
)


def board_spec(spec: str) -> tuple[Path | None, float | None]:
    """The file and the clock [MHz] (None: not given) of a spec such as "ts7800@500",
    "ts7800 @ 500 MHz", "ts5500" or "boards/mine.toml"; no file for "none"."""
    if is_path_spec(spec):
        return resolve("board", spec), None
    match = _SPEC.match(spec)
    if match is None:
        raise ModelFileError(spec, None, "expected NAME, NAME@CLOCK_MHZ or a path to a .toml file",
                             usage=True)
    clock = float(match["clock"]) if match["clock"] else None
    if match["name"] == NO_BOARD:
        return None, clock
    return resolve("board", match["name"]), clock


def load_board(spec: str, clock_mhz: float | None = None) -> Board:
    """Load a board: a preset name, "ts7800@500" (clock in MHz), a path to a .toml file,
    or "none" (`NO_BOARD_MODEL`).

    `clock_mhz` overrides a clock in the spec; without either the board runs at its file's
    `default_clock`. Raises ModelFileError (naming the file and key) for a bad file, an
    unknown preset or an unavailable clock.
    """
    path, spec_clock = board_spec(spec)
    board = NO_BOARD_MODEL if path is None else read_board_file(path)
    wanted = clock_mhz if clock_mhz is not None else spec_clock
    if wanted is None:
        return board
    try:
        return board.at_clock(wanted)
    except ValueError as err:
        raise ModelFileError(str(path or spec), "mode", str(err), usage=True) from None


def read_board_file(path: Path) -> Board:
    """Parse and validate a board data file."""
    top = read_model_file(path, "board")
    sleep = _sleep_mode(top)
    modes = []
    for table in top.tables("mode"):
        clock = table.quantity("clock", "clock", positive=True)
        active = table.quantity("active_power", "power", positive=True)
        idle = table.quantity("idle_power", "power")
        if idle > active:
            raise table.error("idle_power", "must not exceed active_power")
        if sleep is None and table.has("wake_energy"):
            raise table.error("wake_energy", "the board has no [sleep] table to wake from")
        # waking runs the CPU, so its energy is a figure of each clock
        wake = table.quantity("wake_energy", "energy") if sleep else 0.0
        table.finish()
        modes.append(ClockMode(clock, active, idle, wake))
    modes.sort(key=lambda m: m.clock_mhz)
    default_clock = top.quantity("default_clock", "clock", modes[0].clock_mhz, positive=True)
    boot_s = top.quantity("boot_time", "time")
    boot_given = top.has("boot_energy")
    instructions, cpi = _runtime_code(top)
    if top.text("name") == NO_BOARD:  # a plan file could not tell it from `computer none`
        raise top.error("name", f"'{NO_BOARD}' is taken: it means no board (`computer none`)")
    template = Board(
        name=top.text("name"),
        description=top.text("description", ""),
        clock_mhz=modes[0].clock_mhz,
        active_w=modes[0].active_w,
        idle_w=modes[0].idle_w,
        sleep=sleep,
        boot_s=boot_s,
        boot_j=top.quantity("boot_energy", "energy", 0.0),
        cycles_per_s=0.0,
        cycles_per_clock=top.quantity("cycles_per_clock", "cycles_per_clock", 1.0, positive=True),
        clock_modes=tuple(modes),
        boot_j_given=boot_given,
        path=path,
        runtime_instructions=instructions,
        cycles_per_instruction=cpi,
    )
    top.finish()
    try:
        return template.at_clock(default_clock)
    except ValueError as err:
        raise top.error("default_clock", str(err)) from None


def _runtime_code(top: Table) -> tuple[float | None, float | None]:
    """(`runtime_instructions`, `cycles_per_instruction`): both or neither, the count
    meaning nothing in cycles without what an instruction takes."""
    given = [top.has(k) for k in ("runtime_instructions", "cycles_per_instruction")]
    if given == [False, False]:
        return None, None
    if not all(given):
        missing = "cycles_per_instruction" if given[0] else "runtime_instructions"
        raise top.missing(missing, "runtime_instructions and cycles_per_instruction go "
                                   "together: the measured count and what an instruction "
                                   "costs in cycles on this board")
    return (top.quantity("runtime_instructions", "instructions", positive=True),
            top.quantity("cycles_per_instruction", "cycles_per_instruction", positive=True))


def _sleep_mode(top: Table) -> SleepMode | None:
    """The `[sleep]` table (power, wake_latency, wake_on; the energy of a wake-up is each
    mode's `wake_energy`), or None: a board without one cannot sleep between ticks."""
    if not top.has("sleep"):
        return None
    table = top.table("sleep")
    wakes_on = table.text_list("wake_on")
    unknown = [w for w in wakes_on if w not in WAKE_SOURCES]
    if unknown or not wakes_on:
        raise table.error("wake_on", f"expected some of {', '.join(WAKE_SOURCES)}, got "
                          f"{wakes_on!r}")
    table.text("source")
    mode = SleepMode(table.quantity("power", "power"), table.quantity("wake_latency", "time"),
                     0.0, tuple(wakes_on))
    table.finish()
    return mode
