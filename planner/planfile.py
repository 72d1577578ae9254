"""The plan file (docs/plan-format.md): written canonically, read back strictly.

The writer produces exactly the bytes the C runtime expects; the reader enforces every
rule of the format and raises `PlanFileError` naming the line, so tests can check that
what we write is what the runtime will accept.
"""

from __future__ import annotations

import math
import re
import zlib
from dataclasses import dataclass, field
from pathlib import Path

from gliderplan.contract import (
    MAX_NAME_LENGTH,
    MAX_PLAN_BYTES,
    MAX_PLAN_LINE_BYTES,
    MAX_PLAN_SENSORS,
    MAX_PROFILE_ALTERNATIVES,
    MAX_STATES,
)
from gliderplan.contract.errors import GliderplanError
from gliderplan.language.ir import CheckedMission
from gliderplan.planner.plan import Plan

VERSION = 1
_NAME = re.compile(rf"[A-Za-z_][A-Za-z0-9_]{{0,{MAX_NAME_LENGTH - 1}}}\Z")
_NUMBER = re.compile(r"-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?\Z")
_COUNT = re.compile(r"[0-9]+\Z")
_HEX64 = re.compile(r"[0-9a-f]{64}\Z")
_HEX8 = re.compile(r"[0-9a-f]{8}\Z")


class PlanFileError(GliderplanError, ValueError):
    """A plan file that breaks the format; `line` is 1-based (0: the file as a whole);
    `usage`: there is no such file."""

    def __init__(self, line: int, message: str, path: str = "", *, usage: bool = False) -> None:
        self.line, self.message, self.path = line, message, path
        where = f"{path}:" if path else ""
        where += f"{line}:" if line else ""
        super().__init__(f"{where} {message}" if where else message, usage=usage)


class PlanRejected(GliderplanError):
    """A plan that a command cannot fly or ship: the message, "plan rejected: ...", is the
    reader's (the Python reader's or the C runtime's own) and names the file and line."""

    def __init__(self, reason: str, *, usage: bool = False) -> None:
        super().__init__(f"plan rejected: {reason}", usage=usage)


def number(x: float) -> str:
    """A NUMBER as the format writes it: at most 9 significant digits, no '+' mantissa."""
    if not math.isfinite(x):
        raise ValueError(f"a plan file number must be finite, got {x!r}")
    text = format(float(x), ".9g")
    if text in ("-0", "-0.0"):
        text = "0"
    if "e" in text:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}e{int(exponent)}"
    return text


# ---- the contents of a plan file -------------------------------------------------------

@dataclass(frozen=True)
class SensorLine:
    name: str
    period_s: float
    on_s: float


@dataclass(frozen=True)
class ProfileLine:
    index: int
    share: float
    pitch_rad: float
    ballast_cc: float
    speed_mps: float


@dataclass(frozen=True)
class StateBlock:
    name: str
    clock_mhz: float
    cycle_s: float
    sensors: tuple[SensorLine, ...]
    profiles: tuple[ProfileLine, ...]
    line: int = field(default=0, compare=False)  # where the block starts in the file


@dataclass(frozen=True)
class PlanFile:
    mission: str
    hash: str
    computer: str
    clock_mhz: float
    budget_j: float
    predicted_j: float
    states: tuple[StateBlock, ...]


def _rounded(x: float) -> float:
    return float(number(x))


def plan_file_of(plan: Plan) -> PlanFile:
    """The plan file's contents, with every number as it will be written."""
    blocks = []
    for s in plan.states:
        sensors = tuple(SensorLine(x.name, _rounded(x.period_s), _rounded(x.on_s))
                        for x in s.sensors)
        profiles = tuple(ProfileLine(p.index, _rounded(p.share), _rounded(p.pitch_rad),
                                     _rounded(p.ballast_cc), _rounded(p.speed_mps))
                         for p in s.profiles)
        blocks.append(StateBlock(s.name, _rounded(s.clock_mhz), _rounded(s.cycle_s),
                                 sensors, profiles))
    return PlanFile(plan.mission, plan.mission_hash, plan.computer, _rounded(plan.clock_mhz),
                    _rounded(plan.budget_j), _rounded(plan.energy_j), tuple(blocks))


