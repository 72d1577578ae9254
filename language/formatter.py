"""The canonical layout of a mission: one statement per line, comments kept.

The mission is parsed and printed again from its syntax tree, so the layout is fixed
(indentation, spacing, one blank line around states, minimal parentheses) and only
what the writer chose survives: the order of statements, blank lines between
statements (at most one), number spelling (`.454` stays `.454`) and every comment.

A comment is attached to a statement: after code on the line where a statement ends,
it stays at the end of that line; otherwise it is printed on its own line before the
statement that contains or follows it. Comments after the last statement end the file.
The result is checked before it is returned: it must parse to the same syntax tree and
hold the same comments, or FormatError is raised rather than losing anything.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from gliderplan.contract.errors import GliderplanError
from gliderplan.language import ast
from gliderplan.language.diagnostics import MissionError, MissionSyntaxError, render_all
from gliderplan.language.parser import parse
from gliderplan.language.source import read_mission

INDENT = "  "
WIDTH = 88  # longer statements are broken after a ',', a '|' or before 'set' and the action

# Tighter-binding levels first; matches the grammar in mission.lark.
_PRECEDENCE = {"||": 1, "&&": 2, "!": 3, "<": 4, "<=": 4, ">": 4, ">=": 4, "==": 4, "!=": 4,
               "+": 5, "-": 5, "*": 6, "/": 6}
_UNARY_MINUS, _ATOM = 7, 8

_COMMENT_OR_STRING = re.compile(r"\"[^\"\n]*\"|(?P<comment>(#|//)[^\n]*)")


class FormatError(GliderplanError):
    """The formatter could not keep the mission's meaning or comments: nothing is written."""


@dataclass
class _Comment:
    line: int
    text: str
    after_code: bool  # code precedes it on its line


@dataclass
class _Statement:
    """One statement of the output (a line or a few), with the source lines it came from."""

    first_line: int
    last_line: int
    depth: int  # indentation level
    code: list[str]
    blank_before: bool = False  # canonical blank line (states, after the header)
    leading: list[_Comment] = field(default_factory=list)
    trailing: _Comment | None = None


def format_file(path: str | Path) -> tuple[str, str]:
    """(text, canonical text) of a mission file. Raises InputFileError when it cannot be read,
    MissionError (with the diagnostics) when it does not parse, FormatError when the
    formatter could not keep its meaning or comments."""
    text = read_mission(path)
    try:
        return text, format_source(text)
    except MissionSyntaxError as err:
        raise MissionError(f"{path}: does not parse, left as it is",
                           details=render_all(err.diagnostics, str(path), text),
                           diagnostics=[d.to_json(str(path)) for d in err.diagnostics],
                           file=str(path)) from None
    except FormatError as err:
        raise FormatError(f"{path}: {err}") from None


def format_source(text: str) -> str:
    """The canonical text of a mission; MissionSyntaxError if it does not parse."""
    mission = parse(text)
    try:
        return _format(text, mission)
    except RecursionError:
        raise FormatError("expressions are nested too deeply to format") from None


def _format(text: str, mission: ast.Mission) -> str:
    comments = list(_comments(text))
    statements = list(_statements(mission, text))
    trailer = _attach(comments, statements)
    result = _render(statements, trailer, text.splitlines())
    _verify(text, result, mission, comments)
    return result


# ---- comments ------------------------------------------------------------------


def _comments(text: str) -> Iterator[_Comment]:
    for number, line in enumerate(text.splitlines(), start=1):
        for match in _COMMENT_OR_STRING.finditer(line):
            if match.group("comment"):
                before = line[: match.start()].strip()
                yield _Comment(number, match.group().rstrip(), bool(before))
                break


def _attach(comments: list[_Comment], statements: list[_Statement]) -> list[_Comment]:
    """Give each comment to a statement; return those after the last statement."""
    trailer = []
    for comment in comments:
        ending_here = [s for s in statements if s.last_line == comment.line]
        if comment.after_code and ending_here and ending_here[-1].trailing is None:
            ending_here[-1].trailing = comment
            continue
        owner = next((s for s in statements if s.last_line >= comment.line), None)
        if owner is None:
            trailer.append(comment)
        else:
            owner.leading.append(comment)
    return trailer


# ---- statements ------------------------------------------------------------------


def _statements(mission: ast.Mission, text: str) -> Iterator[_Statement]:
    line = mission.name.span.line
    yield _Statement(line, line, 0, [f"mission {mission.name.text}"])
    for index, decl in enumerate(mission.declarations):
        yield _Statement(decl.span.line, decl.span.end_line, 0, [_declaration(decl)],
                         blank_before=index == 0)
    for state in mission.states:
        yield from _state(state, text)


