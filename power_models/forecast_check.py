"""Forward validation: calibrate on a log's earlier whole dives, forecast the later ones from
what a pilot knows before flying them, and compare with the coulomb counter.

The forecast is given the later part's commanded yo band, pitch and pumped volume, its
surfacing schedule (the number of dives before each climb to the surface: a command of
the yo and surface behaviours; the stays at the surface between them are forecast with
the fit part's surfacing figures) and the ocean (the fit part's CTD). Durations, speeds, yo
periods, pumped volumes and energies of the later part are outputs, never inputs. The
bottom of the band is the dive target or, when the sea floor stopped the dives before
it, the depth the fit part's dives turned at (the floor less the altimeter's clearance).

The forecast ends where the later part's last dive does: the glider back at the
surface. What follows in the record (the GPS fix and Iridium calls) needs surfacing
figures the fit part cannot show when it holds no call; it is forecast with the base
vehicle's figures and reported apart, with those figures named and a 90 % interval from
the surfacing figures' sd (the base's, for those it gives).

Truth is the coulomb counter (m_coulomb_amphr_total x m_battery); the fit integrates the
current sensor (m_coulomb_current x m_battery), so the two are compared on the fit part
and the bias is stated with the counter's resolution.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.contract.units import C_PER_AH
from gliderplan.power_models import segments as seg
from gliderplan.power_models.dives import Dive, split_dives
from gliderplan.power_models.draws import (
    DEFAULT_DRAWS,
    DEFAULT_SEED,
    draw_vehicles,
    prediction_spread,
)
from gliderplan.power_models.flight import DensityProfile, glide_leg
from gliderplan.power_models.forecast import (
    INTERVAL_LEVEL,
    Forecast,
    YoCommand,
    energy_interval_j,
    forecast_cycles,
)
from gliderplan.power_models.slocum_log import FlightLog
from gliderplan.power_models.surfacing_fit import SURFACING_KEYS, find_surfacings
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.power_models.vehicle_fit import (
    BOOTSTRAP_RESAMPLES,
    CalibrationError,
    VehicleFit,
    commanded_volume_cc,
    fit_vehicle,
    log_ocean,
)

SPEED_BAND_MARGIN = 0.15  # vertical speeds are compared on the band less 15 % at each end
MIN_STAY_S = 60.0  # [s] at the surface between two dives: a surfacing, not a shallow turn
MIN_FIT_DIVES = 2


@dataclass(frozen=True)
class Observed:
    """What the later part did (measured), for the forecast's outputs."""

    time_s: float  # from the cut to the arrival at the surface
    energy_j: float  # coulomb counter over that span
    yo_period_s: float  # mean time between successive turns of a kind, the surface not between
    w_mps: dict[str, float]  # mean vertical speed of dives / climbs over the speed band
    yos: int


@dataclass(frozen=True)
class ForwardCheck:
    fit_dives: int
    later_dives: int
    cycles: tuple[int, ...]  # the later part's dives before each climb to the surface
    cut_s: float  # record time where the later part starts
    calibration: VehicleFit  # of the fit part
    command: YoCommand
    forecast: Forecast
    interval_j: tuple[float, float]
    observed: Observed
    speed_band_m: tuple[float, float]
    predicted_w_mps: dict[str, float]
    counter_bias: float  # counter / current-sensor energy - 1 over the fit part
    counter_step_j: float  # the counter's resolution over the fit part [J]
    from_base: tuple[str, ...]  # figures the forecast uses that the fit part did not give
    stay_predicted_j: float | None  # the record's remaining surface stay, base figures
    stay_measured_j: float | None
    stay_interval_j: tuple[float, float] | None  # its 90 % interval: the figures' own sd

    @property
    def energy_relative_error(self) -> float:
        return self.forecast.energy_j / self.observed.energy_j - 1.0


def _band(log: FlightLog, fit: list[Dive], later: list[Dive]) -> tuple[float, float]:
    """The commanded yo band of the later part: the climb target (else the depth the fit
    part turned at the top) and the dive target, or where the fit part's dives turned
    when the sea floor stopped them short of it."""
    tops = [log.depth_m[d.top_turn.moving] for d in fit if d.top_turn is not None
            and log.depth_m[d.top_turn.moving] >= seg.SURFACE_DEPTH_M]
    bottoms = [log.depth_m[d.bottom_turn.moving] for d in fit if d.bottom_turn is not None]
    if not bottoms:
        raise CalibrationError("the fit part holds no bottom turn")
    top = log.climb_target_m if np.isfinite(log.climb_target_m) else float(np.mean(tops))
    turned = float(np.mean(bottoms))
    target = log.dive_target_m if np.isfinite(log.dive_target_m) else turned
    return top, min(target, turned)


