"""Where and when the glider will surface: each surfacing's time and position with its
90 % ellipse, from draws of what is uncertain in a dive.

A glider between fixes flies toward its waypoint at its speed through the water, its
heading corrected for the current it measured (`sim.navigation`), and drifts with the
current; at the surface it drifts for its fix and call. The draws (`DEFAULT_DRAWS`) vary
what the last fix cannot tell: the current (a constant offset per draw on each
component, `CURRENT_SIGMA_MPS`: the current changes between fixes with tides and
eddies), the speed through the water (`SPEED_SIGMA`) and each dive's length
(`DIVE_SIGMA`). The forecast position is the draws' mean; the ellipse holds 90 % of a
two-dimensional normal of their covariance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.sim.currents import CurrentField, UniformCurrent
from gliderplan.sim.geo import EARTH_RADIUS_M

if TYPE_CHECKING:
    from gliderplan.language import ir
    from gliderplan.power_models.vehicle import Vehicle

DEFAULT_DRAWS = 200
CHI2_2D_90 = -2.0 * math.log(0.1)  # a 2-D normal's squared radius holding 90 %
# [s] a dive is flown in STEPS_PER_DIVE steps, at least STEP_S and at most MAX_STEP_S
# long: the current looked up, the heading set toward the waypoint, which is reached
# within its capture radius or a step's run of it (a glider covers 30-250 m a step)
STEP_S, MAX_STEP_S, STEPS_PER_DIVE = 120.0, 900.0, 16
# [m s-1] per component: how far the depth-averaged current strays from the one last
# measured over a few hours (tidal and inertial currents on a shelf run at 0.05-0.2 m/s)
CURRENT_SIGMA_MPS = 0.05
SPEED_SIGMA = 0.10  # [1] of the speed through the water: its flight model's fit
DIVE_SIGMA = 0.05  # [1] of a dive's length: yos turned by the altimeter, not the depth
_M_PER_DEG = EARTH_RADIUS_M * math.pi / 180.0


@dataclass(frozen=True)
class Voyage:
    """What a surfacing forecast starts from."""

    lat_deg: float  # the last fix (or the start)
    lon_deg: float
    epoch_s: float  # [s since 1970] when it dives
    waypoints: tuple[tuple[float, float], ...]  # (lat, lon) [deg] in order; () : none
    speed_mps: float  # through the water, horizontally
    dive_s: float  # [s] from diving to the next fix
    surface_s: float  # [s] at the surface, fix to the next dive
    currents: CurrentField = UniformCurrent(0.0, 0.0)
    current_sigma_mps: float = CURRENT_SIGMA_MPS
    dive_sigma_s: float | None = None  # [s] of each dive's length (None: DIVE_SIGMA of it)
    capture_m: float = 10.0  # a waypoint is reached within this [m]
    loops: bool = False  # after the last waypoint the first (a Slocum goto list), else held
    # (dive [s], time at the surface [s]) before and at each surfacing, in order (a dive
    # of 0: it starts at the surface); after them, or without: dive_s and surface_s
    schedule: tuple[tuple[float, float], ...] = ()
    corrects: bool = True  # heads upstream for the current (u_use_current_correction)
    heading_rad: float = 0.0  # [rad] held without waypoints (a `heading` route), uncorrected


@dataclass(frozen=True)
class Surfacing:
    """One forecast surfacing."""

    time_s: float  # [s] since the voyage's dive
    lat_deg: float
    lon_deg: float
    ellipse_m: tuple[float, float]  # 90 % semi-axes, major and minor [m]
    azimuth_deg: float  # of the major axis, clockwise from north [deg]
    north_m: np.ndarray  # each draw's position [m] from the mean
    east_m: np.ndarray

    def to_json(self) -> dict:
        return {"time_s": self.time_s, "lat": self.lat_deg, "lon": self.lon_deg,
                "ellipse_m": list(self.ellipse_m), "ellipse_azimuth_deg": self.azimuth_deg}

    def inside(self, lat_deg: float, lon_deg: float) -> bool:
        """Whether a position [deg] lies inside the 90 % ellipse."""
        cov = np.cov(np.vstack([self.north_m, self.east_m]))
        d = np.array([(lat_deg - self.lat_deg) * _M_PER_DEG,
                      (lon_deg - self.lon_deg) * _M_PER_DEG
                      * math.cos(math.radians(self.lat_deg))])
        return float(d @ np.linalg.pinv(cov) @ d) <= CHI2_2D_90

    def distance_m(self, lat_deg: float, lon_deg: float) -> float:
        """[m] from the forecast position to a position [deg]."""
        return math.hypot((lat_deg - self.lat_deg) * _M_PER_DEG,
                          (lon_deg - self.lon_deg) * _M_PER_DEG
                          * math.cos(math.radians(self.lat_deg)))


def forecast_surfacings(voyage: Voyage, count: int, draws: int = DEFAULT_DRAWS,
                        seed: int = 0) -> list[Surfacing]:
    """The next `count` surfacings of `voyage`, from `draws` draws."""
    rng = np.random.default_rng(seed)
    bias_n, bias_e = rng.normal(0.0, voyage.current_sigma_mps, (2, draws))
    speed = voyage.speed_mps * np.maximum(0.1, 1.0 + SPEED_SIGMA * rng.standard_normal(draws))
    lat = np.full(draws, voyage.lat_deg)
    lon = np.full(draws, voyage.lon_deg)
    target = np.zeros(draws, int)
    points = np.array(voyage.waypoints, float).reshape(-1, 2)
    clock = np.zeros(draws)
    out = []
    for i in range(count):
        dive_s, surface_s = voyage.schedule[i] if i < len(voyage.schedule) else \
            (voyage.dive_s, voyage.surface_s)
        sigma = DIVE_SIGMA * dive_s if voyage.dive_sigma_s is None else voyage.dive_sigma_s
        dive = np.maximum(0.2 * dive_s, dive_s + sigma * rng.standard_normal(draws))
        flown = np.zeros(draws)
        step_s = min(max(STEP_S, dive_s / STEPS_PER_DIVE), MAX_STEP_S)
        while np.any(flown < dive):
            dt = np.minimum(step_s, dive - flown)
            cn, ce = _current(voyage, lat, lon, voyage.epoch_s + float(np.mean(clock + flown)))
            # it steers for the current it knows; the water carries it with the drawn one
            heading = _headings(voyage, points, target, lat, lon, speed, cn, ce)
            lat, lon = _move(lat, lon, (speed * np.cos(heading) + cn + bias_n) * dt,
                             (speed * np.sin(heading) + ce + bias_e) * dt)
            flown += dt
            if len(points):
                target = _advance(points, target, lat, lon, voyage, speed * step_s)
        clock += dive
        out.append(_surfacing(float(np.mean(clock)), lat, lon))
        lat, lon = _surface_drift(voyage, lat, lon, float(np.mean(clock)), surface_s,
                                  bias_n, bias_e)
        clock += surface_s
    return out


def _surface_drift(voyage: Voyage, lat: np.ndarray, lon: np.ndarray, time_s: float,
                   surface_s: float, bias_n: np.ndarray, bias_e: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Where the current carries each draw in `surface_s` [s] at the surface."""
    cn, ce = _current(voyage, lat, lon, voyage.epoch_s + time_s)
    return _move(lat, lon, (cn + bias_n) * surface_s, (ce + bias_e) * surface_s)


