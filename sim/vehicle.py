"""The simulated glider: what the glider's own layered control does with a COMMAND.

Each tick the glider pumps toward the commanded buoyancy volume at the pump rate (an
inflection: no distance covered while pumping, nor while it turns for the vehicle's turn
time after the pump run), moves its battery toward the commanded pitch, and glides the
rest of the tick at the steady-glide speeds of `power_models.flight` for that pitch and
its net buoyancy at its depth (pumped volume, trim, the hull squeezed by sea pressure).
Commanded to the surface it climbs, takes a GPS fix (`surface_s`) that resets its dead
reckoning, makes its Iridium call (`iridium_s`) and waits there. It cannot go below the
sea floor (`floor_m`, which the science computer sets each tick): a glide or a hover
that would take it deeper stops at the floor, and the tick counts as grounded. Horizontally it flies
the commanded heading (upstream of it, with current correction: `sim.navigation`); the
current drifts the true position, and the glider's estimate, which it reports (Slocum
DDMM.MMMM), moves with the current it measured at its last GPS fix (`measured`), the
fix correcting both.

Through a stratified ocean (`Stratification`: `sim --ocean`) the net buoyancy carries the
water's in-situ density at the glider's depth, (Vg - trim)(1 - rho0 / rho(z)) (flight.py's
model), the glider trimmed in water of rho0 (`Vehicle.ballasted_for`); without one it
flies uniform water of its reference density.

One `GliderSim` is stepped once per tick; it is mutable for speed (a 30-day run is
650 000 ticks) and its per-tick outputs feed `power_models.timeline`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gliderplan.power_models.flight import (
    DensityProfile,
    FlightParams,
    glide_geometry,
    net_buoyancy_cc,
)
from gliderplan.power_models.propulsion import thrust_assisted_speed
from gliderplan.power_models.segments import GLIDE, IRIDIUM, MIN_PUMPED_CC, PUMP, SURFACE
from gliderplan.power_models.vehicle import Vehicle
from gliderplan.sim.geo import move_degrees, offset_m
from gliderplan.sim.navigation import corrected_heading, updated_current

SURFACE_DEPTH_M = 0.3  # shallower than this the antenna is out of the water
HOVER_RATE_M_S = 0.05  # assumption: small buoyancy corrections move a hovering glider slowly
# assumption: a propelled vehicle changes depth along a path at most this steep (a glider's
# nominal 26 deg; a LAUV's fins allow more, which only shortens the dive to its depth)
PROPELLED_PATH_RAD = 0.454
PITCH_RATE_RAD_S = 0.1  # assumption: the battery moves ~26 deg in under 5 s
MAX_CURRENT_MPS = 10.0  # [m s-1] beyond any ocean current (the Gulf Stream's core: ~2.5)


@dataclass(frozen=True)
class Current:
    """Depth-averaged current [m s-1] toward the north and the east."""

    north_mps: float = 0.0
    east_mps: float = 0.0


STRATIFICATION_STEP_M = 1.0  # [m] between the depths the water's buoyancy is tabled at


@dataclass(frozen=True)
class Stratification:
    """The buoyancy [cc] the water's density adds to a glider at each depth,
    (Vg - trim)(1 - rho0 / rho(z)) (`flight.net_buoyancy_cc` with an in-situ density),
    tabled every `step_m` [m] from the surface, linear between, held beyond the last. One
    interpolation, written alike here (`at`) and in sim/flight.c, so that the two loops
    add the very same numbers."""

    step_m: float
    lift_cc: tuple[float, ...]

    @classmethod
    def of(cls, flight: FlightParams, water: DensityProfile) -> Stratification:
        """The table of a glider of `flight` through `water` to its deepest depth."""
        depths = np.arange(0.0, float(np.max(water.depth_m)) + STRATIFICATION_STEP_M,
                           STRATIFICATION_STEP_M)
        lift = net_buoyancy_cc(flight, 0.0, depths, water.at(depths)) \
            - net_buoyancy_cc(flight, 0.0, depths)
        return cls(STRATIFICATION_STEP_M, tuple(float(v) for v in lift))

    def at(self, depth_m: float) -> float:
        """[cc] at one depth [m]."""
        x = depth_m / self.step_m
        last = len(self.lift_cc) - 1
        if not x < last:  # beyond the table (or NaN)
            return self.lift_cc[last]
        if x <= 0.0:
            return self.lift_cc[0]
        i = int(x)
        return self.lift_cc[i] + (self.lift_cc[i + 1] - self.lift_cc[i]) * (x - i)


class GliderSim:
    """The glider's motion, stepped once per tick of `tick_s` [s].

    Outputs of the last step (for the energy timeline): `phase` (segments.GLIDE, PUMP,
    SURFACE or IRIDIUM), `pumped_out_cc`, `pumped_in_cc`, `inflection` (the battery
    moved for a turn), and the count of surfacings.
    """

    def __init__(self, vehicle: Vehicle, tick_s: float, lat_deg: float, lon_deg: float,
                 current: Current = Current(), depth_m: float = 0.0,
                 water: DensityProfile | None = None, correction_speed_mps: float = 0.0,
                 measured: Current = Current()) -> None:
        """`water`: the in-situ density the glider flies through (None: uniform water of
        its reference density). `correction_speed_mps` [m s-1]: the speed through the
        water its current correction steers with (0: no current correction);
        `measured`: the depth-averaged current it knows at the start (`m_water_vx/vy`)."""
        self.vehicle = vehicle
        self.stratification = None if water is None else Stratification.of(vehicle.flight,
                                                                           water)
        self.tick_s = tick_s
        self.current = current
        self.depth_m = depth_m
        self.pitch_rad = 0.0
        self.ballast_cc = 0.0  # pumped volume from neutral, positive buoyant
        self.heading_rad = 0.0
        self.lat_deg, self.lon_deg = lat_deg, lon_deg  # true position
        self.dr_lat_deg, self.dr_lon_deg = lat_deg, lon_deg  # dead reckoning
        self.measured = measured  # the current its dead reckoning flies with
        self.ticks_since_fix = 0  # ticks dead reckoned since the last GPS fix
        self.correction_speed_mps = correction_speed_mps
        self.surface_time_s = -1.0  # time at the surface in this surfacing; < 0: not surfaced
        self.surfacings = 0
        self.phase = GLIDE
        self.pumped_out_cc = 0.0
        self.pumped_in_cc = 0.0
        self.inflection = False
        self._turning_to = 0.0  # sign of the buoyancy the last inflection went to
        self._turn_left_s = 0.0  # time the current inflection still turns after pumping
        self._geometry: dict[float, tuple[float, float]] = {}
        self.floor_m = math.inf  # [m] the sea floor under the glider this tick (inf: none)
        self.grounded = False  # the last step stopped at the sea floor
        self.propulsion_w = 0.0  # [W] the propeller's or thruster's draw in the last step

    def glide_speeds(self, pitch_rad: float) -> tuple[float, float]:
        """(u, w) [m s-1] per square root of the net buoyancy [cc] at a pitch [rad]
        magnitude; commands repeat, so the angle-of-attack solve runs once per pitch."""
        if pitch_rad <= 0.0 or pitch_rad >= math.pi / 2:
            return 0.0, 0.0
        per_root = self._geometry.get(pitch_rad)
        if per_root is None:
            gamma, speed = glide_geometry(self.vehicle.flight, pitch_rad)
            per_root = (float(speed * math.cos(gamma)), float(speed * math.sin(gamma)))
            self._geometry[pitch_rad] = per_root
        return per_root

    def step(self, depth_target_m: float, pitch_rad: float, ballast_cc: float,
             heading_rad: float, heading_valid: bool, surface: bool, speed_mps: float = 0.0,
             thrust_w: float = 0.0, corrects: bool = True) -> None:
        """Fly one tick under a command (COMMAND fields, docs/protocol.md): with a speed
        [m/s] level on the propeller, else a glide (assisted by `thrust_w` [W] of a
        thruster) or a hover. `corrects`: False for a heading held as it is
        (FLAG_HEADING_HOLD), which the current correction leaves alone."""
        self.pumped_out_cc = self.pumped_in_cc = 0.0
        self.inflection = self.grounded = False
        self.propulsion_w = 0.0
        propulsion = self.vehicle.propulsion
        if heading_valid:
            self.heading_rad = self._steered(heading_rad, speed_mps) if corrects else heading_rad
        if surface and self.depth_m <= SURFACE_DEPTH_M:
            self._at_surface(self.tick_s)
            return
        self.surface_time_s = -1.0
        if speed_mps > 0.0 and propulsion is not None:
            dz, distance = self._propelled(depth_target_m, speed_mps)
            hovering = False
        else:
            dz, distance, hovering = self.below_surface(depth_target_m, pitch_rad, ballast_cc)
            if thrust_w > 0.0 and propulsion is not None and propulsion.is_thruster:
                dz, distance = self._assisted(dz, distance, thrust_w)
        depth = self.depth_m + dz if hovering else max(0.0, self.depth_m + dz)
        if depth > self.floor_m:  # the sea floor stops it
            depth, self.grounded = self.floor_m, True
        self.depth_m = depth
        self._drift(distance, self.tick_s)

    def _steered(self, heading_rad: float, speed_mps: float) -> float:
        """[rad] the heading flown for a course `heading_rad` under the current correction
        (none: the course itself), at `speed_mps` on the propeller, else at the glide's."""
        propulsion = self.vehicle.propulsion
        through = self.correction_speed_mps
        if through and speed_mps > 0.0 and propulsion is not None:  # on the propeller
            through = min(max(speed_mps, propulsion.min_speed_mps), propulsion.max_speed_mps)
        return heading_rad if not through else corrected_heading(
            heading_rad, through, self.measured.north_mps, self.measured.east_mps)

    def _propelled(self, depth_target_m: float, speed_mps: float) -> tuple[float, float]:
        """One tick on the propeller at `speed_mps` through the water (held to the
        propulsion model's range), toward the target depth along a path no steeper than
        PROPELLED_PATH_RAD; its draw from the model. Returns (depth change [m], horizontal
        distance through the water [m])."""
        propulsion = self.vehicle.propulsion
        speed = min(max(speed_mps, propulsion.min_speed_mps), propulsion.max_speed_mps)
        self.propulsion_w = float(propulsion.power_w(speed))
        self.phase = GLIDE
        path = speed * self.tick_s
        most = path * math.sin(PROPELLED_PATH_RAD)
        dz = min(max(depth_target_m - self.depth_m, -most), most)
        self.pitch_rad = -math.asin(dz / path)  # nose down to dive
        return dz, math.sqrt(path * path - dz * dz)

    def _assisted(self, dz_m: float, distance_m: float, thrust_w: float
                  ) -> tuple[float, float]:
        """A glide tick with the thruster commanded to `thrust_w` [W]: faster along the same
        path by `thrust_assisted_speed` (the planner's model), drawing its power. Returns
        (depth change [m], distance [m])."""
        propulsion, fl = self.vehicle.propulsion, self.vehicle.flight
        self.propulsion_w = propulsion.assist_draw_w(thrust_w)
        speed = distance_m / self.tick_s
        if speed <= 0.0:  # pumping or turning in place: the thruster runs, nothing moves
            return dz_m, distance_m
        faster = float(thrust_assisted_speed(speed, propulsion.thrust_power_w(thrust_w),
                                             fl.rho_kg_m3, fl.wing_area_m2, fl.drag_cd0)) / speed
        return dz_m * faster, distance_m * faster

    def below_surface(self, depth_target_m: float, pitch_rad: float, ballast_cc: float
                      ) -> tuple[float, float, bool]:
        """One tick under water: the battery, the pump and the turn move toward the command
        (outputs and internal state updated), then the glider glides (or hovers, on zero
        buoyancy). Returns (depth change [m], distance through the water [m], hovering);
        a glide's depth is clamped at the surface by the caller, a hover's is not."""
        glide_s, pitch_rad = self._actuate(pitch_rad, ballast_cc)
        if ballast_cc == 0.0 and self.ballast_cc == 0.0:
            # hovering: small buoyancy corrections toward the target depth
            step_m = min(abs(depth_target_m - self.depth_m), HOVER_RATE_M_S * self.tick_s)
            return math.copysign(step_m, depth_target_m - self.depth_m), 0.0, True
        dz, distance = self.glide_rates(self.glide_speeds(abs(pitch_rad)), self.ballast_cc,
                                        glide_s, self.depth_m)
        return dz, distance, False

    def _actuate(self, pitch_rad: float, ballast_cc: float) -> tuple[float, float]:
        """The battery, the pump and the turn move toward a command for one tick (outputs
        and internal state updated). Returns (the time left to glide [s], the pitch the
        servo settles at for the command [rad])."""
        dt = self.tick_s
        v = self.vehicle
        # battery: toward the pitch the servo settles at for the command, at the motor's rate
        if pitch_rad != 0.0:
            error = v.climb_pitch_error_rad if pitch_rad > 0.0 else v.dive_pitch_error_rad
            pitch_rad = math.copysign(abs(pitch_rad) + error, pitch_rad)
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
        return glide_s, pitch_rad

    def glide_rates(self, per_root: tuple[float, float], ballast_cc: float, glide_s: float,
                    depth_m: float) -> tuple[float, float]:
        """(depth change [m], distance through the water [m]) of a tick that glides
        `glide_s` [s] from `depth_m` [m] with `ballast_cc` pumped, at a pitch whose speeds
        per square root of the net buoyancy are `per_root`: `below_surface`'s glide."""
        net = net_buoyancy_cc(self.vehicle.flight, ballast_cc, depth_m)
        if self.stratification is not None:
            net = net + self.stratification.at(depth_m)
        root = math.sqrt(max(math.copysign(1.0, ballast_cc) * net, 0.0))
        u, w = per_root[0] * root, per_root[1] * root
        return (-w if ballast_cc > 0.0 else w) * glide_s, u * glide_s

    @property
    def flows(self) -> bool:
        """Whether a current moves the glider or its estimate."""
        c, m = self.current, self.measured
        return c.north_mps != 0.0 or c.east_mps != 0.0 or m.north_mps != 0.0 \
            or m.east_mps != 0.0

    def _fix(self) -> None:
        """A GPS fix: the measured current corrected by the fix's distance from the
        estimate over the time since the previous fix, the estimate set to the fix."""
        north, east = offset_m(self.dr_lat_deg, self.dr_lon_deg, self.lat_deg, self.lon_deg)
        self.measured = Current(*updated_current(
            self.measured.north_mps, self.measured.east_mps, north, east,
            self.ticks_since_fix * self.tick_s))
        self.ticks_since_fix = 0
        self.dr_lat_deg, self.dr_lon_deg = self.lat_deg, self.lon_deg

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
            self._fix()
        in_call = v.surface_s <= elapsed < v.surface_s + v.iridium_s
        self.phase = IRIDIUM if in_call else SURFACE
        self._drift(0.0, dt)

    def _drift(self, distance_m: float, dt: float) -> None:
        """Move `distance_m` [m] along the heading through the water, plus the current;
        the estimate with the current measured."""
        north = distance_m * math.cos(self.heading_rad)
        east = distance_m * math.sin(self.heading_rad)
        m = self.measured
        dr_north, dr_east = north + m.north_mps * dt, east + m.east_mps * dt
        if dr_north or dr_east:
            self.dr_lat_deg, self.dr_lon_deg = move_degrees(self.dr_lat_deg, self.dr_lon_deg,
                                                            dr_north, dr_east)
        self.ticks_since_fix += 1
        if not self.flows:
            self.lat_deg, self.lon_deg = self.dr_lat_deg, self.dr_lon_deg
            return
        c = self.current
        north += c.north_mps * dt
        east += c.east_mps * dt
        self.lat_deg, self.lon_deg = move_degrees(self.lat_deg, self.lon_deg, north, east)
