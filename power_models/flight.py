"""Steady-glide flight model of a buoyancy glider (Merckelbach et al. 2019).

Net buoyancy B = rho g dV lifts (or sinks) the glider; lift L = 1/2 rho S U^2 (aw + ah)
alpha and drag D = 1/2 rho S U^2 (Cd0 + Cd1 alpha^2) balance it along a glide path
that is steeper than the pitch by the angle of attack alpha:

    tan(theta + alpha) = D / L = (Cd0 + Cd1 alpha^2) / ((aw + ah) alpha)
    U^2 = 2 B sin(gamma) / (rho S (Cd0 + Cd1 alpha^2)),   gamma = theta + alpha
    u = U cos(gamma),  w = U sin(gamma)

Notes
-----
The glider is taken as trimmed neutral at zero pumped volume, so B = rho g dV; hull
compressibility and thermal expansion (the Vg(1 - eps p) and m terms of the full model)
only shift that neutral point. For a given pitch alpha does not depend on dV, so u grows
with sqrt(dV) and the inverse (`ballast_for_speed`) is closed-form. Dives and climbs
are symmetric: angles and volumes are magnitudes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

_BISECTION_STEPS = 60  # halves the bracket to ~1e-18 rad: exact in double precision


@dataclass(frozen=True)
class FlightParams:
    """Hydrodynamic parameters. SI units: [kg m-3], [m s-2], [m2], [rad-1], [1]."""

    rho_kg_m3: float
    g_m_s2: float
    wing_area_m2: float
    lift_wing_per_rad: float  # aw
    lift_hull_per_rad: float  # ah
    drag_cd0: float
    drag_cd1_per_rad2: float


def _check_pitch(pitch_rad: np.ndarray) -> None:
    if np.any(~np.isfinite(pitch_rad)) or np.any((pitch_rad <= 0.0) | (pitch_rad >= math.pi / 2)):
        raise ValueError("pitch must lie strictly between 0 and pi/2 rad (a magnitude)")


def angle_of_attack_rad(params: FlightParams, pitch_rad: np.ndarray | float) -> np.ndarray:
    """Angle of attack [rad] of a steady glide at pitch `pitch_rad` [rad] (magnitude)."""
    theta = np.asarray(pitch_rad, float)
    _check_pitch(theta)
    lift_slope = params.lift_wing_per_rad + params.lift_hull_per_rad
    low = np.zeros_like(theta)
    high = (math.pi / 2 - theta) * (1.0 - 1e-9)

    # f(alpha) = drag/lift coefficient minus tan(glide angle): positive at 0, tends to
    # -inf as the glide path turns vertical, one root in between.
    def residual(alpha: np.ndarray) -> np.ndarray:
        drag = params.drag_cd0 + params.drag_cd1_per_rad2 * alpha**2
        return drag - lift_slope * alpha * np.tan(theta + alpha)

    for _ in range(_BISECTION_STEPS):
        mid = 0.5 * (low + high)
        positive = residual(mid) > 0.0
        low = np.where(positive, mid, low)
        high = np.where(positive, high, mid)
    return 0.5 * (low + high)


def _glide_geometry(
    params: FlightParams, pitch_rad: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Glide-path angle [rad] and drag coefficient [1] at a pitch."""
    alpha = angle_of_attack_rad(params, pitch_rad)
    gamma = np.asarray(pitch_rad, float) + alpha
    drag = params.drag_cd0 + params.drag_cd1_per_rad2 * alpha**2
    return gamma, drag


def glide(
    params: FlightParams, pitch_rad: np.ndarray | float, ballast_cc: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal and vertical speed (u, w) [m s-1] at pitch [rad] and buoyancy volume [cc].

    Both are magnitudes; a zero volume gives zero speed.
    """
    volume = np.asarray(ballast_cc, float)
    if np.any(volume < 0.0):
        raise ValueError("ballast volume must be >= 0 cc (a magnitude either side of neutral)")
    gamma, drag = _glide_geometry(params, pitch_rad)
    buoyancy_n = params.rho_kg_m3 * params.g_m_s2 * volume * 1e-6
    speed = np.sqrt(
        2.0 * buoyancy_n * np.sin(gamma) / (params.rho_kg_m3 * params.wing_area_m2 * drag)
    )
    return speed * np.cos(gamma), speed * np.sin(gamma)


def glide_slope(params: FlightParams, pitch_rad: np.ndarray | float) -> np.ndarray:
    """w / u [1] of the glide path at a pitch (independent of the buoyancy volume)."""
    gamma, _ = _glide_geometry(params, pitch_rad)
    return np.tan(gamma)


def ballast_for_speed(
    params: FlightParams, u_mps: np.ndarray | float, pitch_rad: np.ndarray | float
) -> np.ndarray:
    """Buoyancy volume [cc] that makes the glider fly at horizontal speed `u_mps` [m s-1]."""
    u = np.asarray(u_mps, float)
    if np.any(u < 0.0):
        raise ValueError("speed must be >= 0 m/s")
    gamma, drag = _glide_geometry(params, pitch_rad)
    speed = u / np.cos(gamma)
    buoyancy_n = speed**2 * params.rho_kg_m3 * params.wing_area_m2 * drag / (2.0 * np.sin(gamma))
    return buoyancy_n / (params.rho_kg_m3 * params.g_m_s2) * 1e6
