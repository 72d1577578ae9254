"""The plan (docs/plan-format.md): one type, `Plan`, written canonically and read back
strictly.

A plan is what the planner decided (per state: the clock, the sensors' power windows,
the profiles' shares and glide) and what it predicts (per state: time, visits,
inflections and energy by component; the budget; the assumptions the prediction rests
on). `plan_mission` makes one, the plan file holds one, the C runtime flies one and the
simulator checks a flight against one, with nothing else beside it.

The writer produces exactly the bytes the C runtime expects; the reader enforces every
rule of the format (the C reader's rules, line for line) and raises `PlanFileError`
naming the line, so tests can check that what we write is what the runtime accepts.
"""

from __future__ import annotations

import math
import re
import zlib
from dataclasses import dataclass, field
from pathlib import Path

from gliderplan.contract import (
    MAX_NAME_LENGTH,
    MAX_PLAN_ASSUMPTIONS,
    MAX_PLAN_BYTES,
    MAX_PLAN_COMPONENTS,
    MAX_PLAN_ENERGY_J,
    MAX_PLAN_INFLECTIONS,
    MAX_PLAN_LINE_BYTES,
    MAX_PLAN_SENSORS,
    MAX_PLAN_SEQUENCE,
    MAX_PLAN_SPEED_MPS,
    MAX_PLAN_THRUST_W,
    MAX_PLAN_TIME_S,
    MAX_PROFILE_ALTERNATIVES,
    MAX_STATES,
    NO_BOARD,
    PLAN_FORMAT_VERSION,
    RUNTIME_CYCLES_PER_TICK,
    FlightLimits,
)
from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import read_input
from gliderplan.contract.plan_check import plan_problem
from gliderplan.language import ir
from gliderplan.language.ir import CheckedMission
from gliderplan.language.registry import SENSOR_BY_NAME

MISSION_SUBJECT = "mission"  # the subject of an assumption about the whole mission
_NAME = re.compile(rf"[A-Za-z_][A-Za-z0-9_]{{0,{MAX_NAME_LENGTH - 1}}}\Z")
_NUMBER = re.compile(r"-?[0-9]+(\.[0-9]+)?([eE][-+]?[0-9]+)?\Z")
_COUNT = re.compile(r"[0-9]+\Z")
_HEX64 = re.compile(r"[0-9a-f]{64}\Z")
_HEX8 = re.compile(r"[0-9a-f]{8}\Z")
_SEQUENCE = re.compile(r"[1-9][0-9]{0,9}\Z")
_NOTE = re.compile(rf"([A-Za-z_][A-Za-z0-9_]{{0,{MAX_NAME_LENGTH - 1}}}): (.+)\Z")


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


def as_written(x: float) -> float:
    """`x` as the plan file holds it (9 significant digits): a plan made in memory equals
    the plan read back from its file."""
    return float(number(x))


# ---- the plan --------------------------------------------------------------------------

@dataclass(frozen=True)
class SensorPlan:
    """A sensor whose power the plan manages: on for the first `on_s` of every `period_s`
    [s], counted from entry into the state."""

    name: str
    period_s: float
    on_s: float

    @property
    def duty(self) -> float:
        """Fraction of the time the sensor is powered [1]."""
        return self.on_s / self.period_s

    @property
    def device(self) -> str:
        """The power-model device behind the sensor ("" for a flight sensor)."""
        return SENSOR_BY_NAME[self.name].device or ""


@dataclass(frozen=True)
class ProfilePlan:
    """One alternative of a state's `flightprofile a | b | ...`, as the plan flies it."""

    index: int  # position in the state's list of alternatives
    share: float  # fraction of each profile cycle spent flying it [1]
    pitch_rad: float
    ballast_cc: float  # pumped volume either side of neutral [cc]
    speed_mps: float  # planned horizontal speed [m/s]
    thrust_w: float = 0.0  # a yo's thruster: its commanded power [W] (0: off, not written)


