"""Figures learned at sea: the energy model updated from what each surfacing measured.

The energy a glider draws over an interval between surfacings is, to the model, a sum of
parts, one per figure group g (the base load, the pump, the pitch motor, the surface, the
Iridium calls, the computer, each sensor device), each the model's own energy of that
part for what was flown (the device's measured on-time at its figure, the plan's rate of
each state for the time spent there) times a multiplier theta_g, 1 when the model is right:

    E_interval = sum_g theta_g q_g + noise,   theta ~ N(mu, Sigma)

A coulomb-counter reading gives E_interval; the update of (mu, Sigma) is the Kalman
filter's (a Bayesian update of a linear-Gaussian model, one scalar observation):

    S = q' Sigma q + R,   K = Sigma q / S,   mu += K (E - q' mu),   Sigma -= K q' Sigma

with R the interval's noise: the counter's (read out every 256 s) and what the figures do
not explain (the ocean moves the pump's work between intervals), MODEL_NOISE of the
interval's energy. The prior is the vehicle file's: each figure's sd (a calibrated file's
bootstrap), else the scenario file's relative spread, else (an instrument) a quarter of
its published span, as calibration keeps a device it cannot tell apart; the base load
is the hotel load less the instruments it holds, so its multiplier is correlated (negatively)
with theirs.

The battery's usable share (of its rating) is not in the counter: it is read from the
battery's voltage through a discharge curve (`DischargeCurve`, an assumption: linear from
its nominal voltage at full to 70 % of it when the usable energy is spent): the slope of
the readings against the energy drawn says how much the pack holds, combined with the
prior once the readings span enough of it to tell; the prior is a Student-t's, whose
weight fades where the readings contradict it by far (a pack far off its rating).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from gliderplan.contract import VEHICLE_COMPONENTS, Component
from gliderplan.power_models.devices import base_power_w, held_power_w
from gliderplan.power_models.vehicle import Vehicle, device_key, figure_value

DEFAULT_RELATIVE_SD = 0.10  # a figure no file gives a spread for (assumption)
DEFAULT_DEVICE_RELATIVE_SD = 0.10  # a device with no preset and no stated spread (assumption)
COMPUTER_RELATIVE_SD = 0.02  # a board's measured active and idle power (assumption)
MODEL_NOISE = 0.02  # [1] of an interval's energy, what the figures do not explain (assumption)
COUNTER_NOISE_J = 2000.0  # [J] the counter read out every 256 s: ~5 W x 256 s at each end / 2
CURVE_SLOPE_ERROR = 0.01  # [1] of the curve's slope, what its shape may be off by (assumption)
USABLE_PRIOR_DOF = 4.0  # degrees of freedom of the usable share's Student-t prior (assumption)
COMPONENT_GROUPS = (*VEHICLE_COMPONENTS, Component.COMPUTER)


@dataclass(frozen=True)
class DischargeCurve:
    """The battery's voltage against its depth of discharge (the share of its usable energy
    drawn): linear from `full_v` to `empty_v` (an assumption of this module: an alkaline
    Slocum pack runs from ~15 V to ~10.5 V), read to `noise_v`."""

    full_v: float
    empty_v: float
    noise_v: float = 0.02  # a surfacing's mean of the battery's readings

    @classmethod
    def nominal(cls, volts: float) -> DischargeCurve:
        return cls(volts, 0.7 * volts)

    def voltage(self, depth: float) -> float:
        """[V] at depth of discharge `depth` [1]."""
        return self.full_v - (self.full_v - self.empty_v) * depth



@dataclass(frozen=True)
class FigureMove:
    """How far a figure group moved from its prior: multipliers, and the figure itself
    where it has a unit (a power [W])."""

    name: str
    prior: float
    posterior: float
    sd: float  # of the posterior multiplier
    nominal_w: float | None  # the model's figure [W] the multiplier multiplies, if a power

    @property
    def change(self) -> float:
        """[1] relative to the prior."""
        return self.posterior / self.prior - 1.0

    def __str__(self) -> str:
        figure = "" if self.nominal_w is None else \
            f" ({self.nominal_w * self.prior:.3g} -> {self.nominal_w * self.posterior:.3g} W)"
        return f"{self.name} {100 * self.change:+.1f} %{figure}, sd {100 * self.sd:.1f} %"


@dataclass(frozen=True)
class Belief:
    """What is known of the figures: multipliers' mean and covariance, the battery's
    usable share, and how many intervals taught it."""

    names: tuple[str, ...]  # figure groups: COMPONENT_GROUPS, then the devices
    mean: np.ndarray  # (G,) multipliers [1]
    cov: np.ndarray  # (G, G)
    nominal_w: tuple[float | None, ...]  # the figure each multiplies [W], None: an energy
    usable_mean: float  # [1] of the battery's rating
    usable_sd: float
    usable_prior: tuple[float, float]
    intervals: int = 0
    sources: tuple[str, ...] = ()  # where each prior spread comes from
    readings: tuple[tuple[float, float], ...] = ()  # (drawn of the budget [1], voltage [V])

    @property
    def sd(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.cov), 0.0, None))

    def observe(self, expected_j: dict[str, float], measured_j: float) -> Belief:
        """The belief after an interval whose model energy by group is `expected_j` [J]
        (each at multiplier 1) and whose counter measured `measured_j` [J]."""
        q = np.array([expected_j.get(n, 0.0) for n in self.names])
        noise = (MODEL_NOISE * q.sum()) ** 2 + COUNTER_NOISE_J**2
        spread = self.cov @ q
        gain = spread / (q @ spread + noise)
        mean = self.mean + gain * (measured_j - q @ self.mean)
        cov = self.cov - np.outer(gain, spread)
        return replace(self, mean=mean, cov=0.5 * (cov + cov.T), intervals=self.intervals + 1)

    def observe_battery(self, used_j: float, voltage_v: float | None, budget_j: float,
                        curve: DischargeCurve) -> Belief:
        """The usable share after one more voltage reading, `used_j` [J] drawn of a budget
        of `budget_j` [J] at the rating: the slope of the voltage against the energy drawn,
        over every reading so far (its intercept, the full pack's voltage, left free: it
        moves with the water's temperature), against the curve's, combined with the
        prior. Until the readings span enough of the pack to tell, the prior alone."""
        readings = self.readings if voltage_v is None else \
            (*self.readings, (used_j / budget_j, voltage_v))
        mean, sd = self.usable_prior
        state = replace(self, readings=readings, usable_mean=mean, usable_sd=sd)
        if len(readings) < 3 or sd <= 0.0:
            return state
        depth = np.array([r[0] for r in readings])  # drawn, of the budget at its rating
        volts = np.array([r[1] for r in readings])
        spread = float(np.sum((depth - depth.mean()) ** 2))
        if spread <= 0.0:
            return state
        slope = -float(np.sum((depth - depth.mean()) * (volts - volts.mean()))) / spread
        slope_sd = math.hypot(curve.noise_v / math.sqrt(spread), CURVE_SLOPE_ERROR * slope)
        if slope <= 3.0 * slope_sd:  # too little drawn for the curve to tell anything
            return state
        seen = (curve.full_v - curve.empty_v) / slope  # the share at which the pack is spent
        seen_sd = seen * slope_sd / slope
        # a Student-t prior (USABLE_PRIOR_DOF): where the readings contradict the prior by
        # far, the prior's weight fades (a pack can be far off what it is rated, or drawn to
        # hold); near it, it is the normal prior's
        posterior, weight = mean, 1.0
        for _ in range(20):
            conflict = ((posterior - mean) / sd) ** 2
            weight = (USABLE_PRIOR_DOF + 1.0) / (USABLE_PRIOR_DOF + conflict)
            precision = weight / sd**2 + seen_sd**-2
            posterior = (weight * mean / sd**2 + seen / seen_sd**2) / precision
        return replace(state, usable_mean=posterior, usable_sd=precision**-0.5)

    def moves(self) -> list[FigureMove]:
        """Every figure group's move from its prior (multiplier 1)."""
        return [FigureMove(n, 1.0, float(m), float(s), w)
                for n, m, s, w in zip(self.names, self.mean, self.sd, self.nominal_w,
                                      strict=True)]


def _relative_sd(vehicle: Vehicle, key: str, spreads: dict[str, float]) -> tuple[float, str]:
    """(sd / value, where it comes from) of a vehicle figure."""
    u = vehicle.uncertainty
    value = abs(figure_value(vehicle, key)) if _has(vehicle, key) else 0.0
    if u is not None and key in u.keys and value > 0.0:
        return float(u.sd[u.keys.index(key)]) / value, "vehicle file"
    if key in spreads:
        return spreads[key], "scenario file"
    return math.nan, ""


def _has(vehicle: Vehicle, key: str) -> bool:
    try:
        figure_value(vehicle, key)
    except KeyError:
        return False
    return True


def _published_spread(device: str) -> tuple[float, str]:
    """(sd / figure, where it comes from) of an instrument the vehicle file has no figure
    for: its preset's published figure, sd a quarter of the published span, as calibration
    keeps a device the log cannot tell apart (power_models/device_fit.py)."""
    from gliderplan.power_models.catalog import preset_names
    from gliderplan.power_models.device_fit import _published

    if device not in preset_names("sensor"):
        return DEFAULT_DEVICE_RELATIVE_SD, "assumed"
    figure, sd, _ = _published(device)
    return (sd / figure if figure > 0 else DEFAULT_DEVICE_RELATIVE_SD), "published span"


def prior_belief(vehicle: Vehicle, devices: dict[str, float], usable: tuple[float, float],
                 spreads: dict[str, float] | None = None) -> Belief:
    """The belief before any interval: `devices` maps each device the mission runs to its
    model power [W]; `usable` is the prior (mean, sd) of the battery's usable share;
    `spreads` a scenario file's relative sd of figures the vehicle file gives none for."""
    spreads = spreads or {}

    def combined(*keys: str, default: float) -> tuple[float, str]:
        found = [_relative_sd(vehicle, k, spreads) for k in keys]
        known = [(s, w) for s, w in found if math.isfinite(s)]
        if not known:
            return default, "assumed"
        return math.sqrt(sum(s**2 for s, _ in known)), known[0][1]

    names = [*COMPONENT_GROUPS, *devices]
    rel, sources = {}, {}
    rel["pump"], sources["pump"] = combined("pump_out_energy_per_volume",
                                            default=DEFAULT_RELATIVE_SD)
    rel["pitch"], sources["pitch"] = combined("pitch_energy", default=DEFAULT_RELATIVE_SD)
    rel["surface"], sources["surface"] = combined("surface_power", "surface_time",
                                                  default=DEFAULT_RELATIVE_SD)
    rel["iridium"], sources["iridium"] = combined("iridium_power", "iridium_time",
                                                  default=DEFAULT_RELATIVE_SD)
    # a propeller's or a thruster's motor: no figure of the vehicle file to take it from
    rel["propulsion"], sources["propulsion"] = DEFAULT_RELATIVE_SD, "assumed"
    rel["computer"], sources["computer"] = COMPUTER_RELATIVE_SD, "assumed"
    for device in devices:
        rel[device], sources[device] = combined(device_key(device), default=math.nan)
        if not math.isfinite(rel[device]):
            rel[device], sources[device] = _published_spread(device)
    base = base_power_w(vehicle)
    hotel_rel, sources["hotel"] = combined("hotel_power", default=DEFAULT_RELATIVE_SD)
    held = held_power_w(vehicle)
    variance = (hotel_rel * vehicle.hotel_w) ** 2 + sum(
        (rel.get(d, DEFAULT_DEVICE_RELATIVE_SD) * w) ** 2 for d, w in held.items())
    rel["hotel"] = math.sqrt(variance) / base if base > 0 else DEFAULT_RELATIVE_SD
    sd = np.array([rel[n] for n in names])
    cov = np.diag(sd**2)
    for device, watts in held.items():  # base = hotel - held: a held device drawn high,
        if device in devices and base > 0:  # the base is low by as much
            i, j = names.index("hotel"), names.index(device)
            cov[i, j] = cov[j, i] = -(rel[device] * watts) ** 2 / (base * watts)
    nominal = tuple([*(base if n == "hotel" else None for n in COMPONENT_GROUPS),
                     *devices.values()])
    return Belief(tuple(names), np.ones(len(names)), cov, nominal, usable[0], usable[1],
                  usable, 0, tuple(f"{n}: {sources[n]}" for n in names))
