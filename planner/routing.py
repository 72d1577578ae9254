"""Current-aware routes: the headings that take a glider through a current field to each
waypoint in the least time, against the straight line to it.

A glider at speed u [m s-1] through the water, making good the direction d over the
ground in a current c, holds the heading that cancels the current across d (as its
current correction does); its speed over the ground is c.d + sqrt(u^2 - (c x d)^2), and
it cannot make good d where the current across is faster than u or carries it back
faster than it flies. Each leg is searched on a grid of `cells` x `cells` points over the
leg's box (widened by `MARGIN` of its length on each side) with the 16 directions of
moves of one and two cells (`scipy.sparse.csgraph.dijkstra`); the field is taken at the
leg's start time. The route is the grid path's turning points; both routes' times are
integrated along them with the same step (`STEP_M`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract.units import finite_or_none
from gliderplan.sim.currents import CurrentField
from gliderplan.sim.geo import EARTH_RADIUS_M

MARGIN = 0.5  # [1] of a leg's length the grid reaches beyond its box, each side
STEP_M = 100.0  # [m] a route's time is integrated over steps this long
CAPTURE_M = 1000.0  # [m] a transit's waypoint is reached within this (a dive's length)
SURFACING_S = 1200.0  # [s] a transit's climb, GPS fix and call (sim: 135 s + 206 s)
SURFACE_EVERY_S = 7200.0  # [s] a transit surfaces this often for a fix
TRANSIT_BAND_M = (3.0, 30.0)  # [m] a transit's yo
TRANSIT_PITCH_RAD = 0.454  # a transit's yo pitch unless a route chooses another
_M_PER_DEG = EARTH_RADIUS_M * math.pi / 180.0
_MOVES = [(di, dj) for di in (-2, -1, 0, 1, 2) for dj in (-2, -1, 0, 1, 2)
          if (di, dj) != (0, 0) and math.gcd(abs(di), abs(dj)) == 1]


class NoRoute(ValueError):
    """No route reaches a waypoint: the current holds the glider off it."""


@dataclass(frozen=True)
class Leg:
    """One leg: the straight line and the planned route to a waypoint."""

    waypoint: tuple[float, float]  # (lat, lon) [deg]
    straight_s: float  # [s] along the straight line (inf: the current holds it off)
    planned_s: float  # [s] along the planned route
    route: tuple[tuple[float, float], ...]  # the planned route's points after the start


@dataclass(frozen=True)
class RoutePlan:
    legs: tuple[Leg, ...]

    @property
    def straight_s(self) -> float:
        return sum(leg.straight_s for leg in self.legs)

    @property
    def planned_s(self) -> float:
        return sum(leg.planned_s for leg in self.legs)

    @property
    def gain(self) -> float:
        """[1] the time saved over the straight route, of the straight route's time."""
        return 1.0 - self.planned_s / self.straight_s if math.isfinite(self.straight_s) \
            else 1.0

    def waypoints(self) -> list[tuple[float, float]]:
        """The planned route's points (lat, lon) [deg], every leg's, in order."""
        return [p for leg in self.legs for p in leg.route]

    def to_json(self) -> dict:
        return {"straight_s": finite_or_none(self.straight_s), "planned_s": self.planned_s,
                "gain": self.gain,
                "legs": [{"waypoint": list(leg.waypoint),
                          "straight_s": finite_or_none(leg.straight_s),
                          "planned_s": leg.planned_s, "route": [list(p) for p in leg.route]}
                         for leg in self.legs]}



def ground_speed(north_mps: np.ndarray, east_mps: np.ndarray, course_rad: np.ndarray,
                 speed_mps: float) -> np.ndarray:
    """[m s-1] over the ground along `course_rad` of a glider at `speed_mps` through the
    water holding its course in the current; NaN where it cannot make it good."""
    dn, de = np.cos(course_rad), np.sin(course_rad)
    along = north_mps * dn + east_mps * de
    across = east_mps * dn - north_mps * de
    room = speed_mps ** 2 - across ** 2
    with np.errstate(invalid="ignore"):
        v = along + np.sqrt(room)
    return np.where((room > 0.0) & (v > 1e-3), v, np.nan)


def path_time_s(field: CurrentField, points: list[tuple[float, float]], epoch_s: float,
                speed_mps: float) -> float:
    """[s] to fly the polyline `points` (lat, lon) [deg] holding each segment's course
    (inf where the current holds the glider off it)."""
    total = 0.0
    for (lat1, lon1), (lat2, lon2) in zip(points, points[1:], strict=False):
        north = (lat2 - lat1) * _M_PER_DEG
        east = (lon2 - lon1) * _M_PER_DEG * math.cos(math.radians((lat1 + lat2) / 2))
        length = math.hypot(north, east)
        if length == 0.0:
            continue
        n = max(1, math.ceil(length / STEP_M))
        f = (np.arange(n) + 0.5) / n
        cn, ce = field.along(lat1 + f * (lat2 - lat1), lon1 + f * (lon2 - lon1), epoch_s)
        v = ground_speed(np.nan_to_num(cn), np.nan_to_num(ce),
                         np.full(n, math.atan2(east, north)), speed_mps)
        if np.any(~np.isfinite(v)):
            return math.inf
        total += float(np.sum(length / n / v))
    return total


