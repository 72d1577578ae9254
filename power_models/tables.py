"""The power models as tables, what `gliderplan power` shows: the presets of each kind, a
model file's figures with their units and sources (and a few figures derived from them),
energy per km against the yo band and speed, and the speed that minimises it. Each
function returns plain data (the command's JSON); UsageError for inputs that name
nothing or contradict each other, ModelFileError for a file that cannot be used."""

from __future__ import annotations

import math

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, TICK_S
from gliderplan.contract.errors import UsageError

KINDS = ("board", "sensor", "vehicle", "battery")
DEFAULT_VEHICLE = "slocum_g2_shallow"
YO_BOTTOMS_M = (10.0, 20.0, 40.0, 100.0)  # rows of the energy table by default
SPEEDS_MPS = (0.15, 0.2, 0.25, 0.3, 0.35, 0.4)  # columns of the energy table by default
# Inputs checked against what exists: no ocean is deeper (Challenger Deep, ~10,935 m), and
# a hotel load past 1 kW is no glider's (an AUV's is ~50 W: DESIGN.md section 11).
DEEPEST_OCEAN_M = 11_000.0  # [m]
MAX_HOTEL_W = 1000.0  # [W]


def presets(kind: str | None = None) -> dict[str, list[str]]:
    """Kind -> its preset names (every kind, or just `kind`)."""
    from gliderplan.power_models.catalog import preset_names

    return {k: preset_names(k) for k in ([kind] if kind else KINDS)}


def model_figures(kind: str, spec: str, clock_mhz: float | None = None) -> dict:
    """A preset or a user file of `kind`: every figure with its unit and source, and a few
    derived from them (`clock_mhz`: a board's clock)."""
    from gliderplan.power_models import load_battery, load_board, load_sensor, load_vehicle
    from gliderplan.power_models.board import board_spec
    from gliderplan.power_models.catalog import resolve
    from gliderplan.power_models.datafile import file_entries, file_spans

    if kind not in KINDS:
        raise UsageError(f"{kind!r}: not a kind of model ({', '.join(KINDS)})")
    if clock_mhz is not None and kind != "board":
        raise UsageError("--clock only applies to a board")
    if kind == "board":
        model = load_board(spec, clock_mhz)
        path, _ = board_spec(spec)
    else:
        loader = {"sensor": load_sensor, "vehicle": load_vehicle, "battery": load_battery}
        model = loader[kind](spec)
        path = resolve(kind, spec)
    return {
        "kind": kind,
        "name": model.name,
        "description": model.description,
        "file": None if path is None else str(path),  # none: no board, no file
        "figures": [] if path is None else [{"key": k, "value": v, "unit": u, "source": s}
                                            for k, v, u, s in file_entries(path)],
        # published spans (a sensor's `power_range`): what a fitted figure is checked against
        "ranges": [] if path is None else [
            {"key": k, "low": low, "high": high, "unit": u, "source": s}
            for k, low, high, u, s in file_spans(path)],
        "derived": _derived(kind, model),
        **({"vehicle_kind": model.kind, "propulsion": _propulsion(model)}
           if kind == "vehicle" else {}),
    }


def _propulsion(vehicle: object) -> dict | None:
    """A vehicle's propulsion model as numbers, with the speed that makes the most of a
    joule on its own hotel load in still water and the energy per km there (None: a glider
    without one)."""
    from gliderplan.planner.speed import best_speed

    propulsion = vehicle.propulsion
    if propulsion is None:
        return None
    best = best_speed(propulsion, vehicle.hotel_w)
    return {**propulsion.figures(), "hotel_w": vehicle.hotel_w,
            "best_speed_mps": best.speed_mps, "closed_form_speed_mps":
            propulsion.optimal_speed_mps(vehicle.hotel_w),
            "energy_per_km_kj": best.energy_per_m_j, "propulsion_w": best.propulsion_w}


