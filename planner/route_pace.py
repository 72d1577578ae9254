"""The paces a route may choose among: the yo's pitch sets the glider's speed through the
water and what it draws, and the route is planned at each for the least time or energy.

A pace's speed is over the ground in still water, yos and surfacings included: the
transit speed the simulator measures at the transit's pitch (`routing.transit_speed_mps`),
scaled by the flight model's yo speed at the pitch (full pump stroke, as flown without a
plan) over its yo speed at the transit's. Its power is the planner's forecast of the
transit mission flown at that pitch (`planner.forecast`: yos, surfacings, sensors and
board) over a day. At one pace a route's energy is its power times its time, so the
route of least time at a pace is also its route of least energy: the choice is the pace.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gliderplan.contract.units import finite_or_none
from gliderplan.planner.routing import (
    TRANSIT_BAND_M,
    TRANSIT_PITCH_RAD,
    NoRoute,
    RoutePlan,
    path_time_s,
    plan_route,
    transit_mission,
)
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.sim.currents import CurrentField

# [deg] the yo pitches a route chooses among: the Slocum's usual 15-35 degrees
PITCHES_DEG = (15.0, 20.0, 26.0, 32.0)
PACE_DAY_S = 86400.0  # [s] a pace's power is the forecast's over a day of transit
PACE_DRAWS = 2  # the forecast's drawn vehicles: its central bill is what a pace draws


@dataclass(frozen=True)
class Pace:
    pitch_rad: float
    speed_mps: float  # over the ground in still water, yos and surfacings included
    power_w: float  # mean draw over yos and surfacings


@dataclass(frozen=True)
class PacedRoute:
    """The route chosen, at its pace, against the straight line at the mission's pitch."""

    plan: RoutePlan
    pace: Pace
    nominal: Pace  # the mission's pitch, at which the straight line is flown
    straight_s: float  # [s] the straight line at the nominal pace (inf: held off)

    @property
    def planned_j(self) -> float:
        return self.pace.power_w * self.plan.planned_s

    @property
    def straight_j(self) -> float:
        return self.nominal.power_w * self.straight_s

    def gains(self) -> dict[str, float]:
        """[1] the time and energy saved over the straight line at the nominal pace."""
        return {"time": _saved(self.plan.planned_s, self.straight_s),
                "energy": _saved(self.planned_j, self.straight_j)}

    def to_json(self) -> dict:
        gains = self.gains()
        return {"pitch_rad": self.pace.pitch_rad, "pace_speed_mps": self.pace.speed_mps,
                "power_w": self.pace.power_w, "nominal_pitch_rad": self.nominal.pitch_rad,
                "straight_nominal_s": finite_or_none(self.straight_s),
                "straight_nominal_j": finite_or_none(self.straight_j), "planned_j": self.planned_j,
                "time_gain": gains["time"], "energy_gain": gains["energy"]}


def _saved(planned: float, straight: float) -> float:
    return 1.0 - planned / straight if math.isfinite(straight) else 1.0


def paces(transit_speed_mps: float, waypoints: list[tuple[float, float]]
          ) -> tuple[Pace, list[Pace]]:
    """(the pace at TRANSIT_PITCH_RAD, the paces of PITCHES_DEG the flight model can fly)
    of the glider of `transit_mission` along `waypoints`, whose transit speed at
    TRANSIT_PITCH_RAD is `transit_speed_mps`."""
    from gliderplan.language import check_source
    from gliderplan.planner.forecast import forecast_mission
    from gliderplan.power_models import load_vehicle
    from gliderplan.power_models.flight import FlightModelError

    low, high = TRANSIT_BAND_M

    def yo_speed_mps(vehicle: Vehicle, pitch_rad: float) -> float:
        time_s, _, distance_m = vehicle.yo_cycle(low, high, pitch_rad,
                                                 vehicle.unplanned_ballast_cc)
        return float(distance_m / time_s)

    def pace(pitch_rad: float) -> Pace:
        mission = check_source(transit_mission(waypoints, PACE_DAY_S, pitch_rad=pitch_rad),
                               "<route>").checked()
        forecast = forecast_mission(mission, duration_s=PACE_DAY_S, draws=PACE_DRAWS)
        vehicle = load_vehicle(mission.vehicle)
        ratio = yo_speed_mps(vehicle, pitch_rad) / yo_speed_mps(vehicle, TRANSIT_PITCH_RAD)
        return Pace(pitch_rad, transit_speed_mps * ratio,
                    forecast.energy_j / forecast.duration_s)

    flown = []
    for deg in PITCHES_DEG:
        try:
            flown.append(pace(math.radians(deg)))
        except FlightModelError:  # a pitch the glider cannot fly at the full stroke
            continue
    return pace(TRANSIT_PITCH_RAD), flown


def plan_paced_route(field: CurrentField, start: tuple[float, float],
                     waypoints: list[tuple[float, float]], epoch_s: float, nominal: Pace,
                     choices: list[Pace], minimise: str, cells: int = 100) -> PacedRoute:
    """The route and pace of `choices` that reach the waypoints in the least time or
    energy (`minimise`), against the straight line at `nominal`; NoRoute where no pace
    reaches them."""
    best: tuple[float, RoutePlan, Pace] | None = None
    for pace in choices:
        try:
            plan = plan_route(field, start, waypoints, epoch_s, pace.speed_mps, cells)
        except NoRoute:
            continue
        cost = plan.planned_s * (pace.power_w if minimise == "energy" else 1.0)
        if best is None or cost < best[0]:
            best = (cost, plan, pace)
    if best is None:
        raise NoRoute("no route reaches the waypoints at any pitch of "
                      f"{', '.join(f'{d:g}' for d in PITCHES_DEG)} degrees: the current "
                      "holds the glider off them")
    return PacedRoute(best[1], best[2], nominal,
                      straight_s(field, start, waypoints, epoch_s, nominal.speed_mps))


def straight_s(field: CurrentField, start: tuple[float, float],
               waypoints: list[tuple[float, float]], epoch_s: float, speed_mps: float
               ) -> float:
    """[s] along the straight legs at `speed_mps`, each in the field as it is when the
    leg begins (inf: the current holds the glider off one)."""
    total, here = 0.0, start
    for waypoint in waypoints:
        total += path_time_s(field, [here, waypoint], epoch_s + total, speed_mps)
        if not math.isfinite(total):
            return math.inf
        here = waypoint
    return total
