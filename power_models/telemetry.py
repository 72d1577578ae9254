"""What a glider reports at a surfacing, read into one form: `SurfacingReport`.

A report says when it was taken (mission time [s]), where the glider is (Slocum DDMM.MMMM),
what its coulomb counter has counted since the mission started [Ah] and its battery's
voltage [V], the state it flies and the states on its stack, how long each sensor device
has been on and how long it spent in each state since the mission started [s], the plan in
force and what became of the last plan update (its acknowledgement). It comes from:

- a small JSON file (docs/plan-update.md, "Surfacing reports"): one report, a list of
  them, or {"reports": [...]}, with the keys `time_s`, `lat`, `lon`,
  `coulomb_amphr_total`, `battery_v`, `state`, `stack`, `device_on_s`, `state_time_s`,
  `plan_seq`, `ack`; a key left out or null is a gap;
- Slocum logs read with dbdreader (`.sbd`/`.tbd`, or `.dbd`/`.ebd`, with their `cac/`
  caches as for calibration): each segment (one file, or a flight and a science file of
  one name) is the report of the surfacing that ends it; it knows no state of ours;
- the binary surfacing report a glider sends up in one short Iridium message
  (`pack_report`/`unpack_report`, at most contract.SBD_MO_SHORT_BYTES).

`check_reports` refuses what no replan can rest on (a counter that runs backwards, times
that do not increase, states the mission does not have) and notes the gaps.
"""

from __future__ import annotations

import json
import math
import struct
from dataclasses import dataclass, field, replace
from pathlib import Path

from gliderplan.contract import NO_STATE, SBD_MO_SHORT_BYTES, SENSOR_DEVICES, UpdateStatus
from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import read_input_text

NOMINAL_BUS_V = 15.0  # [V] the Slocum main bus the counter's charge is counted at (battery files)
J_PER_AH = 3600.0 * NOMINAL_BUS_V  # [J Ah-1]
COUNTER_RESOLUTION_AH = 0.001  # [Ah] a counter that goes back less than this has not run back
REPORT_MAGIC = b"GT"
REPORT_VERSION = 1
_NONE32 = 0xFFFFFFFF
_NONE16 = 0xFFFF
_KEYS = ("time_s", "lat", "lon", "coulomb_amphr_total", "battery_v", "state", "stack",
         "device_on_s", "state_time_s", "plan_seq", "ack")
_LOG_SUFFIXES = {".sbd", ".tbd", ".dbd", ".ebd", ".mbd", ".nbd"}


class TelemetryError(GliderplanError):
    """Telemetry no replan can rest on; the message names the report and says why."""


@dataclass(frozen=True)
class UpdateAck:
    """What the glider says became of the last plan update: its verdict and the plan in
    force after it."""

    status: UpdateStatus
    seq: int
    message: str = ""

    def to_json(self) -> dict:
        return {"status": self.status.name.lower(), "seq": self.seq, "message": self.message}


@dataclass(frozen=True)
class SurfacingReport:
    """One surfacing's telemetry; None (or an empty table) where the report has a gap."""

    time_s: float  # [s] mission time
    coulomb_amphr_total: float | None = None  # [Ah] counted since the mission started
    battery_v: float | None = None  # [V]
    lat: float | None = None  # DDMM.MMMM
    lon: float | None = None
    state: str | None = None
    stack: tuple[str, ...] = ()
    device_on_s: dict[str, float] = field(default_factory=dict)  # [s] since the start
    state_time_s: dict[str, float] = field(default_factory=dict)  # [s] since the start
    plan_seq: int | None = None
    ack: UpdateAck | None = None
    source: str = ""  # where it came from, for messages

    @property
    def energy_used_j(self) -> float | None:
        """[J] drawn since the start: the counter's charge at the nominal bus voltage."""
        return None if self.coulomb_amphr_total is None else self.coulomb_amphr_total * J_PER_AH

    def to_json(self) -> dict:
        """The report as the JSON telemetry file holds it."""
        return {"time_s": self.time_s, "lat": self.lat, "lon": self.lon,
                "coulomb_amphr_total": self.coulomb_amphr_total, "battery_v": self.battery_v,
                "state": self.state, "stack": list(self.stack),
                "device_on_s": dict(self.device_on_s), "state_time_s": dict(self.state_time_s),
                "plan_seq": self.plan_seq, "ack": None if self.ack is None else self.ack.to_json()}


# ---- JSON ------------------------------------------------------------------------------

def _number(where: str, key: str, value: object, *, low: float = -math.inf) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise TelemetryError(f"{where}: {key}: expected a finite number, got {value!r}")
    if value < low:
        raise TelemetryError(f"{where}: {key}: {value:g} is below {low:g}")
    return float(value)