def _derived(kind: str, model: object) -> list[dict]:
    """A few figures computed from the file, so a user sees what the numbers mean."""

    def row(what: str, value: float, unit: str) -> dict:
        return {"what": what, "value": float(value), "unit": unit}

    if kind == "board":
        rows = [row(f"active power at {m.clock_mhz:g} MHz", m.active_w, "W")
                for m in model.modes()]
        rows.append(row(f"boot energy at {model.clock_mhz:g} MHz", model.boot_j, "J"))
        return rows + [
            row(f"mean power at {m.clock_mhz:g} MHz, {how} between ticks",
                m.mean_power_w(RUNTIME_CYCLES_PER_TICK, TICK_S, sleep), "W")
            for m in model.modes() for how, sleep in (("idle", False), ("asleep", True))
            if not sleep or m.sleep is not None]
    if kind == "battery":
        return [
            row("energy", model.energy_wh, "Wh"),
            row("usable energy", model.usable_j / 1e6, "MJ"),
            row("capacity at nominal voltage", model.capacity_ah, "Ah"),
        ]
    if kind == "sensor":
        return [
            row("quality at 25 % duty", model.utility(0.25), "1"),
            row("mean power at 25 % duty", model.mean_power_w(0.25), "W"),
        ]
    if not model.has_buoyancy_engine:  # an AUV: its propulsion says the rest
        return [row("surfacing with Iridium", model.surfacing_with_iridium_j, "J")]
    pitch, low, high = model.nominal_pitch_rad, model.nominal_min_depth_m, model.nominal_max_depth_m
    u, w = model.glide(pitch, model.max_ballast_cc)
    best = model.optimal_speed_mps(model.hotel_w)
    return [
        row(f"u at {math.degrees(pitch):.0f} deg, {model.max_ballast_cc:g} cc", u, "m/s"),
        row(f"w at {math.degrees(pitch):.0f} deg, {model.max_ballast_cc:g} cc", w, "m/s"),
        row(
            f"inflections per hour, yo {low:g}-{high:g} m at max ballast",
            model.inflections_per_hour(low, high, pitch, model.max_ballast_cc),
            "1/h",
        ),
        row(f"optimal speed for its own hotel load, yo {low:g}-{high:g} m", best, "m/s"),
        row(
            "energy per km at that speed",
            model.energy_per_km_j(low, high, pitch, min(
                float(model.yo_ballast_cc(best, pitch, low, high)), model.max_ballast_cc)) / 1e3,
            "kJ",
        ),
        row("surfacing with Iridium", model.surfacing_with_iridium_j, "J"),
    ]


def _profile(vehicle_spec: str, min_depth_m: float | None, max_depths_m: list[float] | None,
             pitch_deg: float | None, default_max: tuple[float, ...]):  # noqa: ANN202
    """(vehicle, top [m], bottoms [m], pitch [rad]) with the vehicle's nominal defaults."""
    from gliderplan.power_models import load_vehicle

    vehicle = load_vehicle(vehicle_spec)
    low = vehicle.nominal_min_depth_m if min_depth_m is None else min_depth_m
    highs = list(max_depths_m or default_max or [vehicle.nominal_max_depth_m])
    pitch = vehicle.nominal_pitch_rad if pitch_deg is None else math.radians(pitch_deg)
    if not 0.0 < pitch < math.pi / 2:
        raise UsageError("--pitch-deg must lie strictly between 0 and 90")
    if not 0.0 <= low < DEEPEST_OCEAN_M or any(h <= low for h in highs):
        raise UsageError(
            f"every --max-depth must be deeper than --min-depth ({low:g} m), "
            "and --min-depth must be >= 0"
        )
    if any(h > DEEPEST_OCEAN_M for h in highs):
        raise UsageError(f"--max-depth must be at most {DEEPEST_OCEAN_M:,.0f} m, the deepest "
                         "ocean")
    return vehicle, low, highs, pitch


