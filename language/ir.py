"""The checked mission: what every later stage (planner, codegen, simulator) consumes.

Names are resolved (a sensor or a variable), units are SI, defaults are filled in and
recorded, and the whole thing has a canonical JSON form whose SHA-256 is the mission
hash that plans and compiled runtimes carry.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields, is_dataclass
from functools import cached_property

from gliderplan.contract import DEFAULT_HORIZON_S, DEFAULT_STACK_DEPTH, NO_BOARD
from gliderplan.language.registry import PROFILES

# ---- expressions (no spans: the checker has reported everything by now) ----------


@dataclass(frozen=True)
class Const:
    value: float


@dataclass(frozen=True)
class SensorRef:
    name: str


@dataclass(frozen=True)
class VarRef:
    name: str


@dataclass(frozen=True)
class UnaryOp:
    op: str  # "-" or "!"
    operand: Expr


@dataclass(frozen=True)
class BinaryOp:
    op: str  # + - * / < <= > >= == != && ||
    left: Expr
    right: Expr


@dataclass(frozen=True)
class FuncCall:
    function: str  # abs | min | max, as C's fabs, fmin, fmax (min/max ignore a NaN)
    args: tuple[Expr, ...]


Expr = Const | SensorRef | VarRef | UnaryOp | BinaryOp | FuncCall


def _divide(a: float, b: float) -> float:
    """IEEE-754 division, as the C runtime computes it."""
    if b != 0.0:
        return a / b
    if a == 0.0 or math.isnan(a):
        return math.nan
    return math.copysign(math.inf, a) * math.copysign(1.0, b)


_ARITHMETIC = {
    "+": lambda a, b: a + b,
    "-": lambda a, b: a - b,
    "*": lambda a, b: a * b,
    "/": _divide,
}
_COMPARISONS = {
    "<": lambda a, b: a < b,
    "<=": lambda a, b: a <= b,
    ">": lambda a, b: a > b,
    ">=": lambda a, b: a >= b,
    "==": lambda a, b: a == b,
    "!=": lambda a, b: a != b,
}


def _ignoring_nan(pick: Callable[[float, float], float]) -> Callable[[float, float], float]:
    """C's fmin/fmax from min/max: a NaN argument is ignored (the other is returned);
    NaN only if both are."""
    def c_style(a: float, b: float) -> float:
        if math.isnan(a):
            return b
        if math.isnan(b):
            return a
        return pick(a, b)
    return c_style


_fmin = _ignoring_nan(min)
_fmax = _ignoring_nan(max)


# The generated C calls fabs, fmin and fmax; these must agree with them, NaN included.
def _fmod(a: float, b: float) -> float:
    """C's fmod (exact, the sign of `a`): NaN for an infinite `a` or a zero `b`, where
    Python's math.fmod raises."""
    try:
        return math.fmod(a, b)
    except ValueError:
        return math.nan


_FUNCTIONS = {"abs": abs, "min": _fmin, "max": _fmax, "mod": _fmod}


def evaluate(expr: Expr, sensors: Mapping[str, float], variables: Mapping[str, float]) -> float:
    """Value of an expression with C semantics: true is 1.0, false 0.0, && and || short-circuit.

    `min` and `max` are C's fmin and fmax: a NaN argument (a sensor with no reading) is
    ignored, so `max(depth, 0)` is 0 when depth is NaN; only both NaN gives NaN.
    """
    match expr:
        case Const(value):
            return value
        case SensorRef(name):
            return sensors[name]
        case VarRef(name):
            return variables[name]
        case UnaryOp("-", operand):
            return -evaluate(operand, sensors, variables)
        case UnaryOp("!", operand):
            return float(evaluate(operand, sensors, variables) == 0.0)
        case BinaryOp("&&", left, right):
            return float(evaluate(left, sensors, variables) != 0.0
                         and evaluate(right, sensors, variables) != 0.0)
        case BinaryOp("||", left, right):
            return float(evaluate(left, sensors, variables) != 0.0
                         or evaluate(right, sensors, variables) != 0.0)
        case BinaryOp(op, left, right) if op in _COMPARISONS:
            a, b = evaluate(left, sensors, variables), evaluate(right, sensors, variables)
            return float(_COMPARISONS[op](a, b))
        case BinaryOp(op, left, right):
            a, b = evaluate(left, sensors, variables), evaluate(right, sensors, variables)
            return _ARITHMETIC[op](a, b)
        case FuncCall(function, args):
            return float(_FUNCTIONS[function](*(evaluate(a, sensors, variables) for a in args)))
    raise TypeError(f"not an expression: {expr!r}")


def is_constant(expr: Expr) -> bool:
    """True when the expression reads no sensor and no variable (its value is fixed)."""
    match expr:
        case Const():
            return True
        case UnaryOp(_, operand):
            return is_constant(operand)
        case BinaryOp(_, left, right):
            return is_constant(left) and is_constant(right)
        case FuncCall(_, args):
            return all(is_constant(a) for a in args)
    return False