@dataclass(frozen=True)
class StatePlan:
    """What the plan sets in one state and what it predicts of it."""

    name: str
    clock_mhz: float
    cycle_s: float  # period over which the profiles alternate [s]
    time_s: float  # predicted time in the state over the whole mission [s]
    visits: int  # predicted visits
    inflections: float  # predicted inflections over the mission
    energy_by_component_j: dict[str, float]  # predicted energy [J] per component
    sensors: tuple[SensorPlan, ...]
    profiles: tuple[ProfilePlan, ...]
    sleep: bool = False  # the board sleeps between ticks (`computer sleep between ticks`)
    cycles_per_tick: float = RUNTIME_CYCLES_PER_TICK  # the board's work every tick [cycles]
    line: int = field(default=0, compare=False)  # where the block starts in its file

    @property
    def energy_j(self) -> float:
        return float(sum(self.energy_by_component_j.values()))


@dataclass(frozen=True)
class Assumption:
    """Something the prediction rests on that the flight may prove wrong. `subject` is a
    state, a device or another NAME it concerns, or "mission"."""

    subject: str
    text: str

    @classmethod
    def from_note(cls, note: str) -> Assumption:
        """The planner's notes read "subject: what was assumed"; one without a subject
        concerns the mission."""
        match = _NOTE.match(note)
        return cls(match[1], match[2]) if match else cls(MISSION_SUBJECT, note)

    def __str__(self) -> str:
        return self.text if self.subject == MISSION_SUBJECT else f"{self.subject}: {self.text}"


@dataclass(frozen=True)
class Plan:
    """The plan of a mission: what to fly in each state and what it will cost."""

    mission: str
    mission_hash: str  # CheckedMission.hash of the mission it was made for
    computer: str  # board preset, a user board's name, or "none" (contract.NO_BOARD)
    clock_mhz: float  # the board's default clock; 0 for none
    budget_j: float  # usable energy [J] = (1 - reserve) x battery
    predicted_j: float  # predicted energy of the whole mission [J]
    states: tuple[StatePlan, ...]  # in the mission's order
    assumptions: tuple[Assumption, ...] = ()
    seq: int = field(default=0, compare=False)  # a signed plan's sequence number, 0: unsigned

    @property
    def components(self) -> tuple[str, ...]:
        """The energy components the prediction names, in the file's order."""
        return tuple(dict.fromkeys(k for s in self.states for k in s.energy_by_component_j))

    @property
    def components_j(self) -> dict[str, float]:
        """Predicted energy [J] per component over the mission."""
        return {c: float(sum(s.energy_by_component_j.get(c, 0.0) for s in self.states))
                for c in self.components}


def computer_text(computer: str, clock_mhz: float) -> str:
    """A plan's computer as people read it: "ts7800 @ 300 MHz", or for `computer none`
    "none (the glider's own computers)"."""
    if computer == NO_BOARD:
        return f"{NO_BOARD} (the glider's own computers)"
    return f"{computer} @ {clock_mhz:g} MHz"


# ---- writing ---------------------------------------------------------------------------

def write_plan_bytes(plan: Plan) -> bytes:
    """The bytes of the plan's file, checksum line included. PlanFileError if no plan file
    can carry the plan (too many states, a name that is not a NAME, ...)."""
    components = plan.components
    lines = [f"GPPLAN {PLAN_FORMAT_VERSION}", f"mission {plan.mission}",
             f"hash {plan.mission_hash}", f"computer {plan.computer} {number(plan.clock_mhz)}",
             f"budget_j {number(plan.budget_j)}", f"predicted_j {number(plan.predicted_j)}",
             f"components {' '.join(components)}", f"assumptions {len(plan.assumptions)}"]
    lines += [f"assume {a.subject} {a.text}" for a in plan.assumptions]
    lines.append(f"states {len(plan.states)}")
    for s in plan.states:
        lines.append(f"state {s.name} {number(s.clock_mhz)} {number(s.cycle_s)} "
                     f"{len(s.sensors)} {len(s.profiles)}")
        if s.sleep or s.cycles_per_tick != RUNTIME_CYCLES_PER_TICK:
            lines.append(f"power {int(s.sleep)} {number(s.cycles_per_tick)}")
        lines.append(f"predict {number(s.time_s)} {s.visits} {number(s.inflections)}")
        lines.append("energy " + " ".join(number(s.energy_by_component_j.get(c, 0.0))
                                          for c in components))
        lines += [f"sensor {x.name} {number(x.period_s)} {number(x.on_s)}" for x in s.sensors]
        lines += [f"profile {p.index} {number(p.share)} {number(p.pitch_rad)} "
                  f"{number(p.ballast_cc)} {number(p.speed_mps)}"
                  + (f" {number(p.thrust_w)}" if p.thrust_w else "") for p in s.profiles]
        lines.append("end")
    try:
        body = "".join(line + "\n" for line in lines).encode("ascii")
    except UnicodeEncodeError as err:
        raise PlanFileError(0, f"no plan file can carry this plan: {err.object[:60]!r} is "
                            "not ASCII (docs/plan-format.md)") from None
    data = body + f"crc32 {zlib.crc32(body):08x}\n".encode("ascii")
    # The writer must never emit what the reader (and the runtime) would refuse.
    try:
        read_plan_bytes(data)
    except PlanFileError as err:
        raise PlanFileError(0, f"no plan file can carry this plan: {err.message} "
                            "(docs/plan-format.md)") from None
    return data


