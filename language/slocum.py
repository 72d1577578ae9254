"""Slocum layered-control missions (`.mi` with its `.ma` files) translated into the
gliderplan language, keeping the intent of the behaviors' priorities.

The glider flies one state, `survey`: the yo as its flight profile, the goto list (or
waypoint) as its route, the science sensors the `sample` and `sensors_in` behaviors
switch on. The behaviors above them become that state's events, in the `.mi` file's
priority order (the first true one fires): every `surface` behavior calls a surfacing
state that climbs, waits at the surface as its end action says and returns (or ends
the mission), and the `abend` conditions go to an `abort` state that surfaces and ends
the mission. `prepare_to_dive` is the start state, at the surface.

Surfacing schedules become conditions on `missiontime` and two variables the
surfacing states keep: `surfaced_s`, when the glider last reached the surface
(`start_when` 9, every `when_secs`, counts from there), and `last_comm_s`, when it
last left it (`start_when` 12, no communication for `when_secs`). A yo of N half
cycles ends on the runtime's `halfcycle` reading, on the tick its N-th leg reaches
its turning depth, so the glider climbs on to the surface without another dive. The
route's progress is the runtime's `wptreached` reading, the waypoints reached (a
surfacing call's return resumes it): a goto list run N legs has been flown when it
reaches N (`start_when` 3, and 1 when the yo never ends), and each waypoint reached
raises it by one (`start_when` 8).

Whatever has no counterpart stays visible: as a comment in the mission, next to what
it concerns, and as a warning naming the file and line.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from gliderplan.contract import MAX_ROUTE_POINTS as MAX_POINTS
from gliderplan.contract import SURFACE_PITCH_RAD, WAYPOINT_RADIUS_M
from gliderplan.language.ir import DEFAULT_BATTERY
from gliderplan.language.slocum_files import Arg, Behavior, SlocumFileError, SlocumMission, Where
from gliderplan.language.slocum_files import number_text as _number
from gliderplan.language.slocum_sampling import ALL_ON_SWITCH, SWITCHES, ScienceBay

# Behaviors this translation reads, and real Slocum behaviors it knows but leaves out.
TRANSLATED = ("abend", "surface", "goto_list", "goto_wpt", "set_heading", "yo",
              "prepare_to_dive", "sample", "sensors_in")
NOT_TRANSLATED = ("dive_to", "climb_to", "thruster", "drift_at_depth",
                  "pinger_on", "comatose", "mission_ender", "nop_cmds", "science_super",
                  "tb_bus", "sleep", "sgyo", "hover", "fin_motor", "digifin")
DEFAULT_PITCH_RAD = 0.454  # a yo whose pitch is a battery position, not an angle
AT_SURFACE_M = 0.3  # shallower, the glider is at the surface (sim.vehicle.SURFACE_DEPTH_M)
SAMEDEPTH_CHANGE_M = 1.0  # abend samedepth_for: "the same depth" is within this [m]
FLIGHT_SENSORS = ("missiontime", "depth", "pitch", "lat", "lon")
# behaviors that command the heading: the first in priority order is the route flown
ROUTE_BEHAVIORS = ("goto_list", "goto_wpt", "set_heading")
# set_heading's use_heading modes without a translation, and why
_NO_ROLL_FIT = ("the shared Slocum logs command no roll (c_roll and c_battroll stay 0: "
                "the fin steers), so no turn rate per roll is fitted")
HEADING_MODES_LEFT_OUT = {
    2: f"a roll held (HM_ROLL): {_NO_ROLL_FIT}",
    3: f"a battery roll held (HM_BATTROLL): {_NO_ROLL_FIT}",
    5: "a heading relative to the measured current's direction (HM_CURRENT): the runtime "
       "has no heading that follows the current's"}
HM_FIN = 4  # use_heading: a fin angle held, flown as a turn at the vehicle's fin_turn_rate
FIN_LIMIT_RAD = 0.43  # the Slocum fin's stop: c_fin never beyond it in the shared logs
# surface's start_when modes translated that read when_secs: when they surface
WHEN_SECS_MODES = {9: "when_secs after it last reached the surface",
                   12: "when_secs after it last left the surface"}


@dataclass(frozen=True)
class Warning_:
    """Something the translation could not carry over."""

    where: Where
    message: str

    def __str__(self) -> str:
        return f"{self.where}: warning: {self.message}"


@dataclass(frozen=True)
class Hardware:
    """What an imported mission flies on: a vehicle (preset or file), its computer
    (`none`: the glider's own, in its base load; a Slocum mission needs no extra board)
    and its battery, as the mission's `vehicle`, `computer` and `battery` lines write them.
    `given` names those the user gave (the others are defaults, and the mission says so)."""

    vehicle: str = "slocum_g2_shallow"
    computer: str = "none"
    battery: str = "7.8 MJ reserve 15 %"  # the Slocum alkaline pack (ir.DEFAULT_BATTERY)
    given: frozenset[str] = frozenset()

    def check(self) -> None:
        """UsageError, with the checker's diagnostics, for a vehicle, computer or battery a
        mission could not name (an unknown preset, a malformed battery)."""
        from gliderplan.contract.errors import UsageError
        from gliderplan.language import check_source

        header = "\n".join(["mission hardware", *self.lines(), "state s", "begin",
                            "  flightroute noheading", "  flightprofile surface",
                            "  sensors missiontime", "  events",
                            "    case missiontime >= 1 exit", "end", ""])
        result = check_source(header, "import-slocum")
        if not result.ok:
            raise UsageError("--vehicle, --computer or --battery: not what a mission can fly "
                             "on", details=result.render())

    def lines(self) -> list[str]:
        """The mission's hardware lines, each saying where it came from."""
        def note(what: str, default_why: str) -> str:
            return f"import-slocum --{what}" if what in self.given else \
                f"the default of import-slocum --{what}: {default_why}"

        vehicle = self.vehicle if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", self.vehicle) \
            else f'"{self.vehicle}"'
        computer = self.computer if re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*(\s*@.*)?",
                                                 self.computer) else f'"{self.computer}"'
        return [f"vehicle {vehicle}    # " + note("vehicle", "a preset; give your glider"),
                f"computer {computer}    # " + note("computer", "the glider's own computers, in "
                                                    "its base load: no extra board"),
                f"battery {self.battery}    # " + note("battery", "the Slocum alkaline pack")]


