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

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from gliderplan.contract import Component, Envelope, EnvelopeAction, PumpEnergy
from gliderplan.contract.units import UNITS
from gliderplan.power_models import flight
from gliderplan.power_models.catalog import preset_names, resolve
from gliderplan.power_models.datafile import Table, read_model_file
from gliderplan.power_models.flight import DensityProfile, FlightModelError, FlightParams
from gliderplan.power_models.propulsion import (
    AUV,
    GLIDER,
    POWER_LAW,
    TABLE,
    THRUSTER,
    VEHICLE_KINDS,
    Propulsion,
    read_propulsion,
)
from gliderplan.power_models.vehicle_figures import FIGURES, derive_envelope, envelope_fields

Array = np.ndarray


@dataclass(frozen=True)
class Uncertainty:
    """How sure calibration is of the fitted figures: one standard deviation of each (in
    the model's unit, keyed as in the data file, e.g. "hotel_power", "flight.drag_cd0") and
    their correlation, from a bootstrap over dives."""

    keys: tuple[str, ...]
    sd: np.ndarray  # (k,)
    correlation: np.ndarray  # (k, k)
    source: str
    at_least: tuple[str, ...] = ()  # lower bounds (a call the record cut short): never drawn below


@dataclass(frozen=True)
class Device:
    """A device of the glider with a power figure of its own: a science instrument (named
    as its sensor preset, e.g. "dvl") or an actuator of the flight ("fin").

    An instrument draws `on_power_w` [W] while the mission runs it; an actuator draws it
    while it moves, which it does for `duty` [1] of the time the glider glides."""

    name: str
    kind: str  # "sensor" | "actuator"
    on_power_w: float
    duty: float = 1.0


DEVICE_KINDS = ("sensor", "actuator")
# a device's figures in the vehicle file's [devices.NAME] table: key -> (attribute,
# dimension, options as for FIGURES)
DEVICE_FIGURES: dict[str, tuple[str, str, dict]] = {
    "on_power": ("on_power_w", "power", {}),
    "duty": ("duty", "dimensionless", {"default": 1.0, "maximum": 1.0}),
}