def _command(log: FlightLog, fit: list[Dive], later: list[Dive]) -> YoCommand:
    start, stop = later[0].start, later[-1].stop
    pitch = np.abs(log.commanded_pitch_rad[start:stop])
    pitch = pitch[np.isfinite(pitch)]
    if not pitch.size:
        raise CalibrationError("the later part holds no commanded pitch (c_pitch)")
    down = pitch[log.commanded_pitch_rad[start:stop][np.isfinite(
        log.commanded_pitch_rad[start:stop])] < 0]
    up = pitch[log.commanded_pitch_rad[start:stop][np.isfinite(
        log.commanded_pitch_rad[start:stop])] > 0]
    top, bottom = _band(log, fit, later)
    volume = commanded_volume_cc(log, start, later[-1].bottom_turn.start
                                 if later[-1].bottom_turn else stop)
    return YoCommand(top, bottom, float(np.median(down if down.size else pitch)),
                     float(np.median(up if up.size else pitch)), volume, len(later))


def _arrival(log: FlightLog, later: list[Dive]) -> int:
    """Sample where the last dive's climb reaches the surface."""
    last = later[-1]
    if last.bottom_turn is None:
        raise CalibrationError("the record ends before its last dive turns at the bottom")
    after = np.flatnonzero(log.depth_m[last.bottom_turn.stop:] < seg.SURFACE_DEPTH_M)
    if not after.size:
        raise CalibrationError("the record ends before the glider is back at the surface")
    return last.bottom_turn.stop + int(after[0])


def _observed(log: FlightLog, later: list[Dive], cut: int, arrival: int,
              band: tuple[float, float]) -> Observed:
    t, z = log.t_s, log.depth_m
    turns = {"top": [d.top_turn for d in later if d.top_turn is not None],
             "bottom": [d.bottom_turn for d in later if d.bottom_turn is not None]}
    # a period between two turns with a stay at the surface in between is no yo's
    periods = [t[b.moving] - t[a.moving] for events in turns.values()
               for a, b in zip(events[:-1], events[1:], strict=True)
               if not _stayed_at_surface(log, a.stop, b.moving)]
    speeds: dict[str, list[float]] = {"dive": [], "climb": []}
    for k, dive in enumerate(later):
        halves = [("dive", dive.top_turn, dive.bottom_turn)]
        if k + 1 < len(later):  # the last climb goes to the surface on more buoyancy
            halves.append(("climb", dive.bottom_turn, later[k + 1].top_turn))
        for kind, first, second in halves:
            if first is None or second is None:
                continue
            span = slice(first.stop, second.start)
            depth, time = z[span], t[span]
            if kind == "climb":
                depth, time = depth[::-1], time[::-1]
            if depth.size < 2 or depth.min() > band[0] or depth.max() < band[1]:
                continue
            crossing = np.interp(band, np.maximum.accumulate(depth), time)
            speeds[kind].append((band[1] - band[0]) / abs(crossing[1] - crossing[0]))
    segment = log.slice(cut, arrival + 1)
    return Observed(
        time_s=float(t[arrival] - t[cut]),
        energy_j=seg.counter_energy_j(segment),
        yo_period_s=float(np.mean(periods)) if periods else float("nan"),
        w_mps={k: float(np.mean(v)) if v else float("nan") for k, v in speeds.items()},
        yos=len(later),
    )


def _bias(log: FlightLog) -> tuple[float, float]:
    """(counter / current-sensor energy - 1, one counter step [J]) over `log`."""
    counter = seg.counter_energy_j(log)
    current = float(seg.interval_energy_j(log).sum())
    steps = np.diff(log.charge_ah)
    step_ah = float(np.min(steps[steps > 0])) if (steps > 0).any() else 0.0
    return counter / current - 1.0, step_ah * C_PER_AH * float(np.mean(log.battery_v))


FORECAST_KEYS = (
    "hotel_power", "pump_out_energy_per_volume", "pump_out_energy_per_volume_depth",
    "pump_in_energy_per_volume", "pump_in_energy_per_volume_depth", "pump_rate",
    "max_ballast", "pitch_energy", "top_turn_time", "bottom_turn_time", "dive_pitch_error",
    "climb_pitch_error", "flight.drag_cd0", "flight.trim_volume", "flight.compressibility",
    "flight.water_density", "flight.hull_volume", "flight.wing_area", "flight.lift_slope_wing",
    "flight.lift_slope_hull", "flight.drag_cd1",
)
STAY_KEYS = ("surface_power", "surface_time", "iridium_power", "iridium_time",
             "surfacing_energy")


