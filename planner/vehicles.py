"""The same mission on several vehicles (`gliderplan compare-vehicles`): each vehicle's
plan (energy, time), its cheapest way through the water per km, its range on the
mission's battery, and the head current beyond which a propeller pays.

Per vehicle the energy per metre over ground against a head current c is the least, over
the ways it can fly (a yo of the mission's band on buoyancy, a cruise on its propulsion),
of E_w(U) U / (U - c) (planner/speed.py); a glider that cannot outrun the current makes
no headway. The crossovers are the currents where the cheapest vehicle changes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from gliderplan.language import ir
from gliderplan.planner.speed import NoHeadway, least_energy_speed
from gliderplan.power_models.devices import base_power_w
from gliderplan.power_models.vehicle import Vehicle

HEAD_CURRENTS_MPS = np.linspace(0.0, 1.2, 49)  # [m s-1] the crossover's grid


@dataclass(frozen=True)
class VehicleResult:
    vehicle: str
    kind: str
    energy_j: float  # the mission's planned energy [J]
    duration_s: float  # its planned time [s]
    distance_km: float  # through the water at the planned speeds [km]
    energy_per_km_j: float  # [J km-1] at its cheapest speed in still water, hotel included
    best_speed_mps: float  # that speed [m s-1]
    range_km: float  # usable battery / energy per km [km]
    per_km_against_current_j: tuple[float, ...]  # [J km-1] at HEAD_CURRENTS_MPS, NaN: no way


def _yo_band(mission: ir.CheckedMission) -> tuple[float, float, float] | None:
    """(min, max depth [m], pitch [rad]) of the mission's first constant yo, or None."""
    for state in mission.states:
        for profile in state.profiles:
            args = profile.constant_args()
            if profile.kind == "yo" and args is not None:
                return args[0], args[1], 0.5 * (args[2] + args[3])
    return None


def _ways(vehicle: Vehicle, load_w: float, band: tuple[float, float, float] | None):
    """(energy per metre through the water as a function of speed, low, high speed) of
    each way the vehicle flies."""
    ways = []
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


def per_metre_j(vehicle: Vehicle, load_w: float, band, head_mps: float
                ) -> tuple[float, float]:
    """(least energy per metre over ground [J m-1], its speed [m s-1]) against a head
    current `head_mps`; (NaN, NaN) when no way makes headway."""
    best = (math.nan, math.nan)
    for energy, low, high in _ways(vehicle, load_w, band):
        try:
            speed, cost = least_energy_speed(energy, low, high, along_mps=-head_mps)
        except NoHeadway:
            continue
        if not cost >= best[0]:
            best = (cost, speed)
    return best


def compare_vehicles(mission: ir.CheckedMission, specs: list[str],
                     battery: str | None = None) -> list[VehicleResult]:
    """Plan `mission` on each vehicle of `specs` (presets or files) in place of its own."""
    from gliderplan.planner.make import make_plan
    from gliderplan.power_models.vehicle import load_vehicle

    band = _yo_band(mission)
    results = []
    for spec in specs:
        vehicle = load_vehicle(spec)
        planned = make_plan(replace(mission, vehicle=spec), battery=battery)
        plan = planned.plan
        duration = sum(s.time_s for s in plan.states)
        distance = sum(s.time_s * p.share * p.speed_mps for s in plan.states
                       for p in s.profiles) / 1000.0
        computer_j = sum(s.energy_by_component_j.get("computer", 0.0) for s in plan.states)
        load = base_power_w(vehicle) + computer_j / duration  # [W] drawn at any speed
        curve = [per_metre_j(vehicle, load, band, c)[0] * 1000.0 for c in HEAD_CURRENTS_MPS]
        per_m, speed = per_metre_j(vehicle, load, band, 0.0)
        usable = plan.budget_j
        results.append(VehicleResult(vehicle.name, vehicle.kind, plan.predicted_j, duration,
                                     distance, per_m * 1000.0, speed,
                                     usable / (per_m * 1000.0), tuple(curve)))
    return results


def crossovers(results: list[VehicleResult]) -> list[dict]:
    """Head currents [m s-1] where the vehicle of least energy per km changes."""
    table = np.array([r.per_km_against_current_j for r in results])
    table = np.where(np.isfinite(table), table, np.inf)
    cheapest = [int(np.argmin(col)) if np.isfinite(col).any() else -1 for col in table.T]
    out = []
    for i in range(1, len(cheapest)):
        if cheapest[i] != cheapest[i - 1] and cheapest[i] >= 0:
            out.append({"head_current_mps": float(HEAD_CURRENTS_MPS[i]),
                        "from": results[cheapest[i - 1]].vehicle if cheapest[i - 1] >= 0
                        else None, "to": results[cheapest[i]].vehicle})
    return out
