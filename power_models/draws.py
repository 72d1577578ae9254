"""Drawing vehicles from a calibration's uncertainty, for forecast intervals and Monte Carlo.

A calibrated vehicle file gives each fitted figure a standard deviation and the figures'
correlation (from the bootstrap over dives). A draw is a multivariate normal sample of
those figures around their values, kept inside what a data file may hold (a power is
never negative, a drag coefficient is positive) and above a figure that is a lower bound
(`at_least`: a call the record cut short); the other figures stay as they are. A draw in
which the instruments the hotel load holds draw more than the hotel load itself (their
published figures are wide, the load is measured) is drawn again: a base load is never
negative.
Draws come from a seeded generator, so a forecast's interval is reproducible.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from gliderplan.power_models.devices import held_power_w
from gliderplan.power_models.vehicle import (
    Vehicle,
    device_key,
    figure_spec,
    figure_value,
    with_figures,
)

DEFAULT_DRAWS = 400
DEFAULT_SEED = 11
MAX_REDRAWS = 50  # a row still unphysical after this many (vanishingly rare) bills a 0 W base


def prediction_spread(fitted_dives: int, forecast_dives: float) -> float:
    """Factor on the calibration's standard deviations for a forecast of `forecast_dives`
    dives from `fitted_dives`: the bootstrap gives the uncertainty of the fitted means,
    sd ~ s / sqrt(n); the dives to come scatter about them too, s / sqrt(k), so a
    prediction interval is sqrt(1 + n / k) times wider than the fit's."""
    return float(np.sqrt(1.0 + fitted_dives / max(forecast_dives, 1e-9)))


def draw_figures(
    vehicle: Vehicle, n: int = DEFAULT_DRAWS, rng: np.random.Generator | None = None,
    spread: float | Mapping[str, float] = 1.0,
) -> tuple[tuple[str, ...], np.ndarray]:
    """(keys, (n, k) values [model units]) of the uncertain figures, drawn jointly, their
    standard deviations multiplied by `spread` (one factor, or one per key, 1 for a key
    it does not name)."""
    u = vehicle.uncertainty
    if u is None:
        return (), np.zeros((n, 0))
    rng = rng or np.random.default_rng(DEFAULT_SEED)
    mean = np.array([figure_value(vehicle, k) for k in u.keys])
    # correlated standard normals, then scaled: the figures' units differ by 20 orders of
    # magnitude, too many for one covariance matrix
    root = correlation_root(u.correlation)
    low = np.zeros(len(mean))
    for j, key in enumerate(u.keys):
        options = figure_spec(key)[2]
        low[j] = options.get("minimum", 0.0)
        if options.get("positive"):
            low[j] = max(low[j], 1e-9 * abs(mean[j]) if mean[j] else 1e-12)
        if key in u.at_least:  # a lower bound: the truth is no less
            low[j] = max(low[j], mean[j])

    factor = np.array([spread.get(k, 1.0) for k in u.keys]) if isinstance(spread, Mapping) \
        else spread

    def draw(rows: int) -> np.ndarray:
        normal = mean + (rng.standard_normal((rows, len(mean))) @ root.T) * (u.sd * factor)
        return np.maximum(normal, low)

    values = draw(n)
    for _ in range(MAX_REDRAWS if held_power_w(vehicle) else 0):
        bad = np.flatnonzero(_base_w(vehicle, u.keys, values) < 0.0)
        if not bad.size:
            break
        values[bad] = draw(bad.size)
    return u.keys, values


def correlation_root(correlation: np.ndarray) -> np.ndarray:
    """R with R R^T = `correlation`, its negative eigenvalues taken as 0: a correlation
    written to 3 decimals may be a hair short of positive semi-definite, where a Cholesky
    factorisation fails."""
    eigenvalues, vectors = np.linalg.eigh(correlation)
    return vectors * np.sqrt(np.clip(eigenvalues, 0.0, None))


def _base_w(vehicle: Vehicle, keys: tuple[str, ...], values: np.ndarray) -> np.ndarray:
    """(n,) [W] the base load of each drawn row: its hotel load less the instruments the
    hotel holds (`devices.base_power_w` over rows of figures)."""
    def column(key: str) -> np.ndarray | float:
        return values[:, keys.index(key)] if key in keys else figure_value(vehicle, key)

    held = held_power_w(vehicle)
    return column("hotel_power") - sum(
        (column(device_key(d)) if vehicle.device(d) is not None else w)
        for d, w in held.items())


def draw_vehicles(
    vehicle: Vehicle, n: int = DEFAULT_DRAWS, rng: np.random.Generator | None = None,
    spread: float | Mapping[str, float] = 1.0,
) -> list[Vehicle]:
    """`n` vehicles with their uncertain figures drawn jointly (`draw_figures`); [vehicle]
    if it has none."""
    keys, values = draw_figures(vehicle, n, rng, spread)
    if not keys:
        return [vehicle]
    return [with_figures(vehicle, dict(zip(keys, row, strict=True))) for row in values]
