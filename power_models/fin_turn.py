"""The turn rate a held fin gives a Slocum glider, fitted from its flight logs: the
vehicle file's `fin_turn_rate` [1/s], turn rate [rad/s] per radian of fin, which
`import-slocum` turns a fin hold (set_heading's use_heading 4) into a `turn` route with.

The rate of m_heading between successive samples underwater (deeper than `MIN_DEPTH_M`:
at the surface waves swing the heading) against m_fin half-way between them, a least-
squares line through the origin (no fin, no turn)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.power_models.slocum_log import LogError, default_cache_dir, expand_log_paths

MIN_DEPTH_M = 5.0  # [m] shallower, waves turn the glider
SAMPLE_GAP_S = (0.5, 20.0)  # [s] a heading rate from samples closer or further is noise


@dataclass(frozen=True)
class FinTurnFit:
    rate_per_s: float  # [rad/s per rad of fin] positive: a positive fin turns clockwise
    samples: int  # heading rates fitted
    correlation: float  # of the heading rate with the fin


def fit_fin_turn_rate(paths: list[str]) -> FinTurnFit:
    """Fit the turn rate per radian of fin from Slocum logs (files or directories)."""
    import dbdreader  # heavy, and only needed here

    files = expand_log_paths(paths)
    try:
        logs = dbdreader.MultiDBD(filenames=files, cacheDir=default_cache_dir(files))
        (t, heading), fin, depth = (logs.get(name) for name in ("m_heading", "m_fin",
                                                                  "m_depth"))
    except (dbdreader.DbdError, OSError, ValueError) as err:
        raise LogError(f"cannot read m_heading, m_fin and m_depth from the logs: "
                       f"{' '.join(str(err).split())}") from None
    gap = np.diff(t)
    mid = t[:-1] + gap / 2.0
    rate = np.angle(np.exp(1j * np.diff(heading))) / np.where(gap > 0, gap, np.nan)
    fin_rad = np.interp(mid, *fin)
    kept = (gap > SAMPLE_GAP_S[0]) & (gap < SAMPLE_GAP_S[1]) & (
        np.interp(mid, *depth) > MIN_DEPTH_M) & np.isfinite(fin_rad)
    x, y = fin_rad[kept], rate[kept]
    if x.size < 10 or not np.any(x):
        raise LogError("the logs hold too few underwater heading samples with the fin "
                       "moved to fit its turn rate (need at least 10)")
    return FinTurnFit(float(x @ y / (x @ x)), int(x.size), float(np.corrcoef(x, y)[0, 1]))
