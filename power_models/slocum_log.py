"""Reading Slocum flight logs (.dbd/.ebd and their cache files) with dbdreader.

Returns the time series the calibration needs, on the flight computer's sample times, in
SI units (volumes in cc): depth, pitch, pumped volume, coulomb counter and current,
battery voltage, Iridium and actuator-motion flags, the pump's own velocity readings and
its software limit, what the glider was commanded (pitch, pumped volume, climb and dive
targets), the water's in-situ density from the science computer's CTD (TEOS-10; NaN
where the CTD had no reading), and the state of each device with a power figure of its
own: each science instrument's share of the time it was powered, from the flight
computer's switch for it (`slocum_instruments`), and whether the fin moved.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import read_input
from gliderplan.power_models import slocum_instruments

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
# what a calibration needs each for, to say so when a log lacks it
_NEEDED_FOR = {"m_coulomb_amphr_total": "the coulomb counter, the energy drawn",
               "m_coulomb_current": "the current, which power is fitted to",
               "m_battery": "the battery's voltage", "m_depth": "the depth"}
# optional: what the pilot commanded, and the CTD (density for the flight model)
_COMMANDS = (("c_ballast_pumped", "commanded_ballast_cc"), ("c_pitch", "commanded_pitch_rad"))
_TARGETS = (("c_climb_target_depth", "climb_target_m"), ("c_dive_target_depth", "dive_target_m"))
CTD_VARIABLES = ("sci_water_pressure", "sci_water_temp", "sci_water_cond")
_POSITION = ("m_gps_lat", "m_gps_lon")
# the pump: its velocity [cc/s] (logged each cycle it moves) and the largest volume its
# software pumps [cc] (a setting, logged once)
_PUMP_VELOCITY, _PUMP_LIMIT = "m_ballast_pumped_vel", "x_ballast_pumped_max"
_SAME_CYCLE_S = 1.0  # a reading this close to a flight sample was logged in its cycle
_FIN = "m_fin"  # the fin's measured position [rad]
FIN_MOVE_RAD = 0.002  # the fin moved between two samples when its position changed more
# science instruments (the prefix of their variables) -> the power-model device they are
_PAYLOAD = (
    ("sci_ctd41cp", "ctd"), ("sci_oxy3835", "optode"), ("sci_oxy4", "optode"),
    ("sci_bb3slo", "optics"), ("sci_flbbcd", "optics"), ("sci_flntu", "optics"),
    ("sci_bbfl2s", "optics"),
)
MIN_PAYLOAD_READINGS = 10
# the last byte of a .dbd/.ebd file: the end-of-file tag after its last data cycle (each cycle
# starts with b"d"); a file cut short (an interrupted transfer) ends in a partial cycle, which
# dbdreader decodes into garbage: times that run backwards, absurd readings
END_OF_FILE_TAG = b"X"
_TAGGED_SUFFIXES = {".dbd", ".ebd"}


class LogError(GliderplanError):
    """Logs that cannot be read or lack a variable the calibration needs."""


# The ASCII header of an uncompressed Slocum log: `dbd_label: ...` first, and among the
# lines that follow, `num_ascii_tags: N`, the header's length in lines. (A compressed
# log, *.?cd, is LZ4 blocks: dbdreader checks those itself.)
_COMPRESSED = re.compile(r"\.[a-z]cd\Z", re.IGNORECASE)
_HEADER_BYTES = 4096  # a header is some 15 lines of 20-40 bytes
_TAG_COUNT = re.compile(rb"num_ascii_tags:\s*([0-9]{1,3})\s*\Z")


def check_log_headers(files: Sequence[str | Path]) -> None:
    """Refuse, naming the file, what is no Slocum log before dbdreader reads it: of
    garbage it says only "could not be loaded", and on a header cut short it reads on for
    ever. A path that is no regular file is refused as every input is."""
    for name in files:
        if _COMPRESSED.search(str(name)):
            continue
        lines = read_input(name, "Slocum log", head=_HEADER_BYTES).split(b"\n")[:-1]
        if not lines or not lines[0].startswith(b"dbd_label:"):
            raise LogError(f"{name}: not a Slocum log (no dbd_label line first)")
        counts = [int(m[1]) for line in lines if (m := _TAG_COUNT.match(line.strip()))]
        if not counts:
            raise LogError(f"{name}: not a Slocum log (its header ends after {len(lines)} "
                           "lines, with no num_ascii_tags line)")
        if len(lines) < counts[0]:
            raise LogError(f"{name}: not a Slocum log (its header ends after {len(lines)} "
                           f"of its {counts[0]} lines)")


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
    density_kg_m3: np.ndarray  # in-situ, from the CTD; NaN without a reading
    commanded_ballast_cc: np.ndarray  # NaN where nothing was commanded
    commanded_pitch_rad: np.ndarray
    pump_velocity_cc_s: np.ndarray  # the pump's velocity reading; NaN where none was logged
    climb_target_m: float = float("nan")
    dive_target_m: float = float("nan")
    payload: tuple[str, ...] = ()  # devices that logged readings (their power is in the log)
    ballast_limit_cc: float = float("nan")  # x_ballast_pumped_max: the pump's software limit
    device_names: tuple[str, ...] = ()  # the columns of `device_on`
    # (n, len(device_names)) [1]: the share of each sample's cycle a device was on (an
    # instrument: its sampling duty; the fin: 1 if it moved before the next sample)
    device_on: np.ndarray | None = None

    # the per-sample series, in the order of the fields above
    SERIES = (
        "t_s", "depth_m", "pitch_rad", "ballast_cc", "current_a", "charge_ah", "battery_v",
        "iridium_on", "pump_moving", "battpos_moving", "density_kg_m3",
        "commanded_ballast_cc", "commanded_pitch_rad", "pump_velocity_cc_s",
    )

    def power_w(self) -> np.ndarray:
        """Instantaneous electrical power [W] from the current sensor and battery voltage."""
        return self.current_a * self.battery_v

    def slice(self, start: int, stop: int) -> FlightLog:
        """Samples start..stop-1 (times stay relative to the whole log's start)."""
        cut = {name: getattr(self, name)[start:stop] for name in self.SERIES}
        return replace(self, **cut, device_on=self.devices_on()[start:stop])

    def devices_on(self) -> np.ndarray:
        """`device_on`, (n, 0) for a log without device states."""
        if self.device_on is None:
            return np.zeros((self.t_s.size, 0))
        return self.device_on


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
    check_log_headers(files)
    cache = cache_dir if cache_dir is not None else default_cache_dir(files)
    if cache is not None and not Path(cache).is_dir():
        raise LogError(f"{cache}: cache directory not found", usage=True)
    try:
        logs = dbdreader.MultiDBD(filenames=files, cacheDir=cache)
        _check_required(logs)
        synced = logs.get_sync(*(name for name, _ in _SERIES))
        volt_t, volt = logs.get("m_battery")
        optional = _optional_series(logs, np.asarray(synced[0], float))
        names, states = _device_states(logs, np.asarray(synced[0], float))
    except (dbdreader.DbdError, OSError, ValueError) as err:
        raise LogError(f"cannot read the logs: {' '.join(str(err).split())}") from None
    for name in files:
        _check_complete(name)
    t = np.asarray(synced[0], float)
    ctd_t = optional.pop("ctd_t")
    if _steps_back(t) or _steps_back(ctd_t):
        raise LogError(f"{_file_whose_clock_steps_back(logs)}: its time runs backwards: "
                       "a corrupt file (remove it and calibrate on the others)")
    if t.size < 10 or volt_t.size < 2:
        raise LogError("the logs hold too few samples to calibrate (need at least 10)")
    series = {
        field: np.asarray(values, float)
        for (_, field), values in zip(_SERIES, synced[1:], strict=True)
    }
    good = np.all([np.isfinite(v) for v in series.values()], axis=0)
    series = {k: v[good] for k, v in series.items()}
    series |= {k: v[good] for k, v in optional.items() if isinstance(v, np.ndarray)}
    t = t[good]
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
        density_kg_m3=series["density_kg_m3"],
        commanded_ballast_cc=series["commanded_ballast_cc"],
        commanded_pitch_rad=series["commanded_pitch_rad"],
        pump_velocity_cc_s=series["pump_velocity_cc_s"],
        device_names=names,
        device_on=states[good],
        **{k: v for k, v in optional.items() if not isinstance(v, np.ndarray)},
    )


