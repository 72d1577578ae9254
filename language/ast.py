"""Typed syntax tree of a mission, as written, with a source span on every node.

Spans do not take part in equality, so two trees compare equal when they say the
same thing (the formatter's round trip relies on it). Values are as written: units
are normalised by the checker, not here.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Span:
    """1-based line and column of the first character, and of the one after the last."""

    line: int
    column: int
    end_line: int
    end_column: int


NO_SPAN = Span(0, 0, 0, 0)


def _span() -> Span:
    return field(default=NO_SPAN, compare=False, repr=False)


@dataclass(frozen=True)
class Ident:
    text: str
    span: Span = _span()


# ---- expressions -------------------------------------------------------------


@dataclass(frozen=True)
class Number:
    value: float
    text: str = field(compare=False)  # as written, e.g. ".454"
    span: Span = _span()


@dataclass(frozen=True)
class Name:
    """A sensor or a variable; the checker decides which."""

    name: str
    span: Span = _span()


@dataclass(frozen=True)
class Unary:
    op: str  # "-" or "!"
    operand: Expr
    span: Span = _span()


@dataclass(frozen=True)
class Binary:
    op: str  # + - * / < <= > >= == != && ||
    left: Expr
    right: Expr
    span: Span = _span()


@dataclass(frozen=True)
class Call:
    function: Ident
    args: tuple[Expr, ...]
    span: Span = _span()


Expr = Number | Name | Unary | Binary | Call


@dataclass(frozen=True)
class Point:
    """A (lat, lon) pair in Slocum DDMM.MMMM notation."""

    lat: Expr
    lon: Expr
    span: Span = _span()


# ---- mission-level declarations ------------------------------------------------


@dataclass(frozen=True)
class Quantity:
    value: float
    text: str = field(compare=False)
    unit: Ident | None = None
    span: Span = _span()


@dataclass(frozen=True)
class VehicleDecl:
    preset: Ident  # a preset name, or a file path written as a string
    is_file: bool
    span: Span = _span()


@dataclass(frozen=True)
class ComputerDecl:
    board: Ident
    is_file: bool
    clock: Quantity | None
    span: Span = _span()


@dataclass(frozen=True)
class BatteryDecl:
    capacity: Quantity
    voltage: Quantity | None
    reserve: Quantity | None
    span: Span = _span()


@dataclass(frozen=True)
class HorizonDecl:
    duration: Quantity
    span: Span = _span()


@dataclass(frozen=True)
class ObjectiveDecl:
    sense: Ident  # maximize | minimize
    target: Ident  # quality | energy
    quality_floor: Number | None
    span: Span = _span()


@dataclass(frozen=True)
class Bound:
    """`weight 3`, `duty >= 0.25` or `quality >= 0.5` on a sensor."""

    kind: str  # weight | duty | quality
    op: str  # "=" for weight, else a comparison
    value: Number
    span: Span = _span()


@dataclass(frozen=True)
class SensorDecl:
    sensor: Ident
    bounds: tuple[Bound, ...]
    span: Span = _span()


@dataclass(frozen=True)
class VarDecl:
    name: Ident
    initial: Expr
    span: Span = _span()


@dataclass(frozen=True)
class StackDecl:
    depth: Number
    span: Span = _span()


Declaration = (
    VehicleDecl
    | ComputerDecl
    | BatteryDecl
    | HorizonDecl
    | ObjectiveDecl
    | SensorDecl
    | VarDecl
    | StackDecl
)

# ---- states --------------------------------------------------------------------


@dataclass(frozen=True)
class Invocation:
    """`nav(3910.5, -7349.8)`, `yo(5, 20, .454, .454)` or a bare `noheading`."""

    name: Ident
    args: tuple[Expr | Point, ...]
    has_parens: bool = field(default=True, compare=False)
    span: Span = _span()


@dataclass(frozen=True)
class RouteItem:
    route: Invocation
    span: Span = _span()


@dataclass(frozen=True)
class ProfileItem:
    """One or more alternatives; the planner splits time between them."""

    alternatives: tuple[Invocation, ...]
    span: Span = _span()


@dataclass(frozen=True)
class SensorUse:
    sensor: Ident
    duty: Number | Ident | None  # a fixed duty, `auto`, or None (always on)
    span: Span = _span()


@dataclass(frozen=True)
class SensorsItem:
    sensors: tuple[SensorUse, ...]
    span: Span = _span()


@dataclass(frozen=True)
class ExpectItem:
    low: Quantity
    high: Quantity
    span: Span = _span()


@dataclass(frozen=True)
class RequireItem:
    sensor: Ident
    bounds: tuple[Bound, ...]
    span: Span = _span()


@dataclass(frozen=True)
class Assignment:
    target: Ident
    value: Expr
    span: Span = _span()


@dataclass(frozen=True)
class Action:
    kind: str  # goto | call | return | exit
    target: Ident | None
    span: Span = _span()


@dataclass(frozen=True)
class Event:
    condition: Expr
    assignments: tuple[Assignment, ...]
    action: Action | None
    span: Span = _span()


@dataclass(frozen=True)
class EventsItem:
    events: tuple[Event, ...]
    span: Span = _span()


StateItem = RouteItem | ProfileItem | SensorsItem | ExpectItem | RequireItem | EventsItem


@dataclass(frozen=True)
class State:
    name: Ident
    items: tuple[StateItem, ...]
    span: Span = _span()


@dataclass(frozen=True)
class Mission:
    name: Ident
    declarations: tuple[Declaration, ...]
    states: tuple[State, ...]
    span: Span = _span()