# ---- reading strictly ------------------------------------------------------------------

class _Cursor:
    def __init__(self, lines: list[str]) -> None:
        self.lines = lines
        self.at = 0

    def next(self, keyword: str, n_fields: int | None, optional: int = 0) -> list[str]:
        """The fields after `keyword` on the next line, which must have `n_fields` of them
        and up to `optional` more (None: one or more)."""
        if self.at >= len(self.lines):
            raise PlanFileError(self.at + 1, f"expected a '{keyword}' line, the file ends")
        self.at += 1
        fields = self.lines[self.at - 1].split(" ")
        if fields[0] != keyword:
            raise PlanFileError(self.at, f"expected '{keyword}', found '{fields[0]}'")
        if n_fields is None and len(fields) < 2:
            raise PlanFileError(self.at, f"'{keyword}' takes at least one field, found none")
        if n_fields is not None and not n_fields <= len(fields) - 1 <= n_fields + optional:
            takes = f"{n_fields} to {n_fields + optional}" if optional else f"{n_fields}"
            raise PlanFileError(self.at, f"'{keyword}' takes {takes} fields, "
                                f"found {len(fields) - 1}")
        return fields[1:]

    def coming(self, keyword: str) -> bool:
        """Whether the next line is a `keyword` line (for an optional line)."""
        return self.at < len(self.lines) and self.lines[self.at].split(" ", 1)[0] == keyword

    def name(self, text: str) -> str:
        if not _NAME.match(text):
            raise PlanFileError(self.at, f"{text!r} is not a NAME")
        return text

    def number(self, text: str, what: str, low: float = -math.inf,
               high: float = math.inf) -> float:
        """A NUMBER in [`low`, `high`]."""
        if not _NUMBER.match(text) or not math.isfinite(float(text)):
            raise PlanFileError(self.at, f"{what}: {text!r} is not a NUMBER")
        value = float(text)
        self.check(value >= low, f"{what} must be >= {low:g}")
        self.check(value <= high, f"{what} {value:g} exceeds {high:g}")
        return value

    def clock(self, text: str, limits: FlightLimits | None, no_board: bool) -> float:
        """A clock [MHz]: 0 in a plan for `computer none` (`no_board`), which has no clock
        to set, whatever board the mission is built for; else > 0, and with `limits` one
        of the board's."""
        value = self.number(text, "clock")
        if no_board:
            self.check(value == 0, f"clock {value:g} MHz: computer {NO_BOARD} has no clock "
                       "to set, its clocks are 0")
            return value
        self.check(value > 0, "the clock must be > 0 MHz")
        if limits is not None:
            self.check(limits.has_clock(value), f"clock {value:g} MHz: {_board_clocks(limits)}")
        return value

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


