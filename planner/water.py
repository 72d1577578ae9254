"""The water a plan is made for: the current on each leg of the mission's route, along
and across its track, for the planner to choose each propelled state's speed on
(`planner.speed`).

A state's route legs run from where the previous state's route left the vehicle (the
first from the start) through its waypoints, as the planner times transit legs
(`planner.legs`). On each the current is the mean of the field at LEG_SAMPLES points
along it at the start time and at the state's cruise depth (the surface for another
profile): a plan holds one speed per state, chosen for its legs weighted by their
length. The field is `--currents` as the simulator and the forecast read it
(`sim.current_files.checked_field`: N,E, a NetCDF field or a glider's logs).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from gliderplan.language import ir
from gliderplan.planner.legs import Position, distance_m, offset_m, route_targets
from gliderplan.planner.speed import Leg
from gliderplan.sim.currents import CurrentField

if TYPE_CHECKING:
    from gliderplan.planner.hardware import Hardware

LEG_SAMPLES = 11  # points along a leg the current is averaged over
MIN_LEG_M = 1.0  # [m] a leg shorter than this (the start on a waypoint) has no direction


def track_unit(a: Position, b: Position) -> tuple[float, float]:
    """(north, east) unit vector of the track from `a` to `b` [deg]."""
    north, east = offset_m(a, b)
    length = math.hypot(north, east)
    return north / length, east / length


def cruise_depth_m(state: ir.State) -> float:
    """[m] the depth the state's first `cruise` with a written depth holds, else 0."""
    for profile in state.profiles:
        args = profile.constant_args()
        if profile.kind == "cruise" and args is not None:
            return float(args[0])
    return 0.0


def leg_current(field: CurrentField, a: Position, b: Position, epoch_s: float,
                depth_m: float) -> tuple[float, float]:
    """(along, across) [m s-1] the mean current from `a` to `b` [deg] resolved on the
    track (along: positive with it); NaN where the field has no water."""
    f = np.linspace(0.0, 1.0, LEG_SAMPLES)
    north, east = field.along(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), epoch_s,
                              depth_m)
    n, e = float(np.mean(north)), float(np.mean(east))
    un, ue = track_unit(a, b)
    return n * un + e * ue, n * ue - e * un


def route_legs(mission: ir.CheckedMission, field: CurrentField, start: Position,
               epoch_s: float) -> dict[str, tuple[Leg, ...]]:
    """Per state with waypoints, its route's legs in `field` from `start` [deg] at
    `epoch_s` [s since 1970]; states without waypoints are left out (still water)."""
    legs: dict[str, tuple[Leg, ...]] = {}
    here = start
    for state in mission.states:
        targets = route_targets(state.route)
        depth = cruise_depth_m(state)
        found = []
        for k, target in enumerate(targets, 1):
            length = distance_m(here, target)
            if length >= MIN_LEG_M:
                along, across = leg_current(field, here, target, epoch_s, depth)
                found.append(Leg(f"state {state.name}: leg {k} to {target[0]:.5f}, "
                                 f"{target[1]:.5f}", length, along, across))
            here = target
        if found:
            legs[state.name] = tuple(found)
    return legs


def plan_water(mission: ir.CheckedMission, spec: str, start: Position | None,
               epoch_s: float) -> tuple[dict[str, tuple[Leg, ...]], tuple[str, ...]]:
    """(route legs, notes) of `mission` in the current of `--currents SPEC` (N,E, a NetCDF
    field or a directory of glider logs) from `start` [deg] (None: where the simulator
    puts the vehicle in) at `epoch_s` [s since 1970]. CurrentError where the field does
    not cover the route."""
    from gliderplan.power_models import load_vehicle
    from gliderplan.sim.current_files import checked_field
    from gliderplan.sim.loop import RunConfig, start_position

    start = start if start is not None else start_position(mission, RunConfig())
    field, notes = checked_field(spec, mission, load_vehicle(mission.vehicle), start,
                                 epoch_s, 0.0)
    notes.append(f"currents: each propelled state's speed chosen for the least energy per "
                 f"km over ground on its route from {start[0]:.5f}, {start[1]:.5f}")
    return route_legs(mission, field, start, epoch_s), tuple(notes)


def in_water(hardware: Hardware, mission: ir.CheckedMission, currents: str,
             start: Position | None = None, epoch_s: float | None = None) -> Hardware:
    """`hardware` planned in the current of `--currents` (`plan_water`; `epoch_s` None:
    the simulator's default start)."""
    from gliderplan.sim.loop import DEFAULT_START_EPOCH_S

    legs, notes = plan_water(mission, currents, start,
                             DEFAULT_START_EPOCH_S if epoch_s is None else epoch_s)
    return replace(hardware, legs=legs, water_notes=notes)