def _state(state: ast.State, text: str) -> Iterator[_Statement]:
    yield _Statement(state.span.line, state.name.span.line, 0, [f"state {state.name.text}"],
                     blank_before=True)
    begin = _begin_line(text, state.name.span)
    yield _Statement(begin, begin, 0, ["begin"])
    for item in state.items:
        if isinstance(item, ast.EventsItem):
            yield _Statement(item.span.line, item.span.line, 1, ["events"])
            for event in item.events:
                yield _Statement(event.span.line, event.span.end_line, 2, _event(event))
        else:
            yield _Statement(item.span.line, item.span.end_line, 1, _item(item))
    yield _Statement(state.span.end_line, state.span.end_line, 0, ["end"])


def _begin_line(text: str, name: ast.Span) -> int:
    """Line of the `begin` after a state's name (comments may sit in between)."""
    lines = text.splitlines()
    for number in range(name.end_line, len(lines) + 1):
        line = lines[number - 1]
        if number == name.end_line:
            line = line[name.end_column - 1:]
        code = _COMMENT_OR_STRING.sub(
            lambda m: "" if m.group("comment") else m.group(), line)
        if re.search(r"\bbegin\b", code):
            return number
    return name.end_line


def _declaration(decl: ast.Declaration) -> str:
    match decl:
        case ast.VehicleDecl(preset, is_file):
            return f"vehicle {_preset(preset, is_file)}"
        case ast.ComputerDecl(board, is_file, clock):
            at = f" @ {_quantity(clock)}" if clock else ""
            return f"computer {_preset(board, is_file)}{at}"
        case ast.BatteryDecl(None, _, reserve, _, preset, is_file):
            text = f"battery {_preset(preset, is_file)}"
            return text + (f" reserve {_quantity(reserve)}" if reserve else "")
        case ast.BatteryDecl(capacity, voltage, reserve):
            text = f"battery {_quantity(capacity)}"
            text += f" at {_quantity(voltage)}" if voltage else ""
            return text + (f" reserve {_quantity(reserve)}" if reserve else "")
        case ast.HorizonDecl(duration):
            return f"horizon {_quantity(duration)}"
        case ast.StartDecl(lat, lon):
            return f"start {lat.text}, {lon.text}"
        case ast.CorrectionDecl(setting):
            return f"current_correction {setting.text}"
        case ast.ObjectiveDecl(sense, target, floor):
            text = f"objective {sense.text} {target.text}"
            return text + (f" quality >= {floor.text}" if floor else "")
        case ast.SensorDecl(sensor, bounds):
            return " ".join([f"sensor {sensor.text}", *map(_bound, bounds)])
        case ast.VarDecl(name, initial):
            return f"var {name.text} = {expression(initial)}"
        case ast.StackDecl(depth):
            return f"stack {depth.text}"
    raise TypeError(f"not a declaration: {decl!r}")


def _fill(head: str, items: list[str], separator: str, width: int, hang: int) -> list[str]:
    """head + items joined by separator, broken into lines of at most width where possible;
    a broken line keeps the separator's non-blank part, the next is indented by hang."""
    lines = [head + items[0]]
    for item in items[1:]:
        if len(lines[-1] + separator + item) <= width:
            lines[-1] += separator + item
        else:
            lines[-1] += separator.rstrip()
            lines.append(" " * hang + item)
    return lines


def _item(item: ast.StateItem) -> list[str]:
    width = WIDTH - len(INDENT)
    match item:
        case ast.RouteItem(route):
            return [f"flightroute {_invocation(route)}"]
        case ast.ProfileItem(alternatives):
            return _fill("flightprofile ", [_invocation(a) for a in alternatives], " | ",
                         width, len("flightprofile "))
        case ast.SensorsItem(sensors):
            return _fill("sensors ", [_sensor_use(u) for u in sensors], ", ", width,
                         len("sensors "))
        case ast.ExpectItem(low, high):
            return [f"expect {_quantity(low)} .. {_quantity(high)}"]
        case ast.RequireItem(sensor, bounds):
            return [" ".join([f"require {sensor.text}", *map(_bound, bounds)])]
        case ast.ComputerItem("clock", ast.Ident(text)):
            return [f"computer clock {text}"]
        case ast.ComputerItem("clock", quantity):
            return [f"computer clock {_quantity(quantity)}"]
        case ast.ComputerItem("sleep"):
            return ["computer sleep between ticks"]
        case ast.ComputerItem("workload", cycles):
            return [f"computer workload {cycles.text} cycles per tick"]
    raise TypeError(f"not a state item: {item!r}")


def _event(event: ast.Event) -> list[str]:
    parts = [f"case {expression(event.condition)}"]
    if event.assignments:
        parts.append("set " + ", ".join(f"{a.target.text} = {expression(a.value)}"
                                        for a in event.assignments))
    if event.action is not None:
        target = event.action.target
        parts.append(event.action.kind + (f" {target.text}" if target else ""))
    return _fill("", parts, " ", WIDTH - 2 * len(INDENT), len(INDENT))


