"""`gliderplan power`: look at the power models.

  power list [KIND]                     presets of each kind
  power show KIND SPEC [--clock MHZ]    a preset or a user file, every figure with unit and source
  power energy [--vehicle V] ...        energy per km against yo depth band and speed
  power speed --hotel-w W ...           the speed that minimises energy per km

Every form takes --json. The tables come from `gliderplan.power_models.tables`.
"""

from __future__ import annotations

import argparse
import math

from gliderplan.cli.main import print_json
from gliderplan.power_models.tables import KINDS


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
    from gliderplan.power_models import tables

    match args.power_command:
        case "list":
            data = tables.presets(args.kind)
            text = "\n".join(f"{kind}: {', '.join(names)}" for kind, names in data.items())
        case "show":
            data = tables.model_figures(args.kind, args.spec, args.clock)
            text = _show_text(data)
        case "energy":
            data = tables.energy_per_km(args.vehicle, min_depth_m=args.min_depth,
                                        max_depths_m=args.max_depth, pitch_deg=args.pitch_deg,
                                        speeds_mps=args.speed, hotel_w=args.hotel_w)
            text = _energy_text(data)
        case _:
            data = tables.optimal_speeds(args.hotel_w, args.vehicle,
                                         min_depth_m=args.min_depth,
                                         max_depths_m=args.max_depth, pitch_deg=args.pitch_deg)
            text = _speed_text(data)
    if args.json:
        print_json(data)
    else:
        print(text)
    return 0


def _show_text(data: dict) -> str:
    lines = [
        f"{data['kind']} {data['name']}: {data['description']}",
        "",
        f"{'figure':34s} {'value':>10s} {'unit':9s} source",
    ]
    lines += [f"{r['key']:34s} {_value(r['value']):>10s} {r['unit']:9s} {r['source']}"
              for r in data["figures"]]
    for r in data["ranges"]:  # a published span, low-high
        span = f"{r['low']:g}-{r['high']:g}"
        lines.append(f"{r['key']:34s} {span:>10s} {r['unit']:9s} {r['source']}")
    if data["derived"]:
        lines += ["", "derived:"]
        lines += [f"  {d['what']:50s} {d['value']:10.4g} {d['unit']}" for d in data["derived"]]
    if data.get("propulsion"):
        lines += ["", f"propulsion ({data['vehicle_kind']}): " + _propulsion_text(
            data["propulsion"])]
    return "\n".join(lines)


def _value(value: float | list[float]) -> str:
    """A figure as the table shows it; a column of a table as its values."""
    if isinstance(value, list):
        return ", ".join(f"{v:g}" for v in value)
    return f"{value:10.6g}"


def _propulsion_text(p: dict) -> str:
    text = (f"{p['model']}, {p['min_speed_mps']:.3g}-{p['max_speed_mps']:.3g} m/s; on its "
            f"hotel load of {p['hotel_w']:.3g} W it spends the least per km at "
            f"{p['best_speed_mps']:.3g} m/s ({p['propulsion_w']:.3g} W of propulsion, "
            f"{p['energy_per_km_kj']:.3g} kJ/km)")
    if p["closed_form_speed_mps"] is not None:
        text += f"; closed form U* = {p['closed_form_speed_mps']:.3g} m/s"
    return text


def _energy_text(data: dict) -> str:
    low = data["min_depth_m"]
    lines = [
        f"{data['vehicle']}: energy per km [kJ] at {math.degrees(data['pitch_rad']):.1f} deg "
        f"pitch, hotel {data['hotel_w']:.2f} W",
        "yo [m]    " + "".join(f"{u:>9.2f}" for u in data["speed_mps"]) + "   (speed m/s)",
        "ballast   " + "".join(f"{b:>9.0f}" for b in data["ballast_cc"][-1])
        + "   (cc, deepest yo)",
    ]
    for high, line in zip(data["max_depth_m"], data["energy_per_km_kj"], strict=True):
        cells = "".join(f"{v:>9.1f}" if v is not None else f"{'-':>9s}" for v in line)
        lines.append(f"{low:g}-{high:<7g}" + cells)
    if any(v is None for line in data["energy_per_km_kj"] for v in line):
        lines.append(f"- : needs more than the vehicle's {data['max_ballast_cc']:g} cc")
    return "\n".join(lines)


def _speed_text(data: dict) -> str:
    lines = [
        f"{data['vehicle']}: optimal speed at {math.degrees(data['pitch_rad']):.1f} deg pitch",
        f"{'yo [m]':>10s} {'hotel W':>8s} {'u* m/s':>7s} {'cc':>6s} {'kJ/km':>7s}",
    ]
    for r in data["rows"]:
        note = "  (capped by max ballast)" if r["capped"] else ""
        lines.append(
            f"{r['min_depth_m']:g}-{r['max_depth_m']:<7g} {r['hotel_w']:8.2f} "
            f"{r['speed_mps']:7.3f} {r['ballast_cc']:6.0f} {r['energy_per_km_kj']:7.1f}{note}"
        )
    return "\n".join(lines)
