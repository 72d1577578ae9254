"""Sea-water density from a glider's CTD (TEOS-10, with the `gsw` package) and the density
profile a forecast flies through.

The density of the water sets the glider's buoyancy: 1 kg m-3 is ~60 cc for a 60 l hull,
as much as a quarter of a shallow glider's pumped volume. Baltic water is ~1005 kg m-3,
the open ocean 1025-1028; the North Sea log in `../shared/data` goes from 1023.0 at the
surface to 1024.8 below its thermocline. So the flight model is fitted against the
in-situ density the CTD measured, never a fixed 1025.
"""

from __future__ import annotations

import numpy as np

from gliderplan.power_models.flight import DensityProfile

MS_CM_PER_S_M = 10.0  # conductivity: gsw takes mS/cm, Slocum logs S/m


def in_situ_density_kg_m3(
    temperature_c: np.ndarray,
    conductivity_s_m: np.ndarray,
    pressure_dbar: np.ndarray,
    lat_deg: float,
    lon_deg: float,
) -> np.ndarray:
    """In-situ density [kg m-3] from in-situ temperature [degC], conductivity [S m-1] and sea
    pressure [dbar] at a position [deg] (TEOS-10: practical salinity from conductivity,
    absolute salinity at the position, conservative temperature, then density)."""
    import gsw  # heavy, and only needed when a log is read

    practical = gsw.SP_from_C(conductivity_s_m * MS_CM_PER_S_M, temperature_c, pressure_dbar)
    absolute = gsw.SA_from_SP(practical, pressure_dbar, lon_deg, lat_deg)
    conservative = gsw.CT_from_t(absolute, temperature_c, pressure_dbar)
    return np.asarray(gsw.rho(absolute, conservative, pressure_dbar), float)


def density_profile(
    depth_m: np.ndarray, rho_kg_m3: np.ndarray, bin_m: float = 1.0
) -> DensityProfile:
    """Mean density [kg m-3] in depth bins of `bin_m` [m], at the bins' centres: the water
    column a record flew through. Empty bins are left out (the profile interpolates)."""
    good = np.isfinite(depth_m) & np.isfinite(rho_kg_m3)
    if not good.any():
        raise ValueError("no density readings to make a profile from")
    index = np.floor(depth_m[good] / bin_m).astype(int)
    index -= index.min()
    counts = np.bincount(index)
    sums = np.bincount(index, weights=rho_kg_m3[good])
    filled = counts > 0
    lowest = np.floor(depth_m[good].min() / bin_m) * bin_m
    centres = lowest + (np.flatnonzero(filled) + 0.5) * bin_m
    return DensityProfile(centres, sums[filled] / counts[filled])
