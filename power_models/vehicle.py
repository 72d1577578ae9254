"""The glider as an energy consumer: hotel load, buoyancy pump, pitch motor, surfacing,
and the steady-glide flight model that turns pitch and pumped volume into speed.

A yo between `min_depth_m` and `max_depth_m` at pitch `pitch_rad` with a buoyancy volume
of `ballast_cc` either side of neutral is a cycle of two glides and two inflections:

    at max depth: pump 2 x ballast_cc out (against sea pressure), move the battery (pitch)
    at min depth: pump 2 x ballast_cc in, move the battery

The glider covers no distance while it pumps (pumped volume / pump rate). All methods
take numpy arrays (or floats) and broadcast.

Notes
-----
Per metre travelled, energy = P/u + e_pitch_per_m + c u^2, because the pumped volume
(and with it the pump energy and pumping time) grows with u^2 at a fixed pitch:
c = (a_out + b_out z_max + a_in + 2 P / r) tan(gamma) / (H k^2), with H the depth band,
r the pump rate and k^2 = u^2 / dV.
So u* = (P / 2c)^(1/3): a hungrier hotel load makes the best glider faster.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gliderplan.power_models import flight
from gliderplan.power_models.catalog import resolve
from gliderplan.power_models.datafile import read_model_file
from gliderplan.power_models.flight import FlightParams

Array = np.ndarray


@dataclass(frozen=True)
class Vehicle:
    """A glider's energy figures. Powers [W], energies [J], volumes [cc], times [s]."""

    name: str
    description: str
    hotel_w: float  # submerged base load without pump and pitch motor
    pump_out_j_per_cc: float  # a_out: pump-out energy per cc at the surface
    pump_out_j_per_cc_m: float  # b_out: extra pump-out energy per cc per metre of depth
    pump_in_j_per_cc: float  # a_in: pump-in energy per cc (pressure helps; no depth term)
    pump_rate_cc_s: float
    max_ballast_cc: float  # largest buoyancy volume either side of neutral
    pitch_energy_j: float  # battery-shift energy per inflection
    surface_w: float  # base load at the surface (GPS, antenna up), without Iridium
    surface_s: float  # time at the surface per surfacing, without the Iridium call
    iridium_w: float  # total power while the Iridium call is up
    iridium_s: float  # Iridium call time per surfacing
    surfacing_fixed_j: float  # fixed energy per surfacing (air bladder, etc.)
    nominal_pitch_rad: float
    nominal_min_depth_m: float
    nominal_max_depth_m: float
    flight: FlightParams

    # ---- flight -------------------------------------------------------------------
    def glide(self, pitch_rad: Array | float, ballast_cc: Array | float) -> tuple[Array, Array]:
        """Horizontal and vertical speed (u, w) [m s-1] from pitch [rad] and volume [cc]."""
        return flight.glide(self.flight, pitch_rad, ballast_cc)

    def ballast_for_speed(self, u_mps: Array | float, pitch_rad: Array | float) -> Array:
        """Buoyancy volume [cc] for horizontal speed `u_mps` [m s-1] at `pitch_rad` (glide's
        inverse); the planner turns a planned speed into a buoyancy command with it."""
        return flight.ballast_for_speed(self.flight, u_mps, pitch_rad)

    def max_speed_mps(self, pitch_rad: Array | float) -> Array:
        """Horizontal speed [m s-1] at the largest buoyancy volume."""
        return self.glide(pitch_rad, self.max_ballast_cc)[0]

    # ---- actuators ----------------------------------------------------------------
    def pump_energy_j(self, depth_m: Array | float, volume_cc: Array | float) -> Array:
        """Energy [J] to pump `volume_cc` [cc] out at `depth_m` [m]: (a + b depth) V."""
        depth = np.asarray(depth_m, float)
        return (self.pump_out_j_per_cc + self.pump_out_j_per_cc_m * depth) * np.asarray(
            volume_cc, float
        )

    def pump_in_energy_j(self, volume_cc: Array | float) -> Array:
        """Energy [J] to pump `volume_cc` [cc] back in (sea pressure helps, no depth term)."""
        return self.pump_in_j_per_cc * np.asarray(volume_cc, float)

    def pump_time_s(self, volume_cc: Array | float) -> Array:
        """Time [s] the pump needs for `volume_cc` [cc]."""
        return np.asarray(volume_cc, float) / self.pump_rate_cc_s

    @property
    def surfacing_j(self) -> float:
        """Energy [J] of one surfacing without the Iridium call (fixed + surface base load)."""
        return self.surfacing_fixed_j + self.surface_w * self.surface_s

    @property
    def surfacing_with_iridium_j(self) -> float:
        """Energy [J] of one surfacing including its Iridium call."""
        return self.surfacing_j + self.iridium_w * self.iridium_s

    # ---- yo profiles --------------------------------------------------------------
    def _yo_cycle(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        ballast_cc: Array | float,
    ) -> tuple[Array, Array, Array]:
        """(time [s], actuator energy [J], horizontal distance [m]) of one dive + climb."""
        band = np.asarray(max_depth_m, float) - np.asarray(min_depth_m, float)
        if np.any(band <= 0.0) or np.any(np.asarray(min_depth_m, float) < 0.0):
            raise ValueError("a yo needs 0 <= min_depth < max_depth")
        u, w = self.glide(pitch_rad, ballast_cc)
        pumped = 2.0 * np.asarray(ballast_cc, float)
        glide_s = 2.0 * band / w
        time = glide_s + 2.0 * self.pump_time_s(pumped)
        energy = (
            self.pump_energy_j(max_depth_m, pumped)
            + self.pump_in_energy_j(pumped)
            + 2.0 * self.pitch_energy_j
        )
        return time, energy, glide_s * u

    def inflections_per_hour(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        ballast_cc: Array | float,
    ) -> Array:
        """Inflections per hour [h-1] of a yo (two per dive-climb cycle)."""
        time, _, _ = self._yo_cycle(min_depth_m, max_depth_m, pitch_rad, ballast_cc)
        return 2.0 * 3600.0 / time

    def profile_power_w(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        ballast_cc: Array | float,
    ) -> Array:
        """Mean pump + pitch-motor power [W] of flying a yo, excluding the hotel load."""
        time, energy, _ = self._yo_cycle(min_depth_m, max_depth_m, pitch_rad, ballast_cc)
        return energy / time

    def energy_per_km_j(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        ballast_cc: Array | float,
        hotel_w: Array | float | None = None,
    ) -> Array:
        """Energy [J] per horizontal km of a yo with a hotel load `hotel_w` [W]
        (default: the vehicle's own; pass vehicle + board + sensors for a mission)."""
        hotel = self.hotel_w if hotel_w is None else np.asarray(hotel_w, float)
        time, energy, distance = self._yo_cycle(min_depth_m, max_depth_m, pitch_rad, ballast_cc)
        return 1000.0 * (hotel * time + energy) / distance

    def transit_coefficient(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        hotel_w: Array | float | None = None,
    ) -> Array:
        """c [J m-1 (m/s)-2] of energy per metre = P/u + pitch_j_per_m + c u^2 for a yo band.

        c holds the pump energy and the hotel load spent while pumping (both grow with the
        pumped volume, hence with u^2); `hotel_w` [W] defaults to the vehicle's own.
        """
        hotel = self.hotel_w if hotel_w is None else np.asarray(hotel_w, float)
        band = np.asarray(max_depth_m, float) - np.asarray(min_depth_m, float)
        u_unit, _ = self.glide(pitch_rad, 1.0)  # speed at 1 cc: u = u_unit sqrt(dV)
        slope = flight.glide_slope(self.flight, pitch_rad)
        per_cc = (
            self.pump_out_j_per_cc
            + self.pump_out_j_per_cc_m * np.asarray(max_depth_m, float)
            + self.pump_in_j_per_cc
            + 2.0 * hotel / self.pump_rate_cc_s
        )
        # per cycle: 2 dV pumped out and 2 dV in over 2 band / slope metres; dV = u^2 / u_unit^2
        return per_cc * slope / (band * u_unit**2)

    def pitch_j_per_m(
        self, min_depth_m: Array | float, max_depth_m: Array | float, pitch_rad: Array | float
    ) -> Array:
        """Pitch-motor energy per metre travelled [J m-1] (independent of speed)."""
        band = np.asarray(max_depth_m, float) - np.asarray(min_depth_m, float)
        slope = flight.glide_slope(self.flight, pitch_rad)
        return self.pitch_energy_j * slope / band

    def optimal_speed_mps(
        self,
        hotel_w: Array | float,
        min_depth_m: Array | float | None = None,
        max_depth_m: Array | float | None = None,
        pitch_rad: Array | float | None = None,
    ) -> Array:
        """Horizontal speed [m s-1] that minimises energy per metre, u* = (P / 2c)^(1/3),
        for a total hotel load `hotel_w` [W]; capped by the largest buoyancy volume.
        The yo band and pitch default to the vehicle's nominal profile."""
        low = self.nominal_min_depth_m if min_depth_m is None else min_depth_m
        high = self.nominal_max_depth_m if max_depth_m is None else max_depth_m
        pitch = self.nominal_pitch_rad if pitch_rad is None else pitch_rad
        hotel = np.asarray(hotel_w, float)
        c = self.transit_coefficient(low, high, pitch, hotel)
        return np.minimum(np.cbrt(hotel / (2.0 * c)), self.max_speed_mps(pitch))


