"""Positions on the sphere as the pilot sees them (docs/pilot.md, Routes): Slocum
DDMM.MMMM, decimal degrees, and the equirectangular approximation for short distances."""

from __future__ import annotations

import math

import numpy as np

from gliderplan.contract import EARTH_RADIUS_M
from gliderplan.sim import libm

TWO_PI = 2.0 * math.pi
_RAD = math.pi / 180.0


def ddmm_to_degrees(x: float) -> float:
    """Slocum DDMM.MMMM to decimal degrees: sign(x) (floor(|x|/100) + fmod(|x|, 100)/60)."""
    a = abs(x)
    return math.copysign(math.floor(a / 100.0) + math.fmod(a, 100.0) / 60.0, x)


def degrees_to_ddmm(x: float) -> float:
    """Decimal degrees to Slocum DDMM.MMMM."""
    a = abs(x)
    whole = math.floor(a)
    return math.copysign(whole * 100.0 + (a - whole) * 60.0, x)


def offset_m(lat1: float, lon1: float, lat2: float, lon2: float) -> tuple[float, float]:
    """(north, east) [m] from point 1 to point 2 [deg], equirectangular about point 1."""
    scale = EARTH_RADIUS_M * math.pi / 180.0  # evaluated as the C runtime does, bit for bit
    return (lat2 - lat1) * scale, (lon2 - lon1) * scale * math.cos(lat1 * math.pi / 180.0)


def move_degrees(lat_deg: float, lon_deg: float, north_m: float,
                 east_m: float) -> tuple[float, float]:
    """Position [deg] after moving `north_m`, `east_m` [m] (the inverse of offset_m)."""
    lat = lat_deg + north_m / (EARTH_RADIUS_M * _RAD)
    lon = lon_deg + east_m / (EARTH_RADIUS_M * math.cos(lat_deg * _RAD) * _RAD)
    return lat, lon


def bearing_rad(north_m: float, east_m: float) -> float:
    """Heading [rad] clockwise from north in [0, 2 pi)."""
    heading = math.atan2(east_m, north_m)
    return heading + TWO_PI if heading < 0.0 else heading


# ---- the same, element by element over arrays (the fast executor's), bit for bit -------

def ddmm_to_degrees_array(x: np.ndarray) -> np.ndarray:
    a = np.abs(x)
    return np.copysign(np.floor(a / 100.0) + np.fmod(a, 100.0) / 60.0, x)


def degrees_to_ddmm_array(x: np.ndarray) -> np.ndarray:
    a = np.abs(x)
    whole = np.floor(a)
    return np.copysign(whole * 100.0 + (a - whole) * 60.0, x)


def offset_m_array(lat1: np.ndarray, lon1: np.ndarray, lat2: float,
                   lon2: float) -> tuple[np.ndarray, np.ndarray]:
    scale = EARTH_RADIUS_M * math.pi / 180.0
    return (lat2 - lat1) * scale, (lon2 - lon1) * scale * libm.cos(lat1 * math.pi / 180.0)


def bearing_rad_array(north_m: np.ndarray, east_m: np.ndarray) -> np.ndarray:
    heading = libm.atan2(east_m, north_m)
    return np.where(heading < 0.0, heading + TWO_PI, heading)


def bearing_binary32_array(north_m: np.ndarray, east_m: np.ndarray) -> np.ndarray:
    """`bearing_rad_array` rounded to binary32 (as a COMMAND carries a heading), bit for
    bit, at numpy's speed where numpy's atan2 is not the C library's: numpy's value is
    used where no binary32 rounding boundary lies within (8 x its largest error seen on
    the probe + 8) units in the last place of it, the C library's everywhere else, and
    near 0 and pi, where the sign decides the turn."""
    error = libm.numpy_error_ulps("atan2")
    if error == 0.0:
        return _binary32(bearing_rad_array(north_m, east_m))
    heading = np.arctan2(east_m, north_m)
    bearing = np.where(heading < 0.0, heading + TWO_PI, heading)
    reach = (8.0 * error + 8.0) * np.spacing(bearing)
    unsure = (_binary32(bearing - reach) != _binary32(bearing + reach)) \
        | (np.abs(heading) < 1e-6) | (np.pi - np.abs(heading) < 1e-6)
    rounded = _binary32(bearing)
    if unsure.any():
        at = unsure.nonzero()[0]
        rounded[at] = _binary32(bearing_rad_array(north_m[at], east_m[at]))
    return rounded


def _binary32(x: np.ndarray) -> np.ndarray:
    return x.astype(np.float32).astype(np.float64)
