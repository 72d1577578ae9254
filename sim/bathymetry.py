"""The sea floor by position (`sim --floor FILE.nc`): a bathymetry grid read with xarray,
GEBCO's `elevation` (negative below the sea), `z`, `topo` or a CF `altitude` or
`height_above_*` (up), or a `depth` or CF `sea_floor_depth_below_*` (down), on latitude and
longitude axes; bilinear between its points, held at its edges. Land (no depth below the
surface) has no floor: a glider that starts there is refused (`start_problem`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gliderplan.sim.currents import CurrentError, GriddedCurrent

_DOWN = ("sea_floor_depth_below_geoid", "sea_floor_depth_below_sea_surface",
         "sea_floor_depth", "depth", "bathymetry")
_UP = ("elevation", "z", "topo", "altitude", "height_above_reference_ellipsoid",
       "height_above_mean_sea_level", "height")


@dataclass(frozen=True)
class Bathymetry:
    """Water depths [m, > 0; NaN on land] on a latitude, longitude grid [deg]."""

    grid: GriddedCurrent  # the depths as its north component (one time, one depth)
    source: str

    by_position = True  # the floor under the glider depends on where it is, not when

    def depth_under(self, lat_deg: float, lon_deg: float, time_s: float = 0.0) -> float:
        """[m] the floor under a position [deg] (NaN: land)."""
        return self.grid.at(lat_deg, lon_deg, 0.0)[0]

    @property
    def median_m(self) -> float:
        """[m] the median depth of the grid's water."""
        depths = self.grid.north_mps
        return float(np.nanmedian(depths)) if np.any(np.isfinite(depths)) else math.nan

    def describe(self) -> str:
        depths = self.grid.north_mps
        return (f"sea floor from the bathymetry {self.source}: {np.nanmin(depths):.1f}-"
                f"{np.nanmax(depths):.1f} m (median {self.median_m:.1f} m) under the glider")

    def start_problem(self, lat_deg: float, lon_deg: float) -> str | None:
        """Why the glider cannot start at a position [deg], or None."""
        if math.isfinite(self.depth_under(lat_deg, lon_deg)):
            return None
        return (f"the start {lat_deg:.4f}, {lon_deg:.4f} is on land in the bathymetry "
                f"{self.source} (no water depth there): give --start LAT,LON at sea")


def read_bathymetry(path: str | Path) -> Bathymetry:
    """A bathymetry grid; CurrentError naming what is missing."""
    import xarray as xr

    try:
        dataset = xr.open_dataset(path)
    except (OSError, ValueError) as err:
        raise CurrentError(f"{path}: not a NetCDF file xarray can read ({err})") from None
    with dataset:
        found = _variable(dataset, _DOWN), _variable(dataset, _UP)
        name, down = (found[0], True) if found[0] is not None else (found[1], False)
        if name is None:
            raise CurrentError(
                f"{path}: no bathymetry: expected a variable named or with the standard name "
                f"{', '.join(_DOWN + _UP)}; it holds "
                f"{', '.join(map(str, dataset.data_vars)) or 'no variables'}")
        values = dataset[name]
        axes = [next((d for d in values.dims if str(d).lower().startswith(p)), None)
                for p in ("lat", "lon")]
        if None in axes or len(values.dims) != 2:
            raise CurrentError(f"{path}: {name} is not on latitude and longitude alone (its "
                               f"dimensions: {', '.join(map(str, values.dims))})")
        values = values.transpose(*axes)
        lat = dataset[axes[0]].values.astype(float)
        lon = dataset[axes[1]].values.astype(float)
        depth = values.values.astype(float) * (1.0 if down else -1.0)
    depth = np.where(depth > 0.0, depth, np.nan)  # land and the shore: no floor under water
    lon = np.where(lon > 180.0, lon - 360.0, lon)
    i, j = np.argsort(lat), np.argsort(lon)
    depth = depth[np.ix_(i, j)]
    grid = GriddedCurrent(np.array([0.0]), np.array([0.0]), lat[i], lon[j],
                          depth[None, None], np.zeros((1, 1, len(lat), len(lon))),
                          description=str(path))
    return Bathymetry(grid, str(path))


def _variable(dataset, names: tuple[str, ...]) -> str | None:
    for var_name, var in dataset.data_vars.items():
        if var.attrs.get("standard_name") in names or str(var_name).lower() in names:
            return str(var_name)
    return None