def energy_per_km(vehicle: str = DEFAULT_VEHICLE, *, min_depth_m: float | None = None,
                  max_depths_m: list[float] | None = None, pitch_deg: float | None = None,
                  speeds_mps: list[float] | None = None, hotel_w: float | None = None) -> dict:
    """Energy per km [kJ] of `vehicle` flying yos from `min_depth_m` to each of
    `max_depths_m` [m] at each of `speeds_mps` [m/s] and `pitch_deg`, with a hotel load of
    `hotel_w` [W] (defaults: the vehicle's nominal figures, YO_BOTTOMS_M, SPEEDS_MPS);
    None where the speed needs more buoyancy than the vehicle has."""
    import numpy as np

    model, low, highs, pitch = _profile(vehicle, min_depth_m, max_depths_m, pitch_deg,
                                        YO_BOTTOMS_M)
    speeds = list(speeds_mps or SPEEDS_MPS)
    if any(u <= 0.0 for u in speeds):
        raise UsageError("--speed values must be > 0 m/s")
    hotel = model.hotel_w if hotel_w is None else hotel_w
    if not hotel <= MAX_HOTEL_W:
        raise UsageError(f"--hotel-w must be at most {MAX_HOTEL_W:g} W")
    if hotel < 0.0:
        raise UsageError("--hotel-w must be >= 0 W")
    # the neutral volume for each speed plus the trim offset of each band (yo_ballast_cc)
    ballast = model.yo_ballast_cc(np.array(speeds)[None, :], pitch, low, np.array(highs)[:, None])
    reachable = ballast <= model.max_ballast_cc
    flown = np.minimum(ballast, model.max_ballast_cc)
    grid = model.energy_per_km_j(low, np.array(highs)[:, None], pitch, flown, hotel)
    return {
        "vehicle": model.name,
        "pitch_rad": pitch,
        "hotel_w": hotel,
        "min_depth_m": low,
        "max_depth_m": highs,
        "speed_mps": speeds,
        "ballast_cc": [[float(b) for b in line] for line in ballast],
        "max_ballast_cc": model.max_ballast_cc,
        "energy_per_km_kj": [
            [float(e) / 1e3 if ok else None for e, ok in zip(line, fits, strict=True)]
            for line, fits in zip(grid, reachable, strict=True)
        ],
    }


def optimal_speeds(hotel_w: list[float], vehicle: str = DEFAULT_VEHICLE, *,
                   min_depth_m: float | None = None, max_depths_m: list[float] | None = None,
                   pitch_deg: float | None = None) -> dict:
    """The horizontal speed [m/s] that minimises `vehicle`'s energy per km for each total
    hotel load of `hotel_w` [W] and each yo bottom of `max_depths_m` [m] (default: the
    vehicle's nominal yo), with the buoyancy that flies it and its energy per km."""
    model, low, highs, pitch = _profile(vehicle, min_depth_m, max_depths_m, pitch_deg, ())
    if any(h < 0.0 for h in hotel_w):
        raise UsageError("--hotel-w values must be >= 0 W")
    if any(not h <= MAX_HOTEL_W for h in hotel_w):
        raise UsageError(f"--hotel-w values must be at most {MAX_HOTEL_W:g} W")
    rows = []
    for high in highs:
        for hotel in hotel_w:
            u = float(model.optimal_speed_mps(hotel, low, high, pitch))
            ballast = min(float(model.yo_ballast_cc(u, pitch, low, high)),
                          model.max_ballast_cc)
            rows.append(
                {
                    "min_depth_m": low,
                    "max_depth_m": high,
                    "hotel_w": hotel,
                    "speed_mps": u,
                    "ballast_cc": ballast,
                    "capped": bool(ballast >= model.max_ballast_cc * (1 - 1e-9)),
                    "transit_c": float(model.transit_coefficient(low, high, pitch, hotel)),
                    "energy_per_km_kj": float(
                        model.energy_per_km_j(low, high, pitch, ballast, hotel)
                    )
                    / 1e3,
                }
            )
    return {"vehicle": model.name, "pitch_rad": pitch, "rows": rows}
