"""Each fleet glider's flight: its track over the lines it was given, and the mission (in
the mission language) that flies it.

A glider sweeps its block of lines as a lawn-mower from the end it reaches first, then
back the other way, and so on (ping-pong passes) until it has flown the distance its
battery and the survey's end allow. The track is cut into segments of about one
surfacing interval: each is a state that flies a `waypoints` route and, once all of them
are reached, goes to a surfacing state for the fix and the call. The segments are transit
legs to the planner (planner/README.md, "Transit legs"): their time follows from the
speed it plans, and the mission's horizon (the glider's share of the survey period)
makes it fly fast enough to finish them. The text is checked like any mission
(`language.check_source`) before anything plans or flies it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import MAX_ROUTE_POINTS, MAX_STATES, NO_BOARD
from gliderplan.language.fleet import Fleet, GliderSpec, Part
from gliderplan.language.fleet_geometry import XY, Router

LAUNCH_S = 600.0  # at the surface after it is put in the water: GPS fix, checks [s]
PITCH_RAD = 0.454  # the yo's pitch (the paper's), both ways
MAX_SEGMENTS = MAX_STATES - 3  # states left beside launch and the surfacing state
SEGMENT_POINTS = MAX_ROUTE_POINTS - 1  # a segment's route holds this many points


@dataclass(frozen=True)
class Track:
    """A glider's planned path on the fleet's plane, and when it is where."""

    points: np.ndarray  # (n, 2) [m] east, north: launch position, then every waypoint
    distance_m: np.ndarray  # (n,) along the path from the launch position
    segment_ends: tuple[int, ...]  # index in `points` of each segment's last waypoint
    speed_mps: float  # effective speed over the path (turns included) [m/s]
    surface_every_s: float
    surface_stay_s: float
    start_offset_s: float  # its start after the fleet's [s]
    first_pass_m: float  # distance at which every line of its block has been flown once
    line_visits: dict[int, tuple[float, ...]]  # part index -> distances of its midpoint

    def time_at(self, distance_m) -> np.ndarray:
        """Time [s after the glider's start] at which it reaches `distance_m`: the launch,
        the flight, and a stay at the surface after every finished segment."""
        d = np.asarray(distance_m, float)
        ends = self.distance_m[list(self.segment_ends)]
        stays = np.searchsorted(ends, d, side="left")  # segments finished before d
        return LAUNCH_S + d / self.speed_mps + stays * self.surface_stay_s

    @property
    def length_m(self) -> float:
        return float(self.distance_m[-1])

    @property
    def duration_s(self) -> float:
        """From its start until it has flown the whole track and surfaced [s]."""
        return float(self.time_at(self.length_m)) + self.surface_stay_s

    def first_coverage_s(self) -> float:
        """When every line of its block has been flown once [s after the fleet's start]."""
        return self.start_offset_s + float(self.time_at(self.first_pass_m))

    def samples(self, spacing_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(time [s after the fleet's start], east, north [m]) every `spacing_m` along the
        track after the launch: the profiles that map the field, thinned."""
        d = np.arange(spacing_m / 2.0, self.length_m, spacing_m)
        x = np.interp(d, self.distance_m, self.points[:, 0])
        y = np.interp(d, self.distance_m, self.points[:, 1])
        return self.start_offset_s + self.time_at(d), x, y

    def position_at(self, fleet_time_s) -> tuple[np.ndarray, np.ndarray]:
        """(east, north) [m] at fleet times [s]: at its launch point before it starts,
        at the track's end once it has flown it (surfaced for recovery)."""
        t = np.asarray(fleet_time_s, float) - self.start_offset_s
        grid = np.linspace(0.0, self.length_m, max(2, int(self.length_m / 200.0)))
        times = self.time_at(grid)
        d = np.interp(t, times, grid, left=0.0, right=self.length_m)
        return (np.interp(d, self.distance_m, self.points[:, 0]),
                np.interp(d, self.distance_m, self.points[:, 1]))


def block_order(parts: list[Part], entry_last: bool) -> list[Part]:
    """The block's lines in the order the first pass flies them."""
    return list(reversed(parts)) if entry_last else list(parts)


def build_track(glider: GliderSpec, block: list[Part], entry_last: bool, distance_m: float,
                speed_mps: float, fleet: Fleet, router: Router) -> Track:
    """The path of `glider` from its launch point over `block` (parts in survey order,
    entered at its last line when `entry_last`), ping-pong passes until `distance_m` [m]
    (where the battery or the survey's end stops it, even within the first pass), cut into
    segments of about one surfacing interval at `speed_mps` (effective [m/s]) and at most
    SEGMENT_POINTS points."""
    lines = block_order(block, entry_last)
    points: list[XY] = [glider.start]
    visits: dict[int, list[float]] = {p.index: [] for p in block}
    travelled = 0.0

    def go(to: XY) -> None:
        nonlocal travelled
        for point in router.path(points[-1], to)[1:]:
            travelled += math.dist(points[-1], point)
            points.append(point)

    first_pass = None
    forward = True
    while True:
        sweep = lines if forward else list(reversed(lines))
        for group in _same_line(sweep):
            # the pieces of one line (a keep-out cuts it) flown from its nearer end on
            ends = [group[0].a, group[0].b, group[-1].a, group[-1].b]
            if min(math.dist(points[-1], e) for e in ends[2:]) < \
                    min(math.dist(points[-1], e) for e in ends[:2]):
                group = list(reversed(group))
            for part in group:
                near, far = (part.a, part.b) if math.dist(points[-1], part.a) <= \
                    math.dist(points[-1], part.b) else (part.b, part.a)
                go(near)
                mid = travelled + 0.5 * part.length_m
                go(far)
                visits[part.index].append(mid)
        if first_pass is None:
            first_pass = travelled
        forward = not forward
        if travelled >= distance_m or len(lines) == 0:
            break
    path = np.asarray(points, float)
    cumulative = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])
    end = distance_m
    path, cumulative = _cut(path, cumulative, end)
    path, cumulative = _densify(path, cumulative, speed_mps * fleet.surface_every_s)
    every = fleet.surface_every_s
    while True:
        ends = _segments(cumulative, speed_mps * every)
        if len(ends) <= MAX_SEGMENTS:
            break
        every *= 1.25  # a survey too long for the mission's states: surface less often
    return Track(path, cumulative, tuple(ends), speed_mps, every, fleet.surface_stay_s,
                 glider.start_offset_s, first_pass,
                 {k: tuple(d for d in v if d <= end) for k, v in visits.items()})


def _same_line(parts: list[Part]) -> list[list[Part]]:
    """Consecutive parts grouped by the line they lie on."""
    groups: list[list[Part]] = []
    for part in parts:
        if groups and groups[-1][-1].line == part.line:
            groups[-1].append(part)
        else:
            groups.append([part])
    return groups


def _cut(path: np.ndarray, cumulative: np.ndarray, end_m: float):
    """The path up to `end_m` along it (a point added where it ends)."""
    if end_m >= cumulative[-1]:
        return path, cumulative
    keep = int(np.searchsorted(cumulative, end_m, side="right"))
    point = np.array([np.interp(end_m, cumulative, path[:, 0]),
                      np.interp(end_m, cumulative, path[:, 1])])
    return np.vstack([path[:keep], point]), np.concatenate([cumulative[:keep], [end_m]])


def _densify(path: np.ndarray, cumulative: np.ndarray, longest_m: float):
    """Waypoints added along legs longer than `longest_m`, so that a segment can end
    within one surfacing interval on a line of any length."""
    points, distances = [path[0]], [cumulative[0]]
    for i in range(1, len(path)):
        leg = cumulative[i] - cumulative[i - 1]
        pieces = max(1, math.ceil(leg / max(longest_m, 1.0) - 1e-9))
        for k in range(1, pieces):
            f = k / pieces
            points.append(path[i - 1] + f * (path[i] - path[i - 1]))
            distances.append(cumulative[i - 1] + f * leg)
        points.append(path[i])
        distances.append(cumulative[i])
    return np.asarray(points), np.asarray(distances)


def _segments(cumulative: np.ndarray, interval_m: float) -> list[int]:
    """Index of each segment's last point: a segment ends at the first waypoint at or
    beyond one surfacing interval of flight, or at SEGMENT_POINTS points."""
    ends, first = [], 1
    for i in range(1, len(cumulative)):
        if cumulative[i] - cumulative[first - 1] >= interval_m - 1e-6 \
                or i - first + 1 >= SEGMENT_POINTS or i == len(cumulative) - 1:
            ends.append(i)
            first = i + 1
    return ends


# ---- the mission text --------------------------------------------------------------------

def _ddmm(degrees: float) -> str:
    """Slocum DDMM.MMMM of decimal degrees, to 0.0001 min (0.2 m)."""
    from gliderplan.sim.geo import degrees_to_ddmm

    return f"{degrees_to_ddmm(degrees):.4f}"


def _point(fleet: Fleet, xy) -> str:
    lat, lon = fleet.projection.to_latlon(xy[0], xy[1])
    return f"({_ddmm(float(lat))}, {_ddmm(float(lon))})"


def hardware_lines(glider: GliderSpec) -> list[str]:
    """The glider's vehicle, board and what is left of its battery, in mission syntax:
    the charge left as the battery, the reserve (a share of the rating) as its share of
    that, so the energy guard ends the mission where the fleet file says."""
    vehicle = glider.vehicle if _preset(glider.vehicle) else f'"{glider.vehicle}"'
    board = glider.computer.board if _preset(glider.computer.board) \
        else f'"{glider.computer.board}"'
    clock = f" @ {glider.computer.clock_mhz:g} MHz" if glider.computer.clock_mhz and \
        glider.computer.board != NO_BOARD else ""
    energy = glider.battery.energy_j * glider.charge
    reserve = 100.0 * glider.battery.reserve_fraction / glider.charge
    return [f"vehicle {vehicle}", f"computer {board}{clock}",
            f"battery {energy:.6g} J reserve {reserve:.6g} %"]


def _preset(name: str) -> bool:
    return name.replace("_", "").isalnum()


def mission_text(name: str, glider: GliderSpec, fleet: Fleet, band: tuple[float, float],
                 track: Track, horizon_s: float, header: str) -> str:
    """The mission that flies `track`: launch, one state per segment, the surfacing
    state; `band` (min, max) [m] the yo; `horizon_s` [s] the glider's share of the
    survey; `header` the comment at its top."""
    sensors = ", ".join(f"{s.name}" + (f" duty {s.duty:g}" if s.duty < 1.0 else "")
                        for s in fleet.goal.sensors)
    yo = f"yo({band[0]:g}, {band[1]:g}, {PITCH_RAD:g}, {PITCH_RAD:g})"
    lines = [f"# {line}" if line else "#" for line in header.splitlines()]
    lines += [f"mission {name}", "", *hardware_lines(glider),
              f"horizon {horizon_s:.0f} s", "",
              "var fix_until = 0   # end of the current surfacing [s]",
              "var next = 1        # the segment to fly after it", "",
              "state launch", "begin", f"  flightroute nav{_point(fleet, track.points[0])}",
              "  flightprofile surface", "  sensors missiontime, depth, lat, lon", "  events",
              f"    case missiontime >= {LAUNCH_S:g} goto seg1", "end"]
    first = 1
    for k, last in enumerate(track.segment_ends, start=1):
        route = ", ".join(_point(fleet, p) for p in track.points[first:last + 1])
        count = last - first + 1
        lines += ["", f"state seg{k}", "begin", f"  flightroute waypoints({route})",
                  f"  flightprofile {yo}",
                  f"  sensors missiontime, depth, wptreached, lat, lon, {sensors}", "  events",
                  f"    case wptreached >= {count} set fix_until = missiontime + "
                  f"{track.surface_stay_s:g}, next = {k + 1} goto fix", "end"]
        first = last + 1
    segments = len(track.segment_ends)
    lines += ["", "state fix", "begin", "  flightroute noheading", "  flightprofile surface",
              "  sensors missiontime, depth, lat, lon", "  events"]
    lines += [f"    case missiontime >= fix_until && next == {k} goto seg{k}"
              for k in range(2, segments + 1)]
    lines += ["    case missiontime >= fix_until exit", "end", ""]
    return "\n".join(lines)
