"""The planning problem as numbers: index sets, bounds and coefficients (pure numpy).

Decision variables, all per state s (flattened over states into vectors):
- d[p]: duty of each sensor marked `duty auto` (p = (s, sensor));
- D[q]: on-fraction of each sensor device (q = (s, device)); D >= d of every sensor
  it serves, because temp and conductivity share one CTD;
- f[r]: time share of each flight-profile alternative (r = (s, profile));
- g[m]: time share of each computer clock (m = (s, clock)).
Everything that depends on the time in each state lives in `coefficients`, so that the
cvxpy model takes it as parameter values and is built once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import NO_BOARD
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import ir
from gliderplan.language.registry import SENSOR_BY_NAME
from gliderplan.planner.hardware import Hardware
from gliderplan.planner.occupancy import Occupancy
from gliderplan.planner.rates import (
    ProfileRates,
    clock_columns,
    state_mode_powers,
    state_profiles,
    yo_band,
)
from gliderplan.power_models.board import Board
from gliderplan.power_models.devices import base_power_w, held_power_w

NO_BOARD_NOTE = (f"computer {NO_BOARD}: the glider's own computers run the mission (their "
                 "power is in the vehicle's base load); no extra board is charged")
SENSOR_PERIOD_S = 300.0  # on/off period of a duty-cycled sensor (long against its warm-up)
PROFILE_CYCLE_S = 1800.0  # period over which alternative profiles alternate (a few yos)


class PlanInputError(GliderplanError, ValueError):
    """Annotations that contradict each other (e.g. duty >= 0.6 and duty <= 0.5)."""


def duty_for_quality(alpha: float, quality: float) -> float:
    """Inverse of the utility log(1 + a d) / log(1 + a): the duty that gives `quality`."""
    return math.expm1(quality * math.log1p(alpha)) / alpha


@dataclass(frozen=True)
class Transit:
    """Transit legs, per metre of route (DESIGN.md section 5, the pace formulation):
    energy per metre = P p_total + e + c p^-2 with pace p = 1/u [s m-1], p_total = p +
    k p^-2 + tau the time per metre including pump runs and turns, and on-time per metre
    x <= p."""

    state: np.ndarray  # (n_t,) state index
    length_m: np.ndarray  # (n_t,) route length over the mission [m]
    load_w: np.ndarray  # (n_t,) hotel + computer [W], drawn the whole time
    pump_s: np.ndarray  # (n_t,) k: pump time per metre at 1 m/s [s m-1 (m/s)-2]
    pump_j: np.ndarray  # (n_t,) c: pump energy per metre at 1 m/s [J m-1 (m/s)-2]
    pitch_j_per_m: np.ndarray  # (n_t,) e [J m-1]
    turn_s_per_m: np.ndarray  # (n_t,) tau: turns beyond their pump runs [s m-1]
    inflections_per_m: np.ndarray  # (n_t,) [m-1]
    min_pace: np.ndarray  # (n_t,) 1 / fastest speed [s m-1]
    pitch_rad: np.ndarray  # (n_t,)
    min_depth_m: np.ndarray  # (n_t,) the leg's yo band
    max_depth_m: np.ndarray  # (n_t,)

    @property
    def size(self) -> int:
        return len(self.state)


def _transit_legs(mission: ir.CheckedMission, hardware: Hardware, occupancy: Occupancy,
                  notes: list[str]) -> Transit:
    rows = []
    vehicle = hardware.vehicle
    for name, length in occupancy.legs_m.items():
        state = mission.state(name)
        if name in occupancy.transit_speeds:
            notes.append(f"{name}: propelled transit leg of {length / 1000:.3g} km, timed at "
                         f"its speed ({occupancy.transit_speeds[name]:.3g} m/s)")
            continue
        if len(state.profiles) != 1 or state.profiles[0].kind not in ("yo", "thermotrackyo"):
            notes.append(f"{name}: a transit leg with alternative or non-gliding profiles; "
                         "planned at the nominal speed's time")
            continue
        rates = state_profiles(hardware, state, occupancy, notes)[0]
        args = tuple(ir.evaluate(a, {}, occupancy.variables[name])
                     for a in state.profiles[0].args)
        low, high = yo_band(state.profiles[0], args)
        pitch = rates.pitch_rad
        # billed per second of the leg: the base load and the computer (the instruments
        # are billed per metre, for their on-time)
        load = base_power_w(vehicle) + float(np.nanmin(state_mode_powers(hardware, state)))
        c0 = float(vehicle.transit_coefficient(low, high, pitch, 0.0))
        k = float(vehicle.transit_coefficient(low, high, pitch, 1.0)) - c0
        e = float(vehicle.pitch_j_per_m(low, high, pitch))
        rows.append((mission.state_index[name], length, load, k, c0, e,
                     float(vehicle.turn_s_per_m(low, high, pitch)),
                     e / vehicle.pitch_energy_j if vehicle.pitch_energy_j else 0.0,
                     1.0 / float(vehicle.max_speed_mps(pitch)), pitch, low, high))
        notes.append(f"{name}: transit leg of {length / 1000:.3g} km; its time follows "
                     "from the planned speed (later states keep their nominal-speed times)")
    cols = [np.array(c, float) for c in zip(*rows, strict=True)] if rows else \
        [np.zeros(0)] * 12
    return Transit(cols[0].astype(int), *cols[1:])


@dataclass(frozen=True)
class PlanInputs:
    mission: ir.CheckedMission
    hardware: Hardware
    occupancy: Occupancy
    states: tuple[str, ...]
    time_s: np.ndarray  # (n_s,) [s] fixed time in each state; 0 for transit legs
    # auto duties
    duty_state: np.ndarray  # (n_p,) state index
    duty_sensor: tuple[str, ...]
    duty_device: np.ndarray  # (n_p,) index into the device pairs
    alpha: np.ndarray  # (n_p,) utility curvature
    weight: np.ndarray  # (n_p,) quality weight of the sensor
    duty_lo: np.ndarray
    duty_hi: np.ndarray
    # fixed-duty sensors (always on or a fixed duty): (state index, sensor, duty, alpha, weight)
    fixed: tuple[tuple[int, str, float, float, float], ...]
    # sensor devices
    dev_state: np.ndarray  # (n_q,)
    dev_name: tuple[str, ...]
    dev_power_w: np.ndarray  # (n_q,) on-power [W]
    dev_lo: np.ndarray  # (n_q,) floor from fixed-duty sensors on the device
    dev_hi: np.ndarray  # (n_q,) 1 with an auto sensor, else the floor
    dev_warmup_j: np.ndarray  # (n_q,) [J] per switch-on
    # profiles
    prof_state: np.ndarray  # (n_r,)
    profiles: tuple[ProfileRates, ...]
    # computer clocks
    clocks: tuple[Board, ...]  # the board at each clock of the clock shares, slowest first
    mode_state: np.ndarray  # (n_m,) state of each pair; clocks in `clocks` order
    mode_power_w: np.ndarray  # (n_m,) [W]; NaN: cannot keep up
    sensor_quality_min: dict[str, float]  # mission-wide time-weighted quality floors
    notes: tuple[str, ...]
    transit: Transit  # states whose time follows from the planned speed

    @property
    def duty_in_transit(self) -> np.ndarray:
        """(n_p,) True where the duty variable is on-time per metre of a transit leg."""
        return np.isin(self.duty_state, self.transit.state)

    @property
    def device_in_transit(self) -> np.ndarray:
        return np.isin(self.dev_state, self.transit.state)

    @property
    def planning_time_s(self) -> np.ndarray:
        """(n_s,) time [s] of each state in the walk (transit legs at the nominal speed)."""
        return np.array([self.occupancy.time_s[s] for s in self.states], float)

    @property
    def sizes(self) -> tuple[int, int, int, int]:
        return len(self.duty_state), len(self.dev_state), len(self.prof_state), len(self.mode_state)

    def switch_ons(self) -> np.ndarray:
        """Switch-ons [1] of each device over the mission when it is duty-cycled."""
        t = self.planning_time_s[self.dev_state]
        visits = np.array([self.occupancy.visits[self.states[s]] for s in self.dev_state])
        return np.ceil(t / SENSOR_PERIOD_S) + visits


def duty_bounds(mission: ir.CheckedMission, state: ir.State, use: ir.SensorUse, alpha: float
                ) -> tuple[float, float]:
    """The (least, most) duty [1] a plan may give sensor `use` in `state`: a fixed duty is
    itself, a sensor without one always on, `duty auto` within the mission's and the
    state's bounds (`alpha`: the device's quality curve, for a `require ... quality`)."""
    if use.duty != "auto":
        value = 1.0 if use.duty is None else float(use.duty)
        return value, value
    return _bounds(mission, state, use.name, alpha)


def _bounds(mission: ir.CheckedMission, state: ir.State, sensor: str, alpha: float
            ) -> tuple[float, float]:
    pref = mission.preference(sensor)
    lo, hi = pref.duty_min, pref.duty_max
    for req in state.requirements:
        if req.sensor == sensor:
            lo, hi = max(lo, req.duty_min, duty_for_quality(alpha, req.quality_min)), \
                min(hi, req.duty_max)
    if lo > hi + 1e-12:
        raise PlanInputError(f"state {state.name}: sensor {sensor}: duty must be >= {lo:g} "
                             f"and <= {hi:g}; the annotations contradict each other")
    return lo, min(max(hi, lo), 1.0)


def _no_board_notes(mission: ir.CheckedMission) -> list[str]:
    """What a plan on `computer none` rests on: no board is charged, and the states' own
    computer settings (a mission planned with `--computer none`) have no board to set."""
    return [NO_BOARD_NOTE, *(f"{s.name}: its computer settings do not apply: there is no "
                             f"board to set (computer {NO_BOARD})"
                             for s in mission.states if not s.computer.is_default)]


def water_notes(hardware: Hardware) -> list[str]:
    """What each state's speed is chosen for where the plan has a current."""
    return [f"{name}: speed chosen for the current on its {len(legs)} leg(s), "
            f"{sum(g.length_m for g in legs) / 1000:.3g} km: "
            + "; ".join(f"{g.where.split(': ', 1)[-1]} {g.along_mps:+.3g} m/s along, "
                        f"{abs(g.across_mps):.3g} m/s across" for g in legs)
            for name, legs in hardware.legs.items()]


