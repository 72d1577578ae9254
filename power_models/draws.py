"""Drawing vehicles from a calibration's uncertainty, for forecast intervals and Monte Carlo.

A calibrated vehicle file gives each fitted figure a standard deviation and the figures'
correlation (from the bootstrap over dives). A draw is a multivariate normal sample of
those figures around their values, kept inside what a data file may hold (a power is
never negative, a drag coefficient is positive) and above a figure that is a lower bound
(`at_least`: a call the record cut short); the other figures stay as they are.
Draws come from a seeded generator, so a forecast's interval is reproducible.
"""

from __future__ import annotations

import numpy as np

from gliderplan.power_models.vehicle import FIGURES, Vehicle, figure_value, with_figures

DEFAULT_DRAWS = 400
DEFAULT_SEED = 11


def prediction_spread(fitted_dives: int, forecast_dives: float) -> float:
    """Factor on the calibration's standard deviations for a forecast of `forecast_dives`
    dives from `fitted_dives`: the bootstrap gives the uncertainty of the fitted means,
    sd ~ s / sqrt(n); the dives to come scatter about them too, s / sqrt(k), so a
    prediction interval is sqrt(1 + n / k) times wider than the fit's."""
    return float(np.sqrt(1.0 + fitted_dives / max(forecast_dives, 1e-9)))


def draw_figures(
    vehicle: Vehicle, n: int = DEFAULT_DRAWS, rng: np.random.Generator | None = None,
    spread: float = 1.0,
) -> tuple[tuple[str, ...], np.ndarray]:
    """(keys, (n, k) values [model units]) of the uncertain figures, drawn jointly, their
    standard deviations multiplied by `spread`."""
    u = vehicle.uncertainty
    if u is None:
        return (), np.zeros((n, 0))
    rng = rng or np.random.default_rng(DEFAULT_SEED)
    mean = np.array([figure_value(vehicle, k) for k in u.keys])
    # correlated standard normals, then scaled: the figures' units differ by 20 orders of
    # magnitude, too many for one covariance matrix; and a correlation written to 3
    # decimals may be a hair short of positive semi-definite
    eigenvalues, vectors = np.linalg.eigh(u.correlation)
    root = vectors * np.sqrt(np.clip(eigenvalues, 0.0, None))
    values = mean + (rng.standard_normal((n, len(mean))) @ root.T) * (u.sd * spread)
    for j, key in enumerate(u.keys):
        options = FIGURES[key][2]
        low = options.get("minimum", 0.0)
        if options.get("positive"):
            low = max(low, 1e-9 * abs(mean[j]) if mean[j] else 1e-12)
        if key in u.at_least:  # a lower bound: the truth is no less
            low = max(low, mean[j])
        values[:, j] = np.maximum(values[:, j], low)
    return u.keys, values


def draw_vehicles(
    vehicle: Vehicle, n: int = DEFAULT_DRAWS, rng: np.random.Generator | None = None,
    spread: float = 1.0,
) -> list[Vehicle]:
    """`n` vehicles with their uncertain figures drawn jointly (`draw_figures`); [vehicle]
    if it has none."""
    keys, values = draw_figures(vehicle, n, rng, spread)
    if not keys:
        return [vehicle]
    return [with_figures(vehicle, dict(zip(keys, row, strict=True))) for row in values]
