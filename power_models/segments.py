"""Splitting a flight log into what the glider was doing: gliding, at the surface,
on an Iridium call, pumping (an inflection) or moving its battery (a pitch change).

Each sample interval [t_i, t_i+1] gets one phase. An actuator event covers the samples
its motion flag is set, plus the sample before and a tail after, because the flags are
sampled every few seconds and the motor current decays over the next samples.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.contract.units import C_PER_AH
from gliderplan.power_models.slocum_log import FlightLog

GLIDE, SURFACE, IRIDIUM, PUMP, PITCH = range(5)
PHASE_NAMES = ("glide", "surface", "iridium", "pump", "pitch")

SURFACE_DEPTH_M = 1.0  # shallower than this, outside an inflection, the glider is at the surface
EVENT_TAIL_S = 10.0  # motor current seen this long after a motion flag clears
MIN_PUMPED_CC = 20.0  # smaller volume changes are trim, not an inflection


@dataclass(frozen=True)
class PumpEvent:
    """One inflection's pump run: samples [start, stop) of the log."""

    start: int
    stop: int
    volume_cc: float  # magnitude pumped
    outward: bool  # True: pumped out (buoyancy up), against sea pressure
    depth_m: float  # mean depth while pumping
    moving: int  # first sample the pump is seen moving: where and when the turn begins


@dataclass(frozen=True)
class Segmentation:
    """Per-interval phases (len = samples - 1) and the actuator events."""

    phase: np.ndarray  # int8, one of GLIDE..PITCH for each interval
    pump_events: tuple[PumpEvent, ...]
    pitch_events: tuple[tuple[int, int], ...]  # battery moves outside pump events


def _runs(flag: np.ndarray) -> list[tuple[int, int]]:
    """[start, stop) index ranges where `flag` is True."""
    edges = np.diff(np.concatenate(([0], flag.astype(np.int8), [0])))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1), strict=True))


def _event_window(log: FlightLog, start: int, stop: int) -> tuple[int, int]:
    """Sample range of an actuator event: one sample before the flag, a tail after."""
    first = max(start - 1, 0)
    end_t = log.t_s[stop - 1] + EVENT_TAIL_S
    last = int(np.searchsorted(log.t_s, end_t, side="right"))
    return first, min(max(last, stop + 1), log.t_s.size)


def segment(log: FlightLog) -> Segmentation:
    """Assign a phase to every sample interval of `log` and find its pump and pitch events."""
    n = log.t_s.size
    phase = np.full(n - 1, GLIDE, np.int8)
    shallow = (log.depth_m[:-1] < SURFACE_DEPTH_M) & (log.depth_m[1:] < SURFACE_DEPTH_M)
    phase[shallow] = SURFACE
    phase[log.iridium_on[:-1]] = IRIDIUM

    pump_events = []
    in_event = np.zeros(n - 1, bool)
    for start, stop in _runs(log.pump_moving):
        first, last = _event_window(log, start, stop)
        change = log.ballast_cc[last - 1] - log.ballast_cc[first]
        if abs(change) < MIN_PUMPED_CC:
            continue
        pump_events.append(
            PumpEvent(
                first,
                last,
                abs(float(change)),
                change > 0.0,
                float(np.mean(log.depth_m[first:last])),
                int(start),
            )
        )
        in_event[first : last - 1] = True
    phase[in_event] = PUMP

    pitch_events = []
    for start, stop in _runs(log.battpos_moving):
        first, last = _event_window(log, start, stop)
        if in_event[first : last - 1].any():
            continue  # battery moved while pumping: its energy is in the pump event
        pitch_events.append((first, last))
        phase[first : last - 1] = PITCH
    return Segmentation(phase, tuple(pump_events), tuple(pitch_events))


def interval_energy_j(log: FlightLog) -> np.ndarray:
    """Energy [J] of each sample interval from the current sensor (trapezoid of I V)."""
    power = log.power_w()
    return 0.5 * (power[1:] + power[:-1]) * np.diff(log.t_s)


def counter_energy_j(log: FlightLog) -> float:
    """Energy [J] the coulomb counter records over the log: sum of dQ x V."""
    volts = 0.5 * (log.battery_v[1:] + log.battery_v[:-1])
    return float(np.sum(np.diff(log.charge_ah) * C_PER_AH * volts))