def build_inputs(mission: ir.CheckedMission, hardware: Hardware,
                 occupancy: Occupancy) -> PlanInputs:
    notes: list[str] = [*occupancy.notes, *hardware.water_notes, *water_notes(hardware)]
    duty: list[tuple] = []
    fixed: list[tuple] = []
    dev_keys: dict[tuple[int, str], int] = {}
    dev_lo: list[float] = []
    dev_auto: list[bool] = []
    profiles: list[ProfileRates] = []
    prof_state: list[int] = []
    clocks = clock_columns(hardware, mission)
    powers = [state_mode_powers(hardware, state, clocks) for state in mission.states]
    if hardware.board.is_none:
        notes += _no_board_notes(mission)
    for state, power in zip(mission.states, powers, strict=True):
        if not np.isfinite(power).any():
            raise PlanInputError(f"computer {hardware.board.name}: no clock keeps up with "
                                 f"the work per tick of state {state.name} "
                                 f"({hardware.cycles(state):,.0f} cycles)")
        if hardware.board.is_none:
            continue  # its notes say that the state's settings do not apply
        if state.computer.sleep and not hardware.sleeps(state):
            notes.append(f"{state.name}: board {hardware.board.name} cannot sleep between "
                         "ticks; planned awake")
        wanted = state.computer.clock_mhz
        if hardware.held and wanted is not None and \
                all(abs(m.clock_mhz - wanted) > 1e-6 for m in hardware.modes):
            notes.append(f"{state.name}: computer clock {wanted:g} MHz, but the board is "
                         f"held at {hardware.board.clock_mhz:g} MHz for every state")
    for s, state in enumerate(mission.states):
        for use in state.sensors:
            device = SENSOR_BY_NAME[use.name].device
            if device is None:
                continue  # flight sensors are part of the hotel load
            q = dev_keys.setdefault((s, device), len(dev_keys))
            if q == len(dev_lo):
                dev_lo.append(0.0)
                dev_auto.append(False)
            model = hardware.devices[device]
            weight = mission.preference(use.name).weight
            lo, hi = duty_bounds(mission, state, use, model.quality_alpha)
            if use.duty == "auto":
                duty.append((s, use.name, q, model.quality_alpha, weight, lo, hi))
                dev_auto[q] = True
            else:
                value = lo
                fixed.append((s, use.name, value, model.quality_alpha, weight))
                dev_lo[q] = max(dev_lo[q], value)
        for rates in state_profiles(hardware, state, occupancy, notes):
            profiles.append(rates)
            prof_state.append(s)
    if not duty:
        notes.append("no sensor is marked `duty auto`: every sensor runs as written")
    transit = _transit_legs(mission, hardware, occupancy, notes)
    fixed_time = np.array([0.0 if s in transit.state else occupancy.time_s[st.name]
                           for s, st in enumerate(mission.states)], float)
    devs = list(dev_keys)
    n_s = len(mission.states)
    quality_min = {p.sensor: p.quality_min for p in mission.sensor_preferences
                   if p.quality_min > 0.0}
    cols = list(zip(*duty, strict=True)) if duty else [()] * 7
    held = held_power_w(hardware.vehicle)  # billed as they run: the base load is without
    notes += [f"{name}: in the vehicle's hotel load ({held[name]:.3g} W), billed for the "
              "time the mission runs it" for name in dict.fromkeys(k[1] for k in devs)
              if name in held]
    return PlanInputs(
        mission=mission, hardware=hardware, occupancy=occupancy,
        states=tuple(s.name for s in mission.states),
        time_s=fixed_time,
        duty_state=np.array(cols[0], int), duty_sensor=tuple(cols[1]),
        duty_device=np.array(cols[2], int), alpha=np.array(cols[3], float),
        weight=np.array(cols[4], float), duty_lo=np.array(cols[5], float),
        duty_hi=np.array(cols[6], float), fixed=tuple(fixed),
        dev_state=np.array([k[0] for k in devs], int), dev_name=tuple(k[1] for k in devs),
        dev_power_w=np.array([hardware.devices[k[1]].on_power_w for k in devs], float),
        dev_lo=np.array(dev_lo, float),
        dev_hi=np.array([1.0 if a else lo for a, lo in zip(dev_auto, dev_lo, strict=True)]),
        dev_warmup_j=np.array([hardware.devices[k[1]].warmup_j if auto else 0.0
                               for k, auto in zip(devs, dev_auto, strict=True)], float),
        prof_state=np.array(prof_state, int), profiles=tuple(profiles),
        clocks=clocks,
        mode_state=np.repeat(np.arange(n_s), len(clocks)),
        mode_power_w=np.concatenate(powers),
        sensor_quality_min=quality_min, notes=tuple(dict.fromkeys(notes)), transit=transit,
    )


