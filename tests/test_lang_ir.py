"""Expression evaluation in the checked-mission IR agrees with the C runtime's arithmetic."""

from __future__ import annotations

import ctypes
import ctypes.util
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from gliderplan.language import ir

NAN = math.nan


def _call(function: str, *values: float) -> float:
    return ir.evaluate(ir.FuncCall(function, tuple(ir.Const(v) for v in values)), {}, {})


@pytest.mark.parametrize(
    ("function", "a", "b", "expected"),
    [
        ("min", 1.0, 2.0, 1.0),
        ("max", 1.0, 2.0, 2.0),
        ("min", NAN, 2.0, 2.0),
        ("min", 2.0, NAN, 2.0),
        ("max", NAN, -3.0, -3.0),
        ("max", -3.0, NAN, -3.0),
        ("min", -math.inf, NAN, -math.inf),
        ("max", math.inf, 1.0, math.inf),
    ],
)
def test_min_max_ignore_a_nan_argument_like_fmin_fmax(function, a, b, expected):
    assert _call(function, a, b) == expected


@pytest.mark.parametrize("function", ["min", "max"])
def test_min_max_of_two_nans_is_nan(function):
    assert math.isnan(_call(function, NAN, NAN))


def test_nan_sensor_reading_is_ignored_inside_a_condition():
    # max(depth, 5) > 4 holds while the depth sensor has no reading (NaN).
    condition = ir.BinaryOp(">", ir.FuncCall("max", (ir.SensorRef("depth"), ir.Const(5.0))),
                            ir.Const(4.0))
    assert ir.evaluate(condition, {"depth": NAN}, {}) == 1.0


def _libm() -> ctypes.CDLL | None:
    name = ctypes.util.find_library("m")
    if name is None:
        return None
    lib = ctypes.CDLL(name)
    for function in (lib.fmin, lib.fmax):
        function.restype = ctypes.c_double
        function.argtypes = (ctypes.c_double, ctypes.c_double)
    return lib


_LIBM = _libm()
_DOUBLES = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.just(NAN))


@pytest.mark.skipif(_LIBM is None, reason="no C maths library to compare with")
@given(a=_DOUBLES, b=_DOUBLES)
def test_min_max_agree_with_the_c_library(a, b):
    for function, c_function in (("min", _LIBM.fmin), ("max", _LIBM.fmax)):
        ours, theirs = _call(function, a, b), c_function(a, b)
        if math.isnan(theirs):
            assert math.isnan(ours)
        else:
            assert ours == theirs
