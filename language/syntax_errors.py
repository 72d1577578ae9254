"""Syntax errors in a mission writer's words: what is wrong, where, and how to fix it.

The parser reports which token it did not expect and which terminals it would have
taken; this module turns that into a message about the mistake people actually make
(a missing `end` or `begin`, an unclosed parenthesis, a unit after a number, `and`
for `&&`, a misspelt keyword) and falls back to "unexpected X, expected Y".
"""

from __future__ import annotations

import re
from collections.abc import Mapping

from lark import UnexpectedInput
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

from gliderplan.language import ast
from gliderplan.language.diagnostics import Diagnostic, closest, error
from gliderplan.language.units import ANNOTATION_UNITS

# How terminals with a pattern read in a message (keywords read as themselves).
_TERMINAL_WORDS = {
    "NAME": "a name",
    "NUMBER": "a number",
    "STRING": "a quoted file name",
    "COMPARE": "a comparison (>=, <, ==, ...)",
    "ADD_OP": "'+' or '-'",
    "MUL_OP": "'*' or '/'",
    "PERCENT": "'%'",
    "AUTO": "'auto'",
    "OBJECTIVE_SENSE": "'maximize' or 'minimize'",
    "$END": "end of file",
}

MISSION_SHAPE = ("a mission starts with 'mission NAME', then optional declarations "
                 "(vehicle, battery, sensor, var, ...), then states: "
                 "'state NAME begin ... end'")

# Units people write after numbers that must be plain (SI) in arguments and conditions.
_UNIT_WORDS = ({u for dim in ANNOTATION_UNITS.values() for u in dim}
               | {"m", "km", "cm", "deg", "degrees", "rad", "degC", "C", "sec", "secs",
                  "seconds", "minutes", "hours", "hr", "mps"})

# Terminals that begin a statement: when one is acceptable, the line before was complete.
_STATEMENT_STARTS = {"MISSION", "VEHICLE", "COMPUTER", "BATTERY", "HORIZON", "OBJECTIVE",
                     "SENSOR", "VAR", "STACK", "STATE", "BEGIN", "END", "FLIGHTROUTE",
                     "FLIGHTPROFILE", "SENSORS", "EXPECT", "REQUIRE", "EVENTS", "CASE", "$END"}

_WORD_OPERATORS = {"and": "&&", "or": "||", "not": "!", "AND": "&&", "OR": "||", "NOT": "!"}

_OPEN_STATE = re.compile(r"^[ \t]*state[ \t]+([A-Za-z_]\w*)", re.MULTILINE)
_TRAILING_NUMBER = re.compile(r"(\d+(\.\d*)?|\.\d+)([eE][-+]?\d+)?$")
_COMMENT = re.compile(r"(#|//)[^\n]*")
# Words that start a statement: an unclosed '(' is looked for after the last of them.
_STATEMENT = re.compile(r"\b(case|set|flightprofile|flightroute|var|state|begin|end|sensors"
                        r"|expect|require|events)\b")


def is_blank(text: str) -> bool:
    """True when the text has nothing but whitespace and comments."""
    return not _COMMENT.sub("", text).strip()


def empty_file(text: str) -> Diagnostic:
    what = "the file is empty" if not text.strip() else "the file has only comments"
    return error(f"{what}: there is no mission in it", ast.NO_SPAN, MISSION_SHAPE)


def error_position(err: UnexpectedInput) -> int:
    """Offset in the text where the parser stopped."""
    if isinstance(err, UnexpectedToken) and err.token.type != "$END":
        return err.token.start_pos
    return getattr(err, "pos_in_stream", None) or 0


def describe(err: UnexpectedInput, text: str, literals: Mapping[str, str]) -> Diagnostic:
    """The diagnostic for one parse error. `literals` maps keyword terminals to their text."""
    if isinstance(err, UnexpectedCharacters):
        return _bad_character(err, text)
    expected = set(err.expected) if err.expected else set()
    if isinstance(err, UnexpectedEOF) or err.token.type == "$END":
        return _early_end(expected, text, literals)
    return _bad_token(err.token, expected, text, literals)