@dataclass(frozen=True)
class Coefficients:
    """Parameter values of the convex model. Energies in the model's unit (MJ)."""

    dev_j: np.ndarray  # (n_q,) energy of device q fully on for the whole state
    prof_j: np.ndarray  # (n_r,) energy of flying profile r for the whole state
    mode_j: np.ndarray  # (n_m,) energy of the computer at clock m for the whole state
    fixed_j: float  # warm-ups (charged whenever a device may cycle)
    omega: np.ndarray  # (n_p,) quality weight of each auto duty, normalised
    quality0: float  # quality from fixed-duty sensors
    sensor_omega: dict[str, np.ndarray]  # sensor -> (n_p,) time weights for its floor
    sensor_quality0: dict[str, float]
    # transit legs: energy = pace_j . p + inv_j . p^-2 (+ e in fixed_j, devices in dev_j)
    pace_j: np.ndarray  # (n_t,)
    inv_pace_j: np.ndarray  # (n_t,)
    omega_transit: np.ndarray  # (n_p,) quality weight of transit rows (nominal time)
    leg_m: np.ndarray  # (n_t,) route length [m]: time = leg (p + k p^-2)
    leg_pump_m: np.ndarray  # (n_t,) leg x k
    horizon_left_s: float | None  # horizon minus the fixed states' time