def plan_route(field: CurrentField, start: tuple[float, float],
               waypoints: list[tuple[float, float]], epoch_s: float, speed_mps: float,
               cells: int = 100) -> RoutePlan:
    """The least-time route through `field` from `start` to each waypoint in turn (lat,
    lon) [deg], at `speed_mps` through the water; NoRoute where none reaches one."""
    legs = []
    here, clock = start, epoch_s
    for waypoint in waypoints:
        route = _search(field, here, waypoint, clock, speed_mps, cells)
        planned = path_time_s(field, [here, *route], clock, speed_mps)
        straight = path_time_s(field, [here, waypoint], clock, speed_mps)
        if planned > straight:  # the grid's detour loses to the line: fly the line
            route, planned = (waypoint,), straight
        if not math.isfinite(planned):
            raise NoRoute(f"no route reaches {waypoint[0]:.4f}, {waypoint[1]:.4f} at "
                          f"{speed_mps:.2f} m/s: the current holds the glider off it")
        legs.append(Leg(waypoint, straight, planned, tuple(route)))
        here, clock = waypoint, clock + planned
    return RoutePlan(tuple(legs))


def _search(field: CurrentField, start: tuple[float, float], end: tuple[float, float],
            epoch_s: float, speed_mps: float, cells: int) -> list[tuple[float, float]]:
    """The grid's least-time path's turning points from `start` to `end` (included)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

    span = max(abs(end[0] - start[0]), abs(end[1] - start[1]) * math.cos(
        math.radians(start[0])), 1e-4)
    lat_lo, lat_hi = min(start[0], end[0]) - MARGIN * span, max(start[0], end[0]) + MARGIN * span
    pad_lon = MARGIN * span / math.cos(math.radians(start[0]))
    lon_lo, lon_hi = min(start[1], end[1]) - pad_lon, max(start[1], end[1]) + pad_lon
    b = field.bounds()
    lat_lo, lat_hi = max(lat_lo, b.lat_deg[0]), min(lat_hi, b.lat_deg[1])
    lon_lo, lon_hi = max(lon_lo, b.lon_deg[0]), min(lon_hi, b.lon_deg[1])
    lats, lons = np.linspace(lat_lo, lat_hi, cells), np.linspace(lon_lo, lon_hi, cells)
    grid_lat, grid_lon = np.meshgrid(lats, lons, indexing="ij")
    cn, ce = field.along(grid_lat, grid_lon, epoch_s)
    wet = np.isfinite(cn) & np.isfinite(ce)
    cn, ce = np.nan_to_num(cn), np.nan_to_num(ce)
    rows, cols, times = [], [], []
    index = np.arange(cells * cells).reshape(cells, cells)
    coslat = np.cos(np.radians(grid_lat))
    for di, dj in _MOVES:
        i0, i1 = max(0, -di), cells - max(0, di)
        j0, j1 = max(0, -dj), cells - max(0, dj)
        a = (slice(i0, i1), slice(j0, j1))
        z = (slice(i0 + di, i1 + di), slice(j0 + dj, j1 + dj))
        north = (grid_lat[z] - grid_lat[a]) * _M_PER_DEG
        east = (grid_lon[z] - grid_lon[a]) * _M_PER_DEG * coslat[a]
        v = ground_speed((cn[a] + cn[z]) / 2, (ce[a] + ce[z]) / 2, np.arctan2(east, north),
                         speed_mps)
        ok = np.isfinite(v) & wet[a] & wet[z]
        rows.append(index[a][ok])
        cols.append(index[z][ok])
        times.append(np.hypot(north, east)[ok] / v[ok])
    graph = coo_matrix((np.concatenate(times), (np.concatenate(rows), np.concatenate(cols))),
                       shape=(cells * cells, cells * cells)).tocsr()

    def node(p: tuple[float, float]) -> int:
        return int(index[int(np.argmin(abs(lats - p[0]))), int(np.argmin(abs(lons - p[1])))])

    source, target = node(start), node(end)
    _, previous = dijkstra(graph, indices=source, return_predecessors=True)
    if target != source and previous[target] < 0:
        return [end]
    chain = [target]
    while chain[-1] != source:
        chain.append(int(previous[chain[-1]]))
    chain.reverse()
    steps = [(chain[k + 1] // cells - chain[k] // cells, chain[k + 1] % cells - chain[k] % cells)
             for k in range(len(chain) - 1)]
    turns = [chain[k] for k in range(1, len(chain) - 1) if steps[k] != steps[k - 1]]
    return [(float(lats[n // cells]), float(lons[n % cells])) for n in turns] + [end]


def transit_mission(points: list[tuple[float, float]], duration_s: float,
                    surface_every_s: float = SURFACE_EVERY_S,
                    pitch_rad: float = TRANSIT_PITCH_RAD) -> str:
    """A mission that yos over TRANSIT_BAND_M at `pitch_rad` along `points` (lat, lon)
    [deg] in order (a goto list, each point reached within CAPTURE_M: a glider that
    overshoots a point in a strong current cannot come back to a smaller circle),
    surfacing every `surface_every_s` [s] for a GPS fix (which corrects its position
    estimate and measures the current), for `duration_s` [s]."""
    from gliderplan.sim.geo import degrees_to_ddmm

    pairs = ", ".join(f"({degrees_to_ddmm(lat):.4f}, {degrees_to_ddmm(lon):.4f})"
                      for lat, lon in points)
    low, high = TRANSIT_BAND_M
    return (
        "mission transit\n\nvar surfaced_s = 0\n\nstate go\nbegin\n"
        f"  flightroute goto_list({CAPTURE_M:g}, {pairs})\n"
        f"  flightprofile yo({low:g}, {high:g}, {pitch_rad:.4g}, {pitch_rad:.4g})\n"
        "  sensors missiontime, depth, pitch, lat, lon\n  events\n"
        f"    case missiontime >= {duration_s:.0f} exit\n"
        f"    case missiontime - surfaced_s >= {surface_every_s:.0f}\n"
        "      set surfaced_s = missiontime call fix\nend\n\n"
        "state fix\nbegin\n  flightroute noheading\n  flightprofile surface\n"
        "  sensors missiontime, depth\n  events\n"
        f"    case missiontime - surfaced_s >= {SURFACING_S:.0f}\n"
        "      set surfaced_s = missiontime return\nend\n")


def flown_track(points: list[tuple[float, float]], field: CurrentField,
                start: tuple[float, float], epoch_s: float, duration_s: float,
                pitch_rad: float = TRANSIT_PITCH_RAD
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(time [s], true lat, lon [deg], energy used [J]) of the simulated glider flying
    `transit_mission` at `pitch_rad` along `points` from `start` at `epoch_s` in `field`
    for `duration_s`."""
    from gliderplan.language import check_source
    from gliderplan.sim.energy import account
    from gliderplan.sim.flight import fly
    from gliderplan.sim.setup import FlightOptions, flight_setup

    mission = check_source(transit_mission(points, duration_s, pitch_rad=pitch_rad),
                           "<route>").checked()
    # the field and the epoch as given, not as `sim --currents`, `--start` read them
    setup = flight_setup(mission, FlightOptions(noise="none", duration_s=duration_s,
                                                start_position=start))
    config = replace(setup.config, currents=field, start_epoch_s=epoch_s)
    record = fly(mission, setup.water.ocean, config, setup.vehicle, runtime=setup.runtime)
    c = record.columns
    per_tick = account(record, mission, setup.vehicle, None).per_tick_j.values()
    return (np.asarray(c["time_s"]), np.asarray(c["lat_deg"]), np.asarray(c["lon_deg"]),
            np.cumsum(sum(per_tick)))