def _table(where: str, key: str, value: object, names: tuple[str, ...] | None
           ) -> dict[str, float]:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise TelemetryError(f"{where}: {key}: expected a table of seconds by name")
    out = {}
    for name, seconds in value.items():
        if names is not None and name not in names:
            raise TelemetryError(f"{where}: {key}: {name!r} is not one of {', '.join(names)}")
        out[name] = _number(where, f"{key}.{name}", seconds, low=0.0)
    return {k: v for k, v in out.items() if v is not None}


def report_from_json(entry: object, where: str) -> SurfacingReport:
    """One report of a JSON telemetry file; TelemetryError naming `where` and the key."""
    if not isinstance(entry, dict):
        raise TelemetryError(f"{where}: expected a report (a JSON object)")
    unknown = sorted(set(entry) - set(_KEYS))
    if unknown:
        raise TelemetryError(f"{where}: {unknown[0]}: unknown key (expected {', '.join(_KEYS)})")
    time_s = _number(where, "time_s", entry.get("time_s"), low=0.0)
    if time_s is None:
        raise TelemetryError(f"{where}: time_s: every report says when it was taken")
    state, stack = entry.get("state"), entry.get("stack") or []
    if state is not None and not isinstance(state, str):
        raise TelemetryError(f"{where}: state: expected a state's name")
    if not isinstance(stack, list) or not all(isinstance(s, str) for s in stack):
        raise TelemetryError(f"{where}: stack: expected a list of states' names")
    seq = entry.get("plan_seq")
    if seq is not None and (isinstance(seq, bool) or not isinstance(seq, int) or seq < 0):
        raise TelemetryError(f"{where}: plan_seq: expected a whole number >= 0")
    return SurfacingReport(
        time_s, _number(where, "coulomb_amphr_total", entry.get("coulomb_amphr_total"), low=0),
        _number(where, "battery_v", entry.get("battery_v"), low=0.0),
        _number(where, "lat", entry.get("lat")), _number(where, "lon", entry.get("lon")),
        state, tuple(stack), _table(where, "device_on_s", entry.get("device_on_s"),
                                    SENSOR_DEVICES),
        _table(where, "state_time_s", entry.get("state_time_s"), None), seq,
        _ack(where, entry.get("ack")), where)


def _ack(where: str, value: object) -> UpdateAck | None:
    if value is None:
        return None
    names = {s.name.lower(): s for s in UpdateStatus}
    if not isinstance(value, dict) or value.get("status") not in names \
            or not isinstance(value.get("seq"), int):
        raise TelemetryError(f"{where}: ack: expected {{\"status\": one of {', '.join(names)}, "
                             "\"seq\": N, \"message\": TEXT}")
    return UpdateAck(names[value["status"]], int(value["seq"]), str(value.get("message", "")))


def read_json_telemetry(path: str | Path) -> list[SurfacingReport]:
    """The reports of a JSON telemetry file, in its order."""
    text = read_input_text(path, "telemetry file")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as err:
        raise TelemetryError(f"{path}: not valid JSON: {err}") from None
    if isinstance(data, dict) and "reports" in data:
        data = data["reports"]
    entries = data if isinstance(data, list) else [data]
    return [report_from_json(e, f"{path}: report {i + 1}") for i, e in enumerate(entries)]


def write_json_telemetry(reports: list[SurfacingReport]) -> str:
    """A JSON telemetry file holding `reports`."""
    return json.dumps({"reports": [r.to_json() for r in reports]}, indent=1) + "\n"


# ---- Slocum logs -------------------------------------------------------------------------

