"""The envelope guard, as the C runtime's (runtime/src/gp_envelope.c) holds each COMMAND:
depth, pitch, pumped volume, propelled speed and thruster power within the vehicle's
rating, a yo's band no thinner than its `min_yo_band`, its turns no closer than its pump's
full stroke, the pump's energy within its rated mean power, and every heading turned no
faster than its rated turn rate (docs/pilot.md, The envelope). Values are compared as the
runtime compares them: a COMMAND's binary32 fields against the envelope's doubles."""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from gliderplan.contract import Envelope, EnvelopeAction, EnvelopeLimit

_F32 = struct.Struct("<f")
_HOUR_S = 3600.0
LIMIT_NAMES = {EnvelopeLimit.DEPTH: "depth", EnvelopeLimit.PITCH: "pitch",
               EnvelopeLimit.BALLAST: "pumped volume", EnvelopeLimit.BAND: "yo band",
               EnvelopeLimit.INFLECTION: "time between inflections",
               EnvelopeLimit.SPEED: "speed", EnvelopeLimit.THRUST: "thruster power",
               EnvelopeLimit.PUMP_ENERGY: "pump energy within an hour"}
LIMIT_UNITS = {EnvelopeLimit.DEPTH: "m", EnvelopeLimit.PITCH: "rad", EnvelopeLimit.BALLAST: "cc",
               EnvelopeLimit.BAND: "m", EnvelopeLimit.INFLECTION: "s",
               EnvelopeLimit.SPEED: "m/s", EnvelopeLimit.THRUST: "W",
               EnvelopeLimit.PUMP_ENERGY: "J"}
# the limits the clamp action cannot hold at an edge: they end the flight
_ENDING = (EnvelopeLimit.BAND, EnvelopeLimit.INFLECTION, EnvelopeLimit.PUMP_ENERGY)


def f32(value: float) -> float:
    """`value` through binary32, as a COMMAND field carries it."""
    try:
        return _F32.unpack(_F32.pack(value))[0]
    except OverflowError:  # beyond binary32: C's conversion gives an infinity
        return math.copysign(math.inf, value)


@dataclass(frozen=True)
class Breach:
    """A limit one command broke: the value commanded and the bound, in LIMIT_UNITS."""

    limit: EnvelopeLimit
    value: float
    bound: float

    def text(self) -> str:
        """`depth 3000 m beyond the vehicle's 100 m`, as the runtime says it."""
        unit = LIMIT_UNITS[self.limit]
        return (f"{LIMIT_NAMES[self.limit]} {self.value:g} {unit} beyond the vehicle's "
                f"{self.bound:g} {unit}")


@dataclass
class Held:
    """One tick's command as the guard lets it go: [m, rad, cc, rad, m/s, W]."""

    target_m: float
    pitch_rad: float
    ballast_cc: float
    heading_rad: float
    speed_mps: float
    thrust_w: float


def _within(value: float, low: float, high: float) -> bool:
    """A speed or a thruster's power: 0 (off), or within [low, high]."""
    return value == 0.0 or low <= value <= high


def _edge(value: float, low: float, high: float) -> float:
    """The edge of {0} and [low, high] nearest `value` (not NaN), as a COMMAND carries it."""
    return f32(0.0 if value < 0.0 else low if value < low else high)


