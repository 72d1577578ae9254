"""C code generation: the checked mission as the constant tables of runtime/include/gp_mission.h.

One mission becomes one C file, in the spirit of the paper's Fig. 3: per state an
event table whose rows point to small static functions (a condition, its
assignments), the flight-profile alternatives with their argument functions, the
route's points, and one `gp_mission_table` that ties them together. The output is
deterministic (source order throughout) and clean under
`-std=c11 -Wall -Wextra -Werror -pedantic`.

Expressions follow `ir.evaluate` exactly: every value is a double, truth is `!= 0.0`,
&& and || short-circuit, min/max are C's fmin/fmax written out so that ties of signed
zeros also resolve as the reference does (libm leaves that open), arithmetic goes
through small functions (see `_HELPERS`), and constants are exact (see `c_double`),
so the runtime and the Python reference agree bit for bit on every target.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction

from gliderplan import contract
from gliderplan.contract import FlightLimits
from gliderplan.contract.c_header import sensor_index
from gliderplan.contract.errors import GliderplanError
from gliderplan.language import ir
from gliderplan.language.registry import (
    PROFILES,
    SENSOR_BY_NAME,
    SENSORS,
    held_heading_rad,
    turn_rate_rad_s,
)

_ACTIONS = {None: "GP_ACT_NONE", "goto": "GP_ACT_GOTO", "call": "GP_ACT_CALL",
            "return": "GP_ACT_RETURN", "exit": "GP_ACT_EXIT"}
_PROFILE_KINDS = {"yo": "GP_PROFILE_YO", "thermotrackyo": "GP_PROFILE_THERMOTRACKYO",
                  "surface": "GP_PROFILE_SURFACE", "hover": "GP_PROFILE_HOVER",
                  "cruise": "GP_PROFILE_CRUISE", "altitude": "GP_PROFILE_ALTITUDE"}
_ROUTE_KINDS = {"nav": "GP_ROUTE_NAV", "noheading": "GP_ROUTE_NOHEADING",
                "waypoints": "GP_ROUTE_WAYPOINTS", "sweep": "GP_ROUTE_SWEEP",
                "goto_list": "GP_ROUTE_GOTO_LIST", "heading": "GP_ROUTE_HEADING",
                "turn": "GP_ROUTE_TURN"}
_HEADING_ROUTES = frozenset({"nav", "waypoints", "sweep", "goto_list"})
# Sensors every compiled mission reads: the state timers and the plan's schedule run on
# missiontime, every profile turns on depth (pitch is commanded, never read).
_ALWAYS_READ = ("missiontime", "depth", "energy_left")  # energy_left: the energy guard


class CodegenError(GliderplanError):
    """The mission uses something the C runtime cannot hold (the message says what and where)."""


def envelope_figures(envelope: contract.Envelope) -> tuple[tuple[str, float], ...]:
    """`gp_envelope`'s fields but its action, in its order: (C name, value [the units its
    names carry])."""
    return (("max_depth_m", envelope.max_depth_m), ("max_pitch_rad", envelope.max_pitch_rad),
            ("min_yo_band_m", envelope.min_yo_band_m),
            ("min_inflection_s", envelope.min_inflection_s),
            ("min_speed_mps", envelope.speed_range_mps[0]),
            ("max_speed_mps", envelope.speed_range_mps[1]),
            ("min_thrust_w", envelope.thrust_range_w[0]),
            ("max_thrust_w", envelope.thrust_range_w[1]),
            ("max_turn_rate_rad_s", envelope.max_turn_rate_rad_s),
            ("max_pump_power_w", envelope.max_pump_power_w),
            ("pump_out_j_per_cc", envelope.pump.out_j_per_cc),
            ("pump_out_j_per_cc_m", envelope.pump.out_j_per_cc_m),
            ("pump_in_j_per_cc", envelope.pump.in_j_per_cc),
            ("pump_in_j_per_cc_m", envelope.pump.in_j_per_cc_m))


def generate_c(mission: ir.CheckedMission, limits: FlightLimits, prefix: str = "") -> str:
    """The C source of the mission's tables, ready to compile with the runtime.

    `limits` are the vehicle's and the board's (`planner.limits.flight_limits`): the
    pumped volume flown where no plan sets one, the most a plan may set, the board's
    clocks; the runtime refuses a plan past them. `prefix` starts every name the file
    defines (its table is then `PREFIXgp_mission_table`), so that the sources of several
    missions make one translation unit (the generated differential tests build them so).
    """
    _check_limits(mission)
    return _MissionWriter(mission, limits, prefix).write()


def _sensors_read(mission: ir.CheckedMission) -> int:
    """Bit i set when the mission reads sensor i (conditions, assignments, profiles, routes)."""
    names = set(_ALWAYS_READ)
    for state in mission.states:
        for event in state.events:
            names |= ir.sensors_read(event.condition)
            for assign in event.assignments:
                names |= ir.sensors_read(assign.value)
        for profile in state.profiles:
            for arg in profile.args:
                names |= ir.sensors_read(arg)
            if PROFILES[profile.kind].tracks_thermocline:
                names.add("temp")
            if profile.has_altimeter_stop or profile.kind == "altitude":  # it follows the floor
                names.add("altitude")
        if state.route.kind in _HEADING_ROUTES:
            names |= {"lat", "lon"}
        if state.route.kind == "turn":  # it turns from the heading measured at entry
            names.add("heading")
    return sum(1 << SENSOR_BY_NAME[name].index for name in names)


def read_mask(mission: ir.CheckedMission) -> int:
    """Bit i set when the runtime reads sensor i from the link (HELLO's mask)."""
    return _sensors_read(mission) & ~contract.RUNTIME_READINGS_MASK


def own_read_mask(mission: ir.CheckedMission) -> int:
    """Bit i set for each of the runtime's own readings (halfcycle, wptdist) the mission
    reads: the runtime works out the distance to the waypoint only for a mission that
    reads it."""
    return _sensors_read(mission) & contract.RUNTIME_READINGS_MASK


# ---- expressions -------------------------------------------------------------------


_ARITHMETIC = {"+": "add", "-": "sub", "*": "mul", "/": "div"}
# Helpers the expressions call, emitted only when used (-Wunused-function).
_HELPERS = {
    # A truth value as a double through a call, not a conversion in place (see below).
    "truth": ("static double {p}mission_truth(int c)", "    return c ? 1.0 : 0.0;"),
    # Arithmetic through calls too: gcc's front end folds `0.0 - x` to `-x` for some x
    # (fabs, converted ints), wrong for x == +0.0; and on the i486's x87, whose registers
    # carry 80 bits, the return rounds each result to double as the reference does.
    **{name: (f"static double {{p}}mission_{name}(double a, double b)", f"    return a {op} b;")
       for name, op in (("add", "+"), ("sub", "-"), ("mul", "*"), ("div", "/"))},
    # fmin/fmax as ir.evaluate has them: a NaN argument is ignored, a tie keeps `a`.
    "fmin": ("static double {p}mission_fmin(double a, double b)",
             "    return isnan(a) ? b : isnan(b) ? a : b < a ? b : a;"),
    "fmax": ("static double {p}mission_fmax(double a, double b)",
             "    return isnan(a) ? b : isnan(b) ? a : b > a ? b : a;"),
}


@dataclass
class ExpressionWriter:
    """C text of expressions; `value` is a double, `truth` an int (0 or 1)."""

    helpers: set[str] = field(default_factory=set)  # of _HELPERS, as they are used
    prefix: str = ""  # of every name the file defines

    def value(self, expr: ir.Expr) -> str:
        match expr:
            case ir.Const(number):
                return c_double(number)
            case ir.SensorRef(name):
                return f"s[{sensor_index(name)}]"
            case ir.VarRef(name):
                return f"v[{self.prefix}VAR_{name}]"
            case ir.UnaryOp("-", operand):
                return f"(-{self.value(operand)})"
            case ir.BinaryOp("+" | "-" | "*" | "/" as op, left, right):
                name = _ARITHMETIC[op]
                self.helpers.add(name)
                return f"{self.prefix}mission_{name}({self.value(left)}, {self.value(right)})"
            case ir.FuncCall("abs", (arg,)):
                return f"fabs({self.value(arg)})"
            case ir.FuncCall("mod", (first, second)):  # exact: the same on every target
                return f"fmod({self.value(first)}, {self.value(second)})"
            case ir.FuncCall("min" | "max" as function, (first, second)):
                self.helpers.add(f"f{function}")
                return (f"{self.prefix}mission_f{function}({self.value(first)}, "
                        f"{self.value(second)})")
            case ir.UnaryOp("!") | ir.BinaryOp():
                self.helpers.add("truth")
                return f"{self.prefix}mission_truth{self.truth(expr)}"
        raise CodegenError(f"unsupported expression {expr!r}")

    def truth(self, expr: ir.Expr) -> str:
        match expr:
            case ir.UnaryOp("!", operand):
                return f"({self.value(operand)} == 0.0)"
            case ir.BinaryOp("&&" | "||" as op, left, right):
                return f"({self.truth(left)} {op} {self.truth(right)})"
            case ir.BinaryOp("<" | "<=" | ">" | ">=" | "==" | "!=" as op, left, right):
                return f"({self.value(left)} {op} {self.value(right)})"
        return f"({self.value(expr)} != 0.0)"


def c_double(number: float) -> str:
    """A C double literal whose value is exactly `number`, in any evaluation precision.

    Decimal when the decimal text is the binary value itself (integers, halves, ...);
    otherwise C99 hexadecimal with the decimal in a comment: on the i486's x87 a
    decimal constant is read in 80-bit precision (FLT_EVAL_METHOD 2), so `0.454`
    would not be the double the reference uses.
    """
    if math.isnan(number):
        return "NAN"
    if math.isinf(number):
        return "INFINITY" if number > 0 else "(-INFINITY)"
    text = repr(float(number))
    if Fraction(text) != Fraction(number):
        text = f"{float(number).hex()} /* {text} */"
    return f"({text})" if text.startswith("-") else text


# ---- limits ------------------------------------------------------------------------


def _check_limits(mission: ir.CheckedMission) -> None:
    def limit(what: str, count: int, most: int) -> None:
        if count > most:
            raise CodegenError(f"mission {mission.name}: {what}: {count} exceeds the "
                               f"runtime's limit of {most}")

    limit("states", len(mission.states), contract.MAX_STATES)
    limit("variables", len(mission.variables), contract.MAX_VARIABLES)
    limit("stack depth", mission.stack_depth, contract.MAX_STACK_DEPTH)
    for state in mission.states:
        where = f"state {state.name}"
        limit(f"{where}: flight-profile alternatives", len(state.profiles),
              contract.MAX_PROFILE_ALTERNATIVES)
        limit(f"{where}: events", len(state.events), contract.MAX_EVENTS_PER_STATE)
        limit(f"{where}: route points", len(_route_points(state.route)),
              contract.MAX_ROUTE_POINTS)
        if not state.profiles:
            raise CodegenError(f"mission {mission.name}: {where} has no flight profile")
        for profile in state.profiles:
            if profile.kind not in _PROFILE_KINDS:
                raise CodegenError(f"{where}: flight profile {profile.kind!r} has no "
                                   "runtime routine")
            limit(f"{where}: {profile.kind} arguments", len(profile.args),
                  contract.MAX_PROFILE_ARGS)
        if state.route.kind not in _ROUTE_KINDS:
            raise CodegenError(f"{where}: flight route {state.route.kind!r} has no "
                               "runtime routine")
        for event in state.events:
            if event.action not in _ACTIONS:
                raise CodegenError(f"{where}: unknown action {event.action!r}")


def _route_points(route: ir.Route) -> tuple[tuple[float, float], ...]:
    """The route's (lat, lon) table: nav's single point is its two parameters."""
    if route.kind == "nav":
        lat, lon = route.params
        return ((lat, lon),)
    return route.points


def _route_param(route: ir.Route) -> float:
    """The route's scalar parameter (sweep: line spacing [m], goto_list: radius [m],
    heading: the heading held [rad], as the Python pilot holds it; turn: the turn rate
    [rad/s]); 0 when it has none."""
    if route.kind == "heading":
        return held_heading_rad(route.params[0])
    if route.kind == "turn":
        return turn_rate_rad_s(route.params[0])
    return route.params[0] if route.kind in ("sweep", "goto_list") else 0.0


# ---- the file ----------------------------------------------------------------------


class _MissionWriter:
    """Writes the C file, one `visit_*` per part of the mission, each returning lines."""

    def __init__(self, mission: ir.CheckedMission, limits: FlightLimits, prefix: str = ""):
        self.mission = mission
        self.limits = limits
        self.p = prefix
        self.expressions = ExpressionWriter(prefix=prefix)

    def write(self) -> str:
        body: list[str] = []
        for index, state in enumerate(self.mission.states):
            body += self.visit_state(index, state)
        body += self.visit_mission()
        return "\n".join(self.visit_header() + body) + "\n"

    def visit_header(self) -> list[str]:
        mission = self.mission
        lines = [
            f"/* Mission {mission.name}: generated by gliderplan from the checked mission.",
            f" * Mission hash {mission.hash}.",
            " * Do not edit: run `gliderplan compile` again. */",
            "",
            "#include <math.h>",
            "#include <stddef.h>",
            "#include <stdint.h>",
            "",
            '#include "gp_mission.h"',
            "",
            f'_Static_assert(GP_N_SENSORS == {len(SENSORS)}, '
            '"the runtime and the compiler disagree on the sensor array");',
            "",
        ]
        if mission.variables:
            lines += [f"enum {self.p}variable_index {{",
                      *(f"    {self.p}VAR_{v.name} = {i},"
                        for i, v in enumerate(mission.variables)),
                      "};", ""]
        for name, (signature, body) in _HELPERS.items():
            if name in self.expressions.helpers:
                lines += [signature.format(p=self.p), "{", body, "}", ""]
        return lines

    def visit_state(self, index: int, state: ir.State) -> list[str]:
        prefix = f"{self.p}state{index}"
        lines = [f"/* ---- state {index}: {state.name} " + "-" * 40 + " */", ""]
        for number, event in enumerate(state.events):
            lines += self.visit_event(f"{prefix}_event{number}", event)
        lines += self.visit_event_table(prefix, state)
        for number, profile in enumerate(state.profiles):
            lines += self.visit_profile_args(f"{prefix}_profile{number}_args", profile)
        lines += [f"static const gp_profile {prefix}_profiles[{len(state.profiles)}] = {{"]
        lines += [f"    {{{_PROFILE_KINDS[p.kind]}, {len(p.args)}, "
                  f"{prefix}_profile{n}_args, {c_double(p.written_thrust_w)}}},"
                  for n, p in enumerate(state.profiles)]
        lines += ["};", ""]
        points = _route_points(state.route)
        if points:
            lines += [f"static const double {prefix}_route_points[{len(points)}][2] = {{"]
            lines += [f"    {{{c_double(lat)}, {c_double(lon)}}}," for lat, lon in points]
            lines += ["};", ""]
        if state.sensors:
            indices = ", ".join(sensor_index(u.name) for u in state.sensors)
            lines += [f"static const uint8_t {prefix}_sensors[{len(state.sensors)}] = "
                      f"{{{indices}}};", ""]
        return lines

    def visit_event(self, name: str, event: ir.Event) -> list[str]:
        lines = [f"static int {name}_condition(const double *s, const double *v)", "{",
                 *self._unused(event.condition, reads_vars=True),
                 f"    return {self.expressions.truth(event.condition)};", "}", ""]
        if event.assignments:
            values = [a.value for a in event.assignments]
            lines += [f"static void {name}_assign(const double *s, double *v)", "{",
                      *self._unused(*values, reads_vars=False)]
            lines += [f"    v[{self.p}VAR_{a.variable}] = {self.expressions.value(a.value)};"
                      for a in event.assignments]
            lines += ["}", ""]
        return lines

    def visit_event_table(self, prefix: str, state: ir.State) -> list[str]:
        if not state.events:
            return []
        lines = [f"static const gp_event {prefix}_events[{len(state.events)}] = {{"]
        for number, event in enumerate(state.events):
            assign = f"{prefix}_event{number}_assign" if event.assignments else "NULL"
            target = self.mission.state_index[event.target] if event.target else 0
            comment = f"  /* {event.action} {event.target} */" if event.target else ""
            lines.append(f"    {{{prefix}_event{number}_condition, {assign}, "
                         f"{_ACTIONS[event.action]}, {target}}},{comment}")
        return lines + ["};", ""]

    def visit_profile_args(self, name: str, profile: ir.Profile) -> list[str]:
        lines = [f"static void {name}(const double *s, const double *v, double *args)", "{",
                 *self._unused(*profile.args, reads_vars=True)]
        if not profile.args:
            lines.append("    (void)args;")
        lines += [f"    args[{i}] = {self.expressions.value(a)};"
                  for i, a in enumerate(profile.args)]
        return lines + ["}", ""]

    def visit_mission(self) -> list[str]:
        mission = self.mission
        lines = []
        if mission.variables:
            initial = ", ".join(c_double(v.initial) for v in mission.variables)
            lines += [f"static const double {self.p}var_initial[{len(mission.variables)}] = "
                      f"{{{initial}}};", ""]
        clocks = ", ".join(c_double(c) for c in self.limits.clocks_mhz)
        count = len(self.limits.clocks_mhz)
        lines += [f"static const double {self.p}board_clocks_mhz[{count}] = {{{clocks}}};", ""]
        lines += [f"static const char *const {self.p}sensor_names[GP_N_SENSORS] = {{",
                  *(f'    "{s.name}",' for s in SENSORS), "};", ""]
        lines += [f"static const gp_state {self.p}states[{len(mission.states)}] = {{"]
        for index, state in enumerate(mission.states):
            lines += self.visit_state_entry(index, state)
        lines += ["};", ""]
        lines += self.visit_plan_bounds()
        lines += [
            f"const gp_mission {self.p}gp_mission_table = {{",
            f"    .name = {_c_string(mission.name)},",
            f'    .hash = "{mission.hash}",',
            f"    .states = {self.p}states,",
            f"    .n_states = {len(mission.states)},",
            f"    .var_initial = {f'{self.p}var_initial' if mission.variables else 'NULL'},",
            f"    .n_vars = {len(mission.variables)},",
            f"    .stack_depth = {mission.stack_depth},",
            f"    .read_mask = 0x{read_mask(mission):08x}u,",
            f"    .own_read_mask = 0x{own_read_mask(mission):08x}u,",
            f"    .default_ballast_cc = {c_double(self.limits.default_ballast_cc)},",
            f"    .max_ballast_cc = {c_double(self.limits.max_ballast_cc)},",
            f"    .unplanned_speed_mps = {c_double(self.limits.unplanned_speed_mps)},",
            f"    .reserve_j = {c_double(mission.battery.reserve_j)},",
            *self.visit_envelope(),
            f"    .clocks_mhz = {self.p}board_clocks_mhz,",
            f"    .n_clocks = {len(self.limits.clocks_mhz)},",
            f"    .sensor_names = {self.p}sensor_names,",
            f"    .bounds = &{self.p}plan_bounds,",
            "};",
        ]
        return lines

    def visit_plan_bounds(self) -> list[str]:
        """`plan_bounds`: the figures `gp_plan_check` holds a plan to (`FlightLimits`)."""
        limits, lines, p = self.limits, [], self.p
        if limits.duty_bounds:
            for index, (duties, least) in enumerate(zip(limits.duty_bounds,
                                                        limits.min_ballast_cc, strict=True)):
                if duties:
                    rows = ", ".join(f"{{{SENSOR_BY_NAME[name].index}, {c_double(low)}, "
                                     f"{c_double(high)}}}" for name, low, high in duties)
                    lines.append(f"static const gp_duty_bound {p}state{index}_duties"
                                 f"[{len(duties)}] = {{{rows}}};")
                lines.append(f"static const double {p}state{index}_min_ballast_cc[{len(least)}] "
                             f"= {{{', '.join(c_double(x) for x in least)}}};")
            lines += [f"static const gp_state_bounds {p}state_bounds[{len(limits.duty_bounds)}] "
                      "= {",
                      *(f"    {{{f'{p}state{i}_duties' if duties else 'NULL'}, {len(duties)}, "
                        f"{p}state{i}_min_ballast_cc}},"
                        for i, duties in enumerate(limits.duty_bounds)), "};"]
        low, high = limits.pitch_range_rad
        board = "NULL" if limits.board is None else _c_string(limits.board)
        return lines + [
            f"static const gp_plan_bounds {p}plan_bounds = {{",
            f"    .board = {board},",
            f"    .max_budget_j = {c_double(limits.max_budget_j)},",
            f"    .min_pitch_rad = {c_double(low)},",
            f"    .max_pitch_rad = {c_double(high)},",
            f"    .max_speed_mps = {c_double(limits.max_speed_mps)},",
            f"    .min_propelled_mps = {c_double(limits.propelled_speed_mps[0])},",
            f"    .max_propelled_mps = {c_double(limits.propelled_speed_mps[1])},",
            f"    .min_thrust_w = {c_double(limits.thrust_range_w[0])},",
            f"    .max_thrust_w = {c_double(limits.thrust_range_w[1])},",
            f"    .states = {f'{p}state_bounds' if limits.duty_bounds else 'NULL'},",
            "};", ""]

    def visit_envelope(self) -> list[str]:
        """The vehicle's rating (contract.Envelope) as `gp_mission.envelope`."""
        env = self.limits.envelope
        return ["    .envelope = {",
                *(f"        .{name} = {c_double(value)}," for name, value in
                  envelope_figures(env)),
                f"        .action = GP_ENVELOPE_{env.action.name},",
                "    },"]

    def visit_state_entry(self, index: int, state: ir.State) -> list[str]:
        prefix = f"{self.p}state{index}"
        route = state.route
        points = _route_points(route)
        sensor_mask = sum(1 << SENSOR_BY_NAME[u.name].index for u in state.sensors)
        return [
            "    {",
            f"        .name = {_c_string(state.name)},",
            f"        .route = {{{_ROUTE_KINDS[route.kind]}, {len(points)}, "
            f"{c_double(_route_param(route))}, "
            f"{f'{prefix}_route_points' if points else 'NULL'}}},",
            f"        .profiles = {prefix}_profiles,",
            f"        .n_profiles = {len(state.profiles)},",
            f"        .unplanned_profile = {self.limits.unplanned_profile(index)},",
            f"        .sensors = {f'{prefix}_sensors' if state.sensors else 'NULL'},",
            f"        .n_sensors = {len(state.sensors)},",
            f"        .sensor_mask = 0x{sensor_mask:08x}u,",
            f"        .events = {f'{prefix}_events' if state.events else 'NULL'},",
            f"        .n_events = {len(state.events)},",
            *_power_fields(state.computer),
            "    },",
        ]

    @staticmethod
    def _unused(*exprs: ir.Expr, reads_vars: bool) -> list[str]:
        """`(void)` lines for the parameters the body does not read (-Wunused-parameter)."""
        lines = []
        if not any(ir.sensors_read(e) for e in exprs):
            lines.append("    (void)s;")
        if reads_vars and not any(ir.variables_read(e) for e in exprs):
            lines.append("    (void)v;")
        return lines


def _power_fields(use: ir.ComputerUse) -> list[str]:
    """A state's power management the runtime acts on without a plan: its fixed clock and
    sleep between ticks (fields left out are 0: the plan's clock, awake)."""
    lines = []
    if use.clock_mhz is not None:
        lines.append(f"        .clock_mhz = {c_double(use.clock_mhz)},")
    if use.sleep:
        lines.append("        .sleep = 1,")
    return lines


def _c_string(text: str) -> str:
    """A C string literal; names are identifiers, but escape anyway rather than trust it."""
    escaped = "".join(ch if ch.isascii() and ch.isprintable() and ch not in '"\\?'
                      else f"\\{ord(ch) & 0xFF:03o}" for ch in text)
    return f'"{escaped}"'
