"""The fleet file (`.fleet`): several gliders sharing one survey, checked like a mission.

`check_fleet_source` is the front end in one call: text in, a checked `Fleet` and its
diagnostics out (`file:line:col: error: ...`, the line, a caret, a hint; every error of
a pass at once). Passes: syntax (lark LALR on fleet.lark, resuming at the next setting
after an error), then the settings (units, ranges, names; each glider's vehicle, board
and battery by the mission checker's own rules), then the survey's geometry (areas cut
into transects, keep-outs, overlaps, starts), which runs only when the settings are
sound. The language of the file is docs/fleet.md's.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field
from datetime import datetime
from functools import cache
from pathlib import Path

from gliderplan.contract import MAX_NAME_LENGTH
from gliderplan.contract.errors import GliderplanError
from gliderplan.contract.files import read_input_text
from gliderplan.language import ast, ir
from gliderplan.language.diagnostics import Diagnostic, did_you_mean, error, render_all
from gliderplan.language.fleet_geometry import XY, Projection
from gliderplan.language.registry import SENSOR_BY_NAME

GRAMMAR = Path(__file__).with_name("fleet.lark")
MAX_SYNTAX_ERRORS = 20

# Defaults of the settings a fleet file may leave out (docs/fleet.md says why).
DEFAULT_CONFIDENCE = 0.9
DEFAULT_SURFACE_EVERY_S = 6 * 3600.0  # North Sea gliders surface every 3-5 h (DESIGN.md 11)
DEFAULT_SURFACE_STAY_S = 15 * 60.0  # a GPS fix and an Iridium call
DEFAULT_FIELD_LENGTH_M = 15e3
DEFAULT_FIELD_TIME_S = 2 * 86400.0
DEFAULT_FIELD_NOISE = 0.1
FIELD_SOURCE = (
    "Gaussian space-time covariance of objective analysis (Bretherton, Davis & Fandry "
    "1976), the form R. Davis scored the Monterey Bay glider arrays with (Leonard et al. "
    "2007, Proc. IEEE 95(1)); scales: assumption for a summer shelf sea, lateral features "
    "of 5-20 km (Flexas et al. 2018, Monterey Bay) and a time scale of days; noise: "
    "unresolved variance and sensor error as a share of the field's variance (assumption)")

SHAPE = ("a fleet file starts with 'fleet NAME', then settings (start, finish by, "
         "confidence, ...), one 'survey begin ... end', one 'sample ...' and "
         "'glider NAME begin ... end' blocks")


class FleetError(GliderplanError):
    """A fleet file with errors, or a fleet that cannot be planned; `details` holds the
    rendered diagnostics."""


# ---- the checked fleet -------------------------------------------------------------------

@dataclass(frozen=True)
class SensorGoal:
    name: str
    duty: float  # the duty it is flown at [0..1]: the least the goal asks for, else 1


@dataclass(frozen=True)
class Goal:
    """What the survey samples: sensors, the depth band, line spacing, revisit time."""

    sensors: tuple[SensorGoal, ...]
    min_depth_m: float
    max_depth_m: float
    spacing_m: float | None  # between an area's lines
    revisit_s: float | None  # every part flown again at least this often
    bottom_m: float | None  # deepest a yo may turn (the water's depth less a margin)


@dataclass(frozen=True)
class Part:
    """One line of the survey, flown end to end: a transect cut from an area, a transect
    as written, or one leg of a waypoint route (with the keep-outs cut out)."""

    index: int
    kind: str  # "area" | "transect" | "waypoints"
    item: int  # which survey item it came from (0-based, in the file's order)
    a: XY  # one end [m] on the fleet's plane
    b: XY
    span: ast.Span
    line: int = 0  # pieces of one line (cut by a keep-out) share it; a line per piece else

    @property
    def length_m(self) -> float:
        return math.dist(self.a, self.b)


@dataclass(frozen=True)
class GliderSpec:
    name: str
    vehicle: str  # preset name or file path (as the mission language takes it)
    computer: ir.Computer
    battery: ir.Battery  # the pack as rated; its reserve a share of the rating
    charge: float  # share of the rating left at the start [0..1]
    start: XY  # where it is put in the water [m] on the fleet's plane
    start_ddmm: tuple[float, float]
    start_offset_s: float  # after the fleet's start [s]
    span: ast.Span  # its name
    start_span: ast.Span
    battery_span: ast.Span

    @property
    def usable_j(self) -> float:
        """Energy the plan may use [J]: what is left above the reserve."""
        return self.battery.energy_j * max(self.charge - self.battery.reserve_fraction, 0.0)


@dataclass(frozen=True)
class FieldScales:
    """The mapped field's covariance: exp(-r^2 / length^2 - dt^2 / time^2)."""

    length_m: float
    time_s: float
    noise: float  # noise-to-signal variance ratio of one sample
    source: str = FIELD_SOURCE


