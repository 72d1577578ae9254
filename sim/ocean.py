"""The simulated ocean: water temperature and salinity against depth and time, and the
sea floor under it.

Two kinds of water column share one interface (`temperature_c(depth_m, time_s)` and
`salinity_psu(depth_m, time_s)`, each on floats or numpy arrays):

- `Thermocline`: warm surface water over cold deep water with a tanh-shaped
  thermocline whose centre rides up and down on internal waves;
- `MeasuredProfile`: measured casts (a CSV file, or Slocum science logs replayed by
  `sim.slocum_ocean`), interpolated linearly in depth and in time.

Presets: `bench` (the paper's Fig. 5 bench case: 24 C over 7 C, one internal wave),
`sea-trial` (its Atlantic deployment: thermocline at 10-18 m) and `uniform`.

The sea floor (`SeaFloor`, by `load_water`): none by default (the altimeter reads NaN, as
out of range, and nothing stops a dive), a flat one at `sim --floor DEPTH_M`, or under
replayed Slocum logs the floor the glider saw (`sim.slocum_ocean`): a profile along
time, met at the times the glider met it, as the casts are.

Notes
-----
Thermocline: T(z, t) = T_deep + (T_surf - T_deep) (1 - tanh((z - zc(t)) / h)) / 2 with
h = thickness / 4, so that 96 % of the change happens across `thickness_m`, and
zc(t) = depth_m + sum_k a_k sin(2 pi t / P_k + phase_k).
"""

from __future__ import annotations

import bisect
import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract.errors import GliderplanError, UsageError
from gliderplan.contract.files import read_input_text
from gliderplan.power_models.flight import DensityProfile

if TYPE_CHECKING:
    from gliderplan.sim.bathymetry import Bathymetry

Number = float | np.ndarray


class OceanFileError(GliderplanError, ValueError):
    """A bad ocean profile file; the message starts with `FILE:LINE:`."""


@dataclass(frozen=True)
class InternalWave:
    amplitude_m: float  # vertical displacement of the thermocline
    period_s: float
    phase_rad: float = 0.0


@dataclass(frozen=True)
class Thermocline:
    """A two-layer water column with a thermocline. Depths [m] positive down, temperatures
    [degC], salinities [PSU]; `waves` move the thermocline's centre with time."""

    surface_c: float
    deep_c: float
    depth_m: float  # centre of the thermocline
    thickness_m: float
    waves: tuple[InternalWave, ...] = ()
    surface_psu: float = 35.0
    deep_psu: float = 35.0

    def thermocline_depth_m(self, time_s: Number) -> Number:
        """Depth [m] of the thermocline's centre at `time_s` [s]."""
        xp = np if isinstance(time_s, np.ndarray) else math
        depth = self.depth_m
        for wave in self.waves:
            depth = depth + wave.amplitude_m * xp.sin(
                2.0 * math.pi * time_s / wave.period_s + wave.phase_rad)
        return depth

    def _warm_fraction(self, depth_m: Number, time_s: Number) -> Number:
        """1 in the surface layer, 0 in the deep layer, tanh-shaped between."""
        array = isinstance(depth_m, np.ndarray) or isinstance(time_s, np.ndarray)
        xp = np if array else math
        half_width = max(self.thickness_m, 1e-6) / 4.0
        centre = self.thermocline_depth_m(np.asarray(time_s, float) if array else time_s)
        return 0.5 * (1.0 - xp.tanh((depth_m - centre) / half_width))

    def temperature_c(self, depth_m: Number, time_s: Number = 0.0) -> Number:
        """Water temperature [degC] at `depth_m` [m] and `time_s` [s]."""
        return self.deep_c + (self.surface_c - self.deep_c) * self._warm_fraction(depth_m, time_s)

    def salinity_psu(self, depth_m: Number, time_s: Number = 0.0) -> Number:
        """Practical salinity [PSU] at `depth_m` [m] and `time_s` [s]."""
        return self.deep_psu + (self.surface_psu - self.deep_psu) * self._warm_fraction(
            depth_m, time_s)

    def water_at(self, depth_m: float, time_s: float) -> tuple[float, float]:
        """(temperature [degC], salinity [PSU]) at one depth [m] and time [s]: the model
        above on plain floats in the simulator's order of operations (sim/flight.c's)."""
        centre = self.depth_m
        for wave in self.waves:
            centre = centre + wave.amplitude_m * math.sin(
                2.0 * math.pi * time_s / wave.period_s + wave.phase_rad)
        warm = 0.5 * (1.0 - math.tanh((depth_m - centre) / (max(self.thickness_m, 1e-6) / 4.0)))
        return (self.deep_c + (self.surface_c - self.deep_c) * warm,
                self.deep_psu + (self.surface_psu - self.deep_psu) * warm)