def _expected_words(expected: set[str], literals: Mapping[str, str]) -> str:
    words = sorted({_TERMINAL_WORDS.get(t) or f"'{literals.get(t, t)}'" for t in expected})
    if len(words) > 6:
        words = words[:6] + ["..."]
    return "expected " + ", ".join(words)


def _token_span(token) -> ast.Span:
    end_line = token.end_line or token.line
    end_column = token.end_column or token.column + len(str(token))
    return ast.Span(token.line, token.column, end_line, end_column)


def _position_span(text: str, offset: int) -> ast.Span:
    line = text.count("\n", 0, offset) + 1
    column = offset - (text.rfind("\n", 0, offset) + 1) + 1
    return ast.Span(line, column, line, column + 1)


def _word_span(text: str, offset: int) -> ast.Span:
    """Span of the word starting at offset."""
    word = re.match(r"\w*", text[offset:]).group()
    span = _position_span(text, offset)
    return ast.Span(span.line, span.column, span.line, span.column + max(1, len(word)))


def _code_before(text: str, offset: int) -> str:
    """Up to 400 characters of code before offset, comments removed, trailing space cut."""
    start = max(0, offset - 400)
    return _COMMENT.sub("", text[start:offset]).rstrip()


def _open_state(text: str, offset: int) -> re.Match | None:
    """The last `state NAME` line before offset."""
    matches = list(_OPEN_STATE.finditer(text, 0, offset))
    return matches[-1] if matches else None


def _code_end(text: str, offset: int) -> int:
    """Offset just after the last code character (not space, not comment) before offset."""
    line_start = text.rfind("\n", 0, offset) + 1
    while True:
        code = _COMMENT.sub("", text[line_start:offset]).rstrip()
        if code or line_start == 0:
            return line_start + len(code)
        offset = line_start - 1
        line_start = text.rfind("\n", 0, offset) + 1


def _unclosed_paren(text: str, offset: int) -> int | None:
    """Offset of the last '(' that no ')' closes in the statement before offset."""
    starts = [m.start() for m in _STATEMENT.finditer(text, max(0, offset - 2000), offset)]
    begin = starts[-1] if starts else 0
    open_at: list[int] = []
    for match in re.finditer(r"(#|//)[^\n]*|\"[^\"\n]*\"|[()]", text[begin:offset]):
        if match.group() == "(":
            open_at.append(begin + match.start())
        elif match.group() == ")" and open_at:
            open_at.pop()
    return open_at[-1] if open_at else None


def _bad_character(err: UnexpectedCharacters, text: str) -> Diagnostic:
    offset = err.pos_in_stream
    char = text[offset] if offset < len(text) else "?"
    span = _position_span(text, offset)
    if char in "&":
        return error("'&' is not an operator", span, "write '&&' for and, '||' for or")
    if char == '"':
        return error("unterminated string", span,
                     "a file name is written in double quotes on one line: \"boards/my.toml\"")
    if char == ";":
        return error("unexpected ';'", span, "statements end at the line; remove the ';'")
    shown = repr(char) if not char.isprintable() or char in "'\"" else f"'{char}'"
    return error(f"unexpected character {shown}", span,
                 "missions use letters, digits, '_', '.', operators and ( ) , | @ %; "
                 "a comment starts with '#' or '//'")


def _early_end(expected: set[str], text: str, literals: Mapping[str, str]) -> Diagnostic:
    end = len(text)
    if "RPAR" in expected and (paren := _unclosed_paren(text, end)) is not None:
        return error("'(' is never closed", _position_span(text, paren),
                     "add the matching ')'")
    if dangling := re.search(r"\b(goto|call)\s+end$", _code_before(text, end)):
        return error(f"'{dangling.group(1)}' needs the name of a state",
                     _word_span(text, _code_end(text, end) - len("end")),
                     "'end' here is read as the state's name")
    if "END" in expected and (state := _open_state(text, end)):
        span = _position_span(text, state.start(1))
        span = ast.Span(span.line, span.column, span.line, span.column + len(state.group(1)))
        return error(f"state '{state.group(1)}' has no 'end'", span,
                     "the file ends inside it; close it with 'end'")
    if "MISSION" in expected:
        return error("the file has no mission in it", ast.NO_SPAN, MISSION_SHAPE)
    last = _position_span(text, len(text.rstrip()) or 0)
    return error("unexpected end of file", last, _expected_words(expected, literals))


