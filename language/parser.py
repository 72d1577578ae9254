"""Mission text -> typed syntax tree (gliderplan.language.ast), or syntax diagnostics."""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

from lark import Lark, UnexpectedInput

from gliderplan.contract import MAX_PARSE_DEPTH
from gliderplan.language import ast
from gliderplan.language.diagnostics import Diagnostic, MissionSyntaxError, error
from gliderplan.language.lalr import Parser, TooDeep

GRAMMAR = Path(__file__).with_name("mission.lark")

# A syntax error hides the rest of its state; the parser resumes at the next line that
# starts a state (or, before the first state, a declaration), up to this many errors.
MAX_SYNTAX_ERRORS = 20

# Hundreds of nested operators (`- - - ... x`) exhaust Python's stack in the passes
# that walk expressions; say so instead of crashing.
TOO_DEEP = error("expressions are nested too deeply", ast.NO_SPAN,
                 "split the expression with a variable ('set v = ...')")
_RESUME_AT = re.compile(r"^[ \t]*(state|vehicle|computer|battery|horizon|objective|sensor|var"
                        r"|stack)\b", re.MULTILINE)


@cache
def _lark() -> Lark:
    return Lark.open(
        str(GRAMMAR),
        parser="lalr",
        lexer="contextual",
        propagate_positions=True,
        maybe_placeholders=True,
        cache=True,
        start=["start", "recovery"],
    )


# A token from the driver: (text, line, column, end_line, end_column).
TokenTuple = tuple[str, int, int, int, int]


def _ident(token: TokenTuple) -> ast.Ident:
    return ast.Ident(token[0], ast.Span(*token[1:]))


def _number_token(token: TokenTuple) -> ast.Number:
    return ast.Number(float(token[0]), token[0], ast.Span(*token[1:]))


