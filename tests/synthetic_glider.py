"""A Slocum log of a glider whose figures are known, for the calibration tests.

The glider flies the steady-glide model of `power_models.flight` (with trim, hull
compressibility and a layered ocean) between its turns; a turn is a pump run at the pump
rate (logged as m_ballast_pumped_vel is) plus a turn time standing still; it surfaces
after its last dive for a GPS fix and an Iridium call. Its power is constant in each
phase, so the coulomb counter and the current sensor agree exactly. Devices may be given
a power and the dives they run in (submerged): their switches are logged, their power is
in the current.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from gliderplan.power_models import flight, load_vehicle
from gliderplan.power_models.slocum_log import FlightLog

HOTEL_W, SURFACE_W, IRIDIUM_W, VOLTS = 2.0, 4.0, 5.5, 14.0
PUMP_OUT_J_PER_CC, PUMP_OUT_J_PER_CC_M, PUMP_IN_J_PER_CC = 0.3, 0.012, 0.2
CD0, TRIM_CC, EPSILON = 0.16, 60.0, 6e-10
TOP_TURN_S, BOTTOM_TURN_S = 20.0, 12.0
PITCH_RAD, DIVE_PITCH_ERROR, CLIMB_PITCH_ERROR = 0.43, -0.03, -0.01
BALLAST_CC, TOP_M, PUMP_RATE_CC_S = 230.0, 3.0, 35.0
SURFACE_S, CALL_S = 130.0, 240.0
SAMPLE_S, STEP_S = 2.0, 0.25


def ocean(depth_m: np.ndarray) -> np.ndarray:
    """In-situ density [kg m-3]: 1023 at the surface, 1025 below a thermocline at ~12 m."""
    return 1023.0 + 2.0 / (1.0 + np.exp(-(np.asarray(depth_m) - 12.0) / 2.0))


def truth():
    """The base vehicle with the synthetic glider's flight figures and pump rate (energy
    figures apart)."""
    base = load_vehicle("slocum_g2_shallow")
    params = dataclasses.replace(base.flight, rho_kg_m3=1024.0, drag_cd0=CD0,
                                 trim_cc=TRIM_CC, compressibility_per_pa=EPSILON)
    return dataclasses.replace(base, flight=params, pump_rate_cc_s=PUMP_RATE_CC_S)


def synthetic_log(bottoms=(20.0, 40.0, 60.0, 40.0, 40.0, 40.0),
                  calls_s: tuple[float, ...] = (CALL_S,),
                  devices: dict[str, tuple[float, frozenset[int]]] | None = None) -> FlightLog:
    """100 s at the surface, a dive to each of `bottoms` (turning at TOP_M between them),
    the climb to the surface, a GPS fix and an Iridium call: one surfacing per call time in
    `calls_s`, evenly among the dives, the last after the last dive (the record ends in
    its call). `devices`: name -> (power [W], the dives (from 0) it is on in, while
    submerged)."""
    devices = devices or {}
    if len(bottoms) % len(calls_s):
        raise ValueError("the surfacings must split the dives evenly")
    per_surfacing = len(bottoms) // len(calls_s)
    vehicle = truth()
    rate = vehicle.pump_rate_cc_s
    rows = []  # (time, depth, pitch, ballast, commanded ballast, commanded pitch, power, flags,
    # pump velocity, each device on)
    state = {"t": 0.0, "z": 0.0, "ballast": vehicle.max_ballast_cc, "pitch": 0.0, "dive": -1}

    def record(power: float, command_cc: float, command_pitch: float, pump: bool = False,
               call: bool = False, velocity: float = 0.0) -> None:
        on = [state["dive"] in dives and state["z"] > 0.5 for _, dives in devices.values()]
        power += sum(w for (w, _), running in zip(devices.values(), on, strict=True)
                     if running)
        rows.append((state["t"], state["z"], state["pitch"], state["ballast"], command_cc,
                     command_pitch, power, pump, call, velocity, *on))

    def hold(seconds: float, power: float, command_cc: float, command_pitch: float,
             pump: bool = False, call: bool = False, to_cc: float | None = None) -> None:
        start_cc, steps = state["ballast"], max(int(round(seconds / STEP_S)), 1)
        velocity = 0.0 if to_cc is None else math.copysign(rate, to_cc - start_cc)
        for k in range(steps):
            state["t"] += seconds / steps
            if to_cc is not None:
                state["ballast"] = start_cc + (to_cc - start_cc) * (k + 1) / steps
            record(power, command_cc, command_pitch, pump, call, velocity)

    def turn(to_cc: float, command_pitch: float, top: bool) -> None:
        volume = abs(to_cc - state["ballast"])
        pumping = volume / rate
        per_cc = (PUMP_IN_J_PER_CC if top else PUMP_OUT_J_PER_CC
                  + PUMP_OUT_J_PER_CC_M * state["z"])
        hold(pumping, HOTEL_W + per_cc * volume / pumping, to_cc, command_pitch, pump=True,
             to_cc=to_cc)
        flown = PITCH_RAD + (CLIMB_PITCH_ERROR if to_cc > 0 else DIVE_PITCH_ERROR)
        state["pitch"] = math.copysign(flown, to_cc)
        hold(TOP_TURN_S if top else BOTTOM_TURN_S, HOTEL_W, to_cc, command_pitch)

    def glide(target_m: float, command_pitch: float) -> None:
        up = target_m < state["z"]
        gamma, per_root = flight.glide_geometry(vehicle.flight, abs(state["pitch"]))
        while (state["z"] > target_m) if up else (state["z"] < target_m):
            net = flight.net_buoyancy_cc(vehicle.flight, state["ballast"], state["z"],
                                         float(ocean(state["z"])))
            w = float(per_root * math.sin(gamma)) * math.sqrt(abs(net))
            step = min(STEP_S, abs(target_m - state["z"]) / w)
            state["t"] += step
            state["z"] += -w * step if up else w * step
            record(HOTEL_W, state["ballast"], command_pitch)

    hold(100.0, SURFACE_W, vehicle.max_ballast_cc, PITCH_RAD)
    for k, bottom in enumerate(bottoms):
        state["dive"] = k
        turn(-BALLAST_CC, -PITCH_RAD, top=True)
        glide(bottom, -PITCH_RAD)
        up = (k + 1) % per_surfacing == 0
        turn(vehicle.max_ballast_cc if up else BALLAST_CC, PITCH_RAD, top=False)
        glide(0.0 if up else TOP_M, PITCH_RAD)
        if up:
            hold(SURFACE_S, SURFACE_W, vehicle.max_ballast_cc, math.nan)
            hold(calls_s[k // per_surfacing], IRIDIUM_W, vehicle.max_ballast_cc, math.nan,
                 call=True)
    return _sampled(np.array(rows, float), tuple(devices))


def _sampled(rows: np.ndarray, devices: tuple[str, ...] = ()) -> FlightLog:
    """The fine steps read every SAMPLE_S seconds, as the flight computer logs."""
    t, depth, pitch, ballast, command_cc, command_pitch, power, pump, call, velocity = \
        rows.T[:10]
    switches = rows[:, 10:]
    energy = np.concatenate(([0.0], np.cumsum(power[1:] * np.diff(t))))
    pick = np.concatenate(([0], np.flatnonzero(np.diff(np.floor(t / SAMPLE_S)) > 0) + 1))
    # the current sensor averages over the sample interval around its reading
    window = np.interp(t[pick] + SAMPLE_S / 2, t, energy) - np.interp(t[pick] - SAMPLE_S / 2,
                                                                        t, energy)
    current = window / SAMPLE_S / VOLTS
    # a flag is seen at a sample if it was set at any step since the last one
    seen = [np.maximum.reduceat(flag, pick) > 0.5 for flag in (pump, call)]
    # the pump's velocity is logged on the cycles it moves
    moving = np.add.reduceat(velocity != 0.0, pick)
    pump_velocity = np.where(moving > 0, np.add.reduceat(velocity, pick) / np.maximum(moving, 1),
                             np.nan)
    return FlightLog(
        files=("synthetic",), start_epoch_s=0.0, t_s=t[pick], depth_m=depth[pick],
        pitch_rad=pitch[pick], ballast_cc=ballast[pick], current_a=current,
        charge_ah=energy[pick] / VOLTS / 3600.0, battery_v=np.full(pick.size, VOLTS),
        iridium_on=seen[1], pump_moving=seen[0], battpos_moving=np.zeros(pick.size, bool),
        density_kg_m3=ocean(depth[pick]), commanded_ballast_cc=command_cc[pick],
        commanded_pitch_rad=command_pitch[pick], pump_velocity_cc_s=pump_velocity,
        climb_target_m=TOP_M, dive_target_m=80.0, payload=("ctd",),
        ballast_limit_cc=truth().max_ballast_cc, device_names=devices,
        device_on=switches[pick] if devices else None,
    )