@dataclass(frozen=True)
class Translation:
    source: str  # the mission, in the gliderplan language
    warnings: tuple[Warning_, ...]


@dataclass
class _State:
    name: str
    comment: list[str]
    route: str
    profile: str
    sensors: list[str]
    events: list[str] = field(default_factory=list)  # lines, comments included
    expect: str | None = None


def _at(arg: Arg) -> str:
    return f"{arg.where.path.name}:{arg.where.line}"


class _Translator:
    def __init__(self, mission: SlocumMission, horizon_s: float, hardware: Hardware) -> None:
        self.mission = mission
        self.horizon_s = horizon_s
        self.current_correction = True  # u_use_current_correction, the Slocum's default 1
        self.hardware = hardware
        self.warnings: list[Warning_] = []
        self.header: list[str] = []
        self.variables: dict[str, tuple[float, str]] = {}
        self.survey_events: list[str] = []  # the survey state's events, in priority order
        self.everywhere: list[str] = []  # events every state checks first (abend overtime)
        self.bookkeeping: list[str] = []  # the survey's assignments, checked last
        self.surface_states: list[_State] = []
        self.survey_sensors: dict[str, str] = {}  # sensor -> duty ("" always on)
        self.survey_notes: list[str] = []  # what sample and sensors_in make of the bay
        self.surface_sensors: dict[str, str] = {}
        self.band: tuple[float, float] | None = None  # the yo's, [m]
        self.pitches: list[float] = []  # [rad] of its dives and climbs
        self.reads: set[str] = set()  # runtime readings the survey's events read
        self.abort_needed = False
        self.done_needed = False
        self.surfaces = 0
        # the route's end as (condition, why), or why it never ends; whether it reaches
        # waypoints at all (a goto list), or why not
        self.route_end: tuple[str, str] | None = None
        self.route_never = ("the mission flies no goto list (its heading is idle from the "
                            "start: a Slocum glider would surface at once)")
        self.route_reaches: str | None = "the mission flies no goto list"  # None: it does
        self.yo_never = "the mission has no yo"

    # ---- reporting
    def warn(self, where: Where, message: str) -> None:
        self.warnings.append(Warning_(where, message))

    def leave_out(self, behavior: Behavior, names: list[str], why: str) -> list[str]:
        """Warn once for the b_args of a behavior that are not carried over; the comment."""
        args = [behavior.args[n] for n in names if n in behavior.args]
        if not args:
            return []
        listed = ", ".join(f"{a.name} {a.text} ({_at(a)})" for a in args)
        self.warn(args[0].where, f"{behavior.name}: not translated: {listed}: {why}")
        return [f"not translated: {', '.join(f'{a.name} {a.text}' for a in args)} ({why})"]

    # ---- the whole mission
    def run(self) -> str:
        if not self.mission.behaviors:
            self.warn(Where(self.mission.path, 1), "no behavior: the translated mission only "
                      "waits at the surface (is this a Slocum mission file?)")
            self.header.append("no behavior in the Slocum mission: it only waits at the surface")
        by_name: dict[str, list[Behavior]] = {}
        for behavior in self.mission.behaviors:
            if behavior.name not in TRANSLATED + NOT_TRANSLATED:
                raise SlocumFileError(
                    f"{behavior.where}: unknown behavior {behavior.name!r} "
                    f"(translated: {', '.join(TRANSLATED)})")
            if behavior.missing_mafile is not None:
                self.warn(behavior.where, f"{behavior.name}: its .ma file "
                          f"{behavior.missing_mafile} is missing: the behavior is left out")
                self.header.append(f"left out: {behavior.name} ({behavior.where.path.name}:"
                                   f"{behavior.where.line}), its .ma file "
                                   f"{behavior.missing_mafile.name} is missing")
                continue
            if behavior.name in NOT_TRANSLATED:
                self.warn(behavior.where, f"{behavior.name}: this behavior has no "
                          "translation: it is left out")
                self.header.append(f"left out: behavior {behavior.name} "
                                   f"({behavior.where.path.name}:{behavior.where.line})")
                continue
            by_name.setdefault(behavior.name, []).append(behavior)
        science_all_on = self.sensor_lines()
        yo = self.single(by_name, "yo")
        # the behaviors that command the heading, in priority order
        routes = [b for b in self.mission.behaviors if b.name in ROUTE_BEHAVIORS
                  and b.missing_mafile is None]
        if len(routes) > 1:
            for extra in routes[1:]:
                self.warn(extra.where, f"{extra.name}: only the first route behavior "
                          f"({routes[0].where}) is flown: this one is left out")
        route, route_comment = self.route(routes[0]) if routes else ("noheading", [])
        profile, profile_comment, yo_done = self.yo(yo)
        for behavior in self.mission.behaviors:  # priority order
            if behavior.missing_mafile is not None:
                continue
            if behavior.name == "abend":
                self.abend(behavior, bool(routes) and routes[0].name != "set_heading")
            elif behavior.name == "surface":
                self.surface(behavior, yo_done)
        if yo_done is not None and not any(
                b.value("start_when") == 1 for b in by_name.get("surface", [])):
            condition, why = yo_done
            if yo is not None and yo.value("end_action", 0) == 0:
                self.done_needed = True
                self.survey_events.append(f"# the yo's end ({why}) ends the mission "
                                          "(end_action 0: quit)")
                self.survey_events.append(f"case {condition} goto done")
        self.science(yo, science_all_on)
        prepare = self.single(by_name, "prepare_to_dive")
        states = []
        if prepare is not None:
            states.append(self.prepare_to_dive(prepare))
        states.append(self.survey_state(route, route_comment, profile, profile_comment, yo))
        states += self.surface_states
        if self.abort_needed:
            states.append(self.final_state("abort", "abend: surface and end the mission"))
        if self.done_needed:
            states.append(self.final_state("done", "the mission is complete: surface and "
                                                   "end it"))
        for state in states:
            if state.name != "prepare_to_dive":
                state.events[:0] = self.everywhere if state.name not in ("abort", "done") \
                    else []
        return self.render(states)

    def single(self, by_name: dict[str, list[Behavior]], name: str) -> Behavior | None:
        found = by_name.get(name, [])
        for extra in found[1:]:
            self.warn(extra.where, f"{name}: only the first {name} ({found[0].where}) is "
                      "flown: this one is left out")
        return found[0] if found else None

    # ---- sensor: lines
    def sensor_lines(self) -> bool:
        """Warn for `sensor:` lines without a counterpart; whether c_science_all_on
        controls the science sensors (c_science_all_on_enabled, default 1)."""
        enabled = True
        for arg in self.mission.sensors:
            if arg.name == "c_science_all_on_enabled":
                enabled = arg.value != 0
                verb = "controls" if enabled else "does not control"
                self.header.append(f"sensor {arg.name} {arg.text} ({_at(arg)}): "
                                   f"c_science_all_on {verb} the science sensors")
            elif arg.name == "u_use_current_correction":
                self.current_correction = arg.value != 0
                self.header.append(f"sensor {arg.name} {arg.text} ({_at(arg)}): "
                                   f"current_correction {'on' if arg.value else 'off'}")
            elif arg.name.lower() in SWITCHES or arg.name.lower() == ALL_ON_SWITCH:
                self.header.append(f"sensor {arg.name} {arg.text} ({_at(arg)}): read with "
                                   "sensors_in")
            else:
                self.warn(arg.where, f"sensor {arg.name}({arg.unit}) {arg.text}: not "
                          "translated: gliderplan's power and flight models have no "
                          "counterpart")
                self.header.append(f"not translated: sensor {arg.name}({arg.unit}) {arg.text} "
                                   f"({_at(arg)})")
        return enabled

    # ---- route
    def route(self, behavior: Behavior) -> tuple[str, list[str]]:
        comment = [f"{behavior.name} ({behavior.source})"]
        if behavior.name == "goto_wpt":
            return self.goto_wpt(behavior, comment)
        if behavior.name == "set_heading":
            return self.set_heading(behavior, comment)
        points = behavior.waypoints
        count = behavior.value("num_waypoints")
        if not points:
            raise SlocumFileError(f"{behavior.mafile or behavior.where}: goto_list has no "
                                  "waypoints (<start:waypoints> ... <end:waypoints>)")
        if count is not None and count != len(points):
            arg = behavior.args["num_waypoints"]
            if count > len(points) or count < 1 or count != int(count):
                raise SlocumFileError(f"{arg.where}: num_waypoints {arg.text}, but the list "
                                      f"has {len(points)} waypoints")
            points = points[:int(count)]
            comment.append(f"num_waypoints {arg.text}: the first {int(count)} of the list")
        first = int(behavior.value("initial_wpt", 0))
        if first == -2:
            comment += self.leave_out(behavior, ["initial_wpt"],
                                      "the closest waypoint is unknown before flight; "
                                      "the list starts at its first")
            first = 0
        elif first == -1:
            comment.append("initial_wpt -1: the waypoint after the last one reached "
                           "(at the start: the first; after a surfacing: the one flown to)")
            first = 0
        elif not 0 <= first < len(points):
            arg = behavior.args["initial_wpt"]
            raise SlocumFileError(f"{arg.where}: initial_wpt {arg.text} is not a waypoint "
                                  f"of the list (0 to {len(points) - 1}, -1 or -2)")
        order = points[first:] + points[:first]
        radius = behavior.value("list_when_wpt_dist", 10.0)
        if behavior.value("list_stop_when", 7) != 7:
            comment += self.leave_out(behavior, ["list_stop_when"],
                                      "waypoints count as reached within "
                                      f"list_when_wpt_dist {_number(radius)} m")
        legs = int(behavior.value("num_legs_to_run", -1))
        pairs = [f"({_number(p.lat)}, {_number(p.lon)})" for p in order]
        comment.append("(lat, lon) from the file's (lon, lat) lines "
                       + ", ".join(f"{p.where.line}" for p in order))
        self.route_reaches = None
        if legs == -1:
            comment.append(f"num_legs_to_run -1: the list loops; each waypoint is reached "
                           f"within {_number(radius)} m")
            if len(pairs) > MAX_POINTS:
                raise SlocumFileError(f"{behavior.mafile}: {len(pairs)} waypoints, more than "
                                      f"the {MAX_POINTS} a route holds")
            self.route_never = "num_legs_to_run -1: the goto list loops for ever"
            return f"goto_list({_number(radius)}, {', '.join(pairs)})", comment
        if legs == 0 or legs < -2:
            arg = behavior.args["num_legs_to_run"]
            raise SlocumFileError(f"{arg.where}: num_legs_to_run {arg.text} is illegal "
                                  "(-1 loop, -2 once through, or N > 0 legs)")
        n = len(pairs) if legs == -2 else legs
        flown = [pairs[i % len(pairs)] for i in range(min(n, MAX_POINTS))]
        within = "" if radius == WAYPOINT_RADIUS_M else (
            f", each reached within {_number(WAYPOINT_RADIUS_M)} m, not list_when_wpt_dist "
            f"{_number(radius)} m")
        comment += self.leave_out(behavior, ["num_legs_to_run"],
                                  f"the {len(flown)} waypoints are flown in order{within} "
                                  "and the glider then holds the last; the list's end does "
                                  "not end the mission")
        self.route_end = (f"wptreached >= {len(flown)}",
                          f"its {len(flown)} waypoints reached, num_legs_to_run {_number(legs)}")
        return f"waypoints({', '.join(flown)})", comment

    def goto_wpt(self, behavior: Behavior, comment: list[str]) -> tuple[str, list[str]]:
        units = behavior.value("wpt_units", 0)
        x, y = behavior.args.get("wpt_x"), behavior.args.get("wpt_y")
        if units != 2 or x is None or y is None:
            self.warn(behavior.where, "goto_wpt: only a waypoint in DDMM.MMMM (wpt_units 2, "
                      "wpt_x longitude, wpt_y latitude) is translated: no heading is flown")
            self.route_never = self.route_reaches = ("goto_wpt's waypoint is not translated: "
                                                     "no heading is flown")
            return "noheading", comment + ["not translated: the waypoint is not in DDMM.MMMM"]
        comment.append(f"wpt_y {y.text} (lat), wpt_x {x.text} (lon)")
        self.route_never = self.route_reaches = ("goto_wpt is flown as nav, a heading that "
                                                 "never reaches its waypoint")
        return f"nav({_number(y.value)}, {_number(x.value)})", comment

    def set_heading(self, behavior: Behavior, comment: list[str]) -> tuple[str, list[str]]:
        """use_heading 1 (HM_HEADING): heading_value [rad] held as `heading(deg)`, the
        current correction leaving it alone as the Slocum's does; 4 (HM_FIN) a steady turn
        (`fin_hold`); the others are left out (HEADING_MODES_LEFT_OUT says why)."""
        mode = behavior.args.get("use_heading")
        value = behavior.args.get("heading_value")
        if mode is None or value is None:
            raise SlocumFileError(f"{behavior.mafile or behavior.where}: set_heading needs "
                                  "use_heading and heading_value")
        self.route_never = self.route_reaches = ("set_heading holds a heading: it reaches "
                                                 "no waypoint")
        if mode.value == HM_FIN:
            return self.fin_hold(behavior, value, comment)
        if mode.value != 1:
            why = HEADING_MODES_LEFT_OUT.get(int(mode.value)) \
                if mode.value == int(mode.value) else None
            if why is None:
                raise SlocumFileError(f"{mode.where}: use_heading {mode.text} is no mode of "
                                      "set_heading (1 heading, 2 roll, 3 battery roll, 4 "
                                      "fin, 5 relative to the current)")
            return "noheading", comment + self.leave_out(
                behavior, ["use_heading", "heading_value"],
                f"{why}: no heading is flown")
        degrees = math.degrees(value.value) % 360.0
        degrees = 0.0 if degrees >= 360.0 else degrees  # a tiny negative rounds up to 360
        comment.append(f"use_heading 1, heading_value {value.text} rad: {_number(degrees)} "
                       "deg held, uncorrected for the current")
        comment += self.leave_out(behavior, ["stop_when", "when_secs", "end_action"],
                                  "the heading is held for the whole survey")
        return f"heading({_number(degrees)})", comment

    def fin_hold(self, behavior: Behavior, fin: Arg, comment: list[str]
                 ) -> tuple[str, list[str]]:
        """use_heading 4 (HM_FIN): heading_value [rad] of fin held, flown as `turn(deg/s)`
        at the rate the vehicle's `fin_turn_rate` gives that fin (a spiral)."""
        from gliderplan.power_models.vehicle import load_vehicle

        if not abs(fin.value) <= FIN_LIMIT_RAD:
            raise SlocumFileError(f"{fin.where}: heading_value {fin.text} rad is no fin angle "
                                  f"of use_heading 4: the fin stops at +-{FIN_LIMIT_RAD} rad")
        vehicle = load_vehicle(self.hardware.vehicle)
        if math.isnan(vehicle.fin_turn_rate_per_s):
            return "noheading", comment + self.leave_out(
                behavior, ["use_heading", "heading_value"],
                f"a fin angle held (HM_FIN): vehicle {self.hardware.vehicle} gives no "
                "fin_turn_rate to turn it into a turn rate: no heading is flown")
        rate_deg_s = math.degrees(vehicle.fin_turn_rate_per_s * fin.value)
        comment.append(f"use_heading 4, heading_value {fin.text} rad of fin: a steady turn "
                       f"of {_number(rate_deg_s)} deg/s (the vehicle's fin_turn_rate "
                       f"{_number(vehicle.fin_turn_rate_per_s)} 1/s) from the heading at "
                       "entry, uncorrected for the current")
        comment += self.leave_out(behavior, ["stop_when", "when_secs", "end_action"],
                                  "the fin is held for the whole survey")
        return f"turn({_number(rate_deg_s)})", comment

    # ---- yo
    def yo(self, behavior: Behavior | None) -> tuple[str, list[str], tuple[str, str] | None]:
        """(profile, comment, the yo's end as (condition, why) or None)."""
        if behavior is None:
            return "surface", ["no yo: the glider stays at the surface"], None
        top = behavior.value("c_target_depth", 3.0)
        bottom = behavior.value("d_target_depth", 10.0)
        if not 0.0 <= top < bottom:
            raise SlocumFileError(f"{behavior.mafile or behavior.where}: the yo climbs to "
                                  f"c_target_depth {_number(top)} m, not above its "
                                  f"d_target_depth {_number(bottom)} m")
        comment = [f"yo ({behavior.source}): between c_target_depth {_number(top)} m and "
                   f"d_target_depth {_number(bottom)} m"]
        pitches = []
        for leg in ("d", "c"):
            use, value = behavior.value(f"{leg}_use_pitch", 3), behavior.value(f"{leg}_pitch_value")
            if use == 3 and value is not None and 0.0 < abs(value) < math.pi / 2:
                pitches.append(abs(value))
            else:
                pitches.append(DEFAULT_PITCH_RAD)
                comment += self.leave_out(
                    behavior, [f"{leg}_use_pitch", f"{leg}_pitch_value"],
                    f"a battery position is no pitch angle; flown at {DEFAULT_PITCH_RAD} rad")
        altitude = behavior.value("d_target_altitude", -1)
        if altitude > 0:  # the altimeter stop: yo's fifth argument
            comment.append(f"d_target_altitude {_number(altitude)} m: a dive also turns "
                           f"{_number(altitude)} m above the sea floor (the altimeter stop, "
                           "yo's fifth argument)")
        comment += self.leave_out(
            behavior, ["d_bpump_value", "c_bpump_value"],
            "the plan, or else the vehicle's full pump stroke, sets the buoyancy")
        comment += self.leave_out(
            behavior, [n for n in ("d_stop_when_hover_for", "d_stop_when_stalled_for",
                                   "c_stop_when_hover_for", "c_stop_when_stalled_for")
                       if behavior.value(n, -1) > 0],
            "the simulated glider neither hovers nor stalls in a yo")
        comment += self.leave_out(
            behavior, ["c_target_altitude"] if behavior.value("c_target_altitude", -1) > 0
            else [], "a climb turns at c_target_depth only, never at a height above the floor")
        if behavior.value("start_when", 2) not in (0, 1, 2):
            comment += self.leave_out(behavior, ["start_when"],
                                      "the yo starts as soon as the glider dives")
        self.pitches, self.band = pitches, (top, bottom)
        stop = f", {_number(altitude)}" if altitude > 0 else ""
        profile = (f"yo({_number(top)}, {_number(bottom)}, {_number(pitches[0])}, "
                   f"{_number(pitches[1])}{stop})")
        half_cycles = behavior.value("num_half_cycles_to_do", -1)
        if half_cycles <= 0:
            self.yo_never = f"num_half_cycles_to_do {_number(half_cycles)}: the yo never ends"
            comment.append(self.yo_never)
            return profile, comment, None
        n = int(half_cycles)
        turn = f"depth >= {_number(bottom)}" if n % 2 else f"depth <= {_number(top)}"
        if n % 2 and altitude > 0:  # the last dive may turn at the altimeter stop
            turn = f"({turn} || altitude <= {_number(altitude)})"
            self.reads.add("altitude")
        self.reads.add("halfcycle")
        self.half_cycles = n
        return (profile, comment, (f"halfcycle > {n} || halfcycle == {n} && {turn}",
                                   f"num_half_cycles_to_do {n}"))

    # ---- abend
    def abend(self, behavior: Behavior, has_route: bool) -> None:
        events = [f"# abend ({behavior.source})"]
        overtime = behavior.value("overtime", -1)
        if overtime > 0:
            self.horizon_s = min(self.horizon_s, overtime)
            self.everywhere += [f"# abend overtime {_number(overtime)} s",
                                f"case missiontime >= {_number(overtime)} goto abort"]
        overdepth = behavior.value("overdepth", -1)
        if overdepth > 0:
            events.append(f"case depth > {_number(overdepth)} goto abort"
                          f"    # overdepth {_number(overdepth)} m")
        same = behavior.value("samedepth_for", -1)
        if same > 0:
            self.variables.setdefault("samedepth_m", (0.0, "depth of the last change of "
                                      f"{_number(SAMEDEPTH_CHANGE_M)} m or more [m]"))
            self.variables.setdefault("samedepth_s", (0.0, "when the depth last changed [s]"))
            events.append(f"case depth > {_number(AT_SURFACE_M)} && missiontime - samedepth_s "
                          f">= {_number(same)} goto abort    # samedepth_for {_number(same)} s")
            self.bookkeeping += [
                f"# abend samedepth_for: the depth changes by {_number(SAMEDEPTH_CHANGE_M)} m "
                "or more, or the glider is at the surface",
                f"case abs(depth - samedepth_m) >= {_number(SAMEDEPTH_CHANGE_M)} || depth <= "
                f"{_number(AT_SURFACE_M)} set samedepth_m = depth, samedepth_s = missiontime"]
        far = behavior.value("max_wpt_distance", -1)
        if far > 0 and has_route:
            self.reads.add("wptdist")
            events.append(f"case wptdist > {_number(far)} goto abort"
                          f"    # max_wpt_distance {_number(far)} m")
        charge = behavior.value("remaining_charge_min", -1)
        if charge > 0:
            if charge >= 100:
                arg = behavior.args["remaining_charge_min"]
                raise SlocumFileError(f"{arg.where}: remaining_charge_min {arg.text} %: the "
                                      "mission would abort at once (a charge below 100 %)")
            # the battery's coulomb counter, as the runtime's energy guard reads it; the
            # translated mission has no battery line: the default pack's energy
            left = charge / 100.0 * DEFAULT_BATTERY.energy_j
            self.reads.add("energy_left")
            events.append(f"case energy_left < {_number(left)} goto abort    # "
                          f"remaining_charge_min {_number(charge)} % of the mission's battery "
                          f"({_number(DEFAULT_BATTERY.energy_j)} J: the default pack; another "
                          "battery line changes this threshold)")
        for note in self.leave_out(behavior, ["stalled_for"] if
                                   behavior.value("stalled_for", -1) > 0 else [],
                                   "the simulated glider does not stall"):
            events.append(f"# {note}")
        known = {"overtime", "overdepth", "samedepth_for", "samedepth_for_sample_time",
                 "max_wpt_distance", "stalled_for", "remaining_charge_min"}
        for note in self.leave_out(behavior, [n for n in behavior.args if n not in known],
                                   "no counterpart"):
            events.append(f"# {note}")
        if len(events) > 1 or self.everywhere:
            self.abort_needed = True
        self.survey_events += events if len(events) > 1 else []

    # ---- surface
    def surface(self, behavior: Behavior, yo_done: tuple[str, str] | None) -> None:
        self.surfaces += 1  # states are numbered in the .mi's order of surface behaviors
        number = self.surfaces
        name = f"surface_{number}"
        when = int(behavior.value("start_when", 0))
        secs = behavior.value("when_secs", 180.0)
        head = f"# surface ({behavior.source}): start_when {when}"
        call = f"set surfaced_s = missiontime call {name}"
        self.variables.setdefault("surfaced_s", (0.0, "when the glider last reached the "
                                                      "surface [s]"))
        self.variables.setdefault("last_comm_s", (0.0, "when it last left the surface "
                                                       "(its last call) [s]"))
        used = {"start_when", "args_from_file", "end_action", "keystroke_wait_time",
                "gps_wait_time", "c_use_bpump", "c_bpump_value", "c_use_pitch",
                "c_pitch_value"}
        if when in WHEN_SECS_MODES and secs <= 0:
            arg = behavior.args["when_secs"]
            raise SlocumFileError(f"{arg.where}: when_secs {arg.text} s is no time to wait: "
                                  f"start_when {when} surfaces {WHEN_SECS_MODES[when]} (a "
                                  "positive number of seconds)")
        # a goto list, once flown, stays so: a surfacing on its end that resumes surfaces
        # again at once, as a Slocum glider whose heading stays idle does
        again = "" if int(behavior.value("end_action", 1)) in (0, 5) else (
            "; then again each time it resumes, the list staying flown")
        match when:
            case 1:
                if yo_done is not None:
                    condition, why = yo_done
                    self.survey_events += [f"{head}, stack idle: the yo's end ({why})",
                                           f"case {condition} {call}"]
                elif self.route_end is not None:
                    condition, why = self.route_end
                    self.reads.add("wptreached")
                    self.survey_events += [
                        f"{head}, stack idle: the goto list's end ({why}; {self.yo_never})"
                        f"{again}", f"case {condition} {call}"]
                else:
                    self.never(behavior, head, "stack idle",
                               f"{self.yo_never}, and {self.route_never}")
                    return  # a state nothing calls would be unreachable
            case 3:
                if self.route_end is None:
                    self.never(behavior, head, "at the end of the goto list", self.route_never)
                    return
                condition, why = self.route_end
                self.reads.add("wptreached")
                self.survey_events += [f"{head}, at the end of the goto list ({why}){again}",
                                       f"case {condition} {call}"]
            case 8:
                if self.route_reaches is not None:
                    self.never(behavior, head, "when a waypoint is reached", self.route_reaches)
                    return
                seen = f"wpt_surfaced_{number}"
                self.reads.add("wptreached")
                self.variables[seen] = (0.0, f"the waypoints reached when {name} last surfaced")
                self.survey_events += [
                    f"{head}, when a waypoint is reached (once per waypoint)",
                    f"case wptreached > {seen} set {seen} = wptreached, surfaced_s = "
                    f"missiontime call {name}"]
            case 9:
                used.add("when_secs")
                self.survey_events += [
                    f"{head}, every when_secs {_number(secs)} s since the last surfacing",
                    f"case missiontime - surfaced_s >= {_number(secs)} {call}"]
            case 12:
                used.add("when_secs")
                self.survey_events += [
                    f"{head}, no communication for when_secs {_number(secs)} s",
                    f"case missiontime - last_comm_s >= {_number(secs)} {call}"]
            case 7:
                used.add("when_wpt_dist")
                dist = behavior.value("when_wpt_dist", 10.0)
                flag = f"near_wpt_{number}"
                self.reads.add("wptdist")
                self.variables[flag] = (0.0, f"1 once {name} surfaced near this waypoint")
                self.survey_events += [
                    f"{head}, within when_wpt_dist {_number(dist)} m of the waypoint, once",
                    f"case wptdist <= {_number(dist)} && {flag} == 0 set {flag} = 1, "
                    f"surfaced_s = missiontime call {name}"]
                self.bookkeeping.append(f"case wptdist > {_number(dist)} && {flag} == 1 "
                                        f"set {flag} = 0")
            case 13:
                condition = self.utc_time(behavior, used)
                if condition is None:
                    self.survey_events.append(f"{head}: at a date, not translated, never "
                                              "surfaces")
                    return
                self.reads.add("timeofday")
                self.survey_events += [f"{head}, at a UTC time of day ({condition[1]})",
                                       f"case {condition[0]} {call}"]
            case 0:
                flag = f"{name}_done"
                self.variables[flag] = (0.0, f"1 once {name} has surfaced")
                self.survey_events += [f"{head}, immediately (once)",
                                       f"case {flag} == 0 set {flag} = 1, surfaced_s = "
                                       f"missiontime call {name}"]
            case _:
                arg = behavior.args.get("start_when")
                self.warn(arg.where if arg else behavior.where,
                          f"surface: start_when {when} is not translated (translated: 0 "
                          "immediately, 1 stack idle, 3 the goto list's end, 7 near the "
                          "waypoint, 8 a waypoint reached, 9 every when_secs, 12 no "
                          "communication, 13 a time of day): this surfacing never happens")
                self.survey_events.append(f"{head}: not translated, never surfaces")
                return
        notes = []
        if "when_secs" not in used:
            notes = self.leave_out(behavior, ["when_secs"], f"start_when {when} does not read "
                                   "it; Slocum reads it for start_when 6, 9 and 12")
            used.add("when_secs")
        self.surface_states.append(self.surface_state(behavior, name, used, notes))

    def never(self, behavior: Behavior, head: str, mode: str, why: str) -> None:
        """A surfacing whose start never comes: a comment and a warning at its start_when."""
        arg = behavior.args.get("start_when")
        self.warn(arg.where if arg else behavior.where,
                  f"surface: start_when {int(behavior.value('start_when', 0))} ({mode}) never "
                  f"happens: {why}")
        self.survey_events.append(f"{head}, {mode}: never ({why})")

    def utc_time(self, behavior: Behavior, used: set[str]) -> tuple[str, str] | None:
        """start_when 13: the condition on the glider's clock, true for the minute that
        starts at when_utc_hour:when_utc_min (every hour for hour -1), and its wording;
        None for a date (when_utc_day or when_utc_month), which it cannot read."""
        used |= {"when_utc_min", "when_utc_hour", "when_utc_day", "when_utc_month"}
        minute = behavior.value("when_utc_min", 0)
        hour = behavior.value("when_utc_hour", -1)
        if behavior.value("when_utc_day", -1) >= 0 or behavior.value("when_utc_month", -1) >= 0:
            self.leave_out(behavior, ["when_utc_day", "when_utc_month"],
                           "the glider's clock reading is the time of day only")
            return None
        if not 0 <= minute < 60 or not -1 <= hour < 24:
            arg = behavior.args.get("when_utc_min") or behavior.where
            raise SlocumFileError(f"{getattr(arg, 'where', arg)}: when_utc_hour "
                                  f"{_number(hour)}, when_utc_min {_number(minute)} is not "
                                  "a time of day")
        if hour < 0:
            at = 60 * minute
            return (f"mod(timeofday, 3600) >= {_number(at)} && mod(timeofday, 3600) < "
                    f"{_number(at + 60)}", f"every hour at minute {_number(minute)}")
        at = 3600 * hour + 60 * minute
        return (f"timeofday >= {_number(at)} && timeofday < {_number(at + 60)}",
                f"{int(hour):02d}:{int(minute):02d} UTC")

    def surface_state(self, behavior: Behavior, name: str, used: set[str],
                      notes: list[str]) -> _State:
        end = int(behavior.value("end_action", 1))
        keystroke = behavior.value("keystroke_wait_time", 300.0)
        gps = behavior.value("gps_wait_time", 300.0)
        comment = [f"surface ({behavior.source})", *notes]
        match end:
            case 0:
                wait, action, why = gps, "exit", "end_action 0: quit once at the surface " \
                                                 "with a GPS fix"
            case 1 | 4:
                wait, action, why = keystroke, "return", (
                    f"end_action {end}: wait keystroke_wait_time for a ^C, then resume")
            case 2:
                wait, action, why = gps, "return", ("end_action 2: resume once it has a GPS "
                                                    "fix, here after the whole gps_wait_time")
            case 5:
                wait, action, why = keystroke, "exit", ("end_action 5: wait "
                                                        "keystroke_wait_time, then quit")
            case _:
                wait, action, why = keystroke, "return", "resume after keystroke_wait_time"
                comment += self.leave_out(behavior, ["end_action"], why)
        pitch = behavior.value("c_pitch_value")
        if behavior.value("c_use_pitch", 3) != 3 or (
                pitch is not None and abs(pitch - SURFACE_PITCH_RAD) > 1e-9):
            comment += self.leave_out(behavior, ["c_use_pitch", "c_pitch_value"],
                                      f"the surface routine climbs at {SURFACE_PITCH_RAD} rad")
        if behavior.value("c_use_bpump", 2) != 2 or behavior.value("c_bpump_value", 1000) < 1000:
            comment += self.leave_out(behavior, ["c_use_bpump", "c_bpump_value"],
                                      "the surface routine climbs with the full pump stroke")
        comment += self.leave_out(behavior, [n for n in behavior.args if n not in used],
                                  "gliderplan's models have no counterpart")
        leave = "set last_comm_s = missiontime"
        if "samedepth_s" in self.variables:
            leave += ", samedepth_s = missiontime"
        events = [f"# {why}",
                  f"case depth > {_number(AT_SURFACE_M)} set surfaced_s = missiontime"
                  "    # climbing: the wait starts at the surface",
                  f"case missiontime - surfaced_s >= {_number(wait)} {leave} {action}"]
        return _State(name, comment, "noheading", "surface", [], events)

    # ---- science sensors
    def science(self, yo: Behavior | None, science_all_on: bool) -> None:
        """The devices the sample and sensors_in behaviors switch on, in priority order."""
        from gliderplan.language.ir import DEFAULT_VEHICLE

        band = None if self.band is None else (*self.band, *self.pitches)
        bay = ScienceBay(self.warn, self.leave_out, yo, band, DEFAULT_VEHICLE, science_all_on)
        for behavior in self.mission.behaviors:
            if behavior.missing_mafile is not None:
                continue
            if behavior.name == "sample":
                bay.sample(behavior)
            elif behavior.name == "sensors_in":
                bay.sensors_in(behavior)
        self.survey_sensors, self.surface_sensors = bay.sensors()
        self.survey_notes += bay.notes + bay.union_notes()

    # ---- states
    def prepare_to_dive(self, behavior: Behavior) -> _State:
        wait = behavior.value("wait_time", 720.0)
        comment = [f"prepare_to_dive ({behavior.source}): at the surface, wait_time "
                   f"{_number(wait)} s for a GPS fix"]
        self.warn(behavior.where, f"prepare_to_dive: the glider waits the whole wait_time "
                  f"{_number(wait)} s (a real one dives as soon as it has its GPS fix)")
        if behavior.value("start_when", 0) != 0:
            comment += self.leave_out(behavior, ["start_when"], "it waits at the start")
        leave = "set last_comm_s = missiontime"
        if "samedepth_s" in self.variables:
            leave += ", samedepth_s = missiontime"
        return _State("prepare_to_dive", comment, "noheading", "surface", [],
                      [f"case missiontime >= {_number(wait)} {leave} goto survey"])

    def survey_state(self, route: str, route_comment: list[str], profile: str,
                     profile_comment: list[str], yo: Behavior | None) -> _State:
        sensors = list(FLIGHT_SENSORS) + sorted(self.reads)
        science = [f"{s} duty {d}" if d else s for s, d in self.survey_sensors.items()]
        state = _State("survey", route_comment + profile_comment + self.survey_notes, route,
                       profile, sensors + science)
        state.events = self.survey_events + self.bookkeeping
        if yo is not None and "halfcycle" in self.reads:
            state.expect = self.yo_expect()
        return state

    def yo_expect(self) -> str | None:
        """Bounds on the time the yo's half cycles take, from the vehicle's glide model."""
        from gliderplan.language.ir import DEFAULT_VEHICLE
        from gliderplan.power_models.vehicle import load_vehicle

        vehicle = load_vehicle(DEFAULT_VEHICLE)
        top, bottom = self.band
        seconds = 0.0
        for kind, pitch in enumerate(self.pitches):  # dives are the even legs, climbs odd
            legs = (self.half_cycles + 1 - kind) // 2
            _, w = vehicle.glide(pitch, vehicle.max_ballast_cc)
            seconds += legs * ((bottom - top) / float(w) + 2 * vehicle.max_ballast_cc
                               / vehicle.pump_rate_cc_s)
        low, high = math.floor(0.8 * seconds / 60), math.ceil(1.25 * seconds / 60)
        return (f"{low} min .. {high} min    # {self.half_cycles} half cycles at the "
                f"{DEFAULT_VEHICLE} glide model's speeds, -20 % .. +25 %")

    def final_state(self, name: str, why: str) -> _State:
        return _State(name, [why], "noheading", "surface", [],
                      [f"case depth <= {_number(AT_SURFACE_M)} exit"])

    # ---- text
    def render(self, states: list[_State]) -> str:
        mi = self.mission.path.name
        name = re.sub(r"[^A-Za-z0-9_]", "_", self.mission.path.stem)
        if not re.match(r"[A-Za-z_]", name):
            name = f"m_{name}"
        lines = [f"# Translated from the Slocum mission {mi} by gliderplan import-slocum.",
                 "# Behaviors in priority order: " + ", ".join(
                     f"{b.name} ({b.where.line})" for b in self.mission.behaviors) + "."]
        lines += [f"# {c}" for c in self.header]
        lines += [f"mission {name}", *self.hardware.lines(),
                  f"horizon {_number(self.horizon_s)} s    # planned and simulated for this "
                  "long (the Slocum mission runs until its pilot ends it)",
                  f"current_correction {'on' if self.current_correction else 'off'}", ""]
        for var, (initial, why) in self.variables.items():
            lines.append(f"var {var} = {_number(initial)}    # {why}")
        for state in states:
            lines += ["", *(f"# {c}" for c in state.comment), f"state {state.name}", "begin",
                      f"  flightroute {state.route}", f"  flightprofile {state.profile}"]
            logged = list(dict.fromkeys(list(FLIGHT_SENSORS[:2]) + state.sensors))
            if state.name.startswith("surface_"):
                logged += [f"{s} duty {d}" if d else s for s, d in self.surface_sensors.items()]
            lines.append(f"  sensors {', '.join(logged)}")
            if state.expect:
                lines.append(f"  expect {state.expect}")
            if state.events:
                lines.append("  events")
                for event in state.events:
                    lines.append(f"    {event}")
            lines.append("end")
        return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Imported:
    path: Path  # the mission written
    states: int
    warnings: tuple[Warning_, ...]