def render(contents: PlanFile) -> bytes:
    """The bytes of a plan file, checksum line included."""
    lines = [f"GPPLAN {VERSION}", f"mission {contents.mission}", f"hash {contents.hash}",
             f"computer {contents.computer} {number(contents.clock_mhz)}",
             f"budget_j {number(contents.budget_j)}",
             f"predicted_j {number(contents.predicted_j)}", f"states {len(contents.states)}"]
    for b in contents.states:
        lines.append(f"state {b.name} {number(b.clock_mhz)} {number(b.cycle_s)} "
                     f"{len(b.sensors)} {len(b.profiles)}")
        lines += [f"sensor {x.name} {number(x.period_s)} {number(x.on_s)}" for x in b.sensors]
        lines += [f"profile {p.index} {number(p.share)} {number(p.pitch_rad)} "
                  f"{number(p.ballast_cc)} {number(p.speed_mps)}" for p in b.profiles]
        lines.append("end")
    body = "".join(line + "\n" for line in lines).encode("ascii")
    data = body + f"crc32 {zlib.crc32(body):08x}\n".encode("ascii")
    # The writer must never emit what the reader (and the runtime) would refuse.
    try:
        read_plan_bytes(data)
    except PlanFileError as err:
        raise PlanFileError(0, f"no plan file can carry this plan: {err.message} "
                            "(docs/plan-format.md)") from None
    return data


def write_plan_bytes(plan: Plan) -> bytes:
    """The plan file of a plan."""
    return render(plan_file_of(plan))


# ---- reading strictly ------------------------------------------------------------------

class _Cursor:
    def __init__(self, lines: list[str]) -> None:
        self.lines = lines
        self.at = 0

    def next(self, keyword: str, n_fields: int) -> list[str]:
        """The fields after `keyword` on the next line, which must have `n_fields` of them."""
        if self.at >= len(self.lines):
            raise PlanFileError(self.at + 1, f"expected a '{keyword}' line, the file ends")
        self.at += 1
        fields = self.lines[self.at - 1].split(" ")
        if fields[0] != keyword:
            raise PlanFileError(self.at, f"expected '{keyword}', found '{fields[0]}'")
        if len(fields) != n_fields + 1:
            raise PlanFileError(self.at, f"'{keyword}' takes {n_fields} fields, "
                                f"found {len(fields) - 1}")
        return fields[1:]

    def name(self, text: str) -> str:
        if not _NAME.match(text):
            raise PlanFileError(self.at, f"{text!r} is not a NAME")
        return text

    def number(self, text: str, what: str) -> float:
        if not _NUMBER.match(text) or not math.isfinite(float(text)):
            raise PlanFileError(self.at, f"{what}: {text!r} is not a NUMBER")
        return float(text)

    def count(self, text: str, what: str, low: int, high: int) -> int:
        if not _COUNT.match(text):
            raise PlanFileError(self.at, f"{what}: {text!r} is not a COUNT")
        value = int(text)
        if not low <= value <= high:
            raise PlanFileError(self.at, f"{what} {value} is out of range {low}..{high}")
        return value

    def check(self, ok: bool, message: str) -> None:
        if not ok:
            raise PlanFileError(self.at, message)


def _split_lines(data: bytes) -> list[str]:
    if len(data) > MAX_PLAN_BYTES:
        raise PlanFileError(0, f"the file has {len(data)} bytes, more than {MAX_PLAN_BYTES}")
    if not data.endswith(b"\n"):
        raise PlanFileError(data.count(b"\n") + 1, "truncated: the last line has no LF")
    lines = data[:-1].split(b"\n")
    for i, raw in enumerate(lines, 1):
        bad = next((b for b in raw if not 0x20 <= b <= 0x7E), None)
        if bad is not None:
            raise PlanFileError(i, f"byte 0x{bad:02x} is not printable ASCII")
        if len(raw) + 1 > MAX_PLAN_LINE_BYTES:
            raise PlanFileError(i, f"the line has {len(raw) + 1} bytes, more than "
                                f"{MAX_PLAN_LINE_BYTES}")
        if not raw:
            raise PlanFileError(i, "empty line")
        if raw.startswith(b" ") or raw.endswith(b" ") or b"  " in raw:
            raise PlanFileError(i, "fields must be separated by exactly one space")
    return [raw.decode("ascii") for raw in lines]


def read_plan_bytes(data: bytes) -> PlanFile:
    """Parse a plan file strictly; PlanFileError names the first line that breaks a rule."""
    lines = _split_lines(data)
    cur = _Cursor(lines)
    version = cur.next("GPPLAN", 1)[0]
    cur.check(version == str(VERSION), f"unsupported version {version!r} (expected {VERSION})")
    mission = cur.name(cur.next("mission", 1)[0])
    digest = cur.next("hash", 1)[0]
    cur.check(bool(_HEX64.match(digest)), "hash must be 64 lowercase hex digits")
    computer, clock = cur.next("computer", 2)
    computer = cur.name(computer)
    clock_mhz = cur.number(clock, "clock")
    cur.check(clock_mhz > 0, "the clock must be > 0 MHz")
    budget = cur.number(cur.next("budget_j", 1)[0], "budget_j")
    cur.check(budget >= 0, "budget_j must be >= 0")
    predicted = cur.number(cur.next("predicted_j", 1)[0], "predicted_j")
    cur.check(predicted >= 0, "predicted_j must be >= 0")
    n_states = cur.count(cur.next("states", 1)[0], "states", 1, MAX_STATES)
    blocks = [_state_block(cur) for _ in range(n_states)]
    (checksum,) = cur.next("crc32", 1)
    cur.check(bool(_HEX8.match(checksum)), "crc32 must be 8 lowercase hex digits")
    body = data[: data.rfind(b"crc32 ")]
    cur.check(int(checksum, 16) == zlib.crc32(body),
              f"checksum mismatch: the file says {checksum}, its bytes give "
              f"{zlib.crc32(body):08x}")
    if cur.at != len(lines):
        raise PlanFileError(cur.at + 1, "extra line after crc32")
    return PlanFile(mission, digest, computer, clock_mhz, budget, predicted, tuple(blocks))


