"""Energy of a sampled mission timeline: every component at every step, vectorised.

The simulator and the calibration describe what the glider did as arrays over time steps;
this module turns them into energy per step with the power models, in one pass of numpy
operations (a 30-day timeline at 1 s is 2.6 million steps).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gliderplan.power_models.board import Board
from gliderplan.power_models.segments import GLIDE, IRIDIUM, PITCH, PUMP, SURFACE
from gliderplan.power_models.sensor import Sensor
from gliderplan.power_models.vehicle import Vehicle


@dataclass(frozen=True)
class Timeline:
    """What the glider does at each of n steps of `dt_s` seconds."""

    dt_s: float
    phase: np.ndarray  # (n,) int8: segments.GLIDE, SURFACE, IRIDIUM, PUMP or PITCH
    depth_m: np.ndarray  # (n,) [m]
    pumped_out_cc: np.ndarray  # (n,) [cc] pumped out during the step (0 if none)
    pumped_in_cc: np.ndarray  # (n,) [cc] pumped in during the step
    inflection: np.ndarray  # (n,) bool: the battery shifts for an inflection in this step
    board_busy: np.ndarray  # (n,) [1] busy fraction of the computer
    sensor_on: np.ndarray  # (k, n) bool: sensor k powered during the step


def energy_per_step_j(
    timeline: Timeline, vehicle: Vehicle, board: Board, sensors: list[Sensor]
) -> np.ndarray:
    """Energy [J] drawn in each step: base load of the phase, computer, sensors (with a
    warm-up at every switch-on), pump runs and battery shifts."""
    base_w = np.zeros(5)
    base_w[[GLIDE, PUMP, PITCH]] = vehicle.hotel_w  # actuator energy is added per event
    base_w[SURFACE] = vehicle.surface_w
    base_w[IRIDIUM] = vehicle.iridium_w
    power = base_w[timeline.phase] + board.power_w(timeline.board_busy)
    energy = power * timeline.dt_s
    energy += vehicle.pump_energy_j(timeline.depth_m, timeline.pumped_out_cc)
    energy += vehicle.pump_in_energy_j(timeline.pumped_in_cc)
    energy += np.where(timeline.inflection, vehicle.pitch_energy_j, 0.0)
    if sensors:
        on = timeline.sensor_on
        on_w = np.array([s.on_power_w for s in sensors])[:, None]
        warmup_j = np.array([s.warmup_j for s in sensors])[:, None]
        switched_on = on & ~np.concatenate([np.zeros((on.shape[0], 1), bool), on[:, :-1]], axis=1)
        energy += (on * on_w * timeline.dt_s + switched_on * warmup_j).sum(axis=0)
    return energy
