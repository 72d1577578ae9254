"""`calibrate`: a vehicle fitted to real Slocum logs, the pipeline of `gliderplan calibrate`.

Read the .dbd/.ebd files (dbdreader, the CTD's density with gsw), fit every figure the
logs support with its bootstrap uncertainty (vehicle_fit.py: energy, flight with
gliderflight, pitch, turn times, surfacing), and with `validate` check the fit two ways:
forward (forecast_check.py: fit the earlier dives, forecast the later ones from the fit
alone) and the older replay (calibration.validate: the held-out part's own timeline with
the fitted figures). Write the calibrated vehicle file: every fitted figure with its sd and
its own source, the figures' correlation, and the devices its hotel load holds.
"""

from __future__ import annotations

import re
import tempfile
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from gliderplan.contract.errors import UsageError
from gliderplan.contract.files import read_data, write_atomically
from gliderplan.power_models import calibration
from gliderplan.power_models import segments as seg
from gliderplan.power_models.catalog import resolve
from gliderplan.power_models.config_check import ConfigurationCheck, check_configurations
from gliderplan.power_models.deployments import (
    DEFAULT_DRIFT_W,
    DRIFT_SOURCE,
    combine,
    split_deployments,
)
from gliderplan.power_models.errors import ModelFileError
from gliderplan.power_models.forecast_check import ForwardCheck, check_forward, stay_from_base
from gliderplan.power_models.model_writer import to_toml
from gliderplan.power_models.slocum_log import FlightLog, expand_log_paths, read_flight_log
from gliderplan.power_models.vehicle import (
    DEVICE_FIGURES,
    FIGURES,
    Vehicle,
    device_key,
    figure_unit,
    load_vehicle,
    read_vehicle_file,
)
from gliderplan.power_models.vehicle_fit import CalibrationError, Figure, VehicleFit, fit_vehicle

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,31}")


@dataclass(frozen=True)
class Calibration:
    """A calibrated vehicle and the report of its fit (every key is in `report`, the JSON
    that `gliderplan calibrate --json` prints)."""

    vehicle: Vehicle
    report: dict
    relative_error: float | None  # the forward forecast's energy error; None unvalidated


def calibrate(logs: list[str], *, cache: str | None = None, base: str = "slocum_g2_shallow",
              validate: bool = False, output: str | Path | None = None,
              name: str | None = None,
              progress: Callable[[str], None] | None = None) -> Calibration:
    """Fit `base` (a preset or a .toml file) to the logs (files or directories; `cache`:
    dbdreader's .cac directory, default the logs' cac/). With `validate`, fit the earlier
    whole dives and forecast the later ones, and replay the held-out half. With `output`
    (a .toml path), write the calibrated vehicle, named `name` (default: the file's stem).
    `progress(step)` is told each step as it starts (a fit takes tens of seconds).
    Raises LogError, ModelFileError, CalibrationError, or UsageError for an output that is
    not a .toml."""
    if output is not None and not str(output).endswith(".toml"):
        raise UsageError(f"{output}: the output file must end in .toml")
    step = progress or (lambda _: None)
    vehicle = load_vehicle(base)
    if not vehicle.has_buoyancy_engine:
        raise UsageError(f"--base {base}: an {vehicle.kind} has no buoyancy engine; calibrate "
                         "fits a glider's pump, glide and loads: give a glider's (or a "
                         "hybrid's) file")
    deployments = split_deployments(expand_log_paths(logs))
    step(f"reading {sum(len(d.files) for d in deployments)} log file(s)")
    each = [read_flight_log(list(d.files), cache) for d in deployments]
    log = each[-1]  # the latest: the glider as it flies now
    step("fitting the figures, each with its bootstrap over dives" +
         (f" ({len(each)} deployments)" if len(each) > 1 else ""))
    if len(each) == 1:
        fit = fit_vehicle(log, vehicle)
        fit = replace(fit, vehicle=replace(fit.vehicle, base_drift_w=DEFAULT_DRIFT_W))
        drift_source = f"assumption: one deployment shows no drift; {DRIFT_SOURCE}"
    else:
        fits = [fit_vehicle(one, vehicle) for one in each]
        fit, drift_source = combine(fits, deployments)
    whole = calibration.predict_energy_j(log, fit.vehicle)
    measured = seg.counter_energy_j(log)
    report: dict = {
        "logs": [Path(f).name for d in deployments for f in d.files],
        "deployments": [{"name": d.name, "logs": [Path(f).name for f in d.files],
                         "hotel_power_w": h} for d, h in zip(
                             deployments, [fit.vehicle.hotel_w] if len(each) == 1 else
                             [f.vehicle.hotel_w for f in fits], strict=True)],
        "base_drift": {"value_w": fit.vehicle.base_drift_w, "source": drift_source},
        "duration_s": float(log.t_s[-1]),
        "dives": fit.dives,
        "bootstrap_refits": fit.resamples,
        "figures": [_figure_json(f) for f in fit.figures],
        "hotel_includes": list(fit.vehicle.hotel_includes),
        "devices": _devices_json(fit),
        "pump_events": fit.energy.pump_events,
        "pump_rms_j": fit.energy.pump_rms_j,
        "flight_rms_w_mps": fit.flight.rms_w_mps,
        "in_sample": {
            "predicted_j": sum(whole.values()),
            "measured_j": measured,
            "relative_error": (sum(whole.values()) - measured) / measured,
        },
    }
    relative_error = None
    if validate:
        step("validating: the held-out dives replayed")
        replay = calibration.validate(log, vehicle)
        step("validating: the later dives forecast from the earlier")
        forward = check_forward(log, vehicle)
        relative_error = forward.energy_relative_error
        report["relative_error"] = replay.relative_error
        report["validation"] = {
            "kind": "replay: the held-out part's own timeline (durations, pumped volumes, "
                    "Iridium time) with the fitted figures",
            "split": replay.split,
            "duration_s": replay.duration_s,
            "predicted_j": sum(replay.predicted_j.values()),
            "predicted_by_component_j": replay.predicted_j,
            "measured_j": replay.measured_j,
            "relative_error": replay.relative_error,
        }
        report["forecast"] = _forecast_json(forward)
        step("validating: each set of instruments forecast from another")
        report["configurations"] = _configurations_json(check_configurations(log, vehicle))
    if output is not None:
        report["output"] = str(_write_vehicle(Path(output), name, base, fit, log,
                                              drift_source))
    return Calibration(fit.vehicle, report, relative_error)


