"""Semantic checks of a parsed mission and its lowering to the checked-mission IR.

Passes run in order; the flow analysis runs only when names resolved, since it
needs them. Every pass reports all it finds, never just the first problem.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterable, Mapping
from typing import Any, TypeVar

from gliderplan.contract import (
    MAX_PLAN_ENERGY_J,
    MAX_PLAN_TIME_S,
    MAX_SENSOR_WEIGHT,
    MAX_STACK_DEPTH,
    NO_BOARD,
    RUNTIME_CYCLES_PER_TICK,
    TICK_S,
    Envelope,
)
from gliderplan.language import ast, ir
from gliderplan.language.diagnostics import Diagnostic, did_you_mean, error, warning
from gliderplan.language.flow import check_flow
from gliderplan.language.limits import check_sizes
from gliderplan.language.registry import (
    AUTO_PARAMS,
    FUNCTIONS,
    PROFILES,
    ROUTES,
    SENSOR_BY_NAME,
    ParamSpec,
    cannot_fly,
    turn_rate_rad_s,
)
from gliderplan.language.units import UnitProblem, normalise

_ACTIONS = ("goto", "call", "return", "exit")
T = TypeVar("T")


class _Checker:
    def __init__(self, mission: ast.Mission, stack_depth: int | None, base_dir: str = "",
                 model_files: bool = False):
        self.mission = mission
        self.model_files = model_files  # open the vehicle and board files it names
        self.stack_depth_override = stack_depth
        self.base_dir = base_dir  # the mission's folder: the files it names are beside it
        self.written: list[tuple[str, str]] = []  # (field, file as written) of each file
        self.diagnostics: list[Diagnostic] = []
        self.variables: dict[str, ast.VarDecl] = {}
        self.state_names = {s.name.text for s in mission.states}
        self.computer = ir.DEFAULT_COMPUTER  # the mission's board, for its states' settings
        self._board: object | None = None  # the board, loaded once when a state needs it
        self.vehicle_spec = ir.DEFAULT_VEHICLE  # the mission's vehicle, for its envelope
        self._vehicle: object | None = None  # the vehicle, loaded once when a profile needs it
        # a vehicle file the mission names, loaded and checked when model files are opened
        self._vehicle_file: object | None = None
        self._envelope: object | None = None  # its envelope, loaded once a profile needs it

    # ---- reporting helpers
    def error(self, message: str, span: ast.Span, hint: str | None = None) -> None:
        self.diagnostics.append(error(message, span, hint))

    def warning(self, message: str, span: ast.Span, hint: str | None = None) -> None:
        self.diagnostics.append(warning(message, span, hint))

    def error_count(self) -> int:
        return sum(d.is_error for d in self.diagnostics)

    def quantity(self, quantity: ast.Quantity, *dimensions: str) -> tuple[float, str] | None:
        if not math.isfinite(quantity.value):
            self.error(f"{quantity.text} is too large for a number", quantity.span)
            return None
        try:
            value, dimension = normalise(quantity.value,
                                         quantity.unit.text if quantity.unit else None,
                                         dimensions)
        except UnitProblem as problem:
            span = quantity.unit.span if quantity.unit else quantity.span
            self.error(problem.message, span, problem.hint)
            return None
        if not math.isfinite(value):  # 1e305 kJ is a number, but not once converted
            written = f"{quantity.text} {quantity.unit.text}" if quantity.unit else quantity.text
            self.error(f"{written} is too large for a number", quantity.span)
            return None
        return value, dimension

    # ---- the whole mission
    def run(self) -> ir.CheckedMission | None:
        fields = self.declarations()
        states = self.states()
        lowered = not self.error_count()
        # Read off the tree whatever else is wrong, and no reason to skip the flow analysis.
        self.diagnostics.extend(check_sizes(self.mission))
        if not lowered:
            return None
        mission = ir.CheckedMission(name=self.mission.name.text, states=tuple(states), **fields)
        spans = {s.name.text: s for s in self.mission.states}
        self.diagnostics.extend(check_flow(mission, spans))
        if self._vehicle_file is not None:
            self.yos_flyable(mission)
        if self.error_count():
            return None
        return mission

    def yos_flyable(self, mission: ir.CheckedMission) -> None:
        """An error at each yo of constant depths the mission's vehicle file cannot fly at its
        pitch and unplanned volume (`sim` would refuse it: `yo_flight_problem`); a yo the
        vehicle cannot fly at all (an AUV's) is `flyable`'s to say."""
        from gliderplan.power_models.vehicle import yo_flight_problem

        vehicle = self._vehicle_file
        for state, node in zip(mission.states, self.mission.states, strict=True):
            written = next(i for i in node.items if isinstance(i, ast.ProfileItem))
            for k, (profile, call) in enumerate(zip(state.profiles, written.alternatives,
                                                    strict=True)):
                if cannot_fly(profile.kind, profile.thrust, vehicle) is not None:
                    continue
                problem = yo_flight_problem(f"{state.name}: flightprofile {k}", vehicle,
                                            profile.kind, profile.constant_args())
                if problem is not None:
                    self.error(f"{problem}", call.span, "a deeper pump (max_ballast), a "
                               "lighter trim or a shallower yo")

    # ---- mission-level declarations
    def declarations(self) -> dict:
        fields: dict = {}
        seen: dict[type, ast.Declaration] = {}
        prefs: list[ir.SensorPreference] = []
        variables: list[ir.Variable] = []
        for decl in self.mission.declarations:
            if not isinstance(decl, ast.SensorDecl | ast.VarDecl):
                if type(decl) in seen:
                    first = seen[type(decl)].span.line
                    self.error(f"'{_keyword(decl)}' is declared twice", decl.span,
                               f"the first declaration is on line {first}")
                    continue
                seen[type(decl)] = decl
            match decl:
                case ast.VehicleDecl():
                    known = self.preset_known("vehicle", decl.preset, decl.is_file)
                    fields["vehicle"] = self.beside("vehicle", decl.preset.text, decl.is_file)
                    if known:
                        self.vehicle_spec = fields["vehicle"]
                    if decl.is_file and self.model_files:
                        self._vehicle_file = self.model_file("vehicle", fields["vehicle"],
                                                             decl.preset)
                case ast.ComputerDecl() if decl.board.text == NO_BOARD:
                    fields["computer"] = self.computer = ir.Computer(NO_BOARD)
                    if decl.clock is not None:
                        self.error(f"'computer {NO_BOARD}' has no clock", decl.clock.span,
                                   "the glider's own computers run the mission, unclocked "
                                   f"by it: write 'computer {NO_BOARD}', or name a board, "
                                   "e.g. 'computer ts7800 @ 300 MHz'")
                case ast.ComputerDecl():
                    known = self.preset_known("board", decl.board, decl.is_file)
                    clock_mhz = None
                    if decl.clock is not None and (mhz := self.quantity(decl.clock, "clock")):
                        clock_mhz = mhz[0]
                        if clock_mhz <= 0:
                            self.error("clock must be positive", decl.clock.span)
                    board = self.beside("computer", decl.board.text, decl.is_file)
                    fields["computer"] = self.computer = ir.Computer(board, clock_mhz)
                    if decl.is_file and self.model_files:
                        self._board = self.model_file("board", board, decl.board) or False
                    if known and clock_mhz is not None and clock_mhz > 0 and \
                            (board := self.board(decl.clock.span)) is not None:
                        self.clock_known(board, clock_mhz, decl.clock.span,
                                         "or leave the clock out: the planner picks one")
                case ast.BatteryDecl():
                    if (battery := self.battery(decl)) is not None:
                        fields["battery"] = battery
                case ast.HorizonDecl():
                    if (horizon := self.quantity(decl.duration, "time")) is not None:
                        if not TICK_S <= horizon[0] <= MAX_PLAN_TIME_S:
                            self.error(f"horizon must lie between one tick ({TICK_S:g} s) and "
                                       f"{MAX_PLAN_TIME_S / 86400 / 365:g} years",
                                       decl.duration.span, "the time the mission is planned "
                                       "and simulated for, e.g. 'horizon 30 d'")
                        fields["horizon_s"] = horizon[0]
                case ast.StartDecl(lat, lon):
                    if -90.0 <= lat.value <= 90.0 and -180.0 <= lon.value <= 180.0:
                        fields["start_deg"] = (lat.value, lon.value)
                    else:
                        self.error("start: latitude must lie in [-90, 90] and longitude in "
                                   "[-180, 180] degrees", decl.span, "where the glider is put "
                                   "in the water, decimal degrees: e.g. 'start 54.2, 7.0'")
                case ast.CorrectionDecl(setting):
                    if setting.text in ("on", "off"):
                        fields["current_correction"] = setting.text == "on"
                    else:
                        self.error(f"current_correction {setting.text}: expected on or off",
                                   setting.span, "whether the glider heads upstream of its "
                                   "waypoint for the current it measured (Slocum "
                                   "u_use_current_correction)")
                case ast.ObjectiveDecl():
                    fields["objective"] = self.objective(decl)
                case ast.SensorDecl():
                    if (pref := self.sensor_preference(decl, prefs)) is not None:
                        prefs.append(pref)
                case ast.VarDecl():
                    if (var := self.variable(decl)) is not None:
                        variables.append(var)
                case ast.StackDecl():
                    depth = decl.depth.value
                    if depth != int(depth) or not 1 <= depth <= MAX_STACK_DEPTH:
                        self.error(f"stack depth must be a whole number from 1 to "
                                   f"{MAX_STACK_DEPTH}", decl.depth.span,
                                   f"the runtime's state stack holds at most "
                                   f"{MAX_STACK_DEPTH} states")
                    else:
                        fields["stack_depth"] = int(depth)
        if self.stack_depth_override is not None:
            fields["stack_depth"] = self.stack_depth_override
        fields["files_as_written"] = tuple(self.written)
        fields["sensor_preferences"] = tuple(prefs)
        fields["variables"] = tuple(variables)
        fields["defaults_used"] = tuple(
            name for name, kind in (("vehicle", ast.VehicleDecl), ("computer", ast.ComputerDecl),
                                    ("battery", ast.BatteryDecl))
            if kind not in seen
        )
        return fields

    def beside(self, field: str, spec: str, is_file: bool) -> str:
        """The file a mission names (`vehicle "my.toml"`), found beside the mission rather
        than in the working directory: resolved here, once, for every later stage (the
        IR holds the path, its hash the text as written); a preset name as it is."""
        if not is_file or os.path.isabs(spec) or not self.base_dir:
            return spec
        self.written.append((field, spec))
        return os.path.join(self.base_dir, spec)

    def preset_known(self, kind: str, name: ast.Ident, is_file: bool) -> bool:
        """False, with an error, for a preset name that is not shipped; a user's file is
        loaded and validated by the power models when its figures are needed."""
        if is_file:
            return True
        from gliderplan.power_models.catalog import preset_names

        names = preset_names(kind) + ([NO_BOARD] if kind == "board" else [])
        if name.text not in names:
            hint = did_you_mean(name.text, names) or f"presets: {', '.join(names)}"
            self.error(f"unknown {kind} preset '{name.text}'", name.span,
                       f"{hint}; or give a file as \"path/to/{kind}.toml\"")
            return False
        return True

    def battery(self, decl: ast.BatteryDecl) -> ir.Battery | None:
        reserve = 0.0
        if decl.reserve is not None and (fraction := self.quantity(decl.reserve, "fraction")):
            reserve = fraction[0]
            if not 0 <= reserve < 1:
                self.error("reserve must be at least 0 % and below 100 %", decl.reserve.span,
                           "the reserve is the part of the battery the plan must not use")
        if decl.preset is not None:
            return self.battery_pack(decl, reserve if decl.reserve is not None else None)
        capacity = self.quantity(decl.capacity, "energy", "charge")
        if capacity is None:
            return None
        energy_j, dimension = capacity
        if dimension == "charge":
            if decl.voltage is None:
                self.error("a charge needs a voltage to become energy", decl.capacity.span,
                           f"write e.g. '{decl.capacity.text} {decl.capacity.unit.text} "
                           "at 14.4 V'")
                return None
            if (volts := self.quantity(decl.voltage, "voltage")) is None:
                return None
            energy_j *= volts[0]
        elif decl.voltage is not None:
            self.error("a voltage only applies to a charge (Ah)", decl.voltage.span)
        if energy_j <= 0:
            self.error("battery capacity must be positive", decl.capacity.span)
            return None
        if energy_j > MAX_PLAN_ENERGY_J:
            self.error(f"a battery of {energy_j:.3g} J is larger than any plan can carry "
                       f"({MAX_PLAN_ENERGY_J:g} J; the largest Slocum pack holds 12 MJ)",
                       decl.capacity.span)
            return None
        return ir.Battery(energy_j, reserve)

    def battery_pack(self, decl: ast.BatteryDecl, reserve: float | None) -> ir.Battery | None:
        """`battery alkaline` or `battery "pack.toml"`: the pack's energy, and its reserve
        unless the line gives one (the part the pack's `usable_fraction` leaves), as
        `plan --battery PRESET` reads it."""
        if not self.preset_known("battery", decl.preset, decl.is_file):
            return None

        pack = self.model_file("battery", self.beside("battery", decl.preset.text,
                                                      decl.is_file), decl.preset)
        if pack is None:
            return None
        return ir.Battery(pack.energy_j, 1.0 - pack.usable_fraction if reserve is None
                          else reserve)

    def objective(self, decl: ast.ObjectiveDecl) -> ir.Objective:
        wanted = {("maximize", "quality"), ("minimize", "energy")}
        pair = (decl.sense.text, decl.target.text)
        if pair not in wanted:
            self.error(f"cannot {pair[0]} '{pair[1]}'", decl.target.span,
                       "write 'objective maximize quality' or "
                       "'objective minimize energy quality >= N'")
            return ir.Objective()
        floor = decl.quality_floor.value if decl.quality_floor else 0.0
        if not 0 <= floor <= 1:
            self.error("a quality floor must lie between 0 and 1", decl.quality_floor.span,
                       "quality runs from 0 (no science) to 1 (every sensor always on)")
        if pair == ("maximize", "quality"):
            if decl.quality_floor is not None:
                self.warning("a quality floor has no effect when maximizing quality",
                             decl.quality_floor.span)
            return ir.Objective("maximize_quality", 0.0)
        return ir.Objective("minimize_energy", floor)

    def sensor_preference(self, decl: ast.SensorDecl,
                          earlier: list[ir.SensorPreference]) -> ir.SensorPreference | None:
        if not self.sensor_known(decl.sensor):
            return None
        if any(p.sensor == decl.sensor.text for p in earlier):
            self.error(f"sensor '{decl.sensor.text}' is annotated twice", decl.sensor.span)
            return None
        weight = 1.0
        for bound in decl.bounds:
            if bound.kind == "weight":
                weight = bound.value.value
                if not 0 <= weight <= MAX_SENSOR_WEIGHT:
                    self.error(f"a weight must lie between 0 and {MAX_SENSOR_WEIGHT:g}",
                               bound.value.span, "weights are relative to each other: "
                               "1 and 3 say the second sensor counts three times as much")
        duty_min, duty_max, quality_min = self.bounds(decl.bounds, decl.sensor.text)
        return ir.SensorPreference(decl.sensor.text, weight, duty_min, duty_max, quality_min)

    def bounds(self, bounds: Iterable[ast.Bound], sensor: str) -> tuple[float, float, float]:
        """(duty_min, duty_max, quality_min) from duty and quality bounds; checks consistency."""
        duty_min, duty_max, quality_min = 0.0, 1.0, 0.0
        for bound in bounds:
            value = bound.value.value
            if bound.kind == "weight":
                continue
            if not 0 <= value <= 1:
                self.error(f"{bound.kind} must lie between 0 and 1", bound.value.span,
                           f"a {bound.kind} is a fraction: write e.g. 0.25 for a quarter")
                continue
            if bound.kind == "quality":
                quality_min = max(quality_min, value)
            elif bound.op in (">=", ">"):
                duty_min = max(duty_min, value)
            elif bound.op in ("<=", "<"):
                duty_max = min(duty_max, value)
            elif bound.op == "==":
                duty_min, duty_max = max(duty_min, value), min(duty_max, value)
            else:
                self.error(f"'duty {bound.op}' is not a bound", bound.span,
                           "use >=, <= or ==")
        if duty_min > duty_max:
            duties = [b.span for b in bounds if b.kind == "duty"]
            span = ast.Span(duties[0].line, duties[0].column, duties[-1].end_line,
                            duties[-1].end_column)
            self.error(f"duty bounds of '{sensor}' contradict each other: at least "
                       f"{duty_min:g} but at most {duty_max:g}", span,
                       "no duty satisfies both; drop one bound or swap the numbers")
        return duty_min, duty_max, quality_min

    def variable(self, decl: ast.VarDecl) -> ir.Variable | None:
        name = decl.name.text
        if name in SENSOR_BY_NAME:
            self.error(f"variable '{name}' has the name of a sensor", decl.name.span,
                       "choose another name")
            return None
        if name in self.variables:
            self.error(f"variable '{name}' is declared twice", decl.name.span,
                       f"the first declaration is on line {self.variables[name].span.line}")
            return None
        self.variables[name] = decl
        value = self.constant(decl.initial, "an initial value")
        return None if value is None else ir.Variable(name, value)

    # ---- states
    def states(self) -> list[ir.State]:
        if not self.mission.states:
            self.error("the mission has no states", self.mission.name.span,
                       "add 'state NAME begin ... end'; the first state is the start state")
        seen: dict[str, ast.State] = {}
        lowered = []
        for state in self.mission.states:
            if state.name.text in seen:
                self.error(f"state '{state.name.text}' is defined twice", state.name.span,
                           f"the first definition is on line {seen[state.name.text].span.line}")
                continue
            seen[state.name.text] = state
            if (result := self.state(state)) is not None:
                lowered.append(result)
        return lowered

    def state(self, state: ast.State) -> ir.State | None:
        errors_before = self.error_count()
        items: dict[type, ast.StateItem] = {}
        requirements = []
        computer_items = []
        for item in state.items:
            if isinstance(item, ast.RequireItem):
                requirements.append(item)
                continue
            if isinstance(item, ast.ComputerItem):
                computer_items.append(item)
                continue
            if type(item) in items:
                self.error(f"state '{state.name.text}' has two '{_keyword(item)}' sections",
                           item.span, f"the first is on line {items[type(item)].span.line}")
                continue
            items[type(item)] = item
        if ast.ProfileItem not in items:
            self.error(f"state '{state.name.text}' has no flightprofile", state.name.span,
                       "add e.g. 'flightprofile yo(5, 20, .454, .454)'")
            return None
        route_item = items.get(ast.RouteItem)
        route = self.route(route_item.route) if route_item else ir.Route("noheading")
        written = items[ast.ProfileItem].alternatives
        profiles = [self.profile(p, written) for p in written]
        sensors_item = items.get(ast.SensorsItem)
        sensors = self.sensor_uses(sensors_item) if sensors_item else []
        events_item = items.get(ast.EventsItem)
        events = [self.event(e) for e in events_item.events] if events_item else []
        expect_item = items.get(ast.ExpectItem)
        expect = self.expect(expect_item) if expect_item else None
        logged = {s.name for s in sensors if s is not None}
        reqs = [self.requirement(r, logged) for r in requirements]
        computer = self.computer_use(state.name.text, computer_items)
        if self.error_count() > errors_before:
            return None
        return ir.State(
            name=state.name.text,
            route=route,
            profiles=tuple(profiles),
            sensors=tuple(sensors),
            events=tuple(events),
            expect_s=expect,
            requirements=tuple(reqs),
            computer=computer,
            profile_line=items[ast.ProfileItem].span.line,
        )

    def registered(self, ident: ast.Ident, table: Mapping[str, T], kind: str,
                   plural: str) -> T | None:
        """The registry entry `ident` names, or an error that lists the near misses."""
        info = table.get(ident.text)
        if info is None:
            self.error(f"unknown {kind} '{ident.text}'", ident.span,
                       did_you_mean(ident.text, table) or f"{plural}: {', '.join(table)}")
        return info

    def route(self, invocation: ast.Invocation) -> ir.Route | None:
        name = invocation.name.text
        info = self.registered(invocation.name, ROUTES, "flight route", "routes")
        if info is None:
            return None
        scalars = [a for a in invocation.args if not isinstance(a, ast.Point)]
        points = [a for a in invocation.args if isinstance(a, ast.Point)]
        order_ok = all(not isinstance(a, ast.Point) for a in invocation.args[: len(scalars)])
        count_ok = len(scalars) == len(info.params) and (
            info.min_points <= len(points) <= info.max_points)
        if not (order_ok and count_ok):
            signature = _signature(info.params, info.min_points, info.max_points)
            self.error(f"'{name}' takes {signature}", invocation.span,
                       f"got {len(scalars)} number(s) and {len(points)} point(s)")
            return None
        params = [self.ranged_constant(a, spec, name)
                  for a, spec in zip(scalars, info.params, strict=True)]
        coords = []
        for point in points:
            lat = self.ranged_constant(point.lat, ROUTES["nav"].params[0], name)
            lon = self.ranged_constant(point.lon, ROUTES["nav"].params[1], name)
            coords.append((lat, lon))
        if None in params or any(None in c for c in coords):
            return None
        if name == "turn":
            self.turn_rated(params[0], scalars[0].span)
        return ir.Route(name, tuple(params), tuple(coords))

    def turn_rated(self, rate_deg_s: float, span: ast.Span) -> None:
        """An error for a turn faster than the vehicle's rated `max_turn_rate`: the
        envelope would slew it to that rate in flight, so the spiral would not be flown."""
        envelope = self.envelope()
        if envelope is not None and turn_rate_rad_s(abs(rate_deg_s)) > \
                envelope.max_turn_rate_rad_s:
            rated = math.degrees(envelope.max_turn_rate_rad_s)
            self.error(f"turn rate {rate_deg_s:g} deg/s is beyond the vehicle's rated "
                       f"{rated:.3g} deg/s", span,
                       f"the rating of vehicle {self.vehicle_spec} (its file's [envelope])")

    def profile(self, invocation: ast.Invocation, alternatives: tuple[ast.Invocation, ...]
                ) -> ir.Profile | None:
        name = invocation.name.text
        info = self.registered(invocation.name, PROFILES, "flight profile", "profiles")
        if info is None:
            return None
        if not info.required <= len(invocation.args) <= len(info.params) or any(
                isinstance(a, ast.Point) for a in invocation.args):
            takes = str(len(info.params)) if info.required == len(info.params) else \
                f"{info.required} or {len(info.params)}"
            self.error(f"'{name}' takes {takes} argument(s), "
                       f"got {len(invocation.args)}", invocation.span,
                       f"{name}({', '.join(_parameter(p) for p in info.params)})")
            return None
        auto = self.auto_arguments(invocation, info.params)
        thrust = self.thrust(invocation)
        if auto is None:
            return None
        written = invocation.args[:len(invocation.args) - len(auto)]
        args = [self.expression(a, allow_sensors=False) for a in written]
        if None in args:
            return None
        values, spans = {}, {}
        for arg, node, spec in zip(args, written, info.params, strict=False):
            spans[spec.name] = node.span
            if not ir.variables_read(arg):
                value = ir.evaluate(arg, {}, {})
                if self.in_range(value, spec, name, node.span):
                    values[spec.name] = value
        if "min_depth" in values and "max_depth" in values and (
                values["min_depth"] >= values["max_depth"]):
            self.error(f"min depth {values['min_depth']:g} m is not above max depth "
                       f"{values['max_depth']:g} m", invocation.span,
                       f"{name}(min_depth, max_depth, ...): the glider turns at min_depth "
                       "on the way up and at max_depth on the way down")
        elif values:
            self.within_envelope(invocation, values)
        profile = ir.Profile(name, tuple(args), auto, thrust)
        if profile.propelled or self.vehicle_spec != ir.DEFAULT_VEHICLE:
            # the default glider flies every buoyancy profile: no need to load it
            self.flyable(profile, invocation, values.get("speed"), spans.get("speed"),
                         alternatives)
        return profile

    def auto_arguments(self, invocation: ast.Invocation, params: tuple[ParamSpec, ...]
                       ) -> tuple[str, ...] | None:
        """The names of the arguments written `auto` (a propelled profile's speed, its last
        argument); None, with an error, for an `auto` the profile cannot take."""
        auto = []
        for node, spec in zip(invocation.args, params, strict=False):
            if isinstance(node, ast.Ident):
                if spec.name not in AUTO_PARAMS:
                    self.error(f"'{spec.name}' of '{invocation.name.text}' cannot be 'auto'",
                               node.span, "only a propelled profile's speed is the planner's "
                               "to choose, e.g. 'cruise(10, auto)'")
                    return None
                auto.append(spec.name)
        return tuple(auto)

    def thrust(self, invocation: ast.Invocation) -> float | str | None:
        """A yo's thruster setting: its commanded power [W], "auto" or None (none, or an
        error)."""
        setting = invocation.thrust
        if setting is None:
            return None
        if invocation.name.text not in ("yo", "thermotrackyo"):
            self.error(f"a thruster assists a yo, not '{invocation.name.text}'", setting.span,
                       "a propelled profile sets its speed instead: e.g. 'cruise(10, auto)'")
            return None
        if isinstance(setting, ast.Ident):
            return "auto"
        power = self.quantity(setting, "power")
        if power is None:
            return None
        if power[0] <= 0.0:
            self.error(f"thrust must be positive, got {power[0]:g} W", setting.span,
                       "leave 'thrust' out to glide on buoyancy alone")
            return None
        return power[0]

    def vehicle(self) -> object | None:
        """The mission's vehicle (power_models.vehicle.Vehicle), loaded once; None when its
        file cannot be read or is bad: the stage that needs its figures (plan, sim,
        compile) says so, with its own exit status (a file that cannot be opened is a usage
        error, not the mission's)."""
        if self._vehicle is None and self._vehicle_file is not None:
            self._vehicle = self._vehicle_file  # loaded once
        if self._vehicle is None:
            from gliderplan.contract.files import InputFileError
            from gliderplan.power_models.errors import ModelFileError
            from gliderplan.power_models.vehicle import load_vehicle

            try:
                self._vehicle = load_vehicle(self.vehicle_spec)
            except (ModelFileError, InputFileError):
                self._vehicle = False
        return self._vehicle or None

    def flyable(self, profile: ir.Profile, invocation: ast.Invocation, speed_mps: float | None,
                speed_span: ast.Span | None, alternatives: tuple[ast.Invocation, ...]) -> None:
        """An error where the vehicle cannot fly the profile (`cannot_fly`; a warning for one
        of several `alternatives`, which the planner then skips), or a speed or thrust
        beyond its propulsion model."""
        vehicle = self.vehicle()
        if vehicle is None:
            return
        from gliderplan.power_models.propulsion import SpeedOutOfRange

        if (problem := cannot_fly(profile.kind, profile.thrust, vehicle)) is not None:
            why, hint, thrust = problem
            span = invocation.thrust.span if thrust else invocation.name.span
            if any(a.name.text in PROFILES and cannot_fly(a.name.text, a.thrust, vehicle)
                   is None for a in alternatives):  # the planner flies those
                self.warning(f"{why}: the planner gives it no time", span, hint)
            else:
                self.error(why, span, hint)
            return
        propulsion = vehicle.propulsion
        checks = [(propulsion.check_command, profile.thrust, invocation.thrust.span)] \
            if isinstance(profile.thrust, float) else []
        if speed_mps is not None and propulsion is not None:
            checks.append((propulsion.check_speed, speed_mps, speed_span))
        for check, value, span in checks:
            try:
                check(value)
            except SpeedOutOfRange as err:
                self.error(f"vehicle {vehicle.name}: {err}", span,
                           "'auto' lets the planner choose")

    def within_envelope(self, invocation: ast.Invocation, values: dict[str, float]) -> None:
        """Errors for the constant arguments of a profile outside the vehicle's rating
        (docs/pilot.md, The envelope): what the runtime would refuse in flight."""
        envelope = self.envelope()
        if envelope is None:
            return
        spans = {spec.name: node.span for spec, node in zip(
            PROFILES[invocation.name.text].params, invocation.args, strict=False)}
        hint = f"the rating of vehicle {self.vehicle_spec} (its file's [envelope])"
        for param in ("min_depth", "max_depth", "depth"):
            if values.get(param, 0.0) > envelope.max_depth_m:
                self.error(f"{param.replace('_', ' ')} {values[param]:g} m is beyond the "
                           f"vehicle's rated {envelope.max_depth_m:g} m", spans[param], hint)
        for param in ("dive_pitch", "climb_pitch"):
            if values.get(param, 0.0) > envelope.max_pitch_rad:
                self.error(f"{param.replace('_', ' ')} {values[param]:g} rad is beyond the "
                           f"vehicle's {envelope.max_pitch_rad:.3g} rad", spans[param], hint)
        if "min_depth" in values and "max_depth" in values and (
                values["max_depth"] - values["min_depth"] < envelope.min_yo_band_m):
            band = values["max_depth"] - values["min_depth"]
            self.error(f"yo band {band:g} m is thinner than the "
                       f"vehicle's {envelope.min_yo_band_m:g} m: it would turn all the time",
                       invocation.span, hint)

    def envelope(self) -> Envelope | None:
        """The mission's vehicle's envelope, loaded once; None when its file cannot be read
        (what is wrong with it is said, with its own exit code, where the vehicle is
        loaded to be flown or planned)."""
        if self._envelope is None:
            from gliderplan.contract.files import InputFileError
            from gliderplan.power_models.errors import ModelFileError
            from gliderplan.power_models.vehicle_figures import load_envelope

            try:
                self._envelope = load_envelope(self.vehicle_spec)
            except (ModelFileError, InputFileError):
                self._envelope = False
        return self._envelope or None

    def sensor_uses(self, item: ast.SensorsItem) -> list[ir.SensorUse | None]:
        uses: list[ir.SensorUse | None] = []
        seen: set[str] = set()
        for use in item.sensors:
            name = use.sensor.text
            if not self.sensor_known(use.sensor):
                uses.append(None)
                continue
            if name in seen:
                self.error(f"sensor '{name}' is listed twice", use.sensor.span)
                continue
            seen.add(name)
            duty: float | str | None = None
            if isinstance(use.duty, ast.Ident):
                duty = "auto"
            elif isinstance(use.duty, ast.Number):
                duty = use.duty.value
                if not 0 <= duty <= 1:
                    self.error("duty must lie between 0 and 1", use.duty.span,
                               "a duty is the fraction of time the sensor is on")
            if duty is not None and SENSOR_BY_NAME[name].device is None:
                self.error(f"'{name}' is a flight sensor, always on: it has no duty",
                           use.duty.span, "duty applies to science sensors such as temp")
            uses.append(ir.SensorUse(name, duty))
        return uses

    def expect(self, item: ast.ExpectItem) -> tuple[float, float] | None:
        low, high = self.quantity(item.low, "time"), self.quantity(item.high, "time")
        if low is None or high is None:
            return None
        if not 0 <= low[0] <= high[0]:  # past the horizon (at most 10 y): runs to it
            self.error("expected time must be a range 'low .. high' with 0 <= low <= high",
                       item.span)
            return None
        return low[0], high[0]

    def model_file(self, kind: str, spec: str, written: ast.Ident) -> Any:
        """The vehicle, board or battery in `spec` (a file the mission names, or a preset),
        its figures checked against their physical ranges (`power_models.plausible`); None,
        with an error at the name as `written`, when it cannot be loaded."""
        from gliderplan.contract.errors import GliderplanError

        if kind == "vehicle":  # each kind's loader only: a board's leaves numpy unimported
            from gliderplan.power_models.vehicle import load_vehicle as load
        elif kind == "board":
            from gliderplan.power_models.board import load_board as load
        else:
            from gliderplan.power_models.battery import load_battery as load
        try:
            return load(spec)
        except GliderplanError as err:
            self.error(f"{kind} {written.text}: {err}", written.span)
            return None

    # ---- power management
    def board(self, span: ast.Span) -> object | None:
        """The mission's board (power_models.board.Board), loaded once; None, with an
        error at `span`, when its file cannot be read."""
        if self._board is None:
            from gliderplan.contract.files import InputFileError
            from gliderplan.power_models.board import load_board
            from gliderplan.power_models.errors import ModelFileError

            try:
                self._board = load_board(self.computer.board)
            except (ModelFileError, InputFileError) as err:
                self.error(f"computer settings need the board's figures: {err}", span)
                self._board = False
        return self._board or None

    def clock_known(self, board, clock_mhz: float, span: ast.Span, hint: str) -> bool:
        """Whether the board's data file has this clock (`Board.has_clock`: the test the
        plan readers, Python and C, apply to a plan's clocks); an error at `span` if not."""
        if board.has_clock(clock_mhz):
            return True
        self.error(f"board {board.name} has no {clock_mhz:g} MHz clock", span,
                   f"its clocks: {board.clocks_text()} MHz; {hint}")
        return False

    def computer_use(self, state: str, items: list[ast.ComputerItem]) -> ir.ComputerUse:
        """A state's `computer clock | sleep | workload` settings, checked against the
        board's data file: a clock it has, a sleep it wakes from on the serial line, a
        workload one of its clocks runs within the runtime's tick."""
        if self.computer.is_none:
            for item in items:
                self.error(f"state '{state}' sets 'computer {item.setting}', but the mission "
                           f"has no board to set ('computer {NO_BOARD}')", item.span,
                           "the glider's own computers run the mission: remove the line, "
                           "or name a board, e.g. 'computer ts7800'")
            return ir.NO_COMPUTER_USE
        seen: dict[str, ast.ComputerItem] = {}
        for item in items:
            if item.setting in seen:
                self.error(f"state '{state}' sets 'computer {item.setting}' twice", item.span,
                           f"the first is on line {seen[item.setting].span.line}")
            seen.setdefault(item.setting, item)
        if not seen or (board := self.board(items[0].span)) is None:
            return ir.NO_COMPUTER_USE
        clocks = [m.clock_mhz for m in board.clock_modes]
        use = ir.ComputerUse()
        if (item := seen.get("clock")) is not None:
            if isinstance(item.value, ast.Ident):
                use = ir.ComputerUse(clock_auto=True)
            elif (clock := self.quantity(item.value, "clock")) is not None:
                mhz = clock[0]
                self.clock_known(board, mhz, item.value.span, "or 'computer clock auto'")
                use = ir.ComputerUse(clock_mhz=mhz)
        allowed = [use.clock_mhz] if use.clock_mhz else clocks if use.clock_auto else \
            [self.computer.clock_mhz] if self.computer.clock_mhz else clocks
        fastest_hz = max(allowed) * 1e6 * board.cycles_per_clock
        cycles = None
        if (item := seen.get("workload")) is not None:
            cycles = item.value.value
            capacity = fastest_hz * TICK_S
            if not (math.isfinite(cycles) and cycles > 0):
                self.error("a workload is a positive number of cycles", item.value.span)
                cycles = None
            elif cycles > capacity:
                self.error(f"board {board.name} runs at most {capacity:,.0f} cycles in a "
                           f"{TICK_S:g} s tick (at {max(allowed):g} MHz)", item.value.span,
                           "the runtime must finish a tick's work before the next frame")
                cycles = None
        sleep = False
        if (item := seen.get("sleep")) is not None:
            sleep = self.sleep_allowed(board, item, (cycles or RUNTIME_CYCLES_PER_TICK)
                                       / fastest_hz)
        return ir.ComputerUse(use.clock_mhz, use.clock_auto, sleep, cycles)

    def sleep_allowed(self, board, item: ast.ComputerItem, busy_s: float) -> bool:
        """Whether the board can sleep between ticks: it has a sleep mode, the next frame
        on the serial line wakes it, and the work and the wake-up fit in the tick."""
        mode = board.sleep
        if mode is None:
            self.error(f"board {board.name} cannot sleep between ticks", item.span,
                       "its data file has no [sleep] table (no wake-up on the serial line "
                       "or a timer); remove the line or choose another board")
            return False
        if "serial" not in mode.wakes_on:
            self.error(f"board {board.name} wakes only on {', '.join(mode.wakes_on)}, not on "
                       "the serial line", item.span,
                       "the next SENSORS frame must wake the runtime")
            return False
        if busy_s + mode.wake_latency_s > TICK_S:
            self.warning(f"no time to sleep: the work ({busy_s:.3g} s) and the wake-up "
                         f"({mode.wake_latency_s:g} s) fill the {TICK_S:g} s tick", item.span,
                         "the board idles between ticks instead")
        return True

    def requirement(self, item: ast.RequireItem, logged: set[str]) -> ir.Requirement | None:
        if not self.sensor_known(item.sensor):
            return None
        if item.sensor.text not in logged:
            self.error(f"requirement on '{item.sensor.text}', which this state does not log",
                       item.sensor.span, f"add '{item.sensor.text}' to the state's sensors")
        if any(b.kind == "weight" for b in item.bounds):
            self.error("a weight is mission-wide: put it on a 'sensor' line", item.span)
        duty_min, duty_max, quality_min = self.bounds(item.bounds, item.sensor.text)
        return ir.Requirement(item.sensor.text, duty_min, duty_max, quality_min)

    def event(self, event: ast.Event) -> ir.Event | None:
        bare = event.condition
        if (isinstance(bare, ast.Name) and bare.name in _ACTIONS and event.action is None
                and not event.assignments):
            # `case exit`: the action word was read as the condition.
            self.error(f"'case' needs a condition before '{bare.name}'", bare.span,
                       f"write e.g. 'case missiontime >= 500 {bare.name}'")
            return None
        condition = self.expression(event.condition, allow_sensors=True)
        assignments = []
        for assignment in event.assignments:
            target = assignment.target.text
            value = self.expression(assignment.value, allow_sensors=True)
            if target not in self.variables:
                hint = ("sensors are read-only; assign to a variable"
                        if target in SENSOR_BY_NAME else
                        did_you_mean(target, self.variables) or
                        f"declare it first: 'var {target} = 0'")
                self.error(f"unknown variable '{target}'", assignment.target.span, hint)
            elif value is not None:
                assignments.append(ir.Assign(target, value))
        action = event.action
        if action is None and not event.assignments:
            self.error("this event does nothing", event.span,
                       "add 'set VAR = EXPR' or an action: goto, call, return, exit")
        if action is not None and action.target is not None:
            if action.target.text not in self.state_names:
                self.error(f"unknown state '{action.target.text}'", action.target.span,
                           did_you_mean(action.target.text, self.state_names)
                           or _listing("states", self.state_names))
        if condition is None or len(assignments) != len(event.assignments):
            return None
        return ir.Event(condition, tuple(assignments), action.kind if action else None,
                        action.target.text if action and action.target else None)

    # ---- expressions
    def expression(self, node: ast.Expr, allow_sensors: bool) -> ir.Expr | None:
        """Lower an expression, reporting every unknown name or misuse in it."""
        match node:
            case ast.Number(value):
                if not math.isfinite(value):
                    self.error(f"{node.text} is too large for a number", node.span,
                               "numbers are 64-bit floats: at most about 1.8e308")
                    return None
                return ir.Const(value)
            case ast.Name(name):
                if name in self.variables:
                    return ir.VarRef(name)
                if name in SENSOR_BY_NAME:
                    if allow_sensors:
                        return ir.SensorRef(name)
                    self.error(f"sensor '{name}' cannot be used here", node.span,
                               "profile arguments and initial values read variables only; "
                               "copy the reading into a variable with 'set'")
                    return None
                hint = did_you_mean(name, [*self.variables, *SENSOR_BY_NAME])
                if name in _ACTIONS:
                    hint = f"'case' needs a condition before '{name}'"
                self.error(f"unknown sensor or variable '{name}'", node.span,
                           hint or "declare a variable with 'var NAME = VALUE'")
                return None
            case ast.Unary(op, operand):
                inner = self.expression(operand, allow_sensors)
                return None if inner is None else ir.UnaryOp(op, inner)
            case ast.Binary(op, left, right):
                lhs = self.expression(left, allow_sensors)
                rhs = self.expression(right, allow_sensors)
                return None if lhs is None or rhs is None else ir.BinaryOp(op, lhs, rhs)
            case ast.Call(function, args):
                lowered = [self.expression(a, allow_sensors) for a in args]
                if function.text not in FUNCTIONS:
                    self.error(f"unknown function '{function.text}'", function.span,
                               did_you_mean(function.text, FUNCTIONS)
                               or f"functions: {', '.join(FUNCTIONS)}")
                    return None
                if len(args) != FUNCTIONS[function.text]:
                    self.error(f"'{function.text}' takes {FUNCTIONS[function.text]} "
                               f"argument(s), got {len(args)}", node.span)
                    return None
                if None in lowered:
                    return None
                return ir.FuncCall(function.text, tuple(lowered))
        raise TypeError(f"not an expression: {node!r}")

    def constant(self, node: ast.Expr, what: str) -> float | None:
        lowered = self.expression(node, allow_sensors=False)
        if lowered is None:
            return None
        if ir.variables_read(lowered):
            self.error(f"{what} must be a constant", node.span)
            return None
        value = ir.evaluate(lowered, {}, {})
        if not math.isfinite(value):
            self.error(f"{what} is not a finite number", node.span)
            return None
        return value

    def ranged_constant(self, node: ast.Expr, spec: ParamSpec, owner: str) -> float | None:
        value = self.constant(node, f"argument '{spec.name}' of '{owner}'")
        if value is None or not self.in_range(value, spec, owner, node.span):
            return None
        if spec.unit == "DDMM.MMMM" and abs(value) % 100 >= 60:
            self.error(f"{value:g} is not DDMM.MMMM: the minutes must be below 60",
                       node.span, "Slocum writes 39 deg 10.5 min as 3910.5")
            return None
        return value

    def in_range(self, value: float, spec: ParamSpec, owner: str, span: ast.Span) -> bool:
        if not math.isfinite(value):
            self.error(f"{spec.name} of '{owner}' is {value:g}, not a finite number", span,
                       _range_hint(spec))
            return False
        too_low = value < spec.low or (spec.low_open and value == spec.low)
        too_high = value > spec.high or (spec.high_open and value == spec.high)
        if too_low or too_high:
            self.error(f"{spec.name} of '{owner}' is {value:g} {spec.unit}, outside "
                       f"{_interval(spec)}", span, _range_hint(spec))
            return False
        return True

    def sensor_known(self, ident: ast.Ident) -> bool:
        if ident.text in SENSOR_BY_NAME:
            return True
        self.error(f"unknown sensor '{ident.text}'", ident.span,
                   did_you_mean(ident.text, SENSOR_BY_NAME)
                   or f"sensors: {', '.join(SENSOR_BY_NAME)}")
        return False


def _listing(what: str, names: Iterable[str], limit: int = 12) -> str:
    """'states: a, b, c' (the first few, sorted), for a hint when nothing is close."""
    names = sorted(names)
    shown = ", ".join(names[:limit]) + (", ..." if len(names) > limit else "")
    return f"{what}: {shown}"


def _keyword(node: object) -> str:
    name = type(node).__name__
    for suffix in ("Decl", "Item"):
        name = name.removesuffix(suffix)
    return {"Route": "flightroute", "Profile": "flightprofile"}.get(name, name.lower())


def _interval(spec: ParamSpec) -> str:
    low = "(" if spec.low_open else "["
    high = ")" if spec.high_open else "]"
    return f"{low}{spec.low:g}, {spec.high:g}{high}"


def _parameter(spec: ParamSpec) -> str:
    """'name [unit]', in brackets for an argument that may be left out."""
    text = f"{spec.name} [{spec.unit}]"
    return f"[{text}]" if spec.optional else text


def _range_hint(spec: ParamSpec) -> str | None:
    if spec.name == "altitude":
        return ("the height above the sea floor at which a dive turns (Slocum's "
                "d_target_altitude), 0 or more; 0: no altimeter stop")
    if spec.unit == "rad":
        return "pitch is in radians: 26 degrees is 0.454"
    if spec.name == "heading":
        return ("a compass heading in degrees, true, clockwise from north: 0 north, 90 east, "
                "270 west (Slocum's set_heading is in radians: 4.712 is 270)")
    if spec.unit == "m":
        return "depths are metres below the surface, 0 or more"
    return None


def _signature(params: tuple[ParamSpec, ...], min_points: int, max_points: int) -> str:
    parts = [f"{p.name} [{p.unit}]" for p in params]
    if max_points:
        parts.append(f"{min_points} to {max_points} (lat, lon) points")
    return ", ".join(parts) if parts else "no arguments"


def check(mission: ast.Mission, stack_depth: int | None = None, base_dir: str = "",
          model_files: bool = False) -> tuple[ir.CheckedMission | None, list[Diagnostic]]:
    """Check a parsed mission; the IR is None when there are errors. `stack_depth`
    replaces the mission's own (1 to the runtime's MAX_STACK_DEPTH). `base_dir`: the
    mission's folder, where the files it names are looked for ("": the working one).
    `model_files`: open the vehicle and board files it names, and fly its yos on the
    vehicle file's figures (a battery file is read always: it is the mission's energy)."""
    if stack_depth is not None and not 1 <= stack_depth <= MAX_STACK_DEPTH:
        raise ValueError(f"a stack depth of {stack_depth} is outside 1..{MAX_STACK_DEPTH}")
    checker = _Checker(mission, stack_depth, base_dir, model_files)
    checked = checker.run()
    return checked, sorted(checker.diagnostics, key=lambda d: (d.span.line, d.span.column))
