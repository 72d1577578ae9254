"""Steady-glide flight model of a buoyancy glider (Merckelbach et al. 2019, the model that
`gliderflight` fits to Slocum logs).

Net buoyancy B = g [rho (Vg (1 - eps p) + dV) - m] lifts (or sinks) the glider; lift
L = 1/2 rho S U^2 (aw + ah) alpha and drag D = 1/2 rho S U^2 (Cd0 + Cd1 alpha^2) balance
it along a glide path that is steeper than the pitch by the angle of attack alpha:

    tan(theta + alpha) = D / L = (Cd0 + Cd1 alpha^2) / ((aw + ah) alpha)
    U^2 = 2 B sin(gamma) / (rho S (Cd0 + Cd1 alpha^2)),   gamma = theta + alpha
    u = U cos(gamma),  w = U sin(gamma)

Notes
-----
B / (rho g) is the net buoyancy volume b [cc]. With the trim t, the glider's net buoyancy at
zero pumped volume at the surface in water of the reference density rho0 (positive: light),
the mass is m = rho0 (Vg - t) and

    b(z) = dV + t - Vg eps p(z) + (Vg - t) (1 - rho0 / rho(z)),   p(z) = rho0 g z

so a glider trimmed neutral (t = 0) in uniform water of rho0 without compressibility flies
on b = dV: dives and climbs are then symmetric. A real glider is trimmed a little light or
heavy, is squeezed at depth and flies through water whose density changes with depth,
which makes its dives and climbs differ. For a given pitch alpha does not depend on b, so
the speed grows with sqrt(b) and `ballast_for_speed` is closed-form.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from gliderplan.contract.errors import GliderplanError

_BISECTION_STEPS = 12  # halves the bracket (< 1.6 rad) to < 4e-4 rad ...
_NEWTON_STEPS = 3  # ... which Newton's method squares below double precision
_DEPTH_CELLS = 128  # midpoint rule over a yo band: exact for uniform water, 1e-5 with a profile

Array = np.ndarray


class FlightModelError(GliderplanError, ValueError):
    """A glide the vehicle cannot fly (a yo deeper than its trim and pumped volume can
    climb back from): bad input, exit 1, said in one line."""


@dataclass(frozen=True)
class FlightParams:
    """Hydrodynamic and buoyancy parameters. SI units: [kg m-3], [m s-2], [m2], [rad-1], [1];
    volumes [cc], compressibility [Pa-1]."""

    rho_kg_m3: float  # reference water density: the trim is given in this water
    g_m_s2: float
    wing_area_m2: float
    lift_wing_per_rad: float  # aw
    lift_hull_per_rad: float  # ah
    drag_cd0: float
    drag_cd1_per_rad2: float
    hull_volume_cc: float = 0.0  # Vg
    trim_cc: float = 0.0  # net buoyancy at zero pumped volume at the surface, positive light
    compressibility_per_pa: float = 0.0  # eps: the hull's relative volume loss per Pa


@dataclass(frozen=True)
class DensityProfile:
    """In-situ water density [kg m-3] against depth [m], linear between the points and held
    beyond the ends (an `ocean profile` measured by a CTD)."""

    depth_m: Array
    rho_kg_m3: Array

    def at(self, depth_m: Array | float) -> Array:
        return np.interp(depth_m, self.depth_m, self.rho_kg_m3)


def _check_pitch(pitch_rad: np.ndarray) -> None:
    bad = ~np.isfinite(pitch_rad) | (pitch_rad <= 0.0) | (pitch_rad >= math.pi / 2)
    if np.any(bad):
        flown = float(np.asarray(pitch_rad, float)[bad].flat[0])
        raise FlightModelError(f"the glider would fly a pitch of {flown:.4g} rad (with a "
                               "calibrated vehicle, the pitch commanded plus its pitch error): "
                               "a glide's pitch must lie strictly between 0 and pi/2 rad")


def angle_of_attack_rad(params: FlightParams, pitch_rad: np.ndarray | float) -> np.ndarray:
    """Angle of attack [rad] of a steady glide at pitch `pitch_rad` [rad] (magnitude)."""
    if np.ndim(pitch_rad) == 0:  # a planner asks of the same few pitches, state by state
        return np.asarray(_angle_of_attack_at(params, float(pitch_rad)))
    return _angle_of_attack(params, np.asarray(pitch_rad, float))


@functools.lru_cache(maxsize=1024)
def _angle_of_attack_at(params: FlightParams, pitch_rad: float) -> float:
    return float(_angle_of_attack(params, np.asarray(pitch_rad)))


def _angle_of_attack(params: FlightParams, theta: np.ndarray) -> np.ndarray:
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
    # Newton from inside the bracket: f is smooth with f' < 0 there, so each step squares
    # the error (2e-4 rad -> 1e-8 -> 1e-16)
    alpha = 0.5 * (low + high)
    for _ in range(_NEWTON_STEPS):
        tangent = np.tan(theta + alpha)
        slope = (2.0 * params.drag_cd1_per_rad2 * alpha
                 - lift_slope * (tangent + alpha * (1.0 + tangent**2)))
        alpha = np.clip(alpha - residual(alpha) / slope, low, high)
    return alpha


def glide_geometry(
    params: FlightParams, pitch_rad: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Glide-path angle gamma [rad] and the speed per root buoyancy volume
    U / sqrt(b) [m s-1 cc-1/2] at a pitch (neither depends on b)."""
    alpha = angle_of_attack_rad(params, pitch_rad)
    gamma = np.asarray(pitch_rad, float) + alpha
    drag = params.drag_cd0 + params.drag_cd1_per_rad2 * alpha**2
    # U^2 = 2 rho g b sin(gamma) / (rho S Cd): the density cancels
    per_root_cc = np.sqrt(2.0 * params.g_m_s2 * 1e-6 * np.sin(gamma) / (params.wing_area_m2 * drag))
    return gamma, per_root_cc


