"""A simulated run in the formats glider data pipelines read: NetCDF as the IOOS Glider
DAC, the OceanGliders OG 1.0 format or plain CF reads it (sim.netcdf_formats: TEOS-10
salinity, conductivity and density, ACDD attributes), and the track as GeoJSON and KML
for a map.

Inputs are the run's own files (timeseries.parquet and summary.json), so a run can be
exported again later (`gliderplan export RUNDIR`). Each format is produced as bytes or
text, for the caller to write atomically.

A profile, as the Glider DAC counts them, is one dive or one climb: the legs of the
flown depth series (split where the glider turns, `sim.slocum_ocean.leg_starts`)
that span at least `MIN_PROFILE_M`; time at the surface (shallower than the antenna
depth, `sim.vehicle.SURFACE_DEPTH_M`) belongs to no profile.
"""

from __future__ import annotations

import json
import math
import os
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract import START_YEARS, ExitCode, interrupts
from gliderplan.contract.errors import GliderplanError, UsageError
from gliderplan.contract.files import InputFileError, output_folder, read_data
from gliderplan.sim.loop import DEFAULT_START_EPOCH_S
from gliderplan.sim.slocum_ocean import leg_starts
from gliderplan.sim.vehicle import SURFACE_DEPTH_M

if TYPE_CHECKING:  # pandas: imported by the functions that read a run (`gliderplan sim`
    import pandas as pd  # only writes one, and importing it costs half a second)

MIN_PROFILE_M = 3.0  # a dive or climb spanning less depth is no profile [m]
TRACK_POINTS = 5000  # at most this many points on a map track
NO_PROFILE = -999


class ExportError(GliderplanError):
    """A run directory that cannot be exported; the message names the file."""


def start_epoch_s(meta: dict) -> float:
    """UTC start of the run [s since 1970] from its summary (`start_utc`, ISO 8601)."""
    return parse_utc(meta.get("start_utc") or DEFAULT_START_UTC)


def parse_utc(text: str) -> float:
    """ISO 8601 UTC ('2014-07-24T12:00:00Z', '2014-07-24') to seconds since 1970, within
    the years a run may start in (`contract.START_YEARS`: a run's dates, a month or a
    year on, must still be dates every format writes)."""
    try:
        moment = datetime.fromisoformat(text.strip().replace("Z", "+00:00"))
    except ValueError:
        raise ValueError(f"{text!r} is not an ISO 8601 time (e.g. 2014-07-24T12:00:00Z)") \
            from None
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=UTC)
    first, last = START_YEARS
    if not first <= moment.astimezone(UTC).year <= last:
        raise ValueError(f"{text!r}: a run starts between {first} and {last}")
    return moment.timestamp()