def sensors_read(expr: Expr) -> frozenset[str]:
    """Names of the sensors an expression reads."""
    match expr:
        case SensorRef(name):
            return frozenset({name})
        case UnaryOp(_, operand):
            return sensors_read(operand)
        case BinaryOp(_, left, right):
            return sensors_read(left) | sensors_read(right)
        case FuncCall(_, args):
            return frozenset().union(*(sensors_read(a) for a in args))
    return frozenset()


def variables_read(expr: Expr) -> frozenset[str]:
    """Names of the variables an expression reads."""
    match expr:
        case VarRef(name):
            return frozenset({name})
        case UnaryOp(_, operand):
            return variables_read(operand)
        case BinaryOp(_, left, right):
            return variables_read(left) | variables_read(right)
        case FuncCall(_, args):
            return frozenset().union(*(variables_read(a) for a in args))
    return frozenset()


# ---- mission structure -------------------------------------------------------------


@dataclass(frozen=True)
class Route:
    """`kind` from the route registry; params SI/DDMM.MMMM as the registry says."""

    kind: str  # nav | noheading | heading | turn | waypoints | sweep | goto_list
    params: tuple[float, ...] = ()
    points: tuple[tuple[float, float], ...] = ()  # (lat, lon) DDMM.MMMM


@dataclass(frozen=True)
class Profile:
    """A flight profile alternative; args may read variables, so they stay expressions."""

    kind: str  # yo | thermotrackyo | surface | hover | cruise | altitude
    args: tuple[Expr, ...]  # without the arguments written `auto` (the last ones)
    # Left out of the canonical JSON when unset: a glider's missions keep their hash.
    auto: tuple[str, ...] = field(default=(), metadata={"omit_default": True})  # `speed`
    # a glider's thruster assisting the profile: its commanded power [W], or "auto"
    thrust: float | str | None = field(default=None, metadata={"omit_default": True})

    @property
    def propelled(self) -> bool:
        """Whether it flies on a propeller (or thruster) rather than on buoyancy alone."""
        return PROFILES[self.kind].propelled or self.thrust is not None

    @property
    def written_thrust_w(self) -> float:
        """The thrust written [W], flown without a plan; 0 for none or `auto` (the planner's
        choice: off without a plan)."""
        return self.thrust if isinstance(self.thrust, float) else 0.0

    @property
    def has_altimeter_stop(self) -> bool:
        """Whether it is given an altimeter stop (a yo's `altitude` argument): the runtime
        then reads the altitude."""
        at = PROFILES[self.kind].index("altitude")
        return at is not None and at < len(self.args)

    def constant_args(self) -> tuple[float, ...] | None:
        """Argument values when none reads a variable or sensor, else None."""
        if not all(is_constant(a) for a in self.args):
            return None
        return tuple(evaluate(a, {}, {}) for a in self.args)


@dataclass(frozen=True)
class SensorUse:
    """A sensor a state logs. duty: None = always on; "auto" = the planner picks; else fixed."""

    name: str
    duty: float | str | None = None


@dataclass(frozen=True)
class Requirement:
    """Per-state bound on one sensor (duty in [0, 1], quality utility in [0, 1])."""

    sensor: str
    duty_min: float = 0.0
    duty_max: float = 1.0
    quality_min: float = 0.0


@dataclass(frozen=True)
class Assign:
    variable: str
    value: Expr


@dataclass(frozen=True)
class Event:
    condition: Expr
    assignments: tuple[Assign, ...] = ()
    action: str | None = None  # goto | call | return | exit | None (assignments only)
    target: str | None = None  # state name for goto and call


@dataclass(frozen=True)
class ComputerUse:
    """A state's power management of the board: `computer clock`, `sleep between ticks`,
    `workload`. The defaults are the mission's: its clock, awake between ticks, the
    runtime's own work."""

    clock_mhz: float | None = None  # a clock the state runs at; None: the mission's
    clock_auto: bool = False  # the planner picks the clock of this state
    sleep: bool = False  # the board sleeps between ticks
    cycles_per_tick: float | None = None  # work every tick [cycles]; None: the runtime's

    @property
    def is_default(self) -> bool:
        return self == NO_COMPUTER_USE


NO_COMPUTER_USE = ComputerUse()


@dataclass(frozen=True)
class State:
    name: str
    route: Route
    profiles: tuple[Profile, ...]  # alternatives; the planner splits time between them
    sensors: tuple[SensorUse, ...]
    events: tuple[Event, ...]
    expect_s: tuple[float, float] | None = None  # bounds on time spent per visit [s]
    requirements: tuple[Requirement, ...] = ()
    # Left out of the canonical JSON when a state says nothing (missions written before
    # power management keep their hash, and with it their plans and builds).
    computer: ComputerUse = field(default=NO_COMPUTER_USE, metadata={"omit_default": True})
    # the line of its `flightprofile` in the mission file, for messages (0: not from one);
    # where it was written does not change the mission: not in its hash
    profile_line: int = field(default=0, metadata={"omit_default": True})

    @property
    def place(self) -> str:
        """The state as a message names it: `s1 (line 6)`, the line of its flightprofile."""
        return f"{self.name} (line {self.profile_line})" if self.profile_line else self.name

    @property
    def profile_variables(self) -> tuple[str, ...]:
        """The variables its profiles' arguments read, sorted."""
        return tuple(sorted(set().union(*(variables_read(a) for p in self.profiles
                                          for a in p.args))))