def _board_clocks(limits: FlightLimits) -> str:
    """The clocks a plan may name on the board of `limits`, as its reader says them."""
    if limits.clocks_mhz == (0.0,):  # flight_limits of `computer none`
        return (f"the mission names no board (computer {NO_BOARD}): a plan for it says "
                f"'computer {NO_BOARD} 0'")
    return f"the board has {', '.join(f'{c:g}' for c in limits.clocks_mhz)} MHz"


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


def read_plan_bytes(data: bytes, mission: CheckedMission | None = None,
                    path: str = "", limits: FlightLimits | None = None) -> Plan:
    """Parse a plan file strictly; with `mission`, check that it is a plan for that
    mission as the C runtime does (name, hash, states, each state's profiles and logged
    sensors); with `limits` too, that it keeps to the board's clocks and does not
    contradict the mission (`contract.plan_check.plan_problem`: battery, board, duties,
    flight). A signed plan's `seq` and `hmac` lines are checked for their form only
    (`planner.signing` checks the tag). PlanFileError (`path:line: ...`) names the first
    line that breaks a rule."""
    try:
        plan = _read(data, mission, limits)
        problem = None if mission is None or limits is None else plan_problem(plan, limits)
    except PlanFileError as err:
        raise PlanFileError(err.line, err.message, path) from None
    if problem is not None:
        raise PlanFileError(problem.line, problem.message, path)
    return plan


def _read(data: bytes, mission: CheckedMission | None, limits: FlightLimits | None) -> Plan:
    lines = _split_lines(data)
    cur = _Cursor(lines)
    version = cur.next("GPPLAN", 1)[0]
    cur.check(version == str(PLAN_FORMAT_VERSION),
              f"unsupported version {version!r} (expected {PLAN_FORMAT_VERSION})")
    name = cur.name(cur.next("mission", 1)[0])
    if mission is not None:
        cur.check(name == mission.name, f"plan for mission {name!r}, not {mission.name!r}")
    digest = cur.next("hash", 1)[0]
    cur.check(bool(_HEX64.match(digest)), "hash must be 64 lowercase hex digits")
    if mission is not None:
        cur.check(digest == mission.hash,
                  "plan made for another version of the mission (hash differs)")
    computer, clock = cur.next("computer", 2)
    computer = cur.name(computer)
    no_board = computer == NO_BOARD
    if limits is not None and limits.board not in (None, computer):
        limits = None  # its clocks are another board's: `plan_problem` says so
    clock_mhz = cur.clock(clock, limits, no_board)
    budget = cur.number(cur.next("budget_j", 1)[0], "budget_j", 0.0, MAX_PLAN_ENERGY_J)
    predicted = cur.number(cur.next("predicted_j", 1)[0], "predicted_j", 0.0, MAX_PLAN_ENERGY_J)
    components = [cur.name(c) for c in cur.next("components", None)]
    cur.check(len(components) <= MAX_PLAN_COMPONENTS,
              f"{len(components)} components, more than {MAX_PLAN_COMPONENTS}")
    cur.check(len(set(components)) == len(components), "a component is named twice")
    n_assumptions = cur.count(cur.next("assumptions", 1)[0], "assumptions", 0,
                              MAX_PLAN_ASSUMPTIONS)
    assumptions = tuple(_assumption(cur) for _ in range(n_assumptions))
    n_states = cur.count(cur.next("states", 1)[0], "states", 1, MAX_STATES)
    if mission is not None:
        cur.check(n_states == len(mission.states),
                  f"{n_states} states, the mission has {len(mission.states)}")
    states = tuple(_state_block(cur, components, None if mission is None
                                else mission.states[i], limits, no_board)
                   for i in range(n_states))
    (checksum,) = cur.next("crc32", 1)
    cur.check(bool(_HEX8.match(checksum)), "crc32 must be 8 lowercase hex digits")
    body = data[: data.rfind(b"crc32 ")]
    cur.check(int(checksum, 16) == zlib.crc32(body),
              f"checksum mismatch: the file says {checksum}, its bytes give "
              f"{zlib.crc32(body):08x}")
    seq = _signature_form(cur)
    if cur.at != len(lines):
        raise PlanFileError(cur.at + 1, "extra line after crc32" if not seq
                            else "extra line after hmac")
    return Plan(name, digest, computer, clock_mhz, budget, predicted, states, assumptions, seq)