@dataclass(frozen=True)
class MeasuredProfile:
    """Casts of (depth, temperature, salinity), interpolated linearly in depth and time,
    held constant beyond the shallowest and deepest samples and the first and last cast."""

    depths_m: tuple[float, ...]  # strictly increasing
    casts_s: tuple[float, ...]  # cast times [s], strictly increasing (one cast: static)
    temperatures_c: tuple[tuple[float, ...], ...]  # [cast][depth]
    salinities_psu: tuple[tuple[float, ...], ...]
    start_epoch_s: float | None = None  # UTC time of cast time 0 [s since 1970], if known

    def temperature_c(self, depth_m: Number, time_s: Number = 0.0) -> Number:
        return self._interpolate(self.temperatures_c, depth_m, time_s)

    def salinity_psu(self, depth_m: Number, time_s: Number = 0.0) -> Number:
        return self._interpolate(self.salinities_psu, depth_m, time_s)

    def water_at(self, depth_m: float, time_s: float) -> tuple[float, float]:
        """(temperature [degC], salinity [PSU]) at one depth [m] and time [s]."""
        return (self._interpolate(self.temperatures_c, depth_m, time_s),
                self._interpolate(self.salinities_psu, depth_m, time_s))

    def _interpolate(self, table: tuple[tuple[float, ...], ...], depth_m: Number,
                     time_s: Number) -> Number:
        if isinstance(depth_m, np.ndarray) or isinstance(time_s, np.ndarray):
            depth, time = np.broadcast_arrays(np.asarray(depth_m, float),
                                              np.asarray(time_s, float))
            shape, depth, time = depth.shape, depth.ravel(), time.ravel()
            casts = np.array([np.interp(depth, self.depths_m, row) for row in table])
            if len(self.casts_s) == 1:
                return casts[0].reshape(shape)
            k = np.clip(np.searchsorted(self.casts_s, time) - 1, 0, len(self.casts_s) - 2)
            t0, t1 = np.asarray(self.casts_s)[k], np.asarray(self.casts_s)[k + 1]
            w = np.clip((time - t0) / (t1 - t0), 0.0, 1.0)
            index = np.arange(depth.size)
            return (casts[k, index] * (1.0 - w) + casts[k + 1, index] * w).reshape(shape)
        # one reading per tick: plain floats are ~10x faster than numpy scalars
        if len(self.casts_s) == 1:
            return _interp_scalar(self.depths_m, table[0], depth_m)
        k = min(max(bisect.bisect_left(self.casts_s, time_s) - 1, 0), len(self.casts_s) - 2)
        t0, t1 = self.casts_s[k], self.casts_s[k + 1]
        w = min(max((time_s - t0) / (t1 - t0), 0.0), 1.0)
        a = _interp_scalar(self.depths_m, table[k], depth_m)
        b = _interp_scalar(self.depths_m, table[k + 1], depth_m)
        return a * (1.0 - w) + b * w


def _interp_scalar(xs: tuple[float, ...], ys: tuple[float, ...], x: float) -> float:
    """np.interp for one float."""
    i = bisect.bisect_right(xs, x)
    if i == 0:
        return ys[0]
    if i == len(xs):
        return ys[-1]
    x0, x1 = xs[i - 1], xs[i]
    return ys[i - 1] + (ys[i] - ys[i - 1]) * (x - x0) / (x1 - x0)


def _interp_exact(xs: tuple[float, ...], ys: tuple[float, ...], x: np.ndarray) -> np.ndarray:
    """`_interp_scalar` at each element of `x`, bit for bit."""
    xa, ya = np.asarray(xs), np.asarray(ys)
    i = np.searchsorted(xa, x, side="right")
    inner = np.clip(i, 1, len(xa) - 1)
    x0, x1, y0, y1 = xa[inner - 1], xa[inner], ya[inner - 1], ya[inner]
    with np.errstate(all="ignore"):  # one depth only: no inner interval
        between = y0 + (y1 - y0) * (x - x0) / (x1 - x0)
    return np.where(i == 0, ya[0], np.where(i == len(xa), ya[-1], between))


Ocean = Thermocline | MeasuredProfile


# ---- presets -----------------------------------------------------------------------

def bench() -> Thermocline:
    """The paper's Fig. 5 bench case: 24 C surface, 7 C deep, one internal wave
    (thermocline depth and wave assumed: 11 m +- 3 m over 20 min)."""
    return Thermocline(24.0, 7.0, depth_m=11.0, thickness_m=4.0,
                       waves=(InternalWave(3.0, 1200.0),), surface_psu=31.5, deep_psu=32.5)


