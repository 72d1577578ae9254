"""A simulated run in the formats glider data pipelines read: NetCDF after the CF
trajectory conventions with the IOOS Glider DAC's variable names and ACDD global
attributes (read with xarray and netCDF4), and the track as GeoJSON and KML for a map.

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
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract import TICK_S, ExitCode
from gliderplan.contract.errors import GliderplanError, UsageError
from gliderplan.contract.files import InputFileError, read_data, write_atomically
from gliderplan.sim.loop import DEFAULT_START_EPOCH_S
from gliderplan.sim.slocum_ocean import leg_starts
from gliderplan.sim.vehicle import SURFACE_DEPTH_M

if TYPE_CHECKING:  # pandas: imported by the functions that read a run (`gliderplan sim`
    import pandas as pd  # only writes one, and importing it costs half a second)

MIN_PROFILE_M = 3.0  # a dive or climb spanning less depth is no profile [m]
TRACK_POINTS = 5000  # at most this many points on a map track
FILL = -999.0  # the Glider DAC's fill value
NO_PROFILE = -999
TIME_UNITS = "seconds since 1970-01-01T00:00:00Z"
STANDARD_NAME_TABLE = 93  # the CF standard name table the names were checked against


class ExportError(GliderplanError):
    """A run directory that cannot be exported; the message names the file."""


def start_epoch_s(meta: dict) -> float:
    """UTC start of the run [s since 1970] from its summary (`start_utc`, ISO 8601)."""
    return parse_utc(meta.get("start_utc") or DEFAULT_START_UTC)


def parse_utc(text: str) -> float:
    """ISO 8601 UTC ('2014-07-24T12:00:00Z', '2014-07-24') to seconds since 1970."""
    try:
        moment = datetime.fromisoformat(text.strip().replace("Z", "+00:00"))
    except ValueError:
        raise ValueError(f"{text!r} is not an ISO 8601 time (e.g. 2014-07-24T12:00:00Z)") \
            from None
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=UTC)
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


def _pressure_dbar(depth_m: np.ndarray, lat_deg: np.ndarray) -> np.ndarray:
    import gsw

    return np.asarray(gsw.p_from_z(-depth_m, lat_deg), float)


def trajectory_dataset(table: pd.DataFrame, meta: dict):
    """The run as an xarray Dataset: one trajectory, one observation per tick."""
    import xarray as xr

    start = start_epoch_s(meta)
    time = start + table["time_s"].to_numpy(float)
    lat, lon = table["lat_deg"].to_numpy(float), table["lon_deg"].to_numpy(float)
    depth = table["depth_m"].to_numpy(float)
    reading = table["temp_reading_c"].to_numpy(float)  # NaN while the CTD is off
    ids = profile_ids(depth)
    numbers = np.unique(ids[ids != NO_PROFILE])
    masks = [ids == k for k in numbers]
    name = meta.get("mission", "mission")
    trajectory = f"{name}-{utc_text(start)[:16].replace(':', '')}"
    obs = ("time",)
    coordinates = "time lat lon depth"
    data = {
        "trajectory": ((), trajectory, {
            "cf_role": "trajectory_id", "long_name": "Trajectory/Deployment Name",
            "comment": "mission name and start time of the simulated deployment"}),
        "lat": (obs, lat, {
            "standard_name": "latitude", "long_name": "Latitude", "units": "degrees_north",
            "axis": "Y", "valid_min": -90.0, "valid_max": 90.0, "reference": "WGS84",
            "coordinate_reference_frame": "urn:ogc:crs:EPSG::4326",
            "comment": "simulated true position"}),
        "lon": (obs, lon, {
            "standard_name": "longitude", "long_name": "Longitude", "units": "degrees_east",
            "axis": "X", "valid_min": -180.0, "valid_max": 180.0, "reference": "WGS84",
            "coordinate_reference_frame": "urn:ogc:crs:EPSG::4326",
            "comment": "simulated true position"}),
        "depth": (obs, depth, {
            "standard_name": "depth", "long_name": "Depth", "units": "m", "positive": "down",
            "axis": "Z", "valid_min": 0.0, "valid_max": 2000.0,
            "reference_datum": "sea-surface", "instrument": "instrument_ctd"}),
        "pressure": (obs, _pressure_dbar(depth, lat), {
            "standard_name": "sea_water_pressure", "long_name": "Pressure", "units": "dbar",
            "positive": "down", "valid_min": 0.0, "valid_max": 2000.0,
            "reference_datum": "sea-surface", "instrument": "instrument_ctd",
            "comment": "from depth by TEOS-10 (gsw.p_from_z)", "coordinates": coordinates,
            "coverage_content_type": "physicalMeasurement"}),
        "temperature": (obs, reading, {
            "standard_name": "sea_water_temperature", "long_name": "Temperature",
            "units": "degree_Celsius", "valid_min": -5.0, "valid_max": 40.0,
            "instrument": "instrument_ctd", "coordinates": coordinates,
            "coverage_content_type": "physicalMeasurement",
            "comment": "the simulated CTD's reading as sent to the runtime; "
                       "fill while the CTD is off"}),
        "profile_id": (obs, ids, {
            "long_name": "Profile ID", "units": "1", "valid_min": np.int32(1),
            "coordinates": coordinates, "coverage_content_type": "referenceInformation",
            "comment": "number of the dive or climb the observation belongs to; "
                       "fill at the surface and in turns"}),
        "profile_time": (("profile",), [float(time[m].mean()) for m in masks], {
            "standard_name": "time", "long_name": "Profile Center Time", "units": TIME_UNITS,
            "calendar": "standard",
            "comment": "mean time of the profile's observations"}),
        "profile_lat": (("profile",), [float(lat[m].mean()) for m in masks], {
            "standard_name": "latitude", "long_name": "Profile Center Latitude",
            "units": "degrees_north", "valid_min": -90.0, "valid_max": 90.0}),
        "profile_lon": (("profile",), [float(lon[m].mean()) for m in masks], {
            "standard_name": "longitude", "long_name": "Profile Center Longitude",
            "units": "degrees_east", "valid_min": -180.0, "valid_max": 180.0}),
        "platform": ((), np.int32(0), {
            "type": "platform", "long_name": "Slocum Glider", "id": name,
            "instrument": "instrument_ctd", "wmo_id": "",
            "comment": f"simulated glider, vehicle model {meta.get('vehicle', 'default')}"}),
        "instrument_ctd": ((), np.int32(0), {
            "type": "instrument", "long_name": "Conductivity, Temperature, Depth (CTD) "
            "Sensor", "make_model": "simulated pumped CTD", "serial_number": "",
            "platform": "platform", "calibration_date": "", "factory_calibrated": "",
            "comment": f"sensor noise model {meta.get('noise', '')}"}),
    }
    variables = {k: xr.Variable(dims, np.asarray(v), attrs) for k, (dims, v, attrs) in
                 data.items()}
    variables["time"] = xr.Variable(obs, time, {
        "standard_name": "time", "long_name": "Time", "axis": "T", "calendar": "standard",
        "units": TIME_UNITS, "observation_type": "simulated"})
    variables["profile"] = xr.Variable(("profile",), numbers.astype(np.int32),
                                       {"long_name": "Profile ID"})
    ds = xr.Dataset(variables, attrs=_global_attributes(meta, time, lat, lon, depth))
    for key in ("lat", "lon", "depth", "pressure", "temperature", "profile_lat",
                "profile_lon"):
        ds[key].encoding.update(_FillValue=FILL, dtype="float64")
    ds["profile_id"].encoding.update(_FillValue=NO_PROFILE)
    for key in ("time", "profile_time"):
        ds[key].encoding.update(_FillValue=None, dtype="float64")
    return ds


def _global_attributes(meta: dict, time: np.ndarray, lat: np.ndarray, lon: np.ndarray,
                       depth: np.ndarray) -> dict:
    name = meta.get("mission", "mission")
    now = utc_text(datetime.now(UTC).timestamp())
    first, last = (float(time[0]), float(time[-1])) if time.size else (0.0, 0.0)
    return {
        "Conventions": "CF-1.6, ACDD-1.3",
        "Metadata_Conventions": "CF-1.6, Unidata Dataset Discovery v1.0",
        "featureType": "trajectory",
        "cdm_data_type": "Trajectory",
        "format_version": "IOOS_Glider_NetCDF_v2.0.nc",
        "title": f"{name}: simulated Slocum glider deployment",
        "summary": (f"Simulated flight of mission {name} by gliderplan's glider simulator "
                    f"(runtime {meta.get('runtime', 'python')}, ocean "
                    f"{meta.get('ocean', 'bench')}, seed {meta.get('seed', 0)}): positions, "
                    "depth, pressure and the CTD's temperature at every tick of the "
                    "science computer, with one profile per dive or climb."),
        "keywords": "Oceans > Ocean Temperature > Water Temperature, "
                    "Oceans > Ocean Pressure > Water Pressure, glider, simulation",
        "keywords_vocabulary": "GCMD Science Keywords",
        "id": f"{name}-{utc_text(first)[:16].replace(':', '')}",
        "naming_authority": "gliderplan",
        "source": "gliderplan glider simulator (not observations)",
        "processing_level": "simulated; not quality controlled",
        "history": f"{now} created by gliderplan from a simulated run",
        "comment": f"mission hash {meta.get('mission_hash', '')}",
        "platform_type": "Slocum Glider",
        "platform": "platform",
        "instrument": "instrument_ctd",
        "institution": "gliderplan (simulation)",
        "project": name,
        "creator_name": "gliderplan",
        "creator_email": "",
        "creator_url": "",
        "creator_type": "institution",
        "publisher_name": "gliderplan",
        "publisher_email": "",
        "publisher_url": "",
        "license": "This data may be redistributed and used without restriction.",
        "acknowledgement": "",
        "contributor_name": "gliderplan",
        "contributor_role": "simulator",
        "references": "Woithe and Kremer, A programming architecture for smart autonomous "
                      "underwater vehicles",
        "standard_name_vocabulary": f"CF Standard Name Table v{STANDARD_NAME_TABLE}",
        "date_created": now,
        "date_modified": now,
        "date_issued": now,
        "product_version": "1.0",
        "geospatial_lat_min": float(np.nanmin(lat)) if lat.size else 0.0,
        "geospatial_lat_max": float(np.nanmax(lat)) if lat.size else 0.0,
        "geospatial_lat_units": "degrees_north",
        "geospatial_lon_min": float(np.nanmin(lon)) if lon.size else 0.0,
        "geospatial_lon_max": float(np.nanmax(lon)) if lon.size else 0.0,
        "geospatial_lon_units": "degrees_east",
        "geospatial_vertical_min": float(np.nanmin(depth)) if depth.size else 0.0,
        "geospatial_vertical_max": float(np.nanmax(depth)) if depth.size else 0.0,
        "geospatial_vertical_units": "m",
        "geospatial_vertical_positive": "down",
        "geospatial_bounds": _bounds_wkt(lat, lon),
        "geospatial_bounds_crs": "EPSG:4326",
        "geospatial_bounds_vertical_crs": "EPSG:5831",  # depth below mean sea level
        "time_coverage_start": utc_text(first),
        "time_coverage_end": utc_text(last),
        "time_coverage_duration": f"PT{max(last - first, 0.0):.0f}S",
        "time_coverage_resolution": f"PT{meta.get('tick_s', TICK_S):g}S",
    }


def _bounds_wkt(lat: np.ndarray, lon: np.ndarray) -> str:
    """The track's bounding box as WKT, latitude first (ACDD with EPSG:4326)."""
    if not lat.size:
        return ""
    s, n, w, e = (float(np.nanmin(lat)), float(np.nanmax(lat)), float(np.nanmin(lon)),
                  float(np.nanmax(lon)))
    corners = [(s, w), (n, w), (n, e), (s, e), (s, w)]
    return "POLYGON ((" + ", ".join(f"{a:.6f} {b:.6f}" for a, b in corners) + "))"