def read_log_telemetry(paths: list[str], cache_dir: str | None = None) -> list[SurfacingReport]:
    """One report per segment of Slocum logs (files, or directories of them): the values
    at the segment's end, the surfacing that sent it; mission time and the counter's charge
    from the first segment's first reading; devices' on-time from the flight computer's
    switch of each instrument, as calibration reads them."""
    import dbdreader
    import numpy as np

    from gliderplan.power_models.slocum_log import (
        LogError,
        _device_states,
        check_log_headers,
        default_cache_dir,
    )
    from gliderplan.sim.geo import degrees_to_ddmm  # dbdreader gives decimal degrees

    files: list[Path] = []
    for item in map(Path, paths):
        if item.is_dir():
            files += sorted(p for p in item.iterdir() if p.suffix.lower() in _LOG_SUFFIXES)
        elif item.is_file():
            files.append(item)
        else:
            raise TelemetryError(f"{item}: no such file or directory", usage=True)
    if not files:
        raise TelemetryError(f"{', '.join(paths)}: no Slocum logs (.sbd/.tbd, .dbd/.ebd)")
    check_log_headers(files)
    segments: dict[str, list[str]] = {}
    for f in files:
        segments.setdefault(f.stem, []).append(str(f))
    cache = cache_dir or default_cache_dir([str(files[0])])
    reports, on_so_far = [], dict.fromkeys(SENSOR_DEVICES, 0.0)
    start = baseline = None
    for name, group in segments.items():
        try:
            logs = dbdreader.MultiDBD(filenames=group, cacheDir=cache)
            t = np.asarray(logs.get("m_present_time")[0], float)
            values = {v: _last(logs, v) for v in ("m_gps_lat", "m_gps_lon")}
            counter = _series(logs, "m_coulomb_amphr_total")
            volt = _series(logs, "m_battery")
            devices, shares = _device_states(logs, t)
        except (dbdreader.DbdError, OSError, ValueError, LogError) as err:
            raise TelemetryError(f"{name}: cannot read the segment: "
                                 f"{' '.join(str(err).split())}") from None
        if not t.size:
            raise TelemetryError(f"{name}: the segment holds no samples")
        start = t[0] if start is None else start
        if baseline is None and counter is not None:
            baseline = float(counter[1][0])
        dt = np.diff(t, append=t[-1])
        for k, device in enumerate(devices):
            if device in on_so_far:
                on_so_far[device] += float(np.nansum(shares[:, k] * dt))
        battery = None
        if volt is not None:
            late = volt[1][volt[0] >= volt[0][-1] - 300.0]
            battery = float(np.median(late)) if late.size else None
        reports.append(SurfacingReport(
            float(t[-1] - start), None if counter is None else float(counter[1][-1]) - baseline,
            battery, *(None if values[v] is None else degrees_to_ddmm(values[v])
                       for v in ("m_gps_lat", "m_gps_lon")),
            device_on_s={d: s for d, s in on_so_far.items() if s > 0.0}, source=name))
    return reports


def _series(logs, name: str):  # noqa: ANN001, ANN202
    import dbdreader
    import numpy as np

    try:
        t, v = logs.get(name)
    except dbdreader.DbdError:
        return None
    t, v = np.asarray(t, float), np.asarray(v, float)
    good = np.isfinite(v)
    return (t[good], v[good]) if good.any() else None


def _last(logs, name: str) -> float | None:  # noqa: ANN001
    found = _series(logs, name)
    return None if found is None else float(found[1][-1])


def read_telemetry(paths: str | Path | list[str | Path], cache_dir: str | None = None
                   ) -> list[SurfacingReport]:
    """Reports from JSON telemetry files (one a surfacing, or several in one; in the order
    given) or from Slocum logs (files or directories)."""
    items = [str(p) for p in ([paths] if isinstance(paths, str | Path) else paths)]
    json_files = [p for p in items if Path(p).suffix.lower() == ".json"]
    if not json_files:
        return read_log_telemetry(items, cache_dir)
    if len(json_files) < len(items):
        raise TelemetryError(f"{json_files[0]}: JSON telemetry and Slocum logs cannot be mixed: "
                             "give one or the other")
    return [r for path in json_files for r in read_json_telemetry(path)]


# ---- checks ------------------------------------------------------------------------------

def check_reports(reports: list[SurfacingReport], state_names: tuple[str, ...] | None = None
                  ) -> list[str]:
    """Notes on the gaps of `reports`; TelemetryError for what no replan can rest on: no
    report, times that do not increase, a coulomb counter (or an on-time) that runs
    backwards, a state the mission does not have."""
    if not reports:
        raise TelemetryError("no surfacing report: the telemetry holds none")
    notes: list[str] = []
    last_counted: SurfacingReport | None = None
    for before, report in zip([None, *reports], reports, strict=False):
        where = report.source or f"the report at {report.time_s:g} s"
        if before is not None and report.time_s <= before.time_s:
            raise TelemetryError(f"{where}: taken at {report.time_s:g} s, not after the report "
                                 f"before it ({before.time_s:g} s): reports out of order")
        if state_names is not None:
            for name in (report.state, *report.stack, *report.state_time_s):
                if name is not None and name not in state_names:
                    raise TelemetryError(f"{where}: state {name!r}: the mission has no such "
                                         "state (telemetry of another mission?)")
        if report.coulomb_amphr_total is None:
            notes.append(f"{where}: no coulomb counter reading (a gap): the interval "
                         "runs on to the next report that has one")
            continue
        if last_counted is not None:
            drop = last_counted.coulomb_amphr_total - report.coulomb_amphr_total
            if drop > COUNTER_RESOLUTION_AH:
                raise TelemetryError(
                    f"{where}: the coulomb counter runs backwards: {report.coulomb_amphr_total:g} "
                    f"Ah at {report.time_s:g} s after {last_counted.coulomb_amphr_total:g} Ah at "
                    f"{last_counted.time_s:g} s (a counter reset, or another glider's "
                    "reports): no replan rests on it; the glider keeps flying its current plan")
            for device, seconds in report.device_on_s.items():
                if seconds + 1e-6 < last_counted.device_on_s.get(device, 0.0):
                    raise TelemetryError(f"{where}: device_on_s.{device} runs backwards")
            gap = report.time_s - last_counted.time_s
            if before is not None and before is not last_counted:
                notes.append(f"{where}: {gap:g} s since the last report with a counter "
                             "reading: one interval spans the gap")
        last_counted = report
    if last_counted is None:
        first, last = (r.source or f"the report at {r.time_s:g} s" for r in (reports[0],
                                                                             reports[-1]))
        where = first if len(reports) == 1 else f"{first} to {last}"
        raise TelemetryError(f"{where}: no report has a coulomb counter reading: nothing "
                             "measured the energy drawn; the glider keeps flying its current "
                             "plan")
    return notes


