"""Typed syntax tree of a mission, as written, with a source span on every node.

Spans do not take part in equality, so two trees compare equal when they say the
same thing (the formatter's round trip relies on it). Values are as written: units
are normalised by the checker, not here.
"""

from __future__ import annotations

from typing import Any, ClassVar, NamedTuple, dataclass_transform


@dataclass_transform(eq_default=True)
class Node:
    """An immutable record: fields are the annotations, in order; a class attribute is
    a default. Equality and hashing ignore `span` and the fields in `_uncompared`
    (spellings such as ".454" for 0.454).

    Lighter than frozen dataclasses, which generate six functions per class: this
    module is imported on every `gliderplan check`, and start-up time matters there.
    """

    _fields: ClassVar[tuple[str, ...]] = ()
    _compared: ClassVar[tuple[str, ...]] = ()
    _uncompared: ClassVar[frozenset[str]] = frozenset()

    def __init_subclass__(cls) -> None:
        fields = tuple(n for n in cls.__dict__.get("__annotations__", {})
                       if not n.startswith("_"))
        cls._fields = fields
        cls.__match_args__ = fields
        cls._compared = tuple(n for n in fields if n != "span" and n not in cls._uncompared)
        defaults = {n: cls.__dict__[n] for n in fields if n in cls.__dict__}
        params = ", ".join(f"{n}=_defaults[{n!r}]" if n in defaults else n for n in fields)
        stores = "".join(f"    fields[{n!r}] = {n}\n" for n in fields)
        namespace: dict[str, Any] = {"_defaults": defaults}
        exec(f"def __init__(self, {params}):\n    fields = self.__dict__\n{stores}", namespace)
        cls.__init__ = namespace["__init__"]

    def _key(self) -> tuple:
        return tuple(getattr(self, n) for n in self._compared)

    def __eq__(self, other: object) -> bool:
        if other.__class__ is not self.__class__:
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash((self.__class__, self._key()))

    def __repr__(self) -> str:
        shown = ", ".join(f"{n}={getattr(self, n)!r}" for n in self._fields if n != "span")
        return f"{type(self).__name__}({shown})"

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"{type(self).__name__} is immutable")


class Span(NamedTuple):
    """1-based line and column of the first character, and of the one after the last.

    A named tuple, not a Node: a large mission has hundreds of thousands of spans, and
    a tuple of four numbers takes half the memory of a record with its own dict."""

    line: int
    column: int
    end_line: int
    end_column: int


NO_SPAN = Span(0, 0, 0, 0)


class Ident(Node):
    text: str
    span: Span = NO_SPAN


# ---- expressions -------------------------------------------------------------


class Number(Node):
    _uncompared = frozenset({"text"})
    value: float
    text: str  # as written, e.g. ".454"
    span: Span = NO_SPAN


class Name(Node):
    """A sensor or a variable; the checker decides which."""

    name: str
    span: Span = NO_SPAN


class Unary(Node):
    op: str  # "-" or "!"
    operand: Expr
    span: Span = NO_SPAN


class Binary(Node):
    op: str  # + - * / < <= > >= == != && ||
    left: Expr
    right: Expr
    span: Span = NO_SPAN


class Call(Node):
    function: Ident
    args: tuple[Expr, ...]
    span: Span = NO_SPAN


Expr = Number | Name | Unary | Binary | Call


class Point(Node):
    """A (lat, lon) pair in Slocum DDMM.MMMM notation."""

    lat: Expr
    lon: Expr
    span: Span = NO_SPAN


# ---- mission-level declarations ------------------------------------------------


class Quantity(Node):
    _uncompared = frozenset({"text"})
    value: float
    text: str
    unit: Ident | None = None
    span: Span = NO_SPAN


class VehicleDecl(Node):
    preset: Ident  # a preset name, or a file path written as a string
    is_file: bool
    span: Span = NO_SPAN


class ComputerDecl(Node):
    board: Ident
    is_file: bool
    clock: Quantity | None
    span: Span = NO_SPAN