def _signature_form(cur: _Cursor) -> int:
    """A signed plan's `seq COUNT` and `hmac HEX64` lines after crc32: the sequence number
    (0: no such lines)."""
    if cur.at == len(cur.lines) or not cur.lines[cur.at].startswith("seq "):
        if cur.at < len(cur.lines) and cur.lines[cur.at].startswith("hmac "):
            raise PlanFileError(cur.at + 1, "a signed plan needs 'seq COUNT' before its "
                                "'hmac' line")
        return 0
    (seq,) = cur.next("seq", 1)
    cur.check(bool(_SEQUENCE.match(seq)), f"seq {seq!r} is not a COUNT from 1")
    cur.check(int(seq) <= MAX_PLAN_SEQUENCE, f"seq {seq} exceeds {MAX_PLAN_SEQUENCE}")
    (tag,) = cur.next("hmac", 1)
    cur.check(bool(_HEX64.match(tag)), "hmac must be 64 lowercase hex digits")
    return int(seq)


def _assumption(cur: _Cursor) -> Assumption:
    """`assume SUBJECT TEXT`: TEXT is the rest of the line."""
    words = cur.next("assume", None)
    cur.check(len(words) >= 2, "'assume' takes a SUBJECT and a TEXT")
    return Assumption(cur.name(words[0]), " ".join(words[1:]))


def _state_block(cur: _Cursor, components: list[str], state: ir.State | None,
                 limits: FlightLimits | None, no_board: bool) -> StatePlan:
    """A state block; `state`, the mission's, is what it must fit (None: no mission),
    `limits` the vehicle's and board's (None: the bounds every vehicle shares), `no_board`
    whether the plan is for `computer none`."""
    name, clock, cycle, n_sensors, n_profiles = cur.next("state", 5)
    start = cur.at
    name = cur.name(name)
    if state is not None:
        cur.check(name == state.name, f"state {name!r} where the mission has {state.name!r}")
    clock_mhz = cur.clock(clock, limits, no_board)
    cycle_s = cur.number(cycle, "cycle", 0.0, MAX_PLAN_TIME_S)
    cur.check(cycle_s > 0, "cycle must be > 0")
    n_sensors = cur.count(n_sensors, "sensors", 0, MAX_PLAN_SENSORS)
    n_profiles = cur.count(n_profiles, "profiles", 1, MAX_PROFILE_ALTERNATIVES)
    if state is not None:
        cur.check(n_profiles == len(state.profiles), f"state {name}: {n_profiles} profiles, "
                  f"the mission's state has {len(state.profiles)}")
    sleep, cycles = False, RUNTIME_CYCLES_PER_TICK
    if cur.coming("power"):
        asleep, work = cur.next("power", 2)
        sleep = cur.count(asleep, "SLEEP", 0, 1) == 1
        cycles = cur.number(work, "CYCLES_PER_TICK")
        cur.check(cycles > 0, "CYCLES_PER_TICK must be > 0")
    if state is not None:  # a board that cannot sleep idles where the mission sleeps
        cur.check(not sleep or state.computer.sleep,
                  f"state {name}: SLEEP 1 where the mission does not sleep between ticks")
    time_s, visits, inflections = cur.next("predict", 3)
    prediction = (cur.number(time_s, "predicted time", 0.0, MAX_PLAN_TIME_S),
                  cur.count(visits, "predicted visits", 0, 999_999_999),
                  cur.number(inflections, "predicted inflections", 0.0, MAX_PLAN_INFLECTIONS))
    energy = {c: cur.number(j, f"energy of {c}", 0.0, MAX_PLAN_ENERGY_J)
              for c, j in zip(components, cur.next("energy", len(components)), strict=True)}
    logged = [use.name for use in state.sensors] if state is not None else None
    sensors, after = [], 0
    for _ in range(n_sensors):
        sensor, period, on = cur.next("sensor", 3)
        sensor = cur.name(sensor)
        period_s = cur.number(period, "period", high=MAX_PLAN_TIME_S)
        on_s = cur.number(on, "on time")
        cur.check(period_s > 0 and 0 <= on_s <= period_s, "need 0 <= ON_S <= PERIOD_S, "
                  "PERIOD_S > 0")
        if logged is not None:
            cur.check(sensor in logged, f"state {name}: sensor {sensor!r} is not logged by "
                      "the state")
            cur.check(sensor in logged[after:], f"state {name}: sensor lines out of the "
                      "state's order")
            after = logged.index(sensor, after) + 1
        sensors.append(SensorPlan(sensor, period_s, on_s))
    profiles = []
    for i in range(n_profiles):
        index, share, pitch, ballast, speed, *thrust = cur.next("profile", 5, optional=1)
        cur.check(cur.count(index, "index", 0, MAX_PROFILE_ALTERNATIVES - 1) == i,
                  f"profile index {index} out of order (expected {i})")
        line = ProfilePlan(i, cur.number(share, "share"), cur.number(pitch, "pitch"),
                           cur.number(ballast, "ballast"), cur.number(speed, "speed"),
                           cur.number(thrust[0], "thrust") if thrust else 0.0)
        cur.check(0 <= line.thrust_w <= MAX_PLAN_THRUST_W,
                  f"thrust must lie in [0, {MAX_PLAN_THRUST_W:g}] W")
        cur.check(0 <= line.share <= 1, "share must lie in [0, 1]")
        level = line.pitch_rad == 0.0 and line.ballast_cc == 0.0  # a propelled profile
        cur.check(level or 0 < line.pitch_rad < math.pi / 2, "pitch must lie in (0, pi/2) rad")
        cur.check((level or line.ballast_cc > 0) and line.speed_mps > 0,
                  "ballast and speed must be > 0")
        cur.check(line.speed_mps <= MAX_PLAN_SPEED_MPS,
                  f"speed {line.speed_mps:g} exceeds {MAX_PLAN_SPEED_MPS:g} m/s")
        profiles.append(line)
    cur.check(abs(sum(p.share for p in profiles) - 1.0) <= 1e-6,
              f"state {name}: profile shares sum to {sum(p.share for p in profiles):.9g}, not 1")
    cur.next("end", 0)
    return StatePlan(name, clock_mhz, cycle_s, *prediction, energy, tuple(sensors),
                     tuple(profiles), sleep=sleep, cycles_per_tick=cycles, line=start)


