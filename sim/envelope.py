"""The envelope guard, as the C runtime's (runtime/src/gp_envelope.c) holds each COMMAND:
depth, pitch and pumped volume within the vehicle's rating, a yo's band no thinner than
its `min_yo_band`, its turns no closer than its pump's full stroke (docs/pilot.md, The
envelope). Values are compared as the runtime compares them: a COMMAND's binary32
fields against the envelope's doubles."""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from gliderplan.contract import Envelope, EnvelopeAction, EnvelopeLimit

_F32 = struct.Struct("<f")
LIMIT_NAMES = {EnvelopeLimit.DEPTH: "depth", EnvelopeLimit.PITCH: "pitch",
               EnvelopeLimit.BALLAST: "pumped volume", EnvelopeLimit.BAND: "yo band",
               EnvelopeLimit.INFLECTION: "time between inflections"}
LIMIT_UNITS = {EnvelopeLimit.DEPTH: "m", EnvelopeLimit.PITCH: "rad", EnvelopeLimit.BALLAST: "cc",
         EnvelopeLimit.BAND: "m", EnvelopeLimit.INFLECTION: "s"}


def f32(value: float) -> float:
    """`value` through binary32, as a COMMAND field carries it."""
    try:
        return _F32.unpack(_F32.pack(value))[0]
    except OverflowError:  # beyond binary32: C's conversion gives an infinity
        return math.copysign(math.inf, value)


@dataclass(frozen=True)
class Breach:
    """A limit one command broke: the value commanded and the bound [m, rad, cc, m, s]."""

    limit: EnvelopeLimit
    value: float
    bound: float

    def text(self) -> str:
        """`depth 3000 m beyond the vehicle's 100 m`, as the runtime says it."""
        unit = LIMIT_UNITS[self.limit]
        return (f"{LIMIT_NAMES[self.limit]} {self.value:g} {unit} beyond the vehicle's "
                f"{self.bound:g} {unit}")


class EnvelopeGuard:
    """The guard's memory of a profile's turns, and the check of one command."""

    def __init__(self, envelope: Envelope, max_ballast_cc: float) -> None:
        self.envelope, self.max_ballast_cc = envelope, max_ballast_cc
        self.last_turn_s = 0.0
        self.turned = False
        self.climbing = False
        self.held = False

    def ends(self, breach: Breach | None) -> bool:
        """Whether a breach ends the mission (fault or surface) rather than being held."""
        if breach is None:
            return False
        return (self.envelope.action != EnvelopeAction.CLAMP
                or breach.limit in (EnvelopeLimit.BAND, EnvelopeLimit.INFLECTION)
                or math.isnan(breach.value))

    def hold(self, entered: bool, yo_band: tuple[float, float] | None, time_s: float,
             target_m: float, pitch_rad: float, ballast_cc: float, climbing: bool
             ) -> tuple[Breach | None, float, float, float]:
        """(the first limit broken or None, and the depth target [m], pitch [rad] and
        volume [cc] to command: held at the envelope's edge with the clamp action)."""
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
        values, target_m, pitch_rad, ballast_cc = self._values(target_m, pitch_rad, ballast_cc)
        found = found or values
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
        self.held = found is not None and not self.ends(found)
        return found, target_m, pitch_rad, ballast_cc

    def _values(self, target_m: float, pitch_rad: float, ballast_cc: float
                ) -> tuple[Breach | None, float, float, float]:
        env = self.envelope
        clamp = env.action == EnvelopeAction.CLAMP
        target, pitch, ballast = f32(target_m), f32(pitch_rad), f32(ballast_cc)
        found: list[Breach] = []
        if not 0.0 <= target <= env.max_depth_m:
            found.append(Breach(EnvelopeLimit.DEPTH, target, env.max_depth_m))
            if clamp and not math.isnan(target):
                target_m = 0.0 if target < 0 else f32(env.max_depth_m)
        if not abs(pitch) <= env.max_pitch_rad:
            found.append(Breach(EnvelopeLimit.PITCH, pitch, env.max_pitch_rad))
            if clamp and not math.isnan(pitch):
                pitch_rad = f32(math.copysign(env.max_pitch_rad, pitch))
        if not abs(ballast) <= self.max_ballast_cc:
            found.append(Breach(EnvelopeLimit.BALLAST, ballast, self.max_ballast_cc))
            if clamp and not math.isnan(ballast):
                ballast_cc = f32(math.copysign(self.max_ballast_cc, ballast))
        return (found[0] if found else None), target_m, pitch_rad, ballast_cc
