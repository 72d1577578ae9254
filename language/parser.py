"""Mission text -> typed syntax tree (gliderplan.language.ast), or syntax diagnostics."""

from __future__ import annotations

import re
from functools import cache
from pathlib import Path

from lark import Lark, Token, Tree, UnexpectedInput

from gliderplan.language import ast
from gliderplan.language.diagnostics import Diagnostic, MissionSyntaxError, error

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


def _span_of(item: Token | object) -> ast.Span:
    meta = getattr(item, "meta", item)
    if getattr(meta, "empty", False):
        return ast.NO_SPAN
    return ast.Span(meta.line, meta.column, meta.end_line, meta.end_column)


def _ident(token: Token) -> ast.Ident:
    return ast.Ident(str(token), _span_of(token))


def _number_token(token: Token) -> ast.Number:
    return ast.Number(float(token), str(token), _span_of(token))


class _ToAst:
    """One method per grammar rule; each takes the rule's meta (positions) and its built
    children, and returns the matching ast node.

    A plain bottom-up walk rather than lark's Transformer: it skips per-call wrappers
    and token visits, which made tree building cost half as much as parsing itself.
    """

    def build(self, tree: Tree) -> object:
        children = [self.build(c) if isinstance(c, Tree) else c for c in tree.children]
        return getattr(self, tree.data)(tree.meta, children)

    def start(self, meta, children):
        header, *rest = children
        declarations = tuple(c for c in rest if not isinstance(c, ast.State))
        states = tuple(c for c in rest if isinstance(c, ast.State))
        return ast.Mission(header, declarations, states, _span_of(meta))

    def mission_header(self, meta, children):
        return _ident(children[0])

    # ---- declarations
    def vehicle_decl(self, meta, children):
        return ast.VehicleDecl(*_preset(children[0]), _span_of(meta))

    def computer_decl(self, meta, children):
        board, clock = children
        return ast.ComputerDecl(*_preset(board), clock, _span_of(meta))

    def battery_decl(self, meta, children):
        capacity, voltage, reserve = children
        return ast.BatteryDecl(capacity, voltage, reserve, _span_of(meta))

    def voltage(self, meta, children):
        return children[0]

    reserve = voltage

    def horizon_decl(self, meta, children):
        return ast.HorizonDecl(children[0], _span_of(meta))

    def objective_decl(self, meta, children):
        sense, target, floor = children
        return ast.ObjectiveDecl(_ident(sense), _ident(target), floor, _span_of(meta))

    def quality_floor(self, meta, children):
        return children[0]

    def sensor_decl(self, meta, children):
        sensor, *bounds = children
        return ast.SensorDecl(_ident(sensor), tuple(bounds), _span_of(meta))

    def var_decl(self, meta, children):
        name, value = children
        return ast.VarDecl(_ident(name), value, _span_of(meta))

    def stack_decl(self, meta, children):
        return ast.StackDecl(children[0], _span_of(meta))

    def weight(self, meta, children):
        return ast.Bound("weight", "=", children[0], _span_of(meta))

    def duty_bound(self, meta, children):
        op, value = children
        return ast.Bound("duty", str(op), value, _span_of(meta))

    def quality_bound(self, meta, children):
        return ast.Bound("quality", ">=", children[0], _span_of(meta))

    def quantity(self, meta, children):
        number, unit = children
        return ast.Quantity(number.value, number.text, _ident(unit) if unit else None,
                            _span_of(meta))

    def number(self, meta, children):
        return _number_token(children[0])

    def negative(self, meta, children):
        token = children[0]
        return ast.Number(-float(token), f"-{token}", _span_of(meta))

    # ---- states
    def state(self, meta, children):
        name, *items = children
        return ast.State(_ident(name), tuple(items), _span_of(meta))

    def route_item(self, meta, children):
        return ast.RouteItem(children[0], _span_of(meta))

    def profile_item(self, meta, children):
        return ast.ProfileItem(tuple(children), _span_of(meta))

    def sensors_item(self, meta, children):
        return ast.SensorsItem(tuple(children), _span_of(meta))

    def sensor_use(self, meta, children):
        sensor, duty = children
        if isinstance(duty, Token):
            duty = _ident(duty)
        return ast.SensorUse(_ident(sensor), duty, _span_of(meta))

    def expect_item(self, meta, children):
        return ast.ExpectItem(children[0], children[1], _span_of(meta))

    def require_item(self, meta, children):
        sensor, *bounds = children
        return ast.RequireItem(_ident(sensor), tuple(bounds), _span_of(meta))

    def events_item(self, meta, children):
        return ast.EventsItem(tuple(children), _span_of(meta))

    def invocation(self, meta, children):
        name, *args = children
        has_parens = bool(args)  # maybe_placeholders gives [None] for "()"
        args = tuple(a for a in args if a is not None)
        return ast.Invocation(_ident(name), args, has_parens, _span_of(meta))

    def point(self, meta, children):
        return ast.Point(children[0], children[1], _span_of(meta))

    def event(self, meta, children):
        condition, assignments, action = children
        return ast.Event(condition, assignments or (), action, _span_of(meta))

    def assignments(self, meta, children):
        return tuple(children)

    def assignment(self, meta, children):
        return ast.Assignment(_ident(children[0]), children[1], _span_of(meta))

    def goto(self, meta, children):
        return ast.Action("goto", _ident(children[0]), _span_of(meta))

    def call(self, meta, children):
        return ast.Action("call", _ident(children[0]), _span_of(meta))

    def return_(self, meta, children):
        return ast.Action("return", None, _span_of(meta))

    def exit(self, meta, children):
        return ast.Action("exit", None, _span_of(meta))

    # ---- expressions
    def literal(self, meta, children):
        return _number_token(children[0])

    def name(self, meta, children):
        return ast.Name(str(children[0]), _span_of(meta))

    def function_call(self, meta, children):
        name, *args = children
        return ast.Call(_ident(name), tuple(a for a in args if a is not None), _span_of(meta))

    def neg(self, meta, children):
        return ast.Unary("-", children[0], _span_of(meta))

    def not_(self, meta, children):
        return ast.Unary("!", children[0], _span_of(meta))

    def comparison(self, meta, children):
        left, op, right = children
        return ast.Binary(str(op), left, right, _span_of(meta))

    def or_expr(self, meta, children):
        return _fold(children, "||")

    def and_expr(self, meta, children):
        return _fold(children, "&&")

    def sum(self, meta, children):
        return _fold_with_ops(children)

    product = sum


def _preset(token: Token) -> tuple[ast.Ident, bool]:
    """A preset name, or a "file path" (quotes removed)."""
    if token.type == "STRING":
        return ast.Ident(str(token)[1:-1], _span_of(token)), True
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
        result = ast.Binary(str(op), result, right, _join(result.span, right.span))
    return result


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
    """Parse mission source; raise MissionSyntaxError with every syntax error found."""
    try:
        tree = _lark().parse(text, start="start")
    except UnexpectedInput as err:
        raise MissionSyntaxError(_all_syntax_errors(err, text)) from None
    try:
        return _ToAst().build(tree)
    except RecursionError:
        raise MissionSyntaxError([TOO_DEEP]) from None


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
            _lark().parse(_blank_before(text, resume), start="recovery")
            break
        except UnexpectedInput as err:
            found.append(describe(err, text, literals))
            error_at, resumed_at = error_position(err), resume
    return found
