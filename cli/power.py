"""`gliderplan power`: look at the power models.

  power list [KIND]                     presets of each kind
  power show KIND SPEC [--clock MHZ]    a preset or a user file, every figure with unit and source
  power energy [--vehicle V] ...        energy per km against yo depth band and speed
  power speed --hotel-w W ...           the speed that minimises energy per km

Every form takes --json.
"""

from __future__ import annotations

import argparse
import json
import math

from gliderplan.contract import RUNTIME_CYCLES_PER_TICK, TICK_S
from gliderplan.contract.errors import UsageError

KINDS = ("board", "sensor", "vehicle", "battery")


def _floats(text: str) -> list[float]:
    """A comma-separated list of finite numbers (argparse type)."""
    try:
        values = [float(item) for item in text.split(",") if item.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected numbers separated by commas, got {text!r}"
        ) from None
    if not values or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"expected finite numbers, got {text!r}")
    return values


def _profile_arguments(parser: argparse.ArgumentParser, max_depth_help: str) -> None:
    parser.add_argument(
        "--vehicle",
        default="slocum_g2_shallow",
        help="vehicle preset or .toml file (default: slocum_g2_shallow)",
    )
    parser.add_argument(
        "--min-depth",
        type=float,
        metavar="M",
        help="top of the yo [m] (default: the vehicle's nominal)",
    )
    parser.add_argument("--max-depth", type=_floats, metavar="M[,M...]", help=max_depth_help)
    parser.add_argument(
        "--pitch-deg",
        type=float,
        metavar="DEG",
        help="glide pitch [deg] (default: the vehicle's nominal)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON")


ORDER = 80


def add_arguments(parser: argparse.ArgumentParser) -> None:
    forms = parser.add_subparsers(dest="power_command", metavar="FORM")
    forms.required = True
    listing = forms.add_parser("list", help="list the presets")
    listing.add_argument("kind", nargs="?", choices=KINDS)
    listing.add_argument("--json", action="store_true", help="print JSON")

    show = forms.add_parser("show", help="show a preset or a model file as a table")
    show.add_argument("kind", choices=KINDS)
    show.add_argument("spec", help="preset name (board: NAME[@MHZ]) or path to a .toml file")
    show.add_argument("--clock", type=float, metavar="MHZ", help="board clock [MHz]")
    show.add_argument("--json", action="store_true", help="print JSON")

    energy = forms.add_parser("energy", help="energy per km vs yo depth band and speed")
    _profile_arguments(energy, "bottoms of the yo [m] (default: 10,20,40,100)")
    energy.add_argument(
        "--speed",
        type=_floats,
        metavar="U[,U...]",
        help="horizontal speeds [m/s] (default: 0.15,0.2,0.25,0.3,0.35,0.4)",
    )
    energy.add_argument(
        "--hotel-w",
        type=float,
        metavar="W",
        help="total hotel load [W] (default: the vehicle's own)",
    )

    speed = forms.add_parser("speed", help="optimal horizontal speed for a hotel load")
    _profile_arguments(speed, "bottom of the yo [m] (default: the vehicle's nominal)")
    speed.add_argument(
        "--hotel-w",
        type=_floats,
        required=True,
        metavar="W[,W...]",
        help="total hotel load(s) [W]: vehicle + computer + sensors",
    )


def run(args: argparse.Namespace) -> int:
    handlers = {"list": _list, "show": _show, "energy": _energy, "speed": _speed}
    text, data = handlers[args.power_command](args)
    print(json.dumps(data, indent=2) if args.json else text)
    return 0


def _list(args: argparse.Namespace) -> tuple[str, dict]:
    from gliderplan.power_models.catalog import preset_names

    data = {kind: preset_names(kind) for kind in ([args.kind] if args.kind else KINDS)}
    return "\n".join(f"{kind}: {', '.join(names)}" for kind, names in data.items()), data


def _show(args: argparse.Namespace) -> tuple[str, dict]:
    from gliderplan.power_models import load_battery, load_board, load_sensor, load_vehicle
    from gliderplan.power_models.board import board_spec
    from gliderplan.power_models.catalog import resolve
    from gliderplan.power_models.datafile import file_entries

    if args.clock is not None and args.kind != "board":
        raise UsageError("--clock only applies to a board")
    if args.kind == "board":
        model = load_board(args.spec, args.clock)
        path, _ = board_spec(args.spec)
    else:
        loader = {"sensor": load_sensor, "vehicle": load_vehicle, "battery": load_battery}
        model = loader[args.kind](args.spec)
        path = resolve(args.kind, args.spec)
    rows = [{"key": k, "value": v, "unit": u, "source": s} for k, v, u, s in file_entries(path)]
    derived = _derived(args.kind, model)
    lines = [
        f"{args.kind} {model.name}: {model.description}",
        "",
        f"{'figure':34s} {'value':>10s} {'unit':9s} source",
    ]
    lines += [f"{r['key']:34s} {r['value']:10.6g} {r['unit']:9s} {r['source']}" for r in rows]
    if derived:
        lines += ["", "derived:"]
        lines += [f"  {d['what']:50s} {d['value']:10.4g} {d['unit']}" for d in derived]
    return "\n".join(lines), {
        "kind": args.kind,
        "name": model.name,
        "file": str(path),
        "figures": rows,
        "derived": derived,
    }


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
            model.energy_per_km_j(low, high, pitch, model.ballast_for_speed(best, pitch)) / 1e3,
            "kJ",
        ),
        row("surfacing with Iridium", model.surfacing_with_iridium_j, "J"),
    ]