@dataclass(frozen=True)
class LaterPart:
    """What a forward check asks: the record cut at a whole dive, the later dives'
    commands, and what the glider did flying them."""

    fit: list[Dive]
    later: list[Dive]
    cut: int  # first sample of the later part
    arrival: int  # sample where its last climb reaches the surface
    command: YoCommand
    observed: Observed
    cycles: tuple[int, ...]  # dives before each climb to the surface
    from_surface: bool  # the later part starts at the surface (not at the yo's top)

    def forecast(self, vehicle: Vehicle, ocean: DensityProfile | None) -> Forecast:
        """The later part forecast by `vehicle` through `ocean`."""
        return forecast_cycles(vehicle, self.command, self.cycles, ocean, self.from_surface)


def _stayed_at_surface(log: FlightLog, start: int, stop: int) -> bool:
    """Whether the glider stayed at the surface between samples `start` and `stop`: an
    Iridium call, or MIN_STAY_S above SURFACE_DEPTH_M (a yo turning near the surface
    touches it for a moment)."""
    span = slice(start, max(stop, start + 1))
    shallow = log.depth_m[span][:-1] < seg.SURFACE_DEPTH_M
    stay = float(np.sum(np.diff(log.t_s[span])[shallow[:len(log.t_s[span]) - 1]]))
    return bool(log.iridium_on[span].any()) or stay >= MIN_STAY_S


def _cycles(log: FlightLog, later: list[Dive]) -> tuple[int, ...]:
    """Dives before each climb to the surface: a dive is the last of its cycle when the
    glider stayed at the surface before the next one's top turn (the record's last one
    always)."""
    counts, dives = [], 0
    for dive, after in zip(later, later[1:] + [None], strict=True):
        dives += 1
        if after is None or dive.bottom_turn is None or after.top_turn is None:
            surfaced = after is None
        else:
            surfaced = _stayed_at_surface(log, dive.bottom_turn.stop, after.top_turn.moving)
        if surfaced:
            counts.append(dives)
            dives = 0
    return tuple(counts)


def later_part(log: FlightLog, fit_share: float = 0.5) -> LaterPart:
    """Cut the record after the first `fit_share` of its whole dives."""
    dives = split_dives(log)
    fit_count = max(MIN_FIT_DIVES, round(fit_share * len(dives)))
    if len(dives) - fit_count < 1:
        raise CalibrationError(
            f"the record holds {len(dives)} whole dives: too few to fit {MIN_FIT_DIVES} and "
            "forecast at least one")
    fit, later = dives[:fit_count], dives[fit_count:]
    command = _command(log, fit, later)
    cut, arrival = later[0].start, _arrival(log, later)
    observed = _observed(log, later, cut, arrival, _speed_band(command))
    top = later[0].top_turn
    from_surface = top is not None and log.depth_m[top.moving] < seg.SURFACE_DEPTH_M
    return LaterPart(fit, later, cut, arrival, command, observed, _cycles(log, later),
                     from_surface)


def predicted_w_mps(vehicle: Vehicle, command: YoCommand,
                    ocean: DensityProfile | None) -> dict[str, float]:
    """Mean vertical speed [m s-1] of a dive and a climb across the speed band."""
    band = _speed_band(command)
    pitch = vehicle.flown_pitch_rad(command.dive_pitch_rad, command.climb_pitch_rad)
    return {kind: float(glide_leg(vehicle.flight, *band, pitch[up], command.ballast_cc,
                                  bool(up), ocean).w_mps)
            for kind, up in (("dive", 0), ("climb", 1))}


def check_as_given(log: FlightLog, vehicle: Vehicle, fit_share: float = 0.5) -> dict[str, float]:
    """Relative errors (predicted / measured - 1) of `vehicle` as it is, fitted on nothing,
    forecasting the later part through the earlier part's water: `energy`, `yo_period`,
    `dive` and `climb` (vertical speeds). What a preset predicts for a glider it was not
    fitted on."""
    part = later_part(log, fit_share)
    ocean = log_ocean(log.slice(0, part.cut + 1))
    predicted = part.forecast(vehicle, ocean)
    w = predicted_w_mps(vehicle, part.command, ocean)
    o = part.observed
    return {"energy": predicted.energy_j / o.energy_j - 1.0,
            "yo_period": predicted.yo_period_s / o.yo_period_s - 1.0,
            **{kind: w[kind] / o.w_mps[kind] - 1.0 for kind in ("dive", "climb")}}