class _Build:
    """One method per grammar rule that makes a node (or its alias); each takes the
    rule's position `where` (line, column, end line, end column) and its children:
    nodes already built, tokens, and None for a missing [optional] part."""

    def start(self, where, children):
        header, *rest = children
        declarations = tuple(c for c in rest if not isinstance(c, ast.State))
        states = tuple(c for c in rest if isinstance(c, ast.State))
        return ast.Mission(header, declarations, states, ast.Span(*where))

    def recovery(self, where, children):
        return None  # parsed after an error only to find the next one

    def mission_header(self, where, children):
        return _ident(children[0])

    # ---- declarations
    def vehicle_decl(self, where, children):
        return ast.VehicleDecl(*_preset(children[0]), ast.Span(*where))

    def computer_decl(self, where, children):
        board, clock = children
        return ast.ComputerDecl(*_preset(board), clock, ast.Span(*where))

    def battery_decl(self, where, children):
        capacity, voltage, reserve = children
        return ast.BatteryDecl(capacity, voltage, reserve, ast.Span(*where))

    def battery_preset(self, where, children):
        preset, reserve = children
        name, is_file = _preset(preset)
        return ast.BatteryDecl(None, None, reserve, ast.Span(*where), name, is_file)

    def voltage(self, where, children):
        return children[0]

    reserve = voltage

    def horizon_decl(self, where, children):
        return ast.HorizonDecl(children[0], ast.Span(*where))

    def start_decl(self, where, children):
        return ast.StartDecl(children[0], children[1], ast.Span(*where))

    def correction_decl(self, where, children):
        return ast.CorrectionDecl(_ident(children[0]), ast.Span(*where))

    def objective_decl(self, where, children):
        sense, target, floor = children
        return ast.ObjectiveDecl(_ident(sense), _ident(target), floor, ast.Span(*where))

    def quality_floor(self, where, children):
        return children[0]

    def sensor_decl(self, where, children):
        sensor, *bounds = children
        return ast.SensorDecl(_ident(sensor), tuple(bounds), ast.Span(*where))

    def var_decl(self, where, children):
        name, value = children
        return ast.VarDecl(_ident(name), value, ast.Span(*where))

    def stack_decl(self, where, children):
        return ast.StackDecl(children[0], ast.Span(*where))

    def weight(self, where, children):
        return ast.Bound("weight", "=", children[0], ast.Span(*where))

    def duty_bound(self, where, children):
        op, value = children
        return ast.Bound("duty", op[0], value, ast.Span(*where))

    def quality_bound(self, where, children):
        return ast.Bound("quality", ">=", children[0], ast.Span(*where))

    def quantity(self, where, children):
        number, unit = children
        return ast.Quantity(number.value, number.text, _ident(unit) if unit else None,
                            ast.Span(*where))

    def number(self, where, children):
        return _number_token(children[0])

    def negative(self, where, children):
        text = children[0][0]
        return ast.Number(-float(text), f"-{text}", ast.Span(*where))

    # ---- states
    def state(self, where, children):
        name, *items = children
        return ast.State(_ident(name), tuple(items), ast.Span(*where))

    def route_item(self, where, children):
        return ast.RouteItem(children[0], ast.Span(*where))

    def profile_item(self, where, children):
        return ast.ProfileItem(tuple(children), ast.Span(*where))

    def sensors_item(self, where, children):
        return ast.SensorsItem(tuple(children), ast.Span(*where))

    def sensor_use(self, where, children):
        sensor, duty = children
        if isinstance(duty, tuple):  # `auto`
            duty = _ident(duty)
        return ast.SensorUse(_ident(sensor), duty, ast.Span(*where))

    def expect_item(self, where, children):
        return ast.ExpectItem(children[0], children[1], ast.Span(*where))

    def computer_clock(self, where, children):
        value = children[0]
        if isinstance(value, tuple):  # the `auto` token
            value = _ident(value)
        return ast.ComputerItem("clock", value, ast.Span(*where))

    def computer_sleep(self, where, children):
        return ast.ComputerItem("sleep", None, ast.Span(*where))

    def computer_workload(self, where, children):
        return ast.ComputerItem("workload", children[0], ast.Span(*where))

    def require_item(self, where, children):
        sensor, *bounds = children
        return ast.RequireItem(_ident(sensor), tuple(bounds), ast.Span(*where))

    def events_item(self, where, children):
        return ast.EventsItem(tuple(children), ast.Span(*where))

    def invocation(self, where, children):
        name, *args = children
        has_parens = bool(args)  # maybe_placeholders gives [None] for "()"
        args = tuple(a for a in args if a is not None)
        return ast.Invocation(_ident(name), args, has_parens, ast.Span(*where))

    def thrust(self, where, children):
        invocation, setting = children
        if isinstance(setting, tuple):  # the `auto` token
            setting = _ident(setting)
        return ast.Invocation(invocation.name, invocation.args, invocation.has_parens,
                              ast.Span(*where), setting)

    def auto_argument(self, where, children):
        return _ident(children[0])

    def point(self, where, children):
        return ast.Point(children[0], children[1], ast.Span(*where))

    def event(self, where, children):
        condition, assignments, action = children
        return ast.Event(condition, assignments or (), action, ast.Span(*where))

    def assignments(self, where, children):
        return tuple(children)

    def assignment(self, where, children):
        return ast.Assignment(_ident(children[0]), children[1], ast.Span(*where))

    def goto(self, where, children):
        return ast.Action("goto", _ident(children[0]), ast.Span(*where))

    def call(self, where, children):
        return ast.Action("call", _ident(children[0]), ast.Span(*where))

    def return_(self, where, children):
        return ast.Action("return", None, ast.Span(*where))

    def exit(self, where, children):
        return ast.Action("exit", None, ast.Span(*where))

    # ---- expressions
    def literal(self, where, children):
        return _number_token(children[0])

    def name(self, where, children):
        return ast.Name(children[0][0], ast.Span(*where))

    def function_call(self, where, children):
        name, *args = children
        return ast.Call(_ident(name), tuple(a for a in args if a is not None),
                        ast.Span(*where))

    def neg(self, where, children):
        return ast.Unary("-", children[0], ast.Span(*where))

    def not_(self, where, children):
        return ast.Unary("!", children[0], ast.Span(*where))

    def comparison(self, where, children):
        left, op, right = children
        return ast.Binary(op[0], left, right, ast.Span(*where))

    def or_expr(self, where, children):
        return _fold(children, "||")

    def and_expr(self, where, children):
        return _fold(children, "&&")

    def sum(self, where, children):
        return _fold_with_ops(children)

    product = sum


