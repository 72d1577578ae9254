"""A simulated run as NetCDF in the formats glider data centres read, built from the run's
own files (timeseries.parquet, summary.json):

- `ioos`: the IOOS National Glider DAC's trajectory file (NGDAC format 2.0, checked as
  `gliderdac:3.0`), CF-1.6 and ACDD-1.3: lower-case names, a `time` dimension, the
  container variables (`platform`, `instrument_ctd`), a QC variable for each measured one
  (all "no_qc_performed": nothing was quality controlled), the depth-averaged current;
- `og1`: the OceanGliders format OG 1.0 (checked as `og:1.0`): one `N_MEASUREMENTS`
  dimension, upper-case variables with their OG1 vocabulary, the GPS fixes at the
  surface, the deployment's time and place, dates as YYYYmmddTHHMMss;
- `cf`: a plain CF-1.6 trajectory with ACDD-1.3 attributes and the CTD's variables.

Salinity, conductivity and density are TEOS-10 (`gsw`): the simulated CTD reads the
water's practical salinity while it is on (the run records the water's, `salinity_psu`),
conductivity is `gsw.C_from_SP` of it at the CTD's temperature and the pressure, density
the in-situ `gsw.rho`. A run that recorded no salinity (made by an older gliderplan)
leaves them as fill values and says so.

Who made the data (creator, publisher, institution, project, sea name, WMO id...) comes
from a metadata file (`export --metadata FILE.toml`, `METADATA_KEYS`); without one the
attributes say it is a simulation and use the reserved `.invalid` domain (RFC 2606) for
addresses no real one has. The sea name defaults to the ocean basin of the track's mean
position (`basin_name`), a name of the NCEI sea-names list.
"""

from __future__ import annotations

from datetime import UTC, datetime
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract import TICK_S
from gliderplan.contract.errors import UsageError

if TYPE_CHECKING:
    import pandas as pd
    import xarray as xr

TIME_UNITS = "seconds since 1970-01-01T00:00:00Z"
FILL = -999.0  # the Glider DAC's fill value (NaN in the OG1 file, as its examples have)
NO_PROFILE = -999
QC_NONE = np.int8(0)  # IOOS flag 0: no_qc_performed
QC_FLAGS = {"flag_values": np.array([0, 1, 2, 3, 4, 5, 8, 9], np.int8),
            "flag_meanings": "no_qc_performed good_data probably_good_data "
                             "bad_data_that_are_potentially_correctable bad_data value_changed "
                             "interpolated_value missing_value",
            "valid_min": np.int8(0), "valid_max": np.int8(9)}
STANDARD_NAME_TABLE = 93  # the CF standard name table the names were checked against
# OG1 parameter vocabulary (NERC collection OG1) of each OG1 variable, as the OG format
# manual's examples use them; a term without one there takes the P02 term they use
OG1 = "http://vocab.nerc.ac.uk/collection/OG1/current/"
OG1_TERMS = {"TIME": "TIME", "LATITUDE": "LAT", "LONGITUDE": "LON", "DEPTH": "DEPTH",
             "PRES": "PRES", "TEMP": "TEMP", "CNDC": "CNDC", "PSAL": "PSAL",
             "DENSITY": "DENSITY", "LATITUDE_GPS": "LAT_GPS", "LONGITUDE_GPS": "LON_GPS",
             "TIME_GPS": "TIME_GPS"}
# What a metadata file may give (export --metadata): the deployment's people and names.
METADATA_KEYS = (
    "title", "summary", "comment", "project", "program", "institution", "creator_name",
    "creator_email", "creator_url", "creator_type", "creator_institution", "publisher_name",
    "publisher_email", "publisher_url", "publisher_type", "publisher_institution",
    "contributor_name", "contributor_email", "contributor_role",
    "contributing_institutions", "contributing_institutions_role", "license", "sea_name",
    "wmo_id", "platform_serial_number", "ioos_regional_association", "references",
    "metadata_link")
