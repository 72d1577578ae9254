"""Faults on the simulated serial line and in the runtime's board, for
`gliderplan sim --runtime c --faults SPEC` (docs/reliability.md).

SPEC is a comma-separated list of `name=value`:

  drop=P            each byte is lost with probability P
  flip=P            each bit is inverted with probability P
  dup=P             a frame arrives twice, with probability P
  reorder=P         a frame is held back and arrives after the next one
  truncate=P        a frame loses its tail (it still ends in its delimiter)
  burst=N@P         N consecutive bytes of a frame turn to noise, with probability P per frame
  delay=T@P         a frame arrives T late (wall time; the link re-sends after RETRANSMIT_MS):
                    with the first read or write on the line once it is due
  disconnect=T@AT   the line is cut for T of mission time from mission time AT (repeatable)
  kill=N[@T]        the runtime is killed (SIGKILL) N times at random moments of the run's
                    first T of mission time (default: the whole run: up to the mission's
                    end on its timeline, or --duration if sooner) and restarted from its
                    checkpoint; a run that ends sooner says how many it delivered

Frame faults hit both directions alike; every draw comes from one generator seeded from
the run's seed, so a faulted run is as deterministic as the line's timing allows (a
frame that waits on a retransmission timeout takes real time).
"""

from __future__ import annotations

import math
import os
import random
import re
import select
import time
from collections import Counter
from dataclasses import dataclass, field

from gliderplan.contract.errors import UsageError
from gliderplan.contract.units import UNITS

_NUMBER = r"([0-9]+(?:\.[0-9]*)?(?:[eE][-+]?[0-9]+)?)"
_TIME = re.compile(rf"{_NUMBER}([A-Za-z]+)\Z")
PROBABILITIES = ("drop", "flip", "dup", "reorder", "truncate")
MAX_KILLS = 10_000


@dataclass(frozen=True)
class FaultSpec:
    """What to inject; probabilities in [0, 1], times in seconds."""

    text: str = ""
    drop: float = 0.0  # per byte
    flip: float = 0.0  # per bit
    dup: float = 0.0  # per frame
    reorder: float = 0.0  # per frame
    truncate: float = 0.0  # per frame
    burst: float = 0.0  # per frame
    burst_bytes: int = 0
    delay: float = 0.0  # per frame
    delay_s: float = 0.0  # [s] wall time
    disconnects: tuple[tuple[float, float], ...] = ()  # (from [s], for [s]) mission time
    kills: int = 0
    kills_within_s: float | None = None  # [s] of mission time; None: the whole run

    @property
    def on_the_line(self) -> bool:
        """Faults that damage frames (the line needs the fault layer)."""
        return any((self.drop, self.flip, self.dup, self.reorder, self.truncate, self.burst,
                    self.delay))

    def link_down(self, time_s: float) -> bool:
        """Whether the line is cut at mission time `time_s` [s]."""
        return any(start <= time_s < start + length for start, length in self.disconnects)


def parse_faults(text: str) -> FaultSpec:
    """`--faults SPEC` -> FaultSpec; UsageError naming the part that is wrong."""
    values: dict = {"text": text}
    disconnects = []
    for part in text.split(","):
        name, _, value = part.strip().partition("=")
        where = f"--faults {part.strip()!r}"
        if name in PROBABILITIES:
            values[name] = _probability(value, where)
        elif name == "burst":
            count, probability = _pair(value, where, "N@P")
            if not count.isdigit() or not 1 <= int(count) <= 64:
                raise UsageError(f"{where}: N must be a whole number of bytes, 1..64")
            values["burst_bytes"], values["burst"] = int(count), _probability(probability, where)
        elif name == "delay":
            length, probability = _pair(value, where, "T@P")
            values["delay_s"], values["delay"] = _time(length, where), _probability(
                probability, where)
        elif name == "disconnect":
            length, start = _pair(value, where, "T@AT")
            disconnects.append((_time(start, where, zero=True), _time(length, where)))
        elif name == "kill":
            count, at, within = value.partition("@")
            if not count.isdigit() or not 1 <= int(count) <= MAX_KILLS:
                raise UsageError(f"{where}: kill=N[@T] takes a whole number N, 1..{MAX_KILLS}")
            values["kills"] = int(count)
            values["kills_within_s"] = _time(within, where) if at else None
        else:
            raise UsageError(f"{where}: unknown fault; expected {', '.join(PROBABILITIES)}, "
                             "burst=N@P, delay=T@P, disconnect=T@AT or kill=N[@T]")
    return FaultSpec(**values, disconnects=tuple(sorted(disconnects)))


def _pair(value: str, where: str, form: str) -> tuple[str, str]:
    first, at, second = value.partition("@")
    if not at:
        raise UsageError(f"{where}: expected {form}")
    return first, second


