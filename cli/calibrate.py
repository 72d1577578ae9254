"""`gliderplan calibrate`: fit a vehicle's energy figures to real Slocum logs.

Reads .dbd/.ebd files with dbdreader, fits hotel, surface, Iridium, pump and pitch
energy (see gliderplan.power_models.calibration), and with `--validate` fits on one part
of the record and predicts the coulomb-counter energy of the other.
"""

from __future__ import annotations

import argparse
import json
import re
import tomllib
from pathlib import Path

from gliderplan.cli.errors import CliError, UsageError

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
    from gliderplan.power_models import calibration
    from gliderplan.power_models.errors import ModelFileError
    from gliderplan.power_models.slocum_log import LogError, read_flight_log
    from gliderplan.power_models.vehicle import load_vehicle

    if args.max_error is not None and not args.validate:
        raise UsageError("--max-error needs --validate")
    if args.output and not args.output.endswith(".toml"):
        raise UsageError(f"{args.output}: the output file must end in .toml")
    try:
        base = load_vehicle(args.base)
        log = read_flight_log(args.logs, args.cache)
    except (ModelFileError, LogError) as err:
        raise CliError(str(err)) from None

    fit = calibration.fit_energy(log, base)
    whole = calibration.predict_energy_j(log, fit.vehicle)
    measured = calibration.seg.counter_energy_j(log)
    report: dict = {
        "logs": [Path(f).name for f in log.files],
        "duration_s": float(log.t_s[-1]),
        "coefficients": [
            {"key": c.key, "value": c.value, "unit": c.unit, "fitted": c.fitted, "basis": c.basis}
            for c in fit.coefficients
        ],
        "pump_events": fit.pump_events,
        "pump_rms_j": fit.pump_rms_j,
        "in_sample": {
            "predicted_j": sum(whole.values()),
            "measured_j": measured,
            "relative_error": (sum(whole.values()) - measured) / measured,
        },
    }
    failed = False
    if args.validate:
        try:
            result = calibration.validate(log, base)
        except ValueError as err:
            raise CliError(f"cannot validate: {err}") from None
        split = result.parts
        trim_cc = calibration.fit_trim_offset_cc(split.fit, result.fit.vehicle)
        report["relative_error"] = result.relative_error
        report["validation"] = {
            "split": result.split,
            "duration_s": result.duration_s,
            "predicted_j": sum(result.predicted_j.values()),
            "predicted_by_component_j": result.predicted_j,
            "measured_j": result.measured_j,
            "relative_error": result.relative_error,
        }
        report["vertical_speed"] = _speed_rows(split.validate, result.fit.vehicle, 0.0)
        report["trim_offset_cc"] = trim_cc
        report["vertical_speed_trimmed"] = _speed_rows(split.validate, result.fit.vehicle, trim_cc)
        failed = args.max_error is not None and abs(result.relative_error) > args.max_error
    if args.output:
        report["output"] = _write_vehicle(args, fit, log.files)
    print(json.dumps(report, indent=2) if args.json else _text(report))
    if failed:
        raise CliError(
            f"validation error {report['relative_error']:+.1%} exceeds --max-error "
            f"{args.max_error:.1%}"
        )
    return 0


def _speed_rows(log, vehicle, trim_cc: float) -> list[dict]:  # noqa: ANN001
    from gliderplan.power_models import calibration

    return [
        {
            "direction": s.direction,
            "samples": s.samples,
            "log_w_mps": s.log_w_mps,
            "model_w_mps": s.model_w_mps,
            "relative_error": s.relative_error,
            "pitch_rad": s.pitch_rad,
            "ballast_cc": s.ballast_cc,
        }
        for s in calibration.compare_vertical_speeds(log, vehicle, trim_cc)
    ]


def _write_vehicle(args: argparse.Namespace, fit, files: tuple[str, ...]) -> str:  # noqa: ANN001
    """Write the base vehicle's file with the fitted figures replaced; returns the path."""
    from gliderplan.cli.common import write_atomically
    from gliderplan.power_models.catalog import resolve
    from gliderplan.power_models.errors import ModelFileError
    from gliderplan.power_models.model_writer import to_toml
    from gliderplan.power_models.vehicle import read_vehicle_file

    with open(resolve("vehicle", args.base), "rb") as handle:
        data = tomllib.load(handle)
    output = Path(args.output)
    name = args.name or re.sub(r"[^A-Za-z0-9_]", "_", output.stem)
    if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]{0,31}", name):
        raise UsageError(f"vehicle name {name!r} must match [A-Za-z_][A-Za-z0-9_]{{0,31}}")
    data["name"] = name
    data["description"] = f"calibrated from {', '.join(Path(f).name for f in files)}"
    for c in fit.coefficients:
        if c.fitted:
            data[c.key] = {
                "value": float(f"{c.value:.6g}"),
                "unit": c.unit,
                "source": f"gliderplan calibrate: {c.basis}",
            }
    header = (
        f"Vehicle calibrated by gliderplan calibrate (base: {args.base}).\n"
        "Fitted figures say what they were fitted from; the others are the base's."
    )
    try:
        write_atomically(output, to_toml(data, header))
        read_vehicle_file(output)
    except OSError as err:
        raise CliError(f"{output}: cannot write: {err.strerror}") from None
    except ModelFileError as err:
        raise CliError(f"the written file does not load: {err}") from None
    return str(output)


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
