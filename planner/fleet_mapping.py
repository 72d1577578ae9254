"""The fleet's figure of merit: the mapping error of objective analysis.

A field (temperature in the sampled band, say) with zero mean and covariance

    C(dx, dy, dt) = s^2 exp(-(dx^2 + dy^2) / L^2 - dt^2 / T^2)

(Gaussian in space and time: Bretherton, Davis & Fandry 1976; the form used to score the
Monterey Bay glider arrays, Leonard et al. 2007) is estimated at a point e from samples
with noise n s^2 each. The estimate's error variance, as a share of s^2, is

    err(e) = 1 - c_e^T (C + n I)^-1 c_e,

c_e the (normalised) covariances between e and the samples, C those among the samples:
0 where the samples pin the field down, 1 where they say nothing of it. The mapping error
of a plan is err averaged over a grid of points covering the survey and a set of times
spanning its period. Samples are the glider's profiles thinned to one every L/4 along its
track (closer ones add little at scale L; the noise share n stands for what they would
average away and for the sensor's own error).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from gliderplan.language.fleet import FieldScales, Fleet

SAMPLES_PER_SCALE = 4  # thinned samples per length scale along a track
MAX_SAMPLES = 800  # at most about this many in the whole fleet: thinned further past it
GRID_POINTS = 400  # about this many points on the survey's plane
GRID_TIMES = 12  # evaluation times over the period
CHUNK = 4000  # evaluation points per block of the solve (bounds memory)


@dataclass(frozen=True)
class Grid:
    """Where and when the mapping error is averaged: points on the plane [m] at times [s
    after the fleet's start]; every (point, time) pair counts the same."""

    x: np.ndarray  # (n,)
    y: np.ndarray  # (n,)
    times: np.ndarray  # (m,)

    @property
    def size(self) -> int:
        return len(self.x) * len(self.times)


def sample_spacing(fleet: Fleet) -> float:
    """Distance [m] between the samples kept along a track: a quarter of the length scale,
    or more when the whole fleet would take more than MAX_SAMPLES (the solve grows with
    their cube); one figure per fleet, so that plans and flights are judged alike."""
    reach = sum(0.35 * (fleet.period_s - g.start_offset_s) for g in fleet.gliders)
    return max(fleet.field.length_m / SAMPLES_PER_SCALE, reach / MAX_SAMPLES)


def survey_region(fleet: Fleet):
    """The survey as a shapely area: its areas, and a band around its transects and
    routes (half a line spacing wide, else half a length scale), less the keep-outs."""
    from shapely.geometry import LineString
    from shapely.ops import unary_union

    from gliderplan.language.fleet_geometry import polygon

    half = 0.5 * (fleet.goal.spacing_m or fleet.field.length_m)
    shapes = [polygon(list(a)) for a in fleet.areas]
    shapes += [LineString([p.a, p.b]).buffer(half, cap_style="flat")
               for p in fleet.parts if p.kind != "area"]
    region = unary_union(shapes)
    if fleet.keepouts:
        region = region.difference(unary_union([polygon(list(k)) for k in fleet.keepouts]))
    return region


def evaluation_grid(fleet: Fleet, points: int = GRID_POINTS, times: int = GRID_TIMES) -> Grid:
    """About `points` points on a square grid inside the survey, at `times` times at the
    middle of equal slices of the period."""
    from shapely import contains_xy

    region = survey_region(fleet)
    step = math.sqrt(region.area / points)
    x0, y0, x1, y1 = region.bounds
    while True:
        gx, gy = np.meshgrid(np.arange(x0 + step / 2, x1, step), np.arange(y0 + step / 2, y1,
                                                                            step))
        inside = contains_xy(region, gx.ravel(), gy.ravel())
        if inside.sum() >= 0.5 * points or step < 1.0:
            break
        step /= 1.4  # a thin region: a finer grid until enough points fall inside
    t = (np.arange(times) + 0.5) * fleet.period_s / times
    return Grid(gx.ravel()[inside], gy.ravel()[inside], t)


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """Hold BLAS to one thread within: the mapping error's matrices are small (at most
    some MAX_SAMPLES samples), one thread solves them as fast, where threads that wait
    on each other for a busy core cost a fifth more CPU (bench/README.md, "Fleet")."""
    import scipy.linalg  # noqa: F401  (its own BLAS: loaded before the limit, to be held by it)
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1, user_api="blas"):
        yield


def _covariance(t1, x1, y1, t2, x2, y2, scales: FieldScales) -> np.ndarray:
    dx = x1[:, None] - x2[None, :]
    dy = y1[:, None] - y2[None, :]
    dt = t1[:, None] - t2[None, :]
    return np.exp(-(dx * dx + dy * dy) / scales.length_m ** 2 - dt * dt / scales.time_s ** 2)


def _whitener(t: np.ndarray, x: np.ndarray, y: np.ndarray, scales: FieldScales,
              noise: np.ndarray | float) -> np.ndarray:
    """L, the lower Cholesky factor of the samples' covariance C + n I."""
    from scipy.linalg import cholesky

    gram = _covariance(t, x, y, t, x, y, scales)
    gram[np.diag_indices_from(gram)] += noise
    return cholesky(gram, lower=True, check_finite=False)


def _unexplained(lower: np.ndarray, cross: np.ndarray) -> np.ndarray:
    """err = 1 - c^T (L L^T)^-1 c = 1 - |L^-1 c|^2 for each column c of `cross` (one
    triangular solve, not a Cholesky solve's two)."""
    from scipy.linalg import solve_triangular

    whitened = solve_triangular(lower, cross, lower=True, check_finite=False)
    return np.clip(1.0 - np.einsum("ij,ij->j", whitened, whitened), 0.0, 1.0)