SIMULATION = {  # the defaults: a simulation says it is one
    "project": "gliderplan simulation", "program": "gliderplan simulation",
    "institution": "gliderplan (simulation)", "creator_name": "gliderplan",
    "creator_email": "gliderplan@simulation.invalid",
    "creator_url": "https://simulation.invalid/gliderplan", "creator_type": "institution",
    "creator_institution": "gliderplan (simulation)", "publisher_name": "gliderplan",
    "publisher_email": "gliderplan@simulation.invalid",
    "publisher_url": "https://simulation.invalid/gliderplan", "publisher_type": "institution",
    "publisher_institution": "gliderplan (simulation)", "contributor_name": "gliderplan",
    "contributor_email": "gliderplan@simulation.invalid", "contributor_role": "Data scientist",
    "contributing_institutions": "gliderplan (simulation)",
    "contributing_institutions_role": "Operator",
    "license": "This data may be redistributed and used without restriction.",
    "wmo_id": "none (a simulated glider has no WMO identifier)",
    "platform_serial_number": "simulated",
    "ioos_regional_association": "none (simulation)",
    "references": "Woithe and Kremer, A programming architecture for smart autonomous "
                  "underwater vehicles",
    "metadata_link": "https://simulation.invalid/gliderplan/metadata",
}


def check_metadata(given: dict, where: str) -> dict[str, str]:
    """The metadata file's entries (`METADATA_KEYS`, each a text), or UsageError naming the
    file and key."""
    unknown = sorted(set(given) - set(METADATA_KEYS))
    if unknown:
        raise UsageError(f"{where}: {unknown[0]}: not a metadata key (the keys: "
                         f"{', '.join(METADATA_KEYS)})")
    for key, value in given.items():
        if not isinstance(value, str) or not value.strip():
            raise UsageError(f"{where}: {key}: expected a non-empty text, got {value!r}")
    return dict(given)


def basin_name(lat_deg: float, lon_deg: float) -> str:
    """The ocean basin of a position, as the NCEI sea-names list names it (a coarse sea
    name: a metadata file may give a finer one)."""
    if lat_deg >= 66.0:
        return "Arctic Ocean"
    if lat_deg <= -60.0:
        return "Southern Ocean"
    north = lat_deg >= 0.0
    if -70.0 <= lon_deg <= 20.0 or (lon_deg < -70.0 and north and lon_deg > -100.0
                                    and lat_deg > 8.0):
        return "North Atlantic Ocean" if north else "South Atlantic Ocean"
    if 20.0 < lon_deg <= 146.0 and lat_deg < 30.0:
        return "Indian Ocean"
    return "North Pacific Ocean" if north else "South Pacific Ocean"


def utc_text(epoch_s: float, compact: bool = False) -> str:
    """UTC ISO 8601: 2024-06-01T06:00:00Z, or 20240601T060000 (`compact`: OG1's dates)."""
    moment = datetime.fromtimestamp(epoch_s, UTC)
    return moment.strftime("%Y%m%dT%H%M%S" if compact else "%Y-%m-%dT%H:%M:%SZ")


class Series:
    """The run's per-tick series the formats share, in SI and CF units, NaN where there is
    no value (the CTD off, no salinity recorded)."""

    def __init__(self, table: pd.DataFrame, meta: dict, start_epoch_s: float,
                 profile_ids: np.ndarray) -> None:
        import gsw

        self.meta = meta
        self.time = start_epoch_s + table["time_s"].to_numpy(float)
        self.lat, self.lon = table["lat_deg"].to_numpy(float), table["lon_deg"].to_numpy(float)
        self.depth = table["depth_m"].to_numpy(float)
        self.pressure = np.asarray(gsw.p_from_z(-self.depth, self.lat), float)  # [dbar]
        self.temperature = table["temp_reading_c"].to_numpy(float)  # NaN while the CTD is off
        self.has_salinity = "salinity_psu" in table.columns
        water = table["salinity_psu"].to_numpy(float) if self.has_salinity else \
            np.full(self.time.shape, np.nan)
        self.salinity = np.where(np.isnan(self.temperature), np.nan, water)  # [PSU, 1e-3]
        absolute = gsw.SA_from_SP(self.salinity, self.pressure, self.lon, self.lat)
        conservative = gsw.CT_from_t(absolute, self.temperature, self.pressure)
        self.density = np.asarray(gsw.rho(absolute, conservative, self.pressure), float)
        self.conductivity = np.asarray(gsw.C_from_SP(self.salinity, self.temperature,
                                                     self.pressure), float) / 10.0  # S m-1
        self.profile = profile_ids
        self.name = meta.get("mission", "mission")
        current = meta.get("current_mps") or {}
        self.current_north = float(current.get("north", 0.0))
        self.current_east = float(current.get("east", 0.0))

    @property
    def salinity_note(self) -> str:
        return ("TEOS-10 (gsw) from the simulated CTD's practical salinity, temperature and "
                "pressure" if self.has_salinity else "not recorded by this run (made by an "
                "older gliderplan): fill values; simulate again to have it")