def import_mission(mi: str | Path, output: str | Path, mafiles: str | Path | None = None,
                   horizon_s: float = 7 * 86400.0,
                   allow_missing_mafiles: bool = False,
                   hardware: Hardware = Hardware()) -> Imported:
    """Translate the Slocum mission `mi` (its .ma files in `mafiles`), check the result and
    write it to `output` atomically (`gliderplan import-slocum`). `horizon_s` [s]: how long
    the mission is planned and flown; `allow_missing_mafiles`: leave out a behavior whose
    .ma file is missing (a warning) instead of stopping.

    Raises SlocumFileError (exit 1), its message `FILE:LINE: problem`, for a malformed
    line, an unknown behavior or a .ma file that is not there; exit 2 (usage) for a
    mission file that does not exist or is a directory, a --mafiles that is no directory
    and an output that cannot be written."""
    from gliderplan.contract.errors import GliderplanError, UsageError
    from gliderplan.contract.files import write_atomically
    from gliderplan.language import check_source
    from gliderplan.language.slocum_files import read_mission

    if mafiles is not None and not Path(mafiles).is_dir():
        raise UsageError(f"--mafiles {mafiles}: no such directory")
    hardware.check()
    translation = translate(read_mission(mi, mafiles, allow_missing_mafiles), horizon_s,
                            hardware)
    checked = check_source(translation.source, str(output))
    if checked.mission is None:  # a bug of the translation: show why, write nothing
        raise GliderplanError(f"{output}: the translation of {mi} does not check (not "
                              "written; a bug in gliderplan)", details=checked.render())
    write_atomically(output, translation.source)
    return Imported(Path(output), len(checked.mission.states), translation.warnings)


def translate(mission: SlocumMission, horizon_s: float = 7 * 86400.0,
              hardware: Hardware = Hardware()) -> Translation:
    """The mission in the gliderplan language, planned for `horizon_s` [s] (or abend's
    overtime when shorter) on `hardware`, and what could not be carried over. Raises
    SlocumFileError (FILE:LINE: message) for an unknown behavior or values that contradict
    each other."""
    from gliderplan.language.formatter import format_source

    translator = _Translator(mission, horizon_s, hardware)
    source = translator.run()
    return Translation(format_source(source), tuple(translator.warnings))