@dataclass(frozen=True)
class Fleet:
    name: str
    filename: str
    source: str  # the file's text, for diagnostics found while planning
    hash: str  # sha256 of the text: plans and runs name the fleet file they came from
    start_epoch_s: float  # UTC of the survey's start [s since 1970]
    period_s: float  # the survey ends this long after its start (`finish by`)
    confidence: float
    separation_m: float
    surface_every_s: float
    surface_stay_s: float
    field: FieldScales
    goal: Goal
    gliders: tuple[GliderSpec, ...]
    parts: tuple[Part, ...]
    areas: tuple[tuple[XY, ...], ...]
    keepouts: tuple[tuple[XY, ...], ...]
    projection: Projection
    spans: dict[str, ast.Span] = field(default_factory=dict)  # finish, confidence, survey...

    def error(self, message: str, span_key: str | ast.Span, hint: str | None = None,
              more: tuple[Diagnostic, ...] = ()) -> FleetError:
        """A FleetError located in this fleet file (a span, or a key of `spans`)."""
        span = self.spans.get(span_key, ast.NO_SPAN) if isinstance(span_key, str) \
            else span_key
        found = [error(message, span, hint), *more]
        return FleetError(f"{self.filename}: {message}",
                          details=render_all(found, self.filename, self.source),
                          diagnostics=[d.to_json(self.filename) for d in found],
                          file=self.filename)

    def glider(self, name: str) -> GliderSpec:
        return next(g for g in self.gliders if g.name == name)


@dataclass(frozen=True)
class FleetResult:
    filename: str
    source: str
    fleet: Fleet | None  # None when there are errors
    diagnostics: list[Diagnostic] = field(default_factory=list)

    def render(self) -> str:
        return render_all(self.diagnostics, self.filename, self.source)

    def diagnostics_json(self) -> list[dict]:
        """Every diagnostic as a JSON object (`Diagnostic.to_json`)."""
        return [d.to_json(self.filename) for d in self.diagnostics]

    def checked(self) -> Fleet:
        """The checked fleet; FleetError (with the diagnostics) if it has errors."""
        if self.fleet is None:
            raise FleetError(f"{self.filename}: fleet file has errors", details=self.render(),
                             diagnostics=self.diagnostics_json(), file=self.filename)
        return self.fleet


def check_fleet_file(path: str | Path) -> FleetResult:
    """Read and check a fleet file. Raises InputFileError for a file that cannot be read
    as text; a bad fleet is not an error here but a result with diagnostics."""
    return check_fleet_source(read_input_text(path, "fleet file"), str(path))


def check_fleet_source(source: str, filename: str = "<fleet>") -> FleetResult:
    """Parse and check fleet text."""
    try:
        syntax = parse(source)
    except _SyntaxErrors as err:
        return FleetResult(filename, source, None, err.diagnostics)
    checker = _Checker(syntax, filename, source)
    fleet = checker.run()
    found = sorted(checker.diagnostics, key=lambda d: (d.span.line, d.span.column))
    return FleetResult(filename, source, fleet, found)


# ---- syntax ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Setting:
    """One top-level setting or block as written: its keyword, values and span."""

    kind: str
    values: tuple
    span: ast.Span


class _SyntaxErrors(Exception):
    def __init__(self, diagnostics: list[Diagnostic]) -> None:
        super().__init__("; ".join(d.message for d in diagnostics))
        self.diagnostics = diagnostics


@cache
def _lark():
    from lark import Lark

    return Lark.open(str(GRAMMAR), parser="lalr", lexer="contextual",
                     propagate_positions=True, maybe_placeholders=True, cache=True,
                     start=["fleet_file", "recovery"])


def _span(meta) -> ast.Span:
    if getattr(meta, "empty", True):
        return ast.NO_SPAN
    return ast.Span(meta.line, meta.column, meta.end_line, meta.end_column)


def _token_span(token) -> ast.Span:
    return ast.Span(token.line, token.column, token.end_line, token.end_column)


def _ident(token) -> ast.Ident:
    if token.type == "STRING":
        return ast.Ident(str(token)[1:-1], _token_span(token))
    return ast.Ident(str(token), _token_span(token))


