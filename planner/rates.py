"""What each state costs per second, from the power models: the planner's coefficients.

Per state and flight-profile alternative: the power [W] of each vehicle component
(hotel, pump, pitch, surface, iridium) and the inflection rate, flying at the speed
that minimises energy per metre for the state's fixed load, u* = (P / 2c)^(1/3)
(DESIGN.md section 5; a hungrier computer makes the glider faster). Per clock of the
computer: its mean power for the runtime's workload. Per sensor device: its on-power.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gliderplan.contract import TICK_S, Component
from gliderplan.language import ir
from gliderplan.language.registry import PROFILES, altitude_stop_m, cannot_fly
from gliderplan.planner.hardware import Hardware
from gliderplan.planner.occupancy import Occupancy, mission_occupancy
from gliderplan.planner.speed import (
    STILL_WATER,
    Leg,
    SpeedChoice,
    best_speed,
    choice_at,
    route_pace_s_per_m,
)
from gliderplan.power_models.board import Board
from gliderplan.power_models.devices import base_power_w
from gliderplan.power_models.flight import DensityProfile
from gliderplan.power_models.propulsion import thrust_assisted_speed
from gliderplan.power_models.vehicle import Vehicle, flying_yo

LEVEL_PITCH_RAD = 0.0  # the plan's pitch of a propelled profile: level flight


@dataclass(frozen=True)
class ProfileRates:
    """One flight-profile alternative of a state, at its planned speed."""

    index: int
    kind: str
    power_w: dict[str, float]  # vehicle component -> mean power [W]
    inflections_per_s: float
    speed_mps: float
    pitch_rad: float
    ballast_cc: float
    thrust_w: float = 0.0  # a thruster's commanded power [W] (0: off)
    flyable: bool = True  # False: an alternative the vehicle cannot fly, given no time

    @property
    def total_w(self) -> float:
        return float(sum(self.power_w.values()))


def computer_power_w(board: Board, cycles_per_tick: float, tick_s: float = TICK_S,
                     sleep: bool = False) -> float | None:
    """Mean power [W] of the board idling (or sleeping) between ticks; None if it cannot
    keep up."""
    power = float(board.mean_power_w(cycles_per_tick, tick_s, sleep))
    return None if np.isnan(power) else power


def yo_band(profile: ir.Profile, args: tuple[float, ...]) -> tuple[float, float]:
    """The depth band [m] a yo profile is planned at: its own, or for a `thermotrackyo` the
    band tracking flies on average. Once it has found the thermocline at depth z it flies
    [max(min, z - h), min(max, z + h)], h = depth_threshold / 2; z is not known before
    flight, so the band is planned at its mean width over a thermocline anywhere in
    [min, max] (2 h - h^2 / L, L = max - min, for h <= L), centred in the range."""
    low, high = args[0], args[1]
    if profile.kind == "thermotrackyo" and high > low:
        span, half = high - low, args[5] / 2.0
        width = span if half >= span else 2.0 * half - half * half / span
        middle = 0.5 * (low + high)
        low, high = middle - 0.5 * width, middle + 0.5 * width
    return low, high


MIN_FLOORED_BAND_M = 1.0  # [m] a yo whose stop lies above its min_depth turns about there


def floored_args(kind: str, args: tuple[float, ...], floor_m: float | None
                 ) -> tuple[float, ...]:
    """A yo's arguments with the depth its dives turn at over a sea floor `floor_m` [m]
    (None: unknown, the band as written): max_depth becomes min(max_depth, floor -
    altitude) for a yo with an altimeter stop, and at least MIN_FLOORED_BAND_M below
    min_depth."""
    stop = altitude_stop_m(kind, args)
    if floor_m is None or not stop > 0.0 or floor_m - stop >= args[1]:
        return args
    bottom = max(floor_m - stop, args[0] + MIN_FLOORED_BAND_M)
    return (args[0], bottom, *args[2:])


def altimeter_note(where: str, kind: str, args: tuple[float, ...],
                   floor_m: float | None = None) -> str | None:
    """What a plan assumes of a yo's altimeter stop (None: it has none)."""
    stop = altitude_stop_m(kind, args)
    if not stop > 0.0:
        return None
    if floor_m is None:
        return (f"{where}: turns at {stop:g} m above the sea floor: planned to max_depth "
                f"({args[1]:g} m), the floor unknown")
    bottom = floored_args(kind, args, floor_m)[1]
    return (f"{where}: turns at {stop:g} m above the sea floor: planned to {bottom:.3g} m, "
            f"min(max_depth {args[1]:g} m, the floor's {floor_m:.3g} m less {stop:g} m)")


