"""Fitting a vehicle's energy figures to a real flight log, and checking them on held-out data.

The fit uses the current sensor (I x V, integrated per sample interval) phase by phase:

- hotel, surface and Iridium power: energy over time of each phase;
- pump energy per inflection: each pump run's energy above the hotel load, regressed on
  the pumped volume V and V x depth for pump-out (E = a V + b V z) and on V for pump-in;
  `b` is only fitted when the pump-out depths span at least MIN_DEPTH_SPREAD_M, otherwise
  it is kept from the base vehicle (a log at one depth cannot separate a from b);
- pitch energy: battery moves outside pump runs, spread over the inflections.

Validation predicts the energy of another part of the record from its own depth, pump
and phase timeline and compares it with the coulomb counter (m_coulomb_amphr_total x
m_battery), which the fit never sees.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gliderplan.power_models import segments as seg
from gliderplan.power_models.slocum_log import FlightLog, LogError
from gliderplan.power_models.timeline import Timeline, energy_by_component_j
from gliderplan.power_models.vehicle import Vehicle

MIN_DEPTH_SPREAD_M = 10.0
MIN_PHASE_S = 30.0  # less time than this in a phase is too little to fit its power
# what a phase's fitted power holds: the current sensor measures the whole glider
PHASE_HOLDS = {
    seg.GLIDE: "the whole glider gliding, outside pump runs and battery moves (the flight "
               "computer and every sensor that logged then)",
    seg.SURFACE: "the whole glider at the surface outside its Iridium calls (the air pump "
                 "and the GPS included)",
    seg.IRIDIUM: "the whole glider while an Iridium call is up",
}


@dataclass(frozen=True)
class Coefficient:
    """One fitted (or kept) figure with the evidence behind it."""

    key: str  # key in the vehicle data file
    value: float
    unit: str
    fitted: bool  # False: too little data, kept from the base vehicle
    basis: str  # what it was fitted from, or why it was kept


@dataclass(frozen=True)
class EnergyFit:
    vehicle: Vehicle
    coefficients: tuple[Coefficient, ...]
    pump_rms_j: float  # RMS error of the pump model over the pump runs
    pump_events: int


def _phase_power(energy: np.ndarray, dt: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """(mean power [W], time [s]) of the intervals in `mask`."""
    time = float(dt[mask].sum())
    return (float(energy[mask].sum()) / time if time > 0 else float("nan")), time


def _event_excess_j(
    energy: np.ndarray, dt: np.ndarray, start: int, stop: int, hotel_w: float
) -> float:
    return float(energy[start : stop - 1].sum() - hotel_w * dt[start : stop - 1].sum())


def fit_energy(log: FlightLog, base: Vehicle) -> EnergyFit:
    """Fit the vehicle's energy figures to `log`; what the log cannot support stays as in `base`."""
    parts = seg.segment(log)
    energy = seg.interval_energy_j(log)
    dt = np.diff(log.t_s)
    coeffs: list[Coefficient] = []

    def phase_coefficient(key: str, phase: int, kept: float) -> float:
        power, time = _phase_power(energy, dt, parts.phase == phase)
        name = seg.PHASE_NAMES[phase]
        if time >= MIN_PHASE_S:
            coeffs.append(Coefficient(key, power, "W", True,
                                      f"{time:.0f} s of {name}: {PHASE_HOLDS[phase]}"))
            return power
        coeffs.append(Coefficient(key, kept, "W", False, f"only {time:.0f} s of {name}"))
        return kept

    hotel = phase_coefficient("hotel_power", seg.GLIDE, base.hotel_w)
    surface = phase_coefficient("surface_power", seg.SURFACE, base.surface_w)
    iridium = phase_coefficient("iridium_power", seg.IRIDIUM, base.iridium_w)

    outward = [e for e in parts.pump_events if e.outward]
    inward = [e for e in parts.pump_events if not e.outward]
    excess_out = np.array([_event_excess_j(energy, dt, e.start, e.stop, hotel) for e in outward])
    volume_out = np.array([e.volume_cc for e in outward])
    depth_out = np.array([e.depth_m for e in outward])
    a_out, b_out = base.pump_out_j_per_cc, base.pump_out_j_per_cc_m
    if outward and np.ptp(depth_out) >= MIN_DEPTH_SPREAD_M and len(outward) >= 3:
        design = np.column_stack([volume_out, volume_out * depth_out])
        (a_out, b_out), *_ = np.linalg.lstsq(design, excess_out, rcond=None)
        basis = f"{len(outward)} pump-out runs at {depth_out.min():.0f}-{depth_out.max():.0f} m"
        coeffs.append(Coefficient("pump_out_energy_per_volume", a_out, "J/cc", True, basis))
        coeffs.append(
            Coefficient("pump_out_energy_per_volume_depth", b_out, "J/(cc m)", True, basis)
        )
    elif outward:
        a_out = float(np.sum(excess_out - b_out * volume_out * depth_out) / volume_out.sum())
        span = f"{depth_out.min():.1f}-{depth_out.max():.1f} m"
        coeffs.append(
            Coefficient(
                "pump_out_energy_per_volume",
                a_out,
                "J/cc",
                True,
                f"{len(outward)} pump-out runs at {span}, depth term from the base",
            )
        )
        coeffs.append(
            Coefficient(
                "pump_out_energy_per_volume_depth",
                b_out,
                "J/(cc m)",
                False,
                f"pump-out depths span only {span}",
            )
        )
    else:
        for key, value, unit in (
            ("pump_out_energy_per_volume", a_out, "J/cc"),
            ("pump_out_energy_per_volume_depth", b_out, "J/(cc m)"),
        ):
            coeffs.append(Coefficient(key, value, unit, False, "no pump-out runs"))

    a_in, b_in = base.pump_in_j_per_cc, base.pump_in_j_per_cc_m
    if inward:
        excess_in = np.array([_event_excess_j(energy, dt, e.start, e.stop, hotel)
                              for e in inward])
        volume_in = np.array([e.volume_cc for e in inward])
        depth_in = np.array([e.depth_m for e in inward])
        a_in = max(float(np.sum(excess_in - b_in * volume_in * depth_in) / volume_in.sum()), 0.0)
        span = f"{depth_in.min():.1f}-{depth_in.max():.1f} m"
        coeffs.append(
            Coefficient(
                "pump_in_energy_per_volume", a_in, "J/cc", True,
                f"{len(inward)} pump-in runs at {span}, depth term from the base",
            )
        )
        coeffs.append(
            Coefficient("pump_in_energy_per_volume_depth", b_in, "J/(cc m)", False,
                        f"pump-in depths span only {span}")
        )
    else:
        for key, value, unit in (
            ("pump_in_energy_per_volume", a_in, "J/cc"),
            ("pump_in_energy_per_volume_depth", b_in, "J/(cc m)"),
        ):
            coeffs.append(Coefficient(key, value, unit, False, "no pump-in runs"))

    pitch = base.pitch_energy_j
    inflections = len(parts.pump_events)
    if inflections:
        moves = sum(
            max(_event_excess_j(energy, dt, s, e, hotel), 0.0) for s, e in parts.pitch_events
        )
        pitch = moves / inflections
        coeffs.append(
            Coefficient(
                "pitch_energy",
                pitch,
                "J",
                True,
                f"{len(parts.pitch_events)} battery move(s) outside pump runs "
                f"over {inflections} inflections",
            )
        )
    else:
        coeffs.append(Coefficient("pitch_energy", pitch, "J", False, "no inflections"))

    vehicle = replace(
        base,
        hotel_w=hotel,
        surface_w=surface,
        iridium_w=iridium,
        pump_out_j_per_cc=float(a_out),
        pump_out_j_per_cc_m=float(b_out),
        pump_in_j_per_cc=float(a_in),
        pitch_energy_j=float(pitch),
    )
    predicted = [_pump_model_j(vehicle, e) for e in parts.pump_events]  # per run, for the RMS
    measured = [_event_excess_j(energy, dt, e.start, e.stop, hotel) for e in parts.pump_events]
    rms = (
        float(np.sqrt(np.mean(np.subtract(predicted, measured) ** 2))) if measured else float("nan")
    )
    return EnergyFit(vehicle, tuple(coeffs), rms, len(parts.pump_events))


