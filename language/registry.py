"""The vocabulary a mission may use: sensors, flight profiles, flight routes, functions.

Adding a profile or route is one entry here (and, for the runtime, one library
routine): the grammar never changes. Sensors are one entry each too, in
`gliderplan.contract.SENSORS`: their order is the science computer's sensor array,
shared by the C runtime, the serial protocol and the simulator.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gliderplan.contract import MAX_ROUTE_POINTS, SENSORS, SensorInfo

__all__ = ["FUNCTIONS", "PROFILES", "ROUTES", "SENSORS", "SENSOR_BY_NAME", "ParamSpec",
           "ProfileInfo", "RouteInfo", "SensorInfo"]

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
    optional: bool = False  # may be left out (only the last arguments of a profile)


@dataclass(frozen=True)
class ProfileInfo:
    """A flight profile: a vertical pattern flown by the glider's library routine."""

    name: str
    params: tuple[ParamSpec, ...]
    description: str
    tracks_thermocline: bool = False
    propelled: bool = False  # flown on a propeller or a glider's thruster, not on buoyancy

    @property
    def required(self) -> int:
        """How many of its arguments a profile must be given."""
        return sum(not p.optional for p in self.params)

    def index(self, name: str) -> int | None:
        """Position of the argument called `name`, or None."""
        return next((i for i, p in enumerate(self.params) if p.name == name), None)


_DEPTH = dict(unit="m", low=0.0)
_PITCH = dict(unit="rad", low=0.0, high=math.pi / 2, low_open=True, high_open=True)
# A propelled profile's speed through the water: a number, or `auto` (the planner's choice)
_SPEED = ParamSpec("speed", unit="m/s", low=0.0, low_open=True)
AUTO_PARAMS = frozenset({"speed"})  # the arguments a mission may write as `auto`
# Slocum's d_target_altitude: a dive also turns when the altimeter reads at most this
# height above the sea floor; left out or 0: no altimeter stop
_ALTITUDE = ParamSpec("altitude", unit="m", low=0.0, optional=True)

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
                _ALTITUDE,
            ),
            "dive and climb between two depths (a dive also turns at `altitude` above "
            "the sea floor)",
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
                _ALTITUDE,
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
        ProfileInfo(
            "cruise",
            (ParamSpec("depth", **_DEPTH), _SPEED),
            "fly level at a depth and a speed through the water on the propeller (or a "
            "glider's thruster)",
            propelled=True,
        ),
        ProfileInfo(
            "altitude",
            (ParamSpec("height", unit="m", low=0.0, low_open=True), _SPEED),
            "fly level at a height above the sea floor (the altimeter's reading) and a "
            "speed through the water on the propeller",
            propelled=True,
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
        RouteInfo(
            "heading",
            (ParamSpec("heading", unit="deg", low=0.0, high=360.0, high_open=True),),
            0,
            0,
            "hold a compass heading (true, clockwise from north), uncorrected for the "
            "current: Slocum's set_heading",
        ),
        RouteInfo(
            "turn",
            (ParamSpec("rate", unit="deg/s", low=-180.0, high=180.0),),
            0,
            0,
            "turn steadily from the heading at the state's entry, positive clockwise (a "
            "spiral): Slocum's set_heading holding its fin",
        ),
        RouteInfo("waypoints", (), 1, MAX_ROUTE_POINTS,
                  "fly a list of (lat, lon) waypoints in order"),
        RouteInfo(
            "sweep",
            (ParamSpec("spacing", unit="m", low=0.0, low_open=True),),
            3,
            MAX_ROUTE_POINTS,  # the runtime's route table, whose hull it sweeps
            "lawn-mower sweep of the convex hull of (lat, lon) corner points",
        ),
        RouteInfo(
            "goto_list",
            (ParamSpec("radius", unit="m", low=0.0, low_open=True),),
            1,
            MAX_ROUTE_POINTS,
            "Slocum's goto list: (lat, lon) waypoints in order, each reached within radius, "
            "flown again and again",
        ),
    )
}


def held_heading_rad(heading_deg: float) -> float:
    """[rad] the heading a `heading(deg)` route holds: the runtime is given this value
    (codegen_c) and the Python pilot holds it, so both fly the same number."""
    return math.radians(heading_deg)


def turn_rate_rad_s(rate_deg_s: float) -> float:
    """[rad/s] the rate a `turn(deg/s)` route turns at: the runtime is given this value
    (codegen_c) and the Python pilot turns at it, so both fly the same number."""
    return math.radians(rate_deg_s)


def cannot_fly(kind: str, thrust: object, vehicle: object) -> tuple[str, str, bool] | None:
    """(why, hint, whether the thrust is to blame) when `vehicle`
    (power_models.vehicle.Vehicle) cannot fly profile `kind` with a thruster setting
    `thrust` (None: none): a propelled profile without propulsion,
    a buoyancy profile without a buoyancy engine, a thrust without a thruster."""
    name, propulsion = vehicle.name, vehicle.propulsion
    if PROFILES[kind].propelled and propulsion is None:
        return (f"'{kind}' flies on a propeller, and vehicle {name} is a {vehicle.kind} "
                "without one", "fly a yo, or declare a propelled vehicle, e.g. 'vehicle "
                "slocum_g3_hybrid' or 'vehicle lauv'", False)
    if not PROFILES[kind].propelled and kind != "surface" and \
            not vehicle.has_buoyancy_engine:
        return (f"'{kind}' flies on a buoyancy engine, and vehicle {name} is an "
                f"{vehicle.kind} without one",
                "fly it level on the propeller, e.g. 'cruise(10, auto)'", False)
    if thrust is not None and (propulsion is None or not propulsion.is_thruster):
        return (f"vehicle {name} has no thruster to assist a yo", "leave 'thrust' out, or "
                "declare a hybrid, e.g. 'vehicle slocum_g3_hybrid'", True)
    return None


def altitude_stop_m(kind: str, args: tuple[float, ...]) -> float:
    """[m] the height above the sea floor at which a yo's dive turns (its `altitude`
    argument), 0 where it has none (no altimeter stop); NaN stays NaN."""
    info = PROFILES.get(kind)
    at = None if info is None else info.index("altitude")
    return args[at] if at is not None and at < len(args) else 0.0


# Functions usable in conditions and assignments: name -> argument count.
FUNCTIONS: dict[str, int] = {"abs": 1, "min": 2, "max": 2, "mod": 2}