def band_density(mission: ir.CheckedMission, ocean: DensityProfile, vehicle: Vehicle,
                 floor_m: float | None = None) -> float:
    """[kg m-3] the mean density of `ocean` from the surface to the deepest a yo of the
    mission turns (its arguments as written, at the variables' initial values; the
    vehicle's nominal where they are variables; over a sea floor `floor_m` [m], where the
    altimeter turns it, and never below the floor): the water a pilot ballasts the glider
    for (`ballasted_in`)."""
    deepest = vehicle.nominal_max_depth_m
    initial = {v.name: v.initial for v in mission.variables}
    for state in mission.states:
        profile = state.profiles[0]
        if profile.kind in ("yo", "thermotrackyo"):
            bottom = floored_args(profile.kind, _profile_args(profile, initial), floor_m)[1]
            if math.isfinite(bottom):
                deepest = max(deepest, bottom)
    if floor_m is not None:
        deepest = min(deepest, floor_m)
    return float(np.mean(ocean.at(np.linspace(0.0, deepest, 50))))


def ballasted_in(mission: ir.CheckedMission, ocean: DensityProfile, vehicle: Vehicle,
                 floor_m: float | None = None) -> tuple[Vehicle, float]:
    """(`vehicle` ballasted for `ocean`, the density [kg m-3] it is ballasted for: the
    mean over the depths the mission flies, `band_density`): the glider `sim --ocean`
    flies and `forecast --ocean` bills, whose trim was for its calibration water."""
    rho = band_density(mission, ocean, vehicle, floor_m)
    return vehicle.ballasted_for(rho), rho


def _profile_args(profile: ir.Profile, variables: dict[str, float]) -> tuple[float, ...]:
    return tuple(ir.evaluate(a, {}, variables) for a in profile.args)


def profile_rates(vehicle: Vehicle, profile: ir.Profile, index: int,
                  variables: dict[str, float], fixed_load_w: float,
                  visit_s: float, notes: list[str], where: str,
                  legs: Sequence[Leg] = STILL_WATER) -> ProfileRates:
    """Component powers of one profile alternative. `fixed_load_w` [W] is the load the
    glide speed is optimised for (hotel + computer); `visit_s` the mean time per visit;
    `legs` the route and current a propelled speed is chosen for."""
    pitch0 = vehicle.nominal_pitch_rad
    if (problem := cannot_fly(profile.kind, profile.thrust, vehicle)) is not None:
        notes.append(f"{where}: {problem[0]}: given no time")
        return _not_flown(vehicle, profile, index)
    if PROFILES[profile.kind].propelled:
        return _propelled_rates(vehicle, profile, index, variables, fixed_load_w, legs)
    if profile.kind in ("yo", "thermotrackyo"):
        args = _profile_args(profile, variables)
        low, high = yo_band(profile, args)
        pitch = 0.5 * (args[2] + args[3])
        if not (math.isfinite(low) and math.isfinite(high) and 0.0 <= low < high
                and 0.0 < pitch < math.pi / 2):
            low, high, pitch = vehicle.nominal_min_depth_m, vehicle.nominal_max_depth_m, pitch0
            notes.append(f"{where}: arguments unknown before flight; planned as a yo "
                         f"{low:g}-{high:g} m (the vehicle's nominal)")
        elif profile.kind == "thermotrackyo":
            notes.append(f"{where}: thermocline tracking planned as a yo {low:.3g}-{high:.3g} m, "
                         f"the band it flies on average for a thermocline anywhere in "
                         f"{args[0]:g}-{args[1]:g} m")
        if (note := altimeter_note(where, profile.kind, args)) is not None:
            notes.append(note)
        with flying_yo(where, vehicle, low, high):
            speed = float(vehicle.optimal_speed_mps(fixed_load_w, low, high, pitch))
            ballast = min(float(vehicle.yo_ballast_cc(speed, pitch, low, high)),
                          vehicle.max_ballast_cc)
            per_hour = float(vehicle.inflections_per_hour(low, high, pitch, ballast))
            actuators_w = float(vehicle.profile_power_w(low, high, pitch, ballast))
        pitch_w = vehicle.pitch_energy_j * per_hour / 3600.0
        power = {Component.HOTEL: base_power_w(vehicle), Component.PUMP: actuators_w - pitch_w,
                 Component.PITCH: pitch_w, Component.SURFACE: 0.0, Component.IRIDIUM: 0.0,
                 Component.PROPULSION: 0.0}
        rates = ProfileRates(index, profile.kind, power, per_hour / 3600.0, speed, pitch,
                             ballast)
        return rates if profile.thrust is None else _thrust_assisted(vehicle, profile, rates,
                                                                     fixed_load_w, legs)
    # surface and hover do not glide: the plan file still carries a glide command, the
    # vehicle's nominal pitch at full buoyancy (what it climbs with).
    ballast = vehicle.max_ballast_cc
    speed = float(vehicle.glide(pitch0, ballast)[0])
    if profile.kind == "surface":
        call_s = min(max(visit_s - vehicle.surface_s, 0.0), vehicle.iridium_s)
        call_fraction = call_s / visit_s if visit_s > 0.0 else 0.0
        fixed_w = vehicle.surfacing_fixed_j / visit_s if visit_s > 0.0 else 0.0
        power = {Component.HOTEL: 0.0, Component.PUMP: 0.0, Component.PITCH: 0.0,
                 Component.SURFACE: vehicle.surface_w * (1.0 - call_fraction) + fixed_w,
                 Component.IRIDIUM: vehicle.iridium_w * call_fraction,
                 Component.PROPULSION: 0.0}
    else:  # hover: holds a depth with small corrections, counted in the hotel load
        power = {Component.HOTEL: base_power_w(vehicle), Component.PUMP: 0.0,
                 Component.PITCH: 0.0, Component.SURFACE: 0.0, Component.IRIDIUM: 0.0,
                 Component.PROPULSION: 0.0}
    return ProfileRates(index, profile.kind, power, 0.0, speed, pitch0, ballast)