def _pump_model_j(vehicle: Vehicle, event: seg.PumpEvent) -> float:
    if event.outward:
        return float(vehicle.pump_energy_j(event.depth_m, event.volume_cc))
    return float(vehicle.pump_in_energy_j(event.depth_m, event.volume_cc))


def log_timeline(log: FlightLog) -> Timeline:
    """The log as a timeline of its sample intervals: phases, and each pump run's volume
    at its depth in the run's first interval, which is also when the battery shifts."""
    parts = seg.segment(log)
    steps = parts.phase.size
    depth = 0.5 * (log.depth_m[1:] + log.depth_m[:-1])
    pumped_out, pumped_in = np.zeros(steps), np.zeros(steps)
    inflection = np.zeros(steps, bool)
    for event in parts.pump_events:
        depth[event.start] = event.depth_m
        (pumped_out if event.outward else pumped_in)[event.start] = event.volume_cc
        inflection[event.start] = True
    return Timeline(np.diff(log.t_s), parts.phase, depth, pumped_out, pumped_in, inflection)


def predict_energy_j(log: FlightLog, vehicle: Vehicle) -> dict[str, float]:
    """Energy [J] per component the vehicle model predicts for the log's own timeline."""
    parts = energy_by_component_j(log_timeline(log), vehicle)
    return {name: float(energy.sum()) for name, energy in parts.items()}