def _transformer():
    from lark import Transformer, v_args

    @v_args(meta=True)
    class Build(Transformer):
        """Each rule to a `Setting`, an ast node or a plain value."""

        def fleet_file(self, meta, children):
            return children

        def recovery(self, meta, children):
            return None

        def fleet_header(self, meta, children):
            return _ident(children[0])

        def number(self, meta, children):
            return ast.Number(float(children[0]), str(children[0]), _span(meta))

        def negative(self, meta, children):
            return ast.Number(-float(children[0]), f"-{children[0]}", _span(meta))

        def quantity(self, meta, children):
            number, unit = children
            return ast.Quantity(number.value, number.text,
                                None if unit is None else _ident(unit), _span(meta))

        def point(self, meta, children):
            return ast.Point(children[0], children[1], _span(meta))

        def points(self, meta, children):
            return tuple(children)

        def _setting(kind):  # noqa: N805 - a factory of rule methods, not a method
            def rule(self, meta, children):
                return Setting(kind, tuple(children), _span(meta))
            return rule

        start_decl = _setting("start")
        finish_decl = _setting("finish")
        confidence_decl = _setting("confidence")
        separation_decl = _setting("separation")
        surface_decl = _setting("surface")
        field_decl = _setting("field")
        survey = _setting("survey")
        area = _setting("area")
        transect = _setting("transect")
        waypoints = _setting("waypoints")
        keepout = _setting("keepout")
        sample_decl = _setting("sample")
        sensor_goal = _setting("sensor")
        depth_band = _setting("depth")
        spacing = _setting("spacing")
        revisit = _setting("revisit")
        bottom = _setting("bottom")
        glider = _setting("glider")
        charge_decl = _setting("charge")
        start_position = _setting("start_position")

        def vehicle_decl(self, meta, children):
            name = _ident(children[0])
            return ast.VehicleDecl(name, children[0].type == "STRING", _span(meta))

        def computer_decl(self, meta, children):
            board, clock = children
            return ast.ComputerDecl(_ident(board), board.type == "STRING", clock, _span(meta))

        def battery_decl(self, meta, children):
            capacity, voltage, reserve = children
            return ast.BatteryDecl(capacity, voltage, reserve, _span(meta))

    return Build()


@cache
def _keyword_literals() -> dict[str, str]:
    return {t.name: t.pattern.value for t in _lark().terminals if t.pattern.type == "str"}


def parse(text: str) -> tuple[ast.Ident, list[Setting]]:
    """(the fleet's name, its settings as written), or _SyntaxErrors with every syntax
    error found (the parser resumes at the next line that starts a setting)."""
    import re

    from lark import UnexpectedInput

    from gliderplan.language.syntax_errors import describe, error_position, is_blank

    if is_blank(text):
        what = "the file is empty" if not text.strip() else "the file has only comments"
        raise _SyntaxErrors([error(f"{what}: there is no fleet in it", ast.NO_SPAN, SHAPE)])
    try:
        tree = _lark().parse(text, start="fleet_file")
        name, *settings = _transformer().transform(tree)
        return name, settings
    except UnexpectedInput as first:
        found = [_describe(describe(first, text, _keyword_literals()))]
        resume_at = re.compile(r"^[ \t]*(start|finish|confidence|separation|surface|field"
                               r"|survey|sample|glider)\b", re.MULTILINE)
        error_at, after = error_position(first), -1
        while len(found) < MAX_SYNTAX_ERRORS:
            # the next setting at the top level: not inside a block (a glider's `start`)
            nexts = [m.start(1) for m in resume_at.finditer(text)
                     if m.start(1) >= error_at and m.start(1) > after
                     and not _inside_block(text, m.start(1))]
            if not nexts:
                break
            blanked = re.sub(r"[^\n]", " ", text[:nexts[0]]) + text[nexts[0]:]
            try:
                _lark().parse(blanked, start="recovery")
                break
            except UnexpectedInput as err:
                found.append(_describe(describe(err, text, _keyword_literals())))
                error_at, after = error_position(err), nexts[0]
        raise _SyntaxErrors(found) from None


def _inside_block(text: str, offset: int) -> bool:
    """True when `offset` lies between a `begin` and its `end` (a glider's or the
    survey's), where `start` is a glider's position and not the fleet's start."""
    import re

    depth = 0
    for match in re.finditer(r"(#|//)[^\n]*|\b(begin|end)\b", text[:offset]):
        if match.group(2) == "begin":
            depth += 1
        elif match.group(2) == "end":
            depth = max(depth - 1, 0)
    return depth > 0


