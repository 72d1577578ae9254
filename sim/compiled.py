"""Conditions and profile arguments compiled to Python functions, for speed.

`ir.evaluate` walks the expression tree on every call; the executor checks a state's
events 650 000 times in a 30-day run, so each state's event list becomes one Python
function over the sensor array `s` (registry indices) and the variables `v`. The
generated code computes what `ir.evaluate` computes (comparisons and logic as 0/1,
IEEE division); tests compare the two on every example.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from gliderplan.language import ir
from gliderplan.language.registry import SENSOR_BY_NAME

SensorArray = Sequence[float]
Variables = Mapping[str, float]


def python_source(expr: ir.Expr) -> str:
    """A Python expression equal in value (as a number) to `ir.evaluate(expr, ...)`."""
    match expr:
        case ir.Const(value):
            return f"{float(value)!r}"
        case ir.SensorRef(name):
            return f"s[{SENSOR_BY_NAME[name].index}]"
        case ir.VarRef(name):
            return f"v[{name!r}]"
        case ir.UnaryOp("-", operand):
            return f"(-{python_source(operand)})"
        case ir.UnaryOp("!", operand):
            return f"({python_source(operand)} == 0.0)"
        case ir.BinaryOp("&&" | "||" as op, left, right):
            joined = "and" if op == "&&" else "or"
            return f"(({python_source(left)} != 0.0) {joined} ({python_source(right)} != 0.0))"
        case ir.BinaryOp("/", left, right):
            return f"_divide({python_source(left)}, {python_source(right)})"
        case ir.BinaryOp(op, left, right) if op in ir._COMPARISONS:
            return f"({python_source(left)} {op} {python_source(right)})"
        case ir.BinaryOp(op, left, right):
            return f"({python_source(left)} {op} {python_source(right)})"
        case ir.FuncCall(function, args):
            return f"{function}({', '.join(python_source(a) for a in args)})"
    raise TypeError(f"not an expression: {expr!r}")


# the reference's own functions: min and max are C's fmin and fmax (a NaN is ignored)
_GLOBALS = {"_divide": ir._divide, "__builtins__": {**ir._FUNCTIONS, "float": float}}


def event_checker(state: ir.State) -> Callable[[SensorArray, Variables], int]:
    """f(s, v) -> index of the first event whose condition holds, or -1."""
    lines = ["def first_fired(s, v):"]
    for i, event in enumerate(state.events):
        lines.append(f"    if {python_source(event.condition)} != 0.0: return {i}")
    lines.append("    return -1")
    namespace: dict = {}
    exec("\n".join(lines), dict(_GLOBALS), namespace)  # noqa: S102 - source built above
    return namespace["first_fired"]


def arguments(profile: ir.Profile) -> Callable[[SensorArray, Variables], tuple[float, ...]]:
    """f(s, v) -> the profile's argument values as floats."""
    items = "".join(f"float({python_source(a)}), " for a in profile.args)
    namespace: dict = {}
    exec(f"def args(s, v): return ({items})", dict(_GLOBALS), namespace)  # noqa: S102
    return namespace["args"]
