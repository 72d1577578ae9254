"""How a Slocum glider knows where it is under water and steers in a current: its
position estimate and its current correction.

Under water the glider dead-reckons: its estimate moves with its speed through the water
along its heading, plus the depth-averaged current it last measured (`m_water_vx`,
`m_water_vy`). At each GPS fix the estimate is set to the fix, and the difference between
the two, over the time since the previous fix, corrects the measured current: in a
steady current the second dive's estimate is right. With current correction
(`u_use_current_correction`) the glider heads upstream of its waypoint so that, in the
current it measured, its track over the ground points at it.

The simulated glider (`sim.vehicle.GliderSim`) is the model of record; sim/flight.c
flies it bit for bit in the C flight.
"""

from __future__ import annotations

import math

TWO_PI = 2.0 * math.pi


def corrected_heading(course_rad: float, speed_mps: float, north_mps: float,
                      east_mps: float) -> float:
    """The heading [rad, 0 to 2 pi] that makes good `course_rad` over the ground through
    water of speed `speed_mps` [m s-1] in a current (`north_mps`, `east_mps`) [m s-1]:
    the cross-course part of the current cancelled, asin(-c_cross / speed); a current
    across faster than the glider is met head on across (+-90 degrees). Without a speed
    through the water the course is flown as it is."""
    if not speed_mps > 0.0:
        return course_rad
    across = east_mps * math.cos(course_rad) - north_mps * math.sin(course_rad)
    ratio = -across / speed_mps
    ratio = 1.0 if ratio > 1.0 else -1.0 if ratio < -1.0 else ratio
    heading = course_rad + math.asin(ratio)
    if heading < 0.0:
        heading += TWO_PI
    elif heading >= TWO_PI:
        heading -= TWO_PI
    return heading


def updated_current(north_mps: float, east_mps: float, error_north_m: float,
                    error_east_m: float, since_fix_s: float) -> tuple[float, float]:
    """The depth-averaged current [m s-1] measured at a GPS fix: the one dead reckoning
    flew with, plus the fix's distance from the estimate (`error_*_m`, fix less estimate)
    over the time since the previous fix [s] (none yet: unchanged)."""
    if not since_fix_s > 0.0:
        return north_mps, east_mps
    return north_mps + error_north_m / since_fix_s, east_mps + error_east_m / since_fix_s
