"""The speed through the water that makes the most of a joule: the least energy per metre
over ground, for a propelled vehicle (its propulsion model) or any flight whose energy per
metre through the water is known, in still water or in a current along a route's legs.

Through the water at speed U a vehicle spends E_w(U) per metre; over ground on a leg it
makes g(U) = sqrt(U^2 - c_x^2) + c_a (crabbing into the cross current c_x, helped or held
back by the current along its track c_a), so per metre over ground it spends
E_w(U) U / g(U). Over a route of legs i of length L_i flown at one speed the energy per
metre over ground is sum_i L_i E_w(U) U / g_i(U) / sum_i L_i; a speed that makes no
headway on one leg never reaches the end of the route. For a propeller
E_w(U) = (L + P(U)) / U. In still water and for P = running + k U^3 the least lies at
U* = ((L + running) / (2 k))^(1/3) (`Propulsion.optimal_speed_mps`); a table, a current
or an exponent other than 3 is searched: a grid over the speed range, then golden
sections about its best point.

This is the one search: the planner chooses a state's `auto` speed with it
(`planner.rates`) and `compare-vehicles` each vehicle's cheapest way against a head
current (`cheapest_way`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.contract.errors import GliderplanError
from gliderplan.power_models.propulsion import Propulsion, ground_speed_mps

if TYPE_CHECKING:
    from gliderplan.power_models.vehicle import Vehicle

GRID_POINTS = 401  # speeds tried across the range before refining
_GOLDEN_STEPS = 80  # each shrinks the bracket by 0.618: far below a double's precision


@dataclass(frozen=True)
class Leg:
    """A stretch of track and the current on it: `along_mps` along the track (positive:
    following, negative: head) and `across_mps` across it [m s-1]."""

    where: str  # names the leg in messages: "transect: leg 1 to 39.175, -73.830"
    length_m: float  # [m] its weight in the route's energy per metre
    along_mps: float = 0.0
    across_mps: float = 0.0


STILL_WATER = (Leg("still water", 1.0),)


def head_current(head_mps: float) -> tuple[Leg, ...]:
    """One leg straight into a current of `head_mps` [m s-1]."""
    return (Leg(f"a head current of {head_mps:.3g} m/s", 1.0, -head_mps),)


@dataclass(frozen=True)
class SpeedChoice:
    """The chosen speed and what it costs."""

    speed_mps: float  # through the water [m s-1]
    ground_mps: float  # over ground [m s-1], the route's length over its time
    energy_per_m_j: float  # [J] per metre over ground, load and propulsion together
    propulsion_w: float  # [W] the propulsion draws at that speed (0 for a glider)


class NoHeadway(GliderplanError, ValueError):
    """No speed in the range makes headway against the current of a leg (named): the
    mission cannot be flown in that water as asked."""


def route_pace_s_per_m(speed_mps: np.ndarray | float, legs: Sequence[Leg]) -> np.ndarray:
    """[s m-1] time per metre over ground along `legs` at `speed_mps` through the water
    (the length-weighted mean of 1 / g_i(U)); inf where a leg makes no headway."""
    u = np.asarray(speed_mps, float)
    total = sum(leg.length_m for leg in legs)
    pace = sum(leg.length_m / ground_speed_mps(u, leg.along_mps, leg.across_mps)
               for leg in legs) / total
    return np.where(np.isfinite(pace), pace, np.inf)


def _no_headway(legs: Sequence[Leg], speed_mps: float, what: str) -> NoHeadway:
    """The error for `legs` at `speed_mps` [m s-1], naming the first leg it cannot fly."""
    leg = next(leg for leg in legs
               if not np.isfinite(ground_speed_mps(speed_mps, leg.along_mps, leg.across_mps)))
    return NoHeadway(f"{leg.where}: {what} against its current of "
                     f"{math.hypot(leg.along_mps, leg.across_mps):.3g} m/s "
                     f"({-leg.along_mps:.3g} m/s head, {abs(leg.across_mps):.3g} m/s across)")


def least_energy_speed(energy_per_water_m: Callable[[np.ndarray], np.ndarray],
                       low_mps: float, high_mps: float,
                       legs: Sequence[Leg] = STILL_WATER) -> tuple[float, float]:
    """(speed [m s-1], energy per metre over ground [J m-1]) that minimise
    E_w(U) U x route_pace(U) over [low_mps, high_mps]; `energy_per_water_m` takes an array
    of speeds. Raises NoHeadway, naming the leg, when no speed of the range makes way on
    every leg."""

    def per_ground_m(u: np.ndarray) -> np.ndarray:
        cost = energy_per_water_m(u) * u * route_pace_s_per_m(u, legs)
        return np.where(np.isfinite(cost), cost, np.inf)

    grid = np.linspace(low_mps, high_mps, GRID_POINTS)
    costs = per_ground_m(grid)
    best = int(np.argmin(costs))
    if not np.isfinite(costs[best]):
        raise _no_headway(legs, high_mps,
                          f"no speed of {low_mps:.3g}-{high_mps:.3g} m/s makes headway")
    a, b = grid[max(best - 1, 0)], grid[min(best + 1, GRID_POINTS - 1)]
    ratio = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(_GOLDEN_STEPS):
        c, d = b - ratio * (b - a), a + ratio * (b - a)
        if per_ground_m(np.array(c)) <= per_ground_m(np.array(d)):
            b = d
        else:
            a = c
    u = 0.5 * (a + b)
    found = float(per_ground_m(np.array(u)))
    if costs[best] < found:  # the grid's point is a kink of a table (or an end)
        return float(grid[best]), float(costs[best])
    return float(u), found


def best_speed(propulsion: Propulsion, load_w: float,
               legs: Sequence[Leg] = STILL_WATER) -> SpeedChoice:
    """The speed in the propulsion's range with the least energy per metre over ground
    along `legs`, with a load of `load_w` [W] besides the motor (hotel, computer)."""
    speed, energy = least_energy_speed(lambda u: propulsion.energy_per_m_j(u, load_w),
                                       propulsion.min_speed_mps, propulsion.max_speed_mps,
                                       legs)
    return choice_at(propulsion, load_w, speed, legs, energy)


def choice_at(propulsion: Propulsion, load_w: float, speed_mps: float,
              legs: Sequence[Leg] = STILL_WATER,
              energy_per_m_j: float | None = None) -> SpeedChoice:
    """What flying `speed_mps` [m s-1] along `legs` costs (a speed the mission fixes).
    Raises NoHeadway, naming the leg, where it makes no way."""
    pace = float(route_pace_s_per_m(speed_mps, legs))
    if not math.isfinite(pace):
        raise _no_headway(legs, speed_mps, f"{speed_mps:.3g} m/s makes no headway")
    power = float(propulsion.power_w(speed_mps))
    energy = (load_w + power) * pace if energy_per_m_j is None else energy_per_m_j
    return SpeedChoice(float(speed_mps), 1.0 / pace, energy, power)


def energy_per_km_curve(propulsion: Propulsion, load_w: float,
                        legs: Sequence[Leg] = STILL_WATER, points: int = 60
                        ) -> tuple[np.ndarray, np.ndarray]:
    """(speeds [m s-1], energy per km over ground [kJ], NaN where it makes no way) across
    the propulsion's range along `legs`: the report's curve."""
    speeds = np.linspace(propulsion.min_speed_mps, propulsion.max_speed_mps, points)
    pace = route_pace_s_per_m(speeds, legs)
    return speeds, np.where(np.isfinite(pace), (load_w + propulsion.power_w(speeds)) * pace,
                            np.nan)


Way = tuple[Callable[[np.ndarray], np.ndarray], float, float]  # E_w(U), low, high [m s-1]


def flight_ways(vehicle: Vehicle, load_w: float,
                band: tuple[float, float, float] | None) -> list[Way]:
    """(energy per metre through the water as a function of speed, low, high speed) of
    each way `vehicle` flies with a load of `load_w` [W]: a yo of `band` (min, max depth
    [m], pitch [rad]) on buoyancy, where it has an engine and a band is given, and a
    cruise on its propulsion, where it has one."""
    ways: list[Way] = []
    if vehicle.has_buoyancy_engine and band is not None:
        low, high, pitch = band
        c = float(vehicle.transit_coefficient(low, high, pitch, load_w))
        e = float(vehicle.pitch_j_per_m(low, high, pitch))
        turn = float(vehicle.turn_s_per_m(low, high, pitch))
        ways.append((lambda u: load_w / u + e + load_w * turn + c * u * u, 0.05,
                     float(vehicle.max_speed_mps(pitch))))
    if vehicle.propulsion is not None:
        p = vehicle.propulsion
        ways.append((lambda u: p.energy_per_m_j(u, load_w), p.min_speed_mps, p.max_speed_mps))
    return ways


def cheapest_way(vehicle: Vehicle, load_w: float, band: tuple[float, float, float] | None,
                 legs: Sequence[Leg] = STILL_WATER) -> tuple[float, float]:
    """(least energy per metre over ground [J m-1], its speed [m s-1]) of the ways
    `vehicle` flies (`flight_ways`) along `legs`; (NaN, NaN) when no way makes headway."""
    best = (math.nan, math.nan)
    for energy, low, high in flight_ways(vehicle, load_w, band):
        try:
            speed, cost = least_energy_speed(energy, low, high, legs)
        except NoHeadway:
            continue
        if not cost >= best[0]:
            best = (cost, speed)
    return best