def sea_trial() -> Thermocline:
    """The paper's Atlantic deployment (Fig. 6a): thermocline at 10-18 m off New Jersey
    (temperatures assumed from a typical summer profile there: 22 C over 10 C)."""
    return Thermocline(22.0, 10.0, depth_m=14.0, thickness_m=8.0,
                       waves=(InternalWave(1.0, 1800.0),), surface_psu=31.0, deep_psu=32.5)


def uniform(temperature_c: float = 15.0, salinity_psu: float = 35.0) -> Thermocline:
    """A mixed water column: the same water at every depth."""
    return Thermocline(temperature_c, temperature_c, 0.0, 1.0, (), salinity_psu, salinity_psu)


def read_profile_csv(path: str | Path) -> MeasuredProfile:
    """A profile file: header `depth_m,temperature_c[,salinity_psu][,time_s]`, one sample
    a row; rows of one cast share `time_s`. Errors name the file and line."""
    path = Path(path)
    text = read_input_text(path, "depth profile")
    rows = list(csv.reader(text.splitlines()))
    if not rows:
        raise OceanFileError(f"{path}:1: empty ocean file; expected the header "
                             "depth_m,temperature_c[,salinity_psu][,time_s]")
    header = [h.strip() for h in rows[0]]
    allowed = ("depth_m", "temperature_c", "salinity_psu", "time_s")
    if header[:2] != ["depth_m", "temperature_c"] or any(h not in allowed for h in header) \
            or len(set(header)) != len(header):
        raise OceanFileError(f"{path}:1: header {','.join(header)!r}: expected "
                             "depth_m,temperature_c[,salinity_psu][,time_s]")
    casts: dict[float, list[tuple[float, float, float]]] = {}
    for line_no, row in enumerate(rows[1:], start=2):
        if not row or all(not cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise OceanFileError(f"{path}:{line_no}: expected {len(header)} fields, "
                                 f"got {len(row)}")
        try:
            values = dict(zip(header, (float(cell) for cell in row), strict=True))
        except ValueError:
            raise OceanFileError(f"{path}:{line_no}: not a number in {','.join(row)!r}") from None
        if not all(math.isfinite(v) for v in values.values()):
            raise OceanFileError(f"{path}:{line_no}: values must be finite")
        if values["depth_m"] < 0.0:
            raise OceanFileError(f"{path}:{line_no}: depth_m must be >= 0 (positive down)")
        if not -5.0 <= values["temperature_c"] <= 50.0:
            raise OceanFileError(f"{path}:{line_no}: temperature_c "
                                 f"{values['temperature_c']:g} is not sea water (-5..50 C)")
        cast = casts.setdefault(values.get("time_s", 0.0), [])
        if cast and values["depth_m"] <= cast[-1][0]:
            raise OceanFileError(f"{path}:{line_no}: depths of a cast must increase")
        cast.append((values["depth_m"], values["temperature_c"],
                     values.get("salinity_psu", 35.0)))
    if not casts:
        raise OceanFileError(f"{path}:2: no samples")
    depths = sorted({d for cast in casts.values() for d, _, _ in cast})
    times = sorted(casts)
    temperatures, salinities = [], []
    for t in times:
        cast_depths = [d for d, _, _ in casts[t]]
        temperatures.append(tuple(np.interp(depths, cast_depths, [c[1] for c in casts[t]])))
        salinities.append(tuple(np.interp(depths, cast_depths, [c[2] for c in casts[t]])))
    return MeasuredProfile(tuple(depths), tuple(times), tuple(map(_floats, temperatures)),
                           tuple(map(_floats, salinities)))


def _floats(values: tuple) -> tuple[float, ...]:
    return tuple(float(v) for v in values)


PRESETS = ("bench", "sea-trial", "uniform")
WATER_DEPTHS_M = np.arange(0.0, 1001.0, 5.0)  # where a given ocean's density is taken [m]


def load_ocean(spec: str) -> Ocean:
    """A preset name, a CSV profile file, or Slocum science logs (a *.ebd file or a
    directory of them) replayed by `sim.slocum_ocean`."""
    match spec:
        case "bench":
            return bench()
        case "sea-trial":
            return sea_trial()
        case "uniform":
            return uniform()
    path = Path(spec)
    if path.is_dir() or path.suffix.lower() == ".ebd":
        from gliderplan.sim.slocum_ocean import read_logged_ocean

        return read_logged_ocean(path).profile
    if not path.exists():
        raise OceanFileError(f"{spec}: no such ocean file or preset "
                             f"(presets: {', '.join(PRESETS)}; or Slocum logs: FILE.ebd|DIR)",
                             usage=True)
    return read_profile_csv(path)


@dataclass(frozen=True)
class SeaFloor:
    """The sea floor's depth [m] against the run's time [s]: linear between the samples,
    held beyond the first and the last (one sample: a flat floor). `source` says where it
    comes from."""

    times_s: tuple[float, ...]  # strictly increasing
    depths_m: tuple[float, ...]  # each > 0
    source: str

    def depth_at(self, time_s: float) -> float:
        """Depth [m] of the floor under the glider at `time_s` [s]."""
        return _interp_scalar(self.times_s, self.depths_m, time_s)

    def depth_along(self, time_s: np.ndarray) -> np.ndarray:
        """`depth_at` at each time of an array [s], bit for bit."""
        return _interp_exact(self.times_s, self.depths_m, np.asarray(time_s, float))

    @property
    def median_m(self) -> float:
        """[m] the median of its samples: the depth of water a forecast plans for."""
        return float(np.median(self.depths_m))

    def describe(self) -> str:
        low, high = min(self.depths_m), max(self.depths_m)
        depth = f"{low:.1f} m" if low == high else \
            f"{low:.1f}-{high:.1f} m along time (median {self.median_m:.1f} m)"
        return f"sea floor at {depth}: {self.source}"


def flat_floor(depth_m: float, option: str = "--floor") -> SeaFloor:
    """A flat sea floor at `depth_m` [m]; UsageError (naming `option`) unless it is a
    finite depth below the surface."""
    if not (isinstance(depth_m, int | float) and math.isfinite(depth_m) and depth_m > 0.0):
        raise UsageError(f"{option} {depth_m!r}: the sea floor's depth must be a finite number "
                         "of metres, above 0")
    return SeaFloor((0.0,), (float(depth_m),), f"{option} {depth_m:g}")


def parse_floor(text: str, option: str = "--floor") -> SeaFloor | Bathymetry:
    """`flat_floor` of a command line's text, or the bathymetry grid of a NetCDF file
    (*.nc: sim.bathymetry); UsageError naming `option` for one that is neither."""
    if text.lower().endswith(".nc"):
        from gliderplan.sim.bathymetry import read_bathymetry

        return read_bathymetry(text)
    try:
        depth = float(text)
    except ValueError:
        raise UsageError(f"{option} {text!r}: expected the sea floor's depth in metres, "
                         "e.g. 40") from None
    return flat_floor(depth, option)


@dataclass(frozen=True)
class Water:
    """What a run flies through: the water column, the sea floor under it (None: none)
    and what the floor is or why there is none (for the run's summary and a forecast's
    assumptions)."""

    ocean: Ocean
    floor: SeaFloor | Bathymetry | None
    floor_note: str


NO_FLOOR_NOTE = ("no sea floor: the altimeter reads NaN (out of range) and no dive is "
                 "stopped (sim --floor DEPTH_M sets one)")


def load_water(spec: str, floor: SeaFloor | Bathymetry | None = None) -> Water:
    """The ocean of `spec` (`load_ocean`) and its sea floor: `floor` if given, else for
    replayed Slocum logs the floor their flight logs saw (none, and the note says why,
    where they hold no floor reading), else none."""
    path = Path(spec)
    if spec not in PRESETS and (path.is_dir() or path.suffix.lower() == ".ebd"):
        from gliderplan.sim.slocum_ocean import read_logged_ocean

        logged = read_logged_ocean(path)
        if floor is not None:
            return Water(logged.profile, floor, floor.describe())
        return Water(logged.profile, logged.floor,
                     logged.floor.describe() if logged.floor is not None else
                     f"{spec}: {logged.floor_note}; " + NO_FLOOR_NOTE)
    return Water(load_ocean(spec), floor, NO_FLOOR_NOTE if floor is None else floor.describe())


def density_profile_of(ocean: Ocean, depths_m: np.ndarray = WATER_DEPTHS_M,
                       latitude_deg: float = 45.0) -> DensityProfile:
    """The in-situ density [kg m-3] of `ocean` at `depths_m` [m] (TEOS-10), averaged over
    its casts or waves (a forecast flies through it for days): the water the flight
    model flies in."""
    import gsw

    times = np.asarray(getattr(ocean, "casts_s", None) or np.linspace(0.0, 86400.0, 25))
    depth, time = (a.ravel() for a in np.meshgrid(np.asarray(depths_m, float), times))
    shape = (times.size, np.size(depths_m))
    temp = np.asarray(ocean.temperature_c(depth, time), float).reshape(shape)
    salinity = np.asarray(ocean.salinity_psu(depth, time), float).reshape(shape)
    depth = depth.reshape(shape)
    pressure = gsw.p_from_z(-depth, latitude_deg)
    absolute = gsw.SA_from_SP(salinity, pressure, 0.0, latitude_deg)
    rho = gsw.rho(absolute, gsw.CT_from_t(absolute, temp, pressure), pressure)
    return DensityProfile(np.asarray(depths_m, float), rho.mean(axis=0))