def load_vehicle(spec: str) -> Vehicle:
    """Load a vehicle: a preset name (`slocum_g2_shallow`, ...) or a path to a .toml file."""
    return read_vehicle_file(resolve("vehicle", spec))


def read_vehicle_file(path: Path) -> Vehicle:
    """Parse and validate a vehicle data file."""
    top = read_model_file(path, "vehicle")
    fl = top.table("flight")
    params = FlightParams(
        rho_kg_m3=fl.quantity("water_density", "density", positive=True),
        g_m_s2=fl.quantity("gravity", "acceleration", positive=True),
        wing_area_m2=fl.quantity("wing_area", "area", positive=True),
        lift_wing_per_rad=fl.quantity("lift_slope_wing", "per_angle", positive=True),
        lift_hull_per_rad=fl.quantity("lift_slope_hull", "per_angle"),
        drag_cd0=fl.quantity("drag_cd0", "dimensionless", positive=True),
        drag_cd1_per_rad2=fl.quantity("drag_cd1", "dimensionless"),
    )
    fl.finish()
    min_depth = top.quantity("nominal_min_depth", "length")
    max_depth = top.quantity("nominal_max_depth", "length", positive=True)
    if max_depth <= min_depth:
        raise top.error("nominal_max_depth", "must be deeper than nominal_min_depth")
    vehicle = Vehicle(
        name=top.text("name"),
        description=top.text("description", ""),
        hotel_w=top.quantity("hotel_power", "power"),
        pump_out_j_per_cc=top.quantity("pump_out_energy_per_volume", "pump_per_volume"),
        pump_out_j_per_cc_m=top.quantity(
            "pump_out_energy_per_volume_depth", "pump_per_volume_depth"
        ),
        pump_in_j_per_cc=top.quantity("pump_in_energy_per_volume", "pump_per_volume"),
        pump_rate_cc_s=top.quantity("pump_rate", "flow", positive=True),
        max_ballast_cc=top.quantity("max_ballast", "volume", positive=True),
        pitch_energy_j=top.quantity("pitch_energy", "energy"),
        surface_w=top.quantity("surface_power", "power"),
        surface_s=top.quantity("surface_time", "time"),
        iridium_w=top.quantity("iridium_power", "power"),
        iridium_s=top.quantity("iridium_time", "time"),
        surfacing_fixed_j=top.quantity("surfacing_energy", "energy"),
        nominal_pitch_rad=top.quantity(
            "nominal_pitch", "angle", positive=True, maximum=np.pi / 2 * 0.999
        ),
        nominal_min_depth_m=min_depth,
        nominal_max_depth_m=max_depth,
        flight=params,
    )
    top.finish()
    return vehicle