def _phase_kinds(log: FlightLog) -> set[str]:
    parts = seg.segment(log)
    dt = np.diff(log.t_s)
    kinds = {
        seg.PHASE_NAMES[c]
        for c in (seg.GLIDE, seg.SURFACE, seg.IRIDIUM)
        if dt[parts.phase == c].sum() >= MIN_PHASE_S
    }
    kinds |= {"pump_out" if e.outward else "pump_in" for e in parts.pump_events}
    return kinds


@dataclass(frozen=True)
class Split:
    fit: FlightLog
    validate: FlightLog
    description: str


def split_record(log: FlightLog) -> Split:
    """Cut the record at the inflection nearest its middle; fit on the part that shows
    every kind of activity the other part has (so no validated figure goes unfitted),
    the later part if both do."""
    events = seg.segment(log).pump_events
    if len(events) < 2:
        raise LogError("cannot validate: the record needs at least two inflections to split "
                       "it for validation")
    middle = log.t_s[-1] / 2.0
    cut = min((e.start for e in events[1:]), key=lambda i: abs(log.t_s[i] - middle))
    early, late = log.slice(0, cut + 1), log.slice(cut, log.t_s.size)
    early_kinds, late_kinds = _phase_kinds(early), _phase_kinds(late)
    at = f"{log.t_s[cut]:.0f} s"
    if late_kinds >= early_kinds or not early_kinds >= late_kinds:
        return Split(late, early, f"fit on {at}-end, validate on 0-{at}")
    return Split(early, late, f"fit on 0-{at}, validate on {at}-end")


@dataclass(frozen=True)
class Validation:
    split: str
    parts: Split
    fit: EnergyFit
    predicted_j: dict[str, float]
    measured_j: float  # coulomb counter over the validation part
    duration_s: float

    @property
    def relative_error(self) -> float:
        """(predicted - measured) / measured [1], signed."""
        return (sum(self.predicted_j.values()) - self.measured_j) / self.measured_j


def validate(log: FlightLog, base: Vehicle) -> Validation:
    """Fit on one part of the record, predict the other, compare with its coulomb counter."""
    split = split_record(log)
    fit = fit_energy(split.fit, base)
    return Validation(
        split=split.description,
        parts=split,
        fit=fit,
        predicted_j=predict_energy_j(split.validate, fit.vehicle),
        measured_j=seg.counter_energy_j(split.validate),
        duration_s=float(split.validate.t_s[-1] - split.validate.t_s[0]),
    )