def read_plan_data(path: str | Path) -> bytes:
    """The bytes of a plan file; InputFileError (`usage` when missing) if it cannot be read."""
    return read_input(path, "plan file")


def load_plan(path: str | Path, mission: CheckedMission,
              limits: FlightLimits | None = None) -> Plan:
    """The plan in `path` for `mission`, to fly: InputFileError if there is no such file,
    PlanRejected (naming the file and line) if it is not a plan for `mission` or breaks
    `limits` (default: the mission's own, `planner.limits.flight_limits`)."""
    from gliderplan.planner.limits import flight_limits

    try:
        return read_plan_bytes(read_plan_data(path), mission, str(path),
                               limits or flight_limits(mission))
    except PlanFileError as err:
        raise PlanRejected(str(err)) from None


def flown_board(mission: CheckedMission, plan: Plan | None) -> str:
    """The board a simulated flight of `plan` runs on and is billed for: none for a plan
    made for `computer none`, else the mission's computer (the only board another plan
    may name: `contract.plan_check`)."""
    if plan is not None and plan.computer == NO_BOARD:
        return NO_BOARD
    return mission.computer.board


def plan_board_limits(mission: CheckedMission, plan: Plan) -> FlightLimits:
    """The limits a simulated flight of `plan` keeps: the mission's vehicle, on the board
    it flies on (`flown_board`)."""
    from gliderplan.planner.limits import flight_limits

    return flight_limits(mission, flown_board(mission, plan))


def read_plan_file(path: str | Path, mission: CheckedMission | None = None) -> Plan:
    """Read a plan file strictly (and, given `mission`, check that it is a plan for it).
    Errors are PlanFileError with `path:line:` first."""
    return read_plan_bytes(read_plan_data(path), mission, str(path))
