"""The surfacings of a log: how long a surfacing lasts, what it draws, and how sure the log
makes us of it.

A surfacing is a stay at the surface (its surface and Iridium phases) that holds an
Iridium call and does not start the record. Each gives its time at the surface outside
its calls (the GPS fix before the first, the wait after the last before the glider dives:
a whole stay is both), its calls' total time, and the energy and time of its surface and
Iridium phases. A stay the record cuts short shows neither its whole call nor what
follows it: its times are lower bounds, used only when no whole stay is in the record.

The bootstrap over dives cannot spread these figures: a dive holds a whole surfacing or
none. With MIN_RESAMPLED surfacings or more they are resampled on their own, which gives
the surfacing figures' standard deviations and correlation (taken independent of the
dive figures). With fewer there is nothing to resample, yet a surfacing seen once is no
exact figure: each gets an assumed spread (ASSUMED_RELATIVE_SD), and its source says so.
A call the record cuts short makes the call time a lower bound (`at_least`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.power_models import segments as seg
from gliderplan.power_models.fit_figure import Figure
from gliderplan.power_models.slocum_log import FlightLog

SURFACING_KEYS = ("surface_power", "iridium_power", "surface_time", "iridium_time")
MIN_RESAMPLED = 2
MIN_CORRELATED = 5  # stays a correlation between the surfacing figures is taken from
RESAMPLES = 400
SEED = 2014
# one standard deviation as a fraction of the value, for a log with too few surfacings to
# resample (an assumption, written to the file as one): the powers as the planner's
# sensitivity moves a figure without a stated uncertainty (planner.sensitivity's 20 %); the
# durations as the shipped scenario file spreads the call time (sim/data/
# scenarios_default.toml, 30 %: the GPS fix, the Iridium link and what is sent)
ASSUMED_RELATIVE_SD = {"surface_power": 0.2, "iridium_power": 0.2, "surface_time": 0.3,
                       "iridium_time": 0.3}


@dataclass(frozen=True)
class Surfacing:
    """One surfacing's times [s] and energies [J]."""

    before_call_s: float  # at the surface before the first Iridium call
    outside_calls_s: float  # at the surface outside its calls: before, between and after
    calls_s: float  # the calls' total time
    surface_j: float  # energy and time of its surface phase (outside the calls)
    surface_s: float
    iridium_j: float  # energy and time of its calls
    iridium_s: float


@dataclass(frozen=True)
class Surfacings:
    found: tuple[Surfacing, ...]
    cut_short: bool  # the record ends during the last one: its calls were longer


@dataclass(frozen=True)
class Spread:
    """The surfacing figures' uncertainty: sd [model unit] and correlation of `keys`, what
    each sd rests on, and the figures that are lower bounds."""

    keys: tuple[str, ...]
    sd: np.ndarray
    correlation: np.ndarray
    basis: dict[str, str]  # key -> what its sd rests on
    source: str  # the whole, for the file's [uncertainty] source
    at_least: tuple[str, ...]


def find_surfacings(log: FlightLog, parts: seg.Segmentation) -> Surfacings:
    """Every surfacing of `log` that holds an Iridium call and does not start the record."""
    at_surface = np.isin(parts.phase, (seg.SURFACE, seg.IRIDIUM))
    edges = np.diff(np.concatenate(([0], at_surface.astype(np.int8), [0])))
    dt = np.diff(log.t_s)
    energy = seg.interval_energy_j(log)
    found, cut = [], False
    for start, stop in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True):
        phase = parts.phase[start:stop]
        calling = phase == seg.IRIDIUM
        if start == 0 or not calling.any():
            continue
        first_call = start + int(np.argmax(calling))
        surface = phase == seg.SURFACE
        found.append(Surfacing(
            before_call_s=float(dt[start:first_call].sum()),
            outside_calls_s=float(dt[start:stop][~calling].sum()),
            calls_s=float(dt[start:stop][calling].sum()),
            surface_j=float(energy[start:stop][surface].sum()),
            surface_s=float(dt[start:stop][surface].sum()),
            iridium_j=float(energy[start:stop][calling].sum()),
            iridium_s=float(dt[start:stop][calling].sum()),
        ))
        cut = cut or bool(stop == parts.phase.size)
    return Surfacings(tuple(found), cut)


def _whole(surfacings: Surfacings) -> tuple[Surfacing, ...]:
    """The stays the record holds whole; all of them (the one cut short too) when none is."""
    whole = surfacings.found[:-1] if surfacings.cut_short else surfacings.found
    return whole or surfacings.found