def glide(
    params: FlightParams, pitch_rad: np.ndarray | float, ballast_cc: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Horizontal and vertical speed (u, w) [m s-1] at pitch [rad] on a net buoyancy volume
    [cc] (the pumped volume of a glider trimmed neutral).

    Both are magnitudes; a zero volume gives zero speed.
    """
    volume = np.asarray(ballast_cc, float)
    if np.any(volume < 0.0):
        raise ValueError("ballast volume must be >= 0 cc (a magnitude either side of neutral)")
    gamma, per_root_cc = glide_geometry(params, pitch_rad)
    speed = per_root_cc * np.sqrt(volume)
    return speed * np.cos(gamma), speed * np.sin(gamma)


def glide_slope(params: FlightParams, pitch_rad: np.ndarray | float) -> np.ndarray:
    """w / u [1] of the glide path at a pitch (independent of the buoyancy volume)."""
    gamma, _ = glide_geometry(params, pitch_rad)
    return np.tan(gamma)


def ballast_for_speed(
    params: FlightParams, u_mps: np.ndarray | float, pitch_rad: np.ndarray | float
) -> np.ndarray:
    """Net buoyancy volume [cc] that makes the glider fly at horizontal speed `u_mps` [m s-1]."""
    u = np.asarray(u_mps, float)
    if np.any(u < 0.0):
        raise ValueError("speed must be >= 0 m/s")
    gamma, per_root_cc = glide_geometry(params, pitch_rad)
    return (u / (np.cos(gamma) * per_root_cc)) ** 2


def net_buoyancy_cc(
    params: FlightParams,
    pumped_cc: Array | float,
    depth_m: Array | float,
    rho_kg_m3: Array | float | None = None,
) -> Array | float:
    """Net buoyancy volume b [cc], positive up, at a signed pumped volume [cc] and depth [m]
    in water of in-situ density `rho_kg_m3` (default: the reference density).

    Plain arithmetic, so that the simulator's per-tick floats stay floats.
    """
    pressure_pa = params.rho_kg_m3 * params.g_m_s2 * depth_m
    squeeze_cc = params.hull_volume_cc * params.compressibility_per_pa * pressure_pa
    b = pumped_cc + params.trim_cc - squeeze_cc
    if rho_kg_m3 is not None:
        b = b + (params.hull_volume_cc - params.trim_cc) * (1.0 - params.rho_kg_m3 / rho_kg_m3)
    return b


@dataclass(frozen=True)
class Leg:
    """One glide across a depth band: its duration [s], mean vertical speed [m s-1] (band /
    duration) and horizontal distance [m]."""

    time_s: Array
    w_mps: Array
    distance_m: Array

    def __getitem__(self, k: int) -> Leg:
        """The k-th leg of a solution broadcast over several (`glide_leg` with arrays)."""
        return Leg(*(np.asarray(x)[k] for x in (self.time_s, self.w_mps, self.distance_m)))


def glide_leg(
    params: FlightParams,
    top_m: Array | float,
    bottom_m: Array | float,
    pitch_rad: Array | float,
    pumped_cc: Array | float,
    climbing: bool,
    ocean: DensityProfile | None = None,
) -> Leg:
    """A steady dive (or climb) across [top_m, bottom_m] at pitch [rad] (magnitude) with
    `pumped_cc` [cc] (magnitude) pumped below (above) neutral, through `ocean` (default:
    uniform water of the reference density). Broadcasts over its array arguments.

    Raises FlightModelError where the glider's trim leaves it without buoyancy to glide.
    """
    top = np.asarray(top_m, float)
    bottom = np.asarray(bottom_m, float)
    if np.any(bottom - top <= 0.0) or np.any(top < 0.0):
        raise FlightModelError("a glide needs 0 <= top < bottom")
    gamma, per_root_cc = glide_geometry(params, pitch_rad)
    sign = 1.0 if climbing else -1.0
    cells = (np.arange(_DEPTH_CELLS) + 0.5) / _DEPTH_CELLS
    depth = top[..., None] + (bottom - top)[..., None] * cells
    rho = None if ocean is None else ocean.at(depth)
    volume = sign * net_buoyancy_cc(
        params, sign * np.asarray(pumped_cc, float)[..., None], depth, rho
    )
    if np.any(volume <= 0.0):
        stuck = float(np.min(np.broadcast_to(depth, volume.shape)[volume <= 0.0]))
        raise FlightModelError(
            f"the glider cannot {'climb' if climbing else 'dive'} below {stuck:.0f} m: its "
            "trim and the water (the hull squeezed by sea pressure) leave it without "
            "buoyancy at this pumped volume"
        )
    w = (per_root_cc * np.sin(gamma))[..., None] * np.sqrt(volume)
    band = bottom - top
    time = band * np.mean(1.0 / w, axis=-1)
    return Leg(time, band / time, band / np.tan(gamma))