class BatteryDecl(Node):
    capacity: Quantity | None  # None for a preset or a file
    voltage: Quantity | None
    reserve: Quantity | None
    span: Span = NO_SPAN
    preset: Ident | None = None  # `battery alkaline`, or a file path written as a string
    is_file: bool = False


class HorizonDecl(Node):
    duration: Quantity
    span: Span = NO_SPAN


class StartDecl(Node):
    lat: Number  # [decimal degrees]
    lon: Number
    span: Span = NO_SPAN


class CorrectionDecl(Node):
    setting: Ident  # on | off
    span: Span = NO_SPAN


class ObjectiveDecl(Node):
    sense: Ident  # maximize | minimize
    target: Ident  # quality | energy
    quality_floor: Number | None
    span: Span = NO_SPAN


class Bound(Node):
    """`weight 3`, `duty >= 0.25` or `quality >= 0.5` on a sensor."""

    kind: str  # weight | duty | quality
    op: str  # "=" for weight, else a comparison
    value: Number
    span: Span = NO_SPAN


class SensorDecl(Node):
    sensor: Ident
    bounds: tuple[Bound, ...]
    span: Span = NO_SPAN


class VarDecl(Node):
    name: Ident
    initial: Expr
    span: Span = NO_SPAN


class StackDecl(Node):
    depth: Number
    span: Span = NO_SPAN


Declaration = (
    VehicleDecl
    | ComputerDecl
    | BatteryDecl
    | HorizonDecl
    | StartDecl
    | CorrectionDecl
    | ObjectiveDecl
    | SensorDecl
    | VarDecl
    | StackDecl
)

# ---- states --------------------------------------------------------------------


class Invocation(Node):
    """`nav(3910.5, -7349.8)`, `yo(5, 20, .454, .454)`, `cruise(10, auto)` (an `auto`
    argument is an Ident) or a bare `noheading`; a profile may carry a thruster setting,
    `yo(...) thrust 3 W` (a Quantity, or the Ident `auto`)."""

    _uncompared = frozenset({"has_parens"})

    name: Ident
    args: tuple[Expr | Point | Ident, ...]
    has_parens: bool = True
    span: Span = NO_SPAN
    thrust: Quantity | Ident | None = None


class RouteItem(Node):
    route: Invocation
    span: Span = NO_SPAN


class ProfileItem(Node):
    """One or more alternatives; the planner splits time between them."""

    alternatives: tuple[Invocation, ...]
    span: Span = NO_SPAN


class SensorUse(Node):
    sensor: Ident
    duty: Number | Ident | None  # a fixed duty, `auto`, or None (always on)
    span: Span = NO_SPAN


class SensorsItem(Node):
    sensors: tuple[SensorUse, ...]
    span: Span = NO_SPAN


class ExpectItem(Node):
    low: Quantity
    high: Quantity
    span: Span = NO_SPAN


class RequireItem(Node):
    sensor: Ident
    bounds: tuple[Bound, ...]
    span: Span = NO_SPAN


class ComputerItem(Node):
    """`computer clock 133 MHz | auto`, `computer sleep between ticks` or `computer
    workload N cycles per tick`: one power-management setting of the state's board."""

    setting: str  # clock | sleep | workload
    value: Quantity | Ident | Number | None  # the clock, `auto`, the cycles; None for sleep
    span: Span = NO_SPAN


class Assignment(Node):
    target: Ident
    value: Expr
    span: Span = NO_SPAN


class Action(Node):
    kind: str  # goto | call | return | exit
    target: Ident | None
    span: Span = NO_SPAN


class Event(Node):
    condition: Expr
    assignments: tuple[Assignment, ...]
    action: Action | None
    span: Span = NO_SPAN


class EventsItem(Node):
    events: tuple[Event, ...]
    span: Span = NO_SPAN


StateItem = (RouteItem | ProfileItem | SensorsItem | ExpectItem | RequireItem | EventsItem
             | ComputerItem)


class State(Node):
    name: Ident
    items: tuple[StateItem, ...]
    span: Span = NO_SPAN


class Mission(Node):
    name: Ident
    declarations: tuple[Declaration, ...]
    states: tuple[State, ...]
    span: Span = NO_SPAN
