"""Reading Slocum flight logs (.dbd/.ebd and their cache files) with dbdreader.

Returns the time series the power calibration needs, on the flight computer's sample
times, in SI units (volumes in cc): depth, pitch, pumped volume, coulomb counter and
current, battery voltage, Iridium and actuator-motion flags.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gliderplan.contract.errors import GliderplanError

# dbd variable -> field; the first is the time base every other series is synced onto.
_SERIES = (
    ("m_depth", "depth_m"),
    ("m_pitch", "pitch_rad"),
    ("m_ballast_pumped", "ballast_cc"),
    ("m_coulomb_current", "current_a"),
    ("m_coulomb_amphr_total", "charge_ah"),
    ("m_iridium_on", "iridium_on"),
    ("m_is_ballast_pump_moving", "pump_moving"),
    ("m_is_battpos_moving", "battpos_moving"),
)
REQUIRED_VARIABLES = tuple(name for name, _ in _SERIES) + ("m_battery",)


class LogError(GliderplanError):
    """Logs that cannot be read or lack a variable the calibration needs."""


@dataclass(frozen=True)
class FlightLog:
    """Synced series of a log; times [s] from the first sample, epoch in `start_epoch_s`."""

    files: tuple[str, ...]
    start_epoch_s: float
    t_s: np.ndarray
    depth_m: np.ndarray
    pitch_rad: np.ndarray  # positive nose up
    ballast_cc: np.ndarray  # pumped volume, positive buoyant
    current_a: np.ndarray
    charge_ah: np.ndarray  # coulomb counter, cumulative
    battery_v: np.ndarray
    iridium_on: np.ndarray  # bool
    pump_moving: np.ndarray  # bool
    battpos_moving: np.ndarray  # bool

    def power_w(self) -> np.ndarray:
        """Instantaneous electrical power [W] from the current sensor and battery voltage."""
        return self.current_a * self.battery_v

    def slice(self, start: int, stop: int) -> FlightLog:
        """Samples start..stop-1 (times stay relative to the whole log's start)."""
        cut = {
            name: getattr(self, name)[start:stop]
            for name in (
                "t_s",
                "depth_m",
                "pitch_rad",
                "ballast_cc",
                "current_a",
                "charge_ah",
                "battery_v",
                "iridium_on",
                "pump_moving",
                "battpos_moving",
            )
        }
        return FlightLog(self.files, self.start_epoch_s, **cut)


def expand_log_paths(paths: list[str]) -> list[str]:
    """Log files named by `paths`: files as given, directories as their .dbd/.ebd files."""
    files: list[str] = []
    for item in paths:
        path = Path(item)
        if path.is_dir():
            found = sorted(str(p) for p in path.iterdir() if p.suffix.lower() in {".dbd", ".ebd"})
            if not found:
                raise LogError(f"{item}: no .dbd or .ebd files in this directory")
            files.extend(found)
        elif path.is_file():
            files.append(str(path))
        else:
            raise LogError(f"{item}: no such file or directory", usage=True)
    return files


def default_cache_dir(files: list[str]) -> str | None:
    """The `cac` directory beside the first log, where Slocum tools keep sensor caches."""
    candidate = Path(files[0]).parent / "cac"
    return str(candidate) if candidate.is_dir() else None


def read_flight_log(paths: list[str], cache_dir: str | None = None) -> FlightLog:
    """Read and sync the calibration series from Slocum logs (files or directories)."""
    import dbdreader  # heavy, and only needed here

    files = expand_log_paths(paths)
    cache = cache_dir if cache_dir is not None else default_cache_dir(files)
    if cache is not None and not Path(cache).is_dir():
        raise LogError(f"{cache}: cache directory not found", usage=True)
    try:
        logs = dbdreader.MultiDBD(filenames=files, cacheDir=cache)
        synced = logs.get_sync(*(name for name, _ in _SERIES))
        volt_t, volt = logs.get("m_battery")
    except dbdreader.DbdError as err:
        raise LogError(f"cannot read the logs: {err}") from None
    except (OSError, ValueError) as err:
        raise LogError(f"cannot read the logs: {err}") from None
    t = np.asarray(synced[0], float)
    if t.size < 10 or volt_t.size < 2:
        raise LogError("the logs hold too few samples to calibrate (need at least 10)")
    series = {
        field: np.asarray(values, float)
        for (_, field), values in zip(_SERIES, synced[1:], strict=True)
    }
    good = np.all([np.isfinite(v) for v in series.values()], axis=0)
    t = t[good]
    series = {k: v[good] for k, v in series.items()}
    return FlightLog(
        files=tuple(files),
        start_epoch_s=float(t[0]),
        t_s=t - t[0],
        depth_m=series["depth_m"],
        pitch_rad=series["pitch_rad"],
        ballast_cc=series["ballast_cc"],
        current_a=series["current_a"],
        charge_ah=series["charge_ah"],
        battery_v=np.interp(t, volt_t, volt),
        iridium_on=series["iridium_on"] > 0.5,
        pump_moving=series["pump_moving"] > 0.5,
        battpos_moving=series["battpos_moving"] > 0.5,
    )