def _current(voyage: Voyage, lat: np.ndarray, lon: np.ndarray, epoch_s: float
             ) -> tuple[np.ndarray, np.ndarray]:
    """The field's current [m s-1] at each draw (none where it has no water)."""
    north, east = voyage.currents.along(lat, lon, epoch_s)
    return np.nan_to_num(north), np.nan_to_num(east)


def _headings(voyage: Voyage, points: np.ndarray, target: np.ndarray, lat: np.ndarray,
              lon: np.ndarray, speed: np.ndarray, cn: np.ndarray, ce: np.ndarray
              ) -> np.ndarray:
    """Each draw's heading [rad]: toward its waypoint, upstream of the current across
    the course (sim.navigation.corrected_heading, for many draws at once)."""
    if not len(points):
        return np.full(len(lat), voyage.heading_rad)
    north = (points[target, 0] - lat) * _M_PER_DEG
    east = (points[target, 1] - lon) * _M_PER_DEG * np.cos(np.radians(lat))
    course = np.arctan2(east, north)
    if not voyage.corrects:
        return course
    across = ce * np.cos(course) - cn * np.sin(course)
    return course + np.arcsin(np.clip(-across / speed, -1.0, 1.0))


def _advance(points: np.ndarray, target: np.ndarray, lat: np.ndarray, lon: np.ndarray,
             voyage: Voyage, step_m: np.ndarray) -> np.ndarray:
    """Each draw's waypoint after this step: the next once within the capture radius, or
    a step's run `step_m` [m], of it (a coarse step passes a small circle by); after the
    last the first if the list loops, else the last held."""
    north = (points[target, 0] - lat) * _M_PER_DEG
    east = (points[target, 1] - lon) * _M_PER_DEG * np.cos(np.radians(lat))
    reached = np.hypot(north, east) <= np.maximum(voyage.capture_m, step_m)
    after = (target + 1) % len(points) if voyage.loops else np.minimum(target + 1,
                                                                       len(points) - 1)
    return np.where(reached, after, target)