def _bounds_wkt(lat: np.ndarray, lon: np.ndarray) -> str:
    """The track's bounding box as WKT, latitude first (ACDD with EPSG:4326)."""
    if not lat.size:
        return ""
    s, n, w, e = (float(np.nanmin(lat)), float(np.nanmax(lat)), float(np.nanmin(lon)),
                  float(np.nanmax(lon)))
    corners = [(s, w), (n, w), (n, e), (s, e), (s, w)]
    return "POLYGON ((" + ", ".join(f"{a:.6f} {b:.6f}" for a, b in corners) + "))"


def _partial(meta: dict) -> str:
    """What the attributes add for a run interrupted in flight (a partial run)."""
    if meta.get("ended") != "interrupted":
        return ""
    return (f" PARTIAL RUN: interrupted after {float(meta.get('simulated_s', 0.0)):g} s of "
            "mission time; the flight did not end.")


def global_attributes(s: Series, metadata: dict[str, str], conventions: str,
                      compact_dates: bool = False) -> dict:
    """ACDD-1.3 (and the Glider DAC's, OG1's) global attributes of a run."""
    info = {**SIMULATION, **metadata}
    now = datetime.now(UTC).timestamp()
    first, last = (float(s.time[0]), float(s.time[-1])) if s.time.size else (0.0, 0.0)
    tick = float(s.meta.get("tick_s", TICK_S))
    lat_step = float(np.nanmedian(np.abs(np.diff(s.lat)))) if s.lat.size > 1 else 0.0
    lon_step = float(np.nanmedian(np.abs(np.diff(s.lon)))) if s.lon.size > 1 else 0.0
    depth_step = float(np.nanmedian(np.abs(np.diff(s.depth)))) if s.depth.size > 1 else 0.0
    date = (lambda t: utc_text(t, compact_dates))  # noqa: E731
    sea = info.get("sea_name") or basin_name(float(np.nanmean(s.lat)), float(np.nanmean(s.lon)))
    ident = f"{s.name}-{utc_text(first, True)}"
    return {
        "Conventions": conventions,
        "featureType": "trajectory",
        "cdm_data_type": "Trajectory",
        "title": info.get("title", f"{s.name}: simulated Slocum glider deployment"),
        "summary": info.get("summary", (
            f"Simulated flight of mission {s.name} by gliderplan's glider simulator (runtime "
            f"{s.meta.get('runtime', 'python')}, ocean {s.meta.get('ocean', 'bench')}, seed "
            f"{s.meta.get('seed', 0)}): positions, depth, pressure and the CTD's "
            "temperature, salinity, conductivity and density at every tick of the science "
            "computer.")) + _partial(s.meta),
        "comment": info.get("comment", f"simulated, not observed; mission hash "
                                       f"{s.meta.get('mission_hash', '')}") + _partial(s.meta),
        "keywords": "Oceans > Ocean Temperature > Water Temperature, Oceans > Ocean Pressure "
                    "> Water Pressure, Oceans > Salinity/Density > Salinity, Oceans > "
                    "Salinity/Density > Conductivity, Oceans > Salinity/Density > Density",
        "keywords_vocabulary": "GCMD Science Keywords",
        "id": ident,
        "naming_authority": "gliderplan",
        "source": "gliderplan glider simulator (not observations)",
        "processing_level": "simulated; not quality controlled",
        "history": f"{utc_text(now)} created by gliderplan from a simulated run",
        "date_created": date(now), "date_modified": date(now), "date_issued": date(now),
        "date_metadata_modified": date(now),
        "start_date": date(first),
        "product_version": "1.0",
        "platform": "sub-surface gliders",
        "platform_vocabulary": "https://vocab.nerc.ac.uk/collection/L06/current/27/",
        "platform_type": "Slocum Glider",
        "instrument": "CTD",
        "instrument_vocabulary": "https://vocab.nerc.ac.uk/collection/L05/current/130/",
        "rtqc_method": "none: simulated data, not quality controlled",
        "contributor_role_vocabulary": "https://vocab.nerc.ac.uk/collection/W08/current/",
        "contributing_institutions_role_vocabulary":
            "https://vocab.nerc.ac.uk/collection/W08/current/",
        "sea_name": sea,
        "standard_name_vocabulary": f"CF Standard Name Table v{STANDARD_NAME_TABLE}",
        "geospatial_lat_min": float(np.nanmin(s.lat)) if s.lat.size else 0.0,
        "geospatial_lat_max": float(np.nanmax(s.lat)) if s.lat.size else 0.0,
        "geospatial_lat_units": "degrees_north",
        "geospatial_lat_resolution": f"{lat_step:.3g} degree",
        "geospatial_lon_min": float(np.nanmin(s.lon)) if s.lon.size else 0.0,
        "geospatial_lon_max": float(np.nanmax(s.lon)) if s.lon.size else 0.0,
        "geospatial_lon_units": "degrees_east",
        "geospatial_lon_resolution": f"{lon_step:.3g} degree",
        "geospatial_vertical_min": float(np.nanmin(s.depth)) if s.depth.size else 0.0,
        "geospatial_vertical_max": float(np.nanmax(s.depth)) if s.depth.size else 0.0,
        "geospatial_vertical_units": "m",
        "geospatial_vertical_resolution": f"{depth_step:.3g} m",
        "geospatial_vertical_positive": "down",
        "geospatial_bounds": _bounds_wkt(s.lat, s.lon),
        "geospatial_bounds_crs": "EPSG:4326",
        "geospatial_bounds_vertical_crs": "EPSG:5831",  # depth below mean sea level
        "time_coverage_start": date(first),
        "time_coverage_end": date(last),
        "time_coverage_duration": f"PT{max(last - first, 0.0):.0f}S",
        "time_coverage_resolution": f"PT{tick:g}S",
        "acknowledgement": "simulated with gliderplan",
        **{k: v for k, v in info.items() if k != "sea_name"},
    }