@dataclass(frozen=True)
class Vehicle:
    """A glider's energy figures. Powers [W], energies [J], volumes [cc], times [s]."""

    name: str
    description: str
    hotel_w: float  # submerged base load without pump and pitch motor
    pump_out_j_per_cc: float  # a_out: pump-out energy per cc at the surface
    pump_out_j_per_cc_m: float  # b_out: extra pump-out energy per cc per metre of depth
    pump_in_j_per_cc: float  # a_in: pump-in energy per cc at the surface
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
    pump_in_j_per_cc_m: float = 0.0  # b_in: pump-in energy per cc per metre (< 0: pressure helps)
    top_turn_s: float = 0.0  # time an inflection at the top of a yo takes beyond its pump run
    bottom_turn_s: float = 0.0  # the same at the bottom
    dive_pitch_error_rad: float = 0.0  # |flown| - |commanded| pitch of a dive (servo deadband)
    climb_pitch_error_rad: float = 0.0  # the same for a climb
    # [rad/s per rad of fin] the turn a held fin gives (power_models.fin_turn); NaN: unknown
    fin_turn_rate_per_s: float = math.nan
    hotel_includes: tuple[str, ...] = ()  # devices ("ctd", "computer", ...) in the hotel load
    devices: tuple[Device, ...] = ()  # devices with figures of their own (the file's [devices])
    base_drift_w: float = 0.0  # sd [W] of the hotel load between deployments (another year)
    kind: str = GLIDER  # glider | hybrid (a glider with a thruster) | auv (propeller only)
    propulsion: Propulsion | None = None  # its propeller or thruster; None: a glider's none
    # the file's [envelope]: the rating every command is held to (None: `envelope` derives it)
    max_depth_m: float | None = None
    max_pitch_rad: float | None = None
    min_yo_band_m: float | None = None
    max_turn_rate_rad_s: float | None = None
    max_pump_power_w: float | None = None
    envelope_action: EnvelopeAction = EnvelopeAction.SURFACE
    uncertainty: Uncertainty | None = field(default=None, compare=False)
    path: Path | None = field(default=None, compare=False)  # its data file: the sources

    @property
    def envelope(self) -> Envelope:
        """The rating the runtime holds every command to (`derive_envelope`)."""
        written = {name: getattr(self, name) for name in (
            "max_depth_m", "max_pitch_rad", "min_yo_band_m", "max_turn_rate_rad_s",
            "max_pump_power_w", "envelope_action")}
        propulsion = self.propulsion
        speeds = (0.0, 0.0) if propulsion is None else \
            (propulsion.min_speed_mps, propulsion.max_speed_mps)
        thrust = (propulsion.min_command_w, propulsion.max_command_w) \
            if propulsion is not None and propulsion.is_thruster else (0.0, 0.0)
        pump = PumpEnergy(self.pump_out_j_per_cc, self.pump_out_j_per_cc_m,
                          self.pump_in_j_per_cc, self.pump_in_j_per_cc_m)
        return derive_envelope(self.nominal_max_depth_m, self.nominal_pitch_rad,
                               self.nominal_min_depth_m, self.max_ballast_cc, self.pump_rate_cc_s,
                               {k: v for k, v in written.items() if v is not None}, pump,
                               speeds, thrust)

    @property
    def has_buoyancy_engine(self) -> bool:
        """Whether it pumps to glide (a glider, a hybrid); an AUV has no pump."""
        return self.kind != AUV

    def device(self, name: str) -> Device | None:
        """The device table's entry for `name`, or None."""
        return next((d for d in self.devices if d.name == name), None)

    def ballasted_for(self, surface_rho_kg_m3: float) -> Vehicle:
        """The glider ballasted for other water, of `surface_rho_kg_m3` [kg m-3] at the
        surface: a pilot trims a glider for the sea it will fly in, so its trim volume (net
        buoyancy at zero pumped volume, `flight.trim_volume`) holds relative to that water
        as it held in its calibration water."""
        return replace(self, flight=replace(self.flight, rho_kg_m3=float(surface_rho_kg_m3)))

    def neutral(self) -> Vehicle:
        """The same glider trimmed neutral in uniform water of its reference density, its
        hull not compressible, turning while it pumps and flying the pitch it is commanded:
        the symmetric steady-glide model (DESIGN.md section 8) for which the closed forms
        (`transit_coefficient`, `optimal_speed_mps`) are exact."""
        params = replace(self.flight, trim_cc=0.0, compressibility_per_pa=0.0)
        return replace(self, flight=params, top_turn_s=0.0, bottom_turn_s=0.0,
                       dive_pitch_error_rad=0.0, climb_pitch_error_rad=0.0)

    # ---- flight -------------------------------------------------------------------
    def flown_pitch_rad(
        self, dive_pitch_rad: Array | float, climb_pitch_rad: Array | float
    ) -> tuple[Array, Array]:
        """Pitch [rad] (magnitudes) the glider flies when commanded these for its dives and
        climbs: its pitch servo stops inside a deadband, often on the same side."""
        return (np.asarray(dive_pitch_rad, float) + self.dive_pitch_error_rad,
                np.asarray(climb_pitch_rad, float) + self.climb_pitch_error_rad)

    def glide(self, pitch_rad: Array | float, ballast_cc: Array | float) -> tuple[Array, Array]:
        """Horizontal and vertical speed (u, w) [m s-1] from pitch [rad] and volume [cc]."""
        return flight.glide(self.flight, pitch_rad, ballast_cc)

    def ballast_for_speed(self, u_mps: Array | float, pitch_rad: Array | float) -> Array:
        """Buoyancy volume [cc] for horizontal speed `u_mps` [m s-1] at `pitch_rad` (glide's
        inverse); the planner turns a planned speed into a buoyancy command with it."""
        return flight.ballast_for_speed(self.flight, u_mps, pitch_rad)

    @property
    def unplanned_ballast_cc(self) -> float:
        """Pumped volume [cc] flown without a plan: the full stroke, as the vehicle's
        nominal flight (its calibration log, a yo at ~26 deg pitch) pumps it either side
        of neutral. Compiled into a mission as its default ballast."""
        return self.max_ballast_cc

    def trim_offset_cc(self, min_depth_m: Array | float, max_depth_m: Array | float) -> Array:
        """The largest |net buoyancy| [cc] at zero pumped volume over a yo band: what the
        pump must overcome before the glider dives (or climbs) at all."""
        ends = np.stack(np.broadcast_arrays(np.asarray(min_depth_m, float),
                                            np.asarray(max_depth_m, float)))
        return np.max(np.abs(flight.net_buoyancy_cc(self.flight, 0.0, ends)), axis=0)

    def yo_ballast_cc(
        self,
        u_mps: Array | float,
        pitch_rad: Array | float,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
    ) -> Array:
        """Pumped volume [cc] either side of neutral for a yo planned at horizontal speed
        `u_mps` [m s-1]: the neutral glider's volume for that speed plus the trim offset,
        so that the slower direction still flies it (it may exceed `max_ballast_cc`)."""
        return self.ballast_for_speed(u_mps, pitch_rad) + self.trim_offset_cc(
            min_depth_m, max_depth_m)

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

    def pump_in_energy_j(self, depth_m: Array | float, volume_cc: Array | float) -> Array:
        """Energy [J] to pump `volume_cc` [cc] back in at `depth_m` [m]: (a + b depth) V, never
        below 0 (deep enough, sea pressure alone pushes the oil back)."""
        per_cc = self.pump_in_j_per_cc + self.pump_in_j_per_cc_m * np.asarray(depth_m, float)
        return np.maximum(per_cc, 0.0) * np.asarray(volume_cc, float)

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
    def turn_s(self, volume_cc: Array | float) -> Array:
        """Time [s] of a yo's two inflections at a pumped volume [cc] either side of
        neutral: both pump runs (2 x volume each) and the turns' time beyond them."""
        return 2.0 * self.pump_time_s(2.0 * np.asarray(volume_cc, float)) + (
            self.top_turn_s + self.bottom_turn_s
        )

    def yo_cycle(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        ballast_cc: Array | float,
        ocean: DensityProfile | None = None,
    ) -> tuple[Array, Array, Array]:
        """(time [s], actuator energy [J], horizontal distance [m]) of one dive + climb."""
        if np.any(np.asarray(min_depth_m, float) >= np.asarray(max_depth_m, float)) or np.any(
            np.asarray(min_depth_m, float) < 0.0
        ):
            raise ValueError("a yo needs 0 <= min_depth < max_depth")
        dive, climb = (
            flight.glide_leg(self.flight, min_depth_m, max_depth_m, pitch, ballast_cc, up, ocean)
            for pitch, up in zip(self.flown_pitch_rad(pitch_rad, pitch_rad), (False, True),
                                 strict=True)
        )
        pumped = 2.0 * np.asarray(ballast_cc, float)
        time = dive.time_s + climb.time_s + self.turn_s(ballast_cc)
        energy = (
            self.pump_energy_j(max_depth_m, pumped)
            + self.pump_in_energy_j(min_depth_m, pumped)
            + 2.0 * self.pitch_energy_j
        )
        return time, energy, dive.distance_m + climb.distance_m

    def inflections_per_hour(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        ballast_cc: Array | float,
    ) -> Array:
        """Inflections per hour [h-1] of a yo (two per dive-climb cycle)."""
        time, _, _ = self.yo_cycle(min_depth_m, max_depth_m, pitch_rad, ballast_cc)
        return 2.0 * 3600.0 / time

    def profile_power_w(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        ballast_cc: Array | float,
    ) -> Array:
        """Mean pump + pitch-motor power [W] of flying a yo, excluding the hotel load."""
        time, energy, _ = self.yo_cycle(min_depth_m, max_depth_m, pitch_rad, ballast_cc)
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
        time, energy, distance = self.yo_cycle(min_depth_m, max_depth_m, pitch_rad, ballast_cc)
        return 1000.0 * (hotel * time + energy) / distance

    def transit_coefficient(
        self,
        min_depth_m: Array | float,
        max_depth_m: Array | float,
        pitch_rad: Array | float,
        hotel_w: Array | float | None = None,
    ) -> Array:
        """c [J m-1 (m/s)-2] of energy per metre = P/u + pitch_j_per_m + P turn_s_per_m + c u^2
        for a yo band.

        c holds the pump energy and the hotel load spent while pumping (both grow with the
        pumped volume, hence with u^2); `hotel_w` [W] defaults to the vehicle's own. The
        closed form is exact for a glider trimmed neutral in uniform water without
        compressibility; a calibrated trim and compressibility are in `yo_cycle` only.
        """
        hotel = self.hotel_w if hotel_w is None else np.asarray(hotel_w, float)
        band = np.asarray(max_depth_m, float) - np.asarray(min_depth_m, float)
        u_unit, _ = self.glide(pitch_rad, 1.0)  # speed at 1 cc: u = u_unit sqrt(dV)
        slope = flight.glide_slope(self.flight, pitch_rad)
        per_cc = (
            self.pump_energy_j(max_depth_m, 1.0)
            + self.pump_in_energy_j(min_depth_m, 1.0)
            + 2.0 * hotel / self.pump_rate_cc_s
        )
        # per cycle: 2 dV pumped out and 2 dV in over 2 band / slope metres; dV = u^2 / u_unit^2
        return per_cc * slope / (band * u_unit**2)

    def pitch_j_per_m(
        self, min_depth_m: Array | float, max_depth_m: Array | float, pitch_rad: Array | float
    ) -> Array:
        """Pitch-motor energy per metre travelled [J m-1] (independent of speed)."""
        return self.pitch_energy_j * self._inflections_per_m(min_depth_m, max_depth_m, pitch_rad)

    def turn_s_per_m(
        self, min_depth_m: Array | float, max_depth_m: Array | float, pitch_rad: Array | float
    ) -> Array:
        """Time per metre travelled [s m-1] the turns take beyond their pump runs
        (independent of speed); the hotel load runs through it."""
        per_inflection = 0.5 * (self.top_turn_s + self.bottom_turn_s)
        return per_inflection * self._inflections_per_m(min_depth_m, max_depth_m, pitch_rad)

    def _inflections_per_m(
        self, min_depth_m: Array | float, max_depth_m: Array | float, pitch_rad: Array | float
    ) -> Array:
        band = np.asarray(max_depth_m, float) - np.asarray(min_depth_m, float)
        return flight.glide_slope(self.flight, pitch_rad) / band

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
    from gliderplan.power_models.devices import check_hotel  # it bills devices of vehicles

    vehicle = read_vehicle_file(resolve("vehicle", spec))
    check_hotel(vehicle)
    return vehicle




