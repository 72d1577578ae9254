"""Energy of a sampled mission timeline: every component at every step, vectorised.

The simulator, the calibration and the benchmark describe what the glider did as arrays
over time steps; this module turns them into energy per step with the power models, in
one pass of numpy operations (a 30-day timeline at 1 s is 2.6 million steps).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.contract import Component
from gliderplan.power_models.board import Board
from gliderplan.power_models.segments import GLIDE, IRIDIUM, PITCH, PUMP, SURFACE
from gliderplan.power_models.sensor import Sensor
from gliderplan.power_models.vehicle import Vehicle


@dataclass(frozen=True)
class Timeline:
    """What the glider does during each of n steps."""

    dt_s: np.ndarray | float  # (n,) or scalar [s] step lengths
    phase: np.ndarray  # (n,) int8: segments.GLIDE, SURFACE, IRIDIUM, PUMP or PITCH
    depth_m: np.ndarray  # (n,) [m]
    pumped_out_cc: np.ndarray  # (n,) [cc] pumped out during the step (0 if none)
    pumped_in_cc: np.ndarray  # (n,) [cc] pumped in during the step
    inflection: np.ndarray  # (n,) bool: the battery shifts for an inflection in this step
    board_busy: np.ndarray | None = None  # (n,) [1] busy fraction of the computer
    sensor_on: np.ndarray | None = None  # (k, n) bool: sensor k powered during the step


def energy_by_component_j(
    timeline: Timeline,
    vehicle: Vehicle,
    board: Board | None = None,
    sensors: list[Sensor] | tuple[Sensor, ...] = (),
    gliding_w: float | None = None,
) -> dict[str, np.ndarray]:
    """Energy [J] per step of each component: the vehicle's load by phase (hotel while it
    glides, at `gliding_w` [W], default its whole hotel load; surface, Iridium), pump runs,
    battery shifts, the computer and the sensors (with a warm-up at every switch-on). A
    missing board or sensor list contributes nothing."""
    phase, dt = timeline.phase, timeline.dt_s
    gliding = (phase == GLIDE) | (phase == PUMP) | (phase == PITCH)
    hotel_w = vehicle.hotel_w if gliding_w is None else gliding_w
    parts = {
        Component.HOTEL: np.where(gliding, hotel_w * dt, 0.0),
        Component.SURFACE: np.where(phase == SURFACE, vehicle.surface_w * dt, 0.0),
        Component.IRIDIUM: np.where(phase == IRIDIUM, vehicle.iridium_w * dt, 0.0),
        Component.PUMP: vehicle.pump_energy_j(timeline.depth_m, timeline.pumped_out_cc)
        + vehicle.pump_in_energy_j(timeline.depth_m, timeline.pumped_in_cc),
        Component.PITCH: np.where(timeline.inflection, vehicle.pitch_energy_j, 0.0),
    }
    if board is not None:
        busy = np.zeros(phase.shape) if timeline.board_busy is None else timeline.board_busy
        parts[Component.COMPUTER] = board.power_w(busy) * dt
    if sensors:
        parts[Component.SENSORS] = sum(sensor_energy_j(on, sensor, dt)
                                       for on, sensor in zip(timeline.sensor_on, sensors,
                                                             strict=True))
    return parts


def sensor_energy_j(on: np.ndarray, sensor: Sensor, dt_s: np.ndarray | float) -> np.ndarray:
    """Energy [J] per step of one sensor powered where `on` (n,) bool: its on power over
    the step, plus its warm-up in each step that switches it on (the first step counts
    as one when on)."""
    switched_on = on.copy()
    switched_on[1:] &= ~on[:-1]
    return on * (sensor.on_power_w * dt_s) + switched_on * sensor.warmup_j


def energy_per_step_j(
    timeline: Timeline,
    vehicle: Vehicle,
    board: Board | None = None,
    sensors: list[Sensor] | tuple[Sensor, ...] = (),
) -> np.ndarray:
    """Total energy [J] drawn in each step (the sum of `energy_by_component_j`)."""
    return sum(energy_by_component_j(timeline, vehicle, board, sensors).values())
