"""The vocabulary a mission may use: sensors, flight profiles, flight routes, functions.

Adding a sensor, profile or route is one entry here (and, for the runtime, one
library routine): the grammar never changes. Each sensor has a fixed index: the
position of its value in the science computer's sensor array, shared by the C
runtime, the serial protocol and the simulator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class SensorInfo:
    """A value the glider measures, readable in conditions and loggable in `sensors`."""

    name: str
    index: int  # position in the sensor array (protocol and runtime)
    unit: str  # SI unit of the value
    device: str | None  # power-model device that produces it; None: flight sensor, in hotel load
    description: str


# Order is the sensor-array layout; append only, never reorder (it is a wire format).
SENSORS: tuple[SensorInfo, ...] = (
    SensorInfo("missiontime", 0, "s", None, "time since the mission started"),
    SensorInfo("depth", 1, "m", None, "depth below the surface, positive down"),
    SensorInfo("pitch", 2, "rad", None, "vehicle pitch, positive nose up"),
    SensorInfo("roll", 3, "rad", None, "vehicle roll"),
    SensorInfo("heading", 4, "rad", None, "magnetic heading"),
    SensorInfo("altitude", 5, "m", None, "height above the sea floor"),
    SensorInfo("lat", 6, "DDMM.MMMM", None, "latitude, Slocum degrees and minutes"),
    SensorInfo("lon", 7, "DDMM.MMMM", None, "longitude, Slocum degrees and minutes"),
    SensorInfo("battery", 8, "V", None, "battery voltage"),
    SensorInfo("temp", 9, "degC", "ctd", "water temperature (CTD)"),
    SensorInfo("conductivity", 10, "S/m", "ctd", "water conductivity (CTD)"),
    SensorInfo("salinity", 11, "PSU", "ctd", "practical salinity (CTD)"),
    SensorInfo("oxygen", 12, "umol/kg", "optode", "dissolved oxygen (optode)"),
    SensorInfo("chlorophyll", 13, "ug/l", "optics", "chlorophyll fluorescence (optics)"),
    SensorInfo("backscatter", 14, "1/m", "optics", "optical backscatter (optics)"),
    SensorInfo("current", 15, "m/s", "adcp", "water current speed (ADCP)"),
    SensorInfo("modem", 16, "B", "modem", "bytes received by the acoustic modem"),
)
SENSOR_BY_NAME: dict[str, SensorInfo] = {s.name: s for s in SENSORS}


@dataclass(frozen=True)
class ParamSpec:
    """One argument of a profile or route, with the range it must lie in."""

    name: str
    unit: str
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False  # True: low itself is not allowed
    high_open: bool = False


@dataclass(frozen=True)
class ProfileInfo:
    """A flight profile: a vertical pattern flown by the glider's library routine."""

    name: str
    params: tuple[ParamSpec, ...]
    description: str
    tracks_thermocline: bool = False


_DEPTH = dict(unit="m", low=0.0)
_PITCH = dict(unit="rad", low=0.0, high=math.pi / 2, low_open=True, high_open=True)

PROFILES: dict[str, ProfileInfo] = {
    p.name: p
    for p in (
        ProfileInfo(
            "yo",
            (
                ParamSpec("min_depth", **_DEPTH),
                ParamSpec("max_depth", **_DEPTH),
                ParamSpec("dive_pitch", **_PITCH),
                ParamSpec("climb_pitch", **_PITCH),
            ),
            "dive and climb between two depths",
        ),
        ProfileInfo(
            "thermotrackyo",
            (
                ParamSpec("min_depth", **_DEPTH),
                ParamSpec("max_depth", **_DEPTH),
                ParamSpec("dive_pitch", **_PITCH),
                ParamSpec("climb_pitch", **_PITCH),
                ParamSpec("temp_threshold", unit="degC", low=0.0, low_open=True),
                ParamSpec("depth_threshold", unit="m", low=0.0, low_open=True),
            ),
            "yo whose depth band follows the thermocline",
            tracks_thermocline=True,
        ),
        ProfileInfo("surface", (), "stay at the surface (GPS fix, Iridium)"),
        ProfileInfo(
            "hover",
            (ParamSpec("depth", **_DEPTH),),
            "hold a depth with small buoyancy corrections",
        ),
    )
}


@dataclass(frozen=True)
class RouteInfo:
    """A horizontal route. `points` counts (lat, lon) pairs in DDMM.MMMM notation."""

    name: str
    params: tuple[ParamSpec, ...]  # scalar arguments, before any points
    min_points: int
    max_points: int
    description: str


_LAT = dict(unit="DDMM.MMMM", low=-9000.0, high=9000.0)
_LON = dict(unit="DDMM.MMMM", low=-18000.0, high=18000.0)

ROUTES: dict[str, RouteInfo] = {
    r.name: r
    for r in (
        RouteInfo(
            "nav",
            (ParamSpec("lat", **_LAT), ParamSpec("lon", **_LON)),
            0,
            0,
            "fly toward one waypoint",
        ),
        RouteInfo("noheading", (), 0, 0, "no horizontal goal: hold no heading"),
        RouteInfo("waypoints", (), 1, 64, "fly a list of (lat, lon) waypoints in order"),
        RouteInfo(
            "sweep",
            (ParamSpec("spacing", unit="m", low=0.0, low_open=True),),
            3,
            32,
            "lawn-mower sweep of the convex hull of (lat, lon) corner points",
        ),
    )
}

# Functions usable in conditions and assignments: name -> argument count.
FUNCTIONS: dict[str, int] = {"abs": 1, "min": 2, "max": 2}