@contextmanager
def flying_yo(where: str, vehicle: Vehicle, min_depth_m: float, max_depth_m: float
              ) -> Iterator[None]:
    """Names the state (`where`), the yo band [m] and the vehicle in a FlightModelError
    raised inside: a yo the vehicle cannot fly, said alike by `plan` and `sim`."""
    try:
        yield
    except FlightModelError as err:
        raise FlightModelError(f"{where}: a yo {min_depth_m:g}-{max_depth_m:g} m on vehicle "
                               f"{vehicle.name}: {err}") from None


def yo_flight_problem(where: str, vehicle: Vehicle, kind: str, args: tuple[float, ...] | None,
                      pitch_rad: float | None = None, ballast_cc: float | None = None
                      ) -> FlightModelError | None:
    """Why the vehicle cannot fly a profile of `kind` with constant arguments `args` (None:
    they read variables, left to the flight) at `pitch_rad` [rad] and `ballast_cc` [cc]
    (default: the profile's mean pitch, the vehicle's unplanned volume), or None: a yo
    deeper than its trim and pumped volume climb back from. `where` names the profile."""
    if kind not in ("yo", "thermotrackyo") or args is None:
        return None
    pitch = 0.5 * (args[2] + args[3]) if pitch_rad is None else pitch_rad
    ballast = vehicle.unplanned_ballast_cc if ballast_cc is None else ballast_cc
    try:
        with flying_yo(where, vehicle, args[0], args[1]):
            vehicle.inflections_per_hour(args[0], args[1], pitch, ballast)
    except FlightModelError as err:
        return err
    return None


