"""Reading a plan file (docs/plan-format.md) strictly, as the C runtime does, for the
simulator's Python executor. Errors name the file and line."""

from __future__ import annotations

import re
import zlib
from dataclasses import dataclass
from pathlib import Path

from gliderplan.language.ir import CheckedMission

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,31}\Z")
_NUMBER = re.compile(r"-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?\Z")
_COUNT = re.compile(r"[0-9]+\Z")
_MAX_BYTES = 65536
_MAX_LINE = 255


class PlanFileError(ValueError):
    """A plan the runtime would reject; the message starts with `FILE:LINE:`."""


@dataclass(frozen=True)
class SensorSchedule:
    sensor: str
    period_s: float
    on_s: float


@dataclass(frozen=True)
class ProfilePlan:
    share: float
    pitch_rad: float
    ballast_cc: float
    speed_mps: float


@dataclass(frozen=True)
class StatePlan:
    name: str
    clock_mhz: float
    cycle_s: float
    sensors: tuple[SensorSchedule, ...]
    profiles: tuple[ProfilePlan, ...]


@dataclass(frozen=True)
class Plan:
    mission: str
    hash: str
    computer: str
    clock_mhz: float
    budget_j: float
    predicted_j: float
    states: tuple[StatePlan, ...]


class _Lines:
    def __init__(self, path: str, lines: list[str]) -> None:
        self.path, self.lines, self.index = path, lines, 0

    def error(self, message: str, line: int | None = None) -> PlanFileError:
        return PlanFileError(f"{self.path}:{line or self.index}: {message}")

    def take(self, keyword: str, n_fields: int) -> list[str]:
        if self.index >= len(self.lines):
            raise self.error(f"file ends before the '{keyword}' line (truncated?)",
                             len(self.lines) + 1)
        fields = self.lines[self.index].split(" ")
        self.index += 1
        if fields[0] != keyword:
            raise self.error(f"expected a '{keyword}' line, got '{fields[0]}'")
        if len(fields) != n_fields:
            raise self.error(f"'{keyword}' takes {n_fields - 1} fields, got {len(fields) - 1}")
        return fields[1:]

    def number(self, text: str, what: str) -> float:
        if not _NUMBER.match(text):
            raise self.error(f"{what}: {text!r} is not a number")
        value = float(text)
        if value != value or value in (float("inf"), float("-inf")):
            raise self.error(f"{what}: must be finite")
        return value

    def count(self, text: str, what: str, low: int, high: int) -> int:
        if not _COUNT.match(text) or not low <= int(text) <= high:
            raise self.error(f"{what}: {text!r} is not a count in {low}..{high}")
        return int(text)

    def name(self, text: str, what: str) -> str:
        if not _NAME.match(text):
            raise self.error(f"{what}: {text!r} is not a name")
        return text


def parse_plan(data: bytes, path: str, mission: CheckedMission) -> Plan:
    """The plan in `data`, checked against `mission`; PlanFileError names the line."""
    if len(data) > _MAX_BYTES:
        raise PlanFileError(f"{path}: {len(data)} bytes, more than {_MAX_BYTES}")
    if not data.endswith(b"\n"):
        last_line = data.count(b"\n") + 1
        raise PlanFileError(f"{path}:{last_line}: missing final line feed (truncated?)")
    text_lines = data[:-1].split(b"\n")
    for number, raw in enumerate(text_lines, start=1):
        if len(raw) + 1 > _MAX_LINE:
            raise PlanFileError(f"{path}:{number}: line longer than {_MAX_LINE} bytes")
        if any(b < 0x20 or b > 0x7E for b in raw):
            raise PlanFileError(f"{path}:{number}: byte outside printable ASCII")
        if raw == b"" or raw.startswith(b" ") or raw.endswith(b" ") or b"  " in raw:
            raise PlanFileError(f"{path}:{number}: empty line or stray spaces")
    lines = _Lines(path, [raw.decode("ascii") for raw in text_lines])
    if lines.take("GPPLAN", 2) != ["1"]:
        raise lines.error("unsupported plan version (expected 'GPPLAN 1')")
    (name,) = lines.take("mission", 2)
    if name != mission.name:
        raise lines.error(f"plan for mission {name!r}, not {mission.name!r}")
    (digest,) = lines.take("hash", 2)
    if digest != mission.hash:
        raise lines.error("mission hash differs: the plan was made for another version "
                          "of this mission (plan it again)")
    computer, clock = lines.take("computer", 3)
    lines.name(computer, "computer")
    clock_mhz = lines.number(clock, "clock")
    budget = lines.number(lines.take("budget_j", 2)[0], "budget_j")
    predicted = lines.number(lines.take("predicted_j", 2)[0], "predicted_j")
    n_states = lines.count(lines.take("states", 2)[0], "states", 1, 64)
    if n_states != len(mission.states):
        raise lines.error(f"{n_states} states, the mission has {len(mission.states)}")
    states = tuple(_state_block(lines, state) for state in mission.states)
    body_end = sum(len(line) + 1 for line in lines.lines[: lines.index])
    (crc,) = lines.take("crc32", 2)
    if not re.fullmatch(r"[0-9a-f]{8}", crc):
        raise lines.error("crc32 must be 8 lowercase hex digits")
    if lines.index != len(lines.lines):
        raise lines.error("extra lines after crc32", lines.index + 1)
    if int(crc, 16) != zlib.crc32(data[:body_end]):
        raise lines.error(f"checksum mismatch (file says {crc}, content gives "
                          f"{zlib.crc32(data[:body_end]):08x})")
    return Plan(name, digest, computer, clock_mhz, budget, predicted, states)