def _distance_m(lat: np.ndarray, lon: np.ndarray, to: tuple[float, float]) -> np.ndarray:
    return np.hypot((lat - to[0]) * _M_PER_DEG,
                    (lon - to[1]) * _M_PER_DEG * math.cos(math.radians(to[0])))


def arrival(track: tuple[np.ndarray, ...], end: tuple[float, float],
            reach_m: float = 1.5 * CAPTURE_M) -> tuple[float, float]:
    """([s] when, [J] the energy used by when) a `flown_track` first comes within
    `reach_m` of `end` (lat, lon) [deg] (inf, inf: never)."""
    time_s, lat, lon, used_j = track
    near = np.flatnonzero(_distance_m(lat, lon, end) <= reach_m)
    return (float(time_s[near[0]]), float(used_j[near[0]])) if len(near) else \
        (math.inf, math.inf)


def transit_speed_mps(hours: float = 6.0) -> float:
    """[m s-1] the simulated glider's speed over the ground on a transit in still water,
    its yos' inflections and surfacings included: what a route is planned at."""
    from gliderplan.sim.currents import UniformCurrent

    far = (1.0, 0.0)  # a point it cannot reach in `hours`
    _, lat, lon, _ = flown_track([far], UniformCurrent(0.0, 0.0), (0.0, 0.0), 0.0,
                              hours * 3600.0)
    return float(_distance_m(lat[-1:], lon[-1:], (0.0, 0.0))[0]) / (hours * 3600.0)