def netcdf_bytes(table: pd.DataFrame, meta: dict) -> bytes:
    """The run as a NetCDF-4 file (xarray's netCDF4 engine)."""
    return bytes(trajectory_dataset(table, meta).to_netcdf(engine="netcdf4"))


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


FORMATS = {"netcdf": ("trajectory.nc", netcdf_bytes), "geojson": ("track.geojson", track_geojson),
           "kml": ("track.kml", track_kml)}


def export_run(run_dir: str | Path, formats: list[str],
               output_dir: str | Path | None = None) -> list[Path]:
    """Write the run in `run_dir` in each of `formats` (keys of FORMATS) into
    `output_dir` (default `run_dir`), atomically; the files written (`gliderplan export`).

    Raises UsageError (exit 2) for no format, a run directory that does not exist or
    lacks the run's files, an output that cannot be written; ExportError (exit 1) for a
    run's file that cannot be read as one."""
    if not formats:
        raise UsageError("say what to write: --netcdf, --geojson and/or --kml")
    if not Path(run_dir).exists():
        raise UsageError(f"{run_dir}: no such directory (a run of gliderplan sim)")
    if not Path(run_dir).is_dir():
        raise UsageError(f"{run_dir}: not a directory (a run of gliderplan sim)")
    out = Path(output_dir if output_dir is not None else run_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"-o {out}: not a directory")
    table, meta = read_run(run_dir)
    written = []
    for name in formats:
        filename, produce = FORMATS[name]
        write_atomically(out / filename, produce(table, meta))
        written.append(out / filename)
    return written


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
