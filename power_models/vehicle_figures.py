"""The vehicle file's figures and its envelope, without the flight model (numpy): `check`
holds a mission's profiles to the vehicle's rating before anything heavy loads."""

from __future__ import annotations

import math

from gliderplan.contract import Envelope, EnvelopeAction, PumpEnergy
from gliderplan.power_models.catalog import resolve
from gliderplan.power_models.datafile import Table, read_model_file

# file key -> (attribute, dimension, options); a flight key is "flight.<key>". Every figure
# calibration may fit or draw is here, so that loading, writing and drawing agree.
FIGURES: dict[str, tuple[str, str, dict]] = {
    "hotel_power": ("hotel_w", "power", {}),
    "pump_out_energy_per_volume": ("pump_out_j_per_cc", "pump_per_volume", {}),
    "pump_out_energy_per_volume_depth": ("pump_out_j_per_cc_m", "pump_per_volume_depth", {}),
    "pump_in_energy_per_volume": ("pump_in_j_per_cc", "pump_per_volume", {}),
    "pump_in_energy_per_volume_depth": (
        "pump_in_j_per_cc_m", "pump_per_volume_depth", {"default": 0.0, "minimum": -math.inf}
    ),
    "pump_rate": ("pump_rate_cc_s", "flow", {"positive": True}),
    "max_ballast": ("max_ballast_cc", "volume", {"positive": True}),
    "pitch_energy": ("pitch_energy_j", "energy", {}),
    "surface_power": ("surface_w", "power", {}),
    "surface_time": ("surface_s", "time", {}),
    "iridium_power": ("iridium_w", "power", {}),
    "iridium_time": ("iridium_s", "time", {}),
    "surfacing_energy": ("surfacing_fixed_j", "energy", {}),
    "top_turn_time": ("top_turn_s", "time", {"default": 0.0}),
    "bottom_turn_time": ("bottom_turn_s", "time", {"default": 0.0}),
    "dive_pitch_error": ("dive_pitch_error_rad", "angle", {"default": 0.0, "minimum": -math.inf}),
    "climb_pitch_error": ("climb_pitch_error_rad", "angle", {"default": 0.0, "minimum": -math.inf}),
    "nominal_pitch": (
        "nominal_pitch_rad", "angle", {"positive": True, "maximum": math.pi / 2 * 0.999}
    ),
    "nominal_min_depth": ("nominal_min_depth_m", "length", {}),
    "fin_turn_rate": ("fin_turn_rate_per_s", "frequency",
                      {"default": math.nan, "minimum": -math.inf}),
    "nominal_max_depth": ("nominal_max_depth_m", "length", {"positive": True}),
    "flight.water_density": ("rho_kg_m3", "density", {"positive": True}),
    "flight.gravity": ("g_m_s2", "acceleration", {"positive": True}),
    "flight.wing_area": ("wing_area_m2", "area", {"positive": True}),
    "flight.lift_slope_wing": ("lift_wing_per_rad", "per_angle", {"positive": True}),
    "flight.lift_slope_hull": ("lift_hull_per_rad", "per_angle", {}),
    "flight.drag_cd0": ("drag_cd0", "dimensionless", {"positive": True}),
    "flight.drag_cd1": ("drag_cd1_per_rad2", "dimensionless", {}),
    "flight.hull_volume": ("hull_volume_cc", "volume", {"default": 0.0}),
    "flight.trim_volume": ("trim_cc", "volume", {"default": 0.0, "minimum": -math.inf}),
    "flight.compressibility": ("compressibility_per_pa", "compressibility", {"default": 0.0}),
}


def envelope_fields(top: Table, nominal_max_depth_m: float) -> dict:
    """The optional `[envelope]` table: `max_depth`, `max_pitch`, `min_yo_band`,
    `max_turn_rate`, `max_pump_power` (each a figure with its source) and `action` (fault |
    surface | clamp), as Vehicle's fields; a figure left out is derived (`derive_envelope`)."""
    if not top.has("envelope"):
        return {}
    table = top.table("envelope")
    fields: dict = {}
    for key, attr, dimension, options in (
            ("max_depth", "max_depth_m", "length", {"positive": True}),
            ("max_pitch", "max_pitch_rad", "angle",
             {"positive": True, "maximum": FIGURES["nominal_pitch"][2]["maximum"]}),
            ("min_yo_band", "min_yo_band_m", "length", {}),
            ("max_turn_rate", "max_turn_rate_rad_s", "angular_rate", {"positive": True}),
            ("max_pump_power", "max_pump_power_w", "power", {"positive": True})):
        if table.has(key):
            fields[attr] = table.quantity(key, dimension, **options)
    action = table.text("action", "surface")
    if action.upper() not in EnvelopeAction.__members__:
        raise table.error("action", f"expected fault, surface or clamp, got {action!r}")
    fields["envelope_action"] = EnvelopeAction[action.upper()]
    table.finish()
    depth = fields.get("max_depth_m")
    if depth is not None and depth <= nominal_max_depth_m:
        raise table.error("max_depth", "must be deeper than the vehicle's nominal_max_depth")
    if depth is not None and fields.get("min_yo_band_m", 0.0) >= depth:
        raise table.error("min_yo_band", "must be thinner than max_depth")
    return fields


