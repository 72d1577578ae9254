"""Fitting the steady-glide flight model to a Slocum log with `gliderflight`.

gliderflight (Merckelbach et al. 2019) minimises the misfit between the model's vertical
speed and the depth rate the pressure sensor saw, over the samples where the glider
glides steadily (below the surface layer, away from the turns and pump runs, at a real
pitch). It fits the parasite drag Cd0, the mass (with the hull volume it sets the trim)
and the hull's compressibility; the water's in-situ density comes from the logged CTD.

Our `flight.py` is the same steady-state model; gliderflight only fits it. Its angle of
attack is solved here with `flight.angle_of_attack_rad` on a table of pitches (gliderflight
solves 100 pitches with fsolve at every step of the minimiser: 20x slower, same answer).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract.errors import GliderplanError
from gliderplan.power_models import flight
from gliderplan.power_models.flight import FlightParams
from gliderplan.power_models.slocum_log import FlightLog

STEADY_MIN_DEPTH_M = 3.0  # below the surface layer (and the top turn)
STEADY_BOTTOM_MARGIN_M = 3.0  # above the deepest depth of the record (the bottom turns)
STEADY_MIN_PITCH_RAD = 0.25  # ~14 deg: gliding, not turning over
TURN_MARGIN_S = 20.0  # after a pump run or battery move the glider is still accelerating
# [rad] pitches the angle of attack is solved at (steady glides are 14-60 deg): linear
# interpolation between them is exact to ~1e-6 rad
_PITCH_TABLE = np.linspace(STEADY_MIN_PITCH_RAD, 1.05, 41)
PA_PER_BAR = 1e5
EPSILON_START = 5e-10  # [Pa-1] gliderflight's reference compressibility: where the fit starts


class FlightFitError(GliderplanError):
    """The log cannot support a flight fit (too few steady glides, no density)."""


@dataclass(frozen=True)
class FlightFit:
    params: FlightParams  # fitted drag, trim and compressibility, in the log's mean water
    samples: int  # steady-glide samples fitted
    rms_w_mps: float  # RMS misfit of the vertical speed over them


def steady_glides(log: FlightLog) -> np.ndarray:
    """(n,) bool: samples of steady gliding (what a steady-state model may be fitted to)."""
    moving = log.pump_moving | log.battpos_moving
    last_move = np.full(log.t_s.size, -np.inf)
    moved_at = np.where(moving, log.t_s, -np.inf)
    np.maximum.accumulate(moved_at, out=last_move)
    return (
        (log.depth_m > STEADY_MIN_DEPTH_M)
        & (log.depth_m < np.max(log.depth_m) - STEADY_BOTTOM_MARGIN_M)
        & (np.abs(log.pitch_rad) > STEADY_MIN_PITCH_RAD)
        & (log.t_s - last_move > TURN_MARGIN_S)
        & (np.sign(log.ballast_cc) == np.sign(log.pitch_rad))
        & np.isfinite(log.density_kg_m3)
    )


def depth_rate_mps(log: FlightLog) -> np.ndarray:
    """(n,) vertical speed [m s-1], positive up, from the depth record."""
    return -np.gradient(log.depth_m, log.t_s)


def _calibrator(base: FlightParams):  # noqa: ANN202 (gliderflight has no types)
    import gliderflight  # heavy (scipy), and only needed to calibrate

    class Calibrator(gliderflight.SteadyStateCalibrate):
        """gliderflight's steady-state calibration with our angle-of-attack solver."""

        def solve_for_angle_of_attack(self, pitch: np.ndarray) -> np.ndarray:
            params = replace(base, drag_cd0=float(self.Cd0))
            table = flight.angle_of_attack_rad(params, _PITCH_TABLE)
            return np.sign(pitch) * np.interp(np.abs(pitch), _PITCH_TABLE, table)

    model = Calibrator(rho0=base.rho_kg_m3)
    model.define(
        S=base.wing_area_m2,
        aw=base.lift_wing_per_rad,
        ah=base.lift_hull_per_rad,
        Cd1=base.drag_cd1_per_rad2,
    )
    return model


def fit_flight(log: FlightLog, base: FlightParams, compressibility: bool = True) -> FlightFit:
    """Fit Cd0, the trim and (if `compressibility`) the hull's compressibility to the log's
    steady glides; the other figures stay as in `base`, whose hull volume must be set.
    The result's reference density is the mean in-situ density of the steady glides."""
    if base.hull_volume_cc <= 0.0:
        raise FlightFitError("the base vehicle gives no hull volume (flight.hull_volume)")
    steady = steady_glides(log)
    if steady.sum() < 20:
        raise FlightFitError(
            f"only {int(steady.sum())} samples of steady gliding with a CTD reading "
            "(need at least 20): cannot fit the flight model"
        )
    rho_ref = float(np.mean(log.density_kg_m3[steady]))
    start = replace(base, rho_kg_m3=rho_ref)
    volume_m3 = start.hull_volume_cc * 1e-6
    model = _calibrator(start)
    model.define(
        Vg=volume_m3,
        mg=rho_ref * (volume_m3 - start.trim_cc * 1e-6),
        Cd0=start.drag_cd0,
        epsilon=(start.compressibility_per_pa or EPSILON_START) if compressibility else 0.0,
    )
    pressure_bar = rho_ref * start.g_m_s2 * log.depth_m / PA_PER_BAR  # as net_buoyancy_cc
    model.set_input_data(
        time=log.t_s,
        pressure=pressure_bar,
        pitch=log.pitch_rad,
        buoyancy_change=log.ballast_cc,
        density=np.where(np.isfinite(log.density_kg_m3), log.density_kg_m3, rho_ref),
        dhdt=depth_rate_mps(log),
    )
    model.OR(~steady)
    names = ("Cd0", "mg", "epsilon") if compressibility else ("Cd0", "mg")
    fitted = model.calibrate(*names)
    if fitted.get("epsilon", 0.0) < 0.0:  # a hull that swells with depth: not a glider
        return fit_flight(log, base, compressibility=False)
    model.define(**fitted)
    model.solve(model.input_data)
    params = replace(
        start,
        drag_cd0=float(fitted["Cd0"]),
        trim_cc=(volume_m3 - float(fitted["mg"]) / rho_ref) * 1e6,
        compressibility_per_pa=float(fitted.get("epsilon", 0.0)),
    )
    misfit = model.modelresult.w[steady] - depth_rate_mps(log)[steady]
    return FlightFit(params, int(steady.sum()), float(np.sqrt(np.mean(misfit**2))))
