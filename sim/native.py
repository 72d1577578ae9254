"""The simulator's C loops (sim/native.c, built with gliderplan), called through ctypes.

Each gives, bit for bit, what the Python reference computes one tick at a time (native.c
says how). Arrays are float64 and contiguous; every output is allocated here.
"""

from __future__ import annotations

import ctypes
import importlib.util

import numpy as np

from gliderplan.contract import EARTH_RADIUS_M


def _load(path: str | None = None) -> ctypes.CDLL:
    """The library built with the package (`path`: another build of native.c)."""
    if path is None:
        spec = importlib.util.find_spec("gliderplan.sim._native")
        if spec is None or not spec.origin:
            raise ImportError("gliderplan's C loops (sim/native.c) are not built: "
                              "install gliderplan again (pip install -e .)")
        path = spec.origin
    library = ctypes.CDLL(path)
    pointer, count, real, flag = ctypes.c_void_p, ctypes.c_long, ctypes.c_double, ctypes.c_int
    signatures = {
        "gpn_sin": (None, [pointer, pointer, count]),
        "gpn_cos": (None, [pointer, pointer, count]),
        "gpn_tanh": (None, [pointer, pointer, count]),
        "gpn_atan2": (None, [pointer, pointer, pointer, count]),
        "gpn_lag": (None, [pointer, count, real, real, pointer]),
        "gpn_squeezed_yo": (count, [pointer, pointer, count, real, real, pointer, count, real,
                                    pointer, pointer, pointer, flag, count, pointer, pointer,
                                    pointer]),
        "gpn_route": (count, [pointer, real, flag, pointer, count, count, real, pointer, real,
                              pointer, pointer]),
    }
    for name, (result, arguments) in signatures.items():
        function = getattr(library, name)
        function.restype, function.argtypes = result, arguments
    return library


_C = _load()


def _doubles(x: np.ndarray | float) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=np.float64)


def _address(x: np.ndarray, offset: int = 0) -> int:
    return x.__array_interface__["data"][0] + 8 * offset


def _unary(function, x: np.ndarray) -> np.ndarray:
    x = _doubles(x)
    out = np.empty(x.shape)
    function(_address(x), _address(out), x.size)
    return out


def sin(x: np.ndarray) -> np.ndarray:
    return _unary(_C.gpn_sin, x)


def cos(x: np.ndarray) -> np.ndarray:
    return _unary(_C.gpn_cos, x)


def tanh(x: np.ndarray) -> np.ndarray:
    return _unary(_C.gpn_tanh, x)


def atan2(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    y, x = (_doubles(a) for a in np.broadcast_arrays(y, x))
    out = np.empty(y.shape)
    _C.gpn_atan2(_address(y), _address(x), _address(out), y.size)
    return out


def first_order_lag(water_c: np.ndarray, before_c: float, keep: float) -> np.ndarray:
    """The CTD's lagged temperature each tick: c[i] = w[i] + (c[i-1] - w[i]) keep (c = w
    where the one before is NaN), from `before_c` [degC]."""
    water_c = _doubles(water_c)
    lagged = np.empty(len(water_c))
    _C.gpn_lag(_address(water_c), len(water_c), before_c, keep, _address(lagged))
    return lagged


def squeezed_yo(glides: list[tuple[np.ndarray, int]], weight: float, squeeze: float,
                noise: np.ndarray, near: tuple[float, float], edge: tuple[float, float],
                dive: bool, count: int, depth_m: float,
                lift: tuple[tuple[float, ...], float] | None = None
                ) -> tuple[np.ndarray, np.ndarray, bool]:
    """A compressible hull's yo from `depth_m` (native.c's `gpn_squeezed_yo`; `glides`:
    each glide's rows and settled row; `near`, `edge`: climbing, diving; `lift`: the
    water's buoyancy table [cc] and its step [m], vehicle.Stratification's, None in
    uniform water): (each leg's first tick and ticks, the depths before each tick and after
    the last of them, whether the run stops before a tick that would clamp at the
    surface)."""
    rows = (ctypes.c_void_p * 3)(*(_address(r) for r, _ in glides))
    settled = (ctypes.c_long * 3)(*(n for _, n in glides))
    noise, bounds = _doubles(noise), _doubles((*near, *edge))
    table = _doubles(lift[0] if lift is not None else (0.0,))
    n_lift, step = (len(table), lift[1]) if lift is not None else (0, 1.0)
    depths = np.empty(count + 1)
    depths[0] = depth_m
    legs = np.empty((count + 1, 2), np.dtype("l"))  # C's long
    stop = ctypes.c_int()
    n = _C.gpn_squeezed_yo(rows, settled, len(glides), weight, squeeze, _address(table),
                           n_lift, step, _address(noise), _address(bounds), _address(bounds, 2),
                           dive, count, _address(depths), _address(legs), ctypes.byref(stop))
    flown = int(legs[n - 1].sum()) if n else 0
    return legs[:n], depths[:flown + 1], bool(stop.value)


def route(target: tuple[float, float], reach_m: float, advance: bool, distance_m: np.ndarray,
          fix_at: int, tick_s: float, current_mps: tuple[float, float],
          start: tuple[float, float, float, float]) -> tuple[int, np.ndarray, np.ndarray]:
    """Ticks toward one waypoint [deg] (native.c's `gpn_route`): (the ticks flown before
    the one that may reach it, or all; the heading of each [rad, binary32]; positions
    [deg]: dead-reckoned lat, lon, true lat, lon, rows of count + 1, before each tick and
    after the last). `current_mps`: toward the north and the east."""
    distance_m = _doubles(distance_m)
    count = len(distance_m)
    positions = np.empty((4, count + 1))
    positions[:, 0] = start
    heading = np.empty(count)
    target_deg, current = _doubles(target), _doubles(current_mps)
    flown = _C.gpn_route(_address(target_deg), reach_m, advance, _address(distance_m), count,
                         fix_at, tick_s, _address(current), EARTH_RADIUS_M, _address(positions),
                         _address(heading))
    return flown, heading, positions