def _configurations_json(check: ConfigurationCheck) -> dict:
    """The cross-configuration check: fitted on one set of devices, each other forecast."""
    return {
        "fitted_on": {"devices": list(check.fitted_devices), "dives": check.fitted_dives},
        "forecasts": [{"devices": list(f.devices), "dives": f.dives,
                       "predicted_j": f.predicted_j, "measured_j": f.measured_j,
                       "interval_j": list(f.interval_j), "relative_error": f.relative_error,
                       "inside": f.interval_j[0] <= f.measured_j <= f.interval_j[1]}
                      for f in check.forecasts],
        "not_possible": check.reason or None,
    }


def _devices_json(fit: VehicleFit) -> dict:
    """The glide's power split: the base load, each device's figure and what it rests on,
    the devices merged into the base."""
    d = fit.devices
    figures = {f.key: f for f in fit.figures}
    return {
        "base_w": d.base_w,
        "glide_s": d.glide_s,
        "rms_w": d.rms_w,
        "merged_into_base": list(d.merged),
        "table": [{"device": f.device, "kind": f.kind, "on_power_w": f.on_power_w,
                   "sd_w": figures[device_key(f.device)].sd, "duty": f.duty,
                   "fitted": f.fitted, "in_hotel": f.held, "basis": f.basis,
                   "flag": f.flag or None} for f in d.figures],
    }


def _figure_json(figure: Figure) -> dict:
    return {"key": figure.key, "value": figure.value, "unit": figure_unit(figure.key),
            "sd": figure.sd, "at_least": figure.at_least, "fitted": figure.fitted,
            "basis": figure.basis}


def _relative(predicted: float, measured: float) -> float:
    return predicted / measured - 1.0


def _forecast_json(check: ForwardCheck) -> dict:
    f, o, c = check.forecast, check.observed, check.command
    speeds = {k: {"predicted": check.predicted_w_mps[k], "measured": o.w_mps[k]}
              for k in ("dive", "climb")}
    stay = None
    if check.stay_measured_j is not None:
        stay = {"predicted_j": check.stay_predicted_j, "measured_j": check.stay_measured_j,
                "interval_j": list(check.stay_interval_j),
                "relative_error": _relative(check.stay_predicted_j, check.stay_measured_j),
                "figures_from_base": list(stay_from_base(check))}
    return {
        "energy_relative_error": check.energy_relative_error,
        "measured_j": o.energy_j,
        "predicted_j": f.energy_j,
        "energy_interval_j": list(check.interval_j),
        "yo_period_relative_error": _relative(f.yo_period_s, o.yo_period_s),
        "vertical_speed_relative_error": {k: _relative(v["predicted"], v["measured"])
                                          for k, v in speeds.items()},
        "time_relative_error": _relative(f.time_to_surface_s, o.time_s),
        "fit": f"dives 1-{check.fit_dives} (0-{check.cut_s:.0f} s)",
        "forecast": f"dives {check.fit_dives + 1}-{check.fit_dives + check.later_dives} "
                    f"({check.cut_s:.0f} s to the surface), from the fit alone",
        "command": {"yo_band_m": [c.top_m, c.bottom_m], "dive_pitch_rad": c.dive_pitch_rad,
                    "climb_pitch_rad": c.climb_pitch_rad, "ballast_cc": c.ballast_cc,
                    "surfacing_cycles": list(check.cycles)},
        "time_s": {"predicted": f.time_to_surface_s, "measured": o.time_s},
        "yo_period_s": {"predicted": f.yo_period_s, "measured": o.yo_period_s},
        "vertical_speed_mps": speeds,
        "speed_band_m": list(check.speed_band_m),
        "yos": {"predicted": f.yos, "measured": o.yos,
                "note": "dives before the surfacing: a command of the schedule"},
        "predicted_by_component_j": f.energy_by_component_j,
        "figures_from_base": list(check.from_base),
        "counter_bias": {"relative": check.counter_bias, "counter_step_j": check.counter_step_j,
                         "note": "coulomb counter / current sensor - 1 on the fit part: the "
                                 "fit uses the current sensor, the truth the counter"},
        "surface_stay": stay,
    }