def _state_block(lines: _Lines, state) -> StatePlan:
    name, clock, cycle, n_sensors, n_profiles = lines.take("state", 6)
    if name != state.name:
        raise lines.error(f"state {name!r} where the mission has {state.name!r}")
    clock_mhz = lines.number(clock, "clock")
    cycle_s = lines.number(cycle, "cycle")
    if cycle_s <= 0.0:
        raise lines.error("cycle must be > 0 s")
    ns = lines.count(n_sensors, "sensor count", 0, 16)
    np_ = lines.count(n_profiles, "profile count", 1, 8)
    if np_ != len(state.profiles):
        raise lines.error(f"{np_} profiles, state {state.name} has {len(state.profiles)}")
    logged = [use.name for use in state.sensors]
    sensors = []
    for _ in range(ns):
        sensor, period, on = lines.take("sensor", 4)
        if sensor not in logged:
            raise lines.error(f"sensor {sensor!r} is not logged by state {state.name}")
        period_s, on_s = lines.number(period, "period"), lines.number(on, "on time")
        if period_s <= 0.0 or not 0.0 <= on_s <= period_s:
            raise lines.error("need PERIOD_S > 0 and 0 <= ON_S <= PERIOD_S")
        sensors.append(SensorSchedule(sensor, period_s, on_s))
    order = [logged.index(s.sensor) for s in sensors]
    if order != sorted(set(order)):
        raise lines.error(f"sensor lines of state {state.name} out of the state's order")
    profiles = []
    for index in range(np_):
        i, share, pitch, ballast, speed = lines.take("profile", 6)
        if lines.count(i, "profile index", 0, 7) != index:
            raise lines.error(f"profile index {i}, expected {index}")
        plan = ProfilePlan(lines.number(share, "share"), lines.number(pitch, "pitch"),
                           lines.number(ballast, "ballast"), lines.number(speed, "speed"))
        if not 0.0 <= plan.share <= 1.0 or not 0.0 < plan.pitch_rad < 1.5707963267948966 \
                or plan.ballast_cc <= 0.0 or plan.speed_mps <= 0.0:
            raise lines.error("need 0 <= SHARE <= 1, 0 < PITCH_RAD < pi/2, BALLAST_CC > 0, "
                              "SPEED_MPS > 0")
        profiles.append(plan)
    if abs(sum(p.share for p in profiles) - 1.0) > 1e-6:
        raise lines.error(f"profile shares of state {state.name} do not sum to 1")
    lines.take("end", 1)
    return StatePlan(name, clock_mhz, cycle_s, tuple(sensors), tuple(profiles))


def read_plan(path: str | Path, mission: CheckedMission) -> Plan:
    """Read and check a plan file; PlanFileError for an unreadable or bad one."""
    try:
        data = Path(path).read_bytes()
    except OSError as err:
        raise PlanFileError(f"{path}: cannot read plan: {err.strerror}") from None
    return parse_plan(data, str(path), mission)