@dataclass(frozen=True)
class Variable:
    name: str
    initial: float


@dataclass(frozen=True)
class SensorPreference:
    """Mission-wide tradeoff annotation of a sensor: weight in the quality objective, bounds."""

    sensor: str
    weight: float = 1.0
    duty_min: float = 0.0
    duty_max: float = 1.0
    quality_min: float = 0.0


@dataclass(frozen=True)
class Computer:
    board: str  # preset name, path to a board file, or "none" (contract.NO_BOARD)
    clock_mhz: float | None = None  # None: the board's default (or the planner picks)

    @property
    def is_none(self) -> bool:
        """`computer none`: the glider's own computers run the mission, no board is added
        (their power is in the vehicle's base load)."""
        return self.board == NO_BOARD


@dataclass(frozen=True)
class Battery:
    energy_j: float
    reserve_fraction: float = 0.0

    @property
    def reserve_j(self) -> float:
        """[J] the energy left at which the energy guard ends the mission."""
        return self.energy_j * self.reserve_fraction


@dataclass(frozen=True)
class Objective:
    sense: str = "maximize_quality"  # or "minimize_energy"
    quality_floor: float = 0.0


# Defaults for a mission without annotations (the paper's Fig. 2 as is).
DEFAULT_VEHICLE = "slocum_g2_shallow"
DEFAULT_COMPUTER = Computer("ts7800", 300.0)
DEFAULT_BATTERY = Battery(energy_j=7.8e6, reserve_fraction=0.15)  # Slocum alkaline pack


@dataclass(frozen=True)
class CheckedMission:
    name: str
    states: tuple[State, ...]  # states[0] is the start state
    variables: tuple[Variable, ...] = ()
    vehicle: str = DEFAULT_VEHICLE
    computer: Computer = DEFAULT_COMPUTER
    battery: Battery = DEFAULT_BATTERY
    horizon_s: float | None = None
    start_deg: tuple[float, float] | None = None  # (lat, lon): where it is put in the water
    current_correction: bool = True  # heads upstream for the current it measured
    objective: Objective = field(default_factory=Objective)
    sensor_preferences: tuple[SensorPreference, ...] = ()
    stack_depth: int = DEFAULT_STACK_DEPTH
    defaults_used: tuple[str, ...] = ()  # which annotations were defaulted, for reports
    # (field, text as written) of each file the mission names relative to its folder:
    # `vehicle` and `computer.board` hold the path found there; the hash, the text
    files_as_written: tuple[tuple[str, str], ...] = field(default=(),
                                                          metadata={"omit_default": True})

    def state(self, name: str) -> State:
        return self.states[self.state_index[name]]

    def run_limit_s(self, duration_s: float | None = None) -> float:
        """How long [s] a flight or a forecast of the mission runs: `duration_s` when
        given, else the mission's horizon, else DEFAULT_HORIZON_S (30 days)."""
        if duration_s is not None:
            return duration_s
        return self.horizon_s if self.horizon_s is not None else DEFAULT_HORIZON_S

    @cached_property
    def state_index(self) -> dict[str, int]:
        return {s.name: i for i, s in enumerate(self.states)}

    def preference(self, sensor: str) -> SensorPreference:
        for pref in self.sensor_preferences:
            if pref.sensor == sensor:
                return pref
        return SensorPreference(sensor)

    def to_json(self) -> dict:
        """Plain JSON-able form; expression nodes carry an "expr" tag naming their kind."""
        data = _encode(self)
        data["hash"] = self.hash
        return data

    @cached_property
    def hash(self) -> str:
        """SHA-256 (hex) of the canonical JSON, excluding `defaults_used` (not semantic)."""
        data = _encode(self)
        data.pop("defaults_used")
        # missions without a start or with the default correction keep the hash they had
        if data.get("start_deg") is None:
            data.pop("start_deg", None)
        if data.get("current_correction", True):
            data.pop("current_correction", None)
        for state in data["states"]:
            state.pop("profile_line", None)
        for name, text in data.pop("files_as_written", ()):  # where it was checked from
            if name == "computer":                               # does not change it
                data["computer"]["board"] = text
            elif name == "vehicle":
                data["vehicle"] = text
        canonical = json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False)
        import hashlib  # here, not at the top: `gliderplan check` starts faster without it

        return hashlib.sha256(canonical.encode()).hexdigest()


_EXPRESSIONS = (Const, SensorRef, VarRef, UnaryOp, BinaryOp, FuncCall)


def _encode(value: object) -> object:
    if is_dataclass(value):
        data = {f.name: _encode(getattr(value, f.name)) for f in fields(value)
                if not (f.metadata.get("omit_default") and getattr(value, f.name) == f.default)}
        if isinstance(value, _EXPRESSIONS):
            data = {"expr": type(value).__name__, **data}
        return data
    if isinstance(value, tuple | list):
        return [_encode(v) for v in value]
    if isinstance(value, float) and math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return value