def _preset(name: ast.Ident, is_file: bool) -> str:
    return f'"{name.text}"' if is_file else name.text


def _quantity(quantity: ast.Quantity) -> str:
    if quantity.unit is None:
        return quantity.text
    separator = "" if quantity.unit.text == "%" else " "
    return f"{quantity.text}{separator}{quantity.unit.text}"


def _bound(bound: ast.Bound) -> str:
    op = "" if bound.kind == "weight" else f" {bound.op}"
    return f"{bound.kind}{op} {bound.value.text}"


def _sensor_use(use: ast.SensorUse) -> str:
    match use.duty:
        case None:
            return use.sensor.text
        case ast.Ident(text):
            return f"{use.sensor.text} duty {text}"
        case ast.Number(_, text):
            return f"{use.sensor.text} duty {text}"
    raise TypeError(f"not a duty: {use.duty!r}")


def _invocation(invocation: ast.Invocation) -> str:
    thrust = invocation.thrust
    setting = "" if thrust is None else " thrust " + (
        thrust.text if isinstance(thrust, ast.Ident) else _quantity(thrust))
    if not invocation.has_parens and not invocation.args:
        return invocation.name.text + setting
    args = ", ".join(
        f"({expression(a.lat)}, {expression(a.lon)})" if isinstance(a, ast.Point)
        else a.text if isinstance(a, ast.Ident) else expression(a)
        for a in invocation.args)
    return f"{invocation.name.text}({args}){setting}"


# ---- expressions -----------------------------------------------------------------


def expression(expr: ast.Expr) -> str:
    """An expression with the fewest parentheses that keep its tree."""
    return _expr(expr)[0]


def _expr(expr: ast.Expr) -> tuple[str, int]:
    match expr:
        case ast.Number(_, text):
            return text, _ATOM
        case ast.Name(name):
            return name, _ATOM
        case ast.Call(function, args):
            return f"{function.text}({', '.join(map(expression, args))})", _ATOM
        case ast.Unary("-", operand):
            return "-" + _operand(operand, _UNARY_MINUS), _UNARY_MINUS
        case ast.Unary("!", operand):
            # `!a < b` would parse as !(a < b) but reads as (!a) < b: always bracket.
            return "!" + _operand(operand, _UNARY_MINUS), _PRECEDENCE["!"]
        case ast.Binary(op, left, right):
            level = _PRECEDENCE[op]
            # Left-associative; comparisons do not chain, so neither side may be one.
            left_min = level + 1 if level == _PRECEDENCE["<"] else level
            return (f"{_operand(left, left_min)} {op} {_operand(right, level + 1)}", level)
    raise TypeError(f"not an expression: {expr!r}")


def _operand(expr: ast.Expr, at_least: int) -> str:
    text, level = _expr(expr)
    return text if level >= at_least else f"({text})"


# ---- output --------------------------------------------------------------------


def _render(statements: list[_Statement], trailer: list[_Comment], source: list[str]) -> str:
    out: list[str] = []
    previous_end = 0
    for statement in statements:
        first = min([statement.first_line, *(c.line for c in statement.leading)])
        blank = statement.blank_before or _blank_between(source, previous_end, first)
        keyword = statement.code[0]
        if out and blank and keyword not in ("begin", "end"):
            out.append("")
        # Comments before a state's `end` are inside the state: indent them as its items.
        comment_depth = 1 if keyword == "end" else statement.depth
        out.extend(INDENT * comment_depth + c.text for c in statement.leading)
        lines = [INDENT * statement.depth + line for line in statement.code]
        if statement.trailing:
            lines[-1] += "  " + statement.trailing.text
        out.extend(lines)
        previous_end = max(statement.last_line,
                           statement.trailing.line if statement.trailing else 0)
    if trailer:
        if _blank_between(source, previous_end, trailer[0].line):
            out.append("")
        out.extend(c.text for c in trailer)
    return "\n".join(out) + "\n"


def _blank_between(source: list[str], after_line: int, before_line: int) -> bool:
    """True when an empty line lies strictly between two source lines."""
    return any(not source[n - 1].strip() for n in range(after_line + 1, before_line)
               if 0 < n <= len(source))


def _verify(source: str, result: str, mission: ast.Mission, comments: list[_Comment]) -> None:
    if parse(result) != mission:
        raise FormatError("formatting would change the mission's meaning; file left as is")
    kept = sorted(c.text for c in _comments(result))
    if kept != sorted(c.text for c in comments):
        raise FormatError("formatting would lose or move a comment out of place; "
                          "file left as is")
