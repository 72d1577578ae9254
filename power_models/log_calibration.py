"""`calibrate`: a vehicle's energy figures fitted to real Slocum logs, the pipeline of
`gliderplan calibrate`: read the .dbd/.ebd files (dbdreader), fit hotel, surface,
Iridium, pump and pitch energy (calibration.py), and with `validate` fit on one part of
the record and predict the coulomb-counter energy of the other; write the calibrated
vehicle file."""

from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path

from gliderplan.contract.errors import GliderplanError, UsageError
from gliderplan.contract.files import write_atomically
from gliderplan.power_models import calibration
from gliderplan.power_models.catalog import resolve
from gliderplan.power_models.errors import ModelFileError
from gliderplan.power_models.model_writer import to_toml
from gliderplan.power_models.slocum_log import FlightLog, read_flight_log
from gliderplan.power_models.vehicle import Vehicle, load_vehicle, read_vehicle_file

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,31}")


@dataclass(frozen=True)
class Calibration:
    """A calibrated vehicle and the report of its fit (every key is in `report`, the JSON
    that `gliderplan calibrate --json` prints)."""

    vehicle: Vehicle
    report: dict
    relative_error: float | None  # held-out energy, predicted against measured; None unvalidated


def calibrate(logs: list[str], *, cache: str | None = None, base: str = "slocum_g2_shallow",
              validate: bool = False, output: str | Path | None = None,
              name: str | None = None) -> Calibration:
    """Fit `base`'s energy figures (a preset or a .toml file) to the logs (files or
    directories; `cache`: dbdreader's .cac directory, default the logs' cac/). With
    `validate`, fit on one part and predict the other. With `output` (a .toml path), write
    the base's file with the fitted figures, named `name` (default: the file's stem).
    Raises LogError, ModelFileError, or UsageError for an output that is not a .toml."""
    if output is not None and not str(output).endswith(".toml"):
        raise UsageError(f"{output}: the output file must end in .toml")
    vehicle = load_vehicle(base)
    log = read_flight_log(logs, cache)
    fit = calibration.fit_energy(log, vehicle)
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
    relative_error = None
    if validate:
        result = calibration.validate(log, vehicle)
        trim_cc = calibration.fit_trim_offset_cc(result.parts.fit, result.fit.vehicle)
        relative_error = result.relative_error
        report["relative_error"] = relative_error
        report["validation"] = {
            "split": result.split,
            "duration_s": result.duration_s,
            "predicted_j": sum(result.predicted_j.values()),
            "predicted_by_component_j": result.predicted_j,
            "measured_j": result.measured_j,
            "relative_error": relative_error,
        }
        report["vertical_speed"] = _speed_rows(result.parts.validate, result.fit.vehicle, 0.0)
        report["trim_offset_cc"] = trim_cc
        report["vertical_speed_trimmed"] = _speed_rows(result.parts.validate,
                                                       result.fit.vehicle, trim_cc)
    if output is not None:
        report["output"] = str(_write_vehicle(Path(output), name, base, fit, log.files))
    return Calibration(fit.vehicle, report, relative_error)


def _speed_rows(log: FlightLog, vehicle: Vehicle, trim_cc: float) -> list[dict]:
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


def _write_vehicle(output: Path, name: str | None, base: str, fit: calibration.EnergyFit,
                   files: tuple[str, ...]) -> Path:
    """Write the base vehicle's file with the fitted figures replaced."""
    with open(resolve("vehicle", base), "rb") as handle:
        data = tomllib.load(handle)
    name = name or re.sub(r"[^A-Za-z0-9_]", "_", output.stem)
    if not _NAME.fullmatch(name):
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
        f"Vehicle calibrated by gliderplan calibrate (base: {base}).\n"
        "Fitted figures say what they were fitted from; the others are the base's."
    )
    try:
        write_atomically(output, to_toml(data, header))
    except OSError as err:
        raise GliderplanError(f"{output}: cannot write: {err.strerror}") from None
    try:
        read_vehicle_file(output)
    except ModelFileError as err:
        raise GliderplanError(f"the written file does not load: {err}") from None
    return output
