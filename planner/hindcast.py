"""How well the surfacing forecast does on a real flight: from each surfacing's fixes
and the current the glider measured up to it, forecast the next surfacings and compare
them with the fixes the glider then took (`gliderplan hindcast LOGDIR`).

At surfacing k the forecast knows what a pilot knows: the last fix before the dive, the
depth-averaged current last logged (`m_water_vx`, `m_water_vy`; in logs without them,
the current of the dead-reckoning error between fixes, sim.dr_currents), the waypoint
(`c_wpt_lat`, `c_wpt_lon`), the glider's own estimate of its speed through the water
(`m_avg_speed`), and how long the last dive and surfacing lasted (dives keep their
length while the mission does not change). How far these stray is drawn from the
flight so far: the spread of its dives' lengths and of the currents it measured, at
least the surfacing forecast's own (`planner.surfacings`). Surfacings are the runs of GPS fixes
(`m_gps_lat`, `m_gps_lon`) with less than `SURFACING_GAP_S` between them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gliderplan.planner.surfacings import (
    CURRENT_SIGMA_MPS,
    DIVE_SIGMA,
    Voyage,
    forecast_surfacings,
)
from gliderplan.sim.currents import CurrentError, UniformCurrent

SURFACING_GAP_S = 300.0  # [s] fixes further apart belong to different surfacings
MIN_DIVE_S = 120.0  # [s] a shorter gap is a lost fix, not a dive


@dataclass(frozen=True)
class Check:
    """One forecast surfacing against the glider's fix."""

    from_k: int  # the surfacing it was forecast from
    ahead: int  # surfacings ahead (1: the next)
    horizon_s: float  # [s] from the dive to the fix
    error_m: float  # from the forecast position to the fix
    time_error_s: float  # forecast less real time of the fix
    ellipse_m: tuple[float, float]
    inside: bool  # the fix lies in the 90 % ellipse


@dataclass(frozen=True)
class _Fixes:
    start_s: np.ndarray  # first fix of each surfacing [s since 1970]
    end_s: np.ndarray  # last fix
    first: np.ndarray  # (lat, lon) of the first fix, rows
    last: np.ndarray  # (lat, lon) of the last


def _latest(times: np.ndarray, values: np.ndarray, at_s: float) -> float:
    """The last value logged at or before `at_s` (NaN: none)."""
    i = int(np.searchsorted(times, at_s, side="right")) - 1
    return float(values[i]) if i >= 0 else math.nan


def _series(logs, name: str, path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    import dbdreader

    try:
        times, values = logs.get(name)
    except (dbdreader.DbdError, OSError, ValueError):
        raise CurrentError(f"{path}: the flight logs have no {name}") from None
    keep = np.isfinite(values)
    return np.asarray(times[keep], float), np.asarray(values[keep], float)


def surfacing_fixes(logs, path: str | Path) -> _Fixes:
    """The logged GPS fixes grouped into surfacings."""
    t, lat = _series(logs, "m_gps_lat", path)
    t_lon, lon = _series(logs, "m_gps_lon", path)
    lon = np.interp(t, t_lon, lon)
    good = (np.abs(lat) <= 90.0) & (np.abs(lon) <= 180.0)
    t, lat, lon = t[good], lat[good], lon[good]
    if len(t) < 3:
        raise CurrentError(f"{path}: fewer than 3 GPS fixes (m_gps_lat, m_gps_lon)")
    breaks = np.where(np.diff(t) > SURFACING_GAP_S)[0]
    starts, ends = np.r_[0, breaks + 1], np.r_[breaks, len(t) - 1]
    return _Fixes(t[starts], t[ends], np.c_[lat[starts], lon[starts]],
                  np.c_[lat[ends], lon[ends]])


def hindcast(path: str | Path, ahead: int = 2, draws: int = 200) -> list[Check]:
    """Each surfacing after the first forecast from the fixes and currents up to it,
    `ahead` surfacings on, against the fixes the glider took."""
    from gliderplan.sim.current_files import flight_logs, logged_currents

    logs = flight_logs(path)
    fixes = surfacing_fixes(logs, path)
    currents = logged_currents(logs, path)
    logged = {"m_water_vx": (currents.time_s, currents.east_mps),
              "m_water_vy": (currents.time_s, currents.north_mps),
              **{name: _series(logs, name, path) for name in
                 ("c_wpt_lat", "c_wpt_lon", "m_avg_speed")}}
    checks = []
    for k in range(1, len(fixes.start_s) - 1):
        dive_s = fixes.start_s[k] - fixes.end_s[k - 1]
        at = fixes.end_s[k]
        value = {name: _latest(*series, at) for name, series in logged.items()}
        if dive_s < MIN_DIVE_S or not all(map(math.isfinite, value.values())):
            continue
        waypoint = (value["c_wpt_lat"], value["c_wpt_lon"])
        dives = fixes.start_s[1:k + 1] - fixes.end_s[:k]
        measured = [series[1][series[0] <= at] for name, series in logged.items()
                    if name in ("m_water_vx", "m_water_vy")]
        voyage = Voyage(*fixes.last[k], at, () if waypoint == (0.0, 0.0) else (waypoint,),
                        value["m_avg_speed"], dive_s, fixes.end_s[k] - fixes.start_s[k],
                        UniformCurrent(value["m_water_vy"], value["m_water_vx"]),
                        max(CURRENT_SIGMA_MPS, *(float(np.std(m)) for m in measured)),
                        max(DIVE_SIGMA * dive_s, float(np.std(dives))))
        count = min(ahead, len(fixes.start_s) - 1 - k)
        for h, surfacing in enumerate(forecast_surfacings(voyage, count, draws), start=1):
            real = fixes.first[k + h]
            checks.append(Check(k, h, float(fixes.start_s[k + h] - at),
                                surfacing.distance_m(*real),
                                surfacing.time_s - float(fixes.start_s[k + h] - at),
                                surfacing.ellipse_m, surfacing.inside(*real)))
    return checks


def summary(checks: list[Check]) -> list[dict]:
    """Per surfacings ahead: count, median horizon [s], median and 90th-percentile
    error [m], share of fixes inside the 90 % ellipse."""
    rows = []
    for h in sorted({c.ahead for c in checks}):
        mine = [c for c in checks if c.ahead == h]
        errors = np.array([c.error_m for c in mine])
        rows.append({"ahead": h, "count": len(mine),
                     "median_horizon_s": float(np.median([c.horizon_s for c in mine])),
                     "median_error_m": float(np.median(errors)),
                     "p90_error_m": float(np.percentile(errors, 90)),
                     "inside_ellipse": float(np.mean([c.inside for c in mine]))})
    return rows