PUMP_DUTY = 0.25  # [1] the share of the time a pump may work, averaged over an hour
# the pump's energy figures (`FIGURES` keys), in PumpEnergy's order
PUMP_FIGURES = ("pump_out_energy_per_volume", "pump_out_energy_per_volume_depth",
                "pump_in_energy_per_volume", "pump_in_energy_per_volume_depth")


def derive_envelope(nominal_max_depth_m: float, nominal_pitch_rad: float,
                    nominal_min_depth_m: float, max_ballast_cc: float, pump_rate_cc_s: float,
                    fields: dict, pump: PumpEnergy,
                    speed_range_mps: tuple[float, float] = (0.0, 0.0),
                    thrust_range_w: tuple[float, float] = (0.0, 0.0)) -> Envelope:
    """The rating the runtime holds every command to (docs/pilot.md, The envelope), from a
    vehicle's figures [m, rad, cc, cc/s], its `[envelope]` (`envelope_fields`), its pump's
    energy, and its propulsion's speed range [m/s] and thruster's command range [W] (0, 0:
    none). What the file's [envelope] leaves out comes from the vehicle's own figures: a
    depth rating twice its nominal yo's bottom (the G3's 100 m yo of its 200 m), a pitch
    twice its nominal (within a right angle), a band no thinner than its nominal yo's top;
    inflections no closer than its pump's full stroke (from one side of neutral to the
    other); the pump's mean power over an hour no more than it draws working a quarter of
    the time at its nominal yo's bottom (the paper's Fig. 2, a 5-10 m yo, draws 2.4 W of the
    shallow Slocum's 9 W); no turn-rate limit (the shipped gliders give theirs). A
    vehicle without a buoyancy engine (an AUV: no pitch of its own, NaN, and no pump, 0 cc)
    commands pitch and volume 0: its pitch is bound only short of a right angle, and its
    inflections not at all."""
    right_angle = FIGURES["nominal_pitch"][2]["maximum"]
    max_pitch_rad = fields.get("max_pitch_rad")
    if max_pitch_rad is None:
        max_pitch_rad = right_angle if math.isnan(nominal_pitch_rad) else \
            min(2.0 * nominal_pitch_rad, right_angle)
    return Envelope(
        max_depth_m=fields.get("max_depth_m", 2.0 * nominal_max_depth_m),
        max_pitch_rad=max_pitch_rad,
        min_yo_band_m=fields.get("min_yo_band_m", nominal_min_depth_m),
        min_inflection_s=2.0 * max_ballast_cc / pump_rate_cc_s if max_ballast_cc > 0 else 0.0,
        action=fields.get("envelope_action", EnvelopeAction.SURFACE),
        speed_range_mps=speed_range_mps, thrust_range_w=thrust_range_w,
        max_turn_rate_rad_s=fields.get("max_turn_rate_rad_s", math.inf),
        max_pump_power_w=fields.get("max_pump_power_w", PUMP_DUTY * pump_rate_cc_s * (
            pump.out_j_per_cc + pump.out_j_per_cc_m * nominal_max_depth_m)
            if max_ballast_cc > 0 else math.inf), pump=pump)


def load_envelope(spec: str) -> Envelope:
    """The envelope of a vehicle (a preset name or a .toml file), reading only the figures
    it derives from (a propelled vehicle's: the whole file, its propulsion gives its speed
    range). Raises ModelFileError (or InputFileError) for a file that cannot be read; the
    whole file is validated where the vehicle is flown (`load_vehicle`)."""
    path = resolve("vehicle", spec)
    top = read_model_file(path, "vehicle")
    if top.has("propulsion"):
        from gliderplan.power_models.vehicle import load_vehicle

        return load_vehicle(spec).envelope
    names = ("nominal_max_depth", "nominal_pitch", "nominal_min_depth", "max_ballast",
             "pump_rate")
    figures = [top.quantity(name, FIGURES[name][1], **FIGURES[name][2]) for name in names]
    pump = PumpEnergy(*(top.quantity(name, FIGURES[name][1], **FIGURES[name][2])
                        for name in PUMP_FIGURES))
    return derive_envelope(*figures, envelope_fields(top, figures[0]), pump)