def _log_names(log: FlightLog) -> str:
    return ", ".join(dict.fromkeys(Path(f).stem for f in log.files))


def _write_vehicle(output: Path, name: str | None, base: str, fit: VehicleFit,
                   log: FlightLog, drift_source: str) -> Path:
    """Write the base vehicle's file with every fitted figure replaced (value, sd, what it
    was fitted from), every other figure saying it is the base's and why, the fit's
    correlation and the devices the hotel load holds."""
    data = read_data(resolve("vehicle", base), "vehicle file")
    name = name or re.sub(r"[^A-Za-z0-9_]", "_", output.stem)
    if not _NAME.fullmatch(name):
        raise UsageError(f"vehicle name {name!r} must match [A-Za-z_][A-Za-z0-9_]{{0,31}}")
    logs = _log_names(log)
    data["name"] = name
    data["description"] = f"calibrated from {', '.join(Path(f).name for f in log.files)}"
    figures = {f.key: f for f in fit.figures}
    data["devices"] = {
        device.name: _device_table(device.kind, [figures.get(device_key(device.name, k))
                                                 for k in DEVICE_FIGURES], logs)
        for device in fit.vehicle.devices}
    for key in FIGURES:
        table, short = (data["flight"], key[7:]) if key.startswith("flight.") else (data, key)
        figure = figures.get(key)
        if figure is not None and figure.fitted:
            entry = {"value": float(f"{figure.value:.6g}"), "unit": figure_unit(key),
                     "source": f"gliderplan calibrate on {logs}: {figure.basis}"}
            if figure.sd is not None:
                entry["sd"] = float(f"{figure.sd:.3g}")
            if figure.at_least:
                entry["at_least"] = True
            table[short] = entry
        elif short in table:  # the base's, and the reason it stays
            why = figure.basis if figure is not None else "not a figure the log measures"
            table[short] = {**table[short],
                            "source": f"base {base} ({why}): {table[short]['source']}"}
    data["base_drift"] = {"value": float(f"{fit.vehicle.base_drift_w:.3g}"), "unit": "W",
                          "source": f"gliderplan calibrate on {logs}: {drift_source}"}
    held = fit.vehicle.hotel_includes
    data["hotel_includes"] = {
        "devices": list(held),
        "source": f"gliderplan calibrate on {logs}: the fitted hotel load is the whole "
                  "glider gliding, with the instruments on throughout its glides and the "
                  f"fin's moving share ({', '.join(held) or 'none'}); a mission that does not "
                  "run an instrument is billed without it",
    }
    u = fit.vehicle.uncertainty
    if u is not None:
        data["uncertainty"] = {
            "figures": list(u.keys),
            "correlation": [[round(float(x), 3) for x in row] for row in u.correlation],
            "source": u.source,
        }
    header = (
        f"Vehicle calibrated by gliderplan calibrate (base: {base}).\n"
        "Fitted figures say what they were fitted from and carry their standard deviation\n"
        f"(sd); the others say they are the base's ({base}) and why."
    )
    text = to_toml(data, header)
    _check_loads(text, output)
    write_atomically(output, text)
    return output


def _device_table(kind: str, figures: list[Figure | None], logs: str) -> dict:
    """A `[devices.NAME]` table: its kind and each figure with unit, source and sd."""
    table: dict = {"kind": kind}
    for key, figure in zip(DEVICE_FIGURES, figures, strict=True):
        if figure is None:
            continue
        entry = {"value": float(f"{figure.value:.6g}"), "unit": figure_unit(figure.key),
                 "source": f"gliderplan calibrate on {logs}: {figure.basis}"}
        if figure.sd is not None:
            entry["sd"] = float(f"{figure.sd:.3g}")
        table[key] = entry
    return table


def _check_loads(text: str, output: Path) -> None:
    """Refuse, before `output` is touched, a calibrated vehicle that would not load (a
    figure the logs drove out of its range): the user keeps the file they had."""
    with tempfile.TemporaryDirectory() as scratch:
        candidate = Path(scratch) / "calibrated.toml"  # output.name may be too long here
        candidate.write_text(text)
        try:
            read_vehicle_file(candidate)
        except ModelFileError as err:
            raise CalibrationError(f"{output}: not written: the calibrated {err.key or 'file'} "
                                   f"{err.message}") from None