def _preset(token: TokenTuple) -> tuple[ast.Ident, bool]:
    """A preset name, or a "file path" (quotes removed)."""
    if token[0].startswith('"'):
        return ast.Ident(token[0][1:-1], ast.Span(*token[1:])), True
    return _ident(token), False


def _join(left: ast.Span, right: ast.Span) -> ast.Span:
    return ast.Span(left.line, left.column, right.end_line, right.end_column)


def _fold(operands: list, op: str) -> ast.Expr:
    result = operands[0]
    for right in operands[1:]:
        result = ast.Binary(op, result, right, _join(result.span, right.span))
    return result


def _fold_with_ops(children: list) -> ast.Expr:
    """Left-associative fold of [operand, op, operand, op, operand, ...]."""
    result = children[0]
    for op, right in zip(children[1::2], children[2::2], strict=True):
        result = ast.Binary(op[0], result, right, _join(result.span, right.span))
    return result


@cache
def _parser() -> Parser:
    return Parser(_lark(), _Build())


@cache
def _keyword_literals() -> dict[str, str]:
    """Terminal name -> text, for terminals that are fixed strings ('end', '(', ...)."""
    return {t.name: t.pattern.value for t in _lark().terminals if t.pattern.type == "str"}


def _resume_point(text: str, error_at: int, after: int) -> int | None:
    """Where to parse again after an error at offset error_at: a line starting a state,
    or a declaration line before the first state; always beyond offset `after`."""
    first_state = None
    for match in _RESUME_AT.finditer(text):
        keyword = match.group(1)
        if keyword == "state" and first_state is None:
            first_state = match.start(1)
        if keyword != "state" and first_state is not None:
            continue
        if match.start(1) >= error_at and match.start(1) > after:
            return match.start(1)
    return None


def _blank_before(text: str, offset: int) -> str:
    """The text with everything before offset turned to spaces (lines and columns kept)."""
    head = text[:offset]
    return re.sub(r"[^\n]", " ", head) + text[offset:]


def parse(text: str) -> ast.Mission:
    """Parse mission source; raise MissionSyntaxError with every syntax error found (one
    at the first token nested deeper than MAX_PARSE_DEPTH: parsing stays linear)."""
    try:
        return _parser().parse(text, "start", MAX_PARSE_DEPTH)
    except UnexpectedInput as err:
        raise MissionSyntaxError(_all_syntax_errors(err, text)) from None
    except TooDeep as err:
        _, line, column, end_line, end_column = err.token
        raise MissionSyntaxError([error(
            f"nested more than {MAX_PARSE_DEPTH} deep (brackets and operators together)",
            ast.Span(line, column, end_line, end_column),
            "split the expression with a variable ('set v = ...')")]) from None


def _all_syntax_errors(first: UnexpectedInput, text: str) -> list[Diagnostic]:
    """The first error, then those found by parsing again from each resume point."""
    # Imported on the first error only: a clean check starts faster without it.
    from gliderplan.language.syntax_errors import describe, empty_file, error_position, is_blank

    if is_blank(text):
        return [empty_file(text)]
    literals = _keyword_literals()
    found = [describe(first, text, literals)]
    error_at, resumed_at = error_position(first), -1
    while len(found) < MAX_SYNTAX_ERRORS:
        resume = _resume_point(text, error_at, resumed_at)
        if resume is None:
            break
        try:
            _parser().parse(_blank_before(text, resume), "recovery")
            break
        except UnexpectedInput as err:
            found.append(describe(err, text, literals))
            error_at, resumed_at = error_position(err), resume
    return found