def _state_block(cur: _Cursor) -> StateBlock:
    name, clock, cycle, n_sensors, n_profiles = cur.next("state", 5)
    start = cur.at
    name = cur.name(name)
    clock_mhz, cycle_s = cur.number(clock, "clock"), cur.number(cycle, "cycle")
    cur.check(clock_mhz > 0 and cycle_s > 0, "clock and cycle must be > 0")
    n_sensors = cur.count(n_sensors, "sensors", 0, MAX_PLAN_SENSORS)
    n_profiles = cur.count(n_profiles, "profiles", 1, MAX_PROFILE_ALTERNATIVES)
    sensors = []
    for _ in range(n_sensors):
        sensor, period, on = cur.next("sensor", 3)
        period_s, on_s = cur.number(period, "period"), cur.number(on, "on time")
        cur.check(period_s > 0 and 0 <= on_s <= period_s, "need 0 <= ON_S <= PERIOD_S, "
                  "PERIOD_S > 0")
        sensors.append(SensorLine(cur.name(sensor), period_s, on_s))
    profiles = []
    for i in range(n_profiles):
        index, share, pitch, ballast, speed = cur.next("profile", 5)
        cur.check(cur.count(index, "index", 0, MAX_PROFILE_ALTERNATIVES - 1) == i,
                  f"profile index {index} out of order (expected {i})")
        line = ProfileLine(i, cur.number(share, "share"), cur.number(pitch, "pitch"),
                           cur.number(ballast, "ballast"), cur.number(speed, "speed"))
        cur.check(0 <= line.share <= 1, "share must lie in [0, 1]")
        cur.check(0 < line.pitch_rad < math.pi / 2, "pitch must lie in (0, pi/2) rad")
        cur.check(line.ballast_cc > 0 and line.speed_mps > 0, "ballast and speed must be > 0")
        profiles.append(line)
    cur.check(abs(sum(p.share for p in profiles) - 1.0) <= 1e-6,
              f"state {name}: profile shares sum to {sum(p.share for p in profiles):.9g}, not 1")
    cur.next("end", 0)
    return StateBlock(name, clock_mhz, cycle_s, tuple(sensors), tuple(profiles), start)


def check_against_mission(contents: PlanFile, mission: CheckedMission) -> None:
    """The checks that need the compiled mission: name, hash and state names."""
    mission_name, mission_hash = mission.name, mission.hash
    state_names = tuple(s.name for s in mission.states)
    if contents.mission != mission_name:
        raise PlanFileError(2, f"plan for mission {contents.mission!r}, not {mission_name!r}")
    if contents.hash != mission_hash:
        raise PlanFileError(3, "plan made for another version of the mission (hash differs)")
    if len(contents.states) != len(state_names):
        raise PlanFileError(7, f"{len(contents.states)} states, the mission has "
                            f"{len(state_names)}")
    for block, name in zip(contents.states, state_names, strict=True):
        if block.name != name:
            raise PlanFileError(block.line, f"state {block.name!r} where the mission has "
                                f"{name!r}")


def read_plan_data(path: str | Path) -> bytes:
    """The bytes of a plan file; PlanFileError (`usage` when missing) if it cannot be read."""
    try:
        return Path(path).read_bytes()
    except FileNotFoundError:
        raise PlanFileError(0, "no such file", str(path), usage=True) from None
    except OSError as err:
        raise PlanFileError(0, f"cannot read the plan: {err.strerror}", str(path)) from None


def read_plan_file(path: str | Path, mission: CheckedMission | None = None) -> PlanFile:
    """Read a plan file strictly (and, given the mission's name, hash and states, check
    that it is for that mission). Errors are PlanFileError with `path:line:` first."""
    data = read_plan_data(path)
    try:
        contents = read_plan_bytes(data)
        if mission is not None:
            check_against_mission(contents, mission)
    except PlanFileError as err:
        raise PlanFileError(err.line, err.message, str(path)) from None
    return contents
