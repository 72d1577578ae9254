"""Benchmark: energy of a 30-day mission timeline at 1 s, vectorised vs a plain Python loop.

    .venv/bin/python bench/bench_power.py [--days 30] [--loop-days DAYS]

Builds a yo timeline (glider slocum_g2_shallow, TS-7800 at 500 MHz, CTD + optode on a
duty cycle), evaluates it with `timeline.energy_per_step_j`, and times a plain Python
loop over the same steps (on the whole timeline, or on `--loop-days` of it scaled to the
full length: the loop is linear in the number of steps). Prints both times, the ratio,
and checks that both give the same energy.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from gliderplan.power_models import load_board, load_sensor, load_vehicle
from gliderplan.power_models.segments import GLIDE, IRIDIUM, PITCH, PUMP, SURFACE
from gliderplan.power_models.timeline import Timeline, energy_per_step_j


def yo_timeline(days: float, vehicle, dt_s: float = 1.0) -> Timeline:  # noqa: ANN001
    """Yo 3-38 m at 26 deg and max ballast; a 15-min surfacing (5 min Iridium) every 6 h;
    board busy 20 %; CTD on 50 % and optode 25 % in 10-min periods."""
    n = int(days * 86400 / dt_s)
    t = np.arange(n) * dt_s
    pitch, ballast = math.radians(26.0), vehicle.max_ballast_cc
    _, w = vehicle.glide(pitch, ballast)
    half_s = (38.0 - 3.0) / float(w)
    pump_s = float(vehicle.pump_time_s(2 * ballast))
    cycle_s = 2 * (half_s + pump_s)
    in_cycle = t % cycle_s
    # pump in at the top, dive, pump out at the bottom, climb
    depth = np.where(
        in_cycle < pump_s,
        3.0,
        np.where(
            in_cycle < pump_s + half_s,
            3.0 + (in_cycle - pump_s) * w,
            np.where(
                in_cycle < 2 * pump_s + half_s, 38.0, 38.0 - (in_cycle - 2 * pump_s - half_s) * w
            ),
        ),
    )
    top_start = in_cycle < dt_s
    bottom_start = np.abs(in_cycle - (pump_s + half_s)) < dt_s / 2
    phase = np.full(n, GLIDE, np.int8)
    pumping = (in_cycle < pump_s) | (
        (in_cycle >= pump_s + half_s) & (in_cycle < 2 * pump_s + half_s)
    )
    phase[pumping] = PUMP
    in_surfacing = t % (6 * 3600)
    phase[in_surfacing < 900] = SURFACE
    phase[(in_surfacing >= 600) & (in_surfacing < 900)] = IRIDIUM
    gliding = (phase != SURFACE) & (phase != IRIDIUM)
    depth = np.where(gliding, depth, 0.0)
    return Timeline(
        dt_s=dt_s,
        phase=phase,
        depth_m=depth,
        pumped_out_cc=np.where(bottom_start & gliding, 2 * ballast, 0.0),
        pumped_in_cc=np.where(top_start & gliding, 2 * ballast, 0.0),
        inflection=(top_start | bottom_start) & gliding,
        board_busy=np.full(n, 0.2),
        sensor_on=np.stack([(t % 600) < 300, (t % 600) < 150]),
    )


def loop_energy_j(timeline: Timeline, vehicle, board, sensors, steps: int) -> float:  # noqa: ANN001
    """The baseline: the same energy, one step at a time in plain Python."""
    base = {
        GLIDE: vehicle.hotel_w,
        PUMP: vehicle.hotel_w,
        PITCH: vehicle.hotel_w,
        SURFACE: vehicle.surface_w,
        IRIDIUM: vehicle.iridium_w,
    }
    phase = timeline.phase.tolist()
    depth = timeline.depth_m.tolist()
    out_cc = timeline.pumped_out_cc.tolist()
    in_cc = timeline.pumped_in_cc.tolist()
    inflection = timeline.inflection.tolist()
    busy = timeline.board_busy.tolist()
    on = [row.tolist() for row in timeline.sensor_on]
    dt = timeline.dt_s
    total = 0.0
    for i in range(steps):
        busy_i = min(max(busy[i], 0.0), 1.0)
        power = base[phase[i]] + board.idle_w + (board.active_w - board.idle_w) * busy_i
        energy = power * dt
        energy += (vehicle.pump_out_j_per_cc + vehicle.pump_out_j_per_cc_m * depth[i]) * out_cc[i]
        pump_in = vehicle.pump_in_j_per_cc + vehicle.pump_in_j_per_cc_m * depth[i]
        energy += max(pump_in, 0.0) * in_cc[i]
        if inflection[i]:
            energy += vehicle.pitch_energy_j
        for k, sensor in enumerate(sensors):
            if on[k][i]:
                energy += sensor.on_power_w * dt
                if i == 0 or not on[k][i - 1]:
                    energy += sensor.warmup_j
        total += energy
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--days", type=float, default=30.0)
    parser.add_argument(
        "--loop-days",
        type=float,
        default=None,
        help="time the loop on this many days only, scaled to --days (default: the whole timeline)",
    )
    args = parser.parse_args()
    vehicle, board = load_vehicle("slocum_g2_shallow"), load_board("ts7800@500")
    sensors = [load_sensor("ctd"), load_sensor("optode")]
    timeline = yo_timeline(args.days, vehicle)
    steps = timeline.phase.size

    energy_per_step_j(timeline, vehicle, board, sensors)  # warm-up (page in, allocate)
    runs = []
    for _ in range(5):
        start = time.perf_counter()
        energy = energy_per_step_j(timeline, vehicle, board, sensors)
        runs.append(time.perf_counter() - start)
    vector_s = min(runs)

    loop_days = args.days if args.loop_days is None else args.loop_days
    loop_steps = min(steps, int(loop_days * 86400 / timeline.dt_s))
    start = time.perf_counter()
    loop_total = loop_energy_j(timeline, vehicle, board, sensors, loop_steps)
    loop_s = (time.perf_counter() - start) * steps / loop_steps

    agree = math.isclose(loop_total, float(energy[:loop_steps].sum()), rel_tol=1e-9)
    print(f"timeline: {args.days:g} days at {timeline.dt_s:g} s = {steps:,} steps")
    print(f"mission energy: {energy.sum() / 1e6:.2f} MJ ({energy.sum() / 3.6e6:.2f} kWh)")
    print(f"vectorised (numpy):   {vector_s:8.3f} s  (best of 5)")
    scaled = "" if loop_steps == steps else f"  (timed on {loop_steps:,} steps, scaled)"
    print(f"plain Python loop:    {loop_s:8.3f} s{scaled}")
    print(f"speed-up: {loop_s / vector_s:.0f}x; loop and vectorised agree: {agree}")
    if not agree:
        raise SystemExit("the loop and the vectorised energy differ")


if __name__ == "__main__":
    main()