def figure_spec(key: str) -> tuple[str, str, dict]:
    """(attribute, dimension, options) of a figure by its data-file key: a key of FIGURES, or
    a device's "devices.NAME.on_power" / "devices.NAME.duty". KeyError for any other."""
    if key.startswith("devices."):
        _, _, figure = key.rpartition(".")
        return DEVICE_FIGURES[figure]
    return FIGURES[key]


def device_key(device: str, figure: str = "on_power") -> str:
    """The data-file key of a device's figure."""
    return f"devices.{device}.{figure}"


def figure_unit(key: str) -> str:
    """The model's unit of a figure, as a data file writes it."""
    dimension = figure_spec(key)[1]
    return next(u for u, factor in UNITS[dimension].items() if factor == 1.0)


def with_figures(vehicle: Vehicle, values: dict[str, float]) -> Vehicle:
    """A copy of `vehicle` with figures replaced, keyed as in the data file [model units]."""
    top = {FIGURES[k][0]: float(v) for k, v in values.items()
           if not k.startswith(("flight.", "devices."))}
    fl = {FIGURES[k][0]: float(v) for k, v in values.items() if k.startswith("flight.")}
    devices = tuple(
        replace(d, **{DEVICE_FIGURES[f][0]: float(values[device_key(d.name, f)])
                      for f in DEVICE_FIGURES if device_key(d.name, f) in values})
        for d in vehicle.devices)
    return replace(vehicle, flight=replace(vehicle.flight, **fl), devices=devices, **top)


