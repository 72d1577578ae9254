"""The simulated glider: what the glider's own layered control does with a COMMAND.

Each tick the glider pumps toward the commanded buoyancy volume at the pump rate (an
inflection: no distance covered while pumping, nor while it turns for the vehicle's turn
time after the pump run), moves its battery toward the commanded pitch, and glides the
rest of the tick at the steady-glide speeds of `power_models.flight` for that pitch and
its net buoyancy at its depth (pumped volume, trim, the hull squeezed by sea pressure).
Commanded to the surface it climbs, takes a GPS fix (`surface_s`) that resets its dead
reckoning, makes its Iridium call (`iridium_s`) and waits there. Horizontally it flies
the commanded heading; a depth-averaged current drifts the true position but not the
dead-reckoned one, which is what the glider reports (Slocum DDMM.MMMM) until the next fix.

One `GliderSim` is stepped once per tick; it is mutable for speed (a 30-day run is
650 000 ticks) and its per-tick outputs feed `power_models.timeline`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gliderplan.power_models.flight import glide_geometry, net_buoyancy_cc
from gliderplan.power_models.segments import GLIDE, IRIDIUM, MIN_PUMPED_CC, PUMP, SURFACE
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.sim.geo import move_degrees

SURFACE_DEPTH_M = 0.3  # shallower than this the antenna is out of the water
HOVER_RATE_M_S = 0.05  # assumption: small buoyancy corrections move a hovering glider slowly
PITCH_RATE_RAD_S = 0.1  # assumption: the battery moves ~26 deg in under 5 s


@dataclass(frozen=True)
class Current:
    """Depth-averaged current [m s-1] toward the north and the east."""

    north_mps: float = 0.0
    east_mps: float = 0.0


class GliderSim:
    """The glider's motion, stepped once per tick of `tick_s` [s].

    Outputs of the last step (for the energy timeline): `phase` (segments.GLIDE, PUMP,
    SURFACE or IRIDIUM), `pumped_out_cc`, `pumped_in_cc`, `inflection` (the battery
    moved for a turn), and the count of surfacings.
    """

    def __init__(self, vehicle: Vehicle, tick_s: float, lat_deg: float, lon_deg: float,
                 current: Current = Current(), depth_m: float = 0.0) -> None:
        self.vehicle = vehicle
        self.tick_s = tick_s
        self.current = current
        self.depth_m = depth_m
        self.pitch_rad = 0.0
        self.ballast_cc = 0.0  # pumped volume from neutral, positive buoyant
        self.heading_rad = 0.0
        self.lat_deg, self.lon_deg = lat_deg, lon_deg  # true position
        self.dr_lat_deg, self.dr_lon_deg = lat_deg, lon_deg  # dead reckoning
        self.surface_time_s = -1.0  # time at the surface in this surfacing; < 0: not surfaced
        self.surfacings = 0
        self.phase = GLIDE
        self.pumped_out_cc = 0.0
        self.pumped_in_cc = 0.0
        self.inflection = False
        self._turning_to = 0.0  # sign of the buoyancy the last inflection went to
        self._turn_left_s = 0.0  # time the current inflection still turns after pumping
        self._geometry: dict[float, tuple[float, float]] = {}

    def _speeds(self, pitch_rad: float, ballast_cc: float) -> tuple[float, float]:
        """(u, w) [m s-1] magnitudes at the current depth with `ballast_cc` pumped (signed);
        commands repeat, so the angle-of-attack bisection runs once per pitch."""
        if pitch_rad <= 0.0 or pitch_rad >= math.pi / 2:
            return 0.0, 0.0
        per_root = self._geometry.get(pitch_rad)
        if per_root is None:
            gamma, speed = glide_geometry(self.vehicle.flight, pitch_rad)
            per_root = (float(speed * math.cos(gamma)), float(speed * math.sin(gamma)))
            self._geometry[pitch_rad] = per_root
        net = net_buoyancy_cc(self.vehicle.flight, ballast_cc, self.depth_m)
        root = math.sqrt(max(math.copysign(1.0, ballast_cc) * net, 0.0))
        return per_root[0] * root, per_root[1] * root

    def step(self, depth_target_m: float, pitch_rad: float, ballast_cc: float,
             heading_rad: float, heading_valid: bool, surface: bool) -> None:
        """Fly one tick under a command (COMMAND fields, docs/protocol.md)."""
        dt = self.tick_s
        v = self.vehicle
        self.pumped_out_cc = self.pumped_in_cc = 0.0
        self.inflection = False
        if heading_valid:
            self.heading_rad = heading_rad
        if surface and self.depth_m <= SURFACE_DEPTH_M:
            self._at_surface(dt)
            return
        self.surface_time_s = -1.0

        # battery: toward the commanded pitch at the motor's rate
        dp = pitch_rad - self.pitch_rad
        max_dp = PITCH_RATE_RAD_S * dt
        self.pitch_rad = pitch_rad if abs(dp) <= max_dp else self.pitch_rad + math.copysign(
            max_dp, dp)

        # pump: toward the commanded volume; the glider stands still while it runs
        glide_s = dt
        dv = ballast_cc - self.ballast_cc
        if dv != 0.0:
            moved = min(abs(dv), v.pump_rate_cc_s * dt)
            if dv > 0.0:
                self.pumped_out_cc = moved
            else:
                self.pumped_in_cc = moved
            self.ballast_cc = ballast_cc if moved == abs(dv) else self.ballast_cc + math.copysign(
                moved, dv)
            glide_s = dt - moved / v.pump_rate_cc_s
            going = math.copysign(1.0, dv)
            # smaller volume changes are trim, not an inflection (as in a real log)
            if abs(dv) >= MIN_PUMPED_CC and going != self._turning_to:
                self._turning_to = going
                self.inflection = True
                self._turn_left_s = v.bottom_turn_s if going > 0.0 else v.top_turn_s
        self.phase = PUMP if glide_s < dt else GLIDE
        if self._turn_left_s > 0.0 and self.ballast_cc == ballast_cc:
            turning = min(self._turn_left_s, glide_s)
            self._turn_left_s -= turning
            glide_s -= turning

        if ballast_cc == 0.0 and self.ballast_cc == 0.0:
            # hovering: small buoyancy corrections toward the target depth
            step_m = min(abs(depth_target_m - self.depth_m), HOVER_RATE_M_S * dt)
            self.depth_m += math.copysign(step_m, depth_target_m - self.depth_m)
            u = 0.0
        else:
            u, w = self._speeds(abs(pitch_rad), self.ballast_cc)
            rising = self.ballast_cc > 0.0
            self.depth_m = max(0.0, self.depth_m + (-w if rising else w) * glide_s)
        self._drift(u * glide_s, dt)

    def _at_surface(self, dt: float) -> None:
        """GPS fix, then the Iridium call, then wait (antenna up)."""
        v = self.vehicle
        self.depth_m = 0.0
        if self.surface_time_s < 0.0:
            self.surface_time_s = 0.0
            self.surfacings += 1
        elapsed = self.surface_time_s
        self.surface_time_s += dt
        if elapsed < v.surface_s <= self.surface_time_s:
            self.dr_lat_deg, self.dr_lon_deg = self.lat_deg, self.lon_deg  # GPS fix
        in_call = v.surface_s <= elapsed < v.surface_s + v.iridium_s
        self.phase = IRIDIUM if in_call else SURFACE
        self._drift(0.0, dt)

    def _drift(self, distance_m: float, dt: float) -> None:
        """Move `distance_m` [m] along the heading through the water, plus the current."""
        north = distance_m * math.cos(self.heading_rad)
        east = distance_m * math.sin(self.heading_rad)
        if north or east:
            self.dr_lat_deg, self.dr_lon_deg = move_degrees(self.dr_lat_deg, self.dr_lon_deg,
                                                            north, east)
        c = self.current
        if c.north_mps == 0.0 and c.east_mps == 0.0:
            self.lat_deg, self.lon_deg = self.dr_lat_deg, self.dr_lon_deg
            return
        north += c.north_mps * dt
        east += c.east_mps * dt
        self.lat_deg, self.lon_deg = move_degrees(self.lat_deg, self.lon_deg, north, east)