def _check_required(logs) -> None:  # noqa: ANN001
    """LogError naming every variable a calibration needs that the logs do not hold."""
    held = {n for kind in logs.parameterNames.values() for n in kind}
    missing = [n for n in REQUIRED_VARIABLES if n not in held]
    if missing:
        said = ", ".join(f"{n} ({_NEEDED_FOR[n]})" if n in _NEEDED_FOR else n for n in missing)
        raise LogError(f"the logs hold no {said}: calibration needs the glider's flight logs "
                       "(.dbd, or .sbd/.mbd with these variables) beside its science logs")


def _check_complete(name: str) -> None:
    """Refuse a .dbd/.ebd file that does not end with its end-of-file tag: one cut short."""
    if Path(name).suffix.lower() not in _TAGGED_SUFFIXES:
        return
    with open(name, "rb") as handle:
        handle.seek(0, 2)
        handle.seek(max(handle.tell() - 1, 0))
        if handle.read(1) != END_OF_FILE_TAG:
            raise LogError(f"{name}: truncated: the file does not end with the end-of-file tag "
                           f"{END_OF_FILE_TAG.decode()!r} (an interrupted transfer?); fetch it "
                           "again or calibrate without it")


def _steps_back(t: np.ndarray) -> bool:
    """Whether sample times [s] are not finite or ever decrease (a negative duration)."""
    return bool(t.size) and not (np.all(np.isfinite(t)) and np.all(np.diff(t) >= 0.0))