def _bad_token(token, expected: set[str], text: str,
               literals: Mapping[str, str]) -> Diagnostic:
    span = _token_span(token)
    shown = f"'{token}'"
    before = _code_before(text, token.start_pos)
    kind = token.type

    if "MISSION" in expected:
        return error("a mission file must start with 'mission NAME'", span,
                     "e.g. 'mission survey' on the first line; " + MISSION_SHAPE)
    if kind == "STATE" and "END" in expected and (state := _open_state(text, token.start_pos)):
        return error(f"missing 'end' of state '{state.group(1)}' before the next state", span,
                     "every state is 'state NAME begin ... end'")
    if expected == {"BEGIN"}:
        return error(f"missing 'begin' before {shown}", span,
                     "a state is 'state NAME', then 'begin', its sections, and 'end'")
    if kind == "RPAR" and _unclosed_paren(text, token.start_pos) is None:
        return error("')' has no matching '('", span, "remove it or add the '('")
    if (kind == "NAME" and "NAME" not in expected and str(token) in _UNIT_WORDS
            and _TRAILING_NUMBER.search(before)):
        return error(f"no unit allowed here: {shown}", span,
                     "arguments and conditions are plain numbers in SI units (metres, "
                     "seconds, radians, degC): write '5', not '5 m'; units go only on "
                     "battery, computer, horizon, reserve and expect")
    if "RPAR" in expected and kind not in ("COMMA", "RPAR") and (
            paren := _unclosed_paren(text, token.start_pos)) is not None and (
            kind in literals or _position_span(text, paren).line != token.line):
        opened = _position_span(text, paren)
        return error(f"missing ')' before {shown}", span,
                     f"the '(' on line {opened.line} column {opened.column} is never closed")
    if kind == "NAME" and str(token) in _WORD_OPERATORS:
        return error(f"{shown} is not an operator here", span,
                     f"write '{_WORD_OPERATORS[str(token)]}'")
    if kind == "EQUAL" and "COMPARE" in expected:
        return error("'=' assigns; a condition compares with '=='", span,
                     "write e.g. 'case depth == 5 goto s2'; assign with 'set VAR = EXPR'")
    if kind == "VBAR" and any(literals.get(t) == "||" for t in expected):
        return error("'|' is not an operator in a condition", span, "write '||' for or")
    if kind in ("GOTO", "CALL", "RETURN", "EXIT") and re.search(r"\bcase$", before):
        return error(f"'case' needs a condition before '{token}'", span,
                     f"write e.g. 'case missiontime >= 500 {token}'")
    if action := re.search(r"\bcase\s+(goto|call)$", before):
        return error(f"'case' needs a condition before '{action.group(1)}'",
                     _word_span(text, _code_end(text, token.start_pos) - len(action.group(1))),
                     f"write e.g. 'case missiontime >= 500 {action.group(1)} {token}'")
    if kind == "NUMBER" and _TRAILING_NUMBER.search(before):
        return error(f"unexpected number {shown} right after another", span,
                     "a ',' or an operator is missing between them")
    if expected == {"NAME"} and (word := re.search(r"\b(goto|call)$", before)):
        return error(f"'{word.group(1)}' needs the name of a state", span,
                     f"write e.g. '{word.group(1)} s2'")
    keywords = [literals[t] for t in expected if t in literals and literals[t].isalpha()]
    if kind in ("NAME", *literals) and str(token).isidentifier() and (
            match := closest(str(token), keywords)):
        return error(f"unexpected {shown}", span, f"did you mean '{match}'?")
    hint = _expected_words(expected, literals)
    code_end = _code_end(text, token.start_pos)
    if not expected & _STATEMENT_STARTS and text.count("\n", code_end, token.start_pos):
        last_word = before.split()[-1] if before.split() else ""
        return error(f"the line ends too early, after '{last_word}'",
                     _position_span(text, code_end), hint)
    if "CASE" in expected and "END" in expected:
        hint += "; an event is 'case CONDITION [set VAR = EXPR, ...] ACTION'"
    return error(f"unexpected {shown}", span, hint)
