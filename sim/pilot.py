"""The runtime's library routines in Python, exactly as docs/pilot.md specifies them:
flight profiles (yo, thermotrackyo, surface, hover; on a propeller cruise, altitude),
routes (nav, noheading, heading, turn, waypoints, sweep, goto_list) and the plan's schedule (sensor
power windows, profile alternation).

Each routine is a small object with the pilot's memory (leg, tracked band, waypoint
index) that is re-created on entry, and a per-tick method on plain floats: the
simulator calls it 650 000 times in a 30-day run.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from gliderplan.contract import (
    EARTH_RADIUS_M,
    MAX_SWEEP_WAYPOINTS,
    SURFACE_PITCH_RAD,
    THERMOTRACKYO_ALTITUDE_ARG,
    TRACK_WINDOW,
    WAYPOINT_RADIUS_M,
    YO_ALTITUDE_ARG,
)
from gliderplan.language.registry import held_heading_rad, turn_rate_rad_s
from gliderplan.sim.geo import bearing_rad, ddmm_to_degrees, offset_m

if TYPE_CHECKING:  # the plan reader pulls in the planner (cvxpy): only when a plan is flown
    from gliderplan.planner.planfile import StatePlan

DIVE, CLIMB = 0, 1


# ---- flight profiles -----------------------------------------------------------------
# command(d, temp, args, pitch, ballast, altitude) -> (depth_target_m, pitch_rad,
# ballast_cc, surface); `pitch` replaces the profile's own pitch arguments when a plan
# gives one; `altitude` is the altimeter's reading [m] (NaN: no floor in its range).

def at_altimeter_stop(args: tuple[float, ...], at: int, altitude_m: float) -> bool:
    """Whether a yo's dive turns on the altimeter: its `altitude` argument (at index `at`;
    left out or <= 0: no stop) is positive and the reading at or below it (a NaN reading
    never is)."""
    return len(args) > at and args[at] > 0.0 and altitude_m <= args[at]


class Yo:
    """yo(min, max, dive_pitch, climb_pitch[, altitude]). `halfcycle`: the leg flown, 1
    the first. A dive turns at `max`, or where the altimeter reads `altitude` or less."""

    ALTITUDE_AT = YO_ALTITUDE_ARG

    def __init__(self, depth_m: float, args: tuple[float, ...],
                 altitude_m: float = math.nan) -> None:
        self.leg = DIVE if depth_m < args[1] and not at_altimeter_stop(
            args, self.ALTITUDE_AT, altitude_m) else CLIMB
        self.halfcycle = 1

    def command(self, d: float, temp: float, args: tuple[float, ...], pitch: float | None,
                ballast: float, altitude: float = math.nan
                ) -> tuple[float, float, float, bool]:
        low, high = args[0], args[1]
        if self.leg == DIVE and (d >= high or at_altimeter_stop(args, YO_ALTITUDE_ARG,
                                                                altitude)):
            self.leg = CLIMB
            self.halfcycle += 1
        elif self.leg == CLIMB and d <= low:
            self.leg = DIVE
            self.halfcycle += 1
        return _yo_command(self.leg, low, high, args, pitch, ballast)


def _yo_command(leg: int, low: float, high: float, args: tuple[float, ...],
                pitch: float | None, ballast: float) -> tuple[float, float, float, bool]:
    if leg == DIVE:
        return high, -(args[2] if pitch is None else pitch), -ballast, False
    return low, (args[3] if pitch is None else pitch), ballast, False


class ThermoTrackYo:
    """thermotrackyo(min, max, dive_pitch, climb_pitch, temp_threshold, depth_threshold[,
    altitude]): a yo whose band follows the thermocline (robust or naive detection), its
    dives turning at the altimeter stop as yo's.

    Each tick: first the leg turns at the band's edge (a leg that turns without a
    detection resets the band), then the reading, which belongs to the leg now flown,
    is compared with the leg's window and, if it detects nothing, joins the window.
    """

    ALTITUDE_AT = THERMOTRACKYO_ALTITUDE_ARG

    def __init__(self, depth_m: float, args: tuple[float, ...], robust: bool = True,
                 altitude_m: float = math.nan) -> None:
        self.robust = robust
        self.low, self.high = args[0], args[1]
        self.halfcycle = 1
        self._new_leg(DIVE if depth_m < args[1] and not at_altimeter_stop(
            args, self.ALTITUDE_AT, altitude_m) else CLIMB)

    def _new_leg(self, leg: int) -> None:
        self.leg = leg
        self.window: list[tuple[float, float]] = []  # (depth [m], temperature [degC])
        self.recent: list[float] = []  # robust: the leg's last 3 raw temperatures
        self.previous = math.nan  # naive: the leg's previous raw temperature
        self.detected = False

    def command(self, d: float, temp: float, args: tuple[float, ...], pitch: float | None,
                ballast: float, altitude: float = math.nan
                ) -> tuple[float, float, float, bool]:
        leg = self.leg
        if leg == DIVE and (d >= self.high or at_altimeter_stop(
                args, THERMOTRACKYO_ALTITUDE_ARG, altitude)):
            leg = CLIMB
        elif leg == CLIMB and d <= self.low:
            leg = DIVE
        if leg != self.leg:
            if not self.detected:  # the thermocline was lost: search the whole range
                self.low, self.high = args[0], args[1]
            self._new_leg(leg)
            self.halfcycle += 1
        if math.isfinite(d) and math.isfinite(temp):  # no reading: nothing to learn from
            self._track(d, temp, args)
        return _yo_command(self.leg, self.low, self.high, args, pitch, ballast)

    def _track(self, d: float, temp: float, args: tuple[float, ...]) -> None:
        if self.robust:
            temp, a = self._detect_robust(d, temp, args)
        else:
            a = self._detect_naive(d, temp, args)
        if a is None:
            if len(self.window) == TRACK_WINDOW:
                del self.window[0]
            self.window.append((d, temp))
            return
        z = (a[0] + d) / 2.0
        half = args[5] / 2.0
        self.low, self.high = max(args[0], z - half), min(args[1], z + half)
        self.window = []
        self.detected = True

    def _detect_robust(self, d: float, temp: float, args: tuple[float, ...]
                       ) -> tuple[float, tuple[float, float] | None]:
        """(median-filtered temperature, the window's reading that detects, or None)."""
        recent = self.recent
        if len(recent) == 3:
            del recent[0]
        recent.append(temp)
        if len(recent) == 3:
            filtered = sorted(recent)[1]
        elif len(recent) == 2:
            filtered = (recent[0] + recent[1]) / 2.0
        else:
            filtered = temp
        self.window = window = [r for r in self.window if abs(r[0] - d) <= args[5]]
        if not window:
            return filtered, None
        warmest = max(window, key=lambda r: r[1])
        coldest = min(window, key=lambda r: r[1])
        warm_diff, cold_diff = abs(warmest[1] - filtered), abs(coldest[1] - filtered)
        a = coldest if cold_diff > warm_diff else warmest
        return filtered, (a if max(warm_diff, cold_diff) >= args[4] else None)

    def _detect_naive(self, d: float, temp: float, args: tuple[float, ...]
                      ) -> tuple[float, float] | None:
        previous, self.previous = self.previous, temp
        if previous == previous and (temp > previous if self.leg == DIVE else temp < previous):
            self.window = []
        for a in self.window:
            if abs(a[1] - temp) >= args[4] and abs(a[0] - d) <= args[5]:
                return a
        return None


class Surface:
    halfcycle = 0

    def __init__(self, depth_m: float, args: tuple[float, ...],
                 altitude_m: float = math.nan) -> None:
        pass

    def command(self, d: float, temp: float, args: tuple[float, ...], pitch: float | None,
                ballast: float, altitude: float = math.nan
                ) -> tuple[float, float, float, bool]:
        return 0.0, SURFACE_PITCH_RAD, ballast, True


class Hover:
    halfcycle = 0

    def __init__(self, depth_m: float, args: tuple[float, ...],
                 altitude_m: float = math.nan) -> None:
        pass

    def command(self, d: float, temp: float, args: tuple[float, ...], pitch: float | None,
                ballast: float, altitude: float = math.nan
                ) -> tuple[float, float, float, bool]:
        return args[0], 0.0, 0.0, False


class Cruise(Hover):
    """cruise(depth, speed): level at `depth` on the propeller (`propelled_speed`); its
    command is a hover's, at zero pitch and ballast."""

    propelled = True


class Altitude(Cruise):
    """altitude(height, speed): level where the altimeter reads `height`; with no floor in
    its range (a NaN reading) the floor lies deeper: down by `height`."""

    def command(self, d: float, temp: float, args: tuple[float, ...], pitch: float | None,
                ballast: float, altitude: float = math.nan
                ) -> tuple[float, float, float, bool]:
        target = d + args[0] if math.isnan(altitude) else d + altitude - args[0]
        return target if target > 0.0 else 0.0, 0.0, 0.0, False  # a NaN depth: the surface


def propelled_speed(args: tuple[float, ...], planned_mps: float | None,
                    unplanned_mps: float) -> float:
    """[m/s] a propelled profile's speed: the plan's; without a plan its speed argument, or
    `unplanned_mps` where it is written `auto` (left out of `args`) or is not positive."""
    if planned_mps is not None:
        return planned_mps
    return args[1] if len(args) > 1 and args[1] > 0.0 else unplanned_mps


# Flown with a thruster's assist (`yo(...) thrust`): the yos.
ASSISTED = frozenset({"yo", "thermotrackyo"})
PROFILE_ROUTINES = {"yo": Yo, "thermotrackyo": ThermoTrackYo, "surface": Surface,
                    "hover": Hover, "cruise": Cruise, "altitude": Altitude}


# ---- routes ----------------------------------------------------------------------------

def length_m(north_m: float, east_m: float) -> float:
    """The length [m] of an offset: sqrt(north^2 + east^2), each operation rounded once
    (not math.hypot, whose last bit differs from the C library's)."""
    return math.sqrt(north_m * north_m + east_m * east_m)


class NoHeading:
    k = 0  # no waypoint: nothing to resume
    reached = 0  # waypoints reached (the runtime's `wptreached`): never one
    holds = False  # whether its heading is held uncorrected for the current

    def __init__(self, params: tuple[float, ...], points: tuple[tuple[float, float], ...]):
        pass

    def heading(self, lat_ddmm: float, lon_ddmm: float) -> tuple[float, bool]:
        return 0.0, False

    def distance_m(self, lat_ddmm: float, lon_ddmm: float) -> float:
        return math.nan


class Heading:
    """heading(deg): a compass heading held as it is, with or without a position fix;
    the glider's current correction leaves it alone (FLAG_HEADING_HOLD): Slocum's
    set_heading. No waypoint: nothing to reach or resume."""

    k = 0
    reached = 0
    holds = True

    def __init__(self, params: tuple[float, ...], points: tuple[tuple[float, float], ...]):
        self.heading_rad = held_heading_rad(params[0])

    def heading(self, lat_ddmm: float, lon_ddmm: float) -> tuple[float, bool]:
        return self.heading_rad, True

    def distance_m(self, lat_ddmm: float, lon_ddmm: float) -> float:
        return math.nan


class Turn:
    """turn(deg/s): the heading measured at the state's entry, advanced at a steady rate
    (positive clockwise), held as it is like `heading`'s: a spiral, Slocum's set_heading
    holding its fin. No heading measured at entry: no heading. Its heading depends on
    the time since entry (`turned`), not on the position. Nothing to reach or resume."""

    k = 0
    reached = 0
    holds = True

    def __init__(self, params: tuple[float, ...], points: tuple[tuple[float, float], ...]):
        self.rate_rad_s = turn_rate_rad_s(params[0])
        self.from_rad = math.nan  # the heading measured at entry, set by `enter`

    def distance_m(self, lat_ddmm: float, lon_ddmm: float) -> float:
        return math.nan

    def enter(self, heading_rad: float) -> None:
        self.from_rad = heading_rad

    def turned(self, t_in_s: float) -> tuple[float, bool]:
        """(heading [rad], valid) `t_in_s` after entry, as the runtime's gp_route_turn."""
        if not (math.isfinite(self.from_rad) and math.isfinite(t_in_s)):
            return 0.0, False
        heading = math.fmod(self.from_rad + self.rate_rad_s * t_in_s, 2.0 * math.pi)
        return (heading + 2.0 * math.pi if heading < 0.0 else heading), True


class Waypoints:
    """Toward points[k]; k advances (one per tick) within `radius_m`; after the last,
    hold the heading to it (a goto list starts again from the first). `reached` counts
    the waypoints reached: each advance, and the last of a list that does not loop once."""

    radius_m = WAYPOINT_RADIUS_M
    loops = False
    holds = False
    arrives = True  # False: a heading only, no waypoint is ever reached (nav)

    def __init__(self, params: tuple[float, ...], points: tuple[tuple[float, float], ...]):
        self.points = [(ddmm_to_degrees(a), ddmm_to_degrees(b)) for a, b in points]
        self.k = 0
        self.reached = 0

    def _advances(self) -> bool:
        """Whether reaching the waypoint flown to moves on to another."""
        return self.loops or self.k + 1 < len(self.points)

    def may_reach(self) -> bool:
        """Whether reaching the waypoint flown to would count (advance, or end the list).
        A list that does not loop reaches one waypoint per advance, so it has reached its
        last once it has reached more than its index."""
        return self.arrives and (self._advances() or self.reached <= self.k)

    def distance_m(self, lat_ddmm: float, lon_ddmm: float) -> float:
        """Distance [m] to the waypoint flown to; NaN without a position or a waypoint."""
        if not (math.isfinite(lat_ddmm) and math.isfinite(lon_ddmm)) or not self.points:
            return math.nan
        north, east = offset_m(ddmm_to_degrees(lat_ddmm), ddmm_to_degrees(lon_ddmm),
                               *self.points[self.k])
        return length_m(north, east)

    def heading(self, lat_ddmm: float, lon_ddmm: float) -> tuple[float, bool]:
        if not (math.isfinite(lat_ddmm) and math.isfinite(lon_ddmm)):
            return 0.0, False
        lat, lon = ddmm_to_degrees(lat_ddmm), ddmm_to_degrees(lon_ddmm)
        north, east = offset_m(lat, lon, *self.points[self.k])
        if length_m(north, east) <= self.radius_m and self.may_reach():
            self.reached += 1
            if self._advances():
                self.k = (self.k + 1) % len(self.points)
                north, east = offset_m(lat, lon, *self.points[self.k])
        return bearing_rad(north, east), True


class Nav(Waypoints):
    arrives = False  # a heading toward the point, every tick

    def __init__(self, params: tuple[float, ...], points: tuple[tuple[float, float], ...]):
        super().__init__((), ((params[0], params[1]),))


class GotoList(Waypoints):
    """goto_list(radius, points...): Slocum's goto list, each point reached within
    `radius` [m], the list flown again and again."""

    loops = True

    def __init__(self, params: tuple[float, ...], points: tuple[tuple[float, float], ...]):
        super().__init__((), points)
        self.radius_m = params[0]


class Sweep(Waypoints):
    """Lawn-mower over the convex hull of the corners, flown as waypoints."""

    def __init__(self, params: tuple[float, ...], points: tuple[tuple[float, float], ...]):
        self.points = sweep_waypoints(params[0], points)
        self.k = 0
        self.reached = 0


def _hull(points: list[tuple[float, float]]) -> list[tuple[float, float]]:
    """Convex hull (Andrew's monotone chain), counter-clockwise."""
    pts = sorted(points)
    if len(pts) < 3:
        return pts

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    upper: list[tuple[float, float]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return lower[:-1] + upper[:-1]


def sweep_waypoints(spacing_m: float,
                    corners: tuple[tuple[float, float], ...]) -> list[tuple[float, float]]:
    """Waypoints [deg] of east-west lines `spacing_m` apart across the corners' hull."""
    lat0, lon0 = ddmm_to_degrees(corners[0][0]), ddmm_to_degrees(corners[0][1])
    local = []
    for lat_ddmm, lon_ddmm in corners:
        north, east = offset_m(lat0, lon0, ddmm_to_degrees(lat_ddmm), ddmm_to_degrees(lon_ddmm))
        local.append((east, north))
    hull = _hull(local)
    south = min(p[1] for p in hull)
    north_edge = max(p[1] for p in hull)
    scale = EARTH_RADIUS_M * math.pi / 180.0
    east_scale = scale * math.cos(lat0 * math.pi / 180.0)
    waypoints: list[tuple[float, float]] = []
    line = 0
    while len(waypoints) + 2 <= MAX_SWEEP_WAYPOINTS:
        y = south + spacing_m / 2.0 + line * spacing_m
        ends = _clip(hull, y)
        if y > north_edge or ends is None:
            break
        west, east = ends
        first, second = (west, east) if line % 2 == 0 else (east, west)
        lat = lat0 + y / scale
        waypoints += [(lat, lon0 + first / east_scale), (lat, lon0 + second / east_scale)]
        line += 1
    return waypoints


def _clip(hull: list[tuple[float, float]], y: float) -> tuple[float, float] | None:
    """West and east ends [m] of the hull's cut at northing `y` [m], or None."""
    xs: list[float] = []
    for i, a in enumerate(hull):
        b = hull[(i + 1) % len(hull)]
        if a[1] == b[1]:
            if a[1] == y:
                xs += [a[0], b[0]]
        elif min(a[1], b[1]) <= y <= max(a[1], b[1]):
            xs.append(a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]))
    return (min(xs), max(xs)) if xs else None