def _file_whose_clock_steps_back(logs) -> str:  # noqa: ANN001
    """The first file of the MultiDBD `logs` whose own time variable steps back."""
    for dbd in logs.dbds["eng"] + logs.dbds["sci"]:
        t, _ = dbd.get(dbd.timeVariable)
        if _steps_back(np.asarray(t, float)):
            return dbd.filename
    return ", ".join(logs.filenames)


def _read(logs, name: str) -> tuple[np.ndarray, np.ndarray] | None:  # noqa: ANN001
    """(times, values) of an optional variable, None if the logs do not hold it."""
    import dbdreader

    try:
        t, v = logs.get(name)
    except dbdreader.DbdError:
        return None
    return (np.asarray(t, float), np.asarray(v, float)) if np.size(t) else None


def _optional_series(logs, t: np.ndarray) -> dict:  # noqa: ANN001
    """Commands, targets, the pump's readings and the CTD's density on the flight samples'
    times `t` [epoch s]."""
    from gliderplan.power_models.seawater import in_situ_density_kg_m3

    out: dict[str, np.ndarray | float | tuple[str, ...]] = {}
    for name, field in _COMMANDS:
        found = _read(logs, name)
        # a command holds until the next one; NaN before the first
        out[field] = np.full(t.size, np.nan) if found is None else _held(found, t)
    for name, field in _TARGETS:
        found = _read(logs, name)
        if found is not None:
            out[field] = float(found[1][-1])
    out["payload"] = _payload(logs)
    out["pump_velocity_cc_s"] = _at_samples(_read(logs, _PUMP_VELOCITY), t)
    limit = _read(logs, _PUMP_LIMIT)
    if limit is not None:
        out["ballast_limit_cc"] = float(limit[1][-1])
    out["density_kg_m3"] = np.full(t.size, np.nan)
    out["ctd_t"] = np.empty(0)
    ctd = [_read(logs, name) for name in CTD_VARIABLES]
    if all(c is not None for c in ctd):
        pressure_t, pressure_bar = ctd[0]
        out["ctd_t"] = pressure_t
        temp = np.interp(pressure_t, *ctd[1])
        cond = np.interp(pressure_t, *ctd[2])
        real = (cond > 0.0) & (pressure_bar >= 0.0)  # 0 is the science computer's "no data"
        if real.sum() >= 2:
            lat, lon = (_median(_read(logs, name)) for name in _POSITION)
            rho = in_situ_density_kg_m3(temp[real], cond[real], pressure_bar[real] * 10.0,
                                        lat, lon)
            out["density_kg_m3"] = np.interp(t, pressure_t[real], rho, np.nan, np.nan)
    return out


