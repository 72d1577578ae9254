"""The same mission on several vehicles (`gliderplan compare-vehicles`): each vehicle's
plan (energy, time), its cheapest way through the water per km, its range on the
mission's battery, and the head current beyond which a propeller pays.

Per vehicle the energy per metre over ground against a head current c is the least, over
the ways it can fly (a yo of the mission's band on buoyancy, a cruise on its propulsion),
of E_w(U) U / (U - c), found by the planner's own search (`planner.speed.cheapest_way`,
the one `plan` chooses a cruise speed with); a glider that cannot outrun the current makes
no headway. The crossovers are the currents where the cheapest vehicle changes.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gliderplan.language import ir
from gliderplan.planner.speed import cheapest_way, head_current
from gliderplan.power_models.devices import base_power_w

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


def flies_on(mission: ir.CheckedMission, spec: str) -> bool:
    """Whether the vehicle `spec` (a preset or file) can fly an alternative of each state."""
    from gliderplan.language.registry import cannot_fly
    from gliderplan.power_models.vehicle import load_vehicle

    vehicle = load_vehicle(spec)
    return all(any(cannot_fly(p.kind, p.thrust, vehicle) is None for p in state.profiles)
               for state in mission.states)


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
        curve = [cheapest_way(vehicle, load, band, head_current(c))[0] * 1000.0
                 for c in HEAD_CURRENTS_MPS]
        per_m, speed = cheapest_way(vehicle, load, band)
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
