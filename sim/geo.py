"""Positions on the sphere as the pilot sees them (docs/pilot.md, Routes): Slocum
DDMM.MMMM, decimal degrees, and the equirectangular approximation for short distances."""

from __future__ import annotations

import math

from gliderplan.contract import EARTH_RADIUS_M

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