ENERGY_UNIT_J = 1e6  # the model counts energy in MJ: coefficients of order 1 for Clarabel


def utility(alpha: np.ndarray | float, duty: np.ndarray | float) -> np.ndarray:
    """The sensors' quality curve, log(1 + a d) / log(1 + a), as power_models defines it."""
    a = np.asarray(alpha, float)
    return np.log1p(a * np.asarray(duty, float)) / np.log1p(a)


def coefficients(inputs: PlanInputs) -> Coefficients:
    t = inputs.time_s
    tr = inputs.transit
    scale = 1.0 / ENERGY_UNIT_J
    mode_w = np.where(np.isfinite(inputs.mode_power_w), inputs.mode_power_w, 0.0)
    prof_w = np.array([p.total_w for p in inputs.profiles])
    # the board boots once, at its default clock, before the mission starts
    fixed_j = inputs.hardware.board.boot_j + float(np.sum(inputs.dev_warmup_j
                                                          * inputs.switch_ons()))
    fixed_j += float(tr.length_m @ (tr.pitch_j_per_m + tr.load_w * tr.turn_s_per_m))
    leg = np.zeros(len(inputs.states))
    leg[tr.state] = tr.length_m
    # quality: weight x time of every (state, device sensor), fixed ones included; transit
    # legs count with their nominal-speed time so that the weights do not depend on speed
    nominal = inputs.planning_time_s
    auto_wt = inputs.weight * t[inputs.duty_state]
    fixed_wt = np.array([w * nominal[s] for s, _, _, _, w in inputs.fixed])
    in_transit = inputs.duty_in_transit
    total = float(auto_wt.sum() + fixed_wt.sum()
                  + (inputs.weight * nominal[inputs.duty_state])[in_transit].sum()) or 1.0
    fixed_u = np.array([float(utility(a, d)) for _, _, d, a, _ in inputs.fixed])
    sensor_omega, sensor_q0 = {}, {}
    for sensor in inputs.sensor_quality_min:
        mine = np.array([n == sensor for n in inputs.duty_sensor], bool)
        mine_fixed = [(t[s], float(utility(a, d))) for s, n, d, a, _ in inputs.fixed
                      if n == sensor]
        span = float(t[inputs.duty_state][mine].sum() + sum(x for x, _ in mine_fixed)) or 1.0
        sensor_omega[sensor] = np.where(mine, t[inputs.duty_state], 0.0) / span
        sensor_q0[sensor] = sum(x * u for x, u in mine_fixed) / span
    horizon = inputs.mission.horizon_s
    return Coefficients(
        dev_j=inputs.dev_power_w * (t + leg)[inputs.dev_state] * scale,
        prof_j=prof_w * t[inputs.prof_state] * scale,
        mode_j=mode_w * t[inputs.mode_state] * scale,
        fixed_j=fixed_j * scale,
        omega=auto_wt / total,
        quality0=float((fixed_wt * fixed_u).sum() / total) if len(fixed_u) else 0.0,
        sensor_omega=sensor_omega, sensor_quality0=sensor_q0,
        pace_j=tr.length_m * tr.load_w * scale,
        inv_pace_j=tr.length_m * (tr.load_w * tr.pump_s + tr.pump_j) * scale,
        omega_transit=np.where(in_transit, inputs.weight * nominal[inputs.duty_state], 0.0)
        / total,
        leg_m=tr.length_m, leg_pump_m=tr.length_m * tr.pump_s,
        horizon_left_s=None if horizon is None or not tr.size
        else horizon - float(t.sum()) - float(tr.length_m @ tr.turn_s_per_m),
    )