def _device_states(logs, t: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:  # noqa: ANN001
    """(device names, (n, k) on-shares at the flight samples' times `t` [epoch s]) of every
    science device whose switch the logs hold and that was ever on, and of the fin if its
    position is logged. An instrument sampled every N s is powered for its warm-up and one
    sample each interval (`slocum_instruments.sampling_duty`, with its preset's figures);
    several instruments of one device (two optics pucks) count as on when either is."""
    from gliderplan.power_models.sensor import load_sensor

    logged = {n.lower(): n for kind in logs.parameterNames.values() for n in kind}
    names, columns = [], []
    for device in slocum_instruments.devices():
        preset = load_sensor(device)
        shares = [slocum_instruments.sampling_duty(_held(found, t), preset.warmup_s,
                                                   preset.sample_hz)
                  for instrument in slocum_instruments.instruments_of(device)
                  if instrument.switch in logged
                  and (found := _read(logs, logged[instrument.switch])) is not None]
        if shares and np.max(shares) > 0.0:
            names.append(device)
            columns.append(np.max(shares, axis=0))
    fin = _read(logs, _FIN) if _FIN in logged else None
    if fin is not None:
        position = _held(fin, t)
        moved = np.abs(np.diff(position)) > FIN_MOVE_RAD
        names.append("fin")
        columns.append(np.append(moved, False).astype(float))
    return tuple(names), np.column_stack(columns) if columns else np.zeros((t.size, 0))


def _payload(logs) -> tuple[str, ...]:  # noqa: ANN001
    """Devices of the science instruments that logged readings (not only an installed flag)."""
    names = [n for kind in logs.parameterNames.values() for n in kind]
    logged = []
    for prefix, device in _PAYLOAD:
        for name in (n for n in names if n.startswith(prefix + "_")
                     and not n.endswith("_is_installed")):
            found = _read(logs, name)
            if found is not None and np.count_nonzero(found[1]) >= MIN_PAYLOAD_READINGS:
                logged.append(device)
                break
    return tuple(dict.fromkeys(logged))


def _at_samples(found: tuple[np.ndarray, np.ndarray] | None, t: np.ndarray) -> np.ndarray:
    """Readings of a variable logged only on some cycles, at the flight samples of the same
    cycle; NaN at the others (nothing is held or interpolated between readings)."""
    out = np.full(t.size, np.nan)
    if found is None or t.size < 2:
        return out
    times, values = found
    after = np.clip(np.searchsorted(t, times), 1, t.size - 1)
    nearest = np.where(np.abs(t[after - 1] - times) <= np.abs(t[after] - times), after - 1, after)
    same = np.abs(t[nearest] - times) <= _SAME_CYCLE_S
    out[nearest[same]] = values[same]
    return out


def _held(found: tuple[np.ndarray, np.ndarray], t: np.ndarray) -> np.ndarray:
    times, values = found
    index = np.searchsorted(times, t, side="right") - 1
    return np.where(index >= 0, values[np.maximum(index, 0)], np.nan)


def _median(found: tuple[np.ndarray, np.ndarray] | None) -> float:
    """Median of a position series [deg]; 0 without fixes (the position changes the
    absolute salinity, hence the density, by ~0.01 kg m-3 at most)."""
    if found is None or not np.isfinite(found[1]).any():
        return 0.0
    return float(np.nanmedian(found[1]))