def _propelled_rates(vehicle: Vehicle, profile: ir.Profile, index: int,
                     variables: dict[str, float], fixed_load_w: float,
                     legs: Sequence[Leg]) -> ProfileRates:
    """A level, propelled profile (`cruise`, `altitude`): at its written speed, or with
    `auto` at the speed of least energy per metre over ground along `legs` for the load
    `fixed_load_w` [W] (hotel and computer: a hungrier computer makes it faster). It holds
    its depth on the propeller: no pump, no inflections; the plan carries a level pitch."""
    choice = propelled_speed(vehicle, profile, variables, fixed_load_w, legs)
    power = {Component.HOTEL: base_power_w(vehicle), Component.PUMP: 0.0,
             Component.PITCH: 0.0, Component.SURFACE: 0.0, Component.IRIDIUM: 0.0,
             Component.PROPULSION: choice.propulsion_w}
    return ProfileRates(index, profile.kind, power, 0.0, choice.speed_mps, LEVEL_PITCH_RAD,
                        0.0)


def propelled_speed(vehicle: Vehicle, profile: ir.Profile, variables: dict[str, float],
                    fixed_load_w: float, legs: Sequence[Leg] = STILL_WATER) -> SpeedChoice:
    """The speed a propelled profile flies at: written, or for `auto` the least energy per
    metre over ground along `legs` for the load `fixed_load_w` [W] besides the motor.
    Raises NoHeadway naming the leg where the speed (every speed, for `auto`) makes no
    way against the current."""
    if "speed" in profile.auto:
        return best_speed(vehicle.propulsion, fixed_load_w, legs)
    return choice_at(vehicle.propulsion, fixed_load_w, _profile_args(profile, variables)[1],
                     legs)


def transit_speeds(hardware: Hardware, mission: ir.CheckedMission) -> dict[str, float]:
    """[m/s] the speed of each state whose alternatives the vehicle can fly are all
    propelled (the first of them; its speed written as a number or `auto`, not read from a
    variable): a transit leg through it is timed at that speed, not at a glider's nominal
    (`occupancy.mission_occupancy`)."""
    vehicle = hardware.vehicle
    initial = {v.name: v.initial for v in mission.variables}
    speeds = {}
    for state in mission.states:
        flown = [p for p in state.profiles if cannot_fly(p.kind, p.thrust, vehicle) is None]
        if flown and all(PROFILES[p.kind].propelled for p in flown) and \
                flown[0].constant_args() is not None:
            speeds[state.name] = propelled_speed(vehicle, flown[0], initial,
                                                 state_load_w(hardware, state),
                                                 hardware.water(state)).speed_mps
    return speeds


def hardware_occupancy(mission: ir.CheckedMission, hardware: Hardware,
                       horizon_s: float | None = None) -> Occupancy:
    """The mission's timeline on `hardware`: its propelled transit legs at their speed
    (`transit_speeds`), a glider's at the nominal speed."""
    return mission_occupancy(mission, horizon_s, transit_speeds(hardware, mission))


def _not_flown(vehicle: Vehicle, profile: ir.Profile, index: int) -> ProfileRates:
    """An alternative the vehicle cannot fly (the checker warned): no power, no time; the
    plan file carries the vehicle's own command (a glide, or level on its propeller)."""
    power = dict.fromkeys((Component.HOTEL, Component.PUMP, Component.PITCH,
                           Component.SURFACE, Component.IRIDIUM, Component.PROPULSION), 0.0)
    if vehicle.has_buoyancy_engine:
        pitch, ballast = vehicle.nominal_pitch_rad, vehicle.max_ballast_cc
        speed = float(vehicle.glide(pitch, ballast)[0])
    else:
        pitch, ballast, speed = LEVEL_PITCH_RAD, 0.0, vehicle.propulsion.min_speed_mps
    return ProfileRates(index, profile.kind, power, 0.0, speed, pitch, ballast, flyable=False)