def figure_value(vehicle: Vehicle, key: str) -> float:
    """A figure of `vehicle` by its data-file key [model unit]."""
    if key.startswith("devices."):
        name, figure = key[len("devices."):].rsplit(".", 1)
        device = vehicle.device(name)
        if device is None:
            raise KeyError(key)
        return float(getattr(device, DEVICE_FIGURES[figure][0]))
    owner = vehicle.flight if key.startswith("flight.") else vehicle
    return float(getattr(owner, FIGURES[key][0]))


# Figures of the buoyancy engine and the glide: an AUV has none, and its file gives none.
# The model holds NaN for the glide's (nothing flies them) and 0 for the pump's volume and
# energies, so that its plans and compiled missions command no ballast.
GLIDER_FIGURES = frozenset(
    k for k in FIGURES if k.startswith(("pump_", "flight.")) and k not in (
        "flight.water_density", "flight.gravity")) | {
    "max_ballast", "pitch_energy", "top_turn_time", "bottom_turn_time", "dive_pitch_error",
    "climb_pitch_error", "nominal_pitch"}
_WITHOUT_BUOYANCY_ENGINE = {"max_ballast_cc": 0.0, "pitch_energy_j": 0.0, "trim_cc": 0.0,
                            "hull_volume_cc": 0.0, "compressibility_per_pa": 0.0,
                            **{FIGURES[k][0]: 0.0 for k in FIGURES if k.startswith("pump_")
                               and k != "pump_rate"}}


def read_vehicle_file(path: Path) -> Vehicle:
    """Parse and validate a vehicle data file."""
    top = read_model_file(path, "vehicle")
    kind = top.text("vehicle_kind", GLIDER)
    if kind not in VEHICLE_KINDS:
        raise top.error("vehicle_kind", f"expected one of {', '.join(VEHICLE_KINDS)}, "
                        f"got {kind!r}")
    fl = top.table("flight")
    values: dict[str, float] = {}
    spreads: dict[str, float] = {}
    bounds: set[str] = set()
    for key, (attr, dimension, options) in FIGURES.items():
        table, name = (fl, key[7:]) if key.startswith("flight.") else (top, key)
        if kind == AUV and key in GLIDER_FIGURES:
            if name in table.data:
                raise table.error(name, "an AUV has no buoyancy engine and does not glide: "
                                  "remove the figure, or make the vehicle_kind hybrid")
            values[attr] = _WITHOUT_BUOYANCY_ENGINE.get(attr, np.nan)
            continue
        values[attr] = table.quantity(name, dimension, **options)
        spread = table.sd(name, dimension)
        if spread is not None:
            spreads[key] = spread
        if table.at_least(name):
            bounds.add(key)
    fl.finish()
    if values["nominal_max_depth_m"] <= values["nominal_min_depth_m"]:
        raise top.error("nominal_max_depth", "must be deeper than nominal_min_depth")
    flight_attrs = {FIGURES[k][0] for k in FIGURES if k.startswith("flight.")}
    params = FlightParams(**{a: v for a, v in values.items() if a in flight_attrs})
    devices = _devices(top, spreads, bounds)
    propulsion = _propulsion(top, kind, params)
    vehicle = Vehicle(
        **envelope_fields(top, values["nominal_max_depth_m"]),
        name=top.text("name"),
        description=top.text("description", ""),
        flight=params,
        hotel_includes=_hotel_includes(top, devices),
        devices=devices,
        base_drift_w=top.quantity("base_drift", "power", 0.0),
        kind=kind,
        propulsion=propulsion,
        uncertainty=_uncertainty(top, spreads, bounds),
        path=path,
        **{a: v for a, v in values.items() if a not in flight_attrs},
    )
    top.finish()
    return vehicle