def surfacing_figures(surfacings: Surfacings) -> list[Figure]:
    """`surface_time` and `iridium_time` [s]: the means over the whole stays (a stay the
    record cuts short where it holds no other: then lower bounds)."""
    found = surfacings.found
    if not found:
        return [Figure(k, 0.0, False, "no surfacing with an Iridium call")
                for k in ("surface_time", "iridium_time")]
    whole = _whole(surfacings)
    short = len(whole) == len(found) and surfacings.cut_short
    cut = "; the record ends during it: at least this long" if short else ""
    left_out = "" if len(whole) == len(found) else \
        " (the last, which the record cuts short, left out)"
    return [
        Figure("surface_time", float(np.mean([_outside(s, short) for s in whole])), True,
               f"{len(whole)} surfacing(s){left_out}: time at the surface outside the Iridium "
               f"calls (the GPS fix before, the wait after){cut}", at_least=short),
        Figure("iridium_time", float(np.mean([s.calls_s for s in whole])), True,
               f"{len(whole)} surfacing(s){left_out}: Iridium call time{cut}", at_least=short),
    ]


def _outside(surfacing: Surfacing, cut_short: bool) -> float:
    """[s] a stay's time outside its calls; for one cut short in its call, what came
    before it (what would follow is not in the record)."""
    return surfacing.before_call_s if cut_short else surfacing.outside_calls_s


def _statistics(picked: list[Surfacing]) -> dict[str, float]:
    """The surfacing figures of a resample [model units]: powers as energy over time."""
    def ratio(energy: float, time: float) -> float:
        return energy / time if time > 0.0 else float("nan")

    return {
        "surface_power": ratio(sum(s.surface_j for s in picked),
                               sum(s.surface_s for s in picked)),
        "iridium_power": ratio(sum(s.iridium_j for s in picked),
                               sum(s.iridium_s for s in picked)),
        "surface_time": float(np.mean([s.outside_calls_s for s in picked])),
        "iridium_time": float(np.mean([s.calls_s for s in picked])),
    }


def surfacing_spread(surfacings: Surfacings, figures: list[Figure]) -> Spread:
    """The uncertainty of the fitted surfacing figures among `figures`: a bootstrap over
    the surfacings when there are MIN_RESAMPLED or more, else the assumed spread."""
    fitted = {f.key: f for f in figures if f.fitted and f.key in SURFACING_KEYS}
    keys = tuple(k for k in SURFACING_KEYS if k in fitted)
    found = _whole(surfacings)
    at_least = tuple(k for k in keys if fitted[k].at_least)
    sd = np.zeros(len(keys))
    correlation = np.eye(len(keys))
    if len(found) >= MIN_RESAMPLED and keys:
        rng = np.random.default_rng(SEED)
        samples = np.array([[_statistics([found[i] for i in picks])[k] for k in keys]
                            for picks in rng.integers(0, len(found), (RESAMPLES, len(found)))])
        samples = samples[np.all(np.isfinite(samples), axis=1)]
        sd = samples.std(axis=0, ddof=1)
        spread = sd > 1e-9 * np.abs(samples.mean(axis=0))  # above rounding: they differ
        # a correlation needs more stays than a few (of two, any pair is +-1)
        if spread.sum() >= 2 and len(found) >= MIN_CORRELATED:
            block = np.atleast_2d(np.corrcoef(samples[:, spread], rowvar=False))
            correlation[np.ix_(spread, spread)] = block
        measured = f"bootstrap over {len(found)} surfacings, {len(samples)} resamples" + (
            "" if len(found) >= MIN_CORRELATED else ", taken as independent")
    else:
        spread = np.zeros(len(keys), bool)
        measured = ""
    basis = {}
    for j, key in enumerate(keys):
        # a few stays cannot show how much stays differ: no less than the assumed scatter
        # of one stay over the stays seen (the sd of their mean)
        floor = ASSUMED_RELATIVE_SD[key] * abs(fitted[key].value) / np.sqrt(max(len(found), 1))
        if spread[j] and sd[j] < floor:
            sd[j] = floor
            basis[key] = (f"sd: {measured}, raised to the assumed scatter of a stay "
                          f"({100 * ASSUMED_RELATIVE_SD[key]:.0f} %) over {len(found)} stays")
        elif spread[j]:
            basis[key] = f"sd: {measured}"
        else:  # too few surfacings, or all alike: no spread the log can show
            share = ASSUMED_RELATIVE_SD[key]
            sd[j] = share * abs(fitted[key].value)
            basis[key] = (f"sd: assumption, {100 * share:.0f} % of the value ({len(found)} "
                          "surfacing(s) show no spread between surfacings)")
    keep = sd > 0.0
    keys = tuple(k for k, kept in zip(keys, keep, strict=True) if kept)
    how = measured or "assumed (the figures' sources say why)"
    source = f"surfacing figures: {how}, independent of the dive figures"
    return Spread(keys, sd[keep], correlation[np.ix_(keep, keep)],
                  {k: basis[k] for k in keys}, source, tuple(k for k in at_least if k in keys))
