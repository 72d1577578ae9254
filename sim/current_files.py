"""Current fields from files (`sim --currents`): a CF NetCDF field read with xarray, or
the depth-averaged currents a Slocum glider measured (`m_water_vx`, `m_water_vy` in its
flight logs, *.dbd).

A NetCDF field's velocities are found by their CF standard names
(`eastward_sea_water_velocity`, `northward_sea_water_velocity`), else by the names of
Copernicus Marine (`uo`, `vo`) and HYCOM (`water_u`, `water_v`); its axes by standard
name or name (latitude/lat, longitude/lon, time, depth). Longitudes 0 to 360 are turned
to -180 to 180. A logged current persists: each measurement holds until the next and
the last after the logs end, everywhere (the pilot's forecast of the next dives).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract.errors import UsageError
from gliderplan.sim.currents import (
    Bounds,
    CurrentError,
    CurrentField,
    GriddedCurrent,
    check_speeds,
    coverage_problem,
    ends_note,
    parse_uniform,
)

if TYPE_CHECKING:
    from gliderplan.language.ir import CheckedMission
    from gliderplan.power_models.vehicle import Vehicle

_EAST = ("eastward_sea_water_velocity", "uo", "water_u", "u")
_NORTH = ("northward_sea_water_velocity", "vo", "water_v", "v")
_AXES = {"time": ("time", "t"), "depth": ("depth", "z", "lev"),
         "lat": ("latitude", "lat", "y"), "lon": ("longitude", "lon", "x")}


def load_currents(spec: str) -> CurrentField:
    """A current field from `--currents`: N,E [m s-1], a NetCDF file (*.nc) or Slocum
    flight logs (*.dbd, or a directory of them); CurrentError naming what is wrong."""
    uniform = parse_uniform(spec)
    if uniform is not None:
        return uniform
    path = Path(spec)
    if not path.exists():
        raise UsageError(f"--currents {spec!r}: no such file or directory (expected N,E "
                         "[m/s], a NetCDF current field or Slocum flight logs)")
    if path.is_dir() or path.suffix.lower() == ".dbd":
        return read_logged_currents(path)
    return read_netcdf_currents(path)


def _find(dataset, names: tuple[str, ...], standard: bool = True):
    """The first variable whose standard_name, else name, is one of `names`."""
    if standard:
        for name, var in dataset.variables.items():
            if var.attrs.get("standard_name") in names:
                return name
    for name in names:
        if name in dataset.variables:
            return name
    return None


def read_netcdf_currents(path: str | Path) -> GriddedCurrent:
    """A CF NetCDF current field; CurrentError if it is unreadable, names no current,
    lacks an axis or holds a speed no ocean does."""
    import xarray as xr

    try:
        dataset = xr.open_dataset(path)
    except (OSError, ValueError) as err:
        raise CurrentError(f"{path}: not a NetCDF file xarray can read ({err})") from None
    with dataset:
        east_name, north_name = _find(dataset, _EAST), _find(dataset, _NORTH)
        if east_name is None or north_name is None:
            raise CurrentError(
                f"{path}: no current variables: expected the standard names "
                "eastward_sea_water_velocity and northward_sea_water_velocity, or uo/vo "
                "(Copernicus), water_u/water_v (HYCOM); it holds "
                f"{', '.join(map(str, dataset.data_vars)) or 'no variables'}")
        east = dataset[east_name]
        axes = {}
        for axis, names in _AXES.items():
            found = [d for d in east.dims if d in names
                     or dataset[d].attrs.get("standard_name") in names]
            axes[axis] = found[0] if found else None
        for axis in ("lat", "lon"):
            if axes[axis] is None:
                raise CurrentError(f"{path}: {east_name} has no {axis} axis (its dimensions: "
                                   f"{', '.join(map(str, east.dims))})")
        order = [axes[a] for a in ("time", "depth", "lat", "lon") if axes[a] is not None]
        extra = [d for d in east.dims if d not in order]
        if extra:
            raise CurrentError(f"{path}: {east_name} has dimensions gliderplan does not know: "
                               f"{', '.join(map(str, extra))}")
        east = east.transpose(*order)
        north = dataset[north_name].transpose(*order)
        if axes["time"] is None:
            time_s = np.array([0.0])
        else:
            time_s = _epoch_s(dataset[axes["time"]].values)
        depth_m = np.array([0.0]) if axes["depth"] is None else \
            np.abs(dataset[axes["depth"]].values.astype(float))
        lat = dataset[axes["lat"]].values.astype(float)
        lon = dataset[axes["lon"]].values.astype(float)
        shape = (len(time_s), len(depth_m), len(lat), len(lon))
        east_v = east.values.astype(float).reshape(shape)
        north_v = north.values.astype(float).reshape(shape)
    check_speeds(north_v, east_v, f"{path}: {east_name}, {north_name}")
    lon = np.where(lon > 180.0, lon - 360.0, lon)
    sorts = [np.argsort(a, kind="stable") for a in (time_s, depth_m, lat, lon)]
    index = np.ix_(*sorts)
    return GriddedCurrent(time_s[sorts[0]], depth_m[sorts[1]], lat[sorts[2]], lon[sorts[3]],
                          north_v[index], east_v[index], description=str(path))


def _epoch_s(values: np.ndarray) -> np.ndarray:
    """Times [s since 1970] of a decoded NetCDF time axis."""
    if np.issubdtype(values.dtype, np.datetime64):
        return values.astype("datetime64[ns]").astype(np.int64) / 1e9
    return values.astype(float)


@dataclass(frozen=True)
class LoggedCurrent:
    """The depth-averaged currents a glider measured [m s-1], each held until the next,
    the last after the logs end; the same everywhere."""

    time_s: np.ndarray  # [s since 1970], increasing
    north_mps: np.ndarray
    east_mps: np.ndarray
    description: str = "logged"

    def at(self, lat_deg: float, lon_deg: float, epoch_s: float,
           depth_m: float = 0.0) -> tuple[float, float]:
        i = max(0, int(np.searchsorted(self.time_s, epoch_s, side="right")) - 1)
        return float(self.north_mps[i]), float(self.east_mps[i])

    def along(self, lat_deg: np.ndarray, lon_deg: np.ndarray, epoch_s: float,
              depth_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        north, east = self.at(0.0, 0.0, epoch_s)
        shape = np.shape(lat_deg)
        return np.full(shape, north), np.full(shape, east)

    def bounds(self) -> Bounds:
        return Bounds()


def read_logged_currents(path: str | Path) -> LoggedCurrent:
    """The currents a Slocum glider measured, from its flight logs (*.dbd or a directory
    of them, cache files in cac/ beside them): its `m_water_vx`/`m_water_vy`, else the
    currents of the dead-reckoning error between its fixes (sim.dr_currents);
    CurrentError if they give neither."""
    return logged_currents(flight_logs(path), path)


def flight_logs(path: str | Path):
    """The flight logs (*.dbd, or a directory of them, cache files in cac/ beside them)
    as one dbdreader.MultiDBD; CurrentError where they cannot be read."""
    import dbdreader

    from gliderplan.sim.slocum_ocean import logs_in

    files = logs_in(path, "*.dbd", "flight log")
    cac = files[0].parent / "cac"
    try:
        return dbdreader.MultiDBD(filenames=[str(f) for f in files],
                                  cacheDir=str(cac) if cac.is_dir() else None)
    except (dbdreader.DbdError, OSError, ValueError) as err:
        raise CurrentError(f"{path}: the flight logs cannot be read: {err}") from None


def logged_currents(logs, path: str | Path) -> LoggedCurrent:
    """The currents of opened flight logs (a dbdreader.MultiDBD read from `path`): the
    measured ones, else those of the dead-reckoning error between fixes."""
    measured = _measured_currents(logs)
    if measured is None:
        return _estimated_currents(logs, path)
    t, north, east = measured
    check_speeds(north, east, f"{path}: m_water_vx, m_water_vy")
    return LoggedCurrent(t, north, east, f"the currents measured in {path} ({len(t)} values)")


def _measured_currents(logs) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """(time [s since 1970], north, east [m s-1]) of the logs' m_water_vy/vx where both
    are finite; None where the logs hold none."""
    import dbdreader

    try:
        t_east, east = logs.get("m_water_vx")
        t_north, north = logs.get("m_water_vy")
    except (dbdreader.DbdError, ValueError):
        return None
    if not len(t_east) or not len(t_north):
        return None
    if len(t_east) != len(t_north) or not np.array_equal(t_east, t_north):
        north = np.interp(t_east, t_north, north)
    keep = np.isfinite(east) & np.isfinite(north)
    if not np.any(keep):
        return None
    return (np.asarray(t_east[keep], float), np.asarray(north[keep], float),
            np.asarray(east[keep], float))


def _estimated_currents(logs, path: str | Path) -> LoggedCurrent:
    """The currents of the dead-reckoning error between the logs' fixes, each from the
    fix that ends its segment; CurrentError where the logs allow none."""
    import dbdreader

    from gliderplan.sim.dr_currents import read_track, segment_currents

    try:
        estimate = segment_currents(read_track(logs))
    except (dbdreader.DbdError, ValueError) as err:
        raise CurrentError(f"{path}: no depth-averaged current in the flight logs "
                           "(m_water_vx, m_water_vy), nor the fixes, speed, heading and "
                           f"depth to estimate one (m_gps_lat/lon, m_speed, m_heading, "
                           f"m_depth): {err}") from None
    if not len(estimate.time_s):
        raise CurrentError(f"{path}: no depth-averaged current in the flight logs "
                           "(m_water_vx, m_water_vy), and no dive between two GPS fixes "
                           "to estimate one from")
    check_speeds(estimate.north_mps, estimate.east_mps,
                 f"{path}: the currents of the dead-reckoning error between fixes")
    return LoggedCurrent(estimate.time_s, estimate.north_mps, estimate.east_mps,
                         f"the currents of the dead-reckoning error between the fixes in "
                         f"{path} ({len(estimate.time_s)} dives, 1 sigma "
                         f"{float(np.median(estimate.sigma_mps)):.2f} m/s each)")


def faster_than_glider(field: CurrentField, speed_mps: float, lat_deg: float,
                       lon_deg: float, epoch_s: float) -> str | None:
    """A warning if the current where the glider starts is faster than it flies
    [m s-1]: it will be carried off its route whatever it steers."""
    north, east = field.at(lat_deg, lon_deg, epoch_s)
    speed = math.hypot(north, east)
    if speed > speed_mps:
        return (f"the current at the start ({speed:.2f} m/s, {field.description}) is faster "
                f"than the glider flies through the water ({speed_mps:.2f} m/s): it will be "
                "carried off its route")
    return None


def checked_field(spec: str, mission: CheckedMission, vehicle: Vehicle,
                  start: tuple[float, float], epoch_s: float, duration_s: float
                  ) -> tuple[CurrentField, list[str]]:
    """The field of `--currents SPEC` for a run of `mission` from `start` (lat, lon)
    [deg] at `epoch_s` [s since 1970] for `duration_s` [s], and notes for the user;
    CurrentError where it does not cover the start, the waypoints or the start time, or
    the start is on its land."""
    from gliderplan.sim.loop import correction_speed_mps, route_points_deg

    field = load_currents(spec)
    points = [start, *route_points_deg(mission)]
    problem = coverage_problem(field, [p[0] for p in points], [p[1] for p in points], epoch_s)
    if problem is not None:
        raise CurrentError(f"--currents {spec}: {problem}")
    north, east = field.at(*start, epoch_s)
    if not math.isfinite(north + east):
        raise CurrentError(f"--currents {spec}: the start {start[0]:.4f}, {start[1]:.4f} is "
                           "on land (the field has no water there): give --start LAT,LON at sea")
    notes = [f"currents: {field.description}",
             faster_than_glider(field, correction_speed_mps(vehicle), *start, epoch_s),
             ends_note(field, epoch_s + duration_s)]
    return field, [note for note in notes if note]