def _propulsion(top: Table, kind: str, flight_params: FlightParams) -> Propulsion | None:
    """The `[propulsion]` table: required of a hybrid and an AUV, refused on a glider, its
    model one the kind may carry (an AUV's propeller is no glider's thruster)."""
    if not top.has("propulsion"):
        if kind != GLIDER:
            raise top.missing("propulsion", f"a {kind} needs a [propulsion] table")
        return None
    table = top.table("propulsion")
    if kind == GLIDER:
        raise top.error("propulsion", "a glider has no propulsion: make the vehicle_kind "
                        "hybrid (a glider with a thruster) or auv")
    if kind == AUV and table.data.get("model") == THRUSTER:
        raise table.error("model", "an auv has no hull drag figures to fly a glider's "
                          f"thruster at; use one of {POWER_LAW}, {TABLE}")
    return read_propulsion(table, flight_params.wing_area_m2, flight_params.rho_kg_m3,
                           flight_params.drag_cd0)


def _devices(top: Table, spreads: dict[str, float], bounds: set[str]) -> tuple[Device, ...]:
    """The `[devices.NAME]` tables: `kind`, `on_power` and (an actuator's) `duty`, each
    figure with its source and, when calibrated, its sd (into `spreads`, keyed
    "devices.NAME.FIGURE"). A sensor must be named as a sensor preset."""
    if not top.has("devices"):
        return ()
    devices = []
    tables = top.table("devices")
    for name in tables.data:
        table = tables.table(name)
        kind = table.text("kind")
        if kind not in DEVICE_KINDS:
            raise table.error("kind", f"expected one of {', '.join(DEVICE_KINDS)}, got {kind!r}")
        if kind == "sensor" and name not in preset_names("sensor"):
            raise table.error(None, f"unknown sensor device {name!r}; expected one of "
                              f"{', '.join(preset_names('sensor'))}")
        figures = {}
        for figure, (attr, dimension, options) in DEVICE_FIGURES.items():
            figures[attr] = table.quantity(figure, dimension, **options)
            spread = table.sd(figure, dimension)
            if spread is not None:
                spreads[device_key(name, figure)] = spread
            if table.at_least(figure):
                bounds.add(device_key(name, figure))
        table.finish()
        devices.append(Device(name, kind, **figures))
    tables.finish()
    return tuple(devices)


def _hotel_includes(top: Table, devices: tuple[Device, ...]) -> tuple[str, ...]:
    """Devices the hotel load already holds (`hotel_includes = { devices = [...], source }`):
    a sensor preset, the computer, or a device of the file's own table."""
    if not top.has("hotel_includes"):
        return ()
    table = top.table("hotel_includes")
    devices_held = table.text_list("devices")
    table.text("source")
    known = {*preset_names("sensor"), Component.COMPUTER, *(d.name for d in devices)}
    for device in devices_held:
        if device not in known:
            raise table.error("devices", f"unknown device {device!r}; expected one of "
                              f"{', '.join(sorted(known))}")
    table.finish()
    return tuple(devices_held)


def _uncertainty(top: Table, spreads: dict[str, float], bounds: set[str]) -> Uncertainty | None:
    """The figures' standard deviations and, if the file gives it, their correlation
    (`[uncertainty] figures = [...], correlation = [[...]], source = ...`); without one
    the figures are taken as independent. `bounds`: figures marked `at_least`."""
    keys = tuple(spreads)
    correlation = np.eye(len(keys))
    source = "standard deviations written next to the figures; taken as independent"
    if top.has("uncertainty"):
        table = top.table("uncertainty")
        listed = table.text_list("figures")
        source = table.text("source")
        table.used.add("correlation")
        matrix = np.asarray(table.data.get("correlation"), float)
        if matrix.shape != (len(listed), len(listed)) or not np.allclose(matrix, matrix.T) or \
                not np.allclose(np.diag(matrix), 1.0) or np.any(np.abs(matrix) > 1.0 + 1e-9):
            raise table.error("correlation", f"expected a symmetric {len(listed)} x "
                              f"{len(listed)} matrix of correlations with 1 on its diagonal")
        unknown = [k for k in listed if k not in spreads]
        if unknown:
            raise table.error("figures", f"{', '.join(unknown)}: no sd next to the figure")
        order = [listed.index(k) if k in listed else None for k in keys]
        for i, a in enumerate(order):
            for j, b in enumerate(order):
                if a is not None and b is not None:
                    correlation[i, j] = matrix[a, b]
        table.finish()
    if not keys:
        return None
    return Uncertainty(keys, np.array([spreads[k] for k in keys]), correlation, source,
                       tuple(k for k in keys if k in bounds))