# ---- IOOS Glider DAC ------------------------------------------------------------------

def _qc(name: str, standard_name: str, dims: tuple[str, ...], shape: tuple[int, ...]):
    """The QC variable of `name`: every value no_qc_performed (simulated data)."""
    import xarray as xr

    return xr.Variable(dims, np.full(shape, QC_NONE, np.int8), {
        "long_name": f"{name} Quality Flag", "standard_name": f"{standard_name} status_flag",
        **QC_FLAGS, "comment": "simulated data: no quality control performed"})


def ioos_dataset(s: Series, metadata: dict[str, str]) -> xr.Dataset:
    """The run as an IOOS Glider DAC trajectory file (CF-1.6, ACDD-1.3)."""
    import xarray as xr

    obs = ("time",)
    n = s.time.size
    measured = {"observation_type": "calculated", "platform": "platform",
                "instrument": "instrument_ctd", "accuracy": 0.0, "precision": 0.0,
                "resolution": 0.0, "coordinates": "time lat lon depth profile_id"}
    numbers = np.unique(s.profile[s.profile != NO_PROFILE])
    masks = [s.profile == k for k in numbers]

    def measurement(values, std, long_name, units, low, high, comment,
                    content="physicalMeasurement", **extra):
        return xr.Variable(obs, np.asarray(values, np.float64), {
            "standard_name": std, "long_name": long_name, "units": units,
            "valid_min": float(low), "valid_max": float(high), "comment": comment,
            "coverage_content_type": content, **measured, **extra})

    position = {"observation_type": "calculated", "platform": "platform",
                "coordinate_reference_frame": "urn:ogc:crs:EPSG::4326", "reference": "WGS84",
                "comment": "simulated true position"}
    v: dict[str, xr.Variable] = {
        "trajectory": xr.Variable((), f"{s.name}-{utc_text(s.time[0], True)[:13]}"
                                  if n else s.name, {
            "cf_role": "trajectory_id", "long_name": "Trajectory/Deployment Name",
            "comment": "mission name and start time of the simulated deployment"}),
        "time": xr.Variable(obs, s.time, {
            "standard_name": "time", "long_name": "Time", "axis": "T",
            "calendar": "gregorian", "units": TIME_UNITS, "observation_type": "measured",
            "ancillary_variables": "time_qc", "coverage_content_type": "coordinate",
            "comment": "the simulator's clock at each tick (simulated)"}),
        "lat": xr.Variable(obs, s.lat, {
            "standard_name": "latitude", "long_name": "Latitude", "units": "degrees_north",
            "axis": "Y", "valid_min": -90.0, "valid_max": 90.0, "ancillary_variables":
            "lat_qc", "coverage_content_type": "coordinate", **position}),
        "lon": xr.Variable(obs, s.lon, {
            "standard_name": "longitude", "long_name": "Longitude", "units": "degrees_east",
            "axis": "X", "valid_min": -180.0, "valid_max": 180.0, "ancillary_variables":
            "lon_qc", "coverage_content_type": "coordinate", **position}),
        "depth": measurement(s.depth, "depth", "Depth", "m", 0.0, 2000.0,
                             "the simulated glider's depth", "coordinate", axis="Z",
                             positive="down", reference_datum="sea-surface",
                             ancillary_variables="depth_qc"),
        "pressure": measurement(s.pressure, "sea_water_pressure", "Pressure", "dbar", 0.0,
                                2000.0, "from depth by TEOS-10 (gsw.p_from_z)",
                                positive="down", reference_datum="sea-surface",
                                ancillary_variables="pressure_qc"),
        "temperature": measurement(s.temperature, "sea_water_temperature", "Temperature",
                                   "degree_Celsius", -5.0, 40.0,
                                   "the simulated CTD's reading as sent to the runtime; fill "
                                   "while the CTD is off", ancillary_variables="temperature_qc"),
        "salinity": measurement(s.salinity, "sea_water_practical_salinity", "Salinity", "1",
                                0.0, 42.0, f"practical salinity: {s.salinity_note}",
                                ancillary_variables="salinity_qc"),
        "conductivity": measurement(s.conductivity, "sea_water_electrical_conductivity",
                                    "Conductivity", "S m-1", 0.0, 10.0,
                                    f"gsw.C_from_SP: {s.salinity_note}",
                                    ancillary_variables="conductivity_qc"),
        "density": measurement(s.density, "sea_water_density", "Density", "kg m-3", 1000.0,
                               1040.0, f"in-situ density, gsw.rho: {s.salinity_note}",
                               ancillary_variables="density_qc"),
        "profile_id": xr.Variable(obs, s.profile.astype(np.int32), {
            "long_name": "Profile ID", "valid_min": np.int32(1),
            "valid_max": np.int32(2_147_483_647), "units": "1",
            "coverage_content_type": "referenceInformation",
            "comment": "number of the dive or climb the observation belongs to; fill at the "
                       "surface and in turns"}),
    }
    profile_extra = {"observation_type": "calculated", "platform": "platform"}
    v["profile_time"] = xr.Variable(("profile",), [float(s.time[m].mean()) for m in masks], {
        "standard_name": "time", "long_name": "Profile Center Time", "units": TIME_UNITS,
        "calendar": "gregorian", "comment": "mean time of the profile's observations",
        "ancillary_variables": "profile_time_qc", **profile_extra})
    for key, values, std, units, limit in (("profile_lat", s.lat, "latitude", "degrees_north",
                                            90.0),
                                           ("profile_lon", s.lon, "longitude", "degrees_east",
                                            180.0)):
        v[key] = xr.Variable(("profile",), [float(values[m].mean()) for m in masks], {
            "standard_name": std, "long_name": f"Profile Center {std.title()}",
            "units": units, "valid_min": -limit, "valid_max": limit,
            "comment": "mean position of the profile's observations",
            "ancillary_variables": f"{key}_qc", **profile_extra})
    middle = float(s.time.mean()) if n else 0.0
    uv = {"observation_type": "calculated", "platform": "platform",
          "comment": "the simulation's depth-averaged current (sim --current), constant over "
                     "the run, at its mean time and position"}
    v["time_uv"] = xr.Variable((), middle, {"standard_name": "time", "units": TIME_UNITS,
                                            "calendar": "gregorian",
                                            "long_name": "Depth-Averaged Time",
                                            "ancillary_variables": "time_uv_qc", **uv})
    for key, value, std, units, limit in (
            ("lat_uv", float(np.nanmean(s.lat)) if n else 0.0, "latitude", "degrees_north",
             90.0),
            ("lon_uv", float(np.nanmean(s.lon)) if n else 0.0, "longitude", "degrees_east",
             180.0),
            ("u", s.current_east, "eastward_sea_water_velocity", "m s-1", 10.0),
            ("v", s.current_north, "northward_sea_water_velocity", "m s-1", 10.0)):
        v[key] = xr.Variable((), value, {
            "standard_name": std, "units": units, "long_name": f"Depth-Averaged {std}",
            "valid_min": -limit, "valid_max": limit, "ancillary_variables": f"{key}_qc",
            "coverage_content_type": "modelResult", **uv})
    info = {**SIMULATION, **metadata}
    v["platform"] = xr.Variable((), np.int32(0), {
        "type": "platform", "long_name": "Slocum Glider", "id": s.name,
        "instrument": "instrument_ctd", "wmo_id": info["wmo_id"],
        "comment": f"simulated glider, vehicle model {s.meta.get('vehicle', 'default')}"})
    v["instrument_ctd"] = xr.Variable((), np.int32(0), {
        "type": "instrument", "long_name": "Conductivity, Temperature, Depth (CTD) Sensor",
        "make_model": "simulated pumped CTD", "serial_number": info["platform_serial_number"],
        "platform": "platform", "calibration_date": "none (simulated)",
        "calibration_report": "none (simulated)", "factory_calibrated": "no (simulated)",
        "comment": f"sensor noise model {s.meta.get('noise', '')}"})
    for key in ("time", "lat", "lon", "depth", "pressure", "temperature", "salinity",
                "conductivity", "density"):
        v[f"{key}_qc"] = _qc(key, v[key].attrs["standard_name"], obs, (n,))
    for key in ("profile_time", "profile_lat", "profile_lon"):
        v[f"{key}_qc"] = _qc(key, v[key].attrs["standard_name"], ("profile",),
                             (len(masks),))
    for key in ("time_uv", "lat_uv", "lon_uv", "u", "v"):
        v[f"{key}_qc"] = _qc(key, v[key].attrs["standard_name"], (), ())
    v["profile"] = xr.Variable(("profile",), numbers.astype(np.int32),
                               {"long_name": "Profile ID"})
    ds = xr.Dataset(v, attrs=global_attributes(s, metadata, "CF-1.6, ACDD-1.3") | {
        "Metadata_Conventions": "CF-1.6, Unidata Dataset Discovery v1.0",
        "format_version": "IOOS_Glider_NetCDF_v2.0.nc"})
    for key in ("lat", "lon", "depth", "pressure", "temperature", "salinity", "conductivity",
                "density", "profile_lat", "profile_lon", "profile_time", "lat_uv", "lon_uv",
                "u", "v", "time_uv"):
        ds[key].encoding.update(_FillValue=FILL, dtype="float64")
    ds["profile_id"].encoding.update(_FillValue=np.int32(NO_PROFILE))
    for key in ("platform", "instrument_ctd"):
        ds[key].encoding.update(_FillValue=np.int32(-999))
    for key in ds.variables:
        if key.endswith("_qc"):  # outside the flags' range, as the DAC's template has it
            ds[key].encoding.update(_FillValue=np.int8(-127))
    ds["time"].encoding.update(_FillValue=None, dtype="float64")
    ds["trajectory"].encoding.update(dtype="S1", char_dim_name="traj_strlen")
    return ds