def check_forward(log: FlightLog, base: Vehicle, fit_share: float = 0.5,
                  resamples: int = BOOTSTRAP_RESAMPLES) -> ForwardCheck:
    """Fit the first `fit_share` of the record's whole dives, forecast the rest."""
    part = later_part(log, fit_share)
    command, cut, arrival = part.command, part.cut, part.arrival
    fit_log = log.slice(0, cut + 1)
    calibration = fit_vehicle(fit_log, base, resamples)
    vehicle = calibration.vehicle
    predicted = part.forecast(vehicle, calibration.ocean)
    bias, step = _bias(fit_log)
    rng = np.random.default_rng(DEFAULT_SEED)
    # the dives and the stays to come scatter about the fitted means: each figure's sd
    # widened for how many of its own kind the fit saw and the forecast flies
    dives = prediction_spread(len(part.fit), len(part.later))
    later_stays = len(part.cycles) - 1
    stays = prediction_spread(len(find_surfacings(fit_log, seg.segment(fit_log)).found),
                              later_stays) if later_stays else 1.0
    keys = () if vehicle.uncertainty is None else vehicle.uncertainty.keys
    drawn = draw_vehicles(vehicle, DEFAULT_DRAWS, rng,
                          {k: stays if k in SURFACING_KEYS else dives for k in keys})
    # the counter is read at both ends of the span: each reading is off by up to a step
    quantisation = step * (rng.random(len(drawn)) - rng.random(len(drawn)))
    interval = energy_interval_j(drawn, command, calibration.ocean, noise_j=quantisation,
                                 cycles=part.cycles, from_surface=part.from_surface)
    fitted = {f.key for f in calibration.figures if f.fitted}
    stay_pred = stay_meas = stay_interval = None
    if arrival < log.t_s.size - 1:
        stay = log.slice(arrival, log.t_s.size)
        span = float(stay.t_s[-1] - stay.t_s[0])
        stay_pred = _stay_energy_j(vehicle, span)
        stay_meas = seg.counter_energy_j(stay)
        # one stay: each surfacing figure drawn with its own sd (a surfacing's spread when
        # the log shows one surfacing, or an assumed one), not widened for dives to come
        energies = np.array([_stay_energy_j(v, span) for v in draw_vehicles(
            vehicle, DEFAULT_DRAWS, rng)]) + step * (rng.random(DEFAULT_DRAWS)
                                                     - rng.random(DEFAULT_DRAWS))
        tail = 50.0 * (1.0 - INTERVAL_LEVEL)
        low, high = np.percentile(energies, [tail, 100.0 - tail])
        stay_interval = (float(low), float(high))
    return ForwardCheck(
        fit_dives=len(part.fit), later_dives=len(part.later), cycles=part.cycles,
        cut_s=float(log.t_s[cut]),
        calibration=calibration, command=command, forecast=predicted, interval_j=interval,
        observed=part.observed, speed_band_m=_speed_band(command),
        predicted_w_mps=predicted_w_mps(vehicle, command, calibration.ocean),
        counter_bias=bias, counter_step_j=step,
        from_base=tuple(k for k in FORECAST_KEYS if k not in fitted),
        stay_predicted_j=stay_pred, stay_measured_j=stay_meas, stay_interval_j=stay_interval,
    )


def stay_from_base(check: ForwardCheck) -> tuple[str, ...]:
    fitted = {f.key for f in check.calibration.figures if f.fitted}
    return tuple(k for k in STAY_KEYS if k not in fitted)


def _stay_energy_j(vehicle: Vehicle, span_s: float) -> float:
    """Energy [J] of `span_s` at the surface: the GPS fix, the Iridium call, then waiting."""
    fix = min(span_s, vehicle.surface_s)
    call = min(span_s - fix, vehicle.iridium_s)
    wait = span_s - fix - call
    return (vehicle.surfacing_fixed_j + vehicle.surface_w * (fix + wait)
            + vehicle.iridium_w * call)


def _speed_band(command: YoCommand) -> tuple[float, float]:
    margin = SPEED_BAND_MARGIN * (command.bottom_m - command.top_m)
    return command.top_m + margin, command.bottom_m - margin