class EnvelopeGuard:
    """The guard's memory (a profile's turns, the heading's, the pump's work) and the
    check of one command."""

    def __init__(self, envelope: Envelope, max_ballast_cc: float) -> None:
        self.envelope, self.max_ballast_cc = envelope, max_ballast_cc
        self.last_turn_s = 0.0
        self.turned = False
        self.climbing = False
        self.held = False
        self.heading: float | None = None  # the last heading commanded [rad], None: none
        self.heading_s = 0.0
        self.ballast_cc: float | None = None  # the last volume commanded [cc], None: none
        self.pump_s = 0.0
        self.pump_j = 0.0  # the pump's energy not yet paid back at the rated mean power [J]

    def ends(self, breach: Breach | None) -> bool:
        """Whether a breach ends the mission (fault or surface) rather than being held."""
        if breach is None:
            return False
        return (self.envelope.action != EnvelopeAction.CLAMP or breach.limit in _ENDING
                or math.isnan(breach.value))

    def hold(self, entered: bool, yo_band: tuple[float, float] | None, time_s: float,
             depth_m: float, command: Held, climbing: bool, headed: bool) -> Breach | None:
        """The first limit broken or None; `command` is held at the envelope's edge with
        the clamp action. `depth_m` [m]: the reading, where the pump works; `headed`:
        the command carries a heading."""
        env = self.envelope
        found: Breach | None = None
        if yo_band is not None:
            lo, hi = yo_band
            if not 0.0 <= lo <= env.max_depth_m:
                found = Breach(EnvelopeLimit.DEPTH, lo, env.max_depth_m)
            elif not 0.0 <= hi <= env.max_depth_m:
                found = Breach(EnvelopeLimit.DEPTH, hi, env.max_depth_m)
            elif not hi - lo >= env.min_yo_band_m:
                found = Breach(EnvelopeLimit.BAND, hi - lo, env.min_yo_band_m)
        found = found or self._values(command)
        if entered:
            self.turned = False
        elif yo_band is not None and climbing != self.climbing:  # the yo turned
            since = time_s - self.last_turn_s
            # thrashing ends the flight even where a held value let it go on
            if self.turned and not since >= env.min_inflection_s and not self.ends(found):
                found = Breach(EnvelopeLimit.INFLECTION, since, env.min_inflection_s)
            self.turned = True
            self.last_turn_s = time_s
        self.climbing = climbing
        self._turn(time_s, command, headed)
        pump = self._pump(time_s, depth_m, command.ballast_cc)
        if pump is not None and not self.ends(found):  # as thrashing, it ends the flight
            found = pump
        self.held = found is not None and not self.ends(found)
        return found

    def _values(self, command: Held) -> Breach | None:
        env = self.envelope
        clamp = env.action == EnvelopeAction.CLAMP
        target, pitch, ballast = f32(command.target_m), f32(command.pitch_rad), \
            f32(command.ballast_cc)
        speed, thrust = f32(command.speed_mps), f32(command.thrust_w)
        found: list[Breach] = []
        if not 0.0 <= target <= env.max_depth_m:
            found.append(Breach(EnvelopeLimit.DEPTH, target, env.max_depth_m))
            if clamp and not math.isnan(target):
                command.target_m = 0.0 if target < 0 else f32(env.max_depth_m)
        if not abs(pitch) <= env.max_pitch_rad:
            found.append(Breach(EnvelopeLimit.PITCH, pitch, env.max_pitch_rad))
            if clamp and not math.isnan(pitch):
                command.pitch_rad = f32(math.copysign(env.max_pitch_rad, pitch))
        if not abs(ballast) <= self.max_ballast_cc:
            found.append(Breach(EnvelopeLimit.BALLAST, ballast, self.max_ballast_cc))
            if clamp and not math.isnan(ballast):
                command.ballast_cc = f32(math.copysign(self.max_ballast_cc, ballast))
        low, high = env.speed_range_mps
        if not _within(speed, low, high):
            found.append(Breach(EnvelopeLimit.SPEED, speed, high if speed > high else low))
            if clamp and not math.isnan(speed):
                command.speed_mps = _edge(speed, low, high)
        low, high = env.thrust_range_w
        if not _within(thrust, low, high):
            found.append(Breach(EnvelopeLimit.THRUST, thrust, high if thrust > high else low))
            if clamp and not math.isnan(thrust):
                command.thrust_w = _edge(thrust, low, high)
        return found[0] if found else None

    def _turn(self, time_s: float, command: Held, headed: bool) -> None:
        """The heading turns at most at the rated rate: whatever the route asks, the
        command turns toward it by no more than the vehicle turns in the time since the
        last command, and gets there. Under every action: a turn is flown, never refused."""
        heading = f32(command.heading_rad)
        if not headed or not math.isfinite(heading):
            self.heading = None  # no heading flown: the next one is taken as it is
            return
        if self.heading is not None:
            most = self.envelope.max_turn_rate_rad_s * (time_s - self.heading_s)
            turn = heading - self.heading
            turn = turn - 2.0 * math.pi if turn > math.pi else \
                turn + 2.0 * math.pi if turn < -math.pi else turn
            if abs(turn) > most:  # NaN (an infinite rate, no time since): any turn
                heading = self.heading + math.copysign(most if most > 0.0 else 0.0, turn)
                heading = heading + 2.0 * math.pi if heading < 0.0 else \
                    heading - 2.0 * math.pi if heading >= 2.0 * math.pi else heading
                heading = command.heading_rad = f32(heading)
        self.heading, self.heading_s = heading, time_s

    def _pump(self, time_s: float, depth_m: float, ballast_cc: float) -> Breach | None:
        """The pump's energy as a bucket paid back at the rated mean power: a volume moved
        out at depth z costs (a + b z) per cc, moved in max(0, a + b z); more than an
        hour's worth outstanding is a breach."""
        ballast = f32(ballast_cc)
        if not math.isfinite(ballast):
            return None  # the pumped volume's own limit says so
        if ballast == self.ballast_cc and self.pump_j == 0.0:  # most ticks: nothing owed
            self.pump_s = time_s
            return None
        env, pump = self.envelope, self.envelope.pump
        if self.ballast_cc is not None:
            z = depth_m if depth_m > 0.0 else 0.0  # NaN: no reading, the surface
            moved = ballast - self.ballast_cc
            per_cc = pump.out_j_per_cc + pump.out_j_per_cc_m * z if moved > 0.0 else \
                pump.in_j_per_cc + pump.in_j_per_cc_m * z
            owed = self.pump_j - env.max_pump_power_w * (time_s - self.pump_s)
            self.pump_j = (owed if owed > 0.0 else 0.0) + \
                (per_cc * abs(moved) if per_cc > 0.0 else 0.0)
        self.ballast_cc, self.pump_s = ballast, time_s
        hour_j = env.max_pump_power_w * _HOUR_S
        return Breach(EnvelopeLimit.PUMP_ENERGY, self.pump_j, hour_j) \
            if self.pump_j > hour_j else None