def _describe(diagnostic: Diagnostic) -> Diagnostic:
    """A syntax diagnostic in a fleet writer's words: the mission's shape hint, which the
    shared describer gives for a wrong start, is the fleet's here."""
    if diagnostic.hint and diagnostic.hint.startswith("a mission starts"):
        return Diagnostic(diagnostic.severity, diagnostic.message.replace("mission", "fleet"),
                          diagnostic.span, SHAPE)
    return diagnostic


# ---- semantics ---------------------------------------------------------------------------

_ONCE = ("start", "finish", "confidence", "separation", "surface", "field", "survey",
         "sample")


class _Checker:
    def __init__(self, syntax: tuple[ast.Ident, list[Setting]], filename: str,
                 source: str) -> None:
        from gliderplan.language.checker import _Checker as MissionChecker

        self.name, self.settings = syntax
        self.filename, self.source = filename, source
        # The mission checker's rules for quantities, presets, boards and batteries: a
        # glider's hardware means the same in a fleet file as in a mission.
        self._mission_checker = MissionChecker
        self.units = MissionChecker(ast.Mission(self.name, (), ()), None)
        self.diagnostics = self.units.diagnostics
        self.spans: dict[str, ast.Span] = {}

    def error(self, message: str, span: ast.Span, hint: str | None = None) -> None:
        self.diagnostics.append(error(message, span, hint))

    def errors(self) -> int:
        return sum(d.is_error for d in self.diagnostics)

    def quantity(self, quantity: ast.Quantity | None, *dimensions: str) -> float | None:
        if quantity is None:
            return None
        found = self.units.quantity(quantity, *dimensions)
        return None if found is None else found[0]

    def positive(self, quantity: ast.Quantity, what: str, *dimensions: str) -> float | None:
        value = self.quantity(quantity, *dimensions)
        if value is not None and value <= 0.0:
            self.error(f"{what} must be positive", quantity.span)
            return None
        return value

    # ---- the whole file
    def run(self) -> Fleet | None:
        if len(self.name.text) > MAX_NAME_LENGTH:
            self.error(f"fleet name '{self.name.text}' has {len(self.name.text)} characters, "
                       f"more than the {MAX_NAME_LENGTH} a plan file holds", self.name.span,
                       "choose a shorter name")
        once: dict[str, Setting] = {}
        gliders: list[Setting] = []
        for setting in self.settings:
            if setting.kind == "glider":
                gliders.append(setting)
            elif setting.kind in once:
                first = once[setting.kind].span.line
                self.error(f"'{_keyword(setting.kind)}' is given twice", setting.span,
                           f"the first is on line {first}")
            else:
                once[setting.kind] = setting
        values = self.settings_values(once)
        goal = self.goal(once.get("sample"))
        specs = self.gliders(gliders, values.get("start_epoch_s"), values.get("period_s"))
        survey = once.get("survey")
        survey_points = self.survey_points(survey) if survey is not None else None
        if survey is None:
            self.error("no survey: the gliders have nothing to share", ast.NO_SPAN,
                       "add 'survey begin area (lat, lon), ... end' (or transects, or "
                       "waypoints)")
        if not gliders:
            self.error("no glider in the fleet", ast.NO_SPAN,
                       "add 'glider NAME begin vehicle ... battery ... start (lat, lon) end'")
        if self.errors() or survey is None or goal is None or specs is None:
            return None
        geometry = self.geometry(survey, survey_points, goal, specs)
        if self.errors() or geometry is None:
            return None
        projection, parts, areas, keepouts, placed = geometry
        return Fleet(
            name=self.name.text, filename=self.filename, source=self.source,
            hash=hashlib.sha256(self.source.encode()).hexdigest(),
            start_epoch_s=values["start_epoch_s"], period_s=values["period_s"],
            confidence=values.get("confidence", DEFAULT_CONFIDENCE),
            separation_m=values.get("separation_m", 0.0),
            surface_every_s=values.get("surface_every_s", DEFAULT_SURFACE_EVERY_S),
            surface_stay_s=values.get("surface_stay_s", DEFAULT_SURFACE_STAY_S),
            field=values.get("field", FieldScales(DEFAULT_FIELD_LENGTH_M,
                                                  DEFAULT_FIELD_TIME_S, DEFAULT_FIELD_NOISE)),
            goal=goal, gliders=tuple(placed), parts=tuple(parts), areas=tuple(areas),
            keepouts=tuple(keepouts), projection=projection, spans=self.spans)

    def settings_values(self, once: dict[str, Setting]) -> dict:
        values: dict = {}
        start = once.get("start")
        if start is None:
            self.error("the fleet has no start time", ast.NO_SPAN,
                       "add e.g. 'start 2024-06-01T06:00Z' (UTC)")
        else:
            self.spans["start"] = start.span
            values["start_epoch_s"] = self.time(start.values[0])
        finish = once.get("finish")
        if finish is None:
            self.error("the fleet has no finish time", ast.NO_SPAN,
                       "add e.g. 'finish by 7 d' (after the start) or "
                       "'finish by 2024-06-08T06:00Z'")
        else:
            self.spans["finish"] = finish.span
            values["period_s"] = self.period(finish, values.get("start_epoch_s"))
        if (setting := once.get("confidence")) is not None:
            self.spans["confidence"] = setting.span
            value = self.quantity(setting.values[0], "fraction")
            if value is not None and not 0.0 < value < 1.0:
                self.error("confidence must lie strictly between 0 % and 100 %",
                           setting.values[0].span, "write e.g. 'confidence 90 %'")
            elif value is not None:
                values["confidence"] = value
        if (setting := once.get("separation")) is not None:
            self.spans["separation"] = setting.span
            value = self.quantity(setting.values[0], "length")
            if value is not None and value < 0.0:
                self.error("a separation cannot be negative", setting.values[0].span)
            elif value is not None:
                values["separation_m"] = value
        if (setting := once.get("surface")) is not None:
            self.spans["surface"] = setting.span
            every = self.positive(setting.values[0], "the time between surfacings", "time")
            stay = self.positive(setting.values[1], "a stay at the surface", "time") \
                if setting.values[1] is not None else DEFAULT_SURFACE_STAY_S
            if every is not None and stay is not None:
                if every < 3600.0:
                    self.error("surfacing more often than every hour leaves no time to "
                               "dive", setting.values[0].span, "write e.g. 'surface every 4 h'")
                values["surface_every_s"], values["surface_stay_s"] = every, stay
        if (setting := once.get("field")) is not None:
            self.spans["field"] = setting.span
            length = self.positive(setting.values[0], "the field's length scale", "length")
            time_s = self.positive(setting.values[1], "the field's time scale", "time")
            noise = DEFAULT_FIELD_NOISE
            if setting.values[2] is not None:
                noise = self.quantity(setting.values[2], "fraction")
                if noise is not None and not 0.0 < noise <= 1.0:
                    self.error("noise must lie above 0 % and at most 100 % of the field's "
                               "variance", setting.values[2].span)
                    noise = None
            if None not in (length, time_s, noise):
                values["field"] = FieldScales(length, time_s, noise,
                                              "as the fleet file gives them")
        return values

    def time(self, token) -> float | None:
        try:
            return datetime.fromisoformat(str(token).replace("Z", "+00:00")).timestamp()
        except ValueError:
            self.error(f"{token} is no date and time", _token_span(token),
                       "write UTC as YYYY-MM-DDTHH:MMZ, e.g. 2024-06-01T06:00Z")
            return None

    def period(self, finish: Setting, start_s: float | None) -> float | None:
        value = finish.values[0]
        if isinstance(value, ast.Quantity):
            period = self.positive(value, "the survey's length", "time")
        else:
            end = self.time(value)
            if end is None or start_s is None:
                return None
            period = end - start_s
            if period <= 0.0:
                self.error("the survey finishes before it starts", _token_span(value),
                           "finish by a time after 'start', or give a duration: "
                           "'finish by 7 d'")
                return None
        if period is not None and period > 366 * 86400.0:
            self.error("a survey of more than a year is beyond any glider's battery",
                       finish.span)
            return None
        return period

    # ---- sampling goal
    def goal(self, setting: Setting | None) -> Goal | None:
        if setting is None:
            self.error("the fleet says nothing about what to sample", ast.NO_SPAN,
                       "add e.g. 'sample temp, conductivity depth 5 .. 40 m spacing 4 km'")
            return None
        self.spans["sample"] = setting.span
        sensors: list[SensorGoal] = []
        options: dict[str, Setting] = {}
        for value in setting.values:
            if value.kind == "sensor":
                sensors.append(self.sensor_goal(value, sensors))
            elif value.kind in options:
                self.error(f"'{value.kind}' is given twice in 'sample'", value.span)
            else:
                options[value.kind] = value
        depth = options.get("depth")
        band = (None, None)
        if depth is None:
            self.error("'sample' needs the depth band to sample", setting.span,
                       "add e.g. 'depth 5 .. 40 m'")
        else:
            low, high = depth.values
            if low.unit is None and high.unit is not None:  # `5 .. 40 m`: one unit for both
                low = ast.Quantity(low.value, low.text, high.unit, low.span)
            band = (self.quantity(low, "length"), self.quantity(high, "length"))
            if None not in band and not 0.0 <= band[0] < band[1]:
                self.error("the depth band must run from a shallower to a deeper depth, "
                           "0 m or deeper", depth.span, "write e.g. 'depth 5 .. 40 m'")
        spacing = self.positive(options["spacing"].values[0], "line spacing", "length") \
            if "spacing" in options else None
        if "spacing" in options:
            self.spans["spacing"] = options["spacing"].span
        revisit = self.positive(options["revisit"].values[0], "revisit time", "time") \
            if "revisit" in options else None
        if "revisit" in options:
            self.spans["revisit"] = options["revisit"].span
        bottom = self.positive(options["bottom"].values[0], "the bottom depth", "length") \
            if "bottom" in options else None
        if bottom is not None and band[1] is not None and bottom <= band[1]:
            self.error("the bottom must lie below the depth band", options["bottom"].span)
        if None in band or None in sensors or self.errors():
            return None
        return Goal(tuple(sensors), band[0], band[1], spacing, revisit, bottom)

    def sensor_goal(self, setting: Setting, earlier: list) -> SensorGoal | None:
        name, op, value = setting.values
        info = SENSOR_BY_NAME.get(str(name))
        if info is None or info.device is None or info.source != "glider":
            science = sorted(n for n, s in SENSOR_BY_NAME.items()
                             if s.device is not None and s.source == "glider")
            what = "no sensor" if info is None else "not a science sensor"
            self.error(f"'{name}' is {what} to sample", _token_span(name),
                       did_you_mean(str(name), science) or f"sensors: {', '.join(science)}")
            return None
        if any(s is not None and s.name == str(name) for s in earlier):
            self.error(f"'{name}' is sampled twice", _token_span(name))
            return None
        duty = 1.0
        if value is not None:
            duty = value.value
            if not 0.0 < duty <= 1.0:
                self.error("a duty must lie above 0 and at most 1", value.span,
                           "a duty is the share of the time the sensor is on")
                return None
            if op is not None and str(op) == "<=":
                self.error("a sampling goal asks for at least a duty, not at most",
                           _token_span(op), f"write 'duty >= {value.text}' or "
                           f"'duty {value.text}'")
                return None
        return SensorGoal(str(name), duty)

    # ---- gliders
    def gliders(self, settings: list[Setting], start_s: float | None,
                period_s: float | None) -> list[dict] | None:
        specs: list[dict] = []
        names: dict[str, ast.Span] = {}
        for setting in settings:
            name = _ident(setting.values[0])
            if name.text in names:
                self.error(f"glider '{name.text}' is named twice", name.span,
                           f"the first is on line {names[name.text].line}")
                continue
            names[name.text] = name.span
            if len(name.text) > MAX_NAME_LENGTH:
                self.error(f"glider name '{name.text}' has {len(name.text)} characters, more "
                           f"than the {MAX_NAME_LENGTH} a mission's name holds", name.span,
                           "choose a shorter name")
            spec = self.glider(name, setting.values[1:], start_s, period_s)
            if spec is not None:
                specs.append(spec)
        return specs

    def glider(self, name: ast.Ident, items: tuple, start_s: float | None,
               period_s: float | None) -> dict | None:
        hardware = tuple(i for i in items if isinstance(i, ast.Node))
        others = [i for i in items if isinstance(i, Setting)]
        checker = self._mission_checker(ast.Mission(name, hardware, ()), None)
        fields = checker.declarations()
        self.diagnostics.extend(checker.diagnostics)
        spec = {"name": name.text, "span": name.span,
                "vehicle": fields.get("vehicle", ir.DEFAULT_VEHICLE),
                "computer": fields.get("computer", ir.DEFAULT_COMPUTER),
                "battery": fields.get("battery", ir.DEFAULT_BATTERY),
                "battery_span": next((d.span for d in hardware
                                      if isinstance(d, ast.BatteryDecl)), name.span),
                "charge": 1.0}
        seen: dict[str, Setting] = {}
        for item in others:
            if item.kind in seen:
                self.error(f"'{_keyword(item.kind)}' is given twice for glider "
                           f"'{name.text}'", item.span)
                continue
            seen[item.kind] = item
        if (charge := seen.get("charge")) is not None:
            value = self.quantity(charge.values[0], "fraction")
            if value is not None and not 0.0 < value <= 1.0:
                self.error("charge must lie above 0 % and at most 100 % of the battery",
                           charge.values[0].span, "the share of the rated pack still in it")
            elif value is not None:
                spec["charge"] = value
                spec["battery_span"] = charge.span
        reserve = spec["battery"].reserve_fraction
        if spec["charge"] <= reserve and "charge" in seen:
            self.error(f"glider '{name.text}' has no usable charge: {100 * spec['charge']:.3g} % "
                       f"left and a reserve of {100 * reserve:.3g} %", seen["charge"].span,
                       "charge the glider, or lower its reserve")
        position = seen.get("start_position")
        if position is None:
            self.error(f"glider '{name.text}' has no start position", name.span,
                       "add e.g. 'start (3920.0, -7355.0)' (DDMM.MMMM) to its block")
            return None
        point, when = position.values
        spec["start_ddmm"] = self.point(point)
        spec["start_span"] = point.span
        spec["start_offset_s"] = 0.0
        if when is not None and start_s is not None:
            at = self.time(when)
            if at is not None:
                spec["start_offset_s"] = at - start_s
                if at < start_s:
                    self.error(f"glider '{name.text}' starts before the fleet does",
                               _token_span(when), "start it at or after the fleet's 'start'")
                elif period_s is not None and at - start_s >= period_s:
                    self.error(f"glider '{name.text}' starts after the survey has finished",
                               _token_span(when))
        return spec if spec["start_ddmm"] is not None else None

    def point(self, point: ast.Point) -> tuple[float, float] | None:
        """(lat, lon) DDMM.MMMM of a point, checked as the mission checker checks nav."""
        from gliderplan.language.registry import ROUTES

        lat = self.units.ranged_constant(point.lat, ROUTES["nav"].params[0], "position")
        lon = self.units.ranged_constant(point.lon, ROUTES["nav"].params[1], "position")
        return None if lat is None or lon is None else (lat, lon)

    # ---- the survey's geometry
    def survey_points(self, survey: Setting) -> dict[int, list]:
        """Every survey item's points, checked as DDMM.MMMM with the other settings."""
        return {id(i): [self.point(p) for p in i.values[0]] for i in survey.values}

    def geometry(self, survey: Setting, points: dict[int, list], goal: Goal,
                 specs: list[dict]):
        from shapely.ops import unary_union

        from gliderplan.language.fleet_geometry import (
            KEEPOUT_MARGIN_M,
            longest_edge_heading,
            pieces_outside,
            polygon,
            polygon_problem,
            projection_about,
            transects,
        )

        self.spans["survey"] = survey.span
        items = survey.values
        if not any(i.kind in ("area", "transect", "waypoints") for i in items):
            self.error("the survey has no area, transect or waypoints", survey.span,
                       "add e.g. 'area (3920, -7400), (3950, -7400), (3950, -7330)'")
            return None
        everything = [p for ps in points.values() for p in ps] + [s["start_ddmm"] for s in specs]
        projection = projection_about(everything)
        xy = {k: [projection.point(p) for p in ps] for k, ps in points.items()}
        keepouts, areas = [], []
        for item in items:
            if item.kind == "keepout":
                if self.polygon_ok(item, xy[id(item)], "keep-out area", polygon_problem):
                    keepouts.append((item, polygon(xy[id(item)])))
        # lines end a margin short of a keep-out, where a path around it can start
        blocked = unary_union([k for _, k in keepouts]).buffer(
            KEEPOUT_MARGIN_M, join_style="mitre") if keepouts else None
        parts: list[Part] = []
        for number, item in enumerate(items):
            if item.kind == "area":
                if not self.polygon_ok(item, xy[id(item)], "area", polygon_problem):
                    continue
                shape = polygon(xy[id(item)])
                for earlier, other in areas:
                    if shape.intersection(other).area > 1e-3 * min(shape.area, other.area):
                        self.error("this area overlaps the area on line "
                                   f"{earlier.span.line}", item.span,
                                   "a part of the survey must belong to one area: move a "
                                   "corner, or merge the two areas into one")
                areas.append((item, shape))
                if goal.spacing_m is None:
                    self.error("an area needs a line spacing", item.span,
                               "add e.g. 'spacing 4 km' to 'sample'")
                    continue
                heading = longest_edge_heading(shape)
                if item.values[1] is not None:
                    given = self.quantity(item.values[1], "angle")
                    heading = heading if given is None else given % math.pi
                lines = transects(shape, goal.spacing_m, heading, blocked)
                if not lines:
                    width = _width(shape, heading)
                    inside = blocked is not None and shape.difference(blocked).area < 1.0
                    self.error("this area is empty: " + (
                        "keep-out areas cover it" if inside else
                        f"no line fits at {goal.spacing_m / 1000:g} km spacing (it is "
                        f"{width / 1000:.3g} km across)"), item.span,
                        None if inside else "give a smaller spacing, or a wider area")
                for a, b, line in lines:
                    parts.append(Part(len(parts), "area", number, a, b, item.span,
                                      1000 * number + line))
            elif item.kind in ("transect", "waypoints"):
                ends = xy[id(item)]
                if item.kind == "transect" and len(ends) != 2:
                    self.error(f"a transect runs between 2 points, not {len(ends)}", item.span,
                               "for a route through several points write 'waypoints'")
                    continue
                if len(ends) < 2:
                    self.error("waypoints need at least 2 points", item.span)
                    continue
                kept = [piece for a, b in zip(ends, ends[1:], strict=False)
                        for piece in pieces_outside(a, b, blocked) if math.dist(a, b) > 0.0]
                if not kept:
                    self.error(f"this {item.kind} lies inside keep-out areas: nothing of it "
                               "is left to fly", item.span)
                for a, b in kept:
                    parts.append(Part(len(parts), item.kind, number, a, b, item.span,
                                      1000 * number + len(parts)))
        if self.errors():
            return None
        self.overlapping_lines(parts, areas)
        placed = self.placed(specs, projection, blocked, len(parts))
        return projection, parts, [tuple(tuple(c) for c in s.exterior.coords[:-1])
                                   for _, s in areas], \
            [tuple(tuple(c) for c in k.exterior.coords[:-1]) for _, k in keepouts], placed

    def polygon_ok(self, item: Setting, xy: list[XY], what: str, problem) -> bool:
        if len(xy) < 3:
            self.error(f"an {what} needs at least 3 corners, not {len(xy)}", item.span)
            return False
        why = problem(xy)
        if why is not None:
            empty = "area" in why
            self.error(f"this {what} is {'empty' if empty else 'not usable'}: {why}",
                       item.span, "list its corners in order around it")
            return False
        return True

    def overlapping_lines(self, parts: list[Part], areas: list) -> None:
        """Written transects and routes that run along one another or through an area
        would be flown twice."""
        from shapely.geometry import LineString

        written = [p for p in parts if p.kind != "area"]
        for i, part in enumerate(written):
            line = LineString([part.a, part.b])
            for item, shape in areas:
                if line.intersection(shape).length > 0.5 * line.length:
                    self.error(f"this {part.kind} runs through the area on line "
                               f"{item.span.line}", part.span,
                               "the area's own transects cover it: leave it out")
                    break
            for other in written[:i]:
                if other.item != part.item and line.intersection(
                        LineString([other.a, other.b]).buffer(1.0)).length > 100.0:
                    self.error(f"this {part.kind} overlaps the one on line {other.span.line}",
                               part.span, "a line of the survey must belong to one part")
                    break

    def placed(self, specs: list[dict], projection: Projection, blocked,
               parts: int) -> list[GliderSpec]:
        from shapely.geometry import Point

        placed = []
        for number, spec in enumerate(specs):
            start = projection.point(spec["start_ddmm"])
            if blocked is not None and blocked.contains(Point(start)):
                self.error(f"glider '{spec['name']}' starts inside a keep-out area",
                           spec["start_span"], "put it in the water outside every keep-out")
            if number == parts:
                self.error(f"{len(specs)} gliders share a survey of {parts} "
                           f"part{'s' if parts != 1 else ''}: every glider needs one at least",
                           spec["span"], "leave gliders out, or cut the survey finer (a "
                           "smaller line spacing, more transects)")
            placed.append(GliderSpec(
                spec["name"], spec["vehicle"], spec["computer"], spec["battery"],
                spec["charge"], start, spec["start_ddmm"], spec["start_offset_s"],
                spec["span"], spec["start_span"], spec["battery_span"]))
        return placed


def _width(shape, heading_rad: float) -> float:
    """Extent [m] of a polygon across lines of `heading_rad`."""
    import numpy as np

    corners = np.asarray(shape.exterior.coords)
    offsets = corners @ np.array([math.cos(heading_rad), -math.sin(heading_rad)])
    return float(offsets.max() - offsets.min())


def _keyword(kind: str) -> str:
    return {"finish": "finish by", "start_position": "start", "sample": "sample"}.get(kind, kind)
