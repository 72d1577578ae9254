"""The speed through the water that makes the most of a joule: the least energy per metre
over ground, for a propelled vehicle (its propulsion model) or any flight whose energy per
metre through the water is known, in still water or in a current.

Through the water at speed U a vehicle spends E_w(U) per metre; over ground it makes
g(U) = sqrt(U^2 - c_x^2) + c_a (crabbing into the cross current c_x, helped or held back
by the current along its track c_a), so per metre over ground it spends
E_w(U) U / g(U). For a propeller E_w(U) = (L + P(U)) / U: (L + P(U)) / g(U). In still
water and for P = running + k U^3 the least lies at U* = ((L + running) / (2 k))^(1/3)
(`Propulsion.optimal_speed_mps`); a table, a current or an exponent other than 3 is
searched: a grid over the speed range, then golden sections about its best point.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gliderplan.power_models.propulsion import Propulsion, ground_speed_mps

GRID_POINTS = 401  # speeds tried across the range before refining
_GOLDEN_STEPS = 80  # each shrinks the bracket by 0.618: far below a double's precision


@dataclass(frozen=True)
class SpeedChoice:
    """The chosen speed and what it costs."""

    speed_mps: float  # through the water [m s-1]
    ground_mps: float  # over ground [m s-1]
    energy_per_m_j: float  # [J] per metre over ground, load and propulsion together
    propulsion_w: float  # [W] the propulsion draws at that speed (0 for a glider)


class NoHeadway(ValueError):
    """No speed in the range makes headway against the current."""


def least_energy_speed(energy_per_water_m: Callable[[np.ndarray], np.ndarray],
                       low_mps: float, high_mps: float, along_mps: float = 0.0,
                       across_mps: float = 0.0) -> tuple[float, float]:
    """(speed [m s-1], energy per metre over ground [J m-1]) that minimise
    E_w(U) U / g(U) over [low_mps, high_mps]; `energy_per_water_m` takes an array of speeds.
    Raises NoHeadway when no speed of the range makes way over ground."""

    def per_ground_m(u: np.ndarray) -> np.ndarray:
        cost = energy_per_water_m(u) * u / ground_speed_mps(u, along_mps, across_mps)
        return np.where(np.isfinite(cost), cost, np.inf)

    grid = np.linspace(low_mps, high_mps, GRID_POINTS)
    costs = per_ground_m(grid)
    best = int(np.argmin(costs))
    if not np.isfinite(costs[best]):
        raise NoHeadway(f"no speed of {low_mps:.3g}-{high_mps:.3g} m/s makes headway against "
                        f"a current of {math.hypot(along_mps, across_mps):.3g} m/s")
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


def best_speed(propulsion: Propulsion, load_w: float, along_mps: float = 0.0,
               across_mps: float = 0.0) -> SpeedChoice:
    """The speed in the propulsion's range with the least energy per metre over ground,
    with a load of `load_w` [W] besides the motor (hotel, computer) and a current of
    `along_mps` along the track and `across_mps` across it [m s-1]."""
    speed, energy = least_energy_speed(lambda u: propulsion.energy_per_m_j(u, load_w),
                                       propulsion.min_speed_mps, propulsion.max_speed_mps,
                                       along_mps, across_mps)
    return choice_at(propulsion, load_w, speed, along_mps, across_mps, energy)


def choice_at(propulsion: Propulsion, load_w: float, speed_mps: float, along_mps: float = 0.0,
              across_mps: float = 0.0, energy_per_m_j: float | None = None) -> SpeedChoice:
    """What flying `speed_mps` [m s-1] costs (a speed the mission fixes). Raises NoHeadway
    when it makes no way against the current."""
    ground = float(ground_speed_mps(speed_mps, along_mps, across_mps))
    if not math.isfinite(ground):
        raise NoHeadway(f"{speed_mps:.3g} m/s makes no headway against a current of "
                        f"{math.hypot(along_mps, across_mps):.3g} m/s")
    power = float(propulsion.power_w(speed_mps))
    energy = (load_w + power) / ground if energy_per_m_j is None else energy_per_m_j
    return SpeedChoice(float(speed_mps), ground, energy, power)


def energy_per_km_curve(propulsion: Propulsion, load_w: float, along_mps: float = 0.0,
                        across_mps: float = 0.0, points: int = 60
                        ) -> tuple[np.ndarray, np.ndarray]:
    """(speeds [m s-1], energy per km over ground [kJ], NaN where it makes no way) across
    the propulsion's range: the report's curve."""
    speeds = np.linspace(propulsion.min_speed_mps, propulsion.max_speed_mps, points)
    ground = ground_speed_mps(speeds, along_mps, across_mps)
    return speeds, (load_w + propulsion.power_w(speeds)) / ground
