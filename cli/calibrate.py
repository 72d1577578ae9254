"""`gliderplan calibrate`: fit a vehicle to real Slocum logs, and check it forward.

Reads .dbd/.ebd files with dbdreader and fits every figure the logs support (energy, flight
with gliderflight against the CTD's density, pitch, turn times, surfacing), each with its
bootstrap standard deviation; `--validate` fits the earlier whole dives and forecasts the
later ones from the fit alone, and replays the held-out half
(`gliderplan.power_models.calibrate`).
"""

from __future__ import annotations

import argparse
import math

from gliderplan.contract.errors import GliderplanError, UsageError

ORDER = 90


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "logs",
        nargs="+",
        metavar="LOGS",
        help="Slocum .dbd/.ebd files, or directories holding them",
    )
    parser.add_argument(
        "--cache", metavar="DIR", help="dbdreader cache directory (.cac files); default: LOGS' cac/"
    )
    parser.add_argument(
        "--base",
        default="slocum_g2_shallow",
        metavar="VEHICLE",
        help="vehicle preset or file whose other figures the result keeps "
        "(default: slocum_g2_shallow)",
    )
    parser.add_argument(
        "-o", "--output", metavar="FILE", help="write the calibrated vehicle to this .toml file"
    )
    parser.add_argument("--name", help="vehicle name in the output file (default: file stem)")
    parser.add_argument(
        "--validate",
        action="store_true",
        help="fit the earlier whole dives, forecast the later ones forward, compare with the "
        "coulomb counter",
    )
    parser.add_argument(
        "--max-error",
        type=_fraction,
        metavar="FRACTION",
        help="with --validate: exit 1 if the forecast's |energy error| exceeds this",
    )
    parser.add_argument("--json", action="store_true", help="print the report as JSON")


