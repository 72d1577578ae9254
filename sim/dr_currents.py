"""Depth-averaged currents from the dead-reckoning error between GPS fixes, the Slocum's
own method, for flight logs that do not hold the glider's `m_water_vx`/`m_water_vy`.

A segment runs from the last fix before a dive to the first fix after it. Dead
reckoning through the water moves the glider by its own speed estimate (`m_speed`,
horizontal, through the water) along its heading (`m_heading`, true); what the fixes
moved it beyond that, over the segment's time, is the current:
`current = (fix displacement - dead-reckoned displacement) / duration`.

Its uncertainty (1 sigma per component) adds the two fixes' position errors and the
speed estimate's error in quadrature, over the duration:
`sigma = sqrt(2 GPS_SIGMA_M^2 + (SPEED_ERROR * distance through the water)^2) / duration`.
The time at the surface counts as the current's: a wind drift there is in the estimate,
as it is in the glider's.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.contract import EARTH_RADIUS_M

DIVE_DEPTH_M = 2.0  # deeper between two fixes, the glider dived: a segment
# a shorter one is a fix logged again as the glider leaves the surface, no dive: over
# seconds, a fix's error alone is a current of metres per second
MIN_SEGMENT_S = 300.0
GPS_SIGMA_M = 10.0  # [m] one fix's position error, 1 sigma (a Slocum's GPS, horizontal)
SPEED_ERROR = 0.1  # the glider's speed estimate's relative error, 1 sigma


@dataclass(frozen=True)
class Track:
    """What a glider's flight logs hold for dead reckoning, each on its own clock [s since
    1970]: fixes (lat, lon [deg]), speed through the water [m s-1], true heading [rad],
    depth [m]."""

    fix_s: np.ndarray
    lat_deg: np.ndarray
    lon_deg: np.ndarray
    speed_s: np.ndarray
    speed_mps: np.ndarray
    heading_s: np.ndarray
    heading_rad: np.ndarray
    depth_s: np.ndarray
    depth_m: np.ndarray


@dataclass(frozen=True)
class SegmentCurrents:
    """One estimate per segment: the fix that ends it [s since 1970], the current [m s-1]
    and its 1-sigma uncertainty per component [m s-1]."""

    time_s: np.ndarray
    north_mps: np.ndarray
    east_mps: np.ndarray
    sigma_mps: np.ndarray
    start_s: np.ndarray  # the fix that begins each segment [s since 1970]


def segments(track: Track) -> list[tuple[int, int]]:
    """(i, j) indices of the fixes that begin and end each dive: consecutive fixes at
    least MIN_SEGMENT_S apart with the glider deeper than DIVE_DEPTH_M between them."""
    deep_s = track.depth_s[np.nan_to_num(track.depth_m) > DIVE_DEPTH_M]
    if not len(deep_s):
        return []
    # deep samples strictly between consecutive fixes
    before = np.searchsorted(deep_s, track.fix_s[:-1], side="right")
    after = np.searchsorted(deep_s, track.fix_s[1:], side="left")
    long_enough = np.diff(track.fix_s) >= MIN_SEGMENT_S
    return [(int(i), int(i) + 1) for i in np.flatnonzero((after > before) & long_enough)]


def through_water_m(track: Track, start_s: float, end_s: float) -> tuple[float, float]:
    """(north, east) [m] the glider's speed through the water carried it along its
    heading from `start_s` to `end_s` (trapezoids on the heading's clock, the speed
    interpolated onto it; an unlogged speed is none)."""
    keep = (track.heading_s >= start_s) & (track.heading_s <= end_s)
    t = track.heading_s[keep]
    if len(t) < 2:
        return 0.0, 0.0
    speed = np.interp(t, track.speed_s, np.nan_to_num(track.speed_mps))
    heading = track.heading_rad[keep]
    return (float(np.trapezoid(speed * np.cos(heading), t)),
            float(np.trapezoid(speed * np.sin(heading), t)))


def segment_currents(track: Track) -> SegmentCurrents:
    """The current of every segment of `track`, with its uncertainty."""
    rows = []
    scale = EARTH_RADIUS_M * np.pi / 180.0
    for i, j in segments(track):
        t0, t1 = float(track.fix_s[i]), float(track.fix_s[j])
        north = (track.lat_deg[j] - track.lat_deg[i]) * scale
        east = (track.lon_deg[j] - track.lon_deg[i]) * scale * np.cos(
            np.radians(track.lat_deg[i]))
        dr_north, dr_east = through_water_m(track, t0, t1)
        duration = t1 - t0
        sigma = np.hypot(np.sqrt(2.0) * GPS_SIGMA_M,
                         SPEED_ERROR * np.hypot(dr_north, dr_east)) / duration
        rows.append((t1, (north - dr_north) / duration, (east - dr_east) / duration, sigma,
                     t0))
    values = np.array(rows, float).reshape(-1, 5)
    return SegmentCurrents(*(values[:, k] for k in (0, 1, 2, 3)), start_s=values[:, 4])


def read_track(logs) -> Track:
    """The dead-reckoning inputs of a dbdreader.MultiDBD's flight logs (ValueError, or
    dbdreader's error, where one is missing)."""
    fix_s, lat = logs.get("m_gps_lat")
    lon_s, lon = logs.get("m_gps_lon")
    if len(fix_s) != len(lon_s) or not np.array_equal(fix_s, lon_s):
        lon = np.interp(fix_s, lon_s, lon)
    speed_s, speed = logs.get("m_speed")
    heading_s, heading = logs.get("m_heading")
    depth_s, depth = logs.get("m_depth")
    good = np.isfinite(lat) & np.isfinite(lon)
    return Track(np.asarray(fix_s[good], float), np.asarray(lat[good], float),
                 np.asarray(lon[good], float), np.asarray(speed_s, float),
                 np.asarray(speed, float), np.asarray(heading_s, float),
                 np.asarray(heading, float), np.asarray(depth_s, float),
                 np.asarray(depth, float))