def utc_text(epoch_s: float) -> str:
    return datetime.fromtimestamp(epoch_s, UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


DEFAULT_START_UTC = utc_text(DEFAULT_START_EPOCH_S)  # a run whose summary names no start


def profile_ids(depth_m: np.ndarray) -> np.ndarray:
    """Profile number (1, 2, ...) of each sample, NO_PROFILE outside a profile."""
    ids = np.full(depth_m.shape, NO_PROFILE, dtype=np.int32)
    if depth_m.size == 0:
        return ids
    bounds = leg_starts(depth_m) + [depth_m.size]
    number = 0
    for a, b in zip(bounds, bounds[1:], strict=False):
        leg = depth_m[a:b]
        if leg.max() - leg.min() >= MIN_PROFILE_M:
            number += 1
            ids[a:b][leg > SURFACE_DEPTH_M] = number
    return ids


def netcdf_bytes(table: pd.DataFrame, meta: dict, fmt: str = "ioos",
                 metadata: dict[str, str] | None = None) -> bytes:
    """The run as a NetCDF-4 file in `fmt` ("ioos", "og1" or "cf": sim.netcdf_formats),
    with the deployment's `metadata` (a metadata file's entries) over the defaults."""
    from gliderplan.sim.netcdf_formats import FORMATS as NETCDF
    from gliderplan.sim.netcdf_formats import Series

    series = Series(table, meta, start_epoch_s(meta), profile_ids(table["depth_m"].to_numpy(
        float)))
    dataset = NETCDF[fmt](series, metadata or {})
    return bytes(dataset.to_netcdf(engine="netcdf4"))


def _track(table: pd.DataFrame, max_points: int = TRACK_POINTS) -> np.ndarray:
    """(lon, lat) [deg] of the track to 7 decimals (1 cm), without repeats (a glider
    waiting at the surface), every n-th point so that at most `max_points` remain,
    always with the last."""
    points = np.round(table[["lon_deg", "lat_deg"]].to_numpy(float), 7)
    points = points[np.isfinite(points).all(axis=1)]
    if len(points):
        moved = np.concatenate([[True], np.any(np.diff(points, axis=0) != 0.0, axis=1)])
        points = points[moved]
    step = max(1, math.ceil(len(points) / max_points))
    picked = points[::step]
    if len(points) and (len(points) - 1) % step:
        picked = np.vstack([picked, points[-1]])
    return picked


def track_geojson(table: pd.DataFrame, meta: dict) -> str:
    """The track as a GeoJSON FeatureCollection: the path and its start and end."""
    track = _track(table)
    start = start_epoch_s(meta)
    seconds = table["time_s"].to_numpy(float)
    end = start + (float(seconds[-1]) if seconds.size else 0.0)
    coords = [[float(x), float(y)] for x, y in track]
    name = meta.get("mission", "mission")
    features = [{"type": "Feature", "geometry": {"type": "LineString", "coordinates": coords},
                 "properties": {"name": f"{name} track", "mission": name,
                                "start": utc_text(start), "end": utc_text(end),
                                "ended": meta.get("ended", "")}}]
    for label, point, when in (("start", coords[0] if coords else None, start),
                               ("end", coords[-1] if coords else None, end)):
        if point is not None:
            features.append({"type": "Feature", "geometry": {"type": "Point",
                                                             "coordinates": point},
                             "properties": {"name": f"{name} {label}", "time": utc_text(when)}})
    return json.dumps({"type": "FeatureCollection", "features": features}, indent=1) + "\n"


def track_kml(table: pd.DataFrame, meta: dict) -> str:
    """The track as KML 2.2: a line, and placemarks at its start and end."""
    from xml.sax.saxutils import escape

    track = _track(table)
    name = escape(str(meta.get("mission", "mission")))
    start = start_epoch_s(meta)
    seconds = table["time_s"].to_numpy(float)
    end = start + (float(seconds[-1]) if seconds.size else 0.0)
    line = " ".join(f"{x:.7f},{y:.7f},0" for x, y in track)
    marks = []
    for label, index, when in (("start", 0, start), ("end", -1, end)):
        if len(track):
            x, y = track[index]
            marks.append(
                f"    <Placemark>\n      <name>{name} {label}</name>\n"
                f"      <TimeStamp><when>{utc_text(when)}</when></TimeStamp>\n"
                f"      <Point><coordinates>{x:.7f},{y:.7f},0</coordinates></Point>\n"
                "    </Placemark>\n")
    return (
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<kml xmlns="http://www.opengis.net/kml/2.2">\n'
        "  <Document>\n"
        f"    <name>{name}</name>\n"
        '    <Style id="track"><LineStyle><color>ff0000ff</color><width>2</width>'
        "</LineStyle></Style>\n"
        "    <Placemark>\n"
        f"      <name>{name} track</name>\n"
        f"      <TimeSpan><begin>{utc_text(start)}</begin><end>{utc_text(end)}</end>"
        "</TimeSpan>\n"
        "      <styleUrl>#track</styleUrl>\n"
        f"      <LineString><tessellate>1</tessellate><coordinates>{line}</coordinates>"
        "</LineString>\n"
        "    </Placemark>\n"
        + "".join(marks) +
        "  </Document>\n"
        "</kml>\n")


# format -> (file name, what writes it); "netcdf" is the IOOS file's older name
FORMATS = {"ioos": ("trajectory.nc", lambda t, m, d: netcdf_bytes(t, m, "ioos", d)),
           "og1": ("trajectory_og1.nc", lambda t, m, d: netcdf_bytes(t, m, "og1", d)),
           "cf": ("trajectory_cf.nc", lambda t, m, d: netcdf_bytes(t, m, "cf", d)),
           "geojson": ("track.geojson", lambda t, m, d: track_geojson(t, m)),
           "kml": ("track.kml", lambda t, m, d: track_kml(t, m))}
ALIASES = {"netcdf": "ioos"}
EXPORT_FILES = tuple(filename for filename, _ in FORMATS.values())


def export_run(run_dir: str | Path, formats: list[str],
               output_dir: str | Path | None = None,
               metadata_path: str | Path | None = None, force: bool = False) -> list[Path]:
    """Write the run in `run_dir` in each of `formats` (keys of FORMATS, or "netcdf" for
    "ioos") into `output_dir` (default `run_dir`); the files written (`gliderplan
    export`). Another folder is written whole as a run of its own (contract.files.
    output_folder; `force`: replace one holding other files than a gliderplan run's);
    the run's own folder is replaced whole by itself and these files. Interrupted, it
    writes nothing. `metadata_path`: a TOML file of the deployment's people and
    names (sim.netcdf_formats.METADATA_KEYS) for the NetCDF files.

    Raises UsageError (exit 2) for no format or an unknown one, a run directory that does
    not exist or lacks the run's files, a bad metadata file, an output that cannot be
    written; ExportError (exit 1) for a run's file that cannot be read as one."""
    if not formats:
        raise UsageError("say what to write: --format og1|ioos|cf (NetCDF), --geojson "
                         "and/or --kml")
    formats = list(dict.fromkeys(ALIASES.get(f, f) for f in formats))
    unknown = [f for f in formats if f not in FORMATS]
    if unknown:
        raise UsageError(f"--format {unknown[0]}: expected one of og1, ioos, cf")
    metadata = {}
    if metadata_path is not None:
        from gliderplan.contract.files import read_data
        from gliderplan.sim.netcdf_formats import check_metadata

        metadata = check_metadata(read_data(metadata_path, "metadata file"),
                                  str(metadata_path))
    if not Path(run_dir).exists():
        raise UsageError(f"{run_dir}: no such directory (a run of gliderplan sim)")
    if not Path(run_dir).is_dir():
        raise UsageError(f"{run_dir}: not a directory (a run of gliderplan sim)")
    out = Path(output_dir if output_dir is not None else run_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory")
    table, meta = read_run(run_dir)
    # into the run's own folder: the folder, its run and these files, replaces the run
    into_run = os.path.realpath(out) == os.path.realpath(run_dir)
    with output_folder(out, command="sim" if into_run else "export", force=force,
                       keep=into_run, recognised=EXPORT_FILES,
                       inputs=(run_dir, metadata_path)) as folder:
        if into_run:
            folder.complete = meta.get("complete", meta.get("ended") != "interrupted")
        files = [(name, *FORMATS[name]) for name in formats]
        contents = {filename: produce(table, meta, metadata) for _, filename, produce in files}
        interrupts.raise_if_stopped()
        return [folder.write(filename, data) for filename, data in contents.items()]


def read_run(run_dir: str | Path) -> tuple[pd.DataFrame, dict]:
    """The time series and summary of a run directory written by `gliderplan sim`."""
    run_dir = Path(run_dir)
    series, summary = run_dir / "timeseries.parquet", run_dir / "summary.json"
    try:
        meta = read_data(summary, "run summary")
    except InputFileError as err:
        raise ExportError(f"{err}; is {run_dir} a run of gliderplan sim?",
                          usage=err.exit_code == ExitCode.USAGE) from None
    if not series.is_file():  # read whole by pyarrow: a month's run is larger than one input
        raise ExportError(f"{series}: no such file; is {run_dir} a run of gliderplan sim?",
                          usage=True)
    try:
        import pandas as pd

        table = pd.read_parquet(series)
    except (OSError, ValueError) as err:
        raise ExportError(f"{series}: cannot read: {err}") from None
    missing = {"time_s", "depth_m", "lat_deg", "lon_deg", "temp_reading_c"} - set(table.columns)
    if missing:
        raise ExportError(f"{series}: no column {', '.join(sorted(missing))}")
    return table, meta