def _probability(text: str, where: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not 0.0 <= value <= 1.0:
        raise UsageError(f"{where}: {text!r} is not a probability in [0, 1]")
    return value


def _time(text: str, where: str, zero: bool = False) -> float:
    """'600s', '10min', '0.5s' -> seconds."""
    match = _TIME.match(text.strip())
    if match is None or match[2] not in UNITS["time"]:
        raise UsageError(f"{where}: {text!r} is not a time with a unit "
                         f"({', '.join(UNITS['time'])})")
    seconds = float(match[1]) * UNITS["time"][match[2]]
    if not math.isfinite(seconds) or seconds < 0 or (seconds == 0 and not zero):
        raise UsageError(f"{where}: {text!r} must be a positive time")
    return seconds


# ---- the line --------------------------------------------------------------------


class _Countdown:
    """Events at a rate `p` per unit (a byte, a bit) without one draw per unit: the gap to
    the next event is geometric."""

    def __init__(self, p: float, rng: random.Random) -> None:
        self.p, self.rng = p, rng
        self.left = self._gap()

    def _gap(self) -> float:
        if self.p <= 0.0:
            return math.inf
        if self.p >= 1.0:
            return 0
        return math.floor(math.log(1.0 - self.rng.random()) / math.log(1.0 - self.p))

    def hits(self, units: int) -> list[int]:
        """Which of the next `units` units the event hits (offsets, increasing)."""
        offsets, at = [], 0
        while self.left < units - at:
            at += int(self.left)
            offsets.append(at)
            at += 1
            self.left = self._gap()
        self.left -= units - at
        return offsets


@dataclass
class _Direction:
    """One direction of the line: its fault draws, what it holds back."""

    drop: _Countdown
    flip: _Countdown
    held: bytes | None = None  # a frame reordered behind the next one
    partial: bytearray = field(default_factory=bytearray)  # bytes of a frame not yet ended
    late: list[tuple[float, bytes]] = field(default_factory=list)  # (due [s], frames) delayed

    def due(self) -> bytes:
        """The delayed frames whose time has come, in the order they were sent."""
        now = time.monotonic()
        ready = b"".join(frames for due, frames in self.late if due <= now)
        self.late = [(due, frames) for due, frames in self.late if due > now]
        return ready


class FaultSchedule:
    """A run's faults as they happen: the spec, its one random stream (seeded from the
    run's seed), the ticks at which the runtime is killed, what was injected."""

    def __init__(self, spec: FaultSpec, seed: int, last_tick: int, tick_s: float) -> None:
        self.spec, self.tick_s = spec, tick_s
        self.rng = random.Random(f"{seed}:faults")
        self.injected: Counter[str] = Counter()
        if spec.kills_within_s is not None:
            last_tick = min(last_tick, int(spec.kills_within_s / tick_s))
        ticks = range(1, max(last_tick, 1) + 1)
        self._kills = sorted(self.rng.sample(ticks, min(spec.kills, len(ticks))), reverse=True)

    def kill_due(self, tick: int) -> bool:
        """Whether the runtime is to be killed at `tick` (each drawn tick once)."""
        if self._kills and tick >= self._kills[-1]:
            self._kills.pop()
            return True
        return False


class FaultyLine:
    """A Port (runtime.protocol) that passes frames through the faults of a schedule, both
    directions, and counts what it injected. `down`: the line is cut (writes vanish,
    nothing arrives)."""

    def __init__(self, port, faults: FaultSchedule) -> None:
        self.port, self.spec, self.rng = port, faults.spec, faults.rng
        self.down = False
        self.injected = faults.injected
        spec, rng = self.spec, self.rng
        self._out = _Direction(_Countdown(spec.drop, rng), _Countdown(spec.flip, rng))
        self._in = _Direction(_Countdown(spec.drop, rng), _Countdown(spec.flip, rng))

    def fileno(self) -> int:
        return self.port.fileno()

    def write(self, data: bytes) -> int:
        if not self.down:
            self.port.write(self._pass(self._out, data) + self._out.due())
        return len(data)

    def read(self, size: int = 1) -> bytes:
        data = self.port.read(size)
        if self.down:
            return b""
        if late := self._out.due():  # delayed frames go out while we wait for answers
            self.port.write(late)
        return self._pass(self._in, data) + self._in.due()

    def discard_input(self) -> None:
        """Forget what arrived while the line was cut (and any frame half received)."""
        fd = self.port.fileno()
        try:
            while select.select([fd], [], [], 0)[0] and os.read(fd, 4096):
                pass
        except OSError:  # the other end hung up: nothing to forget
            pass
        self._in.partial.clear()
        self._in.held = None
        self._in.late.clear()

    def _pass(self, way: _Direction, data: bytes) -> bytes:
        """What reaches the other side of `data`: whole frames, damaged as drawn."""
        way.partial += data
        *frames, rest = bytes(way.partial).split(b"\x00")
        way.partial = bytearray(rest)
        out = bytearray()
        for body in frames:
            for frame in self._frame(way, body + b"\x00"):
                out += frame
        return bytes(out)

    def _frame(self, way: _Direction, frame: bytes) -> list[bytes]:
        """One frame (with its delimiter) through the frame and byte faults."""
        spec, rng, count = self.spec, self.rng, self.injected
        late = spec.delay and rng.random() < spec.delay
        if late:
            count["delay"] += 1
        if spec.truncate and len(frame) > 2 and rng.random() < spec.truncate:
            count["truncate"] += 1
            frame = frame[:rng.randrange(1, len(frame) - 1)] + b"\x00"
        damaged = bytearray(frame)
        if spec.burst and rng.random() < spec.burst:
            count["burst"] += 1
            at = rng.randrange(len(damaged))
            for i in range(at, min(at + spec.burst_bytes, len(damaged))):
                damaged[i] = rng.randrange(256)
        for bit in way.flip.hits(8 * len(damaged)):
            count["flip"] += 1
            damaged[bit // 8] ^= 1 << bit % 8
        for i in reversed(way.drop.hits(len(damaged))):
            count["drop"] += 1
            del damaged[i]
        frames = [bytes(damaged)]
        if spec.dup and rng.random() < spec.dup:
            count["dup"] += 1
            frames.append(bytes(damaged))
        if way.held is not None:
            frames.append(way.held)
            way.held = None
        elif spec.reorder and rng.random() < spec.reorder:
            count["reorder"] += 1
            way.held, frames = frames[0], frames[1:]
        if late:  # on the line, late: the sender goes on meanwhile
            way.late.append((time.monotonic() + spec.delay_s, b"".join(frames)))
            return []
        return frames
