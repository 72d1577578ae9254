"""`gliderplan calibrate`: fit a vehicle's energy figures to real Slocum logs.

Reads .dbd/.ebd files with dbdreader, fits hotel, surface, Iridium, pump and pitch
energy, and with `--validate` fits on one part of the record and predicts the
coulomb-counter energy of the other (`gliderplan.power_models.calibrate`).
"""

from __future__ import annotations

import argparse
import json

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
        help="fit on one part of the record, predict the other, report the error",
    )
    parser.add_argument(
        "--max-error",
        type=float,
        metavar="FRACTION",
        help="with --validate: exit 1 if |relative error| exceeds this",
    )
    parser.add_argument("--json", action="store_true", help="print the report as JSON")


def run(args: argparse.Namespace) -> int:
    from gliderplan.power_models import calibrate

    if args.max_error is not None and not args.validate:
        raise UsageError("--max-error needs --validate")
    result = calibrate(args.logs, cache=args.cache, base=args.base, validate=args.validate,
                       output=args.output, name=args.name)
    print(json.dumps(result.report, indent=2) if args.json else _text(result.report))
    if args.max_error is not None and abs(result.relative_error) > args.max_error:
        raise GliderplanError(f"validation error {result.relative_error:+.1%} exceeds "
                              f"--max-error {args.max_error:.1%}")
    return 0


def _speed_lines(rows: list[dict]) -> list[str]:
    return [
        f"  {s['direction']:5s} log {s['log_w_mps']:.3f} m/s  model {s['model_w_mps']:.3f} m/s  "
        f"({s['relative_error']:+.1%}, {s['samples']} samples)"
        for s in rows
    ]


def _text(report: dict) -> str:
    lines = [
        f"logs: {', '.join(report['logs'])} ({report['duration_s']:.0f} s)",
        "",
        f"{'figure':36s} {'value':>10s} {'unit':9s} basis",
    ]
    for c in report["coefficients"]:
        mark = "" if c["fitted"] else " (kept from base)"
        lines.append(f"{c['key']:36s} {c['value']:10.4g} {c['unit']:9s} {c['basis']}{mark}")
    ins = report["in_sample"]
    lines += [
        "",
        f"pump model RMS error over {report['pump_events']} runs: {report['pump_rms_j']:.1f} J",
        f"in-sample energy: predicted {ins['predicted_j']:.0f} J, coulomb counter "
        f"{ins['measured_j']:.0f} J ({ins['relative_error']:+.2%})",
    ]
    if "validation" in report:
        val = report["validation"]
        parts = ", ".join(f"{k} {v:.0f} J" for k, v in val["predicted_by_component_j"].items())
        lines += [
            "",
            f"validation ({val['split']}, {val['duration_s']:.0f} s held out):",
            f"  predicted        {val['predicted_j']:9.0f} J  ({parts})",
            f"  measured         {val['measured_j']:9.0f} J  (coulomb counter x battery)",
            f"  relative error   {val['relative_error']:+9.2%}",
            "",
            "vertical speed, held-out part (flight model at the log's pitch and volume):",
        ]
        lines += _speed_lines(report["vertical_speed"])
        lines += [
            f"  with a trim of {report['trim_offset_cc']:+.1f} cc (positive: light), "
            "fitted on the fit part:"
        ]
        lines += _speed_lines(report["vertical_speed_trimmed"])
    if "output" in report:
        lines += ["", f"wrote {report['output']}"]
    return "\n".join(lines)
