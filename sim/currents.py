"""Currents the glider flies through: a field of velocities [m s-1] toward the north and
the east, by position, time and (where the field has it) depth.

- `UniformCurrent`: one current everywhere and always (`--currents N,E`);
- `GriddedCurrent`: values on a regular latitude, longitude, time (and depth) grid,
  interpolated linearly along each axis (a CF NetCDF file: `sim.current_files`);
  a grid point without a value (land, in ocean models) is left out of the interpolation,
  and a place whose every neighbour is land has no current (NaN);
- a glider's own measurements along time (`sim.logged_currents`).

Every field answers the same two questions, one point a tick (`at`, the simulator) and
many points at once (`along`, the surfacing forecast's draws and the route planner), and
says what it covers so that a run it does not cover is refused before it flies
(`coverage_problem`). `check_speeds` refuses what no ocean holds.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from gliderplan.contract.errors import GliderplanError

# [m s-1] faster than any ocean current a glider meets: the Gulf Stream's core runs at
# ~2.5 m/s; only tidal races between islands (Pentland Firth, ~5 m/s) pass it
FASTEST_OCEAN_MPS = 3.0


class CurrentError(GliderplanError):
    """A current field that cannot be read or flown; the message names what is missing."""


class CurrentField(Protocol):
    """Velocities [m s-1] (toward the north, toward the east) by place and time."""

    description: str  # where it came from, for the run's metadata and the assumptions

    def at(self, lat_deg: float, lon_deg: float, epoch_s: float,
           depth_m: float = 0.0) -> tuple[float, float]:
        """The current at one place [deg], time [s since 1970] and depth [m]."""
        ...

    def along(self, lat_deg: np.ndarray, lon_deg: np.ndarray, epoch_s: float,
              depth_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """The current at many places at one time and depth (NaN where there is none)."""
        ...

    def bounds(self) -> Bounds:
        """What the field covers."""
        ...


@dataclass(frozen=True)
class Bounds:
    """The region [deg] and period [s since 1970] a field covers (infinite: any)."""

    lat_deg: tuple[float, float] = (-math.inf, math.inf)
    lon_deg: tuple[float, float] = (-math.inf, math.inf)
    epoch_s: tuple[float, float] = (-math.inf, math.inf)


@dataclass(frozen=True)
class UniformCurrent:
    """One current [m s-1] everywhere and always."""

    north_mps: float
    east_mps: float
    description: str = "uniform"

    def at(self, lat_deg: float, lon_deg: float, epoch_s: float,
           depth_m: float = 0.0) -> tuple[float, float]:
        return self.north_mps, self.east_mps

    def along(self, lat_deg: np.ndarray, lon_deg: np.ndarray, epoch_s: float,
              depth_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        shape = np.shape(lat_deg)
        return np.full(shape, self.north_mps), np.full(shape, self.east_mps)

    def bounds(self) -> Bounds:
        return Bounds()


@dataclass(frozen=True)
class GriddedCurrent:
    """Currents on a grid: axes in increasing order, `north_mps` and `east_mps` of shape
    (time, depth, lat, lon) with NaN where there is no water."""

    time_s: np.ndarray  # [s since 1970]; one value: constant in time
    depth_m: np.ndarray  # [m, positive down]; one value: the depth-averaged current
    lat_deg: np.ndarray
    lon_deg: np.ndarray
    north_mps: np.ndarray
    east_mps: np.ndarray
    description: str = "gridded"

    def bounds(self) -> Bounds:
        times = (-math.inf, math.inf) if len(self.time_s) == 1 else \
            (float(self.time_s[0]), float(self.time_s[-1]))
        return Bounds((float(self.lat_deg[0]), float(self.lat_deg[-1])),
                      (float(self.lon_deg[0]), float(self.lon_deg[-1])), times)

    def at(self, lat_deg: float, lon_deg: float, epoch_s: float,
           depth_m: float = 0.0) -> tuple[float, float]:
        north, east = self.along(np.array([lat_deg]), np.array([lon_deg]), epoch_s, depth_m)
        return float(north[0]), float(east[0])

    def along(self, lat_deg: np.ndarray, lon_deg: np.ndarray, epoch_s: float,
              depth_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """Linear along each axis, held at the grid's edges; grid points without water
        are left out and the others weighted up (NaN where none has water)."""
        lat = np.asarray(lat_deg, float)
        lon = np.asarray(lon_deg, float)
        time_i, time_w = _bracket(self.time_s, epoch_s)
        depth_i, depth_w = _bracket(self.depth_m, depth_m)
        lat_i, lat_w = _brackets(self.lat_deg, lat)
        lon_i, lon_w = _brackets(self.lon_deg, lon)
        north_sum = np.zeros(lat.shape)
        east_sum = np.zeros(lat.shape)
        weights = np.zeros(lat.shape)
        for ti, tw in ((time_i, 1.0 - time_w), (time_i + 1, time_w)):
            for zi, zw in ((depth_i, 1.0 - depth_w), (depth_i + 1, depth_w)):
                if tw * zw == 0.0:
                    continue
                north_plane = self.north_mps[ti, zi]
                east_plane = self.east_mps[ti, zi]
                for yi, yw in ((lat_i, 1.0 - lat_w), (lat_i + 1, lat_w)):
                    for xi, xw in ((lon_i, 1.0 - lon_w), (lon_i + 1, lon_w)):
                        n, e = north_plane[yi, xi], east_plane[yi, xi]
                        w = tw * zw * yw * xw * (np.isfinite(n) & np.isfinite(e))
                        north_sum += np.where(w > 0.0, n * w, 0.0)
                        east_sum += np.where(w > 0.0, e * w, 0.0)
                        weights += w
        with np.errstate(invalid="ignore", divide="ignore"):
            return (np.where(weights > 0.0, north_sum / weights, np.nan),
                    np.where(weights > 0.0, east_sum / weights, np.nan))


def _bracket(axis: np.ndarray, x: float) -> tuple[int, float]:
    """(index i, weight of i + 1) of `x` between axis[i] and axis[i + 1], held at the ends
    (a one-point axis: (0, 0))."""
    n = len(axis)
    if n == 1 or x <= axis[0]:
        return 0, 0.0
    if x >= axis[-1]:
        return n - 2, 1.0
    i = bisect.bisect_right(axis, x) - 1
    return i, float((x - axis[i]) / (axis[i + 1] - axis[i]))


def _brackets(axis: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """`_bracket` of each value of `x`."""
    n = len(axis)
    if n == 1:
        return np.zeros(x.shape, int), np.zeros(x.shape)
    i = np.clip(np.searchsorted(axis, x, side="right") - 1, 0, n - 2)
    w = np.clip((x - axis[i]) / (axis[i + 1] - axis[i]), 0.0, 1.0)
    return i, np.where(np.isfinite(w), w, 0.0)


def check_speeds(north_mps: np.ndarray, east_mps: np.ndarray, where: str) -> None:
    """CurrentError if any current is faster than FASTEST_OCEAN_MPS (or not a number where
    it is given): no ocean a glider flies holds it; `where` names the source."""
    speed = np.hypot(north_mps, east_mps)
    bad = speed > FASTEST_OCEAN_MPS
    if np.any(bad):
        first = np.unravel_index(int(np.argmax(bad)), np.shape(speed))
        at = f" (the first at index {tuple(int(i) for i in first)})" if first else ""
        raise CurrentError(
            f"{where}: a current of {float(np.nanmax(speed)):.3g} m/s{at}: faster than any "
            "ocean current a glider meets "
            f"(at most {FASTEST_OCEAN_MPS:g} m/s; the Gulf Stream's core runs at ~2.5 m/s); "
            "are the units cm/s, or the components swapped with a speed?")


def coverage_problem(field: CurrentField, lats_deg: list[float], lons_deg: list[float],
                     start_epoch_s: float) -> str | None:
    """What of the places [deg] a mission flies to (its start and waypoints) and of its
    start [s since 1970] `field` does not cover, or None (a run that outlasts the field
    flies its last time: `ends_note`)."""
    from gliderplan.sim.export import utc_text

    b = field.bounds()
    outside = [(lat, lon) for lat, lon in zip(lats_deg, lons_deg, strict=True)
               if not (b.lat_deg[0] <= lat <= b.lat_deg[1]
                       and b.lon_deg[0] <= lon <= b.lon_deg[1])]
    if outside:
        lat, lon = outside[0]
        return (f"the field covers latitudes {b.lat_deg[0]:.4f} to {b.lat_deg[1]:.4f} and "
                f"longitudes {b.lon_deg[0]:.4f} to {b.lon_deg[1]:.4f}; the route reaches "
                f"{lat:.4f}, {lon:.4f} ({len(outside)} of its {len(lats_deg)} points outside)")
    if not b.epoch_s[0] <= start_epoch_s <= b.epoch_s[1]:
        return (f"the field covers {utc_text(b.epoch_s[0])} to {utc_text(b.epoch_s[1])}; the "
                f"run starts at {utc_text(start_epoch_s)} (give --start LAT,LON,UTC within it)")
    return None


def ends_note(field: CurrentField, end_epoch_s: float) -> str | None:
    """A note if the run may outlast the field [s since 1970]: its last time holds."""
    from gliderplan.sim.export import utc_text

    last = field.bounds().epoch_s[1]
    if end_epoch_s <= last:
        return None
    return (f"the current field ends at {utc_text(last)}: a run flying longer flies its "
            "last currents")


def parse_uniform(text: str, option: str = "--currents") -> UniformCurrent | None:
    """`N,E` [m s-1] as a uniform current; None if `text` is not two numbers; CurrentError
    for a speed no ocean holds."""
    parts = text.split(",")
    if len(parts) != 2:
        return None
    try:
        north, east = (float(p) for p in parts)
    except ValueError:
        return None
    if not (math.isfinite(north) and math.isfinite(east)):
        raise CurrentError(f"{option} {text!r}: the current must be finite numbers N,E [m/s]")
    check_speeds(np.array(north), np.array(east), f"{option} {text}")
    return UniformCurrent(north, east, f"uniform {north:g} m/s north, {east:g} m/s east")