# ---- plain CF -------------------------------------------------------------------------

def cf_dataset(s: Series, metadata: dict[str, str]) -> xr.Dataset:
    """The run as a plain CF-1.6 trajectory (the CTD's variables, no DAC containers)."""
    ioos = ioos_dataset(s, metadata)
    keep = ["trajectory", "time", "lat", "lon", "depth", "pressure", "temperature",
            "salinity", "conductivity", "density", "profile_id"]
    ds = ioos[keep]
    ds.attrs = global_attributes(s, metadata, "CF-1.6, ACDD-1.3")
    for key in keep:
        ds[key].attrs = {k: a for k, a in ioos[key].attrs.items()
                         if k not in ("ancillary_variables", "platform", "instrument")}
        ds[key].encoding = dict(ioos[key].encoding)
    ds["time"].attrs["calendar"] = "standard"  # CF's preferred name (the DAC wants gregorian)
    return ds


# ---- OceanGliders OG1.0 ---------------------------------------------------------------

def og1_dataset(s: Series, metadata: dict[str, str]) -> xr.Dataset:
    """The run in the OceanGliders format OG 1.0."""
    import xarray as xr

    from gliderplan.sim.vehicle import SURFACE_DEPTH_M

    dim = ("N_MEASUREMENTS",)
    sensor = "SENSOR_CTD_SIMULATED"
    coordinates = "TIME LATITUDE LONGITUDE DEPTH"
    at_surface = s.depth <= SURFACE_DEPTH_M  # where the simulated glider has a GPS fix

    def variable(name, values, std, long_name, units, low=None, high=None, **extra):
        attrs = {"long_name": long_name, "standard_name": std, "units": units,
                 "vocabulary": OG1 + OG1_TERMS[name] + "/", **extra}
        if low is not None:
            attrs.update(valid_min=float(low), valid_max=float(high))
        return xr.Variable(dim, np.asarray(values, np.float64), attrs)

    ctd = {"sensor": sensor, "coordinates": coordinates,
           "coverage_content_type": "physicalMeasurement"}
    info = {**SIMULATION, **metadata}
    n = s.time.size
    v = {
        "TIME": variable("TIME", s.time, "time", "time of measurement", TIME_UNITS,
                         calendar="gregorian", axis="T", observation_type="measured",
                         coverage_content_type="coordinate"),
        "LATITUDE": variable("LATITUDE", s.lat, "latitude", "latitude of each measurement",
                             "degrees_north", -90, 90, axis="Y", reference="WGS84",
                             coordinate_reference_frame="urn:ogc:crs:EPSG::4326",
                             coverage_content_type="coordinate"),
        "LONGITUDE": variable("LONGITUDE", s.lon, "longitude", "longitude of each "
                              "measurement", "degrees_east", -180, 180, axis="X",
                              reference="WGS84",
                              coordinate_reference_frame="urn:ogc:crs:EPSG::4326",
                              coverage_content_type="coordinate"),
        "DEPTH": variable("DEPTH", s.depth, "depth", "glider depth", "m", 0, 2000, axis="Z",
                          positive="down", reference_datum="sea-surface",
                          coverage_content_type="coordinate"),
        "PRES": variable("PRES", s.pressure, "sea_water_pressure", "sea water pressure, "
                         "equals 0 at sea level", "dbar", 0, 2000, positive="down",
                         comment="from depth by TEOS-10 (gsw.p_from_z)", **ctd),
        "TEMP": variable("TEMP", s.temperature, "sea_water_temperature", "sea temperature "
                         "in-situ ITS-90 scale", "degree_Celsius", -5, 40,
                         comment="the simulated CTD's reading; fill while it is off", **ctd),
        "PSAL": variable("PSAL", s.salinity, "sea_water_practical_salinity", "practical "
                         "salinity", "1e-3", 0, 42, comment=s.salinity_note, **ctd),
        "CNDC": variable("CNDC", s.conductivity * 10.0, "sea_water_electrical_conductivity",
                         "electrical conductivity", "mS cm-1", 0, 85,
                         comment=f"gsw.C_from_SP: {s.salinity_note}", **ctd),
        "DENSITY": variable("DENSITY", s.density, "sea_water_density", "in-situ density",
                            "kg m-3", 1000, 1040, comment=f"gsw.rho: {s.salinity_note}",
                            **ctd),
        "TIME_GPS": variable("TIME_GPS", np.where(at_surface, s.time, np.nan), "time",
                             "time of each GPS location", TIME_UNITS, calendar="gregorian",
                             coordinates=coordinates,
                             coverage_content_type="coordinate"),
        "LATITUDE_GPS": variable("LATITUDE_GPS", np.where(at_surface, s.lat, np.nan),
                                 "latitude", "latitude of each GPS location",
                                 "degrees_north", -90, 90, coordinates=coordinates,
                                 coverage_content_type="coordinate"),
        "LONGITUDE_GPS": variable("LONGITUDE_GPS", np.where(at_surface, s.lon, np.nan),
                                  "longitude", "longitude of each GPS location",
                                  "degrees_east", -180, 180, coordinates=coordinates,
                                  coverage_content_type="coordinate"),
        "TRAJECTORY": xr.Variable((), f"{s.name}_{utc_text(s.time[0], True) if n else ''}",
                                  {"cf_role": "trajectory_id", "long_name": "trajectory name"}),
        "WMO_IDENTIFIER": xr.Variable((), info["wmo_id"], {"long_name": "wmo id"}),
        "PLATFORM_MODEL": xr.Variable((), "Slocum G2 glider (simulated)", {
            "long_name": "model of the glider", "comment":
            f"vehicle model {s.meta.get('vehicle', 'default')}"}),
        "PLATFORM_SERIAL_NUMBER": xr.Variable((), info["platform_serial_number"],
                                              {"long_name": "glider serial number"}),
        "DEPLOYMENT_TIME": xr.Variable((), float(s.time[0]) if n else np.nan, {
            "long_name": "date of deployment", "standard_name": "time", "units": TIME_UNITS,
            "calendar": "gregorian"}),
        "DEPLOYMENT_LATITUDE": xr.Variable((), float(s.lat[0]) if n else np.nan, {
            "long_name": "latitude of deployment", "standard_name": "latitude",
            "units": "degrees_north"}),
        "DEPLOYMENT_LONGITUDE": xr.Variable((), float(s.lon[0]) if n else np.nan, {
            "long_name": "longitude of deployment", "standard_name": "longitude",
            "units": "degrees_east"}),
        sensor: xr.Variable((), np.nan, {
            "long_name": "simulated pumped CTD", "sensor_type": "CTD",
            "sensor_type_vocabulary": "https://vocab.nerc.ac.uk/collection/L05/current/130/",
            "sensor_maker": "gliderplan (simulation)", "sensor_model": "simulated pumped CTD",
            "serial_number": info["platform_serial_number"],
            "comment": f"sensor noise model {s.meta.get('noise', '')}"}),
    }
    ds = xr.Dataset(v, attrs=global_attributes(s, metadata, "CF-1.10, OG-1.0, ACDD-1.3",
                                               compact_dates=True))
    for key, variable_ in ds.variables.items():
        if variable_.dtype.kind == "f":
            ds[key].encoding.update(_FillValue=np.nan, dtype="float64")
    return ds


FORMATS = {"ioos": ioos_dataset, "cf": cf_dataset, "og1": og1_dataset}