def _move(lat: np.ndarray, lon: np.ndarray, north_m: np.ndarray, east_m: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    return lat + north_m / _M_PER_DEG, lon + east_m / (_M_PER_DEG * np.cos(np.radians(lat)))


def _surfacing(time_s: float, lat: np.ndarray, lon: np.ndarray) -> Surfacing:
    """The draws' mean position and their 90 % ellipse."""
    mean_lat, mean_lon = float(np.mean(lat)), float(np.mean(lon))
    north = (lat - mean_lat) * _M_PER_DEG
    east = (lon - mean_lon) * _M_PER_DEG * math.cos(math.radians(mean_lat))
    values, vectors = np.linalg.eigh(np.cov(np.vstack([north, east])))
    major, minor = (math.sqrt(CHI2_2D_90 * max(0.0, float(v))) for v in values[::-1])
    azimuth = math.degrees(math.atan2(vectors[1, 1], vectors[0, 1])) % 180.0
    return Surfacing(time_s, mean_lat, mean_lon, (major, minor), azimuth, north, east)


def mission_surfacings(mission: ir.CheckedMission, vehicle: Vehicle, duration_s: float,
                       start: tuple[float, float] | None, epoch_s: float,
                       currents: CurrentField) -> list[Surfacing]:
    """A mission's surfacings over `duration_s` [s], when its timeline enters a surface
    state (`planner.occupancy`, as the energy forecast walks it), flown from `start`
    (lat, lon) [deg] (None: as the sim puts it in the water) through its waypoints at
    its yos' speed (`yo_speed_mps`) in `currents`; a goto list as the Slocum flies it
    (sim.pilot.Waypoints: within its radius, looping); a mission without waypoints holds
    its first `heading` route's heading, or else, on a `turn` route, goes nowhere through
    the water (a spiral circles back within v / rate, some tens of metres) and drifts."""
    from gliderplan.contract import WAYPOINT_RADIUS_M
    from gliderplan.language.registry import held_heading_rad
    from gliderplan.planner.occupancy import mission_occupancy
    from gliderplan.sim.loop import RunConfig, route_points_deg
    from gliderplan.sim.loop import start_position as sim_start

    kinds = {s.name: s.profiles[0].kind for s in mission.states}
    schedule: list[tuple[float, float]] = []
    left_s = 0.0  # when it last left the surface [s]
    for visit in mission_occupancy(mission, duration_s).trace:
        if kinds.get(visit.state) != "surface":
            continue
        if schedule and visit.entry_s <= left_s:  # one surface state after another
            schedule[-1] = (schedule[-1][0], schedule[-1][1] + visit.duration_s)
        else:
            schedule.append((visit.entry_s - left_s, visit.duration_s))
        left_s = visit.entry_s + visit.duration_s
    if not schedule:
        return []
    lat, lon = start if start is not None else sim_start(mission, RunConfig())
    lists = [s.route for s in mission.states if s.route.kind == "goto_list"]
    held = [s.route for s in mission.states if s.route.kind == "heading"]
    points = tuple(route_points_deg(mission))
    spirals = not (points or held) and any(s.route.kind == "turn" for s in mission.states)
    voyage = Voyage(lat, lon, epoch_s, points,
                    0.0 if spirals else yo_speed_mps(mission, vehicle), schedule[-1][0],
                    schedule[-1][1],
                    currents, capture_m=lists[0].params[0] if lists else WAYPOINT_RADIUS_M,
                    loops=bool(lists), schedule=tuple(schedule),
                    corrects=mission.current_correction,
                    heading_rad=held_heading_rad(held[0].params[0]) if held else 0.0)
    return forecast_surfacings(voyage, len(schedule))


def yo_speed_mps(mission: ir.CheckedMission, vehicle: Vehicle) -> float:
    """[m s-1] the glider's speed through the water averaged over a yo of the first
    state that yos on a route with constant arguments (its inflections covering no
    distance: `Vehicle.yo_cycle`), flown on the full stroke as without a plan; else its
    glide speed at its nominal pitch."""
    from gliderplan.sim.loop import correction_speed_mps

    for state in mission.states:
        profile = state.profiles[0]
        args = profile.constant_args()
        if state.route.kind != "noheading" and profile.kind in ("yo", "thermotrackyo") \
                and args is not None:
            time_s, _, distance_m = vehicle.yo_cycle(args[0], args[1], args[2],
                                                     vehicle.unplanned_ballast_cc)
            return float(distance_m / time_s)
    return correction_speed_mps(vehicle)


def ellipse_ring(s: Surfacing, points: int = 36) -> list[tuple[float, float]]:
    """The 90 % ellipse as a closed ring of (lon, lat) [deg]."""
    a, b = s.ellipse_m
    az = math.radians(s.azimuth_deg)
    ring = []
    for i in range(points + 1):
        t = 2.0 * math.pi * i / points
        major, minor = a * math.cos(t), b * math.sin(t)
        north = major * math.cos(az) - minor * math.sin(az)
        east = major * math.sin(az) + minor * math.cos(az)
        ring.append((s.lon_deg + east / (_M_PER_DEG * math.cos(math.radians(s.lat_deg))),
                     s.lat_deg + north / _M_PER_DEG))
    return ring


def geojson(surfacings: list[Surfacing], start_epoch_s: float) -> str:
    """The surfacings as a GeoJSON FeatureCollection: a point and an ellipse polygon each."""
    import json

    from gliderplan.sim.export import utc_text

    features = []
    for i, s in enumerate(surfacings, start=1):
        props = {"surfacing": i, "time_utc": utc_text(start_epoch_s + s.time_s),
                 **s.to_json()}
        features.append({"type": "Feature", "properties": props,
                         "geometry": {"type": "Point", "coordinates": [s.lon_deg, s.lat_deg]}})
        features.append({"type": "Feature", "properties": {**props, "ellipse": "90 %"},
                         "geometry": {"type": "Polygon",
                                      "coordinates": [[list(p) for p in ellipse_ring(s)]]}})
    return json.dumps({"type": "FeatureCollection", "features": features}, indent=1) + "\n"


def kml(surfacings: list[Surfacing], start_epoch_s: float, name: str) -> str:
    """The surfacings as KML: a placemark and a 90 % ellipse each."""
    from xml.sax.saxutils import escape

    from gliderplan.sim.export import utc_text

    marks = []
    for i, s in enumerate(surfacings, start=1):
        when = utc_text(start_epoch_s + s.time_s)
        ring = " ".join(f"{lon:.6f},{lat:.6f},0" for lon, lat in ellipse_ring(s))
        marks.append(
            f"<Placemark><name>surfacing {i}</name><TimeStamp><when>{when}</when></TimeStamp>"
            f"<MultiGeometry><Point><coordinates>{s.lon_deg:.6f},{s.lat_deg:.6f},0"
            "</coordinates></Point><Polygon><outerBoundaryIs><LinearRing><coordinates>"
            f"{ring}</coordinates></LinearRing></outerBoundaryIs></Polygon></MultiGeometry>"
            f"<description>90 % ellipse {s.ellipse_m[0]:.0f} x {s.ellipse_m[1]:.0f} m"
            "</description></Placemark>")
    return ('<?xml version="1.0" encoding="UTF-8"?>\n<kml xmlns="http://www.opengis.net/kml/2.2">'
            f"<Document><name>{escape(name)} surfacings</name>" + "".join(marks)
            + "</Document></kml>\n")
