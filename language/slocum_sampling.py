"""The science bay of a Slocum mission: which power-model devices its `sample` and
`sensors_in` behaviors switch on, in which phases of the yo, and for what share of
their time; the translated mission logs each device's sensors with that share as duty.

A behavior names instruments (`sample`'s `sensor_type`, `sensors_in`'s `c_<name>_on`
switches), `power_models.slocum_instruments` says which device each is, and the
device's sensors are the language's sensors of that device (`contract.SENSORS`);
sensor_type 0 and `c_science_all_on` switch on every science device.

`state_to_sample` picks the phases: diving (1), hovering (2), climbing (4), on the
surface (8). The yo never hovers. A device sampled while diving only is on for the
share of the yo spent diving, from the default vehicle's glide model (the turn at the
top counted with the dive, the one at the bottom with the climb: Slocum's dive_to and
climb_to begin with them). Each phase's on-share is the sampling interval's duty (0:
always on; t > 0: one warm-up and one sample every t seconds), cut by `min_depth` and
`max_depth` to the share of the yo band they keep, and divided by `nth_yo_to_sample`.

Behaviors act in the .mi's priority order, as layered control has it: the first
behavior that samples a device in a phase sets its interval there (an interval < 0 is
off), the others fill the phases it leaves: the union of their phases.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from gliderplan.contract import SENSORS
from gliderplan.language.slocum_files import Arg, Behavior, SlocumFileError, Where
from gliderplan.language.slocum_files import number_text as _number
from gliderplan.power_models import slocum_instruments as bay

DIVING, HOVERING, CLIMBING, ON_SURFACE = 1, 2, 4, 8  # sample's state_to_sample bits
ALL_ON_SWITCH = "c_science_all_on"  # sensors_in's switch of every instrument (sensor_type 0)
# switch -> instrument, in lower case: missions write some in mixed case (c_uModem_on)
SWITCHES: dict[str, bay.Instrument] = {i.switch: i for i in bay.INSTRUMENTS.values()}
# sample's arguments read here; any other is a warning
SAMPLE_ARGS = ("args_from_file", "sensor_type", "state_to_sample", "intersample_time",
               "nth_yo_to_sample", "min_depth", "max_depth", "sample_time_after_state_change",
               "intersample_depth")
DEFAULT_DEPTHS_M = (-5.0, 2000.0)  # sample's min_depth, max_depth: every depth


def device_sensors(device: str) -> tuple[str, ...]:
    """The language's sensors of a power-model device, in the sensor array's order."""
    return tuple(s.name for s in SENSORS if s.device == device)


# sensor_type 0 and c_science_all_on: every device of the science bay the language logs
SCIENCE_DEVICES = tuple(d for d in bay.devices() if device_sensors(d))


@dataclass(frozen=True)
class YoPhases:
    """The yo a sampled device flies: its band [m] and the share of its time [1] spent
    diving and climbing (they add up to 1), on the vehicle named."""

    top_m: float
    bottom_m: float
    dive_share: float
    vehicle: str

    @property
    def climb_share(self) -> float:
        return 1.0 - self.dive_share

    @property
    def band(self) -> str:
        return f"{_number(self.top_m)}-{_number(self.bottom_m)} m"


def yo_phases(top_m: float, bottom_m: float, dive_pitch_rad: float,
              climb_pitch_rad: float, vehicle_name: str) -> YoPhases:
    """The dive's and the climb's shares of a yo's time [1] on the vehicle, flown as
    without a plan (its full pump stroke), each turn with the leg it begins. Raises
    FlightModelError where the vehicle cannot fly the band."""
    from gliderplan.power_models import flight
    from gliderplan.power_models.vehicle import load_vehicle

    vehicle = load_vehicle(vehicle_name)
    dive_pitch, climb_pitch = vehicle.flown_pitch_rad(dive_pitch_rad, climb_pitch_rad)
    stroke = vehicle.unplanned_ballast_cc
    pump_s = float(vehicle.pump_time_s(2.0 * stroke))  # one inflection's pump run
    dive = flight.glide_leg(vehicle.flight, top_m, bottom_m, dive_pitch, stroke, False)
    climb = flight.glide_leg(vehicle.flight, top_m, bottom_m, climb_pitch, stroke, True)
    dive_s = float(dive.time_s) + pump_s + vehicle.top_turn_s
    climb_s = float(climb.time_s) + pump_s + vehicle.bottom_turn_s
    return YoPhases(top_m, bottom_m, dive_s / (dive_s + climb_s), vehicle.name)


@dataclass
class Sampling:
    """What the science behaviors make of one device: each phase's on-share [1] (None: no
    behavior samples it in that phase) and the behaviors that set them."""

    dive: float | None = None
    climb: float | None = None
    surface: float | None = None
    by: list[str] = field(default_factory=list)

    def claim(self, source: str, dive: float | None, climb: float | None,
              surface: float | None) -> None:
        """A lower-priority behavior: it sets only the phases no earlier one set."""
        self.dive = self.dive if self.dive is not None else dive
        self.climb = self.climb if self.climb is not None else climb
        self.surface = self.surface if self.surface is not None else surface
        self.by.append(source)


def duty_text(duty: float) -> str:
    """A duty as the mission writes it: "" for always on, else two significant digits."""
    return "" if duty >= 1.0 - 1e-9 else f"{duty:.2g}"


def _duty_said(duty: float, factors: list[tuple[float, str]], where: str) -> str:
    """A duty and the shares it is the product of, for a comment."""
    said = [(f, why) for f, why in factors if f != 1.0]
    if duty >= 1.0 - 1e-9:
        return f"always on {where}" + "".join(f", {why}" for _, why in said)
    if len(said) == 1:
        return f"duty {duty_text(duty)} {where}, {said[0][1]}"
    return f"duty {duty_text(duty)} {where} = " + " x ".join(
        f"{f:.2g} ({why})" for f, why in said)


Warn = Callable[[Where, str], None]
LeaveOut = Callable[[Behavior, list[str], str], list[str]]


class ScienceBay:
    """Reads the science behaviors in priority order (`sample`, `sensors_in`), then gives
    the sensors each state logs (`sensors`) and the comments (`notes`, `union_notes`)."""

    def __init__(self, warn: Warn, leave_out: LeaveOut, yo: Behavior | None,
                 band_and_pitches: tuple[float, float, float, float] | None, vehicle: str,
                 science_all_on: bool) -> None:
        """`yo`: the survey's yo behavior and its (top [m], bottom [m], dive pitch [rad],
        climb pitch [rad]), None without one; `vehicle`: the preset whose glide model times
        it; `science_all_on`: whether c_science_all_on controls the science bay."""
        self.warn, self.leave_out = warn, leave_out
        self.yo, self.band_and_pitches, self.vehicle_name = yo, band_and_pitches, vehicle
        self.science_all_on = science_all_on
        self.devices: dict[str, Sampling] = {}
        self.notes: list[str] = []  # comments of the survey state
        self._phases: YoPhases | None = None

    # ---- the yo
    def phases(self) -> YoPhases | None:
        """The survey yo's phases (once), None without a yo; a yo the vehicle cannot fly
        is taken as half dive, half climb, with a warning at the yo."""
        if self.yo is None or self.band_and_pitches is None or self._phases is not None:
            return self._phases
        from gliderplan.power_models.flight import FlightModelError

        top, bottom, dive_pitch, climb_pitch = self.band_and_pitches
        try:
            self._phases = yo_phases(top, bottom, dive_pitch, climb_pitch, self.vehicle_name)
        except FlightModelError as err:
            self.warn(self.yo.where, f"yo: the {self.vehicle_name} glide model cannot fly it "
                      f"({err}): the sampled phases take a dive as half of the yo")
            self._phases = YoPhases(top, bottom, 0.5, self.vehicle_name)
        return self._phases

    # ---- instruments
    def instrument(self, behavior: Behavior, what: str, where: Where, kind: int
                   ) -> tuple[tuple[str, ...], str] | None:
        """(devices, the instrument's Slocum name) of sensor_type `kind` (0: every science
        device, "C_SCIENCE_ALL_ON"), or None, with a warning at `where` and a comment, for
        one without a power model: a number the firmware does not know or has deleted."""
        if kind == bay.ALL_SCIENCE:
            return SCIENCE_DEVICES, "C_SCIENCE_ALL_ON"
        instrument = bay.INSTRUMENTS.get(kind)
        if instrument is not None and instrument.device is not None:
            return (instrument.device,), instrument.name
        if kind in bay.DELETED:
            why = f"{bay.DELETED[kind]}, deleted from the Slocum firmware (it refuses the mission)"
        elif instrument is None:
            why = "no instrument the Slocum firmware knows"
        else:
            why = f"{instrument.name}, an instrument gliderplan has no power model of"
        self.warn(where, f"{behavior.name}: {what} is {why}: the forecast does not power it")
        self.notes.append(f"{behavior.name} ({behavior.source}): {what} ({why}): the forecast "
                          "does not power it")
        return None

    def all_science(self, behavior: Behavior, what: str, where: Where) -> None:
        """The warning for a behavior that switches on the whole science bay."""
        self.warn(where, f"{behavior.name}: {what} switches on every instrument the glider "
                  "carries, which the mission does not name: the forecast powers every science "
                  f"device gliderplan models ({', '.join(SCIENCE_DEVICES)}); sample the "
                  "glider's own instruments instead")

    def sampled(self, devices: tuple[str, ...], source: str, dive: float | None,
                climb: float | None, surface: float | None) -> None:
        """A behavior samples the devices: its on-share [1] of each phase (None: not in it)."""
        for device in devices:
            self.devices.setdefault(device, Sampling()).claim(source, dive, climb, surface)

    def interval_duty(self, device: str, interval_s: float) -> tuple[float, str]:
        """The on-share [1] of sampling every `interval_s` [s] (0: as fast as possible):
        one warm-up and one sample period of the device's preset each time, and why."""
        if interval_s == 0:
            return 1.0, "as fast as possible"
        from gliderplan.power_models.sensor import load_sensor

        sensor = load_sensor(device)
        on_s = sensor.warmup_s + 1.0 / sensor.sample_hz
        return min(1.0, on_s / interval_s), (
            f"intersample_time {_number(interval_s)} s: (its warm-up {_number(sensor.warmup_s)}"
            f" s + {1.0 / sensor.sample_hz:.3g} s a sample) / {_number(interval_s)} s"
            + (", on for good" if on_s >= interval_s else ""))

    # ---- sample
    def sample(self, behavior: Behavior) -> None:
        head = f"sample ({behavior.source})"
        kind_arg = behavior.args.get("sensor_type")
        if kind_arg is None:
            self.warn(behavior.where, "sample: no sensor_type: read as 0 (C_SCIENCE_ALL_ON), "
                      "the default this translation assumes")
        kind = self.whole(kind_arg, "sensor_type", bay.ALL_SCIENCE)
        what = f"sensor_type {kind}"
        kind_at = kind_arg.where if kind_arg else behavior.where
        found = self.instrument(behavior, what, kind_at, kind)
        if found is None:
            return
        devices, name = found
        label = ("every science device" if kind == bay.ALL_SCIENCE else devices[0]) + \
            f" ({what} {name})"
        states_arg = behavior.args.get("state_to_sample")
        states = self.whole(states_arg, "state_to_sample", DIVING)
        if not 0 <= states <= 15:
            raise SlocumFileError(f"{states_arg.where}: state_to_sample {states_arg.text} is no "
                                  "sum of 1 diving, 2 hovering, 4 climbing and 8 on the surface "
                                  "(0-15)")
        nth = self.whole(behavior.args.get("nth_yo_to_sample"), "nth_yo_to_sample", 1)
        if nth == 0:
            arg = behavior.args["nth_yo_to_sample"]
            raise SlocumFileError(f"{arg.where}: nth_yo_to_sample 0: no yo to sample (1 every "
                                  "yo, N one yo in N, -N one in N but not the first)")
        low, high = (behavior.value(n, d) for n, d in zip(("min_depth", "max_depth"),
                                                          DEFAULT_DEPTHS_M, strict=True))
        if low >= high:
            arg = behavior.args.get("max_depth") or behavior.args["min_depth"]
            raise SlocumFileError(f"{arg.where}: sample between min_depth {_number(low)} m "
                                  f"and max_depth {_number(high)} m: no depth lies between")
        notes = self.leave_out(behavior, [n for n in behavior.args if n not in SAMPLE_ARGS],
                               "gliderplan's models have no counterpart")
        notes += self.leave_out(behavior, ["sample_time_after_state_change"]
                                if behavior.value("sample_time_after_state_change", 0) > 0
                                else [], "sensors switch with the state, at once")
        notes += self.leave_out(behavior, ["intersample_depth"]
                                if behavior.value("intersample_depth", -1) > 0 else [],
                                "sampled by intersample_time, not by depth")
        self.notes += [f"{head}: {n}" for n in notes]
        if states == 0:
            self.warn(states_arg.where, f"sample: state_to_sample 0: no state to sample in: "
                      f"{what} is never switched on by it")
            self.notes.append(f"{head}: {label}: state_to_sample 0, in no state: off")
            return
        interval = behavior.value("intersample_time", 0.0)
        if interval < 0:
            self.sampled(devices, head, 0.0 if states & DIVING else None,
                         0.0 if states & CLIMBING else None,
                         0.0 if states & ON_SURFACE else None)
            self.notes.append(f"{head}: {label}: intersample_time {_number(interval)}: off")
            return
        if kind == bay.ALL_SCIENCE and states & (DIVING | CLIMBING | ON_SURFACE):
            self.all_science(behavior, what, kind_at)
        self.sample_phases(behavior, head, devices, label, states, interval, nth, (low, high))

    def sample_phases(self, behavior: Behavior, head: str, devices: tuple[str, ...], label: str,
                      states: int, interval: float, nth: int, depths: tuple[float, float]
                      ) -> None:
        """A sample that samples: each phase's on-share, and the comment that says why."""
        if len(devices) > 1 and interval > 0:  # each device its own warm-up and sample
            for device in devices:
                self.sample_phases(behavior, head, (device,), f"{device}, one of {label}",
                                   states, interval, nth, depths)
            return
        sampling = self.interval_duty(devices[0], interval)
        yo_bits = states & (DIVING | CLIMBING)
        if states & HOVERING and not yo_bits:
            self.notes += [f"{head}: {n}" for n in self.leave_out(
                behavior, ["state_to_sample"], "the yo never hovers: the sensor samples "
                + ("only at the surface" if states & ON_SURFACE else "never"))]
            if not states & ON_SURFACE:
                return
        parts = [f"{label} " + {DIVING: "diving only", CLIMBING: "climbing only",
                                DIVING | CLIMBING: "diving and climbing",
                                0: "at the surface only"}[yo_bits]]
        in_phases = 0.0  # the sampled phases' share sampled
        phases = self.phases()
        if yo_bits and phases is None:
            parts.append("no yo: the survey stays at the surface, off there")
        elif yo_bits:
            share = 1.0 if yo_bits == DIVING | CLIMBING else (
                phases.dive_share if yo_bits == DIVING else phases.climb_share)
            leg, legs = ("diving", "dives") if yo_bits == DIVING else ("climbing", "climbs")
            factors = [] if share == 1.0 else [(share, (
                f"the share of a {phases.band} yo spent {leg} on {phases.vehicle} (a share of "
                f"the time: a plan does not tie it to the {legs})"))]
            factors += self.yo_cuts(behavior, phases, nth, depths) + [sampling]
            in_phases = math.prod(f for f, _ in factors) / share
            parts.append(_duty_said(share * in_phases, factors, "in the yo"))
        if states & HOVERING and yo_bits:
            parts.append("hovering (2): the yo never hovers")
        surface = None
        if states & ON_SURFACE:
            inside = depths[0] <= 0.0 <= depths[1]
            surface = sampling[0] if inside else 0.0
            parts.append("at the surface (8): " + (
                _duty_said(surface, [sampling], "there") if inside else
                f"off, min_depth {_number(depths[0])} m lies below it"))
        self.notes.append(f"{head}: {parts[0]}: " + "; ".join(parts[1:]))
        self.sampled(devices, head, in_phases if yo_bits & DIVING else None,
                     in_phases if yo_bits & CLIMBING else None, surface)

    def yo_cuts(self, behavior: Behavior, phases: YoPhases, nth: int,
                depths: tuple[float, float]) -> list[tuple[float, str]]:
        """What a sample's depths and nth_yo_to_sample leave of the sampled phases, as
        (share [1], why)."""
        cuts = []
        low, high = max(depths[0], phases.top_m), min(depths[1], phases.bottom_m)
        band = phases.bottom_m - phases.top_m
        if high - low < band:
            cuts.append((max(high - low, 0.0) / band, (
                f"min_depth {_number(depths[0])} m to max_depth {_number(depths[1])} m "
                + (f"keep {_number(low)}-{_number(high)} m of the {phases.band} yo (at an "
                   "even vertical speed)" if high > low else
                   f"lie outside the {phases.band} yo"))))
        if abs(nth) > 1:
            cuts.append((1.0 / abs(nth), f"nth_yo_to_sample {nth}: one yo in {abs(nth)}"))
        if nth < 0:
            self.notes += [f"{behavior.name} ({behavior.source}): {n}" for n in self.leave_out(
                behavior, ["nth_yo_to_sample"], "the first yo, which it leaves out, is "
                f"sampled as the others; then one yo in {abs(nth)}" if nth < -1 else
                "the first yo, which it leaves out, is sampled as the others")]
        return cuts

    # ---- sensors_in
    def sensors_in(self, behavior: Behavior) -> None:
        """Each c_<name>_on switch: its interval in every state (< 0 off)."""
        head = f"sensors_in ({behavior.source})"
        switches = [a for a in behavior.args.values()
                    if a.name.lower() == ALL_ON_SWITCH or a.name.lower() in SWITCHES]
        # c_science_all_on, while it controls the bay, sets every instrument at once: the
        # single switches beside it change nothing
        switches.sort(key=lambda a: a.name.lower() != ALL_ON_SWITCH)
        all_on = None
        for arg in switches:
            name = arg.name.lower()
            if name == ALL_ON_SWITCH and not self.science_all_on:
                continue  # the header says c_science_all_on_enabled is 0
            if all_on is not None:
                self.notes.append(f"{head}: {arg.name} {arg.text}: no effect beside "
                                  f"{all_on.name} {all_on.text}, which sets every instrument")
                continue
            kind = bay.ALL_SCIENCE if name == ALL_ON_SWITCH else SWITCHES[name].sensor_type
            found = self.instrument(behavior, arg.name, arg.where, kind)
            if found is None:
                continue
            devices = found[0]
            all_on = arg if kind == bay.ALL_SCIENCE else None
            if arg.value < 0:
                self.sampled(devices, head, 0.0, 0.0, 0.0)
                self.notes.append(f"{head}: {', '.join(devices)} ({arg.name} {arg.text}): off")
                continue
            if kind == bay.ALL_SCIENCE:
                self.all_science(behavior, arg.name, arg.where)
            if arg.value == 0:
                self.sampled(devices, head, 1.0, 1.0, 1.0)
                self.notes.append(f"{head}: {', '.join(devices)} ({arg.name} {arg.text}): "
                                  "always on in every state")
                continue
            for device in devices:  # each its own warm-up and sample
                duty, why = self.interval_duty(device, arg.value)
                self.sampled((device,), head, duty, duty, duty)
                state = "always on in every state" if duty >= 1 else \
                    f"duty {duty_text(duty)} in every state, {why}"
                self.notes.append(f"{head}: {device} ({arg.name} {arg.text}): {state}")
        named = {a.name for a in switches}
        self.notes += [f"{head}: {n}" for n in self.leave_out(
            behavior, [n for n in behavior.args if n not in named],
            "the flight sensors' sampling intervals: the simulated glider reads them every "
            "tick")]

    # ---- the result
    def union_notes(self) -> list[str]:
        """A comment for each device two or more behaviors sample."""
        return [f"{device}: sampled by {' and '.join(s.by)}: the union of their phases (where "
                "two sample one phase, the first in the .mi's priority order sets it)"
                for device, s in self.devices.items() if len(set(s.by)) > 1]

    def sensors(self) -> tuple[dict[str, str], dict[str, str]]:
        """(survey's, surfacing states') sensor -> duty ("" always on); a device that is
        off there is left out. Without a yo the survey stays at the surface."""
        survey: dict[str, str] = {}
        surface: dict[str, str] = {}
        phases = self.phases()
        for device, s in self.devices.items():
            in_survey = (s.surface or 0.0) if phases is None else (
                phases.dive_share * (s.dive or 0.0) + phases.climb_share * (s.climb or 0.0))
            for sensor in device_sensors(device):
                if in_survey > 0:
                    survey[sensor] = duty_text(in_survey)
                if s.surface:
                    surface[sensor] = duty_text(s.surface)
        return survey, surface

    def whole(self, arg: Arg | None, name: str, default: int) -> int:
        """A whole-number argument (`default` when absent); anything else stops the import."""
        if arg is None:
            return default
        if arg.value != int(arg.value):
            raise SlocumFileError(f"{arg.where}: {name} {arg.text} is not a whole number")
        return int(arg.value)