def _fraction(text: str) -> float:
    """An error bound (argparse type): a finite number >= 0; NaN would pass every forecast."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value >= 0.0):
        raise argparse.ArgumentTypeError(f"expected a finite fraction >= 0 (0.03 is 3 %), "
                                         f"got {text!r}")
    return value


def run(args: argparse.Namespace) -> int:
    from gliderplan.cli.common import refuse_unpaired
    from gliderplan.power_models import calibrate

    if args.max_error is not None and not args.validate:
        raise UsageError("--max-error needs --validate")
    refuse_unpaired(args, {"--name": ("--output",)})
    from gliderplan.cli.progress import Steps

    steps = Steps("calibrate")
    try:
        result = calibrate(args.logs, cache=args.cache, base=args.base, validate=args.validate,
                           output=args.output, name=args.name, progress=steps)
    finally:
        steps.finish()
    if args.json:
        from gliderplan.cli.main import print_json

        print_json(result.report)
    else:
        print(_text(result.report))
    if args.max_error is not None and abs(result.relative_error) > args.max_error:
        raise GliderplanError(f"forecast energy error {result.relative_error:+.1%} exceeds "
                              f"--max-error {args.max_error:.1%}")
    return 0


def _text(report: dict) -> str:
    lines = [
        f"logs: {', '.join(report['logs'])} ({report['duration_s']:.0f} s, "
        f"{report['dives']} dives, {report['bootstrap_refits']} bootstrap refits)",
        "",
        f"{'figure':34s} {'value':>11s} {'sd':>9s} {'unit':9s} basis",
    ]
    for f in report["figures"]:
        kept = " (published figure)" if f["key"].startswith("devices.") else " (kept from base)"
        mark = ("" if f["fitted"] else kept) + (
            " (at least)" if f["at_least"] else "")
        sd = f"{f['sd']:9.3g}" if f["sd"] is not None else f"{'':9s}"
        lines.append(f"{f['key']:34s} {f['value']:11.5g} {sd} {f['unit']:9s} {f['basis']}{mark}")
    ins = report["in_sample"]
    lines += [
        "",
        f"pump model RMS error over {report['pump_events']} runs: {report['pump_rms_j']:.1f} J; "
        f"flight model RMS vertical-speed error: {report['flight_rms_w_mps']:.4f} m/s",
        f"in-sample energy: predicted {ins['predicted_j']:.0f} J, coulomb counter "
        f"{ins['measured_j']:.0f} J ({ins['relative_error']:+.2%})",
    ]
    lines += [""] + _devices_text(report["devices"])
    if "forecast" in report:
        lines += [""] + _forecast_text(report["forecast"])
        lines += [""] + _configurations_text(report["configurations"])
        val = report["validation"]
        parts = ", ".join(f"{k} {v:.0f} J" for k, v in val["predicted_by_component_j"].items())
        lines += [
            "",
            f"replay ({val['split']}, {val['duration_s']:.0f} s held out; uses that part's own "
            "durations, pumped volumes and Iridium time, so it is not a forecast):",
            f"  predicted {val['predicted_j']:.0f} J ({parts}), measured "
            f"{val['measured_j']:.0f} J: {val['relative_error']:+.2%}",
        ]
    if "output" in report:
        lines += ["", f"wrote {report['output']}"]
    return "\n".join(lines)


def _devices_text(d: dict) -> list[str]:
    lines = [f"power by device over {d['glide_s']:.0f} s of glide (the base load "
             f"{d['base_w']:.3g} W; the fit's residual RMS {d['rms_w']:.2f} W):"]
    for row in d["table"]:
        sd = f" +- {row['sd_w']:.2g}" if row["sd_w"] is not None else ""
        how = "fitted" if row["fitted"] else "published"
        where = ", in the hotel load" if row["in_hotel"] else ""
        flag = f"  FLAGGED: {row['flag']}" if row["flag"] else ""
        lines.append(f"  {row['device']:8s} {row['on_power_w']:6.3g} W{sd} ({how}{where}): "
                     f"{row['basis']}{flag}")
    if d["merged_into_base"]:
        lines.append(f"  merged into the base (the log cannot separate them, no published "
                     f"figure): {', '.join(d['merged_into_base'])}")
    return lines


def _configurations_text(c: dict) -> list[str]:
    fitted = ", ".join(c["fitted_on"]["devices"]) or "none"
    if c["not_possible"]:
        return [f"cross-configuration check: not possible: {c['not_possible']}"]
    lines = [f"cross-configuration check: fit on {c['fitted_on']['dives']} dives running "
             f"{fitted}; each other set of devices forecast from it (its own durations):"]
    for f in c["forecasts"]:
        low, high = f["interval_j"]
        lines.append(f"  {', '.join(f['devices']) or 'none'} ({f['dives']} dives): predicted "
                     f"{f['predicted_j']:.0f} J, measured {f['measured_j']:.0f} J, "
                     f"{f['relative_error']:+.2%} (90 % interval {low:.0f}-{high:.0f} J"
                     f"{'' if f['inside'] else ', MISSED'})")
    return lines


def _forecast_text(f: dict) -> list[str]:
    c = f["command"]
    lo, hi = f["energy_interval_j"]
    speed = f["vertical_speed_mps"]
    lines = [
        f"forward forecast: fit on {f['fit']}; forecast {f['forecast']}",
        f"  given: yo {c['yo_band_m'][0]:.1f}-{c['yo_band_m'][1]:.1f} m, pitch "
        f"{c['dive_pitch_rad']:.3f}/{c['climb_pitch_rad']:.3f} rad, {c['ballast_cc']:.0f} cc, "
        f"surfacing after {' + '.join(map(str, c['surfacing_cycles']))} dives, the fit "
        "part's CTD and surfacings",
        f"  energy     predicted {f['predicted_j']:7.0f} J  measured {f['measured_j']:7.0f} J  "
        f"{f['energy_relative_error']:+.2%}  (90 % interval {lo:.0f}-{hi:.0f} J)",
        f"  time       predicted {f['time_s']['predicted']:7.0f} s  measured "
        f"{f['time_s']['measured']:7.0f} s  {f['time_relative_error']:+.2%}",
        f"  yo period  predicted {f['yo_period_s']['predicted']:7.0f} s  measured "
        f"{f['yo_period_s']['measured']:7.0f} s  {f['yo_period_relative_error']:+.2%}",
    ]
    for kind in ("dive", "climb"):
        lines.append(
            f"  {kind:5s} w    predicted {speed[kind]['predicted']:7.3f} m/s measured "
            f"{speed[kind]['measured']:7.3f} m/s {f['vertical_speed_relative_error'][kind]:+.2%}"
        )
    bias = f["counter_bias"]
    lines.append(f"  coulomb counter vs current sensor on the fit part: {bias['relative']:+.2%} "
                 f"(one counter step is {bias['counter_step_j']:.0f} J)")
    if f["figures_from_base"]:
        lines.append(f"  not fitted on the fit part, from the base: "
                     f"{', '.join(f['figures_from_base'])}")
    stay = f["surface_stay"]
    if stay is not None:
        low, high = stay["interval_j"]
        lines.append(
            f"  the record's surface stay after it (not part of the forecast): predicted "
            f"{stay['predicted_j']:.0f} J (90 % interval {low:.0f}-{high:.0f} J), measured "
            f"{stay['measured_j']:.0f} J ({stay['relative_error']:+.1%}; from the base: "
            f"{', '.join(stay['figures_from_base']) or 'none'})")
    return lines
