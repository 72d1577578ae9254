"""A log as a sequence of whole dives, and what the pilot commanded for them.

A dive runs from the start of the pump-in at the top of a yo (the top turn) to the start
of the next one: the descent, the pump-out at the bottom (the bottom turn) and the climb.
The first dive starts with the record; the last one ends with it, and holds the climb to
the surface and the time there. Calibration resamples whole dives for its bootstrap, and
validation fits on the earlier dives and forecasts the later ones.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gliderplan.power_models import segments as seg
from gliderplan.power_models.slocum_log import FlightLog


@dataclass(frozen=True)
class Dive:
    """Samples [start, stop] of a log (the boundary sample is shared with the next dive)."""

    start: int
    stop: int
    top_turn: seg.PumpEvent | None  # None for the record's first dive when it starts mid-dive
    bottom_turn: seg.PumpEvent | None  # None if the record ends before it


def split_dives(log: FlightLog, parts: seg.Segmentation | None = None) -> list[Dive]:
    """The log's whole dives, in time order."""
    parts = parts or seg.segment(log)
    tops = [e for e in parts.pump_events if not e.outward]
    bottoms = [e for e in parts.pump_events if e.outward]
    starts = [e.start for e in tops]
    if not starts or any(b.start < starts[0] for b in bottoms):
        starts.insert(0, 0)  # the record begins in the middle of a dive
    else:
        starts[0] = 0  # the record begins before its first top turn (at the surface)
    stops = starts[1:] + [log.t_s.size - 1]
    dives = []
    for start, stop in zip(starts, stops, strict=True):
        top = next((e for e in tops if start <= e.start < stop), None)
        bottom = next((e for e in bottoms if start <= e.start < stop), None)
        dives.append(Dive(start, stop, top, bottom))
    return dives


def concatenate(log: FlightLog, dives: list[Dive]) -> FlightLog:
    """One log of the given dives flown one after another (a dive may repeat: the bootstrap
    resamples dives with replacement). Times run on without gaps; the counter is rebuilt
    from each dive's own increments; what the log says once (targets, payload, the pump's
    limit) stays."""
    pieces = [log.slice(d.start, d.stop + 1) for d in dives]
    times, charge = [], []
    now, counted = 0.0, 0.0
    for piece in pieces:
        times.append(piece.t_s - piece.t_s[0] + now)
        charge.append(piece.charge_ah - piece.charge_ah[0] + counted)
        now = times[-1][-1] + float(np.median(np.diff(piece.t_s)))
        counted = charge[-1][-1]
    joined = {
        name: np.concatenate([getattr(p, name) for p in pieces])
        for name in FlightLog.SERIES
        if name not in ("t_s", "charge_ah")
    }
    return replace(log, t_s=np.concatenate(times), charge_ah=np.concatenate(charge),
                   device_on=np.concatenate([p.devices_on() for p in pieces]), **joined)