THRUST_STEPS = 33  # commanded powers tried across a thruster's range for `thrust auto`


def _thrust_assisted(vehicle: Vehicle, profile: ir.Profile, glide: ProfileRates,
                     fixed_load_w: float, legs: Sequence[Leg]) -> ProfileRates:
    """A yo with the thruster on: thrust along the glide path speeds it up
    (`thrust_assisted_speed`, on the hull's zero-lift drag); with the path's angle kept,
    the yos come faster in proportion, and so do the pump and battery-shift powers. `auto`
    tries off and commands across the thruster's range and keeps the least energy per
    metre over ground along `legs` for the load `fixed_load_w` [W]."""
    propulsion, fl = vehicle.propulsion, vehicle.flight
    commands = np.array([0.0, *np.linspace(propulsion.min_command_w,
                                            propulsion.max_command_w, THRUST_STEPS)]) \
        if profile.thrust == "auto" else np.array([float(profile.thrust)])
    speeds = thrust_assisted_speed(glide.speed_mps,
                                   [propulsion.thrust_power_w(c) for c in commands],
                                   fl.rho_kg_m3, fl.wing_area_m2, fl.drag_cd0)
    actuators = glide.power_w[Component.PUMP] + glide.power_w[Component.PITCH]
    draws = np.array([propulsion.assist_draw_w(c) for c in commands])
    per_m = (fixed_load_w + actuators * speeds / glide.speed_mps + draws) \
        * route_pace_s_per_m(speeds, legs)
    best = int(np.argmin(per_m))
    faster = float(speeds[best] / glide.speed_mps)
    power = {**glide.power_w, Component.PUMP: glide.power_w[Component.PUMP] * faster,
             Component.PITCH: glide.power_w[Component.PITCH] * faster,
             Component.PROPULSION: float(draws[best])}
    return ProfileRates(glide.index, glide.kind, power, glide.inflections_per_s * faster,
                        float(speeds[best]), glide.pitch_rad, glide.ballast_cc,
                        float(commands[best]))


def state_profiles(hardware: Hardware, state: ir.State, occupancy: Occupancy,
                   notes: list[str]) -> list[ProfileRates]:
    """Rates of every alternative of a state."""
    load = state_load_w(hardware, state)
    visits = max(occupancy.visits[state.name], 1)
    visit_s = occupancy.time_s[state.name] / visits
    variables = occupancy.variables[state.name]
    return [profile_rates(hardware.vehicle, p, j, variables, load, visit_s, notes,
                          f"{state.name}: flightprofile {j}", hardware.water(state))
            for j, p in enumerate(state.profiles)]


def state_load_w(hardware: Hardware, state: ir.State) -> float:
    """[W] the load a state's flight speed is chosen for: the vehicle's hotel load and the
    board at its least power in the state."""
    powers = state_mode_powers(hardware, state)
    return hardware.vehicle.hotel_w + (float(np.nanmin(powers)) if np.isfinite(powers).any()
                                       else 0.0)


def clock_columns(hardware: Hardware, mission: ir.CheckedMission) -> tuple[Board, ...]:
    """The clocks the model's clock shares range over: the mission's (`hardware.modes`)
    unless a state's `computer clock` asks for another, then all of the board's."""
    if all(hardware.clocks(s) == hardware.modes for s in mission.states):
        return hardware.modes
    return hardware.board_modes


def state_mode_powers(hardware: Hardware, state: ir.State,
                      columns: tuple[Board, ...] | None = None) -> np.ndarray:
    """Mean power [W] of the board at each clock of `columns` (default: every clock the
    state may run at) in `state`, at the state's workload and sleeping between ticks where
    it does; NaN for a clock the state may not run at or that cannot keep up; 0 for the
    others when the vehicle's hotel load already holds the computer."""
    allowed = {m.clock_mhz for m in hardware.clocks(state)}
    cycles, sleep = hardware.cycles(state), hardware.sleeps(state)
    powers = np.array([np.nan if m.clock_mhz not in allowed
                       or (p := computer_power_w(m, cycles, sleep=sleep)) is None else p
                       for m in (columns or hardware.clocks(state))])
    held = Component.COMPUTER in hardware.vehicle.hotel_includes
    return np.where(np.isnan(powers), np.nan, 0.0) if held else powers
