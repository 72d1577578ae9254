"""The ocean a real Slocum glider saw: temperature and salinity against depth and time
from its science logs (*.ebd, read with dbdreader), for `gliderplan sim --ocean LOGS`.

Each leg of the logged yo (a dive or a climb) becomes one cast, averaged in depth bins;
the simulated ocean interpolates between casts in time (`sim.ocean.MeasuredProfile`),
the simulated run starting at the first logged sample and the last cast holding after
the log ends. Practical salinity and depth follow TEOS-10 (gsw) from the CTD's
conductivity, temperature and pressure, at the latitude of the glider's GPS fixes when
its flight logs (*.dbd) lie beside the science logs, else at 45 degrees (which moves a
depth by less than 0.3 %).

The sea floor the glider saw comes from those flight logs too: its own water depth
(`m_water_depth`, where positive), else its depth plus its altimeter's reading
(`m_depth + m_altitude`, where the altimeter had one), a profile along time on the
casts' clock. Logs without either give no floor (and say why).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gliderplan.contract.errors import GliderplanError
from gliderplan.power_models.slocum_log import check_log_headers
from gliderplan.sim.ocean import MeasuredProfile, OceanFileError, SeaFloor

BIN_M = 1.0  # depth bin of a cast [m]
TURN_M = 2.0  # a leg ends when the glider has come back this far from its extreme [m]
MIN_LEG_M = 3.0  # legs spanning less depth (surface drift, a stalled pump) are no cast [m]
DEFAULT_LATITUDE_DEG = 45.0
BAR_TO_DBAR = 10.0
S_M_TO_MS_CM = 10.0  # conductivity [S m-1] to [mS cm-1]


@dataclass(frozen=True)
class LoggedOcean:
    """A replayed ocean and where it came from (for the run's metadata)."""

    profile: MeasuredProfile  # its start_epoch_s: the first logged CTD sample
    latitude_deg: float
    files: tuple[Path, ...]
    floor: SeaFloor | None = None  # the floor the glider saw, on the casts' clock
    floor_note: str = ""  # why there is no floor


def science_logs(path: str | Path) -> list[Path]:
    """The science logs a path names: one *.ebd file, or every *.ebd in a directory."""
    return logs_in(path, "*.ebd", "science log")


def logs_in(path: str | Path, pattern: str, what: str) -> list[Path]:
    """The Slocum logs (`what`: 'science log', 'flight log') a path names: one file
    matching `pattern` ('*.ebd'), or every one in a directory."""
    path = Path(path)
    if path.is_dir():
        files = sorted(path.glob(pattern))
        if not files:
            raise OceanFileError(f"{path}: no Slocum {what}s ({pattern}) in this directory")
        return files
    if path.suffix.lower() != pattern[1:]:
        raise OceanFileError(f"{path}: not a Slocum {what} ({pattern}) or a directory of them")
    if not path.is_file():
        raise OceanFileError(f"{path}: no such file")
    return [path]


def _cache_dir(files: list[Path]) -> str | None:
    """dbdreader's sensor caches: the logs' `cac` directory when there is one."""
    cac = files[0].parent / "cac"
    return str(cac) if cac.is_dir() else None


def _flight_logs(files: list[Path], cache: str | None):
    """The flight logs (*.dbd) beside the science logs, as one dbdreader.MultiDBD, or
    (None, why not)."""
    import dbdreader

    flight = [f.with_suffix(".dbd") for f in files if f.with_suffix(".dbd").is_file()]
    if not flight:
        return None, "no flight logs (*.dbd) beside the science logs"
    try:
        check_log_headers(flight)
        return dbdreader.MultiDBD(filenames=[str(f) for f in flight], cacheDir=cache), ""
    except (GliderplanError, dbdreader.DbdError, OSError, ValueError) as err:
        return None, f"the flight logs cannot be read: {err}"


def _latitude_deg(logs) -> float:
    """Median GPS latitude [deg] from the flight logs (None: the default)."""
    import dbdreader

    if logs is None:
        return DEFAULT_LATITUDE_DEG
    try:
        _, lat = logs.get("m_gps_lat")
    except (dbdreader.DbdError, OSError, ValueError):
        return DEFAULT_LATITUDE_DEG
    lat = lat[np.isfinite(lat) & (np.abs(lat) <= 90.0)]
    return float(np.median(lat)) if lat.size else DEFAULT_LATITUDE_DEG


def floor_readings(logs) -> tuple[np.ndarray, np.ndarray, str]:
    """(times [s since 1970], depths [m], what they are) of the sea floor the flight logs
    saw: `m_water_depth` where positive, else `m_depth + m_altitude` where the altimeter
    had a reading; empty arrays and why where they hold neither."""
    import dbdreader

    for sensors in (("m_water_depth",), ("m_altitude", "m_depth")):
        try:
            time, *values = logs.get_sync(*sensors) if len(sensors) > 1 else \
                logs.get(*sensors)
        except (dbdreader.DbdError, OSError, ValueError):
            continue
        depth = values[0] if len(sensors) == 1 else values[0] + values[1]
        valid = np.isfinite(time) & np.isfinite(depth) & (values[0] > 0.0)
        if valid.any():
            return time[valid], depth[valid], " + ".join(reversed(sensors))
    return np.empty(0), np.empty(0), ("the flight logs hold no floor reading (m_water_depth, "
                                      "or m_depth with an m_altitude reading)")


def _floor(logs, start_epoch_s: float, path: str | Path) -> tuple[SeaFloor | None, str]:
    """The floor the glider saw on the casts' clock (time 0 at `start_epoch_s`), or
    (None, why not)."""
    if logs is None:
        return None, "no flight logs (*.dbd) beside the science logs, which give the floor"
    time, depth, what = floor_readings(logs)
    if not len(time):
        return None, what
    times, first = np.unique(time - start_epoch_s, return_index=True)
    return SeaFloor(tuple(float(t) for t in times), tuple(float(d) for d in depth[first]),
                    f"{path}: {what} of the flight logs, {len(times)} readings along time, "
                    "met when the glider met them"), ""


def leg_starts(depth_m: np.ndarray, turn_m: float = TURN_M) -> list[int]:
    """Indices where each leg (dive or climb) of a depth series begins: at the previous
    leg's extreme, once the glider has come `turn_m` back from it (hysteresis against
    noise)."""
    starts = [0]
    extreme = 0  # index of the deepest (diving) or shallowest (climbing) point so far
    direction = 0  # +1 diving, -1 climbing, 0 not yet moved turn_m
    for i in range(1, len(depth_m)):
        d = depth_m[i]
        if direction == 0:
            if abs(d - depth_m[0]) >= turn_m:
                direction, extreme = (1 if d > depth_m[0] else -1), i
        elif (d - depth_m[extreme]) * direction > 0:
            extreme = i
        elif (depth_m[extreme] - d) * direction >= turn_m:
            starts.append(extreme)
            direction, extreme = -direction, i
    return starts


def read_logged_ocean(path: str | Path) -> LoggedOcean:
    """The ocean of the Slocum science logs at `path` (a *.ebd file or a directory)."""
    import dbdreader
    import gsw

    files = science_logs(path)
    check_log_headers(files)
    cache = _cache_dir(files)
    try:
        logs = dbdreader.MultiDBD(filenames=[str(f) for f in files], cacheDir=cache)
        time, temp, pressure, conductivity = logs.get_sync(
            "sci_water_temp", "sci_water_pressure", "sci_water_cond")
    except (dbdreader.DbdError, OSError, ValueError) as err:
        raise OceanFileError(f"{path}: cannot read the science logs: {err}") from None
    valid = (temp > 0.0) & (pressure > 0.0) & (conductivity > 0.0) & np.isfinite(time)
    if valid.sum() < 2:
        raise OceanFileError(f"{path}: no CTD samples (sci_water_temp, sci_water_cond, "
                             "sci_water_pressure) in the science logs")
    time, temp = time[valid], temp[valid]
    pressure_dbar = pressure[valid] * BAR_TO_DBAR
    flight, why = _flight_logs(files, cache)
    latitude = _latitude_deg(flight)
    salinity = gsw.SP_from_C(conductivity[valid] * S_M_TO_MS_CM, temp, pressure_dbar)
    depth = -gsw.z_from_p(pressure_dbar, latitude)
    profile = _casts(time - time[0], depth, temp, salinity, float(time[0]))
    if profile is None:
        raise OceanFileError(f"{path}: the CTD samples hold no dive or climb of "
                             f"{MIN_LEG_M:g} m or more")
    floor, floor_note = _floor(flight, float(time[0]), path) if flight is not None else \
        (None, why)
    return LoggedOcean(profile, latitude, tuple(files), floor, floor_note)


def _casts(time_s: np.ndarray, depth_m: np.ndarray, temp_c: np.ndarray,
           salinity_psu: np.ndarray, start_epoch_s: float) -> MeasuredProfile | None:
    """One cast per leg, binned by depth onto a grid shared by all casts."""
    starts = leg_starts(depth_m) + [len(depth_m)]
    grid = np.arange(np.floor(depth_m.min() / BIN_M), np.floor(depth_m.max() / BIN_M) + 1)
    centres = (grid + 0.5) * BIN_M
    casts_s, temps, salts = [], [], []
    for a, b in zip(starts, starts[1:], strict=False):
        d = depth_m[a:b + 1]
        if d.size < 2 or d.max() - d.min() < MIN_LEG_M:
            continue
        bins = np.floor(d / BIN_M)
        used = np.unique(bins)
        at = (used + 0.5) * BIN_M
        t_mean = [temp_c[a:b + 1][bins == k].mean() for k in used]
        s_mean = [salinity_psu[a:b + 1][bins == k].mean() for k in used]
        casts_s.append(float(time_s[a:b + 1].mean()))
        temps.append(tuple(float(v) for v in np.interp(centres, at, t_mean)))
        salts.append(tuple(float(v) for v in np.interp(centres, at, s_mean)))
    if not casts_s:
        return None
    return MeasuredProfile(tuple(float(c) for c in centres), tuple(casts_s), tuple(temps),
                           tuple(salts), start_epoch_s)