ROUTE_ROUTINES = {"nav": Nav, "noheading": NoHeading, "heading": Heading, "turn": Turn,
                  "waypoints": Waypoints, "sweep": Sweep, "goto_list": GotoList}


# ---- the plan's schedule ---------------------------------------------------------------

def profile_index(state_plan: StatePlan | None, t_in_s: float, unplanned: int = 0) -> int:
    """Alternative flown `t_in_s` [s] after entry: shares of the cycle in index order;
    the last alternative with a non-zero share takes any rounding remainder. Without a
    plan, `unplanned`."""
    if state_plan is None:
        return unplanned
    cycle = state_plan.cycle_s
    c = math.fmod(t_in_s, cycle)
    start = 0.0
    last = 0
    for i, p in enumerate(state_plan.profiles):
        if p.share > 0.0:
            last = i
            if start <= c < start + p.share * cycle:
                return i
        start += p.share * cycle
    return last


def sensor_power_mask(logged: tuple[tuple[int, float, float], ...], t_in_s: float) -> int:
    """Bit i set if sensor i's device is powered: `logged` holds (index, period, on) with
    period 0 for sensors always on (unscheduled or without a device)."""
    mask = 0
    for index, period_s, on_s in logged:
        if period_s == 0.0 or math.fmod(t_in_s, period_s) < on_s:
            mask |= 1 << index
    return mask