# ---- the binary report (one short Iridium message up) -------------------------------------

def _scaled(value: float | None, scale: float, none: int, fmt: str) -> bytes:
    if value is None:
        return struct.pack(fmt, none)
    return struct.pack(fmt, int(round(value * scale)))


def pack_report(report: SurfacingReport, state_names: tuple[str, ...]) -> bytes:
    """The report as the glider sends it up (docs/plan-update.md, "The surfacing report");
    TelemetryError when it would not fit one short message (SBD_MO_SHORT_BYTES): the
    states' times are then left out, said by the caller."""
    index = {name: i for i, name in enumerate(state_names)}
    out = bytearray(REPORT_MAGIC + bytes([REPORT_VERSION]))
    out += struct.pack("<I", int(round(report.time_s)))
    out += _scaled(report.lat, 1e4, -2**31, "<i") + _scaled(report.lon, 1e4, -2**31, "<i")
    out += _scaled(report.coulomb_amphr_total, 1e3, _NONE32, "<I")
    out += _scaled(report.battery_v, 1e3, _NONE16, "<H")
    out += bytes([index.get(report.state, NO_STATE), len(report.stack)])
    out += bytes(index[s] for s in report.stack)
    devices = [(SENSOR_DEVICES.index(d), s) for d, s in report.device_on_s.items()]
    out += bytes([len(devices)])
    for i, seconds in devices:
        out += struct.pack("<BI", i, int(round(seconds)))
    states = [(index[s], t) for s, t in report.state_time_s.items()]
    out += bytes([len(states)])
    for i, seconds in states:
        out += struct.pack("<BI", i, int(round(seconds)))
    out += struct.pack("<I", report.plan_seq or 0)
    ack = report.ack
    out += struct.pack("<BI", 0xFF if ack is None else int(ack.status), 0 if ack is None
                       else ack.seq)
    if len(out) > SBD_MO_SHORT_BYTES:
        raise TelemetryError(f"the report takes {len(out)} bytes, more than the "
                             f"{SBD_MO_SHORT_BYTES} of one short message up")
    return bytes(out)


def unpack_report(data: bytes, state_names: tuple[str, ...], source: str = "") -> SurfacingReport:
    """A binary surfacing report; TelemetryError when it is not one."""
    try:
        if data[:2] != REPORT_MAGIC or data[2] != REPORT_VERSION:
            raise TelemetryError(f"{source}: not a surfacing report (version {REPORT_VERSION})")
        time_s, lat, lon, charge, volt = struct.unpack_from("<IiiIH", data, 3)
        at = 21
        state, depth = data[at], data[at + 1]
        stack = tuple(state_names[i] for i in data[at + 2:at + 2 + depth])
        at += 2 + depth
        tables = []
        for names in (SENSOR_DEVICES, state_names):
            n, at = data[at], at + 1
            rows = [struct.unpack_from("<BI", data, at + 5 * k) for k in range(n)]
            tables.append({names[i]: float(s) for i, s in rows})
            at += 5 * n
        seq, status, ack_seq = struct.unpack_from("<IBI", data, at)
        if at + 9 != len(data):
            raise TelemetryError(f"{source}: {len(data) - at - 9} bytes after the report")
    except (IndexError, struct.error):
        raise TelemetryError(f"{source}: a surfacing report cut short") from None
    return SurfacingReport(
        float(time_s), None if charge == _NONE32 else charge / 1e3,
        None if volt == _NONE16 else volt / 1e3, None if lat == -2**31 else lat / 1e4,
        None if lon == -2**31 else lon / 1e4,
        None if state == NO_STATE else state_names[state], stack, tables[0], tables[1],
        seq or None, None if status == 0xFF else UpdateAck(UpdateStatus(status), ack_seq),
        source)


def without_state_times(report: SurfacingReport) -> SurfacingReport:
    """The report without its states' times (what a mission of many states leaves out of
    the short message up)."""
    return replace(report, state_time_s={})
