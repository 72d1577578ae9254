"""Conditions and profile arguments compiled to Python functions, for speed.

`ir.evaluate` walks the expression tree on every call; the executor checks a state's
events 650 000 times in a 30-day run, so each state's event list becomes one Python
function over the sensor array `s` (registry indices) and the variables `v`. The
generated code computes what `ir.evaluate` computes (comparisons and logic as 0/1,
IEEE division); tests compare the two on every example.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from gliderplan.language import ir
from gliderplan.language.registry import SENSOR_BY_NAME

SensorArray = Sequence[float]
Variables = Mapping[str, float]


def python_source(expr: ir.Expr, arrays: bool = False) -> str:
    """A Python expression equal in value (as a number) to `ir.evaluate(expr, ...)`; with
    `arrays`, over numpy arrays of readings, element by element (comparisons and logic
    give 0/1 floats through `_truth`, so that arithmetic on them stays arithmetic)."""
    def source(e: ir.Expr) -> str:
        return python_source(e, arrays)

    def truth(text: str) -> str:
        return f"_truth({text})" if arrays else f"({text})"

    match expr:
        case ir.Const(value):
            return f"{float(value)!r}"
        case ir.SensorRef(name):
            return f"s[{SENSOR_BY_NAME[name].index}]"
        case ir.VarRef(name):
            return f"v[{name!r}]"
        case ir.UnaryOp("-", operand):
            return f"(-{source(operand)})"
        case ir.UnaryOp("!", operand):
            return truth(f"{source(operand)} == 0.0")
        case ir.BinaryOp("&&" | "||" as op, left, right):
            joined = {"&&": "&" if arrays else "and", "||": "|" if arrays else "or"}[op]
            return truth(f"({source(left)} != 0.0) {joined} ({source(right)} != 0.0)")
        case ir.BinaryOp("/", left, right):
            return f"_divide({source(left)}, {source(right)})"
        case ir.BinaryOp(op, left, right) if op in ir._COMPARISONS:
            return truth(f"{source(left)} {op} {source(right)}")
        case ir.BinaryOp(op, left, right):
            return f"({source(left)} {op} {source(right)})"
        case ir.FuncCall(function, args):
            return f"{function}({', '.join(source(a) for a in args)})"
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


def _fmin(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """ir's fmin element by element: a NaN is ignored; `min` picks as Python's does."""
    return np.where(np.isnan(a), b, np.where(np.isnan(b), a, np.where(b < a, b, a)))


def _fmax(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.where(np.isnan(a), b, np.where(np.isnan(b), a, np.where(b > a, b, a)))


def _divide_arrays(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IEEE division, which `ir._divide` spells out for Python floats."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.true_divide(a, b)


def _fmod_arrays(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """ir's mod (C's fmod) element by element: NaN for an infinite `a` or a zero `b`."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.fmod(a, b)


_ARRAY_GLOBALS = {"_divide": _divide_arrays, "_truth": lambda b: np.asarray(b, np.float64),
                  "np": np,
                  "__builtins__": {"abs": np.abs, "min": _fmin, "max": _fmax,
                                   "mod": _fmod_arrays, "float": float}}


def sensors_read(exprs: Sequence[ir.Expr]) -> frozenset[int]:
    """Indices of the sensors the expressions read."""
    found: set[int] = set()

    def visit(e: ir.Expr) -> None:
        match e:
            case ir.SensorRef(name):
                found.add(SENSOR_BY_NAME[name].index)
            case ir.UnaryOp(_, operand):
                visit(operand)
            case ir.BinaryOp(_, left, right):
                visit(left)
                visit(right)
            case ir.FuncCall(_, args):
                for a in args:
                    visit(a)

    for expr in exprs:
        visit(expr)
    return frozenset(found)


def truth_source(expr: ir.Expr) -> str:
    """Over numpy arrays of readings: a boolean expression, element by element whether
    `ir.evaluate(expr, ...) != 0.0` (comparisons and logic stay booleans)."""
    match expr:
        case ir.UnaryOp("!", operand):
            return f"np.logical_not({truth_source(operand)})"
        case ir.BinaryOp("&&" | "||" as op, left, right):
            return f"({truth_source(left)} {'&' if op == '&&' else '|'} {truth_source(right)})"
        case ir.BinaryOp(op, left, right) if op in ir._COMPARISONS:
            return f"({python_source(left, True)} {op} {python_source(right, True)})"
    return f"({python_source(expr, True)} != 0.0)"


def firing_ticks(events: Sequence[ir.Event]
                 ) -> Callable[[Mapping[int, np.ndarray], Variables, int], np.ndarray]:
    """f(s, v, n) -> for each of n ticks, whether any of the events fires: `s` maps each
    sensor they read to its n readings, `v` holds the variables."""
    lines = ["def fires(s, v, n):", "    any_ = np.zeros(n, np.bool_)"]
    for event in events:
        lines.append(f"    any_ |= {truth_source(event.condition)}")
    lines.append("    return any_")
    namespace: dict = {}
    exec("\n".join(lines), dict(_ARRAY_GLOBALS), namespace)  # noqa: S102 - source built above
    return namespace["fires"]


def value_ticks(expr: ir.Expr) -> Callable[[Mapping[int, np.ndarray], Variables, int],
                                         np.ndarray]:
    """f(s, v, n) -> the expression's value on each of n ticks, element by element what
    `ir.evaluate` gives: `s` maps each sensor it reads to its n readings."""
    source = f"np.broadcast_to(np.asarray({python_source(expr, True)}, np.float64), (n,))"
    namespace: dict = {}
    exec(f"def value(s, v, n): return {source}", dict(_ARRAY_GLOBALS), namespace)  # noqa: S102
    return namespace["value"]


def arguments(profile: ir.Profile) -> Callable[[SensorArray, Variables], tuple[float, ...]]:
    """f(s, v) -> the profile's argument values as floats."""
    items = "".join(f"float({python_source(a)}), " for a in profile.args)
    namespace: dict = {}
    exec(f"def args(s, v): return ({items})", dict(_GLOBALS), namespace)  # noqa: S102
    return namespace["args"]