def point_errors(samples: tuple[np.ndarray, np.ndarray, np.ndarray], at_t: np.ndarray,
                 at_x: np.ndarray, at_y: np.ndarray, scales: FieldScales,
                 noise: np.ndarray | float | None = None) -> np.ndarray:
    """err at each evaluation point (at_t [s], at_x, at_y [m]) from samples (t, x, y);
    `noise` per sample (default: the scales' share for every one)."""
    t, x, y = (np.asarray(a, float) for a in samples)
    if len(t) == 0:
        return np.ones(len(at_t))
    lower = _whitener(t, x, y, scales, scales.noise if noise is None else noise)
    errors = np.empty(len(at_t))
    for start in range(0, len(at_t), CHUNK):
        stop = start + CHUNK
        errors[start:stop] = _unexplained(lower, _covariance(
            t, x, y, at_t[start:stop], at_x[start:stop], at_y[start:stop], scales))
    return errors


def mapping_error(samples: tuple[np.ndarray, np.ndarray, np.ndarray], grid: Grid,
                  scales: FieldScales) -> tuple[float, np.ndarray]:
    """(mean err over the grid's points and times, err as (times, points)). The
    covariance is a product of space and time parts: the samples' covariance with the
    grid's points is computed once and scaled for each time (exp over samples x points,
    not samples x points x times)."""
    t, x, y = _relevant(samples, grid, scales)
    errors = np.ones((len(grid.times), len(grid.x)))
    if len(t):
        lower = _whitener(t, x, y, scales, scales.noise)
        dx = x[:, None] - grid.x[None, :]
        dy = y[:, None] - grid.y[None, :]
        space = np.exp(-(dx * dx + dy * dy) / scales.length_m ** 2)
        for m, at in enumerate(grid.times):
            errors[m] = _unexplained(lower, space * np.exp(-((t - at) / scales.time_s) ** 2
                                                           )[:, None])
    return float(errors.mean()), errors


def _relevant(samples, grid: Grid, scales: FieldScales):
    """The samples that can inform the grid at all: within four scales of it in space
    and time (beyond, the covariance is below e^-16)."""
    t, x, y = (np.asarray(a, float) for a in samples)
    near = ((t >= grid.times.min() - 4 * scales.time_s) & (t <= grid.times.max()
                                                            + 4 * scales.time_s)
            & (x >= grid.x.min() - 4 * scales.length_m) & (x <= grid.x.max()
                                                           + 4 * scales.length_m)
            & (y >= grid.y.min() - 4 * scales.length_m) & (y <= grid.y.max()
                                                           + 4 * scales.length_m))
    return t[near], x[near], y[near]


def combined(sample_sets: list[tuple[np.ndarray, np.ndarray, np.ndarray]]):
    """Several gliders' samples as one set."""
    if not sample_sets:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    return tuple(np.concatenate([s[i] for s in sample_sets]) for i in range(3))


# ---- the assignment's surrogate: error of a line revisited every pi ---------------------

def revisit_error(pass_s: np.ndarray, spacing_m: float, scales: FieldScales) -> np.ndarray:
    """Mean err around a line of a block swept back and forth, each line flown once every
    `pass_s` [s] (the sweep's pass time), its neighbours `spacing_m` [m] to either side
    flown as often (staggered, as a lawn-mower reaches them in turn): err averaged across
    the line's band (to half a spacing each side) and over a pass, in steady state.
    Computed with `point_errors` on five long lines; a pass longer than 6 time scales is
    no revisit at all (1)."""
    out = np.ones(len(np.atleast_1d(pass_s)))
    length = scales.length_m
    along = np.arange(-1.5 * length, 1.5 * length + 1e-6, length / 2.0)
    for n, period in enumerate(np.atleast_1d(pass_s).astype(float)):
        if period > 6.0 * scales.time_s:
            continue
        # visits closer than a quarter of the time scale say little more than one: merge
        # them (their noise shrinks with their number)
        step = max(period, 0.25 * scales.time_s)
        merged = step / period
        t_list, x_list, y_list = [], [], []
        for k, line in enumerate(range(-2, 3)):
            phase = (k / 5.0) * period
            visits = np.arange(phase - 2.0 * scales.time_s - period,
                               period + 2.0 * scales.time_s + step, step)
            for v in visits:
                t_list.append(np.full(len(along), v))
                x_list.append(along)
                y_list.append(np.full(len(along), line * spacing_m))
        samples = (np.concatenate(t_list), np.concatenate(x_list), np.concatenate(y_list))
        et, ex, ey = np.meshgrid(period * np.array([0.1, 0.3, 0.5, 0.7, 0.9]),
                                 np.array([-length / 6.0, length / 6.0]),
                                 spacing_m * np.array([0.0, 0.25, 0.5]), indexing="ij")
        out[n] = point_errors(samples, et.ravel(), ex.ravel(), ey.ravel(), scales,
                              scales.noise / merged).mean()
    return out


@dataclass(frozen=True)
class RevisitTable:
    """revisit_error on a log grid of pass times, interpolated in log time."""

    pass_s: np.ndarray
    error: np.ndarray

    def __call__(self, pass_s) -> np.ndarray:
        p = np.clip(np.asarray(pass_s, float), self.pass_s[0], None)
        out = np.interp(np.log(p), np.log(self.pass_s), self.error)
        return np.where(p > self.pass_s[-1], 1.0, out)


def revisit_table(fleet: Fleet) -> RevisitTable:
    scales = fleet.field
    spacing = fleet.goal.spacing_m or scales.length_m
    grid = np.geomspace(1800.0, 6.0 * scales.time_s, 12)
    return RevisitTable(grid, revisit_error(grid, spacing, scales))