def _profile(args: argparse.Namespace, default_max: list[float]):  # noqa: ANN202
    from gliderplan.power_models import load_vehicle

    vehicle = load_vehicle(args.vehicle)
    low = vehicle.nominal_min_depth_m if args.min_depth is None else args.min_depth
    highs = args.max_depth or default_max or [vehicle.nominal_max_depth_m]
    pitch = vehicle.nominal_pitch_rad if args.pitch_deg is None else math.radians(args.pitch_deg)
    if not 0.0 < pitch < math.pi / 2:
        raise UsageError("--pitch-deg must lie strictly between 0 and 90")
    if low < 0.0 or any(h <= low for h in highs):
        raise UsageError(
            f"every --max-depth must be deeper than --min-depth ({low:g} m), "
            "and --min-depth must be >= 0"
        )
    return vehicle, low, highs, pitch


def _energy(args: argparse.Namespace) -> tuple[str, dict]:
    import numpy as np

    vehicle, low, highs, pitch = _profile(args, [10.0, 20.0, 40.0, 100.0])
    speeds = args.speed or [0.15, 0.2, 0.25, 0.3, 0.35, 0.4]
    if any(u <= 0.0 for u in speeds):
        raise UsageError("--speed values must be > 0 m/s")
    hotel = vehicle.hotel_w if args.hotel_w is None else args.hotel_w
    if hotel < 0.0:
        raise UsageError("--hotel-w must be >= 0 W")
    ballast = vehicle.ballast_for_speed(np.array(speeds), pitch)
    reachable = ballast <= vehicle.max_ballast_cc
    grid = vehicle.energy_per_km_j(low, np.array(highs)[:, None], pitch, ballast[None, :], hotel)
    table = [
        [float(e) / 1e3 if ok else None for e, ok in zip(line, reachable, strict=True)]
        for line in grid
    ]
    header = "yo [m]    " + "".join(f"{u:>9.2f}" for u in speeds) + "   (speed m/s)"
    lines = [
        f"{vehicle.name}: energy per km [kJ] at {math.degrees(pitch):.1f} deg pitch, "
        f"hotel {hotel:.2f} W",
        header,
        "ballast   " + "".join(f"{b:>9.0f}" for b in ballast) + "   (cc)",
    ]
    for high, line in zip(highs, table, strict=True):
        cells = "".join(f"{v:>9.1f}" if v is not None else f"{'-':>9s}" for v in line)
        lines.append(f"{low:g}-{high:<7g}" + cells)
    if not reachable.all():
        lines.append(f"- : needs more than the vehicle's {vehicle.max_ballast_cc:g} cc")
    data = {
        "vehicle": vehicle.name,
        "pitch_rad": pitch,
        "hotel_w": hotel,
        "min_depth_m": low,
        "max_depth_m": highs,
        "speed_mps": speeds,
        "ballast_cc": [float(b) for b in ballast],
        "energy_per_km_kj": table,
    }
    return "\n".join(lines), data


def _speed(args: argparse.Namespace) -> tuple[str, dict]:
    vehicle, low, highs, pitch = _profile(args, [])
    if any(h < 0.0 for h in args.hotel_w):
        raise UsageError("--hotel-w values must be >= 0 W")
    rows = []
    for high in highs:
        for hotel in args.hotel_w:
            u = float(vehicle.optimal_speed_mps(hotel, low, high, pitch))
            ballast = float(vehicle.ballast_for_speed(u, pitch))
            rows.append(
                {
                    "min_depth_m": low,
                    "max_depth_m": high,
                    "hotel_w": hotel,
                    "speed_mps": u,
                    "ballast_cc": ballast,
                    "capped": bool(ballast >= vehicle.max_ballast_cc * (1 - 1e-9)),
                    "transit_c": float(vehicle.transit_coefficient(low, high, pitch, hotel)),
                    "energy_per_km_kj": float(
                        vehicle.energy_per_km_j(low, high, pitch, ballast, hotel)
                    )
                    / 1e3,
                }
            )
    lines = [
        f"{vehicle.name}: optimal speed at {math.degrees(pitch):.1f} deg pitch",
        f"{'yo [m]':>10s} {'hotel W':>8s} {'u* m/s':>7s} {'cc':>6s} {'kJ/km':>7s}",
    ]
    for r in rows:
        note = "  (capped by max ballast)" if r["capped"] else ""
        lines.append(
            f"{low:g}-{r['max_depth_m']:<7g} {r['hotel_w']:8.2f} {r['speed_mps']:7.3f} "
            f"{r['ballast_cc']:6.0f} {r['energy_per_km_kj']:7.1f}{note}"
        )
    return "\n".join(lines), {"vehicle": vehicle.name, "pitch_rad": pitch, "rows": rows}
