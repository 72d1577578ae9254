"""Transit legs: how far a state's route takes the glider.

A state that flies toward waypoints and that no missiontime guard or `expect` bound
ends is a transit leg: it lasts as long as the glider needs to cover its route, so its
time follows from the planned speed. Its length runs from where the previous route
left the glider (or from its own first waypoint) through its waypoints, with the
equirectangular approximation the pilot uses for short distances.
"""

from __future__ import annotations

import math

from gliderplan.contract import EARTH_RADIUS_M
from gliderplan.language import ir

Position = tuple[float, float]  # (lat, lon) [deg]


def ddmm_to_degrees(x: float) -> float:
    """Slocum DDMM.MMMM to decimal degrees."""
    a = abs(x)
    return math.copysign(math.floor(a / 100.0) + math.fmod(a, 100.0) / 60.0, x)


def route_targets(route: ir.Route) -> list[Position]:
    """The points [deg] a route flies to, in order; none for routes without a goal."""
    if route.kind == "nav":
        return [(ddmm_to_degrees(route.params[0]), ddmm_to_degrees(route.params[1]))]
    if route.kind == "waypoints":
        return [(ddmm_to_degrees(lat), ddmm_to_degrees(lon)) for lat, lon in route.points]
    return []


def offset_m(a: Position, b: Position) -> tuple[float, float]:
    """(north, east) [m] from `a` to the nearby `b` [deg] (equirectangular about `a`)."""
    scale = EARTH_RADIUS_M * math.pi / 180.0
    return (b[0] - a[0]) * scale, (b[1] - a[1]) * scale * math.cos(math.radians(a[0]))


def distance_m(a: Position, b: Position) -> float:
    """Distance [m] between two nearby points [deg] (equirectangular about `a`)."""
    return math.hypot(*offset_m(a, b))


def leg_length_m(start: Position | None, targets: list[Position]) -> float | None:
    """Length [m] of the path from `start` through `targets`; None when it is unknown
    (no targets, or a start that is unknown and a single target)."""
    path = ([start] if start is not None else []) + targets
    if len(path) < 2:
        return None
    return sum(distance_m(a, b) for a, b in zip(path, path[1:], strict=False))
